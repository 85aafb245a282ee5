"""Where the time of one weighing goes: per phase of each protocol, the steps and force evaluations, and unit costs.

Measured on the first tandem and the first tri-axle bogie of a fixed fleet sample (``params.yaml``,
``fleet.n_bogies`` = 50, as ``bench_protocol``):

1. **Work per phase** (counts from the kernel, exact): accepted and rejected steps, force evaluations (the 2n + 1
   of each tangent included), tangents formed, factorisations of the iteration matrix and steps whose first
   correction was accepted unchecked (``bogie.steel.phases.PhaseOutcome``), and the evaluations per step.
2. **Time** (compiled, warm cache, best of :data:`REPEATS`): the whole of ``bogie.fleet.weighing.weigher.weigh``, the
   compiled call (``bogie.steel.phases._core.run_phases``) within it, and so the Python around it (the road tables, the
   phases, the result row); the time per step and per force evaluation of the compiled call.
3. **Unit costs** (compiled loops, no Python in between, best of 5): one force evaluation with the record (the
   hysteresis' exponential running), forming and factoring the 2n x 2n iteration matrix, one solve with its factors.

Run alone: ``python -m bench.profile_protocol``. Prints the load average; compare shares and ratios, not times.
"""

from __future__ import annotations

import dataclasses
import os
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


def _timed(record: dict, name: str, spec) -> tuple[float, float, list]:
    """Best-of-REPEATS time of ``weigh`` and of its compiled call [s], and the phases' outcomes."""
    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.fleet.weighing import protocols as protocol
    from bogie.fleet.weighing import weigher
    from bogie.steel import phases
    from bogie.steel.phases import _core as pc

    bogie = bogie_from_sample(record)
    inner = {"t": 0.0}
    kernel = pc.run_phases

    def wrapped(*args):
        start = time.perf_counter()
        out = kernel(*args)
        inner["t"] += time.perf_counter() - start
        return out

    args = (bogie, float(record["payload_fraction"]), str(record["road_class"]), int(record["road_seed"]), spec)
    if name == "static":
        run = protocol.static_weighbridge(*args)
    else:
        run = protocol.wim_pass(*args, sensor_seed=int(record["sensor_seed"]))
    best_total = best_kernel = float("inf")
    phases.pc.run_phases = wrapped
    try:
        for _ in range(REPEATS):
            inner["t"] = 0.0
            start = time.perf_counter()
            weigher.weigh(bogie, record, name, spec)
            best_total = min(best_total, time.perf_counter() - start)
            best_kernel = min(best_kernel, inner["t"])
    finally:
        phases.pc.run_phases = kernel
    return best_total, best_kernel, list(run.run.phases)


def _unit_costs(record: dict) -> dict[str, float]:
    """Compiled-loop costs [us] of one force evaluation, one factorisation and one solve, for ``record``'s bogie."""
    from numba import njit

    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.lu import lu_factor, lu_solve
    from bogie.steel import nonlinear as nl
    from bogie.steel.force import core as nlc

    @njit
    def force_loop(count, u, v, drv, data_f, data_i, hist, hist_new, f, kt, ct, rec, work):
        total = 0.0
        for k in range(count):
            u[-1] += 1e-9 * (2 * (k & 1) - 1)  # the last axle moves: its spring's hysteresis exponential runs
            nlc.force(u, v, drv, data_f, data_i, hist, hist_new, f, kt, ct, rec, True, False, work)
            total += f[0]
        return total

    @njit
    def factor_loop(count, mass, kt, ct, jac, piv):
        total = 0.0
        for k in range(count):
            for i in range(mass.shape[0]):
                for j in range(mass.shape[0]):
                    jac[i, j] = 4e6 * mass[i, j] + kt[i, j] + 2e3 * ct[i, j] + k * 1e-9
            lu_factor(jac, piv)
            total += jac[0, 0]
        return total

    @njit
    def solve_loop(count, jac, piv, res):
        total = 0.0
        for k in range(count):
            for i in range(res.shape[0]):
                res[i] = 1.0 + k * 1e-9
            lu_solve(jac, piv, res)
            total += res[0]
        return total

    bogie = bogie_from_sample(record)
    n = bogie.n_axles
    mass, data_f, data_i = nl.pack(bogie)
    drv = np.r_[np.zeros(2 * n), 1.0, bogie.kingpin_height_offset]
    state = nl.equilibrium(bogie, drv)
    u, v, hist = state.u.copy(), np.zeros(2 * n), state.history.copy()
    f, kt, ct = np.zeros(2 * n), np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n))
    rec, work = np.zeros(nlc.record_length(n)), np.zeros(nlc.work_size(n))
    nlc.force(u, v, drv, data_f, data_i, hist, hist.copy(), f, kt, ct, rec, True, True, work)
    jac, piv, res = np.zeros((2 * n, 2 * n)), np.zeros(2 * n, dtype=np.int64), np.zeros(2 * n)
    loops = {
        "force + record": (force_loop, (u, v, drv, data_f, data_i, hist, hist.copy(), f, kt, ct, rec, work)),
        "form + factor": (factor_loop, (mass, kt, ct, jac, piv)),
        "solve": (solve_loop, (jac, piv, res)),
    }
    count = 100_000
    out = {}
    for label, (loop, args) in loops.items():
        loop(10, *args)
        best = float("inf")
        for _ in range(5):
            start = time.perf_counter()
            loop(count, *args)
            best = min(best, time.perf_counter() - start)
        out[label] = 1e6 * best / count
    return out


def main() -> None:
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"load average at start: {load} on {os.cpu_count()} cores\n")
    records, specs = _sample()
    print("| bogie | protocol | phase | steps | rejected | unchecked | force evaluations | per step | tangents | "
          "factorisations |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|---|")
    times = []
    for record in records:
        for name in PROTOCOLS:
            total, kernel, outcomes = _timed(record, name, specs[name])
            steps = evals = 0
            for o in outcomes:
                per = o.force_evaluations / max(1, o.steps + o.rejected)
                print(f"| {record['group']} | {name} | {o.name} | {o.steps} | {o.rejected} | {o.unchecked} | "
                      f"{o.force_evaluations} | {per:.2f} | {o.tangents} | {o.factorisations} |")  # fmt: skip
                steps += o.steps + o.rejected
                evals += o.force_evaluations
            times.append((record["group"], name, total, kernel, steps, evals))
    print("\n| bogie | protocol | weigh [ms] | compiled call [ms] | Python around it [ms] | per step attempt [us] | "
          "per force evaluation [us] |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for group, name, total, kernel, steps, evals in times:
        print(f"| {group} | {name} | {1e3 * total:.2f} | {1e3 * kernel:.2f} | {1e3 * (total - kernel):.2f} | "
              f"{1e6 * kernel / steps:.2f} | {1e6 * kernel / evals:.2f} |")  # fmt: skip
    print("\n| bogie | " + " | ".join(f"{k} [us]" for k in ("force + record", "form + factor", "solve")) + " |")
    print("|---|---|---|---|")
    for record in records:
        costs = _unit_costs(record)
        print(f"| {record['group']} | " + " | ".join(f"{v:.3f}" for v in costs.values()) + " |")
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"\nload average at end: {load}")


if __name__ == "__main__":
    main()
