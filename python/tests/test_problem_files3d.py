"""The 3D problem files of problems/ from Python: their meshes built as `gradvi solve` builds
them, the same solves as the command line (NITER, iteration log, active set, errors and u_K
to round-off), the boundary VTU file, and the dimension mismatches as the command line's
errors."""
import json
import subprocess

import numpy as np
import pytest
from conftest import ROOT, cli_binary

import gradvi

import meshio

#: The 3D examples, each with a 3D family and a scheme (the file's level and domain are kept).
CASES = [
    ("ex9-3d", "cubes", "hmm"),
    ("ex9-3d", "kuhn", "p1"),
    ("ex9-3d", "kuhn", "cr"),
    ("poisson-3d", "cubes", "hmm"),
    ("poisson-3d", "kuhn", "p1"),
    ("disk-obstacle-3d", "cubes", "hmm"),
]


def run_cli(tmp_path, *args):
    """`gradvi solve ARGS --json --vtu` in the repository: (the JSON summary, the VTU path)."""
    exe = cli_binary()
    assert exe is not None, "the gradvi binary is missing: run `make build` (make python-test does)"
    js, vtu = tmp_path / "cli.json", tmp_path / "cli.vtu"
    r = subprocess.run([exe, "solve", *args, "--json", str(js), "--vtu", str(vtu)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(js.read_text()), vtu


def cli_error(*args):
    """The error message of a failing `gradvi solve ARGS` (its stderr without "error: ")."""
    r = subprocess.run([cli_binary(), "solve", *args], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode != 0
    return r.stderr.strip().removeprefix("error: ")


def assert_close(a, b, what):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, what
    scale = max(np.abs(b).max(), 1e-300)
    assert np.abs(a - b).max() <= 1e-12 * scale, (what, np.abs(a - b).max() / scale)


def assert_same_solve(sol, cli, vtu):
    """`sol` (Python) and the command line's JSON summary and VTU file agree."""
    assert sol.niter == cli["niter"]
    assert sol.n_unknowns == cli["n_unknowns"]
    assert sol.n_active == cli["n_active"]
    assert len(sol.constrained_dofs) == cli["n_constrained"]
    assert [(e.active, e.entered, e.left) for e in sol.log] == [(e["active"], e["entered"], e["left"]) for e in cli["log"]]
    for k in ("l2_u", "l2_grad"):
        assert sol.errors[k] == pytest.approx(cli["errors"][k], rel=1e-12, abs=0.0), k
    assert_close(sol.u_cell, meshio.read(vtu).cell_data["u_K"][0], "u_K")


@pytest.mark.parametrize("name, family, scheme", CASES)
def test_3d_problem_files_solve_as_on_the_command_line(tmp_path, name, family, scheme):
    path = ROOT / "problems" / f"{name}.toml"
    cli, vtu = run_cli(tmp_path, f"problems/{name}.toml", "--generate", family, "--scheme", scheme)
    pb = gradvi.Problem.from_file(path)
    own = pb.mesh()
    assert isinstance(own, gradvi.Mesh3)
    # the file's domain and level, on the family of the command line
    mesh = gradvi.Mesh3.generate(family, 2, domain=own.bounding_box)
    assert mesh.n_cells == cli["n_cells"]
    assert mesh.h == pytest.approx(cli["h"], rel=1e-15)
    sol = gradvi.solve(mesh, pb, scheme=scheme)
    assert sol.certificate.ok(1e-10)
    assert_same_solve(sol, cli, vtu)
    # the boundary surface: the same values in both files
    sol.write_vtu(tmp_path / "py.vtu")
    mine, theirs = meshio.read(tmp_path / "py_boundary.vtu"), meshio.read(tmp_path / "cli_boundary.vtu")
    assert set(mine.cell_data) == set(theirs.cell_data) >= {"face", "boundary_tag"}
    assert set(mine.point_data) == set(theirs.point_data) >= {"u_vertex"}
    for k in mine.cell_data:
        assert_close(np.concatenate(mine.cell_data[k]), np.concatenate(theirs.cell_data[k]), k)
    for k in theirs.point_data:
        assert_close(mine.point_data[k], theirs.point_data[k], k)


@pytest.mark.parametrize("name", ["ex9-3d", "poisson-3d"])
def test_the_mesh_of_a_3d_file_is_the_command_lines(tmp_path, name):
    """`gradvi.solve(None, problem)` solves on the file's own [mesh] (a generated 3D family),
    as `gradvi solve FILE` does."""
    cli, vtu = run_cli(tmp_path, f"problems/{name}.toml")
    pb = gradvi.Problem.from_file(ROOT / "problems" / f"{name}.toml")
    sol = gradvi.solve(None, pb)
    assert isinstance(sol.mesh, gradvi.Mesh3) and sol.mesh.n_cells == cli["n_cells"]
    assert_same_solve(sol, cli, vtu)
    assert pb.has_exact and pb.parameters == cli["problem_file"]["parameters"]
    assert pb.constraint == (("obstacle", "lower") if name == "ex9-3d" else None)


def test_a_3d_mesh_file_named_by_a_problem_file_is_read_as_3d(tmp_path):
    """A problem file whose [mesh] names a 3D .vtu file: Problem.mesh() is a Mesh3, and the
    solve is the command line's."""
    gradvi.Mesh3.generate("kuhn", 1).write_vtu(tmp_path / "m.vtu")
    toml = tmp_path / "p.toml"
    toml.write_text('[mesh]\nfile = "m.vtu"\n[source]\nf = "x*z"\n[exact]\nu = "0"\ngrad = ["0", "0", "0"]\n')
    pb = gradvi.Problem.from_file(toml)
    mesh = pb.mesh()
    assert isinstance(mesh, gradvi.Mesh3) and mesh.n_cells == 6 * 4**3
    cli, vtu = run_cli(tmp_path, str(toml), "--scheme", "cr")
    sol = gradvi.solve(None, pb, scheme="cr")
    assert sol.niter == cli["niter"] == 1
    assert_close(sol.u_cell, meshio.read(vtu).cell_data["u_K"][0], "u_K")


# ------------------------------------------------------------------------------ mismatches


def test_a_3d_file_on_a_planar_mesh_is_the_command_lines_error(tmp_path):
    toml = tmp_path / "xz.toml"
    toml.write_text('[source]\nf = "x*z"\n')
    want = cli_error(str(toml), "--generate", "cartesian", "--level", "1")
    assert ":2:8: source.f:" in want and "'z'" in want
    with pytest.raises(gradvi.ProblemFileError) as e:
        gradvi.solve(gradvi.Mesh.generate("cartesian", 1), gradvi.Problem.from_file(toml), scheme="hmm")
    assert str(e.value) == want
    # ex9-3d (x, y, z) on a planar mesh
    with pytest.raises(gradvi.ProblemFileError, match="unknown variable 'z'"):
        gradvi.solve(gradvi.Mesh.generate("cartesian", 1), gradvi.Problem.from_file(ROOT / "problems" / "ex9-3d.toml"))


def test_a_planar_file_on_a_3d_mesh_is_the_command_lines_error(tmp_path):
    toml = tmp_path / "a2.toml"
    toml.write_text("[diffusion]\nA = [[1, 0], [0, 1]]\n")
    want = cli_error(str(toml), "--generate", "cubes", "--level", "1")
    assert ":2:5: diffusion.A: a 2x2 tensor on a 3D mesh" in want
    with pytest.raises(gradvi.ProblemFileError) as e:
        gradvi.solve(gradvi.Mesh3.generate("cubes", 1), gradvi.Problem.from_file(toml), scheme="hmm")
    assert str(e.value) == want


def test_builtin_problems_on_a_3d_mesh_are_the_command_lines(tmp_path):
    """The built-in problems are planar files; those that compile in 3D (test3: f = C and a
    barrier in x, y) solve on a 3D mesh as `gradvi solve --problem` does, the others (fvca5-1.1:
    a 2×2 tensor) raise its error."""
    cli, vtu = run_cli(tmp_path, "--problem", "test3", "--param", "C=-20", "--generate", "cubes", "--level", "1")
    sol = gradvi.solve(gradvi.Mesh3.generate("cubes", 1), gradvi.Problem.builtin("test3", C=-20), scheme="hmm")
    assert sol.niter == cli["niter"] and sol.n_active == cli["n_active"] > 0
    assert_close(sol.u_cell, meshio.read(vtu).cell_data["u_K"][0], "u_K")
    want = cli_error("--problem", "fvca5-1.1", "--generate", "cubes", "--level", "1")
    with pytest.raises(gradvi.ProblemFileError) as e:
        gradvi.solve(gradvi.Mesh3.generate("cubes", 1), gradvi.Problem.builtin("fvca5-1.1"), scheme="hmm")
    assert str(e.value) == want and "on a 3D mesh" in want


# ------------------------------------------------------------------------------ boundary VTU

#: A Signorini problem on the unit cube: contact on the part x < 1/2 of the bottom face (shared
#: with cli/tests/solve3d.rs).
SIGNORINI_CONTACT = (ROOT / "tests" / "data" / "signorini-contact-3d.toml").read_text()


def test_the_boundary_vtu_of_a_signorini_file(tmp_path):
    toml = tmp_path / "contact.toml"
    toml.write_text(SIGNORINI_CONTACT)
    cli, _ = run_cli(tmp_path, str(toml), "--generate", "cubes", "--level", "1")
    mesh = gradvi.Mesh3.generate("cubes", 1)
    sol = gradvi.solve(mesh, gradvi.Problem.from_file(toml), scheme="hmm")
    assert sol.niter == cli["niter"] and sol.n_active == cli["n_active"] == 8
    sol.write_vtu(tmp_path / "s.vtu")
    for path in (tmp_path / "s_boundary.vtu", tmp_path / "cli_boundary.vtu"):
        b = meshio.read(path)
        bf = mesh.boundary_faces
        assert all(c.type == "polygon" for c in b.cells)
        assert sum(len(c.data) for c in b.cells) == len(bf) == 96
        face = np.concatenate(b.cell_data["face"])
        np.testing.assert_array_equal(face, bf)
        active = np.concatenate(b.cell_data["active"])
        np.testing.assert_array_equal(active > 0.5, sol.active_faces[bf])
        assert int(active.sum()) == sol.n_active
        lam = np.zeros(mesh.n_faces)
        lam[sol.dof_index[sol.constrained_dofs]] = sol.multiplier
        assert_close(np.concatenate(b.cell_data["multiplier"]), lam[bf], "multiplier")
        u_face = np.concatenate(b.cell_data["u_face"])
        assert_close(u_face, sol.u_face[bf], "u_face")


# ------------------------------------------------------------------------- all-faces VTU


def test_the_faces_vtu_is_the_command_lines(tmp_path):
    """`write_vtu(..., faces=True)` writes NAME_faces.vtu as `gradvi solve --vtu --vtu-faces`
    does: every face of the mesh, interior ones included, with the same arrays and values."""
    toml = tmp_path / "contact.toml"
    toml.write_text(SIGNORINI_CONTACT)
    run_cli(tmp_path, str(toml), "--generate", "cubes", "--level", "1", "--vtu-faces")
    mesh = gradvi.Mesh3.generate("cubes", 1)
    sol = gradvi.solve(mesh, gradvi.Problem.from_file(toml), scheme="hmm")
    sol.write_vtu(tmp_path / "s.vtu", faces=True)
    assert (tmp_path / "s_boundary.vtu").exists()
    ours, theirs = meshio.read(tmp_path / "s_faces.vtu"), meshio.read(tmp_path / "cli_faces.vtu")
    assert [c.type for c in ours.cells] == ["polygon"] and len(ours.cells[0].data) == mesh.n_faces == 240
    np.testing.assert_array_equal(ours.cell_data["face"][0], np.arange(mesh.n_faces))
    np.testing.assert_array_equal(ours.points, theirs.points)
    np.testing.assert_array_equal(ours.cells[0].data, theirs.cells[0].data)
    for f in (0, 100, 239):
        np.testing.assert_array_equal(ours.points[ours.cells[0].data[f]], mesh.points[mesh.face_vertices(f)])
    assert set(ours.cell_data) == set(theirs.cell_data) == {"face", "boundary_tag", "u_face", "active", "multiplier"}
    assert set(ours.point_data) == set(theirs.point_data) == {"u_vertex"}
    for name in ours.cell_data:
        assert_close(ours.cell_data[name][0], theirs.cell_data[name][0], name)
    assert_close(ours.point_data["u_vertex"], theirs.point_data["u_vertex"], "u_vertex")
    # u_σ on every face; the contact zone on the bottom only
    np.testing.assert_array_equal(ours.cell_data["u_face"][0], sol.u_face)
    active = ours.cell_data["active"][0]
    np.testing.assert_array_equal(active > 0.5, sol.active_faces)
    assert int(active.sum()) == sol.n_active == 8
    # not written unless asked for
    sol.write_vtu(tmp_path / "plain.vtu")
    assert (tmp_path / "plain_boundary.vtu").exists() and not (tmp_path / "plain_faces.vtu").exists()


def test_the_faces_vtu_is_refused_on_a_planar_mesh_as_on_the_command_line(tmp_path):
    sol = gradvi.solve(gradvi.Mesh.generate("cartesian", 1), gradvi.Problem.builtin("test1"))
    with pytest.raises(gradvi.InvalidDataError) as e:
        sol.write_vtu(tmp_path / "flat.vtu", faces=True)
    assert list(tmp_path.iterdir()) == [], "nothing is written"
    vtu = tmp_path / "c.vtu"
    want = cli_error("--problem", "test1", "--generate", "cartesian", "--level", "1", "--vtu", str(vtu), "--vtu-faces")
    assert not vtu.exists()
    # the same message, the option named as each interface names it
    ours, theirs = str(e.value).removeprefix("faces=True "), want.removeprefix("--vtu-faces ")
    assert ours.split("; the mesh ")[0] == theirs.split("; the mesh ")[0] == "writes the faces of a 3D mesh"
    assert ours.endswith(" is 2D") and theirs.endswith(" is 2D")
