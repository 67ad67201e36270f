//! One x-mode of the linearised stochastic vorticity equation.
//!
//! About the shear flow `U(y)` (vorticity `omega_e = -U'`), the perturbation
//! `omega = Re(w(y) e^{ikx})` obeys
//!
//! ```text
//! dw = A w dt + sum_j B_j w o dW^j,   A = -ik (U + U'' L^-1),   B_j = -ik eta_j(y),
//! ```
//!
//! with `L^-1` the stream-function solve. On the grid of [`crate::grid`],
//! `A = -ik R`, `R = diag(U) + diag(U''/m) K`, `K = M L^-1` the energy matrix.
//!
//! The energy–Casimir–momentum form is `V = s (e K + M diag(w))`: `e = 1`
//! (energy), `w = Phi''(omega_e) = (U + c)/U''` from the Casimir
//! `int Phi(omega)` with Galilean shift `c`, `s = ±1` its sign; `e = 0`
//! gives the pseudomomentum `int w^2/U''` (Casimir plus momentum alone).
//!
//! **The generator form in closed form.** Both `K` and `M diag(w)` are
//! real symmetric, `A` and `B_j` are `-ik` times real matrices, and
//! `sym(V A) = 0` exactly on this grid (`K` symmetric and `w U'' = U + c` at
//! every node), so the generator form of the finite-dimensional pipeline,
//! `Q = sym(V A~) + sum_j B_j^H V B_j` (Itô `A~`), reduces to
//!
//! ```text
//! Q = -(k^2/2) sum_j [E_j, [E_j, V]],   (Q)_ab = -(k^2/2) s e sum_j (eta_j(y_a) - eta_j(y_b))^2 K_ab,
//! ```
//!
//! `E_j = diag(eta_j)`. The diagonal Casimir part commutes with every `E_j` and
//! drops out: the Casimir contributes nothing to `Q`. The tests compare this
//! with the generator crate's general formula on the real embedding.

use crate::banded::{BandedCholesky, BandedRows};
use crate::grid::YGrid;
use crate::lanczos::{conjugate_gradients, largest_generalized_eigenvalue, Ritz};
use nalgebra::DMatrix;
use numerics::definite::{positive_definite, Symmetric};
use outcome::Sign;

/// Up to this many unknowns per mode (walls, ny = 1024) a mode whose bound
/// the banded check of [`crate::walls_check`] does not prove is tried by
/// the dense check (about 0.15 s a mode there;
/// [`crate::analysis::verified_mode_bound`], [`Mode::verify`]).
pub const DENSE_FALLBACK_UNKNOWNS: usize = 1023;

/// Where the dense fallback is allowed, the dense check is run alone when
/// the banded check's work `rows (bandwidth + 1)^2`
/// ([`crate::walls_check::lifted_size`]) exceeds this multiple of `n^3`
/// and [`DENSE_PREFERRED_FLOOR`]. Measured at `n = 1023` (`fluid_mode`,
/// the cubic profile with `J` fields `0.1 sin(j y + j/7)`, mode 1, a CI run
/// beside it): the banded bound takes 99 ms at `J = 12` (work `0.21 n^3`)
/// and 412 ms at `J = 16` (`0.45 n^3`), the dense check 250 to 440 ms
/// whatever `J`.
pub const DENSE_PREFERRED_RATIO: f64 = 0.3;

/// The banded work below which the banded check is kept however the dense
/// one compares (`1e8`, about 50 ms of checking): its claim is about the
/// exact pencil of the stored operators, the dense one's about `K` as
/// computed (docs/fluids.md §5b), so it is given up only where it costs.
pub const DENSE_PREFERRED_FLOOR: f64 = 1e8;

/// Whether a walls mode's bounds are proved by the dense check alone,
/// without the banded one: the dense fallback is allowed there
/// (walls, at most [`DENSE_FALLBACK_UNKNOWNS`] unknowns) and the banded
/// check's matrix for `noise_fields` non-constant noise fields, `J + 2`
/// unknowns per node, would cost more (its time grows like `J^3`, the
/// dense check's hardly with `J`). Increasing in `noise_fields`, so the
/// spec layer's estimate from every field given is the safe side. At
/// `n = 1023` the dense check takes over from `J = 14` fields.
///
/// ```
/// use fluid::grid::Boundary;
/// use fluid::modes::dense_check_preferred;
/// assert!(!dense_check_preferred(Boundary::Walls, 1023, 13));
/// assert!(dense_check_preferred(Boundary::Walls, 1023, 14));
/// assert!(!dense_check_preferred(Boundary::Walls, 255, 5)); // both cheap: the stronger claim kept
/// assert!(!dense_check_preferred(Boundary::Periodic, 1024, 64)); // no dense check on periodic grids
/// assert!(!dense_check_preferred(Boundary::Walls, 2047, 64)); // nor above 1023 unknowns
/// ```
pub fn dense_check_preferred(boundary: crate::grid::Boundary, n: usize, noise_fields: usize) -> bool {
    if boundary != crate::grid::Boundary::Walls || n > DENSE_FALLBACK_UNKNOWNS {
        return false;
    }
    let (rows, width) = crate::walls_check::lifted_size(n, crate::grid::stiffness_bandwidth(boundary), noise_fields);
    let banded = rows as f64 * ((width + 1) as f64).powi(2);
    banded > DENSE_PREFERRED_FLOOR && banded > DENSE_PREFERRED_RATIO * (n as f64).powi(3)
}

/// The profile and the noise at the grid nodes.
#[derive(Clone, Debug)]
pub struct Coefficients {
    /// `U(y_a)`.
    pub u: Vec<f64>,
    /// `U''(y_a)`.
    pub upp: Vec<f64>,
    /// `eta_j(y_a)` for each noise field `j`.
    pub eta: Vec<Vec<f64>>,
}

impl Coefficients {
    /// The noise fields that are not constant, each less its mean, and
    /// `S2 = sum_j eta_j^2` at the nodes. A constant field is a multiple of
    /// the identity and drops out of `Q = -(k^2/2) sum [E, [E, V]]` exactly,
    /// and so does the mean of any field: subtracting it leaves `Q`
    /// unchanged (up to the rounding of the subtraction) and avoids
    /// cancellation.
    pub fn centred_noise(&self) -> (Vec<Vec<f64>>, Vec<f64>) {
        let n = self.u.len();
        let eta: Vec<Vec<f64>> = self
            .varying_noise()
            .map(|e| {
                let mean = e.iter().sum::<f64>() / n as f64;
                e.iter().map(|x| x - mean).collect()
            })
            .collect();
        let s2 = (0..n).map(|a| eta.iter().map(|e| e[a] * e[a]).sum()).collect();
        (eta, s2)
    }

    /// The noise fields that are not constant at the nodes: those
    /// [`Coefficients::centred_noise`] keeps and the banded check lifts.
    pub fn varying_noise(&self) -> impl Iterator<Item = &Vec<f64>> {
        self.eta.iter().filter(|e| e.iter().any(|x| *x != e[0]))
    }
}

/// `V = sign (energy K + M diag(w))`.
#[derive(Clone, Debug)]
pub struct Form {
    /// Coefficient of the energy (1 or 0).
    pub energy: f64,
    /// The Casimir weight `Phi''(omega_e(y_a))`.
    pub w: Vec<f64>,
    /// The sign that makes `V` positive.
    pub sign: Sign,
}

/// Why a per-mode computation could not be done.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModeError {
    /// `V` is not positive definite for this mode (numerically).
    #[error("the form is not definite for x-wavenumber {k}")]
    NotDefinite {
        /// The wavenumber.
        k: f64,
    },
    /// A non-finite number appeared (data beyond the range of doubles).
    #[error("the computation for x-wavenumber {k} broke down on a non-finite number")]
    NonFinite {
        /// The wavenumber.
        k: f64,
    },
}

/// Sigma^2 of one mode, from the Lanczos process.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModeSigma2 {
    /// Largest generalised eigenvalue of `(Q, V)` (not floored).
    pub lambda_max: f64,
    /// The Lanczos data.
    pub ritz: Ritz,
}

/// One x-mode `e^{ikx}` on a grid.
#[derive(Clone, Copy, Debug)]
pub struct Mode<'g> {
    grid: &'g YGrid,
    k: f64,
}

impl<'g> Mode<'g> {
    /// Mode of wavenumber `k > 0`.
    pub fn new(grid: &'g YGrid, k: f64) -> Self {
        Mode { grid, k }
    }

    /// The wavenumber.
    pub fn k(&self) -> f64 {
        self.k
    }

    /// The grid.
    pub fn grid(&self) -> &'g YGrid {
        self.grid
    }

    /// The real matrix `R` with `A = -ik R` (dense).
    pub fn drift_matrix(&self, coef: &Coefficients) -> DMatrix<f64> {
        let k = self.grid.energy_matrix(self.k);
        let m = self.grid.weights();
        let n = self.grid.n();
        DMatrix::from_fn(n, n, |a, b| coef.upp[a] / m[a] * k[(a, b)] + if a == b { coef.u[a] } else { 0.0 })
    }

    /// `V` (dense, vorticity coordinates).
    pub fn form_matrix(&self, form: &Form) -> DMatrix<f64> {
        self.form_from_energy(&self.grid.energy_matrix(self.k), form)
    }

    fn form_from_energy(&self, kmat: &DMatrix<f64>, form: &Form) -> DMatrix<f64> {
        let m = self.grid.weights();
        let mut v = kmat * (form.sign.as_f64() * form.energy);
        for a in 0..self.grid.n() {
            v[(a, a)] += form.sign.as_f64() * m[a] * form.w[a];
        }
        v
    }

    /// `Q` of `V` by the closed form of the module docs (dense).
    pub fn generator_matrix(&self, form: &Form, coef: &Coefficients) -> DMatrix<f64> {
        self.generator_from_energy(&self.grid.energy_matrix(self.k), form, coef)
    }

    fn generator_from_energy(&self, kmat: &DMatrix<f64>, form: &Form, coef: &Coefficients) -> DMatrix<f64> {
        let c = -0.5 * self.k * self.k * form.sign.as_f64() * form.energy;
        DMatrix::from_fn(self.grid.n(), self.grid.n(), |a, b| {
            let d: f64 = coef.eta.iter().map(|e| (e[a] - e[b]).powi(2)).sum();
            c * d * kmat[(a, b)]
        })
    }

    /// The Hermitian part of `V A` (imaginary, so returned as the real
    /// antisymmetric matrix `(k/2)(V R - R^T V)` with `sym(VA) = -i` times it):
    /// zero for an energy–Casimir–momentum form.
    pub fn drift_residual(&self, form: &Form, coef: &Coefficients) -> DMatrix<f64> {
        let v = self.form_matrix(form);
        let r = self.drift_matrix(coef);
        (&v * &r - r.transpose() * &v) * (self.k / 2.0)
    }

    /// Largest generalised eigenvalue of `(Q, V)` by Lanczos on
    /// `C^-1 Q C^-T`, `V = C C^T`, with banded solves (both boundaries; the
    /// vectors are in the grid's banded order, which leaves the eigenvalue
    /// unchanged).
    pub fn sigma2(&self, form: &Form, coef: &Coefficients, tol: f64) -> Result<ModeSigma2, ModeError> {
        let n = self.grid.n();
        let max_iter = 600;
        if form.energy == 0.0 {
            // Q = 0 identically (module docs); V must still be definite.
            let m = self.grid.weights();
            if (0..n).any(|a| {
                (form.sign.as_f64() * form.w[a] * m[a]).is_nan() || form.sign.as_f64() * form.w[a] * m[a] <= 0.0
            }) {
                return Err(ModeError::NotDefinite { k: self.k });
            }
            let ritz = Ritz { value: 0.0, residual: 0.0, iterations: 0, scale: 0.0 };
            return Ok(ModeSigma2 { lambda_max: 0.0, ritz });
        }
        let ops = WallOps::new(self.grid, self.k, form, coef).ok_or(ModeError::NotDefinite { k: self.k })?;
        let cell = std::cell::RefCell::new(WallScratch::new(n));
        let ritz = largest_generalized_eigenvalue(
            n,
            |x, out| ops.q_omega(x, out, &mut cell.borrow_mut()),
            |x, out| ops.v_omega(x, out),
            |b, x| ops.v_omega_solve(b, x, &mut cell.borrow_mut()),
            tol,
            max_iter,
        );
        if !(ritz.value.is_finite() && ritz.residual.is_finite() && ritz.scale.is_finite()) {
            return Err(ModeError::NonFinite { k: self.k });
        }
        Ok(ModeSigma2 { lambda_max: ritz.value, ritz })
    }

    /// `(V ≻ 0, sigma2_bar V - Q ≻ 0)`, each proved or not: by the banded
    /// check of [`crate::walls_check`] (`O(ny)`, for the exact pencil of the
    /// stored operators; both boundaries), then, if that fails on a walls
    /// grid of at most [`DENSE_FALLBACK_UNKNOWNS`] unknowns, by the dense
    /// check [`Mode::verify_dense`]. Not on periodic grids: their stiffness
    /// has the constants in its kernel, so `L = S + k^2 M` is nearly
    /// singular for small `k L` and the computed `K` the dense check trusts
    /// can be wrong by far more than its margin (at ny = 16, `k = 7e-7` it
    /// proves a bound 0.12% below the stored pencil's eigenvalue; test
    /// `walls_check::tests::no_dense_fallback_on_periodic_grids`).
    ///
    /// Where [`Mode::prefers_dense`] says so, the dense check runs alone
    /// ([`Mode::ladder_check`]).
    pub fn verify(&self, form: &Form, coef: &Coefficients, sigma2_bar: f64) -> (bool, bool) {
        let banded = self.ladder_check(form, coef, sigma2_bar);
        if banded.1 || !self.dense_fallback() || self.prefers_dense(coef) {
            banded
        } else {
            // The banded check proves only wider margins (walls_check
            // docs); where the dense one is affordable it may prove more.
            let dense = self.verify_dense(form, coef, sigma2_bar);
            (banded.0 || dense.0, dense.1)
        }
    }

    /// Whether [`Mode::verify`] may fall back to the dense check: walls
    /// grids of at most [`DENSE_FALLBACK_UNKNOWNS`] unknowns.
    pub fn dense_fallback(&self) -> bool {
        self.grid.boundary() == crate::grid::Boundary::Walls && self.grid.n() <= DENSE_FALLBACK_UNKNOWNS
    }

    /// [`dense_check_preferred`] for this mode's grid and the noise fields
    /// of `coef` that are not constant ([`Coefficients::varying_noise`]).
    pub fn prefers_dense(&self, coef: &Coefficients) -> bool {
        dense_check_preferred(self.grid.boundary(), self.grid.n(), coef.varying_noise().count())
    }

    /// The one check the margin ladder climbs for this mode
    /// ([`crate::analysis::verified_mode_bound`], the narrowing of the
    /// overall bound, [`Mode::verify`]): the dense one where
    /// [`Mode::prefers_dense`], the banded one of [`crate::walls_check`]
    /// otherwise.
    pub fn ladder_check(&self, form: &Form, coef: &Coefficients, sigma2_bar: f64) -> (bool, bool) {
        if self.prefers_dense(coef) {
            self.verify_dense(form, coef, sigma2_bar)
        } else {
            crate::walls_check::verify_walls(self.grid, self.k, form, coef, sigma2_bar)
        }
    }

    /// The dense check at this grid: `V ≻ 0` and `sigma2_bar V - Q ≻ 0`,
    /// each by the rigorous floating-point dense Cholesky test of
    /// `numerics::definite`, for `V` and `Q` as computed. Forming `sigma2_bar V - Q` in
    /// floating point rounds each entry by at most
    /// `2.01 u (|sigma2_bar V_ab| + |Q_ab|)` (`u = 2^-53`: one rounding for the
    /// product, one for the difference), and symmetrising it (a no-op for
    /// the `V` and `Q` built here from the symmetrised `K`, counted all the
    /// same) by at most as much again
    /// plus `u` of the result, so the second test is run with `3.02 u` times
    /// the Frobenius norm of `|sigma2_bar V| + |Q|` as a radius
    /// ([`numerics::definite::positive_definite`]): the claim holds
    /// for the exact `sigma2_bar V - Q`, not only for its rounding.
    /// Returns `(form_definite, inequality)`.
    pub fn verify_dense(&self, form: &Form, coef: &Coefficients, sigma2_bar: f64) -> (bool, bool) {
        if !(sigma2_bar.is_finite() && sigma2_bar >= 0.0) {
            return (false, false);
        }
        let kmat = self.grid.energy_matrix(self.k);
        let v = self.form_from_energy(&kmat, form);
        let v = symmetrise(v);
        let definite = positive_definite(Symmetric::Dense(&v), 0.0).proved;
        if form.energy == 0.0 {
            // V diagonal, Q = 0: the inequality 0 <= sigma2_bar V holds for sigma2_bar >= 0.
            return (definite, definite);
        }
        if !definite {
            return (false, false);
        }
        let q = self.generator_from_energy(&kmat, form, coef);
        let n = v.nrows();
        let mut g = DMatrix::zeros(n, n);
        let mut bound2 = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let bv = sigma2_bar * v[(i, j)];
                g[(i, j)] = bv - q[(i, j)];
                let e = bv.abs() + q[(i, j)].abs();
                bound2 += e * e;
            }
        }
        // 3.02 u (see above), then a relative (1 + 4n u) for the rounding of
        // the sum of squares and the square root, then the smallest
        // subnormal per entry for underflow in the products.
        let u = f64::EPSILON / 2.0;
        let radius = 3.02 * u * bound2.sqrt() * (1.0 + 4.0 * (n as f64 + 2.0) * u) + 2.0 * n as f64 * 5e-324;
        let g = symmetrise(g);
        (true, positive_definite(Symmetric::Dense(&g), radius).proved)
    }
}

fn symmetrise(a: DMatrix<f64>) -> DMatrix<f64> {
    let t = a.transpose();
    (a + t) * 0.5
}

/// The walls operators, applied with banded solves and never formed:
/// `K x = M L^-1 M x`, `V x = s (e K x + M w x)`, and
/// `Q x = -(k^2/2) s e sum_j (E_j^2 K x - 2 E_j K E_j x + K E_j^2 x)` in
/// vorticity coordinates, where the pencil is well conditioned (`V` is a
/// weighted identity plus a smoothing operator). `V x = b` is solved by
/// conjugate gradients preconditioned with the exact inverse in
/// stream-function coordinates, `V^-1 = M^-1 L V_psi^-1 L M^-1` with
/// `V_psi = s (e L + L diag(w/m) L)` (banded, twice the bandwidth of `L`): that inverse is
/// exact in exact arithmetic but loses accuracy through the conditioning of
/// `L`, which the conjugate-gradient iteration then removes. The banded
/// Cholesky of `V_psi` is also the definiteness screen.
struct WallOps {
    l: BandedRows,
    l_factor: BandedCholesky,
    v_factor: BandedCholesky,
    m: Vec<f64>,
    wm: Vec<f64>,
    eta: Vec<Vec<f64>>,
    eta2: Vec<f64>,
    sign: f64,
    energy: f64,
    coef_q: f64,
}

struct WallScratch {
    t: Vec<f64>,
    t2: Vec<f64>,
    t3: Vec<f64>,
}

impl WallScratch {
    fn new(n: usize) -> Self {
        WallScratch { t: vec![0.0; n], t2: vec![0.0; n], t3: vec![0.0; n] }
    }
}

impl WallOps {
    fn new(grid: &YGrid, k: f64, form: &Form, coef: &Coefficients) -> Option<Self> {
        // everything in the grid's banded order (a permutation of the
        // unknowns: the pencil's eigenvalues do not change)
        let l = grid.helmholtz(k);
        let l_factor = l.cholesky().ok()?;
        let m = grid.to_banded(grid.weights());
        let w = grid.to_banded(&form.w);
        let w_over_m: Vec<f64> = w.iter().zip(&m).map(|(w, m)| w / m).collect();
        let v_psi = l.times(form.energy).plus(&l.sandwich(&w_over_m)).times(form.sign.as_f64());
        let v_factor = v_psi.cholesky().ok()?;
        let (eta, eta2) = coef.centred_noise();
        let (eta, eta2) = (eta.iter().map(|e| grid.to_banded(e)).collect(), grid.to_banded(&eta2));
        let wm = w.iter().zip(&m).map(|(w, m)| w * m).collect();
        Some(WallOps {
            l: l.rows(),
            l_factor,
            v_factor,
            m,
            wm,
            eta,
            eta2,
            sign: form.sign.as_f64(),
            energy: form.energy,
            coef_q: -0.5 * k * k * form.sign.as_f64() * form.energy,
        })
    }

    /// `out = K x = M L^-1 M x`.
    fn k_apply(&self, x: &[f64], out: &mut [f64]) {
        for a in 0..x.len() {
            out[a] = self.m[a] * x[a];
        }
        self.l_factor.solve(out);
        for a in 0..x.len() {
            out[a] *= self.m[a];
        }
    }

    fn v_omega(&self, x: &[f64], out: &mut [f64]) {
        self.k_apply(x, out);
        for a in 0..x.len() {
            out[a] = self.sign * (self.energy * out[a] + self.wm[a] * x[a]);
        }
    }

    fn q_omega(&self, x: &[f64], out: &mut [f64], s: &mut WallScratch) {
        let n = x.len();
        // (sum E^2) K x + K (sum E^2) x
        self.k_apply(x, &mut s.t);
        for a in 0..n {
            s.t2[a] = self.eta2[a] * x[a];
        }
        self.k_apply(&s.t2, out);
        for a in 0..n {
            out[a] += self.eta2[a] * s.t[a];
        }
        // - 2 sum_j E_j K E_j x
        for e in &self.eta {
            for a in 0..n {
                s.t2[a] = e[a] * x[a];
            }
            self.k_apply(&s.t2, &mut s.t3);
            for a in 0..n {
                out[a] -= 2.0 * e[a] * s.t3[a];
            }
        }
        for o in out.iter_mut() {
            *o *= self.coef_q;
        }
    }

    /// The preconditioner `M^-1 L V_psi^-1 L M^-1 b` (exact inverse of `V` in exact arithmetic).
    fn v_inverse_approx(&self, b: &[f64], out: &mut [f64], t: &mut [f64]) {
        for a in 0..b.len() {
            t[a] = b[a] / self.m[a];
        }
        self.l.mul_vec(t, out);
        self.v_factor.solve(out);
        self.l.mul_vec(out, t);
        for a in 0..b.len() {
            out[a] = t[a] / self.m[a];
        }
    }

    fn v_omega_solve(&self, b: &[f64], x: &mut [f64], s: &mut WallScratch) {
        let t = &mut s.t;
        // Non-positive curvature cannot occur once the banded Cholesky of
        // V_psi succeeded, up to rounding; the iterate is used either way and
        // the final Rayleigh quotient does not depend on the solve's accuracy.
        let _ =
            conjugate_gradients(b, x, |p, out| self.v_omega(p, out), |r, z| self.v_inverse_approx(r, z, t), 1e-15, 60);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Boundary;
    use exact::{Matrix as ExactMatrix, Rational};
    use nalgebra::SymmetricEigen;

    fn setup(boundary: Boundary, ny: usize) -> (YGrid, Coefficients) {
        let (a, b) = (0.0, std::f64::consts::PI);
        let g = YGrid::new(boundary, a, b, ny);
        let y = g.nodes();
        let coef = Coefficients {
            // U = y^2/2 + sin(y)/10, U'' = 1 - sin(y)/10 > 0
            u: y.iter().map(|y| 0.5 * y * y + 0.1 * y.sin()).collect(),
            upp: y.iter().map(|y| 1.0 - 0.1 * y.sin()).collect(),
            eta: vec![y.iter().map(|y| 0.4 * (2.0 * y).sin()).collect(), y.iter().map(|y| 0.1 * y).collect()],
        };
        (g, coef)
    }

    /// The real embedding of `-ik X` acting on `(Re w, Im w)`: `[[0, kX], [-kX, 0]]`.
    fn embed_minus_ik(k: f64, x: &DMatrix<f64>) -> DMatrix<f64> {
        let n = x.nrows();
        let mut out = DMatrix::zeros(2 * n, 2 * n);
        out.view_mut((0, n), (n, n)).copy_from(&(x * k));
        out.view_mut((n, 0), (n, n)).copy_from(&(x * -k));
        out
    }

    fn to_exact(m: &DMatrix<f64>) -> ExactMatrix {
        ExactMatrix::from_rows(
            &(0..m.nrows())
                .map(|i| (0..m.ncols()).map(|j| Rational::from_float(m[(i, j)]).unwrap()).collect())
                .collect::<Vec<_>>(),
        )
    }

    #[test]
    fn closed_form_q_equals_the_generator_crates_formula() {
        // The generator crate's Q (exact arithmetic on the float entries) of
        // the real-embedded A, B_j must equal blockdiag(Q, Q) of the closed form.
        for boundary in [Boundary::Walls, Boundary::Periodic] {
            let (g, coef) = setup(boundary, 16);
            let mode = Mode::new(&g, 2.0);
            let form = Form {
                energy: 1.0,
                w: coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + 2.0) / p).collect(),
                sign: Sign::Positive,
            };
            let n = g.n();
            let r = mode.drift_matrix(&coef);
            let a = embed_minus_ik(2.0, &r);
            let noise: Vec<DMatrix<f64>> = coef
                .eta
                .iter()
                .map(|e| embed_minus_ik(2.0, &DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(e))))
                .collect();
            let v = mode.form_matrix(&form);
            let mut v2 = DMatrix::zeros(2 * n, 2 * n);
            v2.view_mut((0, 0), (n, n)).copy_from(&v);
            v2.view_mut((n, n), (n, n)).copy_from(&v);
            let half = Rational::new(1.into(), 2.into());
            let mut a_tilde = to_exact(&a);
            let noise_exact: Vec<ExactMatrix> = noise.iter().map(to_exact).collect();
            for b in &noise_exact {
                a_tilde = a_tilde.add(&b.mul(b).scale(&half));
            }
            let lin = generator::Linearisation { a: to_exact(&a), a_tilde, noise: noise_exact };
            let gf = generator::generator_form(&lin, &to_exact(&v2));
            let q_general = gf.q.to_dmatrix();
            let q = mode.generator_matrix(&form, &coef);
            let mut q2 = DMatrix::zeros(2 * n, 2 * n);
            q2.view_mut((0, 0), (n, n)).copy_from(&q);
            q2.view_mut((n, n), (n, n)).copy_from(&q);
            let scale = q2.norm();
            assert!((&q_general - &q2).norm() < 1e-10 * scale, "{boundary:?}: {}", (&q_general - &q2).norm() / scale);
            // the drift part of the general formula is the discretisation's residual: zero to rounding
            let drift = gf.drift_residual.to_dmatrix();
            assert!(drift.norm() < 1e-12 * v.norm() * 2.0, "{}", drift.norm());
        }
    }

    #[test]
    fn a_wrong_casimir_weight_leaves_a_drift_residual() {
        let (g, coef) = setup(Boundary::Walls, 32);
        let mode = Mode::new(&g, 1.0);
        let right = Form {
            energy: 1.0,
            w: coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + 2.0) / p).collect(),
            sign: Sign::Positive,
        };
        // Two wrong second variations: the energy alone (no Casimir), and a
        // weight that is not Phi''(omega_e) for the equilibrium.
        let energy_only = Form { energy: 1.0, w: vec![0.0; g.n()], sign: Sign::Positive };
        let distorted = Form {
            energy: 1.0,
            w: right.w.iter().zip(g.nodes()).map(|(w, y)| w * (1.0 + 0.3 * (3.0 * y).sin())).collect(),
            sign: Sign::Positive,
        };
        let v = mode.form_matrix(&right).norm();
        let r_right = mode.drift_residual(&right, &coef).norm();
        assert!(r_right < 1e-13 * v, "{r_right} vs {v}");
        for wrong in [energy_only, distorted] {
            let r_wrong = mode.drift_residual(&wrong, &coef).norm();
            assert!(r_wrong > 1e-3 * v, "{r_wrong} vs {v}");
        }
    }

    #[test]
    fn lanczos_matches_dense_generalised_eigenvalues() {
        for boundary in [Boundary::Walls, Boundary::Periodic] {
            let (g, coef) = setup(boundary, 48);
            let mode = Mode::new(&g, 1.5);
            let form = Form {
                energy: 1.0,
                w: coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + 2.0) / p).collect(),
                sign: Sign::Positive,
            };
            let v = mode.form_matrix(&form);
            let q = mode.generator_matrix(&form, &coef);
            let l = nalgebra::Cholesky::new(v.clone()).unwrap().l();
            let linv = l.clone().try_inverse().unwrap();
            let t = &linv * &q * linv.transpose();
            let dense = SymmetricEigen::new((&t + t.transpose()) * 0.5).eigenvalues.max();
            let est = mode.sigma2(&form, &coef, 1e-12).unwrap();
            assert!(
                (est.lambda_max - dense).abs() < 1e-8 * dense.abs().max(1e-12),
                "{boundary:?}: {} vs {dense}",
                est.lambda_max
            );
            let (def, ineq) = mode.verify(&form, &coef, dense * (1.0 + 1e-6) + 1e-12);
            assert!(def && ineq);
            let (_, ineq_low) = mode.verify(&form, &coef, dense * (1.0 - 1e-3));
            assert!(!ineq_low, "a bound below the eigenvalue must not verify");
        }
    }
}
