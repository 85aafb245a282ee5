"""The worker processes of the stages that weigh: the local pool of loky workers, the dask cluster, the check that
a worker computes this process's last bits, and the feeding of a local pool a few tasks at a time.

:mod:`pipeline.simulate` runs its chunks on them (:class:`Feed` on this machine) and the calibrate stage its table
(:func:`map_ordered`): one pool of one-thread workers (:func:`local_executor`), ended with the main process.
"""

from __future__ import annotations

import collections
import os
import queue
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import BrokenExecutor, Future
from typing import Any

from joblib import Parallel, delayed, parallel_config
from joblib.externals.loky import get_reusable_executor

from pipeline.chunks import process_numerics
from pipeline.config import ExecutionConfig
from pipeline.config.errors import ConfigError
from pipeline.config.rules import DASK_ENV, DASK_MISSING

#: how often a loky worker looks whether the main process that started it still runs [s]
MAIN_PROCESS_POLL = 1.0

#: how long an idle loky worker waits for work before it ends [s]: long enough that a worker never times out
#: while chunks are still coming (10 s did, once, on a loaded machine: loky then restarts it with a warning),
#: short enough that an idle worker does not outlive its main process by loky's default 300 s (a killed main process's
#: workers end sooner: :func:`_watch_main_process`)
WORKER_IDLE_TIMEOUT = 30.0

#: the environment of a loky worker: one thread in every threaded library (what joblib's loky backend sets with
#: inner_max_num_threads=1), so that n_jobs processes keep n_jobs cores busy and no more
ONE_THREAD_ENV: dict[str, str] = dict.fromkeys(
    ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS",
     "NUMBA_NUM_THREADS", "NUMEXPR_NUM_THREADS"), "1"
)  # fmt: skip


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


def local_executor(max_workers: int) -> Any:
    """The one pool of local loky worker processes every stage that weighs uses (simulate's chunks, the calibration's
    table): one thread each (:data:`ONE_THREAD_ENV`), ended with the main process (:func:`_watch_main_process`), an
    idle one after :data:`WORKER_IDLE_TIMEOUT`. loky's reusable executor: a second stage in the same process (a test
    session) gets the same pool, resized, and never one that joblib's ``Parallel`` set up otherwise."""
    return get_reusable_executor(
        max_workers=max_workers, timeout=WORKER_IDLE_TIMEOUT, env=ONE_THREAD_ENV,
        initializer=_watch_main_process, initargs=(os.getpid(),),
    )  # fmt: skip


def dask_scheduler(execution: ExecutionConfig) -> dict[str, str]:
    """Where the dask cluster of ``execution`` is, as ``dask.distributed.Client``'s keyword: ``{"address": ...}`` from
    ``execution.dask_scheduler`` or, when that is null, from ``DASK_SCHEDULER_ADDRESS`` (dask's own variable,
    :data:`~pipeline.config.rules.DASK_ENV`); ``{"scheduler_file": ...}`` for a path ending in ``.json`` (the file
    ``dask scheduler --scheduler-file`` writes, relative to the working directory: the project root under DVC).

    Raises
    ------
    ConfigError
        Naming ``execution.dask_scheduler``: none given and the variable unset, or a scheduler file that is not
        there (the scheduler not started yet, or another path)."""
    given = execution.dask_scheduler
    if given is None:
        address = os.environ.get(DASK_ENV, "").strip()
        if not address:
            raise ConfigError("execution.dask_scheduler", f"execution.dask_scheduler = None: {DASK_MISSING}")
        return {"address": address}
    if "://" in given:
        return {"address": given}
    if not os.path.isfile(given):
        raise ConfigError("execution.dask_scheduler", f"execution.dask_scheduler = {given!r}: no such scheduler file "
                          f"(looked for {os.path.abspath(given)}); start the scheduler with dask scheduler "
                          f"--scheduler-file {given}, or give its address")  # fmt: skip
    return {"scheduler_file": given}


def dask_client(execution: ExecutionConfig) -> Any:
    """A ``dask.distributed.Client`` of the cluster :func:`dask_scheduler` names."""
    from dask.distributed import Client

    return Client(**dask_scheduler(execution))


def scheduler_text(execution: ExecutionConfig) -> str:
    """Where the dask cluster is, in words, for the stages' lines."""
    given = execution.dask_scheduler
    if given is None:
        return f"{os.environ.get(DASK_ENV, '').strip()} ({DASK_ENV})"
    return given if "://" in given else f"the scheduler of {given}"


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
        here = process_numerics()
        with dask_client(execution) as client, parallel_config(backend="dask", client=client):
            done = Parallel(batch_size=1)(delayed(_numbered)(func, item) for item in items)
        for index, (_, numerics) in enumerate(done):
            check_numerics(numerics, here, what, index)
        return [value for value, _ in done]
    if execution.n_jobs <= 1:
        return [func(item) for item in items]
    done = dict(fed_results(_indexed, collections.deque((func, k, item) for k, item in enumerate(items)),
                            execution.n_jobs - 1))  # fmt: skip
    return [done[k] for k in range(len(items))]


def _indexed(func: Callable[[Any], Any], index: int, item: Any) -> tuple[int, Any]:
    """``(index, func(item))``: a result that arrives out of order with its place."""
    return index, func(item)


def fed_results(task: Callable[..., Any], todo: collections.deque, n_workers: int, held: int = 2) -> Iterator[Any]:
    """``task(*arguments)`` of each of ``todo``, each as it is done, on ``n_workers`` local loky workers (each fed
    ``held`` tasks at a time, :class:`Feed`, a lost worker's tasks given again) and this process, which runs the
    tasks no worker has taken yet. On an error, an interrupt or a consumer gone, the workers are stopped at once."""
    feed = Feed(lambda: local_executor(n_workers), task, todo)
    try:
        for _ in range(held * n_workers):
            feed.send_next()
        while True:
            yield from feed.done_now()
            arguments = feed.next_here()
            if arguments is None:
                break
            yield task(*arguments)
        yield from feed.the_rest()
    except BaseException:
        feed.executor.shutdown(wait=False, kill_workers=True)
        raise


#: how many times a task whose worker was lost (killed, out of memory, its machine gone) is given to a fresh pool
#: before the stage stops with the error [-]: the task is a pure function of its arguments, so the retry computes the
#: same bits (``tests/pipeline/test_lost_worker.py``). The number is a choice, not a sourced figure: enough for a
#: worker killed once, few enough that a task that kills every worker it meets stops the stage soon (dask's own
#: default, ``distributed.scheduler.allowed-failures``, is 3)
LOST_WORKER_RETRIES = 2


class Feed:
    """Tasks ``task(*arguments)`` fed to a local pool of loky workers a few at a time, the rest left to the caller.

    The caller primes the pool with a few tasks per worker (:meth:`send_next` each); then a worker gets its next
    task from loky's result thread as soon as it returns one, so it never waits for the main process. The main
    process runs the tasks no worker has taken yet itself (:meth:`next_here`) and collects the workers' results as
    they are done (:meth:`done_now`, then :meth:`the_rest`).

    **A lost worker** (issue 46 Must 4): loky then breaks the pool, and every task in the workers' hands fails with
    :class:`concurrent.futures.BrokenExecutor`. Each such task is given again, to a fresh pool (``make_executor``
    called again: loky's reusable executor replaces a broken one), up to :data:`LOST_WORKER_RETRIES` times; its result
    is the one an undisturbed run gives. Any other error of a task stops the run as before.
    """

    def __init__(self, make_executor: Callable[[], Any], task: Callable[..., Any], todo: collections.deque) -> None:
        self.make_executor = make_executor
        self.executor = make_executor()
        self.task = task
        self.todo = todo  # argument tuples not yet taken, by a worker or by the main process
        # (arguments, done future or a submission's error) of each task the workers were given
        self.returned: queue.SimpleQueue = queue.SimpleQueue()
        self.lock = threading.Lock()  # over todo and in_flight, shared with loky's result thread
        self.in_flight = 0
        self.retried: collections.Counter = collections.Counter()  # by id of the arguments: the same tuple again
        self.lost = 0  # tasks given again after their worker was lost

    def send_next(self) -> None:
        """Give the pool the next task, if one is left."""
        with self.lock:
            if not self.todo:
                return
            arguments = self.todo.popleft()
            self.in_flight += 1
        self._submit(arguments)

    def _submit(self, arguments: tuple) -> None:
        try:
            future = self.executor.submit(self.task, *arguments)
        except BaseException as exc:  # noqa: BLE001 - a broken or shut down pool: the main thread sees it
            self.returned.put((arguments, exc))
            return
        future.add_done_callback(lambda done: self._done(arguments, done))

    def _done(self, arguments: tuple, done: Future) -> None:
        """loky's result thread: queue a worker's finished task and give the pool the next one."""
        self.returned.put((arguments, done))
        self.send_next()

    def _take(self, item: tuple[tuple, Future | BaseException]) -> tuple[bool, Any]:
        """(True, the task's result), or (False, None) for a task given again after its worker was lost."""
        arguments, outcome = item
        with self.lock:
            self.in_flight -= 1
        error = outcome if isinstance(outcome, BaseException) else outcome.exception()
        if error is None:
            return True, outcome.result()
        if not isinstance(error, BrokenExecutor) or self.retried[id(arguments)] >= LOST_WORKER_RETRIES:
            raise error
        self.retried[id(arguments)] += 1
        self.lost += 1
        self.executor = self.make_executor()  # a fresh pool for a broken one
        with self.lock:
            self.in_flight += 1
        self._submit(arguments)
        return False, None

    def done_now(self) -> Iterator[Any]:
        """The results the workers have returned so far."""
        while not self.returned.empty():
            ok, result = self._take(self.returned.get())
            if ok:
                yield result

    def next_here(self) -> tuple | None:
        """The next task's arguments for the main process to run itself, or None when every task is taken."""
        with self.lock:
            return self.todo.popleft() if self.todo else None

    def the_rest(self) -> Iterator[Any]:
        """The results of the tasks still in the workers' hands, each as it is done."""
        while True:
            with self.lock:
                if not self.in_flight:
                    return
            ok, result = self._take(self.returned.get())
            if ok:
                yield result
