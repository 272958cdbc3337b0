//! `gradvi._gradvi`: the PyO3 bindings of the gradvi library.
//!
//! This module is private: the Python package `gradvi` (`python/gradvi/`) wraps it in typed,
//! documented classes and functions. It holds the Rust objects (a mesh, a problem) behind
//! opaque handles and exchanges flat numpy arrays with the Python layer:
//!
//! - [`mesh`]: `_Mesh` (read, build from arrays, generate, geometry arrays, VTU/typ2 output);
//! - [`mesh3d`]: `_Mesh3`, the same for 3D polyhedral meshes (read, build from arrays,
//!   generate, geometry arrays, VTU output);
//! - [`problem`]: `_Problem` (built-in problems, problem files, and problems tabulated by the
//!   Python layer on the points a scheme evaluates data at);
//! - [`case`]: the mesh of a problem file's `[mesh]` section, 2D or 3D, as the command line
//!   builds it;
//! - [`solve`]: `solve`, which returns every result as numpy arrays and plain values;
//! - the registries `SCHEMES`, `FAMILIES`, `FAMILIES3` and `BUILTIN_PROBLEMS` (names, from the
//!   library).
//!
//! Every gradvi error becomes an exception of the `GradviError` hierarchy with the same message
//! ([`errors`]); every call into the library runs under [`guard`], which turns a panic into
//! `InternalError` instead of aborting the interpreter or raising pyo3's `PanicException`
//! (which is not an `Exception`).

mod errors;
mod mesh;
mod mesh3d;
mod problem;
mod solve;

use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::panic::{AssertUnwindSafe, catch_unwind};

pub use errors::to_pyerr;

/// Runs `f` with the interpreter detached (other Python threads run meanwhile), turning a
/// gradvi error into its Python exception and a panic into `InternalError`.
pub(crate) fn guard<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> gradvi::Result<T> + Send,
{
    let out = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match out {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(to_pyerr(py, &e)),
        Err(panic) => Err(errors::panic_error(panic)),
    }
}

/// As [`guard`], for work that needs the interpreter (converting arrays, calling Python).
pub(crate) fn guard_attached<T, F>(f: F) -> PyResult<T>
where
    F: FnOnce() -> PyResult<T>,
{
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(panic) => Err(errors::panic_error(panic)),
    }
}

/// The extension module.
#[pymodule]
fn _gradvi(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    mesh::register(m)?;
    mesh3d::register(m)?;
    problem::register(m)?;
    solve::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    register_registries(m)
}

/// The library's registries, as tuples of names in registration order: `SCHEMES`
/// (`gradvi::scheme::SchemeKind::ALL`), `FAMILIES` (`gradvi::mesh::generate::Family::ALL`),
/// `FAMILIES3` (`gradvi::mesh3d::generate::Family3::ALL`) and `BUILTIN_PROBLEMS`
/// (`gradvi::problem::file::BUILTIN`).
fn register_registries(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let schemes = gradvi::scheme::SchemeKind::ALL.iter().map(|k| k.name());
    m.add("SCHEMES", PyTuple::new(py, schemes)?)?;
    let families = gradvi::mesh::generate::Family::ALL.iter().map(|f| f.name());
    m.add("FAMILIES", PyTuple::new(py, families)?)?;
    let families3 = gradvi::mesh3d::generate::Family3::ALL
        .iter()
        .map(|f| f.name());
    m.add("FAMILIES3", PyTuple::new(py, families3)?)?;
    let problems = gradvi::problem::file::BUILTIN.iter().map(|(n, _)| *n);
    m.add("BUILTIN_PROBLEMS", PyTuple::new(py, problems)?)?;
    Ok(())
}
