//! Post-processing: discrete errors against an exact solution, convergence orders, fitted
//! slopes, contact-zone metrics, and the output of a solution on entities the mesh writers do
//! not draw (fields per entity, the boundary surface of a 3D mesh).

pub mod contact;
pub mod fields;
pub mod vtu_boundary;

use crate::mesh::complex::{CellComplex, Vector};
use crate::scheme::GradientDiscretisation;

/// Relative discrete L² errors, as in the paper's Table 2:
/// ‖u‖ is sampled at the centroids, e_u = (Σ_K |K| (Π_D u(x_K) − ū(x_K))²)^{1/2} / (Σ_K |K| ū(x_K)²)^{1/2},
/// and e_∇u likewise with the cell gradient (HMM: ∇_K u; P1: the exact gradient) against ∇ū(x_K).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Errors {
    /// Relative L² error of u at centroids.
    pub l2_u: f64,
    /// Relative L² error of the gradient.
    pub l2_grad: f64,
}

/// Computes [`Errors`] of `u` for the scheme against the exact solution. The exact solution
/// is evaluated at the centroids in parallel; the sums run in cell order, so the result does
/// not depend on the number of threads.
pub fn relative_errors<M: CellComplex<D> + ?Sized, const D: usize>(
    scheme: &dyn GradientDiscretisation<M, D>,
    u: &[f64],
    exact: &(dyn Fn(Vector<D>) -> f64 + Sync),
    exact_grad: &(dyn Fn(Vector<D>) -> Vector<D> + Sync),
) -> Errors {
    use rayon::prelude::*;
    let mesh = scheme.mesh();
    let cv = scheme.cell_values(u);
    let cg = scheme.cell_gradients(u);
    let terms: Vec<[f64; 4]> = (0..mesh.n_cells())
        .into_par_iter()
        .with_min_len(4096)
        .map(|k| {
            let x = mesh.cell_centre(k);
            let a = mesh.cell_measure(k);
            let ue = exact(x);
            let ge = exact_grad(x);
            let dg: f64 = (0..D).map(|i| (cg[k][i] - ge[i]).powi(2)).sum();
            let g2: f64 = (0..D).map(|i| ge[i] * ge[i]).sum();
            [a * (cv[k] - ue).powi(2), a * ue * ue, a * dg, a * g2]
        })
        .collect();
    drop((cv, cg));
    let (mut eu, mut nu, mut eg, mut ng) = (0.0, 0.0, 0.0, 0.0);
    for t in &terms {
        eu += t[0];
        nu += t[1];
        eg += t[2];
        ng += t[3];
    }
    Errors {
        l2_u: (eu / nu.max(f64::MIN_POSITIVE)).sqrt(),
        l2_grad: (eg / ng.max(f64::MIN_POSITIVE)).sqrt(),
    }
}

/// Order of convergence between two successive meshes: ln(e1/e2)/ln(h1/h2).
pub fn order(e1: f64, e2: f64, h1: f64, h2: f64) -> f64 {
    (e1 / e2).ln() / (h1 / h2).ln()
}

/// Least-squares slope of ln e against ln h.
pub fn fitted_slope(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = e.iter().map(|v| v.ln()).collect();
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[cfg(test)]
mod tests {
    #[test]
    fn slope_of_a_power_law() {
        let h = [0.1, 0.05, 0.025];
        let e: Vec<f64> = h.iter().map(|x: &f64| 3.0 * x.powf(1.7)).collect();
        assert!((super::fitted_slope(&h, &e) - 1.7).abs() < 1e-12);
        assert!((super::order(e[0], e[1], h[0], h[1]) - 1.7).abs() < 1e-12);
    }
}
