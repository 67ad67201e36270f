//! The general (matrix) pipeline: tilted zonal states against the zonal
//! pipeline, harmonics input against quantised profiles, every verdict
//! path, instability of a non-zonal state against an independent dense
//! drift, scaling and bad input.

use nalgebra::{Complex, DMatrix};
use outcome::Verdict;
use zeitlin::analysis::{analyse, ZeitlinProblem, ZeitlinSettings};
use zeitlin::general::{analyse_general, Frame, GeneralProblem, GeneralSettings};
use zeitlin::sphere::{from_harmonics, harmonic, rotation_to_axis, spin, to_harmonics};
use zeitlin::zonal::quantise;

type C = Complex<f64>;

fn c(x: f64) -> C {
    C::new(x, 0.0)
}

fn zonal_matrix(d: &[f64]) -> DMatrix<C> {
    DMatrix::from_fn(d.len(), d.len(), |i, j| if i == j { C::new(0.0, d[i]) } else { c(0.0) })
}

fn jet(z: f64) -> f64 {
    (-(z / 0.3).powi(2)).exp()
}

/// A zonal state tilted to an axis is analysed in its zonal frame: the
/// verdict, Sigma^2 and the growth rate are those of the zonal pipeline on
/// the untilted state (the model is rotation invariant).
#[test]
fn a_tilted_zonal_state_gives_the_zonal_answer() {
    let axis = [0.48, -0.6, 0.64];
    let forced = ZeitlinSettings { casimir_momentum: false, ..Default::default() };
    type Profile = Box<dyn Fn(f64) -> f64>;
    let cases: Vec<(usize, Profile, ZeitlinSettings, Verdict)> = vec![
        (12, Box::new(|z: f64| z + 0.3 * z * z * z), ZeitlinSettings::default(), Verdict::Stable),
        (12, Box::new(|z: f64| z + 0.3 * z * z * z), forced, Verdict::Stable),
        (12, Box::new(jet), ZeitlinSettings::default(), Verdict::LinearlyUnstable),
    ];
    for (n, profile, zs, verdict) in cases {
        let omega = quantise(n, &profile).diagonal;
        let xi = quantise(n, |z| 0.1 * z * z).diagonal;
        let zonal = analyse(&ZeitlinProblem { n, omega: omega.clone(), noise: vec![xi.clone()] }, &zs).unwrap();
        assert_eq!(zonal.verdict, verdict);
        let v = rotation_to_axis(n, axis).unwrap();
        let tilt = |m: &DMatrix<C>| &v * m * v.adjoint();
        let (w, x) = (tilt(&zonal_matrix(&omega)), tilt(&zonal_matrix(&xi)));
        assert!(w.iter().enumerate().filter(|(k, _)| k % (n + 1) != 0).any(|(_, z)| z.norm() > 1e-3));
        let settings = GeneralSettings { zonal: zs.clone(), ..Default::default() };
        let g = analyse_general(&GeneralProblem { n, w, noise: vec![x] }, &settings).unwrap();
        assert_eq!(g.verdict, verdict, "{}", g.reason);
        // The reported axis is quflow's: the direction of the l = 1
        // coefficients (v_11, v_1-1, v_10) of T_10 under the same rotation
        // (read off by to_harmonics; the jet has no l = 1 part of its own),
        // largest component positive.
        let h = to_harmonics(&tilt(&from_harmonics(n, &[(1, 0, 1.0)]).unwrap()), 1).unwrap();
        let v1 = |m: i64| h.iter().find(|(l, mm, _)| *l == 1 && *mm == m).map_or(0.0, |x| x.2);
        let l1 = [v1(1), v1(-1), v1(0)];
        let len = l1.iter().map(|x| x * x).sum::<f64>().sqrt();
        match &g.frame {
            Some(Frame::Rotated { axis: a }) => {
                let dot: f64 = a.iter().zip(&l1).map(|(p, q)| p * q).sum::<f64>() / len;
                assert!((dot.abs() - 1.0).abs() < 1e-9, "axis {a:?} against l = 1 part {l1:?}");
                let big = a.iter().copied().fold(0.0f64, |b, x| if x.abs() > b.abs() { x } else { b });
                assert!(big > 0.0, "{a:?}");
            }
            other => panic!("{other:?}"),
        }
        let r = g.zonal.as_ref().unwrap();
        assert!(r.off_diagonal < 1e-12, "{}", r.off_diagonal);
        let (a, b) = (zonal.sigma2, r.analysis.sigma2);
        match (a, b) {
            (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-8 * a.abs().max(1e-300), "{a} vs {b}"),
            (None, None) => {}
            other => panic!("{other:?}"),
        }
        if let (Some(a), Some(b)) = (zonal.growth_rate, r.analysis.growth_rate) {
            assert!((a - b).abs() <= 1e-8 * a.abs(), "growth {a} vs {b}");
        }
        assert_eq!(zonal.level, g.level);
    }
}

/// The same zonal state written as harmonics `(l, 0, a_l)` and as a
/// quantised profile gives the same analysis.
#[test]
fn harmonics_input_equals_the_quantised_profile() {
    let n = 16;
    let q = quantise(n, |z| z + 0.3 * z * z * z);
    let xi = quantise(n, |z| 0.1 * z * z);
    let harm =
        |a: &[f64]| -> Vec<(usize, i64, f64)> { a.iter().enumerate().skip(1).map(|(l, &v)| (l, 0, v)).collect() };
    let w = from_harmonics(n, &harm(&q.coefficients)).unwrap();
    let x = from_harmonics(n, &harm(&xi.coefficients)).unwrap();
    let forced = ZeitlinSettings { casimir_momentum: false, ..Default::default() };
    let g = analyse_general(
        &GeneralProblem { n, w, noise: vec![x] },
        &GeneralSettings { zonal: forced.clone(), ..Default::default() },
    )
    .unwrap();
    assert_eq!(g.frame, Some(Frame::Zonal));
    let z = analyse(&ZeitlinProblem { n, omega: q.diagonal, noise: vec![xi.diagonal] }, &forced).unwrap();
    let (a, b) = (z.sigma2.unwrap(), g.zonal.unwrap().analysis.sigma2.unwrap());
    assert!((a - b).abs() <= 1e-10 * a, "{a} vs {b}");
}

/// `T_10 + T_21` is not steady. With `P = -T_10/2 - T_21/6` (each harmonic is
/// an eigenvector of the Laplacian), `[P, W] = -(1/3) [T_10, T_21]`.
#[test]
fn a_mixed_state_is_not_an_equilibrium_and_a_single_degree_one_is() {
    let n = 6;
    let (t10, t21) = (harmonic(n, 1, 0).unwrap(), harmonic(n, 2, 1).unwrap());
    let w = &t10 + &t21;
    let g = analyse_general(&GeneralProblem { n, w: w.clone(), noise: vec![] }, &GeneralSettings::default()).unwrap();
    assert_eq!(g.verdict, Verdict::NotAnEquilibrium, "{}", g.reason);
    let p = &t10 * c(-0.5) + &t21 * c(-1.0 / 6.0);
    let expected = ((&t10 * &t21 - &t21 * &t10).norm() / 3.0) / (p.norm() * w.norm());
    assert!((g.equilibrium_residual - expected).abs() <= 1e-12 * expected, "{} vs {expected}", g.equilibrium_residual);
    // One degree only (a Rossby–Haurwitz state): steady.
    let rh = from_harmonics(n, &[(3, 1, 1.0), (3, -2, 0.4), (3, 0, -0.3)]).unwrap();
    let g = analyse_general(&GeneralProblem { n, w: rh, noise: vec![] }, &GeneralSettings::default()).unwrap();
    assert!(g.equilibrium_residual < 1e-13, "{}", g.equilibrium_residual);
    assert_ne!(g.verdict, Verdict::NotAnEquilibrium);
}

/// Noise with a non-zonal part on a zonal state is incompatible; its
/// compatible part is its zonal part (the commutant of a diagonal matrix
/// with distinct entries is the diagonal matrices), and tilted likewise.
#[test]
fn non_zonal_noise_is_incompatible_and_its_zonal_part_is_the_compatible_part() {
    let n = 8;
    let omega = quantise(n, |z| z + 0.3 * z * z * z).diagonal;
    let (t20, t21) = (harmonic(n, 2, 0).unwrap(), harmonic(n, 2, 1).unwrap());
    let x = &t20 * c(0.1) + &t21 * c(0.05);
    let w = zonal_matrix(&omega);
    let g = analyse_general(&GeneralProblem { n, w: w.clone(), noise: vec![x.clone()] }, &GeneralSettings::default())
        .unwrap();
    assert_eq!(g.verdict, Verdict::NoiseIncompatible, "{}", g.reason);
    assert!((&g.compatible_noise[0] - &t20 * c(0.1)).norm() < 1e-12);
    // [X, W] = 0.05 [T_21, W]: the residual is that, relative.
    let expected = (&t21 * &w - &w * &t21).norm() * 0.05 / (x.norm() * w.norm());
    assert!((g.noise_residuals[0] - expected).abs() < 1e-12 * expected);
    // Tilted: the compatible part is the tilted zonal part.
    let v = rotation_to_axis(n, [0.0, 0.6, 0.8]).unwrap();
    let tilt = |m: &DMatrix<C>| &v * m * v.adjoint();
    let g = analyse_general(&GeneralProblem { n, w: tilt(&w), noise: vec![tilt(&x)] }, &GeneralSettings::default())
        .unwrap();
    assert_eq!(g.verdict, Verdict::NoiseIncompatible);
    assert!((&g.compatible_noise[0] - tilt(&(&t20 * c(0.1)))).norm() < 1e-11);
}

/// The spin Laplacian on `vec(X)` (column-major), from its definition.
fn dense_laplacian(n: usize) -> DMatrix<C> {
    let s = spin(n);
    let mut lap = DMatrix::zeros(n * n, n * n);
    for k in 0..n * n {
        let mut e = DMatrix::zeros(n, n);
        e[(k % n, k / n)] = c(1.0);
        let mut out = DMatrix::zeros(n, n);
        for sa in &s {
            let inner = sa * &e - &e * sa;
            out -= sa * &inner - &inner * sa;
        }
        for (r, z) in out.iter().enumerate() {
            lap[(r, k)] = *z;
        }
    }
    lap
}

/// The largest real part of the eigenvalues of the linearised drift
/// `X -> ([P_e, X] + [Delta^+ X, W_e]) / hbar` on all of `gl(N)`, assembled
/// from the spin-matrix Laplacian (its kernel, the identity, fixed by a
/// rank-one term), through the real form of the complex matrix.
fn dense_growth(w: &DMatrix<C>) -> f64 {
    let n = w.nrows();
    let lap = dense_laplacian(n);
    let u = DMatrix::from_fn(n * n, 1, |k, _| c(if k % n == k / n { 1.0 / (n as f64).sqrt() } else { 0.0 }));
    let inv = (&lap + &u * u.adjoint()).try_inverse().unwrap();
    let vec_of = |m: &DMatrix<C>| DMatrix::from_fn(n * n, 1, |k, _| m[(k % n, k / n)]);
    let pe_vec = &inv * vec_of(w);
    let pe = DMatrix::from_fn(n, n, |i, j| pe_vec[(j * n + i, 0)]);
    let hbar = 2.0 / ((n * n) as f64 - 1.0).sqrt();
    let mut a = DMatrix::zeros(n * n, n * n);
    for k in 0..n * n {
        let mut e = DMatrix::zeros(n, n);
        e[(k % n, k / n)] = c(1.0);
        let psi_vec = &inv * vec_of(&e);
        let psi = DMatrix::from_fn(n, n, |i, j| psi_vec[(j * n + i, 0)]);
        let out = (&pe * &e - &e * &pe + &psi * w - w * &psi) / c(hbar);
        for (r, z) in out.iter().enumerate() {
            a[(r, k)] = *z;
        }
    }
    let m = n * n;
    let real = DMatrix::from_fn(2 * m, 2 * m, |i, j| {
        let z = a[(i % m, j % m)];
        match (i < m, j < m) {
            (true, true) | (false, false) => z.re,
            (true, false) => -z.im,
            (false, true) => z.im,
        }
    });
    numerics::dense::real_eigenvalues(&real).unwrap().iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max)
}

/// A Rossby–Haurwitz state of degree 3 (steady, zonal about no axis): no
/// energy–Casimir form is definite, and the growth rate of the dense
/// analysis is the largest real part of the drift's eigenvalues assembled
/// independently (1e-6 absolute: a multiple imaginary eigenvalue moves off
/// the axis by about sqrt(eps) |A| in either computation).
#[test]
fn a_non_zonal_state_grows_at_the_independent_drifts_rate() {
    let n = 7;
    let mut saw = (false, false);
    for coefficients in
        [vec![(3usize, 1i64, 1.0), (3, -2, 0.6), (3, 0, -0.2)], vec![(2, 1, 1.0), (2, -2, 0.35), (2, 0, 0.2)]]
    {
        let w = from_harmonics(n, &coefficients).unwrap();
        let g =
            analyse_general(&GeneralProblem { n, w: w.clone(), noise: vec![] }, &GeneralSettings::default()).unwrap();
        assert_eq!(g.frame, Some(Frame::General), "{coefficients:?}");
        let d = g.dense.as_ref().unwrap();
        assert_eq!(d.energy, 0.0);
        assert!(d.restricted_margin <= 1e-9);
        let rate = dense_growth(&w);
        let got = d.growth_rate.unwrap();
        assert!((got - rate.max(0.0)).abs() <= 1e-6, "{coefficients:?}: dense analysis {got}, independent {rate}");
        if rate > 1e-3 {
            assert_eq!(g.verdict, Verdict::LinearlyUnstable, "{}", g.reason);
            saw.0 = true;
        } else {
            assert_eq!(g.verdict, Verdict::Inconclusive, "{}", g.reason);
            saw.1 = true;
        }
    }
    assert!(saw.0 && saw.1, "both a growing and a spectrally stable state: {saw:?}");
}

/// The problem is homogeneous: `W -> k W` scales the growth rate by `k`,
/// `X -> k X` scales Sigma^2 by `k^2`; extremes give no overflow.
#[test]
fn rescaling_moves_only_the_units() {
    let n = 8;
    let omega = quantise(n, |z| z + 0.3 * z * z * z).diagonal;
    let xi = quantise(n, |z| 0.1 * z * z).diagonal;
    let v = rotation_to_axis(n, [0.6, 0.0, 0.8]).unwrap();
    let tilt = |m: &DMatrix<C>| &v * m * v.adjoint();
    let settings = GeneralSettings {
        zonal: ZeitlinSettings { casimir_momentum: false, ..Default::default() },
        ..Default::default()
    };
    let run = |kw: f64, kx: f64| {
        let w = tilt(&zonal_matrix(&omega)) * c(kw);
        let x = tilt(&zonal_matrix(&xi)) * c(kx);
        analyse_general(&GeneralProblem { n, w, noise: vec![x] }, &settings).unwrap()
    };
    let base = run(1.0, 1.0);
    assert_eq!(base.verdict, Verdict::Stable, "{}", base.reason);
    let s0 = base.zonal.as_ref().unwrap().analysis.sigma2.unwrap();
    for (kw, kx) in [(1e-300, 1.0), (1e300, 1.0), (1.0, 1e-100), (1.0, 1e100), (3.7, 0.25)] {
        let g = run(kw, kx);
        assert_eq!(g.verdict, Verdict::Stable, "k = ({kw}, {kx}): {}", g.reason);
        let s = g.zonal.as_ref().unwrap().analysis.sigma2.unwrap();
        assert!((s / (kx * kx) - s0).abs() <= 1e-6 * s0, "k = ({kw}, {kx}): {s} vs {s0}");
    }
}

#[test]
fn bad_input_names_the_field() {
    let n = 4;
    let ok = harmonic(n, 1, 0).unwrap();
    let bad = |w: DMatrix<C>, noise: Vec<DMatrix<C>>| -> String {
        analyse_general(&GeneralProblem { n, w, noise }, &GeneralSettings::default()).unwrap_err().to_string()
    };
    let hermitian = DMatrix::from_fn(n, n, |i, j| c((i + j) as f64));
    assert!(bad(hermitian.clone(), vec![]).contains("equilibrium: not skew-Hermitian"));
    assert!(bad(ok.clone(), vec![hermitian]).contains("noise[0]: not skew-Hermitian"));
    let mut nan = ok.clone();
    nan[(0, 1)] = C::new(f64::NAN, 0.0);
    assert!(bad(nan, vec![]).contains("equilibrium: an entry is not finite"));
    assert!(bad(DMatrix::zeros(3, 3), vec![]).contains("expected 4 x 4"));
}

/// The matrix-free analysis (`zeitlin::matrix_free`), run through the
/// general pipeline by lowering `dense_max_n` below N, against the drift
/// assembled independently on gl(N) (faer's eigenvalues of the `2N^2`
/// real form): a growing state's rate to 1e-8 relative, and nothing for a
/// spectrally stable one. The restricted Hessian is proved indefinite by
/// its Ritz values, as the dense analysis finds (`restricted_margin < 0`),
/// and with repeated eigenvalues neither makes the test.
#[test]
fn the_matrix_free_search_finds_the_independent_drifts_rate() {
    let matrix_free = GeneralSettings { dense_max_n: 2, ..Default::default() };
    type Harmonics = Vec<(usize, i64, f64)>;
    let states: [(usize, Harmonics); 7] = [
        (8, vec![(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2)]),
        (11, vec![(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2)]),
        (9, vec![(4, 1, 1.0), (4, -3, 0.5), (4, 2, 0.3)]),
        (7, vec![(2, 1, 1.0), (2, -2, 0.35), (2, 0, 0.2)]),
        (9, vec![(2, 1, 1.0), (2, -2, 0.35), (2, 0, 0.2)]),
        // Repeated eigenvalues (degree 2, even N): no energy–Casimir test.
        (8, vec![(2, 1, 1.0), (2, -2, 0.35), (2, 0, 0.2)]),
        // The smallest N with a state zonal about no axis: the restricted
        // Hessian's smallest eigenvalue is 0 (its Ritz value, -8e-17, is
        // recorded as 0), so the form is not called indefinite.
        (3, vec![(2, 1, 1.0), (2, -2, 0.35), (2, 0, 0.2)]),
    ];
    let mut saw = (0, 0);
    for (n, coefficients) in states {
        let w = from_harmonics(n, &coefficients).unwrap();
        let g = analyse_general(&GeneralProblem { n, w: w.clone(), noise: vec![] }, &matrix_free).unwrap();
        assert_eq!(g.frame, Some(Frame::General), "{coefficients:?}");
        assert!(g.dense.is_none());
        let m = g.matrix_free.as_ref().expect("the matrix-free analysis ran");
        assert!(m.drift_residual < 1e-13, "{}", m.drift_residual);
        let dense = analyse_general(&GeneralProblem { n, w: w.clone(), noise: vec![] }, &GeneralSettings::default())
            .unwrap()
            .dense
            .unwrap();
        assert_eq!(m.distinct_eigenvalues, dense.distinct_eigenvalues);
        if m.distinct_eigenvalues {
            assert_eq!(m.indefinite, dense.restricted_margin < -1e-9, "N = {n} {coefficients:?}");
        } else {
            assert!(!m.indefinite && m.restricted_ritz.is_none());
        }
        let rate = dense_growth(&w);
        match m.eigenvalue {
            Some((re, _)) => {
                // An eigenvalue of A + E, |E|_F the backward error: within a
                // modest condition number times it of A's own.
                let e = m.backward_error.unwrap();
                assert!(e <= 1e-6 * m.drift_norm && e <= 1e-3 * re);
                assert!(
                    (re - rate).abs() <= 10.0 * e,
                    "N = {n} {coefficients:?}: matrix-free {re}, independent {rate}, backward error {e:e}"
                );
                assert_eq!(g.verdict, Verdict::LinearlyUnstable, "{}", g.reason);
                saw.0 += 1;
            }
            None => {
                assert!(rate < 1e-6, "N = {n} {coefficients:?}: missed the rate {rate}: {}", g.reason);
                assert_eq!(g.verdict, Verdict::Inconclusive, "{}", g.reason);
                assert!(g.reason.contains("found no growing eigenvalue"), "{}", g.reason);
                saw.1 += 1;
            }
        }
    }
    assert_eq!(saw, (3, 4), "three growing and four spectrally stable states");
}

/// The matrix-free verdict scales like the dense one: `W -> k W` multiplies
/// the eigenvalue by `k` (the state is normalised by a power of two first),
/// from 1e-200 to 1e200.
#[test]
fn the_matrix_free_rate_moves_only_with_the_units() {
    let n = 8;
    let settings = GeneralSettings { dense_max_n: 2, ..Default::default() };
    let w = from_harmonics(n, &[(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2)]).unwrap();
    let base = analyse_general(&GeneralProblem { n, w: w.clone(), noise: vec![] }, &settings).unwrap();
    let (re, im) = base.matrix_free.unwrap().eigenvalue.unwrap();
    // The fixture's dense rate (rossby-haurwitz-l3-n8.cert.json).
    assert!((re - 0.1838226221867269).abs() < 1e-9, "{re}");
    for k in [1e-200, 3.0, 1e200] {
        let g = analyse_general(&GeneralProblem { n, w: &w * c(k), noise: vec![] }, &settings).unwrap();
        let (r, i) = g.matrix_free.unwrap().eigenvalue.unwrap();
        assert!((r / k - re).abs() <= 1e-9 * re && (i / k - im).abs() <= 1e-9 * im, "k = {k}: {r} {i}");
    }
}

/// The definite branch is never reached by a true equilibrium zonal in no
/// frame (docs/zeitlin.md); on the artificial pencil of the dense test
/// (`P_e` replaced by `W_e`, every Daleckii–Krein weight 1, `G + I`
/// definite) the Ritz values have one sign, the form is not called
/// indefinite, and no `Sigma^2` is claimed.
#[test]
fn the_matrix_free_analysis_does_not_call_a_definite_form_indefinite() {
    use zeitlin::laplacian::StreamSolver;
    use zeitlin::matrix_free::{matrix_free_analysis, MatrixFreeSettings};
    let n = 9;
    let w = from_harmonics(n, &[(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2), (2, 1, 0.3)]).unwrap();
    let solver = StreamSolver::new(n).unwrap();
    let m = matrix_free_analysis(&solver, &w, &w, &MatrixFreeSettings::default(), &outcome::Progress::new()).unwrap();
    let (lo, hi) = m.restricted_ritz.unwrap();
    assert!(!m.indefinite && lo > 0.0 && hi > lo, "{lo} {hi}");
}

/// The analysis is the same bit for bit on one thread and on two (the
/// products split their columns in blocks of 64 whatever the thread
/// count, so N = 72 splits), and a cancelled run is an error, not a
/// verdict.
#[test]
fn the_matrix_free_analysis_is_reproducible_and_cancellable() {
    use zeitlin::laplacian::StreamSolver;
    use zeitlin::matrix_free::{matrix_free_analysis, MatrixFreeSettings};
    let n = 72;
    let w = from_harmonics(n, &[(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2)]).unwrap();
    let solver = StreamSolver::new(n).unwrap();
    let p = solver.solve(&w).unwrap();
    let settings = MatrixFreeSettings::default();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| matrix_free_analysis(&solver, &w, &p, &settings, &outcome::Progress::new()).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two);
    assert!(one.eigenvalue.is_some());
    let cancelled = outcome::Progress::new();
    cancelled.cancel();
    assert!(matches!(
        matrix_free_analysis(&solver, &w, &p, &settings, &cancelled),
        Err(zeitlin::analysis::ZeitlinError::Cancelled(_))
    ));
}

/// A state of degree 1 with coefficients `(v_11, v_1-1, v_10)` is the
/// function `n.x` for `n` along them (quflow's frame, where `rotate` and
/// `shr2mat` agree), so its reported axis is their direction: the
/// convention of `frame.axis`, fixed from the harmonics alone.
#[test]
fn the_axis_is_the_direction_of_the_degree_one_coefficients() {
    let n = 7;
    for l1 in [[0.48, 0.6, 0.64], [-0.48, 0.6, 0.64], [0.0, -0.6, 0.8], [0.8, 0.0, -0.6]] {
        let w = from_harmonics(n, &[(1, 1, l1[0]), (1, -1, l1[1]), (1, 0, l1[2])]).unwrap();
        let g = analyse_general(&GeneralProblem { n, w, noise: vec![] }, &GeneralSettings::default()).unwrap();
        let sign = l1.iter().copied().fold(0.0f64, |b, x| if x.abs() > b.abs() { x } else { b }).signum();
        match &g.frame {
            Some(Frame::Rotated { axis }) => {
                for k in 0..3 {
                    assert!((axis[k] - sign * l1[k]).abs() < 1e-12, "{axis:?} against {l1:?}");
                }
            }
            other => panic!("{l1:?}: {other:?}"),
        }
    }
}
