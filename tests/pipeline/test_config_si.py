"""The configuration is made from the schema: each params.yaml key declared once, converted by its declared unit."""

from __future__ import annotations

import dataclasses
import math
import pickle
from typing import Annotated

import pytest
from pydantic import BaseModel, Field

from bogie.params import GRAVITY
from pipeline.config import load_params, parse_config, schema, sections
from pipeline.config.distributions import DistributionSpec
from pipeline.config.quantities import QUANTITIES
from pipeline.config.si import FrozenMap, ToConfig, attribute, config_class, to_config


@pytest.fixture()
def raw():
    return load_params("params.yaml")


def test_every_schema_key_is_one_attribute_of_its_config_class_and_nothing_else():
    pairs = [
        (schema.Params, sections.Config),
        (schema.Fleet, sections.FleetConfig),
        (schema.Protocols, sections.ProtocolConfig),
        (schema.Static, sections.StaticProtocol),
        (schema.Wim, sections.WimProtocol),
        (schema.Sensitivity, sections.SensitivityConfig),
        (schema.Ablation, sections.AblationConfig),
        (schema.Execution, sections.ExecutionConfig),
        (schema.Observed, sections.ObservedConfig),
        (schema.Survey, sections.SurveyConfig),
        (schema.Calibrate, sections.CalibrateConfig),
        (schema.Design, sections.DesignConfig),
    ]
    for model, cls in pairs:
        expected = [attribute(k, i)[0] for k, i in model.model_fields.items() if k not in schema.OTHER_SECTIONS]
        assert [f.name for f in dataclasses.fields(cls)] == expected, model.__name__


def test_keys_lose_their_unit_suffix_and_values_are_converted_by_the_declared_unit(raw):
    raw["fleet"]["legal_axle_load_t"] = 10.0
    raw["fleet"]["legal_group_load_t"] = {"tandem": 18.0, "triaxle": 24.0}
    raw["observed"]["min_group_load_t"] = 15.5
    raw["protocol"]["wim"]["site_length_before_m"] = 40.0
    raw["protocol"]["wim"]["speed_m_s"] = 20.0
    raw["calibrate"]["site_iri_levels_m_km"] = [1.0, 3.0]
    raw["calibrate"]["fit"]["site_iri_m_km"] = [1.0, 3.0]
    raw["design"]["grid"] = {"contact_roll_radius_mm": [0, 50], "bush_stiffness": [10]}
    config = parse_config(raw)
    assert config.fleet.legal_axle_load == 10.0 * 1000.0 * GRAVITY  # t -> N: a load
    assert dict(config.fleet.legal_group_load) == {"tandem": 18_000.0 * GRAVITY, "triaxle": 24_000.0 * GRAVITY}
    assert config.observed.min_group_load == 15_500.0  # t -> kg: a mass, as the weighings give it
    assert config.protocol.wim.site_length_before == 40.0 and config.protocol.wim.speed == 20.0
    assert config.calibrate.site_iri_levels == (1.0, 3.0)  # m/km, the IRI's own unit
    assert config.calibrate.fit["site_iri_m_km"] == (1.0, 3.0)  # the bounds in the unit of their names
    assert config.design.tilt_step_deg == raw["design"]["tilt_step_deg"]  # the grid's step stays in degrees
    assert dict(config.design.grid) == {"contact_roll_radius": (0.0, 0.05), "bush_stiffness": (10.0,)}
    assert config.sensitivity.factors == tuple(QUANTITIES[k].name for k in raw["sensitivity"]["factors"])
    tilt = config.distributions["chassis_tilt"]
    assert tilt.support == pytest.approx(tuple(math.radians(raw["distributions"]["chassis_tilt_deg"][b])
                                               for b in ("low", "high")))  # fmt: skip
    assert set(config.distributions) == {q.name for q in QUANTITIES.values()}


def test_an_absent_optional_section_is_none_and_an_absent_survey_writes_nothing(raw):
    for key in ("calibrate", "design", "survey"):
        raw.pop(key)
    config = parse_config(raw)
    assert config.calibrate is None and config.design is None
    assert config.survey == sections.SurveyConfig(export_format=None)


def test_each_distribution_is_built_once(raw, monkeypatch):
    built = []
    original = DistributionSpec.build

    def counted(self):
        built.append(type(self).__name__)
        return original(self)

    monkeypatch.setattr(DistributionSpec, "build", counted)
    parse_config(raw)
    # one per quantity in the schema; the rules read the tilt's bounds from the file as written once more
    assert len(built) == len(QUANTITIES) + 1


def test_a_tonne_field_must_say_whether_it_is_a_load_or_a_mass():
    class Bad(BaseModel):
        load_t: float = Field(json_schema_extra={"unit": "t"})

    with pytest.raises(TypeError, match=r"'load_t' is in t: its json_schema_extra must give si"):
        config_class(Bad)


def test_a_key_whose_name_does_not_end_in_its_unit_is_refused():
    class Bad(BaseModel):
        speed: float = Field(json_schema_extra={"unit": "m/s"})

    with pytest.raises(TypeError, match=r"'speed' is in m/s but its name does not end in '_m_s'"):
        config_class(Bad)


def test_a_field_with_its_own_conversion_and_a_map_of_fixed_keys():
    class Loads(BaseModel):
        as_map: bool = False  # a plain field: not the marker

    class Shares(BaseModel):
        left: float = Field(json_schema_extra={"unit": "t", "si": "kg"})
        right: float = Field(json_schema_extra={"unit": "t", "si": "kg"})

    Shares.as_map = True

    class Section(BaseModel):
        names: Annotated[list[str], ToConfig(lambda v: "+".join(v), "joined")]
        shares_t: Shares = Field(json_schema_extra={"unit": "t", "si": "kg"})
        gap_m: float = Field(json_schema_extra={"unit": "m"})

    converted = to_config(Section(names=["a", "b"], shares_t=Shares(left=1.0, right=2.5), gap_m=0.5))
    assert (converted.names, converted.gap) == ("a+b", 0.5)
    assert converted.shares == FrozenMap({"left": 1000.0, "right": 2500.0})
    assert "joined" in type(converted).__doc__


def test_config_classes_pickle_by_their_module_path(raw):
    config = parse_config(raw)
    assert pickle.loads(pickle.dumps(config)) == config
    assert type(config.fleet).__module__ == "pipeline.config.sections"


def test_a_bad_distribution_is_still_reported_with_its_key(raw):
    raw["distributions"]["tyre_wear_mm"] = {"kind": "uniform", "low": 5.0, "high": 1.0}
    with pytest.raises(ValueError, match=r"distributions\.tyre_wear_mm"):
        parse_config(raw)
