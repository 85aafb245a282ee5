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
import os
import queue
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Future
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import yaml
from joblib import Parallel, delayed, parallel_config
from joblib.externals.loky import get_reusable_executor

from bogie.fleet.sampling import COLUMNS
from bogie.fleet.weighing import weigh_rows
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
from pipeline.config import Config, ConfigError, ExecutionConfig, load_config
from pipeline.portable import warn_if_unportable
from pipeline.resources import worker_count
from pipeline.sample import STUDIES
from pipeline.schema import failed_runs, runs_frame, table_from_rows


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
        Sample rows (columns of :data:`bogie.fleet.sampling.COLUMNS`), in ``sample_id`` order.
    protocols
        (name, settings) pairs, in the order their rows appear for each sample.

    Returns
    -------
    pandas.DataFrame
        ``len(rows) * len(protocols)`` rows with the columns and dtypes of :data:`bogie.fleet.runs.RUN_COLUMNS`.
        A sample that is not a valid bogie, or whose weighing fails, gets rows with ``status = "failed"``, the
        reason in ``message`` and nulls in every result column.
    """
    # the columns' Python scalars, as to_dict("records") gives them, at a third of its cost
    return runs_frame(weigh_rows({c: rows[c].tolist() for c in rows.columns}, protocols))


def chunk_table(rows: Mapping[str, Sequence], protocols: Protocols) -> pa.Table:
    """:func:`run_chunk`'s rows as the Arrow table a part file holds (:func:`pipeline.schema.table_from_rows`),
    built without pandas from the samples column by column (a :class:`pipeline.chunks.Chunk`'s ``rows``)."""
    return table_from_rows(weigh_rows(rows, protocols))


#: how often a loky worker looks whether the main process that started it still runs [s]
MAIN_PROCESS_POLL = 1.0


def _watch_main_process(main_pid: int) -> None:
    """A local loky worker's initializer: end the worker within :data:`MAIN_PROCESS_POLL` of the end of its parent,
    the main process ``main_pid`` (at once if it ended while the worker started).

    Once the main process is killed nothing reads the pipe the results go back through, and a worker blocks for
    ever writing its chunk's result as soon as the pipe's 64 KiB buffer is full (two chunks of 64 samples fill it),
    whatever WORKER_IDLE_TIMEOUT says; a worker still starting would weigh the chunks queued for it first.
    """

    def watch() -> None:
        while os.getppid() == main_pid:
            time.sleep(MAIN_PROCESS_POLL)
        os._exit(1)  # the chunk in hand is lost with the main process that would have written it

    threading.Thread(target=watch, name="watch-main-process", daemon=True).start()


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


class OtherNumericsError(RuntimeError):
    """A worker computes other last bits than the main process: its part is not written."""


def check_numerics(worker: str, here: str, study: str, index: int) -> None:
    """Refuse a chunk computed by a worker whose numerics (:func:`process_numerics`) are not this process's.

    Raises
    ------
    OtherNumericsError
        Naming both and what to do.
    """
    if worker != here:
        raise OtherNumericsError(
            f"the worker that weighed chunk {index} of study {study} computes other last bits than this process "
            f"(numerics digest and compile target {worker!r} there, {here!r} here): its part is not written. Run "
            "the workers on x86-64 machines with AVX2 and FMA and the versions of constraints.txt, and import no "
            "numba-compiled code before bogie in them (docs/architecture.md, 'The same bits on every machine')"
        )


# ---- running ---------------------------------------------------------------------------------------------------
#: how long an idle loky worker waits for work before it ends [s]: long enough that a worker never times out
#: while chunks are still coming (10 s did, once, on a loaded machine: loky then restarts it with a warning),
#: short enough that an idle worker does not outlive its main process by loky's default 300 s (a killed main process's
#: workers end sooner: :func:`_watch_main_process`)
WORKER_IDLE_TIMEOUT = 30.0

#: chunks a local loky worker holds at a time, the one it weighs and the next: each result and each next chunk pass
#: through threads of the main process, which wait up to 5 ms for the interpreter lock each while the main process
#: weighs, so that a worker holding one chunk waited 12 ms for the next, 4 % of its time [-]
WORKER_CHUNKS = 2

#: what a part's task returns: study, chunk index, the part file's bytes, its runs and its failed runs, its numerics
Result = tuple[str, int, bytes, int, int, str]

#: the environment of a loky worker: one thread in every threaded library (what joblib's loky backend sets with
#: inner_max_num_threads=1), so that n_jobs processes keep n_jobs cores busy and no more
ONE_THREAD_ENV: dict[str, str] = dict.fromkeys(
    ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS",
     "NUMBA_NUM_THREADS", "NUMEXPR_NUM_THREADS"), "1"
)  # fmt: skip


def _results(chunks: Sequence[Chunk], execution: ExecutionConfig) -> Iterator[Result]:
    """Run the chunks in parallel and yield each result as soon as it is done (completion order)."""
    if execution.backend != "dask":
        yield from _local_results(chunks, execution.n_jobs)
        return
    from dask.distributed import Client

    tasks = (delayed(_task)(c.study, c.index, c.rows, c.protocols, c.hash) for c in chunks)
    # joblib's dask backend uses every worker thread of the cluster: n_jobs does not apply; dask's nanny starts its
    # workers with OMP/MKL/OPENBLAS_NUM_THREADS=1. A chunk is seconds of work: joblib's automatic batching would
    # only coarsen the progress and the resumption
    with Client(execution.dask_scheduler) as client, parallel_config(backend="dask", client=client):
        yield from Parallel(return_as="generator_unordered", batch_size=1)(tasks)


def local_executor(max_workers: int) -> Any:
    """The one pool of local loky worker processes every stage that weighs uses (simulate's chunks, the calibration's
    table): one thread each (:data:`ONE_THREAD_ENV`), ended with the main process (:func:`_watch_main_process`), an
    idle one after :data:`WORKER_IDLE_TIMEOUT`. loky's reusable executor: a second stage in the same process (a test
    session) gets the same pool, resized, and never one that joblib's ``Parallel`` set up otherwise."""
    return get_reusable_executor(
        max_workers=max_workers, timeout=WORKER_IDLE_TIMEOUT, env=ONE_THREAD_ENV,
        initializer=_watch_main_process, initargs=(os.getpid(),),
    )  # fmt: skip


def _numbered(func: Callable[[Any], Any], item: Any) -> tuple[Any, str]:
    """``func(item)`` and the numerics of the process that computed it (:func:`process_numerics`)."""
    return func(item), process_numerics()


def map_ordered(func: Callable[[Any], Any], items: Sequence[Any], execution: ExecutionConfig, what: str) -> list:
    """``[func(item) for item in items]`` on the workers of ``execution``, in the items' order: simulate's pool of
    loky workers on this machine (:func:`local_executor`, ``n_jobs`` capped as simulate's), or the dask.distributed
    cluster at ``execution.dask_scheduler``, whose every result is checked to come from a worker with this process's
    numerics (:func:`check_numerics`, ``what`` naming the work in the message). The one executor of the stages that
    weigh besides simulate's chunks (the calibration's table)."""
    if execution.backend == "dask":
        from dask.distributed import Client

        here = process_numerics()
        with Client(execution.dask_scheduler) as client, parallel_config(backend="dask", client=client):
            done = Parallel(batch_size=1)(delayed(_numbered)(func, item) for item in items)
        for index, (_, numerics) in enumerate(done):
            check_numerics(numerics, here, what, index)
        return [value for value, _ in done]
    if execution.n_jobs <= 1:
        return [func(item) for item in items]
    return list(local_executor(execution.n_jobs).map(func, items))


def _local_results(chunks: Sequence[Chunk], n_jobs: int) -> Iterator[Result]:
    """The chunks on this machine, ``n_jobs - 1`` loky worker processes and this one, each result as it is done.

    The main process weighs chunks too, between writing the files (a ms a chunk): one worker fewer saves a worker's
    start-up, its imports and its compiled kernels' load (about 2 s of CPU), which the main process has paid
    already, and the main process weighs from the start while the workers start. Each worker holds
    :data:`WORKER_CHUNKS` chunks and gets the next one from loky's result thread as soon as it returns one. A worker
    waits at most WORKER_IDLE_TIMEOUT for its next chunk, and ends when the main process is killed
    (:func:`_watch_main_process`).
    """
    todo = collections.deque(chunks)

    def arguments(chunk: Chunk) -> tuple:
        return chunk.study, chunk.index, chunk.rows, chunk.protocols, chunk.hash

    if n_jobs <= 1:
        while todo:
            yield _task(*arguments(todo.popleft()))
        return
    executor = local_executor(n_jobs - 1)
    returned: queue.SimpleQueue = queue.SimpleQueue()  # the workers' done futures, or an error of a submission
    lock = threading.Lock()  # over todo and in_flight, shared with loky's result thread
    in_flight = 0

    def send_next(done: Future | None = None) -> None:
        nonlocal in_flight
        if done is not None:
            returned.put(done)
        with lock:
            if not todo:
                return
            chunk = todo.popleft()
            in_flight += 1
        try:
            executor.submit(_task, *arguments(chunk)).add_done_callback(send_next)
        except BaseException as exc:  # noqa: BLE001 - a broken or shut down pool: the main thread raises it
            returned.put(exc)

    def take(item: Future | BaseException) -> Result:
        nonlocal in_flight
        with lock:
            in_flight -= 1
        if isinstance(item, BaseException):
            raise item
        return item.result()

    try:
        for _ in range(WORKER_CHUNKS * (n_jobs - 1)):
            send_next()
        while True:
            while not returned.empty():
                yield take(returned.get())
            with lock:
                chunk = todo.popleft() if todo else None
            if chunk is None:
                break
            yield _task(*arguments(chunk))
        while True:
            with lock:
                if not in_flight:
                    break
            yield take(returned.get())
    except BaseException:
        # an error, an interrupt or a consumer gone: no chunk of the workers would be written, stop them now
        executor.shutdown(wait=False, kill_workers=True)
        raise


class Progress:
    """A tqdm bar when stderr is a terminal; otherwise a log line every 10 % of the runs or every 30 s."""

    def __init__(self, total: int, log: Log, interval: float = 30.0, step: float = 0.1) -> None:
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

            self.bar = tqdm(total=total, unit="run", desc="simulate", file=sys.stderr)

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

    @property
    def runs_per_second(self) -> float:
        """Computed runs per second of wall time [1/s] (0 if nothing was computed)."""
        return self.computed_runs / self.wall_time if self.computed_runs and self.wall_time > 0 else 0.0

    def line(self) -> str:
        """The stage's closing log line."""
        return (
            f"simulate: {self.runs} runs, {self.failed} failed; computed {self.computed_runs} runs in "
            f"{self.computed_chunks} chunks in {self.wall_time:.1f} s ({self.runs_per_second:.1f} runs/s); "
            f"{self.skipped_chunks} chunks up to date, {self.removed_files} stale files removed"
        )


def simulate_samples(
    samples: Mapping[str, pd.DataFrame],
    protocols: Mapping[str, Protocols],
    execution: ExecutionConfig,
    out: str | Path,
    log: Log = _print,
) -> Summary:
    """Simulate the given studies into the hive-partitioned dataset ``out``, resuming from the files already there.

    Parameters
    ----------
    samples
        Sample table of each study to simulate (columns of :data:`bogie.fleet.sampling.COLUMNS`). Parts of studies not
        in this mapping are deleted from ``out``.
    protocols
        The protocols of each study (:func:`study_protocols`).
    execution
        Backend, workers, chunk size and dask scheduler.
    out
        The dataset directory (``data/runs``): absent, empty, or a runs dataset the stage made
        (:func:`pipeline.chunks.check_runs_dir`).
    log
        Receives the progress and summary lines.

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
    out = Path(out)
    check_runs_dir(out)  # before the lock: a refused folder gets no lock file beside it either
    chunks = plan_chunks(samples, protocols, execution.chunk_size, out)
    with runs_lock(out):
        claim_runs_dir(out, log)
        pending, done, removed, failed_done = reconcile(chunks, out, log)
        total = sum(c.n_runs for c in pending)
        log(
            f"simulate: {len(chunks)} chunks of up to {execution.chunk_size} samples: {len(done)} up to date, "
            f"{len(pending)} to run ({total} runs) on {execution.backend}"
            + (f" with n_jobs={execution.n_jobs}" if execution.backend == "loky" else f" at {execution.dask_scheduler}")
        )
        if execution.backend == "loky" and pending:
            execution = dataclasses.replace(execution, n_jobs=worker_count(execution.n_jobs, log, "simulate"))
        failed = failed_done + _run_pending(pending, execution, total, log)
    summary = Summary(
        runs=sum(c.n_runs for c in chunks),
        failed=failed,
        computed_runs=total,
        computed_chunks=len(pending),
        skipped_chunks=len(done),
        removed_files=len(removed),
        wall_time=time.perf_counter() - start,
    )
    log(summary.line())
    return summary


def _run_pending(pending: Sequence[Chunk], execution: ExecutionConfig, total: int, log: Log) -> int:
    """Compute the pending chunks, writing each part file as soon as it is done; returns the failed runs."""
    by_key = {(c.study, c.index): c for c in pending}
    failed = 0
    here = process_numerics()
    progress = Progress(total, log)
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
        frame = pd.read_parquet(path)
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
    warn_if_unportable("simulate")
    try:
        config = load_config(args.params)
    except (ConfigError, OSError, yaml.YAMLError) as exc:
        print(f"simulate: {args.params}: {exc}", file=sys.stderr)
        return 2
    try:
        samples = read_samples(args.samples)
    except (OSError, ValueError) as exc:
        print(f"simulate: {exc}", file=sys.stderr)
        return 2
    protocols = {study: study_protocols(config, study) for study in samples}
    try:
        simulate_samples(samples, protocols, config.execution, args.out)
    except (NotRunsDatasetError, RunsLockedError, OtherNumericsError, OSError) as exc:
        print(f"simulate: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    # run as the module pipeline.simulate, not as __main__: the workers then import the task and their initializer by
    # name, instead of receiving a copy of their code with every chunk
    from pipeline.simulate import main as module_main

    sys.exit(module_main())
