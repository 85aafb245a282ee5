"""A synthetic survey: simulated groups written as a survey file in the ``csv`` weighings format, to calibrate to as
to a real one (``docs/calibration.md``; its tractor ``SYNTHETIC_TRACTOR`` in ``docs/weighings.md``). Loads in kg.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from bogie.weighings.writers import write_weighings

__all__ = ["SYNTHETIC_TRACTOR", "write_csv_survey"]

#: the tractor a synthetic survey puts in front of each simulated group (:func:`write_csv_survey`): a 4x2 tractor,
#: steer and drive axle [kg] and the spacings steer-drive and drive-group [m]. Placeholders that make the group the
#: vehicle's third, a trailer group (bogie.weighings.groups); single axles, so no statistic of tandems or tri-axles
#: reads them
SYNTHETIC_TRACTOR = {"loads_kg": (6500.0, 10500.0), "spacings_m": (3.6, 6.0)}


def write_csv_survey(frame: pd.DataFrame, path: str | Path, speed_kmh: float = 80.0, spacing_m: float = 1.31) -> None:
    """Write simulated groups (:func:`simulate_fleet`'s wide loads [kg]) as a survey in the ``csv`` weighings format
    (``docs/weighings.md``), one semi-trailer a record, a second apart, at ``speed_kmh`` [km/h] and axle spacing
    ``spacing_m`` [m] within the group: a synthetic survey read as a real one
    (:func:`bogie.weighings.survey.observed_survey`). Each group is the trailer group of a vehicle behind
    :data:`SYNTHETIC_TRACTOR`; loads in whole kilograms."""
    steer, drive = SYNTHETIC_TRACTOR["loads_kg"]
    n_group = frame["n_axles"].to_numpy(dtype=np.int64)
    width = 2 + int(n_group.max()) if len(frame) else 5
    vehicles = pd.DataFrame({
        "timestamp": pd.Timestamp("2026-01-05T06:00:00") + pd.to_timedelta(np.arange(len(frame)), unit="s"),
        "speed": speed_kmh / 3.6, "lane": 1, "n_axles": 2 + n_group,
    })  # fmt: skip
    for i in range(width):
        if i < 2:
            load = np.full(len(frame), (steer, drive)[i])
        else:
            column = frame[f"axle_load_{i - 1}"].to_numpy(dtype=float) if i - 2 < 3 else np.zeros(len(frame))
            load = np.where(n_group > i - 2, np.round(column), np.nan)
        vehicles[f"axle_load_{i + 1}"] = load
    for i in range(width - 1):
        gap = SYNTHETIC_TRACTOR["spacings_m"][i] if i < 2 else spacing_m
        vehicles[f"spacing_{i + 1}"] = np.where(2 + n_group - 1 > i, gap, np.nan)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_weighings(vehicles, path, "csv")
