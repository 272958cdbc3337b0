//! Problem data: −div(A∇u) = f in Ω with a boundary partition Γ1 (Dirichlet), Γ2 (Neumann),
//! Γ3 (Signorini), and optionally a barrier (obstacle or Signorini), upper or lower.
//!
//! - Obstacle (paper (1.5)–(1.8)): u ≤ g in Ω (upper) or u ≥ ψ (lower); ∂Ω = Γ1.
//! - Signorini (paper (1.1)–(1.4)): on Γ3, u ≤ a, A∇u·n ≤ 0, (u − a) A∇u·n = 0 (upper), or
//!   u ≥ a, A∇u·n ≥ 0, (u − a) A∇u·n = 0 (lower).
//!
//! Neumann data is the outward flux A∇u·n. Barriers are taken piecewise constant
//! (the paper's Section 6): g_K = g(x_K) on cells, a_σ = a(x_σ) on faces (P1: nodal values).
//! The paper's three tests are built by [`paper_test1`], [`paper_test2`], [`paper_test3`].

pub mod expr;
pub mod file;

use crate::mesh::Point;
use crate::scheme::Tensor;
use std::f64::consts::PI;

/// A scalar field on Ω ⊂ ℝᴰ.
pub type ScalarFn<const D: usize = 2> = Box<dyn Fn([f64; D]) -> f64 + Send + Sync>;
/// A tensor field on Ω.
pub type TensorFn<const D: usize = 2> = Box<dyn Fn([f64; D]) -> Tensor<D> + Send + Sync>;
/// A vector field on Ω.
pub type VectorFn<const D: usize = 2> = Box<dyn Fn([f64; D]) -> [f64; D] + Send + Sync>;
/// A tensor field given by cell: A(x_K, cell tag).
pub type TaggedTensorFn<const D: usize = 2> = Box<dyn Fn([f64; D], i32) -> Tensor<D> + Send + Sync>;
/// A source given by cell: f(x, x_K, cell tag).
pub type TaggedScalarFn<const D: usize = 2> =
    Box<dyn Fn([f64; D], [f64; D], i32) -> f64 + Send + Sync>;
/// A source given by the cell's centroid: f(x, x_K) (see [`Problem::source_in_cell`]).
pub type CellScalarFn<const D: usize = 2> = Box<dyn Fn([f64; D], [f64; D]) -> f64 + Send + Sync>;
/// The boundary partition: the kind of a boundary face from its centre x_σ and its mesh tag.
pub type BoundaryFn<const D: usize = 2> = Box<dyn Fn([f64; D], i32) -> BoundaryKind + Send + Sync>;

/// The kind of boundary condition on an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BoundaryKind {
    /// Γ1: u = u_D.
    Dirichlet,
    /// Γ2: A∇u·n = g_N.
    Neumann,
    /// Γ3: the Signorini condition.
    Signorini,
}

/// Direction of a barrier: u ≤ barrier ([`Side::Upper`], the paper's form) or u ≥ barrier
/// ([`Side::Lower`]). The algorithms' type, from the algebra layer below ([`crate::vi`]), so
/// that a problem's barrier reaches them unchanged.
pub use crate::vi::Side;

/// Where a barrier acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ConstraintKind {
    /// In Ω, on the scheme's obstacle unknowns.
    Obstacle,
    /// On Γ3, on the scheme's trace unknowns.
    Signorini,
}

/// A barrier.
pub struct Constraint<const D: usize = 2> {
    /// Obstacle or Signorini.
    pub kind: ConstraintKind,
    /// Upper or lower.
    pub side: Side,
    /// The barrier function (g, ψ or a).
    pub barrier: ScalarFn<D>,
}

/// An exact solution, for error computations.
pub struct Exact<const D: usize = 2> {
    /// ū.
    pub u: ScalarFn<D>,
    /// ∇ū.
    pub grad: VectorFn<D>,
}

/// Full problem data on Ω ⊂ ℝᴰ (D = 2 unless said: points `[f64; D]`, D×D tensors). Build
/// with [`Problem::new`] and the `with_*` methods.
pub struct Problem<const D: usize = 2> {
    /// Name, used in outputs.
    pub name: String,
    /// A(x), symmetric positive definite.
    pub diffusion: TensorFn<D>,
    /// f(x).
    pub source: ScalarFn<D>,
    /// For data that are smooth by pieces (Test 2): f(x) on the piece of the cell whose
    /// centroid is x_K, called as `f(x, x_K)`. The schemes evaluate the source of cell K with
    /// it, so that a vertex on a discontinuity takes the value of the cell being assembled.
    /// `None`: `source` is used everywhere.
    pub source_in_cell: Option<CellScalarFn<D>>,
    /// For media given by subdomains: A on the cell with centroid x_K and cell tag t (its gmsh
    /// physical surface), called as `A(x_K, t)`. `None`: `diffusion` is used.
    pub diffusion_by_tag: Option<TaggedTensorFn<D>>,
    /// For sources given by subdomains: f(x) on the cell with centroid x_K and tag t, called as
    /// `f(x, x_K, t)`; takes precedence over `source_in_cell` and `source`.
    pub source_by_tag: Option<TaggedScalarFn<D>>,
    /// Boundary kind of a boundary face (an edge in 2D) from its centre x_σ and its mesh tag.
    pub boundary: BoundaryFn<D>,
    /// Dirichlet value u_D on Γ1.
    pub dirichlet: ScalarFn<D>,
    /// Neumann flux g_N = A∇u·n on Γ2.
    pub neumann: ScalarFn<D>,
    /// Optional barrier.
    pub constraint: Option<Constraint<D>>,
    /// Optional exact solution.
    pub exact: Option<Exact<D>>,
}

impl<const D: usize> Problem<D> {
    /// −Δu = f with homogeneous Dirichlet conditions on the whole boundary and no barrier.
    pub fn new(name: &str, source: ScalarFn<D>) -> Self {
        Problem {
            name: name.to_string(),
            diffusion: Box::new(|_| identity()),
            source,
            source_in_cell: None,
            diffusion_by_tag: None,
            source_by_tag: None,
            boundary: Box::new(|_, _| BoundaryKind::Dirichlet),
            dirichlet: Box::new(|_| 0.0),
            neumann: Box::new(|_| 0.0),
            constraint: None,
            exact: None,
        }
    }
    /// Sets the cell-wise source f(x, x_K) (see [`Problem::source_in_cell`]).
    pub fn with_source_in_cell(mut self, f: CellScalarFn<D>) -> Self {
        self.source_in_cell = Some(f);
        self
    }
    /// A on the cell with centroid x_K and cell tag t (see [`Problem::diffusion_by_tag`]).
    pub fn diffusion_in(&self, xk: [f64; D], tag: i32) -> Tensor<D> {
        match &self.diffusion_by_tag {
            Some(a) => a(xk, tag),
            None => (self.diffusion)(xk),
        }
    }
    /// f at x for the cell with centroid x_K and cell tag t: the most specific of
    /// [`Problem::source_by_tag`], [`Problem::source_in_cell`] and [`Problem::source`].
    pub fn source_in(&self, x: [f64; D], xk: [f64; D], tag: i32) -> f64 {
        match (&self.source_by_tag, &self.source_in_cell) {
            (Some(f), _) => f(x, xk, tag),
            (None, Some(f)) => f(x, xk),
            (None, None) => (self.source)(x),
        }
    }
    /// Sets A by cell tag (see [`Problem::diffusion_by_tag`]).
    pub fn with_diffusion_by_tag(mut self, a: TaggedTensorFn<D>) -> Self {
        self.diffusion_by_tag = Some(a);
        self
    }
    /// Sets f by cell tag (see [`Problem::source_by_tag`]).
    pub fn with_source_by_tag(mut self, f: TaggedScalarFn<D>) -> Self {
        self.source_by_tag = Some(f);
        self
    }
    /// Sets A(x).
    pub fn with_diffusion(mut self, a: TensorFn<D>) -> Self {
        self.diffusion = a;
        self
    }
    /// Sets the boundary partition.
    pub fn with_boundary(
        mut self,
        b: impl Fn([f64; D], i32) -> BoundaryKind + Send + Sync + 'static,
    ) -> Self {
        self.boundary = Box::new(b);
        self
    }
    /// Sets the Dirichlet data.
    pub fn with_dirichlet(mut self, g: ScalarFn<D>) -> Self {
        self.dirichlet = g;
        self
    }
    /// Sets the Neumann data (outward flux A∇u·n).
    pub fn with_neumann(mut self, g: ScalarFn<D>) -> Self {
        self.neumann = g;
        self
    }
    /// Sets the barrier.
    pub fn with_constraint(
        mut self,
        kind: ConstraintKind,
        side: Side,
        barrier: ScalarFn<D>,
    ) -> Self {
        self.constraint = Some(Constraint {
            kind,
            side,
            barrier,
        });
        self
    }
    /// Sets the exact solution.
    pub fn with_exact(mut self, u: ScalarFn<D>, grad: VectorFn<D>) -> Self {
        self.exact = Some(Exact { u, grad });
        self
    }
}

/// The D×D identity, the default diffusion tensor.
fn identity<const D: usize>() -> Tensor<D> {
    let mut a = [[0.0; D]; D];
    for (i, row) in a.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    a
}

/// Checks that `a` is symmetric positive definite and finite; `what` names the place.
///
/// With s = max |a_ij|: symmetric to 1e-12 s, and positive definite with det A > 1e-14 sᴰ
/// (the pivots of Gaussian elimination, without pivoting, all positive; their product is
/// det A; in 2D the determinant a₀₀a₁₁ − a₀₁a₁₀ is formed directly).
pub fn check_tensor<const D: usize>(a: &Tensor<D>, what: &str) -> crate::Result<()> {
    let finite = a.iter().flatten().all(|x| x.is_finite());
    let scale = a.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let sym = (0..D).all(|i| (0..i).all(|j| (a[i][j] - a[j][i]).abs() <= 1e-12 * scale));
    if !finite || !sym || !positive_definite(a, scale) {
        return Err(crate::Error::InvalidData(format!(
            "diffusion tensor {a:?} at {what} is not symmetric positive definite and finite"
        )));
    }
    Ok(())
}

/// The definiteness test of [`check_tensor`] on a finite symmetric tensor of scale `scale`.
fn positive_definite<const D: usize>(a: &Tensor<D>, scale: f64) -> bool {
    if D == 2 {
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        return a[0][0] > 0.0 && det > 1e-14 * scale * scale;
    }
    let mut m = *a;
    let mut det = 1.0;
    for p in 0..D {
        if !(m[p][p] > 0.0) {
            return false;
        }
        det *= m[p][p];
        let pivot_row = m[p];
        for row in m.iter_mut().skip(p + 1) {
            let l = row[p] / pivot_row[p];
            for (x, y) in row.iter_mut().zip(&pivot_row).skip(p) {
                *x -= l * y;
            }
        }
    }
    det > 1e-14 * scale.powi(D as i32)
}

/// Checks that a data value is finite; `what` names the datum and the place.
pub fn check_finite(v: f64, what: &str) -> crate::Result<f64> {
    check_finite_at(v, || what.to_string())
}

/// [`check_finite`] with the name formatted only for a non-finite value: for the checks
/// made once per unknown or per cell, where formatting every name would cost more than the
/// check.
pub fn check_finite_at(v: f64, what: impl FnOnce() -> String) -> crate::Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(crate::Error::InvalidData(format!("{} is {v}", what())))
    }
}

/// Geometric tolerance for "on the line x = c" tests of edge midpoints on the unit square.
const ON: f64 = 1e-12;

/// The boundary of the Signorini tests: Γ1 (Dirichlet) where `gamma1(x_σ)`, else Γ3
/// (Signorini) where `gamma3(x_σ)`, else Γ2 (Neumann).
fn signorini_sides(
    gamma1: fn(Point) -> bool,
    gamma3: fn(Point) -> bool,
) -> impl Fn(Point, i32) -> BoundaryKind + Send + Sync + 'static {
    move |x, _| {
        if gamma1(x) {
            BoundaryKind::Dirichlet
        } else if gamma3(x) {
            BoundaryKind::Signorini
        } else {
            BoundaryKind::Neumann
        }
    }
}

/// Test 1 of the paper (Signorini, from Yang & Chao): −Δu = 2π sin(2πx) in (0,1)²;
/// Γ1 = \[0,1\]×{1} (u = 0); Γ2 = {0,1}×\[0,1\] (∇u·n = 0); Γ3 = \[0,1\]×{0} with
/// u ≥ 0, ∇u·n ≥ 0, u∇u·n = 0 (a lower barrier 0).
pub fn paper_test1() -> Problem {
    Problem::new("test1", Box::new(|p| 2.0 * PI * (2.0 * PI * p[0]).sin()))
        .with_boundary(signorini_sides(|x| x[1] > 1.0 - ON, |x| x[1] < ON))
        .with_constraint(ConstraintKind::Signorini, Side::Lower, Box::new(|_| 0.0))
}

/// P(y) = −y(y − 1/2)² of Test 2.
fn t2_p(y: f64) -> f64 {
    -y * (y - 0.5) * (y - 0.5)
}
/// G(y) = (1 − y)(y − 1/2)² of Test 2.
fn t2_g(y: f64) -> f64 {
    (1.0 - y) * (y - 0.5) * (y - 0.5)
}

/// The exact solution ū of Test 2 (our reading; see [`paper_test2`]).
pub fn test2_exact(p: Point) -> f64 {
    let (x, y) = (p[0], p[1]);
    if y < 0.5 {
        t2_p(y) * (PI * x).cos()
    } else {
        (0.5 * PI * x).sin().powi(2) * t2_g(y)
    }
}

/// ∇ū of Test 2.
pub fn test2_exact_grad(p: Point) -> Point {
    let (x, y) = (p[0], p[1]);
    if y < 0.5 {
        let dp = -(3.0 * y * y - 2.0 * y + 0.25);
        [-PI * t2_p(y) * (PI * x).sin(), dp * (PI * x).cos()]
    } else {
        let dg = -3.0 * y * y + 4.0 * y - 1.25;
        let s = (0.5 * PI * x).sin();
        [0.5 * PI * (PI * x).sin() * t2_g(y), s * s * dg]
    }
}

/// Distance to y = 1/2 below which a point counts as *on* the interface of Test 2. Some
/// hexagonal cells (the half cells at x = 0 and x = 1) have their centroid on y = 1/2, where A
/// and f jump; without this snapping, round-off in x_K (1e-16) would decide their A_K.
pub const TEST2_INTERFACE_TOL: f64 = 1e-10;

/// Which side of y = 1/2 the data of Test 2 takes at a point; points on the interface (within
/// [`TEST2_INTERFACE_TOL`]) go to the upper side unless `tie_lower`.
fn test2_lower(y: f64, tie_lower: bool) -> bool {
    if (y - 0.5).abs() <= TEST2_INTERFACE_TOL {
        tie_lower
    } else {
        y < 0.5
    }
}

/// f = −div(A∇ū) of Test 2, derived exactly in each half (interface points: upper side).
pub fn test2_source(p: Point) -> f64 {
    test2_source_tie(p, false)
}

/// f of Test 2 with the interface convention `tie_lower`.
pub fn test2_source_tie(p: Point, tie_lower: bool) -> f64 {
    test2_source_piece(p, test2_lower(p[1], tie_lower))
}

/// f of Test 2 at `p`, from the formula of the lower (y < 1/2) or upper piece.
pub fn test2_source_piece(p: Point, lower: bool) -> f64 {
    let (x, y) = (p[0], p[1]);
    if lower {
        // −100 (P h'' + P'' h) with h = cos(πx), P'' = 2 − 6y
        100.0 * (PI * x).cos() * (PI * PI * t2_p(y) - (2.0 - 6.0 * y))
    } else {
        // −(g'' G + g G'') with g = sin²(πx/2), g'' = (π²/2) cos(πx), G'' = 4 − 6y
        let s = (0.5 * PI * x).sin();
        -(0.5 * PI * PI * (PI * x).cos() * t2_g(y) + s * s * (4.0 - 6.0 * y))
    }
}

/// A(x) of Test 2: 100·I for y < 1/2, I for y ≥ 1/2 (evaluated at x_K by the schemes; points
/// within [`TEST2_INTERFACE_TOL`] of y = 1/2 take the upper value).
pub fn test2_diffusion(p: Point) -> Tensor {
    test2_diffusion_tie(p, false)
}

/// A of Test 2 with the interface convention `tie_lower`.
pub fn test2_diffusion_tie(p: Point, tie_lower: bool) -> Tensor {
    let c = if test2_lower(p[1], tie_lower) {
        100.0
    } else {
        1.0
    };
    [[c, 0.0], [0.0, c]]
}

/// Test 2 of the paper, in our reading (the extracted text is garbled):
/// Ω = (0,1)²; A = 100·I for y < 1/2 and I for y > 1/2; Γ1 = {y = 0} ∪ {y = 1} (u = 0),
/// Γ2 = {x = 1} (A∇u·n = 0), Γ3 = {x = 0} with u ≤ 0, A∇u·n ≤ 0, u A∇u·n = 0 (upper barrier 0);
/// ū = P(y) cos(πx) for y < 1/2 with P(y) = −y(y − 1/2)², ū = sin²(πx/2)(1 − y)(y − 1/2)² for
/// y > 1/2, and f = −div(A∇ū).
pub fn paper_test2() -> Problem {
    paper_test2_tie(false)
}

/// Test 2 where data at points on the interface y = 1/2 (cell centroids of the half cells of
/// the hexagonal meshes) takes the lower values (A = 100 I) if `tie_lower`, else the upper ones.
pub fn paper_test2_tie(tie_lower: bool) -> Problem {
    Problem::new(
        if tie_lower {
            "test2-interface-lower"
        } else {
            "test2"
        },
        Box::new(move |p| test2_source_tie(p, tie_lower)),
    )
    .with_source_in_cell(Box::new(move |p, xk| {
        test2_source_piece(p, test2_lower(xk[1], tie_lower))
    }))
    .with_diffusion(Box::new(move |p| test2_diffusion_tie(p, tie_lower)))
    .with_boundary(signorini_sides(
        |x| x[1] < ON || x[1] > 1.0 - ON,
        |x| x[0] < ON,
    ))
    .with_constraint(ConstraintKind::Signorini, Side::Upper, Box::new(|_| 0.0))
    .with_exact(Box::new(test2_exact), Box::new(test2_exact_grad))
}

/// ψ(x, y) = −min(x, 1 − x, y, 1 − y) of Test 3.
pub fn test3_obstacle(p: Point) -> f64 {
    -(p[0].min(1.0 - p[0]).min(p[1]).min(1.0 - p[1]))
}

/// Test 3 of the paper (obstacle): −Δu ≥ C, u ≥ ψ, (Δu + C)(ψ − u) = 0, u = 0 on ∂Ω,
/// ψ = −min(x, 1 − x, y, 1 − y); i.e. f = C with a lower barrier ψ.
pub fn paper_test3(c: f64) -> Problem {
    Problem::new(
        &format!("test3_C{}", format_parameter(c)),
        Box::new(move |_| c),
    )
    .with_constraint(
        ConstraintKind::Obstacle,
        Side::Lower,
        Box::new(test3_obstacle),
    )
}

/// FVCA5 benchmark test 1.1: A = [[1.5, 0.5], [0.5, 1.5]], ū = 16x(1−x)y(1−y), Dirichlet
/// conditions on ∂Ω, f = −div(A∇ū); no barrier.
pub fn fvca5_test11() -> Problem {
    const A: Tensor = [[1.5, 0.5], [0.5, 1.5]];
    Problem::new(
        "fvca5-1.1",
        Box::new(|p| {
            let (x, y) = (p[0], p[1]);
            let uxx = -32.0 * y * (1.0 - y);
            let uyy = -32.0 * x * (1.0 - x);
            let uxy = 16.0 * (1.0 - 2.0 * x) * (1.0 - 2.0 * y);
            -(A[0][0] * uxx + 2.0 * A[0][1] * uxy + A[1][1] * uyy)
        }),
    )
    .with_diffusion(Box::new(|_| A))
    .with_exact(
        Box::new(|p| 16.0 * p[0] * (1.0 - p[0]) * p[1] * (1.0 - p[1])),
        Box::new(|p| {
            [
                16.0 * (1.0 - 2.0 * p[0]) * p[1] * (1.0 - p[1]),
                16.0 * p[0] * (1.0 - p[0]) * (1.0 - 2.0 * p[1]),
            ]
        }),
    )
}

/// A parameter value as it appears in a problem name: the sign kept, integers without a
/// fractional part, other values in Rust's shortest round-trip form (`-5`, `0.25`, `1e308`).
pub fn format_parameter(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x:?}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// −div(A∇ū) by central finite differences of the flux.
    fn fd_source(p: Point) -> f64 {
        let h = 1e-4;
        let flux = |q: Point, d: usize| {
            let a = test2_diffusion(p)[d][d];
            let mut qp = q;
            let mut qm = q;
            qp[d] += 0.5 * h;
            qm[d] -= 0.5 * h;
            a * (test2_exact(qp) - test2_exact(qm)) / h
        };
        let mut s = 0.0;
        for d in 0..2 {
            let mut pp = p;
            let mut pm = p;
            pp[d] += 0.5 * h;
            pm[d] -= 0.5 * h;
            s -= (flux(pp, d) - flux(pm, d)) / h;
        }
        s
    }

    #[test]
    fn test2_source_matches_finite_differences() {
        for &p in &[
            [0.3, 0.2],
            [0.7, 0.41],
            [0.1, 0.6],
            [0.85, 0.93],
            [0.5, 0.75],
        ] {
            let (a, b) = (test2_source(p), fd_source(p));
            assert!((a - b).abs() < 1e-4 * (1.0 + a.abs()), "{p:?}: {a} vs {b}");
        }
    }

    #[test]
    fn test2_exact_meets_every_condition() {
        let n = 101;
        for i in 0..n {
            let t = i as f64 / (n - 1) as f64;
            // Γ1: u = 0 on y = 0 and y = 1
            assert!(test2_exact([t, 0.0]).abs() < 1e-15);
            assert!(test2_exact([t, 1.0]).abs() < 1e-15);
            // Γ2 (x = 1): A∇u·n = A ∂_x u = 0
            assert!(test2_exact_grad([1.0, t])[0].abs() < 1e-14);
            // Γ3 (x = 0): u ≤ 0, A∇u·n = −A ∂_x u ≤ 0, u·(A∇u·n) = 0
            let u = test2_exact([0.0, t]);
            let a = test2_diffusion([0.0, t])[0][0];
            let flux = -a * test2_exact_grad([0.0, t])[0];
            assert!(u <= 0.0 && flux <= 1e-14 && (u * flux).abs() < 1e-14);
            // interface y = 1/2: continuity of ū and of A∇ū·n
            let lo = [t, 0.5 - 1e-12];
            let hi = [t, 0.5];
            assert!((test2_exact(lo) - test2_exact(hi)).abs() < 1e-12);
            let fl = 100.0 * test2_exact_grad(lo)[1];
            let fh = test2_exact_grad(hi)[1];
            assert!((fl - fh).abs() < 1e-9, "{fl} {fh}");
        }
        // gradients match finite differences of ū
        for &p in &[[0.3, 0.2], [0.6, 0.8]] {
            let h = 1e-6;
            let g = test2_exact_grad(p);
            let gx = (test2_exact([p[0] + h, p[1]]) - test2_exact([p[0] - h, p[1]])) / (2.0 * h);
            let gy = (test2_exact([p[0], p[1] + h]) - test2_exact([p[0], p[1] - h])) / (2.0 * h);
            assert!((g[0] - gx).abs() < 1e-7 && (g[1] - gy).abs() < 1e-7);
        }
    }

    #[test]
    fn tensor_check_rejects_bad_tensors() {
        assert!(check_tensor(&[[1.0, 0.0], [0.0, 1.0]], "x").is_ok());
        assert!(check_tensor(&[[1.0, 0.5], [0.0, 1.0]], "x").is_err());
        assert!(check_tensor(&[[1.0, 2.0], [2.0, 1.0]], "x").is_err());
        assert!(check_tensor(&[[f64::NAN, 0.0], [0.0, 1.0]], "x").is_err());
        let a3 = [[2.0, 0.3, 0.1], [0.3, 1.0, 0.2], [0.1, 0.2, 3.0]];
        assert!(check_tensor(&a3, "x").is_ok());
        // indefinite (a leading 2×2 minor is negative), unsymmetric, singular
        assert!(check_tensor(&[[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "x").is_err());
        assert!(check_tensor(&[[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "x").is_err());
        assert!(check_tensor(&[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "x").is_err());
    }
}
