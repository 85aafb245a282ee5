"""A worker lost mid-run (killed, out of memory, its machine gone): its tasks are given again to a fresh pool and
the results are those of an undisturbed run (issue 46 Must 4; :class:`pipeline.workers.Feed`)."""

from __future__ import annotations

import collections
import dataclasses
from concurrent.futures import BrokenExecutor

import pytest
from _dying import always_die, square_or_die
from test_observed import ROOT

from pipeline.config import load_config
from pipeline.workers import fed_results, map_ordered


def test_a_lost_workers_tasks_are_given_again_and_every_result_is_an_undisturbed_runs(tmp_path):
    marker = tmp_path / "a worker died"
    todo = collections.deque((str(marker), v) for v in range(40))
    got = sorted(fed_results(square_or_die, todo, n_workers=1, held=2))
    assert marker.exists()  # a worker did die: the test saw the retry, not a run that never lost one
    assert got == [v**2 for v in range(40)]


def test_the_calibrations_ordered_map_survives_a_lost_worker_in_order(tmp_path):
    marker = tmp_path / "a worker died"
    execution = dataclasses.replace(load_config(ROOT / "params.yaml").execution, backend="loky", n_jobs=2)
    got = map_ordered(square_or_die_at, [(str(marker), v) for v in range(30)], execution, "test")
    assert marker.exists() and got == [v**2 for v in range(30)]


def square_or_die_at(item: tuple[str, int]) -> int:
    return square_or_die(*item)


def test_a_worker_lost_every_time_stops_the_run_once_the_retries_are_spent():
    todo = collections.deque((v,) for v in range(6))
    with pytest.raises(BrokenExecutor):
        list(fed_results(always_die, todo, n_workers=1, held=1))
