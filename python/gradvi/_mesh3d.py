"""3D meshes: :class:`Mesh3`, a validated, immutable polyhedral mesh with its geometry as arrays,
and :class:`Box`, the domain of the generated families."""

from __future__ import annotations

import os
import tempfile
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _gradvi
from ._gradvi import InvalidDataError
from ._mesh import _named, _readonly

if TYPE_CHECKING:  # pragma: no cover
    import meshio

ArrayLike = Any
PathLike = Union[str, "os.PathLike[str]"]

__all__ = ["Mesh3", "Box"]


class Box(NamedTuple):
    """An axis-aligned box [x0, x1] × [y0, y1] × [z0, z1]: the x range, then the y and z ranges
    (the order of :class:`gradvi.Rect`). :attr:`Mesh3.bounding_box` returns one, and the
    ``domain=`` of :meth:`Mesh3.generate` takes one (or six numbers in the same order)."""

    x0: float
    x1: float
    y0: float
    y1: float
    z0: float
    z1: float


def _box(domain: Union[Box, Sequence[float]]) -> Box:
    """``domain`` as a :class:`Box`: a Box, or six numbers ``(x0, x1, y0, y1, z0, z1)``."""
    try:
        d = [float(v) for v in domain]
    except (TypeError, ValueError):
        raise InvalidDataError(f"domain must be a gradvi.Box or (x0, x1, y0, y1, z0, z1), got {domain!r}") from None
    if len(d) != 6:
        raise InvalidDataError(f"domain must be a gradvi.Box or (x0, x1, y0, y1, z0, z1), got {len(d)} numbers")
    return Box(*d)


# The faces of meshio's (VTK's) fixed cell types, as local vertex loops.
_FACES: Dict[str, Tuple[Tuple[int, ...], ...]] = {
    "tetra": ((0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)),
    "hexahedron": ((0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)),
    "wedge": ((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)),
    "pyramid": ((0, 1, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)),
}


class _Csr:
    """The flat description of polyhedra being assembled: cell offsets into the face sides,
    face-side offsets into the vertex loops, the loops."""

    def __init__(self) -> None:
        self.cell_sizes: List[np.ndarray] = []  # faces per cell
        self.face_sizes: List[np.ndarray] = []  # vertices per face side
        self.loops: List[np.ndarray] = []  # vertex loops, concatenated

    def add_block(self, kind: str, data: np.ndarray, i: int) -> None:
        """Cells of a fixed type (rows of vertex ids, meshio's order)."""
        faces = _FACES[kind]
        nv = max(max(f) for f in faces) + 1
        if data.ndim != 2 or data.shape[1] != nv:
            raise InvalidDataError(f"meshio cell block {i} ({kind}) must have {nv} vertices per cell, got shape {data.shape}")
        n = data.shape[0]
        self.cell_sizes.append(np.full(n, len(faces), dtype=np.int64))
        self.face_sizes.append(np.tile(np.array([len(f) for f in faces], dtype=np.int64), n))
        self.loops.append(np.concatenate([data[:, list(f)] for f in faces], axis=1).reshape(-1).astype(np.int64))

    def add_polyhedra(self, cells: Any, where: str) -> None:
        """Cells given as sequences of faces, each a sequence of vertex ids."""
        csizes, fsizes, loops = [], [], []
        for k, cell in enumerate(cells):
            try:
                faces = [np.asarray(f, dtype=np.int64).reshape(-1) for f in cell]
            except (TypeError, ValueError):
                raise InvalidDataError(f"{where} cell {k} must be a sequence of faces, each a list of vertex ids") from None
            csizes.append(len(faces))
            fsizes.extend(f.size for f in faces)
            loops.extend(faces)
        self.cell_sizes.append(np.asarray(csizes, dtype=np.int64))
        self.face_sizes.append(np.asarray(fsizes, dtype=np.int64))
        self.loops.append(np.concatenate(loops) if loops else np.zeros(0, np.int64))

    def arrays(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(cell offsets, face-side offsets, vertex loops)."""

        def offsets(sizes: List[np.ndarray]) -> np.ndarray:
            s = np.concatenate(sizes) if sizes else np.zeros(0, np.int64)
            off = np.zeros(s.size + 1, dtype=np.int64)
            np.cumsum(s, out=off[1:])
            return off

        loops = np.concatenate(self.loops) if self.loops else np.zeros(0, np.int64)
        return offsets(self.cell_sizes), offsets(self.face_sizes), np.ascontiguousarray(loops)


def _points3d(points: ArrayLike) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InvalidDataError(f"points must have shape (n, 3), got {p.shape}")
    return np.ascontiguousarray(p)


def _tagged_faces(face_tags: Any) -> Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(offsets, loops, tags) of ``{tag: [face loop, ...]}``."""
    if face_tags is None:
        return None
    if not isinstance(face_tags, Mapping):
        raise InvalidDataError("face_tags must be a dict {tag: [vertex loop of a boundary face, ...]}")
    sizes: List[int] = []
    loops: List[np.ndarray] = []
    tags: List[int] = []
    for tag, faces in face_tags.items():
        for f in faces:
            a = np.asarray(f, dtype=np.int64).reshape(-1)
            sizes.append(a.size)
            loops.append(a)
            tags.append(int(tag))
    off = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=off[1:])
    conn = np.concatenate(loops) if loops else np.zeros(0, np.int64)
    return off, conn, np.asarray(tags, dtype=np.int32)


class Mesh3:
    """A conforming three-dimensional polyhedral mesh: flat, validated, immutable.

    Build one with :meth:`read` (gmsh ``.msh`` 4.1/2.2 ASCII, VTK ``.vtu``, HArDCore RF
    ``.node``/``.ele``), :meth:`generate` (the families of ``gradvi.FAMILIES3``),
    :meth:`from_meshio`, or the constructor from arrays::

        mesh = gradvi.Mesh3(points, cells)   # cells: per cell, its faces as vertex loops

    Building matches the faces of neighbouring cells, orients them and checks what the schemes
    need (closed, star-shaped cells meeting face to face, no overlap, planar enough faces); a
    bad mesh raises :class:`gradvi.InvalidMeshError` naming the cell, face or vertex at fault.

    Geometry (the notation of the crate's documentation) is exposed as read-only numpy arrays:
    ``points`` (vertices, (n, 3)), ``volumes`` (|K|), ``centroids`` (x_K), ``diameters`` (h_K),
    ``cell_tags``; the faces σ as CSR ``face_offsets``/``face_connectivity`` (vertex loops,
    counter-clockwise seen from outside their first cell), ``face_cells`` (the cells on either
    side, -1 for none), ``face_areas`` (|σ|), ``face_centroids`` (x_σ), ``face_normals``
    (unit, outward from the first cell), ``face_tags``, ``boundary_faces``; per (cell, local
    face) in CSR layout ``cell_face_offsets``, ``cell_faces`` and ``cell_dists`` (d_{K,σ}).
    """

    __slots__ = ("_m", "_geo", "_scalars")

    dim = 3

    def __init__(self, points: ArrayLike, cells: Any, cell_tags: ArrayLike = None, face_tags: Any = None) -> None:
        """Builds and validates a mesh.

        Args:
            points: vertex coordinates, shape (n, 3).
            cells: per cell, its faces, each a sequence of vertex ids around the face (either
                orientation); or ``(cell_offsets, face_offsets, face_vertices)``, the flat
                description (cell k has the face sides ``cell_offsets[k]:cell_offsets[k+1]``,
                side s the loop ``face_vertices[face_offsets[s]:face_offsets[s+1]]``).
            cell_tags: one integer per cell (e.g. the material).
            face_tags: boundary face tags, ``{tag: [vertex loop, ...]}``; a loop that is not a
                boundary face is an error.

        Raises:
            InvalidMeshError: the mesh is invalid (the message names the culprit).
            InvalidDataError: the arrays have the wrong shape.
        """
        if isinstance(cells, tuple) and len(cells) == 3 and all(isinstance(c, np.ndarray) for c in cells):
            arrays = tuple(np.ascontiguousarray(c, dtype=np.int64).reshape(-1) for c in cells)
        else:
            csr = _Csr()
            csr.add_polyhedra(cells, "the")
            arrays = csr.arrays()
        self._init(_points3d(points), arrays, cell_tags, _tagged_faces(face_tags))

    def _init(self, points: np.ndarray, arrays: Tuple[np.ndarray, ...], cell_tags: ArrayLike, tagged: Any) -> None:
        ct = None
        if cell_tags is not None:
            ct = np.ascontiguousarray(cell_tags, dtype=np.int64).reshape(-1)
            if ct.size and (ct.min() < -(2**31) or ct.max() >= 2**31):
                raise InvalidDataError("cell tags must fit in 32 bits")
            ct = ct.astype(np.int32)
        self._m = _gradvi._Mesh3.from_arrays(points, *arrays, ct, tagged)
        self._geo: Optional[Dict[str, Any]] = None
        self._scalars: Optional[Dict[str, Any]] = None

    @classmethod
    def _wrap(cls, handle: Any) -> "Mesh3":
        m = cls.__new__(cls)
        m._m = handle
        m._geo = None
        m._scalars = None
        return m

    # ---------------------------------------------------------------- constructors

    @classmethod
    def read(cls, path: PathLike, warped_faces: str = "fan") -> "Mesh3":
        """Reads a 3D mesh file, the reader chosen by extension: ``.msh`` (gmsh ASCII 4.1 or
        2.2: tetrahedra, hexahedra, prisms, pyramids; physical volumes become cell tags,
        physical surfaces boundary-face tags), ``.vtu`` (what :meth:`write_vtu` writes),
        ``.node``/``.ele`` or the stem of such a pair (HArDCore's RF format, general polyhedra).
        Raises :class:`gradvi.MeshIoError` (with ``path`` and ``line``) or
        :class:`gradvi.InvalidMeshError` (with ``path``).
        ``warped_faces``: ``"fan"`` (the default: a non-planar face is one face, its geometry by
        the fan of triangles from its centre, as HArDCore and FVCA6) or ``"split"`` (each
        non-planar face becomes its fan triangles, the centre a new vertex, so that HMM passes
        the patch test exactly)."""
        return cls._wrap(_gradvi._Mesh3.read(os.fspath(path), str(warped_faces)))

    @classmethod
    def generate(
        cls, family: str, level: int, domain: Optional[Union[Box, Sequence[float]]] = None, warped_faces: str = "fan"
    ) -> "Mesh3":
        """A mesh of a built-in family of the unit cube, with n = 2^(level+1) cubes per side:
        ``"cubes"`` (n³ cubes), ``"kuhn"`` or ``"tetrahedra"`` (each cube cut into 6 Kuhn
        tetrahedra), ``"prisms"`` (each cube cut into 2 triangular prisms), ``"refined"`` (a
        checkerboard of the cubes split into 8, so that the others are polyhedra with up to 24
        faces), ``"warped"`` (randomly perturbed hexahedra with warped faces, fixed seed).
        ``domain``, a :class:`Box` or ``(x0, x1, y0, y1, z0, z1)``, maps it affinely onto that
        box. Raises :class:`gradvi.InvalidDataError` for an unknown family, a level out of
        range or a bad box, :class:`gradvi.OutOfMemoryError` if the mesh would not fit.
        ``warped_faces`` as for :meth:`read`."""
        if int(level) < 1:
            raise InvalidDataError(f"mesh levels start at 1, got {level}")
        d = None if domain is None else list(_box(domain))
        return cls._wrap(_gradvi._Mesh3.generate(str(family), int(level), d, str(warped_faces)))

    @classmethod
    def from_meshio(cls, mesh: "meshio.Mesh", tag_key: Optional[str] = None) -> "Mesh3":
        """Converts a ``meshio.Mesh``.

        Cell blocks ``tetra``, ``hexahedron``, ``wedge``, ``pyramid`` and ``polyhedron*``
        (cells as lists of faces) become the cells, in block order; their cell data
        ``tag_key`` (default: ``"gmsh:physical"``, else ``"cell_tag"``) gives the cell tags.
        ``triangle``, ``quad`` and ``polygon`` blocks tag the boundary faces they match with the
        same cell data (faces that are not boundary faces are ignored); ``vertex`` and ``line``
        blocks are ignored. Points that no cell uses are dropped; the others keep their order.
        Other cell types (quadratic elements) raise :class:`gradvi.InvalidDataError`.
        """
        points = np.asarray(mesh.points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise InvalidDataError(f"a 3D meshio mesh has points of shape (n, 3), got {points.shape}")
        keys = [tag_key] if tag_key else ["gmsh:physical", "cell_tag"]
        key = next((k for k in keys if k in mesh.cell_data), None)
        csr, tags, surfaces = _Csr(), [], []
        for i, block in enumerate(mesh.cells):
            t = block.type
            block_tags = None if key is None else np.asarray(mesh.cell_data[key][i]).reshape(-1)
            if t in _FACES:
                csr.add_block(t, np.asarray(block.data), i)
            elif t.startswith("polyhedron"):
                csr.add_polyhedra(block.data, f"meshio block {i}")
            elif t in ("triangle", "quad") or t.startswith("polygon"):
                if block_tags is not None:
                    surfaces.append((block.data, block_tags))
                continue
            elif t in ("vertex", "line"):
                continue
            else:
                raise InvalidDataError(
                    f"meshio cell block {i} has type {t!r}: gradvi takes tetra, hexahedron, wedge, pyramid, "
                    "polyhedron (and triangle, quad, polygon blocks for boundary tags)"
                )
            tags.append(block_tags)
        if not tags:
            raise InvalidDataError("the meshio mesh has no tetra, hexahedron, wedge, pyramid or polyhedron cells")
        cell_ptr, face_ptr, loops = csr.arrays()
        if loops.size and (loops.min() < 0 or loops.max() >= len(points)):
            raise InvalidDataError("a meshio cell refers to a point that does not exist")
        used = np.zeros(len(points), dtype=bool)
        used[loops] = True
        new_id = np.cumsum(used) - 1
        cell_tags = np.concatenate(tags) if all(t is not None for t in tags) else None
        m = cls.__new__(cls)
        m._init(np.ascontiguousarray(points[used]), (cell_ptr, face_ptr, new_id[loops]), cell_tags, None)
        if surfaces:
            m = m._tag_surfaces([(new_id[np.asarray(d, dtype=np.int64)], t, used) for d, t in surfaces])
        return m

    def _tag_surfaces(self, blocks: List[Tuple[Any, np.ndarray, np.ndarray]]) -> "Mesh3":
        """Tags the boundary faces whose vertex sets are listed (later entries win); faces that
        are not boundary faces are ignored."""
        off, conn = self.face_offsets, self.face_connectivity
        by_set = {tuple(sorted(conn[off[f] : off[f + 1]].tolist())): f for f in self.boundary_faces.tolist()}
        tags = self.face_tags.astype(np.int32).copy()
        for faces, t, _ in blocks:
            for face, tag in zip(faces, t):
                f = by_set.get(tuple(sorted(np.asarray(face).tolist())))
                if f is not None:
                    tags[f] = int(tag)
        return self.with_face_tags(tags)

    # ---------------------------------------------------------------- conversions and output

    def write_vtu(
        self,
        path: PathLike,
        point_data: Optional[Mapping[str, ArrayLike]] = None,
        cell_data: Optional[Mapping[str, ArrayLike]] = None,
    ) -> None:
        """Writes an ASCII VTK ``.vtu`` file with gradvi's own writer (no meshio needed):
        ``VTK_TETRA`` or ``VTK_HEXAHEDRON`` cells when every cell is one, else
        ``VTK_POLYHEDRON``; cell tags as the cell data ``cell_tag``, tagged boundary faces as
        field data; float64 data arrays, one value per vertex or per cell. :meth:`read` reads
        it back."""
        self._m.write_vtu(os.fspath(path), _named(point_data), _named(cell_data))

    def write_boundary_vtu(
        self,
        path: PathLike,
        point_data: Optional[Mapping[str, ArrayLike]] = None,
        face_data: Optional[Mapping[str, ArrayLike]] = None,
    ) -> None:
        """Writes the boundary surface to an ASCII VTK ``.vtu`` file for ParaView: each boundary
        face (in the order of :attr:`boundary_faces`) is a ``VTK_POLYGON`` with its loop
        counter-clockwise seen from outside; the points are the vertices of the boundary faces
        in increasing order. The cell data ``face`` (the index of each face) and
        ``boundary_tag`` are always written; ``point_data`` holds one value per mesh vertex and
        ``face_data`` one value per mesh face (interior faces included): the values on the
        boundary are written."""
        self._m.write_faces_vtu(os.fspath(path), _named(point_data), _named(face_data), True)

    def write_faces_vtu(
        self,
        path: PathLike,
        point_data: Optional[Mapping[str, ArrayLike]] = None,
        face_data: Optional[Mapping[str, ArrayLike]] = None,
    ) -> None:
        """Writes every face of the mesh, interior and boundary, to an ASCII VTK ``.vtu`` file
        for ParaView: face ``f`` is the ``VTK_POLYGON`` number ``f``, its loop the mesh's
        (counter-clockwise seen from outside the first cell of the face); the points are the
        mesh's vertices in increasing order. The cell data ``face`` (the index of each face) and
        ``boundary_tag`` (0 on interior faces) are always written; ``point_data`` holds one
        value per mesh vertex and ``face_data`` one value per mesh face."""
        self._m.write_faces_vtu(os.fspath(path), _named(point_data), _named(face_data), False)

    def to_meshio(
        self,
        point_data: Optional[Mapping[str, ArrayLike]] = None,
        cell_data: Optional[Mapping[str, ArrayLike]] = None,
    ) -> "meshio.Mesh":
        """A ``meshio.Mesh`` (needs the ``meshio`` package): the cells of :meth:`write_vtu`
        (one ``tetra`` or ``hexahedron`` block when every cell is one, in VTK's vertex order,
        else ``polyhedron<n>`` blocks of cells as lists of faces, in the mesh's order), through
        a temporary ``.vtu`` file read by meshio, so that both agree; the cell tags are the cell
        data ``cell_tag``. ``from_meshio(m.to_meshio())`` gives back the same cells.

        Args:
            point_data: arrays with one value (or row) per vertex.
            cell_data: arrays with one value (or row) per cell.
        """
        import meshio

        with tempfile.TemporaryDirectory(prefix="gradvi-") as tmp:
            path = os.path.join(tmp, "mesh.vtu")
            self.write_vtu(path)
            out = meshio.read(path)
        if any(b.type.startswith("polyhedron") for b in out.cells):
            # meshio's VTU reader groups polyhedra by vertex count, out of the mesh's order
            out = self._polyhedra_meshio(meshio)
        spans = np.cumsum([0] + [len(b.data) for b in out.cells])
        for name, arr in (point_data or {}).items():
            a = np.asarray(arr)
            if a.shape[:1] != (self.n_vertices,):
                raise InvalidDataError(f"point data {name!r} must have one entry per vertex ({self.n_vertices}), got shape {a.shape}")
            out.point_data[name] = a
        for name, arr in (cell_data or {}).items():
            a = np.asarray(arr)
            if a.shape[:1] != (self.n_cells,):
                raise InvalidDataError(f"cell data {name!r} must have one entry per cell ({self.n_cells}), got shape {a.shape}")
            out.cell_data[name] = [a[s:e] for s, e in zip(spans[:-1], spans[1:])]
        return out

    def _polyhedra_meshio(self, meshio: Any) -> "meshio.Mesh":
        """The cells as meshio ``polyhedron<n>`` blocks (n: the cell's number of vertices), one
        block per run of cells with the same n, each cell its faces' loops counter-clockwise
        seen from outside it (the loops of :meth:`write_vtu`)."""
        off, conn, first = self.face_offsets, self.face_connectivity, self.face_cells[:, 0]
        blocks: List[Tuple[str, List[List[np.ndarray]]]] = []
        for k in range(self.n_cells):
            faces = []
            for f in self.faces_of(k).tolist():
                loop = conn[off[f] : off[f + 1]]
                faces.append(loop.copy() if first[f] == k else loop[::-1].copy())
            kind = f"polyhedron{np.unique(np.concatenate(faces)).size}"
            if not blocks or blocks[-1][0] != kind:
                blocks.append((kind, []))
            blocks[-1][1].append(faces)
        cd = {}
        if np.any(self.cell_tags):
            spans = np.cumsum([0] + [len(b) for _, b in blocks])
            cd["cell_tag"] = [self.cell_tags[s:e].copy() for s, e in zip(spans[:-1], spans[1:])]
        return meshio.Mesh(self.points.copy(), blocks, cell_data=cd)

    def with_face_tags(self, tags: ArrayLike) -> "Mesh3":
        """A copy whose boundary faces carry ``tags[f]`` (one entry per face; interior entries
        are ignored)."""
        return Mesh3._wrap(self._m.with_face_tags(np.ascontiguousarray(tags, dtype=np.int32)))

    def with_cell_tags(self, tags: ArrayLike) -> "Mesh3":
        """A copy whose cell k carries ``tags[k]`` (one entry per cell)."""
        return Mesh3._wrap(self._m.with_cell_tags(np.ascontiguousarray(tags, dtype=np.int32).reshape(-1)))

    # ---------------------------------------------------------------- sizes and geometry

    def _scalar(self, key: str) -> Any:
        if self._scalars is None:
            self._scalars = self._m.scalars()
        return self._scalars[key]

    def _g(self, key: str) -> np.ndarray:
        if self._geo is None:
            self._geo = {k: _readonly(v) for k, v in self._m.geometry().items()}
        return self._geo[key]

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self._scalar("n_vertices"))

    @property
    def n_cells(self) -> int:
        """Number of cells K."""
        return int(self._scalar("n_cells"))

    @property
    def n_faces(self) -> int:
        """Number of faces σ."""
        return int(self._scalar("n_faces"))

    @property
    def h(self) -> float:
        """h = max_K h_K."""
        return float(self._scalar("h"))

    @property
    def bounding_box(self) -> Box:
        """The smallest box holding the mesh, ``Box(x0, x1, y0, y1, z0, z1)``."""
        return Box(*(float(v) for v in self._scalar("bounding_box")))

    def info(self) -> Dict[str, Any]:
        """A summary: ``dim``, ``n_cells``, ``n_faces``, ``n_boundary_faces``, ``n_vertices``,
        ``h``, ``volume`` (Σ|K|), ``bounding_box``, ``max_faces_per_cell``,
        ``max_face_vertices`` and the distinct ``cell_tags`` and ``face_tags`` (of the boundary
        faces)."""
        return {
            "dim": 3,
            "n_cells": self.n_cells,
            "n_faces": self.n_faces,
            "n_boundary_faces": int(self.boundary_faces.size),
            "n_vertices": self.n_vertices,
            "h": self.h,
            "volume": float(self.volumes.sum()),
            "bounding_box": self.bounding_box,
            "max_faces_per_cell": int(np.diff(self.cell_face_offsets).max(initial=0)),
            "max_face_vertices": int(np.diff(self.face_offsets).max(initial=0)),
            "cell_tags": sorted(set(self.cell_tags.tolist())),
            "face_tags": sorted(set(self.face_tags[self.boundary_faces].tolist())),
        }

    @property
    def points(self) -> np.ndarray:
        """Vertex coordinates, (n_vertices, 3)."""
        return self._g("points")

    @property
    def volumes(self) -> np.ndarray:
        """Cell volumes |K|."""
        return self._g("volumes")

    measures = volumes

    @property
    def centroids(self) -> np.ndarray:
        """Cell centroids x_K (centres of mass), (n_cells, 3)."""
        return self._g("centroids")

    @property
    def diameters(self) -> np.ndarray:
        """Cell diameters h_K."""
        return self._g("diameters")

    @property
    def cell_tags(self) -> np.ndarray:
        """Tag of each cell (0: untagged)."""
        return self._g("cell_tags")

    @property
    def cell_face_offsets(self) -> np.ndarray:
        """CSR offsets (n_cells + 1): cell k has the faces ``cell_faces[cell_face_offsets[k]:cell_face_offsets[k+1]]``."""
        return self._g("cell_face_offsets")

    @property
    def cell_faces(self) -> np.ndarray:
        """Face ids of all cells, concatenated (see :attr:`cell_face_offsets`)."""
        return self._g("cell_faces")

    @property
    def cell_dists(self) -> np.ndarray:
        """d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 per (cell, local face), CSR like :attr:`cell_faces`."""
        return self._g("cell_dists")

    def faces_of(self, k: int) -> np.ndarray:
        """The face ids of cell ``k``."""
        off = self.cell_face_offsets
        return self.cell_faces[off[k] : off[k + 1]]

    @property
    def face_offsets(self) -> np.ndarray:
        """CSR offsets (n_faces + 1): face f is ``face_connectivity[face_offsets[f]:face_offsets[f+1]]``."""
        return self._g("face_offsets")

    @property
    def face_connectivity(self) -> np.ndarray:
        """Vertex loops of all faces, concatenated, each counter-clockwise seen from outside
        ``face_cells[f, 0]``."""
        return self._g("face_connectivity")

    def face_vertices(self, f: int) -> np.ndarray:
        """The vertex loop of face ``f``."""
        off = self.face_offsets
        return self.face_connectivity[off[f] : off[f + 1]]

    @property
    def face_cells(self) -> np.ndarray:
        """The cells on either side of each face, (n_faces, 2): the one the normal points out
        of, then the other; -1 for none (boundary)."""
        return self._g("face_cells")

    @property
    def face_areas(self) -> np.ndarray:
        """Face areas |σ|."""
        return self._g("face_areas")

    @property
    def face_centroids(self) -> np.ndarray:
        """Face centroids x_σ, (n_faces, 3)."""
        return self._g("face_centroids")

    @property
    def face_normals(self) -> np.ndarray:
        """Unit face normals, outward from ``face_cells[f, 0]``, (n_faces, 3)."""
        return self._g("face_normals")

    @property
    def face_tags(self) -> np.ndarray:
        """Boundary tag of each face (0: interior or untagged)."""
        return self._g("face_tags")

    @property
    def boundary_faces(self) -> np.ndarray:
        """Ids of the boundary faces, increasing."""
        return self._g("boundary_faces")

    def __repr__(self) -> str:
        m = getattr(self, "_m", None)
        return "<gradvi.Mesh3 (not built)>" if m is None else repr(m).replace("<gradvi 3D mesh", "<gradvi.Mesh3")

    def __eq__(self, other: object) -> bool:
        """Same vertices (bitwise), faces, cells and tags."""
        if not isinstance(other, Mesh3):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, a), getattr(other, a))
            for a in ("points", "cell_face_offsets", "cell_faces", "face_offsets", "face_connectivity", "face_tags", "cell_tags")
        )

    __hash__ = None  # type: ignore[assignment]
