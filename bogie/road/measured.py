"""A measured road profile, read from CSV (distance, height) and interpolated."""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from bogie.road._checks import _finite_array, _read_only


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
