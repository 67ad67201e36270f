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
//! * **periodic**: the same elements assembled around the circle: `ny / p`
//!   elements, `ny` nodes (the last element's end node is the first node),
//!   `K = M (S + k^2 M)^-1 M` with the cyclic stiffness. The unknowns are
//!   stored in the *banded order* `0, ny - 1, 1, ny - 2, ...` ([`YGrid::banded_order`]),
//!   in which the cyclic band of width `p` becomes an ordinary band of
//!   width `2p`, so every banded solve and the verified banded check of
//!   [`crate::walls_check`] serve both boundaries. (Fourier collocation
//!   would make `K` a dense circulant, whose verified check is dense,
//!   `O(ny^3)`.)
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

/// Degree of the spectral elements (both boundaries).
pub const ELEMENT_DEGREE: usize = 8;

/// The y-grid: nodes, weights, and the stiffness of `-d^2/dy^2`.
#[derive(Clone, Debug)]
pub struct YGrid {
    boundary: Boundary,
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// The stiffness on the unknowns, in the banded order (walls:
    /// bandwidth `ELEMENT_DEGREE`; periodic: `2 ELEMENT_DEGREE`).
    stiffness: SymBanded,
    /// `order[i]`: the node at position `i` of the banded order.
    order: Vec<usize>,
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

/// The number of unknowns of a grid of `ny` (walls: `ny - 1` interior
/// nodes; periodic: `ny`), without building it: for cost estimates.
pub fn unknowns(boundary: Boundary, ny: usize) -> usize {
    match boundary {
        Boundary::Walls => ny.saturating_sub(1),
        Boundary::Periodic => ny,
    }
}

/// An upper bound on the bandwidth of the stiffness (and of
/// [`YGrid::helmholtz`]) of a grid, without building it: an element couples
/// nodes at most [`ELEMENT_DEGREE`] apart, which the walls' node order
/// keeps and the periodic interleaving (`0, n-1, 1, n-2, ..`) at most
/// doubles. Tested against the grids built.
pub fn stiffness_bandwidth(boundary: Boundary) -> usize {
    match boundary {
        Boundary::Walls => ELEMENT_DEGREE,
        Boundary::Periodic => 2 * ELEMENT_DEGREE,
    }
}

impl YGrid {
    /// A grid with `ny` intervals' worth of resolution on `[a, b]`, `ny / ELEMENT_DEGREE`
    /// elements (`ny` must be a multiple of the degree, at least twice it):
    /// walls: `ny - 1` interior unknowns; periodic: `ny` unknowns.
    pub fn new(boundary: Boundary, a: f64, b: f64, ny: usize) -> Self {
        let length = b - a;
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
        let (nodes, mut weights) = element_nodes(a, b, ne, &xi, &wi);
        let nglob = nodes.len();
        // unknown(g): the unknown of global node g (None at a wall)
        let (n, unknown): (usize, Box<dyn Fn(usize) -> Option<usize>>) = match boundary {
            // interior unknowns: global nodes 1..nglob-1
            Boundary::Walls => (nglob - 2, Box::new(move |g| (g != 0 && g != nglob - 1).then(|| g - 1))),
            // node nglob - 1 (= b) is node 0 (= a)
            Boundary::Periodic => (nglob - 1, Box::new(move |g| Some(g % (nglob - 1)))),
        };
        let order: Vec<usize> = match boundary {
            Boundary::Walls => (0..n).collect(),
            // 0, n-1, 1, n-2, ...: node t at 2t, node n-1-t at 2t+1 (n is even)
            Boundary::Periodic => (0..n).map(|i| if i % 2 == 0 { i / 2 } else { n - 1 - i / 2 }).collect(),
        };
        let mut position = vec![0; n];
        for (i, &node) in order.iter().enumerate() {
            position[node] = i;
        }
        let pairs = || (0..ne).flat_map(move |e| (0..=p).flat_map(move |i| (0..=i).map(move |j| (e, i, j))));
        let placed =
            |e: usize, i: usize, j: usize| Some((position[unknown(e * p + i)?], position[unknown(e * p + j)?]));
        let bandwidth = pairs().filter_map(|(e, i, j)| placed(e, i, j)).map(|(r, c)| r.abs_diff(c)).max().unwrap_or(0);
        let mut s = SymBanded::zeros(n, bandwidth);
        for (e, i, j) in pairs() {
            if let Some((r, c)) = placed(e, i, j) {
                // (i, j) and (j, i) both land on the diagonal when they are one
                // node (impossible for ne >= 2: an element's two ends differ)
                s.add(r, c, ke[(i, j)]);
            }
        }
        let (nodes, weights) = match boundary {
            Boundary::Walls => (nodes[1..nglob - 1].to_vec(), weights[1..nglob - 1].to_vec()),
            Boundary::Periodic => {
                weights[0] += weights[nglob - 1];
                (nodes[..nglob - 1].to_vec(), weights[..nglob - 1].to_vec())
            }
        };
        YGrid { boundary, nodes, weights, stiffness: s, order, length }
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

    /// The banded order of the unknowns: `order[i]` is the node at banded
    /// position `i` (walls: `0, 1, ..`; periodic: `0, n-1, 1, n-2, ..`, module docs).
    pub fn banded_order(&self) -> &[usize] {
        &self.order
    }

    /// Node data `x` (one value per node) in the banded order.
    pub fn to_banded(&self, x: &[f64]) -> Vec<f64> {
        self.order.iter().map(|&a| x[a]).collect()
    }

    /// The operator `L_s = S + k^2 M` in the banded order ([`YGrid::banded_order`]):
    /// banded, symmetric positive definite.
    pub fn helmholtz(&self, k: f64) -> SymBanded {
        let mut l = self.stiffness.clone();
        for (i, &a) in self.order.iter().enumerate() {
            l.add(i, i, k * k * self.weights[a]);
        }
        l
    }

    /// The energy matrix `K = M L^-1 M` of mode `k` (dense, symmetric positive
    /// definite, node order): `omega^T K omega = int |u|^2 dy` per unit x-length and mode.
    pub fn energy_matrix(&self, k: f64) -> DMatrix<f64> {
        let n = self.n();
        let l = self.helmholtz(k);
        // S + k^2 M is positive definite in exact arithmetic; its Cholesky
        // fails only when k^2 overflows or underflows the stiffness (the
        // spec layer bounds k L to keep away from that): every consumer
        // then sees NaN and refuses to certify.
        let Ok(f) = l.cholesky() else { return DMatrix::from_element(n, n, f64::NAN) };
        let m = self.to_banded(&self.weights);
        let mut out = DMatrix::zeros(n, n);
        let mut col = vec![0.0; n];
        for j in 0..n {
            col.iter_mut().for_each(|c| *c = 0.0);
            col[j] = m[j];
            f.solve(&mut col);
            for i in 0..n {
                out[(self.order[i], self.order[j])] = m[i] * col[i];
            }
        }
        // exact symmetry of the form (the solve is symmetric up to rounding)
        let t = out.transpose();
        (out + t) * 0.5
    }

    /// Factor of `L_s` (banded order).
    pub fn helmholtz_factor(&self, k: f64) -> Option<BandedCholesky> {
        self.helmholtz(k).cholesky().ok()
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
    fn periodic_stiffness_is_cyclic_and_banded_in_the_interleaved_order() {
        // On the circle the constants are the kernel of -d^2/dy^2: S 1 = 0
        // (to rounding); between walls they are not (S 1 != 0 next to the
        // walls). The interleaved order is a permutation and its band is
        // 2p wide (module docs), and L = S + k^2 M is definite.
        for ny in [16, 24, 64, 1024] {
            let g = YGrid::new(Boundary::Periodic, 0.0, 2.0 * std::f64::consts::PI, ny);
            let mut seen = vec![false; ny];
            g.banded_order().iter().for_each(|&a| seen[a] = true);
            assert!(seen.iter().all(|s| *s), "ny {ny}: not a permutation");
            let s = g.helmholtz(0.0);
            // (nodes d <= p apart within one half land 2d apart; across the
            // middle or the wrap at most 2d - 1; reached once a half holds
            // two nodes p apart, ny > 2p)
            assert!(s.bandwidth() <= 2 * ELEMENT_DEGREE, "ny {ny}: {}", s.bandwidth());
            assert!(ny <= 2 * ELEMENT_DEGREE || s.bandwidth() == 2 * ELEMENT_DEGREE, "ny {ny}: {}", s.bandwidth());
            let mut out = vec![0.0; ny];
            s.mul_vec(&vec![1.0; ny], &mut out);
            let scale = (0..ny).map(|i| s.get(i, i)).fold(0.0, f64::max);
            assert!(out.iter().all(|x| x.abs() < 1e-12 * scale), "ny {ny}: {out:?}");
            assert!(g.helmholtz(1.0).verified_positive_definite_within(0.0), "ny {ny}");
            // the weights integrate 1 to the period
            let total: f64 = g.weights().iter().sum();
            assert!((total - 2.0 * std::f64::consts::PI).abs() < 1e-12, "ny {ny}: {total}");
        }
        let walls = YGrid::new(Boundary::Walls, 0.0, 1.0, 16);
        let mut out = vec![0.0; walls.n()];
        walls.helmholtz(0.0).mul_vec(&vec![1.0; walls.n()], &mut out);
        assert!(out[0].abs() > 1.0, "{out:?}");
    }

    #[test]
    fn the_size_estimates_bound_the_grids_built() {
        // `unknowns` and `stiffness_bandwidth` (used by the spec layer's
        // work limits without building a grid) against the grids themselves
        for boundary in [Boundary::Walls, Boundary::Periodic] {
            for ny in (16..=512).step_by(8) {
                let g = YGrid::new(boundary, -1.0, 2.0, ny);
                assert_eq!(unknowns(boundary, ny), g.n(), "{boundary:?} ny {ny}");
                let b = g.helmholtz(1.0).bandwidth();
                assert!(b <= stiffness_bandwidth(boundary), "{boundary:?} ny {ny}: {b}");
                assert!(ny <= 2 * ELEMENT_DEGREE || b == stiffness_bandwidth(boundary), "{boundary:?} ny {ny}: {b}");
            }
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
