"""Deterministic road inputs: a flat road, a ramped step, a sinusoid; and :func:`axle_heights`, the height under
each axle over time (the wheel-path delay).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from bogie import numerics
from bogie.road._checks import _finite_array
from bogie.settings import check_value


@dataclass(frozen=True)
class Flat:
    """A level road: height 0 m everywhere."""

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Road height [m] at road distance ``x`` [m]; zeros of the shape of ``x``."""
        return np.zeros_like(_finite_array("x", x, "m"))


@dataclass(frozen=True)
class RampedStep:
    """The ramped step of the reference's Figure 4: up a ramp, along a plateau, down a ramp.

    Zero before ``start``; a linear ramp up over ``ramp_length`` to ``rise``; a plateau of ``plateau_length``; a
    linear ramp down over ``ramp_length``; zero after :attr:`end`. The reference's dimensions are lost with its
    figure, so the defaults are ours (reasons in ``docs/road.md``):

    * ``ramp_length = 0.15`` m: about the distance over which the centre of a 0.5 m radius tyre climbs a 25 mm
      step, sqrt(2 R h) = sqrt(2 * 0.5 * 0.025) = 0.158 m, which is what the reference's ramps were for
      ("a realistic motion of the wheel centre").
    * ``plateau_length = 1.5`` m: longer than the 1.31 m axle spacing, so the event has three phases (front wheel
      alone on the plateau, both, rear alone), and the whole event, 2 * 0.15 + 1.5 + 1.31 = 3.11 m, takes about
      15 s at 0.2 m/s and about 1/3 s at 10 m/s, as the reference says of its low- and high-speed runs.

    Parameters
    ----------
    rise
        Height of the plateau [m], in [0, 0.5].
    ramp_length
        Horizontal length of each ramp [m], in (0, 10].
    plateau_length
        Horizontal length of the plateau [m], in [0, 100].
    start
        Road distance where the up-ramp begins [m], in [-1e6, 1e6].
    """

    rise: float = 0.025
    ramp_length: float = 0.15
    plateau_length: float = 1.5
    start: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "rise", check_value("rise", self.rise, "m", low=0.0, high=0.5))
        object.__setattr__(
            self, "ramp_length", check_value("ramp_length", self.ramp_length, "m", low=0.0, high=10.0, low_open=True)
        )
        object.__setattr__(
            self, "plateau_length", check_value("plateau_length", self.plateau_length, "m", low=0.0, high=100.0)
        )
        object.__setattr__(self, "start", check_value("start", self.start, "m", low=-1e6, high=1e6))

    @property
    def end(self) -> float:
        """Road distance where the down-ramp ends [m]."""
        return self.start + 2.0 * self.ramp_length + self.plateau_length

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Road height [m] at road distance ``x`` [m]."""
        s = _finite_array("x", x, "m") - self.start
        r = self.ramp_length
        up = s / r
        down = (2.0 * r + self.plateau_length - s) / r
        return self.rise * np.clip(np.minimum(up, down), 0.0, 1.0)


@dataclass(frozen=True)
class Sinusoid:
    """A sinusoidal road that starts at ``start``: h = amplitude sin(2 pi (x - start) / wavelength + phase).

    Zero before ``start``, so a simulation can begin at rest on a level road; with ``phase = 0`` the height is
    continuous there (any other phase puts a step of amplitude * sin(phase) at ``start``). For a sinusoid without
    a start, put ``start`` far behind the vehicle.

    Parameters
    ----------
    amplitude
        Half the peak-to-peak height [m], in [0, 1].
    wavelength
        Length of one cycle [m], in (0, 1e4].
    phase
        Phase at ``start`` [rad], in [-2 pi, 2 pi].
    start
        Road distance where the sinusoid begins [m], in [-1e6, 1e6].
    """

    amplitude: float
    wavelength: float
    phase: float = 0.0
    start: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude", check_value("amplitude", self.amplitude, "m", low=0.0, high=1.0))
        object.__setattr__(
            self, "wavelength", check_value("wavelength", self.wavelength, "m", low=0.0, high=1e4, low_open=True)
        )
        object.__setattr__(
            self, "phase", check_value("phase", self.phase, "rad", low=-2.0 * math.pi, high=2.0 * math.pi)
        )
        object.__setattr__(self, "start", check_value("start", self.start, "m", low=-1e6, high=1e6))

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Road height [m] at road distance ``x`` [m]."""
        s = _finite_array("x", x, "m") - self.start
        h = self.amplitude * numerics.sin(2.0 * np.pi * s / self.wavelength + self.phase)
        return np.where(s >= 0.0, h, 0.0)


def axle_heights(
    profile: Callable[[np.ndarray], np.ndarray],
    axle_x: ArrayLike,
    speed: float,
    t: ArrayLike,
    front_axle_start: float = 0.0,
) -> np.ndarray:
    """Road height under each axle over time, with the wheel-path delay of the trailing axles.

    The vehicle travels towards increasing road distance. At t = 0 the front axle (``axle_x[0]``) stands at road
    distance ``front_axle_start`` and axle i stands ``axle_x[i] - axle_x[0]`` behind it, so axle i sees
    profile(front_axle_start - (axle_x[i] - axle_x[0]) + speed t): the front axle's history delayed by
    (axle_x[i] - axle_x[0]) / speed.

    Parameters
    ----------
    profile
        A road profile: road distance [m] (any shape) -> height [m].
    axle_x
        Axle positions rearward of the king pin, front to rear, strictly increasing [m].
    speed
        Forward speed [m/s], in [0, 100].
    t
        Times [s], a 1-D array.
    front_axle_start
        Road distance of the front axle at t = 0 [m], in [-1e6, 1e6].

    Returns
    -------
    numpy.ndarray
        Road heights [m], shape ``(len(t), n_axles)``.
    """
    ax = _finite_array("axle_x", axle_x, "m")
    if ax.ndim != 1 or ax.size < 1:
        raise ValueError(f"axle_x = {axle_x!r} must be a 1-D sequence of at least 1 axle position in m")
    if (np.diff(ax) <= 0.0).any():
        raise ValueError(f"axle_x = {ax.tolist()!r} must increase strictly from front to rear (m)")
    v = check_value("speed", speed, "m/s", low=0.0, high=100.0)
    times = _finite_array("t", t, "s")
    if times.ndim != 1:
        raise ValueError(f"t must be a 1-D array of times in s, got shape {times.shape}")
    x0 = check_value("front_axle_start", front_axle_start, "m", low=-1e6, high=1e6)
    road_x = x0 - (ax - ax[0])[np.newaxis, :] + v * times[:, np.newaxis]
    heights = np.asarray(profile(road_x), dtype=float)
    if heights.shape != road_x.shape:
        raise ValueError(f"profile returned shape {heights.shape} for road distances of shape {road_x.shape}")
    return heights
