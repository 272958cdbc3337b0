//! `gradvi solve`: one problem on one mesh with one scheme; prints NITER, the iteration log,
//! the certificate, errors and timings; optionally writes VTU and JSON.

use super::output::{atomic, check_distinct};
use anyhow::{Context, Result, bail};
use clap::Args;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use gradvi::assembly::LinearSolver;
use gradvi::budget::MemoryBudget;
use gradvi::case::AnyMesh;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::Family;
use gradvi::mesh::io::write_vtu;
use gradvi::mesh::solve_mesh::SolveMesh;
use gradvi::mesh3d::generate::Family3;
use gradvi::post::Errors;
use gradvi::post::fields::EntityFields;
use gradvi::problem::file;
use gradvi::scheme::{GradientDiscretisation, SchemeKind, SchemeOptions, build_with};
use gradvi::solver::{
    ActiveSetOptions, IterationLog, Solution, SolveOptions, WarmStart, solve_problem,
};
use std::path::{Path, PathBuf};

#[derive(Args)]
#[command(
    after_help = "A problem of your own is a TOML file: see \"Your own problem\" in README.md \
and the format in problems/README.md (examples: problems/*.toml)."
)]
pub struct SolveArgs {
    /// A problem file (TOML; format: problems/README.md). Give this or --problem.
    #[arg(conflicts_with = "problem", required_unless_present = "problem")]
    file: Option<PathBuf>,
    /// A built-in problem: test1, test2, test3 (paper Section 4) or fvca5-1.1 (linear, exact
    /// solution); served from the files problems/NAME.toml compiled into gradvi.
    #[arg(long)]
    problem: Option<String>,
    /// Problem parameter name=value (repeatable), e.g. --param C=-10 for test3.
    #[arg(long = "param", value_parser = parse_param)]
    params: Vec<(String, f64)>,
    /// Mesh file, 2D (.msh, .typ1, .typ2) or 3D (.msh of 3D elements, .vtu, HArDCore RF
    /// .node/.ele), as `gradvi mesh info` reads it; replaces the problem file's [mesh]
    /// entirely (its `domain` is not applied). A 3D mesh gives a 3D solve.
    #[arg(long, conflicts_with = "generate")]
    pub(crate) mesh: Option<PathBuf>,
    /// Generate the mesh instead: 2D cartesian, hexagonal, kershaw or triangles (the Cartesian
    /// squares cut by a diagonal, for P1); 3D cubes, kuhn (or tetrahedra), prisms, refined or
    /// warped (a 3D solve). Keeps the problem file's `domain` (of the same dimension), and its
    /// `level` unless --level is given.
    #[arg(long)]
    generate: Option<String>,
    /// Level of the generated mesh: with --generate, or alone to change the level of the
    /// problem file's generated mesh (same family and domain).
    #[arg(long)]
    level: Option<usize>,
    /// 3D: faces that are not planar kept whole (fan) or split into triangles (split), as for
    /// `gradvi mesh generate --warped-faces`. No effect in 2D.
    #[arg(long, default_value = "fan", value_parser = crate::mesh::warped_faces())]
    warped_faces: gradvi::mesh3d::WarpedFaces,
    /// The scheme (default: the problem file's `scheme`, else hmm).
    #[arg(long, value_parser = named::<SchemeKind>(SchemeKind::ALL.iter().map(|k| k.name())))]
    pub(crate) scheme: Option<SchemeKind>,
    /// HMM stabilisation parameter α.
    #[arg(long, default_value_t = 1.0)]
    pub(crate) alpha: f64,
    /// Active-set parameter c (> 0).
    #[arg(long, default_value_t = 1.0)]
    c: f64,
    /// Maximum number of linear solves of the active-set method.
    #[arg(long, default_value_t = 500)]
    max_solves: usize,
    /// Tolerance of the certificate.
    #[arg(long, default_value_t = 1e-10)]
    pub(crate) tol: f64,
    /// On cycling or non-convergence, fall back to projected Gauss–Seidel.
    #[arg(long)]
    fallback: bool,
    /// Start of the active-set iteration: nested (the default: an active set predicted by
    /// coarse HMM solves of the same problem on agglomerated meshes of the domain, and each
    /// next active set looked ahead by local solves near its changes; same solution, far fewer
    /// solves on fine meshes; 2D and 3D) or cold (A₀ = ∅, no look-ahead: the paper's
    /// algorithm and NITER).
    #[arg(long, value_parser = named::<WarmStart>(["cold", "nested"]))]
    pub(crate) warm_start: Option<WarmStart>,
    /// Linear solver of the condensed systems: auto (direct below 250 000 condensed unknowns in 2D, 20 000 in 3D,
    /// iterative above), direct (sparse Cholesky) or iterative (algebraic-multigrid
    /// preconditioned conjugate gradients, memory linear in the size).
    #[arg(long, default_value_t = LinearSolver::Auto,
          value_parser = named::<LinearSolver>(["auto", "direct", "iterative"]))]
    linear: LinearSolver,
    /// Write the solution (u, active set, multiplier) to this VTU file (2D and 3D; the
    /// fields are listed in README.md, "Outputs").
    #[arg(long)]
    pub(crate) vtu: Option<PathBuf>,
    /// 3D only (refused on a 2D mesh): also write NAME_faces.vtu beside --vtu NAME.vtu, every
    /// face of the mesh (interior and boundary) with the arrays of NAME_boundary.vtu.
    #[arg(long, requires = "vtu")]
    pub(crate) vtu_faces: bool,
    /// Write a JSON summary to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// The parser of an option whose values are the names of a library type: `names` (listed in the
/// help and checked by clap), turned into a `T` by its `FromStr`.
fn named<T>(names: impl IntoIterator<Item = &'static str>) -> impl TypedValueParser<Value = T>
where
    T: std::str::FromStr<Err = gradvi::Error> + Clone + Send + Sync + 'static,
{
    PossibleValuesParser::new(names).try_map(|s| s.parse::<T>())
}

pub fn parse_param(s: &str) -> Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected key=value, got '{s}'"))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("'{v}' is not a number"))?;
    Ok((k.trim().to_string(), v))
}

/// Generates a mesh of the unit square, within the memory the machine has free.
pub fn generate(family: &str, level: usize) -> Result<PolyMesh> {
    let fam: Family = family.parse()?;
    Ok(fam.generate(level, MemoryBudget::available())?)
}

/// Rejects absurd or conflicting options before any work: the certificate tolerance must be
/// finite and in (0, 1) (a tolerance of 1 or more, or infinite, would switch the certificate
/// off), the numeric options finite, and a parameter given once.
fn check_options(a: &SolveArgs) -> Result<()> {
    if !(a.tol > 0.0 && a.tol < 1.0) {
        bail!(
            "--tol must be in (0, 1), got {} (the certificate would be meaningless)",
            a.tol
        );
    }
    if !(a.c > 0.0 && a.c.is_finite()) {
        bail!("--c must be positive and finite, got {}", a.c);
    }
    if a.level.is_some() && a.mesh.is_some() {
        bail!("--level is only meaningful with --generate (the mesh comes from --mesh)");
    }
    if a.max_solves == 0 {
        bail!("--max-solves must be at least 1");
    }
    for (i, (k, v)) in a.params.iter().enumerate() {
        if !v.is_finite() {
            bail!("--param {k}={v}: parameters must be finite");
        }
        if a.params[..i]
            .iter()
            .any(|(k2, _)| k2.eq_ignore_ascii_case(k))
        {
            bail!("--param {k} is given twice");
        }
    }
    Ok(())
}

/// Outputs distinct from the inputs (the mesh, the problem file and the mesh the problem file
/// names) and from each other, and from `extra_outputs` (the boundary VTU of a 3D solve).
pub(crate) fn check_paths(
    a: &SolveArgs,
    pf: &file::ProblemFile,
    extra_outputs: &[(&str, &Path)],
) -> Result<()> {
    let pf_mesh = match &pf.mesh {
        Some(file::MeshSpec::File(m)) => Some(m.as_path()),
        _ => None,
    };
    let inputs: Vec<(&str, &Path)> = [
        ("mesh", a.mesh.as_deref()),
        ("problem", a.file.as_deref()),
        ("mesh", pf_mesh),
    ]
    .into_iter()
    .filter_map(|(w, p)| p.map(|p| (w, p)))
    .collect();
    let outputs: Vec<(&str, &Path)> = [("VTU", a.vtu.as_deref()), ("JSON", a.json.as_deref())]
        .into_iter()
        .filter_map(|(w, p)| p.map(|p| (w, p)))
        .chain(extra_outputs.iter().copied())
        .collect();
    check_distinct(&inputs, &outputs)
}

/// The mesh of a solve: the problem file's `[mesh]` (`file_mesh`, read from `problem`) with
/// the command line's `--mesh`, `--generate` and `--level` applied.
///
/// | command line | file: `generate` F, `level` L, `domain` D | file: `file` M₀ | no `[mesh]` |
/// |---|---|---|---|
/// | — | F level L on D | M₀ | error |
/// | `--mesh M` | M (D is not applied) | M | M |
/// | `--generate G` | G level L on D | error (no level) | error (no level) |
/// | `--generate G --level K` | G level K on D | G level K | G level K |
/// | `--level K` | F level K on D | error (a file has no level) | error |
///
/// F and G are 2D or 3D families; the domain D is kept for a family of its dimension (a 2D
/// domain with a 3D family, or the converse, is an error). The level is checked against the
/// family here, so that an error says where it came from. `--mesh` with `--level` or
/// `--generate` is an error (also refused earlier, by `check_options` and by clap).
fn resolve_mesh(
    mesh: Option<&Path>,
    generate: Option<&str>,
    level: Option<usize>,
    file_mesh: Option<&file::MeshSpec>,
    problem: &Path,
) -> Result<file::MeshSpec> {
    use file::MeshSpec;
    // the level of the problem file's mesh, when it is generated
    let file_level = match file_mesh {
        Some(MeshSpec::Generated { level, .. } | MeshSpec::Generated3 { level, .. }) => {
            Some(*level)
        }
        _ => None,
    };
    let (spec, origin) = match (mesh, generate, level) {
        (Some(_), _, Some(_)) => {
            bail!("--level is only meaningful with --generate (the mesh comes from --mesh)")
        }
        (Some(_), Some(_), None) => bail!("give --mesh FILE or --generate FAMILY, not both"),
        (Some(m), None, None) => return Ok(MeshSpec::File(m.to_path_buf())),
        (None, Some(g), level) => {
            let (k, origin) = match (level, file_level) {
                (Some(k), _) => (k, "--level".to_string()),
                (None, Some(l)) => (
                    l,
                    format!("the level of the [mesh] of {}", problem.display()),
                ),
                (None, None) => bail!(
                    "--generate {g} needs --level: {} has no generated [mesh] whose level \
                     could be kept",
                    problem.display()
                ),
            };
            (family_spec(g, k, file_mesh)?, origin)
        }
        (None, None, Some(k)) => match file_mesh {
            Some(&MeshSpec::Generated { family, domain, .. }) => (
                MeshSpec::Generated {
                    family,
                    level: k,
                    domain,
                },
                "--level".to_string(),
            ),
            Some(&MeshSpec::Generated3 { family, domain, .. }) => (
                MeshSpec::Generated3 {
                    family,
                    level: k,
                    domain,
                },
                "--level".to_string(),
            ),
            Some(MeshSpec::File(m)) => bail!(
                "--level needs --generate FAMILY: the mesh of {} is the file {}, which has no \
                 level",
                problem.display(),
                m.display()
            ),
            None => bail!(
                "--level needs --generate FAMILY: {} has no [mesh]",
                problem.display()
            ),
        },
        (None, None, None) => match file_mesh {
            Some(spec) => return Ok(spec.clone()),
            None => bail!(
                "give --mesh FILE or --generate FAMILY --level K ({} has no [mesh])",
                problem.display()
            ),
        },
    };
    check_level(&spec, &origin)?;
    Ok(spec)
}

/// The generated mesh `--generate g` at `level`: a 2D or 3D family, on the domain of the
/// problem file's generated mesh when it has one of the same dimension.
fn family_spec(
    g: &str,
    level: usize,
    file_mesh: Option<&file::MeshSpec>,
) -> Result<file::MeshSpec> {
    use file::MeshSpec;
    let other_domain = |d: usize| {
        anyhow::anyhow!(
            "--generate {g} is a {d}D family, but the [mesh] of the problem file is generated on \
             a {}D domain, which a {d}D mesh cannot keep (give --mesh, or --generate a {}D \
             family)",
            5 - d,
            5 - d
        )
    };
    match (g.parse::<Family>(), g.parse::<Family3>()) {
        (Ok(family), _) => {
            let domain = match file_mesh {
                Some(MeshSpec::Generated { domain, .. }) => *domain,
                Some(MeshSpec::Generated3 {
                    domain: Some(_), ..
                }) => return Err(other_domain(2)),
                _ => None,
            };
            Ok(MeshSpec::Generated {
                family,
                level,
                domain,
            })
        }
        (Err(_), Ok(family)) => {
            let domain = match file_mesh {
                Some(MeshSpec::Generated3 { domain, .. }) => *domain,
                Some(MeshSpec::Generated {
                    domain: Some(_), ..
                }) => return Err(other_domain(3)),
                _ => None,
            };
            Ok(MeshSpec::Generated3 {
                family,
                level,
                domain,
            })
        }
        (Err(e), Err(e3)) => Err(anyhow::anyhow!("{e}; {e3}")).context("--generate"),
    }
}

/// The level of a generated `spec` checked against its family; `origin` says where it came
/// from.
fn check_level(spec: &file::MeshSpec, origin: &str) -> Result<()> {
    match *spec {
        file::MeshSpec::Generated { family, level, .. } => family
            .check_level(level)
            .with_context(|| format!("the level {level} ({origin}) of the {family} mesh")),
        file::MeshSpec::Generated3 { family, level, .. } => {
            family.check_level(level).with_context(|| {
                format!(
                    "the level {level} ({origin}) of the 3D {} mesh",
                    family.name()
                )
            })
        }
        file::MeshSpec::File(_) => Ok(()),
    }
}

/// `gradvi solve`.
pub fn run(a: &SolveArgs) -> Result<()> {
    // Ctrl-C and SIGTERM stop the solve between linear solves, leaving no output
    crate::interrupt::install();
    // the mesh time printed: from here (the problem file included) to the validated mesh
    let t0 = std::time::Instant::now();
    check_options(a)?;
    let pf = match (&a.file, &a.problem) {
        (Some(f), _) => file::load(f, &a.params)?,
        (None, Some(name)) => file::builtin(name, &a.params)?,
        (None, None) => bail!("give a problem file or --problem NAME"),
    };
    check_paths(a, &pf, &[])?;
    let spec = resolve_mesh(
        a.mesh.as_deref(),
        a.generate.as_deref(),
        a.level,
        pf.mesh.as_ref(),
        &pf.path,
    )?;
    // the resolved mesh, as the JSON output records it
    let mesh_desc = spec.to_string();
    match crate::solve3d::case_mesh(&spec, &pf, a.warped_faces)? {
        AnyMesh::Two(mesh) => run2(a, &pf, &mesh, &mesh_desc, t0.elapsed().as_secs_f64()),
        AnyMesh::Three(mesh) => {
            let seconds = t0.elapsed().as_secs_f64();
            crate::solve3d::run3(a, &pf, &mesh, &mesh_desc, seconds)
        }
    }
}

/// The solve on a 2D mesh (read or generated in `mesh_seconds`).
fn run2(
    a: &SolveArgs,
    pf: &file::ProblemFile,
    mesh: &PolyMesh,
    mesh_desc: &str,
    mesh_seconds: f64,
) -> Result<()> {
    if a.vtu_faces {
        bail!("--vtu-faces writes the faces of a 3D mesh; the mesh {mesh_desc} is 2D");
    }
    pf.check_against_mesh(mesh)?;
    let problem = pf.problem();
    let kind = a.scheme.or(pf.scheme).unwrap_or(SchemeKind::Hmm);
    let scheme = scheme_on(kind, mesh, a.alpha, mesh_desc)?;
    eprintln!(
        "solving {} with {} on {} cells ({} unknowns)...",
        problem.name,
        kind,
        mesh.n_cells(),
        scheme.n_unknowns()
    );
    let sol = solve_problem(scheme.as_ref(), &problem, &solve_options(a))?;
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
    if let Some(path) = &a.vtu {
        atomic(path, |tmp| write_solution_vtu(tmp, scheme.as_ref(), &sol))?;
        println!("wrote           {}", path.display());
    }
    write_json(a, &case, &sol, errors.as_ref())
}

/// What the report of a solve says about its problem and mesh.
pub(crate) struct Case<'a> {
    pub(crate) pf: &'a file::ProblemFile,
    pub(crate) problem: &'a str,
    pub(crate) kind: SchemeKind,
    pub(crate) mesh_desc: &'a str,
    pub(crate) n_cells: usize,
    pub(crate) h: f64,
    pub(crate) mesh_seconds: f64,
}

/// The solve's summary on stdout (2D and 3D): the problem, the mesh, the iteration, the
/// certificate, the errors and the timings.
pub(crate) fn report<M: SolveMesh<D> + ?Sized, const D: usize>(
    a: &SolveArgs,
    case: &Case,
    sol: &Solution<M, D>,
    errors: Option<&Errors>,
) -> Result<()> {
    for m in &sol.marginal_load {
        eprintln!("warning: {m}");
    }
    println!("problem         {}", case.problem);
    println!("scheme          {}", case.kind);
    println!("mesh            {} cells, h = {:.6}", case.n_cells, case.h);
    print_solution(sol, a.tol);
    if let Some(e) = errors {
        println!(
            "errors          relative L2 of u at centroids {:.6e}, of the gradient {:.6e}",
            e.l2_u, e.l2_grad
        );
    }
    let t = sol.timings;
    println!(
        "timings [s]     mesh {:.3}, setup {:.3} (symbolic {:.3}), warm start {:.3}, assembly {:.3}, factorisation {:.3}, solves {:.3}, look-ahead {:.3}, total {:.3} (mesh excluded)",
        case.mesh_seconds,
        t.setup,
        t.symbolic,
        t.warm_start,
        t.assemble,
        t.factor,
        t.solve,
        t.look_ahead,
        t.total
    );
    Ok(())
}

/// The JSON summary (2D and 3D), if --json was given.
pub(crate) fn write_json<M: SolveMesh<D> + ?Sized, const D: usize>(
    a: &SolveArgs,
    case: &Case,
    sol: &Solution<M, D>,
    errors: Option<&Errors>,
) -> Result<()> {
    let Some(path) = &a.json else {
        return Ok(());
    };
    let pf = case.pf;
    let j = serde_json::json!({
        "problem": case.problem,
        "problem_file": {
            "path": pf.path.display().to_string(),
            "name": pf.name,
            "parameters": pf.parameters.iter().cloned().collect::<std::collections::BTreeMap<_, _>>(),
        },
        "mesh": case.mesh_desc,
        "scheme": case.kind,
        "n_cells": case.n_cells,
        "h": case.h,
        "n_unknowns": sol.system.n_unknowns(),
        "n_constrained": sol.constraints.as_ref().map_or(0, |c| c.dofs.len()),
        "n_active": sol.result.active.iter().filter(|&&x| x).count(),
        "niter": sol.niter(),
        "warm_start": sol.warm_start,
        "marginal_load": sol.marginal_load,
        "method": format!("{:?}", sol.result.method),
        "certificate": sol.result.certificate,
        "errors": errors,
        "timings": sol.timings,
        "mesh_seconds": case.mesh_seconds,
        "log": sol.result.log,
    });
    let text = serde_json::to_string_pretty(&j)?;
    atomic(path, |tmp| {
        std::fs::write(tmp, &text).with_context(|| format!("writing {}", path.display()))
    })?;
    println!("wrote           {}", path.display());
    Ok(())
}

/// The scheme `kind` on `mesh` (described as `mesh_desc`) with the stabilisation `alpha`; a
/// triangle scheme refused on a polygonal mesh says how to get a triangle mesh.
fn scheme_on<'a>(
    kind: SchemeKind,
    mesh: &'a PolyMesh,
    alpha: f64,
    mesh_desc: &str,
) -> Result<Box<dyn GradientDiscretisation + 'a>> {
    build_with(kind, mesh, &SchemeOptions { alpha }).map_err(|e| {
        let e = anyhow::Error::from(e);
        // the triangle schemes on a polygonal mesh: say how to get a triangle mesh
        if matches!(kind, SchemeKind::P1 | SchemeKind::Cr) && !mesh.is_triangular() {
            e.context(format!(
                "the {kind} scheme on {mesh_desc} (a generated triangle mesh: --generate triangles)"
            ))
        } else {
            e
        }
    })
}

/// The solver options of the command line, the iteration's progress printed to stderr.
pub(crate) fn solve_options(a: &SolveArgs) -> SolveOptions {
    let active_set = ActiveSetOptions {
        c: a.c,
        max_solves: a.max_solves,
        tol: a.tol,
        progress: Some(print_progress),
        cancel: Some(crate::interrupt::cancel()),
        ..Default::default()
    };
    SolveOptions {
        active_set,
        warm_start: a.warm_start.unwrap_or(WarmStart::Nested),
        fallback: a.fallback,
        system: gradvi::assembly::SystemOptions {
            linear: a.linear,
            budget: MemoryBudget::available(),
            ..Default::default()
        },
    }
}

/// One line of the iteration log on stderr, as soon as it is known (and the look-ahead's).
fn print_progress(l: &IterationLog) {
    eprintln!(
        "  solve {:>3}: active {} (+{}, -{}), violation {:.2e}, {:.2} s (assembly {:.2}, {} {:.2}, solve {:.2}{})",
        l.step.solve,
        l.step.active,
        l.step.entered,
        l.step.left,
        l.step.violation,
        l.timings.assemble + l.timings.factor + l.timings.solve,
        l.timings.assemble,
        if l.timings.reused {
            "multigrid reused"
        } else {
            "factorisation/multigrid setup"
        },
        l.timings.factor,
        l.timings.solve,
        if l.timings.krylov > 0 {
            format!(", {} CG iterations", l.timings.krylov)
        } else {
            String::new()
        }
    );
    if let Some(la) = l.look_ahead {
        eprintln!(
            "             look-ahead: {} unknowns, {} local solves, {}, {:.2} s",
            la.patch,
            la.solves,
            if la.converged {
                "converged"
            } else {
                "not converged"
            },
            la.seconds
        );
    }
}

/// The system, the warm start, the iteration log and the certificate (tolerance `tol`) of a
/// solve, on stdout.
fn print_solution<M: SolveMesh<D> + ?Sized, const D: usize>(sol: &Solution<M, D>, tol: f64) {
    let on_cells = match sol.cell_system.unzip() {
        (Some(n), Some(0)) => {
            format!("; the solves on the {n} cells, the local matrices being two-point")
        }
        (Some(n), Some(kept)) => format!(
            "; the solves on {n}: the cells and {kept} skeleton unknowns, the others \
             eliminated where the local matrices are two-point"
        ),
        _ => String::new(),
    };
    println!(
        "unknowns        {} ({} after condensation{on_cells})",
        sol.system.n_unknowns(),
        sol.system.n_condensed()
    );
    println!("method          {:?}", sol.result.method);
    if let Some(w) = &sol.warm_start {
        match &w.skipped {
            Some(why) => println!("warm start      skipped, cold start: {why}"),
            None => {
                let lv: Vec<String> = w.levels.iter().map(|n| format!("{n}")).collect();
                println!(
                    "warm start      nested: {} coarse solves on {} cells, {} unknowns predicted active, {:.3} s",
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
            "  {:>5}  {:>6}  {:>7}  {:>4}  {:>9.2e}  {:>8}",
            l.step.solve,
            l.step.active,
            l.step.entered,
            l.step.left,
            l.step.violation,
            // a screened iterate's residual is not computed (IterationStep::residual)
            l.step
                .residual
                .map_or("-".to_string(), |r| format!("{r:.2e}"))
        );
    }
    let c = sol.result.certificate;
    println!(
        "certificate     violation {:.2e}, min multiplier {:.2e}, complementarity {:.2e}, balance residual {:.2e} (tolerance {:.0e})",
        c.max_violation, c.min_multiplier, c.complementarity, c.balance_residual, tol
    );
}

/// Writes u (cell values, vertex values, cell gradients), the active set and the multiplier to
/// a VTU file. The active set and the multiplier are laid out on the entities of the
/// constrained unknowns (any scheme): vertex unknowns as point data `active`/`multiplier`,
/// cell unknowns as cell data `active_cell`/`multiplier_cell`, edge unknowns as cell data
/// `active_edges` (active edges of the cell) and `multiplier_edges` (their sum).
fn write_solution_vtu(
    path: &std::path::Path,
    scheme: &dyn GradientDiscretisation,
    sol: &Solution,
) -> Result<()> {
    let u = sol.u();
    let grads = scheme.cell_gradients(u);
    let mut cell_data: Vec<(&str, Vec<f64>)> = vec![
        ("u_K", scheme.cell_values(u)),
        ("grad_x", grads.iter().map(|g| g[0]).collect()),
        ("grad_y", grads.iter().map(|g| g[1]).collect()),
    ];
    let mut point_data: Vec<(&str, Vec<f64>)> = vec![("u_vertex", scheme.vertex_values(u))];
    if let Some(c) = &sol.constraints {
        let dofs = || c.dofs.iter().map(|d| d.dof);
        let r = &sol.result;
        let act = EntityFields::new(scheme, dofs(), |j| f64::from(u8::from(r.active[j])));
        let lam = EntityFields::new(scheme, dofs(), |j| r.multiplier[j]);
        if let (Some(a), Some(l)) = (act.vertex.clone(), lam.vertex.clone()) {
            point_data.push(("active", a));
            point_data.push(("multiplier", l));
        }
        if let (Some(a), Some(l)) = (act.cell.clone(), lam.cell.clone()) {
            cell_data.push(("active_cell", a));
            cell_data.push(("multiplier_cell", l));
        }
        if let (Some(a), Some(l)) = (
            act.edge_sums_per_cell(scheme),
            lam.edge_sums_per_cell(scheme),
        ) {
            cell_data.push(("active_edges", a));
            cell_data.push(("multiplier_edges", l));
        }
    }
    let pd: Vec<(&str, &[f64])> = point_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    let cd: Vec<(&str, &[f64])> = cell_data.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    write_vtu(path, scheme.mesh(), &pd, &cd)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use file::MeshSpec;
    use gradvi::mesh::Rect;

    const PROBLEM: &str = "problems/ex9.toml";

    /// `[mesh] generate = "cartesian", level = 4, domain = [-2, 2, -2, 2]`, as in ex9.toml.
    fn ex9_mesh() -> MeshSpec {
        MeshSpec::Generated {
            family: Family::Cartesian,
            level: 4,
            domain: Some(Rect::new([-2.0, 2.0], [-2.0, 2.0])),
        }
    }

    fn resolve(
        mesh: Option<&str>,
        generate: Option<&str>,
        level: Option<usize>,
        file_mesh: Option<&MeshSpec>,
    ) -> Result<MeshSpec> {
        resolve_mesh(
            mesh.map(Path::new),
            generate,
            level,
            file_mesh,
            Path::new(PROBLEM),
        )
    }

    /// The error of a resolution that must fail, with its causes.
    fn error(
        mesh: Option<&str>,
        generate: Option<&str>,
        level: Option<usize>,
        file_mesh: Option<&MeshSpec>,
    ) -> String {
        format!(
            "{:#}",
            resolve(mesh, generate, level, file_mesh).unwrap_err()
        )
    }

    fn generated(family: Family, level: usize, domain: Option<Rect>) -> MeshSpec {
        MeshSpec::Generated {
            family,
            level,
            domain,
        }
    }

    #[test]
    fn a_generated_file_mesh_keeps_its_domain_under_overrides() {
        let file = ex9_mesh();
        let d = Some(Rect::new([-2.0, 2.0], [-2.0, 2.0]));
        let cases = [
            // nothing: the file's mesh
            (None, None, file.clone()),
            // --level alone: the file's family and domain
            (None, Some(8), generated(Family::Cartesian, 8, d)),
            // --generate alone: the file's level and domain
            (Some("triangles"), None, generated(Family::Triangles, 4, d)),
            // both: the file's domain
            (Some("kershaw"), Some(2), generated(Family::Kershaw, 2, d)),
        ];
        for (g, level, expected) in cases {
            let spec = resolve(None, g, level, Some(&file)).unwrap();
            assert_eq!(spec, expected, "--generate {g:?} --level {level:?}");
        }
        assert_eq!(
            resolve(None, None, Some(8), Some(&file))
                .unwrap()
                .to_string(),
            "cartesian level 8 on [-2, 2]x[-2, 2]"
        );
    }

    #[test]
    fn a_mesh_file_replaces_the_files_mesh_and_its_domain() {
        let spec = resolve(Some("m.msh"), None, None, Some(&ex9_mesh())).unwrap();
        assert_eq!(spec, MeshSpec::File(PathBuf::from("m.msh")));
        let e = error(Some("m.msh"), None, Some(3), Some(&ex9_mesh()));
        assert!(e.contains("--generate"), "{e}");
        let e = error(Some("m.msh"), Some("cartesian"), None, None);
        assert!(e.contains("not both"), "{e}");
    }

    #[test]
    fn a_level_without_a_generated_mesh_to_apply_to_is_an_error() {
        let file = MeshSpec::File(PathBuf::from("problems/lshape.msh"));
        let e = error(None, None, Some(3), Some(&file));
        assert!(
            e.contains("--level needs --generate") && e.contains("lshape.msh"),
            "{e}"
        );
        let e = error(None, None, Some(3), None);
        assert!(
            e.contains("--level needs --generate") && e.contains(PROBLEM),
            "{e}"
        );
        // --generate without --level, and no level to keep
        for file_mesh in [Some(&file), None] {
            let e = error(None, Some("cartesian"), None, file_mesh);
            assert!(e.contains("needs --level"), "{e}");
        }
        // with --level, a mesh file in the problem file is simply replaced (unit square)
        assert_eq!(
            resolve(None, Some("triangles"), Some(2), Some(&file)).unwrap(),
            generated(Family::Triangles, 2, None)
        );
        let e = error(None, None, None, None);
        assert!(e.contains("has no [mesh]"), "{e}");
    }

    #[test]
    fn bad_families_and_levels_say_where_they_came_from() {
        let file = ex9_mesh();
        let e = error(None, Some("octagonal"), None, Some(&file));
        assert!(
            e.starts_with("--generate: ")
                && e.contains("unknown mesh family \"octagonal\"")
                && e.contains("\"cartesian\", \"hexagonal\", \"kershaw\" or \"triangles\""),
            "{e}"
        );
        let e = error(None, None, Some(13), Some(&file));
        assert!(
            e.contains("(--level)") && e.contains("levels go from 1 to 12"),
            "{e}"
        );
        let big = generated(Family::Cartesian, 11, None);
        let e = error(None, Some("hexagonal"), None, Some(&big));
        assert!(
            e.contains("the level of the [mesh] of") && e.contains("levels go from 1 to 10"),
            "{e}"
        );
    }

    #[test]
    fn three_d_families_are_generated_keeping_a_3d_domain() {
        use gradvi::mesh3d::Cuboid;
        let cube = Cuboid::new([-2.0, 2.0], [-2.0, 2.0], [-2.0, 2.0]);
        let file3 = MeshSpec::Generated3 {
            family: Family3::Cubes,
            level: 2,
            domain: Some(cube),
        };
        let spec = resolve(None, Some("kuhn"), Some(3), Some(&file3)).unwrap();
        let kuhn = |level| MeshSpec::Generated3 {
            family: Family3::Kuhn,
            level,
            domain: Some(cube),
        };
        assert_eq!(spec, kuhn(3));
        assert_eq!(
            spec.to_string(),
            "3D kuhn level 3 on [-2, 2]x[-2, 2]x[-2, 2]"
        );
        // --level alone keeps the 3D family; --generate alone the level
        let spec = resolve(None, None, Some(1), Some(&file3)).unwrap();
        assert!(matches!(
            spec,
            MeshSpec::Generated3 {
                family: Family3::Cubes,
                level: 1,
                ..
            }
        ));
        assert_eq!(
            resolve(None, Some("tetrahedra"), None, Some(&file3)).unwrap(),
            kuhn(2)
        );
        // a domain of the other dimension cannot be kept
        let e = error(None, Some("cubes"), Some(1), Some(&ex9_mesh()));
        assert!(e.contains("--generate cubes is a 3D family"), "{e}");
        let e = error(None, Some("cartesian"), Some(1), Some(&file3));
        assert!(e.contains("--generate cartesian is a 2D family"), "{e}");
        // 3D levels are checked against the 3D family
        let e = error(None, Some("kuhn"), Some(9), None);
        assert!(e.contains("(--level) of the 3D kuhn mesh"), "{e}");
        // an unknown name lists both kinds of families
        let e = error(None, Some("octagonal"), Some(1), None);
        assert!(e.contains("\"cubes\", \"kuhn\""), "{e}");
    }
}
