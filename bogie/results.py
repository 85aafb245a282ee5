"""The result type shared by the dynamic models (linear Stage 3 and non-linear Stage 4)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import metrics

#: a road profile: height [m] as a function of distance along the road [m]
Profile = Callable[[ArrayLike], NDArray[np.float64]]


#: the unit of each history a run records, by name without its axle or end index (SI; "-" non-dimensional): the
#: linear model's (bogie.steel.linear) and the non-linear model's (bogie.steel.force.layout.RECORD,
#: bogie.steel.nonlinear) extras
HISTORY_UNITS: dict[str, str] = {
    "wheel_load": "N", "nondimensional_load": "-", "p": "-", "p1": "-", "chassis_pitch": "rad",
    "centre_displacement": "m", "equaliser_rotation": "rad", "road_height": "m", "axle_displacement": "m",
    "load_factor": "-", "spring_load": "N", "friction_force": "N", "stick": "-", "contact_shift": "m",
    "plastic_slip": "m", "axle_position": "m", "stop_moment": "N m", "spring_deflection": "m",
    "spring_hysteresis": "N",
}  # fmt: skip


def history_unit(column: str) -> str:
    """The unit of a history column of :meth:`DynamicResult.to_frame` (``wheel_load_3`` -> ``N``); ``?`` for a name
    :data:`HISTORY_UNITS` does not know."""
    name = column
    while name and name not in HISTORY_UNITS and "_" in name and name.rsplit("_", 1)[1].isdigit():
        name = name.rsplit("_", 1)[0]
    return HISTORY_UNITS.get(name, "?")


@dataclass(frozen=True, repr=False)
class DynamicResult:
    """Time history of one dynamic simulation.

    Attributes
    ----------
    t
        Times [s], shape (n_t,).
    wheel_loads
        Load of each axle's tyres on the road [N], shape (n_t, n_axles).
    reference_load
        The equal share W_ref of the bogie's static load used to make loads non-dimensional [N].
    status
        "ok" or "failed"; a failed run holds the history up to the failure.
    message
        "ok" or why the run failed, with the time and residual.
    extras
        Further named histories of the model (chassis pitch, equaliser rotations, contact positions, friction
        forces, ...), each of shape (n_t,) or (n_t, k).
    """

    t: NDArray[np.float64]
    wheel_loads: NDArray[np.float64]
    reference_load: float
    status: str
    message: str
    extras: Mapping[str, NDArray[Any]] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """True if the run completed."""
        return self.status == "ok"

    def __repr__(self) -> str:
        """One line: status, size, time span, wheel-load range and the names of the extra histories."""
        n_t, n_axles = np.shape(self.wheel_loads) if np.ndim(self.wheel_loads) == 2 else (len(self.t), 0)
        span = f"t {self.t[0]:g} to {self.t[-1]:g} s" if len(self.t) else "no time steps"
        loads = np.asarray(self.wheel_loads, dtype=float)
        finite = loads.size and np.isfinite(loads).all()
        load = f", wheel loads {loads.min():.6g} to {loads.max():.6g} N" if finite else ""
        why = "" if self.success else f" ({self.message})"
        extras = f", extras: {', '.join(self.extras)}" if self.extras else ""
        return (
            f"{type(self).__name__}(status={self.status!r}{why}, {n_axles} axles, {n_t} samples, {span}{load}{extras})"
        )

    @property
    def nondimensional_loads(self) -> NDArray[np.float64]:
        """Wheel loads over the reference load W / W_ref [-]."""
        return self.wheel_loads / self.reference_load

    @property
    def p(self) -> NDArray[np.float64]:
        """History of the wheel load deviation p (Equation 2) of the non-dimensional loads [-]."""
        return metrics.p(self.nondimensional_loads)

    @property
    def p1(self) -> NDArray[np.float64]:
        """History of P1 (Equation 4) of the non-dimensional loads [-]."""
        return metrics.p1(self.nondimensional_loads)

    @property
    def peak_p(self) -> float:
        """Largest p over the run [-]."""
        return float(np.max(self.p))

    @property
    def peak_p1(self) -> float:
        """Largest P1 over the run [-]."""
        return float(np.max(self.p1))

    @property
    def rms(self) -> float:
        """RMS equalisation parameter of Equation 5 over the run [-]."""
        return float(metrics.rms(self.wheel_loads))

    def to_frame(self, units: bool = False):
        """The histories as a pandas DataFrame indexed by time (loads in N, non-dimensional loads, p, p1, extras);
        ``units``: each column named ``"name [unit]"`` (:data:`HISTORY_UNITS`), the index ``"t [s]"``, as the CLI's
        CSV writes them."""
        import pandas as pd

        n = self.wheel_loads.shape[1]
        cols: dict[str, NDArray[Any]] = {}
        for i in range(n):
            cols[f"wheel_load_{i + 1}"] = self.wheel_loads[:, i]
        for i in range(n):
            cols[f"nondimensional_load_{i + 1}"] = self.nondimensional_loads[:, i]
        cols["p"] = self.p
        cols["p1"] = self.p1
        for name, values in self.extras.items():
            arr = np.asarray(values)
            if arr.ndim == 1:
                cols[name] = arr
            else:
                for k in range(arr.shape[1]):
                    cols[f"{name}_{k + 1}"] = arr[:, k]  # numbered from 1, as the axles are
        frame = pd.DataFrame(cols, index=pd.Index(self.t, name="t"))
        if units:
            frame = frame.rename(columns=lambda c: f"{c} [{history_unit(c)}]")
            frame.index.name = "t [s]"
        return frame
