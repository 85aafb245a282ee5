"""A dask cluster the usual way (issue 46 Must 4, in part): its address in params.yaml, a scheduler file, or dask's
own DASK_SCHEDULER_ADDRESS (pipeline.workers.dask_scheduler)."""

import copy
import os
from pathlib import Path

import pytest

from pipeline.config import ConfigError, load_params, parse_config
from pipeline.config.rules import DASK_ENV
from pipeline.workers import dask_scheduler, map_ordered, scheduler_text

ROOT = Path(__file__).resolve().parents[2]


def execution(scheduler, backend="dask"):
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["execution"].update(backend=backend, dask_scheduler=scheduler)
    return parse_config(raw).execution


def test_an_address_a_scheduler_file_or_the_variable(monkeypatch, tmp_path):
    assert dask_scheduler(execution("tcp://10.0.0.5:8786")) == {"address": "tcp://10.0.0.5:8786"}
    monkeypatch.setenv(DASK_ENV, "tcp://10.0.0.6:8786")
    null = execution(None)  # accepted: the variable is set
    assert dask_scheduler(null) == {"address": "tcp://10.0.0.6:8786"}
    assert scheduler_text(null) == f"tcp://10.0.0.6:8786 ({DASK_ENV})"
    file = tmp_path / "scheduler.json"
    file.write_text('{"address": "tcp://10.0.0.7:8786"}')
    monkeypatch.chdir(tmp_path)  # relative to the working directory: the project root under DVC
    assert dask_scheduler(execution("scheduler.json")) == {"scheduler_file": "scheduler.json"}
    # params.yaml's own value comes first, the variable only for null
    assert dask_scheduler(execution("tcp://10.0.0.5:8786")) == {"address": "tcp://10.0.0.5:8786"}


def test_no_scheduler_at_all_or_a_missing_file_is_refused_naming_the_key(monkeypatch, tmp_path):
    monkeypatch.delenv(DASK_ENV, raising=False)
    with pytest.raises(
        ConfigError, match=f"execution.dask_scheduler = None: backend dask needs the scheduler.*{DASK_ENV}"
    ):
        execution(None)
    monkeypatch.chdir(tmp_path)
    missing = r"'run/scheduler.json': no such scheduler file \(looked for .*run/scheduler.json\); start the scheduler"
    with pytest.raises(ConfigError, match=missing + " with dask scheduler --scheduler-file run/scheduler.json"):
        dask_scheduler(execution("run/scheduler.json"))
    # an address without its scheme is not taken for a file: only a path ending in .json is one
    with pytest.raises(ConfigError, match="execution.dask_scheduler.*'localhost:8786'.*ending in .json"):
        execution("localhost:8786")


@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster

    # two workers: joblib's dask backend runs the tasks in the calling process when the cluster has one thread in all
    # (its effective n_jobs is the cluster's threads, and one is joblib's sequential case)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as made:  # fmt: skip
        yield made


def test_the_work_runs_on_the_cluster_of_a_scheduler_file_and_of_the_variable(cluster, monkeypatch, tmp_path):
    from dask.distributed import Client

    with Client(cluster.scheduler_address) as client:
        client.write_scheduler_file(str(tmp_path / "scheduler.json"))
    monkeypatch.chdir(tmp_path)
    items = [-3, 1, -2]
    assert map_ordered(abs, items, execution("scheduler.json"), "a test") == [3, 1, 2]
    monkeypatch.setenv(DASK_ENV, cluster.scheduler_address)
    assert map_ordered(abs, items, execution(None), "a test") == [3, 1, 2]
    # on the cluster's workers, not in this process
    assert os.getpid() not in map_ordered(worker_pid, items, execution(None), "a test")


def worker_pid(_item) -> int:
    return os.getpid()


def test_a_lost_dask_worker_is_replaced_and_its_tasks_give_an_undisturbed_runs_results(cluster, tmp_path):
    # dask's nanny restarts the killed worker and the scheduler gives its tasks again (dask's allowed-failures, 3);
    # the results are an undisturbed run's, in order (issue 46 Must 4). Last in this file: it kills the module's worker
    from test_lost_worker import square_or_die_at

    marker = tmp_path / "a worker died"
    got = map_ordered(square_or_die_at, [(str(marker), v) for v in range(12)], execution(cluster.scheduler_address),
                      "a test")  # fmt: skip
    assert marker.exists() and got == [v**2 for v in range(12)]
