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

/// A uniform n×n Cartesian mesh of the unit square (independent of the crate's generators).
pub fn square_grid(n: usize) -> PolyMesh {
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            v.push([i as f64 / n as f64, j as f64 / n as f64]);
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let mut c = Vec::new();
    for j in 0..n {
        for i in 0..n {
            c.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    PolyMesh::from_cells(v, c).expect("valid grid")
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
