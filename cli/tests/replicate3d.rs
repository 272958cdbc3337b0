//! The quick variant of the 3D part of the replication (`gradvi replicate --quick` runs it
//! after the 2D experiments): the CSV has one row per problem, scheme, family and level with
//! finite numbers, the report has a table per scheme and family and the measured orders, the
//! figures are PNG files.

use gradvi_cli::replication::three_d::{self, CASES, CSV, Row3d};
use gradvi_cli::replication::{Config, records::read_csv};
use std::path::{Path, PathBuf};

/// The repository: the workspace root, above this package.
fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

#[test]
fn quick_3d_replication_writes_csv_figures_and_report() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("replicate3d-test-{}", std::process::id()));
    let cfg = Config {
        out: out.clone(),
        meshes: root().join("meshes"),
        fvca5: None,
        paper: root().join("replication/paper"),
        quick: true,
    };
    let mut lines = 0;
    three_d::run(&cfg, &mut |_| lines += 1).unwrap();
    three_d::figures::plots_from_csv(&cfg, &CASES).unwrap();
    three_d::report::write(&cfg, root()).unwrap();

    let rows: Vec<Row3d> = read_csv(&out.join("results").join(CSV)).unwrap();
    let levels = three_d::levels(&cfg).count();
    let expected: usize = CASES.iter().map(|c| c.runs.len() * levels).sum();
    assert_eq!(rows.len(), expected);
    assert_eq!(lines, expected, "one progress line per solve");
    for case in &CASES {
        for &(kind, family) in case.runs {
            let of: Vec<&Row3d> = (rows.iter())
                .filter(|r| {
                    r.problem == case.name && r.scheme == kind.name() && r.family == family.name()
                })
                .collect();
            assert_eq!(of.len(), levels, "{} {kind} {family}", case.name);
            // finer levels have smaller h and smaller errors
            for w in of.windows(2) {
                assert!(w[1].h < w[0].h && w[1].err_grad < w[0].err_grad, "{w:?}");
            }
        }
    }
    for r in &rows {
        let numbers = [
            r.h,
            r.err_u,
            r.err_grad,
            r.contact_volume,
            r.certificate,
            r.time_s,
        ];
        assert!(numbers.iter().all(|x| x.is_finite()), "{r:?}");
        assert!(r.err_u > 0.0 && r.err_u < 1.0 && r.err_grad < 1.0, "{r:?}");
        assert!(r.certificate <= 1e-8, "{r:?}");
        // the obstacle problems touch, the linear one is one solve
        if r.problem == "poisson-3d" {
            assert_eq!((r.niter, r.n_active), (1, 0), "{r:?}");
        } else {
            assert!(r.n_active > 0 && r.contact_volume > 0.0, "{r:?}");
        }
    }

    let report = std::fs::read_to_string(out.join("REPORT-3D.md")).unwrap();
    assert!(
        !report.contains("NaN") && !report.contains(" inf"),
        "{report}"
    );
    assert!(report.contains("beyond the paper"));
    assert!(report.contains("HMM on warped") && report.contains("CR on kuhn"));
    assert!(report.contains("Measured orders against the theory"));
    // one convergence table per series, with a row per level
    let series: usize = CASES.iter().map(|c| c.runs.len()).sum();
    assert_eq!(report.matches("| level | h |").count(), series);
    for case in &CASES {
        let mut figs = vec![three_d::figures::errors_png(case.name)];
        if case.name != "poisson-3d" {
            figs.push(three_d::figures::slice_png(case.name));
        }
        for f in figs {
            assert!(report.contains(&f), "{f} not in the report");
            let bytes = std::fs::read(out.join("figures").join(&f)).unwrap();
            assert_eq!(&bytes[1..4], b"PNG", "{f}");
        }
    }
    std::fs::remove_dir_all(&out).ok();
}
