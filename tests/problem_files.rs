//! Problem files (`problems/*.toml`, `gradvi::problem::file`): the built-in problems as files
//! reproduce the Rust closures bit for bit; every example file in `problems/` is solved with an
//! assertion that can fail; every bad file of `tests/data/problems/` gives its typed error,
//! naming the place.

use gradvi::error::ProblemFileErrorKind as K;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{cartesian, hexagonal, kershaw};
use gradvi::mesh::io::read_mesh;
use gradvi::post::{fitted_slope, relative_errors};
use gradvi::problem::file::{self, MeshSpec, ProblemFile};
use gradvi::problem::{Problem, by_name};
use gradvi::scheme::{GradientDiscretisation, Hmm, P1};
use gradvi::solver::{SolveOptions, Solution, solve_problem};
use gradvi::Error;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn problems() -> PathBuf {
    root().join("problems")
}

fn solve<'a>(scheme: &'a dyn GradientDiscretisation, p: &Problem) -> Solution<'a> {
    solve_problem(scheme, p, &SolveOptions::default())
        .unwrap_or_else(|e| panic!("{} with {}: {e}", p.name, scheme.name()))
}

/// Solves the built-in problem and the file with `scheme` and compares them: same NITER, same
/// solution to 1e-12 relative (in practice, the same bits).
fn same_solution(scheme: &dyn GradientDiscretisation, builtin: &Problem, from_file: &Problem) {
    let a = solve(scheme, builtin);
    let b = solve(scheme, from_file);
    assert_eq!(a.niter(), b.niter(), "{}: NITER", builtin.name);
    let scale = a.u().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .u()
        .iter()
        .zip(b.u())
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        diff <= 1e-12 * scale,
        "{} with {}: max difference {diff:e} (scale {scale:e})",
        builtin.name,
        scheme.name()
    );
    assert_eq!(builtin.name, from_file.name);
}

#[test]
fn builtin_files_reproduce_the_rust_problems() {
    let hex = hexagonal(1).unwrap();
    let ker = kershaw(1).unwrap();
    let cases: [(&str, Vec<(String, f64)>, &str); 5] = [
        ("test1", vec![], "meshes/test1_1.msh"),
        ("test2", vec![], "meshes/test2tri_1.msh"),
        ("test3", vec![], "meshes/test3_1.msh"),
        ("test3", vec![("C".into(), -20.0)], "meshes/test3_1.msh"),
        ("fvca5-1.1", vec![], "meshes/test3_1.msh"),
    ];
    for (name, params, tri) in cases {
        let builtin = by_name(name, &params).unwrap();
        let pf = file::load(problems().join(format!("{name}.toml")), &params).unwrap();
        let embedded = file::builtin(name, &params).unwrap();
        assert_eq!(pf.name, embedded.name);
        let tri = read_mesh(root().join(tri)).unwrap();
        for mesh in [&hex, &ker, &tri] {
            pf.check_against_mesh(mesh).unwrap();
            same_solution(&Hmm::new(mesh), &builtin, &pf.problem());
        }
        same_solution(&P1::new(&tri).unwrap(), &builtin, &pf.problem());
    }
}
