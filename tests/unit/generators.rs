//! The deterministic generators against the published FVCA5 / HArDCore2D files.
//!
//! With `../shared/meshes/fvca5` present: `hexagonal(1..=5)` against `hexa1_1..4.typ2` and
//! `converted/hexa1_5.typ2`, `kershaw(1..=6)` against `mesh4_1_1..6.typ2`: same numbers of
//! cells, vertices and edges, same h (1e-4; in fact 1e-9), same number of edges on x = 0,
//! vertex coordinates matched as sets (1e-10 hexagonal, 1e-9 Kershaw: the Kershaw files have 10
//! decimals) and cells matched as sets of vertex-coordinate polygons. Both generators also
//! reproduce the files' vertex order and cell order, which is checked too; hexagonal cells even
//! start at the same vertex. Without the directory only the counts and h are checked, against
//! constants.
//!
//! The typ2 files are read by a tiny parser local to this file, on purpose independent of the
//! crate's reader.

use crate::common::fvca5_dir;
use gradvi::budget::MemoryBudget;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{Family, hexagonal, kershaw};
use std::collections::HashMap;
use std::path::Path;

/// Minimal typ2 reader: "Vertices", count, coordinates, a header line, count, cells
/// (`n v1 … vn`, 1-based). Returns 0-based cells. Panics on malformed input (test only).
fn read_typ2(path: &Path) -> (Vec<[f64; 2]>, Vec<Vec<usize>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut tok = text.split_whitespace();
    let mut next = || {
        tok.next()
            .unwrap_or_else(|| panic!("{}: truncated", path.display()))
    };
    assert!(next().eq_ignore_ascii_case("vertices"));
    let nv: usize = next().parse().unwrap();
    let vertices: Vec<[f64; 2]> = (0..nv)
        .map(|_| [next().parse().unwrap(), next().parse().unwrap()])
        .collect();
    // header: "cells" (one word in the files used here)
    let header = next();
    assert!(
        header.eq_ignore_ascii_case("cells"),
        "unexpected header {header}"
    );
    let nc: usize = next().parse().unwrap();
    let cells = (0..nc)
        .map(|_| {
            let n: usize = next().parse().unwrap();
            (0..n)
                .map(|_| next().parse::<usize>().unwrap() - 1)
                .collect()
        })
        .collect();
    (vertices, cells)
}

/// For every vertex of `a`, the vertex of `b` within `tol` (max norm); panics unless this is a
/// bijection. Spatial hashing on a 1e-6 grid: O(n).
fn match_vertices(a: &[[f64; 2]], b: &[[f64; 2]], tol: f64) -> Vec<usize> {
    assert_eq!(a.len(), b.len(), "numbers of vertices");
    let cell = 1e-6;
    let key = |p: [f64; 2]| ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::with_capacity(b.len());
    for (i, &p) in b.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i);
    }
    let mut used = vec![false; b.len()];
    a.iter()
        .enumerate()
        .map(|(i, &p)| {
            let (kx, ky) = key(p);
            let mut found = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for &j in grid
                        .get(&(kx + dx, ky + dy))
                        .map(Vec::as_slice)
                        .unwrap_or(&[])
                    {
                        let d = (p[0] - b[j][0]).abs().max((p[1] - b[j][1]).abs());
                        if d <= tol {
                            assert!(
                                found.is_none(),
                                "vertex {i} {p:?} matches two file vertices"
                            );
                            found = Some(j);
                        }
                    }
                }
            }
            let j =
                found.unwrap_or_else(|| panic!("generated vertex {i} {p:?} is not in the file"));
            assert!(!used[j], "file vertex {j} matched twice");
            used[j] = true;
            j
        })
        .collect()
}

/// A cell as a cyclic list rotated to start at its smallest id.
fn canonical(c: &[usize]) -> Vec<usize> {
    let mut c = c.to_vec();
    let first = (0..c.len()).min_by_key(|&i| c[i]).unwrap();
    c.rotate_left(first);
    c
}

/// How much of the files' numbering the generator reproduces.
#[derive(Clone, Copy, PartialEq)]
enum Order {
    /// Same vertex order, same cell order, same starting vertex of every cell.
    Exact,
    /// Same vertex order and cell order; cells may start at another vertex.
    UpToRotation,
}

/// Compares a generated mesh with a typ2 file (see the module docs).
fn compare(mesh: &PolyMesh, file: &Path, tol: f64, order: Order) {
    let name = file.display();
    let (fv, fc) = read_typ2(file);
    let fm = PolyMesh::from_cells(fv.clone(), fc.clone()).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(mesh.n_cells(), fm.n_cells(), "{name}: cells");
    assert_eq!(mesh.n_vertices(), fm.n_vertices(), "{name}: vertices");
    assert_eq!(mesh.n_edges(), fm.n_edges(), "{name}: edges");
    assert!(
        (mesh.h() - fm.h()).abs() < 1e-4,
        "{name}: h {} vs {}",
        mesh.h(),
        fm.h()
    );
    assert!(
        (mesh.h() - fm.h()).abs() < 1e-9,
        "{name}: h {} vs {}",
        mesh.h(),
        fm.h()
    );
    assert_eq!(
        mesh.boundary_edges_on(0, 0.0),
        fm.boundary_edges_on(0, 0.0),
        "{name}: edges on x=0"
    );

    // vertices as sets
    let to_file = match_vertices(mesh.vertices(), &fv, tol);
    // cells as sets of polygons (both counter-clockwise in the files and in PolyMesh)
    let mut mesh_cells: Vec<Vec<usize>> = (0..mesh.n_cells())
        .map(|k| {
            canonical(
                &mesh
                    .cell_vertices(k)
                    .iter()
                    .map(|&v| to_file[v as usize])
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    let mut file_cells: Vec<Vec<usize>> = fc.iter().map(|c| canonical(c)).collect();
    let (mesh_in_order, file_in_order) = (mesh_cells.clone(), file_cells.clone());
    mesh_cells.sort_unstable();
    file_cells.sort_unstable();
    assert!(mesh_cells == file_cells, "{name}: the cells differ");

    // the numbering is reproduced as well
    assert!(
        to_file.iter().enumerate().all(|(i, &j)| i == j),
        "{name}: vertex order differs"
    );
    assert!(mesh_in_order == file_in_order, "{name}: cell order differs");
    if order == Order::Exact {
        for (k, c) in fc.iter().enumerate() {
            let cell: Vec<usize> = mesh.cell_vertices(k).iter().map(|&v| v as usize).collect();
            assert_eq!(cell, *c, "{name}: cell {k}");
        }
    }
}

#[test]
#[ignore = "needs ../shared/meshes/fvca5; run by `make test-external`"]
fn hexagonal_levels_1_to_5_are_the_hexa1_files() {
    let dir = fvca5_dir();
    for level in 1..=5 {
        let file = if level == 5 {
            dir.join("converted/hexa1_5.typ2")
        } else {
            dir.join(format!("hexa1_{level}.typ2"))
        };
        assert!(file.is_file(), "{} is not present", file.display());
        compare(&hexagonal(level).unwrap(), &file, 1e-10, Order::Exact);
    }
}

#[test]
#[ignore = "needs ../shared/meshes/fvca5; run by `make test-external`"]
fn kershaw_levels_1_to_6_are_the_mesh4_1_files() {
    let dir = fvca5_dir();
    for level in 1..=6 {
        let file = dir.join(format!("mesh4_1_{level}.typ2"));
        assert!(file.is_file(), "{} is not present", file.display());
        let order = if level == 1 {
            Order::Exact
        } else {
            Order::UpToRotation
        };
        compare(&kershaw(level).unwrap(), &file, 1e-9, order);
    }
}

/// Counts, h and edges on x = 0 of the published files (README of the FVCA5 directory),
/// checked without the files.
#[test]
fn counts_and_h_without_the_files() {
    // (family, level, cells, vertices, edges, h, edges on x = 0)
    let table = [
        (Family::Hexagonal, 1, 121, 280, 400, 0.2414, 20),
        (Family::Hexagonal, 2, 441, 960, 1400, 0.1297, 40),
        (Family::Hexagonal, 3, 1681, 3520, 5200, 0.0657, 80),
        (Family::Hexagonal, 4, 6561, 13440, 20000, 0.0330, 160),
        (Family::Hexagonal, 5, 25921, 52480, 78400, 0.0165, 320),
        (Family::Kershaw, 1, 289, 324, 612, 0.3288, 17),
        (Family::Kershaw, 2, 1156, 1225, 2380, 0.1666, 34),
        (Family::Kershaw, 3, 2601, 2704, 5304, 0.1116, 51),
        (Family::Cartesian, 1, 16, 25, 40, 0.3536, 4),
        (Family::Cartesian, 3, 256, 289, 544, 0.0884, 16),
    ];
    for (family, level, cells, vertices, edges, h, x0) in table {
        assert_eq!(family.cells_at_level(level), cells, "{family} {level}");
        let m = family.generate(level, MemoryBudget::DEFAULT).unwrap();
        let what = format!("{family} level {level}");
        assert_eq!(
            (m.n_cells(), m.n_vertices(), m.n_edges()),
            (cells, vertices, edges),
            "{what}"
        );
        assert!((m.h() - h).abs() < 1e-4, "{what}: h = {}", m.h());
        assert_eq!(m.boundary_edges_on(0, 0.0), x0, "{what}");
        let area: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
        assert!((area - 1.0).abs() < 1e-12, "{what}: area {area}");
    }
}

/// The levels that aborted on allocation under an 8 GB limit (issue 13) are refused at once by
/// a smaller budget, with an error giving the estimate; the estimate grows with the level and
/// the default budget lets the usual levels through.
#[test]
fn memory_budget_refuses_large_levels_up_front() {
    use gradvi::MeshError;
    for (family, level, budget) in [
        (Family::Cartesian, 11, 4u64 << 30),
        (Family::Hexagonal, 8, 512 << 20),
        (Family::Kershaw, 100, 512 << 20),
    ] {
        let estimate = family.memory_estimate(level);
        assert!(estimate > budget);
        assert!(estimate > family.memory_estimate(level - 1));
        let t0 = std::time::Instant::now();
        let e = family
            .generate(level, MemoryBudget::new(budget))
            .unwrap_err();
        assert!(
            t0.elapsed().as_secs_f64() < 1.0,
            "{family} {level}: slow refusal"
        );
        match &e {
            gradvi::Error::InvalidMesh(MeshError::TooLarge {
                bytes, budget: b, ..
            }) => {
                assert_eq!((*bytes, *b), (estimate, budget));
            }
            _ => panic!("{family} {level}: {e:?}"),
        }
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("{family} mesh of level {level}"))
                && msg.contains("more than the memory budget of"),
            "{msg}"
        );
    }
    for f in Family::ALL {
        assert!(f.memory_estimate(3) < 64 << 20, "{f}");
        assert!(f.generate(3, MemoryBudget::new(64 << 20)).is_ok());
    }
}

/// Whether a generator builds a mesh depends on the budget it is given, never on the memory
/// the machine has free: the same request passes at its estimate and fails one byte below,
/// every time, and the generators without a budget argument refuse by the fixed 8 GiB default.
#[test]
fn the_answer_of_a_generator_does_not_depend_on_the_machine() {
    use gradvi::MeshError;
    use gradvi::mesh::generate::{cartesian, cartesian_rect_within, hexagonal_grid_within};
    for f in Family::ALL {
        let estimate = f.memory_estimate(2);
        for _ in 0..2 {
            assert!(f.generate(2, MemoryBudget::new(estimate)).is_ok(), "{f}");
            assert!(
                matches!(
                    f.generate(2, MemoryBudget::new(estimate - 1)),
                    Err(gradvi::Error::InvalidMesh(MeshError::TooLarge { .. }))
                ),
                "{f}"
            );
        }
    }
    let tiny = MemoryBudget::new(1 << 10);
    assert!(cartesian_rect_within(4, 4, [0.0, 1.0], [0.0, 1.0], tiny).is_err());
    assert!(hexagonal_grid_within(2, tiny).is_err());
    // 64 M cells: under the cell cap, about 21 GiB: refused by the default budget whatever the
    // machine has, before anything is allocated
    let t0 = std::time::Instant::now();
    match cartesian(8000, 8000) {
        Err(gradvi::Error::InvalidMesh(MeshError::TooLarge { bytes, budget, .. })) => {
            assert_eq!(budget, MemoryBudget::DEFAULT.bytes());
            assert!(bytes > budget);
        }
        r => panic!("{:?}", r.map(|m| m.n_cells())),
    }
    assert!(t0.elapsed().as_secs_f64() < 1.0);
}
