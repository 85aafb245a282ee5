"""Every Parquet file a stage writes for another carries checksums, and a flipped bit is refused, never read
silently (issue 40 Must 5): before, a flip in the samples changed simulate's output without a word, and one in the
observed groups (an axle of 8,020 kg read as 5,820 kg) changed metrics/road.json."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from pipeline.report.inputs import read_tables
from pipeline.sample import write_parquet_atomic
from pipeline.schema import RunsFileError, read_checksummed, write_checksummed
from pipeline.simulate import COLUMNS, read_samples


def flip(path, where: float) -> None:
    data = bytearray(path.read_bytes())
    data[int(len(data) * where)] ^= 0x04
    path.write_bytes(bytes(data))


def samples_frame(n: int = 40) -> pd.DataFrame:
    rng = np.random.default_rng(0)
    frame = pd.DataFrame({c: np.zeros(n, dtype=t) if t != "category" else ["a"] * n for c, t in COLUMNS.items()})
    for c, t in COLUMNS.items():
        if str(t).startswith("float"):
            frame[c] = rng.uniform(1.0, 2.0, n)
    return frame.astype(COLUMNS)


@pytest.mark.parametrize("where", [0.2, 0.5, 0.8, 0.97])
def test_a_flipped_bit_in_the_samples_is_refused_by_simulate(tmp_path, where):
    path = tmp_path / "fleet.parquet"
    write_parquet_atomic(samples_frame(), path)
    read_samples(tmp_path, ["fleet"])  # as written: read
    flip(path, where)
    with pytest.raises(RunsFileError, match="fleet.parquet"):
        read_samples(tmp_path, ["fleet"])


def test_a_flipped_bit_in_the_observed_groups_is_refused_by_the_readers(tmp_path):
    groups = pd.DataFrame({"axle_load_1": [8020.0, 7990.0], "axle_load_2": [8000.0, 8100.0], "n_axles": [2, 2]})
    (tmp_path / "observed").mkdir()
    path = tmp_path / "observed" / "groups.parquet"
    write_checksummed(groups, path)
    pd.testing.assert_frame_equal(read_checksummed(path, "rerun").to_pandas(), groups)
    assert list(read_tables(tmp_path / "observed", ["groups.parquet"])) == ["groups.parquet"]
    flip(path, 0.3)
    with pytest.raises(RunsFileError, match="damaged|not a whole"):
        read_checksummed(path, "rerun the observed stage")
    with pytest.raises(RunsFileError):
        read_tables(tmp_path / "observed", ["groups.parquet"])


def test_a_parquet_file_without_checksums_is_refused_with_what_to_do(tmp_path):
    path = tmp_path / "fleet.parquet"
    samples_frame().to_parquet(path, index=False)  # the old writer's file
    with pytest.raises(RunsFileError, match="carries no checksum.*rerun the sample stage"):
        read_samples(tmp_path, ["fleet"])
