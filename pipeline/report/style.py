"""The report's look and its words for the pipeline's names: the matplotlib style, labels and colours."""

from __future__ import annotations

import numpy as np

__all__ = [
    "AXLE_COLOR",
    "FACTOR_LABEL",
    "GROUP_COLOR",
    "GROUP_LABEL",
    "MEASURE_LABEL",
    "PROTOCOL_LABEL",
    "PROTOCOL_LINE",
    "SOURCE_COLOR",
    "SOURCE_LABEL",
    "STYLE",
    "axle_name",
    "factor_label",
    "load_share_axes",
]

#: matplotlib rc settings of every page: build the pages inside ``matplotlib.rc_context(STYLE)``
STYLE = {
    "font.family": "DejaVu Sans",
    "font.size": 9.0,
    "axes.titlesize": 9.5,
    "axes.labelsize": 9.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 7.5,
    "legend.title_fontsize": 7.5,
    "axes.grid": True,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.5,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "pdf.fonttype": 42,
    "image.cmap": "RdYlGn",
}
GROUP_LABEL = {"tandem": "tandem", "triaxle": "tri-axle"}
GROUP_COLOR = {"tandem": "C0", "triaxle": "C1"}
PROTOCOL_LABEL = {"static": "static weighbridge", "wim": "weigh-in-motion"}
PROTOCOL_LINE = {"static": "-", "wim": "--"}
AXLE_COLOR = {"front": "C2", "middle": "C4", "rear": "C3"}
#: the sides of the observed page: an observed survey, the simulated fleet's two protocols
SOURCE_LABEL = {"observed": "observed", "static": "simulated static", "wim": "simulated WIM"}
SOURCE_COLOR = {"observed": "0.15", "static": "C0", "wim": "C1"}
FACTOR_LABEL = {
    "bush_stiffness": "bush stiffness",
    "bush_damping": "bush damping",
    "contact_roll_radius": "contact movement",
    "friction_coefficient": "spring-end friction",
    "spring_friction_band": "spring hysteresis",
    "chassis_tilt": "chassis tilt",
    "tyre_wear": "tyre wear",
    "baseline": "none removed",
    "all": "all five removed",
}
MEASURE_LABEL = {"max_deviation": "max. deviation", "p1": "P1", "road_wear_factor": "road-wear factor"}


def factor_label(name: str) -> str:
    """The report's name of a factor or ablation variant (the name itself when it has none)."""
    return FACTOR_LABEL.get(name, name)


def axle_name(i: int, n_axles: int) -> str:
    """front, middle or rear for axle position ``i`` (0 = front) of an ``n_axles`` group."""
    return "front" if i == 0 else "rear" if i == n_axles - 1 else "middle"


def load_share_axes(ax, n_axles: int) -> None:
    """The frame of a load-share chart per axle position: the band within 10 % of an equal share, the equal share,
    the axles named front to rear, the labels."""
    ax.axhspan(0.9, 1.1, color="0.93", lw=0, zorder=0)
    ax.axhline(1.0, color="0.4", lw=0.6, zorder=0)
    ax.set_xticks(np.arange(n_axles), [axle_name(i, n_axles) for i in range(n_axles)])
    ax.set_xlim(-0.5, n_axles - 0.5)
    ax.set_xlabel("axle")
    ax.set_ylabel("load share (1 = equal share) [-]")
