"""Bad inputs raise gradvi.GradviError subclasses with the library's message (never a crash)."""
import resource
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT, make_test3, psi

import gradvi


def test_hierarchy():
    for cls in (gradvi.MeshIoError, gradvi.InvalidMeshError, gradvi.InvalidDataError, gradvi.InfeasibleError,
                gradvi.LinearSolverError, gradvi.IllPosedError, gradvi.SolverError, gradvi.ProblemFileError,
                gradvi.FileError, gradvi.InternalError, gradvi.OutOfMemoryError):
        assert issubclass(cls, gradvi.GradviError) and issubclass(cls, Exception)
    for cls in (gradvi.MaxIterationsError, gradvi.CyclingError, gradvi.NoKktPointError, gradvi.CertificateError):
        assert issubclass(cls, gradvi.SolverError)
    assert gradvi.GradviError.__module__ == "gradvi"
    # the two that are also built-in exceptions
    assert issubclass(gradvi.InvalidDataError, ValueError) and issubclass(gradvi.MeshIoError, OSError)
    assert gradvi.InvalidDataError.__module__ == "gradvi" and gradvi.MeshIoError.__module__ == "gradvi"
    assert not issubclass(gradvi.InvalidMeshError, (ValueError, OSError))
    assert issubclass(gradvi.OutOfMemoryError, MemoryError) and gradvi.OutOfMemoryError.__module__ == "gradvi"


_TOO_LARGE = """
import gradvi
try:
    gradvi.Mesh.generate("cartesian", 11)
except MemoryError as e:
    assert isinstance(e, gradvi.OutOfMemoryError) and isinstance(e, gradvi.GradviError), type(e)
    assert e.bytes > e.budget > 0 and "would need about" in str(e), str(e)
    print("refused:", e)
else:
    raise AssertionError("no error")
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS is a Linux limit")
def test_a_mesh_too_large_for_the_address_space_limit_is_a_memory_error(tmp_path):
    # in a child under a 3 GiB address-space limit: the budget sees it and refuses the 16.8M
    # cells of the level-11 Cartesian mesh by their estimate, before allocating them
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))

    # run from tmp_path, so that the installed gradvi is imported, not the sources beside the tests
    out = subprocess.run([sys.executable, "-c", _TOO_LARGE], preexec_fn=limit, capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)
    assert out.returncode == 0 and "refused:" in out.stdout, out.stderr


def test_builtin_bases_catch_the_library_errors(tmp_path):
    # raised by the library (through the bindings) and by the Python layer alike
    for bad in (lambda: gradvi.Mesh.generate("voronoi", 1), lambda: gradvi.Problem(obstacle=psi)):
        with pytest.raises(ValueError) as e:
            bad()
        assert isinstance(e.value, gradvi.InvalidDataError) and isinstance(e.value, gradvi.GradviError)
    bad = tmp_path / "bad.msh"
    bad.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\nnonsense\n")
    try:
        gradvi.Mesh.read(bad)
    except OSError as e:
        assert isinstance(e, gradvi.MeshIoError) and e.line > 0 and e.path.endswith("bad.msh")
        assert str(e).startswith(str(bad))
    else:
        raise AssertionError("no error")


def test_mesh_files(tmp_path):
    with pytest.raises(gradvi.FileError) as e:
        gradvi.Mesh.read(tmp_path / "missing.msh")
    assert e.value.path.endswith("missing.msh") and e.value.errno == 2
    bad = tmp_path / "bad.msh"
    bad.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\nnonsense\n")
    with pytest.raises(gradvi.MeshIoError) as e:
        gradvi.Mesh.read(bad)
    assert e.value.line > 0 and str(e.value).startswith(str(bad))
    with pytest.raises(gradvi.MeshIoError, match="unknown mesh format"):
        gradvi.Mesh.read(tmp_path / "mesh.obj")


def test_invalid_meshes():
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    with pytest.raises(gradvi.InvalidMeshError, match="refers to vertex 7"):
        gradvi.Mesh(square, [[0, 1, 7]])
    with pytest.raises(gradvi.InvalidMeshError, match="used by no cell"):
        gradvi.Mesh(square, [[0, 1, 2]])
    with pytest.raises(gradvi.InvalidMeshError):  # a bow tie
        gradvi.Mesh(square, [[0, 2, 1, 3]])
    with pytest.raises(gradvi.InvalidMeshError, match="non-finite"):
        gradvi.Mesh([(0, 0), (1, np.nan), (1, 1)], [[0, 1, 2]])
    with pytest.raises(gradvi.InvalidMeshError, match="not a boundary edge"):
        gradvi.Mesh(square, [[0, 1, 2], [0, 2, 3]], boundary_tags=[(0, 2, 5)])
    with pytest.raises(gradvi.InvalidDataError):
        gradvi.Mesh(np.zeros((3, 4)), [[0, 1, 2]])
    with pytest.raises(gradvi.InvalidDataError):
        gradvi.Mesh(square, [[0, 1, -2]])
    with pytest.raises(gradvi.InvalidDataError, match="offsets"):
        gradvi.Mesh(square, (np.array([0, 10, 3]), np.array([0, 1, 2])))
    with pytest.raises(gradvi.InvalidDataError, match="varying z"):
        gradvi.Mesh([(0, 0, 0), (1, 0, 1), (1, 1, 0)], [[0, 1, 2]])
    with pytest.raises(gradvi.InvalidDataError, match="unknown mesh family"):
        gradvi.Mesh.generate("voronoi", 1)
    for level in (0, -1, 99):
        with pytest.raises(gradvi.InvalidDataError, match="level"):
            gradvi.Mesh.generate("cartesian", level)


def test_bad_options(test3_mesh):
    pb = gradvi.Problem.builtin("test3")
    for kw, match in (
        ({"scheme": "fem"}, "unknown scheme"),
        ({"tol": 2.0}, "tol"),
        ({"tol": float("nan")}, "tol"),
        ({"c": -1.0}, "c must be positive"),
        ({"max_solves": 0}, "max_solves"),
        ({"warm_start": "hot"}, "warm start"),
        ({"ordering": "metis"}, "ordering"),
        ({"linear": "gmres"}, "linear solver"),
        ({"alpha": -1.0}, "alpha"),
        ({"scheme": "p1", "alpha": 2.0}, "alpha"),
    ):
        with pytest.raises(gradvi.InvalidDataError, match=match):
            gradvi.solve(test3_mesh, pb, **kw)
    with pytest.raises(gradvi.InvalidDataError, match="unknown problem"):
        gradvi.Problem.builtin("test9")
    # built-ins are problem files: an unknown parameter is the file's Parameter error
    with pytest.raises(gradvi.ProblemFileError, match="no parameter 'C'"):
        gradvi.Problem.builtin("test1", C=1)
    # P1 needs triangles
    with pytest.raises(gradvi.GradviError, match="triang"):
        gradvi.solve(gradvi.Mesh.generate("hexagonal", 1), pb, scheme="p1")


def test_problem_files(tmp_path):
    with pytest.raises(gradvi.FileError):
        gradvi.Problem.from_file(tmp_path / "none.toml")
    p = tmp_path / "bad.toml"
    p.write_text('name = "x"\n[source]\nf = "sin(x"\n')
    with pytest.raises(gradvi.ProblemFileError) as e:
        gradvi.Problem.from_file(p)
    assert e.value.line == 3 and e.value.kind == "expression" and e.value.path.endswith("bad.toml")
    p.write_text('[sourse]\nf = 1\n')
    with pytest.raises(gradvi.ProblemFileError) as e:
        gradvi.Problem.from_file(p)
    assert e.value.kind == "unknown_key"
    with pytest.raises(gradvi.ProblemFileError, match="C"):
        gradvi.Problem.from_file(ROOT / "problems" / "test3.toml", D=1.0)
    # a tag the mesh does not carry: checked against the mesh at solve time
    with pytest.raises(gradvi.ProblemFileError) as e:
        gradvi.solve(gradvi.Mesh.generate("cartesian", 1), ROOT / "problems" / "signorini-layers.toml")
    assert e.value.kind == "tag"


def test_bad_python_data(test3_mesh):
    m = test3_mesh
    with pytest.raises(gradvi.InvalidDataError, match="side"):
        gradvi.Problem(obstacle=psi)
    with pytest.raises(gradvi.InvalidDataError, match="not both"):
        gradvi.Problem(obstacle=psi, signorini=0.0, side="lower")
    with pytest.raises(gradvi.InvalidDataError, match="boundary"):
        gradvi.Problem(signorini=0.0, side="upper")
    # NaN data: the library names the datum and the cell
    with pytest.raises(gradvi.InvalidDataError, match="source term f is not finite in cell"):
        gradvi.solve(m, gradvi.Problem(source=lambda x, y: np.where(x > 0.5, np.nan, 1.0)))
    with pytest.raises(gradvi.InvalidDataError, match="barrier"), np.errstate(invalid="ignore"):
        gradvi.solve(m, gradvi.Problem(obstacle=lambda x, y: np.log(x - 0.5), side="lower"))
    # shapes
    with pytest.raises(gradvi.InvalidDataError, match="returned shape"):
        gradvi.solve(m, gradvi.Problem(source=lambda x, y: np.ones(3)))
    with pytest.raises(gradvi.InvalidDataError, match="ambiguous|not per cell"):
        gradvi.solve(m, gradvi.Problem(source=np.ones(5)))
    with pytest.raises(gradvi.InvalidDataError, match="CellData must have shape"):
        gradvi.solve(m, gradvi.Problem(source=gradvi.CellData(np.ones(5))))
    # a tensor that is not positive definite
    with pytest.raises(gradvi.InvalidDataError, match="positive definite"):
        gradvi.solve(m, gradvi.Problem(source=1.0, diffusion=lambda x, y: [[1.0, 2.0], [2.0, 1.0]]))
    # an exception in a callable propagates as it is, with a note naming the datum
    with pytest.raises(ZeroDivisionError):
        gradvi.solve(m, gradvi.Problem(source=lambda x, y: 1 / 0))
    # boundary rules that do not partition the boundary
    with pytest.raises(gradvi.InvalidDataError, match="selected by no part"):
        gradvi.solve(m, gradvi.Problem(boundary={"dirichlet": lambda x, y: y < 1e-9}))
    with pytest.raises(gradvi.InvalidDataError, match="selected by two parts"):
        gradvi.solve(m, gradvi.Problem(boundary={"dirichlet": 1, "neumann": lambda x, y: y < 1e-9}))
    with pytest.raises(gradvi.InvalidDataError, match="tag"):
        gradvi.solve(m, gradvi.Problem(boundary={"dirichlet": [1, 7]}))


def test_solver_failures(test3_mesh):
    # the Dirichlet value 1 above the upper barrier 0: the convex set is empty
    with pytest.raises(gradvi.InfeasibleError, match="discrete convex set is empty"):
        gradvi.solve(test3_mesh, gradvi.Problem(dirichlet=1.0, obstacle=0.0, side="upper"))
    # the iteration cap, with the history of active-set sizes
    with pytest.raises(gradvi.MaxIterationsError) as e:
        gradvi.solve(test3_mesh, make_test3(-20.0), max_solves=2)
    assert e.value.iterations == 2 and len(e.value.history) >= 2
    assert isinstance(e.value, gradvi.SolverError)
    # Neumann everywhere and no barrier: u is defined up to a constant
    with pytest.raises(gradvi.IllPosedError, match="additive constant"):
        gradvi.solve(gradvi.Mesh.generate("cartesian", 1), gradvi.Problem(source=1.0, boundary={"neumann": "rest"}))


def test_a_marginal_load_is_a_warning_or_named_in_the_error(tmp_path):
    # the example: the paper's Test 2 data on (−1,0)×(0.2,0.8), every edge Signorini
    # with the upper barrier 0; HMM refuses it, P1 solves it, both name the marginal load
    test2 = (ROOT / "problems" / "test2.toml").read_text()
    f = tmp_path / "marginal.toml"
    f.write_text(test2[: test2.index("[dirichlet]")] + '\n[signorini]\nside = "upper"\nbarrier = 0\n')
    pb = gradvi.Problem.from_file(f)
    domain = [-1.0, 0.0, 0.2, 0.8]
    with pytest.raises(gradvi.IllPosedError, match="marginal load"):
        gradvi.solve(gradvi.Mesh.generate("cartesian", 2, domain), pb, scheme="hmm")
    with pytest.warns(gradvi.MarginalLoadWarning, match="depends on the sign of that sum"):
        sol = gradvi.solve(gradvi.Mesh.generate("triangles", 2, domain), pb, scheme="p1")
    [part] = sol.marginal_load
    assert 0 < part["ratio"] < 0.1 and part["sum"] > 0
