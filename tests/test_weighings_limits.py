"""A survey file is read in bounded memory, or refused before it is read (issue 40 Must 2 and 6).

The pavement wear's bootstrap draws its resamples in blocks (the same draws, so the same bits, as one matrix of them);
a FIFO, a device or a folder is refused before it is opened; a gzip bomb is refused at the cap, not expanded; the
validate stage refuses a survey whose estimated memory exceeds the budget, before any work.
"""

from __future__ import annotations

import gzip
import os
import shutil
import tracemalloc
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from bogie.weighings import _records, wear
from bogie.weighings.readers import read_weighings

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "weighings"
LEGAL = {"tandem": 18000.0, "triaxle": 24000.0}


def groups(n: int, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    frame = pd.DataFrame({"group": rng.choice(["tandem", "triaxle"], n)})
    frame["n_axles"] = np.where(frame["group"] == "tandem", 2, 3)
    for i in (1, 2, 3):
        frame[f"axle_load_{i}"] = np.where(i <= frame["n_axles"], rng.uniform(4000.0, 9000.0, n), np.nan)
    return frame


def reference_bounds(frame: pd.DataFrame, k: float, resamples: int, seed: int, cell: int) -> tuple[float, float]:
    """The extra wear's interval of one cell as the code before the blocks computed it: all resamples at once."""
    loads = frame[[f"axle_load_{i}" for i in (1, 2, 3)]].to_numpy() / 1.0
    loads = np.nan_to_num(loads)
    g = wear.group_wear(loads, frame["n_axles"].to_numpy(), k, wear.STANDARD_AXLE_KG)
    cells = frame.groupby("group", sort=True).indices
    index = list(cells.values())[cell]
    stream = np.random.SeedSequence(seed).spawn(len(cells))[cell]
    draws = np.random.default_rng(stream).integers(0, len(index), (resamples, len(index)))
    d, e = g["damage"][index], g["damage_equal"][index]
    shares = d[draws].sum(axis=1) / e[draws].sum(axis=1) - 1.0
    low, high = np.quantile(shares, [0.025, 0.975])
    return float(low), float(high)


def test_the_bootstrap_in_blocks_gives_the_bits_of_all_resamples_at_once(monkeypatch):
    frame = groups(3001, seed=4)
    monkeypatch.setattr(wear, "BOOTSTRAP_BLOCK", 1000)  # blocks of a row or two: many blocks
    table = wear.wear_statistics(frame, LEGAL, 10000.0, exponents={"4": 4.0}, resamples=200, seed=7)
    for cell in (0, 1):
        low, high = reference_bounds(frame, 4.0, 200, 7, cell)
        assert (table.loc[cell, "extra_wear_4_low"], table.loc[cell, "extra_wear_4_high"]) == (low, high)


def test_the_bootstraps_memory_is_bounded_whatever_the_survey(monkeypatch):
    # all resamples at once held resamples x groups indices and a gather of each damage array: 200,000 groups and
    # 1,000 resamples asked 1.6 GB for each (7.45 GiB for a million records); the blocks hold 16 MiB each
    frame = groups(200_000, seed=1)
    tracemalloc.start()
    try:
        wear.wear_statistics(frame, LEGAL, 10000.0, exponents={"4": 4.0}, resamples=1000, seed=1)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 200 * 2**20, f"peak {peak / 2**20:.0f} MiB"


def test_a_fifo_a_device_and_a_folder_are_refused_before_they_are_opened(tmp_path):
    fifo = tmp_path / "site.mon"
    os.mkfifo(fifo)  # opening it to read would wait for a writer for ever
    for path, kind in ((fifo, "a FIFO"), (Path("/dev/zero"), "a device"), (tmp_path, "a folder")):
        with pytest.raises(ValueError, match=f"is {kind}"):
            read_weighings(path, "mon")


def test_a_gzip_bomb_is_refused_at_the_cap_and_a_multi_member_file_is_read_whole(tmp_path, monkeypatch):
    monkeypatch.setattr(_records, "MAX_FILE_BYTES", 10**6)
    bomb = tmp_path / "bomb.mon.gz"
    bomb.write_bytes(gzip.compress(b"0" * 5 * 10**6))
    with pytest.raises(ValueError, match="decompresses to more than"):
        read_weighings(bomb, "mon")
    big = tmp_path / "big.mon"
    big.write_bytes(b"0" * (10**6 + 1))
    with pytest.raises(ValueError, match="split the survey"):
        read_weighings(big, "mon")
    text = (DATA / "site.mon").read_bytes()
    half = text.index(b"\n", len(text) // 2) + 1
    two = tmp_path / "two.mon.gz"
    two.write_bytes(gzip.compress(text[:half]) + gzip.compress(text[half:]))
    whole = read_weighings(DATA / "site.mon", "mon")
    assert read_weighings(two, "mon").vehicles.equals(whole.vehicles)


def test_the_uncompressed_size_is_the_files_or_the_gzip_trailers(tmp_path):
    plain = tmp_path / "a.mon"
    plain.write_bytes(b"1" * 1234)
    packed = tmp_path / "a.mon.gz"
    packed.write_bytes(gzip.compress(b"1" * 123_456))
    assert _records.uncompressed_size(plain) == 1234
    assert _records.uncompressed_size(packed) == 123_456
    assert _records.survey_memory(packed) == _records.SURVEY_BASE_MEMORY + int(123_456 * _records.MEMORY_PER_BYTE)


def test_validate_refuses_a_survey_that_would_not_fit_the_memory_budget(tmp_path, monkeypatch, capsys):
    from pipeline import validate
    from pipeline.config import settings

    (tmp_path / "observed").mkdir()
    shutil.copy(DATA / "site.csv", tmp_path / "observed" / "site.csv")
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["observed"].update(path="observed/site.csv", format="csv")
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw))
    size = (tmp_path / "observed" / "site.csv").stat().st_size
    need = _records.SURVEY_BASE_MEMORY + int(size * _records.MEMORY_PER_BYTE)
    monkeypatch.setattr(settings, "MEMORY_BUDGET", need - 1)
    args = ["--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "config.json")]
    assert validate.main(args) == 2
    err = capsys.readouterr().err
    assert "observed.path" in err and "memory budget" in err and "split the survey" in err, err
    assert not (tmp_path / "config.json").exists()
    monkeypatch.setattr(settings, "MEMORY_BUDGET", need)
    assert validate.main(args) == 0


def test_a_survey_past_the_cap_is_refused_only_when_calibrate_holds_its_groups(tmp_path, monkeypatch, capsys):
    from pipeline import validate

    (tmp_path / "observed").mkdir()
    shutil.copy(DATA / "site.csv", tmp_path / "observed" / "site.csv")
    monkeypatch.setattr(_records, "MAX_FILE_BYTES", 100)  # the file is larger
    from pipeline.config import settings

    monkeypatch.setattr(settings, "MAX_FILE_BYTES", 100)
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    raw["observed"].update(path="observed/site.csv", format="csv")
    args = ["--params", str(tmp_path / "params.yaml"), "--out", str(tmp_path / "config.json")]
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw))
    assert raw["calibrate"] is not None  # the project's params calibrate to the survey
    assert validate.main(args) == 2
    err = capsys.readouterr().err
    assert "calibrate stage" in err and "calibrate: null" in err, err
    assert not (tmp_path / "config.json").exists()
    raw["calibrate"] = None  # the observed stage streams any length: nothing holds the groups
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(raw))
    assert validate.main(args) == 0, capsys.readouterr().err
