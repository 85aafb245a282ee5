"""The Stage 4 model's constants of a bogie (:mod:`bogie.steel.nonlinear`, which re-exports every name here): the pack
of its parameters for the compiled force (:func:`pack`, the layout of :mod:`bogie.steel.force.layout`), the cache of
a bogie's :class:`Constants` (:func:`constants`: the pack, the axles' offsets, each freedom's lever, residual tolerance
and limit), the freedoms' names and limits, and the check of a history's length.
"""

from __future__ import annotations

import functools
import math
import threading
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie.params import GRAVITY, Bogie, design_spring_loads
from bogie.steel.force import core


# ---- packing ---------------------------------------------------------------------------------------------------
def dof_names(n_axles: int) -> tuple[str, ...]:
    """Names of the 2n freedoms of the non-linear model."""
    return (
        ("chassis_pitch",)
        + tuple(f"equaliser_{j}" for j in range(n_axles - 1))
        + tuple(f"axle_{i}" for i in range(n_axles))
    )


def design_wheel_loads(bogie: Bogie) -> NDArray[np.float64]:
    """Tyre loads in the design position [N]: spring loads plus the axle weight."""
    return np.asarray(design_spring_loads(bogie)) + bogie.axle_mass * GRAVITY


def _contacts(bogie: Bogie) -> tuple[list[int], list[float], list[float], list[float], list[float], list[float]]:
    """The spring-end contacts e (2i front and 2i + 1 rear end of spring i) and the equaliser pivots' heights.

    Returns each contact's body (-1 chassis, j equaliser j), its pad point's offset (x, z) in the body's frame
    from the body's origin (the king pin for the chassis, the pivot for an equaliser) [m], its position (x, z) in
    the design position [m], and the pivot heights [m].
    """
    n = bogie.n_axles
    pivots = bogie.equaliser_pivot_x
    z_pad = -bogie.pad_drop
    h_f, h_r = bogie.equaliser_front_tip_drop, bogie.equaliser_rear_tip_drop
    pivot_z = [z_pad + h_f] * (n - 1)
    bodies, pad_x, pad_z, world_x, world_z = [], [], [], [], []
    for i in range(n):
        if i == 0:
            front = (-1, bogie.front_hanger_x, z_pad)
        else:
            front = (i - 1, bogie.equaliser_rear_arm[i - 1], -h_r)
        if i == n - 1:
            rear = (-1, bogie.rear_hanger_x, z_pad)
        else:
            rear = (i, -bogie.equaliser_front_arm[i], -h_f)
        for body, dx, dz in (front, rear):
            bodies.append(body)
            pad_x.append(dx)
            pad_z.append(dz)
            ox, oz = (0.0, 0.0) if body < 0 else (pivots[body], pivot_z[body])
            world_x.append(ox + dx)
            world_z.append(oz + dz)
    return bodies, pad_x, pad_z, world_x, world_z, pivot_z


def _packed_scalars(bogie: Bogie) -> dict[str, float]:
    """The scalars of ``data_f`` by name (:data:`bogie.steel.force.core.SCALARS`), SI."""
    return {
        "road_spring_stiffness": bogie.road_spring_stiffness,
        "tyre_stiffness": bogie.tyre_stiffness,
        "tyre_damping": bogie.tyre_damping,
        "bush_stiffness": bogie.bush_stiffness,
        "bush_damping": bogie.bush_damping,
        "contact_roll_radius": bogie.contact_roll_radius,
        "friction_coefficient": bogie.friction_coefficient,
        "contact_tangential_stiffness": bogie.contact_tangential_stiffness,
        "spring_end_slope_rate": bogie.spring_end_slope_rate,
        "payload_weight": bogie.payload_mass * GRAVITY,
        "payload_cg_x": bogie.payload_cg_x,
        "axle_weight": bogie.axle_mass * GRAVITY,
        "equaliser_stop": bogie.equaliser_stop,
        "equaliser_stop_stiffness": bogie.equaliser_stop_stiffness,
        "spring_friction_band": bogie.spring_friction_band,
        "spring_friction_decay": bogie.spring_friction_decay,
    }


def _packed_arrays(bogie: Bogie) -> tuple[dict[str, list[float]], list[int]]:
    """The arrays of ``data_f`` by name (:data:`bogie.steel.force.core.ARRAYS`), SI, and the contacts' bodies.

    Element by element in Python floats (issue 15: numpy's calls on arrays of two or three entries cost more than
    their arithmetic; the same IEEE operations in the same order give the same bits), numpy only for the chord
    angles' arctan2, cos and sin.
    """
    bodies, pad_x, pad_z, world_x, world_z, pivot_z = _contacts(bogie)
    a_f, a_r = bogie.spring_front_half_length, bogie.spring_rear_half_length
    x_a = [float(x) for x in bogie.axle_x]
    n = len(x_a)
    rate = bogie.spring_length_rate
    xf, xr, zf, zr = world_x[0::2], world_x[1::2], world_z[0::2], world_z[1::2]
    # the spring chords through the design contact points: height at the axle and angle (as its cosine and sine,
    # which the core turns the chord's unit vector back by)
    w_front = [(xr[i] - x_a[i]) / (xr[i] - xf[i]) for i in range(n)]
    chord_height = [w_front[i] * zf[i] + (1.0 - w_front[i]) * zr[i] for i in range(n)]
    chord_angle = [math.atan2(-(zr[i] - zf[i]), xr[i] - xf[i]) for i in range(n)]
    loads = list(design_spring_loads(bogie))
    axle_weight = bogie.axle_mass * GRAVITY
    arrays = {
        "axle_x": x_a,
        "elongation_front": [rate * a_f[i] / (a_f[i] + a_r[i]) for i in range(n)],
        "elongation_rear": [rate * a_r[i] / (a_f[i] + a_r[i]) for i in range(n)],
        "design_spring_load": loads,
        "design_tyre_compression": [(load + axle_weight) / bogie.tyre_stiffness for load in loads],
        "tyre_wear": [float(w) for w in bogie.tyre_wear],
        "design_chord_height": chord_height,
        "design_chord_cos": [math.cos(angle) for angle in chord_angle],
        "design_chord_sin": [math.sin(angle) for angle in chord_angle],
        "pad_x": pad_x,
        "pad_z": pad_z,
        "design_contact_x": world_x,
        "pivot_x": [float(x) for x in bogie.equaliser_pivot_x],
        "pivot_z": [float(z) for z in pivot_z],
        # radius rods: level in the design position, the line radius_rod_drop below each seat's chord height,
        # the anchor on the chassis ahead of the axle
        "rod_anchor_x": [float(x) for x in bogie.radius_rod_anchor_x],
        "rod_anchor_z": [h - bogie.radius_rod_drop for h in chord_height],
        "rod_length": [float(x) for x in bogie.radius_rod_lengths],
    }
    return arrays, bodies


@functools.cache
def _array_lengths(n: int) -> tuple[int, ...]:
    """Each packed array's length for ``n`` axles (:func:`bogie.steel.force.core.array_length`, compiled)."""
    return tuple(core.array_length(k, n) for k in range(len(core.ARRAYS)))


def pack(bogie: Bogie) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Mass matrix and the packed parameters (``data_f``, ``data_i``) of :mod:`bogie.steel.force.core`.

    The layout is the core's: its :data:`~bogie.steel.force.core.SCALARS`, then its
    :data:`~bogie.steel.force.core.ARRAYS`, each as long as :func:`~bogie.steel.force.core.array_length` says.
    The mass matrix is diagonal (the kernels use only its diagonal).
    """
    n = bogie.n_axles
    scalars = _packed_scalars(bogie)
    arrays, bodies = _packed_arrays(bogie)
    values = [scalars[k] for k in core.SCALARS]
    for (name, _, _), length in zip(core.ARRAYS, _array_lengths(n)):
        if len(arrays[name]) != length:
            raise AssertionError(f"packed array {name} has {len(arrays[name])} entries: the core's layout has {length}")
        values += arrays[name]
    data_f = np.array(values, dtype=float)
    data_i = np.asarray([n, *bodies], dtype=np.int64)
    mass = np.diag([bogie.chassis_pitch_inertia] + [bogie.equaliser_inertia] * (n - 1) + [bogie.axle_mass] * n)
    return mass, data_f, data_i


@dataclass(frozen=True)
class Constants:
    """What the solvers need of a bogie that nothing changes (:func:`constants`): its pack (:func:`pack`; the mass
    matrix is diagonal, the kernels use only its diagonal), the axles' offsets behind the front axle, each
    freedom's lever, residual tolerance and limit, and the king pin's height offset."""

    mass: NDArray[np.float64]
    data_f: NDArray[np.float64]
    data_i: NDArray[np.int64]
    offsets: NDArray[np.float64]
    levers: NDArray[np.float64]
    r_tol: NDArray[np.float64]
    u_limit: NDArray[np.float64]
    kingpin: float


#: the bogies :func:`constants` computed last with their constants, by identity: the one cache of a bogie's pack,
#: for the equilibrium (:func:`cached_pack`) and the phases (:func:`bogie.steel.phases.run`). Each entry holds its
#: bogie, so while it lives no other object can take that id() (the ``is`` test says so too). Not by equality: two equal
#: bogies (0.0 == -0.0) may pack other bits, and hashing every field would cost more than the lookup saves.
_CONSTANTS: dict[int, tuple[Bogie, Constants]] = {}
#: how many bogies :data:`_CONSTANTS` keeps
_CONSTANTS_SIZE = 4
_CONSTANTS_LOCK = threading.Lock()


def constants(bogie: Bogie) -> Constants:
    """The bogie's :class:`Constants`, computed once for the phases and the equilibrium of its weighings (issue 15:
    a static weighing packed the same bogie four times). Shared: do not change the arrays (:func:`cached_pack`
    copies)."""
    hit = _CONSTANTS.get(id(bogie))
    if hit is not None and hit[0] is bogie:
        return hit[1]
    mass, data_f, data_i = pack(bogie)
    levers = _levers(bogie)
    found = Constants(
        mass=mass,
        data_f=data_f,
        data_i=data_i,
        offsets=np.asarray(bogie.axle_x, dtype=float) - bogie.axle_x[0],
        levers=levers,
        r_tol=residual_tolerance(bogie, levers),
        u_limit=limits(bogie),
        kingpin=float(bogie.kingpin_height_offset),
    )
    with _CONSTANTS_LOCK:  # threads weighing side by side: one of them drops the oldest entry
        while len(_CONSTANTS) >= _CONSTANTS_SIZE:
            del _CONSTANTS[next(iter(_CONSTANTS))]
        _CONSTANTS[id(bogie)] = (bogie, found)
    return found


def cached_pack(bogie: Bogie) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """:func:`pack` of ``bogie`` from :func:`constants`, packed once per bogie. Fresh copies: the caller may change
    them."""
    c = constants(bogie)
    return c.mass.copy(), c.data_f.copy(), c.data_i.copy()


#: where the relaxed equilibrium zeroes the friction in ``data_f`` (friction_coefficient and spring_friction_band
#: are scalars of the pack only: nothing else packed depends on them)
FRICTION_SLOTS = [core.SCALARS.index("friction_coefficient"), core.SCALARS.index("spring_friction_band")]


def work_size(bogie: Bogie) -> int:
    return core.work_size(bogie.n_axles)


def limits(bogie: Bogie) -> NDArray[np.float64]:
    """Range of validity of each freedom: chassis pitch 20 degrees, equaliser rotation 60 degrees, axle 0.5 m.

    Beyond these the model has spurious equilibria (a chassis pitched 90 degrees on slack springs carries its
    weight without a moment) and a real bogie would have hit its stops long before.
    """
    n = bogie.n_axles
    return np.asarray([math.radians(20.0)] + [math.radians(60.0)] * (n - 1) + [0.5] * n)


def check_limits(bogie: Bogie, u: NDArray[np.float64]) -> None:
    """Refuse a solution outside the freedoms' limits (:func:`limits`): a ``ValueError`` naming the freedom, its
    value and the limit with their unit. Beyond the limits the model's equilibria are spurious, not a bogie's."""
    names = dof_names(bogie.n_axles)
    lim = limits(bogie)
    n = bogie.n_axles
    for k in range(2 * n):
        if not abs(u[k]) <= lim[k]:
            if k < n:
                value, limit, unit = math.degrees(u[k]), math.degrees(lim[k]), "degrees"
            else:
                value, limit, unit = u[k], lim[k], "m"
            raise ValueError(
                f"static equilibrium lies outside the model's range of validity: {names[k]} = {value:.4g} {unit}, "
                f"beyond its limit of +-{limit:g} {unit} (a spurious equilibrium, e.g. an equaliser turned over on a "
                "slack spring: are the equaliser stops switched off, or the king pin rise or load out of reach?)"
            )


def _mean(values: ArrayLike) -> float:
    """``float(np.mean(values))`` of a few numbers, bit for bit (numpy's sum, then the division), at a quarter of
    its cost: np.mean's dispatch cost more than its sum of two or three numbers (issue 15)."""
    array = np.asarray(values, dtype=float)
    return float(np.add.reduce(array)) / array.size


def _levers(bogie: Bogie) -> NDArray[np.float64]:
    """Each freedom's lever [m, -]: the bogie centre's distance behind the king pin for the chassis pitch, the mean
    equaliser arm for an equaliser, 1 for an axle: a force of one wheel's size times the lever is each freedom's
    scale of generalised force."""
    arm = 0.5 * (_mean(bogie.equaliser_front_arm) + _mean(bogie.equaliser_rear_arm))
    return np.asarray([bogie.bogie_centre_x] + [arm] * (bogie.n_axles - 1) + [1.0] * bogie.n_axles, dtype=float)


def residual_tolerance(bogie: Bogie, levers: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """Residual tolerance per freedom: 1e-5 of the design wheel load times each freedom's lever [N, N m]
    (:func:`_levers`, given or computed)."""
    w = _mean(design_wheel_loads(bogie))
    return 1e-5 * w * (_levers(bogie) if levers is None else levers)


def checked_history(bogie: Bogie, history: ArrayLike, what: str) -> NDArray[np.float64]:
    """A copy of a history (:attr:`State.history`) after checking its length against the bogie's axles."""
    hist = np.array(history, dtype=float)
    expected = core.history_length(bogie.n_axles)
    if hist.shape != (expected,):
        raise ValueError(
            f"{what} has shape {hist.shape}: a {bogie.n_axles}-axle bogie's history has {expected} entries "
            f"({', '.join(name for name, *_ in core.HISTORY)}; State.history)"
        )
    return hist
