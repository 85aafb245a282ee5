"""The reference's Table 1 runs: the trends it reports, each asserted (exact numbers differ; see docs/validation.md)."""

import numpy as np
import pytest

from bogie.presets import tandem_trrl
from bogie.road import RampedStep
from bogie.steel import cases, linear

#: Table 1's number of steps and time step
TABLE1_STEPS = {
    "L01": (400, 0.0625),
    "L02": (400, 0.0025),
    "L03": (200, 0.125),
    "L04": (200, 0.005),
    "L05": (400, 0.0025),
    "L06": (400, 0.0625),
    "L07": (400, 0.0625),
}


@pytest.fixture(scope="module")
def runs():
    return {name: cases.run(name) for name in ("L01", "L02", "L03", "L04", "L05", "L06", "L07")}


def test_every_run_succeeds_and_two_axle_p1_is_half_of_p(runs):
    for name, r in runs.items():
        assert r.success, name
        assert np.allclose(r.p1, r.p / 2.0), name
        n_steps, dt = TABLE1_STEPS[name]
        assert len(r.t) == n_steps + 1
        assert r.t[-1] == pytest.approx(n_steps * dt)


def test_soft_bush_equalises_better_at_low_speed(runs):
    assert runs["L03"].peak_p < 0.25 * runs["L01"].peak_p


def test_high_speed_is_much_worse_than_low_speed(runs):
    low = max(runs["L01"].peak_p, runs["L03"].peak_p)
    assert runs["L02"].peak_p > 3.0 * low
    assert runs["L04"].peak_p > 3.0 * low


def test_bush_damping_worsens_low_speed_equalisation(runs):
    assert runs["L06"].peak_p > 2.0 * runs["L01"].peak_p
    assert runs["L07"].peak_p > 2.0 * runs["L01"].peak_p


def test_bush_damping_worsens_high_speed_equalisation_when_the_equaliser_cannot_rock():
    # Our L05 peaks below L02 because damping quiets the equaliser's rocking mode (inertia 0.2 kg m^2); without
    # that mode the reference's finding (L05 worse than L02) holds. See docs/validation.md.
    l02 = cases.run("L02", equaliser_inertia=0.0)
    l05 = cases.run("L05", equaliser_inertia=0.0)
    assert l05.peak_p > 3.0 * l02.peak_p
    rocking = lambda r: np.max(np.abs(np.gradient(r.extras["equaliser_rotation_0"], r.t)))  # noqa: E731
    assert rocking(cases.run("L05")) < 0.5 * rocking(cases.run("L02"))


def test_low_speed_run_settles_to_the_quasi_static_state_with_the_front_wheel_on_the_step(runs):
    r = runs["L01"]
    bogie = cases.get("L01").bogie()
    # front wheel alone on the plateau from 3.25 s to 9.05 s (0.5 m lead, 0.15 m ramp, 1.5 m plateau, 0.2 m/s)
    early = r.p[(r.t > 3.5) & (r.t < 5.0)]
    late = r.p[(r.t > 7.5) & (r.t < 9.0)]
    m = linear.matrices(bogie)
    road = np.array([RampedStep().rise, 0.0])
    u = np.linalg.solve(m.K, m.road_stiffness @ road)
    loads = linear.wheel_loads_from_state(bogie, m, u, u * 0.0, np.zeros(2))
    p_static = abs(loads[0] - loads[1]) / r.reference_load
    assert late.mean() == pytest.approx(p_static, rel=0.03)
    assert np.ptp(late) < 0.1 * p_static
    assert np.ptp(early) < 0.15 * p_static


def test_l01s_residual_oscillation_is_the_equaliser_rocking_mode_as_newmark_maps_it(runs):
    """At the reference's dt = 0.0625 s the small oscillation of L01's p is numerical, not a physical decay.

    The equaliser rocks, with the chassis held, at omega = sqrt((K_S b^2 / 2 + K_B) / I) (docs/validation.md).
    Average-acceleration Newmark, undamped, maps a mode of angular frequency omega to 2 / dt atan(omega dt / 2)
    (period elongation, Newmark 1959): 28 Hz becomes 7.1 Hz at dt = 0.0625 s. At dt / 8 the oscillation is gone but
    for the chassis's own small pitch oscillation.
    """
    r = runs["L01"]
    bogie = cases.get("L01").bogie()
    dt = float(np.mean(np.diff(r.t)))
    window = (r.t > 3.5) & (r.t < 9.0)  # the front wheel alone on the plateau
    x = r.p[window] - r.p[window].mean()
    freq = np.fft.rfftfreq(len(x), dt)
    peak = freq[np.argmax(np.abs(np.fft.rfft(x))[1:]) + 1]
    omega = np.sqrt((bogie.combined_stiffness * bogie.equaliser_front_arm[0] ** 2 / 2 + bogie.bush_stiffness)
                    / bogie.equaliser_inertia)  # fmt: skip
    assert omega / (2 * np.pi) == pytest.approx(28.1, abs=0.1)
    mapped = 2.0 / dt * np.arctan(omega * dt / 2.0) / (2 * np.pi)
    assert peak == pytest.approx(mapped, abs=1.0 / (len(x) * dt))  # within one frequency bin, 0.18 Hz
    fine = linear.simulate(bogie, RampedStep(), 0.2, dt / 8, 8 * len(r.t) - 8, front_axle_start=-cases.STEP_LEAD)
    late = (fine.t > 7.5) & (fine.t < 9.0)
    coarse = (r.t > 7.5) & (r.t < 9.0)
    assert np.ptp(fine.p[late]) < 0.2 * np.ptp(r.p[coarse])  # it converges away: a numerical artefact


def test_unknown_case_and_frame():
    with pytest.raises(ValueError, match="unknown case 'L99'"):
        cases.get("L99")
    frame = cases.run("L03").to_frame()
    assert {"wheel_load_1", "wheel_load_2", "p", "p1", "centre_displacement"} <= set(frame.columns)
    assert frame.index.name == "t"


# ---- the tables as records -------------------------------------------------------------------------------------
def test_every_table_row_is_a_case_in_table_order():
    names = [row.name for row in cases.TABLE1] + [row.name for row in cases.TABLE2]
    assert names == list(cases.CASES)
    assert names == [f"L{k:02d}" for k in range(1, 8)] + [f"N{k:02d}" for k in range(1, 30)]
    for row in cases.TABLE1:
        case = cases.get(row.name)
        assert case.reference == {"peak_p": row.peak_p, "peak_p1": row.peak_p1}
        b = case.bogie()
        assert (b.bush_stiffness, b.bush_damping, b.axle_mass) == (row.bush_stiffness, row.bush_damping, row.axle_mass)
    for row in cases.TABLE2:
        assert cases.get(row.name).description.startswith(f"Table 2 block {row.block} run {row.name}: {row.what};")


def test_step_windows_use_the_preset_axle_spacing():
    # the phase windows were written for a 1.31 m spacing; they now follow tandem_trrl()'s geometry
    axle_x = tandem_trrl().axle_x
    assert axle_x[1] - axle_x[0] == pytest.approx(1.31, abs=1e-12)
    (f0, f1), (r0, r1) = cases._phase_windows(cases.LOW_SPEED)
    assert 0.0 < f0 < f1 < r0 < r1


def test_names_lists_every_run_and_get_refuses_what_is_not_a_name():
    assert cases.names() == [f"L0{i}" for i in range(1, 8)] + [f"N{i:02d}" for i in range(1, 30)]
    assert cases.get("n10").name == "N10"
    for bad in (None, 10, "N99"):
        with pytest.raises(ValueError, match=r"unknown case .*: must be one of L01, "):
            cases.get(bad)


def test_each_figure_has_the_unit_of_its_table():
    assert cases.get("L01").unit("peak_p1") == "[-]"  # Table 1: loads over their mean
    n10 = cases.get("N10")
    assert n10.unit("p1_front_on_step") == "N" and n10.unit("peak_p1") == "N"  # Table 2: newtons
    assert cases.get("N15").unit("rms") == "[-]"  # Equation 5 is non-dimensional


def test_a_table_2_history_plots_p1_in_newtons_with_the_references_figures():
    from types import SimpleNamespace

    from bogie.plotting import case_history

    t = np.linspace(0.0, 1.0, 11)
    loads = np.column_stack([np.full(11, 21e3), np.full(11, 23e3)])  # P1 = 1000 N throughout
    result = SimpleNamespace(t=t, wheel_loads=loads, p=np.zeros(11), p1=np.zeros(11), extras={})
    case = cases.get("N10")
    fig = case_history(result, case=case, ours={"p1_front_on_step": 1000.0})
    ax = fig.axes[0]
    assert ax.get_ylabel() == "P1 [N]"
    assert np.allclose(ax.lines[0].get_ydata(), 1000.0)
    levels = {round(float(line.get_ydata()[0])) for line in ax.lines[1:]}
    assert levels == {1000, 2700, 3200}  # ours, and the reference's front and rear on the step
    linear = case_history(result)  # without a case: the non-dimensional p and P1 as before
    assert linear.axes[0].get_ylabel() == "wheel load\nparameter [-]"


def test_the_summary_of_a_failed_run_is_refused_not_read_as_figures():
    from dataclasses import replace

    result = cases.run("L03")
    failed = replace(result, status="failed", message="Newton did not converge at t = 3.2 s")
    with pytest.raises(ValueError, match=r"run L03 failed \(Newton did not converge at t = 3.2 s\): it has no figures"):
        cases.summary("L03", failed)
    assert cases.summary("L03", result)  # the run itself has its figures
