//! `gradvi solve` on a 3D mesh, and the choice of the mesh's dimension.
//!
//! The dimension of a solve is the mesh's: a generated 3D family (cubes, kuhn, prisms, refined,
//! warped), or a mesh file read as `gradvi mesh info` reads it ([`gradvi::case::read_any`]:
//! a `.msh` with 3D elements, `.vtu`, HArDCore RF). The problem file must compile for that
//! dimension ([`gradvi::problem::file::ProblemFile::check_against_mesh3`] reports a `z` on a
//! 2D mesh or a 2×2 tensor on a 3D one, at its place in the file).
//!
//! ## Warm start
//! As in 2D, the default is the nested warm start (on agglomerated polyhedral meshes).
//!
//! ## The VTU file in 3D
//! One unstructured grid of the polyhedral cells ([`write_vtu3`]): cell data `u_K`, `grad_x`,
//! `grad_y`, `grad_z`; point data `u_vertex` (cell values averaged at the vertices); and,
//! with a barrier, the active set and the multiplier on the entities of the constrained
//! unknowns: cell unknowns (HMM obstacle) as cell data `active_cell`/`multiplier_cell`, vertex
//! unknowns as point data `active`/`multiplier`, face unknowns (HMM Signorini) as cell data
//! summed over the faces of each cell, `active_faces` (the number of active faces of the cell)
//! and `multiplier_faces` (the sum of their multipliers), so that the contact zone shows on the
//! cells along the contact boundary.
//!
//! ## The boundary VTU file
//! Beside it, `NAME_boundary.vtu` for `--vtu NAME.vtu` ([`boundary_path`]; refused, as every
//! output, if it would overwrite an input or another output): the boundary faces as polygons
//! ([`write_boundary_vtu`](gradvi::post::vtu_boundary::write_boundary_vtu)) with cell data `face` (the face's index in the mesh),
//! `boundary_tag`, `u_face` (the face unknown u_σ, HMM and CR), and with a barrier on face
//! unknowns (HMM Signorini, CR) `active` (1 on the faces of the contact zone) and `multiplier`
//! (λ_σ); point data `u_vertex`, and with a barrier on vertex unknowns (P1) `active` and
//! `multiplier` per vertex.
//!
//! With `--vtu-faces` (3D only; refused on a 2D mesh), also `NAME_faces.vtu`: every face of
//! the mesh, interior and boundary, as polygons ([`write_faces_vtu`]) with the same arrays
//! (`boundary_tag` 0 on interior faces; `active` and `multiplier` 0 off the constrained faces,
//! as in the boundary file), so that the interior face unknowns u_σ show in ParaView.

use super::output::atomic;
use super::solve::{Case, SolveArgs, report, solve_options, write_json};
use anyhow::{Context, Result};
use gradvi::budget::MemoryBudget;
use gradvi::case::AnyMesh;
use gradvi::mesh3d::io::write_vtu3;
use gradvi::mesh3d::{PolyMesh3, WarpedFaces};
use gradvi::post::fields::EntityFields;
use gradvi::post::vtu_boundary::write_faces_vtu;
use gradvi::problem::Problem;
use gradvi::problem::file::{MeshSpec, ProblemFile};
use gradvi::scheme::{GradientDiscretisation, SchemeKind, SchemeOptions, build_with3};
use gradvi::solver::{Solution, solve_problem};
use std::path::{Path, PathBuf};

/// The 3D scheme trait object.
type Scheme3<'a> = dyn GradientDiscretisation<PolyMesh3, 3> + 'a;

/// The mesh `spec` describes, 2D or 3D, within the memory available
/// ([`gradvi::case::case_mesh`]: a mesh file is read as 2D, exactly as before 3D solves
/// existed, when the problem file is not a 3D problem or the format is 2D only; else its
/// dimension comes from the file). A 3D mesh's warped faces are as `warped` says.
pub fn case_mesh(spec: &MeshSpec, pf: &ProblemFile, warped: WarpedFaces) -> Result<AnyMesh> {
    Ok(gradvi::case::case_mesh(
        spec,
        pf,
        warped,
        MemoryBudget::available(),
    )?)
}

/// The solve on a 3D mesh (read or generated in `mesh_seconds`).
pub fn run3(
    a: &SolveArgs,
    pf: &ProblemFile,
    mesh: &PolyMesh3,
    mesh_desc: &str,
    mesh_seconds: f64,
) -> Result<()> {
    let boundary_vtu = a.vtu.as_deref().map(|p| sibling_path(p, "_boundary"));
    let faces_vtu = a
        .vtu
        .as_deref()
        .filter(|_| a.vtu_faces)
        .map(|p| sibling_path(p, "_faces"));
    if let Some(b) = &boundary_vtu {
        let mut extra = vec![("boundary VTU", b.as_path())];
        extra.extend(faces_vtu.as_deref().map(|f| ("faces VTU", f)));
        super::solve::check_paths(a, pf, &extra)?;
    }
    pf.check_against_mesh3(mesh)?;
    let problem = pf.problem_in::<3>()?;
    let kind = a.scheme.or(pf.scheme).unwrap_or(SchemeKind::Hmm);
    let scheme = build_with3(kind, mesh, &SchemeOptions { alpha: a.alpha })
        .with_context(|| format!("the {kind} scheme on the 3D mesh {mesh_desc}"))?;
    eprintln!(
        "solving {} with {} on {} cells ({} unknowns, 3D)...",
        problem.name,
        kind,
        mesh.n_cells(),
        scheme.n_unknowns()
    );
    let sol = solve3(a, scheme.as_ref(), &problem)?;
    let errors = problem
        .exact
        .as_ref()
        .map(|ex| gradvi::post::relative_errors(scheme.as_ref(), sol.u(), &ex.u, &ex.grad));
    let case = Case {
        pf,
        problem: &problem.name,
        kind,
        mesh_desc,
        n_cells: mesh.n_cells(),
        h: mesh.h(),
        mesh_seconds,
    };
    report(a, &case, &sol, errors.as_ref())?;
    if let (Some(path), Some(b)) = (&a.vtu, &boundary_vtu) {
        atomic(path, |tmp| write_solution_vtu3(tmp, scheme.as_ref(), &sol))?;
        println!("wrote           {}", path.display());
        let boundary = scheme.mesh().boundary_faces();
        atomic(b, |tmp| {
            write_faces_vtu3(tmp, scheme.as_ref(), &sol, boundary)
        })?;
        println!("wrote           {}", b.display());
    }
    if let Some(f) = &faces_vtu {
        let all: Vec<u32> = (0..mesh.n_faces() as u32).collect();
        atomic(f, |tmp| write_faces_vtu3(tmp, scheme.as_ref(), &sol, &all))?;
        println!("wrote           {}", f.display());
    }
    write_json(a, &case, &sol, errors.as_ref())
}

/// The solve with the command line's options.
fn solve3<'a>(
    a: &SolveArgs,
    scheme: &'a Scheme3<'a>,
    problem: &Problem<3>,
) -> Result<Solution<'a, PolyMesh3, 3>> {
    Ok(solve_problem(scheme, problem, &solve_options(a))?)
}

/// Writes u, its cell gradients, the active set and the multiplier to a 3D VTU file (the
/// fields are listed in the module docs).
fn write_solution_vtu3(path: &Path, scheme: &Scheme3, sol: &Solution<PolyMesh3, 3>) -> Result<()> {
    let u = sol.u();
    let grads = scheme.cell_gradients(u);
    let component = |i: usize| grads.iter().map(|g| g[i]).collect::<Vec<f64>>();
    let mut cell_data: Vec<(&str, Vec<f64>)> = vec![
        ("u_K", scheme.cell_values(u)),
        ("grad_x", component(0)),
        ("grad_y", component(1)),
        ("grad_z", component(2)),
    ];
    let mut point_data: Vec<(&str, Vec<f64>)> = vec![("u_vertex", scheme.vertex_values(u))];
    if let Some((act, lam)) = barrier_fields(scheme, sol) {
        if let (Some(a), Some(l)) = (act.vertex, lam.vertex) {
            point_data.push(("active", a));
            point_data.push(("multiplier", l));
        }
        if let (Some(a), Some(l)) = (act.cell, lam.cell) {
            cell_data.push(("active_cell", a));
            cell_data.push(("multiplier_cell", l));
        }
        let mesh = scheme.mesh();
        let per_cell = |e: &[f64]| -> Vec<f64> {
            (0..mesh.n_cells())
                .map(|k| mesh.cell_faces(k).iter().map(|&f| e[f as usize]).sum())
                .collect()
        };
        if let (Some(a), Some(l)) = (act.edge, lam.edge) {
            cell_data.push(("active_faces", per_cell(&a)));
            cell_data.push(("multiplier_faces", per_cell(&l)));
        }
    }
    let pd: Vec<(&str, &[f64])> = point_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    let cd: Vec<(&str, &[f64])> = cell_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    write_vtu3(path, &scheme.mesh().to_polyhedra(), &pd, &cd)?;
    Ok(())
}

/// The boundary VTU file beside the VTU file `vtu`: `NAME_boundary.EXT` for `NAME.EXT`.
pub fn boundary_path(vtu: &Path) -> PathBuf {
    sibling_path(vtu, "_boundary")
}

/// The file beside the VTU file `vtu`: `NAME{suffix}.EXT` for `NAME.EXT`.
fn sibling_path(vtu: &Path, suffix: &str) -> PathBuf {
    let stem = vtu
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_default();
    let mut name = stem;
    name.push(suffix);
    if let Some(ext) = vtu.extension() {
        name.push(".");
        name.push(ext);
    }
    vtu.with_file_name(name)
}

/// Writes the faces `faces` (the boundary faces, or all) with u_σ, the active set and the
/// multiplier on the faces (and the vertices) to a VTU file (the fields are listed in the
/// module docs).
fn write_faces_vtu3(
    path: &Path,
    scheme: &Scheme3,
    sol: &Solution<PolyMesh3, 3>,
    faces: &[u32],
) -> Result<()> {
    let u = sol.u();
    let mut face_data: Vec<(&str, Vec<f64>)> = Vec::new();
    let mut point_data: Vec<(&str, Vec<f64>)> = vec![("u_vertex", scheme.vertex_values(u))];
    if let Some(e) = EntityFields::new(scheme, 0..u.len(), |j| u[j]).edge {
        face_data.push(("u_face", e));
    }
    if let Some((act, lam)) = barrier_fields(scheme, sol) {
        if let (Some(a), Some(l)) = (act.edge, lam.edge) {
            face_data.push(("active", a));
            face_data.push(("multiplier", l));
        }
        if let (Some(a), Some(l)) = (act.vertex, lam.vertex) {
            point_data.push(("active", a));
            point_data.push(("multiplier", l));
        }
    }
    let pd: Vec<(&str, &[f64])> = point_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    let fd: Vec<(&str, &[f64])> = face_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    write_faces_vtu(path, scheme.mesh(), faces, &pd, &fd)?;
    Ok(())
}

/// The active set (1 or 0) and the multiplier of a solve with a barrier, on the entities of
/// the constrained unknowns; `None` without a barrier.
fn barrier_fields(
    scheme: &Scheme3,
    sol: &Solution<PolyMesh3, 3>,
) -> Option<(EntityFields, EntityFields)> {
    let c = sol.constraints.as_ref()?;
    let dofs = || c.dofs.iter().map(|d| d.dof);
    let r = &sol.result;
    Some((
        EntityFields::new(scheme, dofs(), |j| f64::from(u8::from(r.active[j]))),
        EntityFields::new(scheme, dofs(), |j| r.multiplier[j]),
    ))
}
