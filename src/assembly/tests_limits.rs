//! The assembly under a data limit: the symbolic system, the values, the cell system of the
//! iterative solves (`two_point`) and the whole solve, each run again and again in a child
//! process whose data is limited to what it has plus a growing margin, give their result or
//! the typed out-of-memory error, never an abort.

use crate::assembly::{LinearSolver, SystemOptions};
use crate::budget::child;
use crate::solver::{SolveOptions, solve_problem};

/// The margins of the sweep, in MiB: from none (everything refused) to ample.
const EXTRA_MIB: [u64; 10] = [0, 1, 2, 4, 8, 16, 32, 64, 128, 2048];

/// HMM on a 120 × 120 grid, the paper's Test 3 obstacle problem, solved with `linear` unlimited
/// and then under each margin of [`EXTRA_MIB`]: every limited solve either gives the bits and
/// NITER of the unlimited one or is refused with [`Error::OutOfMemory`](crate::Error) (or a
/// mesh-sized [`MeshError::TooLarge`](crate::error::MeshError)); the smallest margin is
/// refused, the largest solves.
fn sweep(linear: LinearSolver) {
    let mesh = crate::mesh::generate::cartesian(120, 120).unwrap();
    let scheme = crate::scheme::Hmm::new(&mesh);
    let p = crate::problem::paper_test3(-20.0);
    let opts = SolveOptions {
        system: SystemOptions {
            linear,
            ..Default::default()
        },
        ..SolveOptions::paper()
    };
    // unlimited first: the reference, and the per-thread memory mapped once for good (the
    // dense product workspace of the factorisation, the threads' arenas)
    let reference = solve_problem(&scheme, &p, &opts).unwrap();
    assert!(reference.niter() > 1);
    let mut outcomes = Vec::new();
    for extra in EXTRA_MIB {
        child::limit_data(extra << 20);
        let solved = solve_problem(&scheme, &p, &opts).map(|s| (s.niter(), s.u().to_vec()));
        child::limit_data(4 << 30);
        match solved {
            Ok((niter, u)) => {
                assert_eq!(niter, reference.niter(), "{extra} MiB");
                assert!(u == reference.u(), "{extra} MiB: other bits");
                outcomes.push(true);
            }
            Err(e) if e.is_out_of_memory() => outcomes.push(false),
            Err(e) => panic!("{extra} MiB: {e}"),
        }
    }
    assert_eq!(outcomes.first(), Some(&false), "{outcomes:?}");
    assert_eq!(outcomes.last(), Some(&true), "{outcomes:?}");
}

/// The direct path: symbolic system, values, condensation, Cholesky factorisation.
#[cfg(target_os = "linux")]
#[test]
fn a_direct_solve_the_data_limit_refuses_is_a_typed_error() {
    const NAME: &str =
        "assembly::tests_limits::a_direct_solve_the_data_limit_refuses_is_a_typed_error";
    if !child::is_child(NAME) {
        return child::run(NAME);
    }
    sweep(LinearSolver::Direct);
}

/// The iterative path: the same, with the cell system of `two_point` and the multigrid.
#[cfg(target_os = "linux")]
#[test]
fn an_iterative_solve_the_data_limit_refuses_is_a_typed_error() {
    const NAME: &str =
        "assembly::tests_limits::an_iterative_solve_the_data_limit_refuses_is_a_typed_error";
    if !child::is_child(NAME) {
        return child::run(NAME);
    }
    sweep(LinearSolver::Iterative);
}
