//! Tests of the assembled matrix of schemes without interior unknowns ([`super::assembled`]).

use super::symbolic::DofMap;
use super::values::ProblemValues;
use super::{DiscreteSystem, LinearSolver, SolveState, SystemOptions};
use crate::mesh::generate::cartesian_triangles;
use crate::problem::paper_test3;
use crate::scheme::{GradientDiscretisation, P1};
use crate::vi::FixedValues;
use std::collections::BTreeMap;

/// M summed entry by entry in cell order from the scheme's local matrices (their packed lower
/// triangles, as every assembly reads them), sequentially: the reference of the bits.
fn cell_order_sum(
    scheme: &dyn GradientDiscretisation,
    p: &crate::problem::Problem,
) -> BTreeMap<(usize, usize), f64> {
    let dm = DofMap::new(scheme).unwrap();
    let v = ProblemValues::evaluate(scheme, &dm, p).unwrap();
    let mut m = BTreeMap::new();
    for k in 0..dm.n_cells() {
        let (d, _) = dm.cell(k);
        let lower = &v.mats[v.mat_ptr.range(k)];
        let mut t = 0;
        for (b, &j) in d.iter().enumerate() {
            for &i in &d[b..] {
                let key = (i.max(j) as usize, i.min(j) as usize);
                *m.entry(key).or_insert(0.0) += lower[t];
                t += 1;
            }
        }
    }
    m
}

fn bits(t: &[(usize, usize, f64)]) -> Vec<(usize, usize, u64)> {
    t.iter().map(|&(i, j, v)| (i, j, v.to_bits())).collect()
}

/// More cells than one batch of the streamed assembly (65 536): the assembled M has, entry by
/// entry, the bits of the sequential cell-order sum (exact zeros dropped, both triangles),
/// whatever the number of threads, and b those of the local loads summed in cell order.
#[test]
fn the_assembled_matrix_has_the_bits_of_the_cell_order_sum() {
    let mesh = cartesian_triangles(200, 170, [0.0, 1.0], [0.0, 1.0]).unwrap();
    assert!(mesh.n_cells() > 1 << 16);
    let p1 = P1::new(&mesh).unwrap();
    let p = paper_test3(1.0);
    let reference = cell_order_sum(&p1, &p);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let sys = DiscreteSystem::new(&p1, &p, SystemOptions::default()).unwrap();
            (sys.full_matrix_triplets(), sys.load().to_vec())
        })
    };
    let (one, load1) = build(1);
    let mut expected = Vec::new();
    for (&(r, c), &v) in &reference {
        if v != 0.0 || r == c {
            expected.push((r, c, v));
            if r != c {
                expected.push((c, r, v));
            }
        }
    }
    expected.sort_by_key(|&(i, j, _)| (i, j));
    assert_eq!(bits(&one), bits(&expected));
    let (three, load3) = build(3);
    assert_eq!(bits(&one), bits(&three));
    assert_eq!(
        load1.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        load3.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    );
}

/// The masked systems: with some unknowns fixed, the direct solve (lower pattern) and the
/// iterative one (rows) agree to the solver's tolerance, keep the fixed values, and leave a
/// residual b − M u that vanishes on the free unknowns.
#[test]
fn direct_and_iterative_solves_of_the_masked_system_agree() {
    let mesh = cartesian_triangles(40, 40, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&mesh).unwrap();
    let p = paper_test3(-10.0);
    let with = |linear| SystemOptions {
        linear,
        ..Default::default()
    };
    let direct = DiscreteSystem::new(&p1, &p, with(LinearSolver::Direct)).unwrap();
    let iterative = DiscreteSystem::new(&p1, &p, with(LinearSolver::Iterative)).unwrap();
    let n = direct.n_unknowns();
    let fixed = FixedValues::from_options((0..n).map(|i| (i % 7 == 3).then_some(0.25))).unwrap();
    let (ud, _) = direct.solve(&mut SolveState::default(), &fixed).unwrap();
    let (ui, _) = iterative.solve(&mut SolveState::default(), &fixed).unwrap();
    let scale = ud.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let gap = ud
        .iter()
        .zip(&ui)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(gap <= 1e-8 * scale, "{gap:e} against {scale:e}");
    let (r, s) = direct.residual(&ud).unwrap();
    let mut free = 0;
    for i in 0..n {
        match (fixed.get(i), direct.dirichlet().get(i)) {
            (_, Some(v)) => assert_eq!(ud[i], v),
            (Some(v), None) => assert_eq!(ud[i], v),
            (None, None) => {
                free += 1;
                assert!(r[i].abs() <= 1e-12 * s[i].max(1.0), "row {i}: {:e}", r[i]);
            }
        }
    }
    assert!(free > n / 2, "{free} free unknowns of {n}");
}

/// A symbolic system shared by two problems (it keeps no dof map for P1): each system built on
/// it is the one built alone, bit for bit, and well-posedness is read from the pattern.
#[test]
fn a_shared_symbolic_system_assembles_each_problem_as_alone() {
    use super::SymbolicSystem;
    use std::sync::Arc;
    let mesh = cartesian_triangles(20, 20, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&mesh).unwrap();
    let sym = Arc::new(SymbolicSystem::new(&p1, SystemOptions::default()).unwrap());
    assert_eq!(sym.dof_map.n_cells(), 0);
    for c in [1.0, -10.0] {
        let p = paper_test3(c);
        let shared = DiscreteSystem::with_symbolic(Arc::clone(&sym), &p).unwrap();
        let alone = DiscreteSystem::new(&p1, &p, SystemOptions::default()).unwrap();
        assert_eq!(
            bits(&shared.full_matrix_triplets()),
            bits(&alone.full_matrix_triplets())
        );
        let fixed = FixedValues::free(shared.n_unknowns()).unwrap();
        let (a, _) = shared.solve(&mut SolveState::default(), &fixed).unwrap();
        let (b, _) = alone.solve(&mut SolveState::default(), &fixed).unwrap();
        assert_eq!(
            a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            b.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        let analysis = crate::solver::well_posed::analyse(&shared, None).unwrap();
        assert!(analysis.floating.is_empty(), "c = {c}");
    }
}

/// Solved iteratively, a P1 system keeps its assembled matrix but not the pattern it was
/// assembled on (`SymbolicSystem::release_pattern`); what needs the pattern later builds it
/// again: another problem on the same symbolic system (the matrix and the solve of a system
/// built alone, bit for bit) and the direct fallback (the pattern of a direct system, and its
/// solution to round-off). A direct system keeps its pattern.
#[test]
fn a_released_pattern_is_built_again_where_it_is_needed() {
    use std::sync::Arc;
    let mesh = cartesian_triangles(24, 24, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&mesh).unwrap();
    let with = |linear| SystemOptions {
        linear,
        ..SystemOptions::default()
    };
    let (p, q) = (paper_test3(1.0), paper_test3(-10.0));
    let it = DiscreteSystem::new(&p1, &p, with(LinearSolver::Iterative)).unwrap();
    let direct = DiscreteSystem::new(&p1, &p, with(LinearSolver::Direct)).unwrap();
    assert!(it.condensed_pattern().is_none());
    // values in the order of a pattern it does not have: a typed error saying what to do
    let none = FixedValues::free(it.n_unknowns()).unwrap();
    match it.assemble_condensed(&mut SolveState::default(), &none) {
        Err(crate::Error::InvalidData(m)) => assert!(m.contains("SymbolicSystem::new"), "{m}"),
        other => panic!("{:?}", other.map(|(v, _)| v.len())),
    }
    let (dc, dr) = direct.condensed_pattern().unwrap();
    assert_eq!((it.nnz(), it.factor_len()), (dr.len(), 0));
    assert!(direct.factor_len() > 0);
    // another problem on the released symbolic system
    let shared = DiscreteSystem::with_symbolic(Arc::clone(it.symbolic()), &q).unwrap();
    let alone = DiscreteSystem::new(&p1, &q, with(LinearSolver::Iterative)).unwrap();
    assert_eq!(
        bits(&shared.full_matrix_triplets()),
        bits(&alone.full_matrix_triplets())
    );
    let n = it.n_unknowns();
    let fixed = FixedValues::from_options((0..n).map(|i| (i % 7 == 3).then_some(0.01))).unwrap();
    let solve = |s: &DiscreteSystem, state: &mut SolveState| {
        let (u, _) = s.solve(state, &fixed).unwrap();
        u.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    };
    let fresh = SolveState::default;
    assert_eq!(solve(&shared, &mut fresh()), solve(&alone, &mut fresh()));
    // the direct fallback: the pattern of the direct system, and its solve
    let mut state = SolveState::default();
    let built = it.fallback_pattern(&mut state).unwrap();
    assert_eq!((built.col_ptr(), built.row_idx()), (dc, dr));
    // the same matrix and pattern, factorised apart: the same solution to round-off
    let (x, _) = it.solve(&mut state, &fixed).unwrap();
    let (y, _) = direct.solve(&mut fresh(), &fixed).unwrap();
    let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let gap = x
        .iter()
        .zip(&y)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(
        scale > 0.0 && gap <= 1e-12 * scale,
        "{gap:e} against {scale:e}"
    );
    // connected parts are read from the matrix
    let analysis = crate::solver::well_posed::analyse(&it, None).unwrap();
    assert!(analysis.floating.is_empty());
}

/// A sequence of iterative solves on one state whose fixed unknowns change a little each time:
/// the kept hierarchy is reused whole, its masked view of M made again in the rows the changed
/// unknowns touch (`DiscreteSystem::masked_rows_reusing`: the view `masked_rows` builds, row
/// for row, bit for bit) and its fine level updated in those rows; each solve agrees with the
/// direct one to the solver's tolerance.
#[test]
fn solves_that_reuse_a_hierarchy_in_the_changed_rows_solve_each_masked_system() {
    use super::iterative::{NextHierarchy, Reused};
    use crate::linalg::Rows;
    let mesh = cartesian_triangles(48, 48, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&mesh).unwrap();
    let p = paper_test3(-10.0);
    let with = |linear| SystemOptions {
        linear,
        ..Default::default()
    };
    let it = DiscreteSystem::new(&p1, &p, with(LinearSolver::Iterative)).unwrap();
    let direct = DiscreteSystem::new(&p1, &p, with(LinearSolver::Direct)).unwrap();
    let n = it.n_unknowns();
    // the k-th fixed set: the unknowns whose hash falls below 60 of 1000, and the first k of
    // three interior unknowns (one more each time: few enough to be corrected on a patch)
    let extra = [n / 2 + 7, n / 3 + 11, 2 * n / 3 + 5];
    let fixed = |k: usize| {
        FixedValues::from_options((0..n).map(|i| {
            ((i as u64 * 7919 + 13) % 1000 < 60 || extra[..k].contains(&i)).then_some(0.05)
        }))
        .unwrap()
    };
    // the path: after a first solve, the next one reuses the hierarchy whole and remasks
    let mut probe = SolveState::default();
    it.solve(&mut probe, &fixed(0)).unwrap();
    let f1 = fixed(1);
    let next = it.next_hierarchy(&mut probe, &f1, false).unwrap();
    assert!(matches!(
        next,
        NextHierarchy::Reuse {
            levels: Reused::Whole { .. },
            ..
        }
    ));
    let fx = it.fixed_values(&f1);
    let (view, next) = it.masked_rows_reusing(&fx, next).unwrap();
    let NextHierarchy::Reuse {
        levels: Reused::Rows { rows, .. },
        ..
    } = next
    else {
        panic!("not reused in the changed rows");
    };
    assert!(
        !rows.is_empty() && rows.len() < n / 4,
        "{} rows",
        rows.len()
    );
    let fresh = it.masked_rows(&fx).unwrap();
    for i in 0..n {
        let ((c0, v0), (c1, v1)) = (view.row(i), fresh.row(i));
        assert_eq!(c0, c1, "row {i}");
        let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(b(v0), b(v1), "row {i}");
    }
    // the right-hand side read from the view: the one read from M, bit for bit
    let a = it.values.assembled.as_ref().unwrap();
    let b = |v: Vec<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        b(it.masked_rhs_of_view(&view, &fx).unwrap()),
        b(it.masked_rhs(a, &fx).unwrap())
    );
    // the sequence: each solve the direct one's, the later ones with a reused hierarchy
    let mut state = SolveState::default();
    for k in 0..4 {
        let f = fixed(k);
        let (ui, t) = it.solve(&mut state, &f).unwrap();
        assert_eq!(t.reused, k > 0, "solve {k}");
        let (ud, _) = direct.solve(&mut SolveState::default(), &f).unwrap();
        let scale = ud.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let gap = ud
            .iter()
            .zip(&ui)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(gap <= 1e-8 * scale, "solve {k}: {gap:e} against {scale:e}");
    }
}
