"""The schema of params.yaml: pydantic models of the sections the Monte Carlo pipeline reads, in params.yaml units.

Types are strict (a bool or a numeric text is not a number, an integer field takes no float), unknown keys are
refused, ranges are field constraints, maps with fixed keys (``axle_mix: {tandem, triaxle}``) are sub-models and
the distributions are unions tagged by ``kind`` (:mod:`pipeline.config.distributions`). A rule within one value
(a list's distinct items, a power of 2) is a field validator raising :func:`pipeline.config.errors.config_error`;
the rules that span keys, in a section or between sections, are :mod:`pipeline.config.rules`, which
:class:`Params` runs (each rule as soon as its own keys are valid, every broken one reported). Every field's
``json_schema_extra`` gives its ``unit`` (as in params.yaml), and ``what`` it is or the ``expected`` form in words,
for the error messages.
"""

from __future__ import annotations

from pathlib import PurePosixPath
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, Field, ValidatorFunctionWrapHandler, create_model, model_validator

from bogie.fleet.calibration.settings import CalibrationSettings
from bogie.fleet.constants import (
    CALIBRATION_QUANTITIES,
    GROUP_AXLES,
    PROTOCOLS,
    READ_TIME,
    SITE_IRI_RANGE,
    SURVEY_PROTOCOLS,
)
from bogie.fleet.design.settings import DesignSettings
from bogie.fleet.sampling.sample import SAMPLING_SETTINGS
from bogie.fleet.sampling.sample import Fleet as FleetStudy
from bogie.fleet.weighing.settings import StaticProtocol, WimProtocol
from bogie.settings import declared
from bogie.weighings.settings import GROUP_FILTER
from pipeline.config.distributions import Strict
from pipeline.config.errors import config_error, rule_error
from pipeline.config.fields import (
    GroupPresets,
    declared_fields,
    distinct,
    integer,
    library_model,
    named,
    number,
    power_of_two,
)
from pipeline.config.quantities import QUANTITIES, Distributions
from pipeline.config.rules import DASK_ADDRESS, DESIGN_FACTORS, rule_errors
from pipeline.config.si import FrozenMap, ToConfig
from pipeline.resources import MAX_JOBS

BACKENDS: tuple[str, ...] = ("loky", "dask")
#: the record formats of bogie.weighings (``auto`` and formats.FORMATS), written out here so that every stage's code
#: (all of them import this schema) does not depend on the readers; a test keeps them equal. ``auto``: the one layout
#: the file's first lines fit (bogie.weighings.readers.detect_format)
OBSERVED_FORMATS: tuple[str, ...] = ("auto", "csv", "mon", "castor", "bedit", "ditis", "tmg2001", "tmg2013")
#: the formats the survey stage can write the fleet's WIM readings in (bogie.weighings.writers.write_weighings):
#: not the TMG editions, whose records need a station, an FHWA vehicle class and a compass direction the simulated
#: fleet does not have
EXPORT_FORMATS: tuple[str, ...] = OBSERVED_FORMATS[1:6]
#: the directory, relative to the project root, an observed survey's file must be in: dvc.yaml tracks it as a
#: dependency of the observed stage, so that a changed file reruns the stage (docs/observed.md)
OBSERVED_DIR = "observed"

#: top-level sections that other stages read themselves (the schema accepts them without looking inside)
OTHER_SECTIONS: tuple[str, ...] = ("figure2",)


# ---- sections ----------------------------------------------------------------------------------------------------
# ``fleet:``: the library's Fleet (but its distributions, which are ``distributions:``) and sample_fleet's other
# arguments, each key's type, range, unit and doc declared there once (bogie.settings); here only the YAML's units, the
# project's stricter bounds and rules, with why
_FLEET_KEYS = {
    **declared_fields(
        "Fleet", SAMPLING_SETTINGS, ["n_bogies", "sampling"], names={"sampling": "sampling method"},
        bounds={"n_bogies": [("le", 10_000_000, "a sanity cap: 10^7 bogies need about 30 GiB at the pipeline's peak "
                              "(pipeline.sample.BYTES_PER_BOGIE)")]},
    ),
    **declared_fields(
        "Fleet", FleetStudy, ["axle_mix", "suspension_mix", "presets", "legal_group_load", "legal_axle_load"],
        units={"legal_group_load": "t", "legal_axle_load": "t"},
        names={"presets": "preset or bogie file"},
        bounds={
            "legal_group_load_t": [("le", 200.0, "a sanity cap, far above any legal group load (24 t for an EU "
                                    "tri-axle): more was most likely given in another unit")],
            "legal_axle_load_t": [("le", 100.0, "a sanity cap, far above any legal axle load (10-11.5 t in the EU)")],
        },
        required={"legal_axle_load": "the road stage's over-limit counts and the survey's need it"},
        maps={"presets": GroupPresets},
    ),
}  # fmt: skip
Fleet = create_model(
    "Fleet", __base__=Strict, __doc__="``fleet:`` the fleet study (see :class:`bogie.fleet.Fleet`).",
    **{key: made for fields in _FLEET_KEYS.values() for key, made in fields.items()},
)  # fmt: skip


# ``protocol.static`` and ``protocol.wim``: the library's settings classes, each key, type, range, unit and doc
# declared there once (bogie.settings); here only the YAML's units and the project's stricter bounds, with why
Static = library_model(
    "Static", StaticProtocol, "``protocol.static:`` the static weighbridge (see :class:`bogie.fleet.StaticProtocol`).",
    bounds={
        "load_time_s": [("le", 600.0, "a sanity cap: ten minutes")],
        "approach_length_m": [("le", 1000.0, "a sanity cap: a kilometre")],
        "crawl_speed_m_s": [
            ("ge", 0.1, "a crawl slower than 0.1 m/s is no longer a drive onto a weighbridge (and millions of steps)"),
            ("le", 5.0, "walking pace or a little faster; more is not a static weighing"),
        ],
        "settle_time_s": [
            ("ge", READ_TIME, "the reading is the mean over the last READ_TIME of the settle: a shorter one has "
             "nothing to read"),
            ("le", 600.0, "a sanity cap: ten minutes"),
        ],
        "dt_s": [("le", 0.01, "a sanity cap: 10 ms")],
        "step_tolerance_m": [("le", 1e-4, "1e-4 m per step is already a tenth of a millimetre, far coarser than a "
                              "reading needs")],
    },
)  # fmt: skip
Wim = library_model(
    "Wim", WimProtocol, "``protocol.wim:`` the weigh-in-motion pass (see :class:`bogie.fleet.WimProtocol`).",
    units={"sensor_vehicle_error": "%", "sensor_axle_error": "%"},
    names={"sensor": "sensor type"},
    bounds={
        "speed_m_s": [
            ("ge", 1.0, "the slowest a low-speed WIM site weighs at (they run at 5-15 km/h); slower is static"),
            ("le", 50.0, "180 km/h: above it the value was most likely given in km/h"),
        ],
        "approach_length_m": [("le", 10_000.0, "a sanity cap: ten kilometres")],
        "dt_s": [("le", 0.01, "a sanity cap: 10 ms")],
        "site_length_before_m": [("le", 1000.0, "COST 323 sets its requirements over 50 m before the sensor")],
        "site_length_after_m": [("le", 1000.0, "and 25 m after it")],
        "site_iri_m_km": [
            ("ge", 0.3, "a very smooth new pavement"),
            ("le", 6.0, "above 6 m/km no site class applies (COST 323 class III ends at 4)"),
        ],
        "sensor_length_m": [("le", 5.0, "about the longest weighing length (a culvert or a long platform)")],
        "contact_length_m": [("le", 1.0, "a truck tyre's contact patch is 0.15-0.30 m long")],
    },
)  # fmt: skip


Protocol = Literal[PROTOCOLS]  # type: ignore[valid-type]


class Protocols(Strict):
    """``protocol:`` which protocols run, and the settings of each."""

    run: Annotated[list[Protocol], distinct("protocol")] = named("protocol", min_length=1)
    """The protocols the simulation runs: ``static`` and/or ``wim``."""
    static: Static
    """The static weighbridge's settings."""
    wim: Wim
    """The weigh-in-motion pass's settings."""


def _numeric_factors(names: list[str]) -> list[str]:
    for i, name in enumerate(names):
        if QUANTITIES[name].labels:
            numeric = ", ".join(k for k, q in QUANTITIES.items() if not q.labels)
            expected = (
                f"is categorical ({QUANTITIES[name].yaml_unit} labels): a Sobol' factor must be a numeric quantity, "
                f"one of {numeric}"
            )
            raise config_error(f"[{i}]", name, expected)
    return names


class Sensitivity(Strict):
    """``sensitivity:`` the Sobol' design."""

    group: Literal[tuple(GROUP_AXLES)] = named("axle group")  # type: ignore[valid-type]
    """Axle group whose base bogie the design perturbs."""
    base_size: Annotated[int, AfterValidator(power_of_two)] = integer(2, 2**20)
    """Saltelli base sample size N, a power of 2."""
    # the factors are keys of distributions:
    factors: Annotated[  # type: ignore[valid-type]
        list[Literal[tuple(QUANTITIES)]],
        distinct("factor"),
        AfterValidator(_numeric_factors),
        ToConfig(lambda keys: tuple(QUANTITIES[key].name for key in keys), "SI names of the quantities"),
    ] = named("factor", min_length=1)
    """The perturbed quantities, keys of ``distributions:``; in the config their SI names (``tyre_wear`` stands for
    every axle's wear, one SALib group)."""
    bootstrap_resamples: int = integer(1, 100_000)
    """Bootstrap resamples for the confidence intervals."""
    confidence_level: float = number("[-]", gt=0.0, lt=1.0)
    """Confidence level of those intervals."""
    protocol: Protocol = named("protocol")
    """Protocol whose results are analysed."""


class Ablation(Strict):
    """``ablation:`` the switch-off ablation of the first ``n_bogies`` fleet bogies."""

    n_bogies: int = integer(1)
    """The first ``n_bogies`` fleet bogies, each with the inhibitors removed in turn."""


_ADDRESS = DASK_ADDRESS
#: the schemes of dask.distributed's network transports a scheduler listens on (``inproc`` is in-process only)
DASK_SCHEMES: tuple[str, ...] = ("tcp", "tls", "ucx", "ws", "wss")


def _address(value: str | None) -> str | None:
    if value is None:
        return None
    # a scheduler file (its path): told from an address by its ending, .json, our convention (dask's docs name it
    # scheduler.json; dask itself takes any name), so that "localhost:8786" without its scheme is still refused
    if "://" not in value and value.endswith(".json") and value.strip() == value:
        return value
    scheme, sep, host = value.partition("://")
    if not sep or scheme.lower() not in DASK_SCHEMES or not host.strip("/"):
        schemes = ", ".join(f"{s}://" for s in DASK_SCHEMES)
        raise config_error(
            "",
            value,
            f"must be null or {_ADDRESS}: a scheme of {schemes} and a host, or a path "
            "ending in .json (the file dask scheduler --scheduler-file writes)",
        )
    return value


class Execution(Strict):
    """``execution:`` how the simulation runs."""

    backend: Literal[BACKENDS] = named("backend")  # type: ignore[valid-type]
    """``loky`` (processes on this machine) or ``dask`` (a dask.distributed cluster)."""
    # at most pipeline.resources.MAX_JOBS; each stage runs at most this machine's cores (resources.worker_count)
    n_jobs: int = integer(1, MAX_JOBS)
    """Worker processes (at most this machine's cores are used)."""
    chunk_size: int = integer(1, 10_000_000)
    """Samples per chunk of work, the unit of resume."""
    dask_scheduler: Annotated[str | None, AfterValidator(_address)] = Field(
        json_schema_extra={"expected": f"null or {_ADDRESS}"}
    )
    """The dask scheduler's address, or the path of its scheduler file (``dask scheduler --scheduler-file``;
    relative to the project root), for backend ``dask``; None: ``DASK_SCHEDULER_ADDRESS`` (dask's own variable)."""


def observed_path(value: str | None) -> str | None:
    """A path inside :data:`OBSERVED_DIR`, relative to the project root, as a normalised POSIX path."""
    if value is None:
        return None
    if "\0" in value:  # no file system takes it: a path cannot be resolved with one (it raised a traceback)
        raise config_error("", value, "a path must not contain a NUL byte (\\0); name a file in observed/")
    path = PurePosixPath(value.replace("\\", "/"))
    parts = [p for p in path.parts if p != "."]
    inside = not path.is_absolute() and ".." not in parts and len(parts) >= 2 and parts[0] == OBSERVED_DIR
    if not inside:
        raise config_error(
            "",
            value,
            f"must be null or a file or folder in {OBSERVED_DIR}/, relative to the project root (e.g. "
            f"{OBSERVED_DIR}/site.mon, or {OBSERVED_DIR}/network for a folder of files, each a site): "
            f"dvc.yaml tracks {OBSERVED_DIR}/, so only there does a changed file rerun the stage",
        )
    return "/".join(parts)


class _ObservedFile(Strict):
    """``observed:`` an observed survey (WIM or weighbridge records) to hold against the simulated fleet."""

    path: Annotated[str | None, AfterValidator(observed_path)] = Field(
        json_schema_extra={"expected": f"null or a file or folder in {OBSERVED_DIR}/, e.g. {OBSERVED_DIR}/site.mon"}
    )
    """The file of records, or a folder of files each a site (issue 46), a POSIX path relative to the project root
    inside ``observed/``; None: no survey given."""
    # a default, so that a params.yaml written before the key still reads: a WIM file, as it then had to be
    kind: Literal[tuple(SURVEY_PROTOCOLS)] = named("survey kind", default="wim")  # type: ignore[valid-type]
    """What the file's records are: ``wim`` (weigh-in-motion readings) or ``weighbridge`` (static weighings); a
    calibration with ``calibrate.protocol: auto`` holds them against the readings of that protocol."""
    format: Literal[OBSERVED_FORMATS] = named("record format")  # type: ignore[valid-type]
    """Its record format: ``auto`` (the one layout the file's first lines fit), ``csv``, ``mon``, ``castor``, ``bedit``
    or ``ditis`` (``docs/weighings.md``)."""


# the group filter's keys: bogie.weighings.settings.GROUP_FILTER's declarations (filter_groups', axle_groups' and
# check_resolution_kg's own), with the YAML's tonnes; resolution_kg may be left out (None), so that a params.yaml
# written before the key still reads, and is checked against the format's weight unit by the reader
Observed = create_model(
    "Observed", __base__=_ObservedFile, __doc__=_ObservedFile.__doc__,
    **{key: made for fields in declared_fields(
        "Observed", GROUP_FILTER, list(GROUP_FILTER), units={"min_group_load": "t"},
        names={"position": "group position"},
    ).values() for key, made in fields.items()},
)  # fmt: skip


class Survey(Strict):
    """``survey:`` what the survey stage writes besides its statistics."""

    # null: nothing; a format: data/survey/fleet_wim.<format>, the fleet study's WIM readings as records
    export_format: Literal[EXPORT_FORMATS] | None = named("record format")  # type: ignore[valid-type]
    """None, or the record format (``csv``, ``mon``, ``castor``, ``bedit``, ``ditis``) in which the fleet study's WIM
    readings are written to ``data/survey/fleet_wim.<format>``."""


class _CalibrateTable(Strict):
    """``calibrate:`` the fleet quantities fitted to the observed survey."""

    protocol: Literal[("auto", *PROTOCOLS)] = named("protocol")  # type: ignore[valid-type]
    """The protocol whose readings are held against the survey: ``auto``, the one of ``observed.kind`` (a WIM file:
    ``wim``, a weighbridge file: ``static``), or ``wim`` or ``static`` whatever the file is. In the config, the
    protocol itself; a static calibration fits no WIM quantity (``calibrate.fit``'s are dropped, with a note)."""
    n_bogies: int = integer(20, 100_000)
    """The calibration fleet: the first ``n_bogies`` fleet bogies, each as a steel and an air group."""
    fit: Annotated[
        dict[str, list[float]],
        ToConfig(lambda fit: FrozenMap({n: (float(b[0]), float(b[1])) for n, b in fit.items()}), "unit of each name"),
    ] = Field(
        min_length=1,
        json_schema_extra={
            "expected": "a mapping naming at least one quantity to fit, each [low, high]: "
            + ", ".join(CALIBRATION_QUANTITIES),
            "entry": "[low, high], two numbers in the unit of the quantity's name",
        },
    )
    """Quantity -> (low, high): the bounds of each fitted quantity, in the unit of its name."""
    tilt_step_deg: float = number("degree", gt=0.0, le=1.0)
    """Step of the chassis-tilt grid the readings are tabulated on."""
    # each level within the range calibrate fits the site's roughness over (CALIBRATION_QUANTITIES)
    site_iri_levels_m_km: list[Annotated[float, Field(ge=SITE_IRI_RANGE[0], le=SITE_IRI_RANGE[1])]] = Field(
        min_length=2,
        json_schema_extra={
            "unit": "m/km",
            "expected": "a list of two or more increasing roughnesses in "
            f"[{SITE_IRI_RANGE[0]:g}, {SITE_IRI_RANGE[1]:g}] m/km",
        },
    )
    """The WIM site roughnesses the readings are tabulated at."""


#: the keys of ``calibrate:`` that are the library's CalibrationSettings' declared settings, in its order (declared
#: there, bogie.settings), but its ``seed``, params.yaml's top-level one; its ``fit`` is the key above, its ``priors``
#: the documented defaults
CALIBRATION_METHOD_KEYS: tuple[str, ...] = tuple(name for name in declared(CalibrationSettings) if name != "seed")
Calibrate = create_model(
    "Calibrate",
    __base__=_CalibrateTable,
    __doc__=_CalibrateTable.__doc__,
    **{key: spec for made in declared_fields("Calibrate", CalibrationSettings, list(CALIBRATION_METHOD_KEYS), bounds={
        "bootstrap_resamples": [("le", 10_000, "a sanity cap: 10^4 refits")],
        "maxiter": [("le", 10_000, "a sanity cap: 10^4 generations")],
        "popsize": [("le", 200, "a sanity cap: 200 a fitted quantity")],
        "posterior_draws": [("le", 1_000_000, "a sanity cap: 10^6 draws")],
        "chains": [("le", 64, "a sanity cap: 64 chains")],
    }).values() for key, spec in made.items()},
)  # fmt: skip


def _si_grid(grid: dict[str, list[float]]) -> FrozenMap:
    """The design grid by the factors' SI names, its levels in SI."""
    return FrozenMap({QUANTITIES[k].name: tuple(QUANTITIES[k].to_si(float(x)) for x in v) for k, v in grid.items()})


# ``design:``: the library's DesignSettings, its number settings declared there (bogie.settings)
Design = library_model(
    "Design", DesignSettings, "``design:`` the controlled experiment over the design factors.",
    bounds={
        "n_conditions": [("le", 100_000, "a sanity cap: 10^5 conditions a design")],
        "tilt_step_deg": [("le", 2.0, "a sanity cap: 2 degree")],
        "n_space_filling": [("le", 10_000, "a sanity cap: 10^4 designs a group")],
    },
    custom={
        "groups": (
            "groups",
            Annotated[list[Literal[tuple(GROUP_AXLES)]], distinct("axle group")],  # type: ignore[valid-type]
            named("axle group", min_length=1, description="The axle groups whose designs are studied."),
        ),
        "grid": (
            "grid",
            Annotated[dict[str, list[float]], ToConfig(_si_grid, "SI, by SI name")],
            Field(
                min_length=1,
                json_schema_extra={
                    "expected": "a mapping naming at least one design factor, each with its levels: "
                    + ", ".join(DESIGN_FACTORS),
                    "entry": "a list of one or more levels, numbers in the unit of the factor's name",
                },
                description="A design factor (a key of ``distributions:``) -> its levels, in the unit of its key; in "
                "the config by its SI name, in SI. The representative designs are every combination, the other "
                "factors at today's typical values (the fleet distributions' medians).",
            ),
        ),
    },
)  # fmt: skip


def _si_distributions(section: Any) -> FrozenMap:
    """The sampling distributions by the quantities' SI names (each validated into SI, :mod:`.quantities`)."""
    return FrozenMap({q.name: getattr(section, key) for key, q in QUANTITIES.items()})


class Params(Strict):
    """params.yaml: the sections of the Monte Carlo pipeline, and those other stages read themselves."""

    seed: int = integer(0, 2**63 - 1)
    """Seed of every random draw of the pipeline."""
    fleet: Fleet
    distributions: Annotated[Distributions, ToConfig(_si_distributions, "SI")]  # type: ignore[valid-type]
    """The SI name of each sampled quantity (``bush_stiffness``, ``contact_roll_radius``, ``chassis_tilt`` [rad],
    ...) -> its sampling distribution, in SI."""
    protocol: Protocols
    sensitivity: Sensitivity
    ablation: Ablation
    execution: Execution
    observed: Observed
    survey: Survey = Field(default_factory=lambda: Survey(export_format=None))
    calibrate: Calibrate | None = None
    design: Design | None = None
    figure2: Any = None

    @model_validator(mode="wrap")
    @classmethod
    def _sections_agree(cls, data: Any, handler: ValidatorFunctionWrapHandler) -> Params:
        # the rules between keys and the bounds on the costs (pipeline.config.rules) read the file as written; when a
        # field is bad, pipeline.config.parse_config runs those whose keys are valid and reports them with it
        params = handler(data)
        broken = rule_errors(cls, data)
        if broken:
            raise rule_error(broken[0].key, broken[0].value, broken[0].expected)
        return params
