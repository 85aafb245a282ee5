"""Issue 42 Must 2: the two Newton iterations of the Stage 4 time step, measured against each other.

``bogie.steel.nonlinear.simulate`` steps with ``bogie.steel.newmark.kernels._attempt`` (full mass matrix, LU
factors, every history recorded); ``bogie.steel.phases.run``, the weighings' kernel, with
``bogie.steel.phases._step._solve_step`` (diagonal mass, kept inverses, the last correction extrapolated into the
predictor, a first correction accepted unchecked where the measured contraction allows). What would making them one
cost? Three measurements, one process:

1. **Speed**: ``bench_nonlinear``'s problem (``triaxle_stage1()``, ISO 8608 class B, 15 m/s, 20 s in 20,000 fixed
   steps of 1 ms, from rest) through ``simulate``, its compiled kernel alone (``newmark.integrate``), and
   ``phases.run`` as the weighings call it and with its public switches: ``check_every=1`` (every first correction
   checked, as ``simulate`` does) and ``history=True`` (wheel loads and pitch kept at every step). Interleaved,
   :data:`REPEATS` runs of each in each of :data:`WINDOWS` windows, medians; ratios to ``phases.run`` in the same run;
   each one's own counters (``simulate``: Newton iterations; ``phases``: force evaluations, tangents, factorisations,
   first corrections accepted unchecked).
2. **Bits**: the same problem with the same drive and the same start for both: the drive rows that ``phases`` computes
   in its kernel at t = k dt (its road table, exact rates) handed to ``simulate`` as ``Inputs``, both from one static
   equilibrium with consistent accelerations, both in fixed 1 ms steps. The largest difference of the wheel loads at
   every step [N, and over the design wheel load], where they first differ, each one's error against ``simulate`` at
   dt / :data:`REFINEMENT` on the same drive, and ``simulate`` against itself from a start one ulp away (rounding).
3. **Published readings**: the first :data:`N_BOGIES` fleet bogies of ``params.yaml`` (steel ones): each WIM pass's
   error-free reading (``phases.run`` from rest, as the stage weighs; ``data/runs``'s loads are it times the sensor's
   factors) against ``simulate`` on the same drive and start with ``bogie.road.wim.sensor_reading`` on its history
   (and, as the controls, that reading on ``phases``'s own history, and ``simulate`` from one ulp away); both
   protocols' readings with ``check_every=1`` against the default; and the time of the WIM passes each way (best of
   :data:`PASSES` interleaved passes over the sample).

Run alone: ``python -m bench.bench_newton``. Prints the load average at the start and the end; compare ratios, not
times.
"""

from __future__ import annotations

import dataclasses
import os
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bench.bench_nonlinear import DT, DURATION, ROAD, SPEED, KernelCall, interleaved, road_inputs
from bogie.params import Bogie
from bogie.presets import triaxle_stage1
from bogie.road import ISO8608Profile, wim
from bogie.steel import nonlinear as nl
from bogie.steel import phases
from bogie.steel.phases import _core as pc

ROOT = Path(__file__).resolve().parent.parent
#: timed runs of each variant per window, and the windows spread over the benchmark [-]
REPEATS, WINDOWS = 15, 3
#: the bits' reference: simulate at DT / REFINEMENT on the same drive [-]
REFINEMENT = 16
#: fleet bogies of the sample (params.yaml with fleet.n_bogies set to this; the steel ones are weighed) [-]
N_BOGIES = 50
#: timed passes over the sample's WIM weighings, each way [-]
PASSES = 3


# ---- the same drive for both -----------------------------------------------------------------------------------
def drive_inputs(bogie: Bogie, phase: phases.Phase, dt: float) -> nl.Inputs:
    """``phase``'s drive at t = k dt, k = 0 .. round(duration / dt), computed by the phases kernel's own drive
    (``_drive``: the road table read at each axle, exact rates, the load factor and king pin), as ``nl.Inputs``."""
    c = nl.constants(bogie)
    n = bogie.n_axles
    rows, road_h = phases._rows([phase], c)
    m = max(1, int(round(phase.duration / dt)))
    drv = np.zeros(2 * n + 2)
    out = np.zeros((m + 1, 2 * n + 2))
    for k in range(m + 1):
        pc._drive(rows[0], road_h, c.offsets, n, k * dt, drv)
        out[k] = drv
    return nl.Inputs(dt, out[:, :n].copy(), out[:, n : 2 * n].copy(), out[:, 2 * n].copy(),
                     out[:, 2 * n + 1] - bogie.kingpin_height_offset)  # fmt: skip


def start_state(bogie: Bogie, inputs: nl.Inputs) -> nl.State:
    """The static equilibrium at the first row (friction relaxed) with consistent accelerations, as ``simulate``
    starts from rest (bench_nonlinear's :meth:`KernelCall.prepare`)."""
    call = KernelCall.prepare(bogie, inputs)
    return nl.State(call.state.u, call.state.v, call.a0, call.state.history)


def one_ulp(state: nl.State) -> nl.State:
    """``state`` with its chassis pitch moved by one ulp (a last-bit difference, the control)."""
    u = state.u.copy()
    u[0] = np.nextafter(u[0], np.inf)
    return nl.State(u, state.v, state.a, state.history)


def interpolation_ulps(inputs: nl.Inputs, bogie: Bogie) -> float:
    """Share of the drive entries d_(k+1) that ``simulate``'s step end, d_k + 1.0 (d_(k+1) - d_k), does not give
    back exactly (``kernels._predict``); the phases kernel computes d at the step's end directly."""
    d = inputs.drive(bogie)
    return float(np.mean(d[:-1] + 1.0 * (d[1:] - d[:-1]) != d[1:]))


def first_row(a: NDArray[np.float64], b: NDArray[np.float64]) -> int | None:
    """The first row where ``a`` and ``b`` differ in any bit, or None."""
    rows = np.flatnonzero(np.any(a != b, axis=1) if a.ndim == 2 else a != b)
    return int(rows[0]) if rows.size else None


# ---- 1. speed --------------------------------------------------------------------------------------------------
def speed(bogie: Bogie) -> dict:
    """Times and counters of the 20 s run each way (bench_nonlinear's calls)."""
    inputs = road_inputs(bogie, DURATION)
    n_steps = inputs.n_steps
    profile = ISO8608Profile(**ROAD)
    table = phases.RoadTable.from_profile(
        profile, bogie.axle_x[0] - bogie.axle_x[-1] - 0.01, SPEED * DURATION + 0.01, profile.grid_spacing
    )
    run = [phases.Phase(DURATION, 1.0, road=table, speed=SPEED, dt=DT, name="pass")]
    call = KernelCall.prepare(bogie, inputs)
    fns: dict[str, Callable[[], object]] = {
        "phases.run (weighings: check_every=16, readings only)": lambda: phases.run(bogie, run),
        "phases.run check_every=1": lambda: phases.run(bogie, run, check_every=1),
        "phases.run history=True": lambda: phases.run(bogie, run, history=True),
        "phases.run check_every=1, history=True": lambda: phases.run(bogie, run, check_every=1, history=True),
        "newmark.integrate (simulate's kernel alone)": call.run,
        "nonlinear.simulate": lambda: nl.simulate(bogie, inputs),
    }
    counts = {}
    for name, fn in fns.items():  # warm-up: loads (or compiles) the kernels; the counters
        out = fn()
        if isinstance(out, phases.PhasesRun):
            if not out.success:
                raise RuntimeError(f"{name}: {out.message}")
            o = out.phases[0]
            counts[name] = (f"{o.steps} steps, {o.rejected} rejected; {o.force_evaluations / o.steps:.3f} force "
                            f"evaluations a step ({o.tangents} tangents, {o.factorisations} inversions), "
                            f"{o.unchecked / o.steps:.1%} of first corrections unchecked")  # fmt: skip
        elif hasattr(out, "n_iterations"):
            if not out.success:
                raise RuntimeError(f"{name}: {out.message}")
            counts[name] = (f"{n_steps} steps; {out.n_iterations / n_steps:.3f} Newton corrections a step, so "
                            f">= {1 + out.n_iterations / n_steps:.3f} force evaluations a step (tangents not "
                            "counted by the kernel)")  # fmt: skip
        else:
            if not out.success:
                raise RuntimeError(f"{name}: {out.message}")
            counts[name] = "as the kernel alone, plus pack, static start and the result's histories"
    times = {name: [] for name in fns}
    for _ in range(WINDOWS):
        for name, ts in interleaved(fns, REPEATS).items():
            times[name] += ts
    return {"times": times, "counts": counts, "n_steps": n_steps}


# ---- 2. bits ---------------------------------------------------------------------------------------------------
def bits(bogie: Bogie) -> dict:
    """The two iterations on one drive from one start, fixed 1 ms steps: their wheel loads compared."""
    profile = ISO8608Profile(**ROAD)
    table = phases.RoadTable.from_profile(
        profile, bogie.axle_x[0] - bogie.axle_x[-1] - 0.01, SPEED * DURATION + 0.01, profile.grid_spacing
    )
    phase = phases.Phase(DURATION, 1.0, road=table, speed=SPEED, dt=DT, name="pass")
    inputs = drive_inputs(bogie, phase, DT)
    state = start_state(bogie, inputs)
    sim = nl.simulate(bogie, inputs, initial=state)
    fine_inputs = drive_inputs(bogie, phase, DT / REFINEMENT)
    fine = nl.simulate(bogie, fine_inputs, initial=state)
    if not (sim.success and fine.success):
        raise RuntimeError(f"simulate failed: {sim.message} / {fine.message}")
    w_ref = fine.wheel_loads[::REFINEMENT]
    load = sim.reference_load
    out = {
        "load": load,
        "ulps": interpolation_ulps(inputs, bogie),
        "sim_err": np.max(np.abs(sim.wheel_loads - w_ref)),
        "r_tol": float(nl.residual_tolerance(bogie)[-1]),
    }
    # the control: simulate against itself from a start whose chassis pitch is one ulp larger (a last bit)
    bumped = nl.simulate(bogie, inputs, initial=one_ulp(state))
    out["ulp_max"] = float(np.max(np.abs(bumped.wheel_loads - sim.wheel_loads)))
    # one step: the same predictor (no correction to extrapolate yet), a checked correction; LU solve or inverse
    one = phases.Phase(DT, 1.0, road=table, speed=SPEED, dt=DT, name="one step")
    s1 = nl.simulate(bogie, drive_inputs(bogie, one, DT), initial=state).final_state
    p1 = phases.run(bogie, [one], initial=state, check_every=1).final_state
    out["one_step_same"] = all(np.array_equal(getattr(s1, k), getattr(p1, k)) for k in ("u", "v", "a", "history"))
    rows = {}
    for label, check_every in (("check_every=16 (as the weighings run)", pc.CHECK_EVERY), ("check_every=1", 1)):
        ph = phases.run(bogie, [phase], initial=state, history=True, check_every=check_every)
        if not ph.success or not np.array_equal(ph.t, sim.t):
            raise RuntimeError(f"phases.run {label}: {ph.message}")
        d = np.abs(ph.wheel_loads - sim.wheel_loads)
        k = int(np.argmax(np.max(d, axis=1)))
        grow = {lim: first_row(d > lim, np.zeros_like(d, dtype=bool)) for lim in (1e-6, 1e-3, 1.0)}
        rows[label] = {
            "max": float(d.max()), "at": float(sim.t[k]), "rms": float(np.sqrt(np.mean(d**2))),
            "first_load": first_row(ph.wheel_loads, sim.wheel_loads),
            "first_pitch": first_row(ph.chassis_pitch, sim.extras["chassis_pitch"]),
            "grow": grow, "err": float(np.max(np.abs(ph.wheel_loads - w_ref))),
            "steps_differing": float(np.mean(np.any(ph.wheel_loads != sim.wheel_loads, axis=1))),
        }  # fmt: skip
    out["rows"] = rows
    return out


# ---- 3. published readings -------------------------------------------------------------------------------------
def sample() -> tuple[list[dict], object, object]:
    """The steel bogies among the first N_BOGIES of the fleet sample, and the two protocols' settings."""
    from pipeline.config import load_config
    from pipeline.sample import sample_fleet

    config = load_config(ROOT / "params.yaml")
    config = dataclasses.replace(config, fleet=dataclasses.replace(config.fleet, n_bogies=N_BOGIES))
    records = [r for r in sample_fleet(config).to_dict("records") if r["suspension"] == "steel"]
    return records, config.protocol.static, config.protocol.wim


def sim_wim_reading(bogie: Bogie, phase: phases.Phase, spec, initial: nl.State, inputs: nl.Inputs):
    """``simulate`` over the WIM phase's drive from ``initial``, read by ``wim.sensor_reading`` as the air groups' WIM
    pass is (``protocols._air_wim``)."""
    run = nl.simulate(bogie, inputs, initial=initial)
    if not run.success:
        return None, run
    return history_reading(bogie, phase, spec, run.t, run.wheel_loads), run


def history_reading(bogie: Bogie, phase: phases.Phase, spec, t, loads) -> NDArray[np.float64]:
    """Each tyre's WIM reading from a history of its loads (``wim.sensor_reading``)."""
    centres = phase.reading.front_centre + (np.asarray(bogie.axle_x) - bogie.axle_x[0]) / spec.speed
    return np.array([wim.sensor_reading(t, loads[:, i], centres[i], spec.speed, spec.sensor_length,
                                        spec.contact_length) for i in range(bogie.n_axles)])  # fmt: skip


def readings() -> dict:
    """The published WIM readings against simulate's, and both protocols' readings with check_every=1."""
    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.fleet.weighing import protocols

    records, static_spec, wim_spec = sample()
    d_sim, d_ulp, d_ctrl, d_start, d_ce = [], [], [], [], {"static": [], "wim": []}
    rel_sim, rel_ce = [], {"static": [], "wim": []}
    identical = {"sim": 0, "static": 0, "wim": 0}
    jobs = []
    for r in records:
        bogie = bogie_from_sample(r)
        args = (bogie, float(r["payload_fraction"]), str(r["road_class"]), int(r["road_seed"]))
        wim_run = protocols.wim_phases(*args, wim_spec)
        static_run = protocols.static_phases(*args, static_spec)
        phase = wim_run[0]
        published = phases.run(bogie, wim_run)
        inputs = drive_inputs(bogie, phase, phase.dt)
        state = start_state(bogie, inputs)
        same_start = phases.run(bogie, wim_run, initial=state, history=True)
        reading, _ = sim_wim_reading(bogie, phase, wim_spec, state, inputs)
        bumped, _ = sim_wim_reading(bogie, phase, wim_spec, one_ulp(state), inputs)
        if not (published.success and same_start.success) or reading is None:
            continue
        pub = published.phases[0].reading
        ref = float(np.mean(nl.design_wheel_loads(bogie)))
        d_start.append(float(np.max(np.abs(same_start.phases[0].reading - pub))))
        d_sim.append(float(np.max(np.abs(reading - same_start.phases[0].reading))))
        d_ulp.append(float(np.max(np.abs(bumped - reading))))
        rel_sim.append(d_sim[-1] / ref)
        identical["sim"] += int(np.array_equal(reading, same_start.phases[0].reading))
        ctrl = history_reading(bogie, phase, wim_spec, same_start.t, same_start.wheel_loads)
        d_ctrl.append(float(np.max(np.abs(ctrl - same_start.phases[0].reading))))
        for name, run in (("static", static_run), ("wim", wim_run)):
            a = phases.run(bogie, run)
            b = phases.run(bogie, run, check_every=1)
            if a.success and b.success:
                diff = float(np.max(np.abs(a.phases[-1].reading - b.phases[-1].reading)))
                d_ce[name].append(diff)
                rel_ce[name].append(diff / ref)
                identical[name] += int(diff == 0.0)
        jobs.append((bogie, wim_run, phase, inputs, state))

    def all_phases() -> None:
        for bogie, wim_run, *_ in jobs:
            phases.run(bogie, wim_run)

    def all_simulate() -> None:
        for bogie, _, phase, inputs, state in jobs:
            sim_wim_reading(bogie, phase, wim_spec, state, inputs)

    t = interleaved({"phases": all_phases, "simulate": all_simulate}, PASSES)
    return {
        "n": len(jobs), "d_sim": d_sim, "d_ulp": d_ulp, "rel_sim": rel_sim, "d_ctrl": d_ctrl, "d_start": d_start,
        "d_ce": d_ce, "rel_ce": rel_ce, "identical": identical, "t_phases": min(t["phases"]),
        "t_sim": min(t["simulate"]),
    }  # fmt: skip


# ---- report ----------------------------------------------------------------------------------------------------
def main() -> None:
    load_start = os.getloadavg()
    print(f"load average (1, 5, 15 min) at start: {', '.join(f'{x:.2f}' for x in load_start)} "
          f"on {os.cpu_count()} cores", flush=True)  # fmt: skip
    bogie = triaxle_stage1()
    clock = [time.perf_counter()]
    s = speed(bogie)
    clock.append(time.perf_counter())
    b = bits(bogie)
    clock.append(time.perf_counter())
    r = readings()
    clock.append(time.perf_counter())
    load_end = os.getloadavg()
    med = statistics.median
    times, n_steps = s["times"], s["n_steps"]
    base_name = next(iter(times))
    base = med(times[base_name])
    print(f"\n1. Speed: triaxle_stage1(), ISO 8608 class B ({ROAD['length']:g} m, seed {ROAD['seed']}) at "
          f"{SPEED:g} m/s, {DURATION:g} s in {n_steps} fixed steps of {DT * 1e3:g} ms; median of {WINDOWS} x "
          f"{REPEATS} interleaved runs (least in brackets), ratio to the weighings' phases.run")  # fmt: skip
    for name, ts in times.items():
        print(f"   {name:<52s} {med(ts) * 1e3:6.2f} ms ({min(ts) * 1e3:5.2f})  {med(ts) / n_steps * 1e6:5.3f} us a "
              f"step  {med(ts) / base:5.2f} x")  # fmt: skip
        print(f"      {s['counts'][name]}")
    windows = [med(times["nonlinear.simulate"][w * REPEATS : (w + 1) * REPEATS]) * 1e3 for w in range(WINDOWS)]
    windows_p = [med(times[base_name][w * REPEATS : (w + 1) * REPEATS]) * 1e3 for w in range(WINDOWS)]
    print(f"   medians per window: simulate {', '.join(f'{x:.2f}' for x in windows)} ms; phases.run "
          f"{', '.join(f'{x:.2f}' for x in windows_p)} ms")  # fmt: skip
    k = med(times["newmark.integrate (simulate's kernel alone)"])
    closest = med(times["phases.run check_every=1, history=True"])
    print(f"   what the switches do not reach (kernel alone / phases.run check_every=1, history=True): "
          f"{k / closest:.2f} x: inverse vs LU solve, the extrapolated predictor, the diagonal mass, simulate's "
          "u, v, a and 41-entry record kept every step")  # fmt: skip

    load = b["load"]
    print(f"\n2. Bits: the same 20 s run, one drive (the phases kernel's own, at t = k dt) and one start for both, "
          f"fixed {DT * 1e3:g} ms steps; wheel loads at all {n_steps + 1} rows; design wheel load "
          f"{load:.0f} N")  # fmt: skip
    print(f"   after one step (same predictor, checked correction, LU solve vs inverse): states "
          f"{'bit-identical' if b['one_step_same'] else 'DIFFERENT'}; simulate's step end d_k + 1.0 (d_(k+1) - d_k) "
          f"misses the drive row d_(k+1) in {b['ulps']:.1%} of its entries (by an ulp)")  # fmt: skip
    print(f"   simulate against itself at dt/{REFINEMENT} on that drive: max {b['sim_err']:.1f} N "
          f"({b['sim_err'] / load:.2e} of the design load); against itself from a start one ulp of chassis pitch "
          f"away (a last bit): max {b['ulp_max']:.2e} N; Newton's residual tolerance on an axle "
          f"{b['r_tol']:.3f} N (1e-5 of the design load)")  # fmt: skip
    for label, x in b["rows"].items():
        g = x["grow"]
        print(f"   phases.run {label}: max |dW| {x['max']:.3f} N ({x['max'] / load:.2e} of the design load) at "
              f"t = {x['at']:.2f} s, RMS {x['rms']:.3f} N; rows differing {x['steps_differing']:.1%}, the first: "
              f"loads row {x['first_load']}, chassis pitch row {x['first_pitch']}; |dW| first > 1e-6 N at row "
              f"{g[1e-6]}, > 1e-3 N at {g[1e-3]}, > 1 N at {g[1.0]}; its own error against simulate at "
              f"dt/{REFINEMENT}: max {x['err']:.1f} N")  # fmt: skip

    n = r["n"]
    print(f"\n3. Published readings: the {n} steel bogies among the first {N_BOGIES} of params.yaml's fleet sample")
    print(f"   WIM, error free, simulate (+ wim.sensor_reading on its history) against phases.run from the same start: "
          f"max {max(r['d_sim']):.3f} N ({max(r['rel_sim']):.2e} of the design load), median of the bogies' largest "
          f"{med(r['d_sim']):.3f} N; bit-identical {r['identical']['sim']} of {n}")  # fmt: skip
    print(f"     control, simulate against itself from a start one ulp of chassis pitch away: max "
          f"{max(r['d_ulp']):.2e} N, median {med(r['d_ulp']):.2e} N")  # fmt: skip
    print(f"     control, the same reading on phases's own history against its kernel's reading: max "
          f"{max(r['d_ctrl']):.2e} N; phases from that start against the published run from rest: max "
          f"{max(r['d_start']):.2e} N")  # fmt: skip
    for name in ("static", "wim"):
        d = r["d_ce"][name]
        print(f"   {name}: phases.run check_every=1 against the published reading: max {max(d):.3f} N "
              f"({max(r['rel_ce'][name]):.2e} of the design load), median {med(d):.3f} N; bit-identical "
              f"{r['identical'][name]} of {len(d)}")  # fmt: skip
    print(
        f"   the {n} WIM passes' time, best of {PASSES}: phases.run {r['t_phases'] * 1e3:.1f} ms, simulate + "
        f"reading {r['t_sim'] * 1e3:.1f} ms (inputs built outside the timing): {r['t_sim'] / r['t_phases']:.2f} x"
    )

    took = ", ".join(f"{c1 - c0:.0f} s" for c0, c1 in zip(clock, clock[1:]))
    print(f"\nsections 1, 2, 3 took {took}")
    print(f"load average (1, 5, 15 min): start {', '.join(f'{x:.2f}' for x in load_start)}; end "
          f"{', '.join(f'{x:.2f}' for x in load_end)} ({os.cpu_count()} cores)")  # fmt: skip


if __name__ == "__main__":
    main()
