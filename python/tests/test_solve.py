"""Solving: the paper's Test 3 from Python equals the command line and the committed results;
warm starts, options and outputs."""
import csv
import json
import shutil
import subprocess

import numpy as np
import pytest
from conftest import ROOT, cli_binary, make_test3

import gradvi

import meshio


def test_test3_equals_cli(tmp_path, test3_mesh):
    """`gradvi solve --problem test3 --param C=-20 --mesh meshes/test3_1.msh --json --vtu` and the
    same solve from Python (built-in problem, and built from callables): same NITER, log,
    active set, certificate, and u_K to the last digit the VTU file holds."""
    exe = cli_binary()
    assert exe is not None, "the gradvi binary is missing: run `make build` (make python-test does)"
    js, vtu = tmp_path / "out.json", tmp_path / "out.vtu"
    subprocess.run(
        [exe, "solve", "--problem", "test3", "--param", "C=-20", "--mesh", "meshes/test3_1.msh", "--json", str(js), "--vtu", str(vtu)],
        cwd=ROOT, check=True, capture_output=True,
    )
    cli = json.loads(js.read_text())
    u_k = np.asarray(meshio.read(vtu).cell_data["u_K"][0])
    for pb in (gradvi.Problem.builtin("test3", C=-20), make_test3(-20.0)):
        sol = gradvi.solve(test3_mesh, pb, scheme="hmm")
        assert sol.niter == cli["niter"]
        assert sol.n_active == cli["n_active"]
        assert sol.n_unknowns == cli["n_unknowns"]
        assert [(e.active, e.entered, e.left) for e in sol.log] == [(e["active"], e["entered"], e["left"]) for e in cli["log"]]
        mine = sol.certificate.as_dict()
        for k in ("max_violation", "min_multiplier", "complementarity", "balance_residual"):
            assert mine[k] == cli["certificate"][k], k
        np.testing.assert_array_equal(sol.u_cell, u_k)


def test_test3_equals_committed_results():
    """Every row of replication/results/test3.csv (4 meshes, 4 values of C, each scheme):
    NITER, the size of the active set and the contact area, from Python data."""
    rows = list(csv.DictReader(open(ROOT / "replication" / "results" / "test3.csv")))
    assert len(rows) >= 32
    meshes = {}
    problems = {}
    for r in rows:
        mesh = meshes.setdefault(r["mesh"], gradvi.Mesh.read(ROOT / "meshes" / f"{r['mesh']}.msh"))
        assert mesh.n_cells == int(r["n_cells"])
        c = float(r["c"])
        pb = problems.setdefault(c, make_test3(c))
        sol = gradvi.solve(mesh, pb, scheme=r["scheme"], warm_start="cold")  # the paper's NITER
        assert sol.certificate.ok(1e-10)
        assert sol.niter == int(r["niter"]), r
        assert sol.n_active == int(r["n_active"]), r
        assert sol.contact_measure == pytest.approx(float(r["contact_area"]), rel=1e-12), r


def test_nested_warm_start_gives_the_same_solution(root):
    mesh = gradvi.Mesh.read(root / "meshes" / "test3_3.msh")
    cold = gradvi.solve(mesh, make_test3(-5.0), warm_start="cold")
    warm = gradvi.solve(mesh, make_test3(-5.0), warm_start="nested")
    assert warm.warm_start is not None and warm.warm_start["skipped"] is None
    assert warm.untabulated_points > 0 and warm.fallback_calls > 0  # the coarse meshes' points
    np.testing.assert_array_equal(warm.active, cold.active)
    np.testing.assert_allclose(warm.u, cold.u, rtol=0, atol=1e-12)
    assert warm.niter <= cold.niter
    # with array data there is nothing to evaluate on the coarse meshes: the warm start is
    # skipped, with the reason, and the solve goes on cold
    arr = gradvi.Problem(source=gradvi.CellData(np.full(mesh.n_cells, -5.0)), obstacle=gradvi.CellData(
        -np.minimum.reduce([mesh.centroids[:, 0], 1 - mesh.centroids[:, 0], mesh.centroids[:, 1], 1 - mesh.centroids[:, 1]])), side="lower")
    s = gradvi.solve(mesh, arr, warm_start="nested")
    assert s.warm_start["skipped"]
    np.testing.assert_array_equal(s.u, cold.u)


def test_iterative_linear_solver_gives_the_direct_solution(root):
    mesh = gradvi.Mesh.read(root / "meshes" / "test3_3.msh")
    d = gradvi.solve(mesh, make_test3(-5.0), linear="direct")
    i = gradvi.solve(mesh, make_test3(-5.0), linear="iterative")
    assert d.certificate.ok(1e-10) and i.certificate.ok(1e-10)
    np.testing.assert_array_equal(i.active, d.active)
    np.testing.assert_allclose(i.u, d.u, rtol=0, atol=1e-8 * np.abs(d.u).max())
    # a screened iterate has no balance residual (evaluated on the constrained unknowns only),
    # the last, exact one has; every direct iterate has
    assert all(e.residual is not None for e in d.log)
    assert i.log[-1].residual is not None and i.log[-1].residual <= 1e-10
    screened = [e for e in i.log if e.residual is None]
    assert len(i.log) > 1 and screened, [e.residual for e in i.log]
    assert sum(line.endswith(" -") for line in i.summary().splitlines()) == len(screened)


def test_solution_arrays_and_outputs(tmp_path, test3_mesh):
    m = test3_mesh
    for scheme, kind in (("hmm", "cell"), ("p1", "vertex"), ("cr", "edge")):
        sol = gradvi.solve(m, make_test3(-10.0), scheme=scheme, keep_iterates=True)
        n = sol.n_unknowns
        assert sol.u.shape == (n,) and sol.dof_kind.shape == (n,) and sol.dof_index.shape == (n,)
        assert sol.u_cell.shape == (m.n_cells,) and sol.u_vertex.shape == (m.n_vertices,)
        assert sol.gradient.shape == (m.n_cells, 2)
        assert set(sol.dof_kind[sol.constrained_dofs]) == {kind}
        assert len(sol.log) == sol.niter == len(sol.iterates)
        np.testing.assert_array_equal(sol.iterates[-1], sol.u)
        a = sol.active
        # complementarity: u = ψ where active, λ = 0 where inactive
        np.testing.assert_allclose(sol.u[sol.constrained_dofs][a], sol.barrier[a], atol=1e-14)
        scale = np.abs(sol.multiplier).max()
        assert np.abs(sol.multiplier[~a]).max() < 1e-12 * scale and (sol.multiplier[a] >= -1e-12 * scale).all()
        assert sol.contact_measure == pytest.approx(sol.constrained_measures[a].sum(), rel=1e-12)
        plural = {"cell": "cells", "vertex": "vertices", "edge": "edges"}[kind]
        assert getattr(sol, f"active_{plural}").sum() == sol.n_active
        assert set(sol.timings) >= {"data", "setup", "factor", "solve", "total"}
        assert len(sol.free_boundary) > 0
        assert "NITER" in sol.summary()
        # output: gradvi's VTU read by meshio, and the meshio mesh
        sol.write_vtu(tmp_path / f"{scheme}.vtu")
        back = meshio.read(tmp_path / f"{scheme}.vtu")
        np.testing.assert_array_equal(np.concatenate(back.cell_data["u_K"]), sol.u_cell)
        mm = sol.to_meshio()
        np.testing.assert_array_equal(mm.point_data["u_vertex"], sol.u_vertex)
        mm.write(tmp_path / f"{scheme}_meshio.vtu")


def test_options():
    m = gradvi.Mesh.generate("cartesian", 2)
    pb = make_test3(-20.0)
    base = gradvi.solve(m, pb)
    for kw in ({"ordering": "nested-dissection"}, {"factor_threads": "global"}, {"c": 10.0}, {"alpha": 1.0}):
        np.testing.assert_allclose(gradvi.solve(m, pb, **kw).u, base.u, atol=1e-12)
    other = gradvi.solve(m, pb, alpha=2.0)
    assert other.certificate.ok() and not np.array_equal(other.u, base.u)
    # an initial active set: the solution does not change, NITER may
    s = gradvi.solve(m, pb, initial_active=base.active)
    np.testing.assert_array_equal(s.active, base.active)
    assert s.niter == 1
    # a problem file with a [mesh] section needs no mesh
    ex9 = gradvi.solve(None, ROOT / "problems" / "ex9.toml")
    assert ex9.errors is not None and ex9.mesh.n_cells == 1024
    # a built-in name and a mesh path
    assert gradvi.solve(str(ROOT / "meshes" / "test3_1.msh"), "test3", warm_start="cold").niter == 8


def test_solution_attributes_are_declared_and_typed(test3_mesh):
    """Every documented field of a Solution and its Certificate is an attribute declared on the
    class (no dynamic lookup): present, of its type, and an unknown name is an AttributeError."""
    import dataclasses
    import typing

    sol = gradvi.solve(test3_mesh, make_test3(-20.0))
    properties = {n for n, v in vars(gradvi.Solution).items() if isinstance(v, property)}
    documented = {
        "u", "u_cell", "u_vertex", "u_edge", "gradient", "dof_kind", "dof_index", "n_unknowns", "n_condensed",
        "u_exact_cell", "constraint", "constrained_dofs", "constrained_points", "constrained_measures", "barrier",
        "multiplier", "active", "active_set", "n_active", "multiplier_field", "active_field", "active_cells",
        "active_vertices", "active_edges", "contact_measure", "free_boundary", "u_face", "active_faces", "dim",
    }
    assert documented <= properties
    assert "__getattr__" not in vars(gradvi.Solution) and "__getattr__" not in vars(gradvi.Certificate)
    # the plain attributes are declared (typed) on the class
    plain = {"mesh", "problem", "certificate", "niter", "method", "log", "timings", "errors", "warm_start", "scheme",
             "untabulated_points", "fallback_calls", "iterates"}
    hints = typing.get_type_hints(gradvi.Solution)
    assert plain <= set(hints)
    assert hints["niter"] is int and hints["certificate"] is gradvi.Certificate
    assert hints["mesh"] == typing.Union[gradvi.Mesh, gradvi.Mesh3]
    for name in documented | plain:
        assert hasattr(sol, name), name
    assert typing.get_type_hints(gradvi.Solution.n_active.fget)["return"] is int
    assert isinstance(sol.niter, int) and isinstance(sol.n_active, int) and isinstance(sol.contact_measure, float)
    with pytest.raises(AttributeError):
        sol.n_iterations
    with pytest.raises(AttributeError):
        sol.n_iterations = 3  # no attribute beyond the declared ones
    # the certificate: one typed field per field of the library's certificate
    c = sol.certificate
    names = [f.name for f in dataclasses.fields(gradvi.Certificate)]
    assert names == ["max_violation", "min_multiplier", "complementarity", "balance_residual", "data_magnitude"]
    assert all(typing.get_type_hints(gradvi.Certificate)[n] is float for n in names)
    assert c.as_dict() == {n: getattr(c, n) for n in names} and all(isinstance(getattr(c, n), float) for n in names)
    assert c.ok(1e-10) and c.worst() == max(c.max_violation, -c.min_multiplier, c.complementarity, c.balance_residual, 0.0)
    with pytest.raises(AttributeError):
        c.residual
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.max_violation = 0.0  # type: ignore[misc]
