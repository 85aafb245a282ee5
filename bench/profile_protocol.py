"""Where the time of one weighing goes: per phase of each protocol, steps, Newton work and time, and unit costs.

Three measurements on the first tandem and the first tri-axle bogie of a fixed fleet sample (``params.yaml``,
``fleet.n_bogies`` = 50, as ``bench_protocol``):

1. **Work per step** (counts, exact): each protocol run once in a subprocess with ``NUMBA_DISABLE_JIT=1``, the
   kernels' Python source, with the model force wrapped by counters: per phase (the ``simulate`` calls and the
   static equilibrium) its steps, Newton iterations (``IntegrationResult.n_iterations``), tangent formations
   (``force`` calls with ``want_tangent``) and internal-force evaluations (``_internal`` calls: 2n + 1 per
   tangent, one per residual). The numbers are those of the compiled run up to round-off in the last bits.
2. **Time per phase** (compiled, warm cache): each protocol :data:`REPEATS` times per bogie, the time in the
   compiled kernel (``newmark.integrate``) of each phase, the equilibrium, and everything else of ``weigh`` (road
   and inputs, packing, results, the reading): the Python overhead between phases.
3. **Unit costs** (compiled loops, no Python in between): one internal-force evaluation with and without the
   record, one tangent (force with ``want_tangent``), one LU factorisation of the 2n x 2n iteration matrix.

Run alone: ``python -m bench.profile_protocol``. Prints the load average; compare shares and ratios, not times.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
REPEATS = 20
N_BOGIES = 50
PROTOCOLS = ("static", "wim")


def _sample() -> tuple[list[dict], dict]:
    """The first tandem and first tri-axle record of the fixed sample, and the protocol specs."""
    from pipeline.config import load_config
    from pipeline.sample import sample_fleet

    config = load_config(ROOT / "params.yaml")
    config = dataclasses.replace(config, fleet=dataclasses.replace(config.fleet, n_bogies=N_BOGIES))
    records = sample_fleet(config).to_dict("records")
    chosen = [next(r for r in records if r["group"] == g) for g in ("tandem", "triaxle")]
    return chosen, {name: getattr(config.protocol, name) for name in PROTOCOLS}


class _Phases:
    """Wraps ``nonlinear.simulate``, ``nonlinear.integrate`` and ``nonlinear.equilibrium`` to label phases."""

    def __init__(self) -> None:
        from bogie import nonlinear

        self.nonlinear = nonlinear
        self.log: list[dict] = []
        self.current: dict | None = None
        self._simulate, self._integrate, self._equilibrium = (
            nonlinear.simulate,
            nonlinear.integrate,
            nonlinear.equilibrium,
        )

        def simulate(bogie, inputs, initial=None, **kw):
            self.current = {"phase": f"simulate {len(self.log)}", "steps": inputs.n_steps, "kernel": 0.0,
                            "iterations": 0, "tangents": 0, "evaluations": 0}  # fmt: skip
            self.log.append(self.current)
            return self._simulate(bogie, inputs, initial, **kw)

        def integrate(*args, **kw):
            start = time.perf_counter()
            run = self._integrate(*args, **kw)
            self.current["kernel"] += time.perf_counter() - start
            self.current["iterations"] += run.n_iterations
            return run

        def equilibrium(*args, **kw):
            outer = self.current
            self.current = {"phase": "equilibrium", "steps": 0, "kernel": 0.0, "iterations": 0, "tangents": 0,
                            "evaluations": 0}  # fmt: skip
            self.log.append(self.current)
            start = time.perf_counter()
            try:
                return self._equilibrium(*args, **kw)
            finally:
                self.current["kernel"] += time.perf_counter() - start
                self.current = outer

        nonlinear.simulate, nonlinear.integrate, nonlinear.equilibrium = simulate, integrate, equilibrium


def _names(protocol: str, log: list[dict]) -> list[str]:
    """Phase names in call order: static = equilibrium (start of the ramp), ramp, crawl, settle; wim = eq., pass."""
    sims = iter(("load ramp", "crawl", "settle") if protocol == "static" else ("pass",))
    return ["equilibrium" if p["phase"] == "equilibrium" else next(sims) for p in log]


def count_worker(out: str) -> None:
    """Part 1, inside a NUMBA_DISABLE_JIT process: the counts per phase of each protocol and bogie."""
    from bogie import _nonlinear_core as core
    from pipeline.protocol import weigh
    from pipeline.sample import bogie_from_sample

    phases = _Phases()
    force, internal = core.force, core._internal

    def counted_force(*args):
        if args[12] and phases.current is not None:  # want_tangent
            phases.current["tangents"] += 1
        return force(*args)

    def counted_internal(*args):
        if phases.current is not None:
            phases.current["evaluations"] += 1
        return internal(*args)

    core.force, core._internal = counted_force, counted_internal
    records, specs = _sample()
    answer = {}
    for record in records:
        for name in PROTOCOLS:
            phases.log = []
            weigh(bogie_from_sample(record), record, name, specs[name])
            for p, label in zip(phases.log, _names(name, phases.log)):
                p["phase"] = label
            answer[f"{record['group']} {name}"] = phases.log
    Path(out).write_text(json.dumps(answer))


def counts() -> dict:
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", PYTHONPATH=str(ROOT))
    out = Path(os.environ.get("TMPDIR", "/tmp")) / f"profile_counts_{os.getpid()}.json"
    subprocess.run([sys.executable, "-m", "bench.profile_protocol", "--count", str(out)], cwd=ROOT, env=env, check=True)
    answer = json.loads(out.read_text())
    out.unlink()
    return answer


def timings() -> dict:
    """Part 2: compiled, the time per phase and the rest of ``weigh``, medians over REPEATS."""
    from pipeline.protocol import weigh
    from pipeline.sample import bogie_from_sample

    records, specs = _sample()
    phases = _Phases()
    answer = {}
    for record in records:
        bogie = bogie_from_sample(record)
        for name in PROTOCOLS:
            weigh(bogie, record, name, specs[name])  # warm
            runs = []
            for _ in range(REPEATS):
                phases.log = []
                start = time.perf_counter()
                weigh(bogie, record, name, specs[name])
                total = time.perf_counter() - start
                runs.append((total, [dict(p) for p in phases.log]))
            totals = [t for t, _ in runs]
            median = sorted(range(REPEATS), key=lambda k: totals[k])[REPEATS // 2]
            total, log = runs[median]
            for k, (p, label) in enumerate(zip(log, _names(name, log))):
                p["phase"] = label
                p["kernel"] = float(np.median([r[1][k]["kernel"] for r in runs]))
            answer[f"{record['group']} {name}"] = {"total": float(np.median(totals)), "phases": log}
    return answer


def unit_costs() -> dict:
    """Part 3: compiled loops of one force evaluation, one tangent and one LU factorisation per bogie [s]."""
    from numba import njit

    from bogie import _nonlinear_core as core
    from bogie import nonlinear
    from bogie._lu import lu_factor
    from pipeline.sample import bogie_from_sample

    @njit
    def force_loop(calls, u, v, drv, data_f, data_i, h0, h1, f, kt, ct, rec, record, tangent, work):
        for _ in range(calls):
            core.force(u, v, drv, data_f, data_i, h0, h1, f, kt, ct, rec, record, tangent, work)

    @njit
    def lu_loop(calls, jac, a, piv):
        for _ in range(calls):
            a[:] = jac
            lu_factor(a, piv)

    records, _ = _sample()
    answer = {}
    for record in records:
        bogie = bogie_from_sample(record)
        n = bogie.n_axles
        mass, data_f, data_i = nonlinear.pack(bogie)
        drive = nonlinear.hold(bogie, 0.01, 0.001).drive(bogie)
        state = nonlinear.equilibrium(bogie, drive[0])
        ndof = 2 * n
        args = [state.u, state.v, drive[0], data_f, data_i, state.history, state.history.copy(), np.zeros(ndof),
                np.zeros((ndof, ndof)), np.zeros((ndof, ndof)), np.zeros(core.record_length(n))]  # fmt: skip
        work = np.zeros(core.work_size(n))
        costs = {}
        for label, rec_flag, tangent, calls in (("force, no record", False, False, 200_000),
                                                ("force + record", True, False, 200_000),
                                                ("tangent (2n + 1 forces)", True, True, 20_000)):  # fmt: skip
            force_loop(10, *args, rec_flag, tangent, work)
            best = float("inf")
            for _ in range(5):
                start = time.perf_counter()
                force_loop(calls, *args, rec_flag, tangent, work)
                best = min(best, (time.perf_counter() - start) / calls)
            costs[label] = best
        force_loop(1, *args, True, True, work)
        jac = args[8] + 1e6 * mass
        piv = np.zeros(ndof, dtype=np.int64)
        lu_loop(10, jac, jac.copy(), piv)
        start = time.perf_counter()
        lu_loop(200_000, jac, jac.copy(), piv)
        costs["LU factorisation"] = (time.perf_counter() - start) / 200_000
        answer[f"{record['group']} ({ndof} freedoms)"] = costs
    return answer


def main() -> None:
    load = os.getloadavg()
    print(f"load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} cores")
    work = counts()
    times = timings()
    costs = unit_costs()
    print("\n1-2. per phase: steps, Newton work per step (counts, uncompiled run), compiled kernel time (median)")
    print("| run | phase | steps | iterations/step | tangents/step | force evals/step | kernel ms | us/step |")
    print("|---|---|---|---|---|---|---|---|")
    for key, timed in times.items():
        for p, t in zip(work[key], timed["phases"]):
            steps = max(p["steps"], 1)
            per = f"{1e6 * t['kernel'] / p['steps']:.2f}" if p["steps"] else ""
            its = f"{p['iterations'] / steps:.3f}" if p["steps"] else f"{p['evaluations']} evals"
            print(f"| {key} | {p['phase']} | {p['steps']} | {its} | {p['tangents'] / steps:.4f} | "
                  f"{p['evaluations'] / steps:.3f} | {1e3 * t['kernel']:.2f} | {per} |")  # fmt: skip
        kernel = sum(t["kernel"] for t in timed["phases"])
        print(f"| {key} | **weigh total** | | | | | {1e3 * timed['total']:.2f} | "
              f"(Python outside the kernels: {1e3 * (timed['total'] - kernel):.2f} ms, "
              f"{100 * (1 - kernel / timed['total']):.0f} %) |")  # fmt: skip
    print("\n3. unit costs (compiled loops, best of 5) [us]")
    labels = list(next(iter(costs.values())))
    print("| bogie | " + " | ".join(labels) + " |")
    print("|---|" + "---|" * len(labels))
    for key, c in costs.items():
        print(f"| {key} | " + " | ".join(f"{1e6 * c[k]:.3f}" for k in labels) + " |")
    load = os.getloadavg()
    print(f"\nload average at end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--count":
        count_worker(sys.argv[2])
    else:
        main()
