//! `_Problem`: a built-in problem, a problem file, or a problem *tabulated* by the Python layer.
//!
//! A tabulated problem holds, for one mesh, the value of every datum at the points where the
//! scheme evaluates it, as `gradvi::scheme::points` lists them (`_Mesh.evaluation_points`): the
//! Python layer evaluates each vectorised callable once on the arrays of those points. The
//! closures of the `gradvi::problem::Problem` built here look the value up by the bits of the
//! point, on the rows where that datum was given (`{key}_rows`; every row without it). A point
//! without a value (only the coarse meshes of the nested warm start ask for such points) calls
//! the point-wise fallback the Python layer gave for a callable datum, or gets NaN for array
//! data (the warm start is then skipped, with the reason in the solution's report).

use crate::errors::invalid;
use crate::guard;
use crate::mesh::{PyMesh, point_key};
use crate::mesh3d::{PyMesh3, warped_convention};
use gradvi::case::{AnyMesh, case_mesh};
use gradvi::mesh::{CellComplex, PolyMesh, SolveMesh};
use gradvi::mesh3d::PolyMesh3;
use gradvi::problem::file::{ProblemFile, builtin, load};
use gradvi::problem::{BoundaryKind, ConstraintKind, Problem, Side};
use gradvi::scheme::Tensor;
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// What a problem handle stands for.
pub enum Spec {
    /// `gradvi::problem::file::builtin` (the command line's `--problem`).
    Builtin {
        name: String,
        params: Vec<(String, f64)>,
    },
    /// A problem file.
    File(Box<ProblemFile>),
    /// Data tabulated on one planar mesh by the Python layer.
    Tabulated(Arc<Tabulated<PolyMesh, 2>>),
    /// Data tabulated on one 3D mesh by the Python layer.
    Tabulated3(Arc<Tabulated<PolyMesh3, 3>>),
}

/// A problem (private handle; see `gradvi.Problem`).
#[pyclass(name = "_Problem", module = "gradvi._gradvi", frozen)]
pub struct PyProblem {
    pub spec: Spec,
}

/// Points that were not in the table, and errors of the Python fallbacks.
#[derive(Default)]
pub struct Misses {
    /// Points looked up that were not in the table.
    pub count: AtomicUsize,
    /// Calls of Python fallbacks.
    pub calls: AtomicUsize,
    /// The first point without a value and without a fallback (datum, its coordinates).
    pub first_unresolved: Mutex<Option<(&'static str, Vec<f64>)>>,
    /// The first exception raised by a Python fallback.
    pub py_error: Mutex<Option<PyErr>>,
}

impl Misses {
    fn unresolved(&self, what: &'static str, p: &[f64]) {
        if let Ok(mut g) = self.first_unresolved.lock() {
            g.get_or_insert_with(|| (what, p.to_vec()));
        }
    }
    fn py_error(&self, e: PyErr) {
        if let Ok(mut g) = self.py_error.lock() {
            g.get_or_insert(e);
        }
    }
}

/// Values of one datum at the rows of the point table.
struct Column<T> {
    values: Vec<T>,
    /// The rows that hold a value of this datum (`None`: every row). The Python layer
    /// tabulates a datum only on the points where the scheme reads it; a lookup on another
    /// row is a miss, like a point outside the table.
    given: Option<Vec<bool>>,
    fallback: Option<Py<PyAny>>,
}

impl<T: Copy> Column<T> {
    /// The value at row `i`, if the datum was given there.
    fn at(&self, i: usize) -> Option<T> {
        match &self.given {
            Some(g) if !g[i] => None,
            _ => Some(self.values[i]),
        }
    }
}

/// The exact solution ū and its gradient ∇ū, tabulated.
type Exact<const D: usize> = (Column<f64>, Column<[f64; D]>);

/// A problem tabulated on a mesh of type `M` in dimension `D` (see the module docs).
pub struct Tabulated<M, const D: usize> {
    pub name: String,
    pub mesh: Arc<M>,
    index: HashMap<[u64; D], usize>,
    diffusion: Option<Column<Tensor<D>>>,
    source: Column<f64>,
    source_per_cell: bool,
    dirichlet: Column<f64>,
    neumann: Column<f64>,
    /// One code per face (edge in 2D: 0 Dirichlet, 1 Neumann, 2 Signorini; interior faces
    /// ignored).
    boundary: Vec<u8>,
    boundary_fallback: Option<Py<PyAny>>,
    /// The boundary face of each boundary face centre x_σ.
    face_by_centre: HashMap<[u64; D], usize>,
    /// Boundary face centres and codes, for the nearest-face rule on unknown points.
    boundary_points: Vec<([f64; D], u8)>,
    constraint: Option<(ConstraintKind, Side, Column<f64>)>,
    exact: Option<Exact<D>>,
    pub misses: Arc<Misses>,
}

fn kind_of(code: u8) -> BoundaryKind {
    match code {
        1 => BoundaryKind::Neumann,
        2 => BoundaryKind::Signorini,
        _ => BoundaryKind::Dirichlet,
    }
}

/// `p` and `tag` as the arguments of a Python fallback: (x, y[, z][, tag]).
fn point_args<'py, const D: usize>(
    py: Python<'py>,
    p: [f64; D],
    tag: Option<i32>,
) -> PyResult<Bound<'py, PyTuple>> {
    let mut v: Vec<Bound<'py, PyAny>> = Vec::with_capacity(D + 1);
    for c in p {
        v.push(c.into_pyobject(py)?.into_any());
    }
    if let Some(t) = tag {
        v.push(t.into_pyobject(py)?.into_any());
    }
    PyTuple::new(py, v)
}

/// The D×D tensor of the D² values `v` (row by row).
fn tensor_of<const D: usize>(v: &[f64]) -> PyResult<Tensor<D>> {
    if v.len() != D * D {
        return Err(invalid(format!(
            "the diffusion tensor: expected {} values on a {D}D mesh, got {}",
            D * D,
            v.len()
        )));
    }
    Ok(std::array::from_fn(|i| {
        std::array::from_fn(|j| v[D * i + j])
    }))
}

/// The D values of `v` as a point (a gradient).
fn vector_of<const D: usize>(v: &[f64]) -> PyResult<[f64; D]> {
    <[f64; D]>::try_from(v).map_err(|_| {
        invalid(format!(
            "the exact gradient: expected {D} components on a {D}D mesh, got {}",
            v.len()
        ))
    })
}

impl<M: Send + Sync + 'static, const D: usize> Tabulated<M, D> {
    fn row(&self, p: [f64; D]) -> Option<usize> {
        self.index.get(&point_key(p)).copied()
    }

    /// Value of `col` at `p`: from the table, else from the fallback, else NaN (recorded).
    fn lookup<T: Copy>(
        &self,
        col: &Column<T>,
        p: [f64; D],
        what: &'static str,
        convert: impl Fn(&Bound<'_, PyAny>) -> PyResult<T>,
        nan: T,
    ) -> T {
        if let Some(v) = self.row(p).and_then(|i| col.at(i)) {
            return v;
        }
        self.misses.count.fetch_add(1, Ordering::Relaxed);
        match &col.fallback {
            Some(cb) => {
                self.misses.calls.fetch_add(1, Ordering::Relaxed);
                Python::attach(|py| {
                    match point_args(py, p, None)
                        .and_then(|a| cb.call1(py, a))
                        .and_then(|r| convert(r.bind(py)))
                    {
                        Ok(v) => v,
                        Err(e) => {
                            self.misses.py_error(e);
                            nan
                        }
                    }
                })
            }
            None => {
                self.misses.unresolved(what, &p);
                nan
            }
        }
    }

    fn scalar(&self, col: &Column<f64>, p: [f64; D], what: &'static str) -> f64 {
        self.lookup(col, p, what, |r| r.extract::<f64>(), f64::NAN)
    }

    fn boundary_at(&self, x: [f64; D], tag: i32) -> BoundaryKind {
        if let Some(&e) = self.face_by_centre.get(&point_key(x)) {
            return kind_of(self.boundary[e]);
        }
        self.misses.count.fetch_add(1, Ordering::Relaxed);
        if let Some(cb) = &self.boundary_fallback {
            self.misses.calls.fetch_add(1, Ordering::Relaxed);
            return Python::attach(|py| {
                match point_args(py, x, Some(tag))
                    .and_then(|a| cb.call1(py, a))
                    .and_then(|r| r.bind(py).extract::<u8>())
                {
                    Ok(c) => kind_of(c),
                    Err(e) => {
                        self.misses.py_error(e);
                        BoundaryKind::Dirichlet
                    }
                }
            });
        }
        // nearest boundary face of the tabulated mesh (the warm start's coarse meshes)
        let mut best = (f64::INFINITY, 0u8);
        for &(m, c) in &self.boundary_points {
            let d: f64 = (0..D).map(|i| (m[i] - x[i]).powi(2)).sum();
            if d < best.0 {
                best = (d, c);
            }
        }
        kind_of(best.1)
    }

    /// The `gradvi::problem::Problem` whose closures read this table.
    pub fn problem(self: &Arc<Self>) -> Problem<D> {
        let t = Arc::clone(self);
        let mut pb = Problem::new(
            &self.name,
            Box::new(move |p| t.scalar(&t.source, p, "the source term f")),
        );
        if self.source_per_cell {
            let t = Arc::clone(self);
            pb = pb.with_source_in_cell(Box::new(move |_p, xk| {
                t.scalar(&t.source, xk, "the source term f")
            }));
        }
        if self.diffusion.is_some() {
            let t = Arc::clone(self);
            pb = pb.with_diffusion(Box::new(move |p| {
                let col = t.diffusion.as_ref().expect("checked above");
                t.lookup(
                    col,
                    p,
                    "the diffusion tensor A",
                    |r| tensor_of::<D>(&r.extract::<Vec<f64>>()?),
                    [[f64::NAN; D]; D],
                )
            }));
        }
        let t = Arc::clone(self);
        pb = pb.with_boundary(move |x, tag| t.boundary_at(x, tag));
        let t = Arc::clone(self);
        pb = pb.with_dirichlet(Box::new(move |p| {
            t.scalar(&t.dirichlet, p, "the Dirichlet value")
        }));
        let t = Arc::clone(self);
        pb = pb.with_neumann(Box::new(move |p| {
            t.scalar(&t.neumann, p, "the Neumann flux")
        }));
        if let Some((kind, side, _)) = &self.constraint {
            let t = Arc::clone(self);
            pb = pb.with_constraint(
                *kind,
                *side,
                Box::new(move |p| {
                    let col = &t.constraint.as_ref().expect("checked above").2;
                    t.scalar(col, p, "the barrier")
                }),
            );
        }
        if self.exact.is_some() {
            let (t1, t2) = (Arc::clone(self), Arc::clone(self));
            pb = pb.with_exact(
                Box::new(move |p| {
                    t1.scalar(
                        &t1.exact.as_ref().expect("checked above").0,
                        p,
                        "the exact solution",
                    )
                }),
                Box::new(move |p| {
                    let col = &t2.exact.as_ref().expect("checked above").1;
                    t2.lookup(
                        col,
                        p,
                        "the exact gradient",
                        |r| vector_of::<D>(&r.extract::<Vec<f64>>()?),
                        [f64::NAN; D],
                    )
                }),
            );
        }
        pb
    }
}

impl PyProblem {
    /// The `gradvi::problem::Problem` on `mesh` (a problem file is checked against it first),
    /// and the miss record of a tabulated problem.
    pub fn instantiate(
        &self,
        mesh: &Arc<PolyMesh>,
    ) -> gradvi::Result<(Problem, Option<Arc<Misses>>)> {
        match &self.spec {
            Spec::Builtin { name, params } => {
                let pf = builtin(name, params)?;
                pf.check_against_mesh(mesh)?;
                Ok((pf.problem(), None))
            }
            Spec::File(pf) => {
                pf.check_against_mesh(mesh)?;
                Ok((pf.problem(), None))
            }
            Spec::Tabulated(t) => {
                if !Arc::ptr_eq(&t.mesh, mesh) {
                    return Err(gradvi::Error::InvalidData(
                        "this problem was tabulated on another mesh".into(),
                    ));
                }
                Ok((t.problem(), Some(Arc::clone(&t.misses))))
            }
            Spec::Tabulated3(_) => Err(gradvi::Error::InvalidData(
                "this problem was tabulated on a 3D mesh, and the mesh to solve on is planar"
                    .into(),
            )),
        }
    }

    /// As [`PyProblem::instantiate`], on a 3D mesh. A built-in problem or a problem file is
    /// checked against the mesh as `gradvi solve` checks it
    /// ([`ProblemFile::check_against_mesh3`]): a file that is not a 3D problem (a 2×2 tensor,
    /// a 2-component gradient) is a problem-file error with its place in the file.
    pub fn instantiate3(
        &self,
        mesh: &Arc<PolyMesh3>,
    ) -> gradvi::Result<(Problem<3>, Option<Arc<Misses>>)> {
        let from_file = |pf: &ProblemFile| -> gradvi::Result<(Problem<3>, Option<Arc<Misses>>)> {
            pf.check_against_mesh3(mesh)?;
            Ok((pf.problem_in::<3>()?, None))
        };
        match &self.spec {
            Spec::Tabulated3(t) if Arc::ptr_eq(&t.mesh, mesh) => {
                Ok((t.problem(), Some(Arc::clone(&t.misses))))
            }
            Spec::Tabulated3(_) => Err(gradvi::Error::InvalidData(
                "this problem was tabulated on another mesh".into(),
            )),
            Spec::Tabulated(_) => Err(gradvi::Error::InvalidData(
                "this problem was tabulated on a planar mesh, and the mesh to solve on is 3D"
                    .into(),
            )),
            Spec::Builtin { name, params } => from_file(&builtin(name, params)?),
            Spec::File(pf) => from_file(pf),
        }
    }

    /// The problem file of a built-in problem or a file (`None` for a tabulated problem).
    fn file(&self) -> Option<std::borrow::Cow<'_, ProblemFile>> {
        match &self.spec {
            Spec::Builtin { name, params } => {
                builtin(name, params).ok().map(std::borrow::Cow::Owned)
            }
            Spec::File(pf) => Some(std::borrow::Cow::Borrowed(pf)),
            Spec::Tabulated(_) | Spec::Tabulated3(_) => None,
        }
    }

    /// What a built-in problem or a file describes without a mesh: its barrier (kind, side)
    /// and whether its exact solution is known, from the 2D problem, or the 3D one for a file
    /// that is a 3D problem only.
    fn describe(&self) -> Option<Described> {
        fn of<const D: usize>(pb: &Problem<D>) -> Described {
            (
                pb.constraint.as_ref().map(|c| (c.kind, c.side)),
                pb.exact.is_some(),
            )
        }
        let pf = self.file()?;
        match pf.problem_in::<2>() {
            Ok(pb) => Some(of(&pb)),
            Err(_) => pf.problem_in::<3>().ok().map(|pb| of(&pb)),
        }
    }
}

/// A problem's barrier (kind, side), if any, and whether its exact solution is known.
type Described = (Option<(ConstraintKind, Side)>, bool);

// ------------------------------------------------------------------------------------------
// Reading the tabulated data handed over by the Python layer.

fn item<'py>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
    Ok(d.get_item(key)?.filter(|v| !v.is_none()))
}

fn scalar_col(d: &Bound<'_, PyDict>, key: &str, m: usize) -> PyResult<Option<Column<f64>>> {
    let Some(v) = item(d, key)? else {
        return Ok(None);
    };
    let a: PyReadonlyArray1<'_, f64> = v
        .extract()
        .map_err(|_| invalid(format!("{key}: expected a float64 array")))?;
    let values = a.as_array().to_vec();
    if values.len() != m {
        return Err(invalid(format!(
            "{key}: expected {m} values, got {}",
            values.len()
        )));
    }
    Ok(Some(Column {
        values,
        given: given_rows(d, key, m)?,
        fallback: item(d, &format!("{key}_fallback"))?.map(Bound::unbind),
    }))
}

/// The rows `data["{key}_rows"]` where datum `key` was given, as a mask over the `m` rows
/// (`None` without that entry: every row).
fn given_rows(d: &Bound<'_, PyDict>, key: &str, m: usize) -> PyResult<Option<Vec<bool>>> {
    let Some(v) = item(d, &format!("{key}_rows"))? else {
        return Ok(None);
    };
    let rows: PyReadonlyArray1<'_, i64> = v
        .extract()
        .map_err(|_| invalid(format!("{key}_rows: expected an int64 array")))?;
    let mut given = vec![false; m];
    for &r in rows.as_array() {
        match usize::try_from(r).ok().filter(|&r| r < m) {
            Some(r) => given[r] = true,
            None => return Err(invalid(format!("{key}_rows: row {r} is not in 0..{m}"))),
        }
    }
    Ok(Some(given))
}

fn required_scalar(d: &Bound<'_, PyDict>, key: &str, m: usize) -> PyResult<Column<f64>> {
    scalar_col(d, key, m)?.ok_or_else(|| invalid(format!("{key}: missing")))
}

fn side_of(s: &str) -> PyResult<Side> {
    match s {
        "upper" => Ok(Side::Upper),
        "lower" => Ok(Side::Lower),
        _ => Err(invalid(format!(
            "side must be \"upper\" or \"lower\", got {s:?}"
        ))),
    }
}

/// The row of each tabulated point (the first row where a point is repeated).
fn point_index<const D: usize>(
    points: impl Iterator<Item = [f64; D]>,
    m: usize,
) -> HashMap<[u64; D], usize> {
    let mut index = HashMap::with_capacity(m);
    for (i, p) in points.enumerate() {
        index.entry(point_key(p)).or_insert(i);
    }
    index
}

/// The `diffusion` column of `data` (m, D, D), with its `given` rows and fallback; `None`
/// when absent.
fn diffusion_column<const D: usize>(
    data: &Bound<'_, PyDict>,
    m: usize,
) -> PyResult<Option<Column<Tensor<D>>>> {
    let Some(v) = item(data, "diffusion")? else {
        return Ok(None);
    };
    let a: PyReadonlyArray3<'_, f64> = v.extract().map_err(|_| {
        invalid(format!(
            "diffusion: expected a float64 array of shape (m, {D}, {D})"
        ))
    })?;
    let a = a.as_array();
    if a.shape() != [m, D, D] {
        return Err(invalid(format!(
            "diffusion: expected shape ({m}, {D}, {D}), got {:?}",
            a.shape()
        )));
    }
    let values = (0..m)
        .map(|i| std::array::from_fn(|r| std::array::from_fn(|c| a[[i, r, c]])))
        .collect();
    Ok(Some(Column {
        values,
        given: given_rows(data, "diffusion", m)?,
        fallback: item(data, "diffusion_fallback")?.map(Bound::unbind),
    }))
}

/// The `boundary` codes of `data`, one per face (edge in 2D: 0 Dirichlet, 1 Neumann, 2
/// Signorini; all 0 when absent).
fn boundary_codes(data: &Bound<'_, PyDict>, n_faces: usize, noun: &str) -> PyResult<Vec<u8>> {
    let boundary: Vec<u8> = match item(data, "boundary")? {
        None => vec![0; n_faces],
        Some(v) => {
            let a: PyReadonlyArray1<'_, u8> = v
                .extract()
                .map_err(|_| invalid("boundary: expected a uint8 array"))?;
            a.as_array().to_vec()
        }
    };
    if boundary.len() != n_faces || boundary.iter().any(|&c| c > 2) {
        return Err(invalid(format!(
            "boundary: expected one code 0, 1 or 2 per {noun} ({n_faces} {noun}s)"
        )));
    }
    Ok(boundary)
}

/// The barrier of `data`: its `constraint` kind, `side` and `barrier` column; `None` when
/// there is no `constraint`.
fn constraint_column(
    data: &Bound<'_, PyDict>,
    m: usize,
) -> PyResult<Option<(ConstraintKind, Side, Column<f64>)>> {
    let Some(k) = item(data, "constraint")? else {
        return Ok(None);
    };
    let kind = match k.extract::<String>()?.as_str() {
        "obstacle" => ConstraintKind::Obstacle,
        "signorini" => ConstraintKind::Signorini,
        other => return Err(invalid(format!("unknown constraint kind {other:?}"))),
    };
    let side = side_of(
        &item(data, "side")?
            .ok_or_else(|| invalid("side: missing"))?
            .extract::<String>()?,
    )?;
    Ok(Some((kind, side, required_scalar(data, "barrier", m)?)))
}

/// The exact solution of `data`: `exact_u` and its gradient `exact_grad` (m, D); `None` when
/// there is no `exact_u`.
fn exact_columns<const D: usize>(data: &Bound<'_, PyDict>, m: usize) -> PyResult<Option<Exact<D>>> {
    let Some(u) = scalar_col(data, "exact_u", m)? else {
        return Ok(None);
    };
    let g = item(data, "exact_grad")?.ok_or_else(|| invalid("exact_grad: missing"))?;
    let g: PyReadonlyArray2<'_, f64> = g.extract().map_err(|_| {
        invalid(format!(
            "exact_grad: expected a float64 array of shape (m, {D})"
        ))
    })?;
    let g = g.as_array();
    if g.shape() != [m, D] {
        return Err(invalid(format!(
            "exact_grad: expected shape ({m}, {D}), got {:?}",
            g.shape()
        )));
    }
    let values = g
        .rows()
        .into_iter()
        .map(|r| std::array::from_fn(|i| r[i]))
        .collect();
    let grad = Column {
        values,
        given: given_rows(data, "exact_grad", m)?,
        fallback: item(data, "exact_grad_fallback")?.map(Bound::unbind),
    };
    Ok(Some((u, grad)))
}

#[pymethods]
impl PyProblem {
    /// A built-in problem by name, with parameters (e.g. `[("C", -20.0)]` for test3).
    #[staticmethod]
    fn builtin(py: Python<'_>, name: String, params: Vec<(String, f64)>) -> PyResult<Self> {
        // check the name and the parameters now
        let (n, p) = (name.clone(), params.clone());
        guard(py, move || builtin(&n, &p).map(|_| ()))?;
        Ok(PyProblem {
            spec: Spec::Builtin { name, params },
        })
    }

    /// A problem file, with parameter overrides.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf, params: Vec<(String, f64)>) -> PyResult<Self> {
        let pf = guard(py, move || load(&path, &params))?;
        Ok(PyProblem {
            spec: Spec::File(Box::new(pf)),
        })
    }

    /// A problem tabulated on the planar `mesh` at the rows of `points` (m, 2); see the
    /// module docs for the keys of `data`.
    #[staticmethod]
    fn tabulated(
        name: String,
        mesh: &PyMesh,
        points: PyReadonlyArray2<'_, f64>,
        data: &Bound<'_, PyDict>,
    ) -> PyResult<Self> {
        let m = &mesh.mesh;
        let faces = m
            .boundary_edges()
            .iter()
            .map(|&e| (e, m.edge_midpoint(e)))
            .collect();
        let t = tabulate(name, Arc::clone(m), m.n_edges(), faces, points, data)?;
        Ok(PyProblem {
            spec: Spec::Tabulated(Arc::new(t)),
        })
    }

    /// A problem tabulated on the 3D `mesh` at the rows of `points` (m, 3), as `tabulated`
    /// (the boundary codes are per face, the tensors 3×3, the gradients have 3 components).
    #[staticmethod]
    fn tabulated3(
        name: String,
        mesh: &PyMesh3,
        points: PyReadonlyArray2<'_, f64>,
        data: &Bound<'_, PyDict>,
    ) -> PyResult<Self> {
        let m = &mesh.mesh;
        let faces = (0..m.n_boundary_faces())
            .map(|i| {
                let f = m.boundary_face(i);
                (f, m.face_centre(f))
            })
            .collect();
        let t = tabulate(name, Arc::clone(m), m.n_faces(), faces, points, data)?;
        Ok(PyProblem {
            spec: Spec::Tabulated3(Arc::new(t)),
        })
    }

    #[getter]
    fn name(&self) -> String {
        match &self.spec {
            Spec::Builtin { .. } => self.file().map(|pf| pf.name.clone()).unwrap_or_default(),
            Spec::File(pf) => pf.name.clone(),
            Spec::Tabulated(t) => t.name.clone(),
            Spec::Tabulated3(t) => t.name.clone(),
        }
    }
    #[getter]
    fn source(&self) -> &'static str {
        match &self.spec {
            Spec::Builtin { .. } => "builtin",
            Spec::File(_) => "file",
            Spec::Tabulated(_) | Spec::Tabulated3(_) => "python",
        }
    }
    #[getter]
    fn description(&self) -> Option<String> {
        match &self.spec {
            Spec::File(pf) => pf.description.clone(),
            _ => None,
        }
    }
    #[getter]
    fn path(&self) -> Option<String> {
        match &self.spec {
            Spec::File(pf) => Some(pf.path.display().to_string()),
            _ => None,
        }
    }
    /// Parameters with the values used (files: every parameter; built-ins: those given).
    #[getter]
    fn parameters(&self) -> Vec<(String, f64)> {
        match &self.spec {
            Spec::Builtin { params, .. } => params.clone(),
            Spec::File(pf) => pf.parameters.clone(),
            Spec::Tabulated(_) | Spec::Tabulated3(_) => Vec::new(),
        }
    }
    /// The scheme the file asks for (`scheme = ...`), if any.
    #[getter]
    fn scheme(&self) -> Option<String> {
        match &self.spec {
            Spec::File(pf) => pf.scheme.map(|s| s.name().to_string()),
            _ => None,
        }
    }
    /// The `[mesh]` of a problem file, as text, if any.
    #[getter]
    fn mesh_spec(&self) -> Option<String> {
        match &self.spec {
            Spec::File(pf) => pf.mesh.as_ref().map(|m| m.to_string()),
            _ => None,
        }
    }
    /// Builds the mesh of the file's `[mesh]` section, a `_Mesh` or a `_Mesh3` as `gradvi
    /// solve` would build it ([`gradvi::case::case_mesh`]), a 3D mesh's warped faces as
    /// `warped_faces` ("fan" or "split") says; None without one.
    #[pyo3(signature = (warped_faces="fan"))]
    fn build_mesh(&self, py: Python<'_>, warped_faces: &str) -> PyResult<Option<Py<PyAny>>> {
        let Spec::File(pf) = &self.spec else {
            return Ok(None);
        };
        let Some(spec) = pf.mesh.clone() else {
            return Ok(None);
        };
        let warped = warped_convention(py, warped_faces)?;
        let pf = pf.as_ref();
        let budget = gradvi::budget::MemoryBudget::available();
        let mesh = guard(py, move || case_mesh(&spec, pf, warped, budget))?;
        Ok(Some(match mesh {
            AnyMesh::Two(m) => PyMesh {
                mesh: Arc::new(m),
                physical_names: Vec::new(),
            }
            .into_pyobject(py)?
            .into_any()
            .unbind(),
            AnyMesh::Three(m) => PyMesh3::new(m).into_pyobject(py)?.into_any().unbind(),
        }))
    }
    /// (kind, side) of the barrier: ("obstacle" | "signorini", "upper" | "lower"), or None.
    #[getter]
    fn constraint(&self) -> Option<(String, String)> {
        let name = |k: ConstraintKind, s: Side| {
            (
                match k {
                    ConstraintKind::Obstacle => "obstacle",
                    ConstraintKind::Signorini => "signorini",
                }
                .to_string(),
                match s {
                    Side::Upper => "upper",
                    Side::Lower => "lower",
                }
                .to_string(),
            )
        };
        match &self.spec {
            Spec::Tabulated(t) => t.constraint.as_ref().map(|(k, s, _)| name(*k, *s)),
            Spec::Tabulated3(t) => t.constraint.as_ref().map(|(k, s, _)| name(*k, *s)),
            _ => self.describe()?.0.map(|(k, s)| name(k, s)),
        }
    }
    /// Whether the exact solution is known.
    #[getter]
    fn has_exact(&self) -> bool {
        match &self.spec {
            Spec::Tabulated(t) => t.exact.is_some(),
            Spec::Tabulated3(t) => t.exact.is_some(),
            _ => self.describe().is_some_and(|d| d.1),
        }
    }
}

/// The table of `data` at the rows of `points` (m, D) on `mesh`, which has `n_faces` faces
/// (edges in 2D), `boundary` listing its boundary faces with their centres x_σ.
fn tabulate<M, const D: usize>(
    name: String,
    mesh: Arc<M>,
    n_faces: usize,
    boundary: Vec<(usize, [f64; D])>,
    points: PyReadonlyArray2<'_, f64>,
    data: &Bound<'_, PyDict>,
) -> PyResult<Tabulated<M, D>> {
    crate::guard_attached(|| {
        let pts = points.as_array();
        if pts.ncols() != D {
            return Err(invalid(format!("points must have shape (m, {D})")));
        }
        let m = pts.nrows();
        let index = point_index(
            pts.rows()
                .into_iter()
                .map(|r| std::array::from_fn(|i| r[i])),
            m,
        );
        let noun = if D == 2 { "edge" } else { "face" };
        let codes = boundary_codes(data, n_faces, noun)?;
        Ok(Tabulated {
            name,
            index,
            face_by_centre: boundary.iter().map(|&(f, x)| (point_key(x), f)).collect(),
            boundary_points: boundary.iter().map(|&(f, x)| (x, codes[f])).collect(),
            diffusion: diffusion_column(data, m)?,
            source: required_scalar(data, "source", m)?,
            source_per_cell: item(data, "source_per_cell")?
                .map_or(Ok(false), |v| v.extract::<bool>())?,
            dirichlet: required_scalar(data, "dirichlet", m)?,
            neumann: required_scalar(data, "neumann", m)?,
            boundary: codes,
            boundary_fallback: item(data, "boundary_fallback")?.map(Bound::unbind),
            constraint: constraint_column(data, m)?,
            exact: exact_columns(data, m)?,
            mesh,
            misses: Arc::new(Misses::default()),
        })
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyProblem>()
}
