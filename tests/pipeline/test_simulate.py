"""The ``simulate`` stage: schema, determinism, resumption, failed runs and the dask backend (pipeline.simulate).

Every test simulates the same tiny study set (12 fleet bogies, a Sobol' design of base size 4, 2 ablation bogies;
time step 2 ms) in about a second of CPU; the reference dataset is computed once per module.
"""

import copy
import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml
from _flips import flip

from bogie import numerics
from bogie.fleet.sampling.sample import COLUMNS
from pipeline.chunks import (
    HASH_KEY,
    NUMERICS_KEY,
    NotRunsDatasetError,
    RunsLockedError,
    part_content,
    part_name,
    runs_lock,
)
from pipeline.config import load_params, parse_config
from pipeline.resources import worker_count
from pipeline.sample import sample_studies, write_parquet_atomic
from pipeline.schema import CATEGORICAL, RESULT_COLUMNS, RUN_COLUMNS, SAMPLE_COLUMNS, write_runs_file
from pipeline.simulate import chunk_table, run_chunk, simulate_samples, study_protocols

ROOT = Path(__file__).resolve().parents[2]
KEYS = ["study", "sample_id", "protocol"]


def tiny_raw(**execution):
    """The default params with tiny studies, a 2 ms time step and the given execution settings."""
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 12
    raw["sensitivity"]["base_size"] = 4
    raw["ablation"]["n_bogies"] = 2
    raw["protocol"]["static"]["dt_s"] = 0.002
    raw["protocol"]["wim"]["dt_s"] = 0.002
    raw["execution"].update({"backend": "loky", "n_jobs": 2, "chunk_size": 3, "dask_scheduler": None, **execution})
    return raw


@pytest.fixture(scope="module")
def config():
    return parse_config(tiny_raw())


@pytest.fixture(scope="module")
def samples(config):
    return sample_studies(config)


def protocols_of(config):
    return {study: study_protocols(config, study) for study in ("fleet", "sensitivity", "ablation")}


def run(config, samples, out, **execution):
    """Simulate in-process with the execution settings changed; returns the summary and the log lines."""
    lines = []
    summary = simulate_samples(
        samples, protocols_of(config), dataclasses.replace(config.execution, **execution), out, lines.append
    )
    return summary, lines


def dataset(out):
    """The whole runs dataset in a canonical order."""
    frame = pd.read_parquet(out)
    frame["study"] = frame["study"].astype(str)
    return frame.sort_values(KEYS).reset_index(drop=True)


def parts(out):
    return sorted(Path(out).glob("study=*/*"))


@pytest.fixture(scope="module")
def reference(config, samples, tmp_path_factory):
    """The dataset of a plain run: loky, 2 workers, chunks of 3 samples."""
    out = tmp_path_factory.mktemp("reference") / "runs"
    run(config, samples, out)
    return dataset(out)


# ---- schema ------------------------------------------------------------------------------------------------------
def test_each_part_file_has_the_run_schema_and_no_missing_values(config, samples, reference, tmp_path):
    out = tmp_path / "runs"
    summary, _ = run(config, samples, out)
    for path in parts(out):
        frame = pd.read_parquet(path)
        # the file has no study column: pandas takes it from the directory name when it reads the dataset
        assert list(frame.columns) == list(RUN_COLUMNS)
        assert {c: str(t) for c, t in frame.dtypes.items()} == RUN_COLUMNS
        ok = frame["status"] == "ok"
        assert ok.any() and not frame[ok].isna().any().any()
        schema = pq.read_schema(path)
        assert len(schema.metadata[HASH_KEY]) == 64
        units = {f.name: f.metadata[b"unit"].decode() for f in schema}
        assert (units["axle_load_1"], units["chassis_tilt"], units["chassis_tilt_deg"]) == ("N", "rad", "degree")
        assert (units["bush_stiffness"], units["spread_kg"], units["outside_5pct"]) == ("N m/rad", "kg", "-")
    fleet = pd.read_parquet(out, filters=[("study", "==", "fleet")])
    assert set(fleet["study"].astype(str)) == {"fleet"}
    assert len(fleet) == 12 * len(config.protocol.run)
    assert summary.runs == len(reference) and summary.failed == int((reference["status"] != "ok").sum())


def test_a_part_file_is_byte_for_byte_the_file_its_rows_give_through_pandas(config, samples, tmp_path):
    # the stage builds a part's Arrow table from the rows directly (pipeline.schema.table_from_rows), with the pandas
    # metadata Table.from_pandas writes: the file must not tell the two paths apart, failed runs included
    rows = samples["fleet"].iloc[:4].copy()
    rows.loc[1, "payload_fraction"] = 3.0  # the protocol's run fails
    rows.loc[2, "bush_stiffness"] = -1.0  # not a bogie
    protocols = study_protocols(config, "fleet")
    content = part_content(chunk_table({c: rows[c].tolist() for c in COLUMNS}, protocols), "0" * 64, "digest target")
    through_pandas = tmp_path / "pandas.parquet"
    write_runs_file(run_chunk(rows, protocols), through_pandas, {HASH_KEY: b"0" * 64, NUMERICS_KEY: b"digest target"})
    assert pq.read_table(through_pandas).column("status").to_pylist().count("failed") == 4
    assert content == through_pandas.read_bytes()


def test_one_row_per_sample_and_protocol_carrying_the_sample_columns(config, samples, reference):
    for study, table in samples.items():
        runs = reference[reference["study"] == study]
        protocols = [name for name, _ in study_protocols(config, study)]
        assert sorted(set(runs["protocol"])) == sorted(protocols)
        assert len(runs) == len(table) * len(protocols)
        # every run row repeats its sample's parameters exactly, so a runs file answers queries on its own
        for protocol in protocols:
            rows = runs[runs["protocol"] == protocol].reset_index(drop=True)
            # the runs store the labels as categoricals, the samples as text: compare the values
            labels = {c: "str" for c in CATEGORICAL if c in SAMPLE_COLUMNS}
            pd.testing.assert_frame_equal(rows[list(SAMPLE_COLUMNS)].astype(labels), table[list(SAMPLE_COLUMNS)])
    assert set(reference.loc[reference["study"] == "sensitivity", "protocol"]) == {config.sensitivity.protocol}


def test_the_ablation_baseline_reproduces_its_fleet_bogie_bit_for_bit(reference):
    # the same sample row in another study and another chunk: a run is a pure function of its row
    results = [c for c in RUN_COLUMNS if c not in SAMPLE_COLUMNS]
    ablation = reference[(reference["study"] == "ablation") & (reference["variant"] == "baseline")]
    fleet = reference[reference["study"] == "fleet"]
    merged = ablation.merge(fleet, left_on=["base_id", "protocol"], right_on=["sample_id", "protocol"])
    assert len(merged) == len(ablation) > 0
    for c in results:
        if c != "protocol":
            assert (merged[f"{c}_x"] == merged[f"{c}_y"]).all(), c


# ---- determinism -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("n_jobs", "chunk_size"), [(1, 3), (2, 7)])
def test_results_do_not_depend_on_workers_or_chunk_size(config, samples, reference, tmp_path, n_jobs, chunk_size):
    out = tmp_path / "runs"
    run(config, samples, out, n_jobs=n_jobs, chunk_size=chunk_size)
    n_chunks = sum(-(-len(t) // chunk_size) for t in samples.values())
    assert len(parts(out)) == n_chunks
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


# ---- resumption --------------------------------------------------------------------------------------------------
def test_a_rerun_computes_only_the_missing_chunk(config, samples, reference, tmp_path):
    out = tmp_path / "runs"
    first, _ = run(config, samples, out)
    files = parts(out)
    mtimes = {p: p.stat().st_mtime_ns for p in files}
    deleted = out / "study=fleet" / part_name(2)
    deleted.unlink()
    summary, lines = run(config, samples, out)
    assert (summary.computed_chunks, summary.skipped_chunks) == (1, len(files) - 1)
    assert summary.computed_runs == 3 * len(config.protocol.run)
    assert f"{len(files) - 1} up to date, 1 to run" in lines[0]
    assert parts(out) == files
    assert all(p.stat().st_mtime_ns == mtimes[p] for p in files if p != deleted)
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)
    assert summary.runs == first.runs and summary.failed == first.failed


def test_a_rerun_replaces_stale_corrupt_and_leftover_files(config, samples, reference, tmp_path):
    out = tmp_path / "runs"
    run(config, samples, out, chunk_size=2)
    fleet_dir = out / "study=fleet"
    (fleet_dir / part_name(0)).write_bytes(b"not parquet")  # e.g. a disk that lost the file's content
    leftover = fleet_dir / f".{part_name(1)}.abc123.tmp"  # what a write killed before its rename leaves
    leftover.write_bytes(b"half a file")
    gone = out / "study=retired"  # a study that is no longer simulated
    gone.mkdir()
    (gone / part_name(0)).write_bytes(b"")

    summary, _ = run(config, samples, out, chunk_size=3)  # every chunk changes: its rows differ
    expected = {f"study={s}/{part_name(i)}" for s, t in samples.items() for i in range(-(-len(t) // 3))}
    assert {str(p.relative_to(out)) for p in parts(out)} == expected
    assert not gone.exists()
    assert summary.skipped_chunks == 0
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


def _data_page_offset(path):
    """A byte inside the first column chunk's data of a Parquet file (after its page header), footer untouched."""
    column = pq.ParquetFile(path).metadata.row_group(0).column(0)
    start = column.dictionary_page_offset or column.data_page_offset
    return start + column.total_compressed_size // 2


def test_a_flipped_bit_inside_a_data_page_is_detected_and_the_part_recomputed(config, samples, reference, tmp_path):
    out = tmp_path / "runs"
    run(config, samples, out)
    damaged = out / "study=fleet" / part_name(1)
    content = bytearray(damaged.read_bytes())
    content[_data_page_offset(damaged)] ^= 0x04  # one bit; the footer, schema and stored hash stay intact
    damaged.write_bytes(bytes(content))
    assert pq.read_schema(damaged).metadata[HASH_KEY]  # the hash alone cannot see the damage
    summary, lines = run(config, samples, out)
    assert (summary.computed_chunks, summary.skipped_chunks) == (1, len(parts(out)) - 1)
    assert any(f"{damaged} is damaged" in line and "recomputing" in line for line in lines)
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


def test_a_flip_in_page_statistics_or_the_footer_is_detected_and_the_part_recomputed(config, samples, reference,
                                                                                      tmp_path):  # fmt: skip
    # issue 28, item 4: the pages' CRC32s cover their data, not their headers' statistics nor the footer; the file's
    # SHA-256 covers every byte
    out = tmp_path / "runs"
    run(config, samples, out)
    places = {part_name(1): "page statistics", part_name(2): "footer statistics", part_name(3): "footer metadata"}
    for name, place in places.items():
        flip(out / "study=fleet" / name, place)
    summary, lines = run(config, samples, out)
    assert (summary.computed_chunks, summary.skipped_chunks) == (3, len(parts(out)) - 3)
    for name in places:
        damaged = out / "study=fleet" / name
        assert any(f"{damaged} is damaged" in line and "SHA-256" in line for line in lines), lines
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


def test_a_stray_file_in_the_dataset_is_quarantined_with_a_warning(config, samples, reference, tmp_path):
    out = tmp_path / "runs"
    run(config, samples, out)
    notes = out / "study=fleet" / "notes.txt"
    notes.write_text("my notes")
    (out / "README").write_text("top-level notes")
    summary, lines = run(config, samples, out)
    assert summary.computed_chunks == 0
    quarantine = tmp_path / ".quarantine" / "runs"
    assert (quarantine / "study=fleet" / "notes.txt").read_text() == "my notes"  # moved, never deleted
    assert (quarantine / "README").exists() and not notes.exists()
    assert sum("warning" in line and "notes.txt" in line for line in lines) == 1
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)  # pandas reads the dataset again


def snapshot(folder):
    """Every entry under ``folder`` (directories, files with their bytes), to compare before and after a run."""
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else None) for p in Path(folder).rglob("*")}


@pytest.mark.parametrize("out", [".", "samples"])
def test_a_folder_that_is_not_a_runs_dataset_is_refused_and_nothing_in_it_moves(
    samples, tmp_path, monkeypatch, capsys, out
):
    # a copy of the project: `--out .` once moved .git into ./.quarantine/, `--out samples` moved the samples
    from pipeline.simulate import main

    command, _, _ = stage_command(samples, tmp_path)
    (tmp_path / ".git").mkdir()
    (tmp_path / ".git" / "HEAD").write_text("ref: refs/heads/main\n")
    (tmp_path / "README.md").write_text("my project")
    monkeypatch.chdir(tmp_path)
    before, beside = snapshot(tmp_path), sorted(tmp_path.parent.iterdir())
    params, sample_dir = command[command.index("--params") + 1], command[command.index("--samples") + 1]
    assert main(["--params", params, "--samples", sample_dir, "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith(f"simulate: {out} is not a runs dataset of this stage (it has no .bogie-runs)"), err
    assert "touched nothing" in err and ("in .git, README.md" in err if out == "." else "fleet.parquet" in err)
    assert snapshot(tmp_path) == before  # nothing moved, deleted or added (no lock file, no quarantine)
    assert sorted(tmp_path.parent.iterdir()) == beside


def test_files_the_stage_did_not_write_are_never_deleted_nor_overwritten_in_quarantine(
    config, samples, reference, tmp_path
):
    out = tmp_path / "runs"
    run(config, samples, out)
    fleet = out / "study=fleet"
    (fleet / "part-notes.txt").write_text("a part's name, not a part")  # today's sweep deleted it
    theirs = fleet / "part-00099.parquet"  # a part's exact name, but not a file the stage wrote (no content hash)
    pd.DataFrame({"x": [1.0]}).to_parquet(theirs)
    theirs_bytes = theirs.read_bytes()
    (fleet / "notes.txt").write_text("first notes")
    summary, lines = run(config, samples, out)
    assert summary.computed_chunks == 0 and summary.removed_files == 0
    quarantine = tmp_path / ".quarantine" / "runs" / "study=fleet"
    assert (quarantine / "part-notes.txt").read_text() == "a part's name, not a part"
    assert (quarantine / "part-00099.parquet").read_bytes() == theirs_bytes
    for name in ("part-notes.txt", "part-00099.parquet", "notes.txt"):  # each move named in the log
        assert sum(f"{fleet / name} is not a file the stage wrote; moved it to {quarantine / name}" in line
                   for line in lines) == 1, lines  # fmt: skip
    (fleet / "notes.txt").write_text("second notes")  # the same name, quarantined again
    _, lines = run(config, samples, out)
    assert (quarantine / "notes.txt").read_text() == "first notes"
    assert (quarantine / "notes.txt.1").read_text() == "second notes"
    assert any(f"moved it to {quarantine / 'notes.txt.1'}" in line for line in lines)
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


def test_a_dataset_from_before_the_marker_is_kept_and_marked_but_not_with_others_files(
    config, samples, reference, tmp_path
):
    # a user's data/runs from before the marker (or their DVC checkout of it): every file is a part of the stage
    out = tmp_path / "runs"
    run(config, samples, out)
    marker = out / ".bogie-runs"
    assert json.loads(marker.read_text())["format"] == 1
    marker.unlink()
    files = parts(out)
    summary, lines = run(config, samples, out)
    assert summary.computed_chunks == 0 and parts(out) == files and marker.exists()
    assert any("holds only part files of this stage: marked it" in line for line in lines)
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)
    # unmarked with a file of someone else's: refused before anything is read, locked or moved
    marker.unlink()
    (out / "study=fleet" / "notes.txt").write_text("mine")
    before = snapshot(tmp_path)
    with pytest.raises(NotRunsDatasetError, match=r"holds 1 files the stage did not write \(in study=fleet\)"):
        run(config, samples, out)
    assert snapshot(tmp_path) == before


def test_a_second_simulate_on_the_same_dataset_is_refused_while_the_first_holds_it(config, samples, tmp_path):
    out = tmp_path / "runs"
    with runs_lock(out):
        with pytest.raises(RunsLockedError, match=rf"{out} is being written by another simulate process \(pid "):
            run(config, samples, out)
        assert not out.exists()  # the refused run wrote nothing
    summary, _ = run(config, samples, out)  # released: the next run goes ahead
    assert summary.computed_chunks > 0


def test_a_changed_protocol_setting_reruns_only_the_chunks_that_use_it(config, samples, reference, tmp_path):
    out = tmp_path / "runs"
    run(config, samples, out)
    faster = dataclasses.replace(config.protocol.wim, speed=config.protocol.wim.speed + 1.0)
    changed = dataclasses.replace(config, protocol=dataclasses.replace(config.protocol, wim=faster))
    lines = []
    summary = simulate_samples(samples, protocols_of(changed), config.execution, out, lines.append)
    # the sensitivity study runs only the static protocol: its chunks stay valid
    n_sensitivity = -(-len(samples["sensitivity"]) // 3)
    assert summary.skipped_chunks == n_sensitivity
    assert summary.computed_chunks == -(-12 // 3) + -(-len(samples["ablation"]) // 3)
    runs = dataset(out)
    static, wim = runs["protocol"] == "static", runs["protocol"] == "wim"
    pd.testing.assert_frame_equal(runs[static], reference[reference["protocol"] == "static"], check_exact=True)
    assert not np.array_equal(
        runs.loc[wim, "axle_load_1"], reference.loc[reference["protocol"] == "wim", "axle_load_1"]
    )


def stage_command(samples, tmp_path):
    """The simulate stage as a command on the tiny samples, one chunk per sample: (command, environment, out)."""
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump(tiny_raw(chunk_size=1)))
    sample_dir = tmp_path / "samples"
    sample_dir.mkdir()
    for study, table in samples.items():
        write_parquet_atomic(table, sample_dir / f"{study}.parquet")
    out = tmp_path / "runs"
    command = [sys.executable, "-m", "pipeline.simulate", "--params", str(params), "--samples", str(sample_dir)]
    command += ["--out", str(out)]
    return command, {**os.environ, "PYTHONPATH": str(ROOT)}, out


def test_a_killed_run_resumes_to_the_uninterrupted_dataset(config, samples, reference, tmp_path):
    command, env, out = stage_command(samples, tmp_path)
    n_chunks = sum(len(t) for t in samples.values())

    # a session of its own, so that SIGKILL reaches the loky workers too, as when the machine kills the job
    proc = subprocess.Popen(command, cwd=tmp_path, env=env, start_new_session=True, stdout=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not list(out.glob("study=*/part-*.parquet")) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.005)
        os.killpg(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    finished = len(list(out.glob("study=*/part-*.parquet")))
    assert 1 <= finished < n_chunks

    result = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    # every file the killed run left is complete (written under a temporary name, then renamed) and kept
    assert re.search(rf": {finished} up to date, {n_chunks - finished} to run", result.stdout), result.stdout
    assert not list(out.glob("study=*/.*"))
    assert len(parts(out)) == n_chunks
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


# ---- failures ----------------------------------------------------------------------------------------------------
def test_a_sample_that_cannot_be_simulated_is_a_failed_row_not_a_crash(config, samples, reference, tmp_path):
    broken = {study: table.copy() for study, table in samples.items()}
    fleet = broken["fleet"]
    fleet.loc[4, "payload_fraction"] = 3.0  # beyond what the load ramp accepts: the protocol's run fails
    fleet.loc[7, "bush_stiffness"] = -1.0  # not a bogie at all: bogie validation refuses it
    out = tmp_path / "runs"
    summary, _ = run(config, broken, out)

    runs = dataset(out)
    fleet_runs = runs[runs["study"] == "fleet"].set_index(["sample_id", "protocol"])
    results = list(RESULT_COLUMNS)
    for sample_id, reason in ((4, "load_factor"), (7, "invalid bogie: ValueError: bush_stiffness")):
        rows = fleet_runs.loc[sample_id]
        assert len(rows) == len(config.protocol.run)
        assert (rows["status"] == "failed").all()
        assert rows["message"].str.contains(reason).all(), rows["message"].tolist()
        # never a made-up number: every result of a failed row is null, so an unfiltered mean is NaN, not wrong
        assert rows[results].isna().all().all()
        assert np.isnan(rows["max_deviation"].mean())
    ok = runs["status"] == "ok"
    assert not runs[ok].isna().any().any()
    assert runs.loc[~ok, ["status", "message", "chassis_tilt_deg", *SAMPLE_COLUMNS]].notna().all().all()
    assert summary.failed == int((runs["status"] != "ok").sum())
    # the other samples are untouched
    others = ~((runs["study"] == "fleet") & runs["sample_id"].isin([4, 7]))
    expected = ~((reference["study"] == "fleet") & reference["sample_id"].isin([4, 7]))
    pd.testing.assert_frame_equal(
        runs[others].reset_index(drop=True), reference[expected].reset_index(drop=True), check_exact=True
    )


# ---- dask --------------------------------------------------------------------------------------------------------
def test_a_dask_local_cluster_gives_the_loky_results(config, samples, reference, tmp_path):
    from dask.distributed import LocalCluster

    out = tmp_path / "runs"
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        summary, lines = run(config, samples, out, backend="dask", dask_scheduler=cluster.scheduler_address)
    assert cluster.status.name == "closed"
    assert cluster.scheduler_address in lines[0]
    assert summary.computed_chunks == len(parts(out))
    pd.testing.assert_frame_equal(dataset(out), reference, check_exact=True)


def test_n_jobs_beyond_the_cores_or_the_memory_is_capped_with_a_warning():
    lines = []
    assert worker_count(2, lines.append, "simulate", cores=2, memory=8 * 2**30) == 2 and lines == []
    assert worker_count(64, lines.append, "simulate", cores=2, memory=8 * 2**30) == 2
    assert "execution.n_jobs = 64 is more than the cores can hold (2 cores" in lines[-1]
    assert worker_count(16, lines.append, "simulate", cores=32, memory=1 * 2**30) == 3  # 1 GiB / 300 MiB
    assert "more than the available memory can hold" in lines[-1] and "running 3 workers" in lines[-1]
    assert worker_count(4, lines.append, "simulate", cores=8, memory=10 * 2**20) == 1  # never fewer than one


def test_killing_the_main_process_ends_its_workers(config, samples, tmp_path):
    import psutil

    command, env, out = stage_command(samples, tmp_path)
    proc = subprocess.Popen(command, cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not list(out.glob("study=*/part-*.parquet")) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        workers = psutil.Process(proc.pid).children(recursive=True)
        assert workers, "the stage started no worker processes"
        proc.kill()  # the main process alone, as the OOM killer or a `kill -9 <pid>` does
    finally:
        proc.wait()
    gone, alive = psutil.wait_procs(workers, timeout=90)  # the chunk in hand, then WORKER_IDLE_TIMEOUT (30 s)
    for p in alive:
        p.kill()
    assert not alive, f"{len(alive)} workers outlived their main process by 90 s (loky's own default is 300 s)"


# ---- what computed a part --------------------------------------------------------------------------------------
def test_the_numerics_a_part_records_are_the_digest_and_the_compile_target():
    # the digest of the weighing process and the compile target: the same on every x86-64 machine with AVX2 and
    # FMA, so the files stay the same bytes there (docs/architecture.md, "The same bits on every machine")
    from pipeline.chunks import process_numerics

    digest, target = process_numerics().split(" ", 1)
    assert re.fullmatch(r"[0-9a-f]{16}", digest)
    assert target == numerics.compile_target()


def test_a_part_file_records_its_numerics_in_its_metadata(config, samples, tmp_path):
    from pipeline.chunks import process_numerics

    run(config, {"fleet": samples["fleet"].iloc[:3]}, tmp_path / "runs", n_jobs=1)
    (part,) = parts(tmp_path / "runs")
    assert pq.read_schema(part).metadata[NUMERICS_KEY] == process_numerics().encode()


def test_a_worker_that_computes_other_bits_is_refused_and_writes_nothing(config, samples, tmp_path):
    # a dask worker whose numba compiles for a generic x86-64 CPU (no fused multiply-adds): its numerics digest
    # differs, so its chunks would differ in the last bits; the stage stops before writing one. Its first task
    # compiles the kernels for that target (a minute or two, once; then numba's cache has them)
    from dask.distributed import LocalCluster

    from pipeline.workers import OtherNumericsError

    out = tmp_path / "runs"
    with LocalCluster(
        n_workers=1, threads_per_worker=2, processes=True, host="127.0.0.1", dashboard_address=None,
        env={"NUMBA_CPU_NAME": "generic"},  # two threads: joblib runs a one-thread cluster's tasks in this process
    ) as cluster:  # fmt: skip
        with pytest.raises(OtherNumericsError, match="computes other last bits than this process"):
            run(config, {"fleet": samples["fleet"].iloc[:3]}, out, backend="dask",
                dask_scheduler=cluster.scheduler_address)  # fmt: skip
    assert parts(out) == []


# ---- the first run talks (issue 31 item 2) -------------------------------------------------------------------------
def test_numbas_cache_is_found_where_its_locator_puts_a_modules_index(tmp_path):
    import hashlib

    from bogie.numba_cache import is_cached
    from bogie.steel.phases import _core as _phases_core

    parent = Path(_phases_core.__file__).resolve().parent
    sub = tmp_path / f"{parent.name}_{hashlib.sha1(str(parent).encode()).hexdigest()}"
    assert not is_cached(_phases_core.__file__, tmp_path)
    sub.mkdir()
    (sub / "_step.advance-3.py311.nbi").write_text("")  # another module's functions: not it
    (sub / "_core_x.run-1.py311.nbi").write_text("")
    assert not is_cached(_phases_core.__file__, tmp_path)
    (sub / "_core._work_records-174.py311.nbi").write_text("")  # a helper of the module only
    assert is_cached(_phases_core.__file__, tmp_path)
    assert not is_cached(_phases_core.__file__, tmp_path, function="run_phases")
    (sub / "_core.run_phases-512.py311.nbi").write_text("")
    assert is_cached(_phases_core.__file__, tmp_path, function="run_phases")
    (tmp_path / "elsewhere_0123").mkdir()  # another clone's subdirectory does not count for this one
    assert not is_cached(_phases_core.__file__, tmp_path / "elsewhere_0123")


def test_in_the_directory_keyed_by_the_code_a_modules_kernels_lie_by_their_place_in_the_package(tmp_path):
    # issue 45 Must 6: every clone of one version finds them (bogie/_numba_locator.py)
    from bogie import numba_cache
    from bogie.numba_cache import PACKAGE
    from bogie.steel.phases import _core as _phases_core

    keyed = tmp_path / numba_cache.source_digest(PACKAGE)
    (keyed / f"{_phases_core.__file__.split('/')[-2]}_0123").mkdir(parents=True)  # numba's own layout: not here
    (keyed / f"{_phases_core.__file__.split('/')[-2]}_0123" / "_core.run_phases-512.py311.nbi").write_text("")
    assert not is_cached_in(keyed)
    (keyed / "bogie.steel.phases").mkdir()
    (keyed / "bogie.steel.phases" / "_core.run_phases-512.py311.nbi").write_text("")
    assert is_cached_in(keyed)
    assert not numba_cache.is_cached(_phases_core.__file__, tmp_path / "0123456789abcdef", function="run_phases")


def is_cached_in(directory):
    from bogie import numba_cache
    from bogie.steel.phases import _core as _phases_core

    return numba_cache.is_cached(_phases_core.__file__, directory, function="run_phases")


def test_the_kernels_compile_once_before_the_workers_with_a_line_before_and_after(monkeypatch):
    import pipeline.simulate as S
    from bogie import numba_cache

    kinds = [("triaxle", "steel")] * 3 + [("tandem", "steel"), ("triaxle", "air")]
    frame = pd.DataFrame({c: [0] * len(kinds) for c in COLUMNS})
    frame["group"], frame["suspension"] = [g for g, _ in kinds], [k for _, k in kinds]
    samples, protocols = {"fleet": frame}, {"fleet": (("static", None), ("wim", None))}
    weighed, lines, digests = [], [], []
    monkeypatch.setattr(S, "chunk_table", lambda r, protocols: weighed.append((r["group"], r["suspension"])))
    monkeypatch.setattr(S, "process_numerics", lambda: digests.append(1))
    monkeypatch.setattr(numba_cache, "is_cached", lambda *a, **k: True)
    assert S.compile_kernels(samples, protocols, lines.append) == 0.0  # cached: nothing run, nothing said
    assert weighed == [] and lines == [] and digests == []
    monkeypatch.setattr(numba_cache, "is_cached", lambda *a, **k: False)
    S.compile_kernels(samples, protocols, lines.append)
    # the numerics digest (what the chunks' hashes run first), then one sample of each kind, the first of each
    assert digests == [1]
    assert weighed == [(["triaxle"], ["steel"]), (["tandem"], ["steel"]), (["triaxle"], ["air"])]
    assert len(lines) == 2 and "compiling the numba kernels" in lines[0] and "leaves it out" in lines[0]
    assert re.fullmatch(r"simulate: kernels compiled in \d+ s", lines[1])


def test_another_stage_running_its_study_here_is_named_in_every_line(config, samples, tmp_path):
    # issue 31: the design stage's progress lines said "simulate:"
    lines = []
    few = {"fleet": samples["fleet"].iloc[:2]}
    simulate_samples(few, {"fleet": study_protocols(config, "fleet")}, dataclasses.replace(config.execution, n_jobs=1),
                     tmp_path / "runs", lines.append, "design")  # fmt: skip
    assert lines and all(line.startswith("design:") for line in lines), lines
    assert not any("simulate" in line for line in lines)


def test_the_closing_lines_rate_leaves_the_compile_out():
    from pipeline.simulate import Summary

    s = Summary(runs=100, failed=0, computed_runs=100, computed_chunks=4, skipped_chunks=0, removed_files=0,
                wall_time=75.0, compile_time=70.0)  # fmt: skip
    assert s.runs_per_second == 20.0  # 100 runs in the 5 s left after 70 s of compiling
    assert "computed 100 runs in 4 chunks in 75.0 s, 70.0 s of it compiling (20.0 runs/s)" in s.line()
    cached = dataclasses.replace(s, compile_time=0.0)
    assert "compiling" not in cached.line() and cached.runs_per_second == pytest.approx(100 / 75)
