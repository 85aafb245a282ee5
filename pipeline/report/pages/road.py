"""The page "What unequal sharing costs the road": extra pavement wear, axles over the single-axle limit in legal
groups, and what acting saves.

Everything comes from metrics/road.json (the road stage, ``docs/pavement.md``): the simulated fleet's laden steel
groups per protocol, the observed survey's (when one is given) and the design experiment's scenarios.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import new_page, text_block, text_page
from pipeline.report.style import GROUP_LABEL, PROTOCOL_LABEL

__all__ = ["DAMAGE_LABEL", "SCENARIO_LABEL", "page", "road_page", "wear_bars"]

#: the page's title and contents entry
TITLE = "What unequal sharing costs the road"
#: the damage kinds in the chart's order, with their labels
DAMAGE_LABEL = {
    "overall": "overall, the headline\n(k = 4, ESA)",
    "asphalt": "asphalt fatigue\n(k = 5)",
    "subgrade": "subgrade rutting\n(k = 7)",
    "cemented": "cemented layers\n(k = 12)",
}
#: the ways of acting, as the savings chart names them
SCENARIO_LABEL = {"best": "best steel design", "air": "air suspension", "tilt_held": "chassis tilt held"}
#: the sides of the wear chart: (label, path into metrics/road.json, colour)
SIDES = (
    ("tandem, weighbridge", ("simulated", "static", "tandem", "steel"), "C0"),
    ("tri-axle, weighbridge", ("simulated", "static", "triaxle", "steel"), "C1"),
    ("tandem, WIM", ("simulated", "wim", "tandem", "steel"), "C9"),
    ("tri-axle, WIM", ("simulated", "wim", "triaxle", "steel"), "C3"),
    ("observed tandem", ("observed", "tandem", "trailer"), "0.45"),
    ("observed tri-axle", ("observed", "triaxle", "trailer"), "0.15"),
)


def _at(tree: Mapping[str, Any] | None, path: Sequence[str]) -> Mapping[str, Any] | None:
    node: Any = tree
    for key in path:
        if not isinstance(node, Mapping) or key not in node:
            return None
        node = node[key]
    return node if isinstance(node, Mapping) and node.get("n_groups") else None


def wear_bars(ax, m: Mapping[str, Any]) -> list[str]:
    """The extra wear against Austroads' group baseline [%] of each side (:data:`SIDES` present in ``m``) at each
    damage kind, with its interval; returns the labels drawn."""
    sides = [(label, _at(m, path), colour) for label, path, colour in SIDES]
    sides = [s for s in sides if s[1] is not None]
    kinds = [k for k in DAMAGE_LABEL if k in m.get("exponents", {})]
    x = np.arange(len(kinds))
    width = 0.8 / max(len(sides), 1)
    for j, (label, entry, colour) in enumerate(sides):
        # a missing figure is NaN (no bar); a zero is a bar of zero, not a missing one
        value, low, high = (
            np.array([100.0 * (np.nan if entry.get(f"extra_wear_group_{k}{tail}") is None
                               else entry[f"extra_wear_group_{k}{tail}"]) for k in kinds])
            for tail in ("", "_low", "_high")
        )  # fmt: skip
        err = np.clip(np.vstack([value - low, high - value]), 0.0, None)
        ax.bar(x + (j - (len(sides) - 1) / 2) * width, value, width * 0.92, yerr=np.nan_to_num(err), color=colour,
               label=f"{label} (n = {entry['n_groups']})", error_kw={"lw": 0.7, "capsize": 1.5})  # fmt: skip
    ax.set_xticks(x, [DAMAGE_LABEL[k] for k in kinds])
    ax.set_ylabel("extra wear, share of the group count [%]")
    ax.set_title("Extra wear of unequal sharing, share of Austroads' group count")
    ax.set_ylim(top=ax.get_ylim()[1] * 1.45)  # headroom: the legend above the bars, not over them
    ax.legend(loc="upper left", fontsize=7, ncol=2)
    ax.grid(axis="y", lw=0.4, alpha=0.6)
    return [s[0] for s in sides]


def savings_bars(ax, savings: Mapping[str, Any]) -> None:
    """What each way of acting saves: the typical design's extra wear at k = 4 minus the scenario's [percentage
    points], one bar per group and scenario, whiskers the paired bootstrap interval of the saving."""
    rows: list[tuple[str, float, float, float, str]] = []
    for j, g in enumerate(g for g in GROUP_LABEL if g in savings):
        typical = 100.0 * next(iter(savings[g].values()))["extra_wear_overall_typical"]
        for scenario, entry in savings[g].items():
            saved, lo, hi = (entry.get(k) for k in ("saved_wear_overall", "saved_wear_overall_low",
                                                     "saved_wear_overall_high"))  # fmt: skip
            if saved is None:
                continue
            label = f"{GROUP_LABEL[g]} (typical {typical:.2f} %): {SCENARIO_LABEL.get(scenario, scenario)}"
            lo = saved if lo is None else lo
            hi = saved if hi is None else hi
            rows.append((label, 100.0 * saved, 100.0 * (saved - lo), 100.0 * (hi - saved), f"C{j}"))
    y = np.arange(len(rows))[::-1]
    ax.barh(y, [r[1] for r in rows], 0.7, color=[r[4] for r in rows], alpha=0.85,
            xerr=np.clip(np.array([[r[2] for r in rows], [r[3] for r in rows]]), 0.0, None),
            error_kw={"lw": 0.8, "capsize": 2})  # fmt: skip
    ax.set_yticks(y, [r[0] for r in rows], fontsize=7.5)
    ax.axvline(0.0, color="0.3", lw=0.6)
    ax.set_xlabel("extra wear at k = 4 saved against today's typical design, per axle [points]")
    ax.set_title("What acting would save (weighbridge, paired over the design conditions)", loc="right")
    ax.grid(axis="x", lw=0.4, alpha=0.6)


def road_page(m: Mapping[str, Any], caption: Sequence[str]) -> Figure:
    """The page: the wear chart on top, the savings chart below it (when the design study ran), then the words."""
    savings = m.get("savings") or {}
    fig = new_page(TITLE, body=(0.06, 0.50, 0.88, 0.43))
    if savings:
        ax_w, ax_s = fig.subplots(2, 1, gridspec_kw={"height_ratios": (1.25, 1.0)})
        wear_bars(ax_w, m)
        savings_bars(ax_s, savings)
    else:
        wear_bars(fig.subplots(1, 1), m)
    text_block(fig, 0.475, caption, size=8.0)
    return fig


def page(ctx: Context) -> list[Page]:
    """The road page from metrics/road.json; a page of text when the road stage has not run."""
    m = ctx.inputs.road_metrics
    if not m:
        words = ["The road stage has not run (dvc repro road): metrics/road.json is missing."]
        return [Page(TITLE, "", text_page(TITLE, words))]
    caption = text.render("road.j2", m=m, protocol_label=PROTOCOL_LABEL, scenario=SCENARIO_LABEL)
    return [Page(TITLE, "road", road_page(m, caption))]
