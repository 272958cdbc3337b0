//! `solve`: one problem on one mesh with one scheme; every result as numpy arrays.

use crate::errors::INVALID_DATA;
use crate::mesh::{PyMesh, points_array, vec_array};
use crate::mesh3d::PyMesh3;
use crate::problem::{Misses, PyProblem};
use crate::to_pyerr;
use gradvi::assembly::SystemOptions;
use gradvi::linalg::{FactorThreads, Ordering};
use gradvi::mesh3d::PolyMesh3;
use gradvi::post::contact::{free_boundary, neighbours};
use gradvi::post::fields::EntityFields;
use gradvi::post::{Errors, relative_errors};
use gradvi::problem::Problem;
use gradvi::scheme::{
    Entity, GradientDiscretisation, SchemeKind, SchemeOptions, build_with, build_with3,
};
use gradvi::solver::constraints::Constraints;
use gradvi::solver::{
    ActiveSetOptions, Cancel, Certificate, IterationLog, MarginalLoad, Method, SolveOptions,
    SolverMesh, Timings, WarmStart, WarmStartReport, solve_problem,
};
use gradvi::vi::Side;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::str::FromStr;
use std::sync::atomic::Ordering as AtomicOrdering;
use std::sync::{Arc, Mutex};

/// Everything a solve in dimension `D` produces, owned (no borrow of the mesh or the scheme).
struct Output<const D: usize> {
    problem: String,
    scheme: &'static str,
    n_unknowns: usize,
    n_skeleton: usize,
    n_condensed: usize,
    u: Vec<f64>,
    u_cell: Vec<f64>,
    u_vertex: Vec<f64>,
    gradient: Vec<[f64; D]>,
    entity_kind: Vec<u8>,
    entity_index: Vec<i64>,
    u_fields: EntityFields,
    constrained: Option<Constrained<D>>,
    niter: usize,
    method: Method,
    log: Vec<IterationLog>,
    certificate: Certificate,
    timings: Timings,
    warm_start: Option<WarmStartReport>,
    marginal_load: Vec<MarginalLoad>,
    errors: Option<Errors>,
    exact_cell: Option<Vec<f64>>,
    iterates: Vec<Vec<f64>>,
}

struct Constrained<const D: usize> {
    kind: &'static str,
    side: Side,
    dofs: Vec<i64>,
    points: Vec<[f64; D]>,
    measures: Vec<f64>,
    barrier: Vec<f64>,
    multiplier: Vec<f64>,
    active: Vec<bool>,
    multiplier_field: Vec<f64>,
    active_field: Vec<f64>,
    active_fields: EntityFields,
    multiplier_fields: EntityFields,
    active_edge_sums: Option<Vec<f64>>,
    multiplier_edge_sums: Option<Vec<f64>>,
    contact_measure: f64,
    free_boundary: Vec<[f64; D]>,
}

/// The options of one solve, checked.
struct Options {
    kind: SchemeKind,
    scheme: SchemeOptions,
    solve: SolveOptions,
}

/// Checks the numbers of the active-set options.
fn check_numbers(c: f64, max_solves: usize, tol: f64) -> gradvi::Result<()> {
    let bad = |m: String| Err(gradvi::Error::InvalidData(m));
    if !(tol > 0.0 && tol < 1.0) {
        return bad(format!(
            "tol must be in (0, 1), got {tol} (the certificate would be meaningless)"
        ));
    }
    if !(c > 0.0 && c.is_finite()) {
        return bad(format!("c must be positive and finite, got {c}"));
    }
    if max_solves == 0 {
        return bad("max_solves must be at least 1".into());
    }
    Ok(())
}

/// The fill-reducing ordering named `name`.
fn ordering(name: &str) -> gradvi::Result<Ordering> {
    match name.to_ascii_lowercase().as_str() {
        "amd" => Ok(Ordering::Amd),
        "nd" | "nested-dissection" | "nested_dissection" => Ok(Ordering::NestedDissection),
        o => Err(gradvi::Error::InvalidData(format!(
            "unknown ordering {o:?} (expected \"amd\" or \"nested-dissection\")"
        ))),
    }
}

/// The threads of the numeric factorisation named `name`.
fn factor_threads(name: &str) -> gradvi::Result<FactorThreads> {
    match name.to_ascii_lowercase().as_str() {
        "sequential" => Ok(FactorThreads::Sequential),
        "global" | "parallel" => Ok(FactorThreads::Global),
        o => Err(gradvi::Error::InvalidData(format!(
            "unknown factor_threads {o:?} (expected \"sequential\" or \"global\")"
        ))),
    }
}

/// The points of the discrete free boundary of an active set.
type FreeBoundary<'s, const D: usize> = &'s dyn Fn(&Constraints, &[bool]) -> Vec<[f64; D]>;

/// What a solve on one mesh type adds to the common output: the points of the discrete free
/// boundary, and an entity field summed over the faces of each cell.
struct MeshOutput<'s, const D: usize> {
    free_boundary: FreeBoundary<'s, D>,
    face_sums: &'s dyn Fn(&EntityFields) -> Option<Vec<f64>>,
}

/// Solves `pb` with `s`, and collects the output.
fn solve_and_collect<M: SolverMesh<D> + ?Sized, const D: usize>(
    s: &dyn GradientDiscretisation<M, D>,
    pb: &Problem<D>,
    o: &SolveOptions,
    kind: SchemeKind,
    extra: &MeshOutput<'_, D>,
) -> gradvi::Result<Output<D>> {
    let sol = solve_problem(s, pb, o)?;
    let mesh = s.mesh();
    let u = sol.u().to_vec();
    let n = u.len();
    let (entity_kind, entity_index) = (0..n)
        .map(|d| match s.dof_entity(d) {
            Entity::Vertex(i) => (0u8, i as i64),
            Entity::Edge(i) => (1u8, i as i64),
            Entity::Cell(i) => (2u8, i as i64),
        })
        .unzip();
    let fields = match sol.constraints {
        Some(_) => Some((sol.multiplier_field()?, sol.active_field()?)),
        None => None,
    };
    let constrained = sol.constraints.as_ref().zip(fields).map(|(c, fields)| {
        let r = &sol.result;
        let dofs = || c.dofs.iter().map(|d| d.dof);
        let active_fields = EntityFields::new(s, dofs(), |j| f64::from(u8::from(r.active[j])));
        let multiplier_fields = EntityFields::new(s, dofs(), |j| r.multiplier[j]);
        Constrained {
            kind: match pb.constraint.as_ref().map(|k| k.kind) {
                Some(gradvi::problem::ConstraintKind::Signorini) => "signorini",
                _ => "obstacle",
            },
            side: c.side,
            dofs: c.dofs.iter().map(|d| d.dof as i64).collect(),
            points: c.dofs.iter().map(|d| s.dof_point(d.dof)).collect(),
            measures: c.dofs.iter().map(|d| d.measure).collect(),
            barrier: c.barrier.clone(),
            multiplier: r.multiplier.clone(),
            active: r.active.clone(),
            multiplier_field: fields.0,
            active_field: fields.1,
            // Σ_j m_j over the active constrained unknowns
            contact_measure: c
                .dofs
                .iter()
                .zip(&r.active)
                .filter(|(_, a)| **a)
                .map(|(d, _)| d.measure)
                .sum(),
            free_boundary: (extra.free_boundary)(c, &r.active),
            active_edge_sums: (extra.face_sums)(&active_fields),
            multiplier_edge_sums: (extra.face_sums)(&multiplier_fields),
            active_fields,
            multiplier_fields,
        }
    });
    let errors = pb
        .exact
        .as_ref()
        .map(|ex| relative_errors(s, &u, &*ex.u, &*ex.grad));
    let exact_cell = pb.exact.as_ref().map(|ex| {
        (0..mesh.n_cells())
            .map(|k| (ex.u)(mesh.cell_centre(k)))
            .collect()
    });
    Ok(Output {
        problem: pb.name.clone(),
        scheme: kind.name(),
        n_unknowns: n,
        n_skeleton: s.n_skeleton(),
        n_condensed: sol.system.n_condensed(),
        u_cell: s.cell_values(&u),
        u_vertex: s.vertex_values(&u),
        gradient: s.cell_gradients(&u),
        u_fields: EntityFields::new(s, 0..n, |j| u[j]),
        entity_kind,
        entity_index,
        constrained,
        niter: sol.niter(),
        method: sol.result.method,
        log: sol.result.log.clone(),
        certificate: sol.result.certificate,
        timings: sol.timings,
        warm_start: sol.warm_start.clone(),
        marginal_load: sol.marginal_load.clone(),
        errors,
        exact_cell,
        iterates: sol.result.iterates.clone(),
        u,
    })
}

/// A solve on a planar mesh.
fn run(
    mesh: &Arc<gradvi::mesh::PolyMesh>,
    problem: &PyProblem,
    o: &Options,
) -> gradvi::Result<Output<2>> {
    let (pb, _) = problem.instantiate(mesh)?;
    let scheme = build_with(o.kind, mesh, &o.scheme)?;
    let s = scheme.as_ref();
    let extra = MeshOutput {
        free_boundary: &|c, active| free_boundary(s, c, active, &neighbours(s, c)),
        face_sums: &|f| f.edge_sums_per_cell(s),
    };
    solve_and_collect(s, &pb, &o.solve, o.kind, &extra)
}

/// A solve on a 3D mesh (the nested warm start agglomerates the polyhedral mesh, as in 2D).
fn run3(mesh: &Arc<PolyMesh3>, problem: &PyProblem, o: &Options) -> gradvi::Result<Output<3>> {
    let (pb, _) = problem.instantiate3(mesh)?;
    let scheme = build_with3(o.kind, mesh, &o.scheme)?;
    let s = scheme.as_ref();
    // the field of each face unknown summed over the faces of each cell (VTU cell data)
    let face_sums = |f: &EntityFields| {
        f.edge.as_ref().map(|e| {
            (0..mesh.n_cells())
                .map(|k| mesh.cell_faces(k).iter().map(|&s| e[s as usize]).sum())
                .collect()
        })
    };
    let extra = MeshOutput {
        free_boundary: &|_, _| Vec::new(),
        face_sums: &face_sums,
    };
    solve_and_collect(s, &pb, &o.solve, o.kind, &extra)
}

/// The exception of a failed solve of a tabulated problem whose data was missing somewhere:
/// the exception of a Python fallback, or an `InvalidDataError` that says which datum and point.
fn miss_error(py: Python<'_>, e: &gradvi::Error, misses: &Misses) -> Option<PyErr> {
    if let Some(pe) = misses.py_error.lock().ok().and_then(|mut g| g.take()) {
        let cause = to_pyerr(py, e);
        pe.set_cause(py, Some(cause));
        return Some(pe);
    }
    let (what, p) = misses
        .first_unresolved
        .lock()
        .ok()
        .and_then(|g| g.clone())?;
    let p: Vec<String> = p.iter().map(f64::to_string).collect();
    Some(INVALID_DATA.new_err(format!(
        "{e} ({what} was asked at ({}), a point where no value was given: array data is \
         known only on the mesh it was given for)",
        p.join(", ")
    )))
}

fn entity_fields<'py>(py: Python<'py>, f: EntityFields) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in [("vertex", f.vertex), ("edge", f.edge), ("cell", f.cell)] {
        if let Some(v) = v {
            d.set_item(k, vec_array(py, v))?;
        }
    }
    Ok(d)
}

fn to_dict<'py, const D: usize>(
    py: Python<'py>,
    o: Output<D>,
    misses: Option<&Misses>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("problem", o.problem)?;
    d.set_item("scheme", o.scheme)?;
    d.set_item("n_unknowns", o.n_unknowns)?;
    d.set_item("n_skeleton", o.n_skeleton)?;
    d.set_item("n_condensed", o.n_condensed)?;
    d.set_item("niter", o.niter)?;
    d.set_item(
        "method",
        match o.method {
            Method::Linear => "linear",
            Method::ActiveSet => "active-set",
            Method::ProjectedGaussSeidel => "projected-gauss-seidel",
            #[allow(unreachable_patterns)]
            _ => "other",
        },
    )?;
    d.set_item("certificate", json(py, &o.certificate)?)?;
    d.set_item("timings", json(py, &o.timings)?)?;
    d.set_item("log", json(py, &o.log)?)?;
    d.set_item("warm_start", json(py, &o.warm_start)?)?;
    let marginal = PyList::empty(py);
    for m in &o.marginal_load {
        let x = PyDict::new(py);
        x.set_item("cell", m.cell)?;
        x.set_item("sum", m.sum)?;
        x.set_item("ratio", m.ratio)?;
        x.set_item("message", m.to_string())?;
        marginal.append(x)?;
    }
    d.set_item("marginal_load", marginal)?;
    match o.errors {
        None => d.set_item("errors", py.None())?,
        Some(e) => {
            let x = PyDict::new(py);
            x.set_item("l2_u", e.l2_u)?;
            x.set_item("l2_grad", e.l2_grad)?;
            d.set_item("errors", x)?;
        }
    }
    if let Some(m) = misses {
        d.set_item("fallback_calls", m.calls.load(AtomicOrdering::Relaxed))?;
        d.set_item("untabulated_points", m.count.load(AtomicOrdering::Relaxed))?;
    }
    d.set_item("u", vec_array(py, o.u))?;
    d.set_item("u_cell", vec_array(py, o.u_cell))?;
    d.set_item("u_vertex", vec_array(py, o.u_vertex))?;
    d.set_item("gradient", points_array(py, o.gradient.into_iter())?)?;
    d.set_item("entity_kind", vec_array(py, o.entity_kind))?;
    d.set_item("entity_index", vec_array(py, o.entity_index))?;
    d.set_item("u_fields", entity_fields(py, o.u_fields)?)?;
    d.set_item("exact_cell", o.exact_cell.map(|v| vec_array(py, v)))?;
    let its = PyList::empty(py);
    for it in o.iterates {
        its.append(vec_array(py, it))?;
    }
    d.set_item("iterates", its)?;
    match o.constrained {
        None => d.set_item("constraint", py.None())?,
        Some(c) => d.set_item("constraint", constraint_dict(py, c)?)?,
    }
    Ok(d)
}

/// The constrained unknowns of a solution as the dict `Solution.constraint` reads.
fn constraint_dict<'py, const D: usize>(
    py: Python<'py>,
    c: Constrained<D>,
) -> PyResult<Bound<'py, PyDict>> {
    let e = PyDict::new(py);
    e.set_item("kind", c.kind)?;
    e.set_item(
        "side",
        match c.side {
            Side::Upper => "upper",
            Side::Lower => "lower",
        },
    )?;
    e.set_item("dofs", vec_array(py, c.dofs))?;
    e.set_item("points", points_array(py, c.points.into_iter())?)?;
    e.set_item("measures", vec_array(py, c.measures))?;
    e.set_item("barrier", vec_array(py, c.barrier))?;
    e.set_item("multiplier", vec_array(py, c.multiplier))?;
    e.set_item("active", vec_array(py, c.active))?;
    e.set_item("multiplier_field", vec_array(py, c.multiplier_field))?;
    e.set_item("active_field", vec_array(py, c.active_field))?;
    e.set_item("active_fields", entity_fields(py, c.active_fields)?)?;
    e.set_item("multiplier_fields", entity_fields(py, c.multiplier_fields)?)?;
    e.set_item(
        "active_edge_sums",
        c.active_edge_sums.map(|v| vec_array(py, v)),
    )?;
    e.set_item(
        "multiplier_edge_sums",
        c.multiplier_edge_sums.map(|v| vec_array(py, v)),
    )?;
    e.set_item("contact_measure", c.contact_measure)?;
    e.set_item(
        "free_boundary",
        points_array(py, c.free_boundary.into_iter())?,
    )?;
    Ok(e)
}

/// A serialisable value as the Python object `json.loads` makes of it.
fn json<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v)
        .map_err(|e| crate::errors::InternalError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Solves `problem` on `mesh`; see `gradvi.solve` for the options (and their defaults, stated
/// there only: this function is called with every option).
#[pyfunction]
#[pyo3(signature = (mesh, problem, scheme, alpha, c, max_solves, tol, fallback, warm_start,
    initial_active, keep_iterates, ordering, factor_threads, linear))]
#[allow(clippy::too_many_arguments)]
fn solve<'py>(
    py: Python<'py>,
    mesh: AnyMesh<'py>,
    problem: &PyProblem,
    scheme: &str,
    alpha: f64,
    c: f64,
    max_solves: usize,
    tol: f64,
    fallback: bool,
    warm_start: &str,
    initial_active: Option<numpy::PyReadonlyArray1<'_, bool>>,
    keep_iterates: bool,
    ordering: &str,
    factor_threads: &str,
    linear: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let initial_active = initial_active.map(|a| a.as_array().to_vec());
    // Ctrl-C: Python's pending signals are checked between linear solves; the exception a
    // signal handler raised (KeyboardInterrupt) is kept and raised instead of the library's
    // Interrupted
    let raised: Arc<Mutex<Option<PyErr>>> = Arc::default();
    let cancel = {
        let raised = Arc::clone(&raised);
        Cancel::new(move || match Python::attach(|py| py.check_signals()) {
            Ok(()) => false,
            Err(e) => {
                if let Ok(mut r) = raised.lock() {
                    r.get_or_insert(e);
                }
                true
            }
        })
    };
    let options = || -> gradvi::Result<Options> {
        check_numbers(c, max_solves, tol)?;
        let system = SystemOptions {
            ordering: self::ordering(ordering)?,
            factor_threads: self::factor_threads(factor_threads)?,
            linear: gradvi::assembly::LinearSolver::from_str(&linear.to_ascii_lowercase())?,
            budget: gradvi::budget::MemoryBudget::available(),
        };
        Ok(Options {
            kind: SchemeKind::from_str(scheme)?,
            scheme: SchemeOptions { alpha },
            solve: SolveOptions {
                active_set: ActiveSetOptions {
                    c,
                    max_solves,
                    tol,
                    initial_active,
                    keep_iterates,
                    progress: None,
                    cancel: Some(cancel),
                    // screening on, look-ahead as the driver decides (with the nested start)
                    ..Default::default()
                },
                warm_start: WarmStart::from_str(&warm_start.to_ascii_lowercase())?,
                fallback,
                system,
            },
        })
    };
    let o = options().map_err(|e| to_pyerr(py, &e))?;
    let misses = match &problem.spec {
        crate::problem::Spec::Tabulated(t) => Some(Arc::clone(&t.misses)),
        crate::problem::Spec::Tabulated3(t) => Some(Arc::clone(&t.misses)),
        _ => None,
    };
    match mesh {
        AnyMesh::Two(m) => {
            let m = Arc::clone(&m.mesh);
            let out = detached(py, || run(&m, problem, &o));
            finish(py, out, &raised, misses.as_deref())
        }
        AnyMesh::Three(m) => {
            let m = Arc::clone(&m.mesh);
            let out = detached(py, || run3(&m, problem, &o));
            finish(py, out, &raised, misses.as_deref())
        }
    }
}

/// A mesh of either dimension.
#[derive(FromPyObject)]
enum AnyMesh<'py> {
    Two(PyRef<'py, PyMesh>),
    Three(PyRef<'py, PyMesh3>),
}

/// The result of `f`, run detached from the interpreter (other Python threads, and the signal
/// checks of the cancel hook, run meanwhile); a panic is kept as its payload.
fn detached<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> gradvi::Result<T> + Send,
) -> std::thread::Result<gradvi::Result<T>> {
    py.detach(|| std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)))
}

/// The dict of a solve's output, or its exception: the exception a signal handler raised
/// during the solve (`raised`: KeyboardInterrupt for Ctrl-C), the exception of a Python
/// fallback or a missing tabulated value, the gradvi error's, or `InternalError` for a panic.
fn finish<'py, const D: usize>(
    py: Python<'py>,
    out: std::thread::Result<gradvi::Result<Output<D>>>,
    raised: &Mutex<Option<PyErr>>,
    misses: Option<&Misses>,
) -> PyResult<Bound<'py, PyDict>> {
    let out = match out {
        Ok(Ok(v)) => v,
        Ok(Err(gradvi::Error::Interrupted)) => {
            let e = raised.lock().ok().and_then(|mut r| r.take());
            return Err(e.unwrap_or_else(|| {
                pyo3::exceptions::PyKeyboardInterrupt::new_err("the solve was interrupted")
            }));
        }
        Ok(Err(e)) => {
            if let Some(err) = misses.and_then(|m| miss_error(py, &e, m)) {
                return Err(err);
            }
            return Err(to_pyerr(py, &e));
        }
        Err(p) => return Err(crate::errors::panic_error(p)),
    };
    // a signal that arrived during the last linear solve (after the last check of the cancel
    // hook) still interrupts the call: Ctrl-C during `gradvi.solve` always raises
    py.check_signals()?;
    crate::guard_attached(|| to_dict(py, out, misses))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    Ok(())
}
