//! One block's linear SDE (`zeitlin::block_sde`) against independent
//! computations: its drift against the commutators of the full matrices,
//! its `lambda_max(Q, M)` against the analysis's per-block values (a
//! bisection on the inertia of a banded lifting), its exact moment against
//! the moment equation solved by a Kronecker-product exponential, and the
//! Monte Carlo against the exact moment.

use nalgebra::{Complex, DMatrix, DVector};
use outcome::{Progress, Verdict};
use zeitlin::analysis::{analyse, hbar, ZeitlinProblem, ZeitlinSettings};
use zeitlin::block_sde::BlockSde;
use zeitlin::isospectral::zonal_state;
use zeitlin::laplacian::StreamSolver;
use zeitlin::zonal::quantise;

type C = Complex<f64>;

fn monotone(z: f64) -> f64 {
    z + 0.3 * z * z * z
}

/// The paper's family with noise a z^2: stable with the energy in the form.
fn problem(n: usize, a: f64) -> (Vec<f64>, Vec<Vec<f64>>, zeitlin::analysis::ZeitlinAnalysis) {
    let omega = quantise(n, monotone).diagonal;
    let xi = quantise(n, |z| a * z * z).diagonal;
    let settings = ZeitlinSettings { casimir_momentum: false, ..ZeitlinSettings::default() };
    let analysis = analyse(&ZeitlinProblem { n, omega: omega.clone(), noise: vec![xi.clone()] }, &settings).unwrap();
    assert_eq!(analysis.verdict, Verdict::Stable, "{}", analysis.reason);
    (omega, vec![xi], analysis)
}

#[test]
fn each_block_grows_at_the_analysis_lambda_max() {
    let n = 12;
    let (omega, noise, a) = problem(n, 2.0);
    let choice = a.choice.unwrap();
    for blk in &a.blocks {
        let sde = BlockSde::new(&omega, &noise, &choice, blk.m).unwrap();
        let (top, v) = sde.top().unwrap();
        // The analysis's value is the upper end of a bracket of relative
        // width blk.residual (1e-10 or so).
        assert!(
            (top - blk.lambda_max).abs() <= 1e-8 * blk.lambda_max.abs().max(1e-300),
            "m {}: {top} vs {}",
            blk.m,
            blk.lambda_max
        );
        let z: Vec<C> = v.iter().map(|x| C::new(*x, 0.0)).collect();
        assert!((sde.norm2(&z) - 1.0).abs() < 1e-12);
    }
    let largest = a.blocks.iter().map(|b| b.lambda_max).fold(f64::NEG_INFINITY, f64::max);
    assert!((largest - a.sigma2.unwrap()).abs() <= 1e-12 * largest);
}

/// `L z` against `([P_e, E] + [Delta^-1 E, W_e]) / hbar` formed from the
/// full matrices with the O(N^2) stream solve, entry by entry of diagonal m;
/// the noise as `[X, E] / hbar`.
#[test]
fn the_drift_and_noise_are_the_linearised_model_on_the_block() {
    let n = 9;
    let (omega, noise, a) = problem(n, 0.7);
    let choice = a.choice.unwrap();
    let stream = StreamSolver::new(n).unwrap();
    let we = zonal_state(&omega);
    let pe = stream.solve(&we).unwrap();
    let x = zonal_state(&noise[0]);
    let h = C::new(hbar(n), 0.0);
    for m in [1, 4, 8] {
        let sde = BlockSde::new(&omega, &noise, &choice, m).unwrap();
        let len = n - m;
        // z = (1, 2, ..., len) + i (0.5, ...): one column test of the whole map.
        let z: Vec<C> = (0..len).map(|j| C::new(1.0 + j as f64, 0.5 - 0.3 * j as f64)).collect();
        let mut e = DMatrix::<C>::zeros(n, n);
        for j in 0..len {
            e[(j, j + m)] = z[j];
            e[(j + m, j)] = -z[j].conj();
        }
        let full = (&pe * &e - &e * &pe + stream.solve(&e).unwrap() * &we - &we * stream.solve(&e).unwrap()) / h;
        let noisy = (&x * &e - &e * &x) / h;
        // The block's operators are private: they are checked through what
        // they imply, with L z and B z taken from the commutators.
        let lz: Vec<C> = (0..len).map(|j| full[(j, j + m)]).collect();
        let bz: Vec<C> = (0..len).map(|j| noisy[(j, j + m)]).collect();
        // The module's formula L = (i/hbar)(D_pi + D_omega G), G = -Delta_m^-1,
        // P_e = i diag(pi), against the commutators (the next test builds
        // the moment equation from this formula).
        let pi = zeitlin::laplacian::solve_zonal(&omega).unwrap();
        let lap = zeitlin::laplacian::block(n, m);
        let g = -DMatrix::from_fn(len, len, |i, j| lap.get(i, j)).try_inverse().unwrap();
        let gz = g.map(|x| C::new(x, 0.0)) * DVector::from_vec(z.clone());
        for j in 0..len {
            let formula = C::new(0.0, 1.0 / hbar(n)) * ((pi[j] - pi[j + m]) * z[j] + (omega[j] - omega[j + m]) * gz[j]);
            assert!((formula - lz[j]).norm() <= 1e-10 * lz.iter().map(|x| x.norm()).fold(0.0, f64::max), "m {m} j {j}");
            let noise_formula = C::new(0.0, (noise[0][j] - noise[0][j + m]) / hbar(n)) * z[j];
            assert!((noise_formula - bz[j]).norm() <= 1e-12 * bz.iter().map(|x| x.norm()).fold(0.0, f64::max));
        }
        // The drift conserves |z|_M^2: Re <z, M L z> = 0.
        let dz = DVector::from_vec(lz.clone());
        let zv = DVector::from_vec(z.clone());
        let mz = |v: &DVector<C>, w: &DVector<C>| {
            sde.norm2((v + w).as_slice()) - sde.norm2(v.as_slice()) - sde.norm2(w.as_slice())
        };
        assert!(mz(&zv, &dz).abs() <= 1e-10 * sde.norm2(&z).sqrt() * sde.norm2(&lz).sqrt(), "m {m}");
        // d/dt E|z|_M^2 = 2 Re <z, M A~ z> + |B z|_M^2, A~ = L + B^2 / 2 (B
        // diagonal: B^2 z = (bz / z) bz entrywise), against the exact
        // moment's slope at t = 0 (O(dt) from the curvature).
        let b2z: Vec<C> = (0..len).map(|j| bz[j] * bz[j] / z[j]).collect();
        let ito = DVector::from_vec(lz.iter().zip(&b2z).map(|(l, b)| l + b * 0.5).collect::<Vec<_>>());
        let slope = mz(&zv, &ito) + sde.norm2(&bz);
        let dt = 1e-6;
        let r = sde.exact_moment(&z, dt, 1, 1, &Progress::new()).unwrap();
        let numeric = (r[1] - 1.0) / dt * sde.norm2(&z);
        assert!((numeric - slope).abs() <= 1e-4 * slope.abs().max(1e-3 * sde.norm2(&z)), "m {m}: {numeric} vs {slope}");
    }
}

/// The exact moment of the split scheme against the moment equation solved
/// exactly (`vec(S)' = (L x I + I x conj(L) + noise) vec(S)` by nalgebra's
/// matrix exponential), at dt = 1e-3: O(dt^2) apart. And the bound: at most
/// exp(lambda_max t) from the top start.
#[test]
fn the_exact_moment_is_the_moment_equation_and_stays_under_the_bound() {
    let n = 7;
    let (omega, noise, a) = problem(n, 3.0);
    let choice = a.choice.unwrap();
    let h = hbar(n);
    for m in [1, 3] {
        let sde = BlockSde::new(&omega, &noise, &choice, m).unwrap();
        let len = n - m;
        let (top, v) = sde.top().unwrap();
        let z: Vec<C> = v.iter().map(|x| C::new(*x, 0.0)).collect();
        let (dt, steps) = (1e-3, 2000);
        let exact = sde.exact_moment(&z, dt, steps, 4, &Progress::new()).unwrap();
        // The moment equation's generator on vec(S), S_jk = E z_j conj(z_k),
        // with L = (i/hbar)(D_pi + D_omega G) built here (the previous test
        // ties that formula to the commutators of the full matrices).
        let pi = zeitlin::laplacian::solve_zonal(&omega).unwrap();
        let lap = zeitlin::laplacian::block(n, m);
        let g = -DMatrix::from_fn(len, len, |i, j| lap.get(i, j)).try_inverse().unwrap();
        let d = |f: &[f64]| DMatrix::from_diagonal(&DVector::from_iterator(len, (0..len).map(|j| f[j] - f[j + m])));
        let l = (d(&pi) + d(&omega) * &g).map(|x| C::new(0.0, x / h));
        let dx: Vec<f64> = (0..len).map(|j| (noise[0][j] - noise[0][j + m]) / h).collect();
        let eye = DMatrix::<C>::identity(len, len);
        // vec is column-major: vec(L S) = (I x L) vec S, vec(S L^*) = (conj(L) x I) vec S.
        let mut gen = eye.kronecker(&l) + l.map(|x| x.conj()).kronecker(&eye);
        for k in 0..len {
            for j in 0..len {
                gen[(k * len + j, k * len + j)] -= C::new(0.5 * (dx[j] - dx[k]).powi(2), 0.0);
            }
        }
        let s0 = DVector::from_iterator(
            len * len,
            (0..len).flat_map(|k| (0..len).map(move |j| (j, k))).map(|(j, k)| z[j] * z[k].conj()),
        );
        let form = {
            let mut f = DMatrix::<f64>::zeros(len, len);
            // |z|_M^2 = sum_jk M_kj S_jk: recover M from norm2 by polarisation.
            for j in 0..len {
                for k in 0..len {
                    let mut e = vec![C::new(0.0, 0.0); len];
                    e[j] += 1.0;
                    e[k] += 1.0;
                    let both = sde.norm2(&e);
                    let mut ej = vec![C::new(0.0, 0.0); len];
                    ej[j] = C::new(1.0, 0.0);
                    let mut ek = vec![C::new(0.0, 0.0); len];
                    ek[k] = C::new(1.0, 0.0);
                    f[(j, k)] = if j == k { sde.norm2(&ej) } else { (both - sde.norm2(&ej) - sde.norm2(&ek)) / 2.0 };
                }
            }
            f
        };
        let moment = |s: &DVector<C>| -> f64 {
            (0..len).flat_map(|k| (0..len).map(move |j| (j, k))).map(|(j, k)| form[(k, j)] * s[k * len + j].re).sum()
        };
        let start = moment(&s0);
        let every = steps / 4;
        for (i, r) in exact.iter().enumerate() {
            let t = (i * every) as f64 * dt;
            let st = (&gen * C::new(t, 0.0)).exp() * &s0;
            let truth = moment(&st) / start;
            assert!((r - truth).abs() <= 1e-5 * truth, "m {m} t {t}: scheme {r} vs equation {truth}");
            assert!(*r <= (top * t).exp() * (1.0 + 1e-5), "m {m} t {t}: {r} above exp({top} t)");
        }
    }
}

#[test]
fn the_monte_carlo_agrees_with_the_exact_moment() {
    let n = 8;
    let (omega, noise, a) = problem(n, 3.0);
    let choice = a.choice.unwrap();
    let sde = BlockSde::new(&omega, &noise, &choice, 2).unwrap();
    let (_, v) = sde.top().unwrap();
    let z: Vec<C> = v.iter().map(|x| C::new(*x, 0.0)).collect();
    let (dt, steps, outputs) = (0.01, 400, 8);
    let mc = sde.monte_carlo(&z, dt, steps, outputs, 4000, 3, &Progress::new()).unwrap();
    let exact = sde.exact_moment(&z, dt, steps, outputs, &Progress::new()).unwrap();
    assert_eq!(mc.times.len(), exact.len());
    assert_eq!(mc.mean[0], 1.0);
    for k in 1..exact.len() {
        assert!(
            (mc.mean[k] - exact[k]).abs() <= 4.0 * mc.std_error[k],
            "t {}: {} +- {} vs {}",
            mc.times[k],
            mc.mean[k],
            mc.std_error[k],
            exact[k]
        );
    }
    // A cancelled run stops with Cancelled, not a result.
    let cancelled = Progress::new();
    cancelled.cancel();
    assert_eq!(
        sde.monte_carlo(&z, dt, steps, outputs, 4000, 3, &cancelled),
        Err(zeitlin::isospectral::IsospectralError::Cancelled)
    );
    assert_eq!(
        sde.exact_moment(&z, dt, steps, outputs, &cancelled),
        Err(zeitlin::isospectral::IsospectralError::Cancelled)
    );
    // The same seed gives the same numbers on any thread count.
    let again = sde.monte_carlo(&z, dt, steps, outputs, 4000, 3, &Progress::new()).unwrap();
    assert_eq!(again, mc);
}

#[test]
fn bad_input_is_an_error() {
    let n = 6;
    let (omega, noise, a) = problem(n, 1.0);
    let choice = a.choice.unwrap();
    assert!(BlockSde::new(&omega, &noise, &choice, 0).is_err());
    assert!(BlockSde::new(&omega, &noise, &choice, n).is_err());
    assert!(BlockSde::new(&omega, &[vec![0.1; n - 1]], &choice, 1).is_err());
    let sde = BlockSde::new(&omega, &noise, &choice, 1).unwrap();
    let z = vec![C::new(1.0, 0.0); n - 1];
    assert!(sde.monte_carlo(&z, 0.0, 10, 2, 10, 1, &Progress::new()).is_err());
    assert!(sde.monte_carlo(&z, f64::NAN, 10, 2, 10, 1, &Progress::new()).is_err());
    assert!(sde.monte_carlo(&z, 0.1, 10, 2, 0, 1, &Progress::new()).is_err());
    assert!(sde.exact_moment(&z[1..], 0.1, 10, 2, &Progress::new()).is_err());
    assert!(sde.exact_moment(&vec![C::new(0.0, 0.0); n - 1], 0.1, 10, 2, &Progress::new()).is_err());
}
