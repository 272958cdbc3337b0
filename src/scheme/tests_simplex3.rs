//! The local operators of P1 and Crouzeix–Raviart on tetrahedra: symmetric semidefinite local
//! matrices with the constants as kernel, affine functions reproduced (gradients, values at
//! the centroids and vertices, energies), loads exact for affine sources, lumped measures
//! that tile Ω, traces, and the refusal of other cells.

use super::{Cr, Entity, GradientDiscretisation, P1, PointDof, Tensor};
use crate::budget::MemoryBudget;
use crate::mesh3d::{Point3, PolyMesh3, Polyhedra, test_meshes};
use nalgebra::{DMatrix, DVector};

const A: Tensor<3> = [[2.0, 0.3, 0.1], [0.3, 1.0, 0.2], [0.1, 0.2, 1.5]];
const GRAD: Point3 = [0.7, -1.9, 0.4];

fn affine(x: Point3) -> f64 {
    0.4 + GRAD[0] * x[0] + GRAD[1] * x[1] + GRAD[2] * x[2]
}

/// 2³ cubes cut into Kuhn tetrahedra (faces listed in scrambled orientations), the interior
/// vertex moved so that the tetrahedra have different shapes.
fn tets() -> PolyMesh3 {
    let mut p: Polyhedra = test_meshes::tetrahedra(2, 11);
    for v in &mut p.vertices {
        if *v == [0.5, 0.5, 0.5] {
            *v = [0.43, 0.57, 0.52];
        }
    }
    PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap()
}

/// The point of unknown `d`: a vertex or a face centroid.
fn point(m: &PolyMesh3, e: Entity) -> Point3 {
    match e {
        Entity::Vertex(v) => m.vertices()[v],
        Entity::Edge(f) => m.face_centroid(f),
        Entity::Cell(k) => panic!("no cell unknown in a simplex scheme ({k})"),
    }
}

/// The checks shared by both schemes on `m`.
fn check_local_operators(s: &dyn GradientDiscretisation<PolyMesh3, 3>) {
    let m = s.mesh();
    let u: Vec<f64> = (0..s.n_unknowns())
        .map(|d| affine(point(m, s.dof_entity(d))))
        .collect();
    let (cg, cv) = (s.cell_gradients(&u), s.cell_values(&u));
    let (mut mat, mut dofs) = (DMatrix::zeros(0, 0), Vec::new());
    for k in 0..m.n_cells() {
        s.local_dofs(k, &mut dofs);
        s.local_matrix(k, &A, &mut mat);
        assert_eq!((dofs.len(), mat.shape()), (4, (4, 4)));
        let scale = mat.amax();
        assert!((&mat - mat.transpose()).amax() < 1e-14 * scale);
        assert!((&mat * DVector::from_element(4, 1.0)).amax() < 1e-13 * scale);
        let mut e: Vec<f64> = mat.symmetric_eigenvalues().iter().cloned().collect();
        e.sort_by(f64::total_cmp);
        assert!(e[0].abs() < 1e-13 * scale && e[1] > 1e-3 * scale, "{e:?}");
        for c in 0..3 {
            assert!(
                (cg[k][c] - GRAD[c]).abs() < 1e-12,
                "{}: {:?}",
                s.name(),
                cg[k]
            );
        }
        assert!((cv[k] - affine(m.centroid(k))).abs() < 1e-13);
        let ul = DVector::from_iterator(4, dofs.iter().map(|&d| u[d]));
        let energy = ul.dot(&(&mat * &ul));
        let ag: Vec<f64> = (0..3)
            .map(|r| (0..3).map(|c| A[r][c] * GRAD[c]).sum())
            .collect();
        let exact = m.measure(k) * (0..3).map(|r| ag[r] * GRAD[r]).sum::<f64>();
        assert!((energy - exact).abs() < 1e-12 * exact);
        // loads: ∫_K f = |K| f(x_K) for an affine f, |K|/4 each for a constant one
        let mut b = DVector::zeros(0);
        s.local_load(k, &affine, &mut b);
        assert!((b.sum() - m.measure(k) * affine(m.centroid(k))).abs() < 1e-14);
        s.local_load(k, &|_| 1.0, &mut b);
        assert!((&b - DVector::from_element(4, m.measure(k) / 4.0)).amax() < 1e-16);
    }
    for (v, uv) in s.vertex_values(&u).iter().enumerate() {
        assert!((uv - affine(m.vertices()[v])).abs() < 1e-12, "vertex {v}");
    }
    // the lumped measures tile Ω
    let od = s.obstacle_dofs();
    assert_eq!(od.len(), s.n_unknowns());
    let total: f64 = od.iter().map(|d| d.measure).sum();
    assert!((total - 1.0).abs() < 1e-14, "{total}");
    for d in &od {
        assert_eq!(d.point, point(m, s.dof_entity(d.dof)));
    }
}

#[test]
fn p1_on_tetrahedra_reproduces_affine_functions() {
    let m = tets();
    let s = P1::new(&m).unwrap();
    assert_eq!((s.n_skeleton(), s.n_interior()), (m.n_vertices(), 0));
    check_local_operators(&s);
    // the trace of a boundary face: its three vertices with a third of |σ| each
    let f = m.boundary_faces()[0] as usize;
    let mut tr = Vec::new();
    s.face_trace_dofs(f, &mut tr);
    assert_eq!(tr.len(), 3);
    for (t, &v) in tr.iter().zip(m.face_vertices(f)) {
        let v = v as usize;
        assert_eq!((t.dof, t.point), (v, m.vertices()[v]));
        assert!((t.measure - m.face_measure(f) / 3.0).abs() < 1e-16);
    }
}

#[test]
fn cr_on_tetrahedra_reproduces_affine_functions_with_lumped_faces() {
    let m = tets();
    let s = Cr::new(&m).unwrap();
    assert_eq!((s.n_skeleton(), s.n_interior()), (m.n_faces(), 0));
    check_local_operators(&s);
    // the load of each face is |K|/4 f at the centroid of its pyramid, exact for affine f
    let mut b = DVector::zeros(0);
    for k in 0..m.n_cells() {
        s.local_load(k, &affine, &mut b);
        for (i, &f) in m.cell_faces(k).iter().enumerate() {
            // ∫ over the pyramid co(σ ∪ {x_K}) of an affine f: its volume |K|/4 times the
            // mean of f at its four corners
            let corners = m.face_vertices(f as usize).iter();
            let sum = corners.fold(affine(m.centroid(k)), |a, &v| {
                a + affine(m.vertices()[v as usize])
            });
            let exact = m.measure(k) / 4.0 * sum / 4.0;
            assert!(
                (b[i] - exact).abs() < 1e-15,
                "{k}, {i}: {} vs {exact}",
                b[i]
            );
            assert!((affine(s.sub_centroid(k, i)) - sum / 4.0).abs() < 1e-14);
        }
    }
    // a face carries a quarter of each of its cells
    for d in s.obstacle_dofs() {
        let [k, l] = m.face_cells(d.dof);
        let expect = if m.is_boundary_face(d.dof) {
            m.measure(k) / 4.0
        } else {
            (m.measure(k) + m.measure(l)) / 4.0
        };
        assert!((d.measure - expect).abs() < 1e-16);
    }
    let f = m.boundary_faces()[0] as usize;
    let mut tr = Vec::new();
    s.face_trace_dofs(f, &mut tr);
    let expect = PointDof {
        dof: f,
        point: m.face_centroid(f),
        measure: m.face_measure(f),
    };
    assert_eq!(tr, vec![expect]);
}

#[test]
fn cells_that_are_not_tetrahedra_are_refused_by_index() {
    let cubes = PolyMesh3::from_polyhedra(test_meshes::cubes(2, 1), MemoryBudget::DEFAULT).unwrap();
    // a tetrahedron glued on a side of a square pyramid
    let mut p = Polyhedra {
        vertices: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, 1.0],
            [0.5, -1.0, 0.3],
        ],
        ..Polyhedra::default()
    };
    p.push_cell([&[0, 1, 4][..], &[0, 1, 5], &[1, 4, 5], &[0, 4, 5]])
        .unwrap();
    p.push_cell([
        &[0, 1, 2, 3][..],
        &[0, 1, 4],
        &[1, 2, 4],
        &[2, 3, 4],
        &[3, 0, 4],
    ])
    .unwrap();
    let mixed = PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap();
    for (m, what) in [
        (&cubes, "cell 0 is not a tetrahedron (6 faces, 8 vertices)"),
        (&mixed, "cell 1 is not a tetrahedron (5 faces, 5 vertices)"),
    ] {
        for e in [
            P1::new(m).map(|_| ()).unwrap_err(),
            Cr::new(m).map(|_| ()).unwrap_err(),
        ] {
            assert!(
                matches!(&e, crate::Error::InvalidData(msg) if msg.contains(what)),
                "{e}"
            );
        }
    }
}

/// The local matrices and loads are written into reused buffers (one allocation per task, not
/// per cell): a buffer holding another cell's values, or of another size, gives exactly the
/// values of a fresh one, for P1, CR and HMM.
#[test]
fn local_operators_into_reused_buffers_equal_fresh_ones() {
    let m = tets();
    let hmm = super::Hmm::<PolyMesh3, 3>::with_alpha(&m, 1.0).unwrap();
    let (p1, cr) = (P1::new(&m).unwrap(), Cr::new(&m).unwrap());
    let schemes: [&dyn GradientDiscretisation<PolyMesh3, 3>; 3] = [&p1, &cr, &hmm];
    for s in schemes {
        let f = |x: Point3| 1.0 + x[0] - 2.0 * x[2];
        let (mut m_used, mut b_used) = (DMatrix::from_element(9, 2, 7.0), DVector::zeros(1));
        for k in 0..m.n_cells() {
            let (mut m_new, mut b_new) = (DMatrix::zeros(0, 0), DVector::zeros(0));
            s.local_matrix(k, &A, &mut m_new);
            s.local_load(k, &f, &mut b_new);
            s.local_matrix(k, &A, &mut m_used);
            s.local_load(k, &f, &mut b_used);
            assert_eq!(m_used, m_new, "{} cell {k}", s.name());
            assert_eq!(b_used, b_new, "{} cell {k}", s.name());
            // dirty the buffers for the next cell
            m_used.fill(f64::NAN);
            b_used.fill(-3.0);
        }
    }
}
