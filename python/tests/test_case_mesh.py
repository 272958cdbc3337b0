"""`Problem.mesh()`: the mesh of a problem file's `[mesh]`, chosen as `gradvi solve` chooses
it (the library's `gradvi::case::case_mesh`), its warped faces whole or split as
`warped_faces` says, like `gradvi solve --warped-faces`, for a generated family and for a
mesh file."""
import pytest

import gradvi


def problem_with_mesh(tmp_path, mesh_section):
    toml = tmp_path / "case.toml"
    toml.write_text(f"[source]\nf = 1\n[mesh]\n{mesh_section}\n")
    return gradvi.Problem.from_file(toml)


def test_warped_faces_of_a_generated_mesh(tmp_path):
    pb = problem_with_mesh(tmp_path, 'generate = "warped"\nlevel = 1')
    fan, split = pb.mesh(), pb.mesh(warped_faces="split")
    assert isinstance(fan, gradvi.Mesh3) and isinstance(split, gradvi.Mesh3)
    assert fan.n_faces == gradvi.Mesh3.generate("warped", 1).n_faces
    assert split.n_faces == gradvi.Mesh3.generate("warped", 1, warped_faces="split").n_faces
    assert split.n_faces > fan.n_faces
    assert pb.mesh(warped_faces="fan").n_faces == fan.n_faces


def test_warped_faces_of_a_mesh_file(tmp_path):
    gradvi.Mesh3.generate("warped", 1).write_vtu(tmp_path / "warped.vtu")
    pb = problem_with_mesh(tmp_path, 'file = "warped.vtu"')
    for convention in ("fan", "split"):
        read = gradvi.Mesh3.read(tmp_path / "warped.vtu", warped_faces=convention)
        assert pb.mesh(warped_faces=convention).n_faces == read.n_faces, convention
    assert pb.mesh(warped_faces="split").n_faces > pb.mesh().n_faces


def test_an_unknown_convention_is_the_librarys_error(tmp_path):
    pb = problem_with_mesh(tmp_path, 'generate = "warped"\nlevel = 1')
    with pytest.raises(gradvi.InvalidDataError) as e:
        pb.mesh(warped_faces="twist")
    with pytest.raises(gradvi.InvalidDataError) as e3:
        gradvi.Mesh3.generate("warped", 1, warped_faces="twist")
    assert str(e.value) == str(e3.value)
