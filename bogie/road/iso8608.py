"""Random road profiles of ISO 8608 (road classes A-H, the displacement PSD), generated on a grid and interpolated.

References
----------
ISO 8608:2016, Mechanical vibration - Road surface profiles - Reporting of measured data, International
Organization for Standardization (road classes and displacement PSD of :class:`ISO8608Profile`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from bogie import numerics
from bogie.road._checks import _finite_array, _frozen, _uniform_interp
from bogie.settings import check_value, refusal

#: ISO 8608 reference spatial frequency n0 [cycle/m]
ISO8608_N0 = 0.1

#: ISO 8608 class -> geometric-mean displacement PSD G_d(n0) [m^3]: 16e-6 * 4**k for classes A..H (k = 0..7)
ISO8608_CLASSES: dict[str, float] = {c: 16e-6 * 4.0**k for k, c in enumerate("ABCDEFGH")}  # numerics-ok: floats

#: points of the ISO 8608 interpolation grid per wavelength of the highest harmonic [-]
_GRID_POINTS_PER_WAVELENGTH = 64


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
            object.__setattr__(self, "gd_n0", check_value("gd_n0", self.gd_n0, "m^3", low=0.0, high=1.0, low_open=True))
            object.__setattr__(self, "road_class", None)
        elif not isinstance(self.road_class, str) or self.road_class.upper() not in ISO8608_CLASSES:
            raise ValueError(
                f"road_class = {self.road_class!r} must be one of {', '.join(ISO8608_CLASSES)} (or give gd_n0 in m^3)"
            )
        else:
            object.__setattr__(self, "road_class", self.road_class.upper())
        length = check_value("length", self.length, "m", low=1.0, high=1e4)
        object.__setattr__(self, "length", length)
        check_value("seed", self.seed, low=0, whole=True)
        n_min = check_value("n_min", self.n_min, "cycle/m", low=0.0, high=10.0, low_open=True)
        n_max = check_value("n_max", self.n_max, "cycle/m", low=0.0, high=10.0, low_open=True)
        if n_max <= n_min:
            raise ValueError(f"n_max = {n_max!r} must be greater than n_min = {n_min!r} cycle/m")
        object.__setattr__(self, "n_min", n_min)
        object.__setattr__(self, "n_max", n_max)
        object.__setattr__(
            self, "waviness", check_value("waviness", self.waviness, "-", low=0.0, high=5.0, low_open=True)
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
        n_grid = 2 ** math.ceil(math.log2(_GRID_POINTS_PER_WAVELENGTH * k_hi))  # numerics-ok: integers
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
            raise ValueError(refusal("n", float(n[n <= 0.0].flat[0]), "cycle/m", low=0.0, low_open=True))
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
