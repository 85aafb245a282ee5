"""The distributions' parameter rules are the library's (issue 42 Must 1): params.yaml's form of each kind is made
from its class (pipeline.config.distributions.spec_model), and the bounds the class declares as data (``positive``,
``nonnegative``) are the ones its own check enforces, so the two cannot drift apart."""

import dataclasses
import typing

import pytest

from bogie.fleet.sampling.distributions import KINDS, ParameterError

#: a valid set of parameters of each kind, worked by hand (low < high, sd > 0, weights one per value)
VALID = {
    "constant": {"value": 1.0},
    "uniform": {"low": 1.0, "high": 2.0},
    "loguniform": {"low": 1.0, "high": 10.0},
    "normal": {"mean": 0.0, "sd": 1.0},
    "truncnormal": {"mean": 0.0, "sd": 1.0, "low": -1.0, "high": 1.0},
    "lognormal": {"median": 2.0, "sigma": 0.5, "low": 0.5, "high": 8.0},
    "choice": {"values": (1.0, 2.0), "weights": (1.0, 3.0)},
}


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_each_declared_bound_is_the_one_the_class_enforces(kind):
    cls = KINDS[kind]
    cls(**VALID[kind])  # the hand-worked parameters are valid
    for name in cls.positive:
        with pytest.raises(ParameterError) as err:
            cls(**{**VALID[kind], name: 0.0})
        assert err.value.param == name
        cls(**{**VALID[kind], name: VALID[kind][name]})
    for name in cls.nonnegative:
        with pytest.raises(ParameterError) as err:
            cls(**{**VALID[kind], name: -1e-9})
        assert err.value.param == name
        if not (kind == "lognormal" and name == "low"):
            continue
        cls(**{**VALID[kind], name: 0.0})  # zero itself is allowed


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_params_yaml_takes_each_kinds_parameters_and_bounds_from_its_class(kind):
    from pipeline.config.distributions import NumericSpec

    models = {
        m.model_fields["kind"].annotation.__args__[0]: m for m in typing.get_args(typing.get_args(NumericSpec)[0])
    }
    model, cls = models[kind], KINDS[kind]
    assert list(model.model_fields) == ["kind", *(f.name for f in dataclasses.fields(cls))]
    for name in cls.positive:
        assert [c.gt for c in model.model_fields[name].metadata if hasattr(c, "gt")] == [0.0], name
    for name in cls.nonnegative:
        assert [c.ge for c in model.model_fields[name].metadata if hasattr(c, "ge")] == [0.0], name
    for name in cls.dimensionless:
        assert model.model_fields[name].json_schema_extra == {"unit": "-"}
    assert model.sampler is cls
