"""The ``bogie`` command: single cases, figures, observed weighings and a bogie of one's own from the command line."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path


def _cmd_figure2(args: argparse.Namespace) -> int:
    from bogie.plotting import figure2, save_figure

    fe_points = None
    if args.fe:
        from bogie.steel.fe import figure2_points

        fe_points = figure2_points(chassis_deflection=args.alpha_mm / 1e3)
    fig = figure2(q_max=args.q_max, chassis_deflection=args.alpha_mm / 1e3, fe_points=fe_points)
    save_figure(fig, Path(args.out))
    print(f"wrote {args.out}")
    return 0


def _figures(case, values: dict) -> str:
    """A run's figures with their units (:meth:`bogie.steel.cases.Case.unit`): ``p1_front_on_step 1583 N``."""
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
    import textwrap

    from bogie.steel import cases

    for name in cases.names():
        case = cases.get(name)
        text = case.description.split(":", 1)[-1].strip()  # without the "Table 2 block 3 run N10:" prefix
        # whole, wrapped under the name: cut at a width, N07 and N08 read the same (issue 31)
        lines = textwrap.wrap(text, width=110 - len(name) - 2, break_on_hyphens=False) or [""]
        print(f"{name}  {lines[0]}")
        for line in lines[1:]:
            print(" " * (len(name) + 2) + line)
    return 0


def _cmd_case(args: argparse.Namespace) -> int:
    from bogie.steel import cases

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
        result.to_frame(units=True).to_csv(tmp)  # a header with each column's unit
        tmp.replace(out)
        print(f"wrote {args.csv}")
    if args.plot:
        fig = case_history(result, title=f"Run {case.name}", note=f"reference: {ref}", case=case, ours=ours)
        save_figure(fig, Path(args.plot))
        print(f"wrote {args.plot}")
    return 0 if result.success else 1


def _range(name: str, low: float, high: float, unit: str):
    """An argparse type: a float in [low, high], refused with the parameter, value, range and unit
    (:func:`bogie.settings.check_value`'s message)."""

    def parse(text: str) -> float:
        from bogie.settings import check_value

        try:
            value: float | str = float(text)
        except ValueError:
            value = text  # not a number: check_value says so
        return check_value(name, value, unit, low=low, high=high, error=argparse.ArgumentTypeError)

    return parse


def _weighings_table(survey) -> str:
    """The readable table of ``bogie weighings``."""
    from bogie.weighings.survey import SURVEYED

    data = survey.to_dict()["groups"]
    lines = [
        f"{'group':<8} {'n':>5} {'mean spread':>12} {'median spread':>14} {'outside 5 %':>12} {'over 10 %':>10}",
        f"{'':<8} {'':>5} {'[kg]':>12} {'[%]':>14} {'[%]':>12} {'[%]':>10}",
    ]

    def num(x, scale=1.0, fmt=".1f"):
        return "-" if x is None else format(x * scale, fmt)

    for size in SURVEYED:
        e = data[size]
        lines.append(
            f"{size:<8} {e['n_groups']:>5} {num(e['mean_spread_kg'], fmt='.0f'):>12} "
            f"{num(e['median_spread_pct']):>14} {num(e['share_outside_5pct'], 100):>12} "
            f"{num(e['share_over_10pct'], 100):>10}"
        )
    lines += ["", "load share LSC = n W / sum W (1 = equal share), quantiles over the groups:",
              f"{'group':<8} {'axle':>4} {'p05':>6} {'p25':>6} {'p50':>6} {'p75':>6} {'p95':>6}"]  # fmt: skip
    for size in SURVEYED:
        for axle, q in data[size]["load_share_quantiles"].items():
            values = " ".join(f"{num(q.get(k), fmt='.3f'):>6}" for k in ("p05", "p25", "p50", "p75", "p95"))
            lines.append(f"{size:<8} {axle.removeprefix('axle_'):>4} {values}")
    road = survey.to_dict()["road"]
    legal = survey.to_dict()["settings"].get("legal_loads_kg", {})
    axle = f"{legal['axle'] / 1000:g} t" if "axle" in legal else "10 t, 11.5 t in a drive group"
    groups = (
        f"tandem {legal['tandem'] / 1000:g} t, tri-axle {legal['triaxle'] / 1000:g} t" if "tandem" in legal
        else "96/53/EC's by each group's position and spacing"
    )  # fmt: skip
    limits = (
        f"axles above the single-axle limit ({axle}) within legal groups ({groups}): an indicator, not an offence "
        "(the law weighs a group's axles as one)"
    )
    lines += ["", "what unequal sharing costs the road (docs/pavement.md): its extra pavement wear as a share of "
              "Austroads' group count (SAR per group, 135 kN a tandem, 181 kN a tri-axle; k = 4 the headline, "
              "k = 12 cemented layers), the same per axle against equal sharing beside it, and the " + limits + ":",
              f"{'group':<8} {'n':>5} {'extra k=4':>10} {'per axle':>9} {'k=12':>7} {'per axle':>9} "
              f"{'per 1000 k=4':>13} {'over legal group':>17} {'axle over in legal':>19}",
              f"{'':<8} {'':>5} {'[% ESA]':>10} {'[%]':>9} {'[% SAR]':>7} {'[%]':>9} {'[80 kN axles]':>13} "
              f"{'[%]':>17} {'[%]':>19}"]  # fmt: skip
    for size in SURVEYED:
        e = road[size]
        if not e.get("n_groups"):
            lines.append(f"{size:<8} {0:>5} " + " ".join(f"{'-':>{w}}" for w in (10, 9, 7, 9, 13, 17, 19)))
            continue
        lines.append(
            f"{size:<8} {e['n_groups']:>5} {num(e.get('extra_wear_group_overall'), 100, '.2f'):>10} "
            f"{num(e['extra_wear_overall'], 100, '.2f'):>9} {num(e.get('extra_wear_group_cemented'), 100, '.1f'):>7} "
            f"{num(e['extra_wear_cemented'], 100, '.1f'):>9} {num(e['extra_sa_per_1000_overall'], fmt='.1f'):>13} "
            f"{num(e.get('share_group_over'), 100):>17} {num(e['share_hidden_overload'], 100):>19}"
        )
    if legal:
        lines.append(f"legal loads: {legal.get('source', '')}")
    return "\n".join(lines)


def _legal_groups(args: argparse.Namespace) -> dict[str, float] | None:
    """The legal group loads given on the command line, the directive's trailer limit for a size not given (a stated
    single limit for each size); None if none was: 96/53/EC's by each group's position and spacing."""
    from bogie.weighings.wear import EU_LEGAL_GROUP_KG

    given = {"tandem": args.legal_tandem_kg, "triaxle": args.legal_triaxle_kg}
    if all(v is None for v in given.values()):
        return None
    return {size: float(EU_LEGAL_GROUP_KG[size] if v is None else v) for size, v in given.items()}


def _cmd_weighings(args: argparse.Namespace) -> int:
    """``bogie weighings``: one file as before; several files (each a site), or ``--by-site``, also the sites side by
    side (:func:`bogie.weighings.sites.compare_sites`)."""
    import json

    from bogie.weighings.sites import compare_sites, sites_text

    paths = list(args.path)
    if len(paths) > 1 and args.sharing_factors is not None:
        print("bogie: error: --sharing-factors: one file at a time (given several)", file=sys.stderr)
        return 2
    from bogie.weighings.files import survey_files

    try:  # a site is named by its file's name, or its path if two names are alike (one rule with observed_survey's)
        names = [site or "site" for _, site in survey_files(paths)]
    except ValueError as exc:  # a file given twice
        print(f"bogie: error: {exc}", file=sys.stderr)
        return 2
    surveys, sites = {}, {}
    for path, name in zip(paths, names):
        survey = _one_weighings(args, path)
        if survey is None:
            return 2
        surveys[path] = survey
        sites.update(survey.site_counts(name))
    if (len(paths) > 1 or args.by_site) and len(sites) < 2:
        print(f"bogie: error: --by-site: {paths[0]} holds one site (no station column of several stations); give "
              "several files, each a site", file=sys.stderr)  # fmt: skip
        return 2
    table = compare_sites(sites) if len(paths) > 1 or args.by_site else None
    if args.json:
        site_rows = None if table is None else json.loads(table.to_json(orient="records"))
        if len(paths) == 1:
            out = surveys[paths[0]].to_dict() | ({} if site_rows is None else {"sites": site_rows})
        else:
            out = {"surveys": {p: s.to_dict() for p, s in surveys.items()}, "sites": site_rows}
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0
    for path, survey in surveys.items():
        _print_weighings(args, path, survey, brief=len(paths) > 1)
    if table is not None:
        print("\n" + sites_text(table))
    return 0


def _one_weighings(args: argparse.Namespace, path: str):
    """One file's survey under the command's filters (its road figures' sharing factors written when asked), or
    None after saying why on stderr."""
    from bogie.weighings.survey import observed_survey

    try:
        survey = observed_survey(path, args.format, min_group_load_kg=1000.0 * args.min_group_load_t,
                                 group_spacing_m=args.group_spacing_m, position=args.position,
                                 legal_group_kg=_legal_groups(args), legal_axle_kg=args.legal_axle_kg,
                                 resolution_kg=args.resolution_kg, grouping=args.grouping,
                                 keep_groups=False)  # fmt: skip
    except OSError as exc:
        print(f"bogie: error: {path}: {exc.strerror or exc}", file=sys.stderr)
        return None
    if args.sharing_factors is not None:
        from bogie.weighings.pavement import sharing_factors, write_sharing_factors
        from bogie.weighings.wear import DAMAGE_EXPONENTS

        factors = sharing_factors(survey.road, DAMAGE_EXPONENTS, source="observed", position=args.position,
                                  suspension="as observed")  # fmt: skip
        try:
            write_sharing_factors(factors, args.sharing_factors)
        except OSError as exc:
            print(f"bogie: error: --sharing-factors {args.sharing_factors}: {exc.strerror or exc}", file=sys.stderr)
            return None
    return survey


def _print_weighings(args: argparse.Namespace, path: str, survey, brief: bool) -> None:
    """One file's readable output: what was read and kept, and (``brief`` False) its statistics' tables."""
    shown = args.format if args.format != "auto" else f"format auto: {survey.read.format}"
    print(f"{path} ({shown}): {survey.read.summary()}; {survey.read.describe_resolution()}")
    counts = "; ".join(
        f"{where} {sum(sizes.values())} ({', '.join(f'{n} {size}' for size, n in sizes.items() if n)})"
        if sum(sizes.values()) else f"{where} 0"
        for where, sizes in survey.positions.items()
    )  # fmt: skip
    print(f"groups in the file by position: {counts} (steer: the first group; drive: the second; trailer: the rest)")
    print(
        f"{survey.n_kept} axle groups kept: group load >= {args.min_group_load_t:g} t, position "
        f"{args.position}; grouping {survey.settings['grouping']}"
    )
    for station, entry in (survey.stations or {}).items():
        sizes = ", ".join(f"{entry['groups'][s]['n_groups']} {s}" for s in entry["groups"])
        print(f"station {station}: {entry['vehicles']} vehicles, {sizes} kept (--json has its statistics)")
    if not brief:
        print(_weighings_table(survey))


def design_loads_table(name: str, bogie, chassis_tilt_deg: float) -> tuple[str, list[float]]:
    """The text ``bogie design show`` prints, and the static tyre loads [N] it prints, one per axle: the linear
    static model at the tilt (:func:`bogie.steel.static.tilted_axle_loads`)."""
    import math

    from bogie.steel.static import tilted_axle_loads

    loads = [float(w) for w in tilted_axle_loads(bogie, math.radians(chassis_tilt_deg))]
    total = sum(loads)
    lines = [
        f"{name}: {bogie.n_axles} axles at x = {', '.join(f'{v:g}' for v in bogie.axle_x)} m behind the king pin, "
        f"chassis tilt {chassis_tilt_deg:+g} degree (nose up +)",
        "static tyre loads of one side (linear static model, bogie.steel.static.tilted_axle_loads):",
        f"{'axle':>4} {'x [m]':>7} {'load [kN]':>10} {'share [%]':>10}",
    ]
    lines += [
        f"{i + 1:>4} {bogie.axle_x[i]:>7.3f} {w / 1e3:>10.2f} {w / total * 100:>10.2f}" for i, w in enumerate(loads)
    ]
    lines.append(
        f"{'sum':>4} {'':>7} {total / 1e3:>10.2f} {100.0:>10.2f}   (group load, both sides: {2 * total / 1e3:.2f} kN)"
    )
    return "\n".join(lines), loads


def static_verdict(loads: Sequence[float]) -> str:
    """Whether a group's static tyre loads are within 5 %: its lightest axle at most 5 % below its heaviest (the
    project's tolerance, :data:`bogie.weighings.stats.PAIR_TOLERANCE`), with the gap."""
    from bogie.weighings.stats import PAIR_TOLERANCE

    gap = 100.0 * (max(loads) - min(loads)) / max(loads)
    verdict = "within 5 %" if gap <= 100.0 * PAIR_TOLERANCE else "NOT within 5 %"
    return f"static verdict: {verdict} (the lightest axle {gap:.1f} % below the heaviest)"


def _cmd_design_show(args: argparse.Namespace) -> int:
    from bogie.bogie_file import base_bogie, is_bogie_file

    bogie = base_bogie(args.bogie)
    text, loads = design_loads_table(args.bogie, bogie, args.tilt_deg)
    print(text)
    print(static_verdict(loads))
    if not is_bogie_file(args.bogie):
        print("a preset is the fleet's base bogie, not a design: the design study weighs it as today's typical")
    else:
        print(f"over a fleet's conditions: python -m pipeline.own_design {args.bogie} --params params.yaml")
    if args.out:
        import math

        from bogie.plotting import bogie_side_view, save_figure

        title = (f"{Path(args.bogie).name}: static tyre loads of one side at a chassis tilt of {args.tilt_deg:+g}°, "
                 f"{sum(loads) / 1e3:.1f} kN in all")  # fmt: skip
        save_figure(bogie_side_view(bogie, loads, math.radians(args.tilt_deg), title), Path(args.out))
        print(f"wrote {args.out}")
    return 0


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
    _add_figure2(sub)
    _add_case(sub)
    _add_weighings(sub)
    _add_design(sub)
    return parser


def _add_figure2(sub) -> None:
    """The ``figure2`` subcommand."""
    fig2 = sub.add_parser("figure2", help="the reference's Figure 2: p against q for chassis slopes 0-2 degrees")
    fig2.add_argument("--out", required=True, help="output file; the format follows the suffix (.png, .pdf, .svg)")
    fig2.add_argument("--q-max", type=float, default=20.0, help="largest q on the axis [-] (default 20)")
    fig2.add_argument("--alpha-mm", type=float, default=57.0, help="chassis deflection alpha [mm] (default 57)")
    fig2.add_argument(
        "--fe", action="store_true", help="overlay the Stage 1 finite element points at q = 4.3 (bogie.steel.fe)"
    )
    fig2.set_defaults(func=_cmd_figure2, parser=fig2)


def _add_case(sub) -> None:
    """The ``case`` subcommand."""
    case = sub.add_parser("case", help="run one of the reference's named runs (L01-L07, N01-N29); 'list' lists them")
    case.add_argument("name", help="run name, e.g. L01, or 'list' for every name with a one-line description")
    case.add_argument("--plot", help="write the histories (as the reference's Figures 5-12) to this image file")
    case.add_argument("--csv", help="write the histories to this CSV file")
    case.set_defaults(func=_cmd_case, parser=case)


def _add_weighings(sub) -> None:
    """The ``weighings`` subcommand and its filters."""
    from bogie.weighings.formats import FORMATS

    weigh = sub.add_parser(
        "weighings",
        help="survey statistics of observed WIM or weighbridge records (formats: docs/weighings.md)",
        description="Read a file of weighings, split the vehicles into axle groups, keep the groups that pass the "
        "filters and print the survey statistics of the tandems and tri-axles.",
    )
    weigh.add_argument("path", nargs="+", help="the file of records; several files: each a site, compared side by side")
    weigh.add_argument(
        "--format",
        default="auto",
        choices=("auto", *FORMATS),
        help="record layout (docs/weighings.md); auto (default): the one that fits the first lines",
    )
    weigh.add_argument(
        "--min-group-load-t", type=_range("--min-group-load-t", 0.0, 100.0, "t"), default=0.0,
        help="keep groups of at least this load [t] (default 0: every group)",
    )  # fmt: skip
    weigh.add_argument(
        "--group-spacing-m", type=_range("--group-spacing-m", 0.1, 5.0, "m"), default=2.0,
        help="largest spacing of two axles of one group [m] (default 2.0)",
    )  # fmt: skip
    weigh.add_argument("--position", choices=("all", "steer", "drive", "trailer"), default="all",
                       help="which groups: all (default), the steer, drive (second) or trailer (third and later) "
                       "groups")  # fmt: skip
    weigh.add_argument(
        "--grouping", choices=("spacing", "us-tandem"), default="spacing",
        help="how axles form groups: spacing (default: at most --group-spacing-m apart) or us-tandem (23 CFR 658.5: "
        "consecutive axles more than 40 in and at most 96 in apart)",
    )  # fmt: skip
    for size, what in (("tandem", "a tandem group's"), ("triaxle", "a tri-axle group's")):
        weigh.add_argument(
            f"--legal-{size}-kg", type=_range(f"--legal-{size}-kg", 1000.0, 100_000.0, "kg"), default=None,
            help=f"{what} legal load, one for every position and spacing [kg] (default: Directive 96/53/EC's by each "
            "group's position and spacing, docs/pavement.md; given for one size only, the other is the directive's "
            f"trailer limit, {'24,000' if size == 'tandem' else '18,000'} kg)",
        )  # fmt: skip
    weigh.add_argument(
        "--legal-axle-kg", type=_range("--legal-axle-kg", 1000.0, 50_000.0, "kg"), default=None,
        help="a single axle's legal load, one for every position [kg] (default: Directive 96/53/EC's, 11,500 kg in "
        "a drive group, 10,000 kg elsewhere); a US file: 23 CFR 658.17's 20,000 lb is 9,071.847 kg",
    )  # fmt: skip
    weigh.add_argument(
        "--resolution-kg", type=_range("--resolution-kg", 0.0, 1000.0, "kg"), default=None,
        help="the file's weight resolution [kg], a multiple of the format's unit (default: detected from the axle "
        "loads, tolerant of a one-unit offset, and reported with its evidence)",
    )  # fmt: skip
    weigh.add_argument("--by-site", action="store_true",
                       help="the sites side by side: each station of a file of several (a state-wide TMG file), or "
                       "each file of several (always then); shares with 95 %% intervals, a site that disagrees with "
                       "the others flagged (docs/weighings.md, 'Many sites')")  # fmt: skip
    weigh.add_argument("--json", action="store_true", help="print the statistics as JSON (shares as fractions)")
    weigh.add_argument("--sharing-factors", metavar="FILE", default=None,
                       help="also write the file's sharing factors for pavement design tools to FILE (csv with a "
                       "header saying what each column is; docs/pavement.md, 'Sharing factors')")  # fmt: skip
    weigh.set_defaults(func=_cmd_weighings, parser=weigh)


def _add_design(sub) -> None:
    """The ``design`` subcommand and its ``show``."""
    design = sub.add_parser("design", help="a bogie of your own: 'show' draws it and prints its static axle loads")
    design_sub = design.add_subparsers(dest="design_command", required=True)
    show = design_sub.add_parser(
        "show",
        help="print a bogie's static axle loads at a chassis tilt and draw it (docs/bogie-file.md)",
        description="Read a bogie file (docs/bogie-file.md) or take a preset, print its static tyre loads at a "
        "chassis tilt (the linear static model) and, with --out, draw its side view with the loads on it.",
    )
    show.add_argument("bogie", help="a bogie file (.yaml) or a preset name (tandem_trrl, triaxle_stage1)")
    show.add_argument(
        "--tilt-deg", type=_range("--tilt-deg", -10.0, 10.0, "degree"), default=0.0,
        help="chassis tilt, nose up positive [degree] (default 0)",
    )  # fmt: skip
    show.add_argument("--out", help="write the side view to this image file (.png, .pdf, .svg)")
    show.set_defaults(func=_cmd_design_show, parser=show)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra:  # the subcommand's usage, not the top-level one, tells what the subcommand takes
        args.parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if args.command == "case":
        _image_suffix(args.parser, "--plot", args.plot)
    elif args.command == "figure2" or args.command == "design":
        _image_suffix(args.parser, "--out", args.out)
    try:
        code = args.func(args)
        sys.stdout.flush()  # inside the try: a reader that closed the pipe fails here, not at exit
        return code
    except ValueError as exc:
        print(f"bogie: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader of our output stopped early (``bogie weighings ... | head``): not an error of ours. Point stdout
        # at /dev/null so that the interpreter's own flush at exit does not fail again, and exit as a C tool killed
        # by SIGPIPE does (128 + 13)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 128 + 13
    except OSError as exc:  # a file that cannot be read or written (--out /proc/x.png): one line, no traceback
        where = exc.filename if exc.filename is not None else "?"
        print(f"bogie: error: cannot write or read {where}: {exc.strerror or exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
