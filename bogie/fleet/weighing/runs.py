"""The runs table: one row per sampled bogie and protocol, every column's type and unit.

A run row is the sample's columns (:data:`bogie.fleet.sampling.sample.COLUMNS`; a runs dataset on disk carries ``study``
as its partition directory), the tilt in degrees, the protocol, ``status`` and ``message``, then the weighing's
result (:data:`RESULT_COLUMNS`). A failed weighing (``status = "failed"``, the reason in ``message``) has every
result column null (NaN in pandas floats, ``<NA>`` in the booleans): never a made-up number, so an unfiltered mean is
NaN rather than silently wrong. A successful row has no null. The text columns are categoricals of fixed categories,
so tables of different chunks concatenate to the same dtypes. The Parquet form (Arrow schema, checksums) is the
pipeline's (:mod:`pipeline.schema`).
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from bogie.bogie_file import is_bogie_file
from bogie.fleet.constants import GROUP_AXLES, MAX_AXLES, PROTOCOLS, SUSPENSIONS
from bogie.fleet.sampling.sample import COLUMNS, TYRE_WEAR_COLUMNS, VARIANTS
from bogie.presets import PRESETS
from bogie.road import ISO8608_CLASSES

__all__ = [
    "BOOLEAN_RESULTS", "CATEGORICAL", "CATEGORIES", "RESULT_COLUMNS", "RUN_COLUMNS", "SAMPLE_COLUMNS", "UNITS",
    "SchemaError", "check_runs", "conform", "preset_categories", "runs_frame",
]  # fmt: skip

#: text columns stored dictionary-encoded, each with every value it can take in a fixed order: every part file has
#: the same dictionary, so pandas reads them back as the same categoricals whatever the chunking. ``preset`` may also
#: hold bogie files' paths (:func:`preset_categories`), after the presets' names
CATEGORIES: dict[str, tuple[str, ...]] = {
    "group": tuple(GROUP_AXLES),
    "preset": tuple(PRESETS),
    "variant": VARIANTS,
    "suspension": SUSPENSIONS,
    "road_class": tuple(ISO8608_CLASSES),
    "protocol": PROTOCOLS,
    "status": ("ok", "failed"),
}
CATEGORICAL: tuple[str, ...] = tuple(CATEGORIES)

#: sample columns of a run row: the partition directory carries ``study``
SAMPLE_COLUMNS: tuple[str, ...] = tuple(c for c in COLUMNS if c != "study")

#: unit of every column ("-" for a pure number or a label)
UNITS: dict[str, str] = {
    "sample_id": "-", "base_id": "-", "group": "-", "n_axles": "-", "preset": "-", "variant": "-", "suspension": "-",
    "bush_stiffness": "N m/rad", "bush_damping": "N m s/rad", "friction_coefficient": "-", "contact_roll_radius": "m",
    **dict.fromkeys(TYRE_WEAR_COLUMNS, "m"), "chassis_tilt": "rad", "payload_fraction": "-", "equaliser_arm": "m",
    "spring_friction_band": "N", "spring_friction_decay": "m",
    "road_class": "-", "road_seed": "-", "sensor_seed": "-", "legal_group_load": "N", "payload_mass": "kg",
    "chassis_pitch_inertia": "kg m^2", "chassis_tilt_deg": "degree", "protocol": "-", "status": "-", "message": "-",
    **{f"axle_load_{i + 1}": "N" for i in range(MAX_AXLES)}, **{f"load_share_{i + 1}": "-" for i in range(MAX_AXLES)},
    "group_load": "N", "p": "-", "p1": "-", "max_deviation": "-", "spread": "N", "spread_kg": "kg",
    "road_wear_factor": "-", "chassis_pitch": "rad", "outside_5pct": "-", "over_10pct": "-", "wheel_airborne": "-",
    "equaliser_on_stop": "-",
}  # fmt: skip

#: the weighing's result: null in a failed row, never null in a successful one
RESULT_COLUMNS: tuple[str, ...] = (
    *(f"axle_load_{i + 1}" for i in range(MAX_AXLES)), *(f"load_share_{i + 1}" for i in range(MAX_AXLES)),
    "group_load", "p", "p1", "max_deviation", "spread", "spread_kg", "road_wear_factor", "chassis_pitch",
    "outside_5pct", "over_10pct", "wheel_airborne", "equaliser_on_stop",
)  # fmt: skip

#: boolean result columns
BOOLEAN_RESULTS: tuple[str, ...] = ("outside_5pct", "over_10pct", "wheel_airborne", "equaliser_on_stop")

#: column -> pandas dtype of a run row, in file order
RUN_COLUMNS: dict[str, str] = {
    **{c: "category" if c in CATEGORICAL else COLUMNS[c] for c in SAMPLE_COLUMNS},
    "chassis_tilt_deg": "float64",
    "protocol": "category",
    "status": "category",
    "message": "str",
    **{c: "boolean" if c in BOOLEAN_RESULTS else "float64" for c in RESULT_COLUMNS},
}


def preset_categories(labels: object) -> tuple[str, ...]:
    """The ``preset`` column's categories for rows with these labels: the presets' names (:data:`CATEGORIES`), then
    the bogie files' paths among the labels, sorted; a study on the presets alone has exactly the presets' names.

    Raises
    ------
    SchemaError
        If a label is neither a preset's name nor a bogie file's path (``.yaml``/``.yml``).
    """
    names = {str(v) for v in pd.Series(labels, dtype=object).dropna()} - set(CATEGORIES["preset"])
    bad = sorted(v for v in names if not is_bogie_file(v))
    if bad:
        raise SchemaError(f"run rows with labels outside the schema's categories: {{'preset': {bad}}}")
    return (*CATEGORIES["preset"], *sorted(names))


class SchemaError(ValueError):
    """A runs table that does not have the runs schema's columns, types or nulls."""


def conform(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame``'s run columns in file order with the schema's dtypes (labels as categoricals of fixed categories).

    Raises
    ------
    SchemaError
        If a column is missing or a label is not one of its column's categories.
    """
    missing = [c for c in RUN_COLUMNS if c not in frame.columns]
    if missing:
        raise SchemaError(f"run rows lack the columns {', '.join(missing)}")
    frame = frame[list(RUN_COLUMNS)]
    categories = {**CATEGORIES, "preset": preset_categories(frame["preset"])}
    unknown = {c: sorted(set(frame[c].dropna().astype(str)) - set(categories[c])) for c in categories}
    unknown = {c: v for c, v in unknown.items() if v}
    if unknown:
        raise SchemaError(f"run rows with labels outside the schema's categories: {unknown}")
    dtypes: dict[str, object] = {c: pd.CategoricalDtype(categories[c]) if c in categories else d
                                 for c, d in RUN_COLUMNS.items()}  # fmt: skip
    return frame.astype(dtypes)


def runs_frame(rows: list[Mapping[str, object]]) -> pd.DataFrame:
    """Run rows (dicts with every column of :data:`RUN_COLUMNS`; None or NaN for a null) as a typed DataFrame."""
    return conform(pd.DataFrame(rows, columns=list(RUN_COLUMNS)))


def check_runs(frame: pd.DataFrame, where: str = "the runs") -> None:
    """Check that ``frame`` has every run column and the schema's nulls: none in a successful row, only nulls in
    the result columns of a failed row.

    Raises
    ------
    SchemaError
        Naming the columns and the number of rows that break the rule.
    """
    missing = [c for c in RUN_COLUMNS if c not in frame.columns]
    if missing:
        raise SchemaError(f"{where} lack the columns {', '.join(missing)}")
    ok = (frame["status"] == "ok").to_numpy()
    not_result = [c for c in RUN_COLUMNS if c not in RESULT_COLUMNS]
    problems = []
    nulls = frame[not_result].isna().sum()
    problems += [f"{c} null in {n} rows" for c, n in nulls[nulls > 0].items()]
    nulls = frame.loc[ok, list(RESULT_COLUMNS)].isna().sum()
    problems += [f"{c} null in {n} successful rows" for c, n in nulls[nulls > 0].items()]
    filled = frame.loc[~ok, list(RESULT_COLUMNS)].notna().sum()
    problems += [f"{c} set in {n} failed rows (must be null)" for c, n in filled[filled > 0].items()]
    if problems:
        raise SchemaError(f"{where} break the runs schema: {'; '.join(problems)}")
