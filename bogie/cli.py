"""The ``bogie`` command: single cases and figures from the command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path


def _cmd_figure2(args: argparse.Namespace) -> int:
    from bogie.plotting import figure2, save_figure

    fe_points = None
    if args.fe:
        from bogie.fe import figure2_points

        fe_points = figure2_points(chassis_deflection=args.alpha_mm / 1e3)
    fig = figure2(q_max=args.q_max, chassis_deflection=args.alpha_mm / 1e3, fe_points=fe_points)
    save_figure(fig, Path(args.out))
    print(f"wrote {args.out}")
    return 0


def _figures(case, values: dict) -> str:
    """A run's figures with their units (:meth:`bogie.cases.Case.unit`): ``p1_front_on_step 1592 N``."""
    return ", ".join(f"{k} {v:.4g} {case.unit(k)}" if isinstance(v, float) else f"{k} {v} {case.unit(k)}"
                     for k, v in values.items())  # fmt: skip


def _image_suffix(parser: argparse.ArgumentParser, option: str, path: str | None) -> None:
    """Refuse an image file whose suffix matplotlib cannot write, before any simulation runs."""
    if path is None:
        return
    from matplotlib.figure import Figure

    formats = Figure().canvas.get_supported_filetypes()
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in formats:
        parser.error(f"{option} {path}: the suffix {suffix!r} is not an image format; allowed: {', '.join(formats)}")


def _cmd_case_list() -> int:
    from bogie import cases

    for name in cases.names():
        case = cases.get(name)
        text = case.description.split(":", 1)[-1].strip()  # without the "Table 2 block 3 run N10:" prefix
        print(f"{name}  {text if len(text) <= 110 else text[:109] + '…'}")
    return 0


def _cmd_case(args: argparse.Namespace) -> int:
    from bogie import cases

    if args.name.lower() == "list":
        return _cmd_case_list()
    from bogie.plotting import case_history, save_figure

    case = cases.get(args.name)
    result = cases.run(case.name)
    ref = _figures(case, case.reference)
    print(f"{case.name}: {case.description}")
    print(f"status {result.status}: {result.message}")
    ours = cases.summary(case.name, result) if result.success else {}
    print(f"ours: {_figures(case, ours) if result.success else 'none (the run failed)'}")
    print(f"reference: {ref or 'no figure printed'}")
    if args.csv:
        out = Path(args.csv)
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f".{out.name}.tmp")
        result.to_frame().to_csv(tmp)
        tmp.replace(out)
        print(f"wrote {args.csv}")
    if args.plot:
        fig = case_history(result, title=f"Run {case.name}", note=f"reference: {ref}", case=case, ours=ours)
        save_figure(fig, Path(args.plot))
        print(f"wrote {args.plot}")
    return 0 if result.success else 1


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("bogie")
    except PackageNotFoundError:
        return "unknown (not installed)"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bogie", description="Axle load equalisation in mechanically equalised trailer bogies."
    )
    parser.add_argument("--version", action="version", version=f"bogie {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)
    fig2 = sub.add_parser("figure2", help="the reference's Figure 2: p against q for chassis slopes 0-2 degrees")
    fig2.add_argument("--out", required=True, help="output file; the format follows the suffix (.png, .pdf, .svg)")
    fig2.add_argument("--q-max", type=float, default=20.0, help="largest q on the axis [-] (default 20)")
    fig2.add_argument("--alpha-mm", type=float, default=57.0, help="chassis deflection alpha [mm] (default 57)")
    fig2.add_argument(
        "--fe", action="store_true", help="overlay the Stage 1 finite element points at q = 4.3 (bogie.fe)"
    )
    fig2.set_defaults(func=_cmd_figure2, parser=fig2)
    case = sub.add_parser("case", help="run one of the reference's named runs (L01-L07, N01-N29); 'list' lists them")
    case.add_argument("name", help="run name, e.g. L01, or 'list' for every name with a one-line description")
    case.add_argument("--plot", help="write the histories (as the reference's Figures 5-12) to this image file")
    case.add_argument("--csv", help="write the histories to this CSV file")
    case.set_defaults(func=_cmd_case, parser=case)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra:  # the subcommand's usage, not the top-level one, tells what the subcommand takes
        args.parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if args.command == "case":
        _image_suffix(args.parser, "--plot", args.plot)
    else:
        _image_suffix(args.parser, "--out", args.out)
    try:
        return args.func(args)
    except ValueError as exc:
        print(f"bogie: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
