"""Python data is tabulated on the points the Rust schemes evaluate data at
(``gradvi::scheme::points``), and per-entity arrays land on the right ones: a solve of a
Python-built problem reads no point outside its table, and arrays given per vertex, edge or
cell give bitwise the solution of a callable with the same values at those points."""
import numpy as np
import pytest
from conftest import psi

import gradvi


def meshes(scheme, test3_mesh):
    """A gmsh mesh (unstructured, non-uniform) and a generated one; HMM also on polygons and
    on the distorted Kershaw mesh."""
    tri = [test3_mesh, gradvi.Mesh.generate("triangles", 2)]
    if scheme == "hmm":
        return tri + [gradvi.Mesh.generate("kershaw", 1), gradvi.Mesh.generate("hexagonal", 1)]
    return tri


def g(x, y):
    """Smooth data that no scheme reproduces exactly, positive on the unit square."""
    return 0.75 + x - 0.5 * y * y + 0.1 * np.sin(3 * x * y)


@pytest.mark.parametrize("scheme", gradvi.SCHEMES)
@pytest.mark.parametrize("barrier", ["obstacle", "signorini"])
def test_every_point_the_solve_reads_is_tabulated(test3_mesh, scheme, barrier):
    calls = {}

    def recorded(name, f):
        def h(x, y):
            calls[name] = calls.get(name, 0) + x.size
            return f(x, y)

        return h

    for m in meshes(scheme, test3_mesh):
        calls.clear()
        data = dict(
            source=recorded("f", lambda x, y: -20.0 + g(x, y)),
            diffusion=recorded("A", lambda x, y: 1.0 + x * x),
            dirichlet=recorded("u_D", lambda x, y: 0.0 * x),
            neumann=recorded("g_N", lambda x, y: 0.1 * g(x, y)),
            exact=recorded("u", g),
            exact_grad=recorded("grad u", lambda x, y: (x, y)),
        )
        if barrier == "obstacle":
            pb = gradvi.Problem(
                obstacle=recorded("psi", psi),
                side="lower",
                boundary={"neumann": lambda x, y: x > 1 - 1e-9, "dirichlet": "rest"},
                **data,
            )
        else:
            pb = gradvi.Problem(
                signorini=recorded("a", lambda x, y: -0.01 + 0.0 * x),
                side="lower",
                boundary={"signorini": lambda x, y: y < 1e-9, "neumann": lambda x, y: x > 1 - 1e-9, "dirichlet": "rest"},
                **data,
            )
        sol = gradvi.solve(m, pb, scheme=scheme, warm_start="cold")
        # no datum was asked at a point where Python gave no value (no fallback called)
        assert sol.untabulated_points == 0 and sol.fallback_calls == 0, (scheme, m)
        assert set(calls) == {"f", "A", "u_D", "g_N", "u", "grad u", "psi" if barrier == "obstacle" else "a"}
        assert sol.certificate.ok() and sol.n_active > 0
        # each datum is evaluated on its own points only: A and the exact solution at x_K
        assert calls["A"] == calls["u"] == m.n_cells


@pytest.mark.parametrize("scheme", gradvi.SCHEMES)
def test_entity_arrays_equal_callables_at_their_entities(test3_mesh, scheme):
    for m in meshes(scheme, test3_mesh):
        at_vertex, at_edge, at_cell = (g(*p.T) for p in (m.points, m.edge_midpoints, m.centroids))
        psi_v, psi_e, psi_c = (psi(*p.T) for p in (m.points, m.edge_midpoints, m.centroids))
        # u_D = g/10 > 0 is above the barrier ψ, which is 0 on the boundary
        ref = gradvi.solve(
            m, gradvi.Problem(source=lambda x, y: -20 * g(x, y), dirichlet=lambda x, y: g(x, y) / 10, obstacle=psi, side="lower"),
            scheme=scheme, warm_start="cold",
        )
        # each datum as values on the entities where the scheme reads it: the source on the
        # cells (HMM, read at x_K) or the vertices (P1); the Dirichlet data on the trace
        # unknowns' entities; the obstacle on the obstacle unknowns' entities
        source = {"hmm": gradvi.CellData(-20 * at_cell), "p1": gradvi.VertexData(-20 * at_vertex)}.get(
            scheme, lambda x, y: -20 * g(x, y)
        )
        dirichlet = gradvi.VertexData(at_vertex / 10) if scheme == "p1" else gradvi.EdgeData(at_edge / 10)
        obstacle = {"hmm": gradvi.CellData(psi_c), "p1": gradvi.VertexData(psi_v), "cr": gradvi.EdgeData(psi_e)}[scheme]
        arr = gradvi.solve(m, gradvi.Problem(source=source, dirichlet=dirichlet, obstacle=obstacle, side="lower"),
                           scheme=scheme, warm_start="cold")
        np.testing.assert_array_equal(arr.u, ref.u)
        np.testing.assert_array_equal(arr.active, ref.active)
        assert arr.niter == ref.niter and ref.n_active > 0


def edge_of_sub_triangle(m, x, y):
    """For each point (x, y) strictly inside a triangle co(σ ∪ {x_K}) of a triangle mesh: σ,
    found by brute force over the cells (an independent location, not the library's); -1 for
    a point inside none (the centroids themselves)."""
    p = np.column_stack([x, y])
    out = np.full(len(p), -1)
    ce = m.cell_edges.reshape(-1, 3)

    def cross(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (c[..., 0] - a[..., 0]) * (b[..., 1] - a[..., 1])

    for k in range(m.n_cells):
        xk = m.centroids[k]
        for e in ce[k]:
            a, b = m.points[m.edges[e]]
            s = np.sign([cross(xk, a, p), cross(a, b, p), cross(b, xk, p)])
            inside = (np.abs(s.sum(axis=0)) == 3)
            out[inside] = e
    return out


def test_crouzeix_raviart_edge_values_reach_their_own_sub_triangles(test3_mesh):
    """CR evaluates f at the centroid of each sub-triangle co(σ ∪ {x_K}): values given per
    edge must land on the sub-triangle of their own edge (the lumped Π_D u = u_σ there)."""
    rng = np.random.default_rng(31)
    for m in meshes("cr", test3_mesh):
        a = rng.uniform(-30.0, -10.0, m.n_edges)

        def by_location(x, y):
            e = edge_of_sub_triangle(m, x, y)
            return np.where(e >= 0, a[e], -20.0)  # x_K (the data scale only): any value

        arr = gradvi.solve(m, gradvi.Problem(source=gradvi.EdgeData(a), obstacle=psi, side="lower"), scheme="cr",
                           warm_start="cold")
        loc = gradvi.solve(m, gradvi.Problem(source=by_location, obstacle=psi, side="lower"), scheme="cr",
                           warm_start="cold")
        np.testing.assert_array_equal(arr.u, loc.u)
        assert arr.niter == loc.niter and arr.n_active > 0
        # vertex values reach x_{K,σ} by the affine interpolant: exact for affine data
        h = lambda x, y: -20.0 + 3.0 * x - 2.0 * y  # noqa: E731
        v = gradvi.solve(m, gradvi.Problem(source=gradvi.VertexData(h(*m.points.T))), scheme="cr")
        c = gradvi.solve(m, gradvi.Problem(source=h), scheme="cr")
        np.testing.assert_allclose(v.u, c.u, rtol=0, atol=1e-14 * np.abs(c.u).max())
