"""A params.yaml section that is a library settings class is built from the library's declarations (issue 42 Must 1):
every field of the class is a key and every key a field, the key's unit is the field's (or the YAML's stated one),
the schema allows nothing the library refuses, and a project bound looser than the library's cannot be written."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest
from pydantic import BaseModel

from bogie.fleet import CalibrationSettings, DesignSettings, StaticProtocol, WimProtocol
from bogie.settings import FrozenMap, Setting, check_settings, declared, setting
from pipeline.config import load_params, parse_config, schema
from pipeline.config.errors import _bounds
from pipeline.config.fields import library_model
from pipeline.config.si import UNITS, attribute


def library_models() -> list[type[BaseModel]]:
    """Every model of the schema, reached from ``Params``, that names a library class."""
    found, todo, seen = [], [schema.Params], set()
    while todo:
        model = todo.pop()
        if model in seen:
            continue
        seen.add(model)
        if getattr(model, "library_class", None) is not None:
            found.append(model)
        for info in model.model_fields.values():
            for arg in (info.annotation, *getattr(info.annotation, "__args__", ())):
                if isinstance(arg, type) and issubclass(arg, BaseModel):
                    todo.append(arg)
    return found


def test_the_sections_that_are_library_classes_are_found():
    assert {m.library_class for m in library_models()} >= {StaticProtocol, WimProtocol, DesignSettings}


@pytest.mark.parametrize("model", library_models(), ids=lambda m: m.__name__)
def test_every_field_of_the_library_class_is_a_key_and_every_key_a_field(model):
    keys = {attribute(key, info)[0]: key for key, info in model.model_fields.items()}
    fields = [f.name for f in dataclasses.fields(model.library_class)]
    assert sorted(keys) == sorted(fields)
    for name, spec in declared(model.library_class).items():
        info = model.model_fields[keys[name]]
        unit = (info.json_schema_extra or {}).get("unit", "-")
        si = UNITS[unit][2] if unit in UNITS else unit
        assert si == spec.unit or (spec.choices is not None), (name, unit, spec.unit)
        assert info.description == spec.doc
        assert (not info.is_required()) == spec.optional, name


def _schema_limits(info, factor: float) -> tuple[float, bool, float, bool]:
    """The schema field's range in the library's unit: (low, low open, high, high open)."""
    bounds = _bounds(info)
    low = bounds.get("ge", bounds.get("gt", -math.inf)) * factor
    high = bounds.get("le", bounds.get("lt", math.inf)) * factor
    return low, "gt" in bounds, high, "lt" in bounds


def declaring() -> list[tuple[type[BaseModel], type, list[str]]]:
    """(a schema model, the library class, the settings of the class whose keys the model has)."""
    found = [(m, m.library_class, list(declared(m.library_class))) for m in library_models()]
    return [*found, (schema.Calibrate, CalibrationSettings, list(schema.CALIBRATION_METHOD_KEYS))]


@pytest.mark.parametrize(("model", "library", "names"), declaring(), ids=lambda x: getattr(x, "__name__", ""))
def test_the_schema_allows_nothing_the_library_refuses(model, library, names):
    keys = {attribute(key, info)[0]: key for key, info in model.model_fields.items()}
    for name in names:
        spec = declared(library)[name]
        if spec.choices is not None:
            continue
        info = model.model_fields[keys[name]]
        unit = (info.json_schema_extra or {}).get("unit", "-")
        factor = UNITS[unit][1] if unit in UNITS else 1.0
        low, low_open, high, high_open = _schema_limits(info, factor)
        # each end of the schema's range (or a step inside an open one) is the library's too
        for end, is_open, inward in ((low, low_open, 1.0), (high, high_open, -1.0)):
            if math.isinf(end):
                assert (spec.low if inward > 0 else spec.high) is None, (
                    name,
                    "the library bounds what the YAML does not",
                )
                continue
            value = end if not is_open else end + inward * max(abs(end), 1.0) * 1e-9
            value = int(math.ceil(value) if inward > 0 else math.floor(value)) if spec.whole else value
            assert spec.contains(value), (model.__name__, name, value, spec.allowed())


def test_a_project_bound_looser_than_the_librarys_is_refused_when_the_model_is_made():
    with pytest.raises(TypeError, match=r"Wim.dt_s: the project bound ge -1 is not stricter than the library's gt 0"):
        library_model("Wim", WimProtocol, "doc", bounds={"dt_s": [("ge", -1.0, "a looser bound")]})
    with pytest.raises(TypeError, match=r"the project bound lt 60 is not stricter than the library's lt 50"):
        library_model("Wim", WimProtocol, "doc", units={"sensor_axle_error": "%"},
                      bounds={"sensor_axle_error_pct": [("lt", 60.0, "a looser bound")]})  # fmt: skip
    with pytest.raises(TypeError, match=r"the project bound ge 0 is not stricter than the library's gt 0"):
        library_model("Wim", WimProtocol, "doc", bounds={"speed_m_s": [("ge", 0.0, "the end itself")]})


def test_a_bound_for_a_key_the_library_does_not_declare_is_refused():
    with pytest.raises(TypeError, match=r"bounds for keys \['speed_km_h'\]"):
        library_model("Wim", WimProtocol, "doc", bounds={"speed_km_h": [("le", 180.0, "a key of another unit")]})


def test_a_library_field_that_is_neither_declared_nor_custom_is_refused():
    with pytest.raises(TypeError, match=r"DesignSettings.grid is neither declared \(bogie.settings\) nor custom"):
        library_model("Design", DesignSettings, "doc")


def test_a_converted_section_is_the_librarys_object_in_si(raw):
    raw["protocol"]["wim"]["sensor_axle_error_pct"] = 2.5
    raw["design"]["grid"] = {"contact_roll_radius_mm": [0, 50]}
    config = parse_config(raw)
    assert type(config.protocol.wim) is WimProtocol and config.protocol.wim.sensor_axle_error == 0.025
    assert type(config.design) is DesignSettings
    assert dict(config.design.grid) == {"contact_roll_radius": (0.0, 0.05)}


@pytest.fixture
def raw():
    return load_params("params.yaml")


# ---- the declarations themselves ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("spec", "good", "bad"),
    [
        (Setting("-", "a count", low=2, whole=True), [2, np.int64(7)], [1, 2.0, True, None, "3"]),
        (
            Setting("s", "a time", low=0.0, low_open=True),
            [1e-300, 1, np.float32(0.5)],
            [0.0, -1.0, math.nan, math.inf, False],
        ),  # fmt: skip
        (Setting("-", "a share", 0.0, 1.0, True, True), [0.5], [0.0, 1.0]),
        (Setting("-", "a fraction", 0.0, 0.5, high_open=True, optional=True), [0.0, None, 0.499], [0.5, -0.0001]),
        (Setting("-", "a name", choices=("a", "b")), ["a"], ["c", None, 1]),
    ],
)
def test_a_setting_holds_its_range_at_the_ends(spec: Setting, good: list[Any], bad: list[Any]):
    assert all(spec.contains(v) for v in good), good
    assert not any(spec.contains(v) for v in bad), [v for v in bad if spec.contains(v)]


def test_a_setting_out_of_range_is_named_with_what_is_allowed_and_its_unit():
    @dataclasses.dataclass(frozen=True)
    class Demo:
        step: float = setting(0.5, unit="degree", doc="A step.", low=0.0, low_open=True, high=2.0)
        count: int = setting(3, unit="-", doc="A count.", low=2, whole=True)
        spare: float | None = setting(None, unit="m", doc="A length; None: none.", low=0.0)

        def __post_init__(self):
            check_settings(self, KeyError, "Demo.")

    assert Demo(step=2.0, count=2, spare=0.0).step == 2.0
    with pytest.raises(KeyError, match=r"Demo.step = 2.5 is out of range: must be in \(0, 2\] degree"):
        Demo(step=2.5)
    with pytest.raises(KeyError, match=r"Demo.count = 2.0 is not a whole number \(float\): .* >= 2 -"):
        Demo(count=2.0)
    with pytest.raises(KeyError, match=r"Demo.spare = -1 is out of range: must be >= 0 m, or None"):
        Demo(spare=-1)


def test_a_frozen_map_is_a_read_only_hashable_mapping():
    grid = FrozenMap({"a": (1.0, 2.0)})
    assert grid == {"a": (1.0, 2.0)} and hash(grid) == hash(FrozenMap({"a": (1.0, 2.0)}))
    with pytest.raises(TypeError):
        grid["b"] = (3.0,)  # type: ignore[index]


def test_calibrates_method_keys_are_every_calibration_setting_the_yaml_sets(raw):
    """``calibrate:`` is not one library class (its table's keys are the stage's), but every CalibrationSettings
    field is a calibrate key, declared in the library, except the two params.yaml sets elsewhere: the seed (the
    top-level one) and the priors (the documented defaults); and the stage passes each of them on."""
    from pipeline.calibrate import method_settings
    from pipeline.config.schema import CALIBRATION_METHOD_KEYS

    fields = {f.name for f in dataclasses.fields(CalibrationSettings)}
    assert fields - set(CALIBRATION_METHOD_KEYS) == {"fit", "seed", "priors"}
    assert set(CALIBRATION_METHOD_KEYS) <= set(declared(CalibrationSettings))
    for key in CALIBRATION_METHOD_KEYS:
        assert schema.Calibrate.model_fields[key].description == declared(CalibrationSettings)[key].doc
    raw["calibrate"].update(maxiter=7, popsize=3, bootstrap_resamples=11, confidence_level=0.8, posterior_draws=13)
    settings = method_settings(parse_config(raw))
    assert (settings.maxiter, settings.popsize, settings.bootstrap_resamples, settings.confidence_level,
            settings.posterior_draws, settings.seed) == (7, 3, 11, 0.8, 13, raw["seed"])  # fmt: skip
    # the library's range, the project's stricter bound beside it: popsize 2-200 (the example)
    assert _bounds(schema.Calibrate.model_fields["popsize"]) == {"ge": 2, "le": 200}


def test_the_fleet_sections_load_into_the_librarys_fleet_every_field_from_a_key(raw):
    """``fleet:`` and ``distributions:`` together are the library's Fleet (config.fleet_study): each of its fields is
    set from a key, each fleet key is a field of it or an argument of bogie.fleet.sample_fleet, and each distribution
    it samples is the configuration's own object."""
    import inspect

    from bogie.fleet import Fleet, sample_fleet
    from bogie.fleet.sampling.sample import FLEET_QUANTITIES

    config = parse_config(raw)
    fleet = config.fleet_study
    assert isinstance(fleet, Fleet)
    fields = {f.name for f in dataclasses.fields(Fleet)}
    keys = {attribute(key, info)[0] for key, info in schema.Fleet.model_fields.items()}
    arguments = set(inspect.signature(sample_fleet).parameters) - {"fleet", "seed"}
    assert keys == (fields - {"distributions"}) | arguments, (keys, fields, arguments)
    for name in fields - {"distributions"}:
        assert getattr(fleet, name) == getattr(config.fleet, name), name
    assert set(fleet.distributions) == set(FLEET_QUANTITIES) <= set(config.distributions)
    assert all(fleet.distributions[q] is config.distributions[q] for q in FLEET_QUANTITIES)
    from pipeline.validate import as_json

    assert "fleet_study" not in as_json(config)  # derived: data/config.json would repeat fleet: and distributions:


def test_every_fleet_key_is_declared_in_the_library_with_its_unit_range_and_doc():
    """``fleet:``'s keys are made from the declarations of the library's Fleet and of sample_fleet's arguments
    (bogie.settings): each key's doc is the declaration's; a mapping's keys are the declaration's and each value's
    range is the library's, or stricter by a stated project bound; the YAML's tonnes are the library's newtons."""
    from bogie.fleet.sampling.sample import SAMPLING_SETTINGS, Fleet
    from bogie.params import GRAVITY
    from bogie.settings import MapSetting

    specs = {**declared(Fleet), **SAMPLING_SETTINGS}
    for key, info in schema.Fleet.model_fields.items():
        name = attribute(key, info)[0]
        spec = specs[name]
        assert info.description == spec.doc, name
        if not isinstance(spec, MapSetting):
            continue
        entries = info.annotation.model_fields
        assert tuple(entries) == spec.keys, name
        if isinstance(spec.entry, Setting):
            unit = (info.json_schema_extra or {})["unit"]
            factor = 1000.0 * GRAVITY if unit == "t" else 1.0
            for entry in entries.values():
                low, low_open, high, _ = _schema_limits(entry, factor)
                assert (low, low_open) == (spec.entry.low, spec.entry.low_open), name
                assert spec.entry.contains(high), (name, high)
    # the project's stricter bounds, each stated with its reason where the keys are made
    assert _bounds(schema.Fleet.model_fields["legal_group_load_t"].annotation.model_fields["tandem"]) == {
        "gt": 0.0, "le": 200.0}  # fmt: skip
    assert _bounds(schema.Fleet.model_fields["n_bogies"]) == {"ge": 1, "le": 10_000_000}
    # the library lets legal_axle_load be None; the project requires it (the road stage's over-limit counts)
    assert schema.Fleet.model_fields["legal_axle_load_t"].is_required()
    assert not specs["legal_axle_load"].contains(-1.0) and specs["legal_axle_load"].contains(None)


def test_a_fleet_entry_out_of_the_declared_range_is_refused_by_the_library_and_the_yaml_alike(raw):
    from bogie.fleet import Fleet, FleetError

    config = parse_config(raw)
    fleet = config.fleet_study
    with pytest.raises(FleetError, match=r"legal_group_load\['tandem'\] = -1.0"):
        dataclasses.replace(fleet, legal_group_load={**fleet.legal_group_load, "tandem": -1.0})
    raw["fleet"]["legal_group_load_t"]["tandem"] = 0.0
    with pytest.raises(Exception, match=r"fleet.legal_group_load_t.tandem = 0.0: must be a number in \(0, 200\] t"):
        parse_config(raw)
    assert Fleet is type(fleet)
