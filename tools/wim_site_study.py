"""What each part of the WIM site and sensor model does to the simulated WIM statistics (``docs/wim-site.md``).

``python tools/wim_site_study.py [--n-bogies 300]`` samples a reduced fleet from params.yaml (the same design,
distributions and seed, ``fleet.n_bogies`` replaced), weighs every bogie by the WIM protocol only, once per
configuration below, and rewrites the table between ``<!-- table:wim-site begin -->`` and
``<!-- table:wim-site end -->`` in ``docs/wim-site.md`` (``--check``: writes nothing, exits 1 if the table differs).

The configurations start from the old model (a point sensor inside the sampled road, no error) and add the parts
of params.yaml's ``protocol.wim`` one at a time, cumulatively (the first added, the site, is also the site alone),
then the other two parts alone, then the defaults with another sensor or class. Every bogie keeps its road and
sensor seeds in every configuration (common random numbers), so a difference between two rows is the
configurations' difference, not another draw. The statistics are the survey's
(:func:`bogie.weighings.stats.survey_statistics`) over the readings without an axle at 0 N
(:func:`bogie.fleet.weighing.survey.readings`). One process: the machine is shared.
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import sys
import time
from pathlib import Path

import pandas as pd

from bogie.fleet import WimProtocol, sample_fleet
from bogie.fleet.sampling.sample import bogie_from_sample
from bogie.fleet.weighing.survey import readings
from bogie.fleet.weighing.weigher import weigh
from bogie.params import GRAVITY
from bogie.weighings.stats import survey_statistics
from pipeline.config import load_config  # params.yaml's one reader; the study is bogie.fleet's

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "wim-site.md"
BEGIN, END = "<!-- table:wim-site begin -->", "<!-- table:wim-site end -->"


def configurations(default: WimProtocol) -> list[tuple[str, WimProtocol]]:
    """(label, settings) of every row: the old model, the parts added in turn, the others alone, other defaults."""
    old = dataclasses.replace(
        default,
        site_length_before=0.0,
        site_length_after=0.0,
        sensor_length=0.0,
        contact_length=0.0,
        sensor="none",
    )
    site = {"site_length_before": default.site_length_before, "site_length_after": default.site_length_after}
    length = {"sensor_length": default.sensor_length, "contact_length": default.contact_length}
    error = {"sensor": default.sensor}
    r = dataclasses.replace
    return [
        ("old: point sensor in the sampled road, no error", old),
        ("+ site pavement", r(old, **site)),
        ("+ site pavement + weighing length", r(old, **site, **length)),
        ("+ site pavement + weighing length + sensor error (the defaults)", default),
        ("weighing length alone", r(old, **length)),
        ("sensor error alone", r(old, **error)),
        ("defaults with a 0.5 m bending plate", r(default, sensor_length=0.5)),
        ("defaults with no sensor error", r(default, sensor="none")),
        ("defaults with a bending plate's error", r(default, sensor="bending_plate")),
        ("defaults with a piezo-polymer strip's error", r(default, sensor="piezo_polymer")),
    ]


def run(n_bogies: int) -> tuple[pd.DataFrame, float]:
    """The statistics table (one row per configuration and axle group) and the wall time [s]."""
    config = load_config(ROOT / "params.yaml")
    fleet = sample_fleet(config.fleet_study, n_bogies, config.seed, config.fleet.sampling).to_dict("records")
    start = time.perf_counter()
    rows = []
    for label, spec in configurations(config.protocol.wim):
        for sample in fleet:
            row = weigh(bogie_from_sample(sample), sample, "wim", spec)
            rows.append({**row, "config": label, "group": sample["group"]})
    elapsed = time.perf_counter() - start
    runs = pd.DataFrame(rows)
    labels = [label for label, _ in configurations(config.protocol.wim)]
    runs["config"] = pd.Categorical(runs["config"], categories=list(dict.fromkeys(labels)), ordered=True)
    good = readings(runs.assign(wheel_airborne=runs["wheel_airborne"].fillna(False)))
    stats = survey_statistics(good, by=["config", "group"], unit_per_kg=GRAVITY)
    counts = runs.groupby(["config", "group"], observed=True).agg(
        n_failed=("status", lambda s: int((s == "failed").sum())),
        n_airborne=("wheel_airborne", lambda s: int(s.fillna(False).astype(bool).sum())),
    )
    return stats.merge(counts.reset_index(), on=["config", "group"]), elapsed


def markdown(stats: pd.DataFrame, n_bogies: int) -> str:
    """The table as markdown: one row per configuration, tandem and tri-axle side by side."""
    head = (
        "| configuration | tandem: n | outside 5 % | over 10 % | mean spread [kg] "
        "| tri-axle: n | outside 5 % | over 10 % | mean spread [kg] |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    )
    lines = []
    for label, rows in stats.groupby("config", observed=True, sort=False):
        cells = [label]
        for group in ("tandem", "triaxle"):
            g = rows[rows["group"] == group].iloc[0]
            cells += [
                f"{int(g.n_groups)}",
                f"{100 * g.share_outside_5pct:.0f} %",
                f"{100 * g.share_over_10pct:.0f} %",
                f"{g.mean_spread_kg:,.0f}",
            ]
        lines.append("| " + " | ".join(cells) + " |")
    airborne = int(stats["n_airborne"].sum())
    failed = int(stats["n_failed"].sum())
    note = (
        f"\n{n_bogies} bogies (params.yaml's fleet design and seed, `fleet.n_bogies = {n_bogies}`), WIM only; "
        f"n counts the readings in the statistics: {airborne} readings with an axle at 0 N and {failed} failed "
        "runs over all rows are left out, as the survey leaves them out.\n"
    )
    return head + "\n".join(lines) + "\n" + note


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-bogies", type=int, default=300, help="bogies in the reduced fleet (default 300)")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if the table is not current")
    args = parser.parse_args(argv)
    stats, elapsed = run(args.n_bogies)
    table = markdown(stats, args.n_bogies)
    text = DOC.read_text(encoding="utf-8")
    before, rest = text.split(BEGIN, 1)
    _, after = rest.split(END, 1)
    new = f"{before}{BEGIN}\n{table}{END}{after}"
    runs = len(configurations(load_config(ROOT / "params.yaml").protocol.wim)) * args.n_bogies
    print(f"wim_site_study: {runs} WIM runs in {elapsed:.0f} s ({1000 * elapsed / runs:.0f} ms a run, one process)")
    if args.check:
        if new != text:
            sys.stdout.writelines(difflib.unified_diff(text.splitlines(True), new.splitlines(True), "doc", "now"))
            return 1
        return 0
    DOC.write_text(new, encoding="utf-8")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
