//! `gradvi solve` on 3D meshes: the 3D examples of problems/ solved through the binary, their
//! errors against the exact solutions checked against the measured values and their
//! convergence slopes fitted (two-sided); the outputs (JSON, VTU of the cells and of the
//! boundary faces); the dimension mismatches.
//!
//! The Signorini example needs gmsh (its tetrahedral meshes are made from
//! meshes/3d/signorini3d.geo): it is `#[ignore]`d and run by `make test-solve3d` (or
//! `make test-external`); it fails, not skips, when gmsh is missing.

use serde_json::Value;
use std::path::{Path, PathBuf};
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

/// Runs `gradvi solve PROBLEM --generate FAMILY --level LEVEL EXTRA...` in the repository.
fn solve_on(
    problem: &str,
    family: &str,
    level: &str,
    extra: &[&str],
) -> (Option<i32>, String, String) {
    let mut args = vec!["solve", problem, "--generate", family, "--level", level];
    args.extend_from_slice(extra);
    gradvi(&args)
}

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("gradvi-solve3d-{}-{name}", std::process::id()))
}

/// Solves with `args` (after `solve`), writing the JSON summary; the summary.
fn solve_json(args: &[&str], tag: &str) -> Value {
    let json = tmp(&format!("{tag}.json"));
    let mut all = vec!["solve"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--json", json.to_str().unwrap()]);
    let (code, out, err) = gradvi(&all);
    assert_eq!(code, Some(0), "{args:?}: {out}\n{err}");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    std::fs::remove_file(&json).ok();
    v
}

/// (h, relative L2 error of u, of ∇u) of a summary.
fn errors(v: &Value) -> (f64, f64, f64) {
    let e = &v["errors"];
    (
        v["h"].as_f64().unwrap(),
        e["l2_u"].as_f64().unwrap(),
        e["l2_grad"].as_f64().unwrap(),
    )
}

/// The least-squares slope of log e against log h.
fn slope(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let (x, y): (Vec<f64>, Vec<f64>) = h.iter().zip(e).map(|(h, e)| (h.ln(), e.ln())).unzip();
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Solves `problem` on `family` at `levels`; checks each error against its measured value
/// (`measured[i] = (u, grad)`, to 1 %), and the fitted slopes within ±0.15 of `orders`.
fn converges(
    problem: &str,
    family: &str,
    levels: &[usize],
    measured: &[(f64, f64)],
    orders: (f64, f64),
) -> Vec<Value> {
    let mut runs = Vec::new();
    let (mut hs, mut eu, mut eg) = (Vec::new(), Vec::new(), Vec::new());
    for (&level, &(mu, mg)) in levels.iter().zip(measured) {
        let l = level.to_string();
        let v = solve_json(
            &[problem, "--generate", family, "--level", &l],
            // the problem's name too: tests running at once solve the same family and level
            &format!("{}-{family}{l}", problem.replace(['/', '.'], "_")),
        );
        assert_eq!(
            v["certificate"]["max_violation"].as_f64().unwrap(),
            0.0,
            "{v}"
        );
        let (h, u, g) = errors(&v);
        assert!(
            u <= mu * 1.01 && u >= mu * 0.99,
            "{problem} {family} {level}: L2 u {u:e}, measured {mu:e}"
        );
        assert!(
            g <= mg * 1.01 && g >= mg * 0.99,
            "{problem} {family} {level}: L2 grad {g:e}, measured {mg:e}"
        );
        hs.push(h);
        eu.push(u);
        eg.push(g);
        runs.push(v);
    }
    let (su, sg) = (slope(&hs, &eu), slope(&hs, &eg));
    assert!(
        (su - orders.0).abs() <= 0.15,
        "{problem} {family}: slope of u {su}"
    );
    assert!(
        (sg - orders.1).abs() <= 0.15,
        "{problem} {family}: slope of grad u {sg}"
    );
    runs
}

#[test]
fn ex9_3d_converges_and_its_contact_ball_shrinks_to_the_exact_radius() {
    // (−2,2)³, cubes of side 4/8 and 4/16
    let runs = converges(
        "problems/ex9-3d.toml",
        "cubes",
        &[2, 3],
        &[(4.780411e-2, 1.964796e-1), (4.558337e-3, 8.024750e-2)],
        (3.39, 1.29),
    );
    // the radius of the ball of the volume of the active cells, against r₀ = 1/√2
    let r0 = 0.5f64.sqrt();
    let radius = |v: &Value, n: f64| {
        let cells = v["n_active"].as_f64().unwrap();
        (3.0 * cells * (4.0 / n).powi(3) / (4.0 * std::f64::consts::PI)).cbrt()
    };
    let (r2, r3) = (radius(&runs[0], 8.0), radius(&runs[1], 16.0));
    assert!((r3 - r0).abs() < (r2 - r0).abs(), "{r2} {r3}");
    assert!((r3 - r0).abs() < 0.1, "contact radius {r3}, exact {r0}");
    // NITER small with the default (nested) start
    for v in &runs {
        assert!(v["niter"].as_u64().unwrap() <= 4, "{v}");
        assert_eq!(v["mesh"].as_str().unwrap().split(' ').next(), Some("3D"));
    }
}

#[test]
fn disk_obstacle_3d_converges() {
    converges(
        "problems/disk-obstacle-3d.toml",
        "cubes",
        &[1, 2, 3],
        &[
            (6.557387e-2, 3.683802e-2),
            (1.610989e-2, 1.171951e-2),
            (4.019994e-3, 3.462789e-3),
        ],
        (2.01, 1.71),
    );
}

#[test]
fn poisson_3d_converges_on_cubes_and_tetrahedra() {
    converges(
        "problems/poisson-3d.toml",
        "cubes",
        &[1, 2, 3],
        &[
            (7.231457e-2, 5.838697e-2),
            (1.819127e-2, 1.512654e-2),
            (4.567057e-3, 3.865387e-3),
        ],
        (1.99, 1.96),
    );
    converges(
        "problems/poisson-3d.toml",
        "kuhn",
        &[1, 2],
        &[(1.436034e-2, 1.796090e-1), (3.398861e-3, 8.901896e-2)],
        (2.08, 1.01),
    );
}

/// Meshes meshes/3d/signorini3d.geo with gmsh at size `h` into `out`; panics if gmsh is missing.
fn gmsh(h: f64, out: &Path) {
    let status = Command::new("gmsh")
        .args([
            "-3",
            "-nt",
            "1",
            "-format",
            "msh41",
            "-v",
            "2",
            "-setnumber",
            "h",
        ])
        .arg(h.to_string())
        .arg(Path::new(ROOT).join("meshes/3d/signorini3d.geo"))
        .arg("-o")
        .arg(out)
        .status()
        .expect("gmsh is needed for this test (the Debian package gmsh; make reference-deps)");
    assert!(status.success(), "gmsh failed on meshes/3d/signorini3d.geo");
}

#[test]
#[ignore = "needs gmsh (make test-solve3d)"]
fn signorini_3d_on_gmsh_tetrahedra_converges() {
    let (mut hs, mut eu, mut eg) = (Vec::new(), Vec::new(), Vec::new());
    for (i, size) in [0.25, 0.125, 0.0625].into_iter().enumerate() {
        let msh = tmp(&format!("signorini{i}.msh"));
        gmsh(size, &msh);
        let v = solve_json(
            &[
                "problems/signorini-3d.toml",
                "--mesh",
                msh.to_str().unwrap(),
            ],
            &format!("signorini{i}"),
        );
        std::fs::remove_file(&msh).ok();
        assert!(v["n_active"].as_u64().unwrap() > 0, "{v}");
        let (h, u, g) = errors(&v);
        hs.push(h);
        eu.push(u);
        eg.push(g);
    }
    // measured with gmsh 4.8.4: L2 u 0.364, 0.134, 0.0354; grad 1.07, 0.570, 0.286
    let (su, sg) = (slope(&hs, &eu), slope(&hs, &eg));
    assert!(eu[2] < 0.04 && eg[2] < 0.3, "{eu:?} {eg:?}");
    assert!((su - 1.76).abs() <= 0.3, "slope of u {su}");
    assert!((sg - 1.0).abs() <= 0.2, "slope of grad u {sg}");
}

/// A Signorini problem on the unit cube, contact on the bottom face z = 0 (u ≤ 0, pushed
/// down by f = −10): a problem with face unknowns in the constraint.
const SIGNORINI_CUBE: &str = r#"
[source]
f = -10
[dirichlet]
where = "z > 1 - 1e-9"
[signorini]
where = "z < 1e-9"
side = "upper"
barrier = 0
[neumann]
"#;

#[test]
fn vtu_and_json_outputs_of_3d_solves() {
    // obstacle (cell unknowns): u, the gradient and the active set on cells
    let vtu = tmp("ex9.vtu");
    let json = tmp("ex9.json");
    let (code, out, err) = gradvi(&[
        "solve",
        "problems/ex9-3d.toml",
        "--vtu",
        vtu.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    // the default start is the nested one; this mesh is too coarse for a coarse level
    assert!(out.contains("warm start      skipped"), "{out}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    for name in [
        "u_K",
        "grad_x",
        "grad_y",
        "grad_z",
        "u_vertex",
        "active_cell",
        "multiplier_cell",
    ] {
        assert!(text.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    assert!(text.contains("NumberOfCells=\"512\""));
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["n_cells"], 512);
    assert_eq!(v["mesh"], "3D cubes level 2 on [-2, 2]x[-2, 2]x[-2, 2]");
    // Signorini (face unknowns): the active faces and their multipliers summed per cell
    let toml = tmp("signorini.toml");
    std::fs::write(&toml, SIGNORINI_CUBE).unwrap();
    let (code, _, err) = solve_on(
        toml.to_str().unwrap(),
        "cubes",
        "1",
        &["--vtu", vtu.to_str().unwrap()],
    );
    assert_eq!(code, Some(0), "{err}");
    let text = std::fs::read_to_string(&vtu).unwrap();
    for name in ["active_faces", "multiplier_faces"] {
        assert!(text.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    assert!(!text.contains("active_cell"));
    for p in [&vtu, &json, &toml, &boundary_vtu(&vtu)] {
        std::fs::remove_file(p).ok();
    }
}

/// The Signorini cube pushed up (f = 10) against a barrier that rises with x: contact on part
/// of the bottom face (`tests/data/signorini-contact-3d.toml`, shared with the Python tests).
const SIGNORINI_CONTACT: &str = include_str!("../../tests/data/signorini-contact-3d.toml");

#[test]
fn the_boundary_vtu_shows_the_contact_zone_on_the_faces() {
    let (toml, vtu, json) = (tmp("contact.toml"), tmp("contact.vtu"), tmp("contact.json"));
    std::fs::write(&toml, SIGNORINI_CONTACT).unwrap();
    let (code, out, err) = solve_on(
        toml.to_str().unwrap(),
        "cubes",
        "1",
        &[
            "--vtu",
            vtu.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ],
    );
    assert_eq!(code, Some(0), "{err}");
    let b = boundary_vtu(&vtu);
    assert!(
        out.contains(&format!("wrote           {}", b.display())),
        "{out}"
    );
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let text = std::fs::read_to_string(&b).unwrap();
    assert!(
        text.contains("NumberOfCells=\"96\""),
        "6 sides of 4 × 4 squares"
    );
    assert!(
        text.contains("NumberOfPoints=\"98\""),
        "5³ vertices but 3³ inside"
    );
    for name in [
        "face",
        "boundary_tag",
        "u_face",
        "active",
        "multiplier",
        "u_vertex",
    ] {
        assert!(text.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    assert_eq!(data_array(&text, "types"), vec![7.0; 96]);
    // half of the 16 faces of the bottom are in contact, and the multiplier lives there
    let active = data_array(&text, "active");
    let n_active = active.iter().filter(|&&a| a == 1.0).count();
    assert_eq!(n_active, 8);
    assert_eq!(v["n_active"], n_active);
    let lam = data_array(&text, "multiplier");
    // λ = 0 off the contact zone (up to round-off), λ > 0 on it
    assert!(active.iter().zip(&lam).all(|(&a, &l)| if a == 1.0 {
        l > 0.1
    } else {
        l.abs() < 1e-12
    }));
    // u_σ = a_σ on the contact faces: below the barrier 10 (x_σ − 1/2) ≤ 0 where x_σ < 1/2
    let (u, faces) = (data_array(&text, "u_face"), data_array(&text, "face"));
    assert_eq!(faces.len(), 96);
    assert!(active.iter().zip(&u).all(|(&a, &u)| a == 0.0 || u < 0.0));
    for p in [&vtu, &json, &toml, &b] {
        std::fs::remove_file(p).ok();
    }
}

/// The boundary VTU file `gradvi solve --vtu NAME.vtu` writes in 3D: `NAME_boundary.vtu`.
fn boundary_vtu(vtu: &Path) -> PathBuf {
    let stem = vtu.file_stem().unwrap().to_str().unwrap();
    vtu.with_file_name(format!("{stem}_boundary.vtu"))
}

/// The values of the `DataArray` named `name` of a VTU file's text.
fn data_array(text: &str, name: &str) -> Vec<f64> {
    let body = &text[text.find(&format!("Name=\"{name}\"")).unwrap()..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
    body.split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect()
}

#[test]
fn the_boundary_vtu_never_overwrites_an_input() {
    // a 3D mesh named as the boundary file of --vtu would be
    let mesh = tmp("cube_boundary.vtu");
    let (code, _, err) = gradvi(&[
        "mesh",
        "generate",
        "cubes",
        "--level",
        "1",
        "-o",
        mesh.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let before = std::fs::read(&mesh).unwrap();
    let vtu = tmp("cube.vtu");
    let (code, _, err) = gradvi(&[
        "solve",
        "problems/poisson-3d.toml",
        "--mesh",
        mesh.to_str().unwrap(),
        "--vtu",
        vtu.to_str().unwrap(),
    ]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("the boundary VTU output") && err.contains("is the mesh input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&mesh).unwrap(), before);
    assert!(!vtu.exists());
    std::fs::remove_file(&mesh).ok();
}

#[test]
fn dimension_mismatches_are_errors_at_their_place_in_the_file() {
    let toml = tmp("mismatch.toml");
    // a 2×2 tensor on a 3D mesh
    std::fs::write(&toml, "[diffusion]\nA = [[1, 0], [0, 1]]\n").unwrap();
    let (code, _, err) = solve_on(toml.to_str().unwrap(), "cubes", "1", &[]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains(":2:5: diffusion.A: a 2x2 tensor on a 3D mesh"),
        "{err}"
    );
    // a z on a 2D mesh
    std::fs::write(&toml, "[source]\nf = \"x*z\"\n").unwrap();
    let (code, _, err) = solve_on(toml.to_str().unwrap(), "cartesian", "1", &[]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains(":2:8: source.f: \"x*z\" at character 3: unknown variable 'z'"),
        "{err}"
    );
    // the same file solves on a 3D mesh
    let (code, _, err) = solve_on(toml.to_str().unwrap(), "kuhn", "1", &[]);
    assert_eq!(code, Some(0), "{err}");
    // a 3D family with the 2D domain of a problem file's mesh
    let (code, _, err) = gradvi(&["solve", "problems/ex9.toml", "--generate", "cubes"]);
    assert_ne!(code, Some(0));
    assert!(err.contains("--generate cubes is a 3D family"), "{err}");
    std::fs::remove_file(&toml).ok();
}

#[test]
fn vtu_faces_writes_every_face_with_the_boundary_files_values() {
    let (toml, vtu) = (tmp("faces.toml"), tmp("faces.vtu"));
    std::fs::write(&toml, SIGNORINI_CONTACT).unwrap();
    let (code, out, err) = solve_on(
        toml.to_str().unwrap(),
        "cubes",
        "1",
        &["--vtu", vtu.to_str().unwrap(), "--vtu-faces"],
    );
    assert_eq!(code, Some(0), "{err}");
    let f = tmp("faces_faces.vtu");
    assert!(
        out.contains(&format!("wrote           {}", f.display())),
        "{out}"
    );
    let text = std::fs::read_to_string(&f).unwrap();
    // 3 directions × 5 planes × 4 × 4 squares: every face of the mesh
    assert!(text.contains("NumberOfCells=\"240\""), "all 240 faces");
    assert_eq!(data_array(&text, "types"), vec![7.0; 240]);
    let faces = data_array(&text, "face");
    assert_eq!(faces, (0..240).map(f64::from).collect::<Vec<_>>());
    // HMM's u_σ on the boundary faces is the boundary file's
    let b = std::fs::read_to_string(boundary_vtu(&vtu)).unwrap();
    let (u_all, u_b) = (data_array(&text, "u_face"), data_array(&b, "u_face"));
    for (i, &fb) in data_array(&b, "face").iter().enumerate() {
        assert_eq!(u_all[fb as usize], u_b[i], "face {fb}");
    }
    assert_eq!(
        data_array(&text, "active")
            .iter()
            .filter(|&&a| a == 1.0)
            .count(),
        8
    );
    for p in [&vtu, &toml, &f, &boundary_vtu(&vtu)] {
        std::fs::remove_file(p).ok();
    }
    // 2D: refused with a clear error
    let v2 = tmp("faces2d.vtu");
    let (code, _, err) = gradvi(&[
        "solve",
        "--problem",
        "test1",
        "--generate",
        "cartesian",
        "--level",
        "1",
        "--vtu",
        v2.to_str().unwrap(),
        "--vtu-faces",
    ]);
    assert_ne!(code, Some(0));
    assert!(
        err.contains("--vtu-faces writes the faces of a 3D mesh"),
        "{err}"
    );
    assert!(!v2.exists());
}
