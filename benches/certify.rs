//! Criterion benchmark of the whole `certify` pipeline (spec text in,
//! certificate JSON out) on the rigid body and the heavy top, grouped by
//! dimension. The side-by-side numpy/scipy figure comes from
//! `bench/numpy_pipeline.py --bench N` on the same specs.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

fn fixture(name: &str) -> String {
    std::fs::read_to_string(format!("{}/../fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn certify_pipeline(c: &mut Criterion) {
    let mut group = c.benchmark_group("certify");
    for (dim, name) in
        [(3, "rigid-body-major-axis.json"), (6, "heavy-top-asymmetric.json"), (6, "lagrange-top-fast.json")]
    {
        let text = fixture(name);
        group.bench_with_input(BenchmarkId::new(name.trim_end_matches(".json"), dim), &text, |b, text| {
            b.iter(|| {
                let spec = spec::parse_spec(black_box(text)).unwrap();
                let cert = spec::certify(&spec);
                black_box(cert.json)
            })
        });
        // The same, excluding JSON parsing and certificate building.
        let spec = spec::parse_spec(&text).unwrap();
        group.bench_with_input(
            BenchmarkId::new(format!("{}-analysis-only", name.trim_end_matches(".json")), dim),
            &spec,
            |b, spec| b.iter(|| black_box(generator::analyse(&spec.system, &spec.settings.pipeline))),
        );
    }
    group.finish();
}

criterion_group!(benches, certify_pipeline);
criterion_main!(benches);
