"""The report's look and its words for the pipeline's names: the matplotlib style, labels and colours."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from bogie.fleet.constants import GROUP_AXLES

__all__ = [
    "AXLE_COLOR",
    "FACTOR_LABEL",
    "GROUPS",
    "GROUP_COLOR",
    "GROUP_LABEL",
    "MEASURE_LABEL",
    "PROTOCOL_LABEL",
    "PROTOCOL_LINE",
    "QUANTITY",
    "Quantity",
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
    # the PNG pages set text at the font's own advances, as the PDF does, so that a line measured to fit the margins
    # (pipeline.report.layout.wrap_paragraphs) fits in both: hinting widens small type by up to 6 %
    "text.hinting": "none",
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
#: the axle groups in the report's order (the order of bogie.fleet.constants.GROUP_AXLES)
GROUPS: tuple[str, ...] = tuple(GROUP_AXLES)
GROUP_LABEL = dict(zip(GROUPS, ("tandem", "tri-axle"), strict=True))
GROUP_COLOR = dict(zip(GROUPS, ("C0", "C1"), strict=True))
PROTOCOL_LABEL = {"static": "static weighbridge", "wim": "weigh-in-motion"}
PROTOCOL_LINE = {"static": "-", "wim": "--"}
AXLE_COLOR = {"front": "C2", "middle": "C4", "rear": "C3"}
#: the sides of the observed page: an observed survey, the simulated fleet's two protocols
SOURCE_LABEL = {"observed": "observed", "static": "simulated static", "wim": "simulated WIM"}
SOURCE_COLOR = {"observed": "0.15", "static": "C0", "wim": "C1"}


class Quantity(NamedTuple):
    """The report's one name of a sampled or designed quantity, its unit and how a value is written.

    ``name``: in prose, table rows and axis labels; ``short``: in a table header or a panel title, where the name
    does not fit; ``scale``: SI value -> value in ``unit``; ``fmt``: a value in ``unit`` as text.
    """

    name: str
    unit: str
    scale: float = 1.0
    fmt: str = "{:g}"
    short: str = ""

    @property
    def label(self) -> str:
        """Axis label: ``contact roll radius [mm]``."""
        return f"{self.name} [{self.unit}]"

    def value(self, si: float) -> str:
        """A value given in SI, in ``unit`` and without it: ``value(0.04)`` of a radius in mm is "40"; a value the
        design has not one of (NaN: a bogie file's arms of several lengths) is "own"."""
        if si != si:
            return "own"
        return self.fmt.format(si * self.scale)


#: every quantity the report names, by its name in bogie.params / the samples (one label per quantity: the same
#: words in the Sobol' table, the ablation, Appendix A, the fleet correlations and the design guidance).
#: contact_roll_radius is named as in bogie.params: the radius of the cylindrical spring-end/pad contact, whose
#: product with the relative rotation is what the TRRL study calls the movement of the contact point.
QUANTITY: dict[str, Quantity] = {
    "bush_stiffness": Quantity("bush stiffness", "N m/rad", 1.0, "{:.0f}", "bush"),
    "bush_damping": Quantity("bush damping", "N m s/rad", 1.0, "{:.0f}", "damping"),
    "contact_roll_radius": Quantity("contact roll radius", "mm", 1e3, "{:.0f}", "roll radius"),
    "equaliser_arm": Quantity("equaliser arm", "mm", 1e3, "{:.0f}", "arm"),
    "friction_coefficient": Quantity("spring-end friction coefficient", "-", 1.0, "{:.2f}", "friction"),
    "spring_friction_band": Quantity("leaf-spring friction band", "kN", 1e-3, "{:.1f}", "band"),
    "spring_friction_decay": Quantity("leaf-spring friction decay", "mm", 1e3, "{:.1f}", "decay"),
    "tyre_wear": Quantity("tyre wear", "mm", 1e3, "{:.1f}", "wear"),
    "chassis_tilt": Quantity("chassis tilt", "degree", float(np.degrees(1.0)), "{:.2f}", "tilt"),
    "payload_fraction": Quantity("payload", "-", 1.0, "{:.2f}", "payload"),
}
#: the names of the sensitivity's factors and the ablation's variants: a quantity by its one name
FACTOR_LABEL = {
    **{key: q.name for key, q in QUANTITY.items()},
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
