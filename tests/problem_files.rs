//! Problem files (`problems/*.toml`, `gradvi::problem::file`): the built-in problems as files
//! reproduce the Rust closures bit for bit; every example file in `problems/` is solved with an
//! assertion that can fail; every bad file of `tests/data/problems/` gives its typed error,
//! naming the place.

mod common;

use common::assert_close;
use gradvi::Error;
use gradvi::case::build_mesh;
use gradvi::error::ProblemFileErrorKind as K;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{cartesian, hexagonal, kershaw};
use gradvi::mesh::io::read_mesh;
use gradvi::post::{fitted_slope, relative_errors};
use gradvi::problem::file::{self, MeshSpec, ProblemFile};
use gradvi::problem::{Problem, fvca5_test11, paper_test1, paper_test2, paper_test3};
use gradvi::scheme::{GradientDiscretisation, Hmm, P1};
use gradvi::solver::{Solution, SolveOptions, solve_problem};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn problems() -> PathBuf {
    root().join("problems")
}

/// The paper's cold start, so that the pinned NITER are those of its algorithm.
fn solve<'a>(scheme: &'a dyn GradientDiscretisation, p: &Problem) -> Solution<'a> {
    solve_problem(scheme, p, &SolveOptions::paper())
        .unwrap_or_else(|e| panic!("{} with {}: {e}", p.name, scheme.name()))
}

/// Solves the built-in problem and the file with `scheme` and compares them: same NITER, same
/// solution to 1e-12 relative (in practice, the same bits).
fn same_solution(scheme: &dyn GradientDiscretisation, builtin: &Problem, from_file: &Problem) {
    let a = solve(scheme, builtin);
    let b = solve(scheme, from_file);
    assert_eq!(a.niter(), b.niter(), "{}: NITER", builtin.name);
    let what = format!("{} with {}", builtin.name, scheme.name());
    assert_close(a.u(), b.u(), 1e-12, &what);
    assert_eq!(builtin.name, from_file.name);
}

#[test]
fn builtin_files_reproduce_the_rust_problems() {
    let hex = hexagonal(1).unwrap();
    let ker = kershaw(1).unwrap();
    type Case = (&'static str, Vec<(String, f64)>, &'static str);
    let cases: [Case; 5] = [
        ("test1", vec![], "meshes/test1_1.msh"),
        ("test2", vec![], "meshes/test2tri_1.msh"),
        ("test3", vec![], "meshes/test3_1.msh"),
        ("test3", vec![("C".into(), -20.0)], "meshes/test3_1.msh"),
        ("fvca5-1.1", vec![], "meshes/test3_1.msh"),
    ];
    for (name, params, tri) in cases {
        let builtin = rust_problem(name, &params);
        let pf = file::load(problems().join(format!("{name}.toml")), &params).unwrap();
        let embedded = file::builtin(name, &params).unwrap();
        assert_eq!(pf.name, embedded.name);
        let tri = read_mesh(root().join(tri), gradvi::budget::MemoryBudget::DEFAULT).unwrap();
        for mesh in [&hex, &ker, &tri] {
            pf.check_against_mesh(mesh).unwrap();
            same_solution(&Hmm::new(mesh), &builtin, &pf.problem());
        }
        same_solution(&P1::new(&tri).unwrap(), &builtin, &pf.problem());
    }
}

/// Points of (0,1)² where the data are compared: a grid with the boundary, points on and next
/// to the interface y = 1/2 of Test 2, and the centroids and edge midpoints of a hexagonal mesh
/// (some on the interface).
fn sample_points() -> Vec<[f64; 2]> {
    let mut pts = Vec::new();
    for i in 0..=40 {
        for j in 0..=40 {
            pts.push([i as f64 / 40.0, j as f64 / 40.0]);
        }
    }
    for d in [0.0, 1e-11, -1e-11, 1e-9, -1e-9, 1e-16] {
        pts.push([0.3, 0.5 + d]);
    }
    let m = hexagonal(2).unwrap();
    pts.extend((0..m.n_cells()).map(|k| m.centroid(k)));
    pts.extend((0..m.n_edges()).map(|e| m.edge_midpoint(e)));
    pts
}

/// The Rust problem the built-in file `name` must reproduce (the reference of these tests).
fn rust_problem(name: &str, params: &[(String, f64)]) -> Problem {
    match name {
        "test1" => paper_test1(),
        "test2" => paper_test2(),
        "test3" => paper_test3(params.first().map_or(-5.0, |p| p.1)),
        "fvca5-1.1" => fvca5_test11(),
        _ => panic!("no Rust reference for {name}"),
    }
}

/// The closures of the file and of the Rust problem give the same bits at every sample point.
#[test]
fn builtin_files_give_the_same_data_bits() {
    let pts = sample_points();
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
    for (name, _) in file::BUILTIN {
        let r = rust_problem(name, &[]);
        let f = file::builtin(name, &[]).unwrap().problem();
        assert_eq!(
            r.source_in_cell.is_some(),
            f.source_in_cell.is_some(),
            "{name}"
        );
        assert_eq!(r.exact.is_some(), f.exact.is_some(), "{name}");
        for &p in &pts {
            let (ar, af) = ((r.diffusion)(p), (f.diffusion)(p));
            assert!(
                (0..4).all(|i| same(ar[i / 2][i % 2], af[i / 2][i % 2])),
                "{name} A at {p:?}"
            );
            assert!(same((r.source)(p), (f.source)(p)), "{name} f at {p:?}");
            if let (Some(sr), Some(sf)) = (&r.source_in_cell, &f.source_in_cell) {
                for xk in [[0.5, 0.25], [0.5, 0.75], [0.1, 0.5]] {
                    assert!(same(sr(p, xk), sf(p, xk)), "{name} f({p:?}, {xk:?})");
                }
            }
            if p[0] == 0.0 || p[0] == 1.0 || p[1] == 0.0 || p[1] == 1.0 {
                assert_eq!(
                    (r.boundary)(p, 0),
                    (f.boundary)(p, 0),
                    "{name} boundary at {p:?}"
                );
            }
            assert!(
                same((r.dirichlet)(p), (f.dirichlet)(p)),
                "{name} u_D at {p:?}"
            );
            assert!(same((r.neumann)(p), (f.neumann)(p)), "{name} g_N at {p:?}");
            if let (Some(cr), Some(cf)) = (&r.constraint, &f.constraint) {
                assert_eq!((cr.kind, cr.side), (cf.kind, cf.side), "{name}");
                assert!(
                    same((cr.barrier)(p), (cf.barrier)(p)),
                    "{name} barrier at {p:?}"
                );
            }
            if let (Some(er), Some(ef)) = (&r.exact, &f.exact) {
                assert!(same((er.u)(p), (ef.u)(p)), "{name} u at {p:?}");
                let (gr, gf) = ((er.grad)(p), (ef.grad)(p));
                assert!(
                    same(gr[0], gf[0]) && same(gr[1], gf[1]),
                    "{name} grad u at {p:?}"
                );
            }
        }
    }
}

/// Contradictory or incomplete sections, found when loading: problem files, each followed by
/// a line `#> Kind: words the message contains`.
const SCHEMA_MISTAKES: &str = r#"
[obstacle]
side = "lower"
barrier = 0
[signorini]
side = "upper"
barrier = 0
#> Schema: one barrier
[dirichlet]
[neumann]
#> Schema: only one section may take the rest
[[source.piece]]
f = 1
[[source.piece]]
where = "x < 1"
f = 2
#> Schema: only the last piece
[source]
f = 1
piece = [{ f = 2 }]
#> Schema: either 'f' or
[diffusion]
A = [[1, 0], [0, 1], [0, 0]]
#> Schema: invalid length
[obstacle]
side = "above"
barrier = 0
#> Schema: unknown variant
[mesh]
generate = "cartesian"
#> Mesh: level
[mesh]
generate = "voronoi"
level = 1
#> Mesh: voronoi
name = "t{x}"
#> Expression: depends on x or y
"#;

#[test]
fn schema_mistakes_are_reported() {
    let mut text = String::new();
    for line in SCHEMA_MISTAKES.lines().skip(1) {
        let Some(expected) = line.strip_prefix("#> ") else {
            text.push_str(line);
            text.push('\n');
            continue;
        };
        let (kind, words) = expected.split_once(": ").unwrap();
        let e = file::parse(&text, Path::new("inline.toml"), &[]).unwrap_err();
        let Error::ProblemFile { kind: k, msg, .. } = &e else {
            panic!("{text:?}: not a problem-file error: {e}");
        };
        assert!(
            format!("{k:?}") == kind && msg.contains(words),
            "{text:?}: {e}"
        );
        text.clear();
    }
    assert!(
        text.is_empty(),
        "a case without its expected error: {text:?}"
    );
    // a scheme and a mesh file resolved against the problem file's folder
    let pf = file::parse(
        "scheme = \"p1\"\n[mesh]\nfile = \"m.msh\"",
        Path::new("dir/p.toml"),
        &[],
    )
    .unwrap();
    assert_eq!(pf.scheme, Some(gradvi::scheme::SchemeKind::P1));
    assert_eq!(
        pf.mesh,
        Some(MeshSpec::File(Path::new("dir").join("m.msh")))
    );
    assert_eq!(pf.name, "p");
}

// ------------------------------------------------------------------------------------------
// Bad files

/// Loads a bad file and checks it against its mesh; the first error.
fn first_error(name: &str) -> Error {
    let path = root().join("tests/data/problems").join(name);
    let pf = match file::load(&path, &[]) {
        Ok(pf) => pf,
        Err(e) => return e,
    };
    let mesh = match &pf.mesh {
        Some(spec) => build_mesh(spec, gradvi::budget::MemoryBudget::DEFAULT).unwrap(),
        None => cartesian(4, 4).unwrap(),
    };
    if let Err(e) = pf.check_against_mesh(&mesh) {
        return e;
    }
    match solve_problem(&Hmm::new(&mesh), &pf.problem(), &SolveOptions::default()) {
        Ok(_) => panic!("{name}: no error"),
        Err(e) => e,
    }
}

/// (file, kind, line, column, words the message must contain).
#[rustfmt::skip]
const BAD: [(&str, K, usize, usize, &[&str]); 16] = [
    ("syntax.toml",             K::Syntax,           5, 9,  &["string"]),
    ("unknown_key.toml",        K::UnknownKey,       3, 1,  &["unknown field `g`", "`f`"]),
    ("unknown_section.toml",    K::UnknownKey,       2, 2,  &["`sorce`", "`source`"]),
    ("bad_expression.toml",     K::Expression,       3, 21, &["source.f", "character 16", "')'"]),
    ("unknown_variable.toml",   K::Expression,       7, 34, &["obstacle.barrier", "character 23", "unknown variable 'z'"]),
    ("unknown_function.toml",   K::Expression,       3, 6,  &["source.f", "character 1", "unknown function 'sine'"]),
    ("type_error.toml",         K::Expression,       3, 10, &["dirichlet.where", "expected a condition"]),
    ("cyclic_definitions.toml", K::Parameter,        3, 5,  &["a, b", "cycle"]),
    ("cell_tags.toml",          K::Tag,              3, 8,  &["diffusion.piece[0].tags", "cell tag 10", "no cell of the mesh"]),
    ("tag_absent.toml",         K::Tag,              6, 8,  &["dirichlet.tags", "tag 7", "1, 2, 3"]),
    ("uncovered_edge.toml",     K::UncoveredEdge,    0, 0,  &["boundary edge 8", "(1, 0.5)", "tag 2"]),
    ("overlapping_rules.toml",  K::OverlappingRules, 0, 0,  &["[dirichlet] and [signorini]", "edge 0", "(0.25, 0)"]),
    ("not_spd.toml",            K::NotSpd,           6, 5,  &["diffusion.A", "cell 1", "x_K = (0.6666666666666666, 0.16666666666666666)"]),
    ("nan_value.toml",          K::NonFinite,        6, 5,  &["source.f", "NaN", "cell 0", "(0.3333333333333333, 0.16666666666666666)"]),
    ("infinite_barrier.toml",   K::NonFinite,        7, 11, &["obstacle.barrier", "-inf", "(0, 0), vertex 0"]),
    ("infeasible.toml",         K::Syntax,           0, 0,  &[]),
];

#[test]
fn bad_files_give_typed_errors_naming_the_place() {
    for (name, kind, line, column, words) in BAD {
        let e = first_error(name);
        if name == "infeasible.toml" {
            // the barrier below the Dirichlet data is the solver's check, reached through the file
            assert!(
                matches!(&e, Error::Infeasible(m) if m.contains("above the barrier 0.5")),
                "{e}"
            );
            continue;
        }
        let Error::ProblemFile {
            path,
            line: l,
            column: c,
            kind: k,
            msg,
        } = &e
        else {
            panic!("{name}: not a problem-file error: {e:?}");
        };
        assert_eq!((*k, *l, *c), (kind, line, column), "{name}: {e}");
        assert!(path.ends_with(name), "{name}: {e}");
        for w in words {
            assert!(msg.contains(w), "{name}: '{w}' not in: {e}");
        }
        // the displayed message starts with path:line:column
        if line > 0 {
            assert!(
                e.to_string().contains(&format!("{name}:{line}:{column}: ")),
                "{e}"
            );
        }
    }
}

#[test]
fn parameters_are_overridden_by_name_and_unknown_ones_rejected() {
    let p = file::builtin("test3", &[("c".into(), -40.0)]).unwrap();
    assert_eq!(p.parameter("C"), Some(-40.0));
    assert_eq!(p.name, "test3_C-40");
    let e = file::builtin("test3", &[("D".into(), 1.0)]).unwrap_err();
    assert!(
        matches!(&e, Error::ProblemFile { kind: K::Parameter, msg, .. } if msg.contains("'D'") && msg.contains("C")),
        "{e}"
    );
    let e = file::builtin("test1", &[("C".into(), 1.0)]).unwrap_err();
    assert!(e.to_string().contains("none"), "{e}");
    let e = file::builtin("test3", &[("C".into(), f64::NAN)]).unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
    assert!(file::builtin("test4", &[]).is_err());
}

// ------------------------------------------------------------------------------------------
// Example files: each is solved as a user would (mesh from its [mesh] section), with
// assertions that can fail.

/// The example `name` with its own mesh, checked.
fn example(name: &str) -> (ProblemFile, PolyMesh) {
    let pf = file::load(problems().join(format!("{name}.toml")), &[]).unwrap();
    let spec = pf.mesh.clone().expect("examples name their mesh");
    let mesh = build_mesh(&spec, gradvi::budget::MemoryBudget::DEFAULT).unwrap();
    pf.check_against_mesh(&mesh).unwrap();
    (pf, mesh)
}

/// Σ of the measures of the active constrained unknowns (the discrete contact set).
fn contact(sol: &Solution) -> f64 {
    let c = sol.constraints.as_ref().expect("a barrier");
    gradvi::post::contact::contact_measure(c, &sol.result.active)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

/// Solves the example with HMM and P1 and compares with pinned (NITER, contact measure, min
/// and max of the cell values); returns the two contact measures.
fn pinned_example(name: &str, pins: [(usize, f64, f64, f64); 2]) -> [f64; 2] {
    let (pf, mesh) = example(name);
    assert!(mesh.n_cells() < 3000, "{name}: keep example meshes small");
    let p = pf.problem();
    let hmm = Hmm::new(&mesh);
    let p1 = P1::new(&mesh).unwrap();
    let schemes: [&dyn GradientDiscretisation; 2] = [&hmm, &p1];
    let mut out = [0.0; 2];
    for (i, (s, (niter, area, min, max))) in schemes.into_iter().zip(pins).enumerate() {
        let sol = solve(s, &p);
        assert!(
            sol.result.certificate.check(1e-10).is_ok(),
            "{name} {}",
            s.name()
        );
        let cv = s.cell_values(sol.u());
        let lo = cv.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = cv.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let got = (sol.niter(), contact(&sol), lo, hi);
        assert!(
            got.0 == niter
                && close(got.1, area, 1e-9)
                && close(got.2, min, 1e-9)
                && close(got.3, max, 1e-9),
            "{name} {}: (NITER, contact, min, max) = {got:?}, pinned {:?}",
            s.name(),
            (niter, area, min, max)
        );
        out[i] = got.1;
    }
    out
}

#[test]
fn example_lshape_obstacle() {
    let [hmm, p1] = pinned_example(
        "lshape-obstacle",
        [
            (13, 1.6357166398752778, -0.2, -0.01230703362705595),
            (9, 1.6910144450695015, -0.2, -0.010353450987751292),
        ],
    );
    // the two schemes see the same contact set, up to the cells along its boundary
    assert!((hmm - p1).abs() < 0.05 * hmm, "{hmm} vs {p1}");
}

#[test]
fn example_hole_obstacle() {
    let [hmm, p1] = pinned_example(
        "hole-obstacle",
        [
            (
                8,
                2.561751657971214,
                0.0116794226157855,
                0.16047875146175722,
            ),
            (
                5,
                2.6441250456923253,
                0.00910225575735783,
                0.15946704082625596,
            ),
        ],
    );
    assert!((hmm - p1).abs() < 0.05 * hmm, "{hmm} vs {p1}");
}

#[test]
fn example_signorini_layers() {
    let [hmm, p1] = pinned_example(
        "signorini-layers",
        [
            (5, 0.6, -1.8609069699047651, 0.5846141354343068),
            (5, 0.625, -1.8424558244187814, 0.5847182724834001),
        ],
    );
    assert!((hmm - p1).abs() <= 0.05, "{hmm} vs {p1}");
    // contact only where the source pushes up (x < 1), never in the right material
    let (pf, mesh) = example("signorini-layers");
    let s = Hmm::new(&mesh);
    let sol = solve(&s, &pf.problem());
    let c = sol.constraints.as_ref().unwrap();
    for (d, a) in c.dofs.iter().zip(&sol.result.active) {
        let x = s.dof_point(d.dof);
        assert!(!a || x[0] < 1.0, "contact at {x:?}");
    }
}

/// Bueler's radial obstacle (PETSc ex9) on Cartesian meshes of (−2,2)² with n = 16, 32, 64,
/// 128 squares per side, HMM.
///
/// The exact solution is C^{1,1} but not C²: its second derivatives jump across the free
/// boundary r = a, so u ∈ H^{5/2−ε} and no better. On these Cartesian meshes HMM is
/// superconvergent for smooth solutions (order 2 for u and for the cell gradients at the
/// centroids); the free boundary limits both to about h^{3/2}. Measured fitted slopes: 1.53
/// (u) and 1.55 (∇u) on n = 16…128 (1.75 and 1.46 on 16…256, where the errors oscillate
/// as the free boundary crosses cells). Band: 1.5 ± 0.25. The contact set is a union of cells,
/// so its area misses O(h · perimeter): slope 1 ± 0.25 for |contact − πa²| (measured 1.06).
#[test]
fn example_ex9_converges() {
    let pf = file::load(problems().join("ex9.toml"), &[]).unwrap();
    let p = pf.problem();
    let ex = p.exact.as_ref().unwrap();
    let a: f64 = 0.697965148223374;
    let area = std::f64::consts::PI * a * a;
    let (mut h, mut eu, mut eg, mut ea) = (vec![], vec![], vec![], vec![]);
    for n in [16, 32, 64, 128] {
        let mesh = gradvi::mesh::generate::cartesian_rect(n, n, [-2.0, 2.0], [-2.0, 2.0]).unwrap();
        pf.check_against_mesh(&mesh).unwrap();
        let s = Hmm::new(&mesh);
        let sol = solve(&s, &p);
        assert!(sol.result.certificate.check(1e-10).is_ok());
        let e = relative_errors(&s, sol.u(), &ex.u, &ex.grad);
        h.push(mesh.h());
        eu.push(e.l2_u);
        eg.push(e.l2_grad);
        ea.push((contact(&sol) - area).abs());
    }
    let (su, sg, sa) = (
        fitted_slope(&h, &eu),
        fitted_slope(&h, &eg),
        fitted_slope(&h, &ea),
    );
    println!(
        "ex9: e_u {eu:?} slope {su:.3}; e_grad {eg:?} slope {sg:.3}; contact {ea:?} slope {sa:.3}"
    );
    assert!((su - 1.5).abs() <= 0.25, "slope of e_u {su}: {eu:?}");
    assert!((sg - 1.5).abs() <= 0.25, "slope of e_grad {sg}: {eg:?}");
    assert!(
        (sa - 1.0).abs() <= 0.25,
        "slope of the contact area error {sa}: {ea:?}"
    );
    assert!(eu[3] < 2e-4 && ea[3] < 0.06, "{eu:?} {ea:?}");
}

#[test]
fn example_ex9_with_its_own_mesh() {
    let (pf, mesh) = example("ex9");
    assert_eq!(
        pf.mesh,
        Some(MeshSpec::Generated {
            family: gradvi::mesh::generate::Family::Cartesian,
            level: 4,
            domain: Some(gradvi::mesh::Rect::new([-2.0, 2.0], [-2.0, 2.0])),
        })
    );
    assert_eq!(mesh.n_cells(), 32 * 32);
    assert_eq!(
        mesh.bounding_box(),
        gradvi::mesh::Rect::new([-2.0, 2.0], [-2.0, 2.0])
    );
    let p = pf.problem();
    let s = Hmm::new(&mesh);
    let sol = solve(&s, &p);
    let ex = p.exact.as_ref().unwrap();
    let e = relative_errors(&s, sol.u(), &ex.u, &ex.grad);
    // the same as cartesian_rect(32, 32) in example_ex9_converges
    assert!(close(e.l2_u, 1.4990e-3, 1e-4), "{}", e.l2_u);
}

/// The annotated example of problems/README.md loads, fits its mesh and solves.
#[test]
fn readme_example_is_a_valid_problem() {
    let readme = std::fs::read_to_string(problems().join("README.md")).unwrap();
    let start = readme.find("```toml\n").expect("a toml block") + 8;
    let text = &readme[start..start + readme[start..].find("```").unwrap()];
    let pf = file::parse(text, &problems().join("readme.toml"), &[]).unwrap();
    assert_eq!(pf.name, "membrane-C-5");
    assert_eq!(pf.scheme, Some(gradvi::scheme::SchemeKind::Hmm));
    let mesh = build_mesh(
        pf.mesh.as_ref().unwrap(),
        gradvi::budget::MemoryBudget::DEFAULT,
    )
    .unwrap();
    pf.check_against_mesh(&mesh).unwrap();
    let s = Hmm::new(&mesh);
    let sol = solve(&s, &pf.problem());
    assert!(sol.result.certificate.check(1e-10).is_ok());
    assert!(contact(&sol) > 0.0);
}

/// Cells carry the gmsh physical surface they belong to (format 4.1: the surface entity's
/// physical tag), and a piece selected by `tags` gives exactly the solution of the same piece
/// selected by `where`.
#[test]
fn pieces_by_cell_tag_equal_pieces_by_condition() {
    let (pf, mesh) = example("signorini-layers");
    for k in 0..mesh.n_cells() {
        let expected = if mesh.centroid(k)[0] < 1.0 { 1 } else { 2 };
        assert_eq!(mesh.cell_tag(k), expected, "cell {k}");
    }
    let text = std::fs::read_to_string(problems().join("signorini-layers.toml"))
        .unwrap()
        .replace("tags = [1]\nA = 1", "where = \"x < 1\"\nA = 1")
        .replace("tags = [2]\nA = [[10", "A = [[10");
    assert!(
        !text.contains("tags = [2]\nA"),
        "the rewrite must remove the cell tags"
    );
    let by_where = file::parse(&text, &problems().join("signorini-layers.toml"), &[]).unwrap();
    by_where.check_against_mesh(&mesh).unwrap();
    let (a, b) = (pf.problem(), by_where.problem());
    assert!(a.diffusion_by_tag.is_some() && b.diffusion_by_tag.is_none());
    for scheme in [
        &Hmm::new(&mesh) as &dyn GradientDiscretisation,
        &P1::new(&mesh).unwrap(),
    ] {
        same_solution(scheme, &a, &b);
    }
}

/// Format 2.2: a cell's tag is its first (physical) tag.
#[test]
fn gmsh22_cells_carry_their_physical_tag() {
    let mesh = read_mesh(
        root().join("tests/data/good/square_41_gmsh22.msh"),
        gradvi::budget::MemoryBudget::DEFAULT,
    )
    .unwrap();
    assert!(mesh.n_cells() > 0);
    for k in 0..mesh.n_cells() {
        assert_eq!(mesh.cell_tag(k), 10, "cell {k}");
    }
}

/// P1 needs triangles: ex9 on the generated `triangles` family, keeping the file's domain
/// (what `gradvi solve problems/ex9.toml --generate triangles --scheme p1` does). The mapped
/// mesh is exactly `cartesian_triangles(32, 32, [-2, 2], [-2, 2])`; P1 there is the five-point
/// Laplacian of PETSc's ex9 at the vertices.
#[test]
fn example_ex9_with_p1_on_generated_triangles() {
    use gradvi::mesh::generate::{Family, cartesian_triangles};
    let pf = file::load(problems().join("ex9.toml"), &[]).unwrap();
    let Some(MeshSpec::Generated { level, domain, .. }) = pf.mesh.clone() else {
        panic!("ex9 generates its mesh: {:?}", pf.mesh);
    };
    assert_eq!(
        (level, domain),
        (4, Some(gradvi::mesh::Rect::new([-2.0, 2.0], [-2.0, 2.0])))
    );
    let spec = MeshSpec::Generated {
        family: Family::Triangles,
        level,
        domain,
    };
    assert_eq!(spec.to_string(), "triangles level 4 on [-2, 2]x[-2, 2]");
    let mesh = build_mesh(&spec, gradvi::budget::MemoryBudget::DEFAULT).unwrap();
    let reference = cartesian_triangles(32, 32, [-2.0, 2.0], [-2.0, 2.0]).unwrap();
    assert_eq!(mesh.vertices(), reference.vertices());
    assert_eq!(mesh.n_cells(), 2 * 32 * 32);
    for k in 0..mesh.n_cells() {
        assert_eq!(
            mesh.cell_vertices(k),
            reference.cell_vertices(k),
            "cell {k}"
        );
    }
    pf.check_against_mesh(&mesh).unwrap();
    let p = pf.problem();
    let s = P1::new(&mesh).unwrap();
    let sol = solve(&s, &p);
    assert!(sol.result.certificate.check(1e-10).is_ok());
    let ex = p.exact.as_ref().unwrap();
    let e = relative_errors(&s, sol.u(), &ex.u, &ex.grad);
    let a: f64 = 0.697965148223374;
    let area = std::f64::consts::PI * a * a;
    println!(
        "ex9 P1 triangles level 4: NITER {}, e_u {:.4e}, e_grad {:.4e}, contact {:.4} (πa² = {area:.4})",
        sol.niter(),
        e.l2_u,
        e.l2_grad,
        contact(&sol)
    );
    assert!(close(e.l2_u, 5.3948e-3, 1e-3), "{}", e.l2_u);
    assert!(e.l2_grad < 0.05, "{}", e.l2_grad);
}

// ------------------------------------------------------------------------------------------
// 3D

/// The unit cube in cubes of level `level`, tagged as meshes/3d/signorini3d.geo tags it: cells
/// 1 (y < 1/2) and 2; boundary faces 10 (x = 0), 11 (x = 1), 12 (y = 0 or 1), 14 (z = 0),
/// 15 (z = 1).
fn signorini3d_cubes(level: usize) -> gradvi::mesh3d::PolyMesh3 {
    use gradvi::mesh3d::generate::Family3;
    let m = Family3::Cubes
        .generate(level, gradvi::budget::MemoryBudget::DEFAULT)
        .unwrap();
    let on = |a: f64, b: f64| (a - b).abs() < 1e-12;
    let m = m.with_boundary_tags(|x| match x {
        [x, _, _] if on(x, 0.0) => 10,
        [x, _, _] if on(x, 1.0) => 11,
        [_, y, _] if on(y, 0.0) || on(y, 1.0) => 12,
        [_, _, z] if on(z, 0.0) => 14,
        _ => 15,
    });
    let tags = (0..m.n_cells())
        .map(|k| if m.centroid(k)[1] < 0.5 { 1 } else { 2 })
        .collect();
    m.with_cell_tags(tags).unwrap()
}

/// The 3D Signorini example with its materials and boundary parts selected by cell and face
/// tags gives the same data and the same solution as with them selected by `where`; its
/// exact solution meets the data it was derived from.
#[test]
fn signorini_3d_by_tags_equals_by_conditions() {
    use gradvi::scheme::{SchemeKind, SchemeOptions, build_with3};
    let mesh = signorini3d_cubes(1);
    let path = problems().join("signorini-3d.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let by_tags = file::parse(&text, &path, &[]).unwrap();
    let rewritten = text
        .replace("tags = [1]\n", "where = \"y < 0.5\"\n")
        .replace("tags = [2]\n", "")
        .replace(
            "tags = [12, 15]",
            "where = \"y < 1e-9 or y > 1 - 1e-9 or z > 1 - 1e-9\"",
        )
        .replace("tags = [11, 14]", "where = \"x > 1 - 1e-9 or z < 1e-9\"")
        .replace("tags = [10]", "where = \"x < 1e-9\"");
    assert!(
        !rewritten.contains("tags ="),
        "the rewrite must remove every tag"
    );
    let by_where = file::parse(&rewritten, &path, &[]).unwrap();
    assert!(!by_tags.compiles_for(2) && by_tags.compiles_for(3));
    by_tags.check_against_mesh3(&mesh).unwrap();
    by_where.check_against_mesh3(&mesh).unwrap();
    let (a, b) = (
        by_tags.problem_in::<3>().unwrap(),
        by_where.problem_in::<3>().unwrap(),
    );
    assert!(a.diffusion_by_tag.is_some() && b.diffusion_by_tag.is_none());
    let scheme = build_with3(SchemeKind::Hmm, &mesh, &SchemeOptions { alpha: 1.0 }).unwrap();
    let opts = SolveOptions::paper();
    let (sa, sb) = (
        solve_problem(scheme.as_ref(), &a, &opts).unwrap(),
        solve_problem(scheme.as_ref(), &b, &opts).unwrap(),
    );
    assert_eq!(sa.niter(), sb.niter());
    assert_close(sa.u(), sb.u(), 1e-12, "signorini-3d, tags against where");
    assert!(sa.result.certificate.check(1e-10).is_ok());
    // ū against its derivation: the Signorini conditions on x = 0 and the Neumann flux on
    // z = 0 (−A₃₂ ∂ᵧū), at sample points
    let ex = a.exact.as_ref().unwrap();
    for &(y, z) in &[(0.2, 0.3), (0.45, 0.9), (0.7, 0.1), (0.9, 0.5)] {
        let u = (ex.u)([0.0, y, z]);
        assert!(
            u <= 0.0 && (y < 0.5 || u.abs() < 1e-15),
            "u(0, {y}, {z}) = {u}"
        );
        assert!((ex.grad)([0.0, y, z])[0].abs() < 1e-14);
        let g = (ex.grad)([0.4, y, 0.0]);
        let a32 = if y < 0.5 { 30.0 } else { 0.5 };
        assert!(
            ((a.neumann)([0.4, y, 0.0]) + a32 * g[1]).abs() < 1e-12,
            "flux at y = {y}"
        );
    }
}

/// Every 3D example compiles for 3D only or for both, and its exact gradient is the gradient
/// of its exact solution (central differences at sample points).
#[test]
fn exact_gradients_of_the_3d_examples_are_gradients() {
    for name in ["ex9-3d", "disk-obstacle-3d", "signorini-3d", "poisson-3d"] {
        let pf = file::load(problems().join(format!("{name}.toml")), &[]).unwrap();
        let p = pf.problem_in::<3>().unwrap();
        let ex = p.exact.as_ref().unwrap();
        for x in [[0.31, 0.62, 0.17], [0.83, 0.44, 0.56], [0.12, 0.91, 0.73]] {
            let g = (ex.grad)(x);
            for d in 0..3 {
                let (mut xp, mut xm) = (x, x);
                xp[d] += 1e-6;
                xm[d] -= 1e-6;
                let fd = ((ex.u)(xp) - (ex.u)(xm)) / 2e-6;
                assert!(
                    (fd - g[d]).abs() < 1e-6 * (1.0 + g[d].abs()),
                    "{name} {x:?} {d}"
                );
            }
        }
    }
}

/// A tag of a 3D file that no boundary face carries, named with the file's place.
#[test]
fn absent_tags_on_3d_meshes_are_reported() {
    let mesh = signorini3d_cubes(1);
    let pf = file::parse(
        "[dirichlet]\ntags = [99]\n[neumann]\n",
        Path::new("t.toml"),
        &[],
    )
    .unwrap();
    let e = pf.check_against_mesh3(&mesh).unwrap_err();
    let said = e.to_string();
    assert!(
        said.contains("t.toml:2:8: dirichlet.tags: tag 99 is on no boundary face of the mesh (its boundary tags: 10, 11, 12, 14, 15)"),
        "{said}"
    );
}
