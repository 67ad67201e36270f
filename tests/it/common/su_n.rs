//! The Zeitlin model on su(N) written as an ordinary finite-dimensional spec
//! for the generic engine, and the checks that compare it with the Zeitlin
//! pipeline, for any `N >= 4` (used by `zeitlin_su_n`; `zeitlin_generic`
//! keeps its own fixed-size N = 3 version, where
//! every block is rational).
//!
//! The construction (docs/zeitlin.md, "Agreement with the generic engine"):
//! `mu_k = <W, e_k>` with `<A, B> = Re tr(A B^*)/N`, `h = -1/2 <W, Delta^-1
//! W>` (time in units of `hbar`), the Casimirs `tr W^k` for `k = 2..N` (the
//! real part for even `k`, the imaginary part for odd `k`: the other part is
//! zero), the momentum `J = <W, i diag(tau)>`, `tau_j = j - (N-1)/2`, as
//! polynomials in `mu`, and the noise `sigma = -X/hbar`.
//!
//! The Laplacian's block on diagonal `m` has the off-diagonal entries
//! `sqrt(j(N-j)(j+m)(N-j-m))`; where a product is not a perfect square the
//! energy's coefficients on that diagonal are irrational. Such a block is
//! inverted in floating point and its entries are written as the exact
//! rationals of those doubles (the generic engine then analyses a
//! Hamiltonian perturbed by a few units of round-off); the rational blocks,
//! the Cartan one (`m = 0`) among them, are inverted exactly. Because the
//! Laplacian maps each diagonal of a matrix to itself and acts alike on the
//! real and imaginary parts, the rounding keeps
//! * `Dh(mu_e)` in the Cartan directions for a zonal `mu_e`, so the exact
//!   equilibrium and noise residuals stay zero;
//! * `{J, h} = 0` exactly (`ad_{i diag(tau)}` rotates the real and the
//!   imaginary part of one diagonal into each other, and the two parts'
//!   blocks are the same doubles).
//!
//! [`check_monotone`], [`check_non_monotone`], [`check_unstable`] and
//! [`check_perturbations_fail`] hold the assertions; each test file names
//! its states and the constants it derives for its `N`. The generic engine
//! is given the system as a spec ([`Route::Spec`], N = 4 and 5) or through
//! the library API ([`Route::Library`], N = 6, whose `tr W^5` and `tr W^6`
//! exceed the spec's limits on an expression).
#![allow(dead_code)]

use exact::{Matrix, Poly, Rational};
use generator::NumericRoute;
use nalgebra::{Complex, DMatrix};
use outcome::Sign;
use serde_json::json;
use spec::Verdict;
use std::time::{Duration, Instant};
use zeitlin::analysis::{analyse, ZeitlinAnalysis, ZeitlinProblem, ZeitlinSettings};

/// Gaussian-integer `n x n` matrices, `(re, im)` per entry.
pub type Z = Vec<Vec<(i64, i64)>>;

pub fn zero(n: usize) -> Z {
    vec![vec![(0, 0); n]; n]
}

pub fn mul(a: &Z, b: &Z) -> Z {
    let n = a.len();
    let mut c = zero(n);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let (x, y) = (a[i][k], b[k][j]);
                c[i][j].0 += x.0 * y.0 - x.1 * y.1;
                c[i][j].1 += x.0 * y.1 + x.1 * y.0;
            }
        }
    }
    c
}

pub fn commutator(a: &Z, b: &Z) -> Z {
    let (ab, ba) = (mul(a, b), mul(b, a));
    ab.iter().zip(&ba).map(|(r, s)| r.iter().zip(s).map(|(x, y)| (x.0 - y.0, x.1 - y.1)).collect()).collect()
}

/// The entries above the diagonal, `(j, k)` with `j < k`, in the basis order.
pub fn pairs(n: usize) -> Vec<(usize, usize)> {
    (0..n).flat_map(|j| (j + 1..n).map(move |k| (j, k))).collect()
}

/// The basis of su(n): for `j < k`, `E_jk - E_kj` and `i (E_jk + E_kj)`,
/// then `i (E_jj - E_{j+1,j+1})`. Coordinate `2 p` is the real part and
/// `2 p + 1` the imaginary part of pair `p`; the Cartan coordinates come
/// last, from `n (n - 1)` on.
pub fn basis(n: usize) -> Vec<Z> {
    let mut out = Vec::new();
    for (j, k) in pairs(n) {
        let mut re = zero(n);
        re[j][k] = (1, 0);
        re[k][j] = (-1, 0);
        let mut im = zero(n);
        im[j][k] = (0, 1);
        im[k][j] = (0, 1);
        out.push(re);
        out.push(im);
    }
    for j in 0..n - 1 {
        let mut d = zero(n);
        d[j][j] = (0, 1);
        d[j + 1][j + 1] = (0, -1);
        out.push(d);
    }
    out
}

/// Coordinates of a skew-Hermitian trace-free matrix in [`basis`] (any
/// scalar type): `i diag(d)` is `sum_j a_j i (E_jj - E_{j+1,j+1})` with
/// `a_j = d_0 + ... + d_j`.
pub fn coordinates<T: Clone + std::ops::Add<Output = T>>(y: &[Vec<(T, T)>]) -> Vec<T> {
    let n = y.len();
    let mut v = Vec::new();
    for (j, k) in pairs(n) {
        v.push(y[j][k].0.clone());
        v.push(y[j][k].1.clone());
    }
    let mut a = y[0][0].1.clone();
    v.push(a.clone());
    for (j, row) in y.iter().enumerate().take(n - 1).skip(1) {
        a = a + row[j].1.clone();
        v.push(a.clone());
    }
    v
}

pub fn q(n: i64, d: i64) -> Rational {
    Rational::new_small(n, d)
}

/// `Re tr(A B^*) / N` for Gaussian-integer matrices.
pub fn inner(a: &Z, b: &Z) -> Rational {
    let n = a.len();
    let s: i64 = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| a[i][j].0 * b[i][j].0 + a[i][j].1 * b[i][j].1)
        .sum();
    q(s, n as i64)
}

/// The Gram matrix `<e_a, e_b>` of [`basis`].
pub fn gram(e: &[Z]) -> Matrix {
    Matrix::from_rows(&e.iter().map(|a| e.iter().map(|b| inner(a, b)).collect()).collect::<Vec<_>>())
}

/// The Hoppe–Yau Laplacian on diagonal `m` (entries `P[j, j + m]`):
/// tridiagonal with diagonal `-((N-1)(2j+1+m) - 2j(j+m))` and, between
/// `j - 1` and `j`, `sqrt(j(N-j)(j+m)(N-j-m))` (docs/zeitlin.md, "Blocks";
/// checked by [`check_laplacian_blocks`] against the spin-matrix
/// definition).
pub fn laplacian_block(n: usize, m: usize) -> DMatrix<f64> {
    let (n, m) = (n as i64, m as i64);
    let len = (n - m) as usize;
    let mut t = DMatrix::zeros(len, len);
    for j in 0..len {
        let jj = j as i64;
        t[(j, j)] = -((n - 1) * (2 * jj + 1 + m) - 2 * jj * (jj + m)) as f64;
        if j > 0 {
            let off = ((jj * (n - jj) * (jj + m) * (n - jj - m)) as f64).sqrt();
            t[(j, j - 1)] = off;
            t[(j - 1, j)] = off;
        }
    }
    t
}

/// The diagonals `m` whose Laplacian block has an irrational entry: a
/// product `j(N-j)(j+m)(N-j-m)` under a root that is not a perfect square
/// (decided in integers).
pub fn irrational_diagonals(n: usize) -> Vec<usize> {
    let n = n as i64;
    (0..n)
        .filter(|&m| {
            (1..n - m).any(|j| {
                let x = j * (n - j) * (j + m) * (n - j - m);
                let r = (x as f64).sqrt().round() as i64;
                r * r != x
            })
        })
        .map(|m| m as usize)
        .collect()
}

/// The Laplacian on one complex matrix, diagonal by diagonal (the lower
/// diagonals alike: the block is real).
pub fn laplacian(n: usize, p: &[Vec<Complex<f64>>]) -> Vec<Vec<Complex<f64>>> {
    let mut out = vec![vec![Complex::new(0.0, 0.0); n]; n];
    for m in 0..n {
        let t = laplacian_block(n, m);
        for j in 0..n - m {
            for k in 0..n - m {
                out[j][j + m] += p[k][k + m] * t[(j, k)];
                if m > 0 {
                    out[j + m][j] += p[k + m][k] * t[(j, k)];
                }
            }
        }
    }
    out
}

/// `Delta X = -sum_a [S_a, [S_a, X]]` with the spin-`(N-1)/2` matrices
/// (`S_z = diag(s, s-1, ..., -s)`, `S_+` the raising ladder), written as
/// `-[S_z, [S_z, X]] - ([S_+, [S_-, X]] + [S_-, [S_+, X]])/2`: the
/// definition, independent of the block formula.
pub fn spin_laplacian(n: usize, x: &DMatrix<Complex<f64>>) -> DMatrix<Complex<f64>> {
    let s = (n as f64 - 1.0) / 2.0;
    let c = |v: f64| Complex::new(v, 0.0);
    let sz = DMatrix::from_fn(n, n, |i, j| if i == j { c(s - i as f64) } else { c(0.0) });
    // <m+1| S_+ |m> = sqrt(s(s+1) - m(m+1)); row i holds m = s - i.
    let sp = DMatrix::from_fn(n, n, |i, j| {
        let m = s - j as f64;
        if j == i + 1 {
            c((s * (s + 1.0) - m * (m + 1.0)).sqrt())
        } else {
            c(0.0)
        }
    });
    let sm = sp.adjoint();
    let br = |a: &DMatrix<Complex<f64>>, b: &DMatrix<Complex<f64>>| a * b - b * a;
    -br(&sz, &br(&sz, x)) - (br(&sp, &br(&sm, x)) + br(&sm, &br(&sp, x))) * c(0.5)
}

/// A Gaussian-integer matrix in complex floating point.
fn complex_of(eb: &Z) -> Vec<Vec<Complex<f64>>> {
    eb.iter().map(|r| r.iter().map(|&(re, im)| Complex::new(re as f64, im as f64)).collect()).collect()
}

/// The block formula is the Laplacian's definition and its spectrum is
/// `-l(l+1)`, `l = m..N-1` (the spherical harmonics `T_lm`).
pub fn check_laplacian_blocks(n: usize) {
    // Every entry of every basis element: the block formula against
    // -sum_a [S_a, [S_a, X]], to round-off (entries up to ~2N^2).
    for eb in basis(n) {
        let p = complex_of(&eb);
        let by_blocks = laplacian(n, &p);
        let by_spin = spin_laplacian(n, &DMatrix::from_fn(n, n, |i, j| p[i][j]));
        for i in 0..n {
            for j in 0..n {
                assert!((by_blocks[i][j] - by_spin[(i, j)]).norm() < 1e-12, "entry ({i}, {j})");
            }
        }
    }
    for m in 0..n {
        let mut e: Vec<f64> = laplacian_block(n, m).symmetric_eigen().eigenvalues.iter().copied().collect();
        e.sort_by(|a, b| b.total_cmp(a));
        for (l, v) in (m..n).zip(&e) {
            let expected = -((l * (l + 1)) as f64);
            // Absolute: the entries are up to 2 N^2 (l = 0 has eigenvalue 0).
            assert!((v - expected).abs() < 1e-12 * (n * n) as f64, "m = {m}: {v} vs {expected}");
        }
    }
}

/// Which block of the energy's Hessian a coordinate belongs to: `(m, part)`
/// for the real (0) or imaginary (1) part of diagonal `m >= 1`, `(0, 0)` for
/// the Cartan directions.
pub fn group(n: usize, k: usize) -> (usize, usize) {
    let p = pairs(n);
    if k < 2 * p.len() {
        let (j, l) = p[k / 2];
        (l - j, k % 2)
    } else {
        (0, 0)
    }
}

/// The coordinates of diagonal `m >= 1` (real and imaginary parts); none
/// for `m = 0`.
pub fn block(n: usize, m: usize) -> Vec<usize> {
    (0..n * n - 1).filter(|&k| group(n, k).0 == m && m > 0).collect()
}

/// The energy `h = -1/2 mu^T M mu` with `M = (G L)^-1`, `(G L)_ab = <e_a,
/// Delta e_b>`: `W = sum x_a e_a`, `mu = G x`, so `<W, Delta^-1 W> = x^T G
/// L^-1 x = mu^T (G L)^-1 mu`. `G L` is block diagonal (each diagonal of a
/// matrix to itself, real and imaginary parts apart; asserted, exact zeros).
/// A block whose Laplacian entries are integers (the root of a perfect
/// square is exact in floating point) is inverted exactly; the others in
/// floating point, each entry then read exactly (`rational_from_f64`).
/// Returns `M`.
pub fn energy_matrix(n: usize, e: &[Z], g: &Matrix) -> Vec<Vec<Rational>> {
    let d = e.len();
    // L in the basis, in floating point.
    let mut lap = DMatrix::<f64>::zeros(d, d);
    for (b, eb) in e.iter().enumerate() {
        let l = laplacian(n, &complex_of(eb));
        let l: Vec<Vec<(f64, f64)>> = l.iter().map(|r| r.iter().map(|z| (z.re, z.im)).collect()).collect();
        for (a, c) in coordinates(&l).into_iter().enumerate() {
            lap[(a, b)] = c;
        }
    }
    let mut m = vec![vec![q(0, 1); d]; d];
    let mut groups: Vec<(usize, usize)> = (0..d).map(|k| group(n, k)).collect();
    groups.sort();
    groups.dedup();
    for gr in groups {
        let idx: Vec<usize> = (0..d).filter(|&k| group(n, k) == gr).collect();
        // Nothing couples this group to another, in L or in G (exact zeros).
        for &a in &idx {
            for b in (0..d).filter(|&b| group(n, b) != gr) {
                assert!(lap[(a, b)] == 0.0 && g[(a, b)] == q(0, 1), "coordinates {a} and {b} are coupled");
            }
        }
        let k = idx.len();
        let g_sub = Matrix::from_fn(k, k, |i, j| g[(idx[i], idx[j])].clone());
        let l_sub = DMatrix::from_fn(k, k, |i, j| lap[(idx[i], idx[j])]);
        let inverse: Vec<Vec<Rational>> = if l_sub.iter().all(|x| x.fract() == 0.0) {
            let l_exact = Matrix::from_fn(k, k, |i, j| exact::rational_from_f64(l_sub[(i, j)]).unwrap());
            g_sub.mul(&l_exact).inverse().expect("a block of G L is invertible").to_rows()
        } else {
            let gl = g_sub.to_dmatrix() * l_sub;
            let inv = gl.try_inverse().expect("a block of G L is invertible");
            (0..k).map(|i| (0..k).map(|j| exact::rational_from_f64(inv[(i, j)]).unwrap()).collect()).collect()
        };
        for (i, &a) in idx.iter().enumerate() {
            for (j, &b) in idx.iter().enumerate() {
                m[a][b] = inverse[i][j].clone();
            }
        }
    }
    m
}

/// A complex matrix of polynomials, `(re, im)` per entry.
pub type PolyMatrix = Vec<Vec<(Poly, Poly)>>;

pub fn poly_mul(a: &PolyMatrix, b: &PolyMatrix, nvars: usize) -> PolyMatrix {
    let n = a.len();
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let mut re = Poly::zero(nvars);
                    let mut im = Poly::zero(nvars);
                    for k in 0..n {
                        let (x, y) = (&a[i][k], &b[k][j]);
                        re = re.add(&x.0.mul(&y.0)).sub(&x.1.mul(&y.1));
                        im = im.add(&x.0.mul(&y.1)).add(&x.1.mul(&y.0));
                    }
                    (re, im)
                })
                .collect()
        })
        .collect()
}

/// `tr(A B) = sum_ij A_ij B_ji`, real and imaginary parts, without forming
/// the product.
pub fn trace_of_product(a: &PolyMatrix, b: &PolyMatrix, nvars: usize) -> (Poly, Poly) {
    let n = a.len();
    let mut re = Poly::zero(nvars);
    let mut im = Poly::zero(nvars);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (&a[i][j], &b[j][i]);
            re = re.add(&x.0.mul(&y.0)).sub(&x.1.mul(&y.1));
            im = im.add(&x.0.mul(&y.1)).add(&x.1.mul(&y.0));
        }
    }
    (re, im)
}

/// `tr W^k` for `k = 2..=max_k` as real polynomials: `W = i A` with `A`
/// Hermitian, so `tr W^k = i^k tr A^k` is real for even `k` and imaginary
/// for odd `k`; the vanishing part is asserted zero and the other returned.
/// `tr W^k = tr(W^a W^b)`, `a = k/2`, `b = k - a`, so only the powers up to
/// `ceil(n/2)` are formed.
pub fn trace_powers(w: &PolyMatrix, nvars: usize, max_k: usize) -> Vec<Poly> {
    // powers[j] = W^(j+1).
    let mut powers = vec![w.clone()];
    while powers.len() < max_k.div_ceil(2) {
        let next = poly_mul(powers.last().unwrap(), w, nvars);
        powers.push(next);
    }
    (2..=max_k)
        .map(|k| {
            let a = k / 2;
            let (re, im) = trace_of_product(&powers[a - 1], &powers[k - a - 1], nvars);
            let (kept, vanishing) = if k % 2 == 0 { (re, im) } else { (im, re) };
            assert!(vanishing.is_zero(), "tr W^{k} has the wrong phase");
            kept
        })
        .collect()
}

/// How the generic engine is given the system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Route {
    /// As a user gives it: a spec's JSON text, `spec::parse_spec` (which
    /// checks the Casimirs and `{J, h} = 0` exactly) and `spec::certify`.
    Spec,
    /// Through the library API: `casimir::System::new` (the same exact
    /// checks) and `generator::analyse` (what `spec::certify` runs), without
    /// the spec's limits on an expression (100,000 bytes, 5000 terms), which
    /// `tr W^5` exceeds from N = 6 on.
    Library,
}

/// Everything about one zonal state.
pub struct Case {
    pub system: casimir::System,
    /// The certificate ([`Route::Spec`] only).
    pub cert: Option<serde_json::Value>,
    /// The exact-level analysis (behind the certificate, if there is one).
    pub analysis: generator::Analysis,
    pub numeric: generator::NumericAnalysis,
    /// The Zeitlin pipeline, the paper's family (energy forced).
    pub forced: ZeitlinAnalysis,
    /// The Zeitlin pipeline, the Casimir–momentum form allowed.
    pub free: ZeitlinAnalysis,
    /// Wall-clock time of building the system (and writing and parsing the
    /// spec).
    pub system_time: Duration,
    /// Wall-clock time of the exact level (`spec::certify` or
    /// `generator::analyse`).
    pub exact_time: Duration,
    /// Wall-clock time of `generator::analyse_numeric`.
    pub numeric_time: Duration,
}

/// How a spec departs from the model (for the cases that must fail).
#[derive(Clone, Default)]
pub struct Perturbation {
    /// Added to the energy's text.
    pub energy: Option<String>,
    /// Leave the momentum `J` out of the first integrals.
    pub without_momentum: bool,
    /// Give only the Casimirs `tr W^2` to `tr W^d` (`None`: to `tr W^N`,
    /// all of them). Not a departure from the model's dynamics, only from
    /// its full set of conserved quantities: for a state whose functional
    /// needs no higher power (solid-body rotation, `zeitlin_su_n`)
    /// the generic engine sees the same family of forms.
    pub casimir_degree: Option<usize>,
}

/// `i diag(v)` in [`basis`] coordinates.
fn diagonal(v: &[Rational]) -> Vec<Rational> {
    let mut mat = vec![vec![(q(0, 1), q(0, 1)); v.len()]; v.len()];
    for (j, row) in mat.iter_mut().enumerate() {
        row[j].1 = v[j].clone();
    }
    coordinates(&mat)
}

/// `tau_j = j - (N-1)/2`, the momentum's diagonal.
pub fn tau(n: usize) -> Vec<Rational> {
    (0..n).map(|j| q(2 * j as i64 + 1 - n as i64, 2)).collect()
}

/// The su(N) system about `W_e = i diag(omega)` with noise `X = hbar i
/// diag(y)`, i.e. `sigma = -i diag(y)`: the data a spec carries, as exact
/// values.
pub struct SuModel {
    /// `mu0`, `mu1`, ...
    pub names: Vec<String>,
    /// The structure constants `[e_a, e_b] = c^k_ab e_k`, `(a, b, k, c)`
    /// for `a < b` (integers).
    pub structure_constants: Vec<(usize, usize, usize, i64)>,
    /// `h = -1/2 mu^T M mu` (unperturbed).
    pub energy: Poly,
    /// `tr W^k`, `k = 2..=d` (`d = N` unless fewer are asked for), the real
    /// or imaginary part ([`trace_powers`]).
    pub casimirs: Vec<Poly>,
    /// `J = <W, i diag(tau)>`.
    pub momentum: Poly,
    /// `mu_e = <W_e, e_k>`.
    pub equilibrium: Vec<Rational>,
    /// `sigma = -i diag(y)` in coordinates.
    pub noise: Vec<Rational>,
}

pub fn su_model(omega: &[Rational], y: &[Rational], casimir_degree: Option<usize>) -> SuModel {
    let n = omega.len();
    let e = basis(n);
    let d = e.len();
    let names: Vec<String> = (0..d).map(|k| format!("mu{k}")).collect();
    // Structure constants [e_a, e_b] = c^k_ab e_k (integers).
    let mut structure_constants = Vec::new();
    for a in 0..d {
        for b in a + 1..d {
            for (k, x) in coordinates(&commutator(&e[a], &e[b])).iter().enumerate() {
                if *x != 0 {
                    structure_constants.push((a, b, k, *x));
                }
            }
        }
    }
    let g = gram(&e);
    let g_inv = g.inverse().expect("the Gram matrix is invertible");
    // h = -1/2 mu^T M mu.
    let m = energy_matrix(n, &e, &g);
    let var = |k: usize| Poly::var(d, k);
    let mut energy = Poly::zero(d);
    for a in 0..d {
        for b in 0..d {
            if m[a][b] != q(0, 1) {
                energy = energy.add(&var(a).mul(&var(b)).scale(&(&m[a][b] * &q(-1, 2))));
            }
        }
    }
    // W = sum_a x_a e_a with x = G^-1 mu, entrywise as polynomials in mu.
    let x: Vec<Poly> = (0..d).map(|a| Poly::linear(&g_inv.row(a))).collect();
    let w: PolyMatrix = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let mut re = Poly::zero(d);
                    let mut im = Poly::zero(d);
                    for (xa, ea) in x.iter().zip(&e) {
                        re = re.add(&xa.scale(&q(ea[i][j].0, 1)));
                        im = im.add(&xa.scale(&q(ea[i][j].1, 1)));
                    }
                    (re, im)
                })
                .collect()
        })
        .collect();
    let casimirs = trace_powers(&w, d, casimir_degree.unwrap_or(n));
    // J = <W, i diag(tau)> = sum_k t_k <W, e_k> = sum_k t_k mu_k, with t the
    // coordinates of i diag(tau).
    let momentum = Poly::linear(&diagonal(&tau(n)));
    // mu_e = <W_e, e_k> = G a, a the coordinates of W_e.
    let equilibrium = g.mul_vec(&diagonal(omega));
    let noise: Vec<Rational> = diagonal(y).iter().map(|c| -c).collect();
    SuModel { names, structure_constants, energy, casimirs, momentum, equilibrium, noise }
}

/// The su(N) spec about `W_e = i diag(omega)` with noise `X = hbar i
/// diag(y)`, i.e. `sigma = -i diag(y)` ([`su_model`] as JSON).
pub fn su_spec(omega: &[Rational], y: &[Rational], perturbation: &Perturbation) -> serde_json::Value {
    let n = omega.len();
    let model = su_model(omega, y, perturbation.casimir_degree);
    let names = &model.names;
    let rows: Vec<serde_json::Value> =
        model.structure_constants.iter().map(|&(a, b, k, x)| json!([a, b, k, x])).collect();
    let mut h_text = model.energy.to_string_with(names);
    if let Some(extra) = &perturbation.energy {
        h_text = format!("{h_text} + {extra}");
    }
    let casimirs: Vec<String> = model.casimirs.iter().map(|c| c.to_string_with(names)).collect();
    let momentum = model.momentum.to_string_with(names);
    let first_integrals = if perturbation.without_momentum { vec![] } else { vec![momentum] };
    let sigma: Vec<String> = model.noise.iter().map(|c| c.to_string()).collect();
    json!({
        "name": format!("zeitlin-su{n}-generic"),
        "algebra": {"coordinates": names, "structure_constants": rows},
        "hamiltonian": h_text,
        "casimirs": casimirs,
        "first_integrals": first_integrals,
        "equilibrium": model.equilibrium.iter().map(|v| v.to_string()).collect::<Vec<_>>(),
        "noise": [sigma],
    })
}

/// [`SuModel`] as a `casimir::System` (the library API) with the given
/// first integrals; `Err` if `System::new` refuses it (it checks the
/// Casimirs and `{F, h} = 0` exactly, as the spec parser does).
pub fn su_system_with(model: &SuModel, first_integrals: Vec<Poly>) -> Result<casimir::System, casimir::SystemError> {
    let rows: Vec<(usize, usize, usize, Rational)> =
        model.structure_constants.iter().map(|&(a, b, k, x)| (a, b, k, q(x, 1))).collect();
    let algebra =
        algebra::LieAlgebra::from_structure_constants("su(N)", &model.names, &rows).expect("su(N) is a Lie algebra");
    casimir::System::new(
        algebra,
        model.energy.clone(),
        model.casimirs.clone(),
        first_integrals,
        model.equilibrium.clone(),
        vec![model.noise.clone()],
    )
}

/// The su(N) system with `perturbation`, given through `route`; `Err` is
/// the message of its refusal (by the spec parser or `System::new`).
pub fn perturbed_system(
    omega: &[Rational],
    y: &[Rational],
    perturbation: &Perturbation,
    route: Route,
) -> Result<(casimir::System, Option<spec::Spec>), String> {
    match route {
        Route::Spec => {
            let spec = spec::parse_spec(&su_spec(omega, y, perturbation).to_string()).map_err(|e| e.to_string())?;
            Ok((spec.system.clone(), Some(spec)))
        }
        Route::Library => {
            let mut model = su_model(omega, y, perturbation.casimir_degree);
            if let Some(extra) = &perturbation.energy {
                let symbols = exact::Symbols::new(&model.names);
                model.energy = model.energy.add(&exact::parse_expression(extra, &symbols).unwrap());
            }
            let momentum = if perturbation.without_momentum { vec![] } else { vec![model.momentum.clone()] };
            let system = su_system_with(&model, momentum).map_err(|e| e.to_string())?;
            Ok((system, None))
        }
    }
}

/// The exact level on a system: the certificate and its analysis through a
/// spec, or the analysis alone.
fn exact_level(
    system: &casimir::System,
    spec: Option<&spec::Spec>,
) -> (generator::Analysis, Option<serde_json::Value>) {
    match spec {
        Some(spec) => {
            let certificate = spec::certify_lie(spec);
            (certificate.analysis, Some(certificate.json))
        }
        None => (generator::analyse(system, &generator::Settings::default()), None),
    }
}

/// The generic engine's analyses of the su(N) system about `W_e = i
/// diag(omega)` (the exact level, no `"exact": false`), and the Zeitlin
/// pipeline's of the same state.
pub fn case(omega: &[Rational], y: &[Rational], route: Route) -> Case {
    case_with(omega, y, route, None)
}

/// [`case`] with only the Casimirs `tr W^2` to `tr W^d` (`None`: all).
pub fn case_with(omega: &[Rational], y: &[Rational], route: Route, casimir_degree: Option<usize>) -> Case {
    let n = omega.len();
    let start = Instant::now();
    let model = Perturbation { casimir_degree, ..Default::default() };
    let (system, spec) = perturbed_system(omega, y, &model, route).expect("the su(N) system is accepted");
    let system_time = start.elapsed();
    let start = Instant::now();
    let (analysis, cert) = exact_level(&system, spec.as_ref());
    let exact_time = start.elapsed();
    let start = Instant::now();
    // The spec's settings are the defaults.
    let numeric = generator::analyse_numeric(&system, &generator::Settings::default());
    let numeric_time = start.elapsed();
    // The Zeitlin pipeline in its own units (docs/zeitlin.md: hbar = 2/sqrt(N^2 - 1)).
    let hbar = 2.0 / ((n * n - 1) as f64).sqrt();
    let problem = ZeitlinProblem {
        n,
        omega: omega.iter().map(exact::rational_to_f64).collect(),
        noise: vec![y.iter().map(|v| exact::rational_to_f64(v) * hbar).collect()],
    };
    let forced = analyse(&problem, &ZeitlinSettings { casimir_momentum: false, ..Default::default() }).unwrap();
    let free = analyse(&problem, &ZeitlinSettings::default()).unwrap();
    Case { system, cert, analysis, numeric, forced, free, system_time, exact_time, numeric_time }
}

/// The degree-2 zonal noise `i diag(y)`, `y = (tau_j^2 - mean(tau^2))/10`:
/// orthogonal to the trace and to `tau` (a degree-1 field is a rotation
/// about the axis, which keeps every form). At N = 4, `(1, -1, -1, 1)/10`;
/// at N = 5, `(2, -1, -2, -1, 2)/10`.
pub fn degree_two_noise(n: usize) -> Vec<Rational> {
    let t = tau(n);
    let squares: Vec<Rational> = t.iter().map(|v| v * v).collect();
    let mut mean = q(0, 1);
    for s in &squares {
        mean = &mean + s;
    }
    let mean = &mean * &q(1, n as i64);
    squares.iter().map(|s| &(s - &mean) * &q(1, 10)).collect()
}

/// `v / 5`, exactly.
pub fn fifths(v: &[i64]) -> Vec<Rational> {
    v.iter().map(|&x| q(x, 5)).collect()
}

/// The generic engine's `P` and `Q` for the functional `eps h + C + beta J`
/// (`C` the combination of the Casimirs that makes it critical at `mu_e`,
/// unique once `beta` is fixed), exactly, from the system's own
/// polynomials and `generator::linearise`.
pub struct GenericForm {
    pub p: Matrix,
    pub q: Matrix,
    pub drift_residual: Matrix,
}

pub fn generic_form(system: &casimir::System, eps: &Rational, beta: &Rational) -> GenericForm {
    let mu = system.equilibrium();
    let d = system.dim();
    let casimirs = system.casimirs();
    let j = &system.first_integrals()[0];
    let grads: Vec<Vec<Rational>> = casimirs.iter().map(|c| c.gradient_at(mu)).collect();
    let g = Matrix::from_columns(d, &grads);
    let dj = j.gradient_at(mu);
    let rhs: Vec<Rational> =
        system.hamiltonian_gradient().iter().zip(&dj).map(|(h, jj)| -(&(eps * h) + &(beta * jj))).collect();
    let nu = g.solve_affine(&rhs).expect("the functional is critical at mu_e for some Casimir multipliers");
    assert!(nu.directions.is_empty(), "the Casimir multipliers are unique once beta is fixed");
    let mut p = system.hamiltonian_hessian().scale(eps);
    for (c, l) in casimirs.iter().zip(&nu.particular) {
        p.add_scaled_assign(l, &Matrix::from_rows(&c.hessian_at(mu)));
    }
    let form = generator::generator_form(&generator::linearise(system), &p);
    GenericForm { p, q: form.q, drift_residual: form.drift_residual }
}

/// `lambda_max(Q, P)` on the coordinates `idx` (`P` positive definite there):
/// the largest eigenvalue of `L^-1 Q L^-T`, `P = L L^T`, in floating point.
pub fn lambda_max_on(p: &Matrix, q: &Matrix, idx: &[usize]) -> f64 {
    let sub = |m: &Matrix| DMatrix::from_fn(idx.len(), idx.len(), |i, j| exact::rational_to_f64(&m[(idx[i], idx[j])]));
    let l = sub(p).cholesky().expect("P is positive definite on these coordinates").l();
    let li = l.clone().try_inverse().unwrap();
    let c = &li * sub(q) * li.transpose();
    let c = (&c + c.transpose()) * 0.5;
    c.symmetric_eigen().eigenvalues.max()
}

/// The spec's polynomials are the model's functionals: at fixed points
/// `mu` (not near the equilibrium), with `W = sum x_a e_a`, `x = G^-1 mu`,
/// in dense complex floating point, `h = -1/2 <W, P>` with `P` solving the
/// spin-matrix Laplacian `Delta P = W` (plus the trace projector, which
/// makes the operator invertible and keeps `P` trace-free), `tr W^k` (real
/// part for even `k`, imaginary for odd) and `J = <W, i diag(tau)>`; and
/// `mu_e` is `W_e = i diag(omega)`. `tolerance` is relative to the
/// functional's scale (`|W|^2`, `|W^k|`, `|W|`). Returns the largest
/// relative difference seen.
pub fn check_spec_polynomials(omega: &[Rational], y: &[Rational], tolerance: f64, route: Route) -> f64 {
    let n = omega.len();
    let (system, _) = perturbed_system(omega, y, &Perturbation::default(), route).unwrap();
    let system = &system;
    let e = basis(n);
    let d = e.len();
    let g_inv = gram(&e).inverse().unwrap().to_dmatrix();
    let c = |re: f64, im: f64| Complex::new(re, im);
    let matrix_of = |mu: &[f64]| -> DMatrix<Complex<f64>> {
        let x = &g_inv * nalgebra::DVector::from_column_slice(mu);
        let mut w = DMatrix::from_element(n, n, c(0.0, 0.0));
        for (xa, ea) in x.iter().zip(&e) {
            w += DMatrix::from_fn(n, n, |i, j| c(ea[i][j].0 as f64, ea[i][j].1 as f64) * *xa);
        }
        w
    };
    let inner_f = |a: &DMatrix<Complex<f64>>, b: &DMatrix<Complex<f64>>| (a * b.adjoint()).trace().re / n as f64;
    // Delta + (trace projector) on vec(X), column-major.
    let op = DMatrix::from_fn(n * n, n * n, |r, col| {
        let mut x = DMatrix::from_element(n, n, c(0.0, 0.0));
        x[(col % n, col / n)] = c(1.0, 0.0);
        let mut y = spin_laplacian(n, &x);
        let t = x.trace() / c(n as f64, 0.0);
        for i in 0..n {
            y[(i, i)] += t;
        }
        y[(r % n, r / n)]
    });
    let lu = op.lu();
    let tau_matrix =
        DMatrix::from_fn(n, n, |i, j| if i == j { c(0.0, i as f64 - (n as f64 - 1.0) / 2.0) } else { c(0.0, 0.0) });
    assert_eq!(system.casimirs().len(), n - 1);
    let mut worst: f64 = 0.0;
    for point in 0..5 {
        let mu: Vec<f64> = (0..d).map(|k| (1.0 + 2.3 * (k + d * point) as f64).sin()).collect();
        let w = matrix_of(&mu);
        let p = lu.solve(&nalgebra::DVector::from_iterator(n * n, w.iter().copied())).unwrap();
        let p = DMatrix::from_column_slice(n, n, p.as_slice());
        let mut expected = vec![(system.hamiltonian(), -0.5 * inner_f(&w, &p), inner_f(&w, &w))];
        let mut power = w.clone();
        for (k, casimir) in (2..=n).zip(system.casimirs()) {
            power = &power * &w;
            let t = power.trace();
            expected.push((casimir, if k % 2 == 0 { t.re } else { t.im }, power.norm()));
        }
        expected.push((&system.first_integrals()[0], inner_f(&w, &tau_matrix), w.norm()));
        for (k, (poly, value, scale)) in expected.into_iter().enumerate() {
            let got = poly.eval_f64(&mu);
            let relative = (got - value).abs() / scale;
            worst = worst.max(relative);
            assert!(relative <= tolerance, "point {point}, functional {k}: {got} vs {value}");
        }
    }
    let mu_e: Vec<f64> = system.equilibrium().iter().map(exact::rational_to_f64).collect();
    let w_e = matrix_of(&mu_e);
    for i in 0..n {
        for j in 0..n {
            let expected = if i == j { c(0.0, exact::rational_to_f64(&omega[i])) } else { c(0.0, 0.0) };
            assert!((w_e[(i, j)] - expected).norm() < 1e-15, "W_e at ({i}, {j})");
        }
    }
    worst
}

/// What [`check_monotone`] measured, for the docs.
#[derive(Debug)]
pub struct MonotoneReport {
    /// The generic engine's certified `Sigma^2` (exact level).
    pub generic_sigma2: f64,
    /// `generator::analyse_numeric`'s `Sigma^2`.
    pub numeric_sigma2: f64,
    /// The Zeitlin pipeline's `Sigma^2` (paper's family) and its `beta`.
    pub zeitlin_sigma2: f64,
    pub zeitlin_beta: f64,
    /// The generic engine's first definite choice's `Sigma^2`.
    pub first_definite: f64,
    /// Per block `m`: the generic engine's `lambda_max` at the Zeitlin
    /// functional, the Zeitlin pipeline's, and the Zeitlin bisection's
    /// bracket width (`residual`).
    pub blocks: Vec<(usize, f64, f64, f64)>,
    pub system_time: Duration,
    pub exact_time: Duration,
    pub numeric_time: Duration,
}

fn all_zero(v: &[Rational]) -> bool {
    v.iter().all(|x| *x == q(0, 1))
}

/// A monotone state: `stable` in both engines and both levels, the exact
/// equilibrium and noise residuals zero, the infimum 0 approached by both,
/// and at the Zeitlin pipeline's own `(eps, beta)` the generic engine's
/// exact `P`, `Q` give the Zeitlin `lambda_max` of every block to
/// `tolerance` relative (to the Zeitlin `Sigma^2`). The reasons behind each
/// assertion are in `zeitlin_su_n`'s module documentation. The exact level's
/// analysis is checked on either route, and its certificate's record of
/// the same on [`Route::Spec`].
pub fn check_monotone(omega: &[Rational], y: &[Rational], tolerance: f64, route: Route) -> MonotoneReport {
    check_monotone_with(omega, y, tolerance, route, None)
}

/// [`check_monotone`] with only the Casimirs `tr W^2` to `tr W^d` given to
/// the generic engine (`None`: all). The state must be one whose
/// functionals need no higher power.
pub fn check_monotone_with(
    omega: &[Rational],
    y: &[Rational],
    tolerance: f64,
    route: Route,
    casimir_degree: Option<usize>,
) -> MonotoneReport {
    let n = omega.len();
    let c = case_with(omega, y, route, casimir_degree);
    let a = &c.analysis;
    // The zonal claim: exact zero residuals, so not `not_an_equilibrium`.
    assert_eq!(a.verdict, Verdict::Stable, "{}", a.reason);
    assert!(all_zero(&a.equilibrium_residual));
    assert!(all_zero(&a.noise_residuals[0]));
    let evidence = a.stable.as_ref().unwrap();
    assert!(evidence.exact.is_some(), "the exact level proves Sigma^2");
    assert_eq!(evidence.choice.sign, Sign::Positive);
    let generic = a.sigma2().unwrap();
    let first = evidence.first_sigma2;
    let optimum = evidence.optimum.as_ref().expect("the minimisation improved on the first choice");
    if let Some(cert) = &c.cert {
        assert_eq!(cert["verdict"], "stable", "{}", cert["reason"]);
        assert_eq!(cert["level"], "exact");
        assert!(cert["equilibrium"]["residual"].as_array().unwrap().iter().all(|r| r == "0"));
        assert!(cert["noise"]["residuals"][0].as_array().unwrap().iter().all(|r| r == "0"));
        assert_eq!(cert["casimir_choice"]["sign"], 1);
        assert_eq!(cert["sigma2"].as_f64().unwrap(), generic);
        assert_eq!(cert["optimisation"]["first_definite_sigma2"].as_f64().unwrap(), first);
        assert_eq!(cert["optimisation"]["attained"], false);
        if let Some(lb) = cert["optimisation"].get("infimum_lower_bound") {
            assert_eq!(lb, "0", "a positive certified lower bound would contradict the infimum 0");
        }
    }
    // The numeric level: the momentum's gradient at a zonal state lies in
    // the span of the Casimirs' (all Cartan), so the multipliers are a
    // one-parameter family and `analyse_numeric` takes the exact pipeline
    // with `exact = false` (its documented scope), which agrees.
    assert_eq!(c.numeric.verdict, Verdict::Stable, "{}", c.numeric.reason);
    assert_eq!(c.numeric.route, NumericRoute::ExactPipeline("free multipliers (a family to optimise over)"));
    let numeric = c.numeric.sigma2.unwrap();
    assert!((numeric - generic).abs() <= tolerance * generic, "numeric {numeric:e} vs exact level {generic:e}");
    // The Zeitlin pipeline, paper's family: stable with the same sign.
    assert_eq!(c.forced.verdict, Verdict::Stable, "{}", c.forced.reason);
    let choice = c.forced.choice.unwrap();
    assert_eq!(choice.energy, 1.0);
    let zs = c.forced.sigma2.unwrap();
    // The infimum 0, approached.
    assert!(generic > 0.0 && zs > 0.0);
    assert!(generic < 1e-3 * first && zs < 1e-3 * first, "generic {generic:e}, zeitlin {zs:e}, first {first:e}");
    assert!(!optimum.attained);
    assert!(!c.forced.attained);
    if let Some(lb) = &optimum.infimum_lower_bound {
        assert_eq!(*lb, q(0, 1), "a positive certified lower bound would contradict the infimum 0");
    }
    // The same functional in both engines.
    let system = &c.system;
    let eps = q(1, 1);
    let beta = exact::rational_from_f64(choice.momentum).unwrap();
    let at_zeitlin = generic_form(system, &eps, &beta);
    assert!(at_zeitlin.drift_residual.is_zero(), "the functional is conserved by the linearised drift, exactly");
    let all: Vec<usize> = (1..n).flat_map(|m| block(n, m)).collect();
    let value = lambda_max_on(&at_zeitlin.p, &at_zeitlin.q, &all).max(0.0);
    assert!((value - zs).abs() <= tolerance * zs, "generic {value:e} vs zeitlin {zs:e} at beta = {}", choice.momentum);
    assert!(value <= c.forced.sigma2_upper.unwrap(), "the Zeitlin pipeline's proved bound");
    let mut blocks = Vec::new();
    assert_eq!(c.forced.blocks.iter().map(|b| b.m).collect::<Vec<_>>(), (1..n).collect::<Vec<_>>());
    for b in &c.forced.blocks {
        let value = lambda_max_on(&at_zeitlin.p, &at_zeitlin.q, &block(n, b.m));
        assert!(
            (value - b.lambda_max).abs() <= tolerance * zs,
            "block {}: generic {value:e} vs zeitlin {:e}",
            b.m,
            b.lambda_max
        );
        blocks.push((b.m, value, b.lambda_max, b.residual));
    }
    // The generic engine's own choice lies on the same curve: its `J`
    // multiplier (after the Casimirs') is the Zeitlin `beta` (the
    // Cartan block of `P`, where the Casimir Hessian is free, does not enter
    // Sigma^2: `Q` vanishes there).
    let multipliers = &evidence.choice.multipliers;
    let nc = system.casimirs().len();
    assert_eq!(nc, casimir_degree.unwrap_or(n) - 1);
    assert_eq!(multipliers.len(), nc + 1);
    let at_generic = generic_form(system, &eps, &multipliers[nc]);
    let value = lambda_max_on(&at_generic.p, &at_generic.q, &all).max(0.0);
    assert!((value - generic).abs() <= tolerance * generic, "curve {value:e} vs certificate {generic:e}");
    // The Casimir–momentum form: Sigma^2 = 0 in the Zeitlin pipeline, and
    // in the generic engine Q = 0 exactly with P exactly definite off the
    // Cartan block.
    assert_eq!(c.free.verdict, Verdict::Stable);
    assert_eq!(c.free.sigma2, Some(0.0));
    let free = c.free.choice.unwrap();
    assert_eq!(free.energy, 0.0);
    let cm = generic_form(system, &q(0, 1), &exact::rational_from_f64(free.momentum).unwrap());
    assert!(cm.q.is_zero() && cm.drift_residual.is_zero());
    let p_off = Matrix::from_fn(all.len(), all.len(), |i, j| cm.p[(all[i], all[j])].clone());
    assert_eq!(p_off.definiteness(), Some(Sign::Positive));
    MonotoneReport {
        generic_sigma2: generic,
        numeric_sigma2: numeric,
        zeitlin_sigma2: zs,
        zeitlin_beta: choice.momentum,
        first_definite: first,
        blocks,
        system_time: c.system_time,
        exact_time: c.exact_time,
        numeric_time: c.numeric_time,
    }
}

/// A state that is not monotone: neither engine finds a definite form, and
/// both find the spectrum on the imaginary axis (the generic engine proves
/// it exactly by a Sturm sequence).
pub fn check_non_monotone(omega: &[Rational], y: &[Rational], route: Route) -> Case {
    let c = case(omega, y, route);
    let a = &c.analysis;
    assert_eq!(a.verdict, Verdict::Inconclusive, "{}", a.reason);
    assert!(all_zero(&a.equilibrium_residual));
    assert!(a.reason.contains("imaginary axis (proved exactly)"), "{}", a.reason);
    if let Some(cert) = &c.cert {
        assert_eq!(cert["verdict"], "inconclusive", "{}", cert["reason"]);
        assert!(cert["equilibrium"]["residual"].as_array().unwrap().iter().all(|r| r == "0"));
        assert!(cert["reason"].as_str().unwrap().contains("imaginary axis (proved exactly)"));
    }
    assert_eq!(c.numeric.verdict, Verdict::Inconclusive, "{}", c.numeric.reason);
    for z in [&c.forced, &c.free] {
        assert_eq!(z.verdict, Verdict::Inconclusive, "{}", z.reason);
        assert!(z.reason.contains("imaginary axis"), "{}", z.reason);
    }
    c
}

/// A linearly unstable state: both engines say `linearly_unstable`, the
/// generic engine proves it exactly (a Sturm sequence on the characteristic
/// polynomial), and the growth rates agree to `tolerance` relative. The
/// generic engine's time is in units of `hbar` (`W' = [P, W]` against
/// Zeitlin's `[P, W]/hbar`), so its rate is divided by `hbar`. Returns the
/// two rates and the case.
pub fn check_unstable(omega: &[Rational], y: &[Rational], tolerance: f64, route: Route) -> (f64, f64, Case) {
    check_unstable_with(omega, y, tolerance, route, None)
}

/// [`check_unstable`] with only the Casimirs `tr W^2` to `tr W^d` given to
/// the generic engine (`None`: all): its instability proof is about the
/// spectrum of the linearised drift, which no Casimir enters.
pub fn check_unstable_with(
    omega: &[Rational],
    y: &[Rational],
    tolerance: f64,
    route: Route,
    casimir_degree: Option<usize>,
) -> (f64, f64, Case) {
    let n = omega.len();
    let c = case_with(omega, y, route, casimir_degree);
    let a = &c.analysis;
    assert_eq!(a.verdict, Verdict::LinearlyUnstable, "{}", a.reason);
    assert!(all_zero(&a.equilibrium_residual));
    assert!(matches!(a.spectral_proof, Some(generator::SpectralProof::Unstable { .. })), "{}", a.reason);
    if let Some(cert) = &c.cert {
        assert_eq!(cert["verdict"], "linearly_unstable", "{}", cert["reason"]);
        assert_eq!(cert["level"], "exact");
    }
    assert_eq!(c.numeric.verdict, Verdict::LinearlyUnstable, "{}", c.numeric.reason);
    for z in [&c.forced, &c.free] {
        assert_eq!(z.verdict, Verdict::LinearlyUnstable, "{}", z.reason);
    }
    let hbar = 2.0 / ((n * n - 1) as f64).sqrt();
    let generic = a.instability.as_ref().unwrap().eigenvalue.re / hbar;
    let zeitlin = c.forced.growth_rate.unwrap();
    assert_eq!(c.free.growth_rate, Some(zeitlin));
    assert!((generic - zeitlin).abs() <= tolerance * zeitlin, "generic {generic:e} vs zeitlin {zeitlin:e}");
    (generic, zeitlin, c)
}

/// `2^-60`, as the energy's text writes it.
const TINY: &str = "1/1152921504606846976";

/// The perturbations that must fail: the rounded energy keeps the
/// equilibrium and the momentum only because its floating-point blocks
/// leave the exact zeros of the block structure alone and are the same
/// doubles on the real and the imaginary part of a diagonal. A coupling of
/// 2^-60 between `mu0` (the real part of entry (0, 1), diagonal 1) and the
/// first Cartan coordinate (what a dense floating-point inverse of `G L`
/// could leave behind) moves `Dh(mu_e)` off the Cartan directions:
/// `not_an_equilibrium` (the momentum left out, since the coupling also
/// breaks `{J, h} = 0`). A change of 2^-60 on the real part of diagonal 1
/// alone breaks the momentum: the system is refused.
pub fn check_perturbations_fail(omega: &[Rational], y: &[Rational], route: Route) {
    let n = omega.len();
    let first_cartan = n * (n - 1);
    let coupled = Perturbation {
        energy: Some(format!("{TINY}*mu0*mu{first_cartan}")),
        without_momentum: true,
        ..Default::default()
    };
    let (system, spec) = perturbed_system(omega, y, &coupled, route).unwrap();
    assert!(!all_zero(&system.equilibrium_residual()));
    let (analysis, cert) = exact_level(&system, spec.as_ref());
    assert_eq!(analysis.verdict, Verdict::NotAnEquilibrium, "{}", analysis.reason);
    if let Some(cert) = cert {
        assert_eq!(cert["verdict"], "not_an_equilibrium", "{}", cert["reason"]);
    }
    // Control: the same system without the coupling is an equilibrium (its
    // residual, what decides `not_an_equilibrium`, is exactly zero; through
    // a spec, as a certificate; the library route skips that full analysis,
    // 15 s at N = 6).
    let plain = Perturbation { without_momentum: true, ..Default::default() };
    let (system, spec) = perturbed_system(omega, y, &plain, route).unwrap();
    assert!(all_zero(&system.equilibrium_residual()));
    if let Some(spec) = spec {
        assert_ne!(spec::certify_lie(&spec).json["verdict"], "not_an_equilibrium");
    }
    let unequal = Perturbation { energy: Some(format!("{TINY}*mu0^2")), without_momentum: false, ..Default::default() };
    let err = match perturbed_system(omega, y, &unequal, route) {
        Ok(_) => panic!("a system with {{J, h}} != 0 was accepted"),
        Err(err) => err,
    };
    assert!(err.contains("first integral 0 is not conserved"), "{err}");
}
