//! Beyond the paper: the 3D solves. A linear problem with a smooth exact solution
//! (`problems/poisson-3d.toml`) and the two 3D obstacle problems with exact solutions (the
//! radial obstacle `problems/ex9-3d.toml` and DiSk++'s test `problems/disk-obstacle-3d.toml`),
//! solved on the generated 3D families level by level with the library's default solver options
//! (the nested warm start). One row per solve goes to `results/convergence3d.csv`; the figures
//! ([`figures`]) and `REPORT-3D.md` ([`report`]) are made from that file, except the slices of
//! the solutions, drawn from the finest HMM solve on cubes of each obstacle problem.

pub mod figures;
pub mod report;

use super::experiments::worst;
use super::records::write_csv;
use super::{Config, create_dir};
use gradvi::budget::MemoryBudget;
use gradvi::mesh3d::generate::Family3;
use gradvi::mesh3d::{Cuboid, PolyMesh3};
use gradvi::post::relative_errors;
use gradvi::problem::Problem;
use gradvi::problem::file::{self, MeshSpec};
use gradvi::scheme::{SchemeKind, build_with3};
use gradvi::solver::{SolveOptions, solve_problem};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The CSV file of the 3D solves, in `results/`.
pub const CSV: &str = "convergence3d.csv";

/// One row of `results/convergence3d.csv`: one solve.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Row3d {
    /// The problem (its file name in `problems/`, without `.toml`).
    pub problem: String,
    /// hmm, p1 or cr.
    pub scheme: String,
    /// The generated family (cubes, kuhn, prisms, refined, warped).
    pub family: String,
    /// Its level (n = 2^(level+1) cubes per side).
    pub level: usize,
    /// h = max cell diameter.
    pub h: f64,
    /// Number of cells.
    pub n_cells: usize,
    /// Number of unknowns of the scheme (before static condensation).
    pub unknowns: usize,
    /// Relative L² error of u at the centroids.
    pub err_u: f64,
    /// Relative L² error of the cell gradients.
    pub err_grad: f64,
    /// Linear solves of the active-set method (1 for a linear problem).
    pub niter: usize,
    /// Number of active (contact) unknowns.
    pub n_active: usize,
    /// Measure of the contact set (Σ of the measures of the active unknowns).
    pub contact_volume: f64,
    /// Certificate: worst scaled quantity.
    pub certificate: f64,
    /// Total solve time, seconds.
    pub time_s: f64,
}

/// A 3D problem of the report: its file and the (scheme, family) pairs it is solved with.
pub struct Case3d {
    /// The file name in `problems/` without `.toml`.
    pub name: &'static str,
    /// The text of the file (compiled in, as the 2D built-in problems).
    pub text: &'static str,
    /// The schemes and families.
    pub runs: &'static [(SchemeKind, Family3)],
    /// The radius r₀ of the exact contact set, a ball centred at the origin (obstacle
    /// problems).
    pub contact_radius: Option<f64>,
}

const HMM_ALL: &[(SchemeKind, Family3)] = &[
    (SchemeKind::Hmm, Family3::Cubes),
    (SchemeKind::Hmm, Family3::Kuhn),
    (SchemeKind::Hmm, Family3::Prisms),
    (SchemeKind::Hmm, Family3::Refined),
    (SchemeKind::Hmm, Family3::Warped),
    (SchemeKind::P1, Family3::Kuhn),
    (SchemeKind::Cr, Family3::Kuhn),
];

const OBSTACLE_RUNS: &[(SchemeKind, Family3)] = &[
    (SchemeKind::Hmm, Family3::Cubes),
    (SchemeKind::Hmm, Family3::Kuhn),
    (SchemeKind::P1, Family3::Kuhn),
];

/// The three problems, in report order.
pub const CASES: [Case3d; 3] = [
    Case3d {
        name: "poisson-3d",
        text: include_str!("../../../../problems/poisson-3d.toml"),
        runs: HMM_ALL,
        contact_radius: None,
    },
    Case3d {
        name: "ex9-3d",
        text: include_str!("../../../../problems/ex9-3d.toml"),
        runs: OBSTACLE_RUNS,
        // r₀ = 1/√2 (problems/ex9-3d.toml)
        contact_radius: Some(std::f64::consts::FRAC_1_SQRT_2),
    },
    Case3d {
        name: "disk-obstacle-3d",
        text: include_str!("../../../../problems/disk-obstacle-3d.toml"),
        runs: OBSTACLE_RUNS,
        // r₀ = 0.7, r measured from the origin (problems/disk-obstacle-3d.toml)
        contact_radius: Some(0.7),
    },
];

/// The levels solved: 1–2 in quick mode, 1–4 otherwise.
pub fn levels(cfg: &Config) -> std::ops::RangeInclusive<usize> {
    if cfg.quick { 1..=2 } else { 1..=4 }
}

/// The problem of `case` and the box of its `[mesh]` (the unit cube if it names none).
pub fn load(case: &Case3d) -> gradvi::Result<(Problem<3>, Cuboid)> {
    let path = Path::new("problems").join(format!("{}.toml", case.name));
    let f = file::parse(case.text, &path, &[])?;
    let domain = match f.mesh {
        Some(MeshSpec::Generated3 {
            domain: Some(d), ..
        }) => d,
        _ => Cuboid::UNIT,
    };
    Ok((f.problem_in::<3>()?, domain))
}

/// The mesh of `family` at `level` on `domain`.
pub fn mesh(family: Family3, level: usize, domain: Cuboid) -> gradvi::Result<PolyMesh3> {
    family.generate_on(level, domain, MemoryBudget::available())
}

/// The library's default solver options (the nested warm start) within the free memory.
pub fn options() -> SolveOptions {
    let mut o = SolveOptions::default();
    o.system.budget = MemoryBudget::available();
    o
}

/// Solves `problem` with `kind` on `m` and makes its row.
fn solve_row(
    case: &str,
    (kind, family, level): (SchemeKind, Family3, usize),
    m: &PolyMesh3,
    problem: &Problem<3>,
) -> gradvi::Result<Row3d> {
    let scheme = build_with3(kind, m, &Default::default())?;
    let sol = solve_problem(scheme.as_ref(), problem, &options())?;
    let exact = problem.exact.as_ref().ok_or_else(|| {
        gradvi::Error::InvalidData(format!("problem {case} has no exact solution"))
    })?;
    let e = relative_errors(scheme.as_ref(), sol.u(), &exact.u, &exact.grad);
    let (n_active, contact_volume) = sol.constraints.as_ref().map_or((0, 0.0), |c| {
        let on = || (c.dofs.iter().zip(&sol.result.active)).filter(|(_, a)| **a);
        (on().count(), on().map(|(d, _)| d.measure).sum())
    });
    Ok(Row3d {
        problem: case.into(),
        scheme: kind.to_string(),
        family: family.name().into(),
        level,
        h: m.h(),
        n_cells: m.n_cells(),
        unknowns: scheme.n_unknowns(),
        err_u: e.l2_u,
        err_grad: e.l2_grad,
        niter: sol.niter(),
        n_active,
        contact_volume,
        certificate: worst(&sol),
        time_s: sol.timings.total,
    })
}

/// Solves every case on every level, writes `results/convergence3d.csv` and draws the slices
/// of the obstacle problems. `progress` receives one line per solve.
pub fn run(cfg: &Config, progress: &mut dyn FnMut(&str)) -> gradvi::Result<()> {
    create_dir(&cfg.results())?;
    let mut rows = Vec::new();
    for case in &CASES {
        let (problem, domain) = load(case)?;
        for &(kind, family) in case.runs {
            for level in levels(cfg) {
                let m = mesh(family, level, domain)?;
                let r = solve_row(case.name, (kind, family, level), &m, &problem)?;
                progress(&format!(
                    "3d {:<16} {:<4} {:<8} level {level}  NITER {:>2}  e_u = {:.3e}  e_grad = {:.3e}  {:.2} s",
                    r.problem, r.scheme, r.family, r.niter, r.err_u, r.err_grad, r.time_s
                ));
                rows.push(r);
            }
        }
        if problem.constraint.is_some() {
            let level = *levels(cfg).end();
            let m = mesh(Family3::Cubes, level, domain)?;
            figures::slice(cfg, case, &m, &problem)?;
        }
    }
    write_csv(&cfg.results().join(CSV), &rows)
}
