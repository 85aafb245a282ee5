"""The ``simulate`` stage's cost outside the weighings, against a previous revision measured in the same run.

``python -m bench.bench_stage_overhead [--base REV] [--repeats N]`` runs the default params.yaml's studies (15 608
runs in chunks of ``execution.chunk_size``) through :func:`pipeline.simulate.simulate_samples` with
:func:`bogie.fleet.weighing.weigher.weigh` replaced by a stub that returns a precomputed valid row, so that only the
stage's own work runs: planning and hashing the chunks, building each chunk's rows (``bogie_from_sample`` included),
passing them between processes, writing and checking the part files, and verifying them on a rerun. Each measurement is
a fresh process (the stub is installed in it and in its loky workers by a ``sitecustomize`` module), alternately for
the base revision (its ``pipeline`` and ``bogie`` exported with ``git archive``) and for this checkout; the best of
``--repeats`` is kept, as the machine is shared. The machine's load average is printed with the figures.

What the lines mean:

* ``n_jobs=1``: in-process (joblib's sequential backend), each part timed: ``plan`` (the code version, the chunks'
  slices and hashes), ``bogie_from_sample``, ``weigh (stub)``, ``the rest of a task`` (the sample rows read, the
  result rows built and typed; the new code checks and encodes the part file here, in the worker), ``write_part``
  (the main process; the base code checked and encoded the file there), ``the rest`` (reconcile, progress, counts).
* ``rerun``: a second run on the complete dataset: every file's hash read and its pages verified, nothing computed.
* ``n_jobs=2``: as the stage runs on this machine: wall time, the main process's CPU time and the loky workers'
  (start-up included: interpreter, imports; the stub loads no compiled kernel). The base runs two workers beside an
  idle main process, the new code one worker beside a main process that weighs chunks too.
* ``worker start-up`` (this checkout only: the base's copy would compile the kernels anew): a fresh process's
  import of ``pipeline.simulate`` and its first weighing of each group and protocol beyond a second one (the
  cached compiled kernels loaded), real weighings.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: the revision before the stage's overhead work (branch stage-overhead forks from it)
BASE = "b59bc51"

#: installed in every process of a measurement (main and loky workers) through PYTHONPATH
SITECUSTOMIZE = """
import os

if os.environ.get("BENCH_STUB_WEIGH"):
    import numpy as np

    import bogie.fleet.weighing.weigher as protocol

    _ROWS = {}

    def _stub(bogie, sample, name, spec):
        key = (name, int(sample["n_axles"]))
        if key not in _ROWS:
            loads = np.linspace(40000.0, 38000.0, key[1])
            _ROWS[key] = {**protocol.result_row(name, key[1], loads, 0.001), "status": "ok", "message": "ok"}
        return dict(_ROWS[key])

    protocol.weigh = _stub  # weigh_rows calls it from its own module
"""


def _child_samples():
    from pipeline.config import load_config
    from pipeline.sample import sample_studies
    from pipeline.simulate import study_protocols

    config = load_config(ROOT / "params.yaml")
    samples = sample_studies(config)
    return config, samples, {study: study_protocols(config, study) for study in samples}


def _child_serial(out: Path) -> dict:
    """n_jobs = 1, each part timed, then a rerun on the complete dataset."""
    import dataclasses

    import pipeline.simulate as sim

    config, samples, protocols = _child_samples()
    times: dict[str, float] = {}

    def timed(name, function):
        def wrapper(*args, **kwargs):
            start = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                times[name] = times.get(name, 0.0) + time.process_time() - start

        return wrapper

    for name in ("plan_chunks", "reconcile", "_task", "write_part", "bogie_from_sample", "weigh"):
        setattr(sim, name, timed(name, getattr(sim, name)))
    execution = dataclasses.replace(config.execution, n_jobs=1)
    start, cpu = time.perf_counter(), time.process_time()
    summary = sim.simulate_samples(samples, protocols, execution, out, log=lambda line: None)
    first = {"wall": time.perf_counter() - start, "cpu": time.process_time() - cpu, **times}
    times.clear()
    start, cpu = time.perf_counter(), time.process_time()
    sim.simulate_samples(samples, protocols, execution, out, log=lambda line: None)
    rerun = {"wall": time.perf_counter() - start, "cpu": time.process_time() - cpu, **times}
    return {"chunks": summary.computed_chunks, "runs": summary.runs, "first": first, "rerun": rerun}


def _child_loky(out: Path) -> dict:
    """n_jobs = 2 (loky): wall time, main and worker CPU time."""
    import dataclasses
    import resource

    from joblib.externals.loky import reusable_executor

    import pipeline.simulate as sim

    config, samples, protocols = _child_samples()
    execution = dataclasses.replace(config.execution, backend="loky", n_jobs=2)
    start, cpu = time.perf_counter(), time.process_time()
    sim.simulate_samples(samples, protocols, execution, out, log=lambda line: None)
    wall, main_cpu = time.perf_counter() - start, time.process_time() - cpu
    # the workers' CPU time counts once they have ended and been reaped
    reusable_executor._executor.shutdown(wait=True)
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return {"wall": wall, "main_cpu": main_cpu, "workers_cpu": usage.ru_utime + usage.ru_stime}


def _child_import() -> dict:
    start = time.process_time()
    import pipeline.simulate  # noqa: F401

    return {"import": time.process_time() - start}


def _child_startup() -> dict:
    """A fresh worker's imports and first weighings (real ones), beyond a second weighing of each kind [s]."""
    result = _child_import()
    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.fleet.weighing.weigher import weigh

    config, samples, protocols = _child_samples()
    fleet = samples["fleet"]
    for group in ("tandem", "triaxle"):
        first, second = fleet[fleet["group"] == group].head(2).to_dict("records")
        for name, spec in protocols["fleet"]:
            elapsed = []
            for sample in (first, second):
                bogie = bogie_from_sample(sample)
                start = time.process_time()
                weigh(bogie, sample, name, spec)
                elapsed.append(time.process_time() - start)
            result[f"first {group} {name}"] = elapsed[0] - elapsed[1]
    return result


def _run_child(root: Path, site: Path, mode: str, stub: bool) -> dict:
    env = {**os.environ, "PYTHONPATH": f"{site}{os.pathsep}{root}", "PYTHONSAFEPATH": "1"}
    env.pop("BENCH_STUB_WEIGH", None)
    if stub:
        env["BENCH_STUB_WEIGH"] = "1"
    with tempfile.TemporaryDirectory() as tmp:
        command = [sys.executable, str(Path(__file__).resolve()), "--child", mode, "--out", str(Path(tmp) / "runs")]
        done = subprocess.run(command, cwd=root, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{mode} in {root} failed:\n{done.stderr}")
    return json.loads(done.stdout.splitlines()[-1])


def _export(revision: str, into: Path) -> Path:
    """The base revision's ``pipeline`` and ``bogie`` in ``into`` (both run this checkout's params.yaml)."""
    archive = subprocess.run(
        ["git", "archive", revision, "pipeline", "bogie"], cwd=ROOT, capture_output=True, check=True
    ).stdout
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(into, filter="data")
    return into


def _load() -> str:
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def _row(name: str, base: float, new: float, chunks: int) -> str:
    ratio = f"{new / base:.2f}" if base > 0 else "-"
    return f"| {name} | {1000 * base / chunks:.2f} | {1000 * new / chunks:.2f} | {base:.3f} | {new:.3f} | {ratio} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default=BASE, help=f"revision to compare with (default {BASE})")
    parser.add_argument("--repeats", type=int, default=2, help="fresh processes per setting; the best is kept")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        children = {
            "serial": lambda: _child_serial(Path(args.out)),
            "loky": lambda: _child_loky(Path(args.out)),
            "import": _child_import,
            "startup": _child_startup,
        }
        print(json.dumps(children[args.child]()))
        return

    print(f"{_load()} at the start; base {args.base} against this checkout ({ROOT})")
    with tempfile.TemporaryDirectory() as tmp:
        site = Path(tmp) / "site"
        site.mkdir()
        (site / "sitecustomize.py").write_text(SITECUSTOMIZE)
        roots = {"base": _export(args.base, Path(tmp) / "base"), "new": ROOT}
        results: dict[str, dict[str, list[dict]]] = {v: {} for v in roots}
        for _ in range(args.repeats):
            for mode, stub in (("serial", True), ("loky", True), ("import", False)):
                for version, root in roots.items():  # alternately, so that both see the same load
                    results[version].setdefault(mode, []).append(_run_child(root, site, mode, stub))
        startup = _run_child(ROOT, site, "startup", False)

    def best(version: str, mode: str, key) -> dict:
        return min(results[version][mode], key=key)

    serial = {v: best(v, "serial", lambda r: r["first"]["cpu"]) for v in roots}
    chunks, runs = serial["new"]["chunks"], serial["new"]["runs"]
    print(f"\n{runs} runs in {chunks} chunks, weigh stubbed; CPU time, best of {args.repeats}; ratio new / base")
    print("\n| n_jobs=1, in-process | base ms/chunk | new ms/chunk | base s | new s | ratio |")
    print("|---|---|---|---|---|---|")
    parts = {}
    for v in roots:
        first = serial[v]["first"]
        task = first["_task"] - first["bogie_from_sample"] - first["weigh"]
        parts[v] = {
            "plan (code version, slices, hashes)": first["plan_chunks"],
            "bogie_from_sample": first["bogie_from_sample"],
            "weigh (stub)": first["weigh"],
            "the rest of a task": task,
            "write_part (main process)": first["write_part"],
            "the rest (reconcile, progress, counts)": first["cpu"]
            - first["plan_chunks"]
            - first["_task"]
            - first["write_part"],
            "**total**": first["cpu"],
        }
    for name in parts["new"]:
        print(_row(name, parts["base"][name], parts["new"][name], chunks))
    print(_row("wall time", serial["base"]["first"]["wall"], serial["new"]["first"]["wall"], chunks))
    rerun = {v: best(v, "serial", lambda r: r["rerun"]["cpu"])["rerun"] for v in roots}
    print(_row("rerun, every file up to date: CPU", rerun["base"]["cpu"], rerun["new"]["cpu"], chunks))

    loky = {v: best(v, "loky", lambda r: r["wall"]) for v in roots}
    print("\n| n_jobs=2, loky | base s | new s | ratio |")
    print("|---|---|---|---|")
    for key, name in (("wall", "wall time"), ("main_cpu", "main process CPU"), ("workers_cpu", "workers' CPU")):
        base, new = loky["base"][key], loky["new"][key]
        print(f"| {name} | {base:.2f} | {new:.2f} | {new / base:.2f} |")
    imports = {v: min(r["import"] for r in results[v]["import"]) for v in roots}
    print(f"| import pipeline.simulate (a worker's imports), CPU | {imports['base']:.2f} | {imports['new']:.2f} | "
          f"{imports['new'] / imports['base']:.2f} |")  # fmt: skip
    kernels = sum(t for k, t in startup.items() if k.startswith("first"))
    print(
        f"\nworker start-up, this checkout, CPU: import {startup['import']:.2f} s, first weighings beyond a second "
        f"{kernels:.2f} s (" + ", ".join(f"{k[6:]} {t:.3f}" for k, t in startup.items() if k != "import") + ")"
    )
    print(f"{_load()} at the end")


if __name__ == "__main__":
    main()
