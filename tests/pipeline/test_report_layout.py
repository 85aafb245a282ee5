"""The report's page mechanics (pipeline.report.layout): wrapping, text blocks, tables, pagination, numbering."""

import matplotlib
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pipeline.report import layout
from pipeline.report.style import STYLE

LONG = (
    "The heaviest axle carries on average 312 kg (4.57 % of the mean axle load) more than the lightest on tandem "
    "groups and 455 kg (5.12 % of the mean axle load) more than the lightest on tri-axle groups, "
) * 3


def drawn_boxes(fig):
    """The window extent of every text drawn on ``fig``, in pixels, after a draw."""
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    return [t.get_window_extent(renderer) for t in fig.texts], fig.bbox


@pytest.mark.parametrize("size", [7.5, 8.2, 9.0])
def test_wrapped_lines_fit_the_measure_and_keep_numbers_with_their_per_cent(size):
    measure = (layout.RIGHT - layout.LEFT) * layout.A4[0] * 72.0  # [pt]
    blocks = layout.wrap_paragraphs([LONG, "## A heading", "- " + LONG], size)
    assert [b.bold for b in blocks] == [False, True, False]
    assert blocks[1].lines == ("A heading",)
    for block in blocks:
        widths = [layout.text_width_pt(line, size, block.bold) for line in block.lines]
        assert max(widths) <= measure
        # greedy: each line but the last would be too wide with the next line's first word
        for line, after in zip(block.lines, block.lines[1:]):
            assert layout.text_width_pt(line + " " + after.split()[0], size, block.bold) > measure
        assert not any(line.startswith("%") for line in block.lines)
    assert len(blocks[0].lines) > 1
    assert "4.57\u00a0%" in " ".join(blocks[0].lines)
    # a bullet's further lines are indented under its text
    assert blocks[2].lines[0].startswith("- ") and all(line.startswith("  ") for line in blocks[2].lines[1:])


def test_smaller_type_fits_more_characters():
    assert layout.chars_per_line(7.5) > layout.chars_per_line(9.0) > layout.chars_per_line(9.0, x=0.3)


def test_text_block_stays_inside_the_page_margins_and_moves_down():
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=layout.A4)
        bottom = layout.text_block(fig, 0.9, [LONG, "## Heading", LONG], size=9.0)
        boxes, page = drawn_boxes(fig)
    assert len(boxes) == 3
    left, right = layout.LEFT * page.width, layout.RIGHT * page.width
    for box in boxes:
        assert box.x0 >= left - 1 and box.x1 <= right + 1, (box.x0, box.x1, left, right)
    tops = [box.y1 for box in boxes]
    assert tops == sorted(tops, reverse=True)
    # the returned height is below the last paragraph's last line
    assert bottom * page.height <= boxes[-1].y0 + 1
    assert 0.0 < bottom < 0.9


def test_number_pages_writes_page_n_of_n_and_the_footer():
    pages = [Figure(figsize=layout.A4) for _ in range(3)]
    layout.number_pages(pages, "footer text")
    for n, fig in enumerate(pages, start=1):
        texts = [t.get_text() for t in fig.texts]
        assert texts == ["footer text", f"page {n} of 3"]


def test_contents_lists_each_section_at_its_first_page():
    sections = ["Summary", "Survey", "Survey", "Appendix C", "", ""]
    assert layout.contents(sections, first=2) == [("Summary", 2), ("Survey", 3), ("Appendix C", 5)]
    assert layout.contents([]) == []


def test_paginate_fills_pages_and_gives_every_page_a_row():
    assert layout.paginate([0.2, 0.2, 0.2, 0.2], first=0.45, rest=0.65) == [[0, 1], [2, 3]]
    assert layout.paginate([0.2] * 5, first=0.1, rest=0.5) == [[0], [1, 2], [3, 4]]
    # a row taller than a page gets a page of its own rather than none
    assert layout.paginate([0.3, 2.0, 0.1], first=1.0, rest=1.0) == [[0], [1], [2]]
    assert layout.paginate([], first=1.0, rest=1.0) == [[]]


def test_table_pages_continue_a_long_table_with_numbered_titles():
    rows = [[str(k), "a\nb"] for k in range(120)]
    with matplotlib.rc_context(STYLE):
        pages = layout.table_pages("Appendix C: failed runs", ["n", "text"], rows, ["intro"], [0.5, 0.5])
    assert len(pages) > 1
    titles = [pages[k].texts[0].get_text() for k in range(len(pages))]
    assert titles[0] == "Appendix C: failed runs"
    assert titles[1:] == [f"Appendix C: failed runs (continued, page {k})" for k in range(2, len(pages) + 1)]
    cells = [
        cell.get_text().get_text()
        for fig in pages
        for ax in fig.get_axes()
        for (r, c), cell in sorted(ax.tables[0].get_celld().items())
        if r > 0 and c == 0
    ]
    assert cells == [str(k) for k in range(120)]  # every row once, in order
    for fig in pages:
        [ax] = fig.get_axes()
        assert ax.get_position().y0 >= 0.07 - 1e-9  # above the footer


def test_table_pages_without_rows_is_one_page_of_intro():
    pages = layout.table_pages("T", ["a"], [], ["No run failed."], [1.0])
    assert len(pages) == 1 and not pages[0].get_axes()
    assert [t.get_text() for t in pages[0].texts] == ["T", "No run failed."]


def test_table_axes_returns_its_bottom_and_sizes_rows_by_their_lines():
    fig = Figure(figsize=layout.A4)
    bottom = layout.table_axes(fig, 0.8, ["h"], [["one"], ["two\nlines"]], [1.0], size=7.5)
    line = 7.5 * 1.3 / 72.0 / layout.A4[1]
    assert bottom == pytest.approx(0.8 - (1.8 * line + 1.8 * line + 2.8 * line))
    assert bottom == pytest.approx(0.8 - sum(layout.row_height(r, 7.5) for r in (["h"], ["one"], ["two\nlines"])))


def test_a_frozen_page_keeps_its_layout_rounded_and_draws_without_the_engine():
    """freeze_layout: every axes (a subfigure's and a colour bar's included) stays where constrained layout put it,
    to 1e-6 of the page, on a 10^-6 grid, and later draws no longer run the layout (whose solver may differ in the
    last bits between processes)."""
    import io

    import numpy as np
    from matplotlib.axes import Axes

    def page():
        fig = layout.new_page("Frozen")
        top, bottom = fig.subfigures(2, 1)
        maps = top.subplots(1, 2)
        mesh = maps[0].pcolormesh(np.arange(12.0).reshape(3, 4))
        top.colorbar(mesh, ax=list(maps), label="a colour bar")
        bottom.add_subplot().plot([0, 1], [0, 1])
        return fig, fig.findobj(lambda a: isinstance(a, Axes))

    # the layout of a page drawn once, as the report's pages are when frozen
    twin, twin_axes = page()
    twin.draw_without_rendering()
    laid_out = [ax.get_position(original=False).bounds for ax in twin_axes]
    fig, axes = page()
    assert len(axes) == 4
    layout.freeze_layout(fig)
    assert not isinstance(fig.get_layout_engine(), matplotlib.layout_engine.ConstrainedLayoutEngine)
    frozen = [ax.get_position(original=False).bounds for ax in axes]
    assert np.allclose(frozen, laid_out, rtol=0.0, atol=5.1e-7)
    scaled = np.asarray(frozen) * 10**layout.FROZEN_DIGITS
    assert np.allclose(scaled, np.round(scaled), rtol=0.0, atol=1e-6)
    first, second = io.BytesIO(), io.BytesIO()
    fig.savefig(first, format="pdf", metadata={"CreationDate": None})
    fig.savefig(second, format="pdf", metadata={"CreationDate": None})
    assert first.getvalue() == second.getvalue()
    # a colour bar's axes keeps its aspect inside the frozen box (a draw's apply_aspect), to well under 1e-6
    assert np.allclose([ax.get_position(original=False).bounds for ax in axes], frozen, rtol=0.0, atol=1e-6)


def test_the_layout_faults_are_found_where_they_are_and_not_where_they_are_not():
    from pipeline.report.faults import layout_faults

    def page():
        fig = Figure(figsize=layout.A4)
        fig.text(layout.LEFT, 0.95, "A title inside the margins")
        return fig

    with matplotlib.rc_context(STYLE):
        clean = page()
        ax = clean.add_axes((0.1, 0.5, 0.8, 0.3))
        ax.plot([0, 1], [0, 1], label="a line")
        ax.legend(loc="upper left")  # the line runs from lower left to upper right: the upper left is free
        assert layout_faults(clean) == []
        wide = page()
        wide.text(layout.LEFT, 0.5, "x" * 400)
        assert any("outside the margins" in f for f in layout_faults(wide))
        over = page()
        over.text(layout.LEFT, 0.95, "A second text on the first")
        assert any("page texts overlap" in f for f in layout_faults(over))
        hidden = page()
        ax = hidden.add_axes((0.1, 0.5, 0.8, 0.3))
        ax.plot([i / 40 for i in range(41)], [1.0] * 41, label="a line along the top")
        ax.set_ylim(0.0, 1.05)
        ax.legend(loc="upper left")
        assert any("legend over data" in f for f in layout_faults(hidden))
        on_chart = page()
        on_chart.add_axes((0.1, 0.5, 0.8, 0.3)).plot([0, 1], [0, 1])
        on_chart.text(0.3, 0.6, "words over the chart")
        assert any("page text over a chart" in f for f in layout_faults(on_chart))
        side = page()  # two charts side by side, each with a legend above it, centred and wider than its chart
        for x in (0.1, 0.52):
            ax = side.add_axes((x, 0.5, 0.36, 0.3))
            for k in range(4):
                ax.plot([0, 1], [k, k], label=f"a long series label {k}")
            ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=4, frameon=False)
        assert any("charts' texts overlap: the legend of" in f for f in layout_faults(side))
        table = page()
        layout.table_axes(table, 0.8, ["a", "b"], [["a cell far too long for its narrow column", "b"]], [0.1, 0.1])
        assert any("table cell overflows" in f for f in layout_faults(table))


@pytest.mark.parametrize("size", [7.0, 8.2, 9.5])
def test_a_measured_line_is_the_width_the_page_draws_it(size):
    # the report's style sets text unhinted, as the PDF does: the width wrap_paragraphs measures is the drawn one
    line = "Weigh-in-motion: 56.7\u00a0% of tandem and 87.4\u00a0% of tri-axle groups are outside 5\u00a0% (1,086 kg)"
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=layout.A4)
        fig.text(layout.LEFT, 0.5, line, fontsize=size)
        (box,), _ = drawn_boxes(fig)
    assert box.width * 72.0 / fig.dpi == pytest.approx(layout.text_width_pt(line, size), rel=0.01)
