//! `_Mesh3`: an immutable, validated `gradvi::mesh3d::PolyMesh3` shared by reference counting.
//!
//! The Python layer (`gradvi.Mesh3`, `python/gradvi/_mesh3d.py`) converts meshio meshes and
//! nested lists to the flat description taken here (`from_arrays`), and reads the geometry
//! back as flat arrays (`geometry`).

use crate::errors::invalid;
use crate::guard;
use crate::mesh::{point_key, points_array, unique_rows, vec_array};
use gradvi::budget::MemoryBudget;
use gradvi::mesh::{NO_CELL, SolveMesh};
use gradvi::mesh3d::generate::Family3;
use gradvi::mesh3d::io::{read_mesh3, write_vtu3};
use gradvi::mesh3d::{Cuboid, Point3, PolyMesh3, Polyhedra, WarpedFaces};
use gradvi::post::vtu_boundary::{write_boundary_vtu, write_faces_vtu};
use gradvi::scheme::{GradientDiscretisation, SchemeKind, SchemeOptions, build_with3};
use nalgebra::DVector;
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

/// A gradvi 3D mesh (private handle; see `gradvi.Mesh3`).
#[pyclass(name = "_Mesh3", module = "gradvi._gradvi", frozen)]
pub struct PyMesh3 {
    pub mesh: Arc<PolyMesh3>,
}

impl PyMesh3 {
    pub(crate) fn new(mesh: PolyMesh3) -> Self {
        PyMesh3 {
            mesh: Arc::new(mesh),
        }
    }
}

/// `a` as 32-bit ids or offsets, else `InvalidDataError` naming `what` and the entry.
fn to_u32(what: &str, a: PyReadonlyArray1<'_, i64>) -> PyResult<Vec<u32>> {
    a.as_array()
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            u32::try_from(v)
                .ok()
                .filter(|&u| u < u32::MAX)
                .ok_or_else(|| {
                    invalid(format!(
                        "{what} entry {i} is {v}: ids and offsets must be in 0..{}",
                        u32::MAX
                    ))
                })
        })
        .collect()
}

/// Named arrays as the slices the writers take.
pub(crate) fn borrow(v: &[(String, Vec<f64>)]) -> Vec<(&str, &[f64])> {
    v.iter().map(|(n, a)| (n.as_str(), a.as_slice())).collect()
}

/// The convention for warped faces named `name` ("fan" or "split"), else the library's
/// `InvalidDataError`.
pub(crate) fn warped_convention(py: Python<'_>, name: &str) -> PyResult<WarpedFaces> {
    WarpedFaces::from_str(name).map_err(|e| crate::to_pyerr(py, &e))
}

/// Named numpy arrays as owned vectors (to hand them to a detached writer).
pub(crate) fn owned(v: Vec<(String, PyReadonlyArray1<'_, f64>)>) -> Vec<(String, Vec<f64>)> {
    v.into_iter()
        .map(|(n, a)| (n, a.as_array().to_vec()))
        .collect()
}

/// `domain` (x0, x1, y0, y1, z0, z1) as a [`Cuboid`].
fn cuboid(d: [f64; 6]) -> Cuboid {
    Cuboid::new([d[0], d[1]], [d[2], d[3]], [d[4], d[5]])
}

#[pymethods]
impl PyMesh3 {
    /// Reads a 3D mesh file (.msh gmsh 4.1/2.2 ASCII, .vtu, RF .node/.ele or their stem);
    /// `warped_faces`: "fan" (the default) or "split" (`gradvi::mesh3d::WarpedFaces`).
    #[staticmethod]
    #[pyo3(signature = (path, warped_faces="fan"))]
    fn read(py: Python<'_>, path: PathBuf, warped_faces: &str) -> PyResult<Self> {
        let warped = warped_convention(py, warped_faces)?;
        guard(py, move || {
            let p = read_mesh3(&path, MemoryBudget::available())?;
            let m = PolyMesh3::from_file_polyhedra(p, MemoryBudget::available(), warped)
                .map_err(|source| gradvi::Error::InvalidMeshFile { path, source })?;
            Ok(PyMesh3::new(m))
        })
    }

    /// Builds a mesh from points (n, 3), the CSR description of `gradvi::mesh3d::Polyhedra`
    /// (cell offsets into the face sides, face-side offsets into `face_vertices`), optional
    /// cell tags (one per cell) and optional tagged boundary faces (offsets, vertex loops,
    /// tags); `warped_faces` as for `read`.
    #[staticmethod]
    #[pyo3(signature = (points, cell_ptr, face_ptr, face_vertices, cell_tags=None, tagged=None, warped_faces="fan"))]
    #[allow(clippy::too_many_arguments)]
    fn from_arrays(
        py: Python<'_>,
        points: PyReadonlyArray2<'_, f64>,
        cell_ptr: PyReadonlyArray1<'_, i64>,
        face_ptr: PyReadonlyArray1<'_, i64>,
        face_vertices: PyReadonlyArray1<'_, i64>,
        cell_tags: Option<PyReadonlyArray1<'_, i32>>,
        tagged: Option<(
            PyReadonlyArray1<'_, i64>,
            PyReadonlyArray1<'_, i64>,
            PyReadonlyArray1<'_, i32>,
        )>,
        warped_faces: &str,
    ) -> PyResult<Self> {
        let warped = warped_convention(py, warped_faces)?;
        let pts = points.as_array();
        if pts.ncols() != 3 {
            return Err(invalid(format!(
                "points must have shape (n, 3), got {:?}",
                pts.shape()
            )));
        }
        let mut p = Polyhedra {
            vertices: pts.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect(),
            cell_ptr: to_u32("cell offset", cell_ptr)?,
            face_ptr: to_u32("face offset", face_ptr)?,
            face_vertices: to_u32("face vertex", face_vertices)?,
            cell_tags: cell_tags.map_or(Vec::new(), |t| t.as_array().to_vec()),
            ..Polyhedra::default()
        };
        if let Some((ptr, verts, tags)) = tagged {
            p.tagged_ptr = to_u32("tagged face offset", ptr)?;
            p.tagged_vertices = to_u32("tagged face vertex", verts)?;
            p.tagged_tags = tags.as_array().to_vec();
        }
        guard(py, move || {
            Ok(PyMesh3::new(PolyMesh3::from_polyhedra_with(
                p,
                MemoryBudget::available(),
                warped,
            )?))
        })
    }

    /// The built-in 3D family `family` at `level`, optionally mapped onto a box
    /// (x0, x1, y0, y1, z0, z1); `warped_faces` as for `read`.
    #[staticmethod]
    #[pyo3(signature = (family, level, domain=None, warped_faces="fan"))]
    fn generate(
        py: Python<'_>,
        family: &str,
        level: usize,
        domain: Option<[f64; 6]>,
        warped_faces: &str,
    ) -> PyResult<Self> {
        let fam = Family3::from_str(family).map_err(|e| crate::to_pyerr(py, &e))?;
        let warped = warped_convention(py, warped_faces)?;
        let domain = domain.map_or(Cuboid::UNIT, cuboid);
        guard(py, move || {
            let budget = MemoryBudget::available();
            let m = fam.generate_on(level, domain, budget)?;
            Ok(PyMesh3::new(warped.apply(m, budget)?))
        })
    }

    /// A copy whose boundary faces carry `tags[f]` (one entry per face; interior entries are
    /// ignored).
    fn with_face_tags(&self, py: Python<'_>, tags: PyReadonlyArray1<'_, i32>) -> PyResult<Self> {
        let tags = tags.as_array().to_vec();
        let mesh = Arc::clone(&self.mesh);
        if tags.len() != mesh.n_faces() {
            return Err(invalid(format!(
                "face tags must have one entry per face ({}), got {}",
                mesh.n_faces(),
                tags.len()
            )));
        }
        guard(py, move || {
            let by_centroid: HashMap<[u64; 3], usize> = mesh
                .boundary_faces()
                .iter()
                .map(|&f| (point_key(mesh.face_centroid(f as usize)), f as usize))
                .collect();
            let m =
                mesh.with_boundary_tags(|x| by_centroid.get(&point_key(x)).map_or(0, |&f| tags[f]));
            Ok(PyMesh3::new(m))
        })
    }

    /// A copy whose cell k carries `tags[k]`.
    fn with_cell_tags(&self, py: Python<'_>, tags: PyReadonlyArray1<'_, i32>) -> PyResult<Self> {
        let tags = tags.as_array().to_vec();
        let mesh = Arc::clone(&self.mesh);
        guard(py, move || {
            Ok(PyMesh3::new(PolyMesh3::clone(&mesh).with_cell_tags(tags)?))
        })
    }

    /// The scalar attributes (sizes, h, bounding box as (x0, x1, y0, y1, z0, z1)), as a dict
    /// (computed once by the Python layer, which caches it).
    fn scalars<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &*self.mesh;
        let d = PyDict::new(py);
        d.set_item("n_vertices", m.n_vertices())?;
        d.set_item("n_cells", m.n_cells())?;
        d.set_item("n_faces", m.n_faces())?;
        d.set_item("h", m.h())?;
        let [x, y, z] = m.bounding_box().ranges();
        d.set_item("bounding_box", (x[0], x[1], y[0], y[1], z[0], z[1]))?;
        Ok(d)
    }

    /// Whether two handles share the same mesh object.
    fn same_as(&self, other: &PyMesh3) -> bool {
        Arc::ptr_eq(&self.mesh, &other.mesh)
    }

    /// Every geometry array, as a dict (computed once by the Python layer, which caches it).
    fn geometry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &*self.mesh;
        let (nc, nf) = (m.n_cells(), m.n_faces());
        let d = PyDict::new(py);
        d.set_item("points", points_array(py, m.vertices().iter().copied())?)?;
        let (mut cell_ptr, mut cell_faces) = (Vec::with_capacity(nc + 1), Vec::new());
        let mut dists = Vec::new();
        cell_ptr.push(0i64);
        for k in 0..nc {
            let faces = m.cell_faces(k);
            cell_faces.extend(faces.iter().map(|&f| f as i64));
            dists.extend((0..faces.len()).map(|i| m.cell_normal_dist(k, i).1));
            cell_ptr.push(cell_faces.len() as i64);
        }
        d.set_item("cell_face_offsets", vec_array(py, cell_ptr))?;
        d.set_item("cell_faces", vec_array(py, cell_faces))?;
        d.set_item("cell_dists", vec_array(py, dists))?;
        let (mut face_ptr, mut face_verts) = (Vec::with_capacity(nf + 1), Vec::new());
        face_ptr.push(0i64);
        for f in 0..nf {
            face_verts.extend(m.face_vertices(f).iter().map(|&v| v as i64));
            face_ptr.push(face_verts.len() as i64);
        }
        d.set_item("face_offsets", vec_array(py, face_ptr))?;
        d.set_item("face_connectivity", vec_array(py, face_verts))?;
        let side = |k: usize| if k == NO_CELL { -1 } else { k as i64 };
        let cells = (0..nf).map(|f| m.face_cells(f).map(side));
        d.set_item("face_cells", points_array(py, cells)?)?;
        let per_cell = |g: fn(&PolyMesh3, usize) -> f64| (0..nc).map(|k| g(m, k)).collect();
        let per_face = |g: fn(&PolyMesh3, usize) -> f64| (0..nf).map(|f| g(m, f)).collect();
        d.set_item(
            "volumes",
            vec_array::<f64>(py, per_cell(PolyMesh3::measure)),
        )?;
        d.set_item(
            "diameters",
            vec_array::<f64>(py, per_cell(PolyMesh3::diameter)),
        )?;
        let centroids = (0..nc).map(|k| m.centroid(k));
        d.set_item("centroids", points_array(py, centroids)?)?;
        let areas = per_face(PolyMesh3::face_measure);
        d.set_item("face_areas", vec_array::<f64>(py, areas))?;
        let fc = (0..nf).map(|f| m.face_centroid(f));
        d.set_item("face_centroids", points_array(py, fc)?)?;
        let normals = (0..nf).map(|f| m.face_normal(f));
        d.set_item("face_normals", points_array(py, normals)?)?;
        let face_tags: Vec<i32> = (0..nf).map(|f| m.face_tag(f)).collect();
        d.set_item("face_tags", vec_array(py, face_tags))?;
        let cell_tags: Vec<i32> = (0..nc).map(|k| m.cell_tag(k)).collect();
        d.set_item("cell_tags", vec_array(py, cell_tags))?;
        let boundary: Vec<i64> = m.boundary_faces().iter().map(|&f| f as i64).collect();
        d.set_item("boundary_faces", vec_array(py, boundary))?;
        Ok(d)
    }

    /// The points where `scheme` (`gradvi::scheme::build_with3`) evaluates problem data on this
    /// mesh, as the solve computes them (bit for bit): `points` (m, 3), each point once (in
    /// the order of first appearance in the lists below), and `rows`: for each datum, the
    /// rows of its points (each once, ascending): `diffusion` x_K; `source` the points of the
    /// scheme's local load, cell by cell, then x_K (the data scale); `boundary` x_σ of the
    /// boundary faces (the kind and g_N); `trace` the points of the trace unknowns of the
    /// boundary faces (u_D, a Signorini barrier); `obstacle` the points of the obstacle
    /// unknowns, then the trace points; `exact` x_K (the errors).
    fn evaluation_points<'py>(
        &self,
        py: Python<'py>,
        scheme: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let kind = SchemeKind::from_str(scheme).map_err(|e| crate::to_pyerr(py, &e))?;
        let mesh = Arc::clone(&self.mesh);
        let lists = guard(py, move || {
            let s = build_with3(kind, &mesh, &SchemeOptions::default())?;
            Ok(evaluation_lists(s.as_ref()))
        })?;
        let (unique, rows) = unique_rows(py, lists, |p: &Point3| *p)?;
        let d = PyDict::new(py);
        d.set_item("points", points_array(py, unique.into_iter())?)?;
        d.set_item("rows", rows)?;
        Ok(d)
    }

    /// Writes the mesh with named point (per vertex) and cell data to an ASCII .vtu file
    /// (`gradvi::mesh3d::io::write_vtu3`: tetrahedra or hexahedra when every cell is one,
    /// else polyhedra).
    fn write_vtu(
        &self,
        py: Python<'_>,
        path: PathBuf,
        point_data: Vec<(String, PyReadonlyArray1<'_, f64>)>,
        cell_data: Vec<(String, PyReadonlyArray1<'_, f64>)>,
    ) -> PyResult<()> {
        let (pd, cd) = (owned(point_data), owned(cell_data));
        let mesh = Arc::clone(&self.mesh);
        guard(py, move || {
            write_vtu3(&path, &mesh.to_polyhedra(), &borrow(&pd), &borrow(&cd))
        })
    }

    /// Writes the boundary faces (`boundary_only`), or every face of the mesh, as polygons
    /// with named point data (per mesh vertex) and face data (per mesh face) to an ASCII .vtu
    /// file (`gradvi::post::vtu_boundary::write_faces_vtu`).
    fn write_faces_vtu(
        &self,
        py: Python<'_>,
        path: PathBuf,
        point_data: Vec<(String, PyReadonlyArray1<'_, f64>)>,
        face_data: Vec<(String, PyReadonlyArray1<'_, f64>)>,
        boundary_only: bool,
    ) -> PyResult<()> {
        let (pd, fd) = (owned(point_data), owned(face_data));
        let mesh = Arc::clone(&self.mesh);
        guard(py, move || {
            let (pd, fd) = (borrow(&pd), borrow(&fd));
            if boundary_only {
                return write_boundary_vtu(&path, &mesh, &pd, &fd);
            }
            let all: Vec<u32> = (0..mesh.n_faces() as u32).collect();
            write_faces_vtu(&path, &mesh, &all, &pd, &fd)
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "<gradvi 3D mesh: {} cells, {} faces, {} vertices, h = {:.4e}>",
            self.mesh.n_cells(),
            self.mesh.n_faces(),
            self.mesh.n_vertices(),
            self.mesh.h()
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMesh3>()
}

/// The evaluation lists of [`PyMesh3::evaluation_points`] for the scheme `s`, read off the
/// scheme's own methods (its local load is run with a datum that records where it is called).
fn evaluation_lists<M: SolveMesh<D> + ?Sized, const D: usize>(
    s: &dyn GradientDiscretisation<M, D>,
) -> Vec<(&'static str, Vec<[f64; D]>)> {
    let mesh = s.mesh();
    let centres: Vec<[f64; D]> = (0..mesh.n_cells()).map(|k| mesh.cell_centre(k)).collect();
    let called = RefCell::new(Vec::new());
    let mut b = DVector::zeros(0);
    for k in 0..mesh.n_cells() {
        s.local_load(
            k,
            &|p| {
                called.borrow_mut().push(p);
                0.0
            },
            &mut b,
        );
    }
    let mut source = called.into_inner();
    source.extend_from_slice(&centres);
    let faces: Vec<usize> = (0..mesh.n_boundary_faces())
        .map(|i| mesh.boundary_face(i))
        .collect();
    let boundary = faces.iter().map(|&f| mesh.face_centre(f)).collect();
    let (mut trace, mut tr) = (Vec::new(), Vec::new());
    for &f in &faces {
        s.face_trace_dofs(f, &mut tr);
        trace.extend(tr.iter().map(|t| t.point));
    }
    let mut obstacle: Vec<[f64; D]> = s.obstacle_dofs().iter().map(|d| d.point).collect();
    obstacle.extend_from_slice(&trace);
    vec![
        ("diffusion", centres.clone()),
        ("source", source),
        ("boundary", boundary),
        ("trace", trace),
        ("obstacle", obstacle),
        ("exact", centres),
    ]
}
