//! Criterion benchmarks of certification, grouped by dimension:
//!
//! * `certify/<spec>`: the whole path, spec text in, certificate JSON out
//!   (exact level: optimal Casimir choice, rational Sigma^2, exact spectral test);
//! * `analysis-exact/<spec>`: the analysis alone at the exact level;
//! * `analysis-exact-false/<spec>`: the analysis alone with the exact
//!   proofs switched off (`settings.exact = false`): floating-point
//!   Sigma^2, `P` still proved definite and formed exactly;
//! * `analysis-numeric/<spec>`: the numeric level in floating point
//!   throughout (`generator::analyse_numeric`, as `verify sweep --numeric`).
//!
//! The side-by-side numpy/scipy figure comes from `bench/side_by_side.sh`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

fn fixture(name: &str) -> String {
    std::fs::read_to_string(format!("{}/../fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

const SPECS: [(usize, &str); 4] = [
    (3, "rigid-body-major-axis"),
    (6, "heavy-top-asymmetric"),
    (6, "lagrange-top-fast"),
    (6, "lagrange-top-fluctuating-gravity"),
];

fn certify_pipeline(c: &mut Criterion) {
    let mut group = c.benchmark_group("certify");
    for (dim, name) in SPECS {
        let text = fixture(&format!("{name}.json"));
        group.bench_with_input(BenchmarkId::new(name, dim), &text, |b, text| {
            b.iter(|| {
                let spec = spec::parse_spec(black_box(text)).unwrap();
                black_box(spec::certify_lie(&spec).json)
            })
        });
    }
    group.finish();
    for (label, exact) in [("analysis-exact", true), ("analysis-exact-false", false)] {
        let mut group = c.benchmark_group(label);
        for (dim, name) in SPECS {
            let mut spec = spec::parse_spec(&fixture(&format!("{name}.json"))).unwrap();
            spec.settings.pipeline.exact = exact;
            group.bench_with_input(BenchmarkId::new(name, dim), &spec, |b, spec| {
                b.iter(|| black_box(generator::analyse(&spec.system, &spec.settings.pipeline)))
            });
        }
        group.finish();
    }
    let mut group = c.benchmark_group("analysis-numeric");
    for (dim, name) in SPECS {
        let spec = spec::parse_spec(&fixture(&format!("{name}.json"))).unwrap();
        group.bench_with_input(BenchmarkId::new(name, dim), &spec, |b, spec| {
            b.iter(|| black_box(generator::analyse_numeric(&spec.system, &spec.settings.pipeline)))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // criterion's own charts would need plotters' system-font backend; the
    // numbers are what matters here.
    config = Criterion::default().without_plots();
    targets = certify_pipeline
}
criterion_main!(benches);
