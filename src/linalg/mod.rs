//! Sparse symmetric positive definite solves with faer: the symbolic Cholesky factorisation
//! (fill-reducing ordering, elimination tree, supernodes) is computed once per pattern; each
//! solve only refactorises numerically.
//!
//! For an SPD matrix A (n × n, its lower triangle stored in CSC form) and a permutation P,
//!
//!   P A Pᵀ = L Lᵀ,   L lower triangular with a positive diagonal,
//!
//! and A x = b is solved by L y = P b, Lᵀ z = y, x = Pᵀ z. Which entries of L are nonzero (the
//! pattern of A plus its *fill*) depends only on the pattern of A and on P, so the analysis
//! is split as in faer:
//! - symbolic ([`SpdPattern`], in [`cholesky`]): P, the elimination tree, the pattern of L and
//!   its supernodes; built once per pattern;
//! - numeric ([`SpdPattern::factor`] → [`SpdFactor`]): the values of L, written into a
//!   [`CholeskyWork`] the caller keeps from one factorisation to the next; redone for each set
//!   of values (each active set of the VI solver);
//! - solve ([`SpdFactor::solve_in_place`]): the two triangular solves.
//!
//! P is chosen to keep the fill small ([`Ordering`], in [`ordering`]): faer's approximate
//! minimum degree (the default) or a nested dissection by breadth-first level-set separators
//! ([`nested_dissection`]), which needs no coordinates.
//!
//! For systems too large to factorise, the iterative path: the full symmetric matrix in CSR
//! form ([`CsrMatrix::from_lower_csc`], in [`csr`]), a smoothed-aggregation multigrid
//! preconditioner ([`Amg`], in [`amg`]) and preconditioned conjugate gradients ([`pcg()`], in
//! [`pcg`](mod@pcg)); memory O(nnz).
//!
//! State is explicit: a pattern, a factor's symbolic analysis and a multigrid hierarchy do not
//! change once built, and the memory a factorisation or a cycle needs is a workspace the
//! caller owns and passes `&mut` ([`CholeskyWork`], [`AmgWork`], [`Preconditioner::Work`]).
//! A workspace's contents never change a result: solves through a fresh or a used workspace
//! give the same bits.

pub mod amg;
pub mod cholesky;
pub mod csr;
pub mod ordering;
pub mod patch;
pub mod pcg;
pub(crate) mod product_workspace;
pub mod rows;

pub use amg::{Amg, AmgOptions, AmgWork, CoarseHierarchy, LevelSummary, Smoother};
pub use cholesky::{CholeskyWork, FactorThreads, SpdFactor, SpdPattern};
pub use csr::CsrMatrix;
pub use ordering::{Ordering, nested_dissection};
pub use patch::{PatchCorrected, PatchWork};
pub use pcg::{Identity, Jacobi, PcgOptions, PcgReport, Preconditioner, pcg};
pub use rows::{MaskedRows, Rows};
