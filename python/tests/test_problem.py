"""Problems: built-ins, problem files, and problems built in Python from constants, callables
and per-entity arrays, which must give the same discrete solutions as the Rust or file ones."""
import numpy as np
import pytest
from conftest import ROOT, make_ex9, psi, make_test3

import gradvi


def test_builtin_and_file_describe_themselves():
    b = gradvi.Problem.builtin("test3", C=-20)
    assert b.origin == "builtin" and b.constraint == ("obstacle", "lower") and not b.has_exact
    assert b.parameters == {"C": -20.0}
    f = gradvi.Problem.from_file(ROOT / "problems" / "test3.toml", C=-20)
    assert f.origin == "file" and f.constraint == ("obstacle", "lower")
    assert f.parameters == {"C": -20.0} and f.description
    assert gradvi.Problem.builtin("test2").has_exact
    assert gradvi.Problem.builtin("test1").constraint == ("signorini", "lower")
    p = make_test3(-5.0)
    assert p.origin == "python" and p.constraint == ("obstacle", "lower")


@pytest.mark.parametrize("scheme", ["hmm", "p1", "cr"])
def test_callables_equal_builtin_and_file(test3_mesh, scheme):
    ref = gradvi.solve(test3_mesh, gradvi.Problem.builtin("test3", C=-20), scheme=scheme)
    py = gradvi.solve(test3_mesh, make_test3(-20.0), scheme=scheme)
    fi = gradvi.solve(test3_mesh, gradvi.Problem.from_file(ROOT / "problems" / "test3.toml", C=-20), scheme=scheme)
    for s in (py, fi):
        np.testing.assert_array_equal(s.u, ref.u)  # ψ and C are exact in both: bitwise equal
        np.testing.assert_array_equal(s.active, ref.active)
        assert s.niter == ref.niter and s.contact_measure == ref.contact_measure


def test_per_cell_and_per_vertex_arrays(test3_mesh):
    m = test3_mesh
    ref = gradvi.solve(m, gradvi.Problem.builtin("test3", C=-10))
    # a constant source as a per-cell array; the obstacle as per-cell values ψ(x_K)
    pb = gradvi.Problem(source=gradvi.CellData(np.full(m.n_cells, -10.0)),
                        obstacle=gradvi.CellData(psi(*m.centroids.T)), side="lower")
    s = gradvi.solve(m, pb)
    np.testing.assert_array_equal(s.u_cell, ref.u_cell)
    # P1 takes nodal values of the barrier
    ref1 = gradvi.solve(m, gradvi.Problem.builtin("test3", C=-10), scheme="p1")
    pb1 = gradvi.Problem(source=-10.0, obstacle=gradvi.VertexData(psi(*m.points.T)), side="lower")
    np.testing.assert_array_equal(gradvi.solve(m, pb1, scheme="p1").u, ref1.u)
    # a plain array is taken by its length
    pb2 = gradvi.Problem(source=np.full(m.n_cells, -10.0), obstacle=psi, side="lower")
    np.testing.assert_array_equal(gradvi.solve(m, pb2).u, ref.u)


def test_each_callable_is_called_once_on_arrays(test3_mesh):
    calls = []

    def counted(name, f):
        def g(x, y):
            assert isinstance(x, np.ndarray) and x.shape == y.shape and x.size > 1
            calls.append(name)
            return f(x, y)
        return g

    pb = gradvi.Problem(
        source=counted("f", lambda x, y: -20.0 + 0 * x),
        obstacle=counted("psi", psi),
        dirichlet=counted("g", lambda x, y: 0 * x),
        diffusion=counted("A", lambda x, y: np.ones_like(x)),
        side="lower",
    )
    for scheme in ("hmm", "p1", "cr"):
        calls.clear()
        gradvi.solve(test3_mesh, pb, scheme=scheme)
        assert sorted(calls) == ["A", "f", "g", "psi"]


def test_signorini_from_file_equals_python(root):
    """The two-material Signorini problem of problems/signorini-layers.toml, rebuilt in Python
    from gmsh tags, a piecewise tensor and a callable source."""
    ref_pb = gradvi.Problem.from_file(root / "problems" / "signorini-layers.toml")
    mesh = ref_pb.mesh()
    assert mesh is not None and mesh.n_cells > 0
    ref = gradvi.solve(mesh, ref_pb)

    def diffusion(x, y):
        a = np.zeros((x.size, 2, 2))
        left = x < 1
        a[left] = np.eye(2)
        a[~left] = [[10.0, 3.0], [3.0, 2.0]]
        return a

    pb = gradvi.Problem(
        source=lambda x, y: 10 * np.sin(np.pi * x),
        diffusion=diffusion,
        boundary={"dirichlet": [1], "neumann": [2], "signorini": [3]},
        signorini=0.0,
        side="upper",
    )
    for scheme in ("hmm", "p1"):
        a, b = gradvi.solve(mesh, ref_pb, scheme=scheme), gradvi.solve(mesh, pb, scheme=scheme)
        np.testing.assert_allclose(b.u, a.u, rtol=0, atol=1e-12 * np.abs(a.u).max())
        np.testing.assert_array_equal(b.active, a.active)
        assert b.niter == a.niter
    assert ref.constraint == ("signorini", "upper") and 0 < ref.n_active < ref.constrained_dofs.size
    # the same partition given by predicates and 'rest'
    pb2 = gradvi.Problem(
        source=lambda x, y: 10 * np.sin(np.pi * x), diffusion=diffusion,
        boundary={"dirichlet": lambda x, y: y > 1 - 1e-9, "signorini": lambda x, y: y < 1e-9, "neumann": "rest"},
        signorini=0.0, side="upper",
    )
    np.testing.assert_array_equal(gradvi.solve(mesh, pb2).u, gradvi.solve(mesh, pb).u)


def test_ex9_file_equals_python(root):
    pf = gradvi.Problem.from_file(root / "problems" / "ex9.toml")
    mesh = pf.mesh()
    a, b = gradvi.solve(mesh, pf), gradvi.solve(mesh, make_ex9())
    np.testing.assert_allclose(b.u, a.u, rtol=0, atol=1e-13)
    assert b.errors["l2_u"] == pytest.approx(a.errors["l2_u"], rel=1e-10)
    assert b.errors["l2_grad"] == pytest.approx(a.errors["l2_grad"], rel=1e-10)


def test_linear_problem_with_exact_solution():
    """FVCA5 test 1.1 (anisotropic A, no barrier): Python data equal the built-in, errors too."""
    A = np.array([[1.5, 0.5], [0.5, 1.5]])
    u = lambda x, y: 16 * x * (1 - x) * y * (1 - y)  # noqa: E731
    grad = lambda x, y: (16 * (1 - 2 * x) * y * (1 - y), 16 * x * (1 - x) * (1 - 2 * y))  # noqa: E731

    def f(x, y):
        uxx, uyy = -32 * y * (1 - y), -32 * x * (1 - x)
        uxy = 16 * (1 - 2 * x) * (1 - 2 * y)
        return -(A[0, 0] * uxx + 2 * A[0, 1] * uxy + A[1, 1] * uyy)

    pb = gradvi.Problem(source=f, diffusion=A, exact=u, exact_grad=grad)
    m = gradvi.Mesh.generate("kershaw", 1)
    ref = gradvi.solve(m, gradvi.Problem.builtin("fvca5-1.1"))
    s = gradvi.solve(m, pb)
    assert s.method == "linear" and s.niter == 1 and s.constraint is None
    np.testing.assert_allclose(s.u, ref.u, rtol=0, atol=1e-13)
    assert s.errors["l2_u"] == pytest.approx(ref.errors["l2_u"], rel=1e-9)
    assert s.errors["l2_u"] < 0.05


def test_tensor_forms_agree():
    m = gradvi.Mesh.generate("hexagonal", 1)
    ref = gradvi.solve(m, gradvi.Problem(source=1.0, diffusion=[[2.0, 0.5], [0.5, 1.0]]))
    for a in (
        lambda x, y: [[2.0, 0.5], [0.5, 1.0]],
        lambda x, y: [[2.0 + 0 * x, 0.5], [0.5, 1.0]],
        lambda x, y: np.broadcast_to([[2.0, 0.5], [0.5, 1.0]], (x.size, 2, 2)),
        gradvi.CellData(np.broadcast_to([[2.0, 0.5], [0.5, 1.0]], (m.n_cells, 2, 2))),
    ):
        np.testing.assert_array_equal(gradvi.solve(m, gradvi.Problem(source=1.0, diffusion=a)).u, ref.u)


def test_boundary_data_as_edge_and_vertex_arrays():
    m = gradvi.Mesh.generate("cartesian", 2)
    g = lambda x, y: x + 2 * y  # noqa: E731 (affine: HMM and P1 reproduce it exactly)
    ref = gradvi.solve(m, gradvi.Problem(dirichlet=g))
    np.testing.assert_allclose(ref.u_cell, g(*m.centroids.T), atol=1e-12)
    e = gradvi.Problem(dirichlet=gradvi.EdgeData(g(*m.edge_midpoints.T)))
    v = gradvi.Problem(dirichlet=gradvi.VertexData(g(*m.points.T)))
    np.testing.assert_allclose(gradvi.solve(m, e).u, ref.u, atol=1e-13)
    np.testing.assert_allclose(gradvi.solve(m, v).u, ref.u, atol=1e-13)
