"""Non-linear model: one 20 s tri-axle run at 1 ms steps, against scipy's Radau and BDF on the same force.

Four measurements, all in one process except the fresh-process ones (see ``bench/README.md``):

1. ``bogie.steel.nonlinear.simulate`` of ``triaxle_stage1()`` (preset inhibitors) over an ISO 8608 class B road at
   15 m/s for 20 s at dt = 1 ms: median of repeats after a warm-up (target under 50 ms), and the compiled kernel alone.
2. The peer: ``scipy.integrate.solve_ivp`` (Radau and BDF) on the model's first-order form x = [u, v, s],
   du/dt = v, M dv/dt = -f(u, v, s, drive(t)), ds/dt = (s_rm(u, s) - s) / tau, where f is the *same compiled*
   internal force :func:`bogie.steel.force.core.force` the kernel uses and s_rm the plastic slip its return map
   gives from the slip s: the friction force stays capped at the Coulomb limit and the slip relaxes to the
   return-mapped one in a time tau (a viscoplastic regularisation; tau -> 0 is the kernel's law). Both solvers see
   the same drive (the 1 ms input rows, linear in between). Errors are against our kernel at dt / 64 on that drive
   (checked against dt / 32). On the first 2 s of the run (solve_ivp takes seconds for 20 s), plus one full 20 s
   run of the cheapest setting that is as accurate as ours.
3. A fresh ``python -c`` process that imports bogie and runs 1 s of the tri-axle model, with a warm numba cache
   (target under 1 s) and with an empty one (compilation).
4. Cost against the number of axles: 2, 3, 4 axles on the tri-axle preset's chain (same springs, arms, spacing and
   design load per spring), 20 s at 1 ms.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from bogie.params import Bogie
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.road import ISO8608Profile
from bogie.steel import nonlinear as nl
from bogie.steel import phases
from bogie.steel.force import core
from bogie.steel.newmark import MODEL_NONLINEAR, IntegrationResult, consistent_acceleration, integrate

SPEED, DURATION, DT = 15.0, 20.0, 1e-3  # [m/s], [s], [s]
#: ISO 8608 class B, 400 m long so that the 300 m run does not repeat it
ROAD = dict(road_class="B", length=400.0, seed=1)
#: horizon of the solve_ivp comparison [s] (the first part of the 20 s run)
PEER_HORIZON = 2.0
#: the reference is our kernel at dt / REFINEMENT on the same drive, checked against dt / (REFINEMENT / 2)
REFINEMENT = 64
METHODS = ("Radau", "BDF")
#: the headline run is timed in 3 windows of HEADLINE_REPEATS runs spread over the benchmark
HEADLINE_REPEATS = 21
#: repeats of each timed solve_ivp setting; our short run is timed beside each, PEER_OURS_BATCH times
PEER_REPEATS, PEER_OURS_BATCH = 3, 5
#: the 20 s accuracy check uses our kernel at dt / FULL_REFINEMENT
FULL_REFINEMENT = 16
#: relaxation times of the regularised friction [s]
TAUS = (1e-2, 1e-3, 1e-4)
#: rtol values tried, loosest first; atol is rtol times each state's largest magnitude in the reference
RTOL_LADDER = (3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
#: rtol of the run that shows each tau's regularisation error (integration error negligible)
FLOOR_RTOL = 1e-5
#: axle spacing of the tri-axle preset's chain [m]
AXLE_SPACING = 1.31
ROOT = Path(__file__).resolve().parent.parent


# ---- problems --------------------------------------------------------------------------------------------------
def chain_bogie(n: int) -> Bogie:
    """``triaxle_stage1()`` with n axles: same spacing, springs, arms and inhibitors, same design load per spring.

    The payload scales with the sum of the axle positions so that every spring carries the tri-axle's design load
    (equal arms and spring halves share it equally); n = 3 is the preset itself.
    """
    base = triaxle_stage1()
    x = tuple(round(base.axle_x[0] + AXLE_SPACING * i, 9) for i in range(n))
    payload = base.payload_mass * sum(x) / sum(base.axle_x)
    arm = base.equaliser_front_arm[0]
    return base.replace(
        axle_x=x,
        spring_front_half_length=(base.spring_front_half_length[0],) * n,
        spring_rear_half_length=(base.spring_rear_half_length[0],) * n,
        equaliser_front_arm=(arm,) * (n - 1),
        equaliser_rear_arm=(arm,) * (n - 1),
        tyre_wear=(0.0,) * n,
        payload_mass=payload,
        chassis_pitch_inertia=payload * base.chassis_pitch_inertia / base.payload_mass,
    )


def road_inputs(bogie: Bogie, duration: float) -> nl.Inputs:
    """The benchmark's road pass: ISO 8608 class B at 15 m/s, dt = 1 ms."""
    return nl.road_inputs(bogie, ISO8608Profile(**ROAD), SPEED, duration, DT)


def refined(inputs: nl.Inputs, r: int) -> nl.Inputs:
    """The same drive at dt / r: the rows linearly interpolated, as the kernel's sub-steps see them."""
    t = np.arange(inputs.n_steps * r + 1) * (inputs.dt / r)

    def interp(a: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.column_stack([np.interp(t, inputs.t, col) for col in a.T])

    return nl.Inputs(
        inputs.dt / r,
        interp(inputs.road_height),
        interp(inputs.road_rate),
        np.interp(t, inputs.t, inputs.load_factor),
        np.interp(t, inputs.t, inputs.kingpin_rise),
    )


@dataclass(frozen=True)
class KernelCall:
    """The arguments :func:`bogie.steel.nonlinear.simulate` passes to the compiled kernel, prepared once."""

    bogie: Bogie
    inputs: nl.Inputs
    mass: NDArray[np.float64]
    data_f: NDArray[np.float64]
    data_i: NDArray[np.int64]
    drive: NDArray[np.float64]
    state: nl.State
    a0: NDArray[np.float64]

    @classmethod
    def prepare(cls, bogie: Bogie, inputs: nl.Inputs) -> KernelCall:
        """Pack, static start (relaxed friction) and consistent acceleration, as ``simulate`` does."""
        mass, data_f, data_i = nl.pack(bogie)
        drive = inputs.drive(bogie)
        state = nl.equilibrium(bogie, drive[0])
        n = bogie.n_axles
        f0 = np.zeros(2 * n)
        core.force(
            state.u, state.v, drive[0], data_f, data_i, state.history, state.history.copy(), f0,
            np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n)), np.zeros(core.RECORD_PER_AXLE * n), False, False,
            np.zeros(nl.work_size(bogie)),
        )  # fmt: skip
        return cls(bogie, inputs, mass, data_f, data_i, drive, state, consistent_acceleration(mass, f0))

    def run(self) -> IntegrationResult:
        """The kernel call of ``simulate`` (its defaults: average-acceleration Newmark, 25 iterations, 5 halvings)."""
        b, s = self.bogie, self.state
        return integrate(
            MODEL_NONLINEAR, self.mass, self.drive, self.data_f, self.data_i, s.u.copy(), s.v.copy(), self.a0,
            s.history.copy(), self.inputs.dt, self.inputs.n_steps, nl.residual_tolerance(b), max_iter=25,
            max_halvings=5, n_record=core.RECORD_PER_AXLE * b.n_axles, work_size=nl.work_size(b), limits=nl.limits(b),
        )  # fmt: skip


class FirstOrderForm:
    """x = [u, v, s] with du/dt = v, M dv/dt = -f(u, v, s, drive(t)), ds/dt = (s_rm(u, s) - s) / tau.

    f and s_rm come from one call of the compiled :func:`bogie.steel.force.core.force` with the slip s as the
    friction history: f holds the friction force of the return map (capped at the Coulomb limit mu N) and s_rm is
    the plastic slip the return map would commit. During stick s_rm = s; during slip s relaxes towards s_rm with
    time constant tau. The right-hand side is Lipschitz continuous but not smooth at stick/slip changes.
    """

    def __init__(self, call: KernelCall) -> None:
        self.call = call
        self.n_dof = call.mass.shape[0]
        self.m_inv = np.linalg.inv(call.mass)
        n = call.bogie.n_axles
        self.n_axles = n
        if call.bogie.spring_friction_band != 0.0:
            raise ValueError("the first-order form carries the end slips only: give a bogie without a friction band")
        self._rest = np.zeros(core.history_length(n) - 2 * n)
        self._scratch = (
            np.zeros(self.n_dof),
            np.zeros((self.n_dof, self.n_dof)),
            np.zeros((self.n_dof, self.n_dof)),
            np.zeros(core.RECORD_PER_AXLE * n),
            np.zeros(nl.work_size(call.bogie)),
            np.zeros(core.history_length(n)),
            call.drive[0].copy(),
        )

    def initial_state(self) -> NDArray[np.float64]:
        s = self.call.state
        return np.concatenate([s.u, s.v, s.slip])

    def _history(self, s: NDArray[np.float64]) -> NDArray[np.float64]:
        """The force's history for slips ``s``: the springs' deflections and hysteretic forces after them, which
        the peer's bogie (no interleaf friction band) never reads."""
        return np.concatenate([s, self._rest])

    def rhs(self, tau: float):
        """dx/dt(t, x) for relaxation time ``tau`` [s]; the drive is linear between the 1 ms rows."""
        nd, m_inv, drive = self.n_dof, self.m_inv, self.call.drive
        dt, last = self.call.inputs.dt, self.call.inputs.n_steps - 1
        data_f, data_i = self.call.data_f, self.call.data_i
        f, kt, ct, rec, work, s_rm, drv = self._scratch
        force, history = core.force, self._history

        def rhs(t: float, x: NDArray[np.float64]) -> NDArray[np.float64]:
            x = np.ascontiguousarray(x)  # solve_ivp's finite-difference Jacobian passes columns
            k = min(int(t / dt), last)
            np.add(drive[k], (t / dt - k) * (drive[k + 1] - drive[k]), out=drv)
            s = x[2 * nd :]
            force(x[:nd], x[nd : 2 * nd], drv, data_f, data_i, history(s), s_rm, f, kt, ct, rec, False, False, work)
            return np.concatenate([x[nd : 2 * nd], -(m_inv @ f), (s_rm[: s.shape[0]] - s) / tau])

        return rhs

    def wheel_loads(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """Tyre loads [N] at the input rows from states x, shape (n_rows, 3 n_dof)."""
        nd, n = self.n_dof, self.n_axles
        f, kt, ct, rec, work, s_rm, _ = self._scratch
        out = np.empty((x.shape[0], n))
        for k, row in enumerate(x):
            u, v, s = (np.ascontiguousarray(row[j * nd : (j + 1) * nd]) for j in range(3))
            core.force(
                u, v, self.call.drive[k], self.call.data_f, self.call.data_i, self._history(s), s_rm, f, kt, ct, rec,
                True, False, work,
            )  # fmt: skip
            out[k] = rec[:n]
        return out


def peer(form: FirstOrderForm, method: str, tau: float, rtol: float, atol: NDArray[np.float64]):
    """solve_ivp on the first-order form, output at the input rows; Jacobian by solve_ivp's finite differences."""
    inputs = form.call.inputs
    return solve_ivp(
        form.rhs(tau), (0.0, float(inputs.t[-1])), form.initial_state(), method=method, t_eval=inputs.t,
        rtol=rtol, atol=atol,
    )  # fmt: skip


# ---- measuring -------------------------------------------------------------------------------------------------
def interleaved(fns: dict[str, Callable[[], object]], repeats: int) -> dict[str, list[float]]:
    """Wall times [s] of each function, called in turn ``repeats`` times, so that all see the same machine load."""
    times: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            start = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - start)
    return times


def process_time(code: str, env: dict[str, str] | None = None, repeats: int = 3) -> float:
    """Median wall time of ``python -c code`` in a new process at the project root [s]."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def errors(w: NDArray[np.float64], w_ref: NDArray[np.float64], load: float) -> tuple[float, float]:
    """Largest and RMS difference in W / W_ref over the input rows and axles [-]."""
    d = (w - w_ref) / load
    return float(np.max(np.abs(d))), float(np.sqrt(np.mean(d**2)))


@dataclass
class PeerRow:
    """One solve_ivp setting: errors (None if it failed), counts, and if timed its time and ours beside it [s]."""

    method: str
    tau: float
    rtol: float
    err: tuple[float, float] | None
    nfev: int
    njev: int
    as_accurate: bool
    t_peer: float | None = None
    t_ours: float | None = None


def main() -> None:
    med = statistics.median
    # ---- 1. the 20 s tri-axle run ----
    bogie = triaxle_stage1()
    if chain_bogie(3) != bogie:
        raise RuntimeError("chain_bogie(3) is not the triaxle_stage1() preset")
    n = bogie.n_axles
    inputs = road_inputs(bogie, DURATION)
    n_steps = inputs.n_steps
    result = nl.simulate(bogie, inputs)  # warm-up: loads (or compiles) the kernel
    if not result.success:
        raise RuntimeError(f"the benchmark run failed: {result.message}")
    call = KernelCall.prepare(bogie, inputs)
    kernel = call.run()
    if not np.array_equal(kernel.record[:, :n], result.wheel_loads):
        raise RuntimeError("the benchmark's kernel call differs from bogie.steel.nonlinear.simulate")
    # the weighings' kernel (bogie.steel.phases, docs/phases.md) on the same pass: fixed 1 ms steps, the same start
    # at rest, no histories kept; its road is the profile's own grid (exact rates) where simulate's inputs sample it
    # per row
    profile = ISO8608Profile(**ROAD)
    table = phases.RoadTable.from_profile(
        profile, bogie.axle_x[0] - bogie.axle_x[-1] - 0.01, SPEED * DURATION + 0.01, profile.grid_spacing
    )
    pass_phase = [phases.Phase(DURATION, 1.0, road=table, speed=SPEED, dt=DT, name="pass")]
    phased = phases.run(bogie, pass_phase, history=True)
    if not phased.success or len(phased.t) != n_steps + 1:
        raise RuntimeError(f"the phases run failed: {phased.message}")
    load_start = os.getloadavg()[0]
    headline_fns = {
        "simulate": lambda: nl.simulate(bogie, inputs),
        "kernel": call.run,
        "phases": lambda: phases.run(bogie, pass_phase),
    }
    # timed in three windows spread over the run (start, after the peer, after the axle scaling), so that
    # a burst of other work on the machine moves the median less
    windows = [interleaved(headline_fns, HEADLINE_REPEATS)]
    stick = result.extras["stick"]
    slipping = float(np.mean(stick == 0.0))
    changes = int(np.sum(np.abs(np.diff(stick, axis=0))))

    # ---- 2. the peer on the first PEER_HORIZON seconds ----
    # the peer's first-order form carries the end slips as its friction state; the springs' interleaf friction
    # (a Fancher hysteresis with its own history) is not in it, so the comparison runs the preset without the band
    peer_bogie = bogie.replace(spring_friction_band=0.0)
    short = road_inputs(peer_bogie, PEER_HORIZON)
    load = result.reference_load
    fine = KernelCall.prepare(peer_bogie, refined(short, REFINEMENT)).run()
    half = KernelCall.prepare(peer_bogie, refined(short, REFINEMENT // 2)).run()
    w_ref = fine.record[::REFINEMENT, :n]
    e_ref = errors(half.record[:: REFINEMENT // 2, :n], w_ref, load)
    short_call = KernelCall.prepare(peer_bogie, short)
    e_ours = errors(short_call.run().record[:, :n], w_ref, load)
    form = FirstOrderForm(short_call)
    slip_ref = fine.record[:, 8 * n : 10 * n]
    x_scale = np.maximum(np.max(np.abs(np.column_stack([fine.u, fine.v, slip_ref])), axis=0), 1e-9)

    def peer_run(method: str, tau: float, rtol: float):
        sol = peer(form, method, tau, rtol, rtol * x_scale)
        err = errors(form.wheel_loads(sol.y.T), w_ref, load) if sol.success else None
        return err, sol

    def ours_short() -> None:
        for _ in range(PEER_OURS_BATCH):
            nl.simulate(peer_bogie, short)

    floors = {tau: peer_run("Radau", tau, FLOOR_RTOL)[0] for tau in TAUS}
    rows: list[PeerRow] = []
    for method in METHODS:
        for tau in TAUS:
            floor = floors[tau]
            if floor is None or floor[0] > e_ours[0] or floor[1] > e_ours[1]:
                continue  # this tau's regularisation alone is less accurate than our kernel
            for rtol in RTOL_LADDER:
                err, sol = peer_run(method, tau, rtol)
                ok = err is not None and err[0] <= e_ours[0] and err[1] <= e_ours[1]
                row = PeerRow(method, tau, rtol, err, sol.nfev, sol.njev, ok)
                rows.append(row)
                if ok:
                    times = interleaved(
                        {
                            "peer": lambda m=method, ta=tau, r=rtol: peer(form, m, ta, r, r * x_scale),
                            "ours": ours_short,
                        },
                        PEER_REPEATS,
                    )
                    row.t_peer, row.t_ours = med(times["peer"]), med(times["ours"]) / PEER_OURS_BATCH
                    break
    timed = [r for r in rows if r.t_peer is not None]
    best = min(timed, key=lambda r: r.t_peer / r.t_ours) if timed else None
    t_short = interleaved({"simulate": lambda: nl.simulate(peer_bogie, short), "kernel": short_call.run}, 31)
    # cost of one right-hand side call, and the whole 20 s with the cheapest setting
    rhs = form.rhs(TAUS[1])
    x0 = form.initial_state()
    t_rhs = med(interleaved({"rhs": lambda: [rhs(0.5, x0) for _ in range(1000)]}, 5)["rhs"]) / 1000
    full_ref = KernelCall.prepare(bogie, refined(inputs, FULL_REFINEMENT)).run().record[::FULL_REFINEMENT, :n]
    e_ours_full = errors(kernel.record[:, :n], full_ref, load)
    e_phases_full = errors(phased.wheel_loads, full_ref, load)
    if best is not None:
        peer_call = KernelCall.prepare(peer_bogie, inputs)
        peer_ref = KernelCall.prepare(peer_bogie, refined(inputs, FULL_REFINEMENT)).run().record[::FULL_REFINEMENT, :n]
        e_peer_ours_full = errors(peer_call.run().record[:, :n], peer_ref, load)
        full_form = FirstOrderForm(peer_call)
        start = time.perf_counter()
        full = peer(full_form, best.method, best.tau, best.rtol, best.rtol * x_scale)
        t_full = time.perf_counter() - start
        e_full = errors(full_form.wheel_loads(full.y.T), peer_ref, load) if full.success else None
    windows.append(interleaved(headline_fns, HEADLINE_REPEATS))  # also the time beside the peer's 20 s run
    t_sim_full = med(windows[-1]["simulate"])

    # ---- 4. cost against the number of axles ----
    family = [(f"{k} axles (tri-axle chain)", chain_bogie(k)) for k in (2, 3, 4)] + [("tandem_trrl()", tandem_trrl())]
    fns, iters = {}, {}
    for label, b in family:
        inp = road_inputs(b, DURATION)
        kc = KernelCall.prepare(b, inp)
        res = kc.run()
        if not res.success:
            raise RuntimeError(f"{label}: {res.message}")
        iters[label] = res.n_iterations / inp.n_steps
        fns[label] = lambda b=b, inp=inp: nl.simulate(b, inp)
        fns[label + " kernel"] = kc.run
    scaling = interleaved(fns, 9)
    windows.append(interleaved(headline_fns, HEADLINE_REPEATS))
    headline = {name: [t for w in windows for t in w[name]] for name in headline_fns}
    t_sim, t_kernel, t_phases = med(headline["simulate"]), med(headline["kernel"]), med(headline["phases"])

    # ---- 3. fresh processes ----
    code = (
        "import bogie.steel.nonlinear as nl; from bogie.params import triaxle_stage1; "
        "from bogie.road import ISO8608Profile; "
        "b = triaxle_stage1(); nl.simulate(b, nl.road_inputs(b, ISO8608Profile('B', seed=1), 15.0, 1.0, 1e-3))"
    )
    process_time(code, repeats=1)  # warms numba's on-disk cache if the sources changed since the last run
    t_first = process_time(code)
    t_import = process_time("import bogie.steel.nonlinear, bogie.road")
    t_numba = process_time("import bogie.steel.nonlinear, bogie.road; bogie.steel.force.core.scratch_size(3)")
    with tempfile.TemporaryDirectory() as cache:
        t_cold = process_time(code, env={**os.environ, "NUMBA_CACHE_DIR": cache}, repeats=1)

    # ---- report ----
    print(f"triaxle_stage1() (preset inhibitors), ISO 8608 class B ({ROAD['length']:g} m, seed {ROAD['seed']}) at "
          f"{SPEED:g} m/s, {DURATION:g} s in {n_steps} steps of {DT * 1e3:g} ms; {2 * n} freedoms, {2 * n} friction "
          f"contacts slipping {100 * slipping:.1f} % of the time, {changes} stick/slip changes")  # fmt: skip
    verdict = "met" if t_sim < 0.05 else "NOT met"
    n_rep = len(headline["simulate"])
    print(f"Load average (1 min) of the machine at the start {load_start:.1f}, at the end {os.getloadavg()[0]:.1f} "
          f"on {os.cpu_count()} cores")  # fmt: skip
    print(f"1. One {DURATION:g} s run (median of {n_rep} after a warm-up, least in brackets; single-threaded):")
    print(f"   bogie.steel.nonlinear.simulate (pack, static start, kernel, result) {t_sim * 1e3:6.1f} ms "
          f"({min(headline['simulate']) * 1e3:.1f})  {t_sim / n_steps * 1e6:.2f} us per step   "
          f"target < 50 ms: {verdict}")  # fmt: skip
    print(f"   compiled kernel alone (bogie.steel.newmark.integrate)               {t_kernel * 1e3:6.1f} ms "
          f"({min(headline['kernel']) * 1e3:.1f})  {t_kernel / n_steps * 1e6:.2f} us per step, "
          f"{kernel.n_iterations / n_steps:.2f} Newton iterations per step")  # fmt: skip
    evals = phased.phases[0].force_evaluations / n_steps
    verdict = "met" if t_phases < 0.01 else "NOT met"
    print(f"   bogie.steel.phases.run (the weighings' kernel, readings only)       {t_phases * 1e3:6.1f} ms "
          f"({min(headline['phases']) * 1e3:.1f})  {t_phases / n_steps * 1e6:.2f} us per step, "
          f"{evals:.2f} force evaluations per step   target <= 10 ms: {verdict}")  # fmt: skip
    print(f"   wheel loads W / W_ref against the kernel at dt/{FULL_REFINEMENT}: simulate max {e_ours_full[0]:.2e} "
          f"RMS {e_ours_full[1]:.2e}, phases max {e_phases_full[0]:.2e} RMS {e_phases_full[1]:.2e} (its road's "
          "rates are exact, simulate's sampled per row)")  # fmt: skip
    window_text = ", ".join(f"{med(w['simulate']) * 1e3:.1f}" for w in windows)
    print(f"   simulate's median in each of the {len(windows)} windows of {HEADLINE_REPEATS} runs: {window_text} ms")
    print(f"2. Peer: solve_ivp on the first-order form [u, v, s] with the same compiled force, friction regularised "
          f"(the slip s relaxes to the return map's in tau); the first {PEER_HORIZON:g} s of the run, the preset "
          "without its springs' interleaf friction band (the form has no hysteresis state)")  # fmt: skip
    print(f"   accuracy: W / W_ref against our kernel at dt/{REFINEMENT} on the same drive (dt/{REFINEMENT // 2} "
          f"differs from it by max {e_ref[0]:.1e}, RMS {e_ref[1]:.1e})")  # fmt: skip
    print(f"   ours at dt = {DT * 1e3:g} ms: max {e_ours[0]:.2e}, RMS {e_ours[1]:.2e}; simulate "
          f"{med(t_short['simulate']) * 1e3:.2f} ms, kernel alone {med(t_short['kernel']) * 1e3:.2f} ms "
          "(median of 31)")  # fmt: skip
    floor_text = ", ".join(
        f"tau {tau:g} s " + ("failed" if e is None else f"max {e[0]:.1e} RMS {e[1]:.1e}") for tau, e in floors.items()
    )
    print(f"   regularisation error alone (Radau at rtol {FLOOR_RTOL:g}): {floor_text}")
    print(f"   one right-hand side call (compiled force + numpy): {t_rhs * 1e6:.0f} us")
    print(f"   method  tau [s]  rtol    max err   RMS err   rhs calls  Jacobians  time [ms]  peer / simulate "
          f"(ours timed beside it, median of {PEER_REPEATS})")  # fmt: skip
    for r in rows:
        e_text = "failed              " if r.err is None else f"{r.err[0]:.2e}  {r.err[1]:.2e}"
        timing = f"{r.t_peer * 1e3:9.0f}  {r.t_peer / r.t_ours:6.0f} x" if r.t_peer is not None else f"{'-':>9}"
        print(f"   {r.method:<6}  {r.tau:<7g}  {r.rtol:<6g}  {e_text}  {r.nfev:9d}  {r.njev:9d}  {timing}"
              f"{'  as accurate as ours' if r.as_accurate else ''}")  # fmt: skip
    if best is None:
        print("   No solve_ivp setting tried was as accurate as ours.")
    else:
        print(f"   Ratio peer / ours at equal accuracy (cheapest above, {best.method}, tau {best.tau:g} s, rtol "
              f"{best.rtol:g}): {best.t_peer / best.t_ours:.0f} x against simulate")  # fmt: skip
        e_text = "failed" if e_full is None else f"max {e_full[0]:.1e} RMS {e_full[1]:.1e}"
        print(
            f"   The same setting over the whole {DURATION:g} s (one run): {t_full:.2f} s, {full.nfev} rhs calls, "
            f"error {e_text} (ours: max {e_peer_ours_full[0]:.1e} RMS {e_peer_ours_full[1]:.1e}, against our kernel at "
            f"dt/{FULL_REFINEMENT}); {t_full / t_sim_full:.0f} x our simulate ({t_sim_full * 1e3:.1f} ms)"
        )
    print(f"3. Fresh process, `python -c` importing bogie and running {1.0:g} s of the tri-axle model (median of 3):")
    print(f"   warm numba cache {t_first:.2f} s   target < 1 s: {'met' if t_first < 1.0 else 'NOT met'}")
    print(f"     import bogie.steel.nonlinear, bogie.road alone {t_import:.2f} s; import + first call of any cached "
          f"numba function {t_numba:.2f} s")  # fmt: skip
    print(f"   empty cache (compiles everything) {t_cold:.1f} s (one run)")
    print(f"4. Cost against the number of axles ({DURATION:g} s at {DT * 1e3:g} ms; median of 9, interleaved):")
    print(
        "   bogie                       freedoms  simulate [ms]  per step [us]  kernel [ms]  iterations/step  "
        "ratio to 2 axles"
    )
    base = med(scaling[family[0][0]])
    for label, b in family:
        elapsed, t_k = med(scaling[label]), med(scaling[label + " kernel"])
        print(f"   {label:<26}  {2 * b.n_axles:8d}  {elapsed * 1e3:13.1f}  {elapsed / n_steps * 1e6:13.2f}  "
              f"{t_k * 1e3:11.1f}  {iters[label]:15.2f}  {elapsed / base:8.2f} x")  # fmt: skip


if __name__ == "__main__":
    main()
