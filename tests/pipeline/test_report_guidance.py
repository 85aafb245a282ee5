"""The design-guidance pages' words (pipeline.report.pages.guidance): the design stage's sentences placed on their
pages by kind, not by their text, and the prose of the templates."""

import numpy as np
import pandas as pd
import pytest

from bogie.fleet.design.analysis import guidance_sentences
from pipeline.report import text
from pipeline.report.pages import guidance as G
from pipeline.report.style import QUANTITY

FACTORS = {"bush_stiffness": 55.0, "equaliser_arm": 0.2, "contact_roll_radius": 0.06, "friction_coefficient": 0.26,
           "spring_friction_band": 2000.0}  # fmt: skip


def _row(group: str, kind: str, suspension: str, share: float, up: float | None) -> dict:
    return {"group": group, "kind": kind, "suspension": suspension, "design": f"{group}-{kind}", **FACTORS,
            "share_within_5pct": share, "share_within_5pct_low": share - 0.1, "share_within_5pct_high": share,
            "share_within_5pct_level": share, "tilt_tolerance_nose_up_deg": up,
            "tilt_tolerance_nose_down_deg": up}  # fmt: skip


def _metrics(table: pd.DataFrame) -> dict:
    """The keys of metrics/design.json that sentence_kinds reads, and the stage's own sentences."""
    steel = table[table["suspension"] == "steel"].to_dict("records")
    return {
        "designs": [{"group": r["group"]} for r in steel],
        "design_summaries": [{"kind": r["kind"]} for r in steel],
        "air": {r["group"]: {} for r in table[table["suspension"] == "air"].to_dict("records")},
        "guidance": guidance_sentences(table, np.array([-2.0, 0.0, 2.0]), 0.95),
    }


def test_the_kinds_follow_the_design_stage_whichever_sentences_it_writes():
    table = pd.DataFrame([
        _row("tandem", "typical", "steel", 0.65, 0.7), _row("tandem", "grid", "steel", 1.0, 2.0),
        _row("tandem", "air", "air", 1.0, 2.0), _row("triaxle", "grid", "steel", 0.85, None),
    ])  # fmt: skip
    m = _metrics(table)
    kinds = G.sentence_kinds(m)
    assert kinds == [("tandem", "tolerance"), ("tandem", "typical"), ("tandem", "fleet"), ("tandem", "air"),
                     ("triaxle", "tolerance"), ("triaxle", "fleet")]  # fmt: skip
    # what each kind says (the page no longer searches the text; the test checks the order it relies on)
    starts = {"tolerance": ("With ", "No "), "typical": ("Today's typical",), "fleet": ("Across the fleet's own",),
              "air": ("The air-sprung",)}  # fmt: skip
    assert all(s.startswith(starts[k]) for (_, k), s in zip(kinds, m["guidance"], strict=True))
    assert G.sentences(m, "experiment") == [m["guidance"][i] for i in (2, 3, 5)]
    assert G.sentences(m, "tolerance") == [m["guidance"][i] for i in (0, 1, 4)]


def test_the_designers_own_bogie_has_its_sentence_on_the_tolerance_page():
    # issue 45 Must 4: a group whose base bogie is a bogie file has an "own" design, said after the typical one
    table = pd.DataFrame([
        _row("triaxle", "typical", "steel", 0.65, 0.7), _row("triaxle", "own", "steel", 0.8, 1.2),
        _row("triaxle", "grid", "steel", 0.9, 2.0), _row("triaxle", "air", "air", 1.0, 2.0),
    ])  # fmt: skip
    m = _metrics(table)
    assert G.sentence_kinds(m) == [("triaxle", "tolerance"), ("triaxle", "typical"), ("triaxle", "own"),
                                   ("triaxle", "fleet"), ("triaxle", "air")]  # fmt: skip
    assert m["guidance"][2].startswith("Your tri-axle, with a 55 N m/rad bush")
    assert G.sentences(m, "tolerance") == m["guidance"][:3]
    assert G.design_cells({"suspension": "steel", "kind": "own", **FACTORS})[0] == "your file"
    # the tolerance page's table: typical, then the file's own design, then the widest others, then the air group
    rows = G.tolerance_rows(table.assign(share_within_5pct_at_tolerance=0.95))
    assert [r[1] for r in rows] == ["typical", "your file", "grid", "air-sprung"]


def test_sentences_that_do_not_add_up_are_refused():
    m = _metrics(pd.DataFrame([_row("tandem", "typical", "steel", 0.65, 0.7)]))
    assert len(G.sentence_kinds(m)) == 3
    with pytest.raises(ValueError, match="4 guidance sentences, but its designs and air references give 3"):
        G.sentence_kinds({**m, "guidance": [*m["guidance"], "one more"]})


def test_one_label_per_quantity_in_the_guidance_tables_and_titles():
    assert G.DESIGN_HEADER[3] == "roll radius\n[mm]"
    assert G._level("contact_roll_radius", 0.04) == "contact roll radius 40 mm"
    assert G._level("contact_roll_radius", 0.04, short=True) == "roll radius 40 mm"
    assert G.design_cells({"suspension": "steel", "kind": "grid", **FACTORS}) == ["grid", "55", "200", "60", "0.26",
                                                                                   "2.0"]  # fmt: skip
    assert QUANTITY["contact_roll_radius"].label == "contact roll radius [mm]"


def test_the_templates_give_the_pages_prose():
    m = {"n_conditions": 20, "confidence_level": 0.95, "tilt_grid_deg": [-2.0, -0.5, 0.0, 2.0], "runs": 100,
         "failed": 1, "target_share": 0.95}  # fmt: skip
    intro = text.render("guidance_experiment.j2", m=m)
    assert (
        len(intro) == 1
        and "(the shares, with 95 % Wilson intervals) and on a grid of tilts (-2, -0.5, 0, 2 degree)" in intro[0]
    )
    assert "(100 runs, 1 failed)" in intro[0]
    check = {"pairs": 40, "largest_max_deviation_difference_pct": 3.3211, "within_5pct_disagreements": 2}
    assert text.render("guidance_check.j2", check=check) == [
        "Interpolation check: at the 40 conditions' own tilts the interpolated loads differ from the runs by at most "
        "3.32 points of max_deviation, and disagree on within 5 % in 2 cases."
    ]
    assert text.render("guidance_check.j2", check={**check, "pairs": 0}) == []
    tol = text.render("guidance_tolerance.j2", m=m, lo=-2.0, hi=2.0)
    assert "at which at least 95 % of the bogies, over the 20 conditions'" in tol[0] and tol[0].endswith(
        "at least that."
    )
    assert text.render("guidance_skipped.j2", reason="no design: section")[0] == "No design study: no design: section."
