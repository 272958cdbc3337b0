use gradvi::mesh::generate::cartesian;
use gradvi::problem::{Problem, by_name, file};
use rayon::prelude::*;
use std::time::Instant;

fn time(p: &Problem, pts: &[[f64; 2]], par: bool) -> (f64, f64) {
    let t = Instant::now();
    let s: f64 = if par {
        pts.par_iter().map(|&x| {
            let a = (p.diffusion)(x);
            let f = match &p.source_in_cell { Some(g) => g(x, x), None => (p.source)(x) };
            let b = p.constraint.as_ref().map_or(0.0, |c| (c.barrier)(x));
            a[0][0] + a[0][1] + f + b
        }).sum()
    } else {
        pts.iter().map(|&x| {
            let a = (p.diffusion)(x);
            let f = match &p.source_in_cell { Some(g) => g(x, x), None => (p.source)(x) };
            let b = p.constraint.as_ref().map_or(0.0, |c| (c.barrier)(x));
            a[0][0] + a[0][1] + f + b
        }).sum()
    };
    (t.elapsed().as_secs_f64(), s)
}

fn main() {
    let t = Instant::now();
    let mesh = cartesian(1000, 1000).unwrap();
    println!("mesh {} cells in {:.2}s, threads {}", mesh.n_cells(), t.elapsed().as_secs_f64(), rayon::current_num_threads());
    let pts: Vec<[f64; 2]> = (0..mesh.n_cells()).map(|k| mesh.centroid(k)).collect();
    for name in ["test2", "test3", "fvca5-1.1"] {
        let rust = by_name(name, &[]).unwrap();
        let pf = file::builtin(name, &[]).unwrap();
        let fp = pf.problem();
        for rep in 0..2 {
            let (tr, sr) = time(&rust, &pts, false);
            let (tf, sf) = time(&fp, &pts, false);
            let (tfp, _) = time(&fp, &pts, true);
            if rep == 1 {
                println!("{name}: A+f+barrier at 1e6 centroids: rust closures {:.1} ms, file sequential {:.1} ms, file parallel {:.1} ms (sums equal: {})", tr*1e3, tf*1e3, tfp*1e3, sr.to_bits()==sf.to_bits());
            }
        }
        let t = Instant::now();
        pf.check_against_mesh(&mesh).unwrap();
        println!("{name}: check_against_mesh {:.1} ms", t.elapsed().as_secs_f64()*1e3);
    }
    let pf = file::load("problems/ex9.toml", &[]).unwrap();
    let m = file::map_unit_square(&mesh, [-2.0, 2.0, -2.0, 2.0]).unwrap();
    let pts: Vec<[f64; 2]> = (0..m.n_cells()).map(|k| m.centroid(k)).collect();
    let fp = pf.problem();
    let _ = time(&fp, &pts, false);
    let (ts, _) = time(&fp, &pts, false);
    let (tp, _) = time(&fp, &pts, true);
    let t = Instant::now();
    pf.check_against_mesh(&m).unwrap();
    println!("ex9: A+f+barrier seq {:.1} ms par {:.1} ms; check_against_mesh {:.1} ms", ts*1e3, tp*1e3, t.elapsed().as_secs_f64()*1e3);
}
