"""Stage 1: a small 2-D linear frame finite element solver and the tri-axle suspension mesh built on it.

The solver (:class:`FrameModel`) works in the vertical plane of one side of the trailer: ``x`` rearward, ``z``
upward, three degrees of freedom per node: ``u`` (along x) [m], ``w`` (along z) [m] and ``theta``, the rotation
from x towards z (counter-clockwise in a drawing with the rear on the right, so a positive ``theta`` raises the
rear) [rad]. It offers Euler-Bernoulli beam elements of any orientation with optional pin releases at either end
(the released rotation is condensed out), axial springs along a given direction, rotational springs, equal-DOF
ties (pin joints between coincident nodes), prescribed displacements and nodal loads.

:func:`build_mesh` turns a :class:`~bogie.params.Bogie` into the reference's Stage 1 model: hangers and equaliser
brackets clamped to the bed, equalisers pinned to their brackets with the bush as a rotational spring, leaf springs
as beams resting on vertical slipper contacts, axles and wheels, tyre springs to the ground and optional drag links.
The bed is given a rigid translation ``alpha`` and pitch ``psi`` as prescribed displacements. Derivations, the mesh
drawing and the comparison with the static model are in ``docs/fe-model.md``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from bogie.metrics import p as deviation_p
from bogie.params import STAGE1_CHASSIS_DEFLECTION, Bogie, triaxle_stage1

DOF_NAMES = ("u", "w", "theta")
#: smallest pivot of the Jacobi-scaled stiffness (unit diagonal) accepted as non-singular [-]
_PIVOT_TOL = 1e-11


def _dof_index(dof: str | int) -> int:
    if isinstance(dof, str) and dof in DOF_NAMES:
        return DOF_NAMES.index(dof)
    if isinstance(dof, int) and 0 <= dof < 3:
        return dof
    raise ValueError(f"dof = {dof!r} is not a degree of freedom: must be one of {', '.join(DOF_NAMES)} (or 0, 1, 2)")


def _positive(name: str, value: float, unit: str, allow_zero: bool = False) -> float:
    v = float(value)
    ok = v >= 0.0 if allow_zero else v > 0.0
    if not (math.isfinite(v) and ok):
        raise ValueError(f"{name} = {value!r} is out of range: must be {'>= 0' if allow_zero else '> 0'} {unit}")
    return v


def beam_local_stiffness(
    ea: float, ei: float, length: float, release_i: bool = False, release_j: bool = False
) -> NDArray[np.float64]:
    """Stiffness of a 2-D Euler-Bernoulli beam in its local axes, DOFs (u', w', theta) at end i then end j.

    ``x'`` runs from node i to node j, ``z'`` is ``x'`` turned 90 degrees towards ``z``. A released end carries no
    moment: its rotation is condensed out, K_c = K_cc - K_cr K_rr^-1 K_rc, and its row and column are zero.

    Parameters
    ----------
    ea
        Axial rigidity E A [N].
    ei
        Bending rigidity E I [N m^2]; may be 0 when both ends are released (a two-force member).
    length
        Element length [m].
    release_i, release_j
        Pin release (hinge) at end i, end j.
    """
    _positive("ea", ea, "N")
    _positive("ei", ei, "N m^2", allow_zero=release_i and release_j)
    L = _positive("length", length, "m")
    a = ea / L
    k = np.zeros((6, 6))
    k[np.ix_([0, 3], [0, 3])] = a * np.array([[1.0, -1.0], [-1.0, 1.0]])
    if release_i and release_j:
        return k
    b = ei / L**3
    bend = b * np.array(
        [
            [12.0, 6.0 * L, -12.0, 6.0 * L],
            [6.0 * L, 4.0 * L * L, -6.0 * L, 2.0 * L * L],
            [-12.0, -6.0 * L, 12.0, -6.0 * L],
            [6.0 * L, 2.0 * L * L, -6.0 * L, 4.0 * L * L],
        ]
    )
    k[np.ix_([1, 2, 4, 5], [1, 2, 4, 5])] = bend
    released = [r for r, flag in ((2, release_i), (5, release_j)) if flag]
    if released:
        kept = [c for c in range(6) if c not in released]
        k_rr = k[np.ix_(released, released)]
        k_kr = k[np.ix_(kept, released)]
        condensed = k[np.ix_(kept, kept)] - k_kr @ np.linalg.solve(k_rr, k_kr.T)
        k = np.zeros((6, 6))
        k[np.ix_(kept, kept)] = condensed
    return k


def _rotation(c: float, s: float) -> NDArray[np.float64]:
    r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    t = np.zeros((6, 6))
    t[:3, :3] = r
    t[3:, 3:] = r
    return t


@dataclass(frozen=True)
class _Element:
    kind: str  # "beam", "spring", "rotational_spring"
    nodes: tuple[int, int]
    stiffness: NDArray[np.float64]  # in the 6 global DOFs of its two nodes
    recover: NDArray[np.float64]  # maps those 6 displacements to the element's reported forces


@dataclass(frozen=True)
class FrameSolution:
    """Result of :meth:`FrameModel.solve`.

    Attributes
    ----------
    displacements
        Nodal displacements, shape (n_nodes, 3): u [m], w [m], theta [rad].
    reactions
        Force each node receives from its supports and ties, shape (n_nodes, 3): forces [N] and moment [N m];
        ``K u - F`` node by node, so zero (to round-off) at free, untied degrees of freedom.
    forces
        Element forces by element name. Beam: ``[N_i, V_i, M_i, N_j, V_j, M_j]`` in local axes, the forces and
        moments the nodes exert on the element [N, N m] (a tension member has ``N_j > 0``). Axial spring:
        ``[T]``, its tension [N]. Rotational spring: ``[M]``, moment ``k (theta_j - theta_i)`` [N m].
    node_names
        Names of the nodes, in index order.
    """

    displacements: NDArray[np.float64]
    reactions: NDArray[np.float64]
    forces: dict[str, NDArray[np.float64]]
    node_names: tuple[str, ...]

    def node(self, name: str) -> NDArray[np.float64]:
        """Displacements (u [m], w [m], theta [rad]) of the node called ``name``."""
        return self.displacements[self.node_names.index(name)]


@dataclass
class FrameModel:
    """A 2-D linear frame model: add nodes and elements, constrain and load them, then :meth:`solve`.

    Elements and nodes are identified by index and by a unique name. Every method validates its input and raises
    ``ValueError`` naming the bad argument.
    """

    coords: list[tuple[float, float]] = field(default_factory=list)
    node_names: list[str] = field(default_factory=list)
    elements: dict[str, _Element] = field(default_factory=dict)
    prescribed: dict[int, float] = field(default_factory=dict)
    loads: dict[int, float] = field(default_factory=dict)
    ties: list[tuple[int, int]] = field(default_factory=list)

    # ---- building ----------------------------------------------------------------------------------------
    def add_node(self, x: float, z: float, name: str | None = None) -> int:
        """Add a node at (x [m], z [m]) and return its index."""
        if not (math.isfinite(x) and math.isfinite(z)):
            raise ValueError(f"node coordinates ({x!r}, {z!r}) must be finite (m)")
        name = f"n{len(self.coords)}" if name is None else name
        if name in self.node_names:
            raise ValueError(f"node name {name!r} is already used")
        self.coords.append((float(x), float(z)))
        self.node_names.append(name)
        return len(self.coords) - 1

    def node(self, name: str) -> int:
        """Index of the node called ``name``."""
        try:
            return self.node_names.index(name)
        except ValueError:
            raise ValueError(f"no node called {name!r}") from None

    def _check_node(self, i: int) -> int:
        if not (isinstance(i, (int, np.integer)) and 0 <= i < len(self.coords)):
            raise ValueError(f"node = {i!r} is not a node index: must be in [0, {len(self.coords) - 1}]")
        return int(i)

    def _add(self, name: str | None, element: _Element) -> str:
        name = f"e{len(self.elements)}" if name is None else name
        if name in self.elements:
            raise ValueError(f"element name {name!r} is already used")
        self.elements[name] = element
        return name

    def add_beam(
        self,
        i: int,
        j: int,
        ea: float,
        ei: float,
        release_i: bool = False,
        release_j: bool = False,
        name: str | None = None,
    ) -> str:
        """Add an Euler-Bernoulli beam from node i to node j; length and orientation follow the coordinates.

        Parameters
        ----------
        i, j
            End nodes.
        ea
            Axial rigidity [N].
        ei
            Bending rigidity [N m^2].
        release_i, release_j
            Pin release at end i, end j: that end transmits no moment.
        name
            Element name (default ``e<k>``).
        """
        i, j = self._check_node(i), self._check_node(j)
        (xi, zi), (xj, zj) = self.coords[i], self.coords[j]
        length = math.hypot(xj - xi, zj - zi)
        if length == 0.0:
            raise ValueError(f"beam from node {self.node_names[i]!r} to {self.node_names[j]!r} has zero length (m)")
        k_local = beam_local_stiffness(ea, ei, length, release_i, release_j)
        t = _rotation((xj - xi) / length, (zj - zi) / length)
        recover = k_local @ t
        return self._add(name, _Element("beam", (i, j), t.T @ recover, recover))

    def add_spring(
        self, i: int, j: int, stiffness: float, direction: Sequence[float] | None = None, name: str | None = None
    ) -> str:
        """Add an axial spring between nodes i and j acting along ``direction`` (default: from i towards j).

        Parameters
        ----------
        stiffness
            Spring rate [N/m].
        direction
            Line of action (x, z) [-]; needed when the nodes coincide. Tension is positive along it from i to j.
        """
        i, j = self._check_node(i), self._check_node(j)
        k = _positive("stiffness", stiffness, "N/m")
        if direction is None:
            (xi, zi), (xj, zj) = self.coords[i], self.coords[j]
            direction = (xj - xi, zj - zi)
        n = np.asarray(direction, dtype=float)
        norm = float(np.hypot(*n)) if n.shape == (2,) else 0.0
        if not (math.isfinite(norm) and norm > 0.0):
            raise ValueError(f"direction = {direction!r} must be a non-zero (x, z) vector (coincident nodes need one)")
        n = n / norm
        b = np.array([-n[0], -n[1], 0.0, n[0], n[1], 0.0])
        return self._add(name, _Element("spring", (i, j), k * np.outer(b, b), k * b[None, :]))

    def add_rotational_spring(self, i: int, j: int, stiffness: float, name: str | None = None) -> str:
        """Add a rotational spring between the rotations of nodes i and j, moment k (theta_j - theta_i).

        Parameters
        ----------
        stiffness
            Rotational rate [N m/rad].
        """
        i, j = self._check_node(i), self._check_node(j)
        k = _positive("stiffness", stiffness, "N m/rad")
        b = np.array([0.0, 0.0, -1.0, 0.0, 0.0, 1.0])
        return self._add(name, _Element("rotational_spring", (i, j), k * np.outer(b, b), k * b[None, :]))

    def tie(self, i: int, j: int, dofs: Iterable[str | int] = ("u", "w")) -> None:
        """Make the listed degrees of freedom of nodes i and j equal; ``("u", "w")`` is a pin joint."""
        i, j = self._check_node(i), self._check_node(j)
        for d in dofs:
            k = _dof_index(d)
            self.ties.append((3 * i + k, 3 * j + k))

    def prescribe(self, node: int, dof: str | int, value: float = 0.0) -> None:
        """Prescribe one degree of freedom of ``node`` (a support when ``value`` is 0) [m] or [rad]."""
        node = self._check_node(node)
        if not math.isfinite(value):
            raise ValueError(f"prescribed value = {value!r} must be finite (m or rad)")
        self.prescribed[3 * node + _dof_index(dof)] = float(value)

    def fix(self, node: int, dofs: Iterable[str | int] = DOF_NAMES) -> None:
        """Support the listed degrees of freedom of ``node`` (zero displacement)."""
        for d in dofs:
            self.prescribe(node, d, 0.0)

    def add_load(self, node: int, dof: str | int, value: float) -> None:
        """Add a nodal force [N] (``u``, ``w``) or moment [N m] (``theta``) to ``node``."""
        node = self._check_node(node)
        if not math.isfinite(value):
            raise ValueError(f"load = {value!r} must be finite (N or N m)")
        key = 3 * node + _dof_index(dof)
        self.loads[key] = self.loads.get(key, 0.0) + float(value)

    # ---- solving -----------------------------------------------------------------------------------------
    def _dof_label(self, k: int) -> str:
        return f"{self.node_names[k // 3]!r} {DOF_NAMES[k % 3]}"

    def _global_map(self) -> tuple[NDArray[np.int64], int]:
        parent = list(range(3 * len(self.coords)))

        def root(a: int) -> int:
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        for a, b in self.ties:
            ra, rb = root(a), root(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
        roots = np.array([root(a) for a in range(len(parent))])
        _, numbering = np.unique(roots, return_inverse=True)
        return numbering.astype(np.int64), int(numbering.max()) + 1

    def solve(self) -> FrameSolution:
        """Assemble (scipy.sparse), solve K u = F for the free DOFs, recover reactions and element forces.

        Raises
        ------
        ValueError
            If the model has no nodes, conflicting prescribed values on tied DOFs, or is a mechanism (singular
            stiffness); the message names the nodes and DOFs that move in the free mode.
        """
        n_exp = 3 * len(self.coords)
        if n_exp == 0:
            raise ValueError("the model has no nodes")
        rows, cols, vals = [], [], []
        for el in self.elements.values():
            idx = np.concatenate([np.arange(3 * n, 3 * n + 3) for n in el.nodes])
            rows.append(np.repeat(idx, 6))
            cols.append(np.tile(idx, 6))
            vals.append(el.stiffness.ravel())
        empty = [np.zeros(0, dtype=np.int64)]
        k_exp = sp.coo_matrix(
            (np.concatenate(vals or [np.zeros(0)]), (np.concatenate(rows or empty), np.concatenate(cols or empty))),
            shape=(n_exp, n_exp),
        ).tocsr()
        numbering, n_glob = self._global_map()
        tie_map = sp.csr_matrix((np.ones(n_exp), (np.arange(n_exp), numbering)), shape=(n_exp, n_glob))
        k_glob = (tie_map.T @ k_exp @ tie_map).tocsr()
        f_exp = np.zeros(n_exp)
        for key, value in self.loads.items():
            f_exp[key] = value
        f_glob = tie_map.T @ f_exp
        u_glob = np.zeros(n_glob)
        is_prescribed = np.zeros(n_glob, dtype=bool)
        for key, value in self.prescribed.items():
            g = numbering[key]
            if is_prescribed[g] and abs(u_glob[g] - value) > 1e-12 * max(1.0, abs(value)):
                raise ValueError(
                    f"tied DOF {self._dof_label(key)} is prescribed {value!r} but a DOF tied to it is prescribed "
                    f"{u_glob[g]!r}: tied DOFs must share one value"
                )
            u_glob[g], is_prescribed[g] = value, True
        free = np.flatnonzero(~is_prescribed)
        if free.size:
            k_ff = k_glob[free][:, free]
            rhs = f_glob[free] - k_glob[free][:, is_prescribed] @ u_glob[is_prescribed]
            u_glob[free] = self._solve_free(k_ff.tocsc(), rhs, free, numbering)
        u_exp = u_glob[numbering]
        reactions = k_exp @ u_exp - f_exp
        forces = {}
        for name, el in self.elements.items():
            idx = np.concatenate([np.arange(3 * n, 3 * n + 3) for n in el.nodes])
            forces[name] = el.recover @ u_exp[idx]
        return FrameSolution(
            displacements=u_exp.reshape(-1, 3),
            reactions=reactions.reshape(-1, 3),
            forces=forces,
            node_names=tuple(self.node_names),
        )

    def _solve_free(
        self, k_ff: sp.csc_matrix, rhs: NDArray[np.float64], free: NDArray[np.int64], numbering: NDArray[np.int64]
    ) -> NDArray[np.float64]:
        diag = k_ff.diagonal()
        if np.any(diag <= 0.0):
            self._raise_mechanism(np.flatnonzero(diag <= 0.0), free, numbering, None)
        # Jacobi scaling puts translations and rotations on one footing for the singularity test
        scale = 1.0 / np.sqrt(diag)
        k_scaled = sp.diags(scale) @ k_ff @ sp.diags(scale)
        try:
            lu = spla.splu(sp.csc_matrix(k_scaled))
            pivots = np.abs(lu.U.diagonal())
            singular = bool(np.min(pivots) < _PIVOT_TOL)
        except RuntimeError:
            singular = True
        if singular:
            self._raise_mechanism(None, free, numbering, k_scaled)
        return scale * lu.solve(scale * rhs)

    def _raise_mechanism(
        self,
        zero_rows: NDArray[np.int64] | None,
        free: NDArray[np.int64],
        numbering: NDArray[np.int64],
        k_scaled: sp.spmatrix | None,
    ) -> None:
        if zero_rows is None:
            # the free modes are the eigenvectors with round-off eigenvalues; a mechanism is a modelling error,
            # reported once, so a dense eigen-solve is affordable here
            vals, vecs = np.linalg.eigh(k_scaled.toarray())
            null = vecs[:, vals <= max(vals[0], _PIVOT_TOL * vals[-1])]
            mode = np.sqrt(np.sum(null * null, axis=1))  # size of each DOF over the whole null space
            zero_rows = np.flatnonzero(mode >= 0.5 * mode.max())
        labels = []
        for g in free[zero_rows]:
            members = np.flatnonzero(numbering == g)
            labels.append(" = ".join(self._dof_label(int(m)) for m in members))
        shown = ", ".join(labels[:8]) + (f" and {len(labels) - 8} more" if len(labels) > 8 else "")
        raise ValueError(
            f"the model is a mechanism (singular stiffness): its free mode moves {shown}; add a support, a spring "
            "or a tie that restrains it"
        )


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
            _positive(name, getattr(self, name), unit)
        if self.tyre_longitudinal_stiffness is not None:
            _positive("tyre_longitudinal_stiffness", self.tyre_longitudinal_stiffness, "N/m", allow_zero=True)
        if not (math.isfinite(self.drag_link_rise) and abs(self.drag_link_rise) <= 0.5):
            raise ValueError(f"drag_link_rise = {self.drag_link_rise!r} is out of range: must be in [-0.5, 0.5] m")


@dataclass(frozen=True)
class BogieFEResult:
    """Result of :func:`solve_fe`.

    Attributes
    ----------
    wheel_loads
        Vertical tyre force of each axle, compression positive, front to rear [N].
    equaliser_rotation
        Rotation of each equaliser relative to its bracket, rear tip down positive as in
        :func:`bogie.static.solve_static` [rad].
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
    if not (math.isfinite(chassis_deflection) and abs(chassis_deflection) <= 0.5):
        raise ValueError(f"chassis_deflection = {chassis_deflection!r} is out of range: must be in [-0.5, 0.5] m")
    limit = math.radians(10.0)
    if not (math.isfinite(chassis_rotation) and abs(chassis_rotation) <= limit):
        raise ValueError(
            f"chassis_rotation = {chassis_rotation!r} is out of range: must be in [-{limit:.4f}, {limit:.4f}] rad "
            "(10 degrees; the model is linear in small angles)"
        )


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
    steel = opt.steel_modulus
    hanger = (steel * opt.hanger_area, steel * opt.hanger_second_moment)
    arm = (steel * opt.equaliser_area, steel * opt.equaliser_second_moment)
    axle = (steel * opt.axle_area, steel * opt.axle_second_moment)
    k_x = bogie.tyre_stiffness if opt.tyre_longitudinal_stiffness is None else opt.tyre_longitudinal_stiffness
    # the bed's fore-aft position is an unknown only when something couples it to the ground: drag links to
    # axles that the braked tyres hold; otherwise it is set to 0, where it does not affect any force
    surge_free = drag_links and k_x > 0.0
    x_c = bogie.bogie_centre_x
    psi = chassis_rotation

    m = FrameModel()
    bed_nodes: list[int] = []

    def bed(x: float, name: str) -> int:
        node = m.add_node(x, z_bed, name)
        m.prescribe(node, "w", -chassis_deflection - psi * (x - x_c))
        m.prescribe(node, "theta", -psi)
        if not surge_free:
            m.prescribe(node, "u", 0.0)
        elif bed_nodes:
            m.tie(bed_nodes[0], node, ("u",))
        bed_nodes.append(node)
        return node

    # chassis side: hangers carry the outer spring ends, brackets the equalisers
    pads = {}  # "front<i>" / "rear<i>": the pad (hanger or equaliser tip) under spring i's front / rear end
    brackets = []  # bed node ahead of each axle, where its drag link is anchored
    x_fh, x_rh = bogie.front_hanger_x, bogie.rear_hanger_x
    top = bed(x_fh, "bed_front_hanger")
    pads["front0"] = m.add_node(x_fh, z_spring, "pad_front")
    m.add_beam(top, pads["front0"], *hanger, name="hanger_front")
    brackets.append(top)
    for j, x_p in enumerate(bogie.equaliser_pivot_x):
        top = bed(x_p, f"bed_pivot{j}")
        brackets.append(top)
        bracket = m.add_node(x_p, z_pivot, f"bracket{j}")
        m.add_beam(top, bracket, *hanger, name=f"bracket{j}")
        eq = m.add_node(x_p, z_pivot, f"equaliser{j}")
        m.tie(bracket, eq, ("u", "w"))
        if bogie.bush_stiffness > 0.0:
            m.add_rotational_spring(bracket, eq, bogie.bush_stiffness, name=f"bush{j}")
        tip_f = m.add_node(x_p - bogie.equaliser_front_arm[j], z_pivot - drop_f, f"tip{j}_front")
        tip_r = m.add_node(x_p + bogie.equaliser_rear_arm[j], z_pivot - drop_r, f"tip{j}_rear")
        m.add_beam(eq, tip_f, *arm, name=f"arm{j}_front")
        m.add_beam(eq, tip_r, *arm, name=f"arm{j}_rear")
        pads[f"rear{j}"], pads[f"front{j + 1}"] = tip_f, tip_r
    top = bed(x_rh, "bed_rear_hanger")
    pads[f"rear{n - 1}"] = m.add_node(x_rh, z_spring, "pad_rear")
    m.add_beam(top, pads[f"rear{n - 1}"], *hanger, name="hanger_rear")

    # axle side: leaf spring on two slipper contacts, axle, braked wheel, tyre springs to the ground
    for i in range(n):
        a_f, a_r = bogie.spring_front_half_length[i], bogie.spring_rear_half_length[i]
        span = a_f + a_r
        pad_f, pad_r = pads[f"front{i}"], pads[f"rear{i}"]
        (x_f, z_f), (x_r, z_r) = m.coords[pad_f], m.coords[pad_r]
        end_f = m.add_node(x_f, z_f, f"spring{i}_front")
        end_r = m.add_node(x_r, z_r, f"spring{i}_rear")
        x_s = bogie.axle_x[i]
        seat = m.add_node(x_s, z_f + (z_r - z_f) * a_f / span, f"spring{i}_seat")
        m.add_spring(pad_f, end_f, opt.contact_stiffness, (0.0, 1.0), name=f"contact{i}_front")
        m.add_spring(pad_r, end_r, opt.contact_stiffness, (0.0, 1.0), name=f"contact{i}_rear")
        # simply supported beam, point load at the seat: deflection P a_f^2 a_r^2 / (3 EI L) = P / K_R
        ei_leaf = bogie.road_spring_stiffness * a_f**2 * a_r**2 / (3.0 * span)
        m.add_beam(end_f, seat, steel * opt.spring_area, ei_leaf, name=f"leaf{i}_front")
        m.add_beam(seat, end_r, steel * opt.spring_area, ei_leaf, name=f"leaf{i}_rear")
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
        m.prescribe(ground, "w", -float(wear[i]))
        if drag_links:
            x_b = m.coords[brackets[i]][0]
            pin = m.add_node(x_b, z_axle + opt.drag_link_rise, f"link_pin{i}")
            m.add_beam(brackets[i], pin, *hanger, name=f"link_bracket{i}")
            m.add_beam(pin, centre, steel * opt.drag_link_area, 0.0, True, True, name=f"drag_link{i}")
    return m


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
        Fit drag links (radius rods); without them the loads agree with :func:`bogie.static.wheel_loads` to the
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
    bogie's b^2 K_S / (4 K_B). Defaults: :func:`~bogie.params.triaxle_stage1` (q = 4.3), alpha = 57 mm, the
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
    if not (math.isfinite(chassis_deflection) and 0.0 < chassis_deflection <= 0.5):
        raise ValueError(f"chassis_deflection = {chassis_deflection!r} is out of range: must be in (0, 0.5] m")
    points = {}
    for slope in slopes_deg:
        if not (math.isfinite(slope) and abs(slope) <= 10.0):
            raise ValueError(f"slope = {slope!r} is out of range: must be in [-10, 10] degree")
        loads = fe_wheel_loads(bogie, chassis_deflection, math.radians(slope), drag_links, options)
        w_bar = loads / (chassis_deflection * bogie.combined_stiffness)
        points[float(slope)] = (bogie.q(0), float(deviation_p(w_bar)))
    return points
