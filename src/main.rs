//! The `gradvi` command line: mesh tools, single solves, the replication of the paper and the
//! cross-check against dolfinx. Run `gradvi --help` or `gradvi <command> --help`.

mod app;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::Family;
use gradvi::mesh::io::{read_mesh, write_typ2, write_vtu};
use gradvi::problem::{PROBLEM_NAMES, by_name};
use gradvi::scheme::{GradientDiscretisation, Hmm, P1, SchemeKind};
use gradvi::solver::{ActiveSetOptions, solve_problem};
use std::path::PathBuf;

/// Gradient schemes (HMM, P1) for the obstacle and Signorini problems.
#[derive(Parser)]
#[command(name = "gradvi", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh tools: statistics, generation, conversion.
    #[command(subcommand)]
    Mesh(MeshCommand),
    /// Solve one problem on one mesh with one scheme; prints NITER, the certificate, errors and
    /// timings; optionally writes VTU and JSON.
    Solve(SolveArgs),
    /// Reproduce the paper's tables and figures (results/*.csv, figures/*.png, REPORT.md).
    Replicate(ReplicateArgs),
    /// Compare gradvi's P1 and HMM with the dolfinx reference solves (CROSSCHECK.md).
    Crosscheck(app::crosscheck::CrosscheckArgs),
    /// The scaling benchmark (run by `make bench`; see README "Performance"). Arguments:
    /// `--report-only` rewrites BENCHMARKS.md from bench.csv; `--root DIR` is the repository.
    #[command(hide = true)]
    Bench {
        /// Arguments passed to the benchmark driver.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

#[derive(Subcommand)]
enum MeshCommand {
    /// Print the statistics of a mesh file (.msh, .typ1, .typ2).
    Info {
        /// The mesh file.
        file: PathBuf,
    },
    /// Generate a mesh of the unit square and write it (.typ2 or .vtu, by extension).
    Generate {
        /// cartesian, hexagonal or kershaw.
        family: String,
        /// Level (hexagonal k: the FVCA5 hexa1_k mesh; kershaw k: mesh4_1_k; cartesian k:
        /// 2^(k+1) × 2^(k+1) squares).
        #[arg(long)]
        level: usize,
        /// Output file (.typ2 or .vtu).
        #[arg(short, long)]
        output: PathBuf,
    },
}

#[derive(Args)]
struct SolveArgs {
    /// Problem: test1, test2, test3 (paper Section 4) or fvca5-1.1 (linear, exact solution).
    #[arg(long)]
    problem: String,
    /// Problem parameter key=value (repeatable), e.g. --param C=-10 for test3.
    #[arg(long = "param", value_parser = parse_param)]
    params: Vec<(String, f64)>,
    /// Mesh file (.msh, .typ1, .typ2).
    #[arg(long, conflicts_with = "generate")]
    mesh: Option<PathBuf>,
    /// Generate the mesh instead: cartesian, hexagonal or kershaw (with --level).
    #[arg(long, requires = "level")]
    generate: Option<String>,
    /// Level of the generated mesh.
    #[arg(long)]
    level: Option<usize>,
    /// Scheme: hmm or p1.
    #[arg(long, default_value = "hmm")]
    scheme: String,
    /// HMM stabilisation parameter α.
    #[arg(long, default_value_t = 1.0)]
    alpha: f64,
    /// Active-set parameter c (> 0).
    #[arg(long, default_value_t = 1.0)]
    c: f64,
    /// Maximum number of linear solves of the active-set method.
    #[arg(long, default_value_t = 500)]
    max_solves: usize,
    /// Tolerance of the certificate.
    #[arg(long, default_value_t = 1e-10)]
    tol: f64,
    /// On cycling or non-convergence, fall back to projected Gauss–Seidel.
    #[arg(long)]
    fallback: bool,
    /// Start of the active-set iteration: cold (A₀ = ∅, the paper's algorithm and NITER) or
    /// nested (an active set predicted by coarse Cartesian HMM solves of the same problem;
    /// same solution, far fewer solves on fine meshes; rectangular domains).
    #[arg(long, default_value = "cold")]
    warm_start: String,
    /// Write the solution (u, active set, multiplier) to this VTU file.
    #[arg(long)]
    vtu: Option<PathBuf>,
    /// Write a JSON summary to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

#[derive(Args)]
struct ReplicateArgs {
    /// The replication directory.
    #[arg(long, default_value = "replication")]
    out: PathBuf,
    /// The directory of the gmsh meshes.
    #[arg(long, default_value = "meshes")]
    meshes: PathBuf,
    /// The directory of the paper's values (CSV data typed from the paper).
    #[arg(long, default_value = "replication/paper")]
    paper: PathBuf,
    /// Directory of the original FVCA5 mesh files (hexa1_*.typ2, mesh4_1_2.typ2), optional.
    #[arg(long)]
    fvca5: Option<PathBuf>,
    /// Coarsest meshes only (a smoke run).
    #[arg(long)]
    quick: bool,
    /// Only rewrite REPORT.md and the CSV-based plots from existing CSV files.
    #[arg(long)]
    report_only: bool,
}

fn parse_param(s: &str) -> Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected key=value, got '{s}'"))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("'{v}' is not a number"))?;
    Ok((k.trim().to_string(), v))
}

fn generate(family: &str, level: usize) -> Result<PolyMesh> {
    let fam: Family = family.parse()?;
    Ok(fam.generate(level)?)
}

fn mesh_info(file: &PathBuf) -> Result<()> {
    let m = read_mesh(file)?;
    let mut sides = std::collections::BTreeMap::new();
    for k in 0..m.n_cells() {
        *sides.entry(m.cell_vertices(k).len()).or_insert(0usize) += 1;
    }
    let area: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
    let bb = m.bounding_box();
    let mut tags = std::collections::BTreeMap::new();
    for &e in m.boundary_edges() {
        *tags.entry(m.edge_tag(e)).or_insert(0usize) += 1;
    }
    println!("file            {}", file.display());
    println!("cells           {}", m.n_cells());
    println!("vertices        {}", m.n_vertices());
    println!(
        "edges           {} ({} on the boundary)",
        m.n_edges(),
        m.boundary_edges().len()
    );
    println!("h (max diam.)   {:.6}", m.h());
    println!("total area      {area:.12}");
    println!(
        "bounding box    [{}, {}] x [{}, {}]",
        bb[0], bb[2], bb[1], bb[3]
    );
    let s: Vec<String> = sides.iter().map(|(n, c)| format!("{n}:{c}")).collect();
    println!("cells by sides  {}", s.join(" "));
    let t: Vec<String> = tags.iter().map(|(t, c)| format!("tag {t}: {c}")).collect();
    println!("boundary edges  {}", t.join(", "));
    Ok(())
}

fn solve(a: &SolveArgs) -> Result<()> {
    let mesh = match (&a.mesh, &a.generate) {
        (Some(f), None) => read_mesh(f)?,
        (None, Some(fam)) => generate(fam, a.level.unwrap_or(1))?,
        _ => bail!("give either --mesh FILE or --generate FAMILY --level K"),
    };
    let problem = by_name(&a.problem, &a.params)
        .with_context(|| format!("known problems: {}", PROBLEM_NAMES.join(", ")))?;
    let kind: SchemeKind = a.scheme.parse()?;
    let scheme: Box<dyn GradientDiscretisation> = match kind {
        SchemeKind::Hmm => Box::new(Hmm::with_alpha(&mesh, a.alpha)?),
        SchemeKind::P1 => Box::new(P1::new(&mesh)?),
    };
    let opts = ActiveSetOptions {
        c: a.c,
        max_solves: a.max_solves,
        tol: a.tol,
        fallback: a.fallback,
        warm_start: a.warm_start.parse()?,
        progress: Some(|l| {
            eprintln!(
                "  solve {:>3}: active {} (+{}, -{}), violation {:.2e}, {:.2} s",
                l.solve,
                l.active,
                l.entered,
                l.left,
                l.violation,
                l.timings.assemble + l.timings.factor + l.timings.solve
            )
        }),
        ..Default::default()
    };
    eprintln!(
        "solving {} with {} on {} cells ({} unknowns)...",
        problem.name,
        kind,
        mesh.n_cells(),
        scheme.n_unknowns()
    );
    let sol = solve_problem(scheme.as_ref(), &problem, &opts)?;
    println!("problem         {}", problem.name);
    println!("scheme          {kind}");
    println!(
        "mesh            {} cells, h = {:.6}",
        mesh.n_cells(),
        mesh.h()
    );
    println!(
        "unknowns        {} ({} after condensation)",
        sol.system.n_unknowns(),
        sol.system.n_condensed()
    );
    println!("method          {:?}", sol.result.method);
    if let Some(w) = &sol.warm_start {
        match &w.skipped {
            Some(why) => println!("warm start      skipped, cold start: {why}"),
            None => {
                let lv: Vec<String> = w.levels.iter().map(|(x, y)| format!("{x}x{y}")).collect();
                println!(
                    "warm start      nested: {} coarse solves on {}, {} unknowns predicted active, {:.3} s",
                    w.coarse_solves,
                    lv.join(", "),
                    w.predicted_active,
                    w.seconds
                );
            }
        }
    }
    println!("NITER           {} (linear solves)", sol.niter());
    println!("  solve  active  entered  left  violation  residual");
    for l in &sol.result.log {
        println!(
            "  {:>5}  {:>6}  {:>7}  {:>4}  {:>9.2e}  {:>8.2e}",
            l.solve, l.active, l.entered, l.left, l.violation, l.residual
        );
    }
    let c = sol.result.certificate;
    println!(
        "certificate     violation {:.2e}, min multiplier {:.2e}, complementarity {:.2e}, balance residual {:.2e} (tolerance {:.0e})",
        c.max_violation, c.min_multiplier, c.complementarity, c.balance_residual, a.tol
    );
    let errors = problem
        .exact
        .as_ref()
        .map(|ex| gradvi::post::relative_errors(scheme.as_ref(), sol.u(), &ex.u, &ex.grad));
    if let Some(e) = errors {
        println!(
            "errors          relative L2 of u at centroids {:.6e}, of the gradient {:.6e}",
            e.l2_u, e.l2_grad
        );
    }
    let t = sol.timings;
    println!(
        "timings [s]     setup {:.3} (symbolic {:.3}), warm start {:.3}, assembly {:.3}, factorisation {:.3}, solves {:.3}, total {:.3}",
        t.setup, t.symbolic, t.warm_start, t.assemble, t.factor, t.solve, t.total
    );
    if let Some(path) = &a.vtu {
        let u = sol.u();
        let act = sol.active_field();
        let lam = sol.multiplier_field();
        let cells = scheme.cell_values(u);
        let verts = scheme.vertex_values(u);
        let grads = scheme.cell_gradients(u);
        let gx: Vec<f64> = grads.iter().map(|g| g[0]).collect();
        let gy: Vec<f64> = grads.iter().map(|g| g[1]).collect();
        let mut cell_data: Vec<(&str, Vec<f64>)> =
            vec![("u_K", cells), ("grad_x", gx), ("grad_y", gy)];
        let mut point_data: Vec<(&str, Vec<f64>)> = vec![("u_vertex", verts)];
        match kind {
            SchemeKind::Hmm => {
                let n = sol.system.n_condensed();
                cell_data.push(("active_cell", act[n..].to_vec()));
                cell_data.push(("multiplier_cell", lam[n..].to_vec()));
            }
            SchemeKind::P1 => {
                point_data.push(("active", act.clone()));
                point_data.push(("multiplier", lam.clone()));
            }
        }
        let pd: Vec<(&str, &[f64])> = point_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
        let cd: Vec<(&str, &[f64])> = cell_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
        write_vtu(path, &mesh, &pd, &cd)?;
        println!("wrote           {}", path.display());
    }
    if let Some(path) = &a.json {
        let j = serde_json::json!({
            "problem": problem.name,
            "scheme": kind,
            "n_cells": mesh.n_cells(),
            "h": mesh.h(),
            "n_unknowns": sol.system.n_unknowns(),
            "n_constrained": sol.constraints.as_ref().map_or(0, |c| c.dofs.len()),
            "n_active": sol.result.active.iter().filter(|&&x| x).count(),
            "niter": sol.niter(),
            "warm_start": sol.warm_start,
            "method": format!("{:?}", sol.result.method),
            "certificate": c,
            "errors": errors,
            "timings": t,
            "log": sol.result.log,
        });
        std::fs::write(path, serde_json::to_string_pretty(&j)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote           {}", path.display());
    }
    Ok(())
}

fn replicate(a: &ReplicateArgs) -> Result<()> {
    let cfg = app::replication::Config {
        out: a.out.clone(),
        meshes: a.meshes.clone(),
        fvca5: a.fvca5.clone(),
        paper: a.paper.clone(),
        quick: a.quick,
    };
    let root = std::env::current_dir()?;
    let mut progress = |s: &str| eprintln!("  {s}");
    if !a.report_only {
        let t0 = std::time::Instant::now();
        eprintln!("running the experiments of the paper's Section 4 (HMM and P1)...");
        let mut timings = app::replication::experiments::run(&cfg, &mut progress)?;
        let t = std::time::Instant::now();
        eprintln!("drawing the figures...");
        app::replication::figures::run(&cfg, &mut progress)?;
        timings.push(app::replication::records::TimingRow {
            stage: "figures".into(),
            seconds: t.elapsed().as_secs_f64(),
        });
        app::replication::records::write_csv(&cfg.results().join("timings.csv"), &timings)?;
        eprintln!(
            "experiments and figures: {:.1} s",
            t0.elapsed().as_secs_f64()
        );
    } else {
        app::replication::figures::plots_from_csv(&cfg)?;
    }
    app::replication::report::write(&cfg, &root)?;
    eprintln!("wrote {}", cfg.out.join("REPORT.md").display());
    Ok(())
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match &cli.command {
        Command::Mesh(MeshCommand::Info { file }) => mesh_info(file),
        Command::Mesh(MeshCommand::Generate {
            family,
            level,
            output,
        }) => {
            let m = generate(family, *level)?;
            match output.extension().and_then(|e| e.to_str()) {
                Some("typ2") => write_typ2(output, &m)?,
                Some("vtu") => write_vtu(output, &m, &[], &[])?,
                _ => bail!(
                    "unknown output format for {} (use .typ2 or .vtu)",
                    output.display()
                ),
            }
            eprintln!(
                "wrote {} ({} cells, h = {:.6})",
                output.display(),
                m.n_cells(),
                m.h()
            );
            Ok(())
        }
        Command::Solve(a) => solve(a),
        Command::Replicate(a) => replicate(a),
        Command::Crosscheck(a) => app::crosscheck::run(a),
        Command::Bench { args } => {
            let root = std::env::current_dir()?;
            Ok(app::bench::main_with_args(&root, args)?)
        }
    }
}
