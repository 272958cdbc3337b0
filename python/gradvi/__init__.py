"""gradvi: gradient schemes for the obstacle and Signorini problems, from Python.

gradvi solves the variational inequalities of the obstacle problem and of the Signorini problem
for anisotropic, heterogeneous diffusion −div(A∇u) = f on generic polygonal meshes, with the
Hybrid Mimetic Mixed (HMM) scheme, conforming P1 and Crouzeix–Raviart, and a certified
active-set (monotony) solver. This package binds the Rust library: the meshes, the data
tables and the results are numpy arrays.

The pipeline is mesh → problem → solve::

    import numpy as np, gradvi

    mesh = gradvi.Mesh.read("meshes/test3_1.msh")           # or Mesh.generate, Mesh(points, cells), Mesh.from_meshio
    pb = gradvi.Problem(source=-20.0,                        # numbers, vectorised callables, per-cell/edge/vertex arrays
                        obstacle=lambda x, y: -np.minimum.reduce([x, 1 - x, y, 1 - y]),
                        side="lower")                         # u >= psi
    sol = gradvi.solve(mesh, pb, scheme="hmm")               # certified; raises gradvi.GradviError otherwise
    print(sol.niter, sol.contact_measure, sol.certificate)
    sol.write_vtu("u.vtu")                                   # or sol.to_meshio()

Main names: :class:`Mesh`, :class:`Problem` (with :class:`CellData`, :class:`EdgeData`,
:class:`VertexData`), :func:`solve` returning a :class:`Solution`, :class:`Rect`, the 3D
polyhedral :class:`Mesh3` with its :class:`Box` (read, generated, converted, and solved on
with HMM: a :class:`Problem` then takes callables of (x, y, z)), the registries ``SCHEMES``, ``FAMILIES``, ``FAMILIES3`` and ``BUILTIN_PROBLEMS`` (from
the Rust library), and the
exceptions, all subclasses of :class:`GradviError` (:class:`InvalidDataError` is also a
``ValueError``, :class:`MeshIoError` an ``OSError``, :class:`OutOfMemoryError` a
``MemoryError``).
"""

from ._gradvi import (
    BUILTIN_PROBLEMS,
    FAMILIES,
    FAMILIES3,
    SCHEMES,
    CertificateError,
    CyclingError,
    FileError,
    GradviError,
    IllPosedError,
    InfeasibleError,
    InternalError,
    InvalidDataError,
    InvalidMeshError,
    LinearSolverError,
    MaxIterationsError,
    MeshIoError,
    NoKktPointError,
    OutOfMemoryError,
    ProblemFileError,
    SolverError,
)
from ._gradvi import __version__ as _rust_version
from ._mesh import Mesh, Rect
from ._mesh3d import Box, Mesh3
from ._problem import CellData, EdgeData, Problem, VertexData
from ._solve import Certificate, IterationLog, MarginalLoadWarning, Solution, solve

__version__ = _rust_version

# The registries come from the Rust library: SCHEMES (schemes of :func:`solve`), FAMILIES (mesh
# families of :meth:`Mesh.generate`), FAMILIES3 (3D families of :meth:`Mesh3.generate`) and
# BUILTIN_PROBLEMS (problems of :meth:`Problem.builtin`), tuples of names in registration order.


def fitted_slope(h, e) -> float:
    """Least-squares slope of ln e against ln h (the convergence order of errors e on meshes of
    sizes h), as the Rust library's ``post::fitted_slope``."""
    import numpy as np

    x, y = np.log(np.asarray(h, dtype=float)), np.log(np.asarray(e, dtype=float))
    if x.size < 2:
        raise InvalidDataError("a slope needs at least two points")
    xm, ym = x - x.mean(), y - y.mean()
    return float((xm * ym).sum() / (xm * xm).sum())


__all__ = [
    "Mesh",
    "Rect",
    "Mesh3",
    "Box",
    "Problem",
    "CellData",
    "EdgeData",
    "VertexData",
    "solve",
    "Solution",
    "Certificate",
    "IterationLog",
    "fitted_slope",
    "SCHEMES",
    "FAMILIES",
    "FAMILIES3",
    "BUILTIN_PROBLEMS",
    "GradviError",
    "MeshIoError",
    "InvalidMeshError",
    "InvalidDataError",
    "InfeasibleError",
    "LinearSolverError",
    "IllPosedError",
    "SolverError",
    "MaxIterationsError",
    "CyclingError",
    "NoKktPointError",
    "CertificateError",
    "ProblemFileError",
    "FileError",
    "InternalError",
    "OutOfMemoryError",
    "MarginalLoadWarning",
    "__version__",
]
