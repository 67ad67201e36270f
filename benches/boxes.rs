//! Criterion benchmarks of box certificates (docs/boxes.md), against their
//! speed targets on the 2-core machine:
//!
//! * `box-certify/rigid-body-inertia-box`: a two-parameter rigid-body box
//!   certified whole (target: under 1 s);
//! * `box-certify/lagrange-top-map-depth-14`: the heavy-top map over `p`
//!   and `mgl` with its boundary resolved to 1/128 of the box's side
//!   (target: under 60 s);
//! * `box-check/...`: `check` of the same certificates (target: no slower
//!   than certifying).
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, Criterion};
use serde_json::{json, Value};
use std::hint::black_box;

fn fixture(name: &str) -> Value {
    let text = std::fs::read_to_string(format!("{}/../fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn cases() -> Vec<(&'static str, Value)> {
    let mut map = fixture("lagrange-top-fast.json");
    map["box"] = json!({"parameters": {"p": ["1", "3"], "mgl": ["1/2", "3/2"]}, "max_depth": 14});
    vec![("rigid-body-inertia-box", fixture("boxes/rigid-body-inertia-box.json")), ("lagrange-top-map-depth-14", map)]
}

fn boxes(c: &mut Criterion) {
    let mut group = c.benchmark_group("box-certify");
    group.sample_size(10);
    for (name, spec) in cases() {
        group.bench_function(name, |b| {
            b.iter(|| {
                let spec = spec::spec_from_value(black_box(spec.clone())).unwrap();
                black_box(spec::box_cert::certify_box_spec(&spec))
            })
        });
    }
    group.finish();
    let mut group = c.benchmark_group("box-check");
    group.sample_size(10);
    for (name, spec) in cases() {
        let cert = spec::box_cert::certify_box_spec(&spec::spec_from_value(spec).unwrap());
        group.bench_function(name, |b| b.iter(|| black_box(spec::check_certificate_value(black_box(&cert)).unwrap())));
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = boxes
}
criterion_main!(benches);
