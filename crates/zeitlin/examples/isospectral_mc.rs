//! The Gaussian jet `exp(-(z/0.3)^2)` in the nonlinear stochastic Zeitlin
//! model, integrated with the isospectral midpoint, against the certified
//! growth rate (tests/isospectral.rs, test 4, at more N):
//!
//! `cargo run --release -p zeitlin --example isospectral_mc [N ...]` (default 64 128).
//!
//! Per N: the fastest mode from `1e-9`, without noise, at `h = 3.2/N` and
//! `h/2` (the scheme's rate error goes like `(h N)^2`: see the test), the
//! fitted rate of `|W - W_e|_F` over `[1e-8, 1e-6]`, its Richardson
//! extrapolation, the certified rate, the Casimir drift and the time per
//! step; then, with zonal noise `0.1 z^2`, the slope of the mean over 8
//! paths (4 above N = 64) of `log |W - W_e|_F` over the second half of the
//! run, with its standard error (not certified).
use std::time::Instant;
use zeitlin::analysis::{analyse, ZeitlinProblem, ZeitlinSettings};
use zeitlin::isospectral::{diagonal_perturbation, fit_rate, path_rng, zonal_state, MidpointSettings, ZeitlinModel};
use zeitlin::zonal::quantise;

fn jet(z: f64) -> f64 {
    (-(z / 0.3f64).powi(2)).exp()
}

fn main() {
    let sizes: Vec<usize> = std::env::args().skip(1).map(|a| a.parse().expect("N")).collect();
    let sizes = if sizes.is_empty() { vec![64, 128] } else { sizes };
    let t_end = 50.0;
    let settings = MidpointSettings::default();
    for n in sizes {
        let omega = quantise(n, jet).diagonal;
        let a = analyse(&ZeitlinProblem { n, omega: omega.clone(), noise: vec![] }, &ZeitlinSettings::default())
            .expect("valid problem");
        let Some(certified) = a.growth_rate else {
            println!("N = {n}: no growth rate ({})", a.reason);
            continue;
        };
        let model = ZeitlinModel::new(n, vec![]).expect("N >= 2");
        let mode = model.fastest_growing_mode(&omega).expect("finite");
        let we = zonal_state(&omega);
        let pert = diagonal_perturbation(n, mode.m, &mode.vector).expect("a mode");
        let w0 = &we + &pert * nalgebra::Complex::new(1e-9 / pert.norm(), 0.0);
        println!("N = {n}: certified growth rate {certified:.8} (fastest mode on diagonal {})", mode.m);
        let mut rates = vec![];
        let h0 = 3.2 / n as f64;
        for h in [h0, h0 / 2.0] {
            let steps = (t_end / h).round() as usize;
            let (mut t, mut y) = (vec![], vec![]);
            let start = Instant::now();
            let s = model
                .run(&w0, h, steps, &mut path_rng(0, 0), &settings, |_, ti, w| {
                    t.push(ti);
                    y.push((w - &we).norm());
                })
                .expect("the step converges");
            let per_step = start.elapsed().as_secs_f64() / steps as f64;
            let rate = fit_rate(&t, &y, 1e-8, 1e-6).unwrap_or(f64::NAN);
            println!(
                "  h = {h:.5}: fitted {rate:.8} ({:+.2e} relative), Casimir drift {:.1e}, momentum drift {:.1e}, {:.1} iterations a step, {:.2} ms a step",
                (rate - certified) / certified,
                s.casimir_drift,
                s.momentum_drift,
                s.iterations_mean,
                per_step * 1e3
            );
            rates.push(rate);
        }
        let extrapolated = (4.0 * rates[1] - rates[0]) / 3.0;
        println!(
            "  error ratio {:.3} (second order: 4); Richardson {extrapolated:.8} ({:+.2e} relative)",
            (rates[0] - certified) / (rates[1] - certified),
            (extrapolated - certified) / certified
        );
        // With zonal noise: W_e stays an equilibrium of every path.
        let noisy = ZeitlinModel::new(n, vec![quantise(n, |z| 0.1 * z * z).diagonal]).expect("finite noise");
        let (paths, h) = (if n <= 64 { 8usize } else { 4 }, h0);
        let steps = (t_end / h).round() as usize;
        let t: Vec<f64> = (0..=steps).map(|k| k as f64 * h).collect();
        let half = steps / 2;
        let mut slopes = vec![];
        let mut drift = 0.0f64;
        let start = Instant::now();
        for p in 0..paths {
            let mut y = vec![];
            let s = noisy
                .run(&w0, h, steps, &mut path_rng(7, p as u64), &settings, |_, _, w| y.push((w - &we).norm()))
                .expect("the step converges");
            drift = drift.max(s.casimir_drift);
            // The slope of log|W - W_e| on this path (the mean of the
            // slopes is the slope of the mean of the logs).
            slopes.push(fit_rate(&t[half..], &y[half..], 0.0, f64::MAX).unwrap_or(f64::NAN));
        }
        let per_step = start.elapsed().as_secs_f64() / (paths * steps) as f64;
        let k = paths as f64;
        let mean = slopes.iter().sum::<f64>() / k;
        let sd = (slopes.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
        println!(
            "  noise 0.1 z^2, {paths} paths at h = {h:.5}: mean log|W - W_e| grows at {mean:.4} +- {:.4} (standard error) over t in [{:.0}, {t_end}] (not certified); Casimir drift {drift:.1e}, {:.2} ms a step",
            sd / k.sqrt(),
            t[half],
            per_step * 1e3
        );
    }
}
