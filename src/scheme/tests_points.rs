//! [`GradientDiscretisation::dof_point`] of every scheme, in 2D and 3D: the point of each
//! unknown is the one its trace and obstacle unknowns carry (where the boundary data and the
//! barrier are evaluated), and the vertex, face centroid or cell centroid of its entity.

use super::{Cr, Entity, GradientDiscretisation, Hmm, P1};
use crate::budget::MemoryBudget;
use crate::mesh::SolveMesh;
use crate::mesh::generate::{cartesian_triangles, kershaw};
use crate::mesh3d::{PolyMesh3, test_meshes};

/// The checks on the scheme `s`, whose unknowns are at the points `entity_point` gives.
fn check<M: SolveMesh<D> + ?Sized, const D: usize>(
    s: &dyn GradientDiscretisation<M, D>,
    entity_point: impl Fn(Entity) -> [f64; D],
) {
    for d in 0..s.n_unknowns() {
        assert_eq!(s.dof_point(d), entity_point(s.dof_entity(d)), "unknown {d}");
    }
    let od = s.obstacle_dofs();
    assert!(!od.is_empty());
    for d in &od {
        assert_eq!(s.dof_point(d.dof), d.point, "obstacle unknown {}", d.dof);
    }
    let mesh = s.mesh();
    let mut tr = Vec::new();
    assert!(mesh.n_boundary_faces() > 0);
    for i in 0..mesh.n_boundary_faces() {
        s.face_trace_dofs(mesh.boundary_face(i), &mut tr);
        assert!(!tr.is_empty());
        for t in &tr {
            assert_eq!(s.dof_point(t.dof), t.point, "trace unknown {}", t.dof);
        }
    }
}

#[test]
fn the_point_of_an_unknown_is_that_of_its_trace_and_obstacle_entries_in_2d() {
    let tri = cartesian_triangles(5, 3, [0.0, 1.0], [-1.0, 0.5]).unwrap();
    let at = |m: &crate::mesh::PolyMesh| {
        let m = m.clone();
        move |e: Entity| match e {
            Entity::Vertex(v) => m.vertices()[v],
            Entity::Edge(f) => m.edge_midpoint(f),
            Entity::Cell(k) => m.centroid(k),
        }
    };
    check(&P1::new(&tri).unwrap(), at(&tri));
    check(&Cr::new(&tri).unwrap(), at(&tri));
    let quads = kershaw(1).unwrap();
    check(&Hmm::new(&quads), at(&quads));
}

#[test]
fn the_point_of_an_unknown_is_that_of_its_trace_and_obstacle_entries_in_3d() {
    let tets =
        PolyMesh3::from_polyhedra(test_meshes::tetrahedra(2, 5), MemoryBudget::DEFAULT).unwrap();
    let cubes = PolyMesh3::from_polyhedra(
        test_meshes::perturbed_cubes(2, 0.1, 3),
        MemoryBudget::DEFAULT,
    )
    .unwrap();
    let at = |m: &PolyMesh3| {
        let m = m.clone();
        move |e: Entity| match e {
            Entity::Vertex(v) => m.vertices()[v],
            Entity::Edge(f) => m.face_centroid(f),
            Entity::Cell(k) => m.centroid(k),
        }
    };
    check(&P1::new(&tets).unwrap(), at(&tets));
    check(&Cr::new(&tets).unwrap(), at(&tets));
    check(
        &Hmm::<PolyMesh3, 3>::with_alpha(&cubes, 1.0).unwrap(),
        at(&cubes),
    );
}
