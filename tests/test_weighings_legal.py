"""Legal loads of axle groups by position and spacing (bogie.weighings.legal, issue 44 Must 4's table): every row
of Directive 96/53/EC Annex I's point 3 as SR 1999/258 Schedule 3 tabulates it, its boundaries, and the refusals."""

import math

import numpy as np
import pytest

from bogie.weighings.legal import eu_axle_limit_kg, eu_group_limit_kg


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
