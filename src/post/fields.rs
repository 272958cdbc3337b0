//! Values carried by unknowns, laid out on the mesh entities they live on, for output (VTU)
//! and plots: the same code serves every scheme, through
//! [`crate::scheme::GradientDiscretisation::dof_entity`].

use crate::mesh::PolyMesh;
use crate::mesh::complex::CellComplex;
use crate::scheme::{Entity, GradientDiscretisation};

/// Per-entity arrays of a field given on some unknowns: one value per vertex, per face (edge in
/// 2-D) and per cell, each present only if at least one of the unknowns lives on that kind of entity
/// (entities without an unknown get 0).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EntityFields {
    /// One value per mesh vertex.
    pub vertex: Option<Vec<f64>>,
    /// One value per mesh face (edge in 2-D).
    pub edge: Option<Vec<f64>>,
    /// One value per mesh cell.
    pub cell: Option<Vec<f64>>,
}

impl EntityFields {
    /// Spreads `value(j)` of the unknowns `dofs[j]` onto their entities.
    pub fn new<M: CellComplex<D> + ?Sized, const D: usize>(
        scheme: &dyn GradientDiscretisation<M, D>,
        dofs: impl IntoIterator<Item = usize>,
        value: impl Fn(usize) -> f64,
    ) -> Self {
        let mesh = scheme.mesh();
        let mut f = EntityFields::default();
        for (j, d) in dofs.into_iter().enumerate() {
            let (slot, n, i) = match scheme.dof_entity(d) {
                Entity::Vertex(i) => (&mut f.vertex, mesh.n_vertices(), i),
                Entity::Edge(i) => (&mut f.edge, mesh.n_faces(), i),
                Entity::Cell(i) => (&mut f.cell, mesh.n_cells(), i),
            };
            slot.get_or_insert_with(|| vec![0.0; n])[i] = value(j);
        }
        f
    }

    /// The edge field summed over the edges of each cell (edges carry no VTU data of their
    /// own on a polygonal mesh).
    pub fn edge_sums_per_cell(
        &self,
        scheme: &dyn GradientDiscretisation<PolyMesh, 2>,
    ) -> Option<Vec<f64>> {
        let mesh = scheme.mesh();
        self.edge.as_ref().map(|e| {
            (0..mesh.n_cells())
                .map(|k| mesh.cell_edges(k).iter().map(|&s| e[s as usize]).sum())
                .collect()
        })
    }
}
