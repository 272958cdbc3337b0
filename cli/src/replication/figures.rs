//! Figures 4.1–4.5 of the paper (PNG), VTU files of the plotted solutions, and two extra
//! plots drawn from the CSV results (Test 2 convergence, Test 3 NITER).

use super::experiments::{NamedMesh, gmsh_family, test2_polygonal, with_solution};
use super::records::{PaperTable3, Test2Row, Test3Row, read_csv};
use super::{Config, create_dir};
use crate::plot::{
    LineOptions, LineSeries, Marker, MeshPlotOptions, SurfaceOptions, palette, plot_lines,
    plot_mesh, plot_surface,
};
use gradvi::mesh::PolyMesh;
use gradvi::mesh::io::write_vtu;
use gradvi::post::contact::switch_point;
use gradvi::post::fields::EntityFields;
use gradvi::problem::{Problem, paper_test1, paper_test2, paper_test3};
use gradvi::scheme::SchemeKind;
use gradvi::solver::Solution;

fn tags_test2(mesh: &PolyMesh) -> PolyMesh {
    mesh.with_boundary_tags(|x| {
        if x[1] < 1e-12 || x[1] > 1.0 - 1e-12 {
            1
        } else if x[0] < 1e-12 {
            3
        } else {
            2
        }
    })
}

fn labels() -> Vec<(i32, String)> {
    vec![
        (1, "Γ1 (Dirichlet)".into()),
        (2, "Γ2 (Neumann)".into()),
        (3, "Γ3 (Signorini)".into()),
    ]
}

/// A 3D view of the HMM solution titled `title` as seen from `view` (azimuth, elevation), and a
/// VTU file of it; with a marker at the switch point of the contact condition along `axis` on
/// Γ3 if asked.
fn surface(
    cfg: &Config,
    name: &str,
    m: &NamedMesh,
    problem: &Problem,
    (title, view): (String, [f64; 2]),
    switch_axis: Option<usize>,
) -> gradvi::Result<()> {
    with_solution(&m.mesh, SchemeKind::Hmm, problem, |sol: &Solution| {
        let scheme = sol.system.scheme();
        let mut opts = SurfaceOptions {
            title,
            azimuth: view[0],
            elevation: view[1],
            ..Default::default()
        };
        if let (Some(axis), Some(cons)) = (switch_axis, sol.constraints.as_ref())
            && let Some(sw) = switch_point(scheme, cons, &sol.result.active, axis)
        {
            let (p, name) = if axis == 0 {
                ([sw.at, 0.0], "x")
            } else {
                ([0.0, sw.at], "y")
            };
            let text = format!("switch at {name} = {:.3}", sw.at);
            opts.markers.push(([p[0], p[1], 0.0], text));
        }
        let verts = scheme.vertex_values(sol.u());
        plot_surface(
            &cfg.figures().join(format!("{name}.png")),
            &m.mesh,
            &verts,
            &opts,
        )?;
        // the active cell unknowns (none when the constraints are on faces)
        let active = sol.constraints.as_ref().and_then(|c| {
            let dofs = c.dofs.iter().map(|d| d.dof);
            EntityFields::new(scheme, dofs, |j| f64::from(u8::from(sol.result.active[j]))).cell
        });
        let active = active.unwrap_or_else(|| vec![0.0; m.mesh.n_cells()]);
        let cells = scheme.cell_values(sol.u());
        write_vtu(
            cfg.vtu().join(format!("{name}.vtu")),
            &m.mesh,
            &[("u_vertex", &verts)],
            &[("u_K", &cells), ("active_cell", &active)],
        )
    })
}

/// A picture of `mesh` with the boundary parts of Test 2 and a dashed line at the interface
/// y = 1/2.
fn test2_mesh(cfg: &Config, name: &str, mesh: &PolyMesh, title: String) -> gradvi::Result<()> {
    let opts = MeshPlotOptions {
        title,
        boundary_labels: labels(),
        hlines: vec![0.5],
        ..Default::default()
    };
    plot_mesh(&cfg.figures().join(name), &tags_test2(mesh), &opts)
}

/// Draws every figure of the paper (and writes the VTU files of the plotted solutions), then
/// the plots drawn from the CSV files ([`plots_from_csv`]).
pub fn run(cfg: &Config, progress: &mut dyn FnMut(&str)) -> gradvi::Result<()> {
    create_dir(&cfg.figures())?;
    create_dir(&cfg.vtu())?;
    let fine = if cfg.quick { 0 } else { 1 };
    // Figure 4.1: Test 1 at h = 0.05 (test1_2), with the switch point on Γ3
    if let Some(m) = gmsh_family(cfg, "test1")?.get(fine) {
        let title = format!("Test 1, HMM, {} (h = {:.3})", m.name, m.mesh.h());
        surface(
            cfg,
            "fig4_1_test1",
            m,
            &paper_test1(),
            (title, [-30.0, 25.0]),
            Some(0),
        )?;
        progress("figure 4.1 done");
    }
    figures_test2(cfg, progress)?;
    // Figure 4.5: Test 3, h = 0.05 (test3_2), C = −20
    if let Some(m) = gmsh_family(cfg, "test3")?.get(fine) {
        let title = format!("Test 3, HMM, C = -20, {} (h = {:.3})", m.name, m.mesh.h());
        surface(
            cfg,
            "fig4_5_test3",
            m,
            &paper_test3(-20.0),
            (title, [-37.5, 30.0]),
            None,
        )?;
        progress("figure 4.5 done");
    }
    plots_from_csv(cfg)?;
    progress("convergence and NITER plots done");
    Ok(())
}

/// Figures 4.2–4.4: the geometry of Test 2, a typical hexagonal grid, the HMM solutions on it
/// and on the Kershaw mesh (x and y exchanged).
fn figures_test2(cfg: &Config, progress: &mut dyn FnMut(&str)) -> gradvi::Result<()> {
    let corners = vec![
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 0.5],
        [0.0, 0.5],
        [1.0, 1.0],
        [0.0, 1.0],
    ];
    let geo = PolyMesh::from_cells(corners, vec![vec![0, 1, 2, 3], vec![3, 2, 4, 5]])?;
    let opts = MeshPlotOptions {
        title: "Test 2: geometry and diffusion".into(),
        boundary_labels: labels(),
        annotations: vec![
            ([0.5, 0.25], "A = 100 I".into()),
            ([0.5, 0.75], "A = I".into()),
        ],
        ..Default::default()
    };
    plot_mesh(
        &cfg.figures().join("fig4_2_geometry.png"),
        &tags_test2(&geo),
        &opts,
    )?;
    let polys = test2_polygonal(cfg)?;
    let view = [50.0, 25.0];
    let hex_idx = if cfg.quick { 1 } else { 2 };
    let mut hex = polys
        .iter()
        .filter(|(f, _)| f == "hexagonal")
        .map(|(_, m)| m);
    if let Some(m) = hex.nth(hex_idx) {
        let what = format!("{} (h = {:.3})", m.name, m.mesh.h());
        test2_mesh(
            cfg,
            "fig4_2_grid.png",
            &m.mesh,
            format!("Hexagonal grid {what}"),
        )?;
        let title = format!("Test 2, HMM, {what}");
        surface(
            cfg,
            "fig4_3_test2_hexagonal",
            m,
            &paper_test2(),
            (title, view),
            Some(1),
        )?;
        progress("figures 4.2, 4.3 done");
    }
    if let Some((_, m)) = polys.iter().find(|(f, _)| f == "kershaw-transposed") {
        let what = format!("x and y exchanged (h = {:.3})", m.mesh.h());
        let title = format!("Test 2, HMM, Kershaw mesh, {what}");
        surface(
            cfg,
            "fig4_4_test2_kershaw",
            m,
            &paper_test2(),
            (title, view),
            Some(1),
        )?;
        let title = format!("Kershaw mesh mesh4_1_2, {what}");
        test2_mesh(cfg, "fig4_4_kershaw_mesh.png", &m.mesh, title)?;
        progress("figure 4.4 done");
    }
    Ok(())
}

/// The plots drawn from the CSV files only: the Test 2 errors against h (a colour per method,
/// solid for u and dashed for ∇u) and the Test 3 NITER against the number of cells (a colour per
/// C, solid for ours and dashed for the paper's).
pub fn plots_from_csv(cfg: &Config) -> gradvi::Result<()> {
    super::three_d::figures::plots_from_csv(cfg, &super::three_d::CASES)?;
    let rows: Vec<Test2Row> = read_csv(&cfg.results().join("test2.csv"))?;
    let mut series = Vec::new();
    let methods = [
        ("hexagonal", "hmm", "HMM, hexagonal"),
        ("triangles", "hmm", "HMM, triangles"),
        ("triangles", "p1", "P1, triangles"),
    ];
    for (i, (fam, scheme, label)) in methods.into_iter().enumerate() {
        let of = |r: &&Test2Row| r.family == fam && r.scheme == scheme;
        for (what, grad) in [("u", false), ("∇u", true)] {
            let pts: Vec<[f64; 2]> = (rows.iter().filter(of))
                .map(|r| [r.h, if grad { r.err_grad } else { r.err_u }])
                .collect();
            if !pts.is_empty() {
                series.push(LineSeries {
                    color: Some(palette(i)),
                    marker: if grad { Marker::Square } else { Marker::Circle },
                    dashed: grad,
                    ..LineSeries::new(format!("{label}: {what}"), pts)
                });
            }
        }
    }
    if let Some(first) = rows.iter().find(|r| r.family == "hexagonal") {
        let (h0, e0) = (first.h, first.err_grad);
        series.push(LineSeries {
            color: Some([120, 120, 120]),
            marker: Marker::None,
            dashed: true,
            ..LineSeries::new("slope 1", vec![[h0, e0], [h0 / 8.0, e0 / 8.0]])
        });
    }
    plot_lines(
        &cfg.figures().join("test2_convergence.png"),
        &series,
        &LineOptions {
            title: "Test 2: relative L2 errors".into(),
            x_label: "h".into(),
            y_label: "relative error".into(),
            log_x: true,
            log_y: true,
            ..Default::default()
        },
    )?;
    let rows3: Vec<Test3Row> = read_csv(&cfg.results().join("test3.csv"))?;
    let paper: Vec<PaperTable3> = read_csv(&cfg.paper.join("table3.csv"))?;
    let mut series = Vec::new();
    for (i, c) in super::experiments::TEST3_C.into_iter().enumerate() {
        let sorted = |mut pts: Vec<[f64; 2]>| {
            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
            pts
        };
        let ours = (rows3.iter().filter(|r| r.scheme == "hmm" && r.c == c))
            .map(|r| [r.n_cells as f64, r.niter as f64]);
        let theirs =
            (paper.iter().filter(|r| r.c == c)).map(|r| [r.n_cells as f64, r.niter as f64]);
        for (label, pts, dashed) in [
            (
                format!("gradvi HMM, C = {c}"),
                sorted(ours.collect()),
                false,
            ),
            (format!("paper, C = {c}"), sorted(theirs.collect()), true),
        ] {
            series.push(LineSeries {
                color: Some(palette(i)),
                marker: if dashed {
                    Marker::Square
                } else {
                    Marker::Circle
                },
                dashed,
                ..LineSeries::new(label, pts)
            });
        }
    }
    plot_lines(
        &cfg.figures().join("test3_niter.png"),
        &series,
        &LineOptions {
            title: "Test 3: NITER of the monotony algorithm".into(),
            x_label: "number of cells".into(),
            y_label: "NITER".into(),
            log_x: true,
            ..Default::default()
        },
    )?;
    Ok(())
}
