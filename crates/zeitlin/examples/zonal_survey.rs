//! Verdicts of the stochastic Zeitlin model for a few zonal profiles at
//! several N (the table in docs/zeitlin.md):
//! `cargo run --release -p zeitlin --example zonal_survey`.
use zeitlin::analysis::{analyse, ZeitlinProblem, ZeitlinSettings};
use zeitlin::zonal::quantise;

type Profile = (&'static str, fn(f64) -> f64);

fn main() {
    let profiles: [Profile; 5] = [
        ("z (solid-body rotation)", |z| z),
        ("z + 0.3 z^3 (monotone)", |z| z + 0.3 * z * z * z),
        ("z^3 (= l=3 harmonic in a rotating frame)", |z| z * z * z),
        ("P_2(z) (pure harmonic)", |z| 1.5 * z * z - 0.5),
        ("exp(-(z/0.3)^2) (jet)", |z| (-(z / 0.3).powi(2)).exp()),
    ];
    println!(
        "{:<42} {:>5} {:<18} {:>12} {:>12} {:>8}",
        "profile omega(z), noise xi = 0.1 z^2", "N", "verdict", "Sigma^2", "growth", "seconds"
    );
    for (name, f) in profiles {
        for n in [16usize, 32, 64, 128] {
            let omega = quantise(n, f).diagonal;
            let noise = vec![quantise(n, |z| 0.1 * z * z).diagonal];
            let t = std::time::Instant::now();
            let a = analyse(&ZeitlinProblem { n, omega, noise }, &ZeitlinSettings::default()).expect("valid problem");
            let show = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4e}"));
            println!(
                "{:<42} {:>5} {:<18} {:>12} {:>12} {:>8.3}",
                name,
                n,
                a.verdict.as_str(),
                show(a.sigma2),
                show(a.growth_rate),
                t.elapsed().as_secs_f64()
            );
        }
    }
}
