"""3D solves from Python: problems built from callables of (x, y, z) on gradvi.Mesh3, solved with
HMM (the scheme the library has on polyhedra): exactness, convergence, an obstacle and a
Signorini problem with their certificates, output, and the typed errors of data that do not
fit the dimension."""
import numpy as np
import pytest

import gradvi

import meshio

#: An anisotropic constant tensor (symmetric positive definite).
A3 = np.array([[2.0, 0.3, 0.1], [0.3, 1.0, 0.2], [0.1, 0.2, 1.5]])


def affine(x, y, z):
    return 1.0 + 2.0 * x - y + 3.0 * z


# ------------------------------------------------------------------------------- exactness


@pytest.mark.parametrize("family", ["cubes", "kuhn"])
def test_affine_solution_is_reproduced_with_an_anisotropic_tensor(family):
    mesh = gradvi.Mesh3.generate(family, 1)
    pb = gradvi.Problem(
        diffusion=A3,
        dirichlet=affine,
        exact=affine,
        exact_grad=lambda x, y, z: (2.0, -1.0, 3.0),
    )
    sol = gradvi.solve(mesh, pb, scheme="hmm")
    assert sol.dim == 3 and sol.method == "linear"
    # every datum was read from the table evaluated once per callable, at the solve's points
    assert sol.untabulated_points == 0 and sol.fallback_calls == 0
    assert np.abs(sol.u_cell - affine(*mesh.centroids.T)).max() < 1e-10
    faces = mesh.face_centroids
    assert np.abs(sol.u_face - affine(*faces.T)).max() < 1e-10
    assert np.abs(sol.gradient - [2.0, -1.0, 3.0]).max() < 1e-9
    assert sol.errors["l2_u"] < 1e-12 and sol.errors["l2_grad"] < 1e-10
    assert sol.gradient.shape == (mesh.n_cells, 3)


# ------------------------------------------------------------------------------ convergence

# u = sin(πx) cos(πy/2) e^z, −Δu = (5π²/4 − 1) u, Dirichlet data from u on the unit cube.
K = 1.25 * np.pi**2 - 1.0


def smooth(x, y, z):
    return np.sin(np.pi * x) * np.cos(0.5 * np.pi * y) * np.exp(z)


def smooth_grad(x, y, z):
    e = np.exp(z)
    return (
        np.pi * np.cos(np.pi * x) * np.cos(0.5 * np.pi * y) * e,
        -0.5 * np.pi * np.sin(np.pi * x) * np.sin(0.5 * np.pi * y) * e,
        smooth(x, y, z),
    )


def smooth_problem():
    return gradvi.Problem(
        source=lambda x, y, z: K * smooth(x, y, z),
        dirichlet=smooth,
        exact=smooth,
        exact_grad=smooth_grad,
        name="smooth 3D",
    )


# The orders between levels 2 and 3 (h = 0.217, 0.108) were measured at 2.01 (u) and 1.97
# (gradient, superconvergent on cubes) on cubes, 1.97 and 1.00 on Kuhn tetrahedra; the bands
# are ±0.25 around them.
@pytest.mark.parametrize(
    "family, u_band, grad_band",
    [
        ("cubes", (1.76, 2.26), (1.72, 2.22)),
        ("kuhn", (1.72, 2.22), (0.75, 1.25)),
    ],
)
def test_linear_problem_converges_with_the_expected_orders(family, u_band, grad_band):
    pb = smooth_problem()
    runs = []
    for level in (2, 3):
        mesh = gradvi.Mesh3.generate(family, level)
        sol = gradvi.solve(mesh, pb, scheme="hmm")
        assert sol.certificate.ok(1e-10)
        runs.append((mesh.h, sol.errors))
    (h0, e0), (h1, e1) = runs
    assert e1["l2_u"] < e0["l2_u"] and e1["l2_grad"] < e0["l2_grad"]
    order_u = np.log(e0["l2_u"] / e1["l2_u"]) / np.log(h0 / h1)
    order_g = np.log(e0["l2_grad"] / e1["l2_grad"]) / np.log(h0 / h1)
    assert u_band[0] <= order_u <= u_band[1], (order_u, runs)
    assert grad_band[0] <= order_g <= grad_band[1], (order_g, runs)


# ------------------------------------------------------------------------------- obstacle

# The 3D radial obstacle (on (−1, 1)³ here, the (−2, 2)³ cut down to keep the meshes
# small): −Δu = 0, u ≥ ψ, ψ = sqrt(1 − r²) for r ≤ 1 and −1
# beyond; u = ψ for r ≤ r0 = 1/sqrt(2) and 1/(2r) beyond (harmonic in 3D; value and slope
# match ψ at r0); Dirichlet data from u. The contact set is the ball of radius r0.
R0 = 1.0 / np.sqrt(2.0)


def radial_psi(x, y, z):
    r2 = x * x + y * y + z * z
    return np.where(r2 <= 1.0, np.sqrt(np.maximum(1.0 - r2, 0.0)), -1.0)


def radial_exact(x, y, z):
    r = np.sqrt(x * x + y * y + z * z)
    return np.where(r <= R0, radial_psi(x, y, z), 0.5 / np.maximum(r, 1e-300))


def radial_grad(x, y, z):
    r2 = x * x + y * y + z * z
    inside = np.sqrt(r2) <= R0
    s = np.sqrt(np.where(inside, 1.0 - r2, 1.0))
    q = np.where(inside, 1.0, 0.5 / np.maximum(r2, 1e-300) ** 1.5)
    return tuple(np.where(inside, -c / s, -c * q) for c in (x, y, z))


@pytest.fixture(scope="module")
def radial_runs():
    pb = gradvi.Problem(
        obstacle=radial_psi,
        side="lower",
        dirichlet=radial_exact,
        exact=radial_exact,
        exact_grad=radial_grad,
        name="3D radial obstacle",
    )
    box = gradvi.Box(-1, 1, -1, 1, -1, 1)
    return [(lv, gradvi.solve(gradvi.Mesh3.generate("cubes", lv, domain=box), pb, scheme="hmm")) for lv in (2, 3)]


def test_obstacle_solution_is_certified(radial_runs):
    for _, sol in radial_runs:
        assert sol.constraint == ("obstacle", "lower")
        # only the nested start's coarse meshes read data off the tabulated points, through the
        # callables' point-wise fallback
        ws = sol.warm_start
        if ws is None or ws["skipped"] is not None:
            assert sol.untabulated_points == 0
        assert sol.untabulated_points == 0 or sol.fallback_calls > 0
        assert sol.certificate.ok(1e-10), sol.certificate
        assert sol.active_cells is not None and sol.active_cells.shape == (sol.mesh.n_cells,)
        u = sol.u[sol.constrained_dofs]
        psi = sol.barrier
        np.testing.assert_allclose(psi, radial_psi(*sol.constrained_points.T), rtol=0, atol=0)
        # u ≥ ψ, λ ≥ 0, u = ψ where active, λ = 0 where inactive
        assert (u - psi).min() > -1e-10
        assert sol.multiplier.min() >= -1e-12 * sol.multiplier.max()
        assert np.abs(u[sol.active] - psi[sol.active]).max() < 1e-12
        lam = sol.multiplier
        assert np.abs(lam[~sol.active]).max() < 1e-12 * lam.max()
        # the nested warm start is available in 3D: it ran, or says why it was skipped
        assert sol.warm_start is not None
        assert "not available" not in (sol.warm_start.get("skipped") or "")


def test_obstacle_errors_and_contact_volume_decrease(radial_runs):
    (_, s0), (_, s1) = radial_runs
    assert s1.errors["l2_u"] < s0.errors["l2_u"] and s1.errors["l2_grad"] < s0.errors["l2_grad"]
    # the contact volume tends to the ball's (measured: 43% off on level 2, 20% on level 3)
    ball = 4.0 / 3.0 * np.pi * R0**3
    gaps = [abs(s.contact_measure - ball) for s in (s0, s1)]
    assert gaps[1] < 0.6 * gaps[0] and gaps[1] < 0.25 * ball, gaps
    # the active cells lie in (a neighbourhood of) the ball of radius r0
    c = s1.mesh.centroids[s1.active_cells]
    assert np.sqrt((c**2).sum(axis=1)).max() < R0 + s1.mesh.h


# ------------------------------------------------------------------------------ Signorini


@pytest.fixture(scope="module")
def signorini():
    """On the unit cube: u = 0 on the top z = 1, zero flux on the sides and on the half
    y > 1/2 of the bottom, and on the other half of the bottom, z = 0 and y < 1/2 (tag 5),
    the Signorini condition u ≤ 0, A∇u·n ≤ 0; the source f = 10 sin(2πx) pushes u up where
    x < 1/2 (Γ3 touches the barrier there) and down where x > 1/2."""
    mesh = gradvi.Mesh3.generate("cubes", 2)
    c = mesh.face_centroids
    bottom = (np.abs(c[:, 2]) < 1e-12) & (c[:, 1] < 0.5)
    mesh = mesh.with_face_tags(np.where(bottom, 5, 0).astype(np.int32))
    pb = gradvi.Problem(
        source=lambda x, y, z: 10.0 * np.sin(2.0 * np.pi * x),
        diffusion=A3,
        boundary={"signorini": 5, "dirichlet": lambda x, y, z: z > 1.0 - 1e-12, "neumann": "rest"},
        signorini=0.0,
        side="upper",
        name="3D Signorini",
    )
    return mesh, gradvi.solve(mesh, pb, scheme="hmm")


def test_signorini_solution_is_certified_on_the_contact_face(signorini):
    mesh, sol = signorini
    assert sol.constraint == ("signorini", "upper")
    ws = sol.warm_start
    if ws is None or ws["skipped"] is not None:
        assert sol.untabulated_points == 0
    assert sol.untabulated_points == 0 or sol.fallback_calls > 0
    assert sol.certificate.ok(1e-10), sol.certificate
    # the constrained unknowns are the faces of Γ3, at their centroids
    pts = sol.constrained_points
    assert pts.shape == (int((mesh.face_tags == 5).sum()), 3) == (32, 3)
    assert np.abs(pts[:, 2]).max() == 0.0 and pts[:, 1].max() < 0.5
    u = sol.u[sol.constrained_dofs]
    assert u.max() < 1e-10
    assert np.abs(u[sol.active]).max() < 1e-12
    lam = sol.multiplier
    assert lam.min() >= -1e-12 * lam.max() and np.abs(lam[~sol.active]).max() < 1e-12 * lam.max()
    # contact where the source pushes up (its edge, near x = 0.3, bent by the anisotropy),
    # none where it pulls down
    x = pts[:, 0]
    assert sol.active[x < 0.25].all() and not sol.active[x > 0.4].any()
    assert sol.active_faces is not None and sol.active_faces.shape == (mesh.n_faces,)
    faces = sol.dof_index[sol.constrained_dofs]
    assert np.all(sol.dof_kind[sol.constrained_dofs] == "edge") and np.all(mesh.face_tags[faces] == 5)
    area = mesh.face_areas[faces][sol.active].sum()
    assert abs(sol.contact_measure - area) < 1e-12


def test_signorini_from_an_initial_active_set_gives_the_same_solution(signorini):
    mesh, sol = signorini
    again = gradvi.solve(mesh, sol.problem, scheme="hmm", warm_start="cold", initial_active=sol.active)
    assert again.niter == 1
    np.testing.assert_array_equal(again.active, sol.active)
    assert np.abs(again.u - sol.u).max() < 1e-10


def test_3d_solution_output(signorini, tmp_path):
    mesh, sol = signorini
    pd, cd = sol.fields()
    assert set(cd) >= {"u_K", "grad_x", "grad_y", "grad_z", "active_edges", "multiplier_edges"}
    assert pd["u_vertex"].shape == (mesh.n_vertices,)
    path = tmp_path / "signorini3d.vtu"
    sol.write_vtu(path)
    back = gradvi.Mesh3.read(path)
    assert back.n_cells == mesh.n_cells
    text = path.read_text()
    for name in ("u_K", "grad_z", "active_edges", "u_vertex"):
        assert f'Name="{name}"' in text
    m = sol.to_meshio()
    np.testing.assert_array_equal(np.concatenate(m.cell_data["u_K"]), sol.u_cell)
    assert "NITER" in sol.summary()
    # the boundary surface beside it: one polygon per boundary face, the contact zone on Γ3
    b = meshio.read(tmp_path / "signorini3d_boundary.vtu")
    bf = mesh.boundary_faces
    assert [c.type for c in b.cells] == ["polygon"] and len(b.cells[0].data) == len(bf)
    np.testing.assert_array_equal(b.cell_data["face"][0], bf)
    np.testing.assert_array_equal(b.cell_data["boundary_tag"][0], mesh.face_tags[bf])
    active = b.cell_data["active"][0]
    np.testing.assert_array_equal(active > 0.5, sol.active_faces[bf])
    assert 0 < active.sum() == sol.n_active < (mesh.face_tags == 5).sum()
    np.testing.assert_array_equal(b.cell_data["u_face"][0], sol.u_face[bf])
    # each polygon is its face's loop
    for i in (0, len(bf) // 2, len(bf) - 1):
        loop = mesh.points[mesh.face_vertices(bf[i])]
        np.testing.assert_array_equal(b.points[b.cells[0].data[i]], loop)
    assert b.point_data["u_vertex"].shape == (len(b.points),)
    sol.write_vtu(tmp_path / "alone.vtu", boundary=False)
    assert not (tmp_path / "alone_boundary.vtu").exists()
    with pytest.raises(gradvi.InvalidDataError, match="3D"):
        gradvi.solve(gradvi.Mesh.generate("cartesian", 1), gradvi.Problem(source=1.0)).boundary_fields()


# ------------------------------------------------------------------------------ errors


@pytest.fixture(scope="module")
def cube():
    return gradvi.Mesh3.generate("cubes", 1)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(source=lambda x, y: x + y), ["source", "(x, y, z)"]),
        (dict(dirichlet=lambda x, y, z, w: x), ["dirichlet", "(x, y, z)"]),
        (dict(diffusion=np.eye(2)), ["diffusion", "2×2", "3D"]),
        (dict(diffusion=lambda x, y, z: [[1.0, 0.0], [0.0, 1.0]]), ["diffusion", "2×2"]),
        (dict(exact=lambda x, y, z: x, exact_grad=lambda x, y, z: (x, y)), ["exact_grad", "3D", "2 components"]),
        (dict(boundary={"dirichlet": lambda x, y: x > 0, "neumann": "rest"}), ["boundary['dirichlet']", "(x, y, z)"]),
        (dict(boundary=lambda x, y, z: 0), ["boundary", "(x, y, z, tag)"]),
        (dict(source=gradvi.CellData(np.ones(64))), ["source", "planar"]),
        (dict(boundary={"signorini": 7, "dirichlet": "rest"}, signorini=0.0, side="upper"), ["tag(s) [7]", "face"]),
    ],
)
def test_data_that_do_not_fit_a_3d_mesh_are_typed_errors(cube, kwargs, words):
    with pytest.raises(gradvi.InvalidDataError) as e:
        gradvi.solve(cube, gradvi.Problem(**kwargs), scheme="hmm")
    for w in words:
        assert w in str(e.value), (w, str(e.value))


def test_a_3d_callable_on_a_planar_mesh_is_a_typed_error():
    mesh = gradvi.Mesh.generate("cartesian", 1)
    with pytest.raises(gradvi.InvalidDataError, match=r"source.*on a 2D mesh.*\(x, y\)"):
        gradvi.solve(mesh, gradvi.Problem(source=lambda x, y, z: x), scheme="hmm")


def test_planar_problems_and_simplex_schemes_on_cubes_are_refused(cube):
    # a 2×2 tensor and a 2-component gradient: not a 3D problem (tests/test_problem_files3d.py
    # checks the message is the command line's)
    with pytest.raises(gradvi.ProblemFileError, match="on a 3D mesh"):
        gradvi.solve(cube, gradvi.Problem.builtin("fvca5-1.1"), scheme="hmm")
    with pytest.raises(gradvi.InvalidDataError, match="not a tetrahedron"):
        gradvi.solve(cube, gradvi.Problem(source=1.0), scheme="p1")
