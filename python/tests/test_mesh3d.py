"""gradvi.Mesh3: generated families, files, meshio conversions, geometry arrays and errors."""
import resource
import subprocess
import sys

import meshio
import numpy as np
import pytest

import gradvi

from conftest import ROOT

DATA = ROOT / "tests" / "data" / "mesh3d"

# cells at level 1 (n = 4 cubes per side): n³ cubes, 6n³ tetrahedra, 2n³ prisms, the
# checkerboard half of the cubes split into 8 (32·8 + 32), n³ warped hexahedra
CELLS_AT_LEVEL_1 = {"cubes": 64, "kuhn": 384, "prisms": 128, "refined": 288, "warped": 64}


def check_closed(m: gradvi.Mesh3, volume: float, area: float, planar: bool = True) -> None:
    """Volumes and boundary areas sum to the domain's; face counts agree with the face-cell
    incidence; with planar faces, every cell is closed (Σ |σ| n_{K,σ} = 0) and
    Σ |σ| d_{K,σ} = 3|K| (for warped faces |σ| n_σ is not the vector area of the fanned
    triangles, so both only hold to O(warp²))."""
    assert m.volumes.sum() == pytest.approx(volume, rel=1e-12)
    assert m.face_areas[m.boundary_faces].sum() == pytest.approx(area, rel=1e-12)
    assert np.all(m.volumes > 0) and np.all(m.cell_dists > 0)
    fc = m.face_cells
    assert np.array_equal(np.nonzero(fc[:, 1] < 0)[0], m.boundary_faces)
    assert 2 * m.n_faces - m.boundary_faces.size == m.cell_faces.size
    cell_of_side = np.repeat(np.arange(m.n_cells), np.diff(m.cell_face_offsets))
    if not planar:
        return
    sign = np.where(fc[m.cell_faces, 0] == cell_of_side, 1.0, -1.0)
    flux = (m.face_areas[m.cell_faces] * sign)[:, None] * m.face_normals[m.cell_faces]
    closure = np.zeros((m.n_cells, 3))
    np.add.at(closure, cell_of_side, flux)
    assert np.abs(closure).max() < 1e-12
    cone = np.zeros(m.n_cells)
    np.add.at(cone, cell_of_side, m.face_areas[m.cell_faces] * m.cell_dists)
    assert np.allclose(cone, 3 * m.volumes, rtol=1e-12, atol=0)


def test_the_3d_families_come_from_the_library():
    assert gradvi.FAMILIES3 == ("cubes", "kuhn", "prisms", "refined", "warped")
    assert gradvi.Mesh3.generate("tetrahedra", 1) == gradvi.Mesh3.generate("kuhn", 1)


@pytest.mark.parametrize("family", sorted(CELLS_AT_LEVEL_1))
def test_each_family_at_level_1_fills_the_unit_cube(family):
    m = gradvi.Mesh3.generate(family, 1)
    assert m.n_cells == CELLS_AT_LEVEL_1[family] and m.dim == 3
    assert m.bounding_box == gradvi.Box(0, 1, 0, 1, 0, 1)
    check_closed(m, 1.0, 6.0, planar=family != "warped")
    assert m.points.shape == (m.n_vertices, 3) and m.centroids.shape == (m.n_cells, 3)
    assert m.face_normals.shape == (m.n_faces, 3)
    assert np.allclose(np.linalg.norm(m.face_normals, axis=1), 1.0, atol=1e-14)
    assert m.h == pytest.approx(m.diameters.max())
    info = m.info()
    assert info["dim"] == 3 and info["n_cells"] == m.n_cells and info["volume"] == pytest.approx(1.0)
    assert info["n_boundary_faces"] == m.boundary_faces.size
    with pytest.raises(ValueError):
        m.volumes[0] = 2.0  # read-only


def test_cube_counts_and_the_refined_family_has_24_face_cells():
    cubes = gradvi.Mesh3.generate("cubes", 1)
    assert (cubes.n_vertices, cubes.n_faces) == (125, 3 * 16 * 5)
    assert np.all(np.diff(cubes.cell_face_offsets) == 6)
    assert gradvi.Mesh3.generate("refined", 1).info()["max_faces_per_cell"] == 24


def test_generate_on_a_box():
    box = gradvi.Box(-1.0, 3.0, 0.0, 0.5, 2.0, 2.25)
    m = gradvi.Mesh3.generate("prisms", 1, domain=box)
    assert m.bounding_box == box
    check_closed(m, 4 * 0.5 * 0.25, 2 * (4 * 0.5 + 4 * 0.25 + 0.5 * 0.25))
    assert gradvi.Mesh3.generate("cubes", 1, (-1, 3, 0, 0.5, 2, 2.25)) == gradvi.Mesh3.generate("cubes", 1, box)


def test_reading_gmsh_rf_and_vtu_files(tmp_path):
    # one hexahedron [0, 2] x [0, 1] x [0, 1], its bottom on the physical surface 5
    hexes = gradvi.Mesh3.read(DATA / "hex_41.msh")
    assert hexes.n_cells == 1 and hexes.info()["face_tags"] == [0, 5]
    check_closed(hexes, 2.0, 10.0)
    bottom = np.nonzero(hexes.face_tags == 5)[0]
    assert bottom.size == 1 and hexes.face_centroids[bottom[0]].tolist() == [1.0, 0.5, 0.0]
    # an RF pair given by its stem: a hexahedron and a 7-face polyhedron
    rf = gradvi.Mesh3.read(DATA / "two_cells")
    assert rf.n_cells == 2 and list(np.diff(rf.cell_face_offsets)) == [6, 7]
    check_closed(rf, 2.0, 10.0)
    for name in ("cube5_22.msh", "cube6_41.msh", "prism_22.msh", "pyramid_41.msh"):
        m = gradvi.Mesh3.read(DATA / name)
        check_closed(m, m.info()["volume"], m.face_areas[m.boundary_faces].sum())
        path = tmp_path / (name + ".vtu")
        m.write_vtu(path, point_data={"x": m.points[:, 0]}, cell_data={"v": m.volumes})
        back = gradvi.Mesh3.read(path)
        assert back.n_cells == m.n_cells and np.array_equal(back.cell_tags, m.cell_tags)
        assert np.allclose(back.volumes, m.volumes, rtol=1e-14, atol=0)
        assert np.array_equal(back.points, m.points)


def meshio_round_trip(m: gradvi.Mesh3, kind: str) -> gradvi.Mesh3:
    out = m.to_meshio(cell_data={"volume": m.volumes})
    assert all(b.type.startswith(kind) for b in out.cells)
    assert sum(len(b.data) for b in out.cells) == m.n_cells
    assert np.concatenate(out.cell_data["volume"]).tolist() == m.volumes.tolist()
    back = gradvi.Mesh3.from_meshio(out)
    assert (back.n_cells, back.n_faces, back.n_vertices) == (m.n_cells, m.n_faces, m.n_vertices)
    assert np.array_equal(back.points, m.points)
    assert np.allclose(back.volumes, m.volumes, rtol=1e-13, atol=0)
    assert np.allclose(back.centroids, m.centroids, rtol=0, atol=1e-14)
    return back


def test_meshio_round_trip_of_tetrahedra_hexahedra_and_polyhedra():
    meshio_round_trip(gradvi.Mesh3.generate("kuhn", 1), "tetra")
    meshio_round_trip(gradvi.Mesh3.generate("cubes", 1), "hexahedron")
    back = meshio_round_trip(gradvi.Mesh3.generate("refined", 1), "polyhedron")
    assert back.info()["max_faces_per_cell"] == 24
    meshio_round_trip(gradvi.Mesh3.generate("prisms", 1), "polyhedron")


def test_from_meshio_wedges_pyramids_and_tags():
    # two wedges filling the unit cube and a pyramid on its face x = 1 (apex outside the cube),
    # with a tagged boundary triangle (half of the bottom) and a line block (ignored)
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                     [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1], [1.5, 0.5, 0.5]], dtype=float)
    wedges = np.array([[0, 1, 2, 4, 5, 6], [0, 2, 3, 4, 6, 7]])
    pyramid = np.array([[1, 2, 6, 5, 8]])
    half_bottom = np.array([[0, 1, 2]])
    mm = meshio.Mesh(pts, [("wedge", wedges), ("pyramid", pyramid), ("triangle", half_bottom), ("line", [[0, 1]])],
                     cell_data={"gmsh:physical": [np.array([1, 1]), np.array([2]), np.array([7]), np.array([3])]})
    m = gradvi.Mesh3.from_meshio(mm)
    assert m.n_cells == 3 and m.cell_tags.tolist() == [1, 1, 2]
    check_closed(m, 1.0 + 1 / 6, 5.0 + 4 * np.sqrt(0.5**2 + 0.5**2) / 2)
    tagged = np.nonzero(m.face_tags)[0]
    assert m.face_tags[tagged].tolist() == [7] and np.allclose(m.face_centroids[tagged[0]], [2 / 3, 1 / 3, 0])
    assert m.info()["face_tags"] == [0, 7] and m.info()["cell_tags"] == [1, 2]


def test_from_arrays_and_nested_lists():
    # one unit cube as nested face lists, with a tagged face
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    faces = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    m = gradvi.Mesh3(pts, [faces], cell_tags=[5], face_tags={3: [[4, 5, 6, 7]]})
    assert m.volumes.tolist() == [pytest.approx(1.0, rel=1e-15)] and m.cell_tags.tolist() == [5]
    assert m.face_tags[m.face_tags != 0].tolist() == [3]
    flat = (np.array([0, 6]), np.arange(0, 25, 4), np.array(faces).reshape(-1))
    assert gradvi.Mesh3(pts, flat) == gradvi.Mesh3(pts, [faces])
    assert m.with_cell_tags([9]).cell_tags.tolist() == [9]


def test_bad_inputs_raise_the_typed_errors(tmp_path):
    with pytest.raises(gradvi.InvalidDataError, match="voronoi"):
        gradvi.Mesh3.generate("voronoi", 1)
    with pytest.raises(gradvi.InvalidDataError):
        gradvi.Mesh3.generate("cubes", 0)
    with pytest.raises(gradvi.InvalidDataError, match="levels go from 1"):
        gradvi.Mesh3.generate("cubes", 40)
    with pytest.raises(gradvi.InvalidDataError):
        gradvi.Mesh3.generate("cubes", 1, domain=(0, 1, 1, 0, 0, 1))
    with pytest.raises(gradvi.InvalidDataError):
        gradvi.Mesh3.generate("cubes", 1, domain=(0, 1, 0, 1))
    bad = tmp_path / "bad.msh"
    bad.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\nnonsense\n")
    with pytest.raises(gradvi.MeshIoError) as e:
        gradvi.Mesh3.read(bad)
    assert e.value.line > 0 and str(bad) in str(e.value.path)
    with pytest.raises(gradvi.MeshIoError, match="unknown 3D mesh format"):
        gradvi.Mesh3.read(tmp_path / "mesh.xyz")
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    with pytest.raises(gradvi.InvalidMeshError):  # an open cell: a tetrahedron missing a face
        gradvi.Mesh3(pts, [[[0, 1, 2], [0, 1, 3], [1, 2, 3]]])
    with pytest.raises(gradvi.InvalidDataError, match="entry 1"):
        gradvi.Mesh3(pts, [[[0, -1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]]])
    with pytest.raises(gradvi.InvalidDataError, match=r"\(n, 3\)"):
        gradvi.Mesh3(pts[:, :2], [[[0, 1, 2]]])
    with pytest.raises(gradvi.InvalidDataError, match="'hexahedron27'"):
        gradvi.Mesh3.from_meshio(meshio.Mesh(np.zeros((27, 3)), [("hexahedron27", np.arange(27)[None, :])]))
    with pytest.raises(gradvi.InvalidDataError, match="no tetra"):
        gradvi.Mesh3.from_meshio(meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]]))]))


_TOO_LARGE = """
import gradvi
try:
    gradvi.Mesh3.generate("kuhn", 6)
except MemoryError as e:
    assert isinstance(e, gradvi.OutOfMemoryError) and e.bytes > e.budget > 0, str(e)
    print("refused:", e)
else:
    raise AssertionError("no error")
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS is a Linux limit")
def test_a_3d_mesh_too_large_for_the_address_space_limit_is_a_memory_error(tmp_path):
    # in a child under a 3 GiB address-space limit, the 12.6M tetrahedra of Kuhn level 6 are
    # refused by their estimate before anything is allocated
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))

    out = subprocess.run([sys.executable, "-c", _TOO_LARGE], preexec_fn=limit, capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)
    assert out.returncode == 0 and "refused:" in out.stdout, out.stderr


def test_meshio_reads_the_vtu_files_gradvi_writes(tmp_path):
    """The VTU writer's files (VTK_POLYHEDRON, or tetra/hexahedron where all cells are) read by
    an independent reader: meshio finds the points, the cells, their kinds and the data gradvi
    wrote. (meshio groups polyhedra by vertex count into blocks; where the kinds interleave in
    the file, as on the refined family, it cannot split cell data over those blocks, so cell
    data is checked on the families with one cell kind.)"""
    import meshio

    for family, kinds in (("kuhn", {"tetra"}), ("cubes", {"hexahedron"}), ("prisms", None),
                          ("refined", None)):
        m = gradvi.Mesh3.generate(family, 1)
        path = tmp_path / f"{family}.vtu"
        uniform = family != "refined"
        cd = {"v": m.volumes} if uniform else {}
        m.write_vtu(path, point_data={"x": m.points[:, 0]}, cell_data=cd)
        r = meshio.read(path)
        assert sum(len(b.data) for b in r.cells) == m.n_cells, family
        found = {b.type for b in r.cells}
        if kinds is not None:
            assert found == kinds, (family, found)
        else:
            assert all(t.startswith("polyhedron") for t in found), (family, found)
        np.testing.assert_array_equal(r.points, m.points)
        np.testing.assert_array_equal(r.point_data["x"], m.points[:, 0])
        if uniform:
            np.testing.assert_array_equal(np.concatenate(r.cell_data["v"]), m.volumes)


def test_warped_faces_fan_or_split():
    fan = gradvi.Mesh3.generate("warped", 1)
    split = gradvi.Mesh3.generate("warped", 1, warped_faces="split")
    assert split.n_cells == fan.n_cells
    # every warped quadrilateral becomes 4 triangles around a new centre vertex
    added = split.n_vertices - fan.n_vertices
    assert added > 0 and split.n_faces - fan.n_faces == 3 * added
    assert np.allclose(split.volumes, fan.volumes, rtol=0, atol=1e-14)
    # planar faces are never split
    assert gradvi.Mesh3.generate("cubes", 1, warped_faces="split") == gradvi.Mesh3.generate("cubes", 1)
    with pytest.raises(gradvi.InvalidDataError):
        gradvi.Mesh3.generate("warped", 1, warped_faces="bent")
