"""Solving: :func:`solve` and its result, :class:`Solution`."""

from __future__ import annotations

import os
import warnings
from dataclasses import asdict, dataclass, fields
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, Union

import numpy as np

from . import _gradvi
from ._gradvi import SCHEMES, InternalError, InvalidDataError
from ._mesh import Mesh
from ._mesh3d import Mesh3
from ._problem import Problem

if TYPE_CHECKING:  # pragma: no cover
    import meshio

__all__ = ["solve", "Solution", "Certificate", "IterationLog"]

_KIND_NAMES = np.array(["vertex", "edge", "cell"])


@dataclass(frozen=True)
class Certificate:
    """Evidence that u solves the discrete variational inequality; every quantity is scaled
    (see the crate documentation, ``vi::certificate``), one attribute per field of the
    library's ``Certificate``."""

    #: max_j max(0, s(u_j − g_j)) / scale_u.
    max_violation: float
    #: min_j λ_j / scale_r (≥ 0 up to round-off).
    min_multiplier: float
    #: max_j |λ_j (u_j − g_j)| / (scale_r scale_u).
    complementarity: float
    #: max_i |(b − Mu)_i| / scale_r on the free unknowns.
    balance_residual: float
    #: ‖u‖∞ against the size of the data (at most 1e6).
    data_magnitude: float

    @classmethod
    def _from(cls, d: Dict[str, float]) -> "Certificate":
        names = [f.name for f in fields(cls)]
        if sorted(d) != sorted(names):
            raise InternalError(f"the library's certificate has the fields {sorted(d)}, the Python class {sorted(names)}")
        return cls(**{k: float(d[k]) for k in names})

    def as_dict(self) -> Dict[str, float]:
        """Every quantity, by name."""
        return asdict(self)

    def worst(self) -> float:
        """The largest of the four scaled quantities checked against the tolerance (the minimum
        multiplier counted by its negative part)."""
        return max(self.max_violation, max(0.0, -self.min_multiplier), self.complementarity, self.balance_residual)

    def ok(self, tol: float = 1e-10) -> bool:
        """Whether every scaled quantity is below ``tol``."""
        return self.worst() <= tol

    def __repr__(self) -> str:
        return "Certificate(" + ", ".join(f"{k}={v:.2e}" for k, v in self.as_dict().items()) + ")"


@dataclass(frozen=True)
class IterationLog:
    """One linear solve of the active-set (monotony) method."""

    #: Solve number, from 1.
    solve: int
    #: Size of the active set used for this solve.
    active: int
    #: Unknowns that entered the active set for this solve.
    entered: int
    #: Unknowns that left it.
    left: int
    #: Largest scaled constraint violation of the iterate.
    violation: float
    #: Largest scaled balance residual on the inactive unknowns; ``None`` for a screened
    #: iterate (an iterative solve stopped early to choose the next active set), whose
    #: residual is computed on the constrained unknowns only.
    residual: Optional[float]
    #: Seconds: ``assemble`` (condensation and scatter), ``factor``, ``solve``.
    timings: Dict[str, float]

    @classmethod
    def _from(cls, d: Dict[str, Any]) -> "IterationLog":
        names = ("solve", "active", "entered", "left", "violation", "residual", "timings")
        return cls(**{k: d[k] for k in names})


def _residual_cell(r: Optional[float]) -> str:
    """An iteration's residual for the summary: ``-`` for a screened iterate."""
    return "-" if r is None else f"{r:.2e}"


class Solution:
    """The certified result of :func:`solve`.

    Unknowns (``u``, ``multiplier_field``, ``active_field``) are indexed like the scheme's
    unknowns: HMM edges then cells, P1 vertices, CR edges; ``dof_kind``/``dof_index`` say on
    which mesh entity each lives. Per-entity views: ``u_cell`` (Π_D u at x_K), ``u_vertex``
    (P1: nodal values; others: area-weighted averages of the adjacent cells), ``u_edge``
    (HMM/CR face values), ``gradient`` (∇_K u per cell).

    The barrier (obstacle or Signorini) acts on the ``constrained_dofs``; ``barrier``,
    ``multiplier`` (λ ≥ 0 where active) and ``active`` are indexed like them, and
    ``active_cells``/``active_vertices``/``active_edges`` lay the active set on the mesh.
    ``contact_measure`` is Σ m_j over the active constrained unknowns (the contact area of an
    obstacle problem, the contact length of a Signorini problem).

    On a 3D mesh (:class:`Mesh3`) the same fields hold with d = 3: the "edges" of the names
    are the faces (``u_edge``/``u_face``, ``active_edges``/``active_faces``: one value per
    face), ``gradient`` and ``constrained_points`` have 3 columns, ``contact_measure`` is a
    volume (obstacle) or an area (Signorini), and ``free_boundary`` is empty (computed on
    planar meshes only).
    """

    #: The mesh solved on.
    mesh: Union[Mesh, Mesh3]
    #: The problem solved.
    problem: Problem
    #: The certificate of u.
    certificate: Certificate
    #: NITER: the number of linear solves (sweeps for projected Gauss–Seidel).
    niter: int
    #: ``"linear"`` (no barrier), ``"active-set"`` or ``"projected-gauss-seidel"``.
    method: str
    #: The iteration log, one entry per linear solve.
    log: List[IterationLog]
    #: Wall-clock seconds: data (evaluation of Python data), setup, symbolic, warm_start,
    #: assemble, factor, solve, total (total excludes data).
    timings: Dict[str, float]
    #: Relative L² errors at the centroids ``{"l2_u", "l2_grad"}`` (exact solution known), else None.
    errors: Optional[Dict[str, float]]
    #: What the nested warm start did (None: cold start or no barrier).
    warm_start: Optional[Dict[str, Any]]
    #: Parts of the mesh without Dirichlet boundary whose well-posedness hangs on the sign of a
    #: small total load, each ``{"cell", "sum", "ratio", "message"}`` (ratio = |Σb| / Σ|b|,
    #: below 0.1); :func:`solve` also warns with :class:`MarginalLoadWarning`. Usually empty.
    marginal_load: List[Dict[str, Any]]
    #: The scheme's name.
    scheme: str
    #: Points outside the evaluation table that the solve asked data at (only the coarse
    #: meshes of the nested warm start do).
    untabulated_points: int
    #: How many of those called a Python callable.
    fallback_calls: int
    #: The iterates u^1, u^2, … (with ``keep_iterates=True``).
    iterates: List[np.ndarray]

    __slots__ = (
        "_r", "mesh", "problem", "certificate", "niter", "method", "log", "timings", "errors", "warm_start",
        "marginal_load", "scheme", "untabulated_points", "fallback_calls", "iterates",
    )

    def __init__(self, mesh: Union[Mesh, Mesh3], problem: Problem, r: Dict[str, Any], data_seconds: float) -> None:
        self.mesh = mesh
        self.problem = problem
        self._r = r
        self.certificate = Certificate._from(r["certificate"])
        self.niter = int(r["niter"])
        self.method = str(r["method"])
        self.log = [IterationLog._from(e) for e in r["log"]]
        self.timings = dict(r["timings"], data=data_seconds)
        self.errors = r["errors"]
        self.warm_start = r["warm_start"]
        self.marginal_load = list(r["marginal_load"])
        self.scheme = str(r["scheme"])
        self.untabulated_points = int(r.get("untabulated_points", 0))
        self.fallback_calls = int(r.get("fallback_calls", 0))
        self.iterates = list(r["iterates"])

    # ---------------------------------------------------------------- the discrete solution

    @property
    def u(self) -> np.ndarray:
        """All unknowns of the scheme."""
        return self._r["u"]

    @property
    def u_cell(self) -> np.ndarray:
        """Π_D u at the cell centroids, one value per cell."""
        return self._r["u_cell"]

    @property
    def u_vertex(self) -> np.ndarray:
        """One value per vertex (P1: the unknowns; HMM/CR: averages of the adjacent cells)."""
        return self._r["u_vertex"]

    @property
    def u_edge(self) -> Optional[np.ndarray]:
        """The face unknowns u_σ per edge (HMM, CR; per face in 3D), else None."""
        return self._r["u_fields"].get("edge")

    @property
    def u_face(self) -> Optional[np.ndarray]:
        """The face unknowns u_σ per face (edges in 2D): the same array as :attr:`u_edge`."""
        return self.u_edge

    @property
    def dim(self) -> int:
        """The dimension of the mesh, 2 or 3."""
        return 3 if isinstance(self.mesh, Mesh3) else 2

    @property
    def gradient(self) -> np.ndarray:
        """The cell gradient (HMM: ∇_K u; P1, CR: the exact gradient), (n_cells, d)."""
        return self._r["gradient"]

    @property
    def dof_kind(self) -> np.ndarray:
        """The kind of mesh entity of each unknown: ``"vertex"``, ``"edge"`` or ``"cell"``."""
        return _KIND_NAMES[self._r["entity_kind"]]

    @property
    def dof_index(self) -> np.ndarray:
        """The index of the entity of each unknown (see :attr:`dof_kind`)."""
        return self._r["entity_index"]

    @property
    def n_unknowns(self) -> int:
        """dim X_D."""
        return int(self._r["n_unknowns"])

    @property
    def n_condensed(self) -> int:
        """Unknowns of the linear systems after static condensation."""
        return int(self._r["n_condensed"])

    @property
    def u_exact_cell(self) -> Optional[np.ndarray]:
        """ū(x_K), when the exact solution is known."""
        return self._r["exact_cell"]

    # ---------------------------------------------------------------- the barrier

    def _c(self, key: str) -> Any:
        c = self._r["constraint"]
        return None if c is None else c[key]

    @property
    def constraint(self) -> Optional[tuple]:
        """``(kind, side)`` of the barrier, or None."""
        c = self._r["constraint"]
        return None if c is None else (c["kind"], c["side"])

    @property
    def constrained_dofs(self) -> np.ndarray:
        """The unknowns the barrier acts on (Dirichlet unknowns excluded)."""
        v = self._c("dofs")
        return np.zeros(0, dtype=np.int64) if v is None else v

    @property
    def constrained_points(self) -> np.ndarray:
        """Where the barrier was evaluated for each constrained unknown, (n, d)."""
        v = self._c("points")
        return np.zeros((0, self.dim)) if v is None else v

    @property
    def constrained_measures(self) -> np.ndarray:
        """The measure m_j of each constrained unknown (|K|, |σ|, or a lumped vertex measure):
        λ_j / m_j is the contact pressure (Signorini) or the density of the reaction (obstacle)."""
        v = self._c("measures")
        return np.zeros(0) if v is None else v

    @property
    def barrier(self) -> np.ndarray:
        """The barrier value on each constrained unknown (g_K, a_σ or nodal values)."""
        v = self._c("barrier")
        return np.zeros(0) if v is None else v

    @property
    def multiplier(self) -> np.ndarray:
        """λ on each constrained unknown (≥ 0; positive only where active)."""
        v = self._c("multiplier")
        return np.zeros(0) if v is None else v

    @property
    def active(self) -> np.ndarray:
        """Whether each constrained unknown is active (u = barrier)."""
        v = self._c("active")
        return np.zeros(0, dtype=bool) if v is None else v

    @property
    def active_set(self) -> np.ndarray:
        """The active unknowns (ids into :attr:`u`)."""
        return self.constrained_dofs[self.active]

    @property
    def n_active(self) -> int:
        """Size of the active set."""
        return int(np.count_nonzero(self.active))

    @property
    def multiplier_field(self) -> np.ndarray:
        """λ on every unknown (0 off the constrained ones)."""
        v = self._c("multiplier_field")
        return np.zeros(self.n_unknowns) if v is None else v

    @property
    def active_field(self) -> np.ndarray:
        """1.0 on active unknowns, 0.0 elsewhere."""
        v = self._c("active_field")
        return np.zeros(self.n_unknowns) if v is None else v

    def _entity(self, what: str, kind: str) -> Optional[np.ndarray]:
        c = self._r["constraint"]
        if c is None:
            return None
        v = c[what].get(kind)
        return None if v is None else (v > 0.5 if what == "active_fields" else v)

    @property
    def active_cells(self) -> Optional[np.ndarray]:
        """Per cell: whether its constrained unknown is active (HMM obstacle), else None."""
        return self._entity("active_fields", "cell")

    @property
    def active_vertices(self) -> Optional[np.ndarray]:
        """Per vertex: whether its constrained unknown is active (P1), else None."""
        return self._entity("active_fields", "vertex")

    @property
    def active_edges(self) -> Optional[np.ndarray]:
        """Per edge (per face in 3D): whether its constrained unknown is active (HMM
        Signorini, CR), else None."""
        return self._entity("active_fields", "edge")

    @property
    def active_faces(self) -> Optional[np.ndarray]:
        """Per face (edge in 2D): the same array as :attr:`active_edges`."""
        return self.active_edges

    @property
    def contact_measure(self) -> float:
        """Σ_j m_j over the active constrained unknowns (|K|, lumped vertex or edge measures):
        the contact area (obstacle) or length (Signorini)."""
        v = self._c("contact_measure")
        return 0.0 if v is None else float(v)

    @property
    def free_boundary(self) -> np.ndarray:
        """Midpoints between neighbouring active and inactive constrained unknowns: points of the
        discrete free boundary, (n, 2); empty, (0, 3), on a 3D mesh."""
        v = self._c("free_boundary")
        return np.zeros((0, self.dim)) if v is None else v

    # ---------------------------------------------------------------- output

    def fields(self) -> tuple:
        """``(point_data, cell_data)``: the arrays ``gradvi solve --vtu`` writes (``u_vertex``;
        ``u_K``, ``grad_x``, ``grad_y`` (and ``grad_z`` in 3D); the active set and the
        multiplier on the entities of the constrained unknowns: ``active``/``multiplier`` per
        vertex, ``active_cell``/``multiplier_cell`` per cell, ``active_edges``/
        ``multiplier_edges`` summed over each cell's edges (faces in 3D)), plus ``u_exact``
        per cell when known."""
        pd: Dict[str, np.ndarray] = {"u_vertex": self.u_vertex}
        g = self.gradient
        cd: Dict[str, np.ndarray] = {"u_K": self.u_cell}
        for i, c in enumerate("xyz"[: self.dim]):
            cd["grad_" + c] = g[:, i].copy()
        c = self._r["constraint"]
        if c is not None:
            a, lam = c["active_fields"], c["multiplier_fields"]
            if "vertex" in a:
                pd["active"] = a["vertex"]
                pd["multiplier"] = lam["vertex"]
            if "cell" in a:
                cd["active_cell"] = a["cell"]
                cd["multiplier_cell"] = lam["cell"]
            if c["active_edge_sums"] is not None:
                cd["active_edges"] = c["active_edge_sums"]
                cd["multiplier_edges"] = c["multiplier_edge_sums"]
        if self.u_exact_cell is not None:
            cd["u_exact"] = self.u_exact_cell
        return pd, cd

    def boundary_fields(self) -> tuple:
        """``(point_data, face_data)`` of a 3D solution on its boundary surface: the arrays
        ``gradvi solve --vtu`` writes to its boundary file, per mesh vertex (``u_vertex``; with
        a barrier on vertex unknowns (P1) ``active`` and ``multiplier``) and per mesh face
        (``u_face``, the face unknowns u_σ of HMM and CR; with a barrier on face unknowns (HMM
        Signorini, CR) ``active``, 1.0 on the contact zone, and ``multiplier``, λ_σ).
        ``InvalidDataError`` on a planar mesh (the planar file draws the cells only)."""
        if self.dim != 3:
            raise InvalidDataError("the boundary surface is written for 3D solutions only")
        pd: Dict[str, np.ndarray] = {"u_vertex": self.u_vertex}
        fd: Dict[str, np.ndarray] = {}
        if self.u_face is not None:
            fd["u_face"] = self.u_face
        c = self._r["constraint"]
        if c is not None:
            a, lam = c["active_fields"], c["multiplier_fields"]
            for kind, out in (("edge", fd), ("vertex", pd)):
                if kind in a:
                    out["active"] = a[kind]
                    out["multiplier"] = lam[kind]
        return pd, fd

    def write_boundary_vtu(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes the boundary surface of a 3D solution (the boundary faces as polygons with
        :meth:`boundary_fields`, their index ``face`` and their ``boundary_tag``) to an ASCII
        ``.vtu`` file (:meth:`Mesh3.write_boundary_vtu`)."""
        pd, fd = self.boundary_fields()
        self.mesh.write_boundary_vtu(path, pd, fd)  # type: ignore[union-attr]

    def write_faces_vtu(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes every face of the mesh of a 3D solution, interior and boundary, to an ASCII
        ``.vtu`` file (:meth:`Mesh3.write_faces_vtu`) with the arrays of
        :meth:`boundary_fields` on every face (``active`` and ``multiplier`` are 0 off the
        constrained faces, ``boundary_tag`` 0 on interior faces): what ``gradvi solve --vtu
        --vtu-faces`` writes to ``NAME_faces.vtu``. ``InvalidDataError`` on a planar mesh."""
        pd, fd = self.boundary_fields()
        self.mesh.write_faces_vtu(path, pd, fd)  # type: ignore[union-attr]

    def write_vtu(self, path: Union[str, "os.PathLike[str]"], *, boundary: bool = True, faces: bool = False) -> None:
        """Writes the solution (see :meth:`fields`) to an ASCII ``.vtu`` file for ParaView,
        with gradvi's own writer. A 3D solution also writes, as ``gradvi solve --vtu`` does,
        its boundary surface (:meth:`write_boundary_vtu`) beside it: ``NAME_boundary.vtu`` for
        ``NAME.vtu`` (``boundary=False``: not). With ``faces=True``, as ``gradvi solve --vtu
        --vtu-faces``, also every face of the mesh (:meth:`write_faces_vtu`) to
        ``NAME_faces.vtu`` (:func:`faces_path`). ``faces=True`` on a planar solution raises
        :class:`gradvi.InvalidDataError` before any file is written."""
        if faces and self.dim != 3:
            raise InvalidDataError(
                f"faces=True writes the faces of a 3D mesh; the mesh ({self.mesh.n_cells} cells) is 2D"
            )
        pd, cd = self.fields()
        self.mesh.write_vtu(path, pd, cd)
        if boundary and self.dim == 3:
            self.write_boundary_vtu(boundary_path(path))
        if faces:
            self.write_faces_vtu(faces_path(path))

    def to_meshio(self) -> "meshio.Mesh":
        """The mesh with the arrays of :meth:`fields` as point and cell data (needs meshio)."""
        pd, cd = self.fields()
        if isinstance(self.mesh, Mesh3):
            return self.mesh.to_meshio(point_data=pd, cell_data=cd)
        return self.mesh.to_meshio(point_data=pd, cell_data=cd, boundary_lines=False)

    def summary(self) -> str:
        """A text report like ``gradvi solve``'s."""
        lines = [
            f"problem         {self._r['problem']}",
            f"scheme          {self.scheme}",
            f"mesh            {self.mesh.n_cells} cells, h = {self.mesh.h:.6f}",
            f"unknowns        {self.n_unknowns} ({self.n_condensed} after condensation)",
            f"method          {self.method}",
            f"NITER           {self.niter} (linear solves)",
            "  solve  active  entered  left  violation  residual",
        ]
        for e in self.log:
            lines.append(f"  {e.solve:>5}  {e.active:>6}  {e.entered:>7}  {e.left:>4}  {e.violation:>9.2e}  {_residual_cell(e.residual):>8}")
        c = self.certificate
        lines.append(
            f"certificate     violation {c.max_violation:.2e}, min multiplier {c.min_multiplier:.2e}, "
            f"complementarity {c.complementarity:.2e}, balance residual {c.balance_residual:.2e}"
        )
        if self.constraint is not None:
            lines.append(f"contact         {self.n_active} active unknowns, measure {self.contact_measure:.6g}")
        if self.errors is not None:
            lines.append(
                f"errors          relative L2 of u at centroids {self.errors['l2_u']:.6e}, of the gradient {self.errors['l2_grad']:.6e}"
            )
        t = self.timings
        lines.append(
            f"timings [s]     data {t['data']:.3f}, setup {t['setup']:.3f} (symbolic {t['symbolic']:.3f}), warm start "
            f"{t['warm_start']:.3f}, assembly {t['assemble']:.3f}, factorisation {t['factor']:.3f}, solves {t['solve']:.3f}, total {t['total']:.3f}"
        )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (
            f"<gradvi.Solution {self._r['problem']!r} {self.scheme}: {self.n_unknowns} unknowns, "
            f"NITER {self.niter}, {self.n_active} active, certificate {self.certificate.worst():.1e}>"
        )


def boundary_path(path: Union[str, "os.PathLike[str]"]) -> str:
    """The boundary VTU file beside the VTU file ``path``: ``NAME_boundary.EXT`` for
    ``NAME.EXT`` (the name ``gradvi solve --vtu`` gives it)."""
    root, ext = os.path.splitext(os.fspath(path))
    return f"{root}_boundary{ext}"


def faces_path(path: Union[str, "os.PathLike[str]"]) -> str:
    """The all-faces VTU file beside the VTU file ``path``: ``NAME_faces.EXT`` for
    ``NAME.EXT`` (the name ``gradvi solve --vtu --vtu-faces`` gives it)."""
    root, ext = os.path.splitext(os.fspath(path))
    return f"{root}_faces{ext}"


def _as_mesh(mesh: Any) -> Union[Mesh, Mesh3]:
    if isinstance(mesh, (Mesh, Mesh3)):
        return mesh
    if isinstance(mesh, (str, os.PathLike)):
        return Mesh.read(mesh)
    if type(mesh).__name__ == "Mesh" and hasattr(mesh, "cells") and hasattr(mesh, "points"):
        return Mesh.from_meshio(mesh)
    raise InvalidDataError(f"mesh must be a gradvi.Mesh, a gradvi.Mesh3, a file path or a meshio.Mesh, got {type(mesh).__name__}")


def _as_problem(problem: Any) -> Problem:
    if isinstance(problem, Problem):
        return problem
    if isinstance(problem, (str, os.PathLike)):
        s = os.fspath(problem)
        return Problem.from_file(s) if s.endswith(".toml") else Problem.builtin(s)
    raise InvalidDataError(f"problem must be a gradvi.Problem, a built-in name or a .toml path, got {type(problem).__name__}")


def solve(
    mesh: Union[Mesh, Mesh3, str, "os.PathLike[str]", "meshio.Mesh", None],
    problem: Union[Problem, str],
    *,
    scheme: Optional[str] = None,
    alpha: float = 1.0,
    c: float = 1.0,
    max_solves: int = 500,
    tol: float = 1e-10,
    fallback: bool = False,
    warm_start: str = "nested",
    initial_active: Optional[Sequence[bool]] = None,
    keep_iterates: bool = False,
    ordering: str = "amd",
    factor_threads: str = "sequential",
    linear: str = "auto",
) -> Solution:
    """Solves a problem on a mesh with a gradient scheme; returns a certified :class:`Solution`.

    Without a barrier this is one linear solve; with one, the monotony (primal–dual active-set)
    algorithm of the paper, started by default from an active set predicted by coarse solves
    (``warm_start="cold"``: from an empty set, the paper's NITER). Every solution is certified:
    a solve whose certificate exceeds ``tol`` raises :class:`gradvi.CertificateError`.

    Example::

        import gradvi
        mesh = gradvi.Mesh.read("meshes/test3_1.msh")
        sol = gradvi.solve(mesh, gradvi.Problem.builtin("test3", C=-20), scheme="hmm")
        print(sol.niter, sol.contact_measure, sol.certificate)

    Args:
        mesh: a :class:`Mesh`, a 3D :class:`Mesh3`, a mesh file path (planar), a
            ``meshio.Mesh`` (planar), or None for a problem file with a ``[mesh]`` section
            (:meth:`Problem.mesh`: planar or 3D, as ``gradvi solve`` builds it).
        problem: a :class:`Problem`, a built-in name (``"test3"``) or a ``.toml`` path; on a
            :class:`Mesh3`, a problem file that compiles as a 3D problem
            (``problems/ex9-3d.toml``) or a :class:`Problem` built from callables of
            (x, y, z).
        scheme: ``"hmm"`` (any polygonal or polyhedral mesh), ``"p1"`` or ``"cr"`` (triangles
            or tetrahedra; other cells are refused with an :class:`InvalidDataError`);
            default: the problem file's ``scheme``, else ``"hmm"``.
        alpha: HMM stabilisation parameter α > 0 (the other schemes accept only 1).
        c: the active-set parameter c > 0.
        max_solves: cap on the number of linear solves.
        tol: tolerance of the certificate, in (0, 1).
        fallback: on cycling or the cap, fall back to projected Gauss–Seidel instead of raising.
        warm_start: ``"nested"`` (the default: an active set predicted by coarse HMM solves
            of the same problem on agglomerated meshes of the domain: same solution, fewer
            solves on fine meshes; 2D and 3D) or ``"cold"`` (A₀ = ∅, the paper's NITER).
        initial_active: an initial active set, one flag per constrained unknown.
        keep_iterates: keep every iterate in :attr:`Solution.iterates`.
        ordering: fill-reducing ordering of the Cholesky factorisation, ``"amd"`` or
            ``"nested-dissection"``.
        factor_threads: ``"sequential"`` or ``"global"`` (faer's parallel factorisation).
        linear: linear solver, ``"auto"`` (direct below 250 000 condensed unknowns in 2D, 20 000 in 3D, iterative
            above), ``"direct"`` (sparse Cholesky) or ``"iterative"`` (algebraic-multigrid
            preconditioned conjugate gradients, memory linear in the size).

    Raises:
        GradviError: a subclass naming what went wrong: :class:`gradvi.InvalidDataError`
            (options, data with NaN, a scheme unfit for the mesh), :class:`gradvi.InfeasibleError`
            (empty convex set), :class:`gradvi.ProblemFileError`, :class:`gradvi.SolverError`
            (no convergence, cycling, certificate), :class:`gradvi.IllPosedError` (no unique
            solution, e.g. no Dirichlet part and no barrier), :class:`gradvi.LinearSolverError`.
            An exception raised by a callable of a Python-built problem propagates unchanged.
    """
    pb = _as_problem(problem)
    if mesh is None:
        m = pb.mesh()
        if m is None:
            raise InvalidDataError("no mesh given, and the problem has no [mesh] section")
    else:
        m = _as_mesh(mesh)
    sch = scheme if scheme is not None else (pb.scheme or "hmm")
    if not isinstance(sch, str) or sch.lower() not in SCHEMES:
        raise InvalidDataError(f"unknown scheme {sch!r} (expected one of: {', '.join(SCHEMES)})")
    sch = sch.lower()
    if int(max_solves) < 1:
        raise InvalidDataError(f"max_solves must be at least 1, got {max_solves}")
    init = None if initial_active is None else np.ascontiguousarray(initial_active, dtype=bool)
    handle, seconds = pb._for_mesh(m, sch)
    r = _gradvi.solve(
        m._m,
        handle,
        scheme=sch,
        alpha=float(alpha),
        c=float(c),
        max_solves=int(max_solves),
        tol=float(tol),
        fallback=bool(fallback),
        warm_start=str(warm_start),
        initial_active=init,
        keep_iterates=bool(keep_iterates),
        ordering=str(ordering),
        factor_threads=str(factor_threads),
        linear=str(linear),
    )
    sol = Solution(m, pb, r, seconds)
    for part in sol.marginal_load:
        warnings.warn(part["message"], MarginalLoadWarning, stacklevel=2)
    return sol


class MarginalLoadWarning(UserWarning):
    """A part of the mesh without Dirichlet boundary, held by a barrier, whose discrete load
    nearly cancels (|Σb| / Σ|b| < 0.1): whether the problem is well-posed there depends on the
    sign of that load, hence on its discretisation (another scheme or mesh may conclude
    otherwise). See :attr:`Solution.marginal_load`."""
