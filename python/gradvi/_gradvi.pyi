"""Type stubs of the private extension module ``gradvi._gradvi`` (PyO3). The public API is the
``gradvi`` package, which wraps these handles; see ``help(gradvi)``."""

from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
#: gradvi::scheme::SchemeKind::ALL, by name
SCHEMES: Tuple[str, ...]
#: gradvi::mesh::generate::Family::ALL, by name
FAMILIES: Tuple[str, ...]
#: gradvi::mesh3d::generate::Family3::ALL, by name
FAMILIES3: Tuple[str, ...]
#: gradvi::problem::file::BUILTIN, by name
BUILTIN_PROBLEMS: Tuple[str, ...]

class GradviError(Exception):
    """Base class of every error gradvi reports (same message as the Rust library)."""

class MeshIoError(GradviError, OSError):
    path: str
    line: int

class InvalidMeshError(GradviError):
    path: Optional[str]

class InvalidDataError(GradviError, ValueError): ...
class InfeasibleError(GradviError): ...
class LinearSolverError(GradviError): ...
class IllPosedError(GradviError): ...
class SolverError(GradviError): ...

class MaxIterationsError(SolverError):
    iterations: int
    history: List[int]

class CyclingError(SolverError):
    iteration: int
    repeats: int
    history: List[int]

class NoKktPointError(SolverError):
    candidates: int

class CertificateError(SolverError):
    quantity: str
    value: float
    tol: float

class ProblemFileError(GradviError):
    path: str
    line: int
    column: int
    kind: str

class FileError(GradviError):
    path: str
    errno: Optional[int]

class InternalError(GradviError): ...

class OutOfMemoryError(GradviError, MemoryError):
    bytes: int
    budget: int

class _Mesh:
    @staticmethod
    def read(path: str) -> _Mesh: ...
    @staticmethod
    def from_arrays(
        points: npt.NDArray[np.float64],
        offsets: npt.NDArray[np.int64],
        connectivity: npt.NDArray[np.int64],
        tagged_edges: Optional[npt.NDArray[np.int64]] = None,
    ) -> _Mesh: ...
    @staticmethod
    def generate(family: str, level: int, domain: Optional[Sequence[float]] = None) -> _Mesh: ...
    @staticmethod
    def cartesian(nx: int, ny: int, domain: Sequence[float]) -> _Mesh: ...
    def with_edge_tags(self, tags: npt.NDArray[np.int32]) -> _Mesh: ...
    def scalars(self) -> Dict[str, Any]: ...
    def same_as(self, other: _Mesh) -> bool: ...
    def geometry(self) -> Dict[str, np.ndarray]: ...
    # points (m, 2), site_kind (m,), site_index (m,), site_edge (m,), site_weights (m, 3),
    # rows: {datum: row indices}
    def evaluation_points(self, scheme: str) -> Dict[str, Any]: ...
    def write_vtu(
        self,
        path: str,
        point_data: List[Tuple[str, npt.NDArray[np.float64]]],
        cell_data: List[Tuple[str, npt.NDArray[np.float64]]],
    ) -> None: ...
    def write_typ2(self, path: str) -> None: ...

class _Mesh3:
    @staticmethod
    def read(path: str, warped_faces: str = ...) -> _Mesh3: ...
    @staticmethod
    def from_arrays(
        points: npt.NDArray[np.float64],
        cell_ptr: npt.NDArray[np.int64],
        face_ptr: npt.NDArray[np.int64],
        face_vertices: npt.NDArray[np.int64],
        cell_tags: Optional[npt.NDArray[np.int32]] = None,
        tagged: Optional[Tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int32]]] = None,
    ) -> _Mesh3: ...
    @staticmethod
    def generate(family: str, level: int, domain: Optional[Sequence[float]] = None, warped_faces: str = ...) -> _Mesh3: ...
    def with_face_tags(self, tags: npt.NDArray[np.int32]) -> _Mesh3: ...
    def with_cell_tags(self, tags: npt.NDArray[np.int32]) -> _Mesh3: ...
    # n_vertices, n_cells, n_faces, h, bounding_box (x0, x1, y0, y1, z0, z1)
    def scalars(self) -> Dict[str, Any]: ...
    def same_as(self, other: _Mesh3) -> bool: ...
    # points, cell_face_offsets, cell_faces, cell_dists, face_offsets, face_connectivity,
    # face_cells, volumes, diameters, centroids, face_areas, face_centroids, face_normals,
    # face_tags, cell_tags, boundary_faces
    def geometry(self) -> Dict[str, np.ndarray]: ...
    # points (m, 3); rows: {datum: int64 rows}
    def evaluation_points(self, scheme: str) -> Dict[str, Any]: ...
    def write_vtu(
        self,
        path: str,
        point_data: List[Tuple[str, npt.NDArray[np.float64]]],
        cell_data: List[Tuple[str, npt.NDArray[np.float64]]],
    ) -> None: ...
    def write_faces_vtu(
        self,
        path: str,
        point_data: List[Tuple[str, npt.NDArray[np.float64]]],
        face_data: List[Tuple[str, npt.NDArray[np.float64]]],
        boundary_only: bool,
    ) -> None: ...

class _Problem:
    @staticmethod
    def builtin(name: str, params: List[Tuple[str, float]]) -> _Problem: ...
    @staticmethod
    def from_file(path: str, params: List[Tuple[str, float]]) -> _Problem: ...
    @staticmethod
    def tabulated(name: str, mesh: _Mesh, points: npt.NDArray[np.float64], data: Dict[str, Any]) -> _Problem: ...
    @staticmethod
    def tabulated3(name: str, mesh: _Mesh3, points: npt.NDArray[np.float64], data: Dict[str, Any]) -> _Problem: ...
    name: str
    source: str
    description: Optional[str]
    path: Optional[str]
    parameters: List[Tuple[str, float]]
    scheme: Optional[str]
    mesh_spec: Optional[str]
    constraint: Optional[Tuple[str, str]]
    has_exact: bool
    def build_mesh(self, warped_faces: str = ...) -> Optional[Union[_Mesh, _Mesh3]]: ...

# every option is given (their defaults are those of gradvi.solve)
def solve(
    mesh: Union[_Mesh, _Mesh3],
    problem: _Problem,
    scheme: str,
    alpha: float,
    c: float,
    max_solves: int,
    tol: float,
    fallback: bool,
    warm_start: str,
    initial_active: Optional[npt.NDArray[np.bool_]],
    keep_iterates: bool,
    ordering: str,
    factor_threads: str,
    linear: str,
) -> Dict[str, Any]: ...
