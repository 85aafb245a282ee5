"""The formatter of pydantic's errors (pipeline.config.errors), on hand-made errors and a small hand-made schema."""

from typing import Literal

import pytest
from pydantic import Field, ValidationError
from pydantic_core import InitErrorDetails

from pipeline.config.distributions import Strict
from pipeline.config.errors import (
    ConfigError,
    config_error,
    error_lines,
    join_key,
    locate,
    range_text,
    to_config_error,
)
from pipeline.config.fields import named, number
from pipeline.config.schema import Params


class Wheel(Strict):
    radius_mm: float = number("mm", gt=0.0, le=500.0)


class Cart(Strict):
    speed_m_s: float = number("m/s", gt=0.0, lt=50.0)
    mode: Literal["push", "pull"] = named("drive mode")
    wheels: list[Wheel]
    count: int = Field(ge=1, le=8)


def error(kind, loc, given, **ctx):
    """One error as pydantic reports it: its type, location, input and context."""
    return {"type": kind, "loc": tuple(loc), "msg": "pydantic's own text", "input": given, "ctx": ctx}


def line(schema, *errors):
    return error_lines(schema, errors)


def test_a_range_error_names_the_key_the_value_the_range_and_the_unit():
    got = line(Cart, error("less_than", ["speed_m_s"], 80.0, lt=50.0))
    assert got == [("speed_m_s", "speed_m_s = 80.0: must be a number in (0, 50) m/s")]


def test_a_list_item_gets_its_index_and_the_unit_of_its_own_field():
    got = line(Cart, error("greater_than", ["wheels", 1, "radius_mm"], -3, gt=0.0))
    assert got == [("wheels[1].radius_mm", "wheels[1].radius_mm = -3: must be a number in (0, 500] mm")]


def test_an_integer_range_is_written_without_decimals():
    got = line(Cart, error("int_type", ["count"], 2.5))
    assert got == [("count", "count = 2.5: must be an integer in [1, 8]")]


def test_an_unknown_key_gets_the_closest_allowed_key_and_the_list_of_keys():
    (got,) = line(Cart, error("extra_forbidden", ["mdoe"], "push"))
    assert got == ("mdoe", "unknown key mdoe (did you mean mode?): the top level takes speed_m_s, mode, wheels, count")
    (nested,) = line(Cart, error("extra_forbidden", ["wheels", 0, "radius"], 3.0))
    assert nested[1].startswith("unknown key wheels[0].radius (did you mean radius_mm?): wheels[0] takes radius_mm")


def test_no_suggestion_when_nothing_is_close():
    (got,) = line(Cart, error("extra_forbidden", ["zzz"], 1))
    assert "did you mean" not in got[1]


def test_a_missing_key_says_what_was_expected():
    assert line(Cart, error("missing", ["mode"], {})) == [("mode", "missing key mode: expected one of push, pull")]


def test_a_literal_error_names_what_the_value_is_and_suggests_the_closest():
    (got,) = line(Cart, error("literal_error", ["mode"], "pul", expected="'push' or 'pull'"))
    assert got[1] == "mode = 'pul': unknown drive mode (did you mean pull?): must be one of push, pull"


def test_numeric_text_is_explained():
    (exponent,) = line(Cart, error("float_type", ["speed_m_s"], "1e3"))
    assert "is text, not a number" in exponent[1] and "write 1.0e+3" in exponent[1]
    (quoted,) = line(Cart, error("float_type", ["speed_m_s"], "12"))
    assert "is text, not a number" in quoted[1] and "without quotes" in quoted[1]
    (word,) = line(Cart, error("float_type", ["speed_m_s"], "fast"))
    assert word[1] == "speed_m_s = 'fast': must be a number in (0, 50) m/s"


def test_a_custom_error_is_reported_at_its_own_key_below_the_validator():
    (got,) = line(Cart, error("config", ["wheels", 0], {}, key="radius_mm", value=7, expected="is too small"))
    assert got == ("wheels[0].radius_mm", "wheels[0].radius_mm = 7: is too small")
    (top,) = line(Cart, error("config", [], {}, key="count", value=9, expected="is too many"))
    assert top == ("count", "count = 9: is too many")


def test_the_tag_of_a_distribution_is_not_part_of_the_key_and_the_unit_is_the_quantitys():
    got = line(Params, error("missing", ["distributions", "tyre_wear_mm", "uniform", "high"], {}))
    assert got == [
        (
            "distributions.tyre_wear_mm.high",
            "missing key distributions.tyre_wear_mm.high: expected a number in mm (kind uniform takes low, high)",
        )
    ]
    # sigma is dimensionless (the library's LogNormal.dimensionless): no unit, where the median is in the quantity's;
    # both > 0 (LogNormal.positive)
    (sigma,) = line(Params, error("greater_than", ["distributions", "bush_damping", "lognormal", "sigma"], 0, gt=0.0))
    assert sigma[1] == "distributions.bush_damping.sigma = 0: must be a number > 0"
    (median,) = line(Params, error("float_type", ["distributions", "bush_damping", "lognormal", "median"], "big"))
    assert median[1] == "distributions.bush_damping.median = 'big': must be a number > 0 N m s/rad"


def test_a_bad_kind_is_reported_at_the_kind_key():
    bad = error("union_tag_invalid", ["distributions", "road_class"], {"kind": "uniform"}, tag="uniform")
    ((key, text),) = line(Params, bad)
    assert key == "distributions.road_class.kind"
    assert text.startswith("distributions.road_class.kind = 'uniform': unknown distribution kind for the categorical")
    assert text.endswith("must be one of choice, constant")


def test_unknown_keys_come_first_and_repeats_are_dropped():
    errors = [
        error("missing", ["mode"], {}),
        error("extra_forbidden", ["mdoe"], "push"),
        error("missing", ["mode"], {}),
    ]
    assert [key for key, _ in line(Cart, *errors)] == ["mdoe", "mode"]


def test_locate_and_join_key():
    place = locate(Params, ("fleet", "axle_mix", "tandem"))
    assert (place.key, place.node, place.unit) == ("fleet.axle_mix.tandem", float, "-")
    assert locate(Params, ("fleet", "nope")).node is None
    assert join_key(["protocol", "run", 1]) == "protocol.run[1]"
    assert join_key([]) == ""


@pytest.mark.parametrize(
    ("bounds", "unit", "text"),
    [
        ({"ge": 0.0, "le": 1.0}, "-", "in [0, 1]"),
        ({"gt": 0.0, "le": 50.0}, "m/s", "in (0, 50] m/s"),
        ({"gt": 0.0, "lt": 1.0}, "[-]", "in (0, 1)"),
        ({"gt": 0.0}, "N m/rad", "> 0 N m/rad"),
        ({"ge": 1e7}, "N", ">= 1e+07 N"),
        ({}, "mm", "in mm"),
        ({}, "-", ""),
    ],
)
def test_range_text(bounds, unit, text):
    assert range_text(bounds, unit) == text


def test_a_validation_error_becomes_one_config_error_listing_every_key():
    details = [
        InitErrorDetails(type="missing", loc=("mode",), input={}),
        InitErrorDetails(type="less_than", loc=("speed_m_s",), input=99.0, ctx={"lt": 50.0}),
    ]
    exc = to_config_error(Cart, ValidationError.from_exception_data("Cart", details))
    assert isinstance(exc, ConfigError) and isinstance(exc, ValueError)
    assert exc.key == "mode"
    assert [key for key, _ in exc.errors] == ["mode", "speed_m_s"]
    assert str(exc).splitlines() == [
        "missing key mode: expected one of push, pull",
        "speed_m_s = 99.0: must be a number in (0, 50) m/s",
    ]


def test_config_error_carries_its_words_in_the_context():
    err = config_error("high", 3.0, "must be greater than low = 5.0")
    assert err.type == "config"
    assert err.context == {"key": "high", "value": 3.0, "expected": "must be greater than low = 5.0"}
