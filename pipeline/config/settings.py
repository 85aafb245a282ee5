"""Loading and validating params.yaml.

:func:`load_params` returns the raw mapping (used by the ``figure2`` stage). :func:`load_config` validates the
sections of the Monte Carlo fleet pipeline against the pydantic schema of :mod:`pipeline.config.schema` and
converts every value to SI once, into the frozen dataclasses below: keys ending in ``_mm``, ``_deg``, ``_t`` or
``_s`` / ``_m`` / ``_m_s`` give their unit in the name; everything in a :class:`Config` is SI ([m], [rad], [N],
[s], [kg]). Bad values raise one :class:`ConfigError` (a ``ValueError``) with a line per bad key naming its key
path, the value and the expected form, range and unit (:mod:`pipeline.config.errors`); a key given twice in the
file is refused too (:mod:`bogie.guarded_yaml`). :func:`check_params`, the ``validate`` stage's check, adds
the observed survey's file (:func:`observed_file`) to those errors.

A calibration's protocol is the survey's (``calibrate.protocol: auto``, the default, follows ``observed.kind``: a
weighbridge file is held against the static readings), and a static calibration fits no WIM quantity: the
configuration holds the protocol itself and ``calibrate.fit`` without them, and ``note`` says which were dropped
(:func:`calibration_note`), so that calibrating to a weighbridge file is the one switch ``observed.kind:
weighbridge``.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from bogie.fleet.constants import GROUP_AXLES, WIM_QUANTITIES
from bogie.fleet.sampling.sample import SAMPLINGS
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.guarded_yaml import DuplicateKeyError, read_yaml_file
from bogie.weighings.files import survey_files
from bogie.weighings.readers import (
    MAX_FILE_BYTES,
    MEMORY_PER_BYTE,
    SURVEY_BASE_MEMORY,
    survey_memory,
    uncompressed_size,
)
from pipeline.config import si
from pipeline.config.distributions import ROAD_CLASSES
from pipeline.config.errors import RULE_ERROR, ConfigError, error_lines, shown
from pipeline.config.quantities import QUANTITIES, Quantity
from pipeline.config.rules import rule_errors, survey_protocol, why_static
from pipeline.config.schema import (
    BACKENDS,
    OBSERVED_DIR,
    OTHER_SECTIONS,
    PROTOCOLS,
    Params,
    observed_path,
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
from pipeline.resources import MEMORY_BUDGET

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
    "SurveyConfig",
    "StaticProtocol",
    "WimProtocol",
    "calibration_note",
    "check_params",
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
    try:
        data = read_yaml_file(path)
    except DuplicateKeyError as exc:
        keys = [(key, line) for (key, _, _), line in zip(exc.duplicates, str(exc).splitlines())]
        raise ConfigError(keys[0][0], str(exc), keys) from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: the top level must be a mapping of keys to values, got {type(data).__name__}")
    return data


def _static_drops(params: Params) -> tuple[str, ...]:
    """The quantities of ``calibrate.fit`` a static calibration does not fit: the WIM site's and sensor's."""
    cal = params.calibrate
    if cal is None or survey_protocol(cal.protocol, params.observed.kind) != "static":
        return ()
    return tuple(name for name in cal.fit if name in WIM_QUANTITIES)


def calibration_note(params: Params) -> str | None:
    """One line saying which quantities of ``calibrate.fit`` a static calibration leaves out, and why; None if none."""
    dropped = _static_drops(params)
    if not dropped:
        return None
    cal = params.calibrate
    why = why_static(cal.protocol)
    kept = ", ".join(name for name in cal.fit if name not in dropped)
    return (
        f"a static calibration ({why}): calibrate.fit's {', '.join(dropped)} left out, a weighbridge has no WIM site "
        f"or sensor; fitting {kept}"
    )


def to_config(params: Params) -> Config:
    """The validated params.yaml sections (:class:`~pipeline.config.schema.Params`) as a :class:`Config`, SI
    (:func:`pipeline.config.si.to_config`), the calibration's protocol resolved and its WIM quantities dropped for a
    static one (:func:`calibration_note`)."""
    config = si.to_config(params)
    if params.calibrate is None:
        return config
    cal = config.calibrate
    dropped = _static_drops(params)
    calibrate = dataclasses.replace(
        cal,
        protocol=survey_protocol(cal.protocol, params.observed.kind),
        fit=FrozenMap((name, bounds) for name, bounds in cal.fit.items() if name not in dropped),
    )
    return dataclasses.replace(config, calibrate=calibrate)


def parse_config(raw: Mapping[str, Any], note: Callable[[str], None] | None = None) -> Config:
    """Validate the parsed params.yaml and convert it to SI.

    Parameters
    ----------
    raw
        The mapping read from params.yaml (:func:`load_params`).
    note
        Called with :func:`calibration_note`'s line when a static calibration drops quantities of ``calibrate.fit``.

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
    if note is not None and (line := calibration_note(params)) is not None:
        note(line)
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


def _read(path: str | Path) -> dict[str, Any]:
    """:func:`load_params`, a file that is not a YAML mapping a :class:`ConfigError` (an OSError is left as it is)."""
    try:
        return load_params(path)
    except ConfigError:
        raise
    except yaml.YAMLError as exc:
        raise ConfigError("", f"{path} is not valid YAML: {exc}") from None
    except ValueError as exc:
        raise ConfigError("", str(exc)) from None


def load_config(path: str | Path = "params.yaml", note: Callable[[str], None] | None = None) -> Config:
    """Read, validate and convert params.yaml (see :func:`parse_config`, and its ``note``).

    Raises
    ------
    ConfigError
        For bad keys, a key given twice, or a file that is not a YAML mapping.
    OSError
        If the file cannot be read.
    """
    return parse_config(_read(path), note)


def check_params(path: str | Path = "params.yaml", note: Callable[[str], None] | None = None) -> Config:
    """:func:`load_config` and the observed survey's file (:func:`observed_file`, under the directory of ``path``),
    every error of both in one :class:`ConfigError`: a file that is missing is named with the bad keys, not once they
    are fixed. The ``validate`` stage's check.

    Raises
    ------
    ConfigError
        For bad keys, a key given twice, a file that is not a YAML mapping, or an ``observed.path`` that names no file
        in ``observed/``.
    OSError
        If params.yaml cannot be read.
    """
    raw, root = _read(path), Path(path).parent
    try:
        config = parse_config(raw, note)
    except ConfigError as exc:
        raise _with_observed_file(exc, raw, root) from None
    path = observed_file(config.observed, root, held=config.calibrate is not None)
    if path is not None and path.is_dir() and config.calibrate is not None and note is not None:
        note(
            f"observed.path {config.observed.path} is a folder of {len(survey_files(path))} files, each a site: the "
            "calibrate stage skips it (one site's survey is calibrated; a network's, issue 46 Must 2, is not yet in)"
        )
    return config


def _with_observed_file(exc: ConfigError, raw: Mapping[str, Any], root: Path) -> ConfigError:
    """``exc`` and, if ``observed.path`` itself is good (no error at it or above it), the error of its file."""
    if any(key in ("", "observed", "observed.path") for key, _ in exc.errors):
        return exc
    observed = raw.get("observed")
    path = observed.get("path") if isinstance(observed, Mapping) else None
    if not isinstance(path, str):
        return exc
    try:
        _survey_file(observed_path(path), root)
    except ConfigError as missing:
        errors = [*exc.errors, ("observed.path", str(missing))]
        return ConfigError(exc.key, "\n".join(line for _, line in errors), errors)
    return exc


def _survey_folder(folder: Path, allowed: Path, given: str) -> Path:
    """A folder of survey files, each a site (:func:`bogie.weighings.files.survey_files`: its files not named
    ``.*`` nor ``*.dvc``); each must resolve inside ``allowed`` (the project's ``observed/``) and at least one be
    there."""
    try:
        files = survey_files(folder)
    except ValueError as exc:
        raise ConfigError("observed.path", f"{given}: {str(exc).removeprefix('path: ')}") from None
    for file, _ in files:
        target = file.resolve()
        if not target.is_relative_to(allowed):
            raise ConfigError(
                "observed.path",
                f"{given}: its file {file.name} points to {target}, outside the project's {OBSERVED_DIR}/ ({allowed}; "
                f"symlinks followed): copy the survey's records into {OBSERVED_DIR}/ (docs/observed.md)",
            )
    return folder


def observed_file(observed: ObservedConfig, root: str | Path, held: bool = True) -> Path | None:
    """The file of the observed survey under the project root ``root`` (the directory of params.yaml), symlinks
    followed.

    ``observed.path`` names a file in ``observed/`` (the schema checks the name); a symlink there may point to another
    file in ``observed/``, never out of it: what it points to is resolved (every link on the way followed, an
    ``observed/`` that is itself a link included) and must lie in the project's ``observed/`` directory, resolved
    too. A link to a file elsewhere (a secret, ``/proc/self/environ``) is refused before the file is opened, and the
    message names where it points, never what it holds. validate, observed and calibrate all call this.

    Returns None when no survey is given (``observed.path: null``); else the resolved file, so the stage opens the
    file that was checked.

    ``held``: whether a stage will hold the survey's groups in memory (calibrate does; the observed stage streams
    the file, spilling its groups to disk, in memory independent of its length): such a file must be at most
    :data:`bogie.weighings._records.MAX_FILE_BYTES` of records and its estimated memory
    (:func:`bogie.weighings._records.survey_memory`) within the budget.

    Raises
    ------
    ConfigError
        Naming ``observed.path``, its value and where it was looked for, if it is not a file, or where it points if
        that is outside ``observed/``.
    """
    return None if observed.path is None else _survey_file(observed.path, root, held)


def _survey_file(name: str, root: str | Path, held: bool = True) -> Path:
    """:func:`observed_file` of the path ``name`` (``observed.path``, checked by the schema)."""
    path = Path(root) / name
    given = f"observed.path = {name!r}"
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
    if target.is_dir():  # a survey of several sites (issue 46): the calibration does not hold it (it skips)
        return _survey_folder(target, allowed, given)
    if not target.is_file():
        raise ConfigError(
            "observed.path",
            f"{given}: is not a file (looked for {path}); put the survey's records there or set observed.path: null "
            "(docs/observed.md)",
        )
    if not held:
        return target
    records = uncompressed_size(target)
    need = survey_memory(target)
    if records > MAX_FILE_BYTES or need > MEMORY_BUDGET:
        raise ConfigError(
            "observed.path",
            f"{given}: its {records / 2**30:.2f} GiB of records are more than the calibrate stage, which holds the "
            f"survey's groups in memory, reads ({MAX_FILE_BYTES / 2**30:g} GiB, bogie.weighings._records."
            f"MAX_FILE_BYTES; about {need / 2**30:.2f} GiB of memory at {SURVEY_BASE_MEMORY / 2**20:.0f} MiB and "
            f"{MEMORY_PER_BYTE} bytes a byte, SURVEY_BASE_MEMORY and MEMORY_PER_BYTE, against the memory budget of "
            f"{MEMORY_BUDGET / 2**30:g} GiB, pipeline.resources.MEMORY_BUDGET): split the survey, give a part of it, "
            "or set calibrate: null (the observed stage and bogie weighings stream a file of any length)",
        )
    return target
