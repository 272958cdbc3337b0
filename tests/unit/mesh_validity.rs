//! Mesh validity (issue 13): the corpus of minimal invalid meshes in `tests/data/invalid` is
//! rejected with typed errors naming the culprits, every good mesh (the repository's
//! `meshes/*.msh`, `tests/data/good`, the generators at several levels) still validates, and the
//! checks stay fast on inputs that made the old ones quadratic.

use gradvi::budget::MemoryBudget;
use gradvi::mesh::generate::{cartesian, cartesian_rect, hexagonal, hexagonal_grid, kershaw};
use gradvi::mesh::io::read_mesh;
use gradvi::mesh::{MAX_CELL_VERTICES, Point, PolyMesh};
use gradvi::{Error, MeshError};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn data(sub: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(sub)
}

/// What a file of the invalid corpus must give.
enum Expect {
    /// `Error::MeshIo` at this line, its message containing this text.
    Parse(usize, &'static str),
    /// `Error::InvalidMeshFile` with a matching `MeshError`, its message containing this text.
    Mesh(fn(&MeshError) -> bool, &'static str),
}

fn corpus() -> Vec<(&'static str, Expect)> {
    use Expect::*;
    vec![
        (
            "nested_squares.typ2",
            Mesh(
                |e| {
                    matches!(e, MeshError::OverlappingCells { cells_area, enclosed_area, loop_vertex: Some(4), cell: Some(0) }
                        if (cells_area - 1.25).abs() < 1e-15 && (enclosed_area - 0.75).abs() < 1e-15)
                },
                "areas add up to 1.25 but the boundary loops enclose 0.75 (the boundary loop \
                 through vertex 4 lies inside cell 0)",
            ),
        ),
        (
            "crossing_squares.typ2",
            Mesh(
                |e| {
                    matches!(
                        e,
                        MeshError::CrossingEdges {
                            edges: [[2, 3], [4, 7]],
                            cells: [0, 1]
                        }
                    )
                },
                "edges (2, 3) of cell 0 and (4, 7) of cell 1 intersect",
            ),
        ),
        (
            "msh22_overlapping_triangles.msh",
            Mesh(
                |e| matches!(e, MeshError::CrossingEdges { cells: [6, 7], .. }),
                "edges (2, 9) of cell 6 and (6, 8) of cell 7 intersect",
            ),
        ),
        (
            "pentagram.typ2",
            Mesh(
                |e| matches!(e, MeshError::SelfIntersectingCell { cell: 0, .. }),
                "cell 0 is not a simple polygon: its sides (0, 2) and (4, 1) intersect",
            ),
        ),
        (
            "octagon_wound_twice.typ2",
            Mesh(
                |e| matches!(e, MeshError::SelfIntersectingCell { cell: 0, .. }),
                "cell 0 is not a simple polygon: its sides (0, 1) and (3, 4) intersect",
            ),
        ),
        (
            "msh22_absurd_count.msh",
            Parse(9, "cannot read the tag of node 4"),
        ),
        (
            "typ2_absurd_count.typ2",
            Parse(
                8,
                "cell 1 has 1000000000000 vertices, more than the limit of 1000",
            ),
        ),
        (
            "msh22_truncated.msh",
            Parse(15, "unexpected end of file while reading y of node 7"),
        ),
        ("zeros.msh", Parse(1, "byte 0x00 is not text")),
        ("msh22_binary_nodes.msh", Parse(7, "byte 0x00 is not text")),
    ]
}

#[test]
fn invalid_corpus_is_rejected_with_typed_errors() {
    let dir = data("invalid");
    let expectations = corpus();
    crate::mesh_io::assert_corpus_is(&dir, expectations.iter().map(|(n, _)| *n));
    for (name, expect) in expectations {
        let path = dir.join(name);
        let t0 = Instant::now();
        let err = match read_mesh(&path, MemoryBudget::DEFAULT) {
            Ok(m) => panic!("{name}: accepted ({} cells)", m.n_cells()),
            Err(e) => e,
        };
        assert!(t0.elapsed().as_secs_f64() < 5.0, "{name}: slow");
        let msg = err.to_string();
        assert!(!msg.contains('\n'), "{name}: not one line: {msg}");
        match (expect, &err) {
            (
                Expect::Parse(line, text),
                Error::MeshIo {
                    path: p, line: l, ..
                },
            ) => {
                assert_eq!((p, *l), (&path, line), "{name}: {msg}");
                assert!(msg.contains(text), "{name}: {msg}");
            }
            (Expect::Mesh(pred, text), Error::InvalidMeshFile { path: p, source }) => {
                assert_eq!(p, &path, "{name}");
                assert!(pred(source), "{name}: unexpected {source:?}");
                assert!(msg.contains(text), "{name}: {msg}");
            }
            _ => panic!("{name}: unexpected error variant: {err:?}"),
        }
    }
}

fn total_area(m: &PolyMesh) -> f64 {
    (0..m.n_cells()).map(|k| m.measure(k)).sum()
}

#[test]
fn good_meshes_still_validate() {
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in [
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes"),
        data("good"),
    ] {
        for e in std::fs::read_dir(&dir).expect("mesh directory") {
            let p = e.expect("entry").path();
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ["msh", "typ1", "typ2"].contains(&ext) {
                files.push(p);
            }
        }
    }
    files.sort();
    assert!(files.len() >= 18, "{files:?}");
    for p in &files {
        let m = read_mesh(p, MemoryBudget::DEFAULT).unwrap_or_else(|e| panic!("{e}"));
        assert!(m.n_cells() > 0);
    }
    // the annulus around a hole (a clockwise loop inside the cells) with an island in the hole
    let m = read_mesh(data("good/annulus_with_island.typ2"), MemoryBudget::DEFAULT).unwrap();
    assert_eq!((m.n_cells(), m.boundary_edges().len()), (9, 20));
    assert!((total_area(&m) - 8.25).abs() < 1e-14);
}

/// The 3D gmsh meshes of `meshes/3d/` (the 3D cross-check's tetrahedra) read and validate
/// with the 3D reader, and fill their domains: (−2,2)³ for `ex9_3d_*`, (0,1)³ for
/// `signorini3d_*`.
#[test]
fn repository_3d_meshes_validate() {
    use gradvi::mesh3d::PolyMesh3;
    use gradvi::mesh3d::io::read_msh3;
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/3d");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("meshes/3d")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "msh"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 4, "{files:?}");
    for p in &files {
        let b = MemoryBudget::DEFAULT;
        let m = read_msh3(p, b)
            .and_then(|c| PolyMesh3::from_polyhedra(c, b).map_err(Into::into))
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let name = p.file_name().unwrap().to_string_lossy();
        let volume = if name.starts_with("ex9_3d") {
            64.0
        } else {
            1.0
        };
        let total: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
        assert!((total - volume).abs() < 1e-10 * volume, "{name}: {total}");
    }
}

#[test]
fn generated_meshes_validate() {
    for (nx, ny) in [(1, 1), (2, 7), (16, 16), (64, 3)] {
        assert_eq!(cartesian(nx, ny).unwrap().n_cells(), nx * ny);
    }
    let strip = cartesian_rect(40, 2, [0.0, 1.0], [0.0, 0.05]).unwrap();
    assert!((total_area(&strip) - 0.05).abs() < 1e-15);
    for level in 1..=4 {
        let m = hexagonal(level).unwrap();
        assert!((total_area(&m) - 1.0).abs() < 1e-12);
    }
    for n in [1, 2, 3, 7, 13] {
        assert!(hexagonal_grid(n).is_ok(), "hexagonal grid {n}");
    }
    for level in 1..=3 {
        let m = kershaw(level).unwrap();
        assert!((total_area(&m) - 1.0).abs() < 1e-12);
    }
}

/// A regular polygon of `m` corners on the circle of radius 1/2 centred in the unit box,
/// visited `turns` times (m and `turns` coprime), as vertices and one cell.
fn star(m: usize, turns: usize) -> (Vec<Point>, Vec<Vec<usize>>) {
    let v = (0..m)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / m as f64;
            [0.5 + 0.5 * a.cos(), 0.5 + 0.5 * a.sin()]
        })
        .collect();
    (v, vec![(0..m).map(|k| k * turns % m).collect()])
}

#[test]
fn self_intersecting_cells_are_rejected() {
    // small (pairwise test) and large (sweep) cells, winding two or three times
    for (m, turns) in [(5, 2), (7, 3), (17, 2), (101, 3), (999, 2)] {
        let (v, c) = star(m, turns);
        match PolyMesh::from_cells(v, c) {
            Err(MeshError::SelfIntersectingCell { cell: 0, sides }) => {
                assert!(sides.iter().flatten().all(|&v| v < m));
            }
            r => panic!("{m}/{turns}: {r:?}"),
        }
    }
    // simple polygons of the same sizes are fine, with h_K the largest vertex distance (convex
    // hull and rotating calipers beyond 16 vertices)
    for m in [5, 17, 101, 998, MAX_CELL_VERTICES] {
        let (v, c) = star(m, 1);
        let mut h: f64 = 0.0;
        for p in &v {
            for q in &v {
                h = h.max(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt());
            }
        }
        let mesh = PolyMesh::from_cells(v, c).unwrap();
        assert_eq!(mesh.diameter(0), h, "{m}");
    }
    // a bow-tie: zero area (as before), or not, then self-intersecting
    let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    assert!(matches!(
        PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3]]),
        Err(MeshError::DegenerateCell { cell: 0, .. })
    ));
    let v = vec![[0.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.5]];
    let e = PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3]]).unwrap_err();
    assert!(
        matches!(e, MeshError::SelfIntersectingCell { cell: 0, .. }),
        "{e}"
    );
    // a side folding back onto the previous one
    let v = vec![[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
    let e = PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3]]).unwrap_err();
    assert!(
        matches!(e, MeshError::SelfIntersectingCell { cell: 0, .. }),
        "{e}"
    );
}

#[test]
fn cells_beyond_the_vertex_limit_are_refused_at_once() {
    for m in [MAX_CELL_VERTICES + 1, 100_000, 1_000_000] {
        let (v, c) = star(m, 1);
        let t0 = Instant::now();
        let e = PolyMesh::from_cells(v, c).unwrap_err();
        assert_eq!(
            e,
            MeshError::CellTooLarge {
                cell: 0,
                n_vertices: m,
                max: MAX_CELL_VERTICES
            }
        );
        assert_eq!(
            e.to_string(),
            format!("cell 0 has {m} vertices, more than the limit of {MAX_CELL_VERTICES}")
        );
        assert!(t0.elapsed().as_secs_f64() < 2.0);
    }
}

/// A strip of `n` sliver triangles of height 1 between x = 0 and x ≈ 5·10⁻¹⁴: vertex j is at
/// y = j/n, with x values all distinct and within 10⁻¹³ of each other (the input that made the
/// old duplicate scan quadratic), and the thinnest cells that still pass the area check.
fn sliver_strip(n: usize) -> (Vec<Point>, Vec<Vec<usize>>) {
    let v = (0..n + 2)
        .map(|j| {
            [
                (j % 2) as f64 * 5e-14 + j as f64 * 1e-19,
                j as f64 / n as f64,
            ]
        })
        .collect();
    (v, (0..n).map(|j| vec![j, j + 1, j + 2]).collect())
}

#[test]
fn close_x_coordinates_stay_fast() {
    let n = 300_000;
    let (mut v, c) = sliver_strip(n);
    let t0 = Instant::now();
    let m = PolyMesh::from_cells(v.clone(), c.clone()).unwrap();
    let valid = t0.elapsed().as_secs_f64();
    assert_eq!(m.n_cells(), n);
    // one vertex moved onto another (within the tolerance 10⁻¹³ × extent)
    v[n / 2] = [v[n / 2 + 2][0] + 3e-14, v[n / 2 + 2][1] - 5e-14];
    let t0 = Instant::now();
    let e = PolyMesh::from_cells(v, c).unwrap_err();
    let invalid = t0.elapsed().as_secs_f64();
    assert!(
        matches!(e, MeshError::DuplicateVertex { a, b, .. } if (a, b) == (n / 2, n / 2 + 2)),
        "{e}"
    );
    // quadratic work would take hours; this takes a second or so even unoptimised
    assert!(valid < 60.0 && invalid < 60.0, "{valid} s, {invalid} s");
}

#[test]
fn over_long_lines_are_refused() {
    let dir = std::env::temp_dir().join(format!("gradvi_mesh_validity_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("long.typ2");
    let mut text = b"Vertices\n3\n0 0\n".to_vec();
    text.extend(std::iter::repeat_n(b'1', 2 << 20));
    std::fs::write(&path, &text).unwrap();
    let e = read_mesh(&path, MemoryBudget::DEFAULT).unwrap_err();
    assert!(
        matches!(&e, Error::MeshIo { line: 4, msg, .. } if msg.contains("longer than")),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Validation times in release mode, for the report (`cargo test --release --test unit
/// validation_times -- --ignored --nocapture`).
#[test]
#[ignore = "timing report, run in release mode by hand"]
fn validation_times() {
    let time = |what: &str, v: Vec<Point>, c: Vec<Vec<usize>>| {
        let t0 = Instant::now();
        let r = PolyMesh::from_cells(v, c);
        println!(
            "{what}: {:.3} s ({})",
            t0.elapsed().as_secs_f64(),
            match r {
                Ok(m) => format!("{} cells", m.n_cells()),
                Err(e) => e.to_string(),
            }
        );
    };
    let n = 1000;
    let v: Vec<Point> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| [i as f64 / n as f64, j as f64 / n as f64]))
        .collect();
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let c: Vec<Vec<usize>> = (0..n)
        .flat_map(|j| {
            (0..n).map(move |i| vec![id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
        })
        .collect();
    time("10^6 squares", v, c);
    let (v, c) = sliver_strip(300_000);
    time("300k slivers, x within 1e-13", v, c);
    let (v, c) = star(100_000, 1);
    time("one cell of 10^5 vertices", v, c);
    let (v, c) = star(MAX_CELL_VERTICES, 1);
    time("one cell of 1000 vertices", v, c);
    let path = Path::new("/dev/zero");
    if path.exists() {
        let t0 = Instant::now();
        let r = gradvi::mesh::io::read_msh(path, MemoryBudget::DEFAULT).map(|_| ());
        println!(
            "/dev/zero as msh: {:.3} s ({r:?})",
            t0.elapsed().as_secs_f64()
        );
    }
}
