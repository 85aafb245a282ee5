"""The report's words: Jinja2 templates (``templates/``) rendered from the numbers, and the filters they format with.

A template renders to paragraphs separated by blank lines; inside a paragraph the source lines are joined with one
space, so a template can be wrapped freely (a tag alone on its line leaves nothing). A paragraph starting with "## "
is a subheading, "- " a bullet (see :func:`pipeline.report.layout.text_block`). Numbers are formatted only here, by
the filters of :data:`FILTERS`: shares and deviations come in as fractions and go out as per cent.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import jinja2

from pipeline.report.style import FACTOR_LABEL, GROUP_LABEL, MEASURE_LABEL, PROTOCOL_LABEL

__all__ = [
    "FILTERS",
    "duration",
    "environment",
    "fixed",
    "groups",
    "interval",
    "num",
    "paragraphs",
    "pct",
    "points",
    "render",
    "sig",
    "span",
]

TEMPLATES = Path(__file__).with_name("templates")


def _missing(x: Any) -> bool:
    return x is None or not math.isfinite(x)


def pct(x: float | None, digits: int = 1, unit: bool = True) -> str:
    """A fraction as per cent: ``pct(0.1234)`` is "12.3 %"; "n/a" for a missing value (JSON null, NaN).

    ``unit=False`` leaves out the " %" (for a table column that names its unit).
    """
    if _missing(x):
        return "n/a"
    return f"{100.0 * x:.{digits}f}" + (" %" if unit else "")


def num(x: float, digits: int = 2) -> str:
    """A number to ``digits`` decimals, without the "-0.00" of a tiny negative estimate."""
    text = f"{x + 0.0:.{digits}f}"
    return re.sub(r"^-(0\.?0*)$", r"\1", text)


def interval(x: float, half: float) -> str:
    """An estimate and its symmetric interval: ``interval(0.5, 0.1)`` is "0.50 (0.40 to 0.60)"; four decimals when
    the estimate and the half-width are both under 0.01 (``interval(0.0008, 0.0002)`` is "0.0008 (0.0006 to
    0.0010)"), so that two small, different indices do not both read "0.00"."""
    digits = 4 if 0.0 < max(abs(x), abs(half)) < 0.01 else 2
    return f"{num(x, digits)} ({num(x - half, digits)} to {num(x + half, digits)})"


def sig(x: float | None) -> str:
    """An index to two decimals, or to one significant digit under 0.01 (``sig(0.00083)`` is "0.0008"), so a small
    index does not read as zero; "0" for zero and "n/a" for a missing value."""
    if _missing(x):
        return "n/a"
    if x == 0.0:
        return "0"
    return num(x) if abs(x) >= 0.01 else f"{x:.1g}"


def fixed(x: float, digits: int = 0) -> str:
    """A number to ``digits`` decimals: ``fixed(2.345, 1)`` is "2.3"."""
    return f"{x:.{digits}f}"


def points(x: float | None) -> str:
    """A difference of two fractions in percentage points, two decimals: ``points(0.0123)`` is "1.23"; "n/a" for
    a missing value."""
    return "n/a" if x is None or not math.isfinite(x) else f"{100 * x:.2f}"


def span(x: float, low: float | None, high: float | None) -> str:
    """A difference of fractions and its interval in percentage points: "1.23 (0.50 to 2.00)".

    An interval that could not be estimated (None or NaN: fewer than two pairs to resample) reads "no interval".
    """
    if low is None or high is None or not (math.isfinite(low) and math.isfinite(high)):
        return f"{points(x)} (no interval)"
    return f"{points(x)} ({points(low)} to {points(high)})"


def groups(values: Mapping[str, str], noun: str = "groups") -> str:
    """Values per axle group as words: "a of tandem and b of tri-axle groups" for the groups present."""
    parts = [f"{v} of {GROUP_LABEL.get(g, g)}" for g, v in values.items()]
    return " and ".join(parts) + f" {noun}" if parts else "no groups"


def duration(seconds: float) -> str:
    """A duration as "1.25 h", "12.3 min" or "45.6 s"."""
    if seconds >= 3600.0:
        return f"{seconds / 3600.0:.2f} h"
    return f"{seconds / 60.0:.1f} min" if seconds >= 60.0 else f"{seconds:.1f} s"


def _g(x: float) -> str:
    return f"{x:g}"


def _label(table: Mapping[str, str]):
    return lambda name: table.get(name, name)


#: the filters every template can use
FILTERS = {
    "pct": pct,
    "num": num,
    "fixed": fixed,
    "interval": interval,
    "sig": sig,
    "points": points,
    "span": span,
    "groups": groups,
    "duration": duration,
    "g": _g,
    "factor": _label(FACTOR_LABEL),
    "group": _label(GROUP_LABEL),
    "protocol": _label(PROTOCOL_LABEL),
    "measure": _label(MEASURE_LABEL),
}


def environment(loader: jinja2.BaseLoader | None = None) -> jinja2.Environment:
    """The Jinja2 environment of the report: its templates (or ``loader``'s), :data:`FILTERS`, strict undefined."""
    env = jinja2.Environment(
        loader=loader or jinja2.FileSystemLoader(TEMPLATES),
        trim_blocks=True,
        lstrip_blocks=True,
        undefined=jinja2.StrictUndefined,
        autoescape=False,
    )
    env.filters.update(FILTERS)
    return env


_ENV = environment()


def paragraphs(text: str) -> list[str]:
    """Rendered text as paragraphs: split at blank lines, each one's lines joined by single spaces."""
    out = []
    for block in re.split(r"\n\s*\n", text):
        lines = [line.strip() for line in block.splitlines() if line.strip()]
        if lines:
            out.append(" ".join(lines))
    return out


def render(template: str, /, env: jinja2.Environment | None = None, **context: Any) -> list[str]:
    """Render ``template`` (e.g. "summary.j2") with ``context`` into paragraphs (:func:`paragraphs`)."""
    return paragraphs((env or _ENV).get_template(template).render(**context))
