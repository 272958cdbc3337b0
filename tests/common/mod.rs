//! Helpers shared by the test binaries.
#![allow(dead_code)]
use std::path::PathBuf;

/// `../shared/meshes/fvca5` next to the repository. Tests that need the original FVCA5 files
/// are `#[ignore]`d (run by `make test-external`, which CI runs with `../shared` present) and
/// fail, never skip, when the folder is missing.
pub fn fvca5_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes/fvca5");
    assert!(
        d.is_dir(),
        "{} is not present next to the repository (this test needs the FVCA5 files)",
        d.display()
    );
    d
}

use gradvi::mesh::PolyMesh;
use gradvi::problem::{BoundaryKind, Problem};
use gradvi::scheme::Tensor;

/// A uniform n×n Cartesian mesh of the unit square (independent of the crate's generators).
pub fn square_grid(n: usize) -> PolyMesh {
    rect_grid(n, n, 1.0, 1.0)
}

/// The n×n grid with every square cut into two triangles along alternating diagonals,
/// and its vertices moved by a smooth perturbation of amplitude `eps`·h (0 for none).
pub fn triangle_grid(n: usize, eps: f64) -> PolyMesh {
    let h = 1.0 / n as f64;
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 * h, j as f64 * h);
            let inner = i > 0 && i < n && j > 0 && j < n;
            let d = if inner { eps * h } else { 0.0 };
            v.push([
                x + d * (7.0 * y + 3.0 * x).sin(),
                y + d * (5.0 * x - 2.0 * y).cos(),
            ]);
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let mut c = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, cc, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                c.push(vec![a, b, cc]);
                c.push(vec![a, cc, d]);
            } else {
                c.push(vec![a, b, d]);
                c.push(vec![b, cc, d]);
            }
        }
    }
    PolyMesh::from_cells(v, c).expect("valid grid")
}

/// A uniform nx×ny Cartesian mesh of (0,lx)×(0,ly).
pub fn rect_grid(nx: usize, ny: usize, lx: f64, ly: f64) -> PolyMesh {
    let mut v = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            v.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut c = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            c.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    PolyMesh::from_cells(v, c).expect("valid grid")
}

/// The anisotropic tensor of the patch tests (and of FVCA5 test 1.1).
pub const ANISOTROPIC: Tensor = [[1.5, 0.5], [0.5, 1.5]];

/// The patch test: ū = 1 + 2x − 3y (f = 0) with A = [`ANISOTROPIC`], Dirichlet on the left and
/// bottom sides, the Neumann flux A∇ū·n on the right and top sides.
pub fn affine_problem() -> Problem {
    affine_problem_with(ANISOTROPIC)
}

/// [`affine_problem`] with the tensor `a`.
pub fn affine_problem_with(a: Tensor) -> Problem {
    let g = [2.0, -3.0];
    let flux = [
        a[0][0] * g[0] + a[0][1] * g[1],
        a[1][0] * g[0] + a[1][1] * g[1],
    ];
    Problem::new("affine", Box::new(|_| 0.0))
        .with_diffusion(Box::new(move |_| a))
        .with_boundary(|x, _| {
            if x[0] < 1e-12 || x[1] < 1e-12 {
                BoundaryKind::Dirichlet
            } else {
                BoundaryKind::Neumann
            }
        })
        .with_dirichlet(Box::new(move |x| 1.0 + g[0] * x[0] + g[1] * x[1]))
        .with_neumann(Box::new(move |x| {
            // outward normal: +x on x = 1, +y on y = 1
            if x[0] > 1.0 - 1e-12 { flux[0] } else { flux[1] }
        }))
}

/// Asserts that `v` is `u` to `rel` relative to the largest |u_i|: max_i |u_i − v_i| ≤
/// rel · max_i |u_i|.
pub fn assert_close(u: &[f64], v: &[f64], rel: f64, what: &str) {
    let scale = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = u
        .iter()
        .zip(v)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        diff <= rel * scale,
        "{what}: max difference {diff:e} (scale {scale:e})"
    );
}
