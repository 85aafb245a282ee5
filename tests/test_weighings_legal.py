"""Legal loads of axle groups by position and spacing (bogie.weighings.legal, issue 44 Must 4's table): every row
of Directive 96/53/EC Annex I's point 3 as SR 1999/258 Schedule 3 tabulates it, its boundaries, and the refusals."""

import math

import numpy as np
import pandas as pd
import pytest

from bogie.weighings.formats import FORMATS
from bogie.weighings.legal import eu_axle_limit_kg, eu_group_limit_kg, group_limits, spacing_step_m


def test_a_trailer_tandem_by_its_spacing_with_each_boundary_in_the_upper_band():
    d = [0.9, 1.0, 1.2, 1.3, 1.5, 1.8, 2.1]
    # Table VI items 3-5 (11, 16, 18 t for d < 1, 1 <= d < 1.3, 1.3 <= d < 1.8) and Table V item 5 (20 t)
    assert eu_group_limit_kg("tandem", "trailer", d).tolist() == [11e3, 16e3, 16e3, 18e3, 18e3, 20e3, 20e3]
    # a boundary rounded in its last bits stays on it; a millimetre below it does not
    assert eu_group_limit_kg("tandem", "trailer", [1.3 * (1 - 1e-12), 1.299]).tolist() == [18e3, 16e3]


def test_a_motor_vehicles_tandem_and_the_drive_axle():
    d = [0.95, 1.1, 1.35, 1.9]
    # Table VI items 1-2 (11.5, 16 t), Table V item 4 (18 t: the 19 t of item 3 needs a suspension a WIM record does
    # not show)
    assert eu_group_limit_kg("tandem", "drive", d).tolist() == [11.5e3, 16e3, 18e3, 18e3]
    assert eu_group_limit_kg("tandem", ["steer", "trailer"], [1.35, 1.35]).tolist() == [18e3, 18e3]
    assert eu_group_limit_kg("tandem", ["drive", "trailer"], [1.9, 1.9]).tolist() == [18e3, 20e3]
    assert eu_axle_limit_kg(["steer", "drive", "trailer"]).tolist() == [10e3, 11.5e3, 10e3]


def test_a_triaxle_by_its_shortest_spacing():
    # Table VI item 6: 21 t for 1.3 m or less (a boundary included), Table V item 6: 24 t
    assert eu_group_limit_kg("triaxle", "trailer", [1.25, 1.3, 1.31, 1.4, 1.6]).tolist() == [
        21e3,
        21e3,
        24e3,
        24e3,
        24e3,
    ]


def test_no_spacing_no_limit_and_bad_arguments_refused_by_name():
    out = eu_group_limit_kg("tandem", "trailer", [float("nan"), 0.0, 1.5])
    assert math.isnan(out[0]) and math.isnan(out[1]) and out[2] == 18e3
    with pytest.raises(ValueError, match="group = 'quad': must be tandem or triaxle"):
        eu_group_limit_kg("quad", "trailer", [1.4])
    with pytest.raises(ValueError, match="position = 'rear': must be one of steer, drive, trailer"):
        eu_group_limit_kg("tandem", np.array(["trailer", "rear"], dtype=object), [1.4, 1.4])
    with pytest.raises(ValueError, match="position = 'rear'"):
        eu_axle_limit_kg("rear")


def test_each_rows_limits_from_its_position_and_spacing_read_in_the_vehicles_favour():
    groups = pd.DataFrame({
        "group": ["tandem", "tandem", "triaxle", "triaxle", "single", "tandem"],
        "position": ["trailer", "drive", "trailer", "trailer", "steer", "steer"],
        "spacing_1": [1.31, 1.0, 1.3, 1.4, np.nan, 1.2],
        "spacing_2": [np.nan, np.nan, 1.35, 1.3, np.nan, np.nan],
    })  # fmt: skip
    group_kg, axle_kg = group_limits(groups)
    # as read: 18 t (1.3-1.8), a motor tandem's 16 t (1.0-1.3), a tri-axle's 21 t twice (its shortest spacing 1.3),
    # no limit for a single axle, a steer tandem is a motor vehicle's: 16 t
    np.testing.assert_array_equal(group_kg, [18_000.0, 16_000.0, 21_000.0, 21_000.0, math.nan, 16_000.0])
    np.testing.assert_array_equal(axle_kg, [10_000.0, 11_500.0, 10_000.0, 10_000.0, 10_000.0, 10_000.0])
    # read at 0.1 m, 1.3 m may be up to 1.35 m: the tri-axles are given 24 t; a tandem read 1.2 m stays 16 t (1.25)
    group_kg, _ = group_limits(groups, spacing_step_m=0.1)
    np.testing.assert_array_equal(group_kg, [18_000.0, 16_000.0, 24_000.0, 24_000.0, math.nan, 16_000.0])
    # stated single limits: a size not named has none
    group_kg, axle_kg = group_limits(groups, {"tandem": 19_000.0}, 9_000.0)
    np.testing.assert_array_equal(group_kg, [19_000.0, 19_000.0, math.nan, math.nan, math.nan, 19_000.0])
    assert (axle_kg == 9_000.0).all()
    with pytest.raises(ValueError, match="groups has no position, spacing_1, spacing_2 column.*give legal_group"):
        group_limits(groups[["group"]])
    with pytest.raises(ValueError, match="groups has no position column.*give legal_axle"):
        group_limits(groups[["group"]], {"tandem": 19_000.0})


def test_the_step_each_format_reads_spacings_at():
    assert {fmt: spacing_step_m(fmt) for fmt in FORMATS} == pytest.approx({
        "csv": 0.0, "mon": 0.001, "castor": 0.1, "bedit": 0.1, "ditis": 0.1, "tmg2001": 0.1, "tmg2013": 0.03048,
    })  # fmt: skip
    with pytest.raises(ValueError, match="format 'wim' unknown"):
        spacing_step_m("wim")
