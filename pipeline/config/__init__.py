"""params.yaml: its schema, its rules, its errors and the validated configuration the stages read.

The package's modules, in the order a file goes through them: :mod:`~pipeline.config.yaml_loader` reads the YAML
(a key given twice refused), :mod:`~pipeline.config.schema` validates it against the pydantic models (their
distributions in :mod:`~pipeline.config.distributions`), :mod:`~pipeline.config.rules` checks the rules between
keys and the bounds on the costs, :mod:`~pipeline.config.errors` words every bad key as one line, and
:mod:`~pipeline.config.settings` converts the result to SI into the frozen dataclasses (:class:`Config`).

The stages import from here: ``from pipeline.config import Config, ConfigError, load_config``.
"""

from pipeline.config.settings import (
    BACKENDS,
    GROUP_AXLES,
    OTHER_SECTIONS,
    PROTOCOLS,
    QUANTITIES,
    ROAD_CLASSES,
    SAMPLINGS,
    AblationConfig,
    CalibrateConfig,
    Config,
    ConfigError,
    DesignConfig,
    ExecutionConfig,
    FleetConfig,
    FrozenMap,
    ObservedConfig,
    ProtocolConfig,
    Quantity,
    SensitivityConfig,
    StaticProtocol,
    WimProtocol,
    load_config,
    load_params,
    observed_file,
    parse_config,
)

__all__ = [
    "BACKENDS",
    "GROUP_AXLES",
    "OTHER_SECTIONS",
    "PROTOCOLS",
    "QUANTITIES",
    "ROAD_CLASSES",
    "SAMPLINGS",
    "AblationConfig",
    "CalibrateConfig",
    "DesignConfig",
    "Config",
    "ConfigError",
    "ExecutionConfig",
    "FleetConfig",
    "FrozenMap",
    "ObservedConfig",
    "ProtocolConfig",
    "Quantity",
    "SensitivityConfig",
    "StaticProtocol",
    "WimProtocol",
    "load_config",
    "load_params",
    "observed_file",
    "parse_config",
]
