//! Measurement aid for the linear-instability search: the eigenvalues of the
//! discretised Rayleigh operator `R` of one x-mode at each resolution.
//!
//! `cargo run --release -p fluid --example instability_rates -- U a b k [ny...]`
//! e.g. `"4/(exp(y)+exp(-y))^2" -8 8 1.9 128 256 512 1024 2048`.
//! Prints, per ny (dense eigenvalues, walls), the largest `k Im c`, how
//! many are above the instability floor, the five of largest `Im c` (`c`
//! the phase speed, `e^{ik(x - c t)}`) and the one nearest an argument
//! `re,im` if one is given; then the analysis's instability search (spec
//! `ny` 512, one x-mode of wavenumber `k`, no noise) grid by grid.
//! Measured with it: `analysis/instability.rs` docs.

use fluid::grid::{Boundary, YGrid};
use fluid::modes::Mode;
use fluid::profile::Profile;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let u = fluid::expr::parse(&args[0], &Default::default()).expect("U");
    let (a, b, k): (f64, f64, f64) = (args[1].parse().unwrap(), args[2].parse().unwrap(), args[3].parse().unwrap());
    let nys: Vec<usize> = args[4..].iter().filter(|s| !s.contains(',')).map(|s| s.parse().unwrap()).collect();
    // an argument `re,im` is a phase speed to report the nearest eigenvalue to
    let target: Option<(f64, f64)> = args[4..].iter().find(|s| s.contains(',')).map(|s| {
        let (re, im) = s.split_once(',').unwrap();
        (re.parse().unwrap(), im.parse().unwrap())
    });
    let profile = Profile::new(u, vec![], (a, b), Boundary::Walls);
    for ny in nys {
        let t = std::time::Instant::now();
        let grid = YGrid::new(Boundary::Walls, a, b, ny);
        let coef = profile.coefficients(&grid);
        let r = Mode::new(&grid, k).drift_matrix(&coef);
        let n = r.nrows();
        let m = faer::Mat::<f64>::from_fn(n, n, |i, j| r[(i, j)]);
        let mut values: Vec<(f64, f64)> = m.eigenvalues().unwrap().iter().map(|z| (z.re, z.im)).collect();
        values.sort_by(|p, q| q.1.total_cmp(&p.1));
        let secs = t.elapsed().as_secs_f64();
        println!("ny {ny} ({secs:.2} s): max k Im c = {:.10}", k * values[0].1);
        let floor = fluid::constants::INSTABILITY_FLOOR * k;
        let above = values.iter().filter(|v| k * v.1 > floor).count();
        println!("    {above} eigenvalues with k Im c above the floor {floor:.1e}; the five largest:");
        for (re, im) in values.iter().take(5) {
            println!("    c = {re:.10} + {im:.3e} i   k Im c = {:.10}", k * im);
        }
        if let Some(target) = target {
            let near = values.iter().min_by(|p, q| {
                let d = |v: &(f64, f64)| (v.0 - target.0).hypot(v.1 - target.1);
                d(p).total_cmp(&d(q))
            });
            if let Some((re, im)) = near {
                println!("    nearest to {target:?}: c = {re:.10} + {im:.10} i   k Im c = {:.10}", k * im);
            }
        }
    }
    let problem = fluid::analysis::FluidProblem {
        model: fluid::analysis::FluidModel::Incompressible,
        profile,
        x_period: 2.0 * std::f64::consts::PI / k,
        ny: 512,
        x_modes: 1,
    };
    let t = std::time::Instant::now();
    let a = fluid::analysis::analyse(&problem, &Default::default()).expect("analysis");
    println!("analysis ({:.2} s): {:?}: {}", t.elapsed().as_secs_f64(), a.verdict, a.reason);
    for s in &a.instability_search {
        println!("  m = {} k = {} floor {:.2e}: {}", s.m, s.k, s.floor, s.outcome.as_str());
        for g in &s.grids {
            println!(
                "    ny {:6} {} k Im c = {:?} Re c = {:?}",
                g.ny,
                if g.tracked { "tracked" } else { "dense  " },
                g.growth_rate,
                g.phase_speed
            );
        }
    }
}
