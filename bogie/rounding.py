"""Numbers for JSON, one rule for every metrics file and report the project writes (issue 42 Must 2)."""

from __future__ import annotations

import math
from typing import Any

import pandas as pd

__all__ = ["json_number"]


def json_number(x: Any, digits: int = 4) -> float | None:
    """``x`` as a float rounded to ``digits`` decimals (Python's ``round``: to the nearest, ties to even on the
    binary value), -0.0 written 0.0; None for None, a missing value (NaN, pandas' NA) and an infinity, which JSON
    does not have."""
    if x is None or pd.isna(x):
        return None
    value = float(x)
    if not math.isfinite(value):
        return None
    return round(value, digits) + 0.0  # + 0.0 turns -0.0 into 0.0
