//! # gradvi: gradient schemes for the obstacle and Signorini problems
//!
//! gradvi solves the variational inequalities of the obstacle problem and of the Signorini
//! problem for anisotropic, heterogeneous diffusion −div(A∇u) = f on generic polygonal meshes,
//! with schemes of the *gradient discretisation method* (GDM): above all the Hybrid Mimetic
//! Mixed (HMM) scheme, and conforming P1 finite elements through the same interface. It
//! reproduces Alnashri & Droniou, *Gradient schemes for the Signorini and the obstacle problems,
//! and application to hybrid mimetic mixed methods* (Section 4), see `replication/REPORT.md`.
//!
//! ## The problems
//! Obstacle (paper (1.5)–(1.8)): find u ∈ K = {v ∈ H¹₀(Ω) : v ≤ g} with
//! ∫ A∇u·∇(u − v) ≤ ∫ f (u − v) for all v ∈ K (or the lower form u ≥ ψ).
//! Signorini (paper (1.1)–(1.4)): u = 0 on Γ1, A∇u·n = 0 on Γ2, and on Γ3
//! u ≤ a, A∇u·n ≤ 0, (u − a) A∇u·n = 0.
//! The gradient scheme replaces u by u ∈ X_D and the continuous operators by (Π_D, T_D, ∇_D)
//! (paper (2.3) and (2.7)); the discrete inequality is solved by the monotony (primal–dual active
//! set) algorithm, and every solution carries a certificate.
//!
//! ## Notation
//! | symbol | meaning | in the code |
//! |---|---|---|
//! | K, M | a cell, the set of cells | `0..mesh.n_cells()` |
//! | σ, E_K | an edge (face), the edges of K | `mesh.cell_edges(k)` |
//! | \|K\| | area of K | [`mesh::PolyMesh::measure`] |
//! | x_K | centroid of K | [`mesh::PolyMesh::centroid`] |
//! | h_K, h | diameter of K, max over cells | [`mesh::PolyMesh::diameter`], [`mesh::PolyMesh::h`] |
//! | \|σ\|, x_σ | length and midpoint of σ | [`mesh::PolyMesh::edge_measure`], [`mesh::PolyMesh::edge_midpoint`] |
//! | n_{K,σ} | outward unit normal to K on σ | [`mesh::PolyMesh::cell_normal`] |
//! | d_{K,σ} | (x_σ − x_K)·n_{K,σ} > 0 | [`mesh::PolyMesh::cell_dist`] |
//! | X_D | the discrete unknowns | [`scheme::GradientDiscretisation::n_unknowns`] |
//! | Π_D u | function reconstruction (HMM: u_K on K; P1: the interpolant) | [`scheme::GradientDiscretisation::cell_values`] |
//! | ∇_D u | gradient reconstruction (HMM: ∇_K u + stabilisation on co(σ, x_K)) | [`scheme::GradientDiscretisation::local_matrix`], [`scheme::GradientDiscretisation::cell_gradients`] |
//! | T_D u | trace reconstruction (HMM: u_σ on σ; P1: the trace) | [`scheme::GradientDiscretisation::face_trace_dofs`] |
//! | ∇_K u | (1/\|K\|) Σ_σ \|σ\| (u_σ − u_K) n_{K,σ} | [`scheme::hmm`] |
//! | R_{K,σ}(u) | u_σ − u_K − ∇_K u·(x_σ − x_K) | [`scheme::hmm`] |
//! | B_K | α² diag(\|σ\| A_K n_{K,σ}·n_{K,σ} / d_{K,σ}) | [`scheme::Hmm::w_matrix`] |
//! | F_{K,σ}(u) | the HMM fluxes (paper Section 4) | [`scheme::Hmm::fluxes`] |
//! | g_K, a_σ | barriers, piecewise constant: g(x_K), a(x_σ) (paper Section 6) | [`solver::constraints::build`] |
//! | λ | multiplier: residual of the balance equation, s(b − Mu) | [`vi::active_set`], [`vi::certificate`] |
//! | NITER | number of linear solves of the monotony algorithm | [`vi::VariationalSolution::niter`] |
//!
//! ## The pipeline: mesh → scheme → assemble → solve
//! ```
//! use gradvi::mesh::generate::cartesian;
//! use gradvi::problem::paper_test3;
//! use gradvi::scheme::Hmm;
//! use gradvi::solver::{SolveOptions, solve_problem};
//!
//! let mesh = cartesian(16, 16)?;                       // flat, validated, immutable
//! let scheme = Hmm::new(&mesh);                        // emits local matrices
//! let problem = paper_test3(-20.0);                    // obstacle: u ≥ ψ, f = C
//! let sol = solve_problem(&scheme, &problem, &SolveOptions::default())?;
//! println!("NITER = {}, certificate = {:?}", sol.niter(), sol.result.certificate);
//! assert!(sol.result.certificate.check(1e-10).is_ok());
//! # Ok::<(), gradvi::Error>(())
//! ```
//!
//! To solve several problems on the same scheme (the four values of C of Test 3), build the
//! symbolic system once and share it:
//! ```
//! # use gradvi::{mesh::generate::cartesian, problem::paper_test3, scheme::Hmm};
//! use gradvi::assembly::SymbolicSystem;
//! use gradvi::solver::{SolveOptions, solve_with_symbolic};
//! use std::sync::Arc;
//! # let mesh = cartesian(16, 16)?;
//! # let scheme = Hmm::new(&mesh);
//! let symbolic = Arc::new(SymbolicSystem::new(&scheme, Default::default())?);
//! for c in [-5.0, -10.0, -15.0, -20.0] {
//!     let sol = solve_with_symbolic(symbolic.clone(), &paper_test3(c), &SolveOptions::default())?;
//!     assert!(sol.result.certificate.check(1e-10).is_ok());
//! }
//! # Ok::<(), gradvi::Error>(())
//! ```
//!
//! ## Layers
//! Each module uses only the modules above it in this list (no cycles, no back-edges; a
//! module's tests may use its own layer and those above it):
//! 1. [`units`]: byte counts for people; uses no other module.
//! 2. [`error`]: the typed errors ([`Error`], [`MeshError`]).
//! 3. [`budget`]: the caller's [`budget::MemoryBudget`], the memory estimates checked
//!    against it, the fallible allocations ([`budget::try_vec`] and the like) and the limits of
//!    the process and the machine; it uses [`units`] and [`error`]. Beside it [`offsets`]: the
//!    offsets of flat lists, stored as one stride when the lists have one length (the mesh's
//!    cells and faces, the dof map); it uses [`error`].
//! 4. [`linalg`] (sparse Cholesky with symbolic reuse, orderings; algebraic multigrid
//!    [`linalg::amg`] and conjugate gradients; it uses only [`error`] and [`budget`]) and
//!    [`vi`] (the algebraic variational-inequality algorithms over the [`vi::QuadraticEnergy`]
//!    trait: the monotony active-set method and its look-ahead on patches, projected
//!    Gauss–Seidel, exhaustive enumeration, the certificate, the direction of a barrier
//!    [`vi::Side`]; it uses [`linalg`] and no mesh, scheme or problem type). Both are pure
//!    algebra: they sit below the meshes.
//! 5. [`mesh`]: [`mesh::PolyMesh`] (flat arrays, cached geometry, validation), readers
//!    ([`mesh::io`]: gmsh 4.1/2.2, FVCA5 typ1/typ2), writers (VTU, typ2), generators
//!    ([`mesh::generate`]: Cartesian, hexagonal = FVCA5 `hexa1_k`, Kershaw = `mesh4_1_k`,
//!    triangulated Cartesian) within the caller's [`budget::MemoryBudget`], coarse meshes by
//!    agglomeration ([`mesh::agglomerate`]), and the dimension-generic cell–face complex a
//!    scheme reads ([`mesh::CellComplex`], see "Dimension" in [`mesh`]).
//!    Beside it, [`mesh3d`]: three-dimensional polyhedral meshes (it uses [`mesh`], never the
//!    other way).
//! 6. [`scheme`]: the [`scheme::GradientDiscretisation`] trait (local matrix, local load, trace
//!    and barrier unknowns, the mesh [`scheme::Entity`] of each unknown); one file per scheme:
//!    [`scheme::Hmm`], [`scheme::P1`], [`scheme::Cr`]; registered once in [`scheme::SchemeKind`];
//!    the points where each scheme evaluates the data ([`scheme::points`]).
//! 7. [`problem`]: data A, f, Γ1/Γ2/Γ3, barriers; the paper's Tests 1–3; problem files
//!    ([`problem::file`]) and their expressions ([`problem::expr`]).
//!    Above it, [`case`]: a problem file's case, its mesh read or generated from `[mesh]`.
//! 8. [`assembly`]: what depends only on the scheme, built once ([`assembly::symbolic`]: dof
//!    map, condensed pattern, symbolic factorisation, scatter maps; [`assembly::offsets`]);
//!    the values of one problem ([`assembly::values`]); the solves of one active set
//!    (static condensation [`assembly::condense`], the gathered matrix [`assembly::gather`],
//!    the solver choice [`assembly::linear`], direct or [`assembly::iterative`], the two-point
//!    cell system [`assembly::two_point`], recovery [`assembly::solve`], the residual
//!    [`assembly::residual`]); and what one solve leaves for the next, owned by the caller
//!    ([`assembly::state`]). [`assembly::DiscreteSystem`] implements [`vi::QuadraticEnergy`].
//! 9. [`solver`]: the driver: builds the constraints, decides the warm start
//!    ([`solver::warm_start`]), the look-ahead and the fallback, returns a certified
//!    [`solver::Solution`].
//! 10. [`post`]: errors, orders, fitted slopes, contact-zone metrics, fields on mesh entities.
//!
//! The applications live in the other members of the workspace, not in this library: the
//! `gradvi` command line (`cli/`: solve, mesh tools, replication of the paper, cross-check with
//! dolfinx, plots and reports) and the developer tools (`devtools/`: benchmarks, regression
//! check, fuzzer). The library depends on no CLI, plotting, report or CSV crate.
#![warn(missing_docs)]
// `!(x > y)` is used on purpose throughout: unlike `x <= y` it is true when x is NaN, so
// validation rejects NaN data.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
pub mod assembly;
pub mod budget;
pub mod case;
pub mod error;
pub mod heap;
pub mod linalg;
pub mod mesh;
pub mod mesh3d;
pub mod offsets;
pub mod post;
pub mod problem;
pub mod scheme;
pub mod solver;
pub mod units;
pub mod vi;
pub use error::{Error, MeshError, Result, SolverError};
