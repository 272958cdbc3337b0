//! The command line: exit codes, error messages, outputs.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository, where the commands run: the workspace root, above this package.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// Runs `gradvi args` in the repository with `RUST_BACKTRACE=backtrace`: (success, stdout,
/// stderr).
fn gradvi_with(args: &[&str], backtrace: &str) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_gradvi"))
        .args(args)
        .current_dir(ROOT)
        .env("RUST_BACKTRACE", backtrace)
        .output()
        .expect("run gradvi");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn gradvi(args: &[&str]) -> (bool, String, String) {
    gradvi_with(args, "0")
}

/// The words of a command line (no quoting: for arguments without spaces).
fn words(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("gradvi-cli-{}-{name}", std::process::id()))
}

#[test]
fn help_everywhere() {
    for args in [
        vec!["--help"],
        vec!["mesh", "--help"],
        vec!["mesh", "info", "--help"],
        vec!["mesh", "generate", "--help"],
        vec!["solve", "--help"],
        vec!["replicate", "--help"],
    ] {
        let (ok, out, _) = gradvi(&args);
        assert!(ok && out.contains("Usage"), "{args:?}");
    }
}

#[test]
fn bad_meshes_give_a_nonzero_exit_naming_the_file() {
    for f in [
        "typ2_not_star_shaped.typ2",
        "msh41_truncated_nodes.msh",
        "typ1_hanging_unlisted.typ1",
    ] {
        let path = format!("tests/data/malformed/{f}");
        let (ok, _, err) = gradvi(&["mesh", "info", &path]);
        assert!(!ok, "{f} accepted");
        assert!(err.contains(f), "{f}: {err}");
        assert!(!err.contains("panicked"), "{f}: {err}");
    }
}

#[test]
fn bad_arguments_give_a_nonzero_exit() {
    let out = tmp("x.typ2");
    let out = out.to_str().unwrap();
    let solve = "solve --problem test3 --generate cartesian --level";
    for args in [
        format!("mesh generate hexagonal --level 0 -o {out}"),
        format!("mesh generate octagonal --level 1 -o {out}"),
        "solve --problem nope --generate cartesian --level 1".into(),
        format!("{solve} 1 --warm-start lukewarm"),
        format!("{solve} 1 --param D=1"),
        "solve --problem test3 --generate hexagonal --level 1 --scheme p1".into(),
        format!("{solve} 2 --max-solves 1"),
        format!("{solve} 1 --c -1"),
    ] {
        let args = words(&args);
        let (ok, _, err) = gradvi(&args);
        assert!(!ok, "{args:?} succeeded");
        assert!(
            err.contains("Error") || err.contains("error"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn solve_prints_niter_and_writes_vtu_and_json() {
    let (vtu, json) = (tmp("u.vtu"), tmp("u.json"));
    let (ok, out, err) = gradvi(&words(&format!(
        "solve --problem test3 --param C=-20 --mesh meshes/test3_1.msh --scheme hmm \
         --warm-start cold --vtu {} --json {}",
        vtu.display(),
        json.display()
    )));
    assert!(ok, "{err}");
    assert!(out.contains("NITER           5"), "{out}");
    // progress: one stderr line per solve, as it happens
    assert_eq!(err.matches("  solve ").count(), 5, "{err}");
    assert!(out.contains("certificate"));
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(j["niter"], 5);
    assert!(j["certificate"]["max_violation"].as_f64().unwrap() <= 1e-10);
    let v = std::fs::read_to_string(&vtu).unwrap();
    for name in ["u_K", "active_cell", "multiplier_cell", "u_vertex"] {
        assert!(v.contains(&format!("Name=\"{name}\"")), "VTU lacks {name}");
    }
    // a problem with an exact solution prints its errors
    let (ok, out, _) = gradvi(&words(
        "solve --problem fvca5-1.1 --generate kershaw --level 1",
    ));
    assert!(ok && out.contains("errors"), "{out}");
    std::fs::remove_file(vtu).ok();
    std::fs::remove_file(json).ok();
}

#[test]
fn solve_with_a_nested_warm_start_reports_it() {
    let json = tmp("nested.json");
    let (ok, out, err) = gradvi(&words(&format!(
        "solve --problem test3 --param C=-20 --mesh meshes/test3_4.msh --warm-start nested \
         --json {}",
        json.display()
    )));
    assert!(ok, "{err}");
    assert!(out.contains("warm start      nested"), "{out}");
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(j["warm_start"]["coarse_solves"].as_u64().unwrap() >= 1);
    assert!(j["warm_start"]["skipped"].is_null());
    assert!(j["certificate"]["max_violation"].as_f64().unwrap() <= 1e-10);
    std::fs::remove_file(json).ok();
}

#[test]
fn generate_then_read_back() {
    let path = tmp("h.typ2");
    let p = path.to_str().unwrap();
    for (family, expected) in [("hexagonal", "441"), ("triangles", "cells by sides  3:128")] {
        let (ok, _, err) = gradvi(&["mesh", "generate", family, "--level", "2", "-o", p]);
        assert!(ok, "{err}");
        let (ok, out, _) = gradvi(&["mesh", "info", p]);
        assert!(ok && out.contains(expected), "{family}: {out}");
    }
    std::fs::remove_file(path).ok();
}

#[test]
fn absurd_or_conflicting_options_are_refused_before_any_work() {
    let mesh = "meshes/test3_1.msh";
    let x = tmp("same.out");
    let x = x.to_str().unwrap();
    for (args, needle) in [
        (vec!["--tol", "inf"], "--tol"),
        (vec!["--tol", "1e308"], "--tol"),
        (vec!["--tol", "0"], "--tol"),
        (vec!["--c", "NaN"], "--c"),
        (vec!["--param", "C=-5", "--param", "C=-10"], "twice"),
        (vec!["--param", "C=inf"], "finite"),
        (vec!["--vtu", x, "--json", x], "same file"),
        (vec!["--vtu", mesh], "overwritten"),
        (vec!["--scheme", "p1", "--alpha", "2"], "alpha"),
    ] {
        let mut full = vec!["solve", "--problem", "test3", "--mesh", mesh];
        full.extend(args.iter().copied());
        let (ok, _, err) = gradvi(&full);
        assert!(!ok, "{args:?} succeeded");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    // the mesh was not touched
    assert!(
        std::fs::read_to_string(Path::new(ROOT).join(mesh))
            .unwrap()
            .starts_with("$MeshFormat")
    );
    // --level is only meaningful with --generate
    let (ok, _, err) = gradvi(&words(&format!(
        "solve --problem test3 --mesh {mesh} --level 3"
    )));
    assert!(!ok && err.contains("--generate"), "{err}");
}

#[test]
fn a_user_error_is_one_line_whatever_rust_backtrace_says() {
    let (ok, _, err) = gradvi_with(&["mesh", "info", "no/such/file.msh"], "1");
    assert!(!ok);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("no/such/file.msh"),
        "{err}"
    );
    // the cause once (the library's message already holds it; `{:#}` repeated it)
    for args in [
        "mesh info no/such/file.msh",
        "solve --problem test1 --mesh no/such/file.msh",
    ] {
        let (ok, _, err) = gradvi(&words(args));
        assert!(!ok);
        assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    }
}

#[test]
fn problem_names_keep_the_sign_of_their_parameters() {
    // C = 5 pushes u up, away from the lower barrier: a valid problem
    for (c, name) in [("5", "test3_C5\n"), ("-5", "test3_C-5\n")] {
        let (ok, out, err) = gradvi(&words(&format!(
            "solve --problem test3 --param C={c} --generate cartesian --level 1"
        )));
        assert!(ok, "{err}");
        assert!(out.contains(name), "{out}");
    }
}

/// Runs `gradvi solve ARGS --json J` and returns the JSON summary (panics if the solve fails).
fn solve_json(args: &str, name: &str) -> serde_json::Value {
    let json = tmp(name);
    let line = format!("solve {args} --json {}", json.display());
    let (ok, _, err) = gradvi(&words(&line));
    assert!(ok, "{line}: {err}");
    let j = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    std::fs::remove_file(json).ok();
    j
}

/// problems/ex9.toml generates `cartesian`, level 4, on `domain = [-2, 2, -2, 2]`: --level
/// alone changes the level, --generate the family (and --level the level), both keeping the
/// domain; the JSON output records the mesh used. Before, `--level` alone was refused, and
/// `--generate cartesian --level 5` meshed the unit square, where the Dirichlet data
/// −A ln r + B is infinite at the corner (0, 0).
#[test]
fn overriding_a_generated_mesh_keeps_its_domain() {
    let on = "on [-2, 2]x[-2, 2]";
    // h of the unit-square mesh: the diagonal of a square of side 1/n, or (Kershaw level 1)
    // the FVCA5 value
    let square = |n: f64| std::f64::consts::SQRT_2 / n;
    for (args, mesh, cells, h_unit) in [
        (
            "--level 5",
            format!("cartesian level 5 {on}"),
            64 * 64,
            square(64.0),
        ),
        (
            "--generate cartesian --level 5",
            format!("cartesian level 5 {on}"),
            64 * 64,
            square(64.0),
        ),
        (
            "--generate triangles --scheme p1",
            format!("triangles level 4 {on}"),
            2 * 32 * 32,
            square(32.0),
        ),
        (
            "--generate triangles --level 3 --scheme p1",
            format!("triangles level 3 {on}"),
            2 * 16 * 16,
            square(16.0),
        ),
        (
            "--generate kershaw --level 1",
            format!("kershaw level 1 {on}"),
            289,
            0.3288,
        ),
    ] {
        let j = solve_json(&format!("problems/ex9.toml {args}"), "override.json");
        assert_eq!(j["mesh"], mesh.as_str(), "{args}");
        assert_eq!(j["n_cells"], cells, "{args}");
        assert!(
            j["certificate"]["max_violation"].as_f64().unwrap() <= 1e-10,
            "{args}"
        );
        // the mesh is on [-2, 2]²: h is 4 times that of the unit-square mesh
        let h = j["h"].as_f64().unwrap();
        assert!((h - 4.0 * h_unit).abs() <= 1e-3 * h, "{args}: h = {h}");
    }
    // without overrides, the file's mesh
    let j = solve_json("problems/ex9.toml", "file-mesh.json");
    assert_eq!(j["mesh"], format!("cartesian level 4 {on}").as_str());
}

/// --mesh replaces the problem file's mesh entirely: the file's `domain` is not applied.
#[test]
fn a_mesh_file_replaces_a_generated_mesh_and_its_domain() {
    let problem = tmp("strip.toml");
    std::fs::write(
        &problem,
        "name = \"strip\"\n[mesh]\ngenerate = \"cartesian\"\nlevel = 2\ndomain = [0, 4, 0, 1]\n\
         [source]\nf = 1\n",
    )
    .unwrap();
    let p = problem.display();
    let j = solve_json(&format!("{p}"), "strip.json");
    assert_eq!(j["mesh"], "cartesian level 2 on [0, 4]x[0, 1]");
    assert!((j["h"].as_f64().unwrap() - (0.5f64.powi(2) + 0.125f64.powi(2)).sqrt()).abs() < 1e-12);
    let j = solve_json(&format!("{p} --mesh meshes/test3_1.msh"), "strip-file.json");
    assert_eq!(j["mesh"], "meshes/test3_1.msh");
    assert_eq!(j["n_cells"], 856);
    // the h of test3_1.msh on the unit square (`gradvi mesh info`: 0.060867), not stretched
    assert!(
        (j["h"].as_f64().unwrap() - 0.060867).abs() < 1e-6,
        "{}",
        j["h"]
    );
    // --level with --mesh has nothing to apply to
    let (ok, _, err) = gradvi(&words(&format!(
        "solve {p} --mesh meshes/test3_1.msh --level 3"
    )));
    assert!(!ok && err.contains("--generate"), "{err}");
    std::fs::remove_file(problem).ok();
}

/// --level without --generate when the problem file's mesh is a file, or when it has none;
/// --generate without --level when there is no level to keep: one clear line each.
#[test]
fn a_level_with_nothing_to_apply_to_is_refused() {
    for (line, needles) in [
        (
            "solve problems/lshape-obstacle.toml --level 3",
            ["--level needs --generate", "lshape.msh"],
        ),
        (
            "solve --problem test3 --level 3",
            ["--level needs --generate", "has no [mesh]"],
        ),
        (
            "solve --problem test3 --generate cartesian",
            ["--generate cartesian needs --level", "test3.toml"],
        ),
    ] {
        let (ok, _, err) = gradvi(&words(line));
        assert!(!ok, "{line} succeeded");
        assert_eq!(err.trim_end().lines().count(), 1, "{line}: {err}");
        for n in needles {
            assert!(err.contains(n), "{line}: {err}");
        }
    }
}

/// An unknown family lists all four (generated and read back in `generate_then_read_back`);
/// P1 on a generated quadrangle mesh says how to get triangles.
#[test]
fn the_list_of_families() {
    let path = tmp("t.typ2");
    let p = path.to_str().unwrap();
    let all = "\"cartesian\", \"hexagonal\", \"kershaw\" or \"triangles\"";
    for line in [
        format!("mesh generate octagonal --level 1 -o {p}"),
        "solve problems/ex9.toml --generate octagonal".into(),
    ] {
        let (ok, _, err) = gradvi(&words(&line));
        assert!(!ok && err.contains(all), "{line}: {err}");
    }
    let (ok, _, err) = gradvi(&words("solve problems/ex9.toml --scheme p1"));
    assert!(!ok && err.contains("--generate triangles"), "{err}");
}

/// The example of a marginal load: the paper's Test 2 data on (−1,0)×(0.2,0.8), every
/// edge Signorini with the upper barrier 0. HMM refuses it, P1 solves it; both say that the
/// conclusion hangs on the sign of a small total load (P1: on stderr and in the JSON output).
#[test]
fn a_marginal_load_is_reported_on_stderr_and_in_the_json() {
    let test2 = std::fs::read_to_string(Path::new(ROOT).join("problems/test2.toml")).unwrap();
    let data = &test2[..test2.find("[dirichlet]").unwrap()];
    let file = tmp("marginal.toml");
    let json = tmp("marginal.json");
    std::fs::write(
        &file,
        format!(
            "{data}\n[mesh]\ngenerate = \"cartesian\"\nlevel = 2\ndomain = [-1, 0, 0.2, 0.8]\n\n\
             [signorini]\nside = \"upper\"\nbarrier = 0\n"
        ),
    )
    .unwrap();
    let f = file.to_str().unwrap();
    let (ok, _, err) = gradvi(&["solve", f, "--scheme", "hmm"]);
    assert!(
        !ok && err.contains("ill-posed") && err.contains("marginal load"),
        "{err}"
    );
    let j = json.to_str().unwrap();
    let (ok, _, err) = gradvi(&[
        "solve",
        f,
        "--scheme",
        "p1",
        "--generate",
        "triangles",
        "--json",
        j,
    ]);
    assert!(ok && err.contains("warning: marginal load"), "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let m = &v["marginal_load"][0];
    assert!(
        m["ratio"].as_f64().unwrap() < 0.1 && m["sum"].as_f64().unwrap() > 0.0,
        "{v}"
    );
    std::fs::remove_file(&file).ok();
    std::fs::remove_file(&json).ok();
}
