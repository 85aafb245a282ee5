"""Parameters of one side of an n-axle mechanically equalised leaf-spring bogie.

Coordinates: ``x`` is measured rearward from the king pin [m], ``z`` upward [m]. Every length, stiffness and
mass is SI. The geometry is given in the *design position*: chassis level, equalisers level, every spring and
tyre carrying its design share of the payload (see ``docs/models.md``).

The chain of one side, front to rear, is::

    front hanger -a_f[0]- axle 0 -a_r[0]- tip -b_f[0]- pivot 0 -b_r[0]- tip -a_f[1]- axle 1 ... -a_r[n-1]- rear hanger

so the axle positions, spring half-lengths and arm lengths must close: the rear end of spring ``i`` and the
front arm tip of equaliser ``i`` sit at the same ``x``. :func:`Bogie.__post_init__` checks that, and every other
range, and raises ``ValueError`` naming the field, its value, the allowed range and the unit.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

# the range table lives in bogie.ranges (shared with the air-sprung bogie); re-exported here, where callers look
from bogie.ranges import AXLE_RANGES, EQUALISER_RANGES, SCALAR_RANGES, check_scalar, check_vector
from bogie.ranges import FieldRange as FieldRange

GRAVITY = 9.81  # [m/s^2]
#: the empty trailer's weight as a fraction of the design payload weight, where every loading starts [-]
TARE_FRACTION = 0.25

#: per-axle fields that may be left empty, with the rule that then gives their values (see the Bogie docstring)
_AXLE_RULES = ("radius_rod_length",)
#: the inhibitors of equalisation and the value that switches each one off: the reference's four (bush stiffness
#: and damping, contact movement, spring-end friction) and its preface's leaf-spring hysteresis
INHIBITORS: dict[str, float] = {
    "bush_stiffness": 0.0,
    "bush_damping": 0.0,
    "contact_roll_radius": 0.0,
    "friction_coefficient": 0.0,
    "spring_friction_band": 0.0,
}
#: the presets' decay length of the leaf springs' interleaf friction (its band is
#: :data:`bogie.presets.PRESET_SPRING_FRICTION_BAND`): the deflection over which the force crosses from one envelope
#: to the other is a few of these (``docs/presets.md``) [m]
PRESET_SPRING_FRICTION_DECAY = 0.005

#: an ``equaliser_stop`` that no equaliser can reach inside the freedoms' limits (relative rotation at most
#: 60 + 20 degrees): the stop switched off, for what-if runs [rad]
NO_STOP = math.pi
#: the presets' stop angle: 40 mm of free travel at the tip of a 0.155 m arm, asin(0.04 / 0.155) = 15 degrees,
#: mid-way in the model notes' 10-20 degrees (a choice; ``docs/presets.md``) [rad]
PRESET_EQUALISER_STOP = math.radians(15.0)
#: the presets' stop contact stiffness: a 60 x 60 x 12 mm rubber pad of 60 IRHD at 0.15 m from the pivot
#: (``docs/models.md``, "Equaliser stops") [N m/rad]
PRESET_EQUALISER_STOP_STIFFNESS = 8.4e4

#: tolerance on the closure of the spring/equaliser chain [m]
_CLOSURE_TOL = 1e-6


class AxleGroup:
    """What any axle group's parameters derive from their ``axle_x`` [m] and ``chassis_tilt`` [rad]: the steel
    :class:`Bogie` and the air-sprung :class:`bogie.air.AirBogie` alike."""

    axle_x: tuple[float, ...]
    chassis_tilt: float

    @property
    def n_axles(self) -> int:
        """Number of axles n [-]."""
        return len(self.axle_x)

    @property
    def bogie_centre_x(self) -> float:
        """Mean of the axle positions [m]."""
        return sum(self.axle_x) / self.n_axles

    @property
    def kingpin_height_offset(self) -> float:
        """Rise of the king pin above its design height that makes :attr:`chassis_tilt` [m]."""
        return self.bogie_centre_x * math.tan(self.chassis_tilt)


@dataclass(frozen=True)
class Bogie(AxleGroup):
    """One side of an n-axle mechanically equalised leaf-spring bogie (n >= 2, n - 1 equalisers).

    Parameters
    ----------
    axle_x
        Axle positions rearward of the king pin, front to rear [m].
    spring_front_half_length, spring_rear_half_length
        Distance from each axle seat to the front and rear spring-end contact [m], one per axle.
    equaliser_front_arm, equaliser_rear_arm
        Horizontal distance from each equaliser pivot to its front and rear arm-tip contact [m], one per
        equaliser. The pivot positions follow from the chain (:attr:`equaliser_pivot_x`).
    road_spring_stiffness
        Vertical rate of one leaf spring at its axle seat [N/m].
    tyre_stiffness
        Vertical stiffness of the tyres at one axle end (a twin pair) [N/m].
    tyre_damping
        Vertical viscous damping of the tyres at one axle end [N s/m].
    tyre_radius
        Unloaded radius of a new tyre [m].
    tyre_wear
        Loss of radius of each axle's tyres from tread wear [m], one per axle.
    axle_mass
        Unsprung mass per axle end (half axle, hub, wheels) [kg].
    equaliser_inertia
        Moment of inertia of one equaliser about its pivot [kg m^2].
    payload_mass
        Sprung mass carried by this side (chassis and payload) [kg]; the geometry is the design position under
        this load.
    payload_cg_x
        Position of that mass's centre of gravity rearward of the king pin [m].
    chassis_pitch_inertia
        Pitch moment of inertia of the sprung mass about the king pin [kg m^2].
    pad_drop
        Height of the king pin above the hanger pads in the design position [m]; with chassis pitch the pads
        swing fore and aft by this lever.
    equaliser_front_tip_drop, equaliser_rear_tip_drop
        Height of the equaliser pivot above its front and rear arm-tip contacts [m] (negative: tip above pivot).
    spring_length_rate
        Growth of a spring's end-to-end length per unit deflection at its seat [m/m]; the ends slide on their
        pads by half of it each.
    spring_end_slope_rate
        Rotation of each spring end (flattening) per unit deflection [rad/m].
    contact_tangential_stiffness
        Shear stiffness of a spring end on its pad while it sticks [N/m].
    chassis_tilt
        Pitch of the chassis in the design position, nose up positive [rad]; made by raising the king pin
        (:attr:`kingpin_height_offset`).
    bush_stiffness
        Rotational stiffness of each equaliser bush [N m/rad]. Inhibitor 1; 0 switches it off.
    bush_damping
        Rotational viscous damping of each equaliser bush [N m s/rad]. Inhibitor 2; 0 switches it off.
    contact_roll_radius
        Effective radius of the cylindrical spring-end/pad contact [m]: relative rotation moves the contact
        point along the pad by this radius times the rotation. Inhibitor 3; 0 fixes the contact point.
    friction_coefficient
        Coulomb friction coefficient at the spring ends [-]. Inhibitor 4; 0 switches it off.
    radius_rod_length
        Length of each axle's radius rod [m], one per axle, or empty (the default) for a rod from the bracket ahead
        of the axle: the front hanger for the front axle, the pivot bracket of the equaliser ahead for the others
        (:attr:`radius_rod_lengths`). The rod locates the axle fore and aft from an anchor on the chassis; it is
        level in the design position with its anchor ahead of the axle, so the axle follows the chassis's pitch
        on the rod's arc (``docs/models.md``, "Axle location").
    radius_rod_drop
        Height of the spring seat above the rods' line (anchor and axle eye) in the design position [m]; 0 puts
        the rods at the seat's height, where a chassis pitch moves seats and pads together.
    equaliser_stop
        Relative rotation of an equaliser and the chassis, either way, at which the equaliser meets its rubber
        bump stop [rad]; the same for every equaliser (they are alike in every preset and share one bush
        stiffness). :data:`NO_STOP` (pi) switches the stops off: no equaliser reaches it inside the freedoms'
        limits. Not an inhibitor: a physical limit of travel (``docs/models.md``, "Equaliser stops").
    equaliser_stop_stiffness
        Rotational contact stiffness of a stop once fully in contact [N m/rad] (a rubber pad's compression times
        its lever squared); 0 also switches the stops off.
    spring_friction_band
        Interleaf friction of each leaf spring: the half-width [N] of the band about the elastic line inside which
        its force lies; compressing, the force tends to the loading envelope (elastic line + band), extending, to
        the unloading envelope (elastic line - band) (Fancher et al. 1980; ``docs/models.md``, "Leaf-spring
        hysteresis"). The preface's spring hysteresis; 0 switches it off.
    spring_friction_decay
        Decay length of that friction [m]: after a reversal the force closes on the other envelope as
        exp(-|delta - delta_reversal| / decay).
    """

    axle_x: tuple[float, ...]
    spring_front_half_length: tuple[float, ...]
    spring_rear_half_length: tuple[float, ...]
    equaliser_front_arm: tuple[float, ...]
    equaliser_rear_arm: tuple[float, ...]
    road_spring_stiffness: float
    tyre_stiffness: float
    tyre_radius: float
    axle_mass: float
    payload_mass: float
    payload_cg_x: float
    chassis_pitch_inertia: float
    tyre_wear: tuple[float, ...] = field(default=())
    tyre_damping: float = 0.0
    equaliser_inertia: float = 0.2
    pad_drop: float = 0.3
    equaliser_front_tip_drop: float = 0.0
    equaliser_rear_tip_drop: float = 0.0
    spring_length_rate: float = 0.3
    spring_end_slope_rate: float = 0.0
    contact_tangential_stiffness: float = 5e6
    chassis_tilt: float = 0.0
    bush_stiffness: float = 0.0
    bush_damping: float = 0.0
    contact_roll_radius: float = 0.0
    friction_coefficient: float = 0.0
    radius_rod_length: tuple[float, ...] = field(default=())
    radius_rod_drop: float = 0.0
    equaliser_stop: float = PRESET_EQUALISER_STOP
    equaliser_stop_stiffness: float = PRESET_EQUALISER_STOP_STIFFNESS
    spring_friction_band: float = 0.0
    spring_friction_decay: float = PRESET_SPRING_FRICTION_DECAY

    def __post_init__(self) -> None:
        axle_x = self.axle_x
        if type(axle_x) is tuple and len(axle_x) >= 2 and all(type(x) is float for x in axle_x):
            pass  # the usual case (floats, as validation stores them), without numpy's look at the sequence
        elif isinstance(axle_x, str | bytes) or np.ndim(axle_x) != 1 or len(tuple(axle_x)) < 2:
            raise ValueError(f"axle_x = {axle_x!r} must list at least 2 axle positions in m (n >= 2)")
        n = len(tuple(axle_x))
        if isinstance(self.tyre_wear, tuple) and not self.tyre_wear:
            object.__setattr__(self, "tyre_wear", (0.0,) * n)
        for name, (low, high, unit, inc) in AXLE_RANGES.items():
            if name in _AXLE_RULES and isinstance(getattr(self, name), tuple) and not getattr(self, name):
                continue  # empty: the field's rule gives the values (a property), whatever the axle count
            object.__setattr__(self, name, check_vector(name, getattr(self, name), n, "axle", low, high, unit, inc))
        for name, (low, high, unit, inc) in EQUALISER_RANGES.items():
            vec = check_vector(name, getattr(self, name), n - 1, "equaliser", low, high, unit, inc)
            object.__setattr__(self, name, vec)
        for name, (low, high, unit, inc) in SCALAR_RANGES.items():
            object.__setattr__(self, name, check_scalar(name, getattr(self, name), low, high, unit, inc))
        self._check_chain()
        if self.payload_cg_x >= self.axle_x[-1] + self.spring_rear_half_length[-1]:
            raise ValueError(
                f"payload_cg_x = {self.payload_cg_x!r} must lie ahead of the rear hanger "
                f"(x < {self.rear_hanger_x:g} m) so that the king pin carries a downward load"
            )
        if self.chassis_pitch_inertia < self.payload_mass * self.payload_cg_x**2:
            raise ValueError(
                f"chassis_pitch_inertia = {self.chassis_pitch_inertia!r} is below payload_mass * payload_cg_x^2 = "
                f"{self.payload_mass * self.payload_cg_x**2:g} kg m^2, the least a body with that mass and centre of "
                "gravity can have about the king pin"
            )
        if not self.radius_rod_length:
            # the rule's rods must lie in the field's range too (a very short spring half would make a stub rod)
            low, high, unit, inc = AXLE_RANGES["radius_rod_length"]
            for i, length in enumerate(self.radius_rod_lengths):
                check_scalar(f"radius_rod_length[{i}] (from the bracket ahead)", length, low, high, unit, inc)
        for i, length in enumerate(self.radius_rod_lengths):
            if self.axle_x[i] - length <= 0.0:
                raise ValueError(
                    f"radius_rod_length[{i}] = {length!r} puts the rod's anchor at or ahead of the king pin: must be "
                    f"less than axle_x[{i}] = {self.axle_x[i]!r} m"
                )
        for i, w in enumerate(self.tyre_wear):
            if w >= self.tyre_radius:
                raise ValueError(f"tyre_wear[{i}] = {w!r} must be less than tyre_radius = {self.tyre_radius!r} m")

    def _check_chain(self) -> None:
        ax = self.axle_x
        for i in range(self.n_axles - 1):
            if ax[i + 1] <= ax[i]:
                raise ValueError(f"axle_x = {ax!r} must increase from front to rear (m)")
        for j in range(self.n_axles - 1):
            tip_front = ax[j] + self.spring_rear_half_length[j]
            tip_rear = ax[j + 1] - self.spring_front_half_length[j + 1]
            span = self.equaliser_front_arm[j] + self.equaliser_rear_arm[j]
            if abs((tip_rear - tip_front) - span) > _CLOSURE_TOL:
                raise ValueError(
                    f"geometry does not close at equaliser {j}: spring ends at x = {tip_front:.6g} and "
                    f"{tip_rear:.6g} m are {tip_rear - tip_front:.6g} m apart but equaliser_front_arm[{j}] + "
                    f"equaliser_rear_arm[{j}] = {span:.6g} m; axle spacing must equal spring_rear_half_length[{j}] "
                    f"+ equaliser arms + spring_front_half_length[{j + 1}]"
                )
        if ax[0] - self.spring_front_half_length[0] <= 0.0:
            raise ValueError(
                f"spring_front_half_length[0] = {self.spring_front_half_length[0]!r} puts the front hanger at or ahead "
                "of the king pin: must be less than axle_x[0] m"
            )

    # ---- derived geometry -------------------------------------------------------------------------------
    @property
    def equaliser_pivot_x(self) -> tuple[float, ...]:
        """Equaliser pivot positions rearward of the king pin [m]."""
        return tuple(
            self.axle_x[j] + self.spring_rear_half_length[j] + self.equaliser_front_arm[j]
            for j in range(self.n_axles - 1)
        )

    @property
    def front_hanger_x(self) -> float:
        """Front hanger contact position [m]."""
        return self.axle_x[0] - self.spring_front_half_length[0]

    @property
    def rear_hanger_x(self) -> float:
        """Rear hanger contact position [m]."""
        return self.axle_x[-1] + self.spring_rear_half_length[-1]

    @property
    def radius_rod_lengths(self) -> tuple[float, ...]:
        """Length of each axle's radius rod [m]: :attr:`radius_rod_length`, or if that is empty the distance from
        each axle back to the bracket ahead of it (the front hanger, then each equaliser's pivot bracket)."""
        if self.radius_rod_length:
            return tuple(self.radius_rod_length)
        ahead = (self.front_hanger_x, *self.equaliser_pivot_x)
        return tuple(x - a for x, a in zip(self.axle_x, ahead))

    @property
    def radius_rod_anchor_x(self) -> tuple[float, ...]:
        """Position of each radius rod's chassis anchor rearward of the king pin in the design position [m]: the
        rod is level there, with its anchor ahead of the axle."""
        return tuple(x - length for x, length in zip(self.axle_x, self.radius_rod_lengths))

    @property
    def combined_stiffness(self) -> float:
        """Road spring and tyre in series, the reference's K_S: 1/K_S = 1/K_T + 1/K_R [N/m]."""
        return 1.0 / (1.0 / self.tyre_stiffness + 1.0 / self.road_spring_stiffness)

    @property
    def sprung_weight_on_bogie(self) -> float:
        """Weight of the sprung mass carried by the bogie's springs in the design position [N]."""
        return sum(design_spring_loads(self))

    def q(self, equaliser: int = 0) -> float:
        """The reference's stiffness ratio q = b^2 K_S / (4 K_B) for one equaliser [-] (Equation 1).

        ``b`` is the mean arm length of that equaliser; q is infinite for a free bush.
        """
        b = 0.5 * (self.equaliser_front_arm[equaliser] + self.equaliser_rear_arm[equaliser])
        if self.bush_stiffness == 0.0:
            return math.inf
        return b * b * self.combined_stiffness / (4.0 * self.bush_stiffness)

    def replace(self, **changes: Any) -> Bogie:
        """A copy with ``changes`` applied and re-validated (same as :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    def without(self, *inhibitors: str) -> Bogie:
        """A copy with the named inhibitors switched off (each set to its ideal value); all of them if none named."""
        names = inhibitors or tuple(INHIBITORS)
        unknown = [n for n in names if n not in INHIBITORS]
        if unknown:
            raise ValueError(f"unknown inhibitor {unknown[0]!r}: must be one of {', '.join(INHIBITORS)}")
        return self.replace(**{n: INHIBITORS[n] for n in names})


def _design_shares(bogie: Bogie) -> list[float]:
    """Relative spring loads in the design position with moment-free equalisers (sum = n) [-].

    A level equaliser carries its two spring-end loads in inverse ratio of its arms, and each spring splits its
    seat load to its ends by the lever rule, so W_{j+1} / W_j = (b_f c_r,j) / (b_r c_f,j+1).
    """
    n = bogie.n_axles
    shares = [1.0]
    for j in range(n - 1):
        a_f0, a_r0 = bogie.spring_front_half_length[j], bogie.spring_rear_half_length[j]
        a_f1, a_r1 = bogie.spring_front_half_length[j + 1], bogie.spring_rear_half_length[j + 1]
        c_r = a_f0 / (a_f0 + a_r0)  # fraction of spring j's load at its rear end
        c_f = a_r1 / (a_f1 + a_r1)  # fraction of spring j+1's load at its front end
        shares.append(shares[-1] * bogie.equaliser_front_arm[j] * c_r / (bogie.equaliser_rear_arm[j] * c_f))
    total = sum(shares)
    return [n * s / total for s in shares]


def design_spring_loads(bogie: Bogie) -> tuple[float, ...]:
    """Spring seat loads in the design position [N], one per axle.

    The chassis is level, the equalisers are level and carry no bush moment, and the springs carry the sprung
    weight not taken by the king pin: sum_i W_i x_i = m g x_cg (moments about the king pin).
    """
    shares = _design_shares(bogie)
    scale = bogie.payload_mass * GRAVITY * bogie.payload_cg_x / sum(s * x for s, x in zip(shares, bogie.axle_x))
    return tuple(scale * s for s in shares)


def with_equaliser_arms(bogie: Bogie, front: float, rear: float | None = None) -> Bogie:
    """A copy with every equaliser's arms set to ``front`` and ``rear`` [m], axle positions and pivots kept.

    The spring halves beside each equaliser shorten (or lengthen) by the change, so the chain still closes at the
    same axle spacing, as when a longer equaliser is fitted to the same axle layout; the front and rear hangers
    move with the outer springs' other halves, so every spring that was symmetric stays symmetric and a bogie
    designed to share its load equally still does (the lever rule would otherwise load the middle axle of a
    tri-axle more).
    """
    return bogie.replace(**equaliser_arm_changes(bogie, front, rear))


def equaliser_arm_changes(bogie: Any, front: float, rear: float | None = None) -> dict[str, tuple[float, ...]]:
    """The field changes of :func:`with_equaliser_arms` (arms and spring halves) for ``bogie``: a :class:`Bogie`
    or a mapping of its fields (``spring_front_half_length``, ``spring_rear_half_length``, ``equaliser_front_arm``
    and ``equaliser_rear_arm``), so that a caller changing other fields too can validate the bogie once."""
    get = bogie.__getitem__ if isinstance(bogie, dict) else bogie.__getattribute__
    s_f, s_r = get("spring_front_half_length"), get("spring_rear_half_length")
    arm_f, arm_r = get("equaliser_front_arm"), get("equaliser_rear_arm")
    rear = front if rear is None else rear
    n = len(s_f)
    a_f = list(s_f)
    a_r = list(s_r)
    for j in range(n - 1):
        a_r[j] -= front - arm_f[j]
        a_f[j + 1] -= rear - arm_r[j]
    a_f[0] += (a_r[0] - s_r[0]) * (a_f[0] / s_r[0])
    a_r[-1] += (a_f[-1] - s_f[-1]) * (a_r[-1] / s_f[-1])
    return {
        "equaliser_front_arm": (front,) * (n - 1),
        "equaliser_rear_arm": (rear,) * (n - 1),
        "spring_front_half_length": tuple(a_f),
        "spring_rear_half_length": tuple(a_r),
    }


def __getattr__(name: str) -> Any:
    """The presets' names (``tandem_trrl``, ``preset``, ``PRESETS``, ...), moved to :mod:`bogie.presets` (issue 42:
    bogie.presets builds on Bogie, so re-exporting them here made a circle of imports): found here for one release,
    with a DeprecationWarning naming where they are now."""
    from bogie import presets  # a deprecation shim: runs only when a moved name is asked for

    if name in presets.__all__:
        warnings.warn(
            f"bogie.params.{name} moved to bogie.presets.{name}: import it from there (bogie.params finds it for one "
            "release more)",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(presets, name)
    raise AttributeError(f"module 'bogie.params' has no attribute {name!r}")
