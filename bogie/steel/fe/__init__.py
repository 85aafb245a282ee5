"""Stage 1: the finite element mesh of one side of a multi-axle bogie, on the frame solver of
:mod:`bogie.steel.fe.frame`.

:func:`build_mesh` turns a :class:`~bogie.params.Bogie` into the reference's Stage 1 model: hangers and equaliser
brackets clamped to the bed, equalisers pinned to their brackets with the bush as a rotational spring, leaf springs
as beams resting on vertical slipper contacts, axles and wheels, tyre springs to the ground and optional drag links.
The bed is given a rigid translation ``alpha`` and pitch ``psi`` as prescribed displacements. Derivations, the mesh
drawing and the comparison with the static model are in ``docs/fe-model.md``.

The frame solver's names (:class:`~bogie.steel.fe.frame.FrameModel`, :class:`~bogie.steel.fe.frame.FrameSolution`,
:func:`~bogie.steel.fe.frame.beam_local_stiffness`, :data:`~bogie.steel.fe.frame.DOF_NAMES`) are re-exported here, where
they lived before :mod:`bogie.steel.fe.frame` existed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie.metrics import p as deviation_p
from bogie.params import Bogie
from bogie.presets import STAGE1_CHASSIS_DEFLECTION, triaxle_stage1
from bogie.ranges import check_positive
from bogie.settings import check_value
from bogie.steel.fe.frame import DOF_NAMES, FrameModel, FrameSolution, beam_local_stiffness

__all__ = [
    "DOF_NAMES",
    "BogieFEResult",
    "FrameModel",
    "FrameSolution",
    "MeshOptions",
    "beam_local_stiffness",
    "build_mesh",
    "fe_wheel_loads",
    "figure2_points",
    "solve_fe",
]


# ---- the tri-axle suspension mesh ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MeshOptions:
    """Properties of the Stage 1 mesh that a :class:`~bogie.params.Bogie` does not hold (choices in docs/fe-model.md).

    Parameters
    ----------
    seat_height
        Spring seat above the axle centre (overslung spring) [m].
    hanger_length
        Height of the bed (chassis underside) above the spring ends [m].
    steel_modulus
        Young's modulus of the hangers, brackets, equalisers, axles, wheels and drag links [Pa].
    hanger_area, hanger_second_moment
        Section of hangers and brackets [m^2], [m^4].
    equaliser_area, equaliser_second_moment
        Section of the equaliser arms [m^2], [m^4].
    axle_area, axle_second_moment
        Section of the axle clamp (seat to axle centre) and of the braked wheel (axle centre to contact patch)
        [m^2], [m^4].
    spring_area
        Cross-section of the leaf pack, which sets its axial rigidity [m^2]; its bending rigidity follows from the
        bogie's ``road_spring_stiffness``.
    contact_stiffness
        Normal stiffness of each slipper contact between a spring end and its pad [N/m].
    tyre_longitudinal_stiffness
        Fore-aft stiffness of the tyres of one axle end at the contact patch, wheel braked [N/m]; None takes the
        bogie's vertical ``tyre_stiffness``; 0 leaves the axles unrestrained fore-and-aft (a mechanism unless drag
        links and a fixed bed hold them).
    drag_link_area
        Cross-section of a drag link (radius rod) [m^2].
    drag_link_rise
        Height of a drag link's bracket pin above its axle pin, the axle centre [m]; its sign sets the sign of the
        drag-link asymmetry.
    """

    seat_height: float = 0.12
    hanger_length: float = 0.35
    steel_modulus: float = 210e9
    hanger_area: float = 3.0e-3
    hanger_second_moment: float = 4.0e-6
    equaliser_area: float = 4.0e-3
    equaliser_second_moment: float = 3.0e-6
    axle_area: float = 8.0e-3
    axle_second_moment: float = 2.0e-5
    spring_area: float = 6.0e-3
    contact_stiffness: float = 1.0e10
    tyre_longitudinal_stiffness: float | None = None
    drag_link_area: float = 1.25e-3
    drag_link_rise: float = 0.05

    def __post_init__(self) -> None:
        for name, unit in (
            ("seat_height", "m"),
            ("hanger_length", "m"),
            ("steel_modulus", "Pa"),
            ("hanger_area", "m^2"),
            ("hanger_second_moment", "m^4"),
            ("equaliser_area", "m^2"),
            ("equaliser_second_moment", "m^4"),
            ("axle_area", "m^2"),
            ("axle_second_moment", "m^4"),
            ("spring_area", "m^2"),
            ("contact_stiffness", "N/m"),
            ("drag_link_area", "m^2"),
        ):
            check_positive(name, getattr(self, name), unit)
        if self.tyre_longitudinal_stiffness is not None:
            check_positive("tyre_longitudinal_stiffness", self.tyre_longitudinal_stiffness, "N/m", allow_zero=True)
        check_value("drag_link_rise", self.drag_link_rise, "m", low=-0.5, high=0.5)


@dataclass(frozen=True)
class BogieFEResult:
    """Result of :func:`solve_fe`.

    Attributes
    ----------
    wheel_loads
        Vertical tyre force of each axle, compression positive, front to rear [N].
    equaliser_rotation
        Rotation of each equaliser relative to its bracket, rear tip down positive as in
        :func:`bogie.steel.static.solve_static` [rad].
    drag_link_forces
        Tension in each drag link, front to rear [N]; empty without drag links.
    tyre_longitudinal_forces
        Rearward force of the ground on each contact patch [N].
    bed_surge
        Fore-aft displacement of the bed, rearward positive [m]; 0 unless drag links and braked tyres are fitted.
    frame
        The full finite element solution.
    """

    wheel_loads: NDArray[np.float64]
    equaliser_rotation: NDArray[np.float64]
    drag_link_forces: NDArray[np.float64]
    tyre_longitudinal_forces: NDArray[np.float64]
    bed_surge: float
    frame: FrameSolution


def _check_loading(chassis_deflection: float, chassis_rotation: float) -> None:
    check_value("chassis_deflection", chassis_deflection, "m", low=-0.5, high=0.5)
    limit = math.radians(10.0)
    note = "10 degrees; the model is linear in small angles"
    check_value("chassis_rotation", chassis_rotation, "rad", low=-limit, high=limit, note=note)


@dataclass
class _Mesh:
    """A Stage 1 mesh being built, with what its parts share."""

    m: FrameModel
    bogie: Bogie
    opt: MeshOptions
    z_spring: float  # spring ends and hanger pads [m]
    z_pivot: float  # equaliser pivots [m]
    z_bed: float  # bed (chassis underside) [m]
    chassis_deflection: float
    chassis_rotation: float
    surge_free: bool  # the bed's fore-aft displacement is an unknown
    bed_nodes: list[int] = field(default_factory=list)
    #: "front<i>" / "rear<i>": the pad (hanger or equaliser tip) under spring i's front / rear end
    pads: dict[str, int] = field(default_factory=dict)
    #: bed node ahead of each axle, where its drag link is anchored
    brackets: list[int] = field(default_factory=list)

    def section(self, area: float, second_moment: float) -> tuple[float, float]:
        """(E A [N], E I [N m^2]) of a steel section."""
        return self.opt.steel_modulus * area, self.opt.steel_modulus * second_moment

    @property
    def hanger(self) -> tuple[float, float]:
        return self.section(self.opt.hanger_area, self.opt.hanger_second_moment)


def _mesh_heights(bogie: Bogie, opt: MeshOptions) -> tuple[float, float, float]:
    """Heights of the spring ends, the equaliser pivots and the bed above the ground [m]."""
    drop_f, drop_r = bogie.equaliser_front_tip_drop, bogie.equaliser_rear_tip_drop
    z_spring = bogie.tyre_radius + opt.seat_height
    z_pivot = z_spring + 0.5 * (drop_f + drop_r)
    z_bed = z_spring + opt.hanger_length
    highest = max(z_spring, z_pivot, z_pivot - drop_f, z_pivot - drop_r)
    if z_bed <= highest:
        raise ValueError(
            f"hanger_length = {opt.hanger_length!r} m puts the bed at or below an equaliser pivot or tip: must "
            f"exceed {highest - z_spring:g} m"
        )
    return z_spring, z_pivot, z_bed


def _tyre_longitudinal(bogie: Bogie, opt: MeshOptions) -> float:
    """Fore-aft stiffness of the braked tyres [N/m]."""
    return bogie.tyre_stiffness if opt.tyre_longitudinal_stiffness is None else opt.tyre_longitudinal_stiffness


def _bed_node(mesh: _Mesh, x: float, name: str) -> int:
    """A bed node at ``x`` [m], given the bed's rigid motion (its fore-aft motion shared or held at 0)."""
    m = mesh.m
    node = m.add_node(x, mesh.z_bed, name)
    psi = mesh.chassis_rotation
    m.prescribe(node, "w", -mesh.chassis_deflection - psi * (x - mesh.bogie.bogie_centre_x))
    m.prescribe(node, "theta", -psi)
    if not mesh.surge_free:
        m.prescribe(node, "u", 0.0)
    elif mesh.bed_nodes:
        m.tie(mesh.bed_nodes[0], node, ("u",))
    mesh.bed_nodes.append(node)
    return node


def _equaliser(mesh: _Mesh, j: int, x_p: float) -> None:
    """Equaliser j: its bracket from the bed, pinned to it with the bush, and its two arms to the tips."""
    m, bogie = mesh.m, mesh.bogie
    drop_f, drop_r = bogie.equaliser_front_tip_drop, bogie.equaliser_rear_tip_drop
    arm = mesh.section(mesh.opt.equaliser_area, mesh.opt.equaliser_second_moment)
    top = _bed_node(mesh, x_p, f"bed_pivot{j}")
    mesh.brackets.append(top)
    bracket = m.add_node(x_p, mesh.z_pivot, f"bracket{j}")
    m.add_beam(top, bracket, *mesh.hanger, name=f"bracket{j}")
    eq = m.add_node(x_p, mesh.z_pivot, f"equaliser{j}")
    m.tie(bracket, eq, ("u", "w"))
    if bogie.bush_stiffness > 0.0:
        m.add_rotational_spring(bracket, eq, bogie.bush_stiffness, name=f"bush{j}")
    tip_f = m.add_node(x_p - bogie.equaliser_front_arm[j], mesh.z_pivot - drop_f, f"tip{j}_front")
    tip_r = m.add_node(x_p + bogie.equaliser_rear_arm[j], mesh.z_pivot - drop_r, f"tip{j}_rear")
    m.add_beam(eq, tip_f, *arm, name=f"arm{j}_front")
    m.add_beam(eq, tip_r, *arm, name=f"arm{j}_rear")
    mesh.pads[f"rear{j}"], mesh.pads[f"front{j + 1}"] = tip_f, tip_r


def _chassis_side(mesh: _Mesh) -> None:
    """Hangers carrying the outer spring ends, and the equalisers on their brackets, front to rear."""
    m, bogie = mesh.m, mesh.bogie
    n = bogie.n_axles
    x_fh, x_rh = bogie.front_hanger_x, bogie.rear_hanger_x
    top = _bed_node(mesh, x_fh, "bed_front_hanger")
    mesh.pads["front0"] = m.add_node(x_fh, mesh.z_spring, "pad_front")
    m.add_beam(top, mesh.pads["front0"], *mesh.hanger, name="hanger_front")
    mesh.brackets.append(top)
    for j, x_p in enumerate(bogie.equaliser_pivot_x):
        _equaliser(mesh, j, x_p)
    top = _bed_node(mesh, x_rh, "bed_rear_hanger")
    mesh.pads[f"rear{n - 1}"] = m.add_node(x_rh, mesh.z_spring, "pad_rear")
    m.add_beam(top, mesh.pads[f"rear{n - 1}"], *mesh.hanger, name="hanger_rear")


def _leaf_spring(mesh: _Mesh, i: int) -> int:
    """Leaf spring i on its two slipper contacts, as two beams meeting at the seat; returns the seat node."""
    m, bogie, opt = mesh.m, mesh.bogie, mesh.opt
    a_f, a_r = bogie.spring_front_half_length[i], bogie.spring_rear_half_length[i]
    span = a_f + a_r
    pad_f, pad_r = mesh.pads[f"front{i}"], mesh.pads[f"rear{i}"]
    (x_f, z_f), (x_r, z_r) = m.coords[pad_f], m.coords[pad_r]
    end_f = m.add_node(x_f, z_f, f"spring{i}_front")
    end_r = m.add_node(x_r, z_r, f"spring{i}_rear")
    seat = m.add_node(bogie.axle_x[i], z_f + (z_r - z_f) * a_f / span, f"spring{i}_seat")
    m.add_spring(pad_f, end_f, opt.contact_stiffness, (0.0, 1.0), name=f"contact{i}_front")
    m.add_spring(pad_r, end_r, opt.contact_stiffness, (0.0, 1.0), name=f"contact{i}_rear")
    # simply supported beam, point load at the seat: deflection P a_f^2 a_r^2 / (3 EI L) = P / K_R
    ei_leaf = bogie.road_spring_stiffness * a_f**2 * a_r**2 / (3.0 * span)
    m.add_beam(end_f, seat, opt.steel_modulus * opt.spring_area, ei_leaf, name=f"leaf{i}_front")
    m.add_beam(seat, end_r, opt.steel_modulus * opt.spring_area, ei_leaf, name=f"leaf{i}_rear")
    return seat


def _axle_side(mesh: _Mesh, i: int, wear: float, drag_links: bool) -> None:
    """Axle i: leaf spring, axle, braked wheel, tyre springs to the ground (lowered by ``wear`` [m]), drag link."""
    m, bogie, opt = mesh.m, mesh.bogie, mesh.opt
    axle = mesh.section(opt.axle_area, opt.axle_second_moment)
    k_x = _tyre_longitudinal(bogie, opt)
    seat = _leaf_spring(mesh, i)
    x_s = bogie.axle_x[i]
    z_axle = m.coords[seat][1] - opt.seat_height
    centre = m.add_node(x_s, z_axle, f"axle{i}")
    patch = m.add_node(x_s, z_axle - bogie.tyre_radius, f"patch{i}")
    ground = m.add_node(x_s, z_axle - bogie.tyre_radius, f"ground{i}")
    m.add_beam(seat, centre, *axle, name=f"axle{i}")
    m.add_beam(centre, patch, *axle, name=f"wheel{i}")
    m.add_spring(ground, patch, bogie.tyre_stiffness, (0.0, 1.0), name=f"tyre{i}_vertical")
    if k_x > 0.0:
        m.add_spring(ground, patch, k_x, (1.0, 0.0), name=f"tyre{i}_longitudinal")
    m.fix(ground, ("u", "theta"))
    m.prescribe(ground, "w", -wear)
    if drag_links:
        x_b = m.coords[mesh.brackets[i]][0]
        pin = m.add_node(x_b, z_axle + opt.drag_link_rise, f"link_pin{i}")
        m.add_beam(mesh.brackets[i], pin, *mesh.hanger, name=f"link_bracket{i}")
        m.add_beam(pin, centre, opt.steel_modulus * opt.drag_link_area, 0.0, True, True, name=f"drag_link{i}")


def build_mesh(
    bogie: Bogie,
    chassis_deflection: float,
    chassis_rotation: float,
    drag_links: bool = False,
    options: MeshOptions | None = None,
    tyre_wear: ArrayLike | None = None,
) -> FrameModel:
    """The Stage 1 finite element model of one side of ``bogie``, loaded by a rigid motion of the bed.

    Node and element names are listed in ``docs/fe-model.md``. Every bed node is given the rigid motion
    w = -alpha - psi (x - x_c), theta = -psi about the bogie centre x_c at bed height. The bed's fore-aft
    displacement is one free unknown shared by all bed nodes when drag links tie the bed to braked tyres (the bed
    then takes no net fore-aft force), and 0 otherwise, when nothing couples it to the ground.

    Parameters
    ----------
    bogie
        The bogie (any n >= 2); geometry, ``road_spring_stiffness``, ``tyre_stiffness``, ``bush_stiffness``,
        ``tyre_radius`` and the equaliser tip drops are used.
    chassis_deflection
        Downward displacement alpha of the bed at the bogie centre [m].
    chassis_rotation
        Bed pitch psi, nose up positive (lowers the rear) [rad].
    drag_links
        Fit one drag link per axle, from the bracket ahead of it (front hanger or equaliser bracket) to the axle.
    options
        Mesh properties not held by the bogie; :class:`MeshOptions` defaults if None.
    tyre_wear
        Loss of tyre radius per axle [m], applied as a lowering of that axle's ground node; ``bogie.tyre_wear``
        if None.
    """
    _check_loading(chassis_deflection, chassis_rotation)
    opt = MeshOptions() if options is None else options
    n = bogie.n_axles
    wear = np.asarray(bogie.tyre_wear if tyre_wear is None else tyre_wear, dtype=float)
    if wear.shape != (n,) or not np.all(np.isfinite(wear)):
        raise ValueError(f"tyre_wear = {tyre_wear!r} must give one finite value per axle ({n}) in m")
    z_spring, z_pivot, z_bed = _mesh_heights(bogie, opt)
    # the bed's fore-aft position is an unknown only when something couples it to the ground: drag links to
    # axles that the braked tyres hold; otherwise it is set to 0, where it does not affect any force
    surge_free = drag_links and _tyre_longitudinal(bogie, opt) > 0.0
    mesh = _Mesh(FrameModel(), bogie, opt, z_spring, z_pivot, z_bed, chassis_deflection, chassis_rotation, surge_free)
    _chassis_side(mesh)
    for i in range(n):
        _axle_side(mesh, i, float(wear[i]), drag_links)
    return mesh.m


def solve_fe(
    bogie: Bogie,
    chassis_deflection: float,
    chassis_rotation: float,
    drag_links: bool = False,
    options: MeshOptions | None = None,
    tyre_wear: ArrayLike | None = None,
) -> BogieFEResult:
    """Build the Stage 1 mesh of ``bogie`` (:func:`build_mesh`), solve it and extract the wheel loads.

    Parameters are those of :func:`build_mesh`: alpha [m], psi nose up positive [rad], tyre wear [m].
    """
    frame = build_mesh(bogie, chassis_deflection, chassis_rotation, drag_links, options, tyre_wear).solve()
    n = bogie.n_axles
    f = frame.forces
    loads = np.array([-f[f"tyre{i}_vertical"][0] for i in range(n)])
    rotation = np.array([frame.node(f"bracket{j}")[2] - frame.node(f"equaliser{j}")[2] for j in range(n - 1)])
    links = np.array([f[f"drag_link{i}"][3] for i in range(n)]) if drag_links else np.zeros(0)
    longitudinal = np.array([-f[k][0] if (k := f"tyre{i}_longitudinal") in f else 0.0 for i in range(n)])
    return BogieFEResult(
        wheel_loads=loads,
        equaliser_rotation=rotation,
        drag_link_forces=links,
        tyre_longitudinal_forces=longitudinal,
        bed_surge=float(frame.node("bed_front_hanger")[0]),
        frame=frame,
    )


def fe_wheel_loads(
    bogie: Bogie,
    chassis_deflection: float,
    chassis_rotation: float,
    drag_links: bool = False,
    options: MeshOptions | None = None,
) -> NDArray[np.float64]:
    """Wheel loads of the Stage 1 finite element model, front to rear [N].

    Parameters
    ----------
    bogie
        The bogie, n >= 2 axles.
    chassis_deflection
        Downward displacement alpha of the bed at the bogie centre [m].
    chassis_rotation
        Bed pitch psi, nose up positive [rad].
    drag_links
        Fit drag links (radius rods); without them the loads agree with :func:`bogie.steel.static.wheel_loads` to the
        compliance of the steel parts (``docs/fe-model.md``).
    options
        Mesh properties; :class:`MeshOptions` defaults if None.
    """
    return solve_fe(bogie, chassis_deflection, chassis_rotation, drag_links, options).wheel_loads


def figure2_points(
    bogie: Bogie | None = None,
    slopes_deg: Sequence[float] = (0.0, 0.5, 1.0, 1.5, 2.0),
    chassis_deflection: float = STAGE1_CHASSIS_DEFLECTION,
    drag_links: bool = False,
    options: MeshOptions | None = None,
) -> dict[float, tuple[float, float]]:
    """Finite element points for the reference's Figure 2: slope [degree] -> (q [-], p [-]).

    Each point is the wheel load deviation p (Equation 2) of the non-dimensional loads W / (alpha K_S) of the
    Stage 1 model with the bed lowered by ``chassis_deflection`` and tipped nose up by the slope; q is the
    bogie's b^2 K_S / (4 K_B). Defaults: :func:`~bogie.presets.triaxle_stage1` (q = 4.3), alpha = 57 mm, the
    five slopes of Figure 2 (the reference's five starred points), no drag links: with braked tyres our drag
    links roughly double p, which the reference's points do not show (``docs/fe-model.md``, "Drag links").

    Parameters
    ----------
    bogie
        The bogie; ``triaxle_stage1()`` if None.
    slopes_deg
        Bed slopes, nose up positive [degree], each within +-10.
    chassis_deflection
        Bed downward displacement alpha [m], > 0.
    drag_links
        Fit drag links.
    options
        Mesh properties; :class:`MeshOptions` defaults if None.
    """
    bogie = triaxle_stage1() if bogie is None else bogie
    check_value("chassis_deflection", chassis_deflection, "m", low=0.0, low_open=True, high=0.5)
    points = {}
    for slope in slopes_deg:
        check_value("slope", slope, "degree", low=-10.0, high=10.0)
        loads = fe_wheel_loads(bogie, chassis_deflection, math.radians(slope), drag_links, options)
        w_bar = loads / (chassis_deflection * bogie.combined_stiffness)
        points[float(slope)] = (bogie.q(0), float(deviation_p(w_bar)))
    return points
