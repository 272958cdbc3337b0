//! The 3D figures: the errors against h on log axes (one figure per problem, from
//! `results/convergence3d.csv`) and a slice z = const of the HMM solution of each obstacle
//! problem with its active cells.

use super::{CSV, Case3d, Row3d, options};
use crate::plot::{
    LineOptions, LineSeries, SliceCell, SliceOptions, palette, plot_lines, plot_slice,
};
use crate::replication::Config;
use crate::replication::records::read_csv;
use gradvi::mesh3d::PolyMesh3;
use gradvi::problem::Problem;
use gradvi::scheme::{Entity, GradientDiscretisation, Hmm};
use gradvi::solver::solve_problem;

/// The file name of the error figure of `problem`.
pub fn errors_png(problem: &str) -> String {
    format!("errors_{problem}.png").replace("-3d", "_3d")
}

/// The file name of the slice figure of `problem`.
pub fn slice_png(problem: &str) -> String {
    format!("slice_{problem}.png").replace("-3d", "_3d")
}

/// Draws the error figure of every problem from `results/convergence3d.csv`.
pub fn plots_from_csv(cfg: &Config, cases: &[Case3d]) -> gradvi::Result<()> {
    let rows: Vec<Row3d> = read_csv(&cfg.results().join(CSV))?;
    for case in cases {
        let mine: Vec<&Row3d> = rows.iter().filter(|r| r.problem == case.name).collect();
        let mut series = Vec::new();
        for (i, &(kind, family)) in case.runs.iter().enumerate() {
            let of: Vec<&&Row3d> = (mine.iter())
                .filter(|r| r.scheme == kind.name() && r.family == family.name())
                .collect();
            let label = format!("{} {}", kind.name().to_uppercase(), family.name());
            let pts = |e: fn(&Row3d) -> f64| of.iter().map(|r| [r.h, e(r)]).collect();
            // one colour per scheme and family: u solid, ∇u dashed
            let mut u = LineSeries::new(format!("{label}: u"), pts(|r| r.err_u));
            u.color = Some(palette(i));
            let mut g = LineSeries::new(format!("{label}: ∇u"), pts(|r| r.err_grad));
            (g.color, g.dashed) = (Some(palette(i)), true);
            series.extend([u, g]);
        }
        let mut opts = LineOptions::log_log(
            format!("{}: relative L² errors (beyond the paper)", case.name),
            "h",
            "relative L² error",
        );
        opts.size = (900, 650);
        opts.legend = Some(crate::plot::LegendPosition::LowerRight);
        plot_lines(&cfg.figures().join(errors_png(case.name)), &series, &opts)?;
    }
    Ok(())
}

/// The section of cell `k` of `m` by the plane z = `c`: the crossings of its face edges,
/// ordered by angle around their mean (cells of the generated families are convex); `None` if
/// the plane misses the cell.
fn section(m: &PolyMesh3, k: usize, c: f64) -> Option<Vec<[f64; 2]>> {
    let mut pts: Vec<[f64; 2]> = Vec::new();
    for &f in m.cell_faces(k) {
        let fv = m.face_vertices(f as usize);
        for i in 0..fv.len() {
            let a = m.vertices()[fv[i] as usize];
            let b = m.vertices()[fv[(i + 1) % fv.len()] as usize];
            if (a[2] - c) * (b[2] - c) < 0.0 {
                let t = (c - a[2]) / (b[2] - a[2]);
                pts.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
    }
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let g = [
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let angle = |p: &[f64; 2]| (p[1] - g[1]).atan2(p[0] - g[0]);
    pts.sort_by(|p, q| angle(p).total_cmp(&angle(q)));
    pts.dedup_by(|p, q| (p[0] - q[0]).abs() + (p[1] - q[1]).abs() < 1e-12);
    (pts.len() >= 3).then_some(pts)
}

/// Solves `problem` with HMM on `m` and draws the cells cut by the plane z = c through the
/// middle of the layer of cells just above the centre of the box, coloured by u_K, the active
/// cells outlined.
pub fn slice(cfg: &Config, name: &str, m: &PolyMesh3, problem: &Problem<3>) -> gradvi::Result<()> {
    let s = Hmm::<PolyMesh3, 3>::with_alpha(m, 1.0)?;
    let sol = solve_problem(&s, problem, &options())?;
    let bb = m.bounding_box();
    // the cells' layers: n = round((z1 − z0)/h_z) where h_z is the extent of a cell in z
    let cell_dz = |k: usize| {
        let zs = (m.cell_faces(k).iter())
            .flat_map(|&f| m.face_vertices(f as usize))
            .map(|&v| m.vertices()[v as usize][2]);
        let (lo, hi) = zs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
            (a.min(z), b.max(z))
        });
        hi - lo
    };
    let c = 0.5 * (bb.z[0] + bb.z[1]) + 0.5 * cell_dz(0);
    let values = s.cell_values(sol.u());
    let mut active = vec![false; m.n_cells()];
    if let Some(cons) = sol.constraints.as_ref() {
        for (d, &a) in cons.dofs.iter().zip(&sol.result.active) {
            if let (true, Entity::Cell(k)) = (a, s.dof_entity(d.dof)) {
                active[k] = true;
            }
        }
    }
    let cells: Vec<SliceCell> = (0..m.n_cells())
        .filter_map(|k| {
            section(m, k, c).map(|polygon| SliceCell {
                polygon,
                value: values[k],
                marked: active[k],
            })
        })
        .collect();
    let opts = SliceOptions {
        title: format!(
            "{name}: HMM u_K on the cells cut by z = {c:.4} ({} cells)",
            m.n_cells()
        ),
        size: (800, 700),
        value_label: "u_K".into(),
        marked_label: "active (contact) cell".into(),
    };
    plot_slice(&cfg.figures().join(slice_png(name)), &cells, &opts)
}
