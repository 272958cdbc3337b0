"""Meshes: reading, building from arrays (mixed polygons), generators, geometry arrays, and
round trips through meshio and the file formats."""
import re

import numpy as np
import pytest

import gradvi

import meshio


def same(a: gradvi.Mesh, b: gradvi.Mesh) -> None:
    assert a.n_cells == b.n_cells and a.n_vertices == b.n_vertices and a.n_edges == b.n_edges
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.cell_offsets, b.cell_offsets)
    np.testing.assert_array_equal(a.cell_connectivity, b.cell_connectivity)
    np.testing.assert_array_equal(a.edge_tags, b.edge_tags)
    assert a == b


def test_read_gmsh_with_tags_and_names(test3_mesh):
    m = test3_mesh
    assert (m.n_cells, m.n_edges, m.n_vertices) == (856, 1322, 467)
    assert m.physical_names == {"Gamma1": (1, 1), "Omega": (2, 10)}
    assert set(np.unique(m.edge_tags[m.boundary_edges])) == {1}
    assert m.is_triangular
    assert m.measures.sum() == pytest.approx(1.0, abs=1e-14)


def test_geometry_arrays_are_consistent():
    m = gradvi.Mesh.generate("hexagonal", 2)
    nc, ne, nv = m.n_cells, m.n_edges, m.n_vertices
    assert m.points.shape == (nv, 2) and m.centroids.shape == (nc, 2)
    assert m.edges.shape == (ne, 2) and m.edge_cells.shape == (ne, 2)
    assert m.cell_offsets.shape == (nc + 1,) and m.cell_offsets[-1] == m.cell_connectivity.size
    assert m.cell_normals.shape == (m.cell_connectivity.size, 2)
    assert len(set(m.cell_sizes)) > 1  # hexagons and boundary cells of other sizes
    # Σ_σ |σ| n_{K,σ} = 0 and Σ_σ |σ| d_{K,σ} = 2|K| on every cell
    lengths = m.edge_lengths[m.cell_edges]
    flux = np.add.reduceat(lengths[:, None] * m.cell_normals, m.cell_offsets[:-1])
    assert np.abs(flux).max() < 1e-13
    np.testing.assert_allclose(np.add.reduceat(lengths * m.cell_dists, m.cell_offsets[:-1]), 2 * m.measures, rtol=1e-12)
    assert (m.edge_cells[m.boundary_edges, 1] == -1).all()
    np.testing.assert_allclose(m.edge_midpoints, m.points[m.edges].mean(axis=1), rtol=0, atol=1e-15)
    assert m.h == pytest.approx(m.diameters.max())
    with pytest.raises(ValueError):
        m.points[0, 0] = 1.0  # read-only views


def test_mixed_polygons_from_lists():
    # a pentagon (with a vertex on the side x = 0), a quadrangle split into 4 triangles
    points = [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1), (1.5, 0.5), (0, 0.5)]
    cells = [[0, 1, 4, 5, 7], [1, 2, 6], [2, 3, 6], [3, 4, 6], [4, 1, 6]]
    m = gradvi.Mesh(points, cells, boundary_tags={1: [(0, 1), (1, 2)], 2: [(5, 7), (7, 0)]})
    assert m.n_cells == 5 and list(m.cell_sizes) == [5, 3, 3, 3, 3]
    assert m.measures.sum() == pytest.approx(2.0)
    assert sorted(np.unique(m.edge_tags)) == [0, 1, 2]
    # clockwise input is reoriented counter-clockwise
    cw = gradvi.Mesh(points, [c[::-1] for c in cells])
    assert cw.measures.min() > 0
    np.testing.assert_allclose(cw.centroids, m.centroids)
    # the same mesh from (offsets, connectivity) and from a 2-d array of triangles
    same(m, gradvi.Mesh(points, (m.cell_offsets.copy(), m.cell_connectivity.copy()), boundary_tags=np.column_stack([m.edges, m.edge_tags])[m.edge_tags > 0]))
    t = gradvi.Mesh(np.array(points)[[1, 2, 3, 4, 6]], np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    assert t.is_triangular and t.n_cells == 4


def test_generators_and_domain():
    for fam, level, cells in (("cartesian", 1, 16), ("hexagonal", 1, 121), ("kershaw", 1, 289), ("triangles", 1, 32)):
        assert gradvi.Mesh.generate(fam, level).n_cells == cells
    t = gradvi.Mesh.generate("triangles", 2, domain=(-2, 2, -2, 2))
    assert t.is_triangular and t.n_cells == 128 and t.bounding_box == gradvi.Rect(-2.0, 2.0, -2.0, 2.0)
    m = gradvi.Mesh.generate("cartesian", 2, domain=(-2, 2, -1, 3))
    assert m.bounding_box == gradvi.Rect(x0=-2.0, x1=2.0, y0=-1.0, y1=3.0)
    assert m.measures.sum() == pytest.approx(16.0)
    r = gradvi.Mesh.cartesian(3, 2, (0, 3, 0, 1))
    assert r.n_cells == 6 and np.allclose(r.measures, 0.5)


def test_a_rectangle_is_the_x_range_then_the_y_range():
    # a rectangle that is not a square, away from the origin: any swap of the two meanings
    # ([x0, x1, y0, y1] against [xmin, ymin, xmax, ymax]) changes it
    r = gradvi.Rect(x0=-1.0, x1=3.0, y0=10.0, y1=10.5)
    for fam in gradvi.FAMILIES:
        m = gradvi.Mesh.generate(fam, 1, domain=r)
        assert m.bounding_box == r, fam
        assert (m.points.min(axis=0) == (r.x0, r.y0)).all() and (m.points.max(axis=0) == (r.x1, r.y1)).all()
        # a plain sequence in the documented order (x0, x1, y0, y1) means the same
        assert gradvi.Mesh.generate(fam, 1, domain=tuple(r)).bounding_box == r
    c = gradvi.Mesh.cartesian(4, 2, r)
    assert c.bounding_box == r and c.measures.sum() == pytest.approx(2.0)
    assert gradvi.Mesh.generate("cartesian", 1).bounding_box == gradvi.Rect(0.0, 1.0, 0.0, 1.0)
    with pytest.raises(gradvi.InvalidDataError, match="x0 < x1"):
        gradvi.Mesh.generate("cartesian", 1, domain=gradvi.Rect(0.0, 1.0, 2.0, 1.0))
    with pytest.raises(gradvi.InvalidDataError, match="Rect"):
        gradvi.Mesh.generate("cartesian", 1, domain=(0.0, 1.0, 2.0))


def test_registries_are_the_rust_ones():
    from gradvi import _gradvi

    # the package's constants are the extension's, built from the Rust registries
    assert gradvi.SCHEMES is _gradvi.SCHEMES and gradvi.FAMILIES is _gradvi.FAMILIES
    assert gradvi.BUILTIN_PROBLEMS is _gradvi.BUILTIN_PROBLEMS
    for names in (gradvi.SCHEMES, gradvi.FAMILIES, gradvi.BUILTIN_PROBLEMS):
        assert isinstance(names, tuple) and len(names) == len(set(names)) > 0
    # every name is accepted by the Rust parser of its registry, and an unknown name is
    # refused with the Rust registry's list of names, which is the tuple
    tri = gradvi.Mesh.generate("triangles", 1)
    for name in gradvi.SCHEMES:
        assert tri._m.evaluation_points(name)["points"].shape[1] == 2
        assert gradvi.solve(tri, gradvi.Problem(source=1.0), scheme=name).scheme == name
    with pytest.raises(gradvi.InvalidDataError) as e:
        tri._m.evaluation_points("fem")
    assert listed(e.value) == gradvi.SCHEMES
    for name in gradvi.FAMILIES:
        assert gradvi.Mesh.generate(name, 1).n_cells > 0
    with pytest.raises(gradvi.InvalidDataError) as e:
        gradvi.Mesh.generate("voronoi", 1)
    assert listed(e.value) == gradvi.FAMILIES
    for name in gradvi.BUILTIN_PROBLEMS:
        assert gradvi.Problem.builtin(name).origin == "builtin"
    with pytest.raises(gradvi.InvalidDataError) as e:
        gradvi.Problem.builtin("test9")
    assert listed(e.value) == gradvi.BUILTIN_PROBLEMS


def listed(e: Exception) -> tuple:
    """The names a Rust "unknown name" error lists after "expected one of"."""
    tail = str(e).split("expected one of", 1)[1]
    return tuple(n for n in re.findall(r"[A-Za-z0-9][A-Za-z0-9_.-]*[A-Za-z0-9]", tail) if n != "or")


def test_round_trip_through_meshio(test3_mesh):
    for m in (test3_mesh, gradvi.Mesh.generate("hexagonal", 2), gradvi.Mesh.generate("kershaw", 1)):
        mm = m.to_meshio()
        assert isinstance(mm, meshio.Mesh)
        same(m, gradvi.Mesh.from_meshio(mm))
    # tags survive: test3_1 has its boundary tagged 1 (gmsh physical line "Gamma1")
    mm = test3_mesh.to_meshio()
    assert mm.cells[-1].type == "line" and (mm.cell_data["gmsh:physical"][-1] == 1).all()


def same_geometry(a: gradvi.Mesh, b: gradvi.Mesh) -> None:
    """The same cells (vertex coordinates in the same order) and tags, whatever the vertex ids."""
    np.testing.assert_array_equal(a.cell_offsets, b.cell_offsets)
    np.testing.assert_array_equal(a.points[a.cell_connectivity], b.points[b.cell_connectivity])
    ka = np.lexsort(a.edge_midpoints.T)
    kb = np.lexsort(b.edge_midpoints.T)
    np.testing.assert_array_equal(a.edge_midpoints[ka], b.edge_midpoints[kb])
    np.testing.assert_array_equal(a.edge_tags[ka], b.edge_tags[kb])


def test_gmsh_file_read_by_meshio_and_by_gradvi_agree(root, test3_mesh):
    # gradvi's reader numbers the vertices in order of first use by the cells, from_meshio keeps
    # meshio's point order (so that point data stays aligned): the same mesh up to vertex ids
    m = gradvi.Mesh.from_meshio(meshio.read(root / "meshes" / "test3_1.msh"))
    same_geometry(test3_mesh, m)
    for name in ("dam", "hole", "lshape"):
        a = gradvi.Mesh.read(root / "problems" / f"{name}.msh")
        same_geometry(a, gradvi.Mesh.from_meshio(meshio.read(root / "problems" / f"{name}.msh")))


def test_meshio_written_files_read_back(tmp_path, test3_mesh):
    mm = test3_mesh.to_meshio()
    path = tmp_path / "m.msh"
    meshio.write(path, mm, file_format="gmsh22", binary=False)
    same(test3_mesh, gradvi.Mesh.read(path))
    # gradvi's VTU (polygons) read by meshio
    hexa = gradvi.Mesh.generate("hexagonal", 2)
    hexa.write_vtu(tmp_path / "h.vtu", point_data={"x": hexa.points[:, 0]}, cell_data={"area": hexa.measures})
    back = meshio.read(tmp_path / "h.vtu")
    m2 = gradvi.Mesh.from_meshio(back)
    np.testing.assert_array_equal(m2.points, hexa.points)
    np.testing.assert_array_equal(m2.measures, hexa.measures) if m2.cell_offsets.tolist() == hexa.cell_offsets.tolist() else None
    np.testing.assert_allclose(np.sort(m2.measures), np.sort(hexa.measures), rtol=1e-14)
    areas = np.concatenate([np.asarray(a) for a in back.cell_data["area"]])
    assert areas.sum() == pytest.approx(1.0)


def test_typ2_round_trip(tmp_path):
    m = gradvi.Mesh.generate("hexagonal", 2)
    m.write_typ2(tmp_path / "h.typ2")
    b = gradvi.Mesh.read(tmp_path / "h.typ2")
    np.testing.assert_array_equal(b.points, m.points)
    np.testing.assert_array_equal(b.measures, m.measures)


def test_boundary_tags_from_a_callable():
    m = gradvi.Mesh.generate("cartesian", 1).with_boundary_tags(lambda x, y: np.where(y < 1e-12, 3, 1))
    b = m.boundary_edges
    bottom = m.edge_midpoints[b, 1] < 1e-12
    assert (m.edge_tags[b][bottom] == 3).all() and (m.edge_tags[b][~bottom] == 1).all()
    assert (np.delete(m.edge_tags, b) == 0).all()
