//! Contact-zone metrics.
//!
//! - [`switch_point`]: on a boundary part parametrised by one coordinate s (x on Γ3 = \[0,1\]×{0}
//!   for Test 1, y on Γ3 = {0}×\[0,1\] for Test 2), the place where the active constraint
//!   switches. The constrained unknowns are sorted by s; the switch is the midpoint between the
//!   last unknown of the first run and the first of the next run (so it is known to ±h/2).
//! - [`contact_measure`]: the measure of the contact set, Σ_j m_j over active unknowns
//!   (HMM obstacle: Σ |K|; P1: lumped vertex measures).
//! - [`hausdorff`]: the Hausdorff distance between two point sets (used for free boundaries).

use crate::mesh::Point;
use crate::scheme::GradientDiscretisation;
use crate::solver::constraints::Constraints;

/// A switch along a boundary part: where it is and how many switches there are in total
/// (1 for a clean single transition).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Switch {
    /// The coordinate of the first switch (midpoint between the two unknowns around it).
    pub at: f64,
    /// Half the distance between the two unknowns around it (the resolution).
    pub half_gap: f64,
    /// Number of switches between active and inactive along the boundary part.
    pub count: usize,
    /// Whether the first run (small s) is active.
    pub starts_active: bool,
}

/// The switch point along coordinate `axis` (0: x, 1: y) of the constrained unknowns of
/// `scheme` (at their points, [`GradientDiscretisation::dof_point`]); `None` if the whole part
/// is active or the whole part is inactive.
pub fn switch_point(
    scheme: &dyn GradientDiscretisation,
    cons: &Constraints,
    active: &[bool],
    axis: usize,
) -> Option<Switch> {
    let mut pts: Vec<(f64, bool)> = cons
        .dofs
        .iter()
        .zip(active)
        .map(|(d, &a)| (scheme.dof_point(d.dof)[axis], a))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut first: Option<(f64, f64)> = None;
    let mut count = 0;
    for w in pts.windows(2) {
        if w[0].1 != w[1].1 {
            count += 1;
            if first.is_none() {
                first = Some((0.5 * (w[0].0 + w[1].0), 0.5 * (w[1].0 - w[0].0)));
            }
        }
    }
    first.map(|(at, half_gap)| Switch {
        at,
        half_gap,
        count,
        starts_active: pts[0].1,
    })
}

/// Σ_j m_j over the active constrained unknowns.
pub fn contact_measure(cons: &Constraints, active: &[bool]) -> f64 {
    cons.dofs
        .iter()
        .zip(active)
        .filter(|(_, a)| **a)
        .map(|(d, _)| d.measure)
        .sum()
}

/// The points of the discrete free boundary: midpoints between an active and an inactive
/// constrained unknown that are neighbours (`neighbours` lists pairs of constrained-unknown
/// indices).
pub fn free_boundary(
    scheme: &dyn GradientDiscretisation,
    cons: &Constraints,
    active: &[bool],
    neighbours: &[(usize, usize)],
) -> Vec<Point> {
    neighbours
        .iter()
        .filter(|(i, j)| active[*i] != active[*j])
        .map(|&(i, j)| {
            let p = scheme.dof_point(cons.dofs[i].dof);
            let q = scheme.dof_point(cons.dofs[j].dof);
            [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]
        })
        .collect()
}

/// Hausdorff distance between two non-empty point sets (O(n m); the sets are boundaries).
pub fn hausdorff(a: &[Point], b: &[Point]) -> f64 {
    let d = |p: &Point, q: &Point| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
    let one = |a: &[Point], b: &[Point]| {
        a.iter()
            .map(|p| b.iter().map(|q| d(p, q)).fold(f64::INFINITY, f64::min))
            .fold(0.0, f64::max)
    };
    if a.is_empty() || b.is_empty() {
        return f64::NAN;
    }
    one(a, b).max(one(b, a))
}

/// Neighbouring constrained unknowns (pairs of positions in `cons.dofs`, `i < j`, sorted), for
/// [`free_boundary`]. Adjacency follows the mesh entity of each unknown
/// ([`crate::scheme::GradientDiscretisation::dof_entity`]), so it is the same for every
/// scheme: cells sharing an edge, vertices joined by an edge, edges sharing a vertex.
pub fn neighbours(
    scheme: &dyn crate::scheme::GradientDiscretisation,
    cons: &Constraints,
) -> Vec<(usize, usize)> {
    use crate::scheme::Entity;
    use std::collections::HashMap;
    let mesh = scheme.mesh();
    let pos: HashMap<Entity, usize> = cons
        .dofs
        .iter()
        .enumerate()
        .map(|(j, d)| (scheme.dof_entity(d.dof), j))
        .collect();
    let mut out = Vec::new();
    let mut push = |a: Entity, b: Entity| {
        if let (Some(&i), Some(&j)) = (pos.get(&a), pos.get(&b)) {
            out.push((i.min(j), i.max(j)));
        }
    };
    let mut edges_at_vertex: Vec<Vec<usize>> = vec![Vec::new(); mesh.n_vertices()];
    for e in 0..mesh.n_edges() {
        let [k, l] = mesh.edge_cells(e);
        if l != crate::mesh::NO_CELL {
            push(Entity::Cell(k), Entity::Cell(l));
        }
        let [a, b] = mesh.edge_vertices(e);
        push(Entity::Vertex(a), Entity::Vertex(b));
        if pos.contains_key(&Entity::Edge(e)) {
            edges_at_vertex[a].push(e);
            edges_at_vertex[b].push(e);
        }
    }
    for es in &edges_at_vertex {
        for (i, &a) in es.iter().enumerate() {
            for &b in &es[i + 1..] {
                push(Entity::Edge(a), Entity::Edge(b));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switch_and_measure() {
        // P1 on a 4 × 1 strip of [0,1]²: unknowns 0..=4 at x = 0, 0.25, …, 1 on y = 0,
        // constrained in another order
        let mesh =
            crate::mesh::generate::cartesian_triangles(4, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let p1 = crate::scheme::P1::new(&mesh).unwrap();
        let cons = Constraints {
            dofs: [4, 0, 1, 2, 3]
                .iter()
                .map(|&dof| crate::vi::ConstrainedDof {
                    dof,
                    point: (),
                    measure: 0.2,
                })
                .collect(),
            barrier: vec![0.0; 5],
            side: crate::vi::Side::Lower,
        };
        // x = 1 active, 0 and 0.25 free, 0.5 and 0.75 active
        let active = [true, false, false, true, true];
        let s = switch_point(&p1, &cons, &active, 0).unwrap();
        assert!((s.at - 0.375).abs() < 1e-15 && (s.half_gap - 0.125).abs() < 1e-15);
        assert_eq!(s.count, 1);
        assert!(!s.starts_active);
        assert!((contact_measure(&cons, &active) - 0.6).abs() < 1e-15);
        assert!(switch_point(&p1, &cons, &[true; 5], 0).is_none());
        // the free boundary between neighbours: x = 0.375 (unknowns 1 and 2, positions 2, 3)
        let fb = free_boundary(&p1, &cons, &active, &[(2, 3), (3, 4)]);
        assert_eq!(fb, vec![[0.375, 0.0]]);
        let h = hausdorff(&[[0.0, 0.0], [1.0, 0.0]], &[[0.0, 0.5]]);
        assert!((h - (1.25f64).sqrt()).abs() < 1e-15);
    }
}
