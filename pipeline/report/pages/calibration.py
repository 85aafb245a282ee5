"""The calibration pages: the fleet quantities fitted to the observed survey, and the checks of that fit.

Every number comes from what the ``calibrate`` stage wrote (metrics/calibration.json and data/calibration: the
bootstrap, the valley over the most correlated pair, the 1-D profiles, the calibrated fleet's readings and the
ablation on it). Two pages when a fit was made: the fit (its quantities, intervals, distances, trade-offs, valley
and profiles) and its checks (load-share quantiles of the observed, calibrated and held-out groups, their statistics,
the held-out distances, the ablation on the calibrated fleet). When the stage was skipped, one page says why and how
to give a survey.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from bogie.fleet.constants import n_axles
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import first_fit, new_page, table_axes, text_block, text_page
from pipeline.report.style import GROUP_COLOR, GROUP_LABEL, GROUPS, factor_label, load_share_axes
from pipeline.report.style import QUANTITY as SAMPLED_QUANTITY

__all__ = [
    "CAUSE_HEADER", "CHECK_SIDES", "QUANTITY", "SIZES", "cause_page", "cause_rows", "check_page", "convergence_cell",
    "fit_page", "fit_rows", "page", "quantity_label", "skipped_page", "stats_rows",
]  # fmt: skip

#: the group sizes compared
SIZES: tuple[str, ...] = GROUPS
_TILT = SAMPLED_QUANTITY["chassis_tilt"]
#: each fitted quantity's name in the report and its unit (chassis tilt's: its one name, pipeline.report.style)
QUANTITY: dict[str, tuple[str, str]] = {
    "chassis_tilt_mean_deg": (f"{_TILT.name}, centre", _TILT.unit),
    "chassis_tilt_sd_deg": (f"{_TILT.name}, spread (sd)", _TILT.unit),
    "air_share": ("air-sprung share", "-"),
    "site_iri_m_km": ("WIM site roughness (IRI)", "m/km"),
    "sensor_error_pct": ("sensor error per axle (sd)", "%"),
    "contact_roll_radius_mean_mm": ("contact-roll radius, mean", "mm"),
    "bush_stiffness_geomean": ("bush stiffness, geometric mean", "N m/rad"),
    "site_bias_pct": ("WIM site's calibration bias", "%"),
}
#: the sides of the checks page: (label, where in metrics/calibration.json, colour)
CHECK_SIDES: tuple[tuple[str, tuple[str, ...], str], ...] = (
    ("observed", ("observed", "groups"), "0.15"),
    ("calibrated", ("calibrated", "groups"), "C3"),
    ("held-out half, observed", ("held_out", "groups"), "0.6"),
    ("held-out half, calibrated", ("held_out", "calibrated_groups"), "C0"),
)
#: the statistics of the checks table: (key of a groups entry, column header)
STATS: tuple[tuple[str, str], ...] = (
    ("n_groups", "groups"),
    ("share_outside_5pct", "outside 5 %"),
    ("share_over_10pct", "over 10 %"),
    ("mean_spread_kg", "mean spread [kg]"),
    ("median_spread_pct", "median spread [%]"),
)


def quantity_label(name: str, unit: bool = True) -> str:
    """The report's name of a fitted quantity, with its unit in brackets (``unit``)."""
    label, u = QUANTITY.get(name, (name, "-"))
    return f"{label} [{u}]" if unit else label


def _g(x: Any) -> str:
    return "n/a" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:g}"


def _nothing(ax, what: str) -> None:
    ax.text(0.5, 0.5, what, ha="center", va="center", transform=ax.transAxes, color="0.4")
    ax.set_axis_off()


# ---- the fit ------------------------------------------------------------------------------------------------------
def _interval(e: Mapping[str, Any]) -> str:
    return "none" if e.get("low") is None or e.get("high") is None else f"{_g(e['low'])} to {_g(e['high'])}"


def fit_rows(m: Mapping[str, Any]) -> list[list[str]]:
    """The fit table: each fitted quantity (the calibrated fleet's value and interval, the posterior's; the prior-free
    minimum and its bootstrap interval beside it, a diagnostic; the bounds), then each fixed one (its value)."""
    rows = []
    free = (m.get("prior_free_minimum") or {}).get("fitted", {})
    post = (m.get("posterior") or {}).get("quantities", {})
    for q, e in m["fitted"].items():
        f = free.get(q)
        diagnostic = "-" if f is None else f"{_g(f['value'])} ({_interval(f)})"
        kind = "fitted" if e.get("source", "posterior") == "posterior" else "minimum"
        rows.append([quantity_label(q), kind, _g(e["value"]), _interval(e), diagnostic, " to ".join(
            _g(b) for b in e["bounds"]), convergence_cell(post.get(q))])  # fmt: skip
    for q, v in (m.get("fixed") or {}).items():
        if v is not None:
            rows.append([quantity_label(q), "fixed", _g(v), "-", "-", "-", "-"])
    return rows


def convergence_cell(p: Mapping[str, Any] | None) -> str:
    """A quantity's R-hat and its bulk and tail effective sample sizes, ``1.003; 2235/1876`` ("-": none, as in an
    older stage's metrics; "n/a": undefined)."""
    if p is None or "rhat" not in p:
        return "-"
    rhat = "n/a" if p["rhat"] is None else f"{p['rhat']:.3f}"
    ess = "/".join("n/a" if p.get(k) is None else f"{p[k]:.0f}" for k in ("ess_bulk", "ess_tail"))
    return f"{rhat}; {ess}"


#: the fit table's header and column widths
FIT_HEADER = (
    "quantity", "", "posterior\nmedian", "credible\ninterval", "prior-free minimum\n(bootstrap interval)", "bounds",
    "R-hat; ESS\nbulk/tail",
)  # fmt: skip
FIT_WIDTHS = (0.27, 0.05, 0.09, 0.16, 0.19, 0.09, 0.15)


def _valley(
    ax, cax, valley: pd.DataFrame, boot: pd.DataFrame, fitted: Mapping[str, Any], free: Mapping[str, Any]
) -> None:
    qx, qy = valley["quantity_x"].iloc[0], valley["quantity_y"].iloc[0]
    grid = valley.pivot_table(index="y", columns="x", values="distance")
    x, y, z = grid.columns.to_numpy(float), grid.index.to_numpy(float), grid.to_numpy(float)
    mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis_r")
    levels = np.quantile(z[np.isfinite(z)], [0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.7])
    ax.contour(x, y, z, levels=np.unique(levels), colors="white", linewidths=0.6, alpha=0.8)
    if len(boot) and qx in boot and qy in boot:
        ax.plot(boot[qx], boot[qy], "o", ms=4.5, mfc="none", mec="C1", mew=1.2, label="bootstrap refits")
    ax.plot(fitted[qx]["value"], fitted[qy]["value"], "*", ms=12, color="C3", mec="white", mew=0.8,
            label="posterior median")  # fmt: skip
    if qx in free and qy in free:
        ax.plot(free[qx]["value"], free[qy]["value"], "X", ms=8, color="0.15", mec="white", mew=0.8,
                label="prior-free minimum")  # fmt: skip
    ax.set_xlabel(quantity_label(qx))
    ax.set_ylabel(quantity_label(qy))
    ax.set_title("Valley: distance over the most correlated pair\n(the others at the prior-free minimum)", fontsize=9)
    ax.grid(False)
    ax.legend(loc="upper right", framealpha=0.85)
    cax.figure.colorbar(mesh, cax=cax, label="distance [-]")


def _profile(ax, profile: pd.DataFrame, q: str, entry: Mapping[str, Any], free: Any, legend: bool) -> None:
    ax.plot(profile["value"], profile["distance"], color="0.2", lw=1.2)
    if entry["low"] is not None and entry["high"] is not None:
        ax.axvspan(entry["low"], entry["high"], color="C0", alpha=0.2, lw=0, label="credible interval")
    ax.axvline(entry["value"], color="C3", lw=1.2, label="posterior median")
    if free is not None:
        ax.axvline(free["value"], color="0.15", lw=1.0, ls="--", label="prior-free minimum")
    ax.set_xlim(*entry["bounds"])
    ax.set_xlabel(quantity_label(q), fontsize=8)
    ax.set_ylabel("distance [-]", fontsize=8)
    if legend:
        ax.legend(loc="upper center", fontsize=7)


def fit_page(m: Mapping[str, Any], tables: Mapping[str, pd.DataFrame], caption: Sequence[str]) -> Figure:
    """The valley and the profiles above the fit table and ``caption``."""
    fitted, valley, profiles = m["fitted"], tables["valley.csv"], tables["profiles.csv"]
    free = (m.get("prior_free_minimum") or {}).get("fitted", {})
    boot, names = tables["bootstrap.csv"], list(m["fitted"])
    rows = fit_rows(m)

    def draw(fit: tuple[float, float]) -> tuple[Figure, float]:
        bottom, type_size = fit
        fig = new_page("Calibration: the fit", body=(0.06, bottom, 0.88, 0.93 - bottom))
        has_valley = len(valley) > 0
        rest = max(len(names) - (2 if has_valley else 0), 0)
        n_rows = max((2 if has_valley else 0) + math.ceil(rest / 3), 2)  # one profile alone: a third of the width
        grid = fig.add_gridspec(n_rows, 3, width_ratios=(1, 1, 1))
        slots = ([(0, 2), (1, 2)] if has_valley else []) + [
            (r, c) for r in range(2 if has_valley else 0, n_rows) for c in range(3)
        ]
        if has_valley:
            inner = grid[0:2, 0:2].subgridspec(1, 2, width_ratios=(1, 0.045), wspace=0.02)
            _valley(fig.add_subplot(inner[0]), fig.add_subplot(inner[1]), valley, boot, fitted, free)
        for k, q in enumerate(names):
            ax = fig.add_subplot(grid[slots[k]])
            _profile(ax, profiles[profiles["quantity"] == q], q, fitted[q], free.get(q), legend=k == 0)
        top = table_axes(fig, bottom - 0.02, FIT_HEADER, rows, FIT_WIDTHS, size=type_size - 0.6)
        return fig, text_block(fig, top - 0.012, caption, size=type_size)

    return first_fit(FIT_FITS, draw)


#: (bottom of the charts [page fraction], type size [pt]) tried in turn until the text ends above the footer
FIT_FITS = ((0.47, 8.0), (0.49, 7.6), (0.52, 7.4), (0.55, 7.1), (0.58, 6.8))


# ---- the checks ---------------------------------------------------------------------------------------------------
def _side(m: Mapping[str, Any], where: Sequence[str], size: str) -> Mapping[str, Any] | None:
    entry: Any = m
    for key in where:
        entry = entry.get(key) if isinstance(entry, Mapping) else None
    entry = entry.get(size) if isinstance(entry, Mapping) else None
    return entry if entry and entry.get("n_groups") else None


def stats_rows(m: Mapping[str, Any]) -> list[list[str]]:
    """The checks table: each side's statistics of each group size."""
    rows = []
    for size in SIZES:
        for label, where, _ in CHECK_SIDES:
            e = _side(m, where, size) or {}
            cells = []
            for key, _ in STATS:
                v = e.get(key)
                if v is None:
                    cells.append("n/a" if key != "n_groups" else "0")
                elif key.startswith("share_"):
                    cells.append(text.pct(v, unit=False))
                elif key == "mean_spread_kg":
                    cells.append(f"{v:.0f}")
                elif key == "median_spread_pct":
                    cells.append(f"{v:.1f}")
                else:
                    cells.append(f"{v:d}")
            rows.append([GROUP_LABEL[size], label, *cells])
    return rows


STATS_HEADER = ("group", "side", *(h for _, h in STATS))
STATS_WIDTHS = (0.10, 0.24, 0.08, 0.12, 0.12, 0.16, 0.18)


def _quantiles(ax, m: Mapping[str, Any], size: str) -> None:
    """Each side's load-share quantiles per axle: box p25-p75, line p50, whiskers p05-p95."""
    n = n_axles(size)
    title = f"{GROUP_LABEL[size].capitalize()}: load share per axle"
    sides = [(label, color, _side(m, where, size)) for label, where, color in CHECK_SIDES]
    sides = [s for s in sides if s[2] is not None]
    ax.set_title(title)
    if not sides:
        _nothing(ax, f"no {GROUP_LABEL[size]} group")
        return
    width = 0.8 / len(CHECK_SIDES)
    handles = []
    for k, (label, color, e) in enumerate(sides):
        for i in range(n):
            qs = e["load_share_quantiles"][f"axle_{i + 1}"]
            x = i + (k - (len(sides) - 1) / 2) * width
            half = 0.4 * width
            ax.add_patch(Rectangle((x - half, qs["p25"]), 2 * half, qs["p75"] - qs["p25"], facecolor=color,
                                   alpha=0.45, edgecolor=color, lw=0.8))  # fmt: skip
            ax.plot([x, x], [qs["p05"], qs["p25"]], color=color, lw=1.0)
            ax.plot([x, x], [qs["p75"], qs["p95"]], color=color, lw=1.0)
            ax.plot([x - half * 0.6, x + half * 0.6], [qs["p05"]] * 2, color=color, lw=1.0)
            ax.plot([x - half * 0.6, x + half * 0.6], [qs["p95"]] * 2, color=color, lw=1.0)
            ax.plot([x - half, x + half], [qs["p50"]] * 2, color=color, lw=1.8)
        handles.append(Patch(facecolor=color, alpha=0.45, edgecolor=color, label=f"{label}, {e['n_groups']} groups"))
    load_share_axes(ax, n)
    ax.set_title(title, pad=8 + 10 * -(-len(handles) // 2))  # above the legend's rows
    # between the title and the chart: the boxes of the sides can reach any height
    ax.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, fontsize=6.5,
              frameon=False, borderaxespad=0.1, columnspacing=0.8, handletextpad=0.3)  # fmt: skip


def _ablation(ax, ablation: pd.DataFrame) -> None:
    """What removing each inhibitor buys on the calibrated fleet's steel groups, tri-axle and tandem."""
    ax.set_title("Ablation on the calibrated fleet: what removing each inhibitor buys")
    variants = [v for v in dict.fromkeys(ablation["variant"]) if v != "baseline"]
    if ablation.empty or not variants:
        _nothing(ax, "no ablation")
        return
    sizes = [s for s in ("triaxle", "tandem") if s in set(ablation["group"])]
    width = 0.8 / len(sizes)
    x = np.arange(len(variants))
    for k, size in enumerate(sizes):
        sub = ablation[ablation["group"] == size].set_index("variant")
        base = sub.loc["baseline"] if "baseline" in sub.index else None
        values = [float(sub.loc[v, "buys_points"]) if v in sub.index else np.nan for v in variants]
        pos = x + (k - (len(sizes) - 1) / 2) * width
        n = int(base["n_groups"]) if base is not None else int(sub["n_groups"].max())
        mean = f", {base['mean_max_deviation_pct']:.2f} % with all present" if base is not None else ""
        ax.bar(pos, values, 0.9 * width, color=GROUP_COLOR[size],
               label=f"{GROUP_LABEL[size]} ({n} steel groups{mean})")  # fmt: skip
        for p_, v in zip(pos, values):
            if not np.isfinite(v):
                ax.text(p_, 0.0, "n/a", ha="center", va="bottom", fontsize=6.5, color="0.4")
    ax.axhline(0.0, color="0.3", lw=0.7)
    ax.set_xticks(x, [factor_label(v) for v in variants], rotation=15, ha="right")
    ax.set_ylabel("mean max. deviation\nreduced by [% points]")
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + 0.35 * (high - low))  # headroom for the legend
    ax.legend(loc="upper right")


def check_page(
    m: Mapping[str, Any], tables: Mapping[str, pd.DataFrame], intro: Sequence[str], caption: Sequence[str]
) -> Figure:
    """Quantiles per size and the ablation's bars above the statistics table and ``caption``."""
    rows = stats_rows(m)

    def draw(fit: tuple[float, float]) -> tuple[Figure, float]:
        bottom, type_size = fit
        fig = new_page("Calibration: observed against calibrated, held out, ablation",
                       body=(0.06, bottom, 0.88, 0.93 - bottom))  # fmt: skip
        grid = fig.add_gridspec(2, len(SIZES), height_ratios=(1.25, 1))
        for c, size in enumerate(SIZES):
            _quantiles(fig.add_subplot(grid[0, c]), m, size)
        _ablation(fig.add_subplot(grid[1, :]), tables["ablation.csv"])
        y = text_block(fig, bottom - 0.012, intro, size=type_size)
        top = table_axes(fig, y + 0.004, STATS_HEADER, rows, STATS_WIDTHS, size=type_size - 0.3)
        return fig, text_block(fig, top - 0.012, caption, size=type_size)

    return first_fit(CHECK_FITS, draw)


CHECK_FITS = ((0.45, 7.9), (0.47, 7.6), (0.5, 7.4), (0.53, 7.1), (0.56, 6.8))


# ---- what the WIM shows, by cause ---------------------------------------------------------------------------------
#: the causes attributed (bogie.fleet.calibration.attribution.CAUSES), their labels and colours
CAUSE_LABEL: dict[str, tuple[str, str]] = {
    "resolution": ("file resolution", "C7"), "sensor": ("sensor error", "C4"), "tilt": ("chassis tilt", "C3"),
    "dynamics": ("dynamics", "C2"),
}  # fmt: skip
#: the statistics drawn: key, axis label, factor to the axis's unit
CAUSE_STATS: tuple[tuple[str, str, float], ...] = (
    ("share_outside_5pct", "outside 5 % [% of groups]", 100.0),
    ("mean_spread_pct", "mean spread [% of the mean axle load]", 1.0),
)


def _group_key_label(key: str) -> str:
    size, kind = key.split("/")
    return f"{GROUP_LABEL[size]}, {kind}"


def _causes(ax, attribution: Mapping[str, Any], stat: str, ylabel: str, factor: float, legend: bool) -> None:
    """Per size and suspension: the readings as observed, the suspension at rest, each cause's Shapley share (bars,
    with their intervals) and its one-at-a-time share (open diamonds)."""
    keys = [k for k in ("triaxle/steel", "triaxle/air", "tandem/steel", "tandem/air") if k in attribution]
    bars = ["as_observed", *CAUSE_LABEL, "at_rest"]
    width = 0.8 / len(bars)
    x = np.arange(len(keys))
    for j, bar in enumerate(bars):
        pos = x + (j - (len(bars) - 1) / 2) * width
        if bar in ("as_observed", "at_rest"):
            values = [factor * attribution[k][bar][stat] for k in keys]
            color, label = ("0.15", "as observed") if bar == "as_observed" else ("0.7", "at rest (all off)")
            ax.bar(pos, values, 0.9 * width, color=color, label=label)
            continue
        entries = [attribution[k]["shapley"][bar][stat] for k in keys]
        values = np.array([factor * e["value"] for e in entries])
        err = np.array([[factor * (e["value"] - e["low"]), factor * (e["high"] - e["value"])] for e in entries]).T
        ax.bar(pos, values, 0.9 * width, color=CAUSE_LABEL[bar][1], label=f"{CAUSE_LABEL[bar][0]}'s share")
        ax.errorbar(pos, values, yerr=np.maximum(err, 0.0), fmt="none", ecolor="0.2", elinewidth=0.8, capsize=1.5)
        single = [factor * attribution[k]["one_at_a_time"][bar][stat]["value"] for k in keys]
        ax.plot(pos, single, "D", ms=3.5, mfc="white", mec="0.1", mew=0.8, ls="none",
                label="one at a time" if j == len(bars) - 2 else None)  # fmt: skip
    ax.axhline(0.0, color="0.3", lw=0.7)
    ax.set_xticks(x, [f"{_group_key_label(k)}\n({attribution[k]['n_groups']} groups)" for k in keys])
    ax.set_ylabel(ylabel)
    if legend:
        low, high = ax.get_ylim()
        ax.set_ylim(low, high + 0.45 * (high - low))  # headroom for the legend
        handles, labels = ax.get_legend_handles_labels()
        last = labels.index("one at a time")  # the marker after the bars, whatever order matplotlib keeps
        order = [i for i in range(len(labels)) if i != last] + [last]
        ax.legend([handles[i] for i in order], [labels[i] for i in order], loc="upper right", ncol=4, fontsize=7)


def _share(e: Mapping[str, Any]) -> str:
    """A share of groups [-] in % above its interval: ``+33`` and ``(+21 to +46)``."""
    return f"{100 * e['value']:+.0f}\n({100 * e['low']:+.0f} to {100 * e['high']:+.0f})"


def cause_rows(attribution: Mapping[str, Any]) -> list[list[str]]:
    """The table under the bars: per size and suspension, outside 5 % as observed, each cause's Shapley share with
    its interval, the suspension at rest; below, each cause's one-at-a-time share and their interaction, in % of
    groups."""
    rows = []
    for key in (k for k in ("triaxle/steel", "triaxle/air", "tandem/steel", "tandem/air") if k in attribution):
        entry, stat = attribution[key], "share_outside_5pct"
        shapley = [_share(entry["shapley"][cause][stat]) for cause in CAUSE_LABEL]
        single = [_share(entry["one_at_a_time"][cause][stat]) for cause in CAUSE_LABEL]
        rows.append([_group_key_label(key), str(entry["n_groups"]), f"{100 * entry['as_observed'][stat]:.0f}",
                     "Shapley", *shapley, "-", f"{100 * entry['at_rest'][stat]:.0f}"])  # fmt: skip
        rows.append(["", "", "", "one at\na time", *single, _share(entry["interaction"][stat]), ""])
    return rows


#: the cause table's header and widths
CAUSE_HEADER = (
    "group", "groups", "observed", "shares", "resolution", "sensor", "tilt", "dynamics", "interaction", "at rest",
)  # fmt: skip
CAUSE_WIDTHS = (0.12, 0.06, 0.08, 0.08, 0.117, 0.117, 0.117, 0.117, 0.117, 0.065)


def cause_page(m: Mapping[str, Any], caption: Sequence[str]) -> Figure:
    """The attribution's bars, outside 5 % and mean spread, above its table and ``caption``."""
    attribution = m["attribution"]

    def draw(fit: tuple[float, float]) -> tuple[Figure, float]:
        bottom, type_size = fit
        fig = new_page("Calibration: what the WIM shows, by cause", body=(0.06, bottom, 0.88, 0.93 - bottom))
        grid = fig.add_gridspec(len(CAUSE_STATS), 1)
        for r, (stat, label, factor) in enumerate(CAUSE_STATS):
            _causes(fig.add_subplot(grid[r, 0]), attribution, stat, label, factor, r == 0)
        top = table_axes(fig, bottom - 0.01, CAUSE_HEADER, cause_rows(attribution), CAUSE_WIDTHS, size=type_size - 0.8)
        return fig, text_block(fig, top - 0.012, caption, size=type_size)

    return first_fit(CHECK_FITS, draw)


# ---- skipped ------------------------------------------------------------------------------------------------------
def skipped_page(m: Mapping[str, Any]) -> Figure:
    """One page of text: why nothing was calibrated and how to give a survey."""
    return text_page("Calibration", text.render("calibration_skipped.j2", m=m), size=9.0)


def page(ctx: Context) -> list[Page]:
    """The calibration pages: from data/calibration and metrics/calibration.json; none when no survey was given (the
    observed page says what a survey brings), one page of why when a survey was given and the stage skipped."""
    m, tables = ctx.inputs.calibration_metrics, ctx.inputs.calibration
    if m.get("skipped", True):
        if ctx.inputs.observed_metrics.get("observed") is None:
            return []  # no survey to calibrate to: the observed page says how to give one and that it is calibrated
        return [Page("Calibration", "", skipped_page(m))]
    valley = len(tables["valley.csv"]) > 0
    fit = fit_page(m, tables, text.render("calibration_fit.j2", m=m, label=quantity_label, valley=valley))
    intro = text.render("calibration_check_intro.j2", m=m)
    check = check_page(m, tables, intro, text.render("calibration_check.j2", m=m, sizes=SIZES))
    pages = [
        Page("Calibration: the fit", "calibration_fit", fit),
        Page("Calibration: observed against calibrated, held out, ablation", "calibration_checks", check),
    ]
    if m.get("attribution"):
        by_cause = cause_page(m, text.render("calibration_causes.j2", m=m))
        pages.append(Page("Calibration: what the WIM shows, by cause", "calibration_causes", by_cause))
    return pages
