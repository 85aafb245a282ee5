"""Road inputs: vertical road profiles as functions of distance, and the height under each axle over time.

A profile is a frozen dataclass whose ``__call__(x)`` maps road distance ``x`` [m] (array-like, any shape) to road
height [m] (an ndarray of the same shape), vectorised. The vehicle travels in the direction of increasing road
distance; :func:`axle_heights` delays each trailing axle by its spacing behind the front axle (the wheel-path
delay). Formulas, chosen lengths and the verification of the ISO 8608 generator are in ``docs/road.md``.

References
----------
ISO 8608:2016, Mechanical vibration - Road surface profiles - Reporting of measured data, International
Organization for Standardization (road classes and displacement PSD of :class:`ISO8608Profile`).
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from bogie import numerics

#: ISO 8608 reference spatial frequency n0 [cycle/m]
ISO8608_N0 = 0.1

#: ISO 8608 class -> geometric-mean displacement PSD G_d(n0) [m^3]: 16e-6 * 4**k for classes A..H (k = 0..7)
ISO8608_CLASSES: dict[str, float] = {c: 16e-6 * 4.0**k for k, c in enumerate("ABCDEFGH")}

#: points of the ISO 8608 interpolation grid per wavelength of the highest harmonic [-]
_GRID_POINTS_PER_WAVELENGTH = 64


def _range_text(low: float, high: float, unit: str, low_inclusive: bool, high_inclusive: bool) -> str:
    return f"{'[' if low_inclusive else '('}{low:g}, {high:g}{']' if high_inclusive else ')'} {unit}"


def _check_range(
    name: str,
    value: Any,
    low: float,
    high: float,
    unit: str,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
) -> float:
    """``value`` as a float, or a ValueError naming ``name``, the value, the allowed range and the unit."""
    allowed = _range_text(low, high, unit, low_inclusive, high_inclusive)
    if isinstance(value, bool):
        raise ValueError(f"{name} = {value!r} is not a number: must be in {allowed}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not a number: must be in {allowed}") from None
    ok_low = v >= low if low_inclusive else v > low
    ok_high = v <= high if high_inclusive else v < high
    if not (math.isfinite(v) and ok_low and ok_high):
        raise ValueError(f"{name} = {v!r} is out of range: must be in {allowed}")
    return v


def _finite_array(name: str, value: ArrayLike, unit: str) -> np.ndarray:
    """``value`` as a float ndarray, or a ValueError naming the first non-finite entry."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not an array of numbers in {unit}") from None
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f"{name}[{', '.join(map(str, idx))}]" if idx else name
        raise ValueError(f"{where} = {float(arr[idx])!r} is not finite: every {name} must be a finite number in {unit}")
    return arr


def _read_only(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=float)
    arr.flags.writeable = False
    return arr


def _frozen(arr: np.ndarray) -> np.ndarray:
    """``arr`` itself (a float array made here, referenced nowhere else), made read-only without a copy."""
    arr.flags.writeable = False
    return arr


def _uniform_interp(
    x: np.ndarray, grid_x: np.ndarray, grid_h: np.ndarray, slope: np.ndarray, points_per_m: float
) -> np.ndarray | None:
    """``np.interp(x, grid_x, grid_h)`` value for value on a uniform grid (``grid_x[k]`` = k / points_per_m up to
    rounding), the interval found by arithmetic instead of a binary search; None (use np.interp) if some x is not
    strictly inside the grid's span after one correction each way.

    np.interp returns ``grid_h[j]`` where x is ``grid_x[j]`` and ``slope[j] (x - grid_x[j]) + grid_h[j]`` between,
    ``slope[j]`` = (grid_h[j + 1] - grid_h[j]) / (grid_x[j + 1] - grid_x[j]): the same operations here.
    """
    last = len(grid_x) - 2
    j = np.minimum((x * points_per_m).astype(np.intp), last)
    np.maximum(j, 0, out=j)
    j -= grid_x[j] > x
    np.maximum(j, 0, out=j)
    j += grid_x[j + 1] <= x
    np.minimum(j, last, out=j)
    lo = grid_x[j]
    if not ((lo <= x) & (x < grid_x[j + 1])).all():
        return None
    h = grid_h[j]
    return np.where(x == lo, h, slope[j] * (x - lo) + h)


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
        object.__setattr__(self, "rise", _check_range("rise", self.rise, 0.0, 0.5, "m"))
        object.__setattr__(
            self, "ramp_length", _check_range("ramp_length", self.ramp_length, 0.0, 10.0, "m", low_inclusive=False)
        )
        object.__setattr__(self, "plateau_length", _check_range("plateau_length", self.plateau_length, 0.0, 100.0, "m"))
        object.__setattr__(self, "start", _check_range("start", self.start, -1e6, 1e6, "m"))

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
        object.__setattr__(self, "amplitude", _check_range("amplitude", self.amplitude, 0.0, 1.0, "m"))
        object.__setattr__(
            self, "wavelength", _check_range("wavelength", self.wavelength, 0.0, 1e4, "m", low_inclusive=False)
        )
        object.__setattr__(self, "phase", _check_range("phase", self.phase, -2.0 * math.pi, 2.0 * math.pi, "rad"))
        object.__setattr__(self, "start", _check_range("start", self.start, -1e6, 1e6, "m"))

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Road height [m] at road distance ``x`` [m]."""
        s = _finite_array("x", x, "m") - self.start
        h = self.amplitude * numerics.sin(2.0 * np.pi * s / self.wavelength + self.phase)
        return np.where(s >= 0.0, h, 0.0)


@dataclass(frozen=True)
class ISO8608Profile:
    """A random road with the ISO 8608 displacement PSD G_d(n) = G_d(n0) (n / n0)^-w, n0 = 0.1 cycle/m.

    A sum of cosines with random phases (ISO 8608 Annex; model notes "Road inputs"),
    h(x) = sum_k sqrt(2 G_d(n_k) dn) cos(2 pi n_k x + phi_k), over the harmonics n_k = k / length (dn = 1 / length)
    that lie in [n_min, n_max], phi_k uniform on [0, 2 pi) from ``numpy.random.default_rng(seed)``. The phase of
    harmonic k is the k-th draw whatever the band, so the same seed with a narrower band gives the band-filtered
    version of the same road, and another class the same road scaled by 2 per class.

    The profile is periodic with period ``length``. It is synthesised once by an inverse real FFT on a grid of
    2^m >= 64 points per wavelength of the highest harmonic, and evaluated by linear interpolation on that grid
    (exact at the grid points; elsewhere within (2 pi n_k dx)^2 / 8 <= 0.12 % of each component's amplitude).

    Parameters
    ----------
    road_class
        ISO 8608 class, one of A..H; G_d(n0) = 16e-6 * 4^k m^3 with k = 0 for A to 7 for H (the geometric mean of
        the class). Ignored, and stored as None, when ``gd_n0`` is given.
    gd_n0
        Displacement PSD at n0 [m^3], in (0, 1]; overrides ``road_class``.
    length
        Length of the generated road, its period [m], in [1, 1e4].
    seed
        Seed of the random phases, a non-negative integer; the same seed gives the identical profile.
    n_min, n_max
        Band of spatial frequencies synthesised [cycle/m], 0 < n_min < n_max <= 10 (ISO 8608: 0.011 to 2.83).
    waviness
        Exponent w of the PSD [-], in (0, 5]; ISO 8608 uses 2.

    Attributes
    ----------
    frequencies
        Spatial frequencies n_k of the cosines [cycle/m].
    amplitudes
        Their amplitudes sqrt(2 G_d(n_k) dn) [m].
    phases
        Their phases phi_k [rad].

    References
    ----------
    ISO 8608:2016, Mechanical vibration - Road surface profiles - Reporting of measured data, International
    Organization for Standardization (the classes A to H, n0 = 0.1 cycle/m, w = 2; first edition 1995).
    """

    road_class: str | None = "C"
    gd_n0: float | None = None
    length: float = 200.0
    seed: int = 0
    n_min: float = 0.011
    n_max: float = 2.83
    waviness: float = 2.0
    frequencies: np.ndarray = field(init=False, repr=False, compare=False)
    amplitudes: np.ndarray = field(init=False, repr=False, compare=False)
    phases: np.ndarray = field(init=False, repr=False, compare=False)
    _grid_x: np.ndarray = field(init=False, repr=False, compare=False)
    _grid_h: np.ndarray = field(init=False, repr=False, compare=False)
    _grid_slope: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.gd_n0 is not None:
            object.__setattr__(self, "gd_n0", _check_range("gd_n0", self.gd_n0, 0.0, 1.0, "m^3", low_inclusive=False))
            object.__setattr__(self, "road_class", None)
        elif not isinstance(self.road_class, str) or self.road_class.upper() not in ISO8608_CLASSES:
            raise ValueError(
                f"road_class = {self.road_class!r} must be one of {', '.join(ISO8608_CLASSES)} (or give gd_n0 in m^3)"
            )
        else:
            object.__setattr__(self, "road_class", self.road_class.upper())
        length = _check_range("length", self.length, 1.0, 1e4, "m")
        object.__setattr__(self, "length", length)
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed = {self.seed!r} must be a non-negative integer")
        n_min = _check_range("n_min", self.n_min, 0.0, 10.0, "cycle/m", low_inclusive=False)
        n_max = _check_range("n_max", self.n_max, 0.0, 10.0, "cycle/m", low_inclusive=False)
        if n_max <= n_min:
            raise ValueError(f"n_max = {n_max!r} must be greater than n_min = {n_min!r} cycle/m")
        object.__setattr__(self, "n_min", n_min)
        object.__setattr__(self, "n_max", n_max)
        object.__setattr__(
            self, "waviness", _check_range("waviness", self.waviness, 0.0, 5.0, "-", low_inclusive=False)
        )

        # the tolerance keeps a band edge that is a harmonic up to rounding (e.g. 0.015 * 200) inside the band
        k_lo = max(1, math.ceil(n_min * length - 1e-9))
        k_hi = math.floor(n_max * length + 1e-9)
        if k_hi < k_lo:
            raise ValueError(
                f"length = {length!r} m puts no harmonic k / length in [n_min, n_max] = [{n_min:g}, {n_max:g}] "
                f"cycle/m: make it at least 1 / (n_max - n_min) = {1.0 / (n_max - n_min):g} m"
            )
        k = np.arange(k_lo, k_hi + 1)
        freqs = k / length
        # self.psd(freqs), without its checks of a frequency array the harmonics make positive and finite
        amps = np.sqrt(2.0 * (self.psd_n0 * numerics.power(freqs / ISO8608_N0, -self.waviness)) / length)
        phases = np.random.default_rng(self.seed).uniform(0.0, 2.0 * np.pi, size=k_hi)[k_lo - 1 :]
        n_grid = 2 ** math.ceil(math.log2(_GRID_POINTS_PER_WAVELENGTH * k_hi))
        spectrum = np.zeros(n_grid // 2 + 1, dtype=complex)
        # irfft(X)[j] = (2 / N) Re sum_k X_k e^(2 pi i k j / N) for 0 < k < N / 2
        spectrum[k] = 0.5 * n_grid * amps * (numerics.cos(phases) + 1j * numerics.sin(phases))
        grid_h = np.empty(n_grid + 1)
        np.fft.irfft(spectrum, n=n_grid, out=grid_h[:n_grid])
        grid_h[n_grid] = grid_h[0]
        object.__setattr__(self, "frequencies", _frozen(freqs))
        object.__setattr__(self, "amplitudes", _frozen(amps))
        object.__setattr__(self, "phases", _frozen(phases))
        object.__setattr__(self, "_grid_h", _frozen(grid_h))
        # the grid's distances and slopes are made when a call first needs them: a weighing's road table reads the
        # grid's heights only (:meth:`grid_heights`), and each full-length array cost as much as a tenth of the FFT
        object.__setattr__(self, "_grid_x", None)
        object.__setattr__(self, "_grid_slope", None)

    def _interpolation_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """The grid's distances [m] and the slopes between its points [-], made on first use."""
        if self._grid_x is None:
            n_grid = len(self._grid_h) - 1
            gx = _frozen(self.length * np.arange(n_grid + 1) / n_grid)
            gh = self._grid_h
            object.__setattr__(self, "_grid_slope", _frozen((gh[1:] - gh[:-1]) / (gx[1:] - gx[:-1])))
            object.__setattr__(self, "_grid_x", gx)
        return self._grid_x, self._grid_slope

    @property
    def grid_spacing(self) -> float:
        """Spacing of the grid the profile is synthesised on and interpolated from [m]: length / points."""
        return self.length / (len(self._grid_h) - 1)

    def grid_heights(self, k_from: int, k_to: int) -> np.ndarray:
        """Heights [m] at the grid points k_from .. k_to (any integers: the profile repeats every ``length``), at
        road distances k ``grid_spacing`` [m]; exactly the values :meth:`__call__` gives there."""
        n_grid = len(self._grid_h) - 1
        grid = self._grid_h
        if 0 <= k_from <= k_to <= n_grid:  # one period: a slice (the grid's last point is its first again)
            return grid[k_from : k_to + 1].copy()
        if -n_grid <= k_from < 0 <= k_to <= n_grid:  # the end of the period before, then this one: two slices
            return np.concatenate((grid[n_grid + k_from : n_grid], grid[: k_to + 1]))
        return grid[np.arange(k_from, k_to + 1) % n_grid]

    @property
    def psd_n0(self) -> float:
        """Displacement PSD at n0 = 0.1 cycle/m in use, G_d(n0) [m^3]."""
        return self.gd_n0 if self.gd_n0 is not None else ISO8608_CLASSES[self.road_class]

    @property
    def rms_height(self) -> float:
        """Root-mean-square height of the generated profile over one period, sqrt(sum_k A_k^2 / 2) [m]."""
        return float(np.sqrt(0.5 * np.sum(self.amplitudes**2)))

    def psd(self, n: ArrayLike) -> np.ndarray:
        """Target one-sided displacement PSD G_d(n) = G_d(n0) (n / n0)^-w [m^3] at spatial frequency ``n`` [cycle/m].

        The model's PSD at every n > 0; the generated profile carries it only on [n_min, n_max].
        """
        n = _finite_array("n", n, "cycle/m")
        if (n <= 0.0).any():
            raise ValueError(f"n = {float(n[n <= 0.0].flat[0])!r} is out of range: must be in (0, inf) cycle/m")
        return self.psd_n0 * numerics.power(n / ISO8608_N0, -self.waviness)

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Road height [m] at road distance ``x`` [m] (any real x: the profile repeats every ``length``)."""
        x = _finite_array("x", x, "m")
        if not (x.size and 0.0 <= x.min() and x.max() < self.length):
            x = np.mod(x, self.length)
        # else x mod length is x itself on [0, length) (fmod is exact): the approach roads' case (issue 15)
        grid_x, grid_slope = self._interpolation_grid()
        if x.ndim:
            # a road's thousands of points: the grid's interval by arithmetic, a fifth of np.interp's binary search
            h = _uniform_interp(x, grid_x, self._grid_h, grid_slope, (len(grid_x) - 1) / self.length)
            if h is not None:
                return h
        return np.interp(x, grid_x, self._grid_h)


@dataclass(frozen=True, eq=False)
class MeasuredProfile:
    """A measured road: heights at strictly increasing distances, linearly interpolated between them.

    Outside the measured range [distance[0], distance[-1]] the height is unknown, and a call there raises
    ValueError rather than inventing a road (within a rounding tolerance of 1e-9 of the span the end value
    is used). Compared by identity.

    Parameters
    ----------
    distance
        Road distances of the measurements, strictly increasing [m].
    height
        Road heights at those distances [m].
    """

    distance: np.ndarray
    height: np.ndarray

    def __post_init__(self) -> None:
        d = _finite_array("distance", self.distance, "m")
        h = _finite_array("height", self.height, "m")
        if d.ndim != 1 or h.ndim != 1:
            raise ValueError(
                f"distance and height must be 1-D arrays [m], got shapes {d.shape} and {h.shape}: "
                "one height per distance"
            )
        if d.size != h.size:
            raise ValueError(f"distance has {d.size} points but height has {h.size}: give one height [m] per distance")
        if d.size < 2:
            raise ValueError(f"a MeasuredProfile needs at least 2 points (distance [m], height [m]), got {d.size}")
        steps = np.diff(d)
        if (steps <= 0.0).any():
            i = int(np.argmax(steps <= 0.0))
            raise ValueError(
                f"distance must increase strictly: distance[{i + 1}] = {float(d[i + 1])!r} m is not greater than "
                f"distance[{i}] = {float(d[i])!r} m"
            )
        object.__setattr__(self, "distance", _read_only(d))
        object.__setattr__(self, "height", _read_only(h))

    @classmethod
    def from_csv(cls, path: str | os.PathLike[str]) -> MeasuredProfile:
        """Read a two-column CSV file of distance [m] and height [m], comma separated.

        One header line (the first non-blank line, if it is not two numbers) is allowed; blank lines are skipped.

        Parameters
        ----------
        path
            The CSV file.

        Returns
        -------
        MeasuredProfile
            The profile; ValueError names the file and line of a bad row, or what is wrong with the data.
        """
        distance: list[float] = []
        height: list[float] = []
        header_allowed = True
        with open(path, newline="") as fh:
            for line_no, row in enumerate(csv.reader(fh), start=1):
                cells = [c.strip() for c in row]
                if not any(cells):
                    continue
                if len(cells) != 2:
                    raise ValueError(
                        f"{os.fspath(path)}: line {line_no} has {len(cells)} columns but a road profile needs exactly "
                        "2 (distance [m], height [m])"
                    )
                try:
                    d, h = float(cells[0]), float(cells[1])
                except ValueError:
                    if header_allowed:
                        header_allowed = False
                        continue
                    raise ValueError(
                        f"{os.fspath(path)}: line {line_no} = {row!r} is not two numbers (distance [m], height [m])"
                    ) from None
                header_allowed = False
                distance.append(d)
                height.append(h)
        try:
            return cls(distance=np.array(distance), height=np.array(height))
        except ValueError as err:
            raise ValueError(f"{os.fspath(path)}: {err}") from None

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Road height [m] at road distance ``x`` [m], inside the measured range."""
        x = _finite_array("x", x, "m")
        lo, hi = self.distance[0], self.distance[-1]
        tol = 1e-9 * (hi - lo)
        outside = (x < lo - tol) | (x > hi + tol)
        if outside.any():
            raise ValueError(
                f"x = {float(x[outside].flat[0])!r} m is outside the measured range [{lo:g}, {hi:g}] m of this "
                "MeasuredProfile: every road distance must lie inside it (for axle_heights, choose front_axle_start, "
                "speed and t so that every axle stays on the measured road)"
            )
        return np.interp(x, self.distance, self.height)


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
    v = _check_range("speed", speed, 0.0, 100.0, "m/s")
    times = _finite_array("t", t, "s")
    if times.ndim != 1:
        raise ValueError(f"t must be a 1-D array of times in s, got shape {times.shape}")
    x0 = _check_range("front_axle_start", front_axle_start, -1e6, 1e6, "m")
    road_x = x0 - (ax - ax[0])[np.newaxis, :] + v * times[:, np.newaxis]
    heights = np.asarray(profile(road_x), dtype=float)
    if heights.shape != road_x.shape:
        raise ValueError(f"profile returned shape {heights.shape} for road distances of shape {road_x.shape}")
    return heights
