//! The Hoppe–Yau Laplacian `Delta_N P = -sum_a [S_a, [S_a, P]]` on one
//! off-diagonal of an `N x N` matrix.
//!
//! With the spin-`s` matrices (`s = (N - 1)/2`) in the basis `|j>`,
//! `j = 0..N-1`, `S_3 |j> = (s - j) |j>`, the ladder coefficients are
//! `sqrt(j (N - j))`, and `Delta_N` maps the entries `v_j = P[j, j + m]` of
//! the `m`-th diagonal to themselves by the symmetric tridiagonal matrix with
//!
//! * diagonal `-((N - 1)(2j + 1 + m) - 2 j (j + m))`,
//! * off-diagonal (between `j - 1` and `j`) `sqrt(j (N - j) (j + m) (N - j - m))`.
//!
//! (Expand `-sum_a [S_a,[S_a,P]] = -2 s(s+1) P + 2 S_3 P S_3 + S_+ P S_- + S_- P S_+`;
//! quflow's `compute_tridiagonal_laplacian` has the same entries.) Its
//! eigenvalues are `-l (l + 1)` for `l = m..N-1`, so the block is negative
//! definite for `m >= 1`, and for `m = 0` its kernel is the identity matrix.

/// A symmetric tridiagonal matrix: `diag[j]`, and `off[j]` between `j` and `j + 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Tridiagonal {
    /// The diagonal.
    pub diag: Vec<f64>,
    /// The off-diagonal (`diag.len() - 1` entries).
    pub off: Vec<f64>,
}

/// The Laplacian on the `m`-th diagonal (`0 <= m < n`), of size `n - m`.
///
/// Every entry is exact except the off-diagonal square roots, which are
/// correctly rounded (relative error at most `2^-53`): the products under
/// the root are integers below `2^53` for `n < 2^13`.
///
/// ```
/// use zeitlin::laplacian::block;
/// // N = 2, m = 0: [[-1, 1], [1, -1]], eigenvalues 0 and -2 = -l(l+1), l = 0, 1
/// let d = block(2, 0);
/// assert_eq!(d.diag, vec![-1.0, -1.0]);
/// assert_eq!(d.off, vec![1.0]);
/// ```
pub fn block(n: usize, m: usize) -> Tridiagonal {
    assert!(m < n, "diagonal {m} of an {n} x {n} matrix");
    let len = n - m;
    let (n, m) = (n as i64, m as i64);
    let diag = (0..len as i64).map(|j| -((n - 1) * (2 * j + 1 + m) - 2 * j * (j + m)) as f64).collect();
    let off = (1..len as i64).map(|j| ((j * (n - j) * (j + m) * (n - j - m)) as f64).sqrt()).collect();
    Tridiagonal { diag, off }
}

impl Tridiagonal {
    /// Its size.
    pub fn len(&self) -> usize {
        self.diag.len()
    }

    /// Whether it is empty.
    pub fn is_empty(&self) -> bool {
        self.diag.is_empty()
    }

    /// Entry `(i, j)` (zero off the three diagonals).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if i == j {
            self.diag[i]
        } else if i + 1 == j {
            self.off[i]
        } else if j + 1 == i {
            self.off[j]
        } else {
            0.0
        }
    }

    /// `y = T x`.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        let n = self.len();
        for j in 0..n {
            let mut s = self.diag[j] * x[j];
            if j > 0 {
                s += self.off[j - 1] * x[j - 1];
            }
            if j + 1 < n {
                s += self.off[j] * x[j + 1];
            }
            y[j] = s;
        }
    }

    /// The `LDL^T` factors of a definite tridiagonal matrix (no pivoting:
    /// stable for a definite matrix); `None` if a pivot is zero or not finite.
    pub fn factor(&self) -> Option<TridiagonalFactor> {
        let n = self.len();
        let mut d = vec![0.0; n];
        let mut l = vec![0.0; n.saturating_sub(1)];
        for j in 0..n {
            d[j] = self.diag[j] - if j > 0 { l[j - 1] * self.off[j - 1] } else { 0.0 };
            if !(d[j].is_finite() && d[j] != 0.0) {
                return None;
            }
            if j + 1 < n {
                l[j] = self.off[j] / d[j];
            }
        }
        Some(TridiagonalFactor { d, l })
    }
}

/// `T = L D L^T` with unit lower bidiagonal `L` (`l[j]` below the diagonal in column `j`).
#[derive(Clone, Debug)]
pub struct TridiagonalFactor {
    d: Vec<f64>,
    l: Vec<f64>,
}

impl TridiagonalFactor {
    /// Overwrite `x` with `T^-1 x`.
    pub fn solve(&self, x: &mut [f64]) {
        let n = self.d.len();
        for j in 1..n {
            x[j] -= self.l[j - 1] * x[j - 1];
        }
        for j in 0..n {
            x[j] /= self.d[j];
        }
        for j in (0..n.saturating_sub(1)).rev() {
            x[j] -= self.l[j] * x[j + 1];
        }
    }
}

/// The LU factors, with partial pivoting, of a general tridiagonal matrix
/// (LAPACK's `dgttrf`): factored once, solved many times (`dgttrs`).
///
/// Written here rather than taken from a crate: nalgebra and faer solve
/// dense or general sparse systems; this one is `O(n)` and thirty lines.
#[derive(Clone, Debug)]
pub struct GeneralTridiagonalFactor {
    /// Multipliers `l[i]` of the elimination of row `i + 1`.
    l: Vec<f64>,
    /// The upper factor's three diagonals.
    d: Vec<f64>,
    du: Vec<f64>,
    du2: Vec<f64>,
    /// Whether rows `i` and `i + 1` were swapped at step `i`.
    swapped: Vec<bool>,
}

impl GeneralTridiagonalFactor {
    /// Factor `(sub, diag, sup)`: `sub[j]` is entry `(j + 1, j)`, `sup[j]`
    /// entry `(j, j + 1)`. `None` if it is singular in floating point.
    pub fn new(sub: &[f64], diag: &[f64], sup: &[f64]) -> Option<Self> {
        let n = diag.len();
        let (mut d, mut du) = (diag.to_vec(), sup.to_vec());
        let mut l = vec![0.0; n.saturating_sub(1)];
        let mut du2 = vec![0.0; n.saturating_sub(2)];
        let mut swapped = vec![false; n.saturating_sub(1)];
        for i in 0..n.saturating_sub(1) {
            if d[i].abs() >= sub[i].abs() {
                if d[i] == 0.0 {
                    return None;
                }
                l[i] = sub[i] / d[i];
                d[i + 1] -= l[i] * du[i];
            } else {
                // Swap rows i and i + 1.
                swapped[i] = true;
                l[i] = d[i] / sub[i];
                d[i] = sub[i];
                let t = d[i + 1];
                d[i + 1] = du[i] - l[i] * t;
                du[i] = t;
                if i + 2 < n {
                    du2[i] = du[i + 1];
                    du[i + 1] *= -l[i];
                }
            }
        }
        (n == 0 || (d[n - 1] != 0.0 && d.iter().all(|x| x.is_finite()))).then_some(GeneralTridiagonalFactor {
            l,
            d,
            du,
            du2,
            swapped,
        })
    }

    /// Overwrite `b` with the solution; false if it is not finite.
    pub fn solve(&self, b: &mut [f64]) -> bool {
        let n = self.d.len();
        for i in 0..n.saturating_sub(1) {
            if self.swapped[i] {
                b.swap(i, i + 1);
            }
            b[i + 1] -= self.l[i] * b[i];
        }
        for i in (0..n).rev() {
            let mut x = b[i];
            if i + 1 < n {
                x -= self.du[i] * b[i + 1];
            }
            if i + 2 < n {
                x -= self.du2[i] * b[i + 2];
            }
            b[i] = x / self.d[i];
        }
        b.iter().all(|x| x.is_finite())
    }
}

/// `pi` with `Delta_0 pi = omega` and `sum pi = 0`, for `sum omega = 0`: the
/// stream function of a zonal vorticity. `Delta_0` is singular (its kernel
/// is the constant vector, and its rows sum to zero), so the first unknown
/// is fixed at 0, the remaining rows solved (a principal submatrix of a
/// semidefinite matrix whose kernel is not orthogonal to `e_0`: definite),
/// and the mean removed.
pub fn solve_zonal(omega: &[f64]) -> Option<Vec<f64>> {
    let n = omega.len();
    if n <= 1 {
        return Some(vec![0.0; n]);
    }
    let lap = block(n, 0);
    let reduced = Tridiagonal { diag: lap.diag[1..].to_vec(), off: lap.off[1..].to_vec() };
    let mut x = omega[1..].to_vec();
    reduced.factor()?.solve(&mut x);
    let mut pi = Vec::with_capacity(n);
    pi.push(0.0);
    pi.extend(x);
    let mean = pi.iter().sum::<f64>() / n as f64;
    pi.iter_mut().for_each(|p| *p -= mean);
    Some(pi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, SymmetricEigen};

    /// The spin-`s` matrices, built from their definition (independent of
    /// the closed-form entries above).
    fn spin(n: usize) -> [DMatrix<f64>; 3] {
        let s = (n as f64 - 1.0) / 2.0;
        let m = |j: usize| s - j as f64;
        let s3 = DMatrix::from_fn(n, n, |i, j| if i == j { m(j) } else { 0.0 });
        // S_+ |m> = sqrt(s(s+1) - m(m+1)) |m+1>: |j> -> |j-1>
        let sp =
            DMatrix::from_fn(n, n, |i, j| if i + 1 == j { (s * (s + 1.0) - m(j) * (m(j) + 1.0)).sqrt() } else { 0.0 });
        let sm = sp.transpose();
        [(&sp + &sm) * 0.5, (&sp - &sm) * 0.5, s3] // S_1, i S_2 (real), S_3
    }

    /// `-sum_a [S_a, [S_a, P]]` with `S_2 = -i (iS_2)`: `[S_2,[S_2,P]] = -[iS_2,[iS_2,P]]`.
    fn laplacian_dense(n: usize, p: &DMatrix<f64>) -> DMatrix<f64> {
        let [s1, is2, s3] = spin(n);
        let c = |a: &DMatrix<f64>, b: &DMatrix<f64>| a * b - b * a;
        -(c(&s1, &c(&s1, p)) - c(&is2, &c(&is2, p)) + c(&s3, &c(&s3, p)))
    }

    #[test]
    fn blocks_match_the_definition_and_have_spectrum_minus_l_l_plus_1() {
        for n in [2usize, 3, 5, 8] {
            for m in 0..n {
                let t = block(n, m);
                // Apply the definition to each unit matrix E_{j, j+m}.
                for j in 0..n - m {
                    let mut p = DMatrix::zeros(n, n);
                    p[(j, j + m)] = 1.0;
                    let lp = laplacian_dense(n, &p);
                    for k in 0..n - m {
                        let expect = t.get(k, j);
                        assert!((lp[(k, k + m)] - expect).abs() < 1e-12, "n {n} m {m} j {j} k {k}");
                    }
                    // Nothing leaves the diagonal.
                    let off_diagonal: f64 = (0..n)
                        .flat_map(|a| (0..n).map(move |b| (a, b)))
                        .filter(|(a, b)| b < a || b - a != m)
                        .map(|(a, b)| lp[(a, b)].abs())
                        .sum();
                    assert!(off_diagonal < 1e-12);
                }
                let dense = DMatrix::from_fn(n - m, n - m, |i, j| t.get(i, j));
                let mut ev: Vec<f64> = SymmetricEigen::new(dense).eigenvalues.iter().copied().collect();
                ev.sort_by(|a, b| b.total_cmp(a));
                for (i, l) in (m..n).enumerate() {
                    assert!((ev[i] + (l * (l + 1)) as f64).abs() < 1e-9, "n {n} m {m}: {ev:?}");
                }
            }
        }
    }

    #[test]
    fn the_solves_invert() {
        let t = block(9, 2);
        let x: Vec<f64> = (0..7).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut b = vec![0.0; 7];
        t.mul(&x, &mut b);
        let mut y = b.clone();
        t.factor().unwrap().solve(&mut y);
        assert!(x.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-12));
        // A general (non-symmetric) tridiagonal needing a row swap.
        let (sub, diag, sup) = (vec![3.0, 1.0, 2.0], vec![0.0, 1.0, 4.0, 1.0], vec![1.0, 2.0, 0.5]);
        let x = [1.0, -2.0, 0.5, 3.0];
        let mut b: Vec<f64> = (0..4)
            .map(|i| {
                diag[i] * x[i]
                    + if i > 0 { sub[i - 1] * x[i - 1] } else { 0.0 }
                    + if i < 3 { sup[i] * x[i + 1] } else { 0.0 }
            })
            .collect();
        assert!(GeneralTridiagonalFactor::new(&sub, &diag, &sup).unwrap().solve(&mut b));
        assert!(x.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-12), "{b:?}");
        // The zonal solve: Delta_0 pi = omega, mean zero.
        let omega: Vec<f64> = (0..6).map(|j| j as f64 - 2.5).collect();
        let pi = solve_zonal(&omega).unwrap();
        let mut back = vec![0.0; 6];
        block(6, 0).mul(&pi, &mut back);
        assert!(back.iter().zip(&omega).all(|(a, b)| (a - b).abs() < 1e-12));
        assert!(pi.iter().sum::<f64>().abs() < 1e-12);
        // omega is the l = 1 harmonic (linear in j): pi = omega / (-2).
        assert!(pi.iter().zip(&omega).all(|(p, w)| (p + w / 2.0).abs() < 1e-12));
    }
}

type C = nalgebra::Complex<f64>;
use nalgebra::DMatrix;

/// Why a stream solve could not be done.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StreamError {
    /// The input is malformed (the message says which).
    #[error("{0}")]
    Input(String),
    /// A value became non-finite, or a factorisation failed.
    #[error("numerical breakdown: {0}")]
    Numerical(String),
}

/// `P = Delta_N^{-1} W` in `O(N^2)`, diagonal by diagonal.
///
/// ```
/// use nalgebra::{Complex, DMatrix};
/// use zeitlin::laplacian::StreamSolver;
/// let s = StreamSolver::new(5).unwrap();
/// // Any trace-free matrix, skew-Hermitian or not: Delta P = W.
/// let w = DMatrix::from_fn(5, 5, |i, j| Complex::new((i * 5 + j) as f64 * 0.1 - 1.2, (i as f64 - j as f64).sin()));
/// let p = s.solve(&w).unwrap();
/// assert!((s.laplacian(&p).unwrap() - &w).norm() < 1e-12 * w.norm());
/// assert!(p.trace().norm() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct StreamSolver {
    n: usize,
    /// `block(n, m)`, `m = 0..n`.
    blocks: Vec<Tridiagonal>,
    /// Factors of `block(n, m)`, `m = 1..n` (index `m - 1`): negative definite.
    pub(crate) factors: Vec<TridiagonalFactor>,
}

impl StreamSolver {
    /// The solver for `N x N` matrices (`N >= 2`).
    pub fn new(n: usize) -> Result<Self, StreamError> {
        if n < 2 {
            return Err(StreamError::Input(format!("N must be at least 2, got {n}")));
        }
        let blocks: Vec<Tridiagonal> = (0..n).map(|m| block(n, m)).collect();
        let factors = blocks[1..]
            .iter()
            .enumerate()
            .map(|(i, b)| {
                b.factor().ok_or_else(|| StreamError::Numerical(format!("the Laplacian of diagonal {}", i + 1)))
            })
            .collect::<Result<_, _>>()?;
        Ok(StreamSolver { n, blocks, factors })
    }

    /// `N`.
    pub fn n(&self) -> usize {
        self.n
    }

    pub(crate) fn check(&self, w: &DMatrix<C>, what: &str) -> Result<(), StreamError> {
        if w.nrows() != self.n || w.ncols() != self.n {
            return Err(StreamError::Input(format!(
                "{what} is {} x {}, the model is {n} x {n}",
                w.nrows(),
                w.ncols(),
                n = self.n
            )));
        }
        Ok(())
    }

    /// `Delta_N P`, applied block by block (`O(N^2)`).
    pub fn laplacian(&self, p: &DMatrix<C>) -> Result<DMatrix<C>, StreamError> {
        self.check(p, "P")?;
        let n = self.n;
        let mut out = DMatrix::zeros(n, n);
        let (mut re, mut im) = (vec![0.0; n], vec![0.0; n]);
        let (mut yr, mut yi) = (vec![0.0; n], vec![0.0; n]);
        for m in 0..n {
            let len = n - m;
            let t = &self.blocks[m];
            for upper in [true, false] {
                if m == 0 && !upper {
                    continue;
                }
                let at = |j: usize| if upper { (j, j + m) } else { (j + m, j) };
                for j in 0..len {
                    let z = p[at(j)];
                    (re[j], im[j]) = (z.re, z.im);
                }
                t.mul(&re[..len], &mut yr[..len]);
                t.mul(&im[..len], &mut yi[..len]);
                for j in 0..len {
                    out[at(j)] = C::new(yr[j], yi[j]);
                }
            }
        }
        Ok(out)
    }

    /// `P` with `Delta_N P = W - (tr W / N) I` and `tr P = 0`, for any
    /// complex `N x N` matrix (skew-Hermitian in, skew-Hermitian out,
    /// exactly: the real and imaginary parts are solved separately by the
    /// same real factors).
    pub fn solve(&self, w: &DMatrix<C>) -> Result<DMatrix<C>, StreamError> {
        self.check(w, "W")?;
        let n = self.n;
        let mut p = DMatrix::zeros(n, n);
        let (mut re, mut im) = (vec![0.0; n], vec![0.0; n]);
        for m in 1..n {
            let len = n - m;
            let f = &self.factors[m - 1];
            for upper in [true, false] {
                let at = |j: usize| if upper { (j, j + m) } else { (j + m, j) };
                for j in 0..len {
                    let z = w[at(j)];
                    (re[j], im[j]) = (z.re, z.im);
                }
                f.solve(&mut re[..len]);
                f.solve(&mut im[..len]);
                for j in 0..len {
                    p[at(j)] = C::new(re[j], im[j]);
                }
            }
        }
        // The main diagonal: Delta_0's kernel is the identity, so the mean
        // is removed first (rounding leaves a trace-free W with a mean of
        // order 1e-17, which solve_zonal would push into its first row).
        let mean = w.trace() / n as f64;
        let parts = |f: fn(C) -> f64| -> Result<Vec<f64>, StreamError> {
            let d: Vec<f64> = (0..n).map(|j| f(w[(j, j)] - mean)).collect();
            solve_zonal(&d).ok_or_else(|| StreamError::Numerical("the zonal Poisson solve".into()))
        };
        let (dr, di) = (parts(|z| z.re)?, parts(|z| z.im)?);
        for j in 0..n {
            p[(j, j)] = C::new(dr[j], di[j]);
        }
        if p.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
            return Err(StreamError::Numerical("the stream function is not finite".into()));
        }
        Ok(p)
    }
}
