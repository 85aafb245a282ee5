"""DVC stage ``simulate``: every sampled bogie through the survey protocols -> data/runs/.

``python -m pipeline.simulate`` reads params.yaml and the study tables of data/samples/, splits each study into
chunks of ``execution.chunk_size`` consecutive samples, weighs every sample of a chunk by each of its study's
protocols (fleet and ablation: every protocol of ``protocol.run``; sensitivity: ``sensitivity.protocol`` only) and
writes one Parquet file per chunk, ``data/runs/study=<study>/part-<chunk:05d>.parquet``: a hive-partitioned dataset,
so ``pd.read_parquet("data/runs", filters=[("study", "==", "fleet")])`` reads one study (pandas adds ``study`` back
from the directory name as a categorical column; the files themselves have no ``study`` column).

One row per (sample, protocol), with every column of the sample (except ``study``) followed by the protocol's
results, in the one schema of :mod:`pipeline.schema` (types and units). A failed weighing is a row with
``status = "failed"``, the reason in ``message`` and nulls in every result column; the stage never stops for one.

Parallel: on this machine (``execution.backend`` ``loky``) the main process and ``n_jobs - 1`` loky worker processes
(one thread each) weigh the chunks; on a dask.distributed cluster, joblib's ``dask`` backend. A worker returns its
chunk's file as bytes and the main process writes each file as soon as its chunk completes.

Resumable: each file carries in its Parquet metadata (key :data:`HASH_KEY`) a hash of everything that determines its
content: the chunk's sample rows, the protocols and their settings, and the code (the sources of ``bogie`` and of
the pipeline modules that turn a sample into a row, and the numerical libraries' versions). A rerun keeps the files
whose hash matches, deletes every other file of its own (stale chunks, leftovers of an interrupted write) and computes
only the missing chunks. It writes and sweeps only a folder that is its own runs dataset: one it made (the marker
file ``data/runs/.bogie-runs``) or an empty one; it refuses any other folder in one line and touches nothing there,
and it moves every file it did not write to ``data/.quarantine/runs/``, never deleting one (:mod:`pipeline.chunks`).
Files are written under a temporary dot-name and renamed, so a reader or a rerun never sees half a file.
Deterministic: every run is a pure function of its sample row and protocol settings (each bogie's road has its
own seed), so the dataset is byte for byte the same whatever ``n_jobs``, chunk size or backend. (Timing is not
stored in the dataset, which would then differ at every rebuild: the stage's summary line gives the runs per second,
and ``bench/`` measures the cost per run.)
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import sys
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import pyarrow as pa
from joblib import Parallel, delayed, parallel_config

from bogie.fleet.sampling.sample import COLUMNS
from bogie.fleet.weighing.weigher import weigh_rows
from pipeline.atomic import StageError, run_stage, stage_inputs
from pipeline.chunks import (
    Chunk,
    Log,
    NotRunsDatasetError,
    Protocols,
    RunsLockedError,
    _print,
    check_runs_dir,
    claim_runs_dir,
    part_content,
    plan_chunks,
    process_numerics,
    reconcile,
    runs_lock,
    write_part,
)
from pipeline.config import Config, ExecutionConfig, load_config
from pipeline.portable import warn_if_unportable
from pipeline.resources import worker_count
from pipeline.sample import STUDIES
from pipeline.schema import failed_runs, read_checksummed, runs_frame, table_from_rows
from pipeline.workers import OtherNumericsError, check_numerics, dask_client, fed_results, scheduler_text


def study_protocols(config: Config, study: str) -> Protocols:
    """The protocols a study runs: fleet and ablation every one of ``protocol.run``; sensitivity its own."""
    names = (config.sensitivity.protocol,) if study == "sensitivity" else config.protocol.run
    return tuple((name, getattr(config.protocol, name)) for name in names)


# ---- one chunk: the work of one task ---------------------------------------------------------------------------
def run_chunk(rows: pd.DataFrame, protocols: Protocols) -> pd.DataFrame:
    """Weigh every sample of ``rows`` by every protocol: the rows of one part file as a typed DataFrame.

    Parameters
    ----------
    rows
        Sample rows (columns of :data:`bogie.fleet.sampling.sample.COLUMNS`), in ``sample_id`` order.
    protocols
        (name, settings) pairs, in the order their rows appear for each sample.

    Returns
    -------
    pandas.DataFrame
        ``len(rows) * len(protocols)`` rows with the columns and dtypes of
        :data:`bogie.fleet.weighing.runs.RUN_COLUMNS`. A sample that is not a valid bogie, or whose weighing fails, gets
        rows with ``status = "failed"``, the reason in ``message`` and nulls in every result column.
    """
    # the columns' Python scalars, as to_dict("records") gives them, at a third of its cost
    return runs_frame(weigh_rows({c: rows[c].tolist() for c in rows.columns}, protocols))


def chunk_table(rows: Mapping[str, Sequence], protocols: Protocols) -> pa.Table:
    """:func:`run_chunk`'s rows as the Arrow table a part file holds (:func:`pipeline.schema.table_from_rows`),
    built without pandas from the samples column by column (a :class:`pipeline.chunks.Chunk`'s ``rows``)."""
    return table_from_rows(weigh_rows(rows, protocols))


def _task(
    study: str, index: int, rows: dict[str, list], protocols: Protocols, chunk_hash_: str
) -> tuple[str, int, bytes, int, int, str]:
    """One chunk's part file as bytes, its runs and failed runs, and what computed it (:func:`process_numerics`).
    The worker encodes the file: the main process only writes it, and bytes pass between processes at the cost of a
    copy (a table's pickle cost 1 ms a chunk)."""
    numerics = process_numerics()
    table = chunk_table(rows, protocols)
    # results arrive unordered: carry the chunk's identity back with its file
    return study, index, part_content(table, chunk_hash_, numerics), len(table), failed_runs(table), numerics


# ---- running ---------------------------------------------------------------------------------------------------
#: chunks a local loky worker holds at a time, the one it weighs and the next: each result and each next chunk pass
#: through threads of the main process, which wait up to 5 ms for the interpreter lock each while the main process
#: weighs, so that a worker holding one chunk waited 12 ms for the next, 4 % of its time [-]
WORKER_CHUNKS = 2

#: what a part's task returns: study, chunk index, the part file's bytes, its runs and its failed runs, its numerics
Result = tuple[str, int, bytes, int, int, str]


def _results(chunks: Sequence[Chunk], execution: ExecutionConfig) -> Iterator[Result]:
    """Run the chunks in parallel and yield each result as soon as it is done (completion order)."""
    if execution.backend != "dask":
        yield from _local_results(chunks, execution.n_jobs)
        return
    tasks = (delayed(_task)(*_chunk_arguments(c)) for c in chunks)
    # joblib's dask backend uses every worker thread of the cluster: n_jobs does not apply; dask's nanny starts its
    # workers with OMP/MKL/OPENBLAS_NUM_THREADS=1. A chunk is seconds of work: joblib's automatic batching would
    # only coarsen the progress and the resumption
    with dask_client(execution) as client, parallel_config(backend="dask", client=client):
        yield from Parallel(return_as="generator_unordered", batch_size=1)(tasks)


def _chunk_arguments(chunk: Chunk) -> tuple:
    """The arguments of :func:`_task` for ``chunk``."""
    return chunk.study, chunk.index, chunk.rows, chunk.protocols, chunk.hash


def _local_results(chunks: Sequence[Chunk], n_jobs: int) -> Iterator[Result]:
    """The chunks on this machine, ``n_jobs - 1`` loky worker processes and this one, each result as it is done.

    The main process weighs chunks too, between writing the files (a ms a chunk): one worker fewer saves a worker's
    start-up, its imports and its compiled kernels' load (about 2 s of CPU), which the main process has paid
    already, and the main process weighs from the start while the workers start. Each worker holds
    :data:`WORKER_CHUNKS` chunks and gets the next one from loky's result thread as soon as it returns one
    (:class:`pipeline.workers.Feed`). A worker waits at most ``WORKER_IDLE_TIMEOUT`` for its next chunk, and ends
    when the main process is killed (:mod:`pipeline.workers`).
    """
    todo = collections.deque(_chunk_arguments(c) for c in chunks)
    if n_jobs <= 1:
        while todo:
            yield _task(*todo.popleft())
        return
    # an error, an interrupt or a consumer gone stops the workers at once: no chunk of theirs would be written
    yield from fed_results(_task, todo, n_jobs - 1, WORKER_CHUNKS)


class Progress:
    """A tqdm bar when stderr is a terminal; otherwise a log line every 10 % of the runs or every 30 s."""

    def __init__(
        self, total: int, log: Log, interval: float = 30.0, step: float = 0.1, stage: str = "simulate"
    ) -> None:
        self.total = total
        self.log = log
        self.interval = interval
        self.step = step
        self.done = 0
        self.start = self.last_time = time.perf_counter()
        self.last_fraction = 0.0
        self.bar = None
        if sys.stderr.isatty():
            # imported here: a worker imports this module for its task, and tqdm would add 50 ms to its start-up
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit="run", desc=stage, file=sys.stderr)

    def update(self, runs: int) -> None:
        self.done += runs
        if self.bar is not None:
            self.bar.update(runs)
            return
        now = time.perf_counter()
        fraction = self.done / self.total if self.total else 1.0
        if fraction - self.last_fraction >= self.step or now - self.last_time >= self.interval or fraction >= 1.0:
            elapsed = now - self.start
            rate = self.done / elapsed if elapsed > 0 else 0.0
            eta = (self.total - self.done) / rate if rate > 0 else 0.0
            self.log(
                f"simulate: {self.done}/{self.total} runs ({100 * fraction:.0f} %), {rate:.1f} runs/s, "
                f"{elapsed:.0f} s elapsed, about {eta:.0f} s left"
            )
            self.last_time, self.last_fraction = now, fraction

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@dataclass(frozen=True)
class Summary:
    """What one invocation did: runs and failures in the dataset, runs computed now, chunks and files, time [s]."""

    runs: int
    failed: int
    computed_runs: int
    computed_chunks: int
    skipped_chunks: int
    removed_files: int
    wall_time: float
    compile_time: float = 0.0  # of wall_time, compiling the kernels (0: they were cached) [s]

    @property
    def runs_per_second(self) -> float:
        """Computed runs per second of wall time, the compile left out [1/s] (0 if nothing was computed)."""
        running = self.wall_time - self.compile_time
        return self.computed_runs / running if self.computed_runs and running > 0 else 0.0

    def line(self) -> str:
        """The stage's closing log line."""
        compiling = f", {self.compile_time:.1f} s of it compiling" if self.compile_time else ""
        return (
            f"simulate: {self.runs} runs, {self.failed} failed; computed {self.computed_runs} runs in "
            f"{self.computed_chunks} chunks in {self.wall_time:.1f} s{compiling} ({self.runs_per_second:.1f} runs/s); "
            f"{self.skipped_chunks} chunks up to date, {self.removed_files} stale files removed"
        )


def simulate_samples(
    samples: Mapping[str, pd.DataFrame],
    protocols: Mapping[str, Protocols],
    execution: ExecutionConfig,
    out: str | Path,
    log: Log = _print,
    stage: str = "simulate",
) -> Summary:
    """Simulate the given studies into the hive-partitioned dataset ``out``, resuming from the files already there.

    Parameters
    ----------
    samples
        Sample table of each study to simulate (columns of :data:`bogie.fleet.sampling.sample.COLUMNS`). Parts of
        studies not in this mapping are deleted from ``out``.
    protocols
        The protocols of each study (:func:`study_protocols`).
    execution
        Backend, workers, chunk size and dask scheduler.
    out
        The dataset directory (``data/runs``): absent, empty, or a runs dataset the stage made
        (:func:`pipeline.chunks.check_runs_dir`).
    log
        Receives the progress and summary lines.
    stage
        The stage the lines name (``design`` runs its study through here too).

    Returns
    -------
    Summary
        The counts and timing of this invocation.

    Raises
    ------
    NotRunsDatasetError
        If ``out`` holds anything but a runs dataset of the stage; nothing is written or moved then.
    RunsLockedError
        If another process writes ``out``.
    """
    start = time.perf_counter()
    if stage != "simulate":  # the shared code's lines say "simulate:"; the stage running them is another
        log = _relabelled(log, stage)
    out = Path(out)
    check_runs_dir(out)  # before the lock: a refused folder gets no lock file beside it either
    compiling = compile_kernels(samples, protocols, log)  # before the chunks' hashes: their digest runs the kernels
    chunks = plan_chunks(samples, protocols, execution.chunk_size, out)
    with runs_lock(out):
        claim_runs_dir(out, log)
        pending, done, removed, failed_done = reconcile(chunks, out, log)
        total = sum(c.n_runs for c in pending)
        log(_plan_line(chunks, done, pending, total, execution))
        if execution.backend == "loky" and pending:
            execution = dataclasses.replace(execution, n_jobs=worker_count(execution.n_jobs, log, "simulate"))
        failed = failed_done + _run_pending(pending, execution, total, log, stage)
    summary = _summary(chunks, pending, done, removed, failed, total, time.perf_counter() - start, compiling)
    log(summary.line())
    return summary


def _summary(
    chunks: Sequence[Chunk], pending: Sequence[Chunk], done: Sequence[Chunk], removed: Sequence[Path], failed: int,
    total: int, wall_time: float, compiling: float,
) -> Summary:  # fmt: skip
    """The :class:`Summary` of one :func:`simulate_samples` invocation; ``wall_time`` and ``compiling`` in s."""
    return Summary(
        runs=sum(c.n_runs for c in chunks),
        failed=failed,
        computed_runs=total,
        computed_chunks=len(pending),
        skipped_chunks=len(done),
        removed_files=len(removed),
        wall_time=wall_time,
        compile_time=compiling,
    )


def _plan_line(
    chunks: Sequence[Chunk], done: Sequence[Chunk], pending: Sequence[Chunk], total: int, execution: ExecutionConfig
) -> str:
    """The line :func:`simulate_samples` logs before it runs: the chunks up to date, those to run, and where."""
    return (
        f"simulate: {len(chunks)} chunks of up to {execution.chunk_size} samples: {len(done)} up to date, "
        f"{len(pending)} to run ({total} runs) on {execution.backend}"
        + (f" with n_jobs={execution.n_jobs}" if execution.backend == "loky" else f" at {scheduler_text(execution)}")
    )


#: samples weighed in the main process to compile the kernels before the workers start, at most [-]
WARM_SAMPLES = 4


def compile_kernels(
    samples: Mapping[str, pd.DataFrame], protocols: Mapping[str, Protocols], log: Log
) -> float:  # fmt: skip
    """Compile the kernels, once, in this process, saying so, before anything runs them silently (issue 31: a first
    run was silent for minutes while the numerics digest of the chunks' hashes and then every worker compiled, and
    its rate and time left counted the compile).

    When numba's cache holds no ``run_phases`` of this version of the code for this clone
    (:func:`bogie.numba_cache.is_cached`), it says so, computes this process's numerics digest (which runs the
    kernels: :func:`pipeline.chunks.process_numerics`), weighs the first sample of each kind (axle group,
    suspension, study's protocols; at most :data:`WARM_SAMPLES`) of ``samples`` here, which compiles and caches
    every kernel they use, and says how long that took; the workers then load the cache. Returns the seconds spent
    (0 when the cache was there)."""
    from bogie.steel.phases import kernel_cached

    if kernel_cached():
        return 0.0
    log(
        "simulate: compiling the numba kernels for this version of the code, once (a few minutes on 2 cores; "
        "cached for every later run, and the progress below leaves it out)"
    )
    start = time.perf_counter()
    process_numerics()
    seen = set()
    for study, frame in samples.items():
        for i in range(len(frame)):
            kind = (frame["group"].iat[i], frame["suspension"].iat[i], tuple(p for p, _ in protocols[study]))
            if kind in seen or len(seen) >= WARM_SAMPLES:
                continue
            seen.add(kind)
            row = frame.iloc[i : i + 1]
            chunk_table({c: row[c].tolist() for c in COLUMNS}, protocols[study])
    seconds = time.perf_counter() - start
    log(f"simulate: kernels compiled in {seconds:.0f} s")
    return seconds


def _relabelled(log: Log, stage: str) -> Log:
    def relabelled(line: str) -> None:
        log(f"{stage}:{line.removeprefix('simulate:')}" if line.startswith("simulate:") else line)

    return relabelled


def _run_pending(
    pending: Sequence[Chunk], execution: ExecutionConfig, total: int, log: Log, stage: str = "simulate"
) -> int:
    """Compute the pending chunks, writing each part file as soon as it is done; returns the failed runs."""
    by_key = {(c.study, c.index): c for c in pending}
    failed = 0
    here = process_numerics()
    progress = Progress(total, log, stage=stage)
    try:
        for study, index, content, runs, failed_runs, numerics in _results(pending, execution) if pending else ():
            check_numerics(numerics, here, study, index)
            write_part(content, by_key[(study, index)].path)
            failed += failed_runs
            progress.update(runs)
    finally:
        progress.close()
    return failed


def read_samples(samples_dir: str | Path, studies: Sequence[str] = STUDIES) -> dict[str, pd.DataFrame]:
    """The study tables written by the sample stage, checked for the columns the simulation needs."""
    samples = {}
    for study in studies:
        path = Path(samples_dir) / f"{study}.parquet"
        frame = read_checksummed(path, "delete it and rerun the sample stage").to_pandas()
        missing = [c for c in COLUMNS if c not in frame.columns]
        if missing:
            raise ValueError(f"{path} lacks the columns {', '.join(missing)}: rerun the sample stage")
        samples[study] = frame[list(COLUMNS)].astype(COLUMNS)
    return samples


def simulate(config: Config, samples_dir: str | Path, out: str | Path, log: Log = _print) -> Summary:
    """Every study of ``samples_dir`` by its protocols into ``out`` (see :func:`simulate_samples`)."""
    samples = read_samples(samples_dir)
    protocols = {study: study_protocols(config, study) for study in samples}
    return simulate_samples(samples, protocols, config.execution, out, log)


def main(argv: list[str] | None = None) -> int:
    """Run the stage from the command line."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.simulate", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--samples", default="data/samples", help="sample tables (default: data/samples)")
    parser.add_argument("--out", default="data/runs", help="runs dataset directory (default: data/runs)")
    args = parser.parse_args(argv)
    return run_stage("simulate", parser, args, lambda own: _stage(args))


def _stage(args: argparse.Namespace) -> int:
    """Read, compile, simulate; the exit code (errors: :func:`pipeline.atomic.run_stage`'s)."""
    with stage_inputs("simulate", prefix=f"{args.params}: "):
        config = load_config(args.params)
    with stage_inputs("simulate"):
        samples = read_samples(args.samples)
    protocols = {study: study_protocols(config, study) for study in samples}
    # the compile said before the portability check, whose numerics digest would otherwise run it without a word
    compile_kernels(samples, protocols, _print)
    warn_if_unportable("simulate")
    try:
        simulate_samples(samples, protocols, config.execution, args.out)
    except (NotRunsDatasetError, RunsLockedError, OtherNumericsError, OSError) as exc:  # the runs dataset's own
        raise StageError(f"simulate: {exc}") from exc
    return 0


if __name__ == "__main__":
    # run as the module pipeline.simulate, not as __main__: the workers then import the task and their initializer by
    # name, instead of receiving a copy of their code with every chunk
    from pipeline.simulate import main as module_main

    sys.exit(module_main())
