"""A small 2-D linear frame finite element solver (used by the Stage 1 mesh of :mod:`bogie.steel.fe`).

The solver (:class:`FrameModel`) works in a vertical plane: ``x`` rearward, ``z`` upward, three degrees of freedom
per node: ``u`` (along x) [m], ``w`` (along z) [m] and ``theta``, the rotation from x towards z (counter-clockwise
in a drawing with the rear on the right, so a positive ``theta`` raises the rear) [rad]. It offers Euler-Bernoulli
beam elements of any orientation with optional pin releases at either end (the released rotation is condensed
out), axial springs along a given direction, rotational springs, equal-DOF ties (pin joints between coincident
nodes), prescribed displacements and nodal loads. Derivations: ``docs/fe-model.md``.

References
----------
.. [1] J. S. Przemieniecki, *Theory of Matrix Structural Analysis*, McGraw-Hill, 1968 (beam stiffness, static
   condensation of released end rotations).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph
from numpy.typing import NDArray

from bogie import numerics
from bogie.lu import lu_factor, lu_solve
from bogie.ranges import check_positive

DOF_NAMES = ("u", "w", "theta")
#: smallest pivot of the Jacobi-scaled stiffness (unit diagonal) accepted as non-singular [-]
_PIVOT_TOL = 1e-11


def _dof_index(dof: str | int) -> int:
    if isinstance(dof, str) and dof in DOF_NAMES:
        return DOF_NAMES.index(dof)
    if isinstance(dof, int) and 0 <= dof < 3:
        return dof
    raise ValueError(f"dof = {dof!r} is not a degree of freedom: must be one of {', '.join(DOF_NAMES)} (or 0, 1, 2)")


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
    check_positive("ea", ea, "N")
    check_positive("ei", ei, "N m^2", allow_zero=release_i and release_j)
    L = check_positive("length", length, "m")
    a = ea / L
    k = np.zeros((6, 6))
    k[np.ix_([0, 3], [0, 3])] = a * np.array([[1.0, -1.0], [-1.0, 1.0]])
    if release_i and release_j:
        return k
    b = ei / L**3  # numerics-ok: floats, not arrays (libm pow)
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
        condensed = k[np.ix_(kept, kept)] - numerics.matmul(k_kr, numerics.solve(k_rr, k_kr.T))
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
        recover = numerics.matmul(k_local, t)
        return self._add(name, _Element("beam", (i, j), numerics.matmul(t.T, recover), recover))

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
        k = check_positive("stiffness", stiffness, "N/m")
        if direction is None:
            (xi, zi), (xj, zj) = self.coords[i], self.coords[j]
            direction = (xj - xi, zj - zi)
        n = np.asarray(direction, dtype=float)
        # the C library's hypot, not numpy's SIMD loop (bogie/numerics.py)
        norm = math.hypot(float(n[0]), float(n[1])) if n.shape == (2,) else 0.0
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
        k = check_positive("stiffness", stiffness, "N m/rad")
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
        """Global number of each expanded DOF: tied DOFs share one, numbered in order of their lowest DOF."""
        n_exp = 3 * len(self.coords)
        if self.ties:
            a, b = np.asarray(self.ties, dtype=np.int64).T
            graph = sp.coo_matrix((np.ones(a.size), (a, b)), shape=(n_exp, n_exp))
            n_glob, numbering = csgraph.connected_components(graph, directed=False)
        else:
            n_glob, numbering = n_exp, np.arange(n_exp)
        return numbering.astype(np.int64), int(n_glob)

    def _assemble(self) -> tuple[sp.csr_matrix, NDArray[np.float64]]:
        """Stiffness (scipy.sparse) and load vector in the expanded DOFs, 3 per node, before ties and supports."""
        n_exp = 3 * len(self.coords)
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
        f_exp = np.zeros(n_exp)
        for key, value in self.loads.items():
            f_exp[key] = value
        return k_exp, f_exp

    def _prescribed_values(self, numbering: NDArray[np.int64], n_glob: int) -> tuple[NDArray[np.float64], NDArray]:
        """Prescribed value and flag of each global DOF; tied DOFs must agree."""
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
        return u_glob, is_prescribed

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
        k_exp, f_exp = self._assemble()
        numbering, n_glob = self._global_map()
        tie_map = sp.csr_matrix((np.ones(n_exp), (np.arange(n_exp), numbering)), shape=(n_exp, n_glob))
        k_glob = (tie_map.T @ k_exp @ tie_map).tocsr()  # numerics-ok: scipy.sparse products (its own loops, no BLAS)
        f_glob = tie_map.T @ f_exp  # numerics-ok: a scipy.sparse product (its own loops, no BLAS)
        u_glob, is_prescribed = self._prescribed_values(numbering, n_glob)
        free = np.flatnonzero(~is_prescribed)
        if free.size:
            k_ff = k_glob[free][:, free]
            rhs = f_glob[free] - k_glob[free][:, is_prescribed] @ u_glob[is_prescribed]  # numerics-ok: scipy.sparse
            u_glob[free] = self._solve_free(k_ff.tocsc(), rhs, free, numbering)
        u_exp = u_glob[numbering]
        reactions = k_exp @ u_exp - f_exp  # numerics-ok: a scipy.sparse product (its own loops, no BLAS)
        forces = {}
        for name, el in self.elements.items():
            idx = np.concatenate([np.arange(3 * n, 3 * n + 3) for n in el.nodes])
            forces[name] = numerics.matmul(el.recover, u_exp[idx])
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
        k_scaled = sp.diags(scale) @ k_ff @ sp.diags(scale)  # numerics-ok: scipy.sparse products (no BLAS)
        # dense LU with partial pivoting in compiled code (bogie.lu), every sum in index order: SuperLU's dense
        # blocks go through BLAS, whose kernel, and so the last bits, OpenBLAS picks by the CPU (bogie/numerics.py).
        # The models have tens to a few hundred free DOFs, where this costs milliseconds.
        lu = np.ascontiguousarray(k_scaled.toarray())
        piv = np.zeros(lu.shape[0], dtype=np.int64)
        singular = not lu_factor(lu, piv) or bool(np.min(np.abs(np.diagonal(lu))) < _PIVOT_TOL)
        if singular:
            self._raise_mechanism(None, free, numbering, k_scaled)
        x = np.ascontiguousarray(scale * rhs, dtype=float)
        lu_solve(lu, piv, x)
        return scale * x

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
            vals, vecs = np.linalg.eigh(k_scaled.toarray())  # numerics-ok: names a mechanism in an error, no value
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
