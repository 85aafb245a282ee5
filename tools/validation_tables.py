"""Regenerate the tables of ``docs/validation.md`` from :mod:`bogie.steel.cases` (issue 12, "After the changes").

``python tools/validation_tables.py`` (or ``make validation-tables``) runs every named case and rewrites each table
between its markers, ``<!-- table:NAME begin -->`` and ``<!-- table:NAME end -->``, leaving the rest of the page
alone; ``--check`` writes nothing and exits with 1, naming the rows that differ, if the page's tables are not what
the cases give now. Run it after any change to the physics: the tables were once written by hand and went stale.

Every "ours" figure is computed here, from the cases exactly as :mod:`bogie.steel.cases` defines them (no overrides);
every reference figure and run setting comes from the case records (:data:`bogie.steel.cases.TABLE1`,
:data:`bogie.steel.cases.TABLE2`), never retyped. Comments quote only figures computed here. Figures are given to three
significant figures, Table 2's loads in newtons to four as ``bogie case`` prints them, ratios to two, the
reference's as its records hold them; the same cases give the same bytes.
"""

from __future__ import annotations

import argparse
import difflib
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bogie.road import RampedStep
from bogie.steel import cases, linear

DOC = Path(__file__).resolve().parents[1] / "docs" / "validation.md"
#: the finer time step of Table 1's convergence column, as a fraction of Table 1's
DT_REFINEMENT = 8
#: what Table 2 shows of each kind of run's summary, in order (the step runs' p1_after_step is left out)
SHOWN = {
    "static": ("p1_full_load", "p1_after_removal"),
    "sine": ("p1_max_load", "p1_min_load"),
    "step low": ("p1_front_on_step", "p1_rear_on_step"),
    "step high": ("peak_p1",),
    "road": ("rms",),
}


def sig(x: float, n: int = 3) -> str:
    """``x`` to ``n`` significant figures in plain notation, trailing zeros kept: 0.00590, 332, 16800."""
    if x == 0.0 or not math.isfinite(x):
        return f"{x:g}"
    exponent = int(f"{x:.{n - 1}e}".split("e")[1])  # of the rounded value: 9.996 -> 10.0, not 9.99
    decimals = n - 1 - exponent
    if decimals <= 0:
        return f"{round(x, decimals):.0f}"
    return f"{x:.{decimals}f}"


def _figure(value: float, unit: str) -> str:
    """One of our figures: a load in newtons as ``bogie case`` prints it (``:.4g``: 1583, 940, 0.5691), in plain
    notation where that would switch to an exponent (16830); anything else to three significant figures."""
    if unit != "N":
        return sig(value)
    text = f"{value:.4g}"
    return sig(value, 4) if "e" in text else text


def _ref(value: float | str) -> str:
    """A reference figure as its record holds it."""
    return value if isinstance(value, str) else f"{value:g}"


# ---- the figures -------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Figures:
    """What the tables quote: every case's summary and Table 1's extra figures.

    ``fine_peak_p`` is each Table 1 run's peak p at dt / :data:`DT_REFINEMENT` [-]; ``quasi_static_p`` the p of
    L01's bogie in static equilibrium with the front wheel alone on the step [-]; ``rocking_hz`` the equaliser's
    rocking frequency of each Table 1 run with the chassis held [Hz].
    """

    summary: dict[str, dict[str, float]]
    fine_peak_p: dict[str, float]
    quasi_static_p: float
    rocking_hz: dict[str, float]


def _fine_peak_p(row: cases.Table1Row) -> float:
    k = DT_REFINEMENT
    bogie = cases.get(row.name).bogie()
    r = linear.simulate(bogie, RampedStep(), row.speed, row.dt / k, row.n_steps * k, front_axle_start=-cases.STEP_LEAD)
    if not r.success:
        raise ValueError(f"run {row.name} at dt / {k} failed ({r.message})")
    return r.peak_p


def _quasi_static_p(name: str, reference_load: float) -> float:
    """p with the front wheel raised by the step's rise and the rear on the road, from a static solve, over the
    run's ``reference_load`` [N] [-]."""
    bogie = cases.get(name).bogie()
    m = linear.matrices(bogie)
    u = np.linalg.solve(m.K, m.road_stiffness @ np.array([RampedStep().rise, 0.0]))
    loads = linear.wheel_loads_from_state(bogie, m, u, np.zeros_like(u), np.zeros(2))
    return float(abs(loads[0] - loads[1]) / reference_load)


def _rocking_hz(name: str) -> float:
    """The equaliser's rocking frequency with the chassis held, sqrt((K_S b^2 / 2 + K_B) / I) / 2 pi [Hz]."""
    b = cases.get(name).bogie()
    stiffness = b.combined_stiffness * b.equaliser_front_arm[0] ** 2 / 2.0 + b.bush_stiffness
    return math.sqrt(stiffness / b.equaliser_inertia) / (2.0 * math.pi)


def compute() -> Figures:
    """Run every case of :mod:`bogie.steel.cases` once, and Table 1's runs again at the finer time step."""
    results = {name: cases.run(name) for name in cases.names()}
    return Figures(
        summary={name: cases.summary(name, result) for name, result in results.items()},
        fine_peak_p={row.name: _fine_peak_p(row) for row in cases.TABLE1},
        quasi_static_p=_quasi_static_p("L01", results["L01"].reference_load),
        rocking_hz={row.name: _rocking_hz(row.name) for row in cases.TABLE1},
    )


# ---- the tables --------------------------------------------------------------------------------------------------
def _row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    return "\n".join([_row(header), "|" + "---|" * len(header), *map(_row, rows)])


def _table1_comments(f: Figures) -> dict[str, str]:
    p = {name: f.summary[name]["peak_p"] for name in f.summary if name.startswith("L")}
    ref = {row.name: row.peak_p for row in cases.TABLE1}
    dt = {row.name: row.dt for row in cases.TABLE1}

    def times_l01(name: str) -> str:
        return f"{sig(p[name] / p['L01'], 2)} x L01 (reference {sig(ref[name] / ref['L01'], 2)} x)"

    l05_below = p["L05"] < p["L02"]
    return {
        "L01": (
            "Quasi-static: p follows the static value with the front wheel alone on the step "
            f"({sig(f.quasi_static_p)}), with a {100.0 * (p['L01'] / f.quasi_static_p - 1.0):.0f} % overshoot "
            "after the ramp."
        ),
        "L02": f"The equaliser's rocking mode ({f.rocking_hz['L02']:.0f} Hz) overshoots.",
        "L03": (
            "Nearly equal loads throughout; no spikes at the ramp edges (the reference's "
            f"{ref['L03']:g} came from such spikes)."
        ),
        "L04": (
            f"The equaliser's rocking mode ({f.rocking_hz['L04']:.0f} Hz) is under-resolved at Table 1's dt: "
            f"{1.0 / (f.rocking_hz['L04'] * dt['L04']):.0f} steps per period."
        ),
        "L05": (
            f"{'Below' if l05_below else 'Above'} L02 (reference: {'below' if ref['L05'] < ref['L02'] else 'above'})"
            + (": the damper locks the equaliser against its rocking mode." if l05_below else ".")
        ),
        "L06": f"{times_l01('L06')}; the damper moment accounts for the rise.",
        "L07": f"{times_l01('L07')}.",
    }


def table1(f: Figures) -> str:
    """Table 1: the linear runs L01-L07, the reference's settings and peaks beside ours."""
    comments = _table1_comments(f)
    header = ("run", "Kb [N m/rad]", "Db [N m s/rad]", "Ma [kg]", "dt [s]", "speed [m/s]", "reference p",
              "reference P1", "ours p", "ours P1", f"ours p at dt / {DT_REFINEMENT}", "comment")  # fmt: skip
    rows = [
        (row.name, f"{row.bush_stiffness:g}", f"{row.bush_damping:g}", f"{row.axle_mass:g}", f"{row.dt:g}",
         f"{row.speed:g}", _ref(row.peak_p), _ref(row.peak_p1), sig(f.summary[row.name]["peak_p"]),
         sig(f.summary[row.name]["peak_p1"]), sig(f.fine_peak_p[row.name]), comments[row.name])
        for row in cases.TABLE1
    ]  # fmt: skip
    return _table(header, rows)


def table1_findings(f: Figures) -> str:
    """The findings of Table 1 the tests assert, with our figures."""
    p = {name: sig(f.summary[name]["peak_p"]) for name in f.summary if name.startswith("L")}
    low = sig(max(f.summary["L01"]["peak_p"], f.summary["L03"]["peak_p"]))
    rows = [
        ("a soft bush equalises better at low speed (L03 vs L01)", f"{p['L03']} vs {p['L01']}",
         "`test_soft_bush_equalises_better_at_low_speed` (L03 < 0.25 L01)"),
        ("high speed is much worse than low speed (L02, L04 vs L01, L03)", f"{p['L02']}, {p['L04']} vs at most {low}",
         "`test_high_speed_is_much_worse_than_low_speed` (> 3 x)"),
        ("bush damping worsens low-speed equalisation (L06, L07 vs L01)", f"{p['L06']}, {p['L07']} vs {p['L01']}",
         "`test_bush_damping_worsens_low_speed_equalisation` (> 2 x)"),
        ("bush damping worsens high-speed equalisation (L05 vs L02)", "only without equaliser inertia, see below",
         "`test_bush_damping_worsens_high_speed_equalisation_when_the_equaliser_cannot_rock`"),
        ("low-speed runs settle to a steady state with each wheel on the step", "p settles to the quasi-static value",
         "`test_low_speed_run_settles_to_the_quasi_static_state_with_the_front_wheel_on_the_step`"),
    ]  # fmt: skip
    return _table(("finding", "ours", "test"), rows)


def _kind(row: cases.Table2Row) -> str:
    if row.kind == "step":
        return "step low" if row.speed < 1.0 else "step high"
    return row.kind


def table2(f: Figures) -> str:
    """Table 2: the non-linear runs N01-N29, the reference's figures beside ours."""
    rows = []
    for row in cases.TABLE2:
        case = cases.get(row.name)
        b = case.bogie()
        ours = " / ".join(_figure(f.summary[row.name][key], case.unit(key)) for key in SHOWN[_kind(row)])
        reference = " / ".join(_ref(v) for v in row.reference.values()) or "(not printed)"
        rows.append((row.name, row.what, f"{row.friction} ({b.friction_coefficient:g})",
                     f"{row.bush} ({b.bush_stiffness:g} N m/rad)", reference, ours))  # fmt: skip
    return _table(("run", "what", "friction", "bush", "reference P1 [N] or RMS", "ours P1 [N] or RMS"), rows)


#: each table of the page by its marker name
TABLES: dict[str, Callable[[Figures], str]] = {
    "table1": table1,
    "table1-findings": table1_findings,
    "table2": table2,
}


# ---- the page ----------------------------------------------------------------------------------------------------
def _markers(name: str) -> tuple[str, str]:
    return f"<!-- table:{name} begin -->", f"<!-- table:{name} end -->"


def _span(text: str, name: str) -> tuple[int, int]:
    """Start and end of the table ``name`` between its markers in ``text`` (the markers' own lines excluded)."""
    begin, end = _markers(name)
    if text.count(begin) != 1 or text.count(end) != 1:
        raise ValueError(
            f"{DOC.name}: table {name!r} needs exactly one {begin!r} and one {end!r} line; found "
            f"{text.count(begin)} and {text.count(end)}"
        )
    start, stop = text.index(begin) + len(begin) + 1, text.index(end)
    if stop < start:
        raise ValueError(f"{DOC.name}: table {name!r} ends before it begins")
    return start, stop


def committed(text: str) -> dict[str, str]:
    """The tables as the page holds them, by marker name."""
    spans = {name: _span(text, name) for name in TABLES}
    return {name: text[a:b].rstrip("\n") for name, (a, b) in spans.items()}


def render(text: str, tables: dict[str, str]) -> str:
    """``text`` with each table between its markers replaced by ``tables[name]``."""
    for name, table in tables.items():
        start, stop = _span(text, name)
        text = text[:start] + table + "\n" + text[stop:]
    return text


def differences(text: str, tables: dict[str, str]) -> list[str]:
    """A unified diff of every table of ``text`` that is not ``tables``; empty if they all match."""
    out = []
    for name, old in committed(text).items():
        new = tables[name]
        if old == new:
            continue
        lines_old, lines_new = old.splitlines(), new.splitlines()
        changed = set(lines_old[2:]) ^ set(lines_new[2:])
        rows = sorted({line.split("|")[1].strip() for line in changed if line.count("|") > 1})
        if lines_old[:2] != lines_new[:2]:
            rows.insert(0, "(header)")
        out.append(f"table {name}: rows that differ: {', '.join(rows) or '(blank lines only)'}")
        out += difflib.unified_diff(lines_old, lines_new, f"{DOC.name} ({name}, committed)",
                                    f"{DOC.name} ({name}, from bogie.steel.cases)", n=0, lineterm="")  # fmt: skip
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if a table differs")
    parser.add_argument("--doc", type=Path, default=DOC, help=f"the page (default {DOC})")
    args = parser.parse_args(argv)
    text = args.doc.read_text(encoding="utf-8")
    figures = compute()
    tables = {name: make(figures) for name, make in TABLES.items()}
    if args.check:
        diff = differences(text, tables)
        if diff:
            print("\n".join(diff))
            print(f"{args.doc}: the tables are stale; `make validation-tables` rewrites them", file=sys.stderr)
            return 1
        print(f"{args.doc}: every table matches bogie.steel.cases")
        return 0
    new = render(text, tables)
    if new != text:
        args.doc.write_bytes(new.encode("utf-8"))
        print(f"rewrote the tables of {args.doc}")
    else:
        print(f"{args.doc}: the tables were already up to date")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
