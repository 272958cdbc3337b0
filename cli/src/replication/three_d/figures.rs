//! The 3D figures: the errors against h on log axes (one figure per problem, from
//! `results/convergence3d.csv`) and a slice z = const of the HMM solution of each obstacle
//! problem with its active cells and the exact free boundary in that plane.

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

/// The exact free boundary in the plane z = `c`: the circle where that plane cuts the sphere
/// |x| = r₀ (the boundary of the contact ball), of radius ρ = √(r₀² − c²) about the origin,
/// as pieces of polyline inside the rectangle `[x0, x1] × [y0, y1]` (each piece a run of
/// consecutive points of the circle inside it, sampled every 1/720 of a turn); empty if the
/// plane misses the ball.
fn contact_circle(r0: f64, c: f64, x: [f64; 2], y: [f64; 2]) -> Vec<Vec<[f64; 2]>> {
    let rho2 = r0 * r0 - c * c;
    if rho2 <= 0.0 {
        return Vec::new();
    }
    let rho = rho2.sqrt();
    let inside = |p: &[f64; 2]| (x[0]..=x[1]).contains(&p[0]) && (y[0]..=y[1]).contains(&p[1]);
    let n = 720;
    let mut pieces: Vec<Vec<[f64; 2]>> = vec![Vec::new()];
    for i in 0..=n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        let p = [rho * t.cos(), rho * t.sin()];
        if inside(&p) {
            pieces.last_mut().expect("never empty").push(p);
        } else if !pieces.last().expect("never empty").is_empty() {
            pieces.push(Vec::new());
        }
    }
    // a piece that runs through the angle 0 was cut there: join its two ends
    if pieces.len() > 1 && inside(&[rho, 0.0]) {
        let first = pieces.remove(0);
        pieces.last_mut().expect("never empty").extend(first);
    }
    pieces.retain(|p| p.len() >= 2);
    pieces
}

/// Solves `problem` with HMM on `m` and draws the cells cut by the plane z = c through the
/// middle of the layer of cells just above the centre of the box, coloured by u_K, the active
/// cells outlined, and the exact free boundary in that plane (`contact_circle`).
pub fn slice(
    cfg: &Config,
    case: &Case3d,
    m: &PolyMesh3,
    problem: &Problem<3>,
) -> gradvi::Result<()> {
    let name = case.name;
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
        curve: case.contact_radius.map(|r0| {
            (
                format!(
                    "exact contact set: |x| ≤ r₀ = {r0:.4}, here ρ = √(r₀² − z²) = {:.4}",
                    (r0 * r0 - c * c).max(0.0).sqrt()
                ),
                contact_circle(r0, c, bb.x, bb.y),
            )
        }),
    };
    plot_slice(&cfg.figures().join(slice_png(name)), &cells, &opts)
}

#[cfg(test)]
mod tests {
    use super::super::{CASES, load, mesh};
    use super::*;
    use gradvi::mesh3d::generate::Family3;

    #[test]
    fn the_contact_circle_is_the_section_of_the_ball_inside_the_box() {
        let (r0, c) = (std::f64::consts::FRAC_1_SQRT_2, 0.25);
        let rho = (r0 * r0 - c * c).sqrt();
        // ex9-3d: the whole circle in (−2, 2)², one closed piece
        let full = contact_circle(r0, c, [-2.0, 2.0], [-2.0, 2.0]);
        assert_eq!(full.len(), 1);
        let p = &full[0];
        assert_eq!(
            (p.len(), p[0], p[p.len() - 1][1].abs() < 1e-12),
            (721, [rho, 0.0], true)
        );
        for q in p {
            assert!((q[0].hypot(q[1]) - rho).abs() < 1e-14);
        }
        // disk-obstacle-3d: a quarter in (0, 1)², from the x axis to the y axis
        let quarter = contact_circle(0.7, 0.5625, [0.0, 1.0], [0.0, 1.0]);
        assert_eq!(quarter.len(), 1);
        let q = &quarter[0];
        let rho = (0.7f64 * 0.7 - 0.5625 * 0.5625).sqrt();
        assert_eq!(q[0], [rho, 0.0]);
        assert!(q.iter().all(|p| p[0] >= 0.0 && p[1] >= 0.0));
        assert!(q.last().unwrap()[0].abs() < 1e-12 && (q.last().unwrap()[1] - rho).abs() < 1e-14);
        assert_eq!(q.len(), 181);
        // a box cutting the circle twice: two pieces; a plane above the ball: none
        assert_eq!(contact_circle(1.0, 0.0, [-2.0, 2.0], [-0.5, 0.5]).len(), 2);
        assert!(contact_circle(0.7, 0.8, [-2.0, 2.0], [-2.0, 2.0]).is_empty());
    }

    #[test]
    fn the_slice_figures_draw_on_coarse_meshes() {
        let out = std::env::temp_dir().join(format!("gradvi-slice3d-{}", std::process::id()));
        std::fs::create_dir_all(out.join("figures")).unwrap();
        let cfg = Config {
            out: out.clone(),
            meshes: "meshes".into(),
            fvca5: None,
            paper: "replication/paper".into(),
            quick: true,
        };
        for case in CASES.iter().filter(|c| c.contact_radius.is_some()) {
            let (problem, domain) = load(case).unwrap();
            let m = mesh(Family3::Cubes, 1, domain).unwrap();
            slice(&cfg, case, &m, &problem).unwrap();
            let png = out.join("figures").join(slice_png(case.name));
            assert!(std::fs::metadata(&png).unwrap().len() > 1000);
        }
        std::fs::remove_dir_all(&out).ok();
    }
}
