"""The ``simulate`` stage on the default study, from scratch: this tree against a reference commit, alternately.

Issue 15's headline is the default study's runs per second on 2 cores. :mod:`bench.bench_protocol` times the two
protocols on 50 fleet bogies, each on its own road; the stage also weighs the ablation's variants and the Sobol'
design, which share roads, and adds its own work (planning, hashing, Parquet files, two processes). This bench runs
the whole stage as ``make repro`` does, ``python -m pipeline.simulate``, into a temporary directory, on this
checkout's ``data/samples`` (the sample stage's output: run ``make repro`` or ``dvc repro sample`` first), with each
tree's own ``params.yaml``, for this working tree as it is and for a reference commit (default: the merge base of
HEAD and ``main``), extracted once with ``git archive`` into :mod:`bench.bench_protocol`'s cache of trees (its numba
cache then stays warm between runs). Each tree first runs the stage on the first :data:`WARM_SAMPLES` samples of each
study, untimed, which compiles or loads its numba kernels; then :data:`ROUNDS` rounds run the full stage in each
tree, which goes first alternating, so that a burst of other work on the shared machine falls on both.

Printed per tree: the stage's own time (its summary line: from planning to the last file, the main process's
imports excluded) and the process's wall time, each round, their median and best, and runs per second; the ratio
of the medians and of the bests; the load average at the start and the end. Then whether the two trees wrote the
same rows (every column of both datasets, in sample and protocol order) and, if not, the largest difference in
each result column. ``--reference HEAD`` with a clean tree times the same code twice: the ratio it prints is the
bench's own scatter.

Run alone: ``python -m bench.bench_stage [--reference REV] [--rounds N]`` (about 3 minutes with 3 rounds when both
trees weigh at today's speed; the code before issue 15 takes about 2.5 minutes a round by itself).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from bench.bench_protocol import merge_base, reference_tree, tree_env

ROOT = Path(__file__).resolve().parent.parent
#: rounds of the full stage per tree [-]
ROUNDS = 3
#: samples of each study in the untimed warm-up run [-]
WARM_SAMPLES = 8
#: the stage's summary line: runs computed and the stage's time
SUMMARY = re.compile(r"computed (\d+) runs in \d+ chunks in ([0-9.]+) s")
#: the issue's starting point: the default study (then 14,096 runs) took about 150 s on 2 cores [runs/s]
ISSUE_BASELINE = 95.0
#: the rows are put in this order before the two datasets are compared
ORDER = ["study", "sample_id", "protocol"]


def check_imports(tree: Path, cwd: Path) -> None:
    """Refuse a tree whose processes would import ``bogie`` or ``pipeline`` from elsewhere."""
    code = "import bogie, pipeline; print(bogie.__file__); print(pipeline.__file__)"
    found = subprocess.run([sys.executable, "-c", code], cwd=cwd, env=tree_env(tree), check=True, capture_output=True,
                           text=True).stdout.split()  # fmt: skip
    for path in found:
        if Path(path).resolve().parent.parent != tree.resolve():
            raise RuntimeError(f"a process for {tree} imports {path}, not that tree's code")


def run_stage(tree: Path, samples: Path, out: Path) -> tuple[int, float, float]:
    """``python -m pipeline.simulate`` importing ``tree`` with its params.yaml: (runs, stage time [s], wall [s])."""
    env = tree_env(tree)
    command = [sys.executable, "-m", "pipeline.simulate", "--params", str(tree / "params.yaml"),
               "--samples", str(samples), "--out", str(out)]  # fmt: skip
    start = time.perf_counter()
    done = subprocess.run(command, cwd=out.parent, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(
            f"the stage failed in {tree} ({done.returncode}):\n{done.stdout[-2000:]}{done.stderr[-2000:]}"
        )
    found = SUMMARY.search(done.stdout + done.stderr)
    if found is None:
        raise RuntimeError(f"no summary line from the stage in {tree}:\n{done.stdout[-2000:]}")
    return int(found.group(1)), float(found.group(2)), wall


def warm_samples(samples: Path, into: Path) -> Path:
    """The first :data:`WARM_SAMPLES` rows of each study table of ``samples``, written to ``into``."""
    into.mkdir(parents=True, exist_ok=True)
    for table in sorted(samples.glob("*.parquet")):
        pd.read_parquet(table).head(WARM_SAMPLES).to_parquet(into / table.name)
    return into


def compare(a: Path, b: Path) -> list[str]:
    """Lines saying whether two runs datasets hold the same rows, or their largest differences per column."""
    left, right = (pd.read_parquet(p) for p in (a, b))
    for frame in (left, right):
        frame["study"] = frame["study"].astype(str)
    left = left.sort_values(ORDER).reset_index(drop=True)
    right = right.sort_values(ORDER).reset_index(drop=True)
    if left.shape != right.shape or list(left.columns) != list(right.columns):
        return [f"different datasets: {left.shape} against {right.shape} (columns differ: "
                f"{sorted(set(left.columns) ^ set(right.columns))})"]  # fmt: skip
    if left.equals(right):
        return [f"the same rows: {len(left)} rows x {left.shape[1]} columns identical"]
    lines = ["the rows differ; largest difference per column (rows where both succeeded):"]
    both = (left["status"] == "ok") & (right["status"] == "ok")
    lines.append(f"  status differs in {int((left['status'] != right['status']).sum())} rows")
    for column in left.columns:
        x, y = left.loc[both, column], right.loc[both, column]
        if pd.api.types.is_float_dtype(x):
            diff = np.nanmax(np.abs(x.to_numpy(float) - y.to_numpy(float))) if len(x) else 0.0
            if diff != 0.0:
                lines.append(f"  {column}: {diff:.3g}")
        elif not x.equals(y):
            lines.append(f"  {column}: {int((x != y).sum())} rows differ")
    return lines


def main(reference: str | None = None, rounds: int = ROUNDS) -> None:
    samples = ROOT / "data" / "samples"
    if not any(samples.glob("*.parquet")):
        raise SystemExit(f"{samples} holds no study tables: run `make repro` (or `dvc repro sample`) first")
    rev = reference or merge_base()
    sha, ref_tree = reference_tree(rev)
    trees = {"reference": ref_tree, "this": ROOT}
    print(f"reference {rev} = {sha[:10]} ({ref_tree}); this tree {ROOT}; samples {samples}; {rounds} rounds")
    load_start = os.getloadavg()
    times: dict[str, list[tuple[int, float, float]]] = {name: [] for name in trees}
    with tempfile.TemporaryDirectory() as tmp:
        warm = warm_samples(samples, Path(tmp) / "warm-samples")
        for name, tree in trees.items():
            (Path(tmp) / f"warm-{name}").mkdir()
            check_imports(tree, Path(tmp) / f"warm-{name}")
            run_stage(tree, warm, Path(tmp) / f"warm-{name}" / "runs")
        for r in range(rounds):
            order = list(trees) if r % 2 == 0 else list(reversed(trees))
            for name in order:
                work = Path(tmp) / f"{name}-{r}"
                work.mkdir()
                times[name].append(run_stage(trees[name], samples, work / "runs"))
                n_runs, stage, wall = times[name][-1]
                print(
                    f"  round {r + 1} {name:9s}: stage {stage:6.1f} s ({n_runs / stage:6.1f} runs/s), "
                    f"process {wall:6.1f} s",
                    flush=True,
                )
        same = compare(Path(tmp) / f"reference-{rounds - 1}" / "runs", Path(tmp) / f"this-{rounds - 1}" / "runs")
    load_end = os.getloadavg()
    print(
        f"\nload average (1, 5, 15 min): start {', '.join(f'{x:.2f}' for x in load_start)}; "
        f"end {', '.join(f'{x:.2f}' for x in load_end)}  (2 cores)"
    )
    print(
        f"{'tree':9s} | {'runs':>6s} | {'stage median':>12s} | {'best':>6s} | {'runs/s (median)':>15s} | "
        f"{'x issue start':>13s} | {'process median':>14s}"
    )
    medians = {}
    bests = {}
    for name, rows in times.items():
        n_runs = rows[0][0]
        medians[name] = statistics.median(t[1] for t in rows)
        bests[name] = min(t[1] for t in rows)
        rate = n_runs / medians[name]
        print(
            f"{name:9s} | {n_runs:6d} | {medians[name]:10.1f} s | {bests[name]:4.1f} s | {rate:15.1f} | "
            f"{rate / ISSUE_BASELINE:11.2f} x | {statistics.median(t[2] for t in rows):12.1f} s"
        )
    print(
        f"this / reference, runs per second: median {medians['reference'] / medians['this']:.2f} x, best "
        f"{bests['reference'] / bests['this']:.2f} x  (the issue's start: {ISSUE_BASELINE:g} runs/s, the default "
        "study of then in about 150 s)"
    )
    for line in same:
        print(line)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", default=None, help="commit to compare against (default: merge base with main)")
    parser.add_argument("--rounds", type=int, default=ROUNDS, help=f"rounds per tree (default {ROUNDS})")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error(f"--rounds = {args.rounds} must be at least 1")
    main(args.reference, args.rounds)
