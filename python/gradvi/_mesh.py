"""Meshes: :class:`Mesh`, a validated, immutable polygonal mesh with its geometry as arrays."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Callable, Dict, Generic, List, Mapping, NamedTuple, Optional, Sequence, Tuple, TypeVar, Union, overload

import numpy as np

from . import _gradvi
from ._gradvi import InvalidDataError

if TYPE_CHECKING:  # pragma: no cover
    import meshio

ArrayLike = Any
PathLike = Union[str, "os.PathLike[str]"]

__all__ = ["Mesh", "Rect"]


class Rect(NamedTuple):
    """An axis-aligned rectangle [x0, x1] × [y0, y1]: the x range, then the y range (the
    order of the Rust library's rectangle). :attr:`Mesh.bounding_box` returns one, and the
    ``domain=`` of :meth:`Mesh.generate` and :meth:`Mesh.cartesian` takes one (or a plain
    sequence in the same order ``(x0, x1, y0, y1)``)."""

    x0: float
    x1: float
    y0: float
    y1: float


def _rect(domain: Union[Rect, Sequence[float]]) -> Rect:
    """``domain`` as a :class:`Rect`: a Rect, or four numbers ``(x0, x1, y0, y1)``."""
    if isinstance(domain, Rect):
        return Rect(*(float(v) for v in domain))
    try:
        d = [float(v) for v in domain]
    except (TypeError, ValueError):
        raise InvalidDataError(f"domain must be a gradvi.Rect or (x0, x1, y0, y1), got {domain!r}") from None
    if len(d) != 4:
        raise InvalidDataError(f"domain must be a gradvi.Rect or (x0, x1, y0, y1), got {len(d)} numbers")
    return Rect(*d)


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def _named(data: Optional[Mapping[str, ArrayLike]]) -> List[Tuple[str, np.ndarray]]:
    """Named data arrays as the writers take them: (name, contiguous flat float64 array)."""
    return [(str(k), np.ascontiguousarray(v, dtype=np.float64).reshape(-1)) for k, v in (data or {}).items()]


def _points2d(points: ArrayLike) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise InvalidDataError(f"points must have shape (n, 2) or (n, 3), got {p.shape}")
    if p.shape[1] == 3:
        z = p[:, 2]
        if z.size and not np.all(z == z[0]):
            raise InvalidDataError(
                "points have varying z coordinates: gradvi meshes are two-dimensional (z must be constant)"
            )
        p = p[:, :2]
    return np.ascontiguousarray(p)


def _cells_csr(cells: Any) -> Tuple[np.ndarray, np.ndarray]:
    """(offsets, connectivity) of cells given as a 2-d integer array, a sequence of vertex lists
    (polygons of mixed sizes), or a tuple ``(offsets, connectivity)``."""
    if isinstance(cells, tuple) and len(cells) == 2 and all(
        isinstance(c, np.ndarray) and c.ndim == 1 for c in cells
    ):
        off, conn = cells
        return (np.ascontiguousarray(off, dtype=np.int64), np.ascontiguousarray(conn, dtype=np.int64))
    if isinstance(cells, np.ndarray) and cells.ndim == 2:
        if not np.issubdtype(cells.dtype, np.integer):
            raise InvalidDataError(f"cells must hold integer vertex ids, got dtype {cells.dtype}")
        n, k = cells.shape
        off = np.arange(n + 1, dtype=np.int64) * k
        return off, np.ascontiguousarray(cells.reshape(-1), dtype=np.int64)
    try:
        lists = [np.asarray(c) for c in cells]
    except TypeError:
        raise InvalidDataError("cells must be a 2-d integer array or a sequence of vertex lists") from None
    sizes = np.fromiter((c.size for c in lists), dtype=np.int64, count=len(lists))
    for k, c in enumerate(lists):
        if c.ndim != 1 or (c.size and not np.issubdtype(c.dtype, np.integer)):
            raise InvalidDataError(f"cell {k} must be a flat list of integer vertex ids, got {c!r}")
    off = np.zeros(len(lists) + 1, dtype=np.int64)
    np.cumsum(sizes, out=off[1:])
    conn = np.concatenate([c.astype(np.int64) for c in lists]) if lists else np.zeros(0, np.int64)
    return off, conn


def _tag_rows(boundary_tags: Any) -> Optional[np.ndarray]:
    """(k, 3) rows (a, b, tag) from an array of rows or a dict ``{tag: [(a, b), ...]}``."""
    if boundary_tags is None:
        return None
    if isinstance(boundary_tags, Mapping):
        rows = []
        for tag, pairs in boundary_tags.items():
            pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
            rows.append(np.column_stack([pairs, np.full(len(pairs), int(tag), dtype=np.int64)]))
        return np.ascontiguousarray(np.concatenate(rows) if rows else np.zeros((0, 3), np.int64))
    t = np.asarray(boundary_tags, dtype=np.int64)
    if t.ndim != 2 or t.shape[1] != 3:
        raise InvalidDataError(f"boundary_tags must have shape (k, 3) rows (vertex a, vertex b, tag), got {t.shape}")
    return np.ascontiguousarray(t)


T = TypeVar("T")


class _Scalar(Generic[T]):
    """A read-only scalar attribute of :class:`Mesh`: the entry of the same name of the native
    mesh's scalars, converted by ``convert``."""

    def __init__(self, convert: Callable[[Any], T], doc: str) -> None:
        self._convert = convert
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self._name = name

    @overload
    def __get__(self, mesh: None, owner: Optional[type] = None) -> "_Scalar[T]": ...
    @overload
    def __get__(self, mesh: "Mesh", owner: Optional[type] = None) -> T: ...
    def __get__(self, mesh: Optional["Mesh"], owner: Optional[type] = None) -> Any:
        if mesh is None:
            return self
        return self._convert(mesh._scalar(self._name))

    def __set__(self, mesh: "Mesh", value: Any) -> None:
        raise AttributeError(f"Mesh.{self._name} is read-only")


class Mesh:
    """A conforming two-dimensional polygonal mesh: flat, validated, immutable.

    Build one with :meth:`read` (gmsh ``.msh`` 4.1/2.2 ASCII, FVCA5 ``.typ1``/``.typ2``),
    :meth:`generate` (the built-in families), :meth:`cartesian`, :meth:`from_meshio`, or the
    constructor from arrays::

        mesh = gradvi.Mesh(points, cells)        # cells: 2-d array, or lists of mixed sizes

    The constructor orients every cell counter-clockwise, derives the edges σ and checks what the
    schemes need (simple, star-shaped cells meeting edge to edge, no overlap); a bad mesh raises
    :class:`gradvi.InvalidMeshError` naming the cell, edge or vertex at fault.

    Geometry (the notation of the crate's documentation) is exposed as read-only numpy arrays:
    ``points`` (vertices), ``centroids`` (x_K), ``measures`` (|K|), ``diameters`` (h_K),
    ``edges`` (vertex pairs), ``edge_cells`` (the cells on either side, -1 for none),
    ``edge_midpoints`` (x_σ), ``edge_lengths`` (|σ|), ``edge_tags``, ``boundary_edges``, and
    per (cell, local edge) in CSR layout ``cell_offsets``, ``cell_connectivity``,
    ``cell_edges``, ``cell_normals`` (n_{K,σ}), ``cell_dists`` (d_{K,σ}).
    """

    __slots__ = ("_m", "_geo", "_scalars")

    def __init__(
        self,
        points: ArrayLike,
        cells: Any,
        boundary_tags: Any = None,
    ) -> None:
        """Builds and validates a mesh.

        Args:
            points: vertex coordinates, shape (n, 2) (or (n, 3) with a constant z, dropped).
            cells: a 2-d integer array (one row per cell), a sequence of vertex-id lists
                (polygons of mixed sizes, either orientation), or ``(offsets, connectivity)``.
            boundary_tags: boundary edge tags, as (k, 3) rows ``(vertex a, vertex b, tag)`` or a
                dict ``{tag: [(a, b), ...]}``; an entry that is not a boundary edge is an error.

        Raises:
            InvalidMeshError: the mesh is invalid (the message names the culprit).
            InvalidDataError: the arrays have the wrong shape.
        """
        off, conn = _cells_csr(cells)
        self._m = _gradvi._Mesh.from_arrays(_points2d(points), off, conn, _tag_rows(boundary_tags))
        self._geo: Optional[Dict[str, Any]] = None
        self._scalars: Optional[Dict[str, Any]] = None

    @classmethod
    def _wrap(cls, handle: Any) -> "Mesh":
        m = cls.__new__(cls)
        m._m = handle
        m._geo = None
        m._scalars = None
        return m

    # ---------------------------------------------------------------- constructors

    @classmethod
    def read(cls, path: PathLike) -> "Mesh":
        """Reads a mesh file, the reader chosen by extension: ``.msh`` (gmsh ASCII 4.1 or 2.2;
        physical line tags become boundary tags, names in :attr:`physical_names`), ``.typ1``,
        ``.typ2``. Raises :class:`gradvi.MeshIoError` (with ``path`` and ``line``) or
        :class:`gradvi.InvalidMeshError`."""
        return cls._wrap(_gradvi._Mesh.read(os.fspath(path)))

    @classmethod
    def generate(
        cls, family: str, level: int, domain: Optional[Union[Rect, Sequence[float]]] = None
    ) -> "Mesh":
        """A mesh of a built-in family of the unit square: ``"cartesian"`` (level k: 2^(k+1)
        squares per side), ``"hexagonal"`` (FVCA5 ``hexa1_k``), ``"kershaw"`` (``mesh4_1_k``),
        ``"triangles"`` (the Cartesian squares of level k, each cut into two triangles by its
        diagonal from lower left to upper right: a mesh for P1 and CR).
        ``domain``, a :class:`Rect` or ``(x0, x1, y0, y1)``, maps it affinely onto that
        rectangle (then ``bounding_box == Rect(*domain)``)."""
        if int(level) < 1:
            raise InvalidDataError(f"mesh levels start at 1, got {level}")
        d = None if domain is None else list(_rect(domain))
        return cls._wrap(_gradvi._Mesh.generate(str(family), int(level), d))

    @classmethod
    def cartesian(
        cls, nx: int, ny: int, domain: Union[Rect, Sequence[float]] = Rect(0.0, 1.0, 0.0, 1.0)
    ) -> "Mesh":
        """nx × ny rectangles on ``domain``, a :class:`Rect` or ``(x0, x1, y0, y1)``."""
        d = list(_rect(domain))
        if int(nx) < 1 or int(ny) < 1:
            raise InvalidDataError(f"nx and ny must be at least 1, got {nx} x {ny}")
        return cls._wrap(_gradvi._Mesh.cartesian(int(nx), int(ny), d))

    @classmethod
    def from_meshio(cls, mesh: "meshio.Mesh", tag_key: Optional[str] = None) -> "Mesh":
        """Converts a ``meshio.Mesh``.

        Cell blocks ``triangle``, ``quad`` and ``polygon`` become the cells (in block order);
        ``line`` blocks give the boundary tags, from the cell data ``tag_key`` (default:
        ``"gmsh:physical"``, else ``"boundary_tag"``); lines that are not boundary edges are
        ignored; ``vertex`` blocks are ignored. Points that no cell uses (gmsh lists geometry
        nodes) are dropped; the others keep their order. Other cell types (quadratic elements,
        3-d cells) raise :class:`gradvi.InvalidDataError`.
        """
        points = _points2d(np.asarray(mesh.points))
        cell_lists: List[np.ndarray] = []
        lines: List[Tuple[np.ndarray, Optional[np.ndarray]]] = []
        keys = [tag_key] if tag_key else ["gmsh:physical", "boundary_tag"]
        for i, block in enumerate(mesh.cells):
            t, data = block.type, np.asarray(block.data)
            if t in ("triangle", "quad", "polygon") or t.startswith("polygon"):
                cell_lists.append(data.astype(np.int64))
            elif t == "line":
                tags = None
                for k in keys:
                    if k in mesh.cell_data:
                        tags = np.asarray(mesh.cell_data[k][i]).reshape(-1)
                        break
                lines.append((data.astype(np.int64), tags))
            elif t == "vertex":
                continue
            else:
                raise InvalidDataError(
                    f"meshio cell block {i} has type {t!r}: gradvi takes triangle, quad, polygon "
                    "(and line blocks for boundary tags)"
                )
        if not cell_lists:
            raise InvalidDataError("the meshio mesh has no triangle, quad or polygon cells")
        rows: List[np.ndarray] = [r for c in cell_lists for r in c] if any(
            c.shape[1] != cell_lists[0].shape[1] for c in cell_lists
        ) else []
        if rows:
            off = np.zeros(len(rows) + 1, dtype=np.int64)
            np.cumsum([len(r) for r in rows], out=off[1:])
            conn = np.concatenate(rows)
        else:
            allc = np.concatenate(cell_lists)
            off = np.arange(allc.shape[0] + 1, dtype=np.int64) * allc.shape[1]
            conn = allc.reshape(-1)
        # drop unused points, keeping the order of the others
        if conn.size and (conn.min() < 0 or conn.max() >= len(points)):
            raise InvalidDataError("a meshio cell refers to a point that does not exist")
        used = np.zeros(len(points), dtype=bool)
        used[conn] = True
        new_id = np.cumsum(used) - 1
        m = cls((points[used]), (off, new_id[conn]))
        tagged = [(d, t) for d, t in lines if t is not None and len(d)]
        if tagged:
            m = m._tag_lines([(new_id[d], t, used[d].all(axis=1)) for d, t in tagged])
        return m

    def _tag_lines(self, blocks: List[Tuple[np.ndarray, np.ndarray, np.ndarray]]) -> "Mesh":
        """Tags the boundary edges listed as vertex pairs (later entries win); pairs that are not
        boundary edges are ignored."""
        ne = self.n_edges
        edges = self.edges
        key = edges[:, 0] * (self.n_vertices + 1) + edges[:, 1]
        order = np.argsort(key)
        tags = self.edge_tags.astype(np.int32).copy()
        is_boundary = np.zeros(ne, dtype=bool)
        is_boundary[self.boundary_edges] = True
        for pairs, t, ok in blocks:
            pairs, t = pairs[ok], np.asarray(t)[ok]
            a, b = np.minimum(pairs[:, 0], pairs[:, 1]), np.maximum(pairs[:, 0], pairs[:, 1])
            k = a * (self.n_vertices + 1) + b
            pos = np.searchsorted(key[order], k)
            pos = np.minimum(pos, ne - 1)
            found = key[order][pos] == k
            e = order[pos[found]]
            sel = is_boundary[e]
            tags[e[sel]] = t[found][sel].astype(np.int32)
        return self.with_edge_tags(tags)

    # ---------------------------------------------------------------- conversions and output

    def to_meshio(
        self,
        point_data: Optional[Mapping[str, ArrayLike]] = None,
        cell_data: Optional[Mapping[str, ArrayLike]] = None,
        boundary_lines: bool = True,
    ) -> "meshio.Mesh":
        """A ``meshio.Mesh`` (needs the ``meshio`` package).

        Cells become consecutive blocks of ``triangle``, ``quad`` and ``polygon`` cells, in the
        mesh's order (so ``from_meshio(m.to_meshio())`` gives back the same mesh); with
        ``boundary_lines``, the tagged boundary edges follow as a ``line`` block, with the cell
        data ``gmsh:physical`` holding the tags (0 on the cells). Points get z = 0.

        Args:
            point_data: arrays with one value (or row) per vertex.
            cell_data: arrays with one value (or row) per cell.
        """
        import meshio

        off, conn = self.cell_offsets, self.cell_connectivity
        sizes = np.diff(off)
        blocks: List[Tuple[str, np.ndarray]] = []
        spans: List[Tuple[int, int]] = []
        start = 0
        n = len(sizes)
        while start < n:
            end = start + 1
            while end < n and sizes[end] == sizes[start]:
                end += 1
            k = int(sizes[start])
            data = conn[off[start] : off[end]].reshape(end - start, k)
            blocks.append(({3: "triangle", 4: "quad"}.get(k, "polygon"), data.copy()))
            spans.append((start, end))
            start = end
        cd: Dict[str, List[np.ndarray]] = {}
        for name, arr in (cell_data or {}).items():
            a = np.asarray(arr)
            if a.shape[:1] != (self.n_cells,):
                raise InvalidDataError(f"cell data {name!r} must have one entry per cell ({self.n_cells}), got shape {a.shape}")
            cd[name] = [a[s:e] for s, e in spans]
        tagged = np.nonzero(self.edge_tags)[0]
        if boundary_lines and tagged.size:
            blocks.append(("line", self.edges[tagged].copy()))
            for name in list(cd):
                a = cd[name][0]
                cd[name].append(np.zeros((tagged.size,) + a.shape[1:], dtype=a.dtype))
            cd["gmsh:physical"] = [np.zeros(e - s, dtype=np.int32) for s, e in spans] + [
                self.edge_tags[tagged].astype(np.int32)
            ]
        pd: Dict[str, np.ndarray] = {}
        for name, arr in (point_data or {}).items():
            a = np.asarray(arr)
            if a.shape[:1] != (self.n_vertices,):
                raise InvalidDataError(
                    f"point data {name!r} must have one entry per vertex ({self.n_vertices}), got shape {a.shape}"
                )
            pd[name] = a
        pts = np.column_stack([self.points, np.zeros(self.n_vertices)])
        return meshio.Mesh(pts, blocks, point_data=pd, cell_data=cd)

    def write_vtu(
        self,
        path: PathLike,
        point_data: Optional[Mapping[str, ArrayLike]] = None,
        cell_data: Optional[Mapping[str, ArrayLike]] = None,
    ) -> None:
        """Writes an ASCII VTK ``.vtu`` file (polygons; float64 data arrays, one value per vertex
        or per cell) with gradvi's own writer (no meshio needed)."""
        self._m.write_vtu(os.fspath(path), _named(point_data), _named(cell_data))

    def write_typ2(self, path: PathLike) -> None:
        """Writes an FVCA5 / HArDCore ``.typ2`` file (readable by :meth:`read`)."""
        self._m.write_typ2(os.fspath(path))

    def with_boundary_tags(self, tags: Union[ArrayLike, Callable[[np.ndarray, np.ndarray], ArrayLike]]) -> "Mesh":
        """A copy whose boundary edges carry new tags: ``tags`` is one integer per edge (interior
        entries ignored), or a vectorised callable ``tags(x, y)`` evaluated once on the arrays
        of the boundary edge midpoints x_σ."""
        b = self.boundary_edges
        if callable(tags):
            mid = self.edge_midpoints[b]
            t = np.broadcast_to(np.asarray(tags(mid[:, 0], mid[:, 1])), (b.size,))
            full = np.zeros(self.n_edges, dtype=np.int32)
            full[b] = t.astype(np.int32)
        else:
            full = np.asarray(tags)
            if full.shape != (self.n_edges,):
                raise InvalidDataError(f"tags must have one entry per edge ({self.n_edges}), got shape {full.shape}")
        return self.with_edge_tags(full.astype(np.int32))

    def with_edge_tags(self, tags: ArrayLike) -> "Mesh":
        """A copy whose boundary edges carry ``tags[e]`` (one entry per edge)."""
        return Mesh._wrap(self._m.with_edge_tags(np.ascontiguousarray(tags, dtype=np.int32)))

    # ---------------------------------------------------------------- sizes and geometry

    n_vertices = _Scalar(int, "Number of vertices.")
    n_cells = _Scalar(int, "Number of cells K.")
    n_edges = _Scalar(int, "Number of edges σ.")
    h = _Scalar(float, "h = max_K h_K.")
    is_triangular = _Scalar(bool, "Whether every cell is a triangle (P1 and CR need it).")

    @property
    def bounding_box(self) -> Rect:
        """The smallest rectangle holding the mesh, ``Rect(x0=xmin, x1=xmax, y0=ymin,
        y1=ymax)``."""
        return Rect(*(float(v) for v in self._scalar("bounding_box")))

    @property
    def physical_names(self) -> Dict[str, Tuple[int, int]]:
        """gmsh physical names of a ``.msh`` file: ``{name: (dimension, tag)}``."""
        return {name: (dim, tag) for dim, tag, name in self._scalar("physical_names")}

    def _scalar(self, key: str) -> Any:
        if self._scalars is None:
            self._scalars = self._m.scalars()
        return self._scalars[key]

    def _g(self, key: str) -> np.ndarray:
        if self._geo is None:
            self._geo = {k: _readonly(v) for k, v in self._m.geometry().items()}
        return self._geo[key]

    @property
    def points(self) -> np.ndarray:
        """Vertex coordinates, (n_vertices, 2)."""
        return self._g("points")

    @property
    def cell_offsets(self) -> np.ndarray:
        """CSR offsets (n_cells + 1): cell k is ``cell_connectivity[cell_offsets[k]:cell_offsets[k+1]]``."""
        return self._g("cell_offsets")

    @property
    def cell_connectivity(self) -> np.ndarray:
        """Counter-clockwise vertex ids of all cells, concatenated (see :attr:`cell_offsets`)."""
        return self._g("cell_connectivity")

    @property
    def cells(self) -> List[np.ndarray]:
        """The vertex ids of each cell, counter-clockwise (a list of arrays of mixed sizes)."""
        off, conn = self.cell_offsets, self.cell_connectivity
        return np.split(conn, off[1:-1])

    def cell_vertices(self, k: int) -> np.ndarray:
        """Counter-clockwise vertex ids of cell ``k``."""
        off = self.cell_offsets
        return self.cell_connectivity[off[k] : off[k + 1]]

    @property
    def cell_sizes(self) -> np.ndarray:
        """Number of vertices (= edges) of each cell."""
        return np.diff(self.cell_offsets)

    @property
    def cell_edges(self) -> np.ndarray:
        """Edge ids per (cell, local edge), CSR like :attr:`cell_connectivity`; local edge i
        joins local vertices i and i+1."""
        return self._g("cell_edges")

    @property
    def cell_normals(self) -> np.ndarray:
        """Outward unit normals n_{K,σ} per (cell, local edge), (sum of cell sizes, 2)."""
        return self._g("cell_normals")

    @property
    def cell_dists(self) -> np.ndarray:
        """d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 per (cell, local edge)."""
        return self._g("cell_dists")

    @property
    def centroids(self) -> np.ndarray:
        """Cell centroids x_K (centres of mass), (n_cells, 2)."""
        return self._g("centroids")

    @property
    def measures(self) -> np.ndarray:
        """Cell areas |K|."""
        return self._g("measures")

    areas = measures

    @property
    def diameters(self) -> np.ndarray:
        """Cell diameters h_K."""
        return self._g("diameters")

    @property
    def edges(self) -> np.ndarray:
        """Edge end points (vertex ids, smaller first), (n_edges, 2)."""
        return self._g("edges")

    @property
    def edge_cells(self) -> np.ndarray:
        """The cells on either side of each edge, (n_edges, 2); -1 for none (boundary)."""
        return self._g("edge_cells")

    @property
    def edge_midpoints(self) -> np.ndarray:
        """Edge midpoints x_σ, (n_edges, 2)."""
        return self._g("edge_midpoints")

    @property
    def edge_lengths(self) -> np.ndarray:
        """Edge lengths |σ|."""
        return self._g("edge_lengths")

    @property
    def edge_tags(self) -> np.ndarray:
        """Boundary tag of each edge (0: interior or untagged)."""
        return self._g("edge_tags")

    @property
    def boundary_edges(self) -> np.ndarray:
        """Ids of the boundary edges, increasing."""
        return self._g("boundary_edges")

    def __repr__(self) -> str:
        m = getattr(self, "_m", None)
        return "<gradvi.Mesh (not built)>" if m is None else repr(m).replace("<gradvi mesh", "<gradvi.Mesh")

    def __eq__(self, other: object) -> bool:
        """Same vertices (bitwise), cells (same order, same starting vertex) and edge tags."""
        if not isinstance(other, Mesh):
            return NotImplemented
        return (
            self.n_cells == other.n_cells
            and np.array_equal(self.points, other.points)
            and np.array_equal(self.cell_offsets, other.cell_offsets)
            and np.array_equal(self.cell_connectivity, other.cell_connectivity)
            and np.array_equal(self.edge_tags, other.edge_tags)
        )

    __hash__ = None  # type: ignore[assignment]
