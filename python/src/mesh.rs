//! `_Mesh`: an immutable, validated `gradvi::mesh::PolyMesh` shared by reference counting.

use crate::errors::invalid;
use crate::guard;
use crate::mesh3d::{borrow, owned};
use gradvi::mesh::generate::{Family, cartesian_rect_within};
use gradvi::mesh::io::{read_mesh, read_msh, write_typ2, write_vtu};
use gradvi::budget::MemoryBudget;
use gradvi::mesh::{NO_CELL, Point, PolyMesh, Rect};
use gradvi::scheme::points::{self, Site};
use gradvi::scheme::{SchemeKind, build};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rustc_hash::FxHashMap;
use std::collections::HashMap;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Arc;

/// A gradvi mesh (private handle; see `gradvi.Mesh`).
#[pyclass(name = "_Mesh", module = "gradvi._gradvi", frozen)]
pub struct PyMesh {
    pub mesh: Arc<PolyMesh>,
    /// `(dimension, tag, name)` of a gmsh file's `$PhysicalNames`.
    pub physical_names: Vec<(i32, i32, String)>,
}

impl PyMesh {
    fn new(mesh: PolyMesh) -> Self {
        PyMesh {
            mesh: Arc::new(mesh),
            physical_names: Vec::new(),
        }
    }
}

/// The key of a point in hash tables: its bits (−0 taken as +0).
pub fn point_key<const D: usize>(p: [f64; D]) -> [u64; D] {
    p.map(|v| (v + 0.0).to_bits())
}

/// An (n, N) array of the rows `rows` (points, index pairs, ...).
pub fn points_array<'py, T: numpy::Element + Copy, const N: usize>(
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

/// The evaluation points of several data, each point once: `lists` gives, for each datum, the
/// items (points with whatever they carry) where the solve reads it, and `point` the point of
/// an item. Returns the unique items in the order of first appearance and, for each datum, the
/// rows of its points (each once, ascending) as a dict of int64 arrays.
pub fn unique_rows<'py, T: Copy, const D: usize>(
    py: Python<'py>,
    lists: Vec<(&'static str, Vec<T>)>,
    point: impl Fn(&T) -> [f64; D],
) -> PyResult<(Vec<T>, Bound<'py, PyDict>)> {
    let total = lists.iter().map(|(_, l)| l.len()).sum();
    let mut row_of: FxHashMap<[u64; D], usize> =
        FxHashMap::with_capacity_and_hasher(total, Default::default());
    let mut unique: Vec<T> = Vec::with_capacity(total);
    let rows = PyDict::new(py);
    for (name, list) in lists {
        let mut r: Vec<i64> = list
            .iter()
            .map(|q| {
                *row_of.entry(point_key(point(q))).or_insert_with(|| {
                    unique.push(*q);
                    unique.len() - 1
                }) as i64
            })
            .collect();
        r.sort_unstable();
        r.dedup();
        rows.set_item(name, vec_array(py, r))?;
    }
    Ok((unique, rows))
}

/// `f(m, k)` for every cell k of `m`.
fn per_cell<T>(m: &PolyMesh, f: fn(&PolyMesh, usize) -> T) -> Vec<T> {
    (0..m.n_cells()).map(|k| f(m, k)).collect()
}

/// `f(m, e)` for every edge e of `m`.
fn per_edge<T>(m: &PolyMesh, f: fn(&PolyMesh, usize) -> T) -> Vec<T> {
    (0..m.n_edges()).map(|e| f(m, e)).collect()
}

/// A 1-d array from a vector, without copying.
pub fn vec_array<'py, T: numpy::Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyAny> {
    PyArray1::from_vec(py, v).into_any()
}

fn index_array(py: Python<'_>, v: impl Iterator<Item = usize>) -> Bound<'_, PyAny> {
    vec_array(py, v.map(|i| i as i64).collect::<Vec<i64>>())
}

fn check_rect(d: [f64; 4]) -> PyResult<()> {
    if !(d.iter().all(|v| v.is_finite()) && d[1] > d[0] && d[3] > d[2]) {
        return Err(invalid(format!(
            "the rectangle [{}, {}] x [{}, {}] must be finite with x0 < x1 and y0 < y1",
            d[0], d[1], d[2], d[3]
        )));
    }
    Ok(())
}

#[pymethods]
impl PyMesh {
    /// Reads a mesh file (.msh gmsh 4.1/2.2 ASCII, .typ1, .typ2), keeping gmsh physical names.
    #[staticmethod]
    fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let is_msh = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("msh"));
        guard(py, move || {
            if is_msh {
                let m = read_msh(&path, MemoryBudget::available())?;
                Ok(PyMesh {
                    mesh: Arc::new(m.mesh),
                    physical_names: m.physical_names,
                })
            } else {
                Ok(PyMesh::new(read_mesh(&path, MemoryBudget::available())?))
            }
        })
    }

    /// Builds a mesh from points (n, 2), CSR cells (offsets, connectivity) and optional
    /// boundary tags (k, 3) rows (vertex a, vertex b, tag).
    #[staticmethod]
    #[pyo3(signature = (points, offsets, connectivity, tagged_edges=None))]
    fn from_arrays(
        py: Python<'_>,
        points: PyReadonlyArray2<'_, f64>,
        offsets: PyReadonlyArray1<'_, i64>,
        connectivity: PyReadonlyArray1<'_, i64>,
        tagged_edges: Option<PyReadonlyArray2<'_, i64>>,
    ) -> PyResult<Self> {
        let pts = points.as_array();
        if pts.ncols() != 2 {
            return Err(invalid(format!(
                "points must have shape (n, 2), got {:?}",
                pts.shape()
            )));
        }
        let vertices: Vec<Point> = pts.rows().into_iter().map(|r| [r[0], r[1]]).collect();
        let off = offsets.as_array();
        let conn = connectivity.as_array();
        if off.is_empty() || off[0] != 0 || off[off.len() - 1] as usize != conn.len() {
            return Err(invalid(format!(
                "cell offsets must start at 0 and end at the length of the connectivity ({})",
                conn.len()
            )));
        }
        let mut cells = Vec::with_capacity(off.len() - 1);
        for k in 0..off.len() - 1 {
            let (a, b) = (off[k], off[k + 1]);
            if b < a || a < 0 || b as usize > conn.len() {
                return Err(invalid(format!(
                    "cell offsets must be non-decreasing from 0 to {}: cell {k} has offsets {a}..{b}",
                    conn.len()
                )));
            }
            let mut c = Vec::with_capacity((b - a) as usize);
            for &v in conn.slice(numpy::ndarray::s![a as usize..b as usize]) {
                if v < 0 {
                    return Err(invalid(format!(
                        "cell {k} refers to the negative vertex id {v}"
                    )));
                }
                c.push(v as usize);
            }
            cells.push(c);
        }
        let mut tags = Vec::new();
        if let Some(t) = tagged_edges {
            let t = t.as_array();
            if t.ncols() != 3 {
                return Err(invalid(format!(
                    "tagged edges must have shape (k, 3) rows (vertex a, vertex b, tag), got {:?}",
                    t.shape()
                )));
            }
            for (i, r) in t.rows().into_iter().enumerate() {
                if r[0] < 0 || r[1] < 0 || i32::try_from(r[2]).is_err() {
                    return Err(invalid(format!(
                        "tagged edge {i} ({}, {}, tag {}) has a negative vertex or a tag out of the 32-bit range",
                        r[0], r[1], r[2]
                    )));
                }
                tags.push((r[0] as usize, r[1] as usize, r[2] as i32));
            }
        }
        guard(py, move || {
            Ok(PyMesh::new(PolyMesh::from_cells_tagged(
                vertices, cells, &tags,
            )?))
        })
    }

    /// The built-in family `family` at `level`, optionally mapped onto a rectangle.
    #[staticmethod]
    #[pyo3(signature = (family, level, domain=None))]
    fn generate(
        py: Python<'_>,
        family: &str,
        level: usize,
        domain: Option<[f64; 4]>,
    ) -> PyResult<Self> {
        let fam = Family::from_str(family).map_err(|e| crate::to_pyerr(py, &e))?;
        if let Some(d) = domain {
            check_rect(d)?;
        }
        guard(py, move || {
            Ok(PyMesh::new(match domain {
                None => fam.generate(level, MemoryBudget::available())?,
                Some([x0, x1, y0, y1]) => fam.generate_on(
                    level,
                    Rect::new([x0, x1], [y0, y1]),
                    MemoryBudget::available(),
                )?,
            }))
        })
    }

    /// nx × ny rectangles on [x0, x1] × [y0, y1].
    #[staticmethod]
    fn cartesian(py: Python<'_>, nx: usize, ny: usize, domain: [f64; 4]) -> PyResult<Self> {
        check_rect(domain)?;
        guard(py, move || {
            Ok(PyMesh::new(cartesian_rect_within(
                nx,
                ny,
                [domain[0], domain[1]],
                [domain[2], domain[3]],
                MemoryBudget::available(),
            )?))
        })
    }

    /// A copy whose boundary edges carry `tags[e]` (one entry per edge; interior entries are
    /// ignored).
    fn with_edge_tags(&self, py: Python<'_>, tags: PyReadonlyArray1<'_, i32>) -> PyResult<Self> {
        let tags = tags.as_array().to_vec();
        let mesh = Arc::clone(&self.mesh);
        if tags.len() != mesh.n_edges() {
            return Err(invalid(format!(
                "edge tags must have one entry per edge ({}), got {}",
                mesh.n_edges(),
                tags.len()
            )));
        }
        let names = self.physical_names.clone();
        guard(py, move || {
            let by_mid: HashMap<[u64; 2], usize> = mesh
                .boundary_edges()
                .iter()
                .map(|&e| (point_key(mesh.edge_midpoint(e)), e))
                .collect();
            let m = mesh.with_boundary_tags(|x| by_mid.get(&point_key(x)).map_or(0, |&e| tags[e]));
            Ok(PyMesh {
                mesh: Arc::new(m),
                physical_names: names,
            })
        })
    }

    /// The scalar attributes (sizes, h, whether every cell is a triangle, bounding box as
    /// (x0, x1, y0, y1), gmsh physical names), as a dict (computed once by the Python layer,
    /// which caches it).
    fn scalars<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &*self.mesh;
        let d = PyDict::new(py);
        d.set_item("n_vertices", m.n_vertices())?;
        d.set_item("n_cells", m.n_cells())?;
        d.set_item("n_edges", m.n_edges())?;
        d.set_item("h", m.h())?;
        d.set_item("is_triangular", m.is_triangular())?;
        // (x0, x1, y0, y1): the x range, then the y range (gradvi.Rect)
        let b = m.bounding_box();
        d.set_item("bounding_box", (b.x[0], b.x[1], b.y[0], b.y[1]))?;
        d.set_item("physical_names", self.physical_names.clone())?;
        Ok(d)
    }
    /// Whether two handles share the same mesh object.
    fn same_as(&self, other: &PyMesh) -> bool {
        Arc::ptr_eq(&self.mesh, &other.mesh)
    }

    /// Every geometry array, as a dict (computed once by the Python layer, which caches it).
    fn geometry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &*self.mesh;
        let (nc, ne) = (m.n_cells(), m.n_edges());
        let d = PyDict::new(py);
        d.set_item("points", points_array(py, m.vertices().iter().copied())?)?;
        let mut offsets = Vec::with_capacity(nc + 1);
        offsets.push(0i64);
        let (mut conn, mut cedges, mut normals, mut dists) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for k in 0..nc {
            conn.extend(m.cell_vertices(k).iter().map(|&v| v as i64));
            cedges.extend(m.cell_edges(k).iter().map(|&e| e as i64));
            for (n, dk) in m.cell_normals_dists(k) {
                normals.push(n);
                dists.push(dk);
            }
            offsets.push(conn.len() as i64);
        }
        d.set_item("cell_offsets", vec_array(py, offsets))?;
        d.set_item("cell_connectivity", vec_array(py, conn))?;
        d.set_item("cell_edges", vec_array(py, cedges))?;
        d.set_item("cell_normals", points_array(py, normals.into_iter())?)?;
        d.set_item("cell_dists", vec_array(py, dists))?;
        d.set_item(
            "centroids",
            points_array(py, per_cell(m, PolyMesh::centroid).into_iter())?,
        )?;
        d.set_item("measures", vec_array(py, per_cell(m, PolyMesh::measure)))?;
        d.set_item("diameters", vec_array(py, per_cell(m, PolyMesh::diameter)))?;
        let mut edges = Vec::with_capacity(2 * ne);
        let mut ecells = Vec::with_capacity(2 * ne);
        for e in 0..ne {
            edges.extend(m.edge_vertices(e).iter().map(|&v| v as i64));
            ecells.extend(
                m.edge_cells(e)
                    .iter()
                    .map(|&k| if k == NO_CELL { -1 } else { k as i64 }),
            );
        }
        d.set_item("edges", PyArray1::from_vec(py, edges).reshape([ne, 2])?)?;
        d.set_item(
            "edge_cells",
            PyArray1::from_vec(py, ecells).reshape([ne, 2])?,
        )?;
        d.set_item(
            "edge_midpoints",
            points_array(py, per_edge(m, PolyMesh::edge_midpoint).into_iter())?,
        )?;
        d.set_item(
            "edge_lengths",
            vec_array(py, per_edge(m, PolyMesh::edge_measure)),
        )?;
        d.set_item("edge_tags", vec_array(py, per_edge(m, PolyMesh::edge_tag)))?;
        d.set_item(
            "boundary_edges",
            index_array(py, m.boundary_edges().iter().copied()),
        )?;
        Ok(d)
    }

    /// The points where `scheme` evaluates problem data on this mesh, from
    /// `gradvi::scheme::points`: `points` (m, 2), each point once (in the order of first
    /// appearance in the lists below); its site (`site_kind`: 0 vertex, 1 edge midpoint, 2
    /// centroid, 3 another point of a cell; `site_index`: the vertex, edge or cell; for kind 3,
    /// `site_edge`: the edge σ of the triangle co(σ ∪ {x_K}) holding it and `site_weights` (m, 3):
    /// its barycentric weights there with respect to x_K and the ends of σ, else -1 and 0);
    /// and `rows`: for each datum (`diffusion`, `source`, `boundary`, `trace`, `obstacle`,
    /// `exact`), the rows of the points where the solve reads it (each once, ascending).
    fn evaluation_points<'py>(
        &self,
        py: Python<'py>,
        scheme: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let kind = SchemeKind::from_str(scheme).map_err(|e| crate::to_pyerr(py, &e))?;
        let mesh = Arc::clone(&self.mesh);
        let lists = guard(py, move || {
            let s = build(kind, &mesh)?;
            let m = mesh.as_ref();
            Ok([
                ("diffusion", points::diffusion_points(m)),
                ("source", points::source_points(s.as_ref())),
                ("boundary", points::boundary_points(m)),
                ("trace", points::trace_points(s.as_ref())),
                ("obstacle", points::obstacle_points(s.as_ref())),
                ("exact", points::exact_points(m)),
            ])
        })?;
        let (unique, rows) = unique_rows(py, lists.into(), |q| q.point)?;
        let m = unique.len();
        let (mut kind, mut index, mut edge) = (Vec::with_capacity(m), Vec::new(), Vec::new());
        let mut weights = Vec::with_capacity(3 * m);
        for q in &unique {
            let (c, i, e, w) = match q.site {
                Site::Vertex(v) => (0u8, v, -1, [0.0; 3]),
                Site::Edge(e) => (1, e, -1, [0.0; 3]),
                Site::Cell(k) => (2, k, -1, [0.0; 3]),
                Site::InCell {
                    cell,
                    edge,
                    weights,
                } => (3, cell, edge as i64, weights),
            };
            kind.push(c);
            index.push(i as i64);
            edge.push(e);
            weights.extend_from_slice(&w);
        }
        let d = PyDict::new(py);
        d.set_item("points", points_array(py, unique.iter().map(|q| q.point))?)?;
        d.set_item("site_kind", vec_array(py, kind))?;
        d.set_item("site_index", vec_array(py, index))?;
        d.set_item("site_edge", vec_array(py, edge))?;
        d.set_item(
            "site_weights",
            PyArray1::from_vec(py, weights).reshape([m, 3])?,
        )?;
        d.set_item("rows", rows)?;
        Ok(d)
    }

    /// Writes the mesh with named point (per vertex) and cell data to an ASCII .vtu file.
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
            write_vtu(&path, &mesh, &borrow(&pd), &borrow(&cd))
        })
    }

    /// Writes the mesh as an FVCA5 / HArDCore .typ2 file.
    fn write_typ2(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let mesh = Arc::clone(&self.mesh);
        guard(py, move || write_typ2(&path, &mesh))
    }

    fn __repr__(&self) -> String {
        format!(
            "<gradvi mesh: {} cells, {} edges, {} vertices, h = {:.4e}>",
            self.mesh.n_cells(),
            self.mesh.n_edges(),
            self.mesh.n_vertices(),
            self.mesh.h()
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMesh>()
}
