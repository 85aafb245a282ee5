"""Page mechanics of the report: A4 pages, headers, wrapped text blocks, plain tables, page numbers, contents.

Every page is one portrait A4 :class:`matplotlib.figure.Figure` (no pyplot state): a section title at the top, the
charts in a body rectangle laid out by matplotlib's constrained layout, and captions below. Positions are page
fractions (0 at the foot, 1 at the top). Page numbers go on in :func:`number_pages` once the whole report is
assembled.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.lines import Line2D
from matplotlib.textpath import TextToPath

from pipeline.report.style import STYLE

__all__ = [
    "A4",
    "BODY",
    "LEFT",
    "RIGHT",
    "Block",
    "adopt_page",
    "contents",
    "freeze_layout",
    "new_page",
    "number_pages",
    "page_header",
    "paginate",
    "table_axes",
    "table_pages",
    "text_block",
    "text_page",
    "wrap_paragraphs",
]

#: A4 portrait [inch]
A4 = (8.27, 11.69)
#: the left and right margin of text and tables [page fraction]
LEFT, RIGHT = 0.08, 0.92
#: where the charts go on a page: (left, bottom, width, height) in page fractions
BODY = (0.06, 0.25, 0.88, 0.68)
#: line spacing of text blocks [font sizes]
LINE_SPACING = 1.45
#: line spacing of table cells [font sizes]
TABLE_SPACING = 1.3


# ---- pages ---------------------------------------------------------------------------------------------------------
def page_header(fig: Figure, title: str) -> None:
    """The section ``title`` at the top of a page, over a thin rule."""
    fig.text(LEFT, 0.962, title, fontsize=14, weight="bold", va="top")
    fig.add_artist(Line2D([LEFT, RIGHT], [0.94, 0.94], lw=0.6, color="0.5"))


def new_page(title: str, body: Sequence[float] = BODY) -> Figure:
    """An empty A4 page with its section ``title``; charts added to it are laid out inside ``body``."""
    fig = Figure(figsize=A4, layout=ConstrainedLayoutEngine(rect=tuple(body), h_pad=0.08, w_pad=0.08))
    page_header(fig, title)
    return fig


def adopt_page(fig: Figure, title: str, body: Sequence[float] = BODY) -> Figure:
    """Turn a figure made elsewhere (bogie.plotting, constrained layout) into an A4 page with ``title``."""
    fig.set_size_inches(*A4)
    fig.get_layout_engine().set(rect=tuple(body))
    page_header(fig, title)
    return fig


#: lowest page height a page's text may reach: above the footer's rule at 0.04 [page fraction]
TEXT_BOTTOM = 0.05
#: smallest type a text page shrinks to so that its text ends above the footer [pt]
SMALLEST_TEXT = 7.0


def first_fit(options: Sequence[Any], draw: Callable[[Any], tuple[Figure, float]]) -> Figure:
    """The page ``draw`` (option) makes with the first of ``options`` whose text ends above :data:`TEXT_BOTTOM`
    (``draw`` returns the figure and the height its text ended at); the last option's page if none does."""
    fig = None
    for option in options:
        fig, bottom = draw(option)
        if bottom >= TEXT_BOTTOM:
            break
    assert fig is not None, "first_fit needs at least one option"
    return fig


def text_page(title: str, paragraphs: Sequence[str], size: float = 8.8) -> Figure:
    """A page of text only (definitions, assumptions), in ``size`` point type or, if the text would run into the
    footer, the largest smaller size (in steps of 0.3 pt, down to :data:`SMALLEST_TEXT`) with which it ends above
    :data:`TEXT_BOTTOM`."""

    def draw(type_size: float) -> tuple[Figure, float]:
        fig = Figure(figsize=A4)
        page_header(fig, title)
        return fig, text_block(fig, 0.92, paragraphs, size=type_size)

    steps = int((size - SMALLEST_TEXT) / 0.3 + 1e-9)
    return first_fit([round(size - 0.3 * k, 2) for k in range(steps + 1)], draw)


# ---- text ----------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Block:
    """One wrapped paragraph of a text block: its lines and whether it is a subheading."""

    lines: tuple[str, ...]
    bold: bool


def line_height(size: float, spacing: float = LINE_SPACING) -> float:
    """Height of one line of ``size`` point text [page fraction]."""
    return size * spacing / 72.0 / A4[1]


def chars_per_line(size: float, x: float = LEFT) -> int:
    """About how many characters of ``size`` point text fit between ``x`` and the right margin (an average: DejaVu
    Sans runs about 0.53 em a character; digits are 0.64 em). :func:`wrap_paragraphs` measures instead."""
    return int((RIGHT - x) * A4[0] * 72.0 / (0.53 * size))


#: measures text by its glyphs (the font's advances and kerning, as the renderers set it)
_TEXT_PATH = TextToPath()


@functools.lru_cache(maxsize=65536)
def text_width_pt(text: str, size: float, bold: bool = False) -> float:
    """The width of ``text`` set in the report's font at ``size`` points, measured from the font's glyphs [pt]."""
    prop = FontProperties(family=STYLE["font.family"], size=size, weight="bold" if bold else "normal")
    return float(_TEXT_PATH.get_text_width_height_descent(text, prop, ismath=False)[0])


def _wrap(text: str, width_pt: float, size: float, bold: bool, indent: str) -> list[str]:
    """Greedy wrap of ``text`` at spaces (a no-break space joins) so that each line measures at most ``width_pt``."""
    lines: list[str] = []
    line = ""
    for word in text.split(" "):
        trial = word if not line else line + " " + word
        if line and text_width_pt(trial, size, bold) > width_pt:
            lines.append(line)
            line = indent + word
        else:
            line = trial
    return [*lines, line] if line or not lines else lines


def wrap_paragraphs(paragraphs: Sequence[str], size: float = 9.0, x: float = LEFT) -> list[Block]:
    """Wrap paragraphs to the width between ``x`` and the right margin, by the width the font gives each line.

    A paragraph starting with "## " is a bold subheading; "- " starts a bullet (its further lines indented); a
    number and its per cent sign are joined by a no-break space so a line never starts with "%".
    """
    width_pt = (RIGHT - x) * A4[0] * 72.0
    blocks = []
    for para in paragraphs:
        bold = para.startswith("## ")
        # runs of spaces, line breaks and tabs are one space (as textwrap made them); a no-break space is kept
        text = " ".join(w for w in para.removeprefix("## ").replace(" %", "\u00a0%").replace("\n", " ").split(" ") if w)
        indent = "  " if text.startswith("- ") else ""
        lines = _wrap(text, width_pt, size, bold, indent) if text.strip() else [""]
        blocks.append(Block(tuple(lines), bold))
    return blocks


def text_block(fig: Figure, y: float, paragraphs: Sequence[str], size: float = 9.0, x: float = LEFT) -> float:
    """Write wrapped paragraphs (:func:`wrap_paragraphs`) from height ``y`` down; returns the height below them."""
    line = line_height(size)
    for block in wrap_paragraphs(paragraphs, size, x):
        weight = "bold" if block.bold else None
        fig.text(x, y, "\n".join(block.lines), fontsize=size, va="top", linespacing=LINE_SPACING, weight=weight)
        y -= line * len(block.lines) + line * (0.25 if block.bold else 0.6)
    return y


# ---- tables --------------------------------------------------------------------------------------------------------
def row_height(row: Sequence[str], size: float) -> float:
    """Height of a table row of ``size`` point text: its tallest cell's lines plus padding [page fraction]."""
    return line_height(size, TABLE_SPACING) * (1.8 + max(str(c).count("\n") for c in row))


def table_axes(
    fig: Figure,
    top: float,
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    widths: Sequence[float],
    size: float = 7.5,
) -> float:
    """A plain table (header row shaded) hanging from page height ``top``; returns the height of its bottom edge.

    Cells may hold several lines ("\\n"); each row is as tall as its tallest cell (:func:`row_height`).
    """
    line = line_height(size, TABLE_SPACING)
    heights = [line * (1 + max(str(c).count("\n") for c in row)) + 0.8 * line for row in [header, *rows]]
    total = sum(heights)
    ax = fig.add_axes((LEFT, top - total, RIGHT - LEFT, total))
    ax.axis("off")
    ax.set_in_layout(False)
    table = ax.table(
        cellText=[list(r) for r in rows],
        colLabels=list(header),
        colWidths=list(widths),
        loc="upper center",
        cellLoc="left",
    )
    table.auto_set_font_size(False)
    table.set_fontsize(size)
    for (r, _), cell in table.get_celld().items():
        cell.set_linewidth(0.3)
        cell.set_height(heights[r] / total)
        if r == 0:
            cell.set_facecolor("0.9")
            cell.get_text().set_weight("bold")
    return top - total


def paginate(heights: Sequence[float], first: float, rest: float) -> list[list[int]]:
    """Split rows of ``heights`` into pages: ``first`` of room on the first page, ``rest`` on every other.

    Every page takes at least one row (a row taller than a page gets a page of its own); no rows gives one empty
    page. Returns the row indices of each page.
    """
    pages: list[list[int]] = []
    k = 0
    while True:
        room, chunk = first if not pages else rest, []
        while k < len(heights) and (not chunk or heights[k] <= room):
            room -= heights[k]
            chunk.append(k)
            k += 1
        pages.append(chunk)
        if k >= len(heights):
            return pages


def table_pages(
    title: str, header: Sequence[str], rows: Sequence[Sequence[str]], intro: Sequence[str], widths: Sequence[float]
) -> list[Figure]:
    """A table over as many pages as it needs, ``intro`` above it on the first (one page when there are no rows)."""
    size, bottom = 7.0, 0.07
    heights = [row_height(r, size) for r in rows]
    pages: list[Figure] = []
    # the room of the first page depends on its intro: lay it out first; the others have none
    fig = Figure(figsize=A4)
    page_header(fig, title)
    top = text_block(fig, 0.92, intro, size=8.8) - 0.005
    rest_top = 0.92 - 0.005
    chunks = paginate(heights, top - bottom - row_height(header, size), rest_top - bottom - row_height(header, size))
    for n, chunk in enumerate(chunks):
        if n:
            fig = Figure(figsize=A4)
            page_header(fig, f"{title} (continued, page {n + 1})")
            top = text_block(fig, 0.92, [], size=8.8) - 0.005
        if chunk:
            table_axes(fig, top, header, [rows[k] for k in chunk], widths, size)
        pages.append(fig)
    return pages


# ---- the whole document -------------------------------------------------------------------------------------------
#: digits of a page fraction an axes' position is rounded to when frozen (1e-6 of a page: under 0.001 pt)
FROZEN_DIGITS = 6


def freeze_layout(fig: Figure) -> None:
    """Lay the page out once and fix every axes (colour bars and those in subfigures included) where the layout put
    it, rounded to :data:`FROZEN_DIGITS` digits of the page, with the layout engine then switched off.

    matplotlib's constrained layout solves its constraints with kiwisolver, whose solution can differ in the last
    bits from one process to the next (measured: one design-guidance page came out three ways in four runs, an axes
    width of 105.9239164062 or ...4063 pt): the PDF's bytes, and so ``dvc.lock``, followed. Rounded positions are
    the same every run, and the PDF and the PNG pages, each drawn afterwards, share them.
    """
    if fig.get_layout_engine() is None:
        return
    fig.draw_without_rendering()
    boxes = [(ax, ax.get_position(original=False).bounds) for ax in fig.findobj(lambda a: isinstance(a, Axes))]
    fig.set_layout_engine("none")
    for ax, bounds in boxes:
        ax.set_position([round(v, FROZEN_DIGITS) for v in bounds])


def number_pages(pages: Sequence[Figure], footer: str) -> None:
    """Write ``page n of N`` and the ``footer`` text at the foot of every page."""
    for n, fig in enumerate(pages, start=1):
        fig.add_artist(Line2D([LEFT, RIGHT], [0.04, 0.04], lw=0.4, color="0.6"))
        fig.text(LEFT, 0.03, footer, fontsize=7, color="0.35", va="top")
        fig.text(RIGHT, 0.03, f"page {n} of {len(pages)}", fontsize=7.5, ha="right", va="top")


def contents(sections: Sequence[str], first: int = 1) -> list[tuple[str, int]]:
    """The contents: each section's name and the number of its first page, pages numbered from ``first``.

    A page with an empty section name continues the section before it; a section met again is not listed again.
    """
    out, seen = [], set()
    for n, section in enumerate(sections, start=first):
        if section and section not in seen:
            seen.add(section)
            out.append((section, n))
    return out
