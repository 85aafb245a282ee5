"""The ``bogie`` command: single cases and figures from the command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path


def _cmd_figure2(args: argparse.Namespace) -> int:
    from bogie.plotting import figure2, save_figure

    fig = figure2(q_max=args.q_max, chassis_deflection=args.alpha_mm / 1e3)
    save_figure(fig, Path(args.out))
    print(f"wrote {args.out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bogie", description="Axle load equalisation in mechanically equalised trailer bogies."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    fig2 = sub.add_parser("figure2", help="the reference's Figure 2: p against q for chassis slopes 0-2 degrees")
    fig2.add_argument("--out", required=True, help="output file; the format follows the suffix (.png, .pdf, .svg)")
    fig2.add_argument("--q-max", type=float, default=20.0, help="largest q on the axis [-] (default 20)")
    fig2.add_argument("--alpha-mm", type=float, default=57.0, help="chassis deflection alpha [mm] (default 57)")
    fig2.set_defaults(func=_cmd_figure2)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ValueError as exc:
        print(f"bogie: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
