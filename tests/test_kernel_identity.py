"""The time-stepping kernel reproduces stored runs bit for bit: a speed-up of its implementation changes no result.

``tests/data/kernel_identity.npz`` was written by this file's ``__main__`` (``python tests/test_kernel_identity.py
tests/data/kernel_identity.npz``) with the kernels as issue 15 left them (the force without atan2 and library sin/cos,
with fused multiply-adds; its formulation is checked against the former one in ``tests/test_force_formulation.py``):
the tri-axle and tandem presets over an ISO 8608 class B road at 15 m/s (Newmark and generalised-alpha), a load ramp
and a hold continued from its final state, the quasi-static path, a coarse-step run whose steps fail and are
retried as sub-steps, one that fails outright, and direct kernel runs (iteration counts, status, the record)
including the linear model id. Every 10th row and the last are stored (about 200 kB). A change of the kernels'
arithmetic (operation order included) fails this test: an implementation speed-up must not change one bit, and a
change of the arithmetic rewrites the file on purpose, with the reason in its commit.

Bits are defined on the machine that wrote the file: numba compiles for the host CPU (where fused multiply-adds
contract is the instruction set's choice), numpy and BLAS dispatch by the CPU's features. The machine and library
facts (``tests/_fingerprint.py``) are stored beside the runs in ``kernel_identity.machine.json``; where they differ,
each stored array must instead agree within ``FOREIGN_RTOL`` of its largest magnitude, integers (status, step and
iteration counts) and the NaN pattern exactly. Measured: numba compiling for Haswell with numpy's AVX-512 loops
disabled moved the arrays by at most 1.7e-9 of their scale, another CI machine by 3.5e-8 (the run that fails, whose
last state is an unconverged iterate); a change of a formula moves them by orders of magnitude more.
"""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from _fingerprint import describe, fingerprint

from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.road import ISO8608Profile
from bogie.steel import nonlinear as nl
from bogie.steel.force import core
from bogie.steel.newmark import MODEL_LINEAR, MODEL_NONLINEAR, consistent_acceleration, integrate

DATA = Path(__file__).parent / "data" / "kernel_identity.npz"
MACHINE = DATA.with_name("kernel_identity.machine.json")
SCALAR_KEYS = ("status", "n", "n_iterations")
#: off the machine that wrote the runs: largest |difference| as a fraction of the stored array's largest magnitude
FOREIGN_RTOL = 1e-6


def _thin(key, value):
    """Every 10th row and the last of a history; scalars, final states and history variables as they are."""
    field = key.split("/")[1]
    if field in SCALAR_KEYS or field == "history" or field.startswith("final_") or value.shape[0] <= 20:
        return value
    rows = np.unique(np.r_[np.arange(0, value.shape[0], 10), value.shape[0] - 1])
    return value[rows]


def _cases():
    prof = ISO8608Profile("B", length=400, seed=1)
    tri, tan = triaxle_stage1(), tandem_trrl()
    rough = ISO8608Profile("D", length=400, seed=2)
    out = {}
    out["tri_road"] = nl.simulate(tri, nl.road_inputs(tri, prof, 15.0, 2.0, 1e-3))
    out["tan_road"] = nl.simulate(tan, nl.road_inputs(tan, prof, 15.0, 2.0, 1e-3))
    r = nl.simulate(tri, nl.load_ramp(tri, 0.2, 1.0, 1.0, 1e-3))
    out["tri_ramp"] = r
    out["tri_hold"] = nl.simulate(tri, nl.hold(tri, 0.5, 1e-3), initial=r.final_state)
    out["tan_galpha"] = nl.simulate(tan, nl.road_inputs(tan, prof, 15.0, 1.0, 1e-3), rho_inf=0.8)
    # a coarse step with a tight iteration budget: steps fail and are retried as sub-steps
    out["tri_substeps"] = nl.simulate(tri, nl.road_inputs(tri, rough, 25.0, 1.0, 4e-3), max_iter=2, max_halvings=5)
    # one that fails outright (no sub-steps allowed)
    out["tri_fail"] = nl.simulate(tri, nl.road_inputs(tri, rough, 25.0, 1.0, 4e-3), max_iter=1, max_halvings=0)
    out["tri_static"] = nl.static_loads(tri, nl.load_ramp(tri, 0.2, 1.0, 0.2, 1e-3))
    return out


def _raw_runs():
    """Direct kernel runs (iteration counts and status): the non-linear model and the linear model id."""
    res = {}
    tri = triaxle_stage1()
    prof = ISO8608Profile("D", length=400, seed=2)
    for name, dt, mi, mh in (("k_sub", 4e-3, 2, 5), ("k_fail", 4e-3, 1, 0), ("k_ok", 1e-3, 25, 5)):
        inputs = nl.road_inputs(tri, prof, 25.0, 1.0, dt)
        mass, data_f, data_i = nl.pack(tri)
        drive = inputs.drive(tri)
        st = nl.equilibrium(tri, drive[0])
        n_rec = core.record_length(3)
        f0 = np.zeros(6)
        hn = st.history.copy()
        core.force(
            st.u,
            st.v,
            drive[0],
            data_f,
            data_i,
            st.history,
            hn,
            f0,
            np.zeros((6, 6)),
            np.zeros((6, 6)),
            np.zeros(n_rec),
            False,
            False,
            np.zeros(nl.work_size(tri)),
        )
        a0 = consistent_acceleration(mass, f0)
        res[name] = integrate(
            MODEL_NONLINEAR,
            mass,
            drive,
            data_f,
            data_i,
            st.u.copy(),
            st.v.copy(),
            a0,
            st.history.copy(),
            inputs.dt,
            inputs.n_steps,
            nl.residual_tolerance(tri),
            max_iter=mi,
            max_halvings=mh,
            n_record=n_rec,
            work_size=nl.work_size(tri),
            limits=nl.limits(tri),
        )
    rng = np.random.default_rng(3)
    n = 3
    M = np.diag([2.0, 1.0, 1.5])
    K = np.array([[300.0, -100, 0], [-100, 250, -80], [0, -80, 200]])
    C = 0.01 * K + 0.1 * M
    loads = rng.normal(size=(501, n))
    a0 = np.linalg.solve(M, loads[0])
    res["k_linear"] = integrate(
        MODEL_LINEAR,
        M,
        loads,
        np.concatenate([K.ravel(), C.ravel()]),
        np.array([n]),
        np.zeros(n),
        np.zeros(n),
        a0,
        np.zeros(0),
        0.01,
        500,
        np.full(n, 1e-9),
        rho_inf=0.7,
    )
    return res


def arrays():
    d = {}
    for name, r in _cases().items():
        ex = r.extras
        d[f"{name}/status"] = np.array([r.status == "ok"])
        d[f"{name}/n"] = np.array([len(r.t)])
        d[f"{name}/wheel_loads"] = r.wheel_loads
        for key in (
            "chassis_pitch",
            "equaliser_rotation",
            "axle_displacement",
            "spring_load",
            "friction_force",
            "stick",
            "plastic_slip",
            "spring_hysteresis",
            "stop_moment",
            "axle_position",
        ):
            d[f"{name}/{key}"] = np.asarray(ex[key])
        if r.final_state is not None:
            for k in ("u", "v", "a", "history"):
                d[f"{name}/final_{k}"] = getattr(r.final_state, k)
    for name, r in _raw_runs().items():
        d[f"{name}/status"] = np.array([r.status])
        d[f"{name}/n_iterations"] = np.array([r.n_iterations])
        d[f"{name}/n"] = np.array([len(r.t)])
        for k in ("u", "v", "a", "record"):
            d[f"{name}/{k}"] = getattr(r, k)
        d[f"{name}/history"] = r.history
    return d


def _computed():
    return {key: _thin(key, value) for key, value in arrays().items()}


@pytest.fixture(scope="module")
def computed():
    return _computed()


def test_the_stored_runs_are_all_computed(computed):
    stored = np.load(DATA)
    assert sorted(stored.files) == sorted(computed)


def _stored_machine() -> dict:
    return json.loads(MACHINE.read_text()) if MACHINE.exists() else {}


@pytest.mark.parametrize("key", sorted(np.load(DATA).files) if DATA.exists() else [])
def test_the_kernels_reproduce_the_stored_run_bit_for_bit(computed, key):
    stored = np.load(DATA)[key]
    got = computed[key]
    assert got.shape == stored.shape
    there, here = _stored_machine(), fingerprint()
    if there == here or stored.dtype.kind in "biu":
        same = np.array_equal(got, stored, equal_nan=stored.dtype.kind == "f")
        assert same, (
            f"{key}: {got!r} against {stored!r}"
            if stored.dtype.kind in "biu"
            else (f"{key}: largest difference {np.nanmax(np.abs(got - stored), initial=0.0):.3g}")
        )
        return
    # another machine or library build: the same runs to FOREIGN_RTOL of each array's scale
    assert np.array_equal(np.isnan(got), np.isnan(stored)), f"{key}: NaN where the stored run has none, or not"
    finite = ~np.isnan(stored)
    scale = float(np.max(np.abs(stored[finite]), initial=0.0))
    worst = float(np.max(np.abs(got[finite] - stored[finite]), initial=0.0))
    assert worst <= FOREIGN_RTOL * scale, (
        f"{key}: largest difference {worst:.3g} is {worst / scale:.3g} of the array's scale {scale:.3g}, allowed "
        f"{FOREIGN_RTOL:g} off the machine that wrote the runs ({describe(there, here)})"
    )


def test_the_machine_that_wrote_the_runs_is_recorded():
    there = _stored_machine()
    assert set(there) == set(fingerprint()), f"{MACHINE.name} lacks or has extra facts: {sorted(there)}"


if __name__ == "__main__":
    np.savez_compressed(sys.argv[1], **_computed())
    MACHINE.write_text(json.dumps(fingerprint(), indent=1) + "\n")
