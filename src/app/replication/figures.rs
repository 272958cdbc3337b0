//! Figures 4.1–4.5 of the paper (PNG), VTU files of the plotted solutions, and two extra
//! plots drawn from the CSV results (Test 2 convergence, Test 3 NITER).

use super::experiments::{NamedMesh, gmsh_family, test2_polygonal, with_solution};
use super::records::{PaperTable3, Test2Row, Test3Row, read_csv};
use super::{Config, create_dir};
use gradvi::mesh::PolyMesh;
use gradvi::mesh::io::write_vtu;
use crate::app::plot::{
    Field, LineOptions, LineSeries, MeshPlotOptions, SurfaceOptions, plot_lines, plot_mesh,
    plot_surface,
};
use gradvi::post::contact::switch_point;
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

/// Surface plot of the HMM solution and a VTU file of it; returns the solution's switch point
/// along `axis` on Γ3 if asked.
fn surface(
    cfg: &Config,
    name: &str,
    m: &NamedMesh,
    problem: &Problem,
    mut opts: SurfaceOptions,
    switch_axis: Option<usize>,
) -> gradvi::Result<Option<f64>> {
    with_solution(&m.mesh, SchemeKind::Hmm, problem, |sol: &Solution| {
        let scheme = sol.system.scheme();
        let cells = scheme.cell_values(sol.u());
        let mut at = None;
        if let (Some(axis), Some(cons)) = (switch_axis, sol.constraints.as_ref())
            && let Some(sw) = switch_point(cons, &sol.result.active, axis)
        {
            let p = if axis == 0 {
                [sw.at, 0.0]
            } else {
                [0.0, sw.at]
            };
            let name = if axis == 0 { "x" } else { "y" };
            opts.markers.push((
                [p[0], p[1], 0.0],
                format!("switch at {name} = {:.3}", sw.at),
            ));
            at = Some(sw.at);
        }
        let verts = scheme.vertex_values(sol.u());
        plot_surface(
            &cfg.figures().join(format!("{name}.png")),
            &m.mesh,
            Field::Vertex(&verts),
            &opts,
        )?;
        let active: Vec<f64> = {
            let a = sol.active_field();
            let n_skel = scheme.n_skeleton();
            // cell unknowns follow the skeleton ones (HMM)
            (0..m.mesh.n_cells())
                .map(|k| a.get(n_skel + k).copied().unwrap_or(0.0))
                .collect()
        };
        write_vtu(
            cfg.vtu().join(format!("{name}.vtu")),
            &m.mesh,
            &[("u_vertex", &verts)],
            &[("u_K", &cells), ("active_cell", &active)],
        )?;
        Ok(at)
    })
}

/// Draws every figure. Returns (figure file, caption) pairs for the report.
pub fn run(cfg: &Config, progress: &mut dyn FnMut(&str)) -> gradvi::Result<()> {
    create_dir(&cfg.figures())?;
    create_dir(&cfg.vtu())?;
    let pick = |v: Vec<NamedMesh>, i: usize| v.into_iter().nth(i);

    // Figure 4.1: Test 1 at h = 0.05 (test1_2), with the switch point on Γ3
    let t1 = gmsh_family(cfg, "test1")?;
    let idx = if cfg.quick { 0 } else { 1 };
    if let Some(m) = pick(t1, idx) {
        let opts = SurfaceOptions {
            title: format!("Test 1, HMM, {} (h = {:.3})", m.name, m.mesh.h()),
            azimuth: -30.0,
            elevation: 25.0,
            ..Default::default()
        };
        surface(cfg, "fig4_1_test1", &m, &paper_test1(), opts, Some(0))?;
        progress("figure 4.1 done");
    }

    // Figure 4.2: geometry and a typical hexagonal grid
    let geo = PolyMesh::from_cells(
        vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 0.5],
            [0.0, 0.5],
            [1.0, 1.0],
            [0.0, 1.0],
        ],
        vec![vec![0, 1, 2, 3], vec![3, 2, 4, 5]],
    )?;
    plot_mesh(
        &cfg.figures().join("fig4_2_geometry.png"),
        &tags_test2(&geo),
        &MeshPlotOptions {
            title: "Test 2: geometry and diffusion".into(),
            boundary_labels: labels(),
            annotations: vec![
                ([0.5, 0.25], "A = 100 I".into()),
                ([0.5, 0.75], "A = I".into()),
            ],
            ..Default::default()
        },
    )?;
    let polys = test2_polygonal(cfg)?;
    let hex_idx = if cfg.quick { 1 } else { 2 };
    let hex = polys
        .iter()
        .filter(|(f, _)| f == "hexagonal")
        .nth(hex_idx)
        .map(|(_, m)| m);
    if let Some(m) = hex {
        plot_mesh(
            &cfg.figures().join("fig4_2_grid.png"),
            &tags_test2(&m.mesh),
            &MeshPlotOptions {
                title: format!("Hexagonal grid {} (h = {:.3})", m.name, m.mesh.h()),
                boundary_labels: labels(),
                hlines: vec![0.5],
                ..Default::default()
            },
        )?;
        // Figure 4.3: HMM solution of Test 2 on that mesh
        let opts = SurfaceOptions {
            title: format!("Test 2, HMM, {} (h = {:.3})", m.name, m.mesh.h()),
            azimuth: 50.0,
            elevation: 25.0,
            ..Default::default()
        };
        surface(
            cfg,
            "fig4_3_test2_hexagonal",
            m,
            &paper_test2(),
            opts,
            Some(1),
        )?;
        progress("figures 4.2, 4.3 done");
    }
    // Figure 4.4: Kershaw
    if let Some((_, m)) = polys.iter().find(|(f, _)| f == "kershaw-transposed") {
        let opts = SurfaceOptions {
            title: format!(
                "Test 2, HMM, Kershaw mesh, x and y exchanged (h = {:.3})",
                m.mesh.h()
            ),
            azimuth: 50.0,
            elevation: 25.0,
            ..Default::default()
        };
        surface(
            cfg,
            "fig4_4_test2_kershaw",
            m,
            &paper_test2(),
            opts,
            Some(1),
        )?;
        plot_mesh(
            &cfg.figures().join("fig4_4_kershaw_mesh.png"),
            &tags_test2(&m.mesh),
            &MeshPlotOptions {
                title: format!(
                    "Kershaw mesh mesh4_1_2, x and y exchanged (h = {:.3})",
                    m.mesh.h()
                ),
                hlines: vec![0.5],
                boundary_labels: labels(),
                ..Default::default()
            },
        )?;
        progress("figure 4.4 done");
    }
    // Figure 4.5: Test 3, h = 0.05 (test3_2), C = −20
    let t3 = gmsh_family(cfg, "test3")?;
    let idx = if cfg.quick { 0 } else { 1 };
    if let Some(m) = pick(t3, idx) {
        let opts = SurfaceOptions {
            title: format!("Test 3, HMM, C = -20, {} (h = {:.3})", m.name, m.mesh.h()),
            ..Default::default()
        };
        surface(cfg, "fig4_5_test3", &m, &paper_test3(-20.0), opts, None)?;
        progress("figure 4.5 done");
    }
    plots_from_csv(cfg)?;
    progress("convergence and NITER plots done");
    Ok(())
}

/// The plots drawn from the CSV files only.
pub fn plots_from_csv(cfg: &Config) -> gradvi::Result<()> {
    let rows: Vec<Test2Row> = read_csv(&cfg.results().join("test2.csv"))?;
    let mut series = Vec::new();
    for (fam, scheme, label) in [
        ("hexagonal", "hmm", "HMM, hexagonal"),
        ("triangles", "hmm", "HMM, triangles"),
        ("triangles", "p1", "P1, triangles"),
    ] {
        for (what, pick) in [("u", 0), ("∇u", 1)] {
            let pts: Vec<[f64; 2]> = rows
                .iter()
                .filter(|r| r.family == fam && r.scheme == scheme)
                .map(|r| [r.h, if pick == 0 { r.err_u } else { r.err_grad }])
                .collect();
            if !pts.is_empty() {
                series.push(LineSeries::new(format!("{label}: {what}"), pts));
            }
        }
    }
    if let Some(first) = rows.iter().find(|r| r.family == "hexagonal") {
        let h0 = first.h;
        let e0 = first.err_grad;
        let mut s = LineSeries::new("slope 1", vec![[h0, e0], [h0 / 8.0, e0 / 8.0]]);
        s.dashed = true;
        s.marker = crate::app::plot::Marker::None;
        series.push(s);
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
    for c in super::experiments::TEST3_C {
        let mut pts: Vec<[f64; 2]> = rows3
            .iter()
            .filter(|r| r.scheme == "hmm" && r.c == c)
            .map(|r| [r.n_cells as f64, r.niter as f64])
            .collect();
        pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
        series.push(LineSeries::new(format!("gradvi HMM, C = {c}"), pts));
        let mut pp: Vec<[f64; 2]> = paper
            .iter()
            .filter(|r| r.c == c)
            .map(|r| [r.n_cells as f64, r.niter as f64])
            .collect();
        pp.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let mut s = LineSeries::new(format!("paper, C = {c}"), pp);
        s.dashed = true;
        series.push(s);
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
