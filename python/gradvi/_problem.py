"""Problems: :class:`Problem` (built-in, from a problem file, or built from Python data)."""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _gradvi
from ._gradvi import InvalidDataError
from ._mesh import Mesh
from ._mesh3d import Mesh3

__all__ = ["Problem", "CellData", "EdgeData", "VertexData"]

ArrayLike = Any
#: A scalar datum: a number, a vectorised callable ``f(x, y)``, or per-entity values.
Scalar = Union[float, Callable[[np.ndarray, np.ndarray], ArrayLike], "CellData", "EdgeData", "VertexData", np.ndarray]

_KINDS = {"dirichlet": 0, "neumann": 1, "signorini": 2}


class _EntityData:
    kind = ""

    def __init__(self, values: ArrayLike) -> None:
        self.values = np.asarray(values, dtype=np.float64)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(shape={self.values.shape})"


class CellData(_EntityData):
    """Values per cell (one per cell, in mesh order): a datum constant on each cell.

    For the source f and the diffusion A (shape (n_cells,) or (n_cells, 2, 2)) each cell takes
    its own value, whatever the scheme. Where a scheme needs the datum at an edge midpoint or a
    vertex (e.g. an obstacle with P1), the value there is the mean over the adjacent cells; at
    another point of a cell, the cell's value."""

    kind = "cell"


class EdgeData(_EntityData):
    """Values per edge (one per edge, in mesh order), e.g. boundary data on x_σ.

    At a vertex (P1), the value is the mean over the adjacent edges weighted by 1/|σ| (for
    boundary data: over the adjacent boundary edges; exact for affine data along a straight
    side); at a cell centroid, the mean over the cell's edges; at another point of a cell (CR's
    sub-triangle centroids), the value of the edge σ whose triangle co(σ ∪ {x_K}) holds it."""

    kind = "edge"


class VertexData(_EntityData):
    """Values per vertex (nodal values, as P1 uses them).

    At an edge midpoint the value is the mean of the two ends, at a centroid the mean over the
    cell's vertices (the linear interpolant on triangles), at another point of a cell (CR's
    sub-triangle centroids) the affine interpolant on the triangle co(σ ∪ {x_K}) holding it,
    from the values at the ends of σ and that mean at x_K."""

    kind = "vertex"


#: The site kinds of :meth:`_Mesh.evaluation_points` (``gradvi::scheme::points::Site``).
_VERTEX, _EDGE, _CELL, _IN_CELL = 0, 1, 2, 3


class _Points:
    """The points where the scheme evaluates data on one mesh, as the Rust library lists them
    (``gradvi::scheme::points``): each point once (``xy``), the mesh entity it lies on, and for
    each datum the rows where the solve reads it (``rows``: ``diffusion``, ``source``,
    ``boundary``, ``trace``, ``obstacle``, ``exact``)."""

    def __init__(self, mesh: Mesh, scheme: str) -> None:
        p = mesh._m.evaluation_points(scheme)
        self.mesh = mesh
        self.nc, self.ne, self.nv = mesh.n_cells, mesh.n_edges, mesh.n_vertices
        self.xy = np.ascontiguousarray(p["points"])
        self.m = len(self.xy)
        self.x, self.y = self.xy[:, 0].copy(), self.xy[:, 1].copy()
        self.site_kind = np.asarray(p["site_kind"])
        self.site_index = np.asarray(p["site_index"])
        self.site_edge = np.asarray(p["site_edge"])
        self.site_weights = np.asarray(p["site_weights"])
        #: for each datum, the rows of its points (each once, ascending)
        self.rows: Dict[str, np.ndarray] = dict(p["rows"])

    dim = 2

    def at(self, rows: np.ndarray) -> List[np.ndarray]:
        """The coordinate arrays (x, y) of the points ``rows``."""
        return [self.x[rows], self.y[rows]]

    def faces(self) -> "_Faces":
        """The boundary edges, for the boundary partition."""
        m, be = self.mesh, self.mesh.boundary_edges
        return _Faces(self.ne, be, m.edge_midpoints[be], m.edge_tags[be], "edge", 2)

    # means over incidences -------------------------------------------------------------
    def _cell_to_edges(self, a: np.ndarray) -> np.ndarray:
        ec = self.mesh.edge_cells
        two = ec[:, 1] >= 0
        out = a[ec[:, 0]].copy()
        out[two] = 0.5 * (a[ec[two, 0]] + a[ec[two, 1]])
        return out

    def _cell_to_vertices(self, a: np.ndarray) -> np.ndarray:
        off, conn = self.mesh.cell_offsets, self.mesh.cell_connectivity
        per = np.repeat(a, np.diff(off))
        s = np.bincount(conn, weights=per, minlength=self.nv)
        n = np.bincount(conn, minlength=self.nv)
        return s / np.maximum(n, 1)

    def _edge_to_cells(self, a: np.ndarray) -> np.ndarray:
        off, ce = self.mesh.cell_offsets, self.mesh.cell_edges
        s = np.add.reduceat(a[ce], off[:-1])
        return s / np.diff(off)

    def _edge_to_vertices(self, a: np.ndarray, boundary_only: bool) -> np.ndarray:
        ed = self.mesh.edges
        sel = self.mesh.boundary_edges if boundary_only else np.arange(self.ne)
        v = ed[sel].reshape(-1)
        inv = np.repeat(1.0 / self.mesh.edge_lengths[sel], 2)  # weights 1/|σ|
        s = np.bincount(v, weights=np.repeat(a[sel], 2) * inv, minlength=self.nv)
        n = np.bincount(v, weights=inv, minlength=self.nv)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n > 0, s / np.where(n > 0, n, 1.0), np.nan)

    def _vertex_to_cells(self, a: np.ndarray) -> np.ndarray:
        off, conn = self.mesh.cell_offsets, self.mesh.cell_connectivity
        return np.add.reduceat(a[conn], off[:-1]) / np.diff(off)

    def spread(self, d: _EntityData, what: str, rows: np.ndarray, boundary: bool = False) -> np.ndarray:
        """A per-entity array spread onto ``rows`` (NaN on the other rows), by the site of each
        point (see the docs of the entity classes): its own entity's value, a mean over
        incidences, and at a point of the triangle co(σ ∪ {x_K}) of a cell: the cell's value,
        the edge σ's value, or the affine interpolant of the vertex values of σ and the cell's
        mean at x_K."""
        a = d.values
        n = {"cell": self.nc, "edge": self.ne, "vertex": self.nv}[d.kind]
        if a.shape != (n,):
            raise InvalidDataError(f"{what}: {type(d).__name__} must have shape ({n},), got {a.shape}")
        if d.kind == "cell":
            at = {_CELL: a, _EDGE: self._cell_to_edges(a), _VERTEX: self._cell_to_vertices(a)}
        elif d.kind == "edge":
            at = {_EDGE: a, _CELL: self._edge_to_cells(a), _VERTEX: self._edge_to_vertices(a, boundary)}
        else:
            ed = self.mesh.edges
            at = {_VERTEX: a, _EDGE: 0.5 * (a[ed[:, 0]] + a[ed[:, 1]]), _CELL: self._vertex_to_cells(a)}
        out = np.full(self.m, np.nan)
        kind = self.site_kind[rows]
        for k in (_VERTEX, _EDGE, _CELL):
            sel = rows[kind == k]
            out[sel] = at[k][self.site_index[sel]]
        sel = rows[kind == _IN_CELL]
        if sel.size:
            cell, edge = self.site_index[sel], self.site_edge[sel]
            if d.kind == "cell":
                out[sel] = a[cell]
            elif d.kind == "edge":
                out[sel] = a[edge]
            else:
                w, ends = self.site_weights[sel], self.mesh.edges[edge]
                out[sel] = w[:, 0] * at[_CELL][cell] + w[:, 1] * a[ends[:, 0]] + w[:, 2] * a[ends[:, 1]]
        return out

    def entity(self, values: ArrayLike, what: str) -> _EntityData:
        """A plain array taken as per-cell, per-edge or per-vertex by its length."""
        a = np.asarray(values, dtype=np.float64)
        kinds = [k for k, n in (("cell", self.nc), ("edge", self.ne), ("vertex", self.nv)) if a.shape[:1] == (n,)]
        if len(kinds) != 1:
            raise InvalidDataError(
                f"{what}: an array of shape {a.shape} is "
                + ("ambiguous" if kinds else "not per cell, edge or vertex")
                + f" (the mesh has {self.nc} cells, {self.ne} edges, {self.nv} vertices); "
                "wrap it in gradvi.CellData, EdgeData or VertexData"
            )
        return {"cell": CellData, "edge": EdgeData, "vertex": VertexData}[kinds[0]](a)


_PLANAR_ONLY = (
    "{what}: per-entity arrays (CellData, EdgeData, VertexData) are taken on planar meshes only; "
    "on a 3D mesh give a number or a vectorised callable of (x, y, z)"
)


class _Points3:
    """The points where the scheme evaluates data on one 3D mesh (``_Mesh3.evaluation_points``:
    the scheme's own lists, as the solve computes them): each point once (``xy``, (m, 3)) and
    for each datum the rows where the solve reads it (``rows``, as in :class:`_Points`). Data
    are numbers or callables of (x, y, z) there; per-entity arrays are refused."""

    dim = 3

    def __init__(self, mesh: "Mesh3", scheme: str) -> None:
        p = mesh._m.evaluation_points(scheme)
        self.mesh = mesh
        self.nc = mesh.n_cells
        self.xy = np.ascontiguousarray(p["points"])
        self.m = len(self.xy)
        self.coords = [self.xy[:, i].copy() for i in range(3)]
        self.rows: Dict[str, np.ndarray] = dict(p["rows"])

    def at(self, rows: np.ndarray) -> List[np.ndarray]:
        """The coordinate arrays (x, y, z) of the points ``rows``."""
        return [c[rows] for c in self.coords]

    def faces(self) -> "_Faces":
        """The boundary faces, for the boundary partition."""
        m, bf = self.mesh, self.mesh.boundary_faces
        return _Faces(m.n_faces, bf, m.face_centroids[bf], m.face_tags[bf], "face", 3)

    def entity(self, values: ArrayLike, what: str) -> _EntityData:
        raise InvalidDataError(_PLANAR_ONLY.format(what=what))

    def spread(self, d: _EntityData, what: str, rows: np.ndarray, boundary: bool = False) -> np.ndarray:
        raise InvalidDataError(_PLANAR_ONLY.format(what=what))


def _call(f: Callable[..., Any], what: str, *args: Any) -> Any:
    """Calls a user callable; an exception it raises propagates, with a note naming the datum."""
    try:
        return f(*args)
    except Exception as e:
        if hasattr(e, "add_note"):
            e.add_note(f"(raised while gradvi evaluated the datum {what!r} of the problem)")
        raise


def _scalar_result(r: Any, m: int, what: str) -> np.ndarray:
    a = np.asarray(r, dtype=np.float64)
    try:
        return np.ascontiguousarray(np.broadcast_to(a, (m,)), dtype=np.float64)
    except ValueError:
        raise InvalidDataError(f"{what}: the callable returned shape {a.shape}, expected ({m},) or a scalar") from None


def _point_adapter(f: Callable[..., Any], what: str) -> Callable[..., float]:
    """f(x, y[, z]) on one point (for points outside the table: the nested warm start)."""

    def g(*c: float) -> float:
        return float(_scalar_result(f(*[np.array([v]) for v in c]), 1, what)[0])

    return g


def _const_adapter(c: float) -> Callable[..., float]:
    return lambda *_: c


#: The coordinate names of a callable's arguments, by dimension.
_COORDS = {2: ("x", "y"), 3: ("x", "y", "z")}


def _check_arity(f: Any, what: str, dim: int, extra: Tuple[str, ...] = ()) -> None:
    """Raises InvalidDataError if the callable ``f`` cannot be called with the ``dim``
    coordinates (and ``extra`` arguments) of a ``dim``-D mesh; callables whose signature
    Python cannot tell (some built-ins) are not checked here."""
    import inspect

    try:
        sig = inspect.signature(f)
    except (TypeError, ValueError):
        return
    args = _COORDS[dim] + extra
    try:
        sig.bind(*args)
    except TypeError:
        raise InvalidDataError(
            f"{what}: the callable has the signature {sig}, but on a {dim}D mesh it is called as "
            f"{what}({', '.join(args)})"
        ) from None


def _tensor_result(r: Any, m: int, what: str, dim: int = 2) -> np.ndarray:
    """(m, d, d) from a scalar, (m,), (d, d), (m, d, d), (d, d, m) or nested lists of those,
    d = ``dim``."""
    d = dim
    if isinstance(r, (list, tuple)):
        try:
            r = [[np.broadcast_to(np.asarray(e, dtype=np.float64), (m,)) for e in row] for row in r]
        except ValueError:
            raise InvalidDataError(f"{what}: the entries of the returned tensor do not broadcast to ({m},)") from None
        a = np.asarray(r, dtype=np.float64)  # (d, d, m)
    else:
        a = np.asarray(r, dtype=np.float64)
    if a.ndim == 0 or a.shape == (m,):
        out = np.zeros((m, d, d))
        for i in range(d):
            out[:, i, i] = a
        return out
    if a.shape == (d, d):
        return np.ascontiguousarray(np.broadcast_to(a, (m, d, d)))
    if a.shape == (m, d, d):
        return np.ascontiguousarray(a)
    if a.shape == (d, d, m):
        return np.ascontiguousarray(np.moveaxis(a, 2, 0))
    other = 5 - d
    if a.shape in ((other, other), (m, other, other), (other, other, m)):
        raise InvalidDataError(
            f"{what}: a {other}×{other} tensor on a {d}D mesh (shape {a.shape}); give a {d}×{d} tensor"
        )
    raise InvalidDataError(
        f"{what}: expected a scalar, (n,), ({d}, {d}), (n, {d}, {d}) or ({d}, {d}, n) values, got shape {a.shape}"
    )


class Problem:
    """A problem −div(A∇u) = f with boundary conditions and, optionally, a barrier.

    Three ways to get one:

    - :meth:`builtin`: the problems of the command line (``test1``, ``test2``, ``test3`` with
      its parameter ``C``, ``fvca5-1.1``), the very same Rust code;
    - :meth:`from_file`: a TOML problem file (``problems/*.toml``), with parameter overrides;
    - the constructor, from Python data. Every datum is a number, a **vectorised** callable
      ``f(x, y)`` taking numpy arrays, or per-entity values (:class:`CellData`,
      :class:`EdgeData`, :class:`VertexData`; a plain array is taken by its length). At
      :func:`gradvi.solve`, each callable is called **once**, on the arrays of the points where
      the scheme evaluates that datum, as the Rust library lists them
      (``gradvi::scheme::points``): A and the exact solution at the cell centroids x_K; f
      where the scheme's load reads it (HMM x_K, P1 the vertices, CR the centroids of the
      sub-triangles co(σ ∪ {x_K})) and at x_K; g_N at the boundary edge midpoints; u_D and a
      Signorini barrier at the trace unknowns (HMM and CR the boundary edge midpoints, P1 the
      boundary vertices); an obstacle barrier at the obstacle unknowns (HMM x_K, P1 the
      vertices, CR the edge midpoints) and the trace unknowns. The Rust assembly then reads
      the values from that table, by point. (Only the coarse meshes of ``warm_start="nested"`` ask for other points:
      callables are then called point by point there, array data cannot be, and the warm start
      is skipped with the reason in :attr:`Solution.warm_start`.)

    **On a 3D mesh** (:class:`Mesh3`) the same problem object takes callables of
    ``(x, y, z)`` (the dimension comes from the mesh it is solved on): A is a number, a 3×3
    matrix or a callable returning (n,), (n, 3, 3) or (3, 3, n) values; ``exact_grad`` returns
    three components; ``boundary`` selects boundary *faces* (tags of gmsh physical surfaces,
    predicates ``sel(x, y, z)`` on the face centroids, masks per face, or a callable
    ``boundary(x, y, z, tag)``); a Signorini barrier acts on the boundary faces of Γ3. The
    points are the scheme's own (HMM: A, f and ū at x_K, u_D, g_N and a Signorini barrier at
    the boundary face centroids x_σ, an obstacle at x_K). Per-entity arrays are planar only.
    Problem files (``problems/ex9-3d.toml``, ...) and built-in problems are solved on a 3D mesh
    when they compile as 3D problems, with the very code of ``gradvi solve``; one that does not
    (a ``z`` on a planar mesh, a 2×2 tensor on a 3D one) raises
    :class:`gradvi.ProblemFileError` with its place in the file. A callable with the wrong number of arguments, a 2×2
    tensor or a 2-component gradient on a 3D mesh (or the converse) raises
    :class:`gradvi.InvalidDataError` naming the datum.

    Example (the paper's Test 3, an obstacle problem u ≥ ψ with f = C)::

        pb = gradvi.Problem(
            source=-20.0,
            obstacle=lambda x, y: -np.minimum.reduce([x, 1 - x, y, 1 - y]),
            side="lower",
        )

    Args:
        source: f.
        diffusion: A: a number (A = a I), a 2×2 matrix, a callable returning (n,), (n, 2, 2)
            or (2, 2, n) values (or nested lists ``[[a11, a12], [a21, a22]]``), or
            :class:`CellData` of shape (n_cells,) or (n_cells, 2, 2). Evaluated at x_K.
        dirichlet: u_D on Γ1.
        neumann: g_N = A∇u·n (outward flux) on Γ2, evaluated at x_σ.
        boundary: the partition of ∂Ω into Γ1 (Dirichlet), Γ2 (Neumann), Γ3 (Signorini).
            ``None``: all Dirichlet. A dict ``{"dirichlet": sel, "neumann": sel,
            "signorini": sel}`` where each ``sel`` is a tag or list of tags (gmsh physical
            lines), a vectorised predicate ``sel(x, y)`` on the boundary edge midpoints, a
            boolean mask per edge, or ``"rest"`` (the edges the others leave; at most one);
            every boundary edge must be selected exactly once. Or a callable
            ``boundary(x, y, tag)`` returning per-edge kinds (strings or 0/1/2), or an array of
            kinds per edge.
        obstacle: the barrier g (``side="upper"``, u ≤ g) or ψ (``side="lower"``, u ≥ ψ) in Ω.
        signorini: the barrier a on Γ3 (``side="upper"``: u ≤ a, A∇u·n ≤ 0; ``"lower"``:
            u ≥ a, A∇u·n ≥ 0).
        side: ``"upper"`` or ``"lower"``, required with a barrier.
        exact: the exact solution ū(x, y) (a callable), for errors and output.
        exact_grad: ∇ū as a callable returning ``(gx, gy)`` (or an (n, 2) / (2, n) array).
        name: used in outputs.
    """

    __slots__ = ("_handle", "_spec", "_name")

    def __init__(
        self,
        *,
        source: Scalar = 0.0,
        diffusion: Any = None,
        dirichlet: Scalar = 0.0,
        neumann: Scalar = 0.0,
        boundary: Any = None,
        obstacle: Optional[Scalar] = None,
        signorini: Optional[Scalar] = None,
        side: Optional[str] = None,
        exact: Optional[Callable[[np.ndarray, np.ndarray], ArrayLike]] = None,
        exact_grad: Optional[Callable[[np.ndarray, np.ndarray], Any]] = None,
        name: str = "problem",
    ) -> None:
        if obstacle is not None and signorini is not None:
            raise InvalidDataError("give either obstacle= or signorini=, not both")
        barrier = obstacle if obstacle is not None else signorini
        if barrier is not None and side not in ("upper", "lower"):
            raise InvalidDataError(
                f'a barrier needs side="upper" (u <= barrier) or side="lower" (u >= barrier), got side={side!r}'
            )
        if barrier is None and side is not None:
            raise InvalidDataError("side= is given but there is no obstacle= or signorini= barrier")
        if signorini is not None and boundary is None:
            raise InvalidDataError("a Signorini barrier needs boundary= with a 'signorini' part (Γ3)")
        if exact_grad is not None and exact is None:
            raise InvalidDataError("exact_grad= is given without exact=")
        for key, v in (("exact", exact), ("exact_grad", exact_grad)):
            if v is not None and not callable(v):
                raise InvalidDataError(f"{key}= must be a vectorised callable of (x, y) or (x, y, z)")
        self._handle: Any = None
        self._name = str(name)
        self._spec: Dict[str, Any] = dict(
            source=source,
            diffusion=diffusion,
            dirichlet=dirichlet,
            neumann=neumann,
            boundary=boundary,
            constraint=None if barrier is None else ("obstacle" if obstacle is not None else "signorini"),
            barrier=barrier,
            side=side,
            exact=exact,
            exact_grad=exact_grad,
        )

    @classmethod
    def _wrap(cls, handle: Any) -> "Problem":
        p = cls.__new__(cls)
        p._handle = handle
        p._spec = {}
        p._name = handle.name
        return p

    @classmethod
    def builtin(cls, name: str, **params: float) -> "Problem":
        """A built-in problem, as on the command line (``gradvi solve --problem NAME --param K=V``):
        ``"test1"``, ``"test2"``, ``"test3"`` (parameter ``C``, default −5), ``"fvca5-1.1"``."""
        return cls._wrap(_gradvi._Problem.builtin(str(name), [(str(k), float(v)) for k, v in params.items()]))

    @classmethod
    def from_file(cls, path: Union[str, "os.PathLike[str]"], **params: float) -> "Problem":
        """A TOML problem file (see ``problems/README.md`` in the repository), with parameter
        overrides, e.g. ``Problem.from_file("problems/test3.toml", C=-20)``. Raises
        :class:`gradvi.ProblemFileError` with the file, line, column and key at fault. The file
        is checked against the mesh at :func:`gradvi.solve`, planar or 3D (``Mesh3``), e.g.
        ``gradvi.solve(gradvi.Mesh3.generate("cubes", 2), Problem.from_file("problems/poisson-3d.toml"))``;
        :meth:`mesh` builds the mesh of its ``[mesh]`` section."""
        return cls._wrap(_gradvi._Problem.from_file(os.fspath(path), [(str(k), float(v)) for k, v in params.items()]))

    # ---------------------------------------------------------------- description

    @property
    def name(self) -> str:
        """The problem's name."""
        return self._name

    @property
    def origin(self) -> str:
        """``"builtin"``, ``"file"`` or ``"python"``."""
        return "python" if self._handle is None else str(self._handle.source)

    @property
    def parameters(self) -> Dict[str, float]:
        """Parameters with their values (files: all of them; built-ins: those given)."""
        return {} if self._handle is None else dict(self._handle.parameters)

    @property
    def description(self) -> Optional[str]:
        """A problem file's ``description``."""
        return None if self._handle is None else self._handle.description

    @property
    def scheme(self) -> Optional[str]:
        """The scheme a problem file asks for, if any (used by :func:`gradvi.solve` by default)."""
        return None if self._handle is None else self._handle.scheme

    @property
    def constraint(self) -> Optional[Tuple[str, str]]:
        """``(kind, side)``: kind ``"obstacle"`` or ``"signorini"``, side ``"upper"`` or
        ``"lower"``; None without a barrier."""
        if self._handle is None:
            c = self._spec["constraint"]
            return None if c is None else (c, self._spec["side"])
        c = self._handle.constraint
        return None if c is None else tuple(c)  # type: ignore[return-value]

    @property
    def has_exact(self) -> bool:
        """Whether the exact solution is known (errors are then computed)."""
        return self._spec.get("exact") is not None if self._handle is None else bool(self._handle.has_exact)

    def mesh(self, warped_faces: str = "fan") -> Optional[Union[Mesh, Mesh3]]:
        """The mesh of a problem file's ``[mesh]`` section (read or generated), or None: a
        :class:`Mesh3` for a generated 3D family, or for a mesh file with 3D cells (a gmsh
        ``.msh`` with 3D elements, ``.vtu``, HArDCore RF) when the file is a 3D problem; else
        a planar :class:`Mesh`. The choice is ``gradvi solve``'s. ``warped_faces``: the faces
        of a 3D mesh that are not planar kept whole (``"fan"``, the default) or split
        (``"split"``), as ``gradvi solve --warped-faces`` and :meth:`Mesh3.read` say."""
        if self._handle is None:
            return None
        h = self._handle.build_mesh(str(warped_faces))
        if h is None:
            return None
        return Mesh3._wrap(h) if isinstance(h, _gradvi._Mesh3) else Mesh._wrap(h)

    def __repr__(self) -> str:
        c = self.constraint
        what = "no barrier" if c is None else f"{c[0]} barrier, {c[1]}"
        return f"<gradvi.Problem {self.name!r} ({self.origin}, {what})>"

    # ---------------------------------------------------------------- tabulation

    def _for_mesh(self, mesh: Union[Mesh, "Mesh3"], scheme: str) -> Tuple[Any, float]:
        """The Rust handle for a solve on ``mesh`` (planar or 3D) with ``scheme``, and the
        seconds spent evaluating Python data."""
        if self._handle is not None:
            return self._handle, 0.0
        import time

        t0 = time.perf_counter()
        pts = _points_of(mesh, scheme)
        data = self.tabulate(mesh, scheme, _points=pts)
        make = _gradvi._Problem.tabulated3 if pts.dim == 3 else _gradvi._Problem.tabulated
        h = make(self._name, mesh._m, pts.xy, data)
        return h, time.perf_counter() - t0

    def tabulate(
        self, mesh: Union[Mesh, "Mesh3"], scheme: str = "hmm", *, _points: Optional[Union[_Points, _Points3]] = None
    ) -> Dict[str, Any]:
        """The data of a Python-built problem on the evaluation points of ``scheme`` on ``mesh``
        (what :func:`gradvi.solve` hands to the Rust assembly): a dict with ``points`` (m, d),
        d = 2 or 3 the dimension of the mesh, the points the Rust library lists for ``scheme``
        (``gradvi::scheme::points`` in 2D, the scheme's own lists in 3D), and one array per
        datum over those rows, with ``<datum>_rows``: the rows where the solve reads it (NaN on
        the others; a constant has every row). Each callable is called once here, on its
        datum's points, with the d coordinate arrays (x, y) or (x, y, z); a callable that cannot
        take them raises :class:`gradvi.InvalidDataError`."""
        if self._handle is not None:
            raise InvalidDataError("only problems built in Python are tabulated")
        s = self._spec
        pts = _points or _points_of(mesh, scheme)
        m = pts.m
        out: Dict[str, Any] = {}

        def scalar(key: str, v: Any, at: str, boundary: bool = False) -> None:
            """Datum ``key`` on the rows ``pts.rows[at]`` (NaN on the others); ``boundary``:
            per-edge values reach a vertex through the boundary edges only."""
            what = {"barrier": f"{s['constraint']} barrier", "exact_u": "exact"}.get(key, key)
            rows = pts.rows[at]
            if callable(v):
                _check_arity(v, what, pts.dim)
                vals = np.full(m, np.nan)
                vals[rows] = _scalar_result(_call(v, what, *pts.at(rows)), rows.size, what)
                out[key] = vals
                out[key + "_rows"] = rows
                out[key + "_fallback"] = _point_adapter(v, what)
            elif isinstance(v, (_EntityData, np.ndarray, list, tuple)):
                d = v if isinstance(v, _EntityData) else pts.entity(v, what)
                out[key] = pts.spread(d, what, rows, boundary)
                out[key + "_rows"] = rows
            else:
                try:
                    c = float(v)
                except (TypeError, ValueError):
                    raise InvalidDataError(f"{what}: expected a number, a callable or an array, got {v!r}") from None
                out[key] = np.full(m, c)
                out[key + "_fallback"] = _const_adapter(c)

        src = s["source"]
        if isinstance(src, CellData) or (
            isinstance(src, (np.ndarray, list, tuple)) and isinstance(pts.entity(src, "source"), CellData)
        ):
            out["source_per_cell"] = True
        scalar("source", src, "source")
        scalar("dirichlet", s["dirichlet"], "trace", boundary=True)
        scalar("neumann", s["neumann"], "boundary", boundary=True)
        if s["constraint"] is not None:
            signorini = s["constraint"] == "signorini"
            scalar("barrier", s["barrier"], "trace" if signorini else "obstacle", boundary=signorini)
            out["constraint"] = s["constraint"]
            out["side"] = s["side"]
        out.update(self._diffusion(pts))
        out.update(self._boundary(pts))
        if s["exact"] is not None:
            scalar("exact_u", s["exact"], "exact")
            g = s["exact_grad"]
            out["exact_grad"] = np.full((m, pts.dim), np.nan)
            if g is not None:
                _check_arity(g, "exact_grad", pts.dim)
                rows = pts.rows["exact"]
                out["exact_grad"][rows] = _grad_result(_call(g, "exact_grad", *pts.at(rows)), rows.size, pts.dim)
                out["exact_grad_rows"] = rows

                def gfb(*c: float) -> Tuple[float, ...]:
                    r = _grad_result(g(*[np.array([v]) for v in c]), 1, pts.dim)
                    return tuple(float(v) for v in r[0])

                out["exact_grad_fallback"] = gfb
        out["points"] = pts.xy
        return out

    def _diffusion(self, pts: Union[_Points, _Points3]) -> Dict[str, Any]:
        a = self._spec["diffusion"]
        m = pts.m
        if a is None:
            return {}
        d = pts.dim
        if callable(a):
            _check_arity(a, "diffusion", d)

            def fb(*c: float) -> Tuple[float, ...]:
                t = _tensor_result(a(*[np.array([v]) for v in c]), 1, "diffusion", d)[0]
                return tuple(float(v) for v in t.reshape(-1))

            rows = pts.rows["diffusion"]  # A_K = A(x_K)
            out = np.full((m, d, d), np.nan)
            out[rows] = _tensor_result(_call(a, "diffusion", *pts.at(rows)), rows.size, "diffusion", d)
            return {"diffusion": out, "diffusion_rows": rows, "diffusion_fallback": fb}
        if isinstance(a, CellData) or (isinstance(a, np.ndarray) and a.shape[:1] == (pts.nc,) and a.shape != (d, d)):
            if d != 2:
                raise InvalidDataError(_PLANAR_ONLY.format(what="diffusion"))
            v = a.values if isinstance(a, CellData) else np.asarray(a, dtype=np.float64)
            if v.shape not in ((pts.nc,), (pts.nc, 2, 2)):
                raise InvalidDataError(f"diffusion: per-cell values must have shape ({pts.nc},) or ({pts.nc}, 2, 2), got {v.shape}")
            rows = pts.rows["diffusion"]
            if (pts.site_kind[rows] != _CELL).any():
                raise InvalidDataError("diffusion: the scheme reads A off the cell centroids; give it as a callable")
            out = np.full((m, 2, 2), np.nan)
            out[rows] = _tensor_result(v, pts.nc, "diffusion")[pts.site_index[rows]]
            return {"diffusion": out, "diffusion_rows": rows}
        t = _tensor_result(a, m, "diffusion", d)
        c = tuple(float(v) for v in (t[0] if m else np.eye(d)).reshape(-1))
        return {"diffusion": t, "diffusion_fallback": lambda *_: c}

    def _boundary(self, pts: Union[_Points, "_Points3"]) -> Dict[str, Any]:
        return _boundary_data(self._spec["boundary"], pts.faces())


def _points_of(mesh: Union[Mesh, "Mesh3"], scheme: str) -> Union[_Points, _Points3]:
    """The evaluation points of ``scheme`` on a planar or 3D mesh."""
    if isinstance(mesh, Mesh3):
        return _Points3(mesh, scheme)
    if isinstance(mesh, Mesh):
        return _Points(mesh, scheme)
    raise InvalidDataError(f"expected a gradvi.Mesh or gradvi.Mesh3, got {type(mesh).__name__}")


class _Faces(NamedTuple):
    """The boundary of a mesh as the boundary partition sees it: faces (edges in 2D)."""

    #: Faces (edges) of the mesh.
    n: int
    #: The boundary faces.
    be: np.ndarray
    #: Their centres x_σ, (nb, dim).
    mid: np.ndarray
    #: Their tags (gmsh physical lines / surfaces).
    tags: np.ndarray
    #: "edge" or "face".
    noun: str
    dim: int

    def coords(self) -> List[np.ndarray]:
        """The coordinate arrays of the centres (x, y[, z])."""
        return [self.mid[:, i].copy() for i in range(self.dim)]

    def at(self, i: int) -> str:
        """``"face f at (x, y, z) (tag t)"`` for the i-th boundary face."""
        c = ", ".join(str(v) for v in self.mid[i])
        return f"{self.noun} {self.be[i]} at ({c}) (tag {self.tags[i]})"


def _boundary_data(b: Any, faces: _Faces) -> Dict[str, Any]:
    """The ``boundary`` codes per face (and a point-wise fallback) of the partition ``b``."""
    codes = np.zeros(faces.n, dtype=np.uint8)
    if b is None:
        return {"boundary": codes}
    be = faces.be
    if isinstance(b, Mapping):
        return _boundary_rules(b, faces)
    if callable(b):
        _check_arity(b, "boundary", faces.dim, ("tag",))
        kinds = _kind_codes(_call(b, "boundary", *faces.coords(), faces.tags.copy()), be.size)
        codes[be] = kinds

        def fb(*c: Any) -> int:
            *xs, tag = c
            pts = [np.array([v]) for v in xs]
            return int(_kind_codes(b(*pts, np.array([tag], dtype=np.int32)), 1)[0])

        return {"boundary": codes, "boundary_fallback": fb}
    v = b.values if isinstance(b, EdgeData) else np.asarray(b)
    if v.shape != (faces.n,):
        raise InvalidDataError(
            f"boundary: expected a dict, a callable, or one kind per {faces.noun} ({faces.n}), got shape {v.shape}"
        )
    codes[be] = _kind_codes(v[be], be.size)
    return {"boundary": codes}


def _boundary_rules(rules: Mapping[str, Any], faces: _Faces) -> Dict[str, Any]:
    be, tags, noun = faces.be, faces.tags, faces.noun
    unknown = set(rules) - set(_KINDS)
    if unknown:
        raise InvalidDataError(f"boundary: unknown part(s) {sorted(unknown)} (expected dirichlet, neumann, signorini)")
    count = np.zeros(be.size, dtype=np.int64)
    codes_b = np.zeros(be.size, dtype=np.uint8)
    rest = [k for k, sel in rules.items() if isinstance(sel, str) and sel == "rest"]
    if len(rest) > 1:
        raise InvalidDataError(f"boundary: only one part may be 'rest', got {rest}")
    pointwise = True
    masks: Dict[str, Any] = {}
    for kind, sel in rules.items():
        if isinstance(sel, str):
            if sel != "rest":
                raise InvalidDataError(f"boundary[{kind!r}]: the only string selector is 'rest', got {sel!r}")
            continue
        mask = _select(kind, sel, faces)
        if not (callable(sel) or _is_tags(sel)):
            pointwise = False
        masks[kind] = sel
        count += mask
        codes_b[mask] = _KINDS[kind]
    present = set(int(t) for t in np.unique(tags))
    for kind, sel in masks.items():
        if _is_tags(sel):
            missing = sorted(set(_tag_list(sel)) - present)
            if missing:
                raise InvalidDataError(
                    f"boundary[{kind!r}]: tag(s) {missing} are on no boundary {noun} of the mesh "
                    f"(its boundary tags: {sorted(present)})"
                )
    two = np.nonzero(count > 1)[0]
    if two.size:
        raise InvalidDataError(f"boundary: {faces.at(two[0])} is selected by two parts")
    none = np.nonzero(count == 0)[0]
    if none.size:
        if rest:
            codes_b[none] = _KINDS[rest[0]]
        else:
            raise InvalidDataError(
                f"boundary: {none.size} boundary {noun}(s) are selected by no part, e.g. {faces.at(none[0])}; "
                "add them to a part or mark one part 'rest'"
            )
    codes = np.zeros(faces.n, dtype=np.uint8)
    codes[be] = codes_b
    out: Dict[str, Any] = {"boundary": codes}
    if pointwise:
        def fb(*c: Any) -> int:
            *xs, tag = c
            for kind, sel in masks.items():
                hit = (tag in _tag_list(sel)) if _is_tags(sel) else bool(
                    np.broadcast_to(np.asarray(sel(*[np.array([v]) for v in xs])), (1,))[0]
                )
                if hit:
                    return _KINDS[kind]
            return _KINDS[rest[0]] if rest else 0

        out["boundary_fallback"] = fb
    return out


def _select(kind: str, sel: Any, faces: _Faces) -> np.ndarray:
    be = faces.be
    if _is_tags(sel):
        return np.isin(faces.tags, _tag_list(sel))
    if callable(sel):
        _check_arity(sel, f"boundary[{kind!r}]", faces.dim)
        r = np.asarray(_call(sel, f"boundary[{kind!r}]", *faces.coords()))
        try:
            return np.broadcast_to(r, (be.size,)).astype(bool)
        except ValueError:
            raise InvalidDataError(f"boundary[{kind!r}]: the predicate returned shape {r.shape}, expected ({be.size},)") from None
    v = sel.values if isinstance(sel, EdgeData) else np.asarray(sel)
    if v.shape != (faces.n,):
        args = ", ".join(_COORDS[faces.dim])
        raise InvalidDataError(
            f"boundary[{kind!r}]: expected tags, a predicate ({args}) -> bool, 'rest' or a mask per {faces.noun} ({faces.n}), got {sel!r}"
        )
    return v.astype(bool)[be]


def _is_tags(sel: Any) -> bool:
    if isinstance(sel, (bool, np.bool_)):
        return False
    if isinstance(sel, (int, np.integer)):
        return True
    return isinstance(sel, (list, tuple, set)) and all(isinstance(t, (int, np.integer)) and not isinstance(t, bool) for t in sel)


def _tag_list(sel: Any) -> list:
    return [int(sel)] if isinstance(sel, (int, np.integer)) else [int(t) for t in sel]


def _kind_codes(r: Any, n: int) -> np.ndarray:
    a = np.asarray(r)
    try:
        a = np.broadcast_to(a, (n,))
    except ValueError:
        raise InvalidDataError(f"boundary: expected {n} kinds, got shape {a.shape}") from None
    if a.dtype.kind in "USO":
        try:
            return np.array([_KINDS[str(k).lower()] for k in a], dtype=np.uint8)
        except KeyError as e:
            raise InvalidDataError(f"boundary: unknown kind {e.args[0]!r} (expected dirichlet, neumann or signorini)") from None
    ai = a.astype(np.int64)
    if ai.size and (ai.min() < 0 or ai.max() > 2):
        raise InvalidDataError("boundary: kind codes must be 0 (dirichlet), 1 (neumann) or 2 (signorini)")
    return ai.astype(np.uint8)


def _grad_result(r: Any, m: int, dim: int = 2) -> np.ndarray:
    """(m, dim) from ``dim`` component arrays (or scalars), an (m, dim) or a (dim, m) array."""
    if isinstance(r, (list, tuple)) and len(r) == dim:
        try:
            return np.ascontiguousarray(np.column_stack([np.broadcast_to(np.asarray(c, dtype=np.float64), (m,)) for c in r]))
        except ValueError:
            pass
    a = np.asarray(r, dtype=np.float64)
    if a.shape == (m, dim):
        return np.ascontiguousarray(a)
    if a.shape == (dim, m):
        return np.ascontiguousarray(a.T)
    names = ", ".join("g" + c for c in _COORDS[dim])
    got = f"{len(r)} components" if isinstance(r, (list, tuple)) else f"shape {a.shape}"
    raise InvalidDataError(
        f"exact_grad: on a {dim}D mesh expected ({names}) arrays of shape ({m},) or an ({m}, {dim}) array, got {got}"
    )
