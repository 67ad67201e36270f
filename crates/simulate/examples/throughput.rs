//! Path-steps per second of an ensemble on a spec (for profiling and the
//! side-by-side benchmark `bench/simulate_side_by_side.sh`):
//! `throughput SPEC [PATHS] [STEPS] [lie|heun]`. Prints one JSON line.
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: throughput SPEC [PATHS] [STEPS] [lie|heun]");
    let paths: usize = args.get(2).map_or(100_000, |s| s.parse().expect("PATHS"));
    let steps: u64 = args.get(3).map_or(1000, |s| s.parse().expect("STEPS"));
    let scheme = simulate::Scheme::from_name(args.get(4).map_or("lie", String::as_str)).expect("lie or heun");
    let spec = spec::parse_spec(&std::fs::read_to_string(path).expect("read spec")).expect("valid spec");
    let model = simulate::Model::new(&spec.system);
    let mu0: Vec<f64> = spec.system.equilibrium().iter().map(|x| exact::rational_to_f64(x) + 0.01).collect();
    let settings = simulate::EnsembleSettings {
        paths,
        dt: 1e-3,
        t_end: steps as f64 * 1e-3,
        outputs: 10,
        seed: 1,
        observable: simulate::Observable { index: 0, lo: -2.0, hi: 2.0, bins: 50 },
        norm: None,
        epsilon: None,
    };
    let t = std::time::Instant::now();
    let target = simulate::Target::Nonlinear { model: &model, scheme, mu0 };
    let stats = simulate::run_ensemble(&target, &settings, &|_| {}).expect("valid settings");
    let secs = t.elapsed().as_secs_f64();
    println!(
        "{{\"spec\": \"{}\", \"scheme\": \"{}\", \"paths\": {paths}, \"steps\": {steps}, \"seconds\": {secs:.3}, \"path_steps_per_second\": {:.4e}, \"casimir_drift\": {:e}, \"threads\": {}}}",
        spec.name,
        scheme.as_str(),
        paths as f64 * steps as f64 / secs,
        stats.casimir_drift,
        rayon::current_num_threads()
    );
}
