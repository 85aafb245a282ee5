"""Loading and validating params.yaml.

:func:`load_params` returns the raw mapping (used by the ``figure2`` stage). :func:`load_config` validates the
sections of the Monte Carlo fleet pipeline against the pydantic schema of :mod:`pipeline.config.schema` and
converts every value to SI once, into the frozen dataclasses below: keys ending in ``_mm``, ``_deg``, ``_t`` or
``_s`` / ``_m`` / ``_m_s`` give their unit in the name; everything in a :class:`Config` is SI ([m], [rad], [N],
[s], [kg]). Bad values raise one :class:`ConfigError` (a ``ValueError``) with a line per bad key naming its key
path, the value and the expected form, range and unit (:mod:`pipeline.config.errors`); a key given twice in the
file is refused too (:mod:`pipeline.config.yaml_loader`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from bogie.fleet.constants import GROUP_AXLES, SUSPENSIONS
from bogie.fleet.protocol_settings import StaticProtocol, WimProtocol
from bogie.params import GRAVITY
from pipeline.config.distributions import ROAD_CLASSES
from pipeline.config.errors import RULE_ERROR, ConfigError, error_lines, shown
from pipeline.config.quantities import QUANTITIES, Quantity, si_distribution
from pipeline.config.rules import rule_errors
from pipeline.config.schema import (
    BACKENDS,
    OBSERVED_DIR,
    OTHER_SECTIONS,
    PROTOCOLS,
    SAMPLINGS,
    Params,
)
from pipeline.config.sections import (
    AblationConfig,
    CalibrateConfig,
    Config,
    DesignConfig,
    ExecutionConfig,
    FleetConfig,
    FrozenMap,
    ObservedConfig,
    ProtocolConfig,
    SensitivityConfig,
    SurveyConfig,
)
from pipeline.config.yaml_loader import DuplicateKeyError, read_yaml

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


def load_params(path: str | Path = "params.yaml") -> dict[str, Any]:
    """The parsed params.yaml as a dict (empty if the file is empty).

    Raises
    ------
    ConfigError
        If a mapping gives a key twice (every such key, with both line numbers).
    ValueError
        If the top level is not a mapping.
    yaml.YAMLError
        If the file is not valid YAML.
    """
    with open(path, encoding="utf-8") as fh:
        try:
            data = read_yaml(fh, str(path))
        except DuplicateKeyError as exc:
            keys = [(key, line) for (key, _, _), line in zip(exc.duplicates, str(exc).splitlines())]
            raise ConfigError(keys[0][0], str(exc), keys) from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: the top level must be a mapping of keys to values, got {type(data).__name__}")
    return data


# ---- from the schema to the configuration -------------------------------------------------------------------
def _fleet(fleet: Any) -> FleetConfig:
    tonnes = fleet.legal_group_load_t
    return FleetConfig(
        n_bogies=fleet.n_bogies,
        sampling=fleet.sampling,
        axle_mix=FrozenMap({g: getattr(fleet.axle_mix, g) for g in GROUP_AXLES}),
        suspension_mix=FrozenMap(
            {g: FrozenMap({k: getattr(getattr(fleet.suspension_mix, g), k) for k in SUSPENSIONS}) for g in GROUP_AXLES}
        ),
        presets=FrozenMap({g: getattr(fleet.presets, g) for g in GROUP_AXLES}),
        legal_group_load=FrozenMap({g: getattr(tonnes, g) * 1000.0 * GRAVITY for g in GROUP_AXLES}),
        legal_axle_load=fleet.legal_axle_load_t * 1000.0 * GRAVITY,
    )


def _protocol(protocol: Any) -> ProtocolConfig:
    st, wim = protocol.static, protocol.wim
    return ProtocolConfig(
        run=tuple(protocol.run),
        static=StaticProtocol(
            load_time=st.load_time_s,
            approach_length=st.approach_length_m,
            crawl_speed=st.crawl_speed_m_s,
            settle_time=st.settle_time_s,
            dt=st.dt_s,
            step_tolerance=st.step_tolerance_m,
        ),
        wim=WimProtocol(
            speed=wim.speed_m_s,
            approach_length=wim.approach_length_m,
            dt=wim.dt_s,
            site_before=wim.site_length_before_m,
            site_after=wim.site_length_after_m,
            site_iri=wim.site_iri_m_km,
            sensor_length=wim.sensor_length_m,
            contact_length=wim.contact_length_m,
            accuracy_class=wim.accuracy_class,
            confidence_level=wim.confidence_level,
        ),
    )


def _sensitivity(sens: Any) -> SensitivityConfig:
    return SensitivityConfig(
        group=sens.group,
        base_size=sens.base_size,
        factors=tuple(QUANTITIES[key].name for key in sens.factors),
        bootstrap_resamples=sens.bootstrap_resamples,
        confidence_level=sens.confidence_level,
        protocol=sens.protocol,
    )


def _execution(execution: Any) -> ExecutionConfig:
    return ExecutionConfig(
        backend=execution.backend,
        n_jobs=execution.n_jobs,
        chunk_size=execution.chunk_size,
        dask_scheduler=execution.dask_scheduler,
    )


def _observed(observed: Any) -> ObservedConfig:
    return ObservedConfig(
        path=observed.path,
        format=observed.format,
        min_group_load=observed.min_group_load_t * 1000.0,
        group_spacing=observed.group_spacing_m,
        position=observed.position,
    )


def _calibrate(calibrate: Any) -> CalibrateConfig | None:
    if calibrate is None:
        return None
    return CalibrateConfig(
        protocol=calibrate.protocol,
        n_bogies=calibrate.n_bogies,
        fit=FrozenMap({name: (float(b[0]), float(b[1])) for name, b in calibrate.fit.items()}),
        tilt_step=calibrate.tilt_step_deg,
        site_iri_levels=tuple(float(x) for x in calibrate.site_iri_levels_m_km),
        bootstrap_resamples=calibrate.bootstrap_resamples,
        confidence_level=calibrate.confidence_level,
        maxiter=calibrate.maxiter,
        popsize=calibrate.popsize,
    )


def _design(design: Any) -> DesignConfig | None:
    if design is None:
        return None
    grid = design.grid
    return DesignConfig(
        groups=tuple(design.groups),
        n_conditions=design.n_conditions,
        tilt_step=design.tilt_step_deg,
        grid=FrozenMap({QUANTITIES[k].name: tuple(QUANTITIES[k].to_si(float(x)) for x in v) for k, v in grid.items()}),
        n_space_filling=design.n_space_filling,
        target_share=design.target_share,
        confidence_level=design.confidence_level,
    )


def to_config(params: Params) -> Config:
    """The validated params.yaml sections (:class:`~pipeline.config.schema.Params`) as a :class:`Config`, SI."""
    distributions = {q.name: si_distribution(getattr(params.distributions, key), q) for key, q in QUANTITIES.items()}
    return Config(
        seed=params.seed,
        fleet=_fleet(params.fleet),
        distributions=FrozenMap(distributions),
        protocol=_protocol(params.protocol),
        sensitivity=_sensitivity(params.sensitivity),
        ablation=AblationConfig(n_bogies=params.ablation.n_bogies),
        execution=_execution(params.execution),
        observed=_observed(params.observed),
        survey=SurveyConfig(export_format=params.survey.export_format if params.survey is not None else None),
        calibrate=_calibrate(params.calibrate),
        design=_design(params.design),
    )


def parse_config(raw: Mapping[str, Any]) -> Config:
    """Validate the parsed params.yaml and convert it to SI.

    Parameters
    ----------
    raw
        The mapping read from params.yaml (:func:`load_params`).

    Returns
    -------
    Config
        Every pipeline parameter, SI.

    Raises
    ------
    ConfigError
        Naming every bad key, one line each, with its key path, value and the expected form, range and unit; its
        :attr:`~ConfigError.key` is the first of them.
    """
    if not isinstance(raw, Mapping):
        raise ConfigError("", f"the top level must be a mapping of keys to values, got {type(raw).__name__}")
    try:
        params = Params.model_validate(dict(raw))
    except ValidationError as exc:
        raise _with_rules(raw, exc) from None
    return to_config(params)


def _with_rules(raw: Mapping[str, Any], exc: ValidationError) -> ConfigError:
    """The field errors of ``exc`` and every rule between keys whose keys are valid (pipeline.config.rules), at once."""
    fields = [e for e in exc.errors() if e["type"] != RULE_ERROR]
    lines = error_lines(Params, fields)
    bad = [key for key, _ in lines]
    rules = rule_errors(Params, raw, bad)
    lines += [(r.key, f"{r.key} = {shown(r.value)}: {r.expected}") for r in rules]
    lines = list(dict.fromkeys(lines))
    return ConfigError(lines[0][0], "\n".join(line for _, line in lines), lines)


def load_config(path: str | Path = "params.yaml") -> Config:
    """Read, validate and convert params.yaml (see :func:`parse_config`).

    Raises
    ------
    ConfigError
        For bad keys, a key given twice, or a file that is not a YAML mapping.
    OSError
        If the file cannot be read.
    """
    try:
        raw = load_params(path)
    except ConfigError:
        raise
    except yaml.YAMLError as exc:
        raise ConfigError("", f"{path} is not valid YAML: {exc}") from None
    except ValueError as exc:
        raise ConfigError("", str(exc)) from None
    return parse_config(raw)


def observed_file(observed: ObservedConfig, root: str | Path) -> Path | None:
    """The file of the observed survey under the project root ``root`` (the directory of params.yaml), symlinks
    followed.

    ``observed.path`` names a file in ``observed/`` (the schema checks the name); a symlink there may point to another
    file in ``observed/``, never out of it: what it points to is resolved (every link on the way followed, an
    ``observed/`` that is itself a link included) and must lie in the project's ``observed/`` directory, resolved
    too. A link to a file elsewhere (a secret, ``/proc/self/environ``) is refused before the file is opened, and the
    message names where it points, never what it holds. validate, observed and calibrate all call this.

    Returns None when no survey is given (``observed.path: null``); else the resolved file, so the stage opens the
    file that was checked.

    Raises
    ------
    ConfigError
        Naming ``observed.path``, its value and where it was looked for, if it is not a file, or where it points if
        that is outside ``observed/``.
    """
    if observed.path is None:
        return None
    path = Path(root) / observed.path
    given = f"observed.path = {observed.path!r}"
    try:
        target = path.resolve(strict=True)
    except FileNotFoundError:
        raise ConfigError(
            "observed.path",
            f"{given}: no such file (looked for {path}"
            + (f", a symlink to {Path(os.readlink(path))} which does not exist" if path.is_symlink() else "")
            + "); put the survey's records there or set observed.path: null (docs/observed.md)",
        ) from None
    except (OSError, RuntimeError) as exc:  # a symlink loop, a directory that cannot be searched
        raise ConfigError("observed.path", f"{given}: cannot be resolved ({path}: {exc})") from None
    allowed = Path(root).resolve() / OBSERVED_DIR
    if not target.is_relative_to(allowed):
        raise ConfigError(
            "observed.path",
            f"{given} points to {target}, outside the project's {OBSERVED_DIR}/ ({allowed}; symlinks followed): "
            f"it must be a file in {OBSERVED_DIR}/ or a symlink to one there; copy the survey's records into "
            f"{OBSERVED_DIR}/ (docs/observed.md)",
        )
    if not target.is_file():
        raise ConfigError(
            "observed.path",
            f"{given}: is not a file (looked for {path}); put the survey's records there or set observed.path: null "
            "(docs/observed.md)",
        )
    return target
