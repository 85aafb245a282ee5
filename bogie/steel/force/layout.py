"""The layout of the Stage 4 model's packed data (:mod:`bogie.steel.force.core`'s force): the one definition of
``data_f`` (the scalars of :data:`SCALARS`, then the arrays of :data:`ARRAYS`), the record (:data:`RECORD`), the
history (:data:`HISTORY`) and the force's work buffer (:data:`WORK`), with their compiled offsets and their Python
slices. :mod:`bogie.steel.force.core` re-exports every name: ``core.SCALARS`` and the like work as before.
"""

from __future__ import annotations

from numba import njit

SCALARS = (
    "road_spring_stiffness",
    "tyre_stiffness",
    "tyre_damping",
    "bush_stiffness",
    "bush_damping",
    "contact_roll_radius",
    "friction_coefficient",
    "contact_tangential_stiffness",
    "spring_end_slope_rate",
    "payload_weight",
    "payload_cg_x",
    "axle_weight",
    "equaliser_stop",
    "equaliser_stop_stiffness",
    "spring_friction_band",
    "spring_friction_decay",
)
(
    _KR,
    _KT,
    _CT,
    _KB,
    _CB,
    _RHO,
    _MU,
    _KTAN,
    _KAPPA,
    _WPAY,
    _XCG,
    _WAXLE,
    _STOP,
    _KSTOP,
    _BAND,
    _BETA,
) = range(len(SCALARS))
NS = len(SCALARS)

#: packed arrays after the scalars: (name, length per axle, extra length); length = per_axle * n + extra, so
#: (1, 0) is one per axle, (2, 0) one per contact and (1, -1) one per equaliser
ARRAYS = (
    ("axle_x", 1, 0),
    ("elongation_front", 1, 0),
    ("elongation_rear", 1, 0),
    ("design_spring_load", 1, 0),
    ("design_tyre_compression", 1, 0),
    ("tyre_wear", 1, 0),
    ("design_chord_height", 1, 0),
    ("design_chord_cos", 1, 0),
    ("design_chord_sin", 1, 0),
    ("pad_x", 2, 0),
    ("pad_z", 2, 0),
    ("design_contact_x", 2, 0),
    ("pivot_x", 1, -1),
    ("pivot_z", 1, -1),
    ("rod_anchor_x", 1, 0),
    ("rod_anchor_z", 1, 0),
    ("rod_length", 1, 0),
)
(
    _XA,
    _LF,
    _LR,
    _WD,
    _C0,
    _WEAR,
    _H0,
    _CB0,
    _SB0,
    _PX,
    _PZ,
    _MX0,
    _VX,
    _VZ,
    _RAX,
    _RAZ,
    _RL,
) = range(len(ARRAYS))
_ARRAY_PER_AXLE = tuple(a[1] for a in ARRAYS)
_ARRAY_EXTRA = tuple(a[2] for a in ARRAYS)
# start of array k = NS + _START_PER_AXLE[k] n + _START_EXTRA[k]: prefix sums of the table, so that the compiled
# code finds an offset without a loop (k is a compile-time constant there)
_START_PER_AXLE = tuple(sum(_ARRAY_PER_AXLE[:k]) for k in range(len(ARRAYS) + 1))
_START_EXTRA = tuple(sum(_ARRAY_EXTRA[:k]) for k in range(len(ARRAYS) + 1))

#: recorded outputs: (name, entries per axle, extra entries), in record order; length = per_axle * n + extra, as
#: in :data:`ARRAYS`. New outputs go at the end, so that the earlier ones keep their slices.
RECORD = (
    ("tyre_load", 1, 0),
    ("spring_load", 1, 0),
    ("friction_force", 2, 0),
    ("stick", 2, 0),
    ("contact_shift", 2, 0),
    ("plastic_slip", 2, 0),
    ("axle_position", 1, 0),
    ("stop_moment", 1, -1),
    ("spring_deflection", 1, 0),
    ("spring_hysteresis", 1, 0),
)
(
    _REC_TYRE,
    _REC_SPRING,
    _REC_FRICTION,
    _REC_STICK,
    _REC_SHIFT,
    _REC_SLIP,
    _REC_AXLE_X,
    _REC_STOP,
    _REC_DEFLECTION,
    _REC_HYSTERESIS,
) = range(len(RECORD))
_RECORD_START_PER_AXLE = tuple(sum(r[1] for r in RECORD[:k]) for k in range(len(RECORD) + 1))
_RECORD_START_EXTRA = tuple(sum(r[2] for r in RECORD[:k]) for k in range(len(RECORD) + 1))
#: record entries per axle: ``RECORD_PER_AXLE * n`` is at least the record's length, :func:`record_length` (n)
#: exactly (the per-equaliser outputs are one short of n)
RECORD_PER_AXLE = _RECORD_START_PER_AXLE[-1]

#: history variables, committed at converged steps: (name, entries per axle, extra entries), in order
HISTORY = (
    ("plastic_slip", 2, 0),
    ("spring_deflection", 1, 0),
    ("spring_hysteresis", 1, 0),
)
_HIST_SLIP, _HIST_DEFLECTION, _HIST_HYSTERESIS = range(len(HISTORY))
_HISTORY_START = tuple(sum(h[1] for h in HISTORY[:k]) for k in range(len(HISTORY) + 1))


@njit(cache=True, inline="always")
def history_start(k, n):
    """Index in the history of the first entry of variable k (an index into :data:`HISTORY`) for n axles.

    k = len(HISTORY) gives the history's length.
    """
    return _HISTORY_START[k] * n


def history_length(n: int) -> int:
    """Length of the history of n axles: the plastic slips, then each spring's deflection and hysteretic force."""
    return int(history_start(len(HISTORY), n))


def history_slices(n: int) -> dict[str, slice]:
    """Where each history variable sits in the history of n axles, by name."""
    return {
        name: slice(int(history_start(k, n)), int(history_start(k + 1, n))) for k, (name, _, _) in enumerate(HISTORY)
    }


# ---- layout ----------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def array_length(k, n):
    """Number of entries of packed array k (an index into :data:`ARRAYS`) for n axles."""
    return _ARRAY_PER_AXLE[k] * n + _ARRAY_EXTRA[k]


@njit(cache=True, inline="always")
def array_start(k, n):
    """Index in ``data_f`` of the first entry of packed array k (an index into :data:`ARRAYS`) for n axles.

    k = len(ARRAYS) gives the length of ``data_f``.
    """
    return NS + _START_PER_AXLE[k] * n + _START_EXTRA[k]


def array_offsets(n: int) -> dict[str, tuple[int, int]]:
    """Start and length of each packed array in ``data_f`` for n axles, by name."""
    return {name: (int(array_start(k, n)), int(array_length(k, n))) for k, (name, _, _) in enumerate(ARRAYS)}


def data_length(n: int) -> int:
    """Length of ``data_f`` for n axles."""
    return int(array_start(len(ARRAYS), n))


@njit(cache=True, inline="always")
def record_start(k, n):
    """Index in the record of the first entry of output k (an index into :data:`RECORD`) for n axles.

    k = len(RECORD) gives the record's length.
    """
    return _RECORD_START_PER_AXLE[k] * n + _RECORD_START_EXTRA[k]


def record_length(n: int) -> int:
    """Length of the record of n axles."""
    return int(record_start(len(RECORD), n))


def record_slices(n: int) -> dict[str, slice]:
    """Where each recorded output sits in the record of n axles, by name."""
    return {name: slice(int(record_start(k, n)), int(record_start(k + 1, n))) for k, (name, _, _) in enumerate(RECORD)}


#: scratch arrays of :func:`_internal` in the work buffer, in order: (name, length per axle, extra length)
WORK = (
    ("pivot_x", 1, -1),
    ("pivot_z", 1, -1),
    ("material_x", 2, 0),
    ("material_z", 2, 0),
    ("pad_sin", 2, 0),
    ("pad_cos", 2, 0),
    ("contact_x", 2, 0),
    ("contact_z", 2, 0),
    ("friction_force", 2, 0),
    ("stick", 2, 0),
    ("normal_load", 2, 0),
    ("spring_load", 1, 0),
    ("equaliser_cos", 1, -1),
    ("equaliser_sin", 1, -1),
    ("axle_x", 1, 0),
    ("axle_x_pitch", 1, 0),
    ("axle_x_rise", 1, 0),
)
_WORK_START_PER_AXLE = tuple(sum(w[1] for w in WORK[:k]) for k in range(len(WORK) + 1))
_WORK_START_EXTRA = tuple(sum(w[2] for w in WORK[:k]) for k in range(len(WORK) + 1))


@njit(cache=True, inline="always")
def _work_start(k, n):
    """Index in the work buffer of scratch array k (an index into :data:`WORK`); k = len(WORK) gives the total."""
    return _WORK_START_PER_AXLE[k] * n + _WORK_START_EXTRA[k]


@njit(cache=True, inline="always")
def scratch_size(n):
    """Length of the work array :func:`_internal` needs for n axles (:data:`WORK`)."""
    return _work_start(len(WORK), n)


def work_size(n: int) -> int:
    """Length of the work array :func:`force` needs for n axles: :func:`scratch_size` plus 4n for the tangent."""
    return int(scratch_size(n)) + 4 * n


(
    _W_PIVOT_X,
    _W_PIVOT_Z,
    _W_MAT_X,
    _W_MAT_Z,
    _W_PAD_SIN,
    _W_PAD_COS,
    _W_CONTACT_X,
    _W_CONTACT_Z,
    _W_FRICTION,
    _W_STICK,
    _W_NORMAL,
    _W_SPRING,
    _W_EQ_COS,
    _W_EQ_SIN,
    _W_AXLE_X,
    _W_AXLE_X_PITCH,
    _W_AXLE_X_RISE,
) = range(len(WORK))
# The scratch arrays are read and written as work[_work_start(k, n) + i], not through views: each view of a
# buffer is a new array object, and its reference counting at every use cost more than the arithmetic it served.
