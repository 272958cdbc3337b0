//! The iterative linear solver (multigrid-preconditioned conjugate gradients) inside the
//! active-set method: the same certified solution as the direct solver, on obstacle and
//! Signorini problems, with HMM, P1 and CR, cold and nested; and the automatic choice.

use crate::common::*;
use gradvi::assembly::{AUTO_ITERATIVE_MIN, LinearSolver, SolveState, SystemOptions};
use gradvi::mesh::generate::{cartesian, cartesian_triangles, hexagonal};
use gradvi::problem::*;
use gradvi::scheme::*;
use gradvi::solver::*;
use gradvi::vi::FixedValues;

fn opts(linear: LinearSolver, warm_start: WarmStart) -> SolveOptions {
    SolveOptions {
        warm_start,
        system: SystemOptions {
            linear,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Direct and iterative solves of `p`: both certified at 1e-10, the same active set, u equal
/// to 1e-8 relative (the conjugate gradients stop at a relative residual of 1e-12), and the
/// iterative one reports its Krylov iterations. Returns the iterative solution.
fn same_solution<'a>(
    s: &'a dyn GradientDiscretisation,
    p: &Problem,
    ws: WarmStart,
) -> Solution<'a> {
    let d = solve_problem(s, p, &opts(LinearSolver::Direct, ws)).unwrap();
    let i = solve_problem(s, p, &opts(LinearSolver::Iterative, ws)).unwrap();
    d.result.certificate.check(1e-10).unwrap();
    i.result.certificate.check(1e-10).unwrap();
    assert_eq!(d.result.active, i.result.active, "{} {}", p.name, s.name());
    assert_eq!(d.niter(), i.niter(), "{} {}", p.name, s.name());
    assert_close(
        d.u(),
        i.u(),
        1e-8,
        &format!("{} {} direct vs iterative", p.name, s.name()),
    );
    assert!(d.result.log.iter().all(|l| l.timings.krylov == 0));
    let krylov: usize = i.result.log.iter().map(|l| l.timings.krylov).sum();
    assert!(
        krylov >= i.niter(),
        "{krylov} CG iterations for {} solves",
        i.niter()
    );
    assert_eq!(
        (i.system.factor_len(), i.factor_len),
        (0, 0),
        "no Cholesky factor with the iterative solver"
    );
    i
}

/// HMM on rectangles with a diagonal tensor is the two-point flux scheme: its iterative solves
/// take the cell system (`assembly::two_point`: faces eliminated instead of cells) and give the
/// direct solver's solution, on non-dyadic rectangles, with a heterogeneous diagonal tensor,
/// with Dirichlet and Neumann data (exact on an affine solution), and with Signorini faces
/// (whose solves with fixed faces take the skeleton system); on other meshes, or with an
/// off-diagonal tensor, the skeleton system is kept.
#[test]
fn hmm_on_rectangles_solves_on_the_cells() {
    let rect = rect_grid(30, 45, 1.0, 1.0);
    let hmm = Hmm::new(&rect);
    let nc = Some(rect.n_cells());
    let diag = |p: Problem| p.with_diffusion(Box::new(|x| [[1.0 + x[0], 0.0], [0.0, 0.3 + x[1]]]));
    for ws in [WarmStart::Cold, WarmStart::Nested] {
        let s = same_solution(&hmm, &diag(paper_test3(-20.0)), ws);
        assert_eq!(s.cell_system.map(|c| c.0), nc);
    }
    let s = same_solution(&hmm, &diag(paper_test1()), WarmStart::Cold);
    assert_eq!(s.cell_system.map(|c| c.0), nc);
    // ū = 1 + 2x − 3y, A = diag(1.5, 0.7): Dirichlet left and bottom, its flux elsewhere
    let (a, g) = ([[1.5, 0.0], [0.0, 0.7]], [2.0, -3.0]);
    let affine = affine_problem_with(a);
    let s = same_solution(&hmm, &affine, WarmStart::Cold);
    assert_eq!(s.cell_system.map(|c| c.0), nc);
    let exact: Vec<f64> = (0..rect.n_cells())
        .map(|k| {
            let x = rect.centroid(k);
            1.0 + g[0] * x[0] + g[1] * x[1]
        })
        .collect();
    let cells: Vec<f64> = (0..rect.n_cells())
        .map(|k| s.u()[hmm.cell_dof(k)])
        .collect();
    assert_close(&exact, &cells, 1e-10, "affine solution on the cells");
    // not two-point: an off-diagonal tensor, a hexagonal mesh
    let full = paper_test3(-20.0).with_diffusion(Box::new(|_| ANISOTROPIC));
    let s = same_solution(&hmm, &full, WarmStart::Cold);
    assert_eq!(s.cell_system.map(|c| c.0), None);
    let hex = hexagonal(3).unwrap();
    let hmm = Hmm::new(&hex);
    let s = same_solution(&hmm, &paper_test3(-10.0), WarmStart::Cold);
    assert_eq!(s.cell_system.map(|c| c.0), None);
}

/// Squares whose boundary sides are cut into collinear faces (the coarse meshes of the warm
/// start on a triangulated grid): the faces of the inner squares are eliminated, those coupled
/// with another skeleton unknown in some cell (the boundary cells' free faces) stay in the
/// cell system beside the cells; same solution as the direct solver, with Dirichlet, Neumann
/// and Signorini data, exact on an affine solution (HMM reproduces it on any mesh).
#[test]
fn hmm_solves_on_the_cells_and_the_coupled_faces() {
    let tri = cartesian_triangles(96, 80, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let agg = gradvi::mesh::agglomerate::agglomerate(&tri, 0.05).unwrap();
    let mesh = &agg.mesh;
    assert_eq!(agg.dissolved_cells, 0);
    let hmm = Hmm::new(mesh);
    let nc = mesh.n_cells();
    let check = |s: &Solution, what: &str| {
        let (n, kept) = s.cell_system.expect(what);
        assert_eq!(n, nc + kept, "{what}");
        assert!(
            kept > 0 && n < s.system.n_condensed(),
            "{what}: {kept} faces kept for {nc} cells"
        );
    };
    for ws in [WarmStart::Cold, WarmStart::Nested] {
        check(&same_solution(&hmm, &paper_test3(-20.0), ws), "test 3");
    }
    // Signorini on the bottom side: the cell system is built and the solution is the direct
    // one (in this case no solve fixes a kept face: those that fix a face take the skeleton
    // system)
    check(
        &same_solution(&hmm, &paper_test1(), WarmStart::Cold),
        "test 1",
    );
    let g = [2.0, -3.0];
    let s = same_solution(
        &hmm,
        &affine_problem_with([[1.5, 0.0], [0.0, 0.7]]),
        WarmStart::Cold,
    );
    check(&s, "affine");
    let exact: Vec<f64> = (0..s.u().len())
        .map(|d| match hmm.dof_entity(d) {
            Entity::Cell(k) => mesh.centroid(k),
            Entity::Edge(e) => mesh.edge_midpoint(e),
            Entity::Vertex(v) => mesh.vertex(v),
        })
        .map(|x| 1.0 + g[0] * x[0] + g[1] * x[1])
        .collect();
    assert_close(&exact, s.u(), 1e-10, "affine solution, cells and faces");
}

#[test]
fn iterative_gives_the_direct_solution() {
    let mesh = cartesian(48, 48).unwrap();
    let hmm = Hmm::new(&mesh);
    same_solution(&hmm, &paper_test3(-20.0), WarmStart::Cold);
    same_solution(&hmm, &paper_test1(), WarmStart::Cold);
    let tri = cartesian_triangles(40, 40, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&tri).unwrap();
    same_solution(&p1, &paper_test3(-10.0), WarmStart::Nested);
    same_solution(&p1, &paper_test1(), WarmStart::Cold);
    let cr = build(SchemeKind::Cr, &tri).unwrap();
    same_solution(cr.as_ref(), &paper_test3(-10.0), WarmStart::Cold);
    let hex = hexagonal(3).unwrap();
    let hmm = Hmm::new(&hex);
    same_solution(&hmm, &paper_test3(-10.0), WarmStart::Nested);
}

#[test]
fn multigrid_iterations_stay_bounded_under_refinement() {
    // Poisson-type obstacle problem with P1 on 32², 64², 128² grids: the CG iterations per
    // solve must not grow like the condition number (h⁻², a factor 16 here); allow at most 2×
    let per_solve = |n: usize| {
        let tri = cartesian_triangles(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let p1 = P1::new(&tri).unwrap();
        let s = solve_problem(
            &p1,
            &paper_test3(-10.0),
            &opts(LinearSolver::Iterative, WarmStart::Cold),
        )
        .unwrap();
        s.result.certificate.check(1e-10).unwrap();
        let k: usize = s.result.log.iter().map(|l| l.timings.krylov).sum();
        k as f64 / s.niter() as f64
    };
    let (a, b) = (per_solve(32), per_solve(128));
    assert!(
        b <= 2.0 * a.max(5.0) && b <= 40.0,
        "CG iterations per solve: {a} at 32², {b} at 128²"
    );
}

#[test]
fn auto_picks_direct_on_small_systems() {
    let mesh = cartesian(16, 16).unwrap();
    let hmm = Hmm::new(&mesh);
    assert!(hmm.n_skeleton() < AUTO_ITERATIVE_MIN);
    let s = solve_problem(
        &hmm,
        &paper_test3(-5.0),
        &opts(LinearSolver::Auto, WarmStart::Cold),
    )
    .unwrap();
    // on squares the cell system takes the solves: its factor is the only one, the
    // skeleton system's factorisation was deferred and never needed
    assert!(s.system.symbolic().is_direct());
    assert!(s.cell_system.is_some());
    assert_eq!(s.system.factor_len(), 0);
    assert!(s.factor_len > 0);
    assert!(s.result.log.iter().all(|l| l.timings.krylov == 0));
    let tri = cartesian_triangles(12, 12, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let hmm = Hmm::new(&tri);
    let s = solve_problem(
        &hmm,
        &paper_test3(-5.0),
        &opts(LinearSolver::Auto, WarmStart::Cold),
    )
    .unwrap();
    assert!(s.system.factor_len() > 0 && s.factor_len == s.system.factor_len());
    assert!(s.result.log.iter().all(|l| l.timings.krylov == 0));
    assert_eq!(
        "iterative".parse::<LinearSolver>().unwrap(),
        LinearSolver::Iterative
    );
    assert!("gmres".parse::<LinearSolver>().is_err());
}

/// A screening solve stops early and is continued by `refine` with its hierarchy to the
/// full solve's answer; nothing is left to refine after that, after a direct solve, or after
/// a full solve; refining with other fixed unknowns is an error.
#[test]
fn screening_solves_are_refined_to_the_full_solution() {
    use gradvi::assembly::DiscreteSystem;
    let tri = cartesian_triangles(64, 64, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&tri).unwrap();
    let p = paper_test3(-10.0);
    let system = |linear| {
        DiscreteSystem::new(
            &p1,
            &p,
            SystemOptions {
                linear,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let n = p1.n_unknowns();
    // the unknowns of the left half fixed at 0.01
    let fixed = FixedValues::from_options((0..n).map(|i| (i % 64 < 32).then_some(0.01))).unwrap();
    let full = system(LinearSolver::Iterative);
    let st = &mut SolveState::default();
    let (reference, t) = full.solve(st, &fixed).unwrap();
    assert!(!t.inexact);
    assert!(full.refine(st, &fixed).unwrap().is_none());

    let it = system(LinearSolver::Iterative);
    let st = &mut SolveState::default();
    let (screened, t) = it.screen(st, &fixed).unwrap();
    assert!(t.inexact && t.krylov > 0);
    let other = FixedValues::from_options(fixed.iter().map(|f| f.map(|v| v + 1.0))).unwrap();
    assert!(it.refine(st, &other).is_err());
    // the mismatch consumed the kept solve (a second screen would start from its iterate):
    // screen again from the start, through a fresh state
    assert!(it.refine(st, &fixed).unwrap().is_none());
    let st = &mut SolveState::default();
    let (_, t) = it.screen(st, &fixed).unwrap();
    assert!(t.inexact);
    let (refined, more) = it
        .refine(st, &fixed)
        .unwrap()
        .expect("an inexact solve to refine");
    assert!(!more.inexact && more.krylov > 0 && more.factor == 0.0);
    let gap = |a: &[f64]| {
        a.iter()
            .zip(&reference)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    };
    assert!(gap(&screened) > 1e-12, "the screening solve stopped early");
    assert!(gap(&refined) < 1e-10, "refined: {:e}", gap(&refined));
    assert!(it.refine(st, &fixed).unwrap().is_none());

    let direct = system(LinearSolver::Direct);
    let st = &mut SolveState::default();
    let (u, t) = direct.screen(st, &fixed).unwrap();
    assert!(!t.inexact);
    assert!(gap(&u) < 1e-10);
    assert!(direct.refine(st, &fixed).unwrap().is_none());
}

/// Consecutive iterative solves reuse the coarse levels of the previous multigrid hierarchy
/// when at most `REUSE_MAX_CHANGED` of the unknowns changed status since the matrix it was
/// built for (counted from that matrix, over several solves; on a grid large enough for the
/// patch around the changes to be factorised), and build a new one otherwise or after
/// `release`; the solutions are those of fresh systems.
#[test]
fn multigrid_hierarchies_are_reused_when_few_unknowns_change() {
    use gradvi::assembly::{DiscreteSystem, REUSE_MAX_CHANGED};
    let tri = cartesian_triangles(256, 256, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&tri).unwrap();
    let p = paper_test3(-10.0);
    let system = || {
        DiscreteSystem::new(
            &p1,
            &p,
            SystemOptions {
                linear: LinearSolver::Iterative,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let n = p1.n_unknowns();
    let max = (REUSE_MAX_CHANGED * n as f64) as usize;
    assert!(max >= 4, "{n} unknowns allow {max} changes");
    // the unknowns below index `k` fixed at 0.01
    let fixed = |k: usize| -> FixedValues {
        FixedValues::from_options((0..n).map(|i| (i < k).then_some(0.01))).unwrap()
    };
    // the Dirichlet unknowns (boundary vertices) never change status: the changes are
    // counted over the free ones
    let free: Vec<bool> = (0..n)
        .map(|d| match p1.dof_entity(d) {
            Entity::Vertex(v) => {
                let x = tri.vertex(v);
                x[0] > 0.0 && x[0] < 1.0 && x[1] > 0.0 && x[1] < 1.0
            }
            _ => true,
        })
        .collect();
    // the index k such that [from, k) holds `c` free unknowns, or [k, from) if `down`
    let shift = |from: usize, c: usize, down: bool| {
        let (mut k, mut seen) = (from, 0);
        while seen < c {
            if down {
                k -= 1;
                seen += usize::from(free[k]);
            } else {
                seen += usize::from(free[k]);
                k += 1;
            }
        }
        k
    };
    let k0 = n / 2;
    let it = system();
    let mut state = SolveState::default();
    let check = |state: &mut SolveState, k: usize, reused: bool| {
        let (u, t) = it.solve(state, &fixed(k)).unwrap();
        assert_eq!(t.reused, reused, "k = {k}");
        let (reference, t) = system()
            .solve(&mut SolveState::default(), &fixed(k))
            .unwrap();
        assert!(!t.reused);
        let gap = u
            .iter()
            .zip(&reference)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(gap < 1e-10, "k = {k}: {gap:e}");
    };
    check(&mut state, k0, false);
    // a few more fixed, then a few fewer: reused, the changes counted from the first matrix
    check(&mut state, shift(k0, max / 2, false), true);
    check(&mut state, shift(k0, max, false), true);
    // one more than the bound from the first matrix: a new hierarchy
    let k1 = shift(k0, max + 1, false);
    check(&mut state, k1, false);
    check(&mut state, shift(k1, max / 2, true), true);
    // many changes: a new hierarchy
    check(&mut state, k0 + 20 * max, false);
    // after the iteration is over, nothing is kept
    state.release();
    check(&mut state, k0 + 20 * max, false);
}

/// The memory budget of the assembly is the caller's (`SystemOptions::budget`): the same
/// solve succeeds with a large budget and is refused, with the estimate, with a tiny one,
/// whatever memory the machine has free.
#[test]
fn a_solve_is_refused_beyond_the_callers_memory_budget() {
    let mesh = cartesian(16, 16).unwrap();
    let hmm = Hmm::new(&mesh);
    let p = paper_test3(-20.0);
    for ws in [WarmStart::Cold, WarmStart::Nested] {
        let mut o = opts(LinearSolver::Direct, ws);
        o.system.budget = gradvi::budget::MemoryBudget::new(u64::MAX);
        let sol = solve_problem(&hmm, &p, &o).unwrap();
        sol.result.certificate.check(1e-10).unwrap();
        o.system.budget = gradvi::budget::MemoryBudget::new(4096);
        match solve_problem(&hmm, &p, &o) {
            Err(e @ gradvi::Error::OutOfMemory { budget: 4096, .. }) => {
                assert!(
                    e.to_string().contains("more than the 4.0 KiB of memory"),
                    "{e}"
                )
            }
            other => panic!(
                "expected the budget error, got {:?}",
                other.map(|s| s.niter())
            ),
        }
    }
}

/// The residual on chosen rows (`residual_at`, what a screened iterate is evaluated by) has the
/// bits of the whole residual's rows, and the largest of their scales, on HMM (gathered from
/// the cells) and P1 (the assembled matrix), rows in any order and repeated; a row beyond the
/// system is an error.
#[test]
fn the_residual_on_chosen_rows_has_the_bits_of_the_whole_residual() {
    use gradvi::assembly::DiscreteSystem;
    let hex = hexagonal(3).unwrap();
    let tri = cartesian_triangles(12, 9, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let hmm = Hmm::new(&hex);
    let p1 = P1::new(&tri).unwrap();
    let p = paper_test3(-10.0);
    for s in [&hmm as &dyn GradientDiscretisation, &p1] {
        let sys = DiscreteSystem::new(s, &p, SystemOptions::default()).unwrap();
        let n = sys.n_unknowns();
        let u: Vec<f64> = (0..n)
            .map(|i| ((i * 37 % 101) as f64 - 50.0) / 7.0)
            .collect();
        let (r, scale) = sys.residual(&u).unwrap();
        let rows: Vec<usize> = (0..n).rev().step_by(3).chain([0, 0, n - 1]).collect();
        let (ra, sa) = sys.residual_at(&u, rows.len(), &|k| rows[k]).unwrap();
        assert_eq!(ra.len(), rows.len());
        for (k, &i) in rows.iter().enumerate() {
            assert_eq!(ra[k].to_bits(), r[i].to_bits(), "{} row {i}", s.name());
        }
        let max = rows.iter().map(|&i| scale[i]).fold(0.0, f64::max);
        assert_eq!(sa.to_bits(), max.to_bits(), "{}", s.name());
        let e = sys.residual_at(&u, 2, &|k| [1, n][k]).unwrap_err();
        assert!(e.to_string().contains(&format!("row {n}")), "{e}");
    }
}

/// An iterative obstacle solve with screening evaluates its screened iterates on the
/// constrained unknowns only: their log lines have no balance residual, the last (exact)
/// one has it, below the tolerance; the multipliers of a screened evaluation have the bits
/// of the whole one, which alone can pass a certificate check; and the solution is the
/// direct solver's, with the same active sets' count of solves.
#[test]
fn screened_iterates_are_evaluated_on_the_constrained_unknowns() {
    use gradvi::vi::certificate::{evaluate, evaluate_screened};
    let hex = hexagonal(5).unwrap();
    let hmm = Hmm::new(&hex);
    let p = paper_test3(-10.0);
    let sol = same_solution(&hmm, &p, WarmStart::Cold);
    let log = &sol.result.log;
    assert!(log.len() >= 3, "{} solves", log.len());
    let screened = log.iter().filter(|l| l.step.residual.is_none()).count();
    assert!(screened >= 1, "no screened iterate in {} solves", log.len());
    let last = log
        .last()
        .unwrap()
        .step
        .residual
        .expect("the last iterate is exact");
    assert!(last <= 1e-10, "{last:e}");

    // one screened iterate, evaluated both ways
    let cons = sol.constraints.as_ref().expect("an obstacle");
    let mut state = SolveState::default();
    let mut q = sol.system.with_state(&mut state);
    use gradvi::vi::QuadraticEnergy;
    let active: Vec<bool> = sol.result.active.clone();
    let fixed = cons.fixed(q.n_unknowns(), &active).unwrap();
    let (u, t) = q.screen_with_fixed(&fixed).unwrap();
    // hexagons have no cell system: the iterate is complete
    assert!(t.inexact && !t.partial);
    let full = evaluate(&q, Some(cons), &u, &active).unwrap();
    let part = evaluate_screened(&q, cons, &u, false).unwrap();
    assert!(part.screened && !full.screened);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&part.multiplier), bits(&full.multiplier));
    assert_eq!(part.scale_u.to_bits(), full.scale_u.to_bits());
    assert!(part.scale_r <= full.scale_r && part.scale_r > 0.0);
    assert!(part.certificate.balance_residual.is_nan());
    assert!(part.certificate.check(1e-3).is_err());
}

/// On rectangles a screened iterative solve of HMM solves the cell system and returns a
/// partial iterate: NaN at the eliminated faces and only there. Its faces recovered one by
/// one (`partial_values`) and all at once (`complete`) agree to the bit; its residual on the cell system (`partial_residual_at`) is the full system's residual
/// of the completed iterate up to rounding, and so are the multipliers of its screened
/// evaluation; a refinement returns a complete iterate; and the obstacle solve through such
/// iterates is the direct solver's (`same_solution`), with partial iterates in its log.
#[test]
fn screened_cell_solves_return_partial_iterates() {
    use gradvi::vi::QuadraticEnergy;
    use gradvi::vi::certificate::{evaluate, evaluate_screened};
    let rect = rect_grid(60, 45, 1.0, 1.0);
    let hmm = Hmm::new(&rect);
    let p = paper_test3(-20.0);
    let sol = same_solution(&hmm, &p, WarmStart::Cold);
    assert!(
        sol.result.log.iter().any(|l| l.timings.partial),
        "partial iterates in the log"
    );
    assert!(sol.result.log.last().is_some_and(|l| !l.timings.partial));
    let cons = sol.constraints.as_ref().expect("an obstacle");
    // the screened solve of the second active set of a cold start (the first: nothing fixed)
    let active: Vec<bool> = (0..cons.dofs.len())
        .map(|j| sol.result.active[j] && j % 3 != 0)
        .collect();
    let mut state = SolveState::default();
    let mut q = sol.system.with_state(&mut state);
    let n = q.n_unknowns();
    let fixed = cons.fixed(n, &active).unwrap();
    let (u, t) = q.screen_with_fixed(&fixed).unwrap();
    assert!(t.inexact && t.partial && t.krylov > 0);
    let unset: Vec<usize> = (0..n).filter(|&i| u[i].is_nan()).collect();
    let faces = rect.n_edges();
    let dirichlet = q.dirichlet().clone();
    let interior_faces = (0..faces).filter(|&s| !dirichlet.is_fixed(s)).count();
    assert_eq!(unset.len(), interior_faces, "every free face is eliminated");
    assert!(unset.iter().all(|&i| i < faces));
    // recovered as the complete iterate's
    let mut whole = u.clone();
    q.complete(&mut whole).unwrap();
    let all: Vec<usize> = (0..n).collect();
    let values = q.partial_values(&u, &all).unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&values), bits(&whole));
    assert!(whole.iter().all(|v| v.is_finite()));
    // the residual on the cell system, against the full one of the completed iterate
    let rows: Vec<usize> = cons.dofs.iter().map(|d| d.dof).collect();
    let (rp, sp) = q.partial_residual_at(&u, rows.len(), &|k| rows[k]).unwrap();
    let (rf, sf) = q.residual_at(&whole, rows.len(), &|k| rows[k]).unwrap();
    assert!(sp > 0.0 && sp <= sf, "scales {sp:e}, {sf:e}");
    let gap = rp
        .iter()
        .zip(&rf)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        gap <= 1e-13 * sf,
        "residual gap {gap:e} for the scale {sf:e}"
    );
    let max_r = rf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        max_r > 1e3 * gap,
        "the residual is not round-off: {max_r:e}"
    );
    let part = evaluate_screened(&q, cons, &u, true).unwrap();
    let full = evaluate(&q, Some(cons), &whole, &active).unwrap();
    let lgap = part
        .multiplier
        .iter()
        .zip(&full.multiplier)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(lgap <= 1e-13 * sf, "multipliers {lgap:e}");
    // a refinement is complete
    let (refined, more) = q
        .refine(&fixed)
        .unwrap()
        .expect("an inexact solve to refine");
    assert!(!more.inexact && !more.partial);
    assert!(refined.iter().all(|v| v.is_finite()));
    // a partial iterate of the wrong length is an error
    assert!(q.partial_values(&u[1..], &[0]).is_err());
}
