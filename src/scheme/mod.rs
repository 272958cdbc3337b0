//! Gradient discretisations D = (X_D, Π_D, T_D, ∇_D) (the paper's Definitions 2.3 and 2.5).
//!
//! A scheme is one file that emits *local* quantities for a cell K: which unknowns it couples,
//! the local stiffness matrix ∫_K A_K ∇_D u·∇_D v (plus stabilisation), and the local load
//! ∫_K f Π_D v. It knows nothing about global assembly, constraints or reports.
//!
//! Unknowns are split into two kinds:
//! - *skeleton* unknowns, coupled between cells (HMM: face values u_σ; P1: vertex values),
//!   numbered `0..n_skeleton()`;
//! - *interior* unknowns, owned by one cell and eliminated by static condensation
//!   (HMM: cell values u_K; P1: none), numbered `n_skeleton()..n_unknowns()`.
//!
//! `local_dofs(k)` lists the interior unknowns of K first, then its skeleton unknowns; the local
//! matrix and load follow that order.
//!
//! P1 and Crouzeix–Raviart are both schemes on simplices (triangles in 2-D, tetrahedra in 3-D)
//! with D + 1 skeleton unknowns per cell and a gradient constant on each: what follows from that
//! (local matrix, gradients, cell values, lumped obstacle measures) is written once, for any D,
//! in `simplex.rs`, and each of the two files states only its basis gradients, its quadratures
//! and its vertex values, for triangles and for tetrahedra.

pub mod cr;
pub mod hmm;
pub mod p1;
pub mod points;
mod simplex;
#[cfg(test)]
mod tests_points;
#[cfg(test)]
mod tests_simplex3;

use crate::mesh::PolyMesh;
use crate::mesh::complex::{CellComplex, Vector};
use crate::mesh3d::PolyMesh3;
use nalgebra::{DMatrix, DVector};

pub use cr::Cr;
pub use hmm::Hmm;
pub use p1::P1;
pub use simplex::{Local, SimplexMesh};

/// A D×D diffusion tensor (row-major), symmetric positive definite; 2×2 unless said.
pub type Tensor<const D: usize = 2> = [[f64; D]; D];

/// An unknown on which a barrier acts or a boundary value is imposed: the unknown, the point
/// where data is evaluated (x_K, x_σ or a vertex) and the measure it carries (|K|, |σ|, or the
/// lumped measure of a vertex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointDof<const D: usize = 2> {
    /// Global unknown index.
    pub dof: usize,
    /// Where data (barrier, Dirichlet value) is evaluated.
    pub point: Vector<D>,
    /// Measure attached to the unknown (used to scale multipliers).
    pub measure: f64,
}

/// The mesh entity an unknown lives on (its value is attached to that vertex, face or cell, for
/// output and post-processing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum Entity {
    /// A mesh vertex.
    Vertex(usize),
    /// A mesh face: an edge in 2-D (the name of the 2-D meshes this crate reads), a polygon
    /// in 3-D.
    Edge(usize),
    /// A mesh cell.
    Cell(usize),
}

/// The interface every gradient discretisation implements. See the module docs.
///
/// A scheme is defined on a mesh type `M` of dimension `D`; both default to the planar
/// polygonal meshes of this crate (`PolyMesh`, D = 2), on which every registered scheme and
/// the outputs work. Nothing in the trait assumes D = 2: points and gradients are
/// `Vector<D>`, tensors `Tensor<D>`, and the mesh is any [`CellComplex<D>`] (cells, faces,
/// measures, centres, normals). The assembly and the solve driver take it for any mesh with
/// tags and boundary faces ([`crate::mesh::SolveMesh<D>`]): on a [`PolyMesh3`], HMM on
/// general polyhedra (`Hmm::<PolyMesh3, 3>::with_alpha`) and P1 and Crouzeix–Raviart on
/// tetrahedra (`P1::<PolyMesh3, 3>::new`, `Cr::<PolyMesh3, 3>::new`) solve 3-D problems
/// through them (`solver/tests_3d.rs`, `tests/unit/schemes3d.rs`, `tests/convergence3d.rs`).
pub trait GradientDiscretisation<M: ?Sized = PolyMesh, const D: usize = 2>: Sync
where
    M: CellComplex<D>,
{
    /// Short name ("hmm", "p1").
    fn name(&self) -> &'static str;
    /// The mesh.
    fn mesh(&self) -> &M;
    /// Number of skeleton unknowns (numbered first).
    fn n_skeleton(&self) -> usize;
    /// Number of interior (statically condensed) unknowns.
    fn n_interior(&self) -> usize;
    /// Total number of unknowns, dim X_D.
    fn n_unknowns(&self) -> usize {
        self.n_skeleton() + self.n_interior()
    }
    /// The mesh entity of unknown `dof` (HMM: faces then cells; P1: vertices).
    fn dof_entity(&self, dof: usize) -> Entity;
    /// Where unknown `dof` is a value, the point at which the data are evaluated for it: the
    /// vertex (P1), the face centroid x_σ (CR; HMM face unknowns) or the cell centroid x_K (HMM
    /// cell unknowns) — the point [`Self::face_trace_dofs`] and [`Self::obstacle_dofs`] give
    /// that unknown.
    fn dof_point(&self, dof: usize) -> Vector<D>;
    /// Number of interior unknowns of cell `k` (they come first in [`Self::local_dofs`]).
    fn n_local_interior(&self, k: usize) -> usize;
    /// The unknowns of cell `k`: interior first, then skeleton. Clears and fills `dofs`.
    fn local_dofs(&self, k: usize, dofs: &mut Vec<usize>);
    /// Local matrix of cell `k` for the constant tensor `a` = A_K, in the order of `local_dofs`.
    /// `m` is resized as needed.
    fn local_matrix(&self, k: usize, a: &Tensor<D>, m: &mut DMatrix<f64>);
    /// Local load ∫_K f Π_D v (with the scheme's quadrature), in the order of `local_dofs`.
    fn local_load(&self, k: usize, f: &dyn Fn(Vector<D>) -> f64, b: &mut DVector<f64>);
    /// The unknowns carrying the trace T_D on boundary face `e` (an edge in 2-D), with the
    /// point where boundary data is evaluated and the weight of each in ∫_σ g T_D v (the
    /// scheme's quadrature on σ, with g evaluated at x_σ). Clears and fills `out`.
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof<D>>);
    /// The unknowns on which an obstacle barrier acts (HMM: cells; P1: vertices), with their
    /// points and measures. Unknowns that turn out to be Dirichlet are removed by the caller.
    fn obstacle_dofs(&self) -> Vec<PointDof<D>>;
    /// Π_D u evaluated at the cell centroids x_K.
    fn cell_values(&self, u: &[f64]) -> Vec<f64>;
    /// A cell-wise gradient: HMM the consistent gradient ∇_K u, P1 the exact (constant) gradient.
    fn cell_gradients(&self, u: &[f64]) -> Vec<Vector<D>>;
    /// Values at the mesh vertices for plotting and VTU output (P1: the nodal values; HMM:
    /// measure-weighted averages of the adjacent cell values,
    /// [`VertexAverage`](crate::mesh::complex::VertexAverage)).
    fn vertex_values(&self, u: &[f64]) -> Vec<f64>;
}

/// The trace of the schemes with one unknown per face, numbered like the faces (HMM,
/// Crouzeix–Raviart): T_D v = v_σ on σ, so boundary face `e` carries its own unknown, at x_σ,
/// with weight |σ|.
fn face_unknown_trace<M: CellComplex<D> + ?Sized, const D: usize>(
    mesh: &M,
    e: usize,
    out: &mut Vec<PointDof<D>>,
) {
    out.clear();
    out.push(PointDof {
        dof: e,
        point: mesh.face_centre(e),
        measure: mesh.face_measure(e),
    });
}

/// Options common to the constructors of the registered schemes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SchemeOptions {
    /// HMM stabilisation parameter α (> 0); other schemes have no stabilisation and reject a
    /// value other than 1.
    pub alpha: f64,
}

impl Default for SchemeOptions {
    fn default() -> Self {
        SchemeOptions { alpha: 1.0 }
    }
}

/// Declares the registered schemes: the [`SchemeKind`] enum, its names, and [`build`]. One line
/// per scheme: its 2-D constructor, then its 3-D constructor.
macro_rules! register_schemes {
    ($($(#[$doc:meta])* $variant:ident = $name:literal => $ctor:expr, $ctor3:expr;)*) => {
        /// The registered schemes (`--scheme NAME` on the command line).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
        #[serde(rename_all = "lowercase")]
        pub enum SchemeKind {
            $($(#[$doc])* $variant,)*
        }

        impl SchemeKind {
            /// Every registered scheme, in registration order.
            pub const ALL: &'static [SchemeKind] = &[$(SchemeKind::$variant),*];
            /// The scheme's name ("hmm", "p1", …).
            pub fn name(self) -> &'static str {
                match self { $(SchemeKind::$variant => $name,)* }
            }
        }

        /// Builds the scheme of kind `kind` on `mesh` with `options` (a typed error if the mesh
        /// does not suit the scheme, e.g. P1 on a non-triangular mesh, or an option is invalid).
        pub fn build_with<'a>(
            kind: SchemeKind,
            mesh: &'a PolyMesh,
            options: &SchemeOptions,
        ) -> crate::Result<Box<dyn GradientDiscretisation + 'a>> {
            match kind {
                $(SchemeKind::$variant => {
                    let ctor: fn(&'a PolyMesh, &SchemeOptions)
                        -> crate::Result<Box<dyn GradientDiscretisation + 'a>> = $ctor;
                    ctor(mesh, options)
                })*
            }
        }

        /// Builds the scheme of kind `kind` on the 3-D mesh `mesh` with `options` (a typed
        /// error if the mesh does not suit the scheme or an option is invalid).
        pub fn build_with3<'a>(
            kind: SchemeKind,
            mesh: &'a PolyMesh3,
            options: &SchemeOptions,
        ) -> crate::Result<Box<dyn GradientDiscretisation<PolyMesh3, 3> + 'a>> {
            match kind {
                $(SchemeKind::$variant => {
                    let ctor: fn(&'a PolyMesh3, &SchemeOptions)
                        -> crate::Result<Box<dyn GradientDiscretisation<PolyMesh3, 3> + 'a>> = $ctor3;
                    ctor(mesh, options)
                })*
            }
        }
    };
}

/// Rejects a stabilisation parameter for a scheme without stabilisation.
fn no_alpha(name: &str, o: &SchemeOptions) -> crate::Result<()> {
    if o.alpha != 1.0 {
        return Err(crate::Error::InvalidData(format!(
            "the stabilisation parameter alpha = {} is an HMM option; the {name} scheme has none",
            o.alpha
        )));
    }
    Ok(())
}

register_schemes! {
    /// Hybrid Mimetic Mixed (SUSHI stabilisation).
    Hmm = "hmm" => |m, o| Ok(Box::new(Hmm::with_alpha(m, o.alpha)?)),
        |m, o| Ok(Box::new(Hmm::with_alpha(m, o.alpha)?));
    /// Conforming P1 finite elements on triangles and tetrahedra.
    P1 = "p1" => |m, o| { no_alpha("p1", o)?; Ok(Box::new(P1::new(m)?)) },
        |m, o| { no_alpha("p1", o)?; Ok(Box::new(P1::new(m)?)) };
    /// Crouzeix–Raviart (non-conforming P1) with mass lumping, on triangles and tetrahedra.
    Cr = "cr" => |m, o| { no_alpha("cr", o)?; Ok(Box::new(Cr::new(m)?)) },
        |m, o| { no_alpha("cr", o)?; Ok(Box::new(Cr::new(m)?)) };
}

impl std::str::FromStr for SchemeKind {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        let l = s.to_ascii_lowercase();
        SchemeKind::ALL
            .iter()
            .copied()
            .find(|k| k.name() == l)
            .ok_or_else(|| {
                let names: Vec<_> = SchemeKind::ALL.iter().map(|k| k.name()).collect();
                crate::Error::InvalidData(format!(
                    "unknown scheme '{s}' (expected one of: {})",
                    names.join(", ")
                ))
            })
    }
}

impl std::fmt::Display for SchemeKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Builds the scheme of kind `kind` on `mesh` with the default options.
pub fn build<'a>(
    kind: SchemeKind,
    mesh: &'a PolyMesh,
) -> crate::Result<Box<dyn GradientDiscretisation + 'a>> {
    build_with(kind, mesh, &SchemeOptions::default())
}

/// `m` as a `rows × cols` matrix of zeros, keeping its allocation when it has that shape
/// already: the local matrices are computed cell after cell into one buffer per task, and an
/// allocation per cell would serialise the threads on the allocator's lock (one malloc arena,
/// `gradvi_cli::tune_malloc`).
pub(crate) fn zeroed_matrix(m: &mut DMatrix<f64>, rows: usize, cols: usize) {
    if m.shape() == (rows, cols) {
        m.fill(0.0);
    } else {
        *m = DMatrix::zeros(rows, cols);
    }
}

/// `b` as a vector of `n` zeros, keeping its allocation when it has that length already (see
/// [`zeroed_matrix`]).
pub(crate) fn zeroed_vector(b: &mut DVector<f64>, n: usize) {
    if b.len() == n {
        b.fill(0.0);
    } else {
        *b = DVector::zeros(n);
    }
}
