//! Regression tier: a few pinned numbers of the replication (Table 2, Table 3, Table 1 on the
//! coarsest meshes). The smoke run of the whole replication pipeline, an application of the
//! library, is a test of the command line (`cli/tests/replicate.rs`).

mod common;

use gradvi::mesh::generate::hexagonal;
use gradvi::mesh::io::read_mesh;
use gradvi::post::relative_errors;
use gradvi::problem::{paper_test1, paper_test2, paper_test3};
use gradvi::scheme::{Hmm, P1};
use gradvi::solver::{SolveOptions, solve_problem};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn table2_hexagonal_levels_1_and_2() {
    // pinned from replication/results/test2.csv (HMM, our reading of Test 2)
    let pinned = [
        (1, 0.5658778205875443, 0.3485982699715217, 3),
        (2, 0.2104252874399887, 0.16054483611107914, 3),
    ];
    let p = paper_test2();
    let ex = p.exact.as_ref().unwrap();
    for (level, eu, eg, niter) in pinned {
        let mesh = hexagonal(level).unwrap();
        let s = Hmm::new(&mesh);
        let sol = solve_problem(&s, &p, &SolveOptions::paper()).unwrap();
        let e = relative_errors(&s, sol.u(), &ex.u, &ex.grad);
        assert!(
            close(e.l2_u, eu, 1e-9),
            "level {level}: e_u {} vs {eu}",
            e.l2_u
        );
        assert!(
            close(e.l2_grad, eg, 1e-9),
            "level {level}: e_grad {} vs {eg}",
            e.l2_grad
        );
        assert_eq!(sol.niter(), niter, "level {level}");
    }
}

#[test]
fn table3_and_table1_on_the_coarsest_meshes() {
    let m3 = read_mesh(
        root().join("meshes/test3_1.msh"),
        gradvi::budget::MemoryBudget::DEFAULT,
    )
    .unwrap();
    for (c, hmm, p1) in [(-5.0, 8, 6), (-10.0, 8, 6), (-15.0, 5, 5), (-20.0, 5, 4)] {
        let hmm_scheme = Hmm::new(&m3);
        let sol = solve_problem(&hmm_scheme, &paper_test3(c), &SolveOptions::paper()).unwrap();
        assert_eq!(sol.niter(), hmm, "HMM, C = {c}");
        let s1 = P1::new(&m3).unwrap();
        let sol = solve_problem(&s1, &paper_test3(c), &SolveOptions::paper()).unwrap();
        assert_eq!(sol.niter(), p1, "P1, C = {c}");
    }
    let m1 = read_mesh(
        root().join("meshes/test1_1.msh"),
        gradvi::budget::MemoryBudget::DEFAULT,
    )
    .unwrap();
    let s1 = Hmm::new(&m1);
    let sol = solve_problem(&s1, &paper_test1(), &SolveOptions::paper()).unwrap();
    assert_eq!(sol.niter(), 4);
    let cons = sol.constraints.as_ref().unwrap();
    let sw = gradvi::post::contact::switch_point(&s1, cons, &sol.result.active, 0).unwrap();
    assert!(close(sw.at, 0.6875, 1e-9), "switch at {}", sw.at);
}
