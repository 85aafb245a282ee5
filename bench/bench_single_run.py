"""Issue 15's second target: one 20 s tri-axle run at 1 ms in at most 10 ms, single-threaded, built two ways.

``python -m bench.bench_single_run [--rounds N]`` times ``bogie.steel.phases.run`` (the weighings' kernel, readings
only) on ``bench_nonlinear``'s problem (``triaxle_stage1()``, ISO 8608 class B, 15 m/s, 20 s in fixed 1 ms steps) in
child processes of two kinds, alternately, so that a burst of other work on the shared machine falls on both:

* ``pinned``: numba compiling for x86-64-v3, as ``import bogie`` fixes it (:func:`bogie.numerics.fix_compile_target`)
  in every stage and every user's process;
* ``host``: numba compiling for this machine's own CPU and its features (``NUMBA_CPU_NAME`` and
  ``NUMBA_CPU_FEATURES`` set to them in the child's environment, which bogie leaves as the user's choice).

Each child loads (or compiles) its kernels, checks that the run succeeds with ``round(duration / dt)`` steps, then
times :data:`REPEATS` runs. Printed: each round's median per kind, the median of all runs and the least, the time per
step, the ratio host / pinned, whether the two builds give the same wheel loads (bit for bit) and the 10 ms verdict,
with the load average at the start and the end. ``bench_nonlinear`` times the same run in its own (unpinned)
process beside ``simulate`` and the solve_ivp peer.

``--reference REV`` adds a third kind, ``reference``: the commit REV's code (extracted as :mod:`bench.bench_protocol`
does), pinned, in the same alternation: the speed-up of this tree's kernel over REV's, and whether their wheel loads
are the same bits.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from bench.bench_nonlinear import DT, DURATION, ROAD, SPEED
from bench.bench_protocol import reference_tree, tree_env

ROOT = Path(__file__).resolve().parent.parent
#: timed runs per child process [-]
REPEATS = 25
#: rounds, each one child of each kind [-]
ROUNDS = 3
#: the target of issue 15 [s]
TARGET = 0.010

CHILD = """
import sys, time, json
import numba
from bogie.steel import phases
from bogie.params import triaxle_stage1
from bogie.road import ISO8608Profile
SPEED, DURATION, DT = float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
ROAD = json.loads(sys.argv[6])
bogie = triaxle_stage1()
profile = ISO8608Profile(**ROAD)
table = phases.RoadTable.from_profile(
    profile, bogie.axle_x[0] - bogie.axle_x[-1] - 0.01, SPEED * DURATION + 0.01, profile.grid_spacing
)
run = [phases.Phase(DURATION, 1.0, road=table, speed=SPEED, dt=DT, name="pass")]
first = phases.run(bogie, run, history=True)
if not first.success or len(first.t) != round(DURATION / DT) + 1:
    raise SystemExit(f"the run failed: {first.message}")
times = []
for _ in range(int(sys.argv[2])):
    start = time.perf_counter()
    phases.run(bogie, run)
    times.append(time.perf_counter() - start)
import llvmlite.binding as llvm
cpu = numba.config.CPU_NAME or f"host {llvm.get_host_cpu_name()}"
print(json.dumps({"times": times, "cpu": cpu, "steps": len(first.t) - 1,
                  "loads": first.wheel_loads.tobytes().hex()}))
"""


def child(kind: str, repeats: int, tree: Path = ROOT) -> dict:
    """One child process of ``kind`` importing ``tree``'s code: its run times [s], numba's CPU and the loads.

    ``host``: numba's target set to this machine's CPU and features in its environment; any other kind: the target
    the tree's own code chooses (x86-64-v3 since issue 26; the pin of ``pipeline`` before it, which this process no
    longer sets, so an older tree's kernel compiles for the host).
    """
    env = {k: v for k, v in tree_env(tree).items() if k not in ("NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES")}
    if kind == "host":
        import llvmlite.binding as llvm

        env["NUMBA_CPU_NAME"] = llvm.get_host_cpu_name()
        env["NUMBA_CPU_FEATURES"] = llvm.get_host_cpu_features().flatten()
    arguments = [str(repeats), str(SPEED), str(DURATION), str(DT), json.dumps(ROAD)]
    done = subprocess.run([sys.executable, "-c", CHILD, kind, *arguments], cwd=tree, env=env, check=True,
                          capture_output=True, text=True)  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.bench_single_run", description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=ROUNDS, help=f"rounds of every kind (default {ROUNDS})")
    parser.add_argument("--reference", default=None, help="also time this commit's code, pinned (default: none)")
    args = parser.parse_args(argv)
    if args.rounds < 1:
        raise SystemExit(f"--rounds = {args.rounds} is out of range: must be an integer >= 1")
    trees = {"pinned": ROOT, "host": ROOT}
    if args.reference is not None:
        sha, trees["reference"] = reference_tree(args.reference)
        print(f"reference {args.reference} = {sha[:10]} ({trees['reference']})")
    load_start = os.getloadavg()
    for kind, tree in trees.items():  # untimed: loads or compiles each build's kernels
        child(kind, 1, tree)
    results: dict[str, list[dict]] = {kind: [] for kind in trees}
    for r in range(args.rounds):
        order = list(trees) if r % 2 == 0 else list(reversed(trees))
        for kind in order:
            out = child(kind, REPEATS, trees[kind])
            results[kind].append(out)
            print(f"  round {r + 1} {kind:9s} ({out['cpu']}): median {statistics.median(out['times']) * 1e3:5.2f} ms, "
                  f"least {min(out['times']) * 1e3:5.2f} ms", flush=True)  # fmt: skip
    load_end = os.getloadavg()
    medians = {}
    for kind, outs in results.items():
        times = [t for out in outs for t in out["times"]]
        steps = outs[0]["steps"]
        medians[kind] = statistics.median(times)
        verdict = "met" if medians[kind] <= TARGET else "NOT met"
        print(f"{kind:9s} ({outs[0]['cpu']}): median {medians[kind] * 1e3:5.2f} ms, least {min(times) * 1e3:5.2f} ms "
              f"over {len(times)} runs; {medians[kind] / steps * 1e6:.3f} us a step ({steps} steps); "
              f"target <= {TARGET * 1e3:g} ms: {verdict}")  # fmt: skip
    for other in [k for k in results if k != "pinned"]:
        same = results["pinned"][0]["loads"] == results[other][0]["loads"]
        print(f"{other} / pinned: {medians[other] / medians['pinned']:.3f} x; wheel loads at every step "
              f"{'identical' if same else 'DIFFERENT'}")  # fmt: skip
    print(f"load average (1, 5, 15 min): start {', '.join(f'{x:.2f}' for x in load_start)}; end "
          f"{', '.join(f'{x:.2f}' for x in load_end)}  ({os.cpu_count()} cores)")  # fmt: skip


if __name__ == "__main__":
    main()
