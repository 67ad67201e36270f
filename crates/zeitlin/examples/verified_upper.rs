//! The verified upper bound on Sigma^2 against the Lanczos value, with the
//! energy forced (`casimir_momentum: false`), for `z + 0.3 z^3` and noise
//! `0.1 z^2`: `cargo run --release -p zeitlin --example verified_upper [N...]`.
use zeitlin::analysis::{analyse, ZeitlinProblem, ZeitlinSettings};
use zeitlin::zonal::quantise;

fn main() {
    let ns: Vec<usize> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let ns = if ns.is_empty() { vec![8, 16, 32, 64, 128] } else { ns };
    let settings = ZeitlinSettings { casimir_momentum: false, energy_search_max_n: 4096, ..Default::default() };
    println!("{:>5} {:>14} {:>14} {:>10} {:>16} {:>8}", "N", "Sigma^2", "upper", "upper/S-1", "level", "seconds");
    for n in ns {
        let omega = quantise(n, |z| z + 0.3 * z * z * z).diagonal;
        let noise = vec![quantise(n, |z| 0.1 * z * z).diagonal];
        let t = std::time::Instant::now();
        let a = analyse(&ZeitlinProblem { n, omega, noise }, &settings).expect("valid problem");
        let (s, u) = (a.sigma2.unwrap_or(f64::NAN), a.sigma2_upper.unwrap_or(f64::NAN));
        println!(
            "{n:>5} {s:>14.6e} {u:>14.6e} {:>10.2e} {:>16} {:>8.3}",
            u / s - 1.0,
            a.level.as_str(),
            t.elapsed().as_secs_f64()
        );
    }
}
