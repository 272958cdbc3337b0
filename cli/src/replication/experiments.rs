//! The experiments of the paper's Section 4, each solved with HMM (the paper's scheme) and P1
//! (the extension the paper invites in its Section 3.1). Results go to `results/*.csv`.

use super::records::*;
use super::{Config, create_dir};
use gradvi::assembly::SymbolicSystem;
use gradvi::budget::MemoryBudget;
use gradvi::mesh::generate::{hexagonal::hexagonal, kershaw::kershaw};
use gradvi::mesh::io::read_mesh;
use gradvi::mesh::{PolyMesh, SolveMesh};
use gradvi::post::contact::{contact_measure, switch_point};
use gradvi::post::relative_errors;
use gradvi::problem::{Problem, file, paper_test2_tie};
use gradvi::scheme::{SchemeKind, build};
use gradvi::solver::{Solution, SolveOptions, solve_problem, solve_with_symbolic};
use serde::Serialize;
use std::fmt::{self, Display};
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
        mesh: read_mesh(&path, MemoryBudget::available())?,
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
        .map(|k| k2.cell_vertices(k).iter().map(|&v| v as usize).collect())
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
                    mesh: read_mesh(&path, MemoryBudget::available())?,
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
    let sol = solve_problem(scheme.as_ref(), problem, &paper_options())?;
    f(&sol)
}

/// The paper's solver options ([`SolveOptions::paper`]), within the memory the machine has
/// free ([`MemoryBudget::available`]).
pub fn paper_options() -> SolveOptions {
    let mut o = SolveOptions::paper();
    o.system.budget = MemoryBudget::available();
    o
}

/// The worst scaled quantity of the certificate of `sol`.
pub fn worst<M: SolveMesh<D> + ?Sized, const D: usize>(sol: &Solution<M, D>) -> f64 {
    sol.result.certificate.worst()
}

fn log_rows(case: &str, kind: SchemeKind, mesh: &str, sol: &Solution) -> Vec<IterationRow> {
    sol.result
        .log
        .iter()
        .map(|l| IterationRow {
            run: Run {
                case: case.into(),
                scheme: kind.to_string(),
                mesh: mesh.into(),
            },
            step: l.step,
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

    /// Keeps the iteration log of `sol`, the solve of `case` with `kind` on mesh `mesh`.
    fn keep_log(&mut self, case: &str, kind: SchemeKind, mesh: &str, sol: &Solution) {
        self.iterations.extend(log_rows(case, kind, mesh, sol));
    }

    /// Solves `problem` (case `case`) with `kind` on `m`, keeps its iteration log, and makes
    /// the row of the solution with `row`, reported on one line.
    fn solve_row<R: Display>(
        &mut self,
        case: &str,
        m: &NamedMesh,
        kind: SchemeKind,
        problem: &Problem,
        row: impl FnOnce(&Solution) -> R,
    ) -> gradvi::Result<R> {
        let r = with_solution(&m.mesh, kind, problem, |sol| {
            self.keep_log(case, kind, &m.name, sol);
            Ok(row(sol))
        })?;
        (self.progress)(&r.to_string());
        Ok(r)
    }
}

// The progress line of each row.

impl Display for Test1Row {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "test1 {:<4} {:<10} NITER {:>3}  switch x = {:.4}",
            self.scheme, self.mesh, self.niter, self.switch_x
        )
    }
}

impl Display for Test2Row {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "test2 {:<4} {:<14} {:<28} NITER {:>3}  e_u = {:.4}  e_grad = {:.4}",
            self.scheme, self.mesh, self.family, self.niter, self.err_u, self.err_grad
        )
    }
}

impl Display for Test3Row {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "test3 {:<4} {:<8} C = {:>4}  NITER {:>3}  contact area {:.4}",
            self.scheme, self.mesh, self.c, self.niter, self.contact_area
        )
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
    table(cfg, &mut logs, "test1", test1)?;
    table(cfg, &mut logs, "test2", test2)?;
    table(cfg, &mut logs, "test3", test3)?;
    write_csv(&cfg.results().join("meshes.csv"), &logs.meshes)?;
    write_csv(&cfg.results().join("iterations.csv"), &logs.iterations)?;
    let t = Instant::now();
    super::three_d::run(cfg, logs.progress)?;
    logs.stage("3d", t);
    Ok(logs.timings)
}

/// Runs `experiment`, writes its rows to `results/NAME.csv` and records its time.
fn table<R: Serialize>(
    cfg: &Config,
    logs: &mut Logs,
    name: &str,
    experiment: fn(&Config, &mut Logs) -> gradvi::Result<Vec<R>>,
) -> gradvi::Result<()> {
    let t = Instant::now();
    let rows = experiment(cfg, logs)?;
    write_csv(&cfg.results().join(format!("{name}.csv")), &rows)?;
    logs.stage(name, t);
    Ok(())
}

/// The rows `rows(logs, m, kind)` for every gmsh mesh `m` of `family` (kept for `meshes.csv`)
/// and every triangle scheme `kind`.
fn on_gmsh_family<R>(
    cfg: &Config,
    logs: &mut Logs,
    family: &str,
    mut rows: impl FnMut(&mut Logs, &NamedMesh, SchemeKind) -> gradvi::Result<Vec<R>>,
) -> gradvi::Result<Vec<R>> {
    let mut out = Vec::new();
    for m in gmsh_family(cfg, family)? {
        logs.meshes.push(mesh_row(&m));
        for &kind in TRIANGLE_SCHEMES {
            out.extend(rows(logs, &m, kind)?);
        }
    }
    Ok(out)
}

/// Test 1 (Signorini): NITER and the switch point on Γ3 (the rows of `test1.csv`).
fn test1(cfg: &Config, logs: &mut Logs) -> gradvi::Result<Vec<Test1Row>> {
    on_gmsh_family(cfg, logs, "test1", |logs, m, kind| {
        let p = builtin("test1", &[])?;
        let row = logs.solve_row("test1", m, kind, &p, |sol| {
            let cons = sol.constraints.as_ref().expect("Test 1 has a barrier");
            let sw = switch_point(sol.system.scheme(), cons, &sol.result.active, 0);
            Test1Row {
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
            }
        })?;
        Ok(vec![row])
    })
}

/// Test 2 (heterogeneous Signorini, exact solution): errors, NITER, switch (the rows of
/// `test2.csv`).
fn test2(cfg: &Config, logs: &mut Logs) -> gradvi::Result<Vec<Test2Row>> {
    let mut rows = Vec::new();
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
                rows.push(logs.solve_row("test2", m, kind, p, |sol| {
                    let cons = sol.constraints.as_ref().expect("Test 2 has a barrier");
                    let scheme = sol.system.scheme();
                    let sw = switch_point(scheme, cons, &sol.result.active, 1);
                    let e = relative_errors(scheme, sol.u(), &exact.u, &exact.grad);
                    Test2Row {
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
                    }
                })?);
            }
        }
    }
    Ok(rows)
}

/// Test 3 (obstacle) for the four values of C (the rows of `test3.csv`). The symbolic system
/// (pattern, symbolic factorisation, scatter maps) of each scheme on each mesh is built once and
/// shared by the four problems.
fn test3(cfg: &Config, logs: &mut Logs) -> gradvi::Result<Vec<Test3Row>> {
    on_gmsh_family(cfg, logs, "test3", |logs, m, kind| {
        let scheme = build(kind, &m.mesh)?;
        let symbolic = Arc::new(SymbolicSystem::new(
            scheme.as_ref(),
            paper_options().system,
        )?);
        let mut rows = Vec::new();
        for c in TEST3_C {
            let p = builtin("test3", &[("C".into(), c)])?;
            let sol = solve_with_symbolic(symbolic.clone(), &p, &paper_options())?;
            let cons = sol.constraints.as_ref().expect("Test 3 has a barrier");
            logs.keep_log(&p.name, kind, &m.name, &sol);
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
            (logs.progress)(&row.to_string());
            rows.push(row);
        }
        Ok(rows)
    })
}
