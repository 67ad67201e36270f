//! Criterion benchmark of ensemble throughput (path-steps per second) with
//! the Lie–Heun scheme on the rigid body and the heavy top. The numpy
//! comparison is `bench/simulate_side_by_side.sh`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use simulate::{run_ensemble, EnsembleSettings, Model, Observable, Scheme, Target};
use std::hint::black_box;

fn ensembles(c: &mut Criterion) {
    let mut group = c.benchmark_group("ensemble");
    let (paths, steps) = (4096usize, 250u64);
    group.throughput(Throughput::Elements(paths as u64 * steps));
    for (dim, name) in [(3, "rigid-body-major-axis"), (6, "heavy-top-asymmetric")] {
        let text = std::fs::read_to_string(format!("{}/../fixtures/{name}.json", env!("CARGO_MANIFEST_DIR"))).unwrap();
        let spec = spec::parse_spec(&text).unwrap();
        let model = Model::new(&spec.system);
        let mu0: Vec<f64> = spec.system.equilibrium().iter().map(|x| exact::rational_to_f64(x) + 0.01).collect();
        for scheme in [Scheme::LieHeun, Scheme::Heun] {
            let settings = EnsembleSettings {
                paths,
                dt: 1e-3,
                t_end: steps as f64 * 1e-3,
                outputs: 5,
                seed: 1,
                observable: Observable { index: 0, lo: -5.0, hi: 5.0, bins: 20 },
                norm: None,
                epsilon: None,
            };
            group.bench_with_input(BenchmarkId::new(format!("{name}-{}", scheme.as_str()), dim), &settings, |b, s| {
                b.iter(|| {
                    let target = Target::Nonlinear { model: &model, scheme, mu0: mu0.clone() };
                    black_box(run_ensemble(&target, s, &|_| {}).unwrap())
                })
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // criterion's own charts would need plotters' system-font backend; the
    // numbers are what matters here.
    config = Criterion::default().without_plots();
    targets = ensembles
}
criterion_main!(benches);
