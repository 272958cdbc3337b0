use gradvi::problem::{by_name, file};
use std::time::Instant;

fn best<F: FnMut() -> f64>(mut f: F) -> (f64, f64) {
    let mut t = f64::INFINITY; let mut s = 0.0;
    for _ in 0..60 { let t0 = Instant::now(); s = f(); t = t.min(t0.elapsed().as_secs_f64()); }
    (t, s)
}

fn main() {
    let n = 50_000;
    let pts: Vec<[f64; 2]> = (0..n).map(|i| [((i % 1000) as f64 + 0.5) / 1000.0, ((i / 1000) as f64 + 0.5) / 1000.0]).collect();
    for name in ["test2", "test3", "fvca5-1.1"] {
        let r = by_name(name, &[]).unwrap();
        let f = file::builtin(name, &[]).unwrap().problem();
        for (lbl, p) in [("rust", &r), ("file", &f)] {
            let (ta, _) = best(|| pts.iter().map(|&x| (p.diffusion)(x)[0][1] + (p.diffusion)(x)[0][0]).sum());
            let (tf, _) = best(|| pts.iter().map(|&x| (p.source)(x)).sum());
            let (tb, _) = best(|| pts.iter().map(|&x| p.constraint.as_ref().map_or(0.0, |c| (c.barrier)(x))).sum());
            let (te, _) = best(|| pts.iter().map(|&x| p.exact.as_ref().map_or(0.0, |e| (e.u)(x))).sum());
            println!("{name} {lbl}: ns/point A {:.1} f {:.1} barrier {:.1} exact {:.1}", ta*1e9/n as f64, tf*1e9/n as f64, tb*1e9/n as f64, te*1e9/n as f64);
        }
    }
}
