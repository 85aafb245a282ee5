"""The validated configuration: one frozen dataclass per params.yaml section, every value in SI.

Made by :func:`pipeline.config.settings.load_config` from the schema (:mod:`pipeline.config.schema`); the stages
read these. The protocols' settings are the library's own classes (:mod:`bogie.fleet.protocol_settings`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from bogie.fleet.protocol_settings import StaticProtocol, WimProtocol


class FrozenMap(Mapping):
    """A read-only, hashable, picklable mapping (the dict-valued fields of the frozen config)."""

    def __init__(self, items: Mapping | Iterable[tuple[Any, Any]] = ()) -> None:
        self._data = dict(items)

    def __getitem__(self, key: Any) -> Any:
        return self._data[key]

    def __iter__(self) -> Iterator:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __hash__(self) -> int:
        return hash(tuple(self._data.items()))

    def __repr__(self) -> str:
        return f"FrozenMap({self._data!r})"


# ---- the configuration ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FleetConfig:
    """The fleet study.

    Attributes
    ----------
    n_bogies
        Number of bogies [-].
    sampling
        ``lhs`` (Latin hypercube) or ``sobol`` (scrambled Sobol'), both from scipy.stats.qmc.
    axle_mix
        Fraction of the fleet in each axle group [-], summing to 1.
    suspension_mix
        Per axle group, the fraction of its groups of each suspension (``steel``: leaf springs and equalisers,
        ``air``: connected air springs) [-], summing to 1.
    presets
        Name of the base bogie (a bogie.params preset) of each group.
    legal_group_load
        Legal load of each group, both sides together [N].
    legal_axle_load
        Legal load of a single axle, both sides together [N].
    """

    n_bogies: int
    sampling: str
    axle_mix: FrozenMap
    suspension_mix: FrozenMap
    presets: FrozenMap
    legal_group_load: FrozenMap
    legal_axle_load: float

    @property
    def groups(self) -> tuple[str, ...]:
        """The axle groups in a fixed order (fewest axles first), whatever the order in params.yaml."""
        return tuple(self.axle_mix)


@dataclass(frozen=True)
class ProtocolConfig:
    """Which protocols the simulation runs (``run``) and the settings of each."""

    run: tuple[str, ...]
    static: StaticProtocol
    wim: WimProtocol


@dataclass(frozen=True)
class SensitivityConfig:
    """The Sobol' sensitivity design.

    Attributes
    ----------
    group
        Axle group whose base bogie the design perturbs.
    base_size
        Saltelli base sample size N, a power of 2 [-].
    factors
        SI names of the perturbed quantities (``tyre_wear`` stands for every axle's wear, one SALib group).
    bootstrap_resamples
        Bootstrap resamples for the confidence intervals [-].
    confidence_level
        Confidence level of those intervals [-].
    protocol
        Protocol whose results are analysed.
    """

    group: str
    base_size: int
    factors: tuple[str, ...]
    bootstrap_resamples: int
    confidence_level: float
    protocol: str


@dataclass(frozen=True)
class AblationConfig:
    """The switch-off ablation: the first ``n_bogies`` fleet bogies, each with the inhibitors removed in turn."""

    n_bogies: int


@dataclass(frozen=True)
class ExecutionConfig:
    """How the simulation runs: joblib ``backend``, workers, samples per chunk, dask scheduler address."""

    backend: str
    n_jobs: int
    chunk_size: int
    dask_scheduler: str | None


@dataclass(frozen=True)
class ObservedConfig:
    """An observed survey to hold against the simulated fleet (``observed:``; ``docs/observed.md``).

    Attributes
    ----------
    path
        The file of records, a POSIX path relative to the project root inside ``observed/``; None: no survey given.
    format
        Its record format: ``csv``, ``mon``, ``castor``, ``bedit`` or ``ditis`` (``docs/weighings.md``).
    min_group_load
        Smallest group load kept, observed and simulated groups alike [kg] (a mass, as the weighings give it).
    group_spacing
        Largest spacing of two axles of one observed group [m].
    position
        Group position kept: ``all``, ``steer``, ``drive`` or ``trailer``.
    """

    path: str | None
    format: str
    min_group_load: float
    group_spacing: float
    position: str


@dataclass(frozen=True)
class SurveyConfig:
    """What the survey stage writes besides its statistics (``survey:``; ``docs/outputs.md``).

    Attributes
    ----------
    export_format
        None, or the record format (``csv``, ``mon``, ``castor``, ``bedit``, ``ditis``) in which the fleet study's WIM
        readings are written to ``data/survey/fleet_wim.<format>``.
    """

    export_format: str | None = None


@dataclass(frozen=True)
class CalibrateConfig:
    """The fleet quantities fitted to an observed survey (``calibrate:``; ``docs/calibration.md``).

    Attributes
    ----------
    protocol
        The protocol whose readings are held against the survey: ``wim`` or ``static``.
    n_bogies
        The calibration fleet: the first ``n_bogies`` fleet bogies, each as a steel and an air group [-].
    fit
        Quantity -> (low, high): the bounds of each fitted quantity, in the unit of its name.
    tilt_step
        Step of the chassis-tilt grid the readings are tabulated on [degree].
    site_iri_levels
        The WIM site roughnesses the readings are tabulated at [m/km].
    bootstrap_resamples, confidence_level
        Of the fitted values' intervals [-].
    maxiter, popsize
        Of the differential evolution [-].
    """

    protocol: str
    n_bogies: int
    fit: FrozenMap
    tilt_step: float
    site_iri_levels: tuple[float, ...]
    bootstrap_resamples: int
    confidence_level: float
    maxiter: int
    popsize: int


@dataclass(frozen=True)
class DesignConfig:
    """The controlled experiment over the design factors (``design:``; ``docs/design.md``).

    Attributes
    ----------
    groups
        The axle groups whose designs are studied.
    n_conditions
        Operating conditions (tilt, tyre wear, payload, approach road) every design runs over [-].
    tilt_step
        Step of the chassis-tilt grid, outward from level over the tilt distribution's bounds [degree].
    grid
        SI name of a design factor -> its levels [SI]: the representative designs are every combination, the other
        factors at today's typical values (the fleet distributions' medians).
    n_space_filling
        Further designs per group, a scrambled Sobol' design over all five factors' fleet distributions [-].
    target_share, confidence_level
        The share of bogies within 5 % the guidance asks for, and the confidence level of the intervals [-].
    """

    groups: tuple[str, ...]
    n_conditions: int
    tilt_step: float
    grid: FrozenMap
    n_space_filling: int
    target_share: float
    confidence_level: float


@dataclass(frozen=True)
class Config:
    """The validated pipeline parameters, all SI.

    ``distributions`` maps the SI name of each sampled quantity (``bush_stiffness``, ``bush_damping``,
    ``friction_coefficient``, ``contact_roll_radius`` [m], ``tyre_wear`` [m], ``chassis_tilt`` [rad],
    ``payload_fraction``, ``equaliser_arm`` [m], ``spring_friction_band`` [N], ``spring_friction_decay`` [m],
    ``road_class``) to its distribution in SI units.
    """

    seed: int
    fleet: FleetConfig
    distributions: FrozenMap
    protocol: ProtocolConfig
    sensitivity: SensitivityConfig
    ablation: AblationConfig
    execution: ExecutionConfig
    observed: ObservedConfig
    survey: SurveyConfig = SurveyConfig()
    calibrate: CalibrateConfig | None = None
    design: DesignConfig | None = None
