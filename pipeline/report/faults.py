"""Layout faults of a report page, found from the renderer's bounding boxes (issue 45 Must 3): text outside the page
or its margins, page text over other page text or over a chart, a legend over a chart's data.

A page is a matplotlib ``Figure`` (:mod:`pipeline.report.layout`); it is drawn once with the Agg renderer and every
text's window extent compared. What counts:

- **outside**: any text (the page's own, a chart's title, axis labels, tick labels, legend) not within the paper,
  or a page text or a chart's title past the left or right margin (:data:`~pipeline.report.layout.LEFT`,
  :data:`~pipeline.report.layout.RIGHT`, with :data:`SLACK` of the page's width);
- **overlap**: two page texts whose boxes intersect by more than :data:`SLACK` of the page's height, or a page
  text over a chart's area (its axes with their labels);
- **charts' texts overlap**: a legend or title of one chart over another chart's (a legend wider than its chart);
- **legend over data**: a legend's box holding a plotted point of its chart (a line's vertices, a bar's top, a
  marker) within the chart's view, so that the legend hides data; or over its chart's title. A line is seen by its
  vertices: one drawn straight across the legend between two vertices outside it is not found.

- **a table cell's text wider or taller than its cell** (:func:`~pipeline.report.layout.table_axes`), cut by or
  running into the next.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import Collection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from pipeline.report.layout import LEFT, RIGHT

__all__ = ["SLACK", "layout_faults"]

#: how far a box may pass a margin or into another box before it is a fault [page fraction]: a convention, a few
#: points on A4 (glyphs' boxes include their side bearings)
SLACK = 0.004


def _texts(ax: Axes) -> list[Text]:
    legend = ax.get_legend()
    out = [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label]
    # the tick labels drawn: those of the ticks within the view (the others are kept, unplaced, and not drawn)
    out += [t.label1 for axis in (ax.xaxis, ax.yaxis) for t in axis._update_ticks() if t.label1.get_visible()]
    out += list(legend.get_texts()) if legend is not None else []
    return [t for t in out if t.get_visible() and t.get_text().strip()]


def _data_points(ax: Axes) -> np.ndarray:
    """The display coordinates of what a chart plots: lines' vertices, bars' outer corners, markers' offsets."""
    points = []
    for line in ax.get_lines():
        if isinstance(line, Line2D) and line.get_visible() and len(line.get_xydata()):
            points.append(ax.transData.transform(line.get_xydata()))
    for patch in ax.patches:
        if isinstance(patch, Rectangle) and patch.get_visible() and patch.get_height() != 0 and patch.get_width() != 0:
            x, y, w, h = patch.get_x(), patch.get_y(), patch.get_width(), patch.get_height()
            points.append(patch.get_data_transform().transform([(x + w / 2, y + h), (x + w, y + h / 2)]))
    for coll in ax.collections:
        if isinstance(coll, Collection) and coll.get_visible() and len(coll.get_offsets()):
            points.append(coll.get_offset_transform().transform(coll.get_offsets()))
    good = [p for p in points if len(p)]
    return np.vstack(good) if good else np.zeros((0, 2))


def _inside(box: Bbox, page: Bbox, slack: float) -> bool:
    return (
        box.x0 >= page.x0 - slack
        and box.x1 <= page.x1 + slack
        and box.y0 >= page.y0 - slack
        and (box.y1 <= page.y1 + slack)
    )


def _overlap(a: Bbox, b: Bbox, slack: float) -> bool:
    return min(a.x1, b.x1) - max(a.x0, b.x0) > slack and min(a.y1, b.y1) - max(a.y0, b.y0) > slack


def _short(text: str) -> str:
    line = " ".join(text.split())
    return line if len(line) <= 50 else line[:47] + "..."


def layout_faults(fig: Figure) -> list[str]:
    """What is wrong with page ``fig``'s layout, one line a fault (none: an empty list); see the module docstring."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    page = fig.bbox
    w, h = page.width, page.height
    margins = Bbox.from_extents(LEFT * w, 0.0, RIGHT * w, h)
    faults: list[str] = []
    page_texts = [(t, t.get_window_extent(renderer)) for t in fig.texts if t.get_visible() and t.get_text().strip()]
    charts = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    tables = [ax for ax in fig.axes if ax.get_visible() and not ax.axison]
    for t, box in page_texts:
        if not _inside(box, margins, SLACK * w):
            faults.append(f"page text outside the margins: {_short(t.get_text())!r}")
    for ax in charts:
        for t in _texts(ax):
            box = t.get_window_extent(renderer)
            if not _inside(box, page, 0.0):
                faults.append(f"chart text off the page: {_short(t.get_text())!r}")
            elif t is ax.title and not _inside(box, margins, SLACK * w):
                faults.append(f"chart title past the margins: {_short(t.get_text())!r}")
    for i, (a, box_a) in enumerate(page_texts):
        for b, box_b in page_texts[i + 1 :]:
            if _overlap(box_a, box_b, SLACK * h):
                faults.append(f"page texts overlap: {_short(a.get_text())!r} and {_short(b.get_text())!r}")
        for ax in charts:
            if _overlap(box_a, ax.get_tightbbox(renderer), SLACK * h):
                faults.append(f"page text over a chart: {_short(a.get_text())!r}")
    for ax in tables:
        faults += _cell_faults(ax, renderer, SLACK * w)
    for ax in charts:
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            box = legend.get_window_extent(renderer)
            points = _data_points(ax)
            area = ax.bbox  # only what is drawn: a point outside the chart's view is clipped away
            points = points[
                (points[:, 0] >= area.x0) & (points[:, 0] <= area.x1) & (points[:, 1] >= area.y0)
                & (points[:, 1] <= area.y1)
            ]  # fmt: skip
            if ax.title.get_text() and _overlap(box, ax.title.get_window_extent(renderer), 0.0):
                faults.append(f"legend over its chart's title: {_short(ax.get_title())!r}")
            if len(points) and np.any(
                (points[:, 0] > box.x0) & (points[:, 0] < box.x1) & (points[:, 1] > box.y0) & (points[:, 1] < box.y1)
            ):
                faults.append(f"legend over data: chart {_short(ax.get_title())!r}")
    return faults + _between_charts(charts, renderer)


def _between_charts(charts: list[Axes], renderer) -> list[str]:
    """Two charts' legends or titles over each other (a legend wider than its chart, centred over it, runs into its
    neighbour's)."""
    boxes = []
    for ax in charts:
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            boxes.append((ax, "legend", legend.get_window_extent(renderer)))
        if ax.title.get_text():
            boxes.append((ax, "title", ax.title.get_window_extent(renderer)))
    faults = []
    for i, (ax_a, kind_a, box_a) in enumerate(boxes):
        for ax_b, kind_b, box_b in boxes[i + 1 :]:
            if ax_a is not ax_b and _overlap(box_a, box_b, 0.0):
                faults.append(
                    f"charts' texts overlap: the {kind_a} of {_short(ax_a.get_title())!r} and the {kind_b} of "
                    f"{_short(ax_b.get_title())!r}"
                )
    return faults


def _cell_faults(ax: Axes, renderer, slack: float) -> list[str]:
    """Cells of ``ax``'s tables whose text is wider or taller than the cell (cut by, or running into, the next)."""
    out = []
    for table in ax.tables:
        for cell in table.get_celld().values():
            text = cell.get_text()
            if not text.get_visible() or not text.get_text().strip():
                continue
            tbox, cbox = text.get_window_extent(renderer), cell.get_window_extent(renderer)
            # the text keeps at least half the cell's left padding on its right: other renderers (the PDF's unhinted
            # glyphs) draw it a little wider than Agg measures it
            if tbox.x1 > cbox.x1 - 0.5 * max(tbox.x0 - cbox.x0, 0.0) or tbox.x0 < cbox.x0 - slack:
                out.append(f"table cell overflows: {_short(text.get_text())!r}")
    return out
