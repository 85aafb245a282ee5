"""DVC stage ``headline``: the ten or so figures a reader wants first -> metrics/headline.json.

``dvc metrics show`` prints every metric of every file on one line; ``metrics/survey.json`` and
``metrics/sensitivity.json`` hold over two hundred. ``python -m pipeline.headline`` reads them (and the status
column of every run) and writes the headline: the inhibitors' total Sobol' indices, most influential first (the
ranking is their order; a string of it was the widest column of ``dvc exp show``, issue 45 Must 2), and chassis
tilt's, the share of groups outside the 5 % tolerance, the mean heaviest-minus-lightest spread [kg] and the extra
pavement wear at the fourth power (metrics/road.json) for each axle group and protocol, and the runs and failures
of all studies. ``dvc metrics show metrics/headline.json`` reads
it in one screen; the README shows a ``dvc exp show`` that compares experiments on it.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from bogie.fleet.constants import GROUP_AXLES, PROTOCOLS
from pipeline.atomic import atomic_file, run_stage, stage_inputs
from pipeline.schema import read_runs_frame

__all__ = ["headline", "main"]


def headline(
    survey: Mapping[str, Any],
    sensitivity: Mapping[str, Any],
    status: pd.Series,
    road: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The headline figures from the metrics files and the ``status`` of every run (all studies).

    Keys: ``ST_<factor>`` (total Sobol' index of the ranking measure for the five inhibitors, most influential
    first, then chassis tilt), ``outside_5pct_<protocol>_<group>`` (share of
    groups whose lightest axle is more than 5 % below the heaviest [-]), ``spread_kg_<protocol>_<group>`` (mean
    heaviest minus lightest axle load [kg]), ``extra_wear_<protocol>_<group>`` (the extra pavement wear at the
    fourth power of the laden steel groups over equal sharing [-], from ``road``: metrics/road.json, None: none),
    ``runs`` and ``failed`` [-]. A figure the metrics lack is left out.
    """
    out: dict[str, Any] = {}
    indices = sensitivity["sobol"]["indices"]
    for factor in (*sensitivity["ranking"], "chassis_tilt"):
        if factor in indices:
            out[f"ST_{factor}"] = indices[factor]["ST"]
    for key, name in (("share_outside_5pct", "outside_5pct"), ("mean_spread_kg", "spread_kg")):
        for protocol in PROTOCOLS:
            for group in GROUP_AXLES:
                value = survey.get(protocol, {}).get(group, {}).get(key)
                if value is not None:
                    out[f"{name}_{protocol}_{group}"] = value
    for protocol in PROTOCOLS:
        for group in GROUP_AXLES:
            entry = ((road or {}).get("simulated") or {}).get(protocol, {}).get(group, {}).get("steel") or {}
            if entry.get("extra_wear_overall") is not None:
                out[f"extra_wear_{protocol}_{group}"] = entry["extra_wear_overall"]
    out["runs"] = int(len(status))
    out["failed"] = int((status != "ok").sum())
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the stage: read the metrics and the runs' status, write metrics/headline.json."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.headline", description=__doc__.splitlines()[0])
    parser.add_argument("--metrics", default="metrics", help="directory of survey.json, sensitivity.json")
    parser.add_argument("--runs", default="data/runs", help="runs dataset (default: data/runs)")
    parser.add_argument("--out", default="metrics/headline.json", help="default: metrics/headline.json")
    args = parser.parse_args(argv)
    return run_stage("headline", parser, args, lambda own: _stage(args))


def _stage(args: argparse.Namespace) -> int:
    """Read, sum up, write; the exit code (errors: :func:`pipeline.atomic.run_stage`'s)."""
    metrics = Path(args.metrics)
    with stage_inputs("headline", KeyError):
        survey = json.loads((metrics / "survey.json").read_text(encoding="utf-8"))
        sensitivity = json.loads((metrics / "sensitivity.json").read_text(encoding="utf-8"))
        road_file = metrics / "road.json"  # the road stage's (docs/pavement.md); a project without it has none
        road = json.loads(road_file.read_text(encoding="utf-8")) if road_file.is_file() else None
        # every part file verified (pipeline.schema.read_runs_frame): a damaged one is refused, not counted
        status = read_runs_frame(args.runs, columns=["status"])["status"].astype(str)
    figures = headline(survey, sensitivity, status, road)
    ranking = " > ".join(sensitivity["ranking"])
    with atomic_file(Path(args.out)) as tmp:
        tmp.write_text(json.dumps(figures, indent=2) + "\n", encoding="utf-8")
    print(f"headline: {ranking}; {figures['runs']} runs, {figures['failed']} failed; wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
