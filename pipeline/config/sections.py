"""The validated configuration: one frozen dataclass per params.yaml section, made from the schema, in SI.

Each key is declared once, in :mod:`pipeline.config.schema`; the classes here are made from its models by
:func:`pipeline.config.si.config_class` (an attribute per key, named and converted by the unit its field declares;
the table is in :mod:`pipeline.config.si`), and :func:`pipeline.config.settings.load_config` fills them. The
protocols' settings are the library's own classes (:mod:`bogie.fleet.weighing.settings`). Every attribute is SI, but
for the IRI (m/km, its own unit) and the tilt grids' steps (``tilt_step_deg``, named with their unit, degree).
"""

from __future__ import annotations

from typing import Any

from bogie.fleet.sampling.sample import FLEET_QUANTITIES, Fleet
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.settings import declared
from pipeline.config import schema
from pipeline.config.si import FrozenMap, config_class

__all__ = [
    "AblationConfig",
    "CalibrateConfig",
    "Config",
    "DesignConfig",
    "ExecutionConfig",
    "FleetConfig",
    "FrozenMap",
    "ObservedConfig",
    "ProtocolConfig",
    "SensitivityConfig",
    "StaticProtocol",
    "SurveyConfig",
    "WimProtocol",
]

FleetConfig = config_class(schema.Fleet, "FleetConfig")
ProtocolConfig = config_class(schema.Protocols, "ProtocolConfig")
SensitivityConfig = config_class(schema.Sensitivity, "SensitivityConfig")
AblationConfig = config_class(schema.Ablation, "AblationConfig")
ExecutionConfig = config_class(schema.Execution, "ExecutionConfig")
ObservedConfig = config_class(schema.Observed, "ObservedConfig")
SurveyConfig = config_class(schema.Survey, "SurveyConfig")
CalibrateConfig = config_class(schema.Calibrate, "CalibrateConfig")
DesignConfig = config_class(schema.Design, "DesignConfig")


def _fleet_study(config: Any) -> Fleet:
    """The fleet study's fleet, ``fleet:`` and ``distributions:`` together, as the library's
    :class:`bogie.fleet.Fleet` (SI): what :func:`bogie.fleet.sample_fleet` samples."""
    fleet = config.fleet
    return Fleet(
        distributions={name: config.distributions[name] for name in FLEET_QUANTITIES},
        **{name: getattr(fleet, name) for name in declared(Fleet)},
    )


#: the whole file; ``figure2`` (and the other sections of schema.OTHER_SECTIONS) are read by their own stages
Config = config_class(
    schema.Params, "Config", skip=schema.OTHER_SECTIONS, properties={"fleet_study": property(_fleet_study)}
)
