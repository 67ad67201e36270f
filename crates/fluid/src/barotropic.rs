//! One x-mode of the linearised stochastic barotropic (compressible) Euler
//! equations about the shear flow `m_e = (U(y), 0)`, `rho_e = 1`, between
//! walls (docs/fluids.md §1b).
//!
//! **Unknowns.** The perturbation of the semidirect-product dual `g*`:
//! momentum and density `(dm1, dm2, drho)` of x-mode `exp(ikx)`, continuous
//! piecewise polynomials on the spectral elements of [`crate::grid`] (degree
//! [`ELEMENT_DEGREE`], Gauss–Lobatto–Legendre nodes and quadrature), with
//! `dm2 = 0` at the walls (the algebra's vector fields are tangent there).
//! With `dm2 = i a2` every operator below is real, so the unknowns are
//! `(a1, a2, a3) = (dm1, dm2 / i, drho)`, interleaved node by node (bandwidth
//! `3p + 2`).
//!
//! **The form.** The energy–Casimir–momentum–mass functional
//! `H + int rho Phi(q) + c int m1 + lambda int rho` (`q = omega/rho` the
//! potential vorticity, `Phi''(q_e) = w = (U + c)/U''`) has second variation
//!
//! ```text
//! K = int |dm1 + c drho|^2 + |dm2|^2 + (c_s^2 - (U + c)^2) |drho|^2 + w |dq|^2,
//! dq = ik dm2 - dm1' + U drho' + 2 U' drho,
//! ```
//!
//! positive definite when `|U + c| < c_s` and `w >= 0`; here it is the GLL
//! quadrature of that integral with `dq` differentiated element by element.
//!
//! **The drift.** The linearised Lie–Poisson drift is `J_e D^2 H_C` with
//! `J_e xi = ad*_xi (m_e, rho_e)`; for `xi = (v1, v2, f)` in the algebra,
//! `J_e xi = -(2ikU v1 + (U v2)' + ik f, U v1' + f', ik v1 + v2')`. Its
//! quadrature pairing is made exactly skew, so [`BarotropicMode::drift`]
//! `A = W^-1 J W^-1 K` satisfies `K A + A^H K = 0` to rounding: the form is
//! an exact invariant of the discrete drift. The tests check `A` against the
//! analytic linearised compressible Euler equations.
//!
//! **The noise and the generator.** A noise element `((eta(y), 0), r(y))`
//! acts by `B = -[[ik eta, 0, 0], [eta', ik eta, r'], [0, 0, ik eta]]` on
//! `(dm1, dm2, drho)`. With the compatible potential `r' = -U eta'` it
//! transports the potential vorticity exactly (`B dq = -ik eta dq`), so the
//! Casimir part of `K` contributes nothing to the generator form and
//!
//! ```text
//! Q = sum_j int |eta_j' dm1 + r_j' drho|^2 = sum_j int eta_j'^2 |du1|^2,   du1 = dm1 - U drho,
//! ```
//!
//! which is what [`BarotropicMode::generator`] assembles (the same
//! quadrature, wall nodes included). `Sigma^2` of the mode is the largest
//! generalised eigenvalue of `(Q, K)`: the Rayleigh–Ritz value of the
//! continuum quotient on the discrete space. Applying the pointwise `B` to
//! the discrete `K` instead gives `Q` plus a defect, the discrete error of
//! `B dq = -ik eta dq` ([`BarotropicMode::casimir_defect_apply`]); it tends
//! to zero under refinement at fixed `k` and is reported, not used.

use crate::banded::{BandedCholesky, SymBanded};
use crate::grid::{element_nodes, gll, gll_derivative, ELEMENT_DEGREE};
use crate::lanczos::{largest_generalized_eigenvalue, Ritz};
use nalgebra::{Complex, DMatrix};
use numerics::definite::{positive_definite, Symmetric};

/// The largest eigenvalue of `(op, K)` by Lanczos, with the banded Cholesky
/// factor of `K` for the solves.
fn top_against(
    kf: &SymBanded,
    chol: &BandedCholesky,
    op: impl FnMut(&[f64], &mut [f64]),
    tol: f64,
    max_iter: usize,
) -> Ritz {
    let solve = |b: &[f64], x: &mut [f64]| {
        x.copy_from_slice(b);
        chol.solve(x)
    };
    largest_generalized_eigenvalue(kf.n(), op, |x, o| kf.mul_vec(x, o), solve, tol, max_iter)
}

/// The element grid of a channel `[a, b]` with all nodes, walls included.
#[derive(Clone, Debug)]
pub struct WallGrid {
    nodes: Vec<f64>,
    weights: Vec<f64>,
    elements: usize,
    /// Element derivative matrix on the element (reference matrix times `2/h`).
    derivative: DMatrix<f64>,
    /// GLL weights on the element.
    element_weights: Vec<f64>,
}

impl WallGrid {
    /// `ny / ELEMENT_DEGREE` elements on `[a, b]` (`ny` a multiple of the
    /// degree, at least two elements), as for the incompressible walls grid.
    ///
    /// # Panics
    /// If `ny` is not such a multiple (the spec parser guarantees it).
    pub fn new(a: f64, b: f64, ny: usize) -> Self {
        let p = ELEMENT_DEGREE;
        assert!(ny % p == 0 && ny >= 2 * p, "ny must be a multiple of {p}, at least {}", 2 * p);
        let elements = ny / p;
        let h = (b - a) / elements as f64;
        let (xi, wi) = gll(p);
        let derivative = gll_derivative(p, &xi) * (2.0 / h);
        let (nodes, weights) = element_nodes(a, b, elements, &xi, &wi);
        WallGrid { nodes, weights, elements, derivative, element_weights: wi.iter().map(|w| w * h / 2.0).collect() }
    }

    /// All nodes, walls included.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Assembled quadrature weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Unknowns per mode: `3 ny + 1` (`dm2` has none at the walls).
    pub fn unknowns(&self) -> usize {
        3 * self.nodes.len() - 2
    }

    /// Index of component `c` (0: `a1`, 1: `a2`, 2: `a3`) at node `g`, `None`
    /// for `a2` at a wall.
    pub fn index(&self, g: usize, c: usize) -> Option<usize> {
        let last = self.nodes.len() - 1;
        let wall = g == 0 || g == last;
        let start = if g == 0 { 0 } else { 2 + 3 * (g - 1) };
        match (c, wall) {
            (0, _) => Some(start),
            (1, true) => None,
            (1, false) => Some(start + 1),
            (_, true) => Some(start + 1),
            _ => Some(start + 2),
        }
    }

    fn bandwidth(&self) -> usize {
        3 * ELEMENT_DEGREE + 2
    }
}

/// The profile, the Casimir weight and the noise at the nodes.
#[derive(Clone, Debug)]
pub struct BarotropicCoefficients {
    /// `U(y_g)`.
    pub u: Vec<f64>,
    /// `U'(y_g)`.
    pub up: Vec<f64>,
    /// `w(y_g) = Phi''(q_e)`, non-negative.
    pub w: Vec<f64>,
    /// `eta_j(y_g)`.
    pub eta: Vec<Vec<f64>>,
    /// `eta_j'(y_g)`.
    pub eta_prime: Vec<Vec<f64>>,
    /// `r_j'(y_g)`.
    pub r_prime: Vec<Vec<f64>>,
}

impl BarotropicCoefficients {
    /// Whether every coefficient is finite and every weight non-negative.
    pub fn usable(&self) -> bool {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        finite(&self.u)
            && finite(&self.up)
            && finite(&self.w)
            && self.w.iter().all(|w| *w >= 0.0)
            && self.eta.iter().chain(&self.eta_prime).chain(&self.r_prime).all(|v| finite(v))
    }
}

/// One x-mode: wavenumber, sound speed, Galilean shift and the coefficients.
#[derive(Clone, Debug)]
pub struct BarotropicMode<'g> {
    grid: &'g WallGrid,
    coef: &'g BarotropicCoefficients,
    k: f64,
    sound_speed: f64,
    shift: f64,
}

/// `lambda_max(Q, K)` of a mode.
#[derive(Clone, Debug, PartialEq)]
pub struct BarotropicSigma2 {
    /// The Ritz value (a Rayleigh quotient: a lower estimate).
    pub lambda_max: f64,
    /// The Lanczos record.
    pub ritz: Ritz,
}

impl<'g> BarotropicMode<'g> {
    /// The mode `exp(ikx)` with sound speed `c_s` and Galilean shift `c`.
    pub fn new(grid: &'g WallGrid, coef: &'g BarotropicCoefficients, k: f64, sound_speed: f64, shift: f64) -> Self {
        BarotropicMode { grid, coef, k, sound_speed, shift }
    }

    /// The form `K` (module docs), real symmetric banded.
    pub fn form(&self) -> SymBanded {
        let g = self.grid;
        let (c, cs) = (self.shift, self.sound_speed);
        let mut k = SymBanded::zeros(g.unknowns(), g.bandwidth());
        for (n, &wq) in g.weights.iter().enumerate() {
            let i1 = g.index(n, 0).unwrap_or(0);
            let i3 = g.index(n, 2).unwrap_or(0);
            let b = self.coef.u[n] + c;
            // |a1 + c a3|^2 + (c_s^2 - (U + c)^2) a3^2
            k.add(i1, i1, wq);
            k.add(i3, i1, wq * c);
            k.add(i3, i3, wq * (c * c + (cs - b) * (cs + b)));
            if let Some(i2) = g.index(n, 1) {
                k.add(i2, i2, wq);
            }
        }
        // w dq^2, element by element: dq = -k a2 - D a1 + U D a3 + 2 U' a3.
        let p = ELEMENT_DEGREE;
        let mut row: Vec<(usize, f64)> = Vec::with_capacity(2 * p + 3);
        for e in 0..g.elements {
            for j in 0..=p {
                let n = e * p + j;
                let weight = g.element_weights[j] * self.coef.w[n];
                if weight == 0.0 {
                    continue;
                }
                row.clear();
                for l in 0..=p {
                    let d = g.derivative[(j, l)];
                    let m = e * p + l;
                    row.push((g.index(m, 0).unwrap_or(0), -d));
                    row.push((g.index(m, 2).unwrap_or(0), self.coef.u[n] * d));
                }
                row.push((g.index(n, 2).unwrap_or(0), 2.0 * self.coef.up[n]));
                if let Some(i2) = g.index(n, 1) {
                    row.push((i2, -self.k));
                }
                // merge repeated unknowns (a3 at node n enters twice)
                row.sort_by_key(|r| r.0);
                row.dedup_by(|next, kept| {
                    let same = next.0 == kept.0;
                    if same {
                        kept.1 += next.1;
                    }
                    same
                });
                for (x, &(ia, va)) in row.iter().enumerate() {
                    for &(ib, vb) in &row[..=x] {
                        // SymBanded::add fills (ia, ib) and (ib, ia), the diagonal once
                        k.add(ia, ib, weight * va * vb);
                    }
                }
            }
        }
        k
    }

    /// The generator form `Q = sum_j int |eta_j' a1 + r_j' a3|^2` (module docs).
    pub fn generator(&self) -> SymBanded {
        let g = self.grid;
        let mut q = SymBanded::zeros(g.unknowns(), g.bandwidth());
        for (n, &wq) in g.weights.iter().enumerate() {
            let i1 = g.index(n, 0).unwrap_or(0);
            let i3 = g.index(n, 2).unwrap_or(0);
            for (ep, rp) in self.coef.eta_prime.iter().zip(&self.coef.r_prime) {
                let (s, t) = (ep[n], rp[n]);
                q.add(i1, i1, wq * s * s);
                q.add(i3, i1, wq * s * t);
                q.add(i3, i3, wq * t * t);
            }
        }
        q
    }

    /// `Sigma^2` of the mode: Lanczos on `(Q, K)` with the banded Cholesky
    /// of `K`; `None` if `K` is not (numerically) positive definite or the
    /// iteration produced a non-finite value.
    pub fn sigma2(&self, tol: f64) -> Option<BarotropicSigma2> {
        let kf = self.form();
        let q = self.generator();
        let chol = kf.cholesky().ok()?;
        let ritz = top_against(&kf, &chol, |x, out| q.mul_vec(x, out), tol, 600);
        (ritz.value.is_finite() && ritz.residual.is_finite() && ritz.scale.is_finite())
            .then_some(BarotropicSigma2 { lambda_max: ritz.value, ritz })
    }

    /// `(K ≻ 0, bound K - Q ≻ 0)`, each proved by the verified banded
    /// Cholesky test ([`SymBanded::verified_positive_definite_within`]) for
    /// the matrices as computed, the rounding of `bound K - Q` included.
    pub fn verify(&self, bound: f64) -> (bool, bool) {
        if !(bound.is_finite() && bound >= 0.0) {
            return (false, false);
        }
        let kf = self.form();
        if !positive_definite(Symmetric::Banded(&kf), 0.0).proved {
            return (false, false);
        }
        let q = self.generator();
        let (g, radius) = kf.scaled_minus(bound, &q);
        (true, positive_definite(Symmetric::Banded(&g), radius).proved)
    }

    /// The real noise operator `R_j` with `B_j = -i R_j` in the unknowns
    /// `(a1, a2, a3)`: `R = [[k eta, 0, 0], [-eta', k eta, -r'], [0, 0, k eta]]`
    /// (the `a2` row only at interior nodes).
    fn noise_apply(&self, j: usize, x: &[f64], out: &mut [f64], transpose: bool) {
        let g = self.grid;
        let (eta, ep, rp) = (&self.coef.eta[j], &self.coef.eta_prime[j], &self.coef.r_prime[j]);
        out.iter_mut().for_each(|v| *v = 0.0);
        for n in 0..g.nodes.len() {
            let ke = self.k * eta[n];
            let i1 = g.index(n, 0).unwrap_or(0);
            let i3 = g.index(n, 2).unwrap_or(0);
            out[i1] += ke * x[i1];
            out[i3] += ke * x[i3];
            if let Some(i2) = g.index(n, 1) {
                out[i2] += ke * x[i2];
                if transpose {
                    out[i1] -= ep[n] * x[i2];
                    out[i3] -= rp[n] * x[i2];
                } else {
                    out[i2] -= ep[n] * x[i1] + rp[n] * x[i3];
                }
            }
        }
    }

    /// `x -> (Q_B - Q) x`, where `Q_B = sum_j R_j^T K R_j - (K R_j^2 + R_j^2T K)/2`
    /// is the generator form of the pointwise noise on the discrete `K`: the
    /// discrete defect of `B dq = -ik eta dq` (zero in the continuum).
    pub fn casimir_defect_apply<'a>(&'a self, kf: &'a SymBanded, q: &'a SymBanded) -> impl Fn(&[f64], &mut [f64]) + 'a {
        // Scratch vectors made once, not per product (Lanczos calls this
        // hundreds of times).
        let scratch = std::cell::RefCell::new([vec![0.0; kf.n()], vec![0.0; kf.n()], vec![0.0; kf.n()]]);
        move |x: &[f64], out: &mut [f64]| {
            let mut scratch = scratch.borrow_mut();
            let [t1, t2, t3] = &mut *scratch;
            q.mul_vec(x, out);
            out.iter_mut().for_each(|v| *v = -*v);
            for j in 0..self.coef.eta.len() {
                // R^T K R x
                self.noise_apply(j, x, t1, false);
                kf.mul_vec(t1, t2);
                self.noise_apply(j, t2, t3, true);
                out.iter_mut().zip(t3.iter()).for_each(|(o, v)| *o += v);
                // -(1/2) K R R x
                self.noise_apply(j, t1, t2, false);
                kf.mul_vec(t2, t3);
                out.iter_mut().zip(t3.iter()).for_each(|(o, v)| *o -= 0.5 * v);
                // -(1/2) R^T R^T K x
                kf.mul_vec(x, t1);
                self.noise_apply(j, t1, t2, true);
                self.noise_apply(j, t2, t3, true);
                out.iter_mut().zip(t3.iter()).for_each(|(o, v)| *o -= 0.5 * v);
            }
        }
    }

    /// The largest `|lambda|` of `(Q_B - Q, K)`: how far the pointwise noise
    /// on the discrete form is from the continuum generator, relative to `K`.
    pub fn casimir_defect(&self, tol: f64) -> Option<f64> {
        let kf = self.form();
        let q = self.generator();
        let chol = kf.cholesky().ok()?;
        let apply = self.casimir_defect_apply(&kf, &q);
        let top = top_against(&kf, &chol, &apply, tol, 300);
        let negated = |x: &[f64], o: &mut [f64]| {
            apply(x, o);
            o.iter_mut().for_each(|v| *v = -*v)
        };
        let bottom = top_against(&kf, &chol, negated, tol, 300);
        let v = top.value.abs().max(bottom.value.abs());
        v.is_finite().then_some(v)
    }

    /// `lambda_max(Q_B, K)`, `Q_B` the generator form of the pointwise noise
    /// on the discrete `K` (see [`Self::casimir_defect_apply`]): the growth
    /// constant of the discretised linear SDE itself, `d E V/dt = E X^H Q_B X`
    /// (docs/fluids.md §1b). A Lanczos estimate (a Ritz value, so from below).
    pub fn pointwise_noise_sigma2(&self, tol: f64) -> Option<f64> {
        let kf = self.form();
        let q = self.generator();
        let chol = kf.cholesky().ok()?;
        let defect = self.casimir_defect_apply(&kf, &q);
        let mut qx = vec![0.0; kf.n()];
        let apply = |x: &[f64], o: &mut [f64]| {
            defect(x, o);
            q.mul_vec(x, &mut qx);
            o.iter_mut().zip(&qx).for_each(|(o, v)| *o += v);
        };
        let top = top_against(&kf, &chol, apply, tol, 300);
        (top.value.is_finite() && top.residual.is_finite()).then_some(top.value)
    }

    /// The phase `S = diag(1, i, 1)` per node: `(dm1, dm2, drho) = S (a1, a2, a3)`.
    fn phase(&self) -> Vec<Complex<f64>> {
        let g = self.grid;
        let mut s = vec![Complex::new(1.0, 0.0); g.unknowns()];
        for n in 0..g.nodes.len() {
            if let Some(i2) = g.index(n, 1) {
                s[i2] = Complex::new(0.0, 1.0);
            }
        }
        s
    }

    /// The drift `A = W^-1 J W^-1 K` (dense, in the unknowns
    /// `(dm1, dm2, drho)` of the module docs' ordering), in the frame moving
    /// with the shift: `A = A_lab - ikc`. For tests and evidence.
    pub fn drift(&self) -> DMatrix<Complex<f64>> {
        let g = self.grid;
        let n = g.unknowns();
        let p = ELEMENT_DEGREE;
        let ik = Complex::new(0.0, self.k);
        let s = self.phase();
        // K in (dm1, dm2, drho): S K S^H.
        let kr = self.form().to_dense();
        let kc = DMatrix::from_fn(n, n, |i, j| s[i] * kr[(i, j)] * s[j].conj());
        // J: zeta^H J xi = -sum_e sum_j wq [conj z1 (2ikU v1 + D(U v2) + ik f)
        //   + conj z2 (U D v1 + D f) + conj g (ik v1 + D v2)].
        let mut jm = DMatrix::<Complex<f64>>::zeros(n, n);
        for e in 0..g.elements {
            for j in 0..=p {
                let nj = e * p + j;
                let wq = g.element_weights[j];
                let u = self.coef.u[nj];
                let (z1, z2, z3) = (g.index(nj, 0).unwrap_or(0), g.index(nj, 1), g.index(nj, 2).unwrap_or(0));
                jm[(z1, z1)] -= ik * (2.0 * u * wq);
                jm[(z1, z3)] -= ik * wq;
                jm[(z3, z1)] -= ik * wq;
                for l in 0..=p {
                    let nl = e * p + l;
                    let d = g.derivative[(j, l)] * wq;
                    let (v1, v2, v3) = (g.index(nl, 0).unwrap_or(0), g.index(nl, 1), g.index(nl, 2).unwrap_or(0));
                    if let Some(v2) = v2 {
                        jm[(z1, v2)] -= Complex::new(d * self.coef.u[nl], 0.0);
                        jm[(z3, v2)] -= Complex::new(d, 0.0);
                    }
                    if let Some(z2) = z2 {
                        jm[(z2, v1)] -= Complex::new(u * d, 0.0);
                        jm[(z2, v3)] -= Complex::new(d, 0.0);
                    }
                }
            }
        }
        let js = (&jm - jm.adjoint()) * Complex::new(0.5, 0.0);
        let mut wd = vec![0.0; n];
        for (m, &w) in g.weights.iter().enumerate() {
            for c in 0..3 {
                if let Some(i) = g.index(m, c) {
                    wd[i] = w;
                }
            }
        }
        let winv =
            DMatrix::from_fn(n, n, |i, j| if i == j { Complex::new(1.0 / wd[i], 0.0) } else { Complex::new(0.0, 0.0) });
        &winv * js * &winv * kc
    }

    /// The pointwise noise `B_j` (dense, in `(dm1, dm2, drho)`).
    pub fn noise(&self, j: usize) -> DMatrix<Complex<f64>> {
        let g = self.grid;
        let n = g.unknowns();
        let mut b = DMatrix::<Complex<f64>>::zeros(n, n);
        for m in 0..g.nodes.len() {
            let ike = Complex::new(0.0, self.k * self.coef.eta[j][m]);
            for c in 0..3 {
                if let Some(i) = g.index(m, c) {
                    b[(i, i)] = -ike;
                }
            }
            if let Some(i2) = g.index(m, 1) {
                b[(i2, g.index(m, 0).unwrap_or(0))] = Complex::new(-self.coef.eta_prime[j][m], 0.0);
                b[(i2, g.index(m, 2).unwrap_or(0))] = Complex::new(-self.coef.r_prime[j][m], 0.0);
            }
        }
        b
    }

    /// `K` in `(dm1, dm2, drho)` (dense, complex Hermitian).
    pub fn form_complex(&self) -> DMatrix<Complex<f64>> {
        let s = self.phase();
        let kr = self.form().to_dense();
        let n = kr.nrows();
        DMatrix::from_fn(n, n, |i, j| s[i] * kr[(i, j)] * s[j].conj())
    }

    /// Number of noise fields.
    pub fn noise_fields(&self) -> usize {
        self.coef.eta.len()
    }

    /// Wavenumber.
    pub fn k(&self) -> f64 {
        self.k
    }
}
