//! Criterion benchmark of one fluid x-mode: the Lanczos estimate of Sigma^2
//! (banded operators in vorticity coordinates), the banded verified check
//! (`fluid::walls_check`, `O(ny)`; walls and periodic grids) and the dense
//! verified check, grouped by
//! the number of unknowns; and one compressible mode (Lanczos, the banded
//! verified check, and the discrete SDE's own constant `lambda_max(Q_B, K)`).
//! The scipy comparison on the same matrices is `bench/fluid_side_by_side.sh`.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use fluid::analysis::chosen_form;
use fluid::barotropic::{BarotropicCoefficients, BarotropicMode, WallGrid};
use fluid::modes::Mode;
use fluid::walls_check::verify_walls;
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
    for (name, ny) in [
        ("channel-sin-walls", 256),
        ("channel-sin-walls", 1024),
        ("kolmogorov-periodic", 256),
        ("kolmogorov-periodic", 1024),
    ] {
        let spec = load(name, ny);
        let (grid, coef, form) = chosen_form(&spec.problem).unwrap();
        let k = 2.0 * std::f64::consts::PI / spec.problem.x_period;
        let mode = Mode::new(&grid, k);
        group.bench_with_input(BenchmarkId::new(format!("{name}-lanczos"), grid.n()), &mode, |b, m| {
            b.iter(|| black_box(m.sigma2(&form, &coef, 1e-10).unwrap()))
        });
        let s = mode.sigma2(&form, &coef, 1e-10).unwrap().lambda_max;
        // A margin the banded check proves at these sizes (docs/fluids.md §2).
        let bar = s * (1.0 + 1e-5);
        assert_eq!(verify_walls(&grid, k, &form, &coef, bar), (true, true));
        group.bench_with_input(BenchmarkId::new(format!("{name}-banded-check"), grid.n()), &mode, |b, _| {
            b.iter(|| black_box(verify_walls(&grid, k, &form, &coef, bar)))
        });
        group.bench_with_input(BenchmarkId::new(format!("{name}-dense-check"), grid.n()), &mode, |b, m| {
            b.iter(|| black_box(m.verify_dense(&form, &coef, s * (1.0 + 1e-8))))
        });
    }
    group.finish();
}

/// The paper's compressible flow: `U = -cos y` on `[-1, 1]`, `c_s = 2`,
/// shift `c = 1.2`, noise `0.3 sin y` with its compatible potential.
fn compressible(c: &mut Criterion) {
    let mut group = c.benchmark_group("compressible-mode");
    group.sample_size(20);
    for ny in [256, 1024] {
        let grid = WallGrid::new(-1.0, 1.0, ny);
        let y = grid.nodes();
        let u: Vec<f64> = y.iter().map(|y| -y.cos()).collect();
        let coef = BarotropicCoefficients {
            up: y.iter().map(|y| y.sin()).collect(),
            w: y.iter().zip(&u).map(|(y, u)| (u + 1.2) / y.cos()).collect(),
            eta: vec![y.iter().map(|y| 0.3 * y.sin()).collect()],
            eta_prime: vec![y.iter().map(|y| 0.3 * y.cos()).collect()],
            r_prime: vec![y.iter().zip(&u).map(|(y, u)| -u * 0.3 * y.cos()).collect()],
            u,
        };
        let mode = BarotropicMode::new(&grid, &coef, 1.0, 2.0, 1.2);
        let n = grid.unknowns();
        group.bench_with_input(BenchmarkId::new("lanczos", n), &mode, |b, m| {
            b.iter(|| black_box(m.sigma2(1e-10).unwrap()))
        });
        let s = mode.sigma2(1e-10).unwrap().lambda_max;
        assert_eq!(mode.verify(s * (1.0 + 1e-6)), (true, true));
        group.bench_with_input(BenchmarkId::new("banded-check", n), &mode, |b, m| {
            b.iter(|| black_box(m.verify(s * (1.0 + 1e-6))))
        });
        group.bench_with_input(BenchmarkId::new("discrete-sde-sigma2", n), &mode, |b, m| {
            b.iter(|| black_box(m.pointwise_noise_sigma2(1e-10).unwrap()))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // criterion's own charts need a plotting backend we do not ship
    config = Criterion::default().without_plots();
    targets = modes, compressible
}
criterion_main!(benches);
