//! Criterion benchmark of sweeps: rigid-body points per second through
//! `sweep::run` (all threads, lines written to a sink), at the numeric level
//! (floating-point verdicts) and at the exact level. Criterion reports the
//! throughput in points per second (`Throughput::Elements`).
//!
//! The side-by-side figure against the numpy/scipy pipeline, and the memory
//! of a 10^6-point run, come from `bench/sweep_side_by_side.sh`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

fn sweep_points(c: &mut Criterion) {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/rigid-body-major-axis.json"))
        .unwrap();
    let spec = spec::parse_any_spec(&text).unwrap();
    // I2, I3 from 1/10 to 6 around I1 = 3: major, minor and intermediate axis.
    let ranges =
        vec![spec::ParamRange::parse("I2=1/10:6:100").unwrap(), spec::ParamRange::parse("I3=1/10:6:100").unwrap()];
    let plan = sweep::Plan::new(ranges, sweep::Sampling::Grid).unwrap();
    let mut group = c.benchmark_group("sweep-rigid-body");
    group.throughput(Throughput::Elements(plan.len()));
    group.sample_size(20);
    for (label, level) in [("numeric", sweep::Level::Numeric), ("exact", sweep::Level::Spec)] {
        let id = sweep::sweep_id(&spec, &plan, level);
        let ev = sweep::Evaluator::new(spec.clone(), vec!["I2".into(), "I3".into()], level).unwrap();
        group.bench_function(label, |b| {
            b.iter(|| {
                let mut sink = std::io::sink();
                black_box(
                    sweep::run(&ev, &plan, &id, sweep::Shard::ALL, &sweep::Done::none(), &mut sink, &|_| {}).unwrap(),
                )
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = sweep_points
}
criterion_main!(benches);
