//! Criterion benchmark of one fluid x-mode: the Lanczos estimate of Sigma^2
//! (walls: banded operators in vorticity coordinates; periodic: dense
//! Cholesky) and the dense verified check, grouped by the number of unknowns.
//! The scipy comparison on the same matrices is `bench/fluid_side_by_side.sh`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use fluid::analysis::chosen_form;
use fluid::modes::Mode;
use std::hint::black_box;

fn load(name: &str, ny: usize) -> spec::FluidSpec {
    let text =
        std::fs::read_to_string(format!("{}/../fixtures/fluids/{name}.json", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut s = spec::parse_fluid_spec(&text).unwrap();
    s.problem.ny = ny;
    s
}

fn modes(c: &mut Criterion) {
    let mut group = c.benchmark_group("fluid-mode");
    group.sample_size(20);
    for (name, ny) in [("channel-sin-walls", 256), ("channel-sin-walls", 1024), ("kolmogorov-periodic", 256)] {
        let spec = load(name, ny);
        let (grid, coef, form) = chosen_form(&spec.problem).unwrap();
        let k = 2.0 * std::f64::consts::PI / spec.problem.x_period;
        let mode = Mode::new(&grid, k);
        group.bench_with_input(BenchmarkId::new(format!("{name}-lanczos"), grid.n()), &mode, |b, m| {
            b.iter(|| black_box(m.sigma2(&form, &coef, 1e-10).unwrap()))
        });
        let s = mode.sigma2(&form, &coef, 1e-10).unwrap().lambda_max;
        group.bench_with_input(BenchmarkId::new(format!("{name}-dense-check"), grid.n()), &mode, |b, m| {
            b.iter(|| black_box(m.verify(&form, &coef, s * (1.0 + 1e-8))))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // criterion's own charts need a plotting backend we do not ship
    config = Criterion::default().without_plots();
    targets = modes
}
criterion_main!(benches);
