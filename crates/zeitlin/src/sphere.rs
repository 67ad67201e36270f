//! States that need not be zonal: quflow's real spherical-harmonic basis
//! `T_lm` of `u(N)`, the spin matrices, and rotations of the sphere.
//!
//! **The basis** (quflow's `shr2mat`/`elmr2mat`, which the tests check
//! against quflow's own output). For `m = |m'|`, let `b_{l m}` be the
//! eigenvector of the Laplacian block on diagonal `m`
//! ([`crate::laplacian::block`]) for `-l (l + 1)`, `l = m..N-1`, of unit
//! length times `sqrt(N)`, signed so that its last entry is positive for
//! even `m` and negative for odd `m`. With `sgn = (-1)^m`:
//!
//! * `T_l0 = i diag(b_{l0})`;
//! * `T_{l,m}`, `m > 0`: `i sgn b_{lm} / sqrt 2` on both the `m`-th upper
//!   diagonal (`W[j, j + m]`) and the `m`-th lower one (`W[j + m, j]`);
//! * `T_{l,-m}`, `m > 0`: `sgn b_{lm} / sqrt 2` on the upper and its
//!   negative on the lower diagonal.
//!
//! Each `T_lm` is skew-Hermitian with `<T_lm, T_lm> = 1` for quflow's
//! `<A, B> = Re tr(A B^*)/N`, and they are orthogonal; `T_00 = i I` is the
//! trace, which su(N) leaves out. A state is `W = sum v_lm T_lm`, quflow's
//! `omega` vector holding `v_lm` at index `l^2 + l + m`.
//!
//! **Spin and rotations.** `S_3 = diag(s - j)`, `s = (N - 1)/2`, and the
//! ladder `S_+[j - 1, j] = sqrt(j (N - j))`, as in the Laplacian's
//! derivation. The Laplacian commutes with `Ad_V` for `V = exp(-i theta u.S)`
//! (it is `-sum_a ad_{S_a}^2`, and `Ad_V` rotates the `S_a` among
//! themselves), so a state that commutes with `n.S` is zonal about the axis
//! `n`, and [`rotation_to_axis`] turns it into a diagonal one.

use crate::laplacian::{block, GeneralTridiagonalFactor};
use nalgebra::{Complex, DMatrix};

type C = Complex<f64>;

/// Why a basis vector or a rotation could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SphereError {
    /// `(l, m)` is not a harmonic of `u(N)`: `|m| <= l < N` is required.
    #[error("no harmonic (l, m) = ({l}, {m}) for N = {n}: |m| <= l <= N - 1 is required")]
    OutOfRange {
        /// `N`.
        n: usize,
        /// `l`.
        l: usize,
        /// `m`.
        m: i64,
    },
    /// A numerical step failed (the message says which).
    #[error("numerical breakdown: {0}")]
    Numerical(String),
}

/// `b_{lm}`: the eigenvector of [`block`]`(n, m)` for `-l (l + 1)`, length
/// `n - m`, normalised to `sqrt(n)` and signed as quflow does.
///
/// By inverse iteration with the known eigenvalue, shifted off it by a
/// relative 1e-10 (the eigenvalue gaps are at least `2 (l + 1)`, so each
/// step gains a factor of about 1e10 over every other eigenvector; four
/// steps from a fixed start vector): `O(n)`.
///
/// ```
/// // N = 2, m = 0, l = 1: block [[-1, 1], [1, -1]], eigenvector (1, -1)/sqrt 2
/// // for -2; times sqrt(2), last entry positive: (-1, 1)
/// let b = zeitlin::sphere::basis_vector(2, 1, 0).unwrap();
/// assert!((b[0] + 1.0).abs() < 1e-14 && (b[1] - 1.0).abs() < 1e-14);
/// ```
pub fn basis_vector(n: usize, l: usize, m: usize) -> Result<Vec<f64>, SphereError> {
    if m > l || l >= n {
        return Err(SphereError::OutOfRange { n, l, m: m as i64 });
    }
    let lap = block(n, m);
    let len = n - m;
    let lambda = -((l * (l + 1)) as f64);
    let mut v: Vec<f64> = (0..len).map(|j| 1.0 + 0.5 * ((j as f64) * 0.754_877_666_2).sin()).collect();
    if len > 1 {
        // (A factor singular in floating point at the first shift retries further off.)
        let factor = [1e-10, 1e-8, 1e-6]
            .iter()
            .find_map(|rel| {
                let shift = lambda * (1.0 + rel) + rel;
                let diag: Vec<f64> = lap.diag.iter().map(|d| d - shift).collect();
                GeneralTridiagonalFactor::new(&lap.off, &diag, &lap.off)
            })
            .ok_or_else(|| SphereError::Numerical(format!("the shifted Laplacian block (l, m) = ({l}, {m})")))?;
        for _ in 0..4 {
            if !factor.solve(&mut v) {
                return Err(SphereError::Numerical(format!("inverse iteration for (l, m) = ({l}, {m})")));
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(SphereError::Numerical(format!("inverse iteration for (l, m) = ({l}, {m})")));
            }
            v.iter_mut().for_each(|x| *x /= norm);
        }
    } else {
        v = vec![1.0];
    }
    let scale = (n as f64).sqrt();
    // quflow's adjust_basis_orientation_: the last entry positive for even
    // m, negative for odd m (it is never zero: the block is unreduced).
    let want_positive = m % 2 == 0;
    let flip = (v[len - 1] > 0.0) != want_positive;
    v.iter_mut().for_each(|x| *x *= if flip { -scale } else { scale });
    Ok(v)
}

/// The real harmonic `T_lm` as an `n x n` matrix (see the module docs).
///
/// ```
/// use zeitlin::sphere::harmonic;
/// let t = harmonic(5, 3, -2).unwrap();
/// // skew-Hermitian, unit norm for <A, B> = Re tr(A B*)/N
/// assert!((&t + t.adjoint()).norm() < 1e-14);
/// assert!(((t.norm_squared() / 5.0) - 1.0).abs() < 1e-13);
/// ```
pub fn harmonic(n: usize, l: usize, m: i64) -> Result<DMatrix<C>, SphereError> {
    let mut w = DMatrix::zeros(n, n);
    add_harmonic(&mut w, l, m, 1.0)?;
    Ok(w)
}

/// `W += v T_lm`.
fn add_harmonic(w: &mut DMatrix<C>, l: usize, m: i64, v: f64) -> Result<(), SphereError> {
    let n = w.nrows();
    let am = m.unsigned_abs() as usize;
    if am > l || l >= n {
        return Err(SphereError::OutOfRange { n, l, m });
    }
    let b = basis_vector(n, l, am)?;
    if am == 0 {
        for (j, bj) in b.iter().enumerate() {
            w[(j, j)] += C::new(0.0, v * bj);
        }
        return Ok(());
    }
    let sgn = if am % 2 == 0 { 1.0 } else { -1.0 };
    let c = sgn * v / std::f64::consts::SQRT_2;
    for (j, bj) in b.iter().enumerate() {
        let x = c * bj;
        if m > 0 {
            w[(j, j + am)] += C::new(0.0, x);
            w[(j + am, j)] += C::new(0.0, x);
        } else {
            w[(j, j + am)] += C::new(x, 0.0);
            w[(j + am, j)] += C::new(-x, 0.0);
        }
    }
    Ok(())
}

/// `W = sum v T_lm` over the given `(l, m, v)`.
///
/// ```
/// use zeitlin::sphere::{from_harmonics, harmonic};
/// let w = from_harmonics(4, &[(1, 0, 2.0), (2, 1, -0.5)]).unwrap();
/// let t = harmonic(4, 2, 1).unwrap() * nalgebra::Complex::new(-0.5, 0.0) + harmonic(4, 1, 0).unwrap() * nalgebra::Complex::new(2.0, 0.0);
/// assert!((w - t).norm() < 1e-14);
/// ```
pub fn from_harmonics(n: usize, coefficients: &[(usize, i64, f64)]) -> Result<DMatrix<C>, SphereError> {
    let mut w = DMatrix::zeros(n, n);
    for &(l, m, v) in coefficients {
        add_harmonic(&mut w, l, m, v)?;
    }
    Ok(w)
}

/// The coefficients `v_lm = <W, T_lm>` of a matrix for `1 <= l <= lmax`,
/// `-l <= m <= l`, as `(l, m, v)` in quflow's order (`l^2 + l + m`).
/// `O(lmax^2 N)` (each `T_lm` has `2 (N - |m|)` entries).
///
/// ```
/// use zeitlin::sphere::{from_harmonics, to_harmonics};
/// let w = from_harmonics(6, &[(2, -1, 0.25), (5, 3, 1.5)]).unwrap();
/// let v = to_harmonics(&w, 5).unwrap();
/// for (l, m, x) in v {
///     let want = match (l, m) { (2, -1) => 0.25, (5, 3) => 1.5, _ => 0.0 };
///     assert!((x - want).abs() < 1e-13, "({l}, {m}): {x}");
/// }
/// ```
pub fn to_harmonics(w: &DMatrix<C>, lmax: usize) -> Result<Vec<(usize, i64, f64)>, SphereError> {
    let n = w.nrows();
    let lmax = lmax.min(n.saturating_sub(1));
    let nf = n as f64;
    // Diagonals that hold nothing have zero coefficients: their basis
    // vectors are not formed (a zonal matrix costs O(lmax N), not O(lmax^2 N)).
    let empty: Vec<bool> = (0..n)
        .map(|m| (0..n - m).all(|j| w[(j, j + m)] == C::new(0.0, 0.0) && w[(j + m, j)] == C::new(0.0, 0.0)))
        .collect();
    let mut out = Vec::new();
    for l in 1..=lmax {
        for m in -(l as i64)..=(l as i64) {
            let am = m.unsigned_abs() as usize;
            if empty[am] {
                out.push((l, m, 0.0));
                continue;
            }
            let b = basis_vector(n, l, am)?;
            // <W, T> = Re tr(W T^*)/N = Re sum_jk W_jk conj(T_jk) / N.
            let mut s = 0.0;
            if am == 0 {
                for (j, bj) in b.iter().enumerate() {
                    s += w[(j, j)].im * bj;
                }
            } else {
                let sgn = if am % 2 == 0 { 1.0 } else { -1.0 };
                let c = sgn / std::f64::consts::SQRT_2;
                for (j, bj) in b.iter().enumerate() {
                    let (up, lo) = (w[(j, j + am)], w[(j + am, j)]);
                    s += if m > 0 { c * bj * (up.im + lo.im) } else { c * bj * (up.re - lo.re) };
                }
            }
            out.push((l, m, s / nf));
        }
    }
    Ok(out)
}

/// The spin matrices `[S_1, S_2, S_3]` for spin `s = (n - 1)/2`.
///
/// ```
/// use zeitlin::sphere::spin;
/// let [s1, s2, s3] = spin(3);
/// // [S_1, S_2] = i S_3
/// let c = &s1 * &s2 - &s2 * &s1;
/// assert!((c - s3 * nalgebra::Complex::new(0.0, 1.0)).norm() < 1e-14);
/// ```
pub fn spin(n: usize) -> [DMatrix<C>; 3] {
    let ladder = |i: usize, j: usize| -> f64 {
        // S_+[j - 1, j] = sqrt(j (N - j))
        if i + 1 == j {
            ((j * (n - j)) as f64).sqrt()
        } else {
            0.0
        }
    };
    let sp = DMatrix::from_fn(n, n, |i, j| C::new(ladder(i, j), 0.0));
    let sm = sp.adjoint();
    let s1 = (&sp + &sm) * C::new(0.5, 0.0);
    let s2 = (&sp - &sm) * C::new(0.0, -0.5);
    let s = (n as f64 - 1.0) / 2.0;
    let s3 = DMatrix::from_fn(n, n, |i, j| C::new(if i == j { s - i as f64 } else { 0.0 }, 0.0));
    [s1, s2, s3]
}

/// `exp(-i theta u.S)` for a unit axis `u`: the rotation of the sphere by
/// `theta` about `u`, in the spin representation (unitary). By the
/// eigen-decomposition of the Hermitian `u.S`.
pub fn rotation(n: usize, u: [f64; 3], theta: f64) -> Result<DMatrix<C>, SphereError> {
    let s = spin(n);
    let us = &s[0] * C::new(u[0], 0.0) + &s[1] * C::new(u[1], 0.0) + &s[2] * C::new(u[2], 0.0);
    if us.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) || !theta.is_finite() {
        return Err(SphereError::Numerical("the rotation axis or angle is not finite".into()));
    }
    let (values, y) = crate::eigen::hermitian_eigen(&us)
        .ok_or_else(|| SphereError::Numerical("the eigenvalues of u.S did not converge".into()))?;
    // Y diag(phases) Y^*: scale the columns, then one product.
    let mut scaled = y.clone();
    for (j, mu) in values.iter().enumerate() {
        let phase = C::from_polar(1.0, -theta * mu);
        scaled.column_mut(j).iter_mut().for_each(|z| *z *= phase);
    }
    Ok(crate::eigen::complex_product(&scaled, &y.adjoint()))
}

/// The axis of a state as quflow means it, from the axis `a` of the spin
/// matrices with `[a.S, W] = 0`: `(-a_1, -a_2, a_3)`, scaled to unit length
/// with its largest component positive (an axis is a line).
///
/// quflow's frame (that of `quflow.geometry.rotate`) is the one in which a
/// state zonal about `n` has its `l = 1` coefficients
/// `(v_{1,1}, v_{1,-1}, v_{1,0})` along `n`. quflow's spin matrices are
/// `i (S_1, S_2, -S_3)` of these (its `S_3` runs `-s..s` where this
/// module's runs `s..-s`), so `T_{1,1}`, `T_{1,-1}` and `T_{1,0}` are
/// multiples of `S_1`, `S_2` and `-S_3`: the spin frame is quflow's turned
/// by pi about z. The map is its own inverse up to sign.
///
/// ```
/// use zeitlin::sphere::{from_harmonics, quflow_axis, spin};
/// // A state with l = 1 coefficients (v_11, v_1-1, v_10) = (0.48, 0.6, 0.64):
/// let w = from_harmonics(6, &[(1, 1, 0.48), (1, -1, 0.6), (1, 0, 0.64)]).unwrap();
/// // commutes with a.S for a = (-0.48, -0.6, 0.64) ...
/// let [s1, s2, s3] = spin(6);
/// let c = |x: f64| nalgebra::Complex::new(x, 0.0);
/// let a_s = &s1 * c(-0.48) + &s2 * c(-0.6) + &s3 * c(0.64);
/// assert!((&a_s * &w - &w * &a_s).norm() < 1e-12 * w.norm());
/// // ... and its axis in quflow's frame is its l = 1 direction.
/// let n = quflow_axis([-0.48, -0.6, 0.64]);
/// assert!((n[0] - 0.48).abs() < 1e-15 && (n[1] - 0.6).abs() < 1e-15 && (n[2] - 0.64).abs() < 1e-15);
/// ```
pub fn quflow_axis(a: [f64; 3]) -> [f64; 3] {
    let n = [-a[0], -a[1], a[2]];
    let norm = n.iter().map(|x| x * x).sum::<f64>().sqrt();
    let big = n.iter().copied().fold(0.0f64, |b, x| if x.abs() > b.abs() { x } else { b });
    if !(norm > 0.0 && norm.is_finite()) {
        return n;
    }
    n.map(|x| x * big.signum() / norm)
}

/// The unitary `V` (a rotation of the sphere) that takes the axis `n` (unit)
/// to the pole: `V^* (n.S) V = S_3`, so a state zonal about `n` becomes
/// diagonal under `W -> V^* W V`.
///
/// ```
/// use zeitlin::sphere::{rotation_to_axis, spin};
/// let axis = [0.6, 0.0, 0.8];
/// let v = rotation_to_axis(4, axis).unwrap();
/// let [s1, s2, s3] = spin(4);
/// let ns = &s1 * nalgebra::Complex::new(0.6, 0.0) + &s3 * nalgebra::Complex::new(0.8, 0.0);
/// assert!((v.adjoint() * ns * &v - s3).norm() < 1e-13);
/// ```
pub fn rotation_to_axis(n: usize, axis: [f64; 3]) -> Result<DMatrix<C>, SphereError> {
    let norm = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(SphereError::Numerical("the axis is zero or not finite".into()));
    }
    let a = axis.map(|x| x / norm);
    // The rotation R with R e_3 = a is about u = e_3 x a by the angle between them.
    let (cross, dot) = ([-a[1], a[0], 0.0], a[2]);
    let sin = (cross[0] * cross[0] + cross[1] * cross[1]).sqrt();
    let theta = sin.atan2(dot);
    let u = if sin > 0.0 { [cross[0] / sin, cross[1] / sin, 0.0] } else { [1.0, 0.0, 0.0] };
    // exp(-i theta u.S) S_3 exp(i theta u.S) = (R e_3).S for one orientation
    // convention and (R^-1 e_3).S for the other: take the one that works.
    let s = spin(n);
    let target = &s[0] * C::new(a[0], 0.0) + &s[1] * C::new(a[1], 0.0) + &s[2] * C::new(a[2], 0.0);
    let mut best: Option<(f64, DMatrix<C>)> = None;
    let product = crate::eigen::complex_product;
    for angle in [theta, -theta] {
        let v = rotation(n, u, angle)?;
        let err = (product(&product(&v.adjoint(), &target), &v) - &s[2]).norm();
        if best.as_ref().is_none_or(|(e, _)| err < *e) {
            best = Some((err, v));
        }
    }
    let (err, v) = best.expect("two candidates");
    let scale = s[2].norm().max(1.0);
    if err > 1e-10 * scale {
        return Err(SphereError::Numerical(format!("the rotation to the axis is off by {err:e}")));
    }
    Ok(v)
}
