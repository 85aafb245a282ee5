"""The weight resolution of a file: detected from the loads' residues, tolerant of a one-unit offset, or set.

Issue 41 Must 2. Every expected figure below is worked by hand from the rule in bogie/weighings/resolution.py: a
step s is supported when at least 99 % of the N loads are on a multiple of it (chance p = u/s for loads of the
format's unit u) or, for s >= 10 u, within one unit of one (p = 3u/s), and the Chernoff bound exp(-N KL) <= 1e-6,
i.e. N KL >= 13.8155 nats.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bogie.weighings.readers import read_weighings
from bogie.weighings.resolution import ResidueCounts, check_resolution_kg, detect_resolution
from bogie.weighings.survey import observed_survey
from bogie.weighings.writers import write_weighings

DATA = Path(__file__).parent / "data" / "weighings"


def mon_file(path: Path, loads: list[list[int]]) -> Path:
    """A MON file of one vehicle per row of ``loads`` [kg], a minute apart, 1.35 m between axles."""
    width = max(len(r) for r in loads)
    rows = []
    for k, row in enumerate(loads):
        rows.append({
            "timestamp": pd.Timestamp("2026-03-14 07:00") + pd.Timedelta(minutes=k), "speed": 80 / 3.6, "lane": 1,
            "direction": 1, "n_axles": len(row), "gross_weight": float(sum(row)), "length": 16.0,
            **{f"axle_load_{i + 1}": float(w) for i, w in enumerate(row)},
            **{f"spacing_{i + 1}": (3.5 if i == 0 else 1.35) for i in range(len(row) - 1)},
        })  # fmt: skip
    frame = pd.DataFrame(rows)
    for i in range(width):
        frame[f"axle_load_{i + 1}"] = frame.get(f"axle_load_{i + 1}", np.nan)
    write_weighings(frame, path, "mon")
    return path


def test_loads_ending_in_00_or_99_are_a_100_kg_file(tmp_path):
    # 40 five-axle vehicles: 120 loads end in 00 and 80 in 99 (a conversion that lands one kilogram low)
    loads = [[7000 - (i + k) % 5 * 100 - ((i + k) % 5 < 2) for i in range(5)] for k in range(40)]
    flat = [w for row in loads for w in row]
    assert sum(w % 100 == 0 for w in flat) == 120 and sum(w % 100 == 99 for w in flat) == 80
    result = read_weighings(mon_file(tmp_path / "site.mon", loads), "mon")
    r = result.resolution
    assert (r.step_kg, r.source, r.n_loads, r.on, r.below, r.above) == (100.0, "detected", 200, 120, 80, 0)
    # every load near: N KL(1 || 0.03) = 200 ln(100/3) = 701.3 nats, log10 -304.6
    assert r.chance_log10 == pytest.approx(-200 * math.log10(100 / 3), abs=1e-9)
    text = result.describe_resolution()
    assert "weight resolution 100 kg (detected: 200 of 200 axle loads within 1 kg of a multiple of 100 kg" in text
    assert "60.0 % on one, 40.0 % 1 kg below" in text and "probability below 1e-305" in text


def test_one_odd_load_in_two_hundred_keeps_the_step_and_three_in_a_hundred_do_not(tmp_path):
    base = [[7000, 7100, 6900, 7200, 6800] for _ in range(40)]
    one = [row[:] for row in base]
    one[7][2] = 6937  # 199 of 200 on a multiple of 100: 99.5 % >= 99 %
    assert read_weighings(mon_file(tmp_path / "one.mon", one), "mon").resolution.step_kg == 100.0
    three = [row[:] for row in base[:20]]
    three[1][1], three[5][3], three[9][0] = 7137, 7243, 6971  # 97 of 100: below 99 % for every step above 1 kg
    r = read_weighings(mon_file(tmp_path / "three.mon", three), "mon").resolution
    assert (r.step_kg, r.source) == (1.0, "format")
    assert "the format's unit; no coarser step fits" in r.describe()


def test_two_loads_do_not_prove_a_resolution():
    counts = ResidueCounts(1.0)
    counts.add(np.array([7000.0, 6800.0]))
    # multiples of 1000 and 200 only for 6800? 7000 % 200 = 0 and 6800 % 200 = 0: both on 200 kg's grid, but
    # 2 ln(200) = 10.6 nats < 13.8: not enough; 100 kg: 2 ln 100 = 9.2; no step is supported with two loads
    r = detect_resolution(counts)
    assert (r.step_kg, r.source) == (1.0, "format")
    counts.add(np.array([7200.0, 7400.0, 6600.0]))  # five loads on 200 kg: 5 ln 200 = 26.5 nats: supported
    assert detect_resolution(counts).step_kg == 200.0


def test_counts_of_chunks_add_up_to_the_counts_of_the_whole():
    rng = np.random.default_rng(41)
    loads = 100.0 * rng.integers(20, 100, 5000) - rng.integers(0, 2, 5000)
    whole = ResidueCounts(1.0)
    whole.add(loads)
    parts = ResidueCounts(1.0)
    for piece in np.array_split(loads, 7):
        parts.add(piece)
    assert parts == whole and detect_resolution(parts) == detect_resolution(whole)
    assert detect_resolution(whole).step_kg == 100.0


def test_a_resolution_set_by_the_user_is_applied_and_the_detection_kept_beside_it(tmp_path):
    path = mon_file(tmp_path / "site.mon", [[7000, 7100, 6900] for _ in range(10)])
    result = read_weighings(path, "mon", resolution_kg=50)
    r = result.resolution
    assert (r.step_kg, r.source, r.detected_kg) == (50.0, "set", 100.0)
    assert result.describe_resolution() == "weight resolution 50 kg (set; detected from the file: 100 kg)"
    survey = observed_survey(path, "mon", resolution_kg=50)
    assert survey.to_dict()["records"]["resolution"]["source"] == "set"
    assert survey.to_dict()["records"]["weight_step_kg"] == 50.0


@pytest.mark.parametrize(
    ("value", "fmt", "message"),
    [
        (0, "mon", "resolution_kg = 0 is out of range: must be in (0, 1000] kg, or None (None: detect it from"),
        (-100, "mon", "resolution_kg = -100 is out of range: must be in (0, 1000] kg, or None"),
        (1500, "mon", "resolution_kg = 1500 is out of range: must be in (0, 1000] kg, or None"),
        (float("nan"), "mon", "resolution_kg = nan is out of range: must be in (0, 1000] kg, or None"),
        ("100", "mon", "resolution_kg = '100' is not a number (text): must be in (0, 1000] kg, or None"),
        (50, "castor", "resolution_kg = 50 kg is not a whole multiple of the format's weight unit (100 kg)"),
    ],
)
def test_a_bad_resolution_is_refused_with_its_range_and_unit(value, fmt, message):
    with pytest.raises(ValueError) as err:
        read_weighings(DATA / f"site.{fmt}", fmt, resolution_kg=value)
    assert message in str(err.value)


def test_check_resolution_kg_takes_a_multiple_of_the_unit():
    assert check_resolution_kg(None, 100.0) is None
    assert check_resolution_kg(200, 100.0) == 200.0
    with pytest.raises(ValueError, match="not a whole multiple"):
        check_resolution_kg(150, 100.0)


def test_bogie_weighings_prints_the_resolution_and_takes_one(tmp_path, capsys):
    from bogie.cli import main

    loads = [[7000 - (i + k) % 5 * 100 - ((i + k) % 5 < 2) for i in range(5)] for k in range(40)]
    path = mon_file(tmp_path / "site.mon", loads)
    assert main(["weighings", str(path)]) == 0
    assert "weight resolution 100 kg (detected: 200 of 200 axle loads within 1 kg" in capsys.readouterr().out
    assert main(["weighings", str(path), "--resolution-kg", "200"]) == 0
    assert "weight resolution 200 kg (set; detected from the file: 100 kg)" in capsys.readouterr().out
    assert main(["weighings", str(path), "--resolution-kg", "0"]) == 2
    assert "resolution_kg = 0.0 is out of range: must be in (0, 1000] kg, or None" in capsys.readouterr().err


def test_the_observed_stage_reports_the_resolution_and_applies_the_one_set(tmp_path):
    from pipeline.config import load_config
    from pipeline.observed import observed_table

    loads = [[7000 - (i + k) % 5 * 100 - ((i + k) % 5 < 2) for i in range(5)] for k in range(40)]
    path = mon_file(tmp_path / "site.mon", loads)
    raw = (Path(__file__).parents[1] / "params.yaml").read_text()
    params = tmp_path / "params.yaml"
    params.write_text(raw.replace("  resolution_kg:      ", "  resolution_kg: 200  ", 1))
    config = load_config(params)
    assert config.observed.resolution_kg == 200.0
    _, stats = observed_table(path, config.observed)
    assert stats["records"]["weight_step_kg"] == 200.0 and stats["records"]["resolution"]["detected_kg"] == 100.0
    # the stage's figures do not depend on where the project is: no absolute path in them
    assert str(tmp_path) not in json.dumps(stats)
    _, stats = observed_table(path, load_config(Path(__file__).parents[1] / "params.yaml").observed)
    assert stats["records"]["weight_step_kg"] == 100.0 and stats["records"]["resolution"]["source"] == "detected"
    params.write_text(raw.replace("  resolution_kg:      ", "  resolution_kg: -5   ", 1))
    with pytest.raises(Exception, match=r"observed.resolution_kg"):
        load_config(params)
