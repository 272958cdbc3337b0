//! The experiments of the paper's Section 4, each solved with HMM (the paper's scheme) and P1
//! (the extension the paper invites in its Section 3.1). Results go to `results/*.csv`.

use super::records::*;
use super::{Config, create_dir};
use gradvi::assembly::SymbolicSystem;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{hexagonal::hexagonal, kershaw::kershaw};
use gradvi::mesh::io::read_mesh;
use gradvi::post::contact::{contact_measure, switch_point};
use gradvi::post::relative_errors;
use gradvi::problem::{Problem, file, paper_test2_tie};
use gradvi::scheme::{SchemeKind, build};
use gradvi::solver::{Solution, SolveOptions, solve_problem, solve_with_symbolic};
use std::sync::Arc;
use std::time::Instant;

/// The constants C of Test 3.
pub const TEST3_C: [f64; 4] = [-5.0, -10.0, -15.0, -20.0];

/// A named mesh and where it came from.
pub struct NamedMesh {
    /// Name used in the CSV files.
    pub name: String,
    /// Provenance.
    pub source: String,
    /// The mesh.
    pub mesh: PolyMesh,
}

fn load(cfg: &Config, file: &str) -> gradvi::Result<NamedMesh> {
    let path = cfg.meshes.join(file);
    Ok(NamedMesh {
        name: file.trim_end_matches(".msh").to_string(),
        source: format!("gmsh file meshes/{file}"),
        mesh: read_mesh(&path)?,
    })
}

/// The gmsh meshes of a test (`test1`, `test2tri`, `test3`), coarsest first.
pub fn gmsh_family(cfg: &Config, prefix: &str) -> gradvi::Result<Vec<NamedMesh>> {
    let levels = if cfg.quick { 1 } else { 4 };
    (1..=levels)
        .map(|l| load(cfg, &format!("{prefix}_{l}.msh")))
        .collect()
}

/// The Test 2 polygonal meshes: hexagonal levels 1–4 and Kershaw level 2 from the generators,
/// and the original FVCA5 files when available.
pub fn test2_polygonal(cfg: &Config) -> gradvi::Result<Vec<(String, NamedMesh)>> {
    let levels = if cfg.quick { 2 } else { 4 };
    let mut v = Vec::new();
    for l in 1..=levels {
        v.push((
            "hexagonal".to_string(),
            NamedMesh {
                name: format!("hexagonal_{l}"),
                source: format!("generator hexagonal level {l}"),
                mesh: hexagonal(l)?,
            },
        ));
    }
    v.push((
        "kershaw".to_string(),
        NamedMesh {
            name: "kershaw_2".into(),
            source: "generator kershaw level 2".into(),
            mesh: kershaw(2)?,
        },
    ));
    // the same mesh with x and y exchanged: its straight middle line becomes y = 1/2, the
    // discontinuity of A (the paper's remark that its Kershaw mesh is aligned with it)
    let k2 = kershaw(2)?;
    let swapped: Vec<[f64; 2]> = k2.vertices().iter().map(|p| [p[1], p[0]]).collect();
    let cells: Vec<Vec<usize>> = (0..k2.n_cells())
        .map(|k| k2.cell_vertices(k).to_vec())
        .collect();
    v.push((
        "kershaw-transposed".to_string(),
        NamedMesh {
            name: "kershaw_2_transposed".into(),
            source: "generator kershaw level 2, x and y exchanged".into(),
            mesh: PolyMesh::from_cells(swapped, cells)?,
        },
    ));
    if let Some(dir) = &cfg.fvca5 {
        let mut files: Vec<String> = (1..=levels).map(|l| format!("hexa1_{l}.typ2")).collect();
        files.push("mesh4_1_2.typ2".into());
        for f in files {
            let path = dir.join(&f);
            v.push((
                "fvca5-file".to_string(),
                NamedMesh {
                    name: f.trim_end_matches(".typ2").to_string(),
                    source: format!("FVCA5 file {}", path.display()),
                    mesh: read_mesh(&path)?,
                },
            ));
        }
    }
    Ok(v)
}

/// Statistics of a mesh, as a CSV row.
pub fn mesh_row(m: &NamedMesh) -> MeshRow {
    MeshRow {
        mesh: m.name.clone(),
        source: m.source.clone(),
        n_cells: m.mesh.n_cells(),
        n_vertices: m.mesh.n_vertices(),
        n_edges: m.mesh.n_edges(),
        h: m.mesh.h(),
        edges_x0: m.mesh.boundary_edges_on(0, 0.0),
        edges_y0: m.mesh.boundary_edges_on(1, 0.0),
    }
}

/// Solves `problem` with scheme `kind` on `mesh` and hands the certified solution to `f`.
pub fn with_solution<R>(
    mesh: &PolyMesh,
    kind: SchemeKind,
    problem: &Problem,
    f: impl FnOnce(&Solution) -> gradvi::Result<R>,
) -> gradvi::Result<R> {
    let scheme = build(kind, mesh)?;
    let sol = solve_problem(scheme.as_ref(), problem, &SolveOptions::default())?;
    f(&sol)
}

fn worst(sol: &Solution) -> f64 {
    let c = sol.result.certificate;
    c.max_violation
        .max(-c.min_multiplier)
        .max(c.complementarity)
        .max(c.balance_residual)
}

fn log_rows(case: &str, kind: SchemeKind, mesh: &str, sol: &Solution) -> Vec<IterationRow> {
    sol.result
        .log
        .iter()
        .map(|l| IterationRow {
            case: case.into(),
            scheme: kind.to_string(),
            mesh: mesh.into(),
            solve: l.solve,
            active: l.active,
            entered: l.entered,
            left: l.left,
            violation: l.violation,
            residual: l.residual,
        })
        .collect()
}

/// A built-in problem, from its file `problems/NAME.toml` (compiled into gradvi), the way
/// `gradvi solve --problem NAME` serves it.
fn builtin(name: &str, params: &[(String, f64)]) -> gradvi::Result<Problem> {
    Ok(file::builtin(name, params)?.problem())
}

/// What the experiments accumulate besides their own tables.
struct Logs<'a> {
    meshes: Vec<MeshRow>,
    iterations: Vec<IterationRow>,
    timings: Vec<TimingRow>,
    progress: &'a mut dyn FnMut(&str),
}

impl Logs<'_> {
    /// Records the time of a stage begun at `t`.
    fn stage(&mut self, name: &str, t: Instant) {
        self.timings.push(TimingRow {
            stage: name.into(),
            seconds: t.elapsed().as_secs_f64(),
        });
    }
}

/// The schemes of Tables 1 and 3 (triangle meshes), in registration order.
const TRIANGLE_SCHEMES: &[SchemeKind] = SchemeKind::ALL;

/// Runs every experiment and writes `results/{meshes,test1,test2,test3,iterations}.csv`.
/// `progress` receives one line per solve.
pub fn run(cfg: &Config, progress: &mut dyn FnMut(&str)) -> gradvi::Result<Vec<TimingRow>> {
    create_dir(&cfg.results())?;
    let mut logs = Logs {
        meshes: Vec::new(),
        iterations: Vec::new(),
        timings: Vec::new(),
        progress,
    };
    test1(cfg, &mut logs)?;
    test2(cfg, &mut logs)?;
    test3(cfg, &mut logs)?;
    write_csv(&cfg.results().join("meshes.csv"), &logs.meshes)?;
    write_csv(&cfg.results().join("iterations.csv"), &logs.iterations)?;
    Ok(logs.timings)
}

/// Test 1 (Signorini): NITER and the switch point on Γ3 -> `test1.csv`.
fn test1(cfg: &Config, logs: &mut Logs) -> gradvi::Result<()> {
    let t = Instant::now();
    let mut rows1 = Vec::new();
    for m in gmsh_family(cfg, "test1")? {
        logs.meshes.push(mesh_row(&m));
        for &kind in TRIANGLE_SCHEMES {
            let p = builtin("test1", &[])?;
            let row = with_solution(&m.mesh, kind, &p, |sol| {
                let cons = sol.constraints.as_ref().expect("Test 1 has a barrier");
                let sw = switch_point(cons, &sol.result.active, 0);
                logs.iterations
                    .extend(log_rows("test1", kind, &m.name, sol));
                Ok(Test1Row {
                    scheme: kind.to_string(),
                    mesh: m.name.clone(),
                    h: m.mesh.h(),
                    n_cells: m.mesh.n_cells(),
                    n_gamma3: m.mesh.boundary_edges_on(1, 0.0),
                    niter: sol.niter(),
                    switch_x: sw.map_or(f64::NAN, |s| s.at),
                    switch_half_gap: sw.map_or(f64::NAN, |s| s.half_gap),
                    switch_count: sw.map_or(0, |s| s.count),
                    certificate: worst(sol),
                    time_s: sol.timings.total,
                })
            })?;
            (logs.progress)(&format!(
                "test1 {:<4} {:<10} NITER {:>3}  switch x = {:.4}",
                row.scheme, row.mesh, row.niter, row.switch_x
            ));
            rows1.push(row);
        }
    }
    write_csv(&cfg.results().join("test1.csv"), &rows1)?;
    logs.stage("test1", t);
    Ok(())
}

/// Test 2 (heterogeneous Signorini, exact solution): errors, NITER, switch -> `test2.csv`.
fn test2(cfg: &Config, logs: &mut Logs) -> gradvi::Result<()> {
    let t = Instant::now();
    let mut rows2 = Vec::new();
    let mut cases: Vec<(String, NamedMesh, &[SchemeKind])> = Vec::new();
    for (fam, m) in test2_polygonal(cfg)? {
        cases.push((fam, m, &[SchemeKind::Hmm]));
    }
    for m in gmsh_family(cfg, "test2tri")? {
        cases.push(("triangles".into(), m, &[SchemeKind::Hmm, SchemeKind::P1]));
    }
    let p = builtin("test2", &[])?;
    let p_low = paper_test2_tie(true);
    let exact = p.exact.as_ref().expect("Test 2 has an exact solution");
    for (fam, m, kinds) in &cases {
        logs.meshes.push(mesh_row(m));
        // the interface convention matters where some x_K lies on y = 1/2 (hexagonal meshes):
        // run the other convention too, as family "<family>-interface-lower"
        let on_interface = (0..m.mesh.n_cells())
            .any(|k| (m.mesh.centroid(k)[1] - 0.5).abs() <= gradvi::problem::TEST2_INTERFACE_TOL);
        let mut variants = vec![(fam.clone(), &p)];
        if on_interface {
            variants.push((format!("{fam}-interface-lower"), &p_low));
        }
        for (fam, p) in variants {
            for &kind in kinds.iter() {
                let row = with_solution(&m.mesh, kind, p, |sol| {
                    let cons = sol.constraints.as_ref().expect("Test 2 has a barrier");
                    let sw = switch_point(cons, &sol.result.active, 1);
                    let scheme = sol.system.scheme();
                    let e = relative_errors(scheme, sol.u(), &exact.u, &exact.grad);
                    logs.iterations
                        .extend(log_rows("test2", kind, &m.name, sol));
                    Ok(Test2Row {
                        scheme: kind.to_string(),
                        family: fam.clone(),
                        mesh: m.name.clone(),
                        h: m.mesh.h(),
                        n_cells: m.mesh.n_cells(),
                        n_gamma3: m.mesh.boundary_edges_on(0, 0.0),
                        err_u: e.l2_u,
                        err_grad: e.l2_grad,
                        niter: sol.niter(),
                        switch_y: sw.map_or(f64::NAN, |s| s.at),
                        switch_count: sw.map_or(0, |s| s.count),
                        certificate: worst(sol),
                        time_s: sol.timings.total,
                    })
                })?;
                (logs.progress)(&format!(
                    "test2 {:<4} {:<14} {:<28} NITER {:>3}  e_u = {:.4}  e_grad = {:.4}",
                    row.scheme, row.mesh, row.family, row.niter, row.err_u, row.err_grad
                ));
                rows2.push(row);
            }
        }
    }
    write_csv(&cfg.results().join("test2.csv"), &rows2)?;
    logs.stage("test2", t);
    Ok(())
}

/// Test 3 (obstacle) for the four values of C -> `test3.csv`. The symbolic system (pattern,
/// symbolic factorisation, scatter maps) of each scheme on each mesh is built once and shared
/// by the four problems.
fn test3(cfg: &Config, logs: &mut Logs) -> gradvi::Result<()> {
    let t = Instant::now();
    let mut rows3 = Vec::new();
    for m in gmsh_family(cfg, "test3")? {
        logs.meshes.push(mesh_row(&m));
        for &kind in TRIANGLE_SCHEMES {
            let scheme = build(kind, &m.mesh)?;
            let symbolic = Arc::new(SymbolicSystem::new(scheme.as_ref(), Default::default())?);
            for c in TEST3_C {
                let p = builtin("test3", &[("C".into(), c)])?;
                let sol = solve_with_symbolic(symbolic.clone(), &p, &SolveOptions::default())?;
                let cons = sol.constraints.as_ref().expect("Test 3 has a barrier");
                logs.iterations
                    .extend(log_rows(&p.name, kind, &m.name, &sol));
                let row = Test3Row {
                    scheme: kind.to_string(),
                    mesh: m.name.clone(),
                    h: m.mesh.h(),
                    n_cells: m.mesh.n_cells(),
                    c,
                    niter: sol.niter(),
                    n_active: sol.result.active.iter().filter(|&&a| a).count(),
                    contact_area: contact_measure(cons, &sol.result.active),
                    certificate: worst(&sol),
                    time_s: sol.timings.total,
                };
                (logs.progress)(&format!(
                    "test3 {:<4} {:<8} C = {:>4}  NITER {:>3}  contact area {:.4}",
                    row.scheme, row.mesh, c, row.niter, row.contact_area
                ));
                rows3.push(row);
            }
        }
    }
    write_csv(&cfg.results().join("test3.csv"), &rows3)?;
    logs.stage("test3", t);
    Ok(())
}
