//! Smoothed-aggregation multigrid + conjugate gradients against sparse Cholesky on model
//! problems: `make bench-amg` (`cargo bench --bench amg`; arguments after `--`: `quick`,
//! `kernels`, `sweep`, `schemes`, `schemes-sweep`, `setup`).
//!
//! For each matrix (5-point Poisson on n × n grids, the 7-point P1 stencil of a triangulated
//! grid, an anisotropic and a jump-coefficient diffusion, one with fixed unknowns as the
//! active-set solver makes them), it prints the multigrid setup time, the iterations and time
//! of PCG to ‖r‖ ≤ 1e-10 ‖b‖, the operator complexity, the memory of the hierarchy against
//! that of the matrix, and for the smaller sizes the time of a sparse Cholesky (faer, AMD;
//! symbolic + numeric + solve) on the same matrix.

use gradvi::assembly::{DiscreteSystem, SymbolicSystem, SystemOptions};
use gradvi::linalg::{
    Amg, AmgOptions, CholeskyWork, CsrMatrix, PcgOptions, Smoother, SpdPattern, pcg,
};
use gradvi::mesh::generate::{
    cartesian, cartesian_rect, cartesian_triangles, hexagonal_grid, kershaw,
};
use gradvi::problem::{Problem, paper_test2};
use gradvi::scheme::{GradientDiscretisation, Hmm, P1};
use std::time::Instant;

/// A symmetric matrix as its lower triangle in CSC form.
struct Lower {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

/// The lower CSC of −div(k ∇u) on an m × m grid of unknowns (Dirichlet boundary eliminated),
/// with the 5-point finite-volume stencil: the x-coupling of nodes p, q is kx·harm(k_p, k_q),
/// the y-coupling ky·harm(k_p, k_q). With `diag_coupling` the P1 stencil of the triangulation
/// by the diagonals (i, j)–(i+1, j+1) is used instead: same values, plus structurally present
/// zero couplings along the diagonals (7 entries per row).
fn grid(
    m: usize,
    kx: f64,
    ky: f64,
    coef: &dyn Fn(usize, usize) -> f64,
    diag_coupling: bool,
) -> Lower {
    let n = m * m;
    let id = |i: usize, j: usize| j * m + i;
    let harm = |a: f64, b: f64| 2.0 * a * b / (a + b);
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(4 * n);
    let mut values = Vec::with_capacity(4 * n);
    col_ptr.push(0);
    for j in 0..m {
        for i in 0..m {
            let c = coef(i, j);
            let nb = |ii: isize, jj: isize| -> f64 {
                if ii < 0 || jj < 0 || ii >= m as isize || jj >= m as isize {
                    c // boundary: the coefficient of the node itself
                } else {
                    harm(c, coef(ii as usize, jj as usize))
                }
            };
            let (ii, jj) = (i as isize, j as isize);
            let d = kx * (nb(ii - 1, jj) + nb(ii + 1, jj)) + ky * (nb(ii, jj - 1) + nb(ii, jj + 1));
            row_idx.push(id(i, j));
            values.push(d);
            if i + 1 < m {
                row_idx.push(id(i + 1, j));
                values.push(-kx * nb(ii + 1, jj));
            }
            if j + 1 < m {
                row_idx.push(id(i, j + 1));
                values.push(-ky * nb(ii, jj + 1));
                if diag_coupling && i + 1 < m {
                    row_idx.push(id(i + 1, j + 1));
                    values.push(0.0);
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    Lower {
        n,
        col_ptr,
        row_idx,
        values,
    }
}

/// Fixes the unknowns of the disc of radius 0.3 at the centre as the active-set solver does:
/// their rows and columns zeroed, a unit diagonal.
fn fix_disc(l: &mut Lower, m: usize) {
    let fixed = |k: usize| {
        let (i, j) = (k % m, k / m);
        let (x, y) = (
            (i as f64 + 0.5) / m as f64 - 0.5,
            (j as f64 + 0.5) / m as f64 - 0.5,
        );
        x * x + y * y < 0.09
    };
    for c in 0..l.n {
        for p in l.col_ptr[c]..l.col_ptr[c + 1] {
            let r = l.row_idx[p];
            if fixed(r) || fixed(c) {
                l.values[p] = if r == c { 1.0 } else { 0.0 };
            }
        }
    }
}

fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// Setup, solve and report one matrix; times are the best of `reps` runs (the machine may be
/// shared).
fn run(name: &str, l: &Lower, opts: &AmgOptions, cholesky: bool, reps: usize) {
    let t = Instant::now();
    let a = match CsrMatrix::from_lower_csc(l.n, &l.col_ptr, &l.row_idx, &l.values) {
        Ok(a) => a,
        Err(e) => return println!("{name}: {e}"),
    };
    let t_csr = t.elapsed().as_secs_f64();
    // b = A·(a field with all frequencies), x₀ = 0
    let n = l.n;
    let xs: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.37).sin() + 1.0).collect();
    let mut b = vec![0.0; n];
    a.spmv(&xs, &mut b).expect("lengths");
    let bn = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    let (mut t_setup, mut t_solve) = (f64::INFINITY, f64::INFINITY);
    let mut summary = None;
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        let amg = match Amg::new(&a, opts) {
            Ok(m) => m,
            Err(e) => return println!("{name}: {e}"),
        };
        // the cycle's vectors, allocated with the hierarchy
        let mut work = amg.work();
        t_setup = t_setup.min(t.elapsed().as_secs_f64());
        let mut x = vec![0.0; n];
        let t = Instant::now();
        let rep = pcg(
            &a,
            &amg,
            &mut work,
            &b,
            &mut x,
            &PcgOptions {
                rtol: 1e-10,
                atol: 0.0,
                max_iter: 500,
            },
        );
        t_solve = t_solve.min(t.elapsed().as_secs_f64());
        let (iters, res) = match rep {
            Ok(r) => (r.iterations.to_string(), r.residual_norm / bn),
            Err(e) => {
                eprintln!("{name}: {e}");
                (">max".to_string(), f64::NAN)
            }
        };
        summary = Some((
            iters,
            res,
            amg.n_levels(),
            amg.operator_complexity(),
            amg.memory_bytes() + work.memory_bytes(),
        ));
    }
    let Some((iters, res, levels, oc, mem)) = summary else {
        return;
    };
    let chol = if cholesky {
        let t = Instant::now();
        let p = SpdPattern::new(l.n, l.col_ptr.clone(), l.row_idx.clone()).expect("pattern");
        let mut work = CholeskyWork::new();
        let f = p.factor(&l.values, &mut work).expect("factor");
        let mut y = b.clone();
        f.solve_in_place(&mut y);
        format!("{:8.3}", t.elapsed().as_secs_f64())
    } else {
        "       -".into()
    };
    println!(
        "{name:<26} {n:>9} {levels:>3} {t_csr:6.3} {t_setup:6.3} {iters:>5} {t_solve:6.3} {:6.3} {oc:5.3} {:7.1} {:7.1} {:4.2} {res:8.1e} {chol}",
        t_setup + t_solve,
        mib(a.memory_bytes()),
        mib(mem),
        mem as f64 / a.memory_bytes() as f64,
    );
}

fn header() {
    println!(
        "{:<26} {:>9} {:>3} {:>6} {:>6} {:>5} {:>6} {:>6} {:>5} {:>7} {:>7} {:>4} {:>8} {:>8}",
        "matrix",
        "n",
        "lev",
        "csr s",
        "setup",
        "iter",
        "solve",
        "total",
        "OC",
        "A MiB",
        "AMG MiB",
        "×A",
        "‖r‖/‖b‖",
        "chol s"
    );
}

/// The condensed matrix of `scheme` and `problem` as the active-set solver assembles it, with
/// no unknown fixed but the Dirichlet ones.
fn scheme_matrix(scheme: &dyn GradientDiscretisation, problem: &Problem) -> gradvi::Result<Lower> {
    // through a symbolic system of its own, which keeps the pattern (a system built by
    // `DiscreteSystem::new` for an iterative solve of P1 or CR releases it)
    let sym = SymbolicSystem::new(scheme, SystemOptions::default())?;
    let sys = DiscreteSystem::with_symbolic(std::sync::Arc::new(sym), problem)?;
    let Some((col_ptr, row_idx)) = sys.condensed_pattern() else {
        return Err(gradvi::Error::Internal("no condensed pattern".into()));
    };
    let fixed = gradvi::vi::FixedValues::free(sys.n_unknowns())?;
    let (values, _) =
        sys.assemble_condensed(&mut gradvi::assembly::SolveState::default(), &fixed)?;
    Ok(Lower {
        n: sys.n_condensed(),
        col_ptr: col_ptr.to_vec(),
        row_idx: row_idx.to_vec(),
        values,
    })
}

/// −div(A∇u) = 1 with A the anisotropic tensor of eigenvalues 1 and 1e-3 along axes turned by
/// 30°, and Dirichlet conditions.
fn rotated_anisotropy() -> Problem {
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let (l1, l2) = (1.0, 1e-3);
    let a = [
        [l1 * c * c + l2 * s * s, (l1 - l2) * c * s],
        [(l1 - l2) * c * s, l1 * s * s + l2 * c * c],
    ];
    Problem::new("rotated-anisotropy", Box::new(|_| 1.0)).with_diffusion(Box::new(move |_| a))
}

/// The condensed matrices of the schemes on the generated and gmsh meshes.
fn schemes(opts: &AmgOptions) -> gradvi::Result<()> {
    type MeshFn = Box<dyn Fn() -> gradvi::Result<gradvi::mesh::PolyMesh>>;
    let cases: [(&str, MeshFn); 4] = [
        ("cartesian 512²", Box::new(|| cartesian(512, 512))),
        ("cartesian 724²", Box::new(|| cartesian(724, 724))),
        ("hexagonal 400", Box::new(|| hexagonal_grid(400))),
        ("kershaw 30", Box::new(|| kershaw(30))),
    ];
    for (name, mesh) in &cases {
        let mesh = mesh()?;
        let hmm = Hmm::new(&mesh);
        let small = mesh.n_cells() <= 300_000;
        for (pname, problem) in [
            ("test2", paper_test2()),
            ("rot-aniso", rotated_anisotropy()),
        ] {
            let l = scheme_matrix(&hmm, &problem)?;
            run(&format!("hmm {name} {pname}"), &l, opts, small, REPS);
        }
    }
    let mesh = gradvi::mesh::io::read_mesh(
        "meshes/test2tri_4.msh",
        gradvi::budget::MemoryBudget::DEFAULT,
    )?;
    let p1 = P1::new(&mesh)?;
    for (pname, problem) in [
        ("test2", paper_test2()),
        ("rot-aniso", rotated_anisotropy()),
    ] {
        let l = scheme_matrix(&p1, &problem)?;
        run(&format!("p1 test2tri_4 {pname}"), &l, opts, true, REPS);
    }
    Ok(())
}

/// Repetitions of each measurement (the best is kept).
const REPS: usize = 3;

/// The checkerboard of 8 × 8 blocks with coefficients 1 and 1000 on an m × m grid.
fn checkerboard(m: usize) -> impl Fn(usize, usize) -> f64 {
    move |i, j| {
        if (i * 8 / m + j * 8 / m).is_multiple_of(2) {
            1.0
        } else {
            1000.0
        }
    }
}

/// Times of the building blocks at 1024²: a product with A, one multigrid cycle.
fn kernels() {
    let l = grid(1024, 1.0, 1.0, &|_, _| 1.0, false);
    let a = CsrMatrix::from_lower_csc(l.n, &l.col_ptr, &l.row_idx, &l.values).expect("matrix");
    let x = vec![1.0; l.n];
    let mut y = vec![0.0; l.n];
    let best = |f: &mut dyn FnMut()| {
        let mut t_min = f64::INFINITY;
        for _ in 0..30 {
            let t = Instant::now();
            f();
            t_min = t_min.min(t.elapsed().as_secs_f64());
        }
        t_min
    };
    let t = best(&mut || a.spmv(&x, &mut y).expect("lengths"));
    println!(
        "y = A x at 1024²: {:.2} ms ({:.1} GB/s of matrix and vectors)",
        t * 1e3,
        (a.memory_bytes() + 16 * l.n) as f64 / t / 1e9
    );
    for (name, smoother) in [
        (
            "chebyshev 1",
            Smoother::Chebyshev {
                degree: 1,
                ratio: 30.0,
            },
        ),
        (
            "chebyshev 2",
            Smoother::Chebyshev {
                degree: 2,
                ratio: 30.0,
            },
        ),
        (
            "chebyshev 3",
            Smoother::Chebyshev {
                degree: 3,
                ratio: 30.0,
            },
        ),
        ("l1-gauss-seidel", Smoother::L1GaussSeidel),
        ("l1-jacobi", Smoother::L1Jacobi),
    ] {
        let amg = Amg::new(
            &a,
            &AmgOptions {
                smoother,
                ..AmgOptions::default()
            },
        )
        .expect("amg");
        let mut work = amg.work();
        let t = best(&mut || amg.apply(&x, &mut y, &mut work).expect("lengths"));
        println!("one V(1,1) cycle, {name}: {:.2} ms", t * 1e3);
    }
}

/// The multigrid variants measured by the sweeps, by name: "default", "theta X" (strength
/// threshold), "theta_P X" (prolongator-smoothing threshold), "cheb D" or "cheb D rR"
/// (Chebyshev of degree D on [λ/R, λ], R = 30 unless given), "gershgorin only" (no Lanczos
/// steps), "l1-jacobi", "l1-gs", "coarse N" (largest coarse level). An unknown name is
/// reported and left out.
fn variants(opts: &AmgOptions, names: &[&'static str]) -> Vec<(&'static str, AmgOptions)> {
    let one = |name: &str| -> Option<AmgOptions> {
        let o = *opts;
        let words: Vec<&str> = name.split_whitespace().collect();
        let num = |i: usize| words.get(i).and_then(|w| w.parse::<f64>().ok());
        Some(match words.as_slice() {
            ["default"] => o,
            ["theta", _] => AmgOptions {
                strength_threshold: num(1)?,
                ..o
            },
            ["theta_P", _] => AmgOptions {
                smoothing_threshold: num(1)?,
                ..o
            },
            ["cheb", d, rest @ ..] => {
                let ratio = match rest {
                    [] => 30.0,
                    [r] => r.strip_prefix('r')?.parse().ok()?,
                    _ => return None,
                };
                AmgOptions {
                    smoother: Smoother::Chebyshev {
                        degree: d.parse().ok()?,
                        ratio,
                    },
                    ..o
                }
            }
            ["gershgorin", "only"] => AmgOptions {
                spectral_steps: 0,
                ..o
            },
            ["l1-jacobi"] => AmgOptions {
                smoother: Smoother::L1Jacobi,
                ..o
            },
            ["l1-gs"] => AmgOptions {
                smoother: Smoother::L1GaussSeidel,
                ..o
            },
            ["coarse", n] => AmgOptions {
                max_coarse: n.parse().ok()?,
                ..o
            },
            _ => return None,
        })
    };
    names
        .iter()
        .filter_map(|&n| match one(n) {
            Some(o) => Some((n, o)),
            None => {
                println!("unknown variant {n:?}: left out");
                None
            }
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let has = |w: &str| args.iter().any(|a| a == w);
    println!("threads: {}", rayon::current_num_threads());
    if has("kernels") {
        return kernels();
    }
    let one = |_: usize, _: usize| 1.0;
    let opts = AmgOptions::default();
    if has("sweep") {
        let m = 1024;
        println!("\nvariants at {m}² (default: {opts:?}):");
        header();
        let mats = [
            ("poisson5", grid(m, 1.0, 1.0, &one, false)),
            ("aniso", grid(m, 0.01, 1.0, &one, false)),
            ("jump", grid(m, 1.0, 1.0, &checkerboard(m), false)),
        ];
        let variants = variants(
            &opts,
            &[
                "default",
                "theta 0",
                "theta 0.25",
                "theta_P 0",
                "theta_P 0.02",
                "theta_P 0.2",
                "theta_P 0.04",
                "cheb 1",
                "cheb 3",
                "cheb 2 r10",
                "gershgorin only",
                "l1-jacobi",
                "l1-gs",
                "coarse 300",
                "coarse 3000",
            ],
        );
        let only: Vec<&String> = args.iter().skip(2).collect();
        for (vname, o) in &variants {
            if !only.is_empty() && !only.iter().any(|w| w.as_str() == *vname) {
                continue;
            }
            for (mname, l) in &mats {
                run(&format!("{vname}/{mname}"), l, o, false, REPS);
            }
        }
        return;
    }
    if has("schemes-sweep") {
        header();
        let mk = |mesh: gradvi::Result<gradvi::mesh::PolyMesh>, p: Problem| -> Lower {
            let mesh = mesh.expect("mesh");
            scheme_matrix(&Hmm::new(&mesh), &p).expect("matrix")
        };
        let mats = [
            (
                "hmm cart rot",
                mk(cartesian(256, 256), rotated_anisotropy()),
            ),
            ("hmm kershaw test2", mk(kershaw(15), paper_test2())),
            ("hmm hex rot", mk(hexagonal_grid(200), rotated_anisotropy())),
        ];
        let variants = variants(
            &opts,
            &[
                "default",
                "theta 0",
                "theta 0.02",
                "theta 0.25",
                "theta_P 0",
                "theta_P 0.2",
                "cheb 3",
                "l1-jacobi",
            ],
        );
        for (vname, o) in &variants {
            for (mname, l) in &mats {
                run(&format!("{vname}/{mname}"), l, o, false, 1);
            }
        }
        return;
    }
    if has("setup") {
        // the matrices of the obstacle problems' active-set steps: the P1 stencil with a
        // disc of fixed unknowns (unit rows), 1024²; best of 7
        header();
        let mut l = grid(1024, 1.0, 1.0, &one, true);
        fix_disc(&mut l, 1024);
        run("p1-7pt fixed disc 1024²", &l, &opts, false, 7);
        // the condensed matrices of ex9's discretisations at 1025² nodes (no contact set)
        let laplace = || Problem::new("laplace", Box::new(|_| 1.0));
        let tri = cartesian_triangles(1024, 1024, [-2.0, 2.0], [-2.0, 2.0]).expect("mesh");
        let l = scheme_matrix(&P1::new(&tri).expect("p1"), &laplace()).expect("matrix");
        drop(tri);
        run("ex9 p1 1025²", &l, &opts, false, 7);
        drop(l);
        let rect = cartesian_rect(1024, 1024, [-2.0, 2.0], [-2.0, 2.0]).expect("mesh");
        let l = scheme_matrix(&Hmm::new(&rect), &laplace()).expect("matrix");
        drop(rect);
        run("ex9 hmm 1024²", &l, &opts, false, 7);
        return;
    }
    if has("schemes") {
        header();
        if let Err(e) = schemes(&opts) {
            println!("schemes: {e}");
        }
        return;
    }
    header();
    let sizes: &[usize] = if has("quick") {
        &[512, 1024]
    } else {
        &[512, 1024, 2048]
    };
    for &m in sizes {
        let l = grid(m, 1.0, 1.0, &one, false);
        run(&format!("poisson5 {m}²"), &l, &opts, m <= 1024, REPS);
    }
    let m = 1024;
    let l = grid(m, 1.0, 1.0, &one, true);
    run(&format!("p1-7pt {m}²"), &l, &opts, false, REPS);
    let l = grid(m, 0.01, 1.0, &one, false);
    run(&format!("aniso 0.01 {m}²"), &l, &opts, false, REPS);
    let l = grid(m, 1.0, 1.0, &checkerboard(m), false);
    run(&format!("jump 1e3 {m}²"), &l, &opts, false, REPS);
    let mut l = grid(m, 1.0, 1.0, &one, false);
    fix_disc(&mut l, m);
    run(&format!("fixed disc {m}²"), &l, &opts, false, REPS);
}
