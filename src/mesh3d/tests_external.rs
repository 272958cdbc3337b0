//! Measurements on HArDCore3D's warped meshes (`../shared/meshes/hardcore3d/Random-Hexahedra`,
//! ignored tests run by `make test-external`; they fail when the files are missing). The RF
//! files are read by a minimal token reader of the test's own, enough for these well-formed
//! files.

use super::tests_build::consistency_defect;
use super::{PolyMesh3, Polyhedra};
use crate::budget::MemoryBudget;

/// The numbers of an RF file, comment lines dropped.
fn numbers(path: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .flat_map(|l| l.split_whitespace().map(|t| t.parse::<f64>().unwrap()))
        .collect()
}

/// The mesh `NAME.node` + `NAME.ele` as a [`Polyhedra`].
fn read_rf(name: &str) -> Polyhedra {
    let node = numbers(&format!("{name}.node"));
    let nv = node[0] as usize;
    let vertices = (0..nv)
        .map(|i| [1, 2, 3].map(|c| node[4 + 4 * i + c]))
        .collect();
    let mut p = Polyhedra {
        vertices,
        ..Polyhedra::default()
    };
    let ele = numbers(&format!("{name}.ele"));
    let (nc, mut at) = (ele[0] as usize, 2);
    for _ in 0..nc {
        let nf = ele[at + 1] as usize;
        at += 2;
        let mut faces = Vec::new();
        for _ in 0..nf {
            let n = ele[at + 1] as usize;
            faces.push((0..n).map(|i| ele[at + 2 + i] as u32).collect::<Vec<u32>>());
            at += 2 + n;
        }
        p.push_cell(faces.iter().map(|f| &f[..])).unwrap();
    }
    p
}

#[test]
#[ignore = "needs ../shared/meshes/hardcore3d (make test-external)"]
fn random_hexahedra_are_accepted_and_hmm_consistent() {
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/meshes/hardcore3d/Random-Hexahedra"
    );
    for level in 1..=3 {
        let m = PolyMesh3::from_polyhedra(
            read_rf(&format!("{dir}/gcube.{level}")),
            MemoryBudget::DEFAULT,
        )
        .unwrap();
        let total: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
        assert!((total - 1.0).abs() < 1e-12);
        let warp = (0..m.n_faces()).map(|f| m.face_warp(f)).fold(0.0, f64::max);
        let defect = consistency_defect(&m);
        eprintln!(
            "gcube.{level}: {} cells, h = {:.4}, max warp {warp:.4e}, consistency defect {defect:.4e}",
            m.n_cells(),
            m.h()
        );
        // despite the family's name, the faces of these files are planar to round-off
        assert!(warp < 1e-13);
        assert!(defect < 1e-12);
    }
}
