//! `gradvi mesh` on 3D meshes: statistics of gmsh, RF and VTU files, the generated families
//! written as VTU and read back, conversion, and the refusals.

use std::path::PathBuf;
use std::process::Command;

/// The repository, where the commands run: the workspace root, above this package.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// Runs `gradvi args` in the repository: (exit code, stdout, stderr).
fn gradvi(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_gradvi"))
        .args(args)
        .current_dir(ROOT)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run gradvi");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("gradvi-mesh3d-{}-{name}", std::process::id()))
}

/// The value printed after `key` on its line of `gradvi mesh info`.
fn field<'a>(out: &'a str, key: &str) -> &'a str {
    out.lines()
        .find_map(|l| l.strip_prefix(key))
        .unwrap_or_else(|| panic!("no {key:?} in {out}"))
        .trim()
}

#[test]
fn info_prints_the_counts_volume_and_tags_of_3d_files() {
    // five tetrahedra of the unit cube (gmsh 2.2), two tagged bottom triangles
    let (code, out, err) = gradvi(&["mesh", "info", "tests/data/mesh3d/cube5_22.msh"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(field(&out, "dimension"), "3");
    assert_eq!(field(&out, "cells"), "5");
    assert_eq!(field(&out, "vertices"), "8");
    assert_eq!(field(&out, "faces"), "16 (12 on the boundary)");
    assert_eq!(field(&out, "total volume"), "1.000000000000");
    assert_eq!(field(&out, "h (max diam.)"), "1.414214");
    assert_eq!(field(&out, "bounding box"), "[0, 1] x [0, 1] x [0, 1]");
    assert_eq!(field(&out, "cells by faces"), "4:5");
    assert_eq!(field(&out, "cell tags"), "tag 1: 4, tag 2: 1");
    assert_eq!(field(&out, "boundary faces"), "tag 0: 10, tag 10: 2");
    // gmsh 4.1: a prism of volume 1.5, the RF pair by its stem and by its .ele
    let (code, out, err) = gradvi(&["mesh", "info", "tests/data/mesh3d/prism_22.msh"]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(field(&out, "total volume"), "1.500000000000");
    assert_eq!(field(&out, "cells by faces"), "5:1");
    for rf in ["two_cells", "two_cells.ele", "two_cells.node"] {
        let (code, out, err) = gradvi(&["mesh", "info", &format!("tests/data/mesh3d/{rf}")]);
        assert_eq!(code, Some(0), "{rf}: {err}");
        assert_eq!(field(&out, "cells by faces"), "6:1 7:1", "{rf}");
        assert_eq!(field(&out, "faces"), "12 (11 on the boundary)", "{rf}");
        assert_eq!(field(&out, "total volume"), "2.000000000000", "{rf}");
    }
    // a 2D gmsh file is still read as 2D
    let (code, out, _) = gradvi(&["mesh", "info", "meshes/test3_1.msh"]);
    assert_eq!(code, Some(0));
    assert_eq!(field(&out, "total area"), "1.000000000000");
    assert!(!out.contains("dimension"), "{out}");
}

#[test]
fn every_3d_family_is_generated_as_vtu_and_read_back() {
    // cells at level 1 (4³ cubes) and the faces per cell
    for (family, cells, by_faces) in [
        ("cubes", "64", "6:64"),
        ("kuhn", "384", "4:384"),
        ("tetrahedra", "384", "4:384"),
        ("prisms", "128", "5:128"),
        ("refined", "288", "6:256 15:4 18:12 21:12 24:4"),
        ("warped", "64", "6:64"),
    ] {
        let path = tmp(&format!("{family}.vtu"));
        let p = path.to_str().unwrap();
        let (code, _, err) = gradvi(&["mesh", "generate", family, "--level", "1", "-o", p]);
        assert_eq!(code, Some(0), "{family}: {err}");
        let (code, out, err) = gradvi(&["mesh", "info", p]);
        assert_eq!(code, Some(0), "{family}: {err}");
        assert_eq!(field(&out, "cells"), cells, "{family}");
        assert_eq!(field(&out, "cells by faces"), by_faces, "{family}");
        let volume: f64 = field(&out, "total volume").parse().unwrap();
        assert!((volume - 1.0).abs() < 1e-12, "{family}: {volume}");
        let warp: f64 = field(&out, "max face warp").parse().unwrap();
        assert_eq!(warp > 1e-6, family == "warped", "{family}: warp {warp}");
        std::fs::remove_file(path).ok();
    }
}

#[test]
fn warped_faces_are_split_on_request() {
    // level 1 of the warped family: 240 faces, the 144 interior ones warped; split, each
    // becomes 4 triangles around a new vertex (15 to 24 faces per cell), the volume unchanged
    let path = tmp("warped-fan.vtu");
    let p = path.to_str().unwrap();
    let (code, _, err) = gradvi(&["mesh", "generate", "warped", "--level", "1", "-o", p]);
    assert_eq!(code, Some(0), "{err}");
    let (_, fan, _) = gradvi(&["mesh", "info", p]);
    assert_eq!(field(&fan, "faces"), "240 (96 on the boundary)");
    let split_path = tmp("warped-split.vtu");
    let q = split_path.to_str().unwrap();
    for args in [
        vec!["mesh", "info", p, "--warped-faces", "split"],
        vec!["mesh", "convert", p, q, "--warped-faces", "split"],
        vec!["mesh", "info", q],
    ] {
        let (code, out, err) = gradvi(&args);
        assert_eq!(code, Some(0), "{args:?}: {err}");
        if args[1] == "info" {
            assert_eq!(field(&out, "faces"), "672 (96 on the boundary)", "{args:?}");
            assert_eq!(field(&out, "vertices"), (125 + 144).to_string());
            assert_eq!(field(&out, "cells by faces"), "15:8 18:24 21:24 24:8");
            assert_eq!(field(&out, "total volume"), field(&fan, "total volume"));
            let warp: f64 = field(&out, "max face warp").parse().unwrap();
            assert!(warp < 1e-12, "{args:?}: warp {warp}");
        }
    }
    let (code, _, err) = gradvi(&["mesh", "info", p, "--warped-faces", "planar"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("[possible values: fan, split]"), "{err}");
    std::fs::remove_file(path).ok();
    std::fs::remove_file(split_path).ok();
}

#[test]
fn generate_on_a_domain_and_convert_to_vtu() {
    let path = tmp("box.vtu");
    let p = path.to_str().unwrap();
    let args = [
        "--level", "1", "--domain", "-1", "1", "0", "3", "0", "0.5", "-o", p,
    ];
    let (code, _, err) = gradvi(&[&["mesh", "generate", "prisms"][..], &args].concat());
    assert_eq!(code, Some(0), "{err}");
    let (_, out, _) = gradvi(&["mesh", "info", p]);
    assert_eq!(field(&out, "bounding box"), "[-1, 1] x [0, 3] x [0, 0.5]");
    assert_eq!(field(&out, "total volume"), "3.000000000000");
    // gmsh → VTU keeps the cells, volume and tags
    let (code, _, err) = gradvi(&["mesh", "convert", "tests/data/mesh3d/cube6_41.msh", p]);
    assert_eq!(code, Some(0), "{err}");
    let (_, direct, _) = gradvi(&["mesh", "info", "tests/data/mesh3d/cube6_41.msh"]);
    let (_, converted, _) = gradvi(&["mesh", "info", p]);
    for key in [
        "cells",
        "faces",
        "total volume",
        "cells by faces",
        "cell tags",
        "boundary faces",
    ] {
        assert_eq!(field(&direct, key), field(&converted, key), "{key}");
    }
    // never over its input
    let (code, _, err) = gradvi(&["mesh", "convert", p, p]);
    assert_eq!(code, Some(1));
    assert!(err.contains("would be overwritten"), "{err}");
    assert!(std::fs::metadata(&path).unwrap().len() > 0);
    std::fs::remove_file(path).ok();
}

#[test]
fn bad_families_levels_domains_and_outputs_are_refused() {
    let vtu = tmp("refused.vtu");
    let v = vtu.to_str().unwrap();
    let typ2 = tmp("refused.typ2");
    let t = typ2.to_str().unwrap();
    for (args, message) in [
        (
            vec!["cubes", "--level", "0", "-o", v],
            "levels go from 1 to 7",
        ),
        (
            vec!["kuhn", "--level", "7", "-o", v],
            "levels go from 1 to 6",
        ),
        (
            vec!["spheres", "--level", "1", "-o", v],
            "unknown mesh family",
        ),
        (
            vec!["cubes", "--level", "1", "-o", t],
            ".typ2 is a 2D format",
        ),
        (vec!["cubes", "--level", "1", "-o", "x.msh"], "use .vtu"),
        (
            vec![
                "warped", "--level", "1", "--domain", "0", "1", "0", "1", "-o", v,
            ],
            "needs 6 bounds",
        ),
        (
            vec![
                "cartesian",
                "--level",
                "1",
                "--domain",
                "0",
                "1",
                "0",
                "1",
                "0",
                "1",
                "-o",
                t,
            ],
            "needs 4 bounds",
        ),
        (
            vec![
                "cubes", "--level", "1", "--domain", "0", "1", "1", "0", "0", "1", "-o", v,
            ],
            "not a finite box",
        ),
    ] {
        let full = [&["mesh", "generate"][..], &args].concat();
        let (code, _, err) = gradvi(&full);
        assert_eq!(code, Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(message),
            "{args:?}: {err}"
        );
        assert!(!vtu.exists() && !typ2.exists(), "{args:?} wrote a file");
    }
    // 3D files that cannot be read name the file and the line
    let good = std::fs::read_to_string(format!("{ROOT}/tests/data/mesh3d/cube5_22.msh")).unwrap();
    let bad = tmp("bad.msh");
    std::fs::write(&bad, good.replace("9 2 2 2", "9 2 x 2")).unwrap();
    let (code, _, err) = gradvi(&["mesh", "info", bad.to_str().unwrap()]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("bad.msh:20:"), "{err}");
    std::fs::remove_file(bad).ok();
}
