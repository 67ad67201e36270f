//! A stochastic Lie–Poisson system compiled to floating point for stepping.

use crate::kernel::{Fixed, Kernel};
use algebra::{builtin, LieAlgebra};
use casimir::System;
use exact::{rational_to_f64, Poly};
use nalgebra::DMatrix;

/// How `exp(ad*_xi)` is applied.
#[derive(Clone, Debug)]
enum Group {
    /// `so3`: `exp(ad*_xi) mu = exp(-xi^) mu` by the Rodrigues formula.
    So3,
    /// `se3`: `exp(ad*_(xi,u)) (Pi, Gamma) = (R^T (Pi - T x Gamma), R^T Gamma)` with
    /// `R = exp(xi^)`, `T = J(xi) u` (`J` the left Jacobian of SO(3)).
    Se3,
    /// Any other algebra: the matrix exponential of `ad*_xi`
    /// (scaling and squaring), from the basis matrices `ad*_{e_a}`.
    General(Vec<DMatrix<f64>>),
}

/// How `Dh(mu)` is evaluated.
#[derive(Clone, Debug)]
enum Gradient {
    /// `h = 1/2 mu^T H mu + b.mu + c`: `Dh = H mu + b` (row-major `H`).
    Quadratic { h: Vec<f64>, b: Vec<f64> },
    /// Any polynomial: the gradient polynomials, evaluated in floating point.
    Polynomial(Vec<Poly>),
}

/// A system in floating point: `d mu = ad*_{Dh(mu)} mu dt + sum ad*_{sigma_i} mu o dW^i`.
#[derive(Clone, Debug)]
pub struct Model {
    n: usize,
    group: Group,
    gradient: Gradient,
    /// `(a, b, k, c)`: `(ad*_xi mu)_b += c xi_a mu_k`.
    sparse: Vec<(usize, usize, usize, f64)>,
    noise: Vec<Vec<f64>>,
    casimirs: Vec<Poly>,
}

fn same_algebra(a: &LieAlgebra, name: &str) -> bool {
    builtin(name).is_some_and(|b| {
        b.algebra.dim() == a.dim() && b.algebra.structure_constant_rows() == a.structure_constant_rows()
    })
}

/// Taylor series are used below `THETA2_SMALL` (squared angle), where the
/// truncation error is below 1e-17 relative; the closed forms with sin/cos
/// lose accuracy there.
const THETA2_SMALL: f64 = 1e-2;

/// `sin(t)/t`, `(1 - cos t)/t^2`, `(t - sin t)/t^3` as functions of `t^2`.
#[inline]
pub(crate) fn rodrigues(theta2: f64) -> (f64, f64, f64) {
    if theta2 < THETA2_SMALL {
        // Horner in t^2 (multiplications only: divisions cost more here).
        let t2 = theta2;
        let a = 1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0 + t2 * (1.0 / 362_880.0))));
        let b = 0.5 + t2 * (-1.0 / 24.0 + t2 * (1.0 / 720.0 + t2 * (-1.0 / 40_320.0 + t2 * (1.0 / 3_628_800.0))));
        let c =
            1.0 / 6.0 + t2 * (-1.0 / 120.0 + t2 * (1.0 / 5040.0 + t2 * (-1.0 / 362_880.0 + t2 * (1.0 / 39_916_800.0))));
        (a, b, c)
    } else {
        let t = theta2.sqrt();
        let (s, co) = t.sin_cos();
        (s / t, (1.0 - co) / theta2, (t - s) / (theta2 * t))
    }
}

#[inline]
pub(crate) fn cross(a: &[f64], b: &[f64]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `exp(-xi^) v = v - a xi x v + b xi x (xi x v)`.
#[inline]
pub(crate) fn rotate_back(xi: &[f64], v: &[f64], a: f64, b: f64) -> [f64; 3] {
    let c1 = cross(xi, v);
    let c2 = cross(xi, &c1);
    [v[0] - a * c1[0] + b * c2[0], v[1] - a * c1[1] + b * c2[1], v[2] - a * c1[2] + b * c2[2]]
}

impl Model {
    /// Compile a validated system.
    pub fn new(system: &System) -> Model {
        let algebra = system.algebra();
        let n = algebra.dim();
        let group = if same_algebra(algebra, "so3") {
            Group::So3
        } else if same_algebra(algebra, "se3") {
            Group::Se3
        } else {
            Group::General(
                (0..n)
                    .map(|a| {
                        let mut e = vec![exact::Rational::from(0); n];
                        e[a] = exact::Rational::from(1);
                        algebra.coad_matrix(&e).to_dmatrix()
                    })
                    .collect(),
            )
        };
        let h = system.hamiltonian();
        let gradient = if h.total_degree() <= 2 {
            let zero = vec![exact::Rational::from(0); n];
            let hess = h.hessian_at(&zero);
            let b = h.gradient_at(&zero);
            Gradient::Quadratic {
                h: hess.iter().flatten().map(rational_to_f64).collect(),
                b: b.iter().map(rational_to_f64).collect(),
            }
        } else {
            Gradient::Polynomial(h.gradient())
        };
        let mut sparse = Vec::new();
        for a in 0..n {
            for b in 0..n {
                for (k, c) in algebra.bracket_of_basis(a, b) {
                    sparse.push((a, b, *k, rational_to_f64(c)));
                }
            }
        }
        let noise = system.noise().iter().map(|s| s.iter().map(rational_to_f64).collect()).collect();
        let casimirs = system.casimirs().to_vec();
        Model { n, group, gradient, sparse, noise, casimirs }
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of noise fields.
    pub fn noise_count(&self) -> usize {
        self.noise.len()
    }

    /// The noise fields `sigma_i`.
    pub fn noise(&self) -> &[Vec<f64>] {
        &self.noise
    }

    /// Whether `exp(ad*)` has a closed form here (`so3`, `se3`).
    pub fn closed_form_exponential(&self) -> bool {
        !matches!(self.group, Group::General(_))
    }

    /// `out = Dh(mu)`.
    pub fn gradient(&self, mu: &[f64], out: &mut [f64]) {
        match &self.gradient {
            Gradient::Quadratic { h, b } => {
                let n = self.n;
                for i in 0..n {
                    let row = &h[i * n..(i + 1) * n];
                    let mut s = b[i];
                    for j in 0..n {
                        s += row[j] * mu[j];
                    }
                    out[i] = s;
                }
            }
            Gradient::Polynomial(g) => {
                for (o, gi) in out.iter_mut().zip(g) {
                    *o = gi.eval_f64(mu);
                }
            }
        }
    }

    /// `out = ad*_xi mu`.
    pub fn coad(&self, xi: &[f64], mu: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for &(a, b, k, c) in &self.sparse {
            out[b] += c * xi[a] * mu[k];
        }
    }

    /// `out = exp(ad*_xi) mu`, the coadjoint action of a group element: it
    /// keeps `mu` on its coadjoint orbit (Casimirs are conserved to round-off).
    pub fn exp_coad(&self, xi: &[f64], mu: &[f64], out: &mut [f64]) {
        match &self.group {
            Group::So3 => {
                let (a, b, _) = rodrigues(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
                out[..3].copy_from_slice(&rotate_back(&xi[..3], &mu[..3], a, b));
            }
            Group::Se3 => {
                let w = &xi[..3];
                let u = &xi[3..6];
                let (a, b, c) = rodrigues(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
                // T = J(w) u = u + b w x u + c w x (w x u)
                let wu = cross(w, u);
                let wwu = cross(w, &wu);
                let t = [u[0] + b * wu[0] + c * wwu[0], u[1] + b * wu[1] + c * wwu[1], u[2] + b * wu[2] + c * wwu[2]];
                let (pi, gamma) = mu.split_at(3);
                let tg = cross(&t, gamma);
                let shifted = [pi[0] - tg[0], pi[1] - tg[1], pi[2] - tg[2]];
                out[..3].copy_from_slice(&rotate_back(w, &shifted, a, b));
                out[3..6].copy_from_slice(&rotate_back(w, gamma, a, b));
            }
            Group::General(basis) => {
                let n = self.n;
                let mut k = DMatrix::<f64>::zeros(n, n);
                for (x, m) in xi.iter().zip(basis) {
                    if *x != 0.0 {
                        k += m * *x;
                    }
                }
                let e = k.exp();
                for i in 0..n {
                    out[i] = (0..n).map(|j| e[(i, j)] * mu[j]).sum();
                }
            }
        }
    }

    /// The fixed-size kernel for `so3` (with a quadratic Hamiltonian).
    pub(crate) fn kernel3(&self) -> Option<Kernel<3>> {
        self.kernel(Fixed::So3)
    }

    /// The fixed-size kernel for `se3` (with a quadratic Hamiltonian).
    pub(crate) fn kernel6(&self) -> Option<Kernel<6>> {
        self.kernel(Fixed::Se3)
    }

    fn kernel<const N: usize>(&self, want: Fixed) -> Option<Kernel<N>> {
        let group = match self.group {
            Group::So3 => Fixed::So3,
            Group::Se3 => Fixed::Se3,
            Group::General(_) => return None,
        };
        let Gradient::Quadratic { h, b } = &self.gradient else { return None };
        if group != want || self.n != N {
            return None;
        }
        let mut hh = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                hh[i][j] = h[i * N + j];
            }
        }
        let mut bb = [0.0; N];
        bb.copy_from_slice(b);
        if self.noise.len() > 8 {
            return None; // the kernels keep the increments on the stack
        }
        let noise = self
            .noise
            .iter()
            .map(|s| {
                let mut a = [0.0; N];
                a.copy_from_slice(s);
                a
            })
            .collect();
        let diagonal =
            (0..N).all(|i| (0..N).all(|j| i == j || hh[i][j] == 0.0)).then(|| std::array::from_fn(|i| hh[i][i]));
        Some(Kernel { group, h: hh, diagonal, b: bb, noise })
    }

    /// The Casimirs at `mu` (to monitor their drift).
    pub fn casimir_values(&self, mu: &[f64]) -> Vec<f64> {
        self.casimirs.iter().map(|c| c.eval_f64(mu)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use exact::{parse_expression, Rational, Symbols};

    fn system(name: &str) -> System {
        let g = builtin(name).unwrap();
        let s = Symbols::new(g.algebra.coordinates());
        let n = g.algebra.dim();
        let h = parse_expression(
            &g.algebra.coordinates().iter().map(|c| format!("{c}^2")).collect::<Vec<_>>().join(" + "),
            &s,
        )
        .unwrap();
        let cas = g.casimirs.iter().map(|c| parse_expression(c, &s).unwrap()).collect();
        System::new(g.algebra, h, cas, vec![], vec![Rational::from(0); n], vec![]).unwrap()
    }

    /// The closed-form exponentials agree with the matrix exponential of
    /// `ad*_xi` (the general path), for small and large angles.
    #[test]
    fn closed_forms_match_the_matrix_exponential() {
        for name in ["so3", "se3"] {
            let sys = system(name);
            let fast = Model::new(&sys);
            assert!(fast.closed_form_exponential());
            let mut general = fast.clone();
            let n = fast.dim();
            general.group = Group::General(
                (0..n)
                    .map(|a| {
                        let mut e = vec![Rational::from(0); n];
                        e[a] = Rational::from(1);
                        sys.algebra().coad_matrix(&e).to_dmatrix()
                    })
                    .collect(),
            );
            for scale in [1e-4, 0.03, 0.3, 2.0] {
                let xi: Vec<f64> = (0..n).map(|i| scale * ((i as f64 * 1.7).sin() + 0.3)).collect();
                let mu: Vec<f64> = (0..n).map(|i| (i as f64 * 0.9).cos() + 0.5).collect();
                let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
                fast.exp_coad(&xi, &mu, &mut a);
                general.exp_coad(&xi, &mu, &mut b);
                for i in 0..n {
                    assert!((a[i] - b[i]).abs() < 1e-13 * (1.0 + b[i].abs()), "{name} scale {scale}: {a:?} vs {b:?}");
                }
            }
        }
    }
}
