"""A designer's bogie file over the fleet's conditions of a params.yaml, beside today's typical design, in seconds
(issue 45 Must 4): ``python -m pipeline.own_design FILE [--params params.yaml]``.

``bogie design show FILE`` (the library's command) gives the file's static loads and verdict; the fleet's conditions
come from a params.yaml, which the pipeline reads, so this half lives here: the params file's fleet, ``design:``
settings, static weighbridge and seed, and :func:`bogie.fleet.design.experiment.weigh_own_design` in this process.
"""

from __future__ import annotations

import argparse
import sys
import time

from bogie.fleet.design.analysis import describe
from bogie.fleet.design.experiment import weigh_own_design
from bogie.fleet.design.settings import DesignError, DesignSettings
from pipeline.config import load_config


def fleet_verdict(path: str, params: str) -> list[str]:
    """The lines on a bogie file over the fleet's conditions of ``params`` (a params.yaml):
    :func:`bogie.fleet.design.experiment.weigh_own_design`, in this process."""
    config = load_config(params)
    spec = config.design or DesignSettings(grid={"bush_stiffness": [1.0]})  # the grid is not weighed here
    start = time.perf_counter()
    study = weigh_own_design(config.fleet_study, path, spec, config.seed, config.protocol.static)
    pct = f"{100 * spec.target_share:.0f} %"

    def line(row) -> str:
        up, down = row["tilt_tolerance_nose_up_deg"], row["tilt_tolerance_nose_down_deg"]
        tolerance = (f"{pct} within 5 % from {down:.1f} degrees nose down to {up:.1f} degrees nose up"
                     if up is not None and up == up else f"none ({pct} within 5 % not reached even level)")  # fmt: skip
        share, low, high, level = (100 * row[f"share_within_5pct{e}"] for e in ("", "_low", "_high", "_level"))
        return f"{share:.0f} % ({low:.0f}-{high:.0f} %) within 5 %; level {level:.0f} %; tilt tolerance: {tolerance}"

    rows = {r["kind"]: r for r in study.analysis.designs.to_dict("records")}
    return [
        f"over the fleet's conditions of {params} ({spec.n_conditions} conditions: tilt, tyre wear, payload, approach "
        f"road; static weighbridge; {len(study.runs)} runs in {time.perf_counter() - start:.1f} s):",
        f"  your design:     {line(rows['own'])}",
        f"  today's typical: {line(rows['typical'])} ({describe(rows['typical'])})",
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m pipeline.own_design", description=__doc__.splitlines()[0])
    parser.add_argument("bogie", help="a bogie file (.yaml), docs/bogie-file.md")
    parser.add_argument("--params", default="params.yaml", help="the fleet's params.yaml (default: params.yaml)")
    args = parser.parse_args(argv)
    try:
        lines = fleet_verdict(args.bogie, args.params)
    except (DesignError, ValueError, OSError) as exc:
        print(f"pipeline.own_design: error: {exc}", file=sys.stderr)
        return 2
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
