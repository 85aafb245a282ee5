"""Figures shared by the command line and the report. Each function returns a matplotlib Figure and writes nothing."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from bogie.metrics import p
from bogie.presets import STAGE1_CHASSIS_DEFLECTION, triaxle_stage1
from bogie.settings import check_value
from bogie.steel.static import nondimensional_loads

#: the reference's Figure 2: chassis slopes 0 to 2 degrees in half-degree steps
FIGURE2_SLOPES_DEG = (0.0, 0.5, 1.0, 1.5, 2.0)


def new_figure(width: float = 6.4, height: float = 4.2) -> Figure:
    """A figure with the project's style (no pyplot state, safe in worker processes)."""
    fig = Figure(figsize=(width, height), layout="constrained")
    return fig


#: metadata that would stamp the build time into a file, by format: left out so a figure is byte-reproducible
_NO_DATE = {".pdf": {"CreationDate": None}, ".svg": {"Date": None}, ".ps": {"CreationDate": None},
            ".eps": {"CreationDate": None}}  # fmt: skip


def save_figure(fig: Figure, path: str | Path, dpi: int = 150) -> None:
    """Write ``fig`` to ``path`` atomically (temporary name, then rename); the format follows the suffix.

    No creation date is written, so the same figure gives the same bytes whenever it is drawn.
    """
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp{out.suffix}")
    # SVG element ids are random unless salted
    try:
        with matplotlib.rc_context({"svg.hashsalt": "bogie"}):
            fig.savefig(tmp, dpi=dpi, metadata=_NO_DATE.get(out.suffix.lower()))
        tmp.replace(out)
    except BaseException:
        tmp.unlink(missing_ok=True)  # nothing half-written left behind
        raise


def figure2(
    q_max: float = 20.0,
    slopes_deg: Sequence[float] = FIGURE2_SLOPES_DEG,
    chassis_deflection: float = STAGE1_CHASSIS_DEFLECTION,
    axle_spacing: float | None = None,
    stage1_q: float | None = None,
    fe_points: dict[float, tuple[float, float]] | None = None,
) -> Figure:
    """The reference's Figure 2: wheel load deviation p (Equation 2) against q for a tri-axle bogie.

    Parameters
    ----------
    q_max
        Largest stiffness ratio on the axis [-].
    slopes_deg
        Chassis slopes, one curve each [degree].
    chassis_deflection
        Chassis downward displacement alpha [m]; the reference's 57 mm by default.
    axle_spacing
        Axle spacing s in d = psi s / alpha [m]; that of :func:`~bogie.presets.triaxle_stage1` by default.
    stage1_q
        q of the Stage 1 suspension to mark [-]; that of :func:`~bogie.presets.triaxle_stage1` (4.3) by default.
    fe_points
        Optional finite element results to overlay: slope [degree] -> (q, p).
    """
    check_value("q_max", q_max, "-", low=0.0, low_open=True, note="stiffness ratio")
    check_value("chassis_deflection", chassis_deflection, "m", low=0.0, low_open=True)
    stage1 = triaxle_stage1()
    spacing = stage1.axle_x[1] - stage1.axle_x[0] if axle_spacing is None else axle_spacing
    q_mark = stage1.q(0) if stage1_q is None else stage1_q
    q = np.linspace(0.0, q_max, 401)
    fig = new_figure()
    ax = fig.add_subplot()
    for slope in slopes_deg:
        d = math.radians(slope) * spacing / chassis_deflection
        ax.plot(q, p(nondimensional_loads(q, d)), lw=1.6, label=f"{slope:g}°", clip_on=False)
        p_mark = float(p(nondimensional_loads(q_mark, d)))
        ax.plot([q_mark], [p_mark], "o", color="0.2", ms=3.5, zorder=3)
    ax.axvline(q_mark, color="0.5", lw=0.8, ls="--")
    ax.annotate(
        f"Stage 1 suspension, q = {q_mark:.1f}",
        xy=(q_mark, ax.get_ylim()[1] * 0.92),
        xytext=(6, 0),
        textcoords="offset points",
        fontsize=8,
        color="0.3",
    )
    if fe_points:
        qs, ps = zip(*fe_points.values())
        ax.plot(qs, ps, "*", color="k", ms=9, label="finite element (Stage 1)")
    _figure2_axes(ax, q_max, chassis_deflection, spacing)
    return fig


def _figure2_axes(ax, q_max: float, chassis_deflection: float, spacing: float) -> None:
    """Limits, labels, title [alpha in mm, s in m], legend and grid of Figure 2."""
    ax.set_xlim(0.0, q_max)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel(r"relative stiffness parameter $q = b^2 K_S / 4 K_B$ [-]")
    ax.set_ylabel(r"wheel load deviation $p$ (Equation 2) [-]")
    ax.set_title(
        f"Tri-axle static equalisation (Equation 1), α = {chassis_deflection * 1e3:.0f} mm, s = {spacing:.2f} m",
        fontsize=10,
    )
    ax.legend(title="chassis slope", fontsize=8, title_fontsize=8)
    ax.grid(True, lw=0.4, alpha=0.5)


def case_history(result, title: str = "", note: str = "", case=None, ours: dict | None = None) -> Figure:
    """Histories of one dynamic run, as the reference's Figures 5-12: centre displacement, p and P1, wheel loads.

    Parameters
    ----------
    result
        A :class:`bogie.results.DynamicResult`.
    title
        Figure title.
    note
        A line printed under the title (e.g. what the reference reported).
    case
        The :class:`bogie.steel.cases.Case` of the run, if it is one. For a Table 2 run the P1 panel is in newtons, the
        unit of the reference's table, with the reference's figures and ``ours`` (the run's summary) drawn on it.
    ours
        The run's summary (:func:`bogie.steel.cases.summary`), drawn with the reference's for a Table 2 run.
    """
    panels = 3 if "centre_displacement" in result.extras else 2
    fig = new_figure(7.0, 2.0 + 1.9 * panels)
    axes = fig.subplots(panels, 1, sharex=True)
    k = 0
    if panels == 3:
        axes[0].plot(result.t, np.asarray(result.extras["centre_displacement"]) * 1e3, color="C0", lw=1.2)
        axes[0].set_ylabel("centre displacement\n[mm]")
        k = 1
    if case is not None and case.unit("p1_") == "N":
        _p1_newtons_panel(axes[k], result, case, ours or {})
    else:
        axes[k].plot(result.t, result.p, lw=1.2, label="p (Eq. 2)")
        axes[k].plot(result.t, result.p1, lw=1.2, ls="--", label="P1 (Eq. 4)")
        axes[k].set_ylabel("wheel load\nparameter [-]")
        _headroom(axes[k])
        axes[k].legend(fontsize=8, loc="upper right")
    for i in range(result.wheel_loads.shape[1]):
        axes[k + 1].plot(result.t, result.wheel_loads[:, i] / 1e3, lw=1.2, label=f"axle {i + 1}")
    axes[k + 1].set_ylabel("wheel load\n[kN]")
    axes[k + 1].set_xlabel("time [s]")
    _headroom(axes[k + 1])
    axes[k + 1].legend(fontsize=8, loc="upper right", ncol=result.wheel_loads.shape[1])
    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
    if title or note:
        fig.suptitle(title + (f"\n{note}" if note else ""), fontsize=10)
    return fig


def _headroom(ax, share: float = 0.3) -> None:
    """Raise ``ax``'s upper limit by ``share`` of its range: room for a legend above the curves, not over them."""
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + share * (high - low))


def _p1_newtons_panel(ax, result, case, ours: dict) -> None:
    """P1 of the wheel loads in newtons, with each figure of the reference's table and ours as a level line."""
    from bogie.metrics import p1

    history = p1(result.wheel_loads)
    ax.plot(result.t, history, lw=1.2, color="C1", label="P1 (Eq. 4), ours")
    levels = [float(np.max(history))]
    for j, (key, value) in enumerate(ours.items()):
        if case.unit(key) == "N" and isinstance(value, float):
            ax.axhline(value, color="0.2", lw=0.9, ls=(0, (4, 2 + j)), label=f"ours: {key} {value:.0f} N")
            levels.append(value)
    for j, (key, value) in enumerate(case.reference.items()):
        if case.unit(key) == "N" and isinstance(value, int | float):
            ax.axhline(value, color="C3", lw=1.1, ls=(0, (1, 1 + j)), label=f"reference: {key} {value:g} N")
            levels.append(float(value))
    ax.set_ylabel("P1 [N]")
    ax.set_ylim(0.0, 1.6 * max(levels))  # room above the lines for the legend
    ax.legend(fontsize=7, loc="upper right")


# ---- a bogie's side view ----------------------------------------------------------------------------------------
#: heights of the side view's schematic parts [m]: the spring seat above the axle centre, and the leaves' camber, the
#: drop from the seat to the pads of an arched spring (the model has one seat height, ``docs/models.md``; these only
#: draw it)
_SEAT_RISE, _CAMBER = 0.10, 0.06


def bogie_side_view(bogie, loads: Sequence[float], chassis_tilt: float, title: str = "") -> Figure:
    """One side of a bogie seen from the side, its static axle loads written under the tyres.

    Drawn to scale from the bogie's geometry: the tyres on the road (radius less wear), each leaf spring from its
    seat on the axle to its two pads, the front and rear hangers and each equaliser's bracket, pivot and arms, and
    the chassis at the king pin's height (``pad_drop`` above the pads), pitched by the tilt about the bogie centre
    with the pads; the spring and pad heights are schematic (the model has one seat height).

    Parameters
    ----------
    bogie
        A :class:`bogie.params.Bogie`.
    loads
        Each axle's static tyre load, front to rear [N] (:func:`bogie.steel.static.tilted_axle_loads`).
    chassis_tilt
        Pitch of the chassis, nose up positive [rad]: the rear of the drawing lower.
    title
        The figure's title.
    """
    n = bogie.n_axles
    x = np.asarray(bogie.axle_x)
    loads = np.asarray(loads, dtype=float)
    radius = bogie.tyre_radius - np.asarray(bogie.tyre_wear)
    centre = bogie.bogie_centre_x
    slope = math.tan(chassis_tilt)
    z_pad0 = float(np.max(radius)) + _SEAT_RISE - _CAMBER

    def pad(xx):  # the chassis's pads, pitched with it about the bogie centre (nose up: rear lower)
        return z_pad0 - (np.asarray(xx) - centre) * slope

    fig = new_figure(7.6, 4.6)
    ax = fig.add_subplot()
    x0, x1 = bogie.front_hanger_x - 0.45, bogie.rear_hanger_x + 0.45
    z_chassis = z_pad0 + max(bogie.pad_drop, 0.12)
    _side_view_frame(ax, bogie, chassis_tilt, pad, (x0, x1), z_chassis, slope)
    for i in range(n):
        _side_view_axle(ax, bogie, i, x, radius, loads, pad)
    _side_view_spacings(ax, x, n)
    _side_view_finish(fig, ax, (x0, x1), z_chassis, title)
    return fig


#: the side view's colours: steel, leaf springs, tyre loads
_SIDE_STEEL, _SIDE_SPRING, _SIDE_LOAD = "0.25", "tab:blue", "tab:red"


def _side_view_frame(ax, bogie, chassis_tilt: float, pad, span, z_chassis: float, slope: float) -> None:
    """The road, the tilted chassis, the hangers and each equaliser (bracket, arms, pivot) of the side view."""
    from matplotlib.patches import Circle

    centre = bogie.bogie_centre_x
    x0, x1 = span
    ax.plot([x0 - 0.3, x1 + 0.3], [0.0, 0.0], color="0.5", lw=1.0)  # the road
    ax.fill_between([x0 - 0.3, x1 + 0.3], -0.06, 0.0, color="0.88", lw=0)
    chassis_x = np.array([x0, x1])
    chassis_z = z_chassis - (chassis_x - centre) * slope
    ax.fill_between(chassis_x, chassis_z, chassis_z + 0.09, color="0.55", lw=0)
    ax.text(x0 + 0.05, chassis_z[0] + 0.13, f"chassis, tilted {math.degrees(chassis_tilt):+.2f}° (nose up +)",
            fontsize=8, va="bottom")  # fmt: skip
    for hx in (bogie.front_hanger_x, bogie.rear_hanger_x):  # the hangers: brackets from the chassis to the outer pads
        ax.plot([hx, hx], [pad(hx), z_chassis - (hx - centre) * slope], color=_SIDE_STEEL, lw=2.5,
                solid_capstyle="butt")  # fmt: skip
    for j, px in enumerate(bogie.equaliser_pivot_x):
        tip_f, tip_r = px - bogie.equaliser_front_arm[j], px + bogie.equaliser_rear_arm[j]
        z_pivot = pad(px) + 0.5 * (bogie.equaliser_front_tip_drop + bogie.equaliser_rear_tip_drop) + 0.03
        ax.plot([px, px], [z_pivot, z_chassis - (px - centre) * slope], color=_SIDE_STEEL, lw=2.5,
                solid_capstyle="butt")  # fmt: skip
        ax.plot([tip_f, px, tip_r], [pad(tip_f), z_pivot, pad(tip_r)], color="tab:orange", lw=3.0,
                solid_capstyle="round", zorder=4)  # fmt: skip
        ax.add_patch(Circle((px, z_pivot), 0.025, facecolor="white", edgecolor="k", lw=1.0, zorder=5))


def _side_view_axle(ax, bogie, i: int, x, radius, loads, pad) -> None:
    """Axle ``i`` of the side view: its arched leaf spring and seat, its tyre, and its load arrow and label."""
    from matplotlib.patches import Circle, FancyArrowPatch

    ends = (x[i] - bogie.spring_front_half_length[i], x[i] + bogie.spring_rear_half_length[i])
    seat = radius[i] + _SEAT_RISE
    # an arched leaf: a parabola through its front pad, its seat on the axle and its rear pad, three leaves deep
    fit = np.polyfit(  # numerics-ok: the leaf drawn in a figure, no number out
        [ends[0], x[i], ends[1]], [pad(ends[0]), seat, pad(ends[1])], 2
    )
    xs = np.linspace(ends[0], ends[1], 60)
    for k, depth in enumerate((0.0, 0.018, 0.036)):
        cut = xs[np.abs(xs - x[i]) <= (1.0 - 0.25 * k) * max(x[i] - ends[0], ends[1] - x[i])]
        ax.plot(cut, np.polyval(fit, cut) - depth, color=_SIDE_SPRING, lw=1.6, zorder=3)
    ax.plot([x[i], x[i]], [radius[i], seat - 0.036], color=_SIDE_STEEL, lw=4.0, zorder=3)  # the U-bolted seat
    # the tyre as an outline, so that the suspension behind it shows
    ax.add_patch(Circle((x[i], radius[i]), radius[i], facecolor="0.93", edgecolor="0.2", lw=2.2, zorder=1))
    ax.add_patch(Circle((x[i], radius[i]), 0.55 * radius[i], facecolor="none", edgecolor="0.55", lw=0.8, zorder=1))
    ax.add_patch(Circle((x[i], radius[i]), 0.05, facecolor="white", edgecolor="k", zorder=3))
    ax.add_patch(FancyArrowPatch((x[i], -0.42), (x[i], -0.07), arrowstyle="-|>", mutation_scale=12,
                                 color=_SIDE_LOAD, lw=1.6))  # fmt: skip
    share = loads[i] / loads.sum() * 100.0
    ax.text(x[i], -0.47, f"axle {i + 1}\n{loads[i] / 1e3:.1f} kN\n{share:.1f} %", ha="center", va="top",
            fontsize=8.5, color=_SIDE_LOAD)  # fmt: skip


def _side_view_spacings(ax, x, n: int) -> None:
    """The axle spacings of the side view, dimensioned under the loads [mm]."""
    z_dim = -1.0
    for i in range(n - 1):
        mid = 0.5 * (x[i] + x[i + 1])
        ax.annotate("", (x[i], z_dim), (x[i + 1], z_dim), arrowprops={"arrowstyle": "<->", "lw": 0.8, "color": "0.3"})
        ax.text(mid, z_dim + 0.03, f"{(x[i + 1] - x[i]) * 1e3:.0f} mm", ha="center", va="bottom", fontsize=7.5,
                color="0.3")  # fmt: skip
    for xi in x:
        ax.plot([xi, xi], [z_dim - 0.05, z_dim + 0.05], color="0.3", lw=0.8)


def _side_view_finish(fig, ax, span, z_chassis: float, title: str) -> None:
    """The side view's legend, limits (to scale), labels, title and grid."""
    from matplotlib.lines import Line2D

    x0, x1 = span
    handles = [Line2D([], [], color=_SIDE_SPRING, lw=1.6, label="leaf spring"),
               Line2D([], [], color="tab:orange", lw=3.0, label="equaliser (pivot o)"),
               Line2D([], [], color=_SIDE_STEEL, lw=2.5, label="hanger, bracket, seat"),
               Line2D([], [], color=_SIDE_LOAD, lw=1.6, marker="^", label="tyre load, share of side")]  # fmt: skip
    fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=7.5, frameon=False)
    ax.set_aspect("equal")
    ax.set_xlim(x0 - 0.3, x1 + 0.3)
    ax.set_ylim(-1.12, z_chassis + 0.5)
    ax.set_xlabel("distance behind the king pin x [m]")
    ax.set_ylabel("height z [m]")
    ax.set_title(title, fontsize=10)
    ax.grid(True, color="0.92", lw=0.6)
    ax.set_axisbelow(True)
