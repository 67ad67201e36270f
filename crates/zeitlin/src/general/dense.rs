//! The dense energy–Casimir analysis of a state zonal in no frame
//! ([`dense_analysis`]), in real orthonormal coordinates of su(N).

use super::{clusters, commutator, eigenbasis, DenseAnalysis, C};
use crate::analysis::{hbar, ZeitlinError};
use crate::laplacian::StreamSolver;
use nalgebra::DMatrix;

/// Orthonormal trace-free vectors (Helmert): `h_r = (1, ..., 1, -r, 0, ...)
/// / sqrt(r (r + 1))`, `r = 1..n-1`.
fn helmert(n: usize) -> Vec<Vec<f64>> {
    (1..n)
        .map(|r| {
            let c = 1.0 / ((r * (r + 1)) as f64).sqrt();
            (0..n)
                .map(|j| {
                    if j < r {
                        c
                    } else if j == r {
                        -(r as f64) * c
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect()
}

/// The dense energy–Casimir analysis of a steady `W_e` (unit size) with
/// compatible noise, in real coordinates orthonormal for `<A, B> = Re tr(A
/// B^*)/N`, taken in the eigenbasis `U` of `-i W_e`: for `j < k` the real
/// and imaginary parts of `(U^* X U)_jk` times `sqrt(2/N)` (the orbit's
/// tangent space), then the diagonal's trace-free part in a Helmert basis
/// times `1/sqrt N` (the directions of the Casimir gradients).
///
/// * `G = -Delta^-1` (the energy's Hessian), from the stream solve;
/// * the Casimir `tr Phi(-iW)/N` has, by the Daleckii–Krein formula, the
///   Hessian `c_jk |(U^* X U)_jk|^2 / N` with `c_jk = (pi_j - pi_k)/(omega_j -
///   omega_k)` times `eps` (criticality: `Phi'(omega_j) = eps pi_j`, with
///   `pi` the eigenvalues of `-i P_e` on the same eigenvectors), and free
///   curvature on the diagonal, which is the Casimir Hessian `K` of the
///   finite-dimensional engine;
/// * `P = eps (G + C) + K`, `Q = P A~ + A~^T P + sum B_i^T P B_i` with the
///   drift `A X = ([P_e, X] + [Delta^-1 X, W_e])/hbar` and the noise `B_i X
///   = [X_i, X]/hbar` (`Q` does not depend on `K`: the drift and the noise
///   keep every Casimir);
/// * `eps` is the sign that makes the restricted `R = Z^T (G + C) Z`
///   definite (Finsler); the infimum of `Sigma^2` over `K` is
///   `lambda_max(Z^T Q Z, Z^T P Z)`, approached as `K` grows; `K` is built
///   for a target just above it by the Schur complement, as the
///   finite-dimensional optimiser does.
///
/// Without a definite form, the largest real part of the drift's
/// eigenvalues (faer) decides linear instability.
pub fn dense_analysis(
    solver: &StreamSolver,
    w: &DMatrix<C>,
    p_e: &DMatrix<C>,
    noise: &[DMatrix<C>],
) -> Result<DenseAnalysis, ZeitlinError> {
    let n = w.nrows();
    let (omega, u) = eigenbasis(w)?;
    let cl = clusters(&omega);
    let distinct = cl.last().copied().unwrap_or(0) + 1 == n;
    let pi: Vec<f64> = {
        let t = u.adjoint() * (p_e * C::new(0.0, -1.0)) * &u;
        (0..n).map(|j| t[(j, j)].re).collect()
    };
    let coordinates = Coordinates::new(&u);
    let ops = Operators::assemble(&coordinates, solver, w, p_e, noise)?;
    let p1 = energy_casimir_hessian(&ops.g, &coordinates.pairs, &pi, &omega, distinct);
    let drift_residual = drift_residual(&p1, &ops.a, distinct);
    let q1 = ops.generator(&p1);
    let restricted = Restricted::new(&p1, coordinates.off, distinct)?;
    let mut out = DenseAnalysis {
        dimension: coordinates.dim,
        distinct_eigenvalues: distinct,
        energy: 0.0,
        restricted_margin: restricted.margin_plus.max(restricted.margin_minus),
        sigma2: None,
        infimum: None,
        condition_number: None,
        drift_residual,
        growth_rate: None,
    };
    const DEFINITE: f64 = 1e-9;
    let eps = if restricted.margin_plus > DEFINITE {
        1.0
    } else if restricted.margin_minus > DEFINITE {
        -1.0
    } else {
        0.0
    };
    if eps == 0.0 {
        out.growth_rate = Some(growth_rate(&ops.a)?);
        return Ok(out);
    }
    out.energy = eps;
    complete_casimir_hessian(&mut out, (&p1, &q1), eps, coordinates.off, &restricted)?;
    Ok(out)
}

/// A numerical breakdown in `what`.
fn numerical(what: &str) -> ZeitlinError {
    ZeitlinError::Numerical(what.to_string())
}

/// The real orthonormal coordinates of su(N) of [`dense_analysis`], in the
/// eigenbasis `U`: off-diagonal pairs first, then the diagonal.
struct Coordinates<'a> {
    u: &'a DMatrix<C>,
    n: usize,
    /// The pairs `j < k`; pair `q` has the coordinates `2q` (real part) and
    /// `2q + 1` (imaginary part).
    pairs: Vec<(usize, usize)>,
    /// The number of off-diagonal coordinates (the first diagonal one).
    off: usize,
    /// `N^2 - 1`.
    dim: usize,
    /// The Helmert basis of the trace-free diagonal.
    helmert: Vec<Vec<f64>>,
    /// `sqrt(2/N)`.
    root: f64,
}

impl<'a> Coordinates<'a> {
    /// The coordinates in the eigenbasis `u`.
    fn new(u: &'a DMatrix<C>) -> Coordinates<'a> {
        let n = u.nrows();
        let nf = n as f64;
        let pairs: Vec<(usize, usize)> = (0..n).flat_map(|j| (j + 1..n).map(move |k| (j, k))).collect();
        let off = 2 * pairs.len();
        Coordinates { u, n, pairs, off, dim: n * n - 1, helmert: helmert(n), root: (2.0 / nf).sqrt() }
    }

    /// The coordinates of `T = U^* X U`: `sqrt(2/N) (Re, Im) T_jk` for
    /// `j < k`, then `<h_r, Im diag T> / sqrt N`.
    fn coords(&self, t: &DMatrix<C>) -> Vec<f64> {
        let nf = self.n as f64;
        let mut v = Vec::with_capacity(self.dim);
        for &(j, k) in &self.pairs {
            v.push(self.root * t[(j, k)].re);
            v.push(self.root * t[(j, k)].im);
        }
        for hr in &self.helmert {
            v.push(hr.iter().enumerate().map(|(j, x)| x * t[(j, j)].im).sum::<f64>() / nf.sqrt());
        }
        v
    }

    /// The basis element `a` of su(N), in the spin basis (`U T U^*`).
    fn element(&self, a: usize) -> DMatrix<C> {
        let (n, nf) = (self.n, self.n as f64);
        let mut t = DMatrix::zeros(n, n);
        if a < self.off {
            let (j, k) = self.pairs[a / 2];
            let x = 1.0 / self.root; // sqrt(N/2)
            if a % 2 == 0 {
                t[(j, k)] = C::new(x, 0.0);
                t[(k, j)] = C::new(-x, 0.0);
            } else {
                t[(j, k)] = C::new(0.0, x);
                t[(k, j)] = C::new(0.0, x);
            }
        } else {
            for (j, x) in self.helmert[a - self.off].iter().enumerate() {
                t[(j, j)] = C::new(0.0, x * nf.sqrt());
            }
        }
        self.u * t * self.u.adjoint()
    }

    /// `U^* X U`.
    fn to_frame(&self, x: &DMatrix<C>) -> DMatrix<C> {
        self.u.adjoint() * x * self.u
    }
}

/// The operators of the dense analysis in the coordinates: `G = -Delta^-1`
/// (symmetrised), the drift `A` and the noise `B_i`.
struct Operators {
    g: DMatrix<f64>,
    a: DMatrix<f64>,
    b: Vec<DMatrix<f64>>,
}

impl Operators {
    /// Column by column: one stream solve and the commutators per basis
    /// element.
    fn assemble(
        coordinates: &Coordinates,
        solver: &StreamSolver,
        w: &DMatrix<C>,
        p_e: &DMatrix<C>,
        noise: &[DMatrix<C>],
    ) -> Result<Operators, ZeitlinError> {
        let dim = coordinates.dim;
        let hb = hbar(coordinates.n);
        let inv_lap = |x: &DMatrix<C>| solver.solve(x).map_err(|e| ZeitlinError::Numerical(e.to_string()));
        // The coordinates of X, taken in the eigenbasis.
        let coords = |x: &DMatrix<C>| coordinates.coords(&coordinates.to_frame(x));
        let mut g = DMatrix::<f64>::zeros(dim, dim);
        let mut a_mat = DMatrix::<f64>::zeros(dim, dim);
        let mut b_mats: Vec<DMatrix<f64>> = vec![DMatrix::zeros(dim, dim); noise.len()];
        for b in 0..dim {
            let e = coordinates.element(b);
            let psi = inv_lap(&e)?;
            let gcol = coords(&(-&psi));
            let acol = coords(&((commutator(p_e, &e) + commutator(&psi, w)) / C::new(hb, 0.0)));
            for r in 0..dim {
                g[(r, b)] = gcol[r];
                a_mat[(r, b)] = acol[r];
            }
            for (bm, x) in b_mats.iter_mut().zip(noise) {
                let col = coords(&(commutator(x, &e) / C::new(hb, 0.0)));
                for r in 0..dim {
                    bm[(r, b)] = col[r];
                }
            }
        }
        let g = (&g + g.transpose()) * 0.5;
        Ok(Operators { g, a: a_mat, b: b_mats })
    }

    /// `Q = P A~ + A~^T P + sum B_i^T P B_i` (symmetrised), `A~ = A + sum
    /// B_i^2 / 2`.
    fn generator(&self, p: &DMatrix<f64>) -> DMatrix<f64> {
        let mut at = self.a.clone();
        for b in &self.b {
            at += b * b * 0.5;
        }
        let mut q = p * &at + at.transpose() * p;
        for b in &self.b {
            q += b.transpose() * p * b;
        }
        (&q + q.transpose()) * 0.5
    }
}

/// eps-free part of P: G + C, C diagonal in these coordinates, with the
/// Daleckii–Krein weights `c_jk = (pi_j - pi_k) / (omega_j - omega_k)`.
fn energy_casimir_hessian(
    g: &DMatrix<f64>,
    pairs: &[(usize, usize)],
    pi: &[f64],
    omega: &[f64],
    distinct: bool,
) -> DMatrix<f64> {
    let mut p1 = g.clone();
    for (q, &(j, k)) in pairs.iter().enumerate() {
        // (Between equal eigenvalues, where no test is made, 0.)
        let c = if distinct { (pi[j] - pi[k]) / (omega[j] - omega[k]) } else { 0.0 };
        p1[(2 * q, 2 * q)] += c;
        p1[(2 * q + 1, 2 * q + 1)] += c;
    }
    p1
}

/// `|P A + A^T P|_F / (|P|_F |A|_F)` (0 without distinct eigenvalues).
fn drift_residual(p1: &DMatrix<f64>, a_mat: &DMatrix<f64>, distinct: bool) -> f64 {
    let drift = p1 * a_mat + a_mat.transpose() * p1;
    let d = p1.norm() * a_mat.norm();
    if d > 0.0 && distinct {
        drift.norm() / d
    } else {
        0.0
    }
}

/// The spectrum of the restricted Hessian `R = Z^T (G + C) Z`: the margin
/// `lambda_min(eps R) / max |eig R|` of each sign, and `lambda_min` and
/// `max |eig|`.
struct Restricted {
    margin_plus: f64,
    margin_minus: f64,
    lo: f64,
    hi: f64,
}

impl Restricted {
    /// From the eigenvalues of the leading `off x off` block of `P1`.
    fn new(p1: &DMatrix<f64>, off: usize, distinct: bool) -> Result<Restricted, ZeitlinError> {
        let r = p1.view((0, 0), (off, off)).into_owned();
        let eig = if distinct {
            crate::eigen::symmetric_eigenvalues(&r).ok_or_else(|| numerical("the restricted Hessian's eigenvalues"))?
        } else {
            vec![]
        };
        let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x.abs())));
        let top = eig.iter().fold(f64::NEG_INFINITY, |a, &x| a.max(x));
        // With repeated eigenvalues the orbit is smaller and the Casimir
        // directions are not the diagonal: no energy–Casimir test is made (the
        // margin is reported as -infinity), only the spectrum.
        let (margin_plus, margin_minus) = if !distinct {
            (f64::NEG_INFINITY, f64::NEG_INFINITY)
        } else if hi > 0.0 {
            (lo / hi, -top / hi)
        } else {
            (0.0, 0.0)
        };
        Ok(Restricted { margin_plus, margin_minus, lo, hi })
    }
}

/// The largest real part of the drift's eigenvalues (faer), 0 within
/// 1e-6 of the largest modulus.
fn growth_rate(a_mat: &DMatrix<f64>) -> Result<f64, ZeitlinError> {
    let values = crate::eigen::real_eigenvalues(a_mat).ok_or_else(|| numerical("the drift's eigenvalues"))?;
    let rate = values.iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max);
    let scale = values.iter().map(|z| z.norm()).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
    Ok(if rate > 1e-6 * scale { rate } else { 0.0 })
}

/// The Casimir Hessian `K` on the diagonal directions for a target just
/// above the infimum of `Sigma^2` (the Schur complement of the pencil
/// `(eps P1, eps Q1)` split into tangent and Casimir parts): the infimum,
/// `Sigma^2` and `cond(P)`.
fn complete_casimir_hessian(
    out: &mut DenseAnalysis,
    (p1, q1): (&DMatrix<f64>, &DMatrix<f64>),
    eps: f64,
    off: usize,
    restricted: &Restricted,
) -> Result<(), ZeitlinError> {
    let p = p1 * eps;
    let q = q1 * eps;
    let cas = out.dimension - off; // the N - 1 Casimir directions
    let block = |m: &DMatrix<f64>, r0: usize, c0: usize, nr: usize, nc: usize| m.view((r0, c0), (nr, nc)).into_owned();
    let frame = numerics::dense::FramePencil {
        pz: block(&p, 0, 0, off, off),
        pzw: block(&p, 0, off, off, cas),
        pw: block(&p, off, off, cas, cas),
        qz: block(&q, 0, 0, off, off),
        qzw: block(&q, 0, off, off, cas),
        qw: block(&q, off, off, cas, cas),
    };
    // The level-set block's natural size, added along the Casimir directions.
    let level = (restricted.lo.abs() * restricted.hi).sqrt().max(f64::MIN_POSITIVE);
    let c = frame.complete(level, 1e10).ok_or_else(|| numerical("no Casimir Hessian made P definite"))?;
    out.infimum = Some(c.infimum);
    let (sigma2, cond) = (c.sigma2, c.condition_number);
    out.sigma2 = Some(sigma2.max(0.0));
    out.condition_number = Some(cond);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sphere::from_harmonics;

    /// The definite branch, which no Zeitlin equilibrium zonal in no frame
    /// has reached (docs/zeitlin.md), on an artificial pencil: with `P_e`
    /// replaced by `W_e` itself, `pi = omega`, every `c_jk = 1`, and `G + C
    /// = G + I` is definite on the tangent space (`eps = +1`). The Casimir
    /// Hessian built for a target just above the infimum gives a `Sigma^2`
    /// at most 1e-6 above it (the first target, 1e-8 above, with `cond(P)`
    /// within 1e10), and never below it (the infimum is over all Casimir
    /// Hessians).
    #[test]
    fn the_definite_branch_reaches_the_infimum_on_an_artificial_pencil() {
        let n = 5;
        let w = from_harmonics(n, &[(3, 1, 1.0), (3, -2, 0.6), (3, 0, -0.2), (2, 1, 0.3)]).unwrap();
        let solver = StreamSolver::new(n).unwrap();
        // Noise that commutes with W: 0.1 i (H^2 - tr(H^2)/N) with H = -i W.
        let h = &w * C::new(0.0, -1.0);
        let mut h2 = &h * &h;
        let mean = h2.trace() / n as f64;
        for j in 0..n {
            h2[(j, j)] -= mean;
        }
        let x = h2 * C::new(0.0, 0.1);
        let d = dense_analysis(&solver, &w, &w, &[x]).unwrap();
        assert_eq!(d.energy, 1.0);
        assert!(d.restricted_margin > 1e-3, "{}", d.restricted_margin);
        let (s, inf) = (d.sigma2.unwrap(), d.infimum.unwrap());
        assert!(inf > 0.0);
        assert!(s >= inf * (1.0 - 1e-10) && s <= inf * (1.0 + 1e-6), "sigma2 {s}, infimum {inf}");
        assert!(d.condition_number.unwrap() <= 1e10);
    }
}
