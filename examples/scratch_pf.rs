use gradvi::mesh::generate::cartesian_rect;
use gradvi::post::{contact::contact_measure, relative_errors};
use gradvi::problem::file;
use gradvi::scheme::{GradientDiscretisation, Hmm, P1};
use gradvi::solver::{SolveOptions, solve_problem};

fn main() {
    for name in ["lshape-obstacle", "hole-obstacle", "signorini-layers", "ex9"] {
        let pf = file::load(format!("problems/{name}.toml"), &[]).unwrap();
        let mesh = pf.mesh.as_ref().unwrap().build().unwrap();
        pf.check_against_mesh(&mesh).unwrap();
        let p = pf.problem();
        let hmm = Hmm::new(&mesh);
        let p1 = if mesh.is_triangular() { Some(P1::new(&mesh).unwrap()) } else { None };
        let mut schemes: Vec<&dyn GradientDiscretisation> = vec![&hmm];
        if let Some(p1) = &p1 { schemes.push(p1); }
        for s in schemes {
            let sol = solve_problem(s, &p, &SolveOptions::default()).unwrap();
            let c = sol.constraints.as_ref().unwrap();
            let cm = contact_measure(c, &sol.result.active);
            let cv = s.cell_values(sol.u());
            let mn = cv.iter().cloned().fold(f64::INFINITY, f64::min);
            let mx = cv.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            println!("{name} {} cells {} niter {} contact {cm:.17e} min {mn:.17e} max {mx:.17e} cert {:?}", s.name(), mesh.n_cells(), sol.niter(), sol.result.certificate.check(1e-10).is_ok());
        }
    }
    let pf = file::load("problems/ex9.toml", &[]).unwrap();
    let p = pf.problem();
    let ex = p.exact.as_ref().unwrap();
    for n in [8usize, 16, 32, 64, 128, 256] {
        let mesh = cartesian_rect(n, n, [-2.0, 2.0], [-2.0, 2.0]).unwrap();
        pf.check_against_mesh(&mesh).unwrap();
        let s = Hmm::new(&mesh);
        let sol = solve_problem(&s, &p, &SolveOptions::default()).unwrap();
        let e = relative_errors(&s, sol.u(), &ex.u, &ex.grad);
        let c = sol.constraints.as_ref().unwrap();
        let cm = contact_measure(c, &sol.result.active);
        println!("ex9 n {n} h {} niter {} eu {:.4e} eg {:.4e} contact {cm:.5} exact {:.5}", mesh.h(), sol.niter(), e.l2_u, e.l2_grad, std::f64::consts::PI * 0.697965148223374f64.powi(2));
    }
}
