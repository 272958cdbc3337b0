//! The `GradviError` exception hierarchy: one class per variant of `gradvi::Error` (and of
//! `gradvi::SolverError`), with the library's message unchanged and the variant's fields as
//! attributes (`path`, `line`, `column`, `kind`, ...).
//!
//! ```text
//! GradviError
//! ├── MeshIoError            Error::MeshIo            (path, line); also an OSError
//! ├── InvalidMeshError       Error::InvalidMesh, Error::InvalidMeshFile   (path or None)
//! ├── InvalidDataError       Error::InvalidData (also: bad arrays given to the bindings);
//! │                          also a ValueError
//! ├── InfeasibleError        Error::Infeasible
//! ├── LinearSolverError      Error::Linear
//! ├── IllPosedError          Error::IllPosed
//! ├── SolverError            Error::Solver
//! │   ├── MaxIterationsError     SolverError::MaxIterations (iterations, history)
//! │   ├── CyclingError           SolverError::Cycling       (iteration, repeats, history)
//! │   ├── NoKktPointError        SolverError::NoKktPoint
//! │   └── CertificateError       SolverError::Certificate   (quantity, value, tol)
//! ├── ProblemFileError       Error::ProblemFile       (path, line, column, kind)
//! ├── FileError              Error::Io                (path, errno)
//! ├── InternalError          a panic inside gradvi (a bug): the interpreter survives
//! └── OutOfMemoryError       Error::OutOfMemory, and a mesh refused as MeshError::TooLarge
//!                            (bytes, budget); also a MemoryError
//! ```

use gradvi::SolverError as Stall;
use gradvi::error::ProblemFileErrorKind;
use gradvi::{Error, MeshError};
use pyo3::BoundObject;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use std::any::Any;

create_exception!(
    gradvi,
    GradviError,
    PyException,
    "Base class of every error gradvi reports (same message as the Rust library)."
);
create_exception!(
    gradvi,
    InvalidMeshError,
    GradviError,
    "The mesh is geometrically or topologically invalid (attribute path: the file, or None)."
);
create_exception!(
    gradvi,
    InfeasibleError,
    GradviError,
    "The discrete convex set is empty (e.g. Dirichlet data on the wrong side of the barrier)."
);
create_exception!(
    gradvi,
    LinearSolverError,
    GradviError,
    "A linear solve failed (e.g. the matrix is not numerically positive definite)."
);
create_exception!(
    gradvi,
    IllPosedError,
    GradviError,
    "The discrete problem has no unique solution (energy unbounded or flat), found before solving."
);
create_exception!(
    gradvi,
    SolverError,
    GradviError,
    "The active-set iteration did not converge, cycled, or its certificate failed."
);
create_exception!(
    gradvi,
    MaxIterationsError,
    SolverError,
    "The active-set iteration reached its cap (attributes: iterations, history)."
);
create_exception!(
    gradvi,
    CyclingError,
    SolverError,
    "An active set came back (attributes: iteration, repeats, history)."
);
create_exception!(
    gradvi,
    NoKktPointError,
    SolverError,
    "Exhaustive enumeration found no active set satisfying the KKT conditions."
);
create_exception!(
    gradvi,
    CertificateError,
    SolverError,
    "The final iterate failed its certificate (attributes: quantity, value, tol)."
);
create_exception!(
    gradvi,
    ProblemFileError,
    GradviError,
    "A problem file is invalid (attributes: path, line, column, kind)."
);
create_exception!(
    gradvi,
    FileError,
    GradviError,
    "A file could not be read or written (attributes: path, errno)."
);
create_exception!(
    gradvi,
    InternalError,
    GradviError,
    "A bug in gradvi (a panic); the interpreter survives. Please report it with the input."
);

/// An exception class with two bases: `GradviError` and a built-in exception, created once.
/// (`create_exception!` takes one base.)
pub struct DualBase {
    name: &'static str,
    doc: &'static str,
    builtin: fn(Python<'_>) -> Bound<'_, PyType>,
    class: PyOnceLock<Py<PyType>>,
}

impl DualBase {
    /// The class `gradvi.<name>(GradviError, <builtin>)`.
    fn class<'py>(&self, py: Python<'py>) -> PyResult<&Bound<'py, PyType>> {
        self.class
            .get_or_try_init(py, || {
                let bases = PyTuple::new(py, [py.get_type::<GradviError>(), (self.builtin)(py)])?;
                let ns = PyDict::new(py);
                ns.set_item("__doc__", self.doc)?;
                ns.set_item("__module__", "gradvi")?;
                let t = py
                    .get_type::<PyType>()
                    .call1((self.name, bases, ns))?
                    .cast_into::<PyType>()?;
                Ok::<_, PyErr>(t.unbind())
            })
            .map(|t| t.bind(py))
    }

    /// An exception of this class with `msg` (a `GradviError` if the class cannot be made).
    pub fn new_err(&self, msg: String) -> PyErr {
        Python::attach(|py| match self.class(py) {
            Ok(t) => PyErr::from_type(t.clone(), msg),
            Err(e) => e,
        })
    }
}

/// `InvalidDataError`, also a `ValueError`.
pub static INVALID_DATA: DualBase = DualBase {
    name: "InvalidDataError",
    doc: "Invalid data: problem data, options, or arrays of the wrong shape or with NaN (also a ValueError).",
    builtin: |py| py.get_type::<PyValueError>(),
    class: PyOnceLock::new(),
};

/// `MeshIoError`, also an `OSError`.
pub static MESH_IO: DualBase = DualBase {
    name: "MeshIoError",
    doc: "A mesh file could not be read or parsed (attributes: path, line; line 0 when unknown; also an OSError).",
    builtin: |py| py.get_type::<PyOSError>(),
    class: PyOnceLock::new(),
};

/// `OutOfMemoryError`, also a `MemoryError`.
pub static OUT_OF_MEMORY: DualBase = DualBase {
    name: "OutOfMemoryError",
    doc: "The computation would need more memory than this process may take, refused by its estimate before allocating (attributes: bytes, budget; also a MemoryError).",
    builtin: |py| py.get_type::<PyMemoryError>(),
    class: PyOnceLock::new(),
};

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GradviError", py.get_type::<GradviError>())?;
    m.add("MeshIoError", MESH_IO.class(py)?)?;
    m.add("InvalidMeshError", py.get_type::<InvalidMeshError>())?;
    m.add("InvalidDataError", INVALID_DATA.class(py)?)?;
    m.add("InfeasibleError", py.get_type::<InfeasibleError>())?;
    m.add("LinearSolverError", py.get_type::<LinearSolverError>())?;
    m.add("IllPosedError", py.get_type::<IllPosedError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("MaxIterationsError", py.get_type::<MaxIterationsError>())?;
    m.add("CyclingError", py.get_type::<CyclingError>())?;
    m.add("NoKktPointError", py.get_type::<NoKktPointError>())?;
    m.add("CertificateError", py.get_type::<CertificateError>())?;
    m.add("ProblemFileError", py.get_type::<ProblemFileError>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    m.add("OutOfMemoryError", OUT_OF_MEMORY.class(py)?)?;
    Ok(())
}

/// An `InvalidDataError` with `msg` (for bad arrays and options caught by the bindings).
pub fn invalid(msg: impl Into<String>) -> PyErr {
    INVALID_DATA.new_err(msg.into())
}

/// The snake-case name of a problem-file error kind (`"unknown_key"`, `"not_spd"`, ...).
fn kind_name(kind: ProblemFileErrorKind) -> &'static str {
    use ProblemFileErrorKind as K;
    match kind {
        K::Syntax => "syntax",
        K::UnknownKey => "unknown_key",
        K::Schema => "schema",
        K::Expression => "expression",
        K::Parameter => "parameter",
        K::Mesh => "mesh",
        K::Tag => "tag",
        K::UncoveredEdge => "uncovered_edge",
        K::OverlappingRules => "overlapping_rules",
        K::UncoveredPoint => "uncovered_point",
        K::NotSpd => "not_spd",
        K::NonFinite => "non_finite",
        #[allow(unreachable_patterns)]
        _ => "other",
    }
}

/// The Python exception of a gradvi error: same message, fields as attributes.
pub fn to_pyerr(py: Python<'_>, e: &Error) -> PyErr {
    let msg = e.to_string();
    let (err, attrs): (PyErr, Vec<(&str, Py<PyAny>)>) = match e {
        Error::OutOfMemory { bytes, budget, .. }
        | Error::InvalidMesh(MeshError::TooLarge { bytes, budget, .. })
        | Error::InvalidMeshFile {
            source: MeshError::TooLarge { bytes, budget, .. },
            ..
        } => (
            OUT_OF_MEMORY.new_err(msg),
            vec![("bytes", obj(py, *bytes)), ("budget", obj(py, *budget))],
        ),
        Error::MeshIo { path, line, .. } => (
            MESH_IO.new_err(msg),
            vec![("path", path_obj(py, path)), ("line", obj(py, *line))],
        ),
        Error::InvalidMesh(_) => (InvalidMeshError::new_err(msg), vec![("path", py.None())]),
        Error::InvalidMeshFile { path, .. } => (
            InvalidMeshError::new_err(msg),
            vec![("path", path_obj(py, path))],
        ),
        Error::InvalidData(_) => (INVALID_DATA.new_err(msg), vec![]),
        Error::Infeasible(_) => (InfeasibleError::new_err(msg), vec![]),
        Error::Linear(_) => (LinearSolverError::new_err(msg), vec![]),
        Error::IllPosed(_) => (IllPosedError::new_err(msg), vec![]),
        Error::Solver(s) => solver_error(py, s, msg),
        Error::ProblemFile {
            path,
            line,
            column,
            kind,
            ..
        } => (
            ProblemFileError::new_err(msg),
            vec![
                ("path", path_obj(py, path)),
                ("line", obj(py, *line)),
                ("column", obj(py, *column)),
                ("kind", obj(py, kind_name(*kind))),
            ],
        ),
        Error::Io { path, source } => (
            FileError::new_err(msg),
            vec![
                ("path", path_obj(py, path)),
                ("errno", obj(py, source.raw_os_error())),
            ],
        ),
        #[allow(unreachable_patterns)]
        _ => (GradviError::new_err(msg), vec![]),
    };
    let value = err.value(py);
    for (name, v) in attrs {
        // setting an attribute on a fresh exception instance cannot fail in practice; if it
        // did, the exception is still raised, without that attribute
        let _ = value.setattr(name, v);
    }
    err
}

fn obj<'py, T: IntoPyObject<'py>>(py: Python<'py>, v: T) -> Py<PyAny> {
    match v.into_pyobject(py) {
        Ok(o) => o.into_any().unbind(),
        Err(_) => py.None(),
    }
}

fn path_obj(py: Python<'_>, p: &std::path::Path) -> Py<PyAny> {
    obj(py, p.display().to_string())
}

/// Matches a solver error to its exception class, with the variant's fields as attributes of
/// the same names: `Variant => ExceptionClass { field, ... }`.
macro_rules! solver_exceptions {
    ($py:expr, $s:expr, $msg:expr;
     $($variant:ident => $class:ident { $($field:ident),* }),* $(,)?) => {
        match $s {
            $(Stall::$variant { $($field),* } => (
                $class::new_err($msg),
                vec![$((stringify!($field), obj($py, $field.clone()))),*],
            ),)*
            #[allow(unreachable_patterns)]
            _ => (SolverError::new_err($msg), vec![]),
        }
    };
}

fn solver_error(py: Python<'_>, s: &Stall, msg: String) -> (PyErr, Vec<(&'static str, Py<PyAny>)>) {
    solver_exceptions!(py, s, msg;
        MaxIterations => MaxIterationsError { iterations, history },
        Cycling => CyclingError { iteration, repeats, history },
        NoKktPoint => NoKktPointError { candidates },
        Certificate => CertificateError { quantity, value, tol },
    )
}

/// `InternalError` for a caught panic, with its message.
pub fn panic_error(panic: Box<dyn Any + Send>) -> PyErr {
    let what = if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    };
    InternalError::new_err(format!(
        "internal error in gradvi (a bug, please report it with the input): {what}"
    ))
}
