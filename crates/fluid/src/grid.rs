//! Discretisation in y.
//!
//! The vorticity of one x-mode `exp(i k x)` is represented by its values at
//! nodes `y_a` with quadrature weights `m_a > 0`; the stream function solves
//! `(k^2 - d^2/dy^2) psi = omega`. Two discretisations, both chosen so that
//! the discrete energy `omega^T K omega` with `K = M L^-1` is an exactly
//! symmetric positive definite form and multiplication by a function of `y`
//! is diagonal, self-adjoint in the weights:
//!
//! * **walls** (`psi = 0` at both ends, no normal flow): continuous Galerkin
//!   spectral elements with Gauss–Lobatto–Legendre (GLL) nodes of degree
//!   `p` and GLL quadrature (the "G-NI" method). With stiffness `S`
//!   (banded, bandwidth `p`) and lumped mass `M` on the interior nodes,
//!   `psi = (S + k^2 M)^-1 M omega`, so `K = M (S + k^2 M)^-1 M`. The error
//!   is `O(h^p)` for smooth data; the wall nodes carry no unknown because
//!   vorticity there decouples (it is only advected).
//! * **periodic**: Fourier collocation on a uniform grid, `K` the circulant
//!   with symbol `h / (k^2 + l^2)`; spectrally accurate for smooth periodic data.
//!
//! These two properties are what make the energy–Casimir–momentum form an
//! exact invariant of the discrete linearised drift (module [`crate::modes`]):
//! the discrete system keeps the structure that the continuous proof uses.

use crate::banded::{BandedCholesky, SymBanded};
use nalgebra::DMatrix;

/// The boundary condition in y.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// Rigid walls at both ends of the interval.
    Walls,
    /// Periodic in y.
    Periodic,
}

impl Boundary {
    /// Name as in the spec.
    pub fn as_str(&self) -> &'static str {
        match self {
            Boundary::Walls => "walls",
            Boundary::Periodic => "periodic",
        }
    }
}

/// Degree of the spectral elements used for walls.
pub const ELEMENT_DEGREE: usize = 8;

/// The y-grid: nodes, weights, and the stiffness of `-d^2/dy^2`.
#[derive(Clone, Debug)]
pub struct YGrid {
    boundary: Boundary,
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// Walls: stiffness on interior nodes (bandwidth `ELEMENT_DEGREE`).
    stiffness: Option<SymBanded>,
    length: f64,
}

/// Gauss–Lobatto–Legendre nodes and weights of degree `p` on `[-1, 1]`
/// (`p + 1` nodes, ascending), by Newton's method on `(1 - x^2) P_p'(x)`.
pub fn gll(p: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(p >= 1);
    let pf = p as f64;
    let mut x = vec![0.0; p + 1];
    let mut w = vec![0.0; p + 1];
    for (i, xi) in x.iter_mut().enumerate() {
        // Chebyshev–Gauss–Lobatto initial guess, then Newton on the
        // recurrence (the standard algorithm, e.g. Canuto et al. §2.3).
        let mut t = -(std::f64::consts::PI * i as f64 / pf).cos();
        for _ in 0..100 {
            let (l, _) = legendre(p, t);
            let (lm1, _) = legendre(p - 1, t);
            // f = t P_p - P_{p-1} vanishes at the GLL nodes (up to a factor)
            let f = t * l - lm1;
            let df = (pf + 1.0) * l;
            let dt = f / df;
            t -= dt;
            if dt.abs() < 1e-16 {
                break;
            }
        }
        *xi = t;
    }
    x[0] = -1.0;
    x[p] = 1.0;
    for i in 0..=p {
        let (l, _) = legendre(p, x[i]);
        w[i] = 2.0 / (pf * (pf + 1.0) * l * l);
    }
    (x, w)
}

/// All nodes (walls included) and assembled GLL weights of `elements`
/// equal elements on `[a, b]` with reference nodes `xi` and weights `wi`
/// (`elements * p + 1` nodes, the last exactly `b`).
pub fn element_nodes(a: f64, b: f64, elements: usize, xi: &[f64], wi: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let p = xi.len() - 1;
    let h = (b - a) / elements as f64;
    let mut nodes = vec![0.0; elements * p + 1];
    let mut weights = vec![0.0; elements * p + 1];
    for e in 0..elements {
        let y0 = a + h * e as f64;
        for i in 0..=p {
            nodes[e * p + i] = y0 + (xi[i] + 1.0) * h / 2.0;
            weights[e * p + i] += wi[i] * h / 2.0;
        }
    }
    nodes[elements * p] = b;
    (nodes, weights)
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    if n == 0 {
        return (1.0, 0.0);
    }
    let (mut p0, mut p1) = (1.0, x);
    let (mut d0, mut d1) = (0.0, 1.0);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        let d2 = d0 + (2.0 * kf - 1.0) * p1;
        p0 = p1;
        p1 = p2;
        d0 = d1;
        d1 = d2;
    }
    (p1, d1)
}

/// The GLL differentiation matrix of degree `p` (row `i` = derivative at node `i`).
pub fn gll_derivative(p: usize, x: &[f64]) -> DMatrix<f64> {
    let pf = p as f64;
    DMatrix::from_fn(p + 1, p + 1, |i, j| {
        if i == j {
            if i == 0 {
                -pf * (pf + 1.0) / 4.0
            } else if i == p {
                pf * (pf + 1.0) / 4.0
            } else {
                0.0
            }
        } else {
            legendre(p, x[i]).0 / (legendre(p, x[j]).0 * (x[i] - x[j]))
        }
    })
}

impl YGrid {
    /// A grid with `ny` intervals' worth of resolution on `[a, b]`:
    /// walls: `ny / ELEMENT_DEGREE` elements (`ny` must be a multiple of the
    /// degree), `ny - 1` interior unknowns; periodic: `ny` uniform nodes.
    pub fn new(boundary: Boundary, a: f64, b: f64, ny: usize) -> Self {
        let length = b - a;
        match boundary {
            Boundary::Periodic => {
                let h = length / ny as f64;
                YGrid {
                    boundary,
                    nodes: (0..ny).map(|j| a + h * j as f64).collect(),
                    weights: vec![h; ny],
                    stiffness: None,
                    length,
                }
            }
            Boundary::Walls => {
                let p = ELEMENT_DEGREE;
                assert!(ny % p == 0 && ny >= 2 * p, "ny must be a multiple of {p}, at least {}", 2 * p);
                let ne = ny / p;
                let he = length / ne as f64;
                let (xi, wi) = gll(p);
                let d = gll_derivative(p, &xi);
                // element stiffness (2/h) D^T diag(w) D
                let ke = DMatrix::from_fn(p + 1, p + 1, |i, j| {
                    (0..=p).map(|q| wi[q] * d[(q, i)] * d[(q, j)]).sum::<f64>() * 2.0 / he
                });
                let (nodes, weights) = element_nodes(a, b, ne, &xi, &wi);
                let nglob = nodes.len();
                // interior unknowns: global nodes 1..nglob-1
                let n = nglob - 2;
                let mut s = SymBanded::zeros(n, p);
                for e in 0..ne {
                    for i in 0..=p {
                        for j in 0..=i {
                            let (gi, gj) = (e * p + i, e * p + j);
                            if gi == 0 || gj == 0 || gi == nglob - 1 || gj == nglob - 1 {
                                continue;
                            }
                            s.add(gi - 1, gj - 1, if i == j { ke[(i, i)] } else { ke[(i, j)] });
                        }
                    }
                }
                YGrid {
                    boundary,
                    nodes: nodes[1..nglob - 1].to_vec(),
                    weights: weights[1..nglob - 1].to_vec(),
                    stiffness: Some(s),
                    length,
                }
            }
        }
    }

    /// Boundary condition.
    pub fn boundary(&self) -> Boundary {
        self.boundary
    }

    /// Number of unknowns per x-mode.
    pub fn n(&self) -> usize {
        self.nodes.len()
    }

    /// The nodes carrying unknowns.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Quadrature weights at those nodes.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Length of the y-interval.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The operator `L_s = S + k^2 M` (walls only): banded, symmetric positive definite.
    pub fn helmholtz(&self, k: f64) -> Option<SymBanded> {
        let s = self.stiffness.as_ref()?;
        let mut l = s.clone();
        for (i, m) in self.weights.iter().enumerate() {
            l.add(i, i, k * k * m);
        }
        Some(l)
    }

    /// The energy matrix `K = M L^-1` of mode `k` (dense, symmetric positive
    /// definite): `omega^T K omega = int |u|^2 dy` per unit x-length and mode.
    pub fn energy_matrix(&self, k: f64) -> DMatrix<f64> {
        let n = self.n();
        match self.boundary {
            Boundary::Walls => {
                let l = self.helmholtz(k).expect("walls grid has a stiffness");
                // S + k^2 M is positive definite in exact arithmetic; its
                // Cholesky fails only when k^2 overflows or underflows the
                // stiffness (the spec layer bounds k L to keep away from
                // that): every consumer then sees NaN and refuses to certify.
                let Ok(f) = l.cholesky() else { return DMatrix::from_element(n, n, f64::NAN) };
                let mut out = DMatrix::zeros(n, n);
                let mut col = vec![0.0; n];
                for j in 0..n {
                    col.iter_mut().for_each(|c| *c = 0.0);
                    col[j] = self.weights[j];
                    f.solve(&mut col);
                    for i in 0..n {
                        out[(i, j)] = self.weights[i] * col[i];
                    }
                }
                // exact symmetry of the form (the solve is symmetric up to rounding)
                let t = out.transpose();
                (out + t) * 0.5
            }
            Boundary::Periodic => {
                let h = self.length / n as f64;
                let col = self.periodic_symbol_column(k);
                DMatrix::from_fn(n, n, |i, j| h * col[(i + n - j) % n])
            }
        }
    }

    /// First column of the periodic `L^-1 M` (a circulant): `c_d = (h/N) sum_m cos(2 pi m d / N) / (k^2 + l_m^2)`.
    fn periodic_symbol_column(&self, k: f64) -> Vec<f64> {
        let n = self.n();
        let two_pi = 2.0 * std::f64::consts::PI;
        // wavenumbers m = -(n/2)+1 .. n/2 ; the Nyquist term enters with its cosine (real, symmetric)
        let half = n / 2;
        let ms: Vec<i64> = (-(half as i64) + if n % 2 == 0 { 1 } else { 0 }..=half as i64).collect();
        let symbol: Vec<f64> = ms
            .iter()
            .map(|&m| {
                let l = two_pi * m as f64 / self.length;
                let denom = k * k + l * l;
                // the mean of psi is not determined at k = 0; the k = 0 mode is not used
                if denom == 0.0 {
                    0.0
                } else {
                    1.0 / denom
                }
            })
            .collect();
        // cos(2 pi m d / n) depends on (m d) mod n only: one table of n cosines
        let table: Vec<f64> = (0..n).map(|j| (two_pi * j as f64 / n as f64).cos()).collect();
        (0..n)
            .map(|d| {
                ms.iter().zip(&symbol).map(|(&m, s)| table[(m.rem_euclid(n as i64) as usize * d) % n] * s).sum::<f64>()
                    / n as f64
            })
            .collect()
    }

    /// Factor of `L_s` (walls only).
    pub fn helmholtz_factor(&self, k: f64) -> Option<BandedCholesky> {
        self.helmholtz(k).and_then(|l| l.cholesky().ok())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gll_quadrature_is_exact_to_degree_2p_minus_1() {
        // GLL with p+1 nodes integrates polynomials of degree <= 2p-1 exactly:
        // int_{-1}^{1} x^j dx = 2/(j+1) for even j, 0 for odd j.
        for p in [2, 5, 8] {
            let (x, w) = gll(p);
            for j in 0..2 * p {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(j as i32)).sum();
                let exact = if j % 2 == 0 { 2.0 / (j as f64 + 1.0) } else { 0.0 };
                assert!((q - exact).abs() < 1e-14, "p={p} j={j}: {q} vs {exact}");
            }
        }
    }

    #[test]
    fn energy_of_a_sine_mode_matches_the_closed_form() {
        // omega = sin(n pi y / L) on [0, L] with walls: psi = omega / (k^2 + (n pi/L)^2),
        // so int omega psi dy = (L/2) / (k^2 + (n pi / L)^2).
        let l = std::f64::consts::PI;
        for (boundary, n_sin) in [(Boundary::Walls, 3.0), (Boundary::Periodic, 2.0)] {
            let g = YGrid::new(boundary, 0.0, l, 64);
            let k = 1.5;
            let omega: Vec<f64> = g.nodes().iter().map(|y| (n_sin * y).sin()).collect();
            let kmat = g.energy_matrix(k);
            let v = nalgebra::DVector::from_vec(omega);
            let e = (v.transpose() * &kmat * &v)[(0, 0)];
            let exact = (l / 2.0) / (k * k + n_sin * n_sin);
            assert!((e - exact).abs() < 1e-12, "{boundary:?}: {e} vs {exact}");
        }
    }

    #[test]
    fn walls_solution_converges_at_the_element_order() {
        // omega = 1 (does not vanish at the walls) on [0, 1], k = 1:
        // psi = 1 - cosh(y - 1/2)/cosh(1/2); compare psi at the nodes.
        let exact = |y: f64| 1.0 - (y - 0.5).cosh() / 0.5f64.cosh();
        let mut errs = vec![];
        for ny in [16, 32, 64] {
            let g = YGrid::new(Boundary::Walls, 0.0, 1.0, ny);
            let f = g.helmholtz_factor(1.0).unwrap();
            let mut psi: Vec<f64> = g.weights().to_vec();
            f.solve(&mut psi);
            let err = g.nodes().iter().zip(&psi).map(|(y, p)| (p - exact(*y)).abs()).fold(0.0, f64::max);
            errs.push(err);
        }
        // degree-8 elements: error falls by ~2^8 per halving until rounding
        assert!(errs[0] < 1e-9 && errs[1] < errs[0] / 50.0 || errs[1] < 1e-13, "{errs:?}");
    }
}
