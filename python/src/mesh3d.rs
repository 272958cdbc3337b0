//! `_Mesh3`: an immutable, validated `gradvi::mesh3d::PolyMesh3` shared by reference counting.
//!
//! The Python layer (`gradvi.Mesh3`, `python/gradvi/_mesh3d.py`) converts meshio meshes and
//! nested lists to the flat description taken here (`from_arrays`), and reads the geometry
//! back as flat arrays (`geometry`).

use crate::errors::invalid;
use crate::guard;
use crate::mesh::vec_array;
use gradvi::mesh::{MemoryBudget, NO_CELL};
use gradvi::mesh3d::generate::Family3;
use gradvi::mesh3d::io::{read_mesh3, write_vtu3};
use gradvi::mesh3d::{Cuboid, Point3, PolyMesh3, Polyhedra};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
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
    fn new(mesh: PolyMesh3) -> Self {
        PyMesh3 {
            mesh: Arc::new(mesh),
        }
    }
}

/// An (n, N) array of the rows `rows`.
fn rows_array<'py, T: numpy::Element + Copy, const N: usize>(
    py: Python<'py>,
    rows: impl ExactSizeIterator<Item = [T; N]>,
) -> PyResult<Bound<'py, PyAny>> {
    let n = rows.len();
    let mut flat = Vec::with_capacity(N * n);
    for r in rows {
        flat.extend_from_slice(&r);
    }
    Ok(PyArray1::from_vec(py, flat).reshape([n, N])?.into_any())
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
fn borrow(v: &[(String, Vec<f64>)]) -> Vec<(&str, &[f64])> {
    v.iter().map(|(n, a)| (n.as_str(), a.as_slice())).collect()
}

/// `domain` (x0, x1, y0, y1, z0, z1) as a [`Cuboid`].
fn cuboid(d: [f64; 6]) -> Cuboid {
    Cuboid::new([d[0], d[1]], [d[2], d[3]], [d[4], d[5]])
}

/// The key of a point in hash tables: its bits (−0 taken as +0).
fn point_key(p: Point3) -> [u64; 3] {
    p.map(|v| (v + 0.0).to_bits())
}

#[pymethods]
impl PyMesh3 {
    /// Reads a 3D mesh file (.msh gmsh 4.1/2.2 ASCII, .vtu, RF .node/.ele or their stem).
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        guard(py, move || {
            let p = read_mesh3(&path, MemoryBudget::available())?;
            let m = PolyMesh3::from_polyhedra(p, MemoryBudget::available())
                .map_err(|source| gradvi::Error::InvalidMeshFile { path, source })?;
            Ok(PyMesh3::new(m))
        })
    }

    /// Builds a mesh from points (n, 3), the CSR description of `gradvi::mesh3d::Polyhedra`
    /// (cell offsets into the face sides, face-side offsets into `face_vertices`), optional
    /// cell tags (one per cell) and optional tagged boundary faces (offsets, vertex loops,
    /// tags).
    #[staticmethod]
    #[pyo3(signature = (points, cell_ptr, face_ptr, face_vertices, cell_tags=None, tagged=None))]
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
    ) -> PyResult<Self> {
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
            Ok(PyMesh3::new(PolyMesh3::from_polyhedra(
                p,
                MemoryBudget::available(),
            )?))
        })
    }

    /// The built-in 3D family `family` at `level`, optionally mapped onto a box
    /// (x0, x1, y0, y1, z0, z1).
    #[staticmethod]
    #[pyo3(signature = (family, level, domain=None))]
    fn generate(
        py: Python<'_>,
        family: &str,
        level: usize,
        domain: Option<[f64; 6]>,
    ) -> PyResult<Self> {
        let fam = Family3::from_str(family).map_err(|e| crate::to_pyerr(py, &e))?;
        let domain = domain.map_or(Cuboid::UNIT, cuboid);
        guard(py, move || {
            Ok(PyMesh3::new(fam.generate_on(
                level,
                domain,
                MemoryBudget::available(),
            )?))
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
        d.set_item("points", rows_array(py, m.vertices().iter().copied())?)?;
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
        d.set_item("face_cells", rows_array(py, cells)?)?;
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
        d.set_item("centroids", rows_array(py, centroids)?)?;
        let areas = per_face(PolyMesh3::face_measure);
        d.set_item("face_areas", vec_array::<f64>(py, areas))?;
        let fc = (0..nf).map(|f| m.face_centroid(f));
        d.set_item("face_centroids", rows_array(py, fc)?)?;
        let normals = (0..nf).map(|f| m.face_normal(f));
        d.set_item("face_normals", rows_array(py, normals)?)?;
        let face_tags: Vec<i32> = (0..nf).map(|f| m.face_tag(f)).collect();
        d.set_item("face_tags", vec_array(py, face_tags))?;
        let cell_tags: Vec<i32> = (0..nc).map(|k| m.cell_tag(k)).collect();
        d.set_item("cell_tags", vec_array(py, cell_tags))?;
        let boundary: Vec<i64> = m.boundary_faces().iter().map(|&f| f as i64).collect();
        d.set_item("boundary_faces", vec_array(py, boundary))?;
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
        let owned = |v: Vec<(String, PyReadonlyArray1<'_, f64>)>| -> Vec<(String, Vec<f64>)> {
            v.into_iter()
                .map(|(n, a)| (n, a.as_array().to_vec()))
                .collect()
        };
        let (pd, cd) = (owned(point_data), owned(cell_data));
        let mesh = Arc::clone(&self.mesh);
        guard(py, move || {
            write_vtu3(&path, &mesh.to_polyhedra(), &borrow(&pd), &borrow(&cd))
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
