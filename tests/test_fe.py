import math

import numpy as np
import pytest

from bogie.cli import main
from bogie.metrics import p
from bogie.presets import tandem_trrl, triaxle_stage1
from bogie.steel.fe import FrameModel, MeshOptions, beam_local_stiffness, fe_wheel_loads, figure2_points, solve_fe
from bogie.steel.static import nondimensional_loads, solve_static, wheel_loads

EA, EI, L, P = 2.0e8, 5.0e4, 1.7, 1.0e3  # [N], [N m^2], [m], [N]
ALPHA = 0.057  # [m]

# FE vs static, no drag links: the FE gives the "rigid" parts (hangers, brackets, equaliser arms, axle, wheel,
# slipper contacts) steel stiffness; their series compliance, about 1.5e-9 m/N against 1/K_S = 2.3e-6 m/N, makes
# the FE loads lower by about 7e-4 of the mean load (docs/fe-model.md). Largest seen over q and slope: 1.2e-3.
LOAD_TOL = 2e-3  # relative to the mean load [-]
P_TOL = 1.5e-3  # absolute on p [-]


def _bogie_with_q(q: float):
    b = triaxle_stage1()
    arm = b.equaliser_front_arm[0]
    k_b = 0.0 if math.isinf(q) else arm * arm * b.combined_stiffness / (4.0 * q)
    return b.replace(bush_stiffness=k_b)


# ---- element level ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 117.0])
def test_cantilever_tip_deflection_rotation_and_stretch(angle_deg):
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    m = FrameModel()
    root, tip = m.add_node(0.0, 0.0, "root"), m.add_node(L * c, L * s, "tip")
    m.add_beam(root, tip, EA, EI, name="beam")
    m.fix(root)
    # transverse load P along the element's local z' (x' turned 90 degrees towards z) plus an axial pull P
    m.add_load(tip, "u", -P * s + P * c)
    m.add_load(tip, "w", P * c + P * s)
    sol = m.solve()
    u, w, theta = sol.node("tip")
    transverse = -u * s + w * c
    axial = u * c + w * s
    assert transverse == pytest.approx(P * L**3 / (3 * EI), rel=1e-10)
    assert theta == pytest.approx(P * L**2 / (2 * EI), rel=1e-10)
    assert axial == pytest.approx(P * L / EA, rel=1e-10)
    # end forces the nodes exert on the element, local axes: the clamp holds the load's moment P L about the root
    # with -P L, the free end carries the load itself (tension N_j = P, shear V_j = P) and no moment
    n_i, v_i, m_i, n_j, v_j, m_j = sol.forces["beam"]
    assert (n_i, v_i, m_i, n_j, v_j, m_j) == pytest.approx((-P, -P, -P * L, P, P, 0.0), abs=1e-6)


def test_simply_supported_midspan_deflection_and_end_rotation():
    m = FrameModel()
    a, mid, b = (m.add_node(x, 0.0) for x in (0.0, L / 2, L))
    m.add_beam(a, mid, EA, EI)
    m.add_beam(mid, b, EA, EI)
    m.fix(a, ("u", "w"))
    m.fix(b, ("w",))
    m.add_load(mid, "w", -P)
    sol = m.solve()
    assert sol.displacements[mid, 1] == pytest.approx(-P * L**3 / (48 * EI), rel=1e-10)
    assert sol.displacements[a, 2] == pytest.approx(-P * L**2 / (16 * EI), rel=1e-10)
    assert sol.reactions[[a, b], 1] == pytest.approx([P / 2, P / 2], rel=1e-10)


@pytest.mark.parametrize("hinge", [True, False])
def test_pinned_joint_transmits_no_moment(hinge):
    # cantilever A-B carrying beam B-C, which rests on a roller at C and is loaded at its midspan D
    m = FrameModel()
    a, b, d, c = (m.add_node(x, 0.0, name) for x, name in ((0.0, "A"), (L, "B"), (1.5 * L, "D"), (2 * L, "C")))
    m.add_beam(a, b, EA, EI, release_j=hinge, name="AB")
    m.add_beam(b, d, EA, EI, name="BD")
    m.add_beam(d, c, EA, EI, name="DC")
    m.fix(a)
    m.fix(c, ("w",))
    m.add_load(d, "w", -P)
    sol = m.solve()
    if hinge:
        # B-C is then simply supported: B passes P/2 to the cantilever and no moment
        assert sol.forces["AB"][5] == 0.0
        assert sol.forces["BD"][2] == pytest.approx(0.0, abs=1e-9 * P * L)
        assert sol.node("B")[1] == pytest.approx(-(P / 2) * L**3 / (3 * EI), rel=1e-10)
        assert sol.reactions[a, 2] == pytest.approx(P / 2 * L, rel=1e-10)
    else:
        # a rigid joint does carry moment: the test above is not passing trivially
        assert abs(sol.forces["AB"][5]) > 0.05 * P * L


@pytest.mark.parametrize("releases", [(False, False), (True, False), (False, True), (True, True)])
def test_rigid_body_motions_of_a_free_element_give_no_force(releases):
    xi, zi, xj, zj = 0.3, -0.2, 1.4, 0.9
    rng = np.random.default_rng(7)
    for motion in range(4):
        a, b, th = rng.normal(size=3) * (0.01, 0.01, 0.02)
        strain = 0.0 if motion < 3 else 1e-3  # the last one is not rigid: forces must appear
        m = FrameModel()
        i, j = m.add_node(xi, zi), m.add_node(xj, zj)
        m.add_beam(i, j, EA, EI, *releases, name="beam")
        m.add_spring(i, j, 3e6, name="spring")
        m.add_rotational_spring(i, j, 2e3, name="rot")
        for node, (x, z) in ((i, (xi, zi)), (j, (xj, zj))):
            m.prescribe(node, "u", a - th * (z - zi) + strain * (x - xi))
            m.prescribe(node, "w", b + th * (x - xi))
            m.prescribe(node, "theta", th)
        sol = m.solve()
        largest = max(np.max(np.abs(f)) for f in sol.forces.values())
        if strain == 0.0:
            assert largest < 1e-9 * EA * 0.01
            assert np.max(np.abs(sol.reactions)) < 1e-9 * EA * 0.01
        else:
            assert sol.forces["spring"][0] == pytest.approx(3e6 * strain * (xj - xi) ** 2 / math.hypot(1.1, 1.1))


def test_local_stiffness_condensation_matches_closed_form():
    # propped cantilever element (pin at j): transverse stiffness at j is 3 EI / L^3
    k = beam_local_stiffness(EA, EI, L, release_j=True)
    assert k[4, 4] == pytest.approx(3 * EI / L**3, rel=1e-12)
    assert k[2, 2] == pytest.approx(3 * EI / L, rel=1e-12)
    assert np.all(k[5] == 0.0) and np.all(k[:, 5] == 0.0)
    assert np.allclose(k, k.T)


def test_reactions_balance_applied_loads_in_a_portal_frame():
    m = FrameModel()
    n = [m.add_node(x, z) for x, z in ((0, 0), (0, 3), (4, 3.5), (4, 0))]
    m.add_beam(n[0], n[1], EA, EI)
    m.add_beam(n[1], n[2], EA, EI, release_j=True)
    m.add_beam(n[2], n[3], EA, EI)
    m.fix(n[0])
    m.fix(n[3], ("u", "w"))
    loads = {(n[1], "u"): 2e3, (n[2], "w"): -5e3, (n[1], "theta"): 700.0}
    for (node, dof), value in loads.items():
        m.add_load(node, dof, value)
    sol = m.solve()
    xz = np.array(m.coords)
    r = sol.reactions
    assert r[:, 0].sum() + 2e3 == pytest.approx(0.0, abs=1e-6)
    assert r[:, 1].sum() - 5e3 == pytest.approx(0.0, abs=1e-6)
    # moments about the origin: x F_z - z F_x + M
    moment = np.sum(xz[:, 0] * r[:, 1] - xz[:, 1] * r[:, 0] + r[:, 2])
    moment += 4 * -5e3 - 3 * 2e3 + 700.0
    assert moment == pytest.approx(0.0, abs=1e-6)
    assert abs(r[n[0], 2]) > 1e2  # the clamped base does take a moment


# ---- mechanism and input errors -----------------------------------------------------------------------------
def test_mechanism_error_names_the_free_node():
    m = FrameModel()
    a, b, c = m.add_node(0, 0, "A"), m.add_node(1, 0, "hinge"), m.add_node(2, 0, "C")
    m.add_beam(a, b, EA, EI, release_j=True)
    m.add_beam(b, c, EA, EI, release_i=True)
    m.fix(a)
    m.fix(c, ("u", "w"))
    with pytest.raises(ValueError, match=r"mechanism.*'hinge' theta"):
        m.solve()
    m2 = FrameModel()
    a, b = m2.add_node(0, 0, "A"), m2.add_node(1, 0, "B")
    m2.add_beam(a, b, EA, EI)
    m2.fix(a, ("u", "w"))  # a pin: the beam swings about A
    with pytest.raises(ValueError, match=r"mechanism.*'B' w"):
        m2.solve()


def test_mesh_without_fore_aft_restraint_names_the_axles():
    with pytest.raises(ValueError, match=r"mechanism.*'axle0' u.*'axle2' u"):
        solve_fe(triaxle_stage1(), ALPHA, 0.0, options=MeshOptions(tyre_longitudinal_stiffness=0.0))


def test_bad_input_names_parameter_range_and_unit():
    with pytest.raises(ValueError, match=r"chassis_rotation = 0\.5 .*rad"):
        fe_wheel_loads(triaxle_stage1(), ALPHA, 0.5)
    with pytest.raises(ValueError, match=r"ea = -1\.0 .*> 0 N"):
        beam_local_stiffness(-1.0, EI, L)
    m = FrameModel()
    a, b = m.add_node(0, 0), m.add_node(0, 0)
    with pytest.raises(ValueError, match="direction"):
        m.add_spring(a, b, 1e6)
    with pytest.raises(ValueError, match=r"hanger_length = -0\.1 .*m"):
        MeshOptions(hanger_length=-0.1)
    with pytest.raises(ValueError, match=r"slope = 12\.0 .*degree"):
        figure2_points(slopes_deg=(12.0,))


# ---- the tri-axle mesh against the static model -------------------------------------------------------------
@pytest.mark.parametrize("q", [0.5, 1.0, 4.3, 10.0, 20.0])
@pytest.mark.parametrize("slope_deg", [0.0, 0.5, 1.0, 2.0, -1.5])
def test_fe_matches_static_model_without_drag_links(q, slope_deg):
    b = _bogie_with_q(q)
    psi = math.radians(slope_deg)
    static = solve_static(b, ALPHA, psi)
    fe = solve_fe(b, ALPHA, psi)
    scale = static.wheel_loads.mean()
    assert np.max(np.abs(fe.wheel_loads - static.wheel_loads)) < LOAD_TOL * scale
    # the FE is a little softer, never stiffer: every member it adds is in series with K_S
    assert fe.wheel_loads.sum() < static.wheel_loads.sum()
    w_bar = ALPHA * b.combined_stiffness
    assert abs(p(fe.wheel_loads / w_bar) - p(static.wheel_loads / w_bar)) < P_TOL
    # equaliser rotation: the same relative tolerance, plus 1e-4 rad for the tip-height mismatch of about 1e-5 m
    # that the unequal compression of hangers and brackets makes over a 0.155 m arm at zero slope
    assert fe.equaliser_rotation == pytest.approx(static.equaliser_rotation, rel=LOAD_TOL, abs=1e-4)


def test_fe_deviation_is_the_compliance_of_the_steel_parts():
    b, psi = triaxle_stage1(), math.radians(1.0)
    static = wheel_loads(b, ALPHA, psi)
    base = MeshOptions()
    stiff = MeshOptions(steel_modulus=100 * base.steel_modulus, contact_stiffness=100 * base.contact_stiffness)
    dev = np.max(np.abs(fe_wheel_loads(b, ALPHA, psi) - static)) / static.mean()
    dev_stiff = np.max(np.abs(fe_wheel_loads(b, ALPHA, psi, options=stiff) - static)) / static.mean()
    assert 4e-4 < dev < LOAD_TOL
    assert dev_stiff == pytest.approx(dev / 100, rel=0.05)


def test_free_bush_equalises_exactly_in_the_fe_model():
    b = _bogie_with_q(math.inf)
    for slope in (0.5, 2.0):
        loads = fe_wheel_loads(b, ALPHA, math.radians(slope))
        assert np.ptp(loads) < 1e-9 * loads.mean()


def test_bed_carries_the_wheel_loads_and_the_ground_reacts_them():
    b = triaxle_stage1()
    for links in (False, True):
        res = solve_fe(b, ALPHA, math.radians(1.0), drag_links=links)
        names = res.frame.node_names
        r = res.frame.reactions
        bed = [k for k, nm in enumerate(names) if nm.startswith("bed_")]
        ground = [k for k, nm in enumerate(names) if nm.startswith("ground")]
        assert -r[bed, 1].sum() == pytest.approx(res.wheel_loads.sum(), rel=1e-9)
        assert r[ground, 1] == pytest.approx(res.wheel_loads, rel=1e-9)
        assert r[:, 0].sum() == pytest.approx(0.0, abs=1e-6)


def test_two_axle_bogie_and_tyre_wear_match_static():
    bt = tandem_trrl()
    for slope in (0.0, 1.0):
        static = wheel_loads(bt, 0.05, math.radians(slope))
        assert fe_wheel_loads(bt, 0.05, math.radians(slope)) == pytest.approx(static, rel=LOAD_TOL)
    b, wear = triaxle_stage1(), (0.0, 0.005, 0.0)
    static = wheel_loads(b, ALPHA, 0.0, wear)
    fe = solve_fe(b, ALPHA, 0.0, tyre_wear=wear).wheel_loads
    assert fe == pytest.approx(static, rel=LOAD_TOL)
    assert fe[1] < fe[0] - 0.005 * fe.mean()  # the worn middle tyre is unloaded by about 0.6 %


def test_unequal_arms_and_spring_halves_match_static():
    # the static model's general form (lever rule, arm ratios): design shares are unequal here
    b = triaxle_stage1(
        axle_x=(6.69, 7.99, 9.34),
        spring_front_half_length=(0.5, 0.45, 0.5),
        spring_rear_half_length=(0.55, 0.5, 0.5),
        equaliser_front_arm=(0.14, 0.17),
        equaliser_rear_arm=(0.16, 0.18),
    )
    for slope in (0.0, 1.0):
        static = solve_static(b, ALPHA, math.radians(slope))
        fe = solve_fe(b, ALPHA, math.radians(slope))
        assert np.ptp(static.wheel_loads) > 0.05 * static.wheel_loads.mean()
        assert np.max(np.abs(fe.wheel_loads - static.wheel_loads)) < LOAD_TOL * static.wheel_loads.mean()
        assert fe.equaliser_rotation == pytest.approx(static.equaliser_rotation, rel=LOAD_TOL, abs=1e-4)


# ---- drag links ---------------------------------------------------------------------------------------------
def test_drag_links_break_the_symmetry_at_zero_slope():
    b = triaxle_stage1()
    res = solve_fe(b, ALPHA, 0.0, drag_links=True)
    w_bar = res.wheel_loads / (ALPHA * b.combined_stiffness)
    # documented in docs/fe-model.md: W = (1.0005, 0.9948, 1.0029), p = 0.0098 where the static model has 0
    assert w_bar == pytest.approx([1.0005, 0.9948, 1.0029], abs=2e-4)
    assert p(w_bar) == pytest.approx(0.0098, abs=5e-4)
    assert w_bar[2] > w_bar[0] > w_bar[1]
    # the short, steeper front link is in compression, the two others in tension; the bed is free fore-and-aft
    assert res.drag_link_forces[0] < 0.0 < min(res.drag_link_forces[1:])
    assert res.tyre_longitudinal_forces.sum() == pytest.approx(0.0, abs=1e-6)
    # nose up and nose down are no longer mirror images
    up = p(fe_wheel_loads(b, ALPHA, math.radians(0.5), True) / (ALPHA * b.combined_stiffness))
    down = p(fe_wheel_loads(b, ALPHA, math.radians(-0.5), True) / (ALPHA * b.combined_stiffness))
    assert up - down == pytest.approx(0.0028, abs=3e-4)


def test_drag_links_with_braked_tyres_restrain_spring_pitch():
    # with slope the links and the braked tyres hold each axle against pitch, so the springs wind up instead of
    # following the equalisers: p nearly doubles at q = 4.3 and a free bush no longer equalises
    b = triaxle_stage1()
    w_bar = ALPHA * b.combined_stiffness
    for slope in (0.5, 1.0, 2.0):
        psi = math.radians(slope)
        ratio = p(fe_wheel_loads(b, ALPHA, psi, True) / w_bar) / p(wheel_loads(b, ALPHA, psi) / w_bar)
        assert 1.85 < ratio < 1.97
    free = _bogie_with_q(math.inf)
    assert p(fe_wheel_loads(free, ALPHA, math.radians(2.0), True) / w_bar) == pytest.approx(0.281, abs=2e-3)


def test_drag_links_on_free_rolling_wheels_carry_no_force():
    # without fore-aft tyre restraint each link is the only fore-aft support of its axle: statically determinate
    b, psi = triaxle_stage1(), math.radians(1.5)
    rolling = MeshOptions(tyre_longitudinal_stiffness=0.0)
    res = solve_fe(b, ALPHA, psi, drag_links=True, options=rolling)
    assert np.max(np.abs(res.drag_link_forces)) < 1e-6
    assert res.wheel_loads == pytest.approx(fe_wheel_loads(b, ALPHA, psi), rel=1e-9)


# ---- Figure 2 -----------------------------------------------------------------------------------------------
def test_figure2_points_lie_on_equation_1():
    points = figure2_points()
    assert sorted(points) == [0.0, 0.5, 1.0, 1.5, 2.0]
    axle_x = triaxle_stage1().axle_x
    spacing = axle_x[1] - axle_x[0]
    for slope, (q, p_fe) in points.items():
        assert q == pytest.approx(4.3, rel=1e-12)
        p_eq1 = float(p(nondimensional_loads(q, math.radians(slope) * spacing / ALPHA)))
        assert p_fe == pytest.approx(p_eq1, abs=P_TOL)
    assert points[2.0][1] == pytest.approx(0.214, abs=1e-3)


def test_cli_figure2_with_fe_overlay(tmp_path):
    out = tmp_path / "fig2.png"
    assert main(["figure2", "--out", str(out), "--fe"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_ties_chain_into_one_global_dof_numbered_by_its_lowest_member():
    m = FrameModel()
    a, b, c = m.add_node(0.0, 0.0), m.add_node(0.0, 0.0), m.add_node(0.0, 0.0)
    m.tie(c, b, ("w",))
    m.tie(b, a, ("w",))
    numbering, n_glob = m._global_map()
    assert n_glob == 9 - 2
    assert numbering[3 * a + 1] == numbering[3 * b + 1] == numbering[3 * c + 1] == 1
    # global DOFs are numbered in the order of their lowest member
    first = [int(g) for k, g in enumerate(numbering) if g not in numbering[:k]]
    assert first == list(range(n_glob))
