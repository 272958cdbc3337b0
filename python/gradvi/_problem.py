"""Problems: :class:`Problem` (built-in, from a problem file, or built from Python data)."""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _gradvi
from ._gradvi import InvalidDataError
from ._mesh import Mesh

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


def _point_adapter(f: Callable[..., Any], what: str) -> Callable[[float, float], float]:
    """f(x, y) on one point (for points outside the table: the nested warm start)."""

    def g(x: float, y: float) -> float:
        return float(_scalar_result(f(np.array([x]), np.array([y])), 1, what)[0])

    return g


def _const_adapter(c: float) -> Callable[[float, float], float]:
    return lambda x, y: c


def _tensor_result(r: Any, m: int, what: str) -> np.ndarray:
    """(m, 2, 2) from a scalar, (m,), (2, 2), (m, 2, 2), (2, 2, m) or nested lists of those."""
    if isinstance(r, (list, tuple)):
        try:
            r = [[np.broadcast_to(np.asarray(e, dtype=np.float64), (m,)) for e in row] for row in r]
        except ValueError:
            raise InvalidDataError(f"{what}: the entries of the returned tensor do not broadcast to ({m},)") from None
        a = np.asarray(r, dtype=np.float64)  # (2, 2, m)
    else:
        a = np.asarray(r, dtype=np.float64)
    if a.ndim == 0 or a.shape == (m,):
        out = np.zeros((m, 2, 2))
        out[:, 0, 0] = a
        out[:, 1, 1] = a
        return out
    if a.shape == (2, 2):
        return np.ascontiguousarray(np.broadcast_to(a, (m, 2, 2)))
    if a.shape == (m, 2, 2):
        return np.ascontiguousarray(a)
    if a.shape == (2, 2, m):
        return np.ascontiguousarray(np.moveaxis(a, 2, 0))
    raise InvalidDataError(f"{what}: expected a scalar, (n,), (2, 2), (n, 2, 2) or (2, 2, n) values, got shape {a.shape}")


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
                raise InvalidDataError(f"{key}= must be a vectorised callable of (x, y)")
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
        is checked against the mesh at :func:`gradvi.solve`."""
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

    def mesh(self) -> Optional[Mesh]:
        """The mesh of a problem file's ``[mesh]`` section (read or generated), or None."""
        if self._handle is None:
            return None
        h = self._handle.build_mesh()
        return None if h is None else Mesh._wrap(h)

    def __repr__(self) -> str:
        c = self.constraint
        what = "no barrier" if c is None else f"{c[0]} barrier, {c[1]}"
        return f"<gradvi.Problem {self.name!r} ({self.origin}, {what})>"

    # ---------------------------------------------------------------- tabulation

    def _for_mesh(self, mesh: Mesh, scheme: str) -> Tuple[Any, float]:
        """The Rust handle for a solve on ``mesh`` with ``scheme``, and the seconds spent
        evaluating Python data."""
        if self._handle is not None:
            return self._handle, 0.0
        import time

        t0 = time.perf_counter()
        pts = _Points(mesh, scheme)
        data = self.tabulate(mesh, scheme, _points=pts)
        h = _gradvi._Problem.tabulated(self._name, mesh._m, pts.xy, data)
        return h, time.perf_counter() - t0

    def tabulate(self, mesh: Mesh, scheme: str = "hmm", *, _points: Optional[_Points] = None) -> Dict[str, Any]:
        """The data of a Python-built problem on the evaluation points of ``scheme`` on ``mesh``
        (what :func:`gradvi.solve` hands to the Rust assembly): a dict with ``points`` (m, 2),
        the points the Rust library lists for ``scheme`` (``gradvi::scheme::points``), and one
        array per datum over those rows, with ``<datum>_rows``: the rows where the solve reads
        it (NaN on the others; a constant has every row). Each callable is called once here, on
        its datum's points."""
        if self._handle is not None:
            raise InvalidDataError("only problems built in Python are tabulated")
        s = self._spec
        pts = _points or _Points(mesh, scheme)
        m = pts.m
        out: Dict[str, Any] = {}

        def scalar(key: str, v: Any, at: str, boundary: bool = False) -> None:
            """Datum ``key`` on the rows ``pts.rows[at]`` (NaN on the others); ``boundary``:
            per-edge values reach a vertex through the boundary edges only."""
            what = {"barrier": f"{s['constraint']} barrier", "exact_u": "exact"}.get(key, key)
            rows = pts.rows[at]
            if callable(v):
                vals = np.full(m, np.nan)
                vals[rows] = _scalar_result(_call(v, what, pts.x[rows], pts.y[rows]), rows.size, what)
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
            out["exact_grad"] = np.full((m, 2), np.nan)
            if g is not None:
                rows = pts.rows["exact"]
                out["exact_grad"][rows] = _grad_result(_call(g, "exact_grad", pts.x[rows], pts.y[rows]), rows.size)
                out["exact_grad_rows"] = rows

                def gfb(x: float, y: float) -> Tuple[float, float]:
                    r = _grad_result(g(np.array([x]), np.array([y])), 1)
                    return float(r[0, 0]), float(r[0, 1])

                out["exact_grad_fallback"] = gfb
        out["points"] = pts.xy
        return out

    def _diffusion(self, pts: _Points) -> Dict[str, Any]:
        a = self._spec["diffusion"]
        m = pts.m
        if a is None:
            return {}
        if callable(a):
            def fb(x: float, y: float) -> Tuple[float, float, float, float]:
                t = _tensor_result(a(np.array([x]), np.array([y])), 1, "diffusion")[0]
                return float(t[0, 0]), float(t[0, 1]), float(t[1, 0]), float(t[1, 1])

            rows = pts.rows["diffusion"]  # A_K = A(x_K)
            out = np.full((m, 2, 2), np.nan)
            out[rows] = _tensor_result(_call(a, "diffusion", pts.x[rows], pts.y[rows]), rows.size, "diffusion")
            return {"diffusion": out, "diffusion_rows": rows, "diffusion_fallback": fb}
        if isinstance(a, CellData) or (isinstance(a, np.ndarray) and a.shape[:1] == (pts.nc,) and a.shape != (2, 2)):
            v = a.values if isinstance(a, CellData) else np.asarray(a, dtype=np.float64)
            if v.shape not in ((pts.nc,), (pts.nc, 2, 2)):
                raise InvalidDataError(f"diffusion: per-cell values must have shape ({pts.nc},) or ({pts.nc}, 2, 2), got {v.shape}")
            rows = pts.rows["diffusion"]
            if (pts.site_kind[rows] != _CELL).any():
                raise InvalidDataError("diffusion: the scheme reads A off the cell centroids; give it as a callable")
            out = np.full((m, 2, 2), np.nan)
            out[rows] = _tensor_result(v, pts.nc, "diffusion")[pts.site_index[rows]]
            return {"diffusion": out, "diffusion_rows": rows}
        t = _tensor_result(a, m, "diffusion")
        c = t[0].copy() if m else np.eye(2)
        return {
            "diffusion": t,
            "diffusion_fallback": lambda x, y: (float(c[0, 0]), float(c[0, 1]), float(c[1, 0]), float(c[1, 1])),
        }

    def _boundary(self, pts: _Points) -> Dict[str, Any]:
        b = self._spec["boundary"]
        mesh = pts.mesh
        ne = pts.ne
        be = mesh.boundary_edges
        codes = np.zeros(ne, dtype=np.uint8)
        if b is None:
            return {"boundary": codes}
        mid = mesh.edge_midpoints[be]
        tags = mesh.edge_tags[be]
        if isinstance(b, Mapping):
            return self._boundary_rules(b, pts, be, mid, tags)
        if callable(b):
            kinds = _kind_codes(_call(b, "boundary", mid[:, 0].copy(), mid[:, 1].copy(), tags.copy()), be.size)
            codes[be] = kinds

            def fb(x: float, y: float, tag: int) -> int:
                return int(_kind_codes(b(np.array([x]), np.array([y]), np.array([tag], dtype=np.int32)), 1)[0])

            return {"boundary": codes, "boundary_fallback": fb}
        v = b.values if isinstance(b, EdgeData) else np.asarray(b)
        if v.shape != (ne,):
            raise InvalidDataError(f"boundary: expected a dict, a callable, or one kind per edge ({ne}), got shape {v.shape}")
        codes[be] = _kind_codes(v[be], be.size)
        return {"boundary": codes}

    def _boundary_rules(self, rules: Mapping[str, Any], pts: _Points, be: np.ndarray, mid: np.ndarray, tags: np.ndarray) -> Dict[str, Any]:
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
            mask = self._select(kind, sel, pts, be, mid, tags)
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
                        f"boundary[{kind!r}]: tag(s) {missing} are on no boundary edge of the mesh "
                        f"(its boundary tags: {sorted(present)})"
                    )
        two = np.nonzero(count > 1)[0]
        if two.size:
            e = be[two[0]]
            raise InvalidDataError(
                f"boundary: edge {e} at ({mid[two[0], 0]}, {mid[two[0], 1]}) (tag {tags[two[0]]}) is selected by two parts"
            )
        none = np.nonzero(count == 0)[0]
        if none.size:
            if rest:
                codes_b[none] = _KINDS[rest[0]]
            else:
                i = none[0]
                raise InvalidDataError(
                    f"boundary: {none.size} boundary edge(s) are selected by no part, e.g. edge {be[i]} at "
                    f"({mid[i, 0]}, {mid[i, 1]}) (tag {tags[i]}); add them to a part or mark one part 'rest'"
                )
        codes = np.zeros(pts.ne, dtype=np.uint8)
        codes[be] = codes_b
        out: Dict[str, Any] = {"boundary": codes}
        if pointwise:
            def fb(x: float, y: float, tag: int) -> int:
                for kind, sel in masks.items():
                    hit = (tag in _tag_list(sel)) if _is_tags(sel) else bool(
                        np.broadcast_to(np.asarray(sel(np.array([x]), np.array([y]))), (1,))[0]
                    )
                    if hit:
                        return _KINDS[kind]
                return _KINDS[rest[0]] if rest else 0

            out["boundary_fallback"] = fb
        return out

    @staticmethod
    def _select(kind: str, sel: Any, pts: _Points, be: np.ndarray, mid: np.ndarray, tags: np.ndarray) -> np.ndarray:
        if _is_tags(sel):
            return np.isin(tags, _tag_list(sel))
        if callable(sel):
            r = np.asarray(_call(sel, f"boundary[{kind!r}]", mid[:, 0].copy(), mid[:, 1].copy()))
            try:
                return np.broadcast_to(r, (be.size,)).astype(bool)
            except ValueError:
                raise InvalidDataError(f"boundary[{kind!r}]: the predicate returned shape {r.shape}, expected ({be.size},)") from None
        v = sel.values if isinstance(sel, EdgeData) else np.asarray(sel)
        if v.shape != (pts.ne,):
            raise InvalidDataError(
                f"boundary[{kind!r}]: expected tags, a predicate (x, y) -> bool, 'rest' or a mask per edge ({pts.ne}), got {sel!r}"
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


def _grad_result(r: Any, m: int) -> np.ndarray:
    if isinstance(r, (list, tuple)) and len(r) == 2:
        try:
            return np.ascontiguousarray(np.column_stack([np.broadcast_to(np.asarray(c, dtype=np.float64), (m,)) for c in r]))
        except ValueError:
            pass
    a = np.asarray(r, dtype=np.float64)
    if a.shape == (m, 2):
        return np.ascontiguousarray(a)
    if a.shape == (2, m):
        return np.ascontiguousarray(a.T)
    raise InvalidDataError(f"exact_grad: expected (gx, gy) arrays of shape ({m},) or an ({m}, 2) array, got shape {a.shape}")
