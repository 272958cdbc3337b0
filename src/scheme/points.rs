//! Where problem data is evaluated: for a scheme on a planar mesh, the points at which the
//! solve reads each datum, each with the mesh entity it lies on.
//!
//! A caller that tabulates data before a solve (the Python bindings evaluate a vectorised
//! callable once on an array of points) asks these functions instead of rebuilding the points:
//!
//! | datum | read by | points |
//! |---|---|---|
//! | A | the local matrices, the data scale | [`diffusion_points`]: x_K |
//! | f | the scheme's local load, the data scale | [`source_points`] |
//! | boundary kind, g_N | the boundary conditions | [`boundary_points`]: x_σ on ∂Ω |
//! | u_D, Signorini barrier | the trace unknowns | [`trace_points`] |
//! | obstacle barrier | the obstacle unknowns, the feasibility check | [`obstacle_points`] |
//! | ū, ∇ū | the errors at the centroids | [`exact_points`]: x_K |
//!
//! The scheme-dependent lists come from the scheme's own methods (its local load is run with a
//! datum that records where it is called, its trace and obstacle unknowns carry their points),
//! so that they follow the scheme. Each point carries its [`Site`], which says how values given
//! per vertex, edge or cell reach it.

use super::GradientDiscretisation;
use crate::mesh::{Point, PolyMesh};
use nalgebra::DVector;
use std::cell::RefCell;

/// The mesh entity an evaluation point lies on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Site {
    /// The vertex of that index.
    Vertex(usize),
    /// The midpoint x_σ of the edge of that index.
    Edge(usize),
    /// The centroid x_K of the cell of that index.
    Cell(usize),
    /// Another point of cell `cell`, in the triangle co(σ ∪ {x_K}) of its edge σ = `edge`
    /// (e.g. Crouzeix–Raviart's x_{K,σ}), with its barycentric `weights` in that triangle with
    /// respect to x_K and the two ends of σ (in the order of
    /// [`PolyMesh::edge_vertices`]).
    InCell {
        /// The cell K.
        cell: usize,
        /// The edge σ of K.
        edge: usize,
        /// Barycentric coordinates with respect to (x_K, a, b), σ = [a, b].
        weights: [f64; 3],
    },
}

/// A point where a datum is evaluated, and the entity it lies on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EvaluationPoint {
    /// The point, bit for bit as the solve passes it to the datum.
    pub point: Point,
    /// Where it lies.
    pub site: Site,
}

/// The centroids x_K, in cell order.
fn centroids(mesh: &PolyMesh) -> Vec<EvaluationPoint> {
    (0..mesh.n_cells())
        .map(|k| EvaluationPoint {
            point: mesh.centroid(k),
            site: Site::Cell(k),
        })
        .collect()
}

/// The diffusion tensor A: A_K = A(x_K), one point per cell, in cell order (the local
/// matrices; the data scale of the certificate reads A there too).
pub fn diffusion_points(mesh: &PolyMesh) -> Vec<EvaluationPoint> {
    centroids(mesh)
}

/// The source f: cell by cell, the points at which the scheme's local load evaluates f, in the
/// order it calls f (HMM: x_K; P1: the three vertices; Crouzeix–Raviart: the centroids
/// x_{K,σ} of its three sub-triangles), then x_K of every cell (the data scale of the
/// certificate). A point shared by several cells appears once per cell.
pub fn source_points(scheme: &dyn GradientDiscretisation) -> Vec<EvaluationPoint> {
    let mesh = scheme.mesh();
    let called = RefCell::new(Vec::new());
    let mut out = Vec::new();
    let mut b = DVector::zeros(0);
    for k in 0..mesh.n_cells() {
        let record = |p: Point| {
            called.borrow_mut().push(p);
            0.0
        };
        scheme.local_load(k, &record, &mut b);
        out.extend(called.borrow_mut().drain(..).map(|p| EvaluationPoint {
            point: p,
            site: locate(mesh, k, p),
        }));
    }
    out.extend(centroids(mesh));
    out
}

/// The boundary partition (kind of each boundary edge, from its midpoint and tag) and the
/// Neumann flux g_N: x_σ of every boundary edge, in the order of
/// [`PolyMesh::boundary_edges`].
pub fn boundary_points(mesh: &PolyMesh) -> Vec<EvaluationPoint> {
    mesh.boundary_edges()
        .iter()
        .map(|&e| EvaluationPoint {
            point: mesh.edge_midpoint(e),
            site: Site::Edge(e),
        })
        .collect()
}

/// The Dirichlet value u_D and a Signorini barrier: boundary edge by boundary edge (in the
/// order of [`PolyMesh::boundary_edges`]), the points of the unknowns carrying the trace on
/// it ([`GradientDiscretisation::face_trace_dofs`]: HMM and Crouzeix–Raviart x_σ, P1 the two
/// ends of σ).
pub fn trace_points(scheme: &dyn GradientDiscretisation) -> Vec<EvaluationPoint> {
    let mesh = scheme.mesh();
    let mut tr = Vec::new();
    let mut out = Vec::new();
    for &e in mesh.boundary_edges() {
        scheme.face_trace_dofs(e, &mut tr);
        let [k, _] = mesh.edge_cells(e);
        out.extend(tr.iter().map(|t| EvaluationPoint {
            point: t.point,
            site: locate(mesh, k, t.point),
        }));
    }
    out
}

/// An obstacle barrier: the points of the obstacle unknowns
/// ([`GradientDiscretisation::obstacle_dofs`]: HMM x_K, P1 the vertices, Crouzeix–Raviart
/// x_σ), then the [`trace_points`] (the check that Dirichlet data satisfy the barrier).
pub fn obstacle_points(scheme: &dyn GradientDiscretisation) -> Vec<EvaluationPoint> {
    let mesh = scheme.mesh();
    let mut vertex_cells = None;
    let mut out: Vec<EvaluationPoint> = scheme
        .obstacle_dofs()
        .iter()
        .map(|d| EvaluationPoint {
            point: d.point,
            site: entity_site(mesh, d.point, scheme.dof_entity(d.dof), &mut vertex_cells),
        })
        .collect();
    out.extend(trace_points(scheme));
    out
}

/// The exact solution ū and its gradient ∇ū: x_K, in cell order (the errors of
/// `post::relative_errors`).
pub fn exact_points(mesh: &PolyMesh) -> Vec<EvaluationPoint> {
    centroids(mesh)
}

/// The site of the point `p` of an unknown living on `entity`: that entity when `p` is its
/// point, else where `p` lies in a cell of the entity (`vertex_cells`: the cells around each
/// vertex, [`PolyMesh::vertex_cells`], computed on first need).
fn entity_site(
    mesh: &PolyMesh,
    p: Point,
    entity: super::Entity,
    vertex_cells: &mut Option<(Vec<usize>, Vec<usize>)>,
) -> Site {
    use super::Entity;
    match entity {
        Entity::Vertex(v) if mesh.vertex(v) == p => Site::Vertex(v),
        Entity::Edge(e) if mesh.edge_midpoint(e) == p => Site::Edge(e),
        Entity::Cell(k) if mesh.centroid(k) == p => Site::Cell(k),
        Entity::Cell(k) => locate(mesh, k, p),
        Entity::Edge(e) => locate(mesh, mesh.edge_cells(e)[0], p),
        Entity::Vertex(v) => {
            let (ptr, ids) = vertex_cells.get_or_insert_with(|| mesh.vertex_cells());
            match ids[ptr[v]..ptr[v + 1]].first() {
                Some(&k) => locate(mesh, k, p),
                // a validated mesh has no vertex outside every cell
                None => Site::Vertex(v),
            }
        }
    }
}

/// Twice the signed area of the triangle (a, b, c).
fn orient(a: Point, b: Point, c: Point) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// The site of a point `p` of cell `k`: a vertex, an edge midpoint or the centroid of K when
/// `p` is that point bit for bit, else the triangle co(σ ∪ {x_K}) of K that holds it (for a
/// point on the side shared by two of them, the first in K's edge order; for a point outside
/// K, which no scheme evaluates, the triangle it is least outside of).
pub fn locate(mesh: &PolyMesh, k: usize, p: Point) -> Site {
    if let Some(&v) = mesh
        .cell_vertices(k)
        .iter()
        .find(|&&v| mesh.vertex(v as usize) == p)
    {
        return Site::Vertex(v as usize);
    }
    let edges = mesh.cell_edges(k);
    if let Some(&e) = edges.iter().find(|&&e| mesh.edge_midpoint(e as usize) == p) {
        return Site::Edge(e as usize);
    }
    let xk = mesh.centroid(k);
    if xk == p {
        return Site::Cell(k);
    }
    // the triangle of each edge, and how far inside it p is (its smallest barycentric weight)
    let mut best: Option<(f64, usize, [f64; 3])> = None;
    for &e in edges {
        let e = e as usize;
        let [a, b] = mesh.edge_vertices(e).map(|v| mesh.vertex(v));
        let area = orient(xk, a, b);
        let w = [
            orient(p, a, b) / area,
            orient(xk, p, b) / area,
            orient(xk, a, p) / area,
        ];
        let inside = w[0].min(w[1]).min(w[2]);
        if best.is_none_or(|(m, _, _)| inside > m && m < 0.0) {
            best = Some((inside, e, w));
        }
    }
    match best {
        Some((_, edge, weights)) => Site::InCell {
            cell: k,
            edge,
            weights,
        },
        None => Site::Cell(k),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::{Cr, Hmm, P1};

    /// Triangles of different shapes and sizes (not a uniform family).
    fn triangles() -> PolyMesh {
        let v = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.37, 0.61],
            [0.8, 0.3],
        ];
        let cells = vec![
            vec![0, 1, 5],
            vec![1, 2, 5],
            vec![5, 2, 4],
            vec![2, 3, 4],
            vec![3, 0, 4],
            vec![0, 5, 4],
        ];
        PolyMesh::from_cells(v, cells).unwrap()
    }

    /// Every site names an entity at its point, and in-cell weights rebuild the point.
    fn check_sites(mesh: &PolyMesh, pts: &[EvaluationPoint]) {
        for q in pts {
            let p = q.point;
            match q.site {
                Site::Vertex(v) => assert_eq!(mesh.vertex(v), p),
                Site::Edge(e) => assert_eq!(mesh.edge_midpoint(e), p),
                Site::Cell(k) => assert_eq!(mesh.centroid(k), p),
                Site::InCell {
                    cell,
                    edge,
                    weights,
                } => {
                    assert!(mesh.cell_edges(cell).contains(&(edge as u32)));
                    let [a, b] = mesh.edge_vertices(edge).map(|v| mesh.vertex(v));
                    let xk = mesh.centroid(cell);
                    assert!(weights.iter().all(|&w| w > 0.0), "{weights:?}");
                    assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-14);
                    for d in 0..2 {
                        let r = weights[0] * xk[d] + weights[1] * a[d] + weights[2] * b[d];
                        assert!((r - p[d]).abs() < 1e-14, "{r} vs {}", p[d]);
                    }
                }
            }
        }
    }

    #[test]
    fn crouzeix_raviart_sources_are_the_sub_triangle_centroids_of_each_edge() {
        let m = triangles();
        let cr = Cr::new(&m).unwrap();
        let pts = source_points(&cr);
        assert_eq!(pts.len(), 3 * m.n_cells() + m.n_cells());
        check_sites(&m, &pts);
        for k in 0..m.n_cells() {
            for i in 0..3 {
                let q = pts[3 * k + i];
                assert_eq!(q.point, cr.sub_centroid(k, i));
                let Site::InCell { cell, edge, .. } = q.site else {
                    panic!("{q:?}")
                };
                // the edge whose sub-triangle holds x_{K,σ} has the two ends it is built from
                let v = m.cell_vertices(k);
                let mut ends = m.edge_vertices(edge);
                ends.sort();
                let mut want = [v[i] as usize, v[(i + 1) % 3] as usize];
                want.sort();
                assert_eq!((cell, ends), (k, want));
            }
            assert_eq!(pts[3 * m.n_cells() + k].site, Site::Cell(k));
        }
    }

    #[test]
    fn p1_and_hmm_points_are_entities() {
        let m = triangles();
        let p1 = P1::new(&m).unwrap();
        let src = source_points(&p1);
        check_sites(&m, &src);
        for k in 0..m.n_cells() {
            for (i, &v) in m.cell_vertices(k).iter().enumerate() {
                assert_eq!(src[3 * k + i].site, Site::Vertex(v as usize));
            }
        }
        let tr = trace_points(&p1);
        assert_eq!(tr.len(), 2 * m.boundary_edges().len());
        assert!(tr.iter().all(|q| matches!(q.site, Site::Vertex(_))));
        let ob = obstacle_points(&p1);
        check_sites(&m, &ob);
        assert_eq!(ob.len(), m.n_vertices() + tr.len());

        let hex = crate::mesh::generate::Family::Hexagonal
            .generate(1, crate::budget::MemoryBudget::DEFAULT)
            .unwrap();
        let hmm = Hmm::new(&hex);
        let src = source_points(&hmm);
        assert_eq!(src.len(), 2 * hex.n_cells());
        assert!(src.iter().all(|q| matches!(q.site, Site::Cell(_))));
        let ob = obstacle_points(&hmm);
        check_sites(&hex, &ob);
        assert_eq!(ob[..hex.n_cells()], diffusion_points(&hex)[..]);
        let tr = trace_points(&hmm);
        check_sites(&hex, &tr);
        assert_eq!(tr, boundary_points(&hex));
        assert_eq!(exact_points(&hex), diffusion_points(&hex));
    }

    #[test]
    fn an_unknown_evaluated_off_its_entity_is_located_in_a_cell_of_it() {
        use crate::scheme::Entity;
        let m = triangles();
        let mut vc = None;
        // a point of cell 2 = (5, 2, 4) near its vertex 4, the first cell around vertex 4
        let [a, b, c] = [5, 2, 4].map(|v| m.vertex(v));
        let p = [
            0.01 * a[0] + 0.01 * b[0] + 0.98 * c[0],
            0.01 * a[1] + 0.01 * b[1] + 0.98 * c[1],
        ];
        for entity in [Entity::Vertex(4), Entity::Cell(2)] {
            let site = entity_site(&m, p, entity, &mut vc);
            assert!(matches!(site, Site::InCell { cell: 2, .. }), "{site:?}");
            check_sites(&m, &[EvaluationPoint { point: p, site }]);
        }
        assert_eq!(
            entity_site(&m, m.vertex(4), Entity::Vertex(4), &mut vc),
            Site::Vertex(4)
        );
        let e = m.cell_edges(2)[1] as usize;
        assert_eq!(
            entity_site(&m, m.edge_midpoint(e), Entity::Edge(e), &mut vc),
            Site::Edge(e)
        );
    }

    #[test]
    fn a_point_is_located_in_the_triangle_of_its_edge() {
        let m = triangles();
        for k in 0..m.n_cells() {
            let xk = m.centroid(k);
            for &e in m.cell_edges(k) {
                let mid = m.edge_midpoint(e as usize);
                // a point between x_K and x_σ lies in the triangle of σ
                let p = [0.5 * (xk[0] + mid[0]), 0.5 * (xk[1] + mid[1])];
                match locate(&m, k, p) {
                    Site::InCell { cell, edge, .. } => assert_eq!((cell, edge), (k, e as usize)),
                    s => panic!("{s:?}"),
                }
            }
        }
    }
}
