//! The system with its parameters kept symbolic: every quantity of the
//! pipeline at the equilibrium as a rational function of the box
//! parameters ([`Frac`]), exactly.
//!
//! The coordinates are variables `0..n`, the box parameters `n..n+p`. The
//! Hamiltonian, Casimirs and first integrals are polynomials in the
//! coordinates with rational-function coefficients; the equilibrium and
//! the noise are rational functions of the parameters. The conventions are
//! the exact pipeline's (`generator::linearise`): `ad*_xi` is
//! `algebra.coad_matrix(xi)`, linear in `xi`, so it is formed here as
//! `sum_a xi_a coad_matrix(e_a)`; likewise `Lambda(mu)`.

use crate::frac::{common_denominator, times_denominator, Frac};
use algebra::LieAlgebra;
use casimir::lie_poisson_bracket;
use exact::{Matrix, Monomial, Poly, Rational};
use num_traits::{One, Zero};
use outcome::Sign;

/// A square matrix of rational functions.
pub type FracMatrix = Vec<Vec<Frac>>;

/// The inputs: the algebra and the system's functions, parsed with the
/// box parameters as variables ([`crate::parse_box_expression`]).
#[derive(Clone, Debug)]
pub struct BoxSystem {
    /// The Lie algebra (no parameters).
    pub algebra: LieAlgebra,
    /// The box parameters' names (variables `n..n+p`).
    pub parameters: Vec<String>,
    /// `h`.
    pub hamiltonian: Frac,
    /// The Casimirs.
    pub casimirs: Vec<Frac>,
    /// The first integrals.
    pub first_integrals: Vec<Frac>,
    /// `mu_e` (functions of the parameters).
    pub equilibrium: Vec<Frac>,
    /// The noise fields (functions of the parameters).
    pub noise: Vec<Vec<Frac>>,
    /// The divisors met when parsing, before any cancellation
    /// ([`crate::parse::parse_box_expression_with_divisors`]): each must
    /// keep one sign on a sub-box, like the functions' denominators.
    pub divisors: Vec<Poly>,
}

/// Why a box system is refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum BoxSystemError {
    /// A Casimir fails to commute with a coordinate for some parameters.
    #[error("casimir {index} is not a Casimir for every parameter value: {{C, {coordinate}}} is not identically zero")]
    NotACasimir {
        /// Index in the Casimir list.
        index: usize,
        /// The coordinate.
        coordinate: String,
    },
    /// A first integral is not conserved for some parameters.
    #[error("first integral {index} is not conserved for every parameter value: {{F, h}} is not identically zero")]
    NotConserved {
        /// Index in the first-integral list.
        index: usize,
    },
    /// An equilibrium or noise component depends on the coordinates.
    #[error("{0} must not depend on the coordinates")]
    DependsOnCoordinates(String),
}

/// The symbolic pipeline quantities at `mu_e(theta)`.
#[derive(Clone, Debug)]
pub struct Symbolic {
    n: usize,
    np: usize,
    /// `Dh(mu_e)`.
    pub gradient_h: Vec<Frac>,
    /// `D^2h(mu_e)`.
    pub hessian_h: FracMatrix,
    /// `DK_j(mu_e)` per conserved quantity (Casimirs, then first integrals).
    pub gradients: Vec<Vec<Frac>>,
    /// `D^2K_j(mu_e)`.
    pub hessians: Vec<FracMatrix>,
    /// `ad*_{Dh(mu_e)} mu_e`.
    pub equilibrium_residual: Vec<Frac>,
    /// `ad*_{sigma_i} mu_e`.
    pub noise_residuals: Vec<Vec<Frac>>,
    /// The linearised drift `A`.
    pub a: FracMatrix,
    /// `B_i = ad*_{sigma_i}`.
    pub noise: Vec<FracMatrix>,
    /// The denominators of the inputs (`h`, the conserved quantities,
    /// `mu_e`, the noise): where one vanishes the system is undefined.
    input_denominators: Vec<(Poly, u32)>,
}

fn zero_matrix(nv: usize, n: usize) -> FracMatrix {
    vec![vec![Frac::zero(nv); n]; n]
}

/// `sum_a x_a M_a` for rational matrices `M_a`.
fn combine(x: &[Frac], basis: &[Matrix], nv: usize) -> FracMatrix {
    let n = basis.first().map_or(0, Matrix::nrows);
    let mut out = zero_matrix(nv, n);
    for (xa, m) in x.iter().zip(basis) {
        if xa.is_zero() {
            continue;
        }
        for i in 0..n {
            for j in 0..n {
                let c = &m[(i, j)];
                if !c.is_zero() {
                    out[i][j] = out[i][j].add(&xa.scale(c));
                }
            }
        }
    }
    out
}

/// Matrix product.
pub fn mat_mul(a: &FracMatrix, b: &FracMatrix) -> FracMatrix {
    let (n, k, m) = (a.len(), b.len(), b.first().map_or(0, Vec::len));
    let nv = a.first().and_then(|r| r.first()).map_or(0, Frac::nvars);
    let mut out = vec![vec![Frac::zero(nv); m]; n];
    for i in 0..n {
        for j in 0..m {
            let mut s = Frac::zero(nv);
            for l in 0..k {
                if !a[i][l].is_zero() && !b[l][j].is_zero() {
                    s = s.add(&a[i][l].mul(&b[l][j]));
                }
            }
            out[i][j] = s;
        }
    }
    out
}

fn transpose(a: &FracMatrix) -> FracMatrix {
    let n = a.len();
    let m = a.first().map_or(0, Vec::len);
    (0..m).map(|j| (0..n).map(|i| a[i][j].clone()).collect()).collect()
}

fn mat_add(a: &FracMatrix, b: &FracMatrix) -> FracMatrix {
    a.iter().zip(b).map(|(x, y)| x.iter().zip(y).map(|(p, q)| p.add(q)).collect()).collect()
}

fn mat_scale(a: &FracMatrix, s: &Rational) -> FracMatrix {
    a.iter().map(|r| r.iter().map(|x| x.scale(s)).collect()).collect()
}

/// `(X + X^T) / 2`.
fn symmetric_part(a: &FracMatrix) -> FracMatrix {
    let half = Rational::new(1.into(), 2.into());
    mat_scale(&mat_add(a, &transpose(a)), &half)
}

/// `p` (in `n` variables) in `nv >= n` variables, the new ones last.
pub fn extend(p: &Poly, nv: usize) -> Poly {
    let mut out = Poly::zero(nv);
    for (m, c) in p.terms() {
        let mut e: Monomial = Monomial::from_vec(vec![0; nv]);
        e[..m.len()].copy_from_slice(m);
        out = out.add(&Poly::monomial(c.clone(), e));
    }
    out
}

/// `p` with the parameters (variables `n..`) set to `theta`: a
/// polynomial in the `n` coordinates.
pub fn specialise_poly(p: &Poly, n: usize, theta: &[Rational]) -> Poly {
    let mut out = Poly::zero(n);
    for (m, c) in p.terms() {
        let mut v = c.clone();
        for (i, t) in theta.iter().enumerate() {
            let e = m[n + i] as u32;
            if e > 0 {
                v *= t.pow(e);
            }
        }
        out = out.add(&Poly::monomial(v, Monomial::from_slice(&m[..n])));
    }
    out
}

/// `f` at parameters `theta`: a polynomial in the coordinates; `None`
/// where its denominator vanishes.
pub fn specialise(f: &Frac, n: usize, theta: &[Rational]) -> Option<Poly> {
    let mut x = vec![Rational::zero(); n];
    x.extend_from_slice(theta);
    let d = f.den_poly().eval(&x);
    if d.is_zero() {
        return None;
    }
    Some(specialise_poly(f.num(), n, theta).scale(&d.recip()))
}

/// The value of a parameter-only function at `theta`.
pub fn value_at(f: &Frac, n: usize, theta: &[Rational]) -> Option<Rational> {
    let mut x = vec![Rational::zero(); n];
    x.extend_from_slice(theta);
    f.eval(&x)
}

/// Evaluates polynomials at `mu = mu_e(theta)` with `mu_e = e / L`
/// (common denominator `L`).
struct AtEquilibrium {
    n: usize,
    numerators: Vec<Poly>,
    lcm: Vec<(Poly, u32)>,
    lcm_poly: Poly,
}

impl AtEquilibrium {
    fn new(mu: &[Frac]) -> Self {
        let n = mu.len();
        let lcm = common_denominator(mu);
        let numerators: Vec<Poly> = mu.iter().map(|m| times_denominator(m, &lcm)).collect();
        let nv = mu.first().map_or(n, Frac::nvars);
        let lcm_poly = lcm.iter().fold(Poly::constant(nv, Rational::one()), |acc, (f, e)| acc.mul(&f.pow(*e)));
        AtEquilibrium { n, numerators, lcm, lcm_poly }
    }

    /// `f(mu_e(theta), theta) / den`, with `den` the denominator `f` had.
    fn eval(&self, f: &Poly, den: &[(Poly, u32)]) -> Frac {
        let n = self.n;
        let nv = f.nvars();
        let degree = |m: &Monomial| m[..n].iter().map(|&e| e as u32).sum::<u32>();
        let top = f.terms().map(|(m, _)| degree(m)).max().unwrap_or(0);
        let mut num = Poly::zero(nv);
        for (m, c) in f.terms() {
            let mut rest: Monomial = m.clone();
            for e in rest[..n].iter_mut() {
                *e = 0;
            }
            let mut t = Poly::monomial(c.clone(), rest);
            for j in 0..n {
                if m[j] > 0 {
                    t = t.mul(&self.numerators[j].pow(m[j] as u32));
                }
            }
            let missing = top - degree(m);
            if missing > 0 {
                t = t.mul(&self.lcm_poly.pow(missing));
            }
            num = num.add(&t);
        }
        let mut full: Vec<(Poly, u32)> = self.lcm.iter().map(|(p, e)| (p.clone(), e * top)).collect();
        for (p, e) in den {
            match full.iter_mut().find(|(q, _)| q == p) {
                Some((_, x)) => *x += e,
                None => full.push((p.clone(), *e)),
            }
        }
        // Re-form through Frac so that zero and variable factors reduce.
        let one = Frac::constant(nv, Rational::one());
        let den_frac = full.iter().fold(one.clone(), |acc, (p, e)| acc.mul(&Frac::from_poly(p.pow(*e))));
        Frac::from_poly(num).div(&den_frac).expect("a product of nonzero factors")
    }
}

impl BoxSystem {
    /// Number of coordinates.
    pub fn dim(&self) -> usize {
        self.algebra.dim()
    }

    /// Check the brackets for every parameter value and form the symbolic
    /// quantities at the equilibrium.
    pub fn symbolic(&self) -> Result<Symbolic, BoxSystemError> {
        let n = self.dim();
        let np = self.parameters.len();
        let nv = n + np;
        let coordinate_free = |f: &Frac, what: String| {
            if crate::parse::has_coordinates(f.num(), n) {
                Err(BoxSystemError::DependsOnCoordinates(what))
            } else {
                Ok(())
            }
        };
        for (j, f) in self.equilibrium.iter().enumerate() {
            coordinate_free(f, format!("equilibrium component {j}"))?;
        }
        for (i, s) in self.noise.iter().enumerate() {
            for (j, f) in s.iter().enumerate() {
                coordinate_free(f, format!("noise field {i} component {j}"))?;
            }
        }
        for (index, c) in self.casimirs.iter().enumerate() {
            for a in 0..n {
                if !lie_poisson_bracket(&self.algebra, c.num(), &Poly::var(nv, a)).is_zero() {
                    return Err(BoxSystemError::NotACasimir {
                        index,
                        coordinate: self.algebra.coordinates()[a].clone(),
                    });
                }
            }
        }
        for (index, f) in self.first_integrals.iter().enumerate() {
            if !lie_poisson_bracket(&self.algebra, f.num(), self.hamiltonian.num()).is_zero() {
                return Err(BoxSystemError::NotConserved { index });
            }
        }
        let at = AtEquilibrium::new(&self.equilibrium);
        let gradient = |f: &Frac| -> Vec<Frac> { (0..n).map(|a| at.eval(&f.num().derivative(a), f.den())).collect() };
        let hessian = |f: &Frac| -> FracMatrix {
            (0..n)
                .map(|a| {
                    let da = f.num().derivative(a);
                    (0..n).map(|b| at.eval(&da.derivative(b), f.den())).collect()
                })
                .collect()
        };
        let gradient_h = gradient(&self.hamiltonian);
        let hessian_h = hessian(&self.hamiltonian);
        let conserved: Vec<&Frac> = self.casimirs.iter().chain(&self.first_integrals).collect();
        let gradients = conserved.iter().map(|f| gradient(f)).collect();
        let hessians = conserved.iter().map(|f| hessian(f)).collect();
        let unit = |a: usize| -> Vec<Rational> {
            (0..n).map(|i| if i == a { Rational::one() } else { Rational::zero() }).collect()
        };
        let coad_basis: Vec<Matrix> = (0..n).map(|a| self.algebra.coad_matrix(&unit(a))).collect();
        let tensor_basis: Vec<Matrix> = (0..n).map(|k| self.algebra.poisson_tensor(&unit(k))).collect();
        let apply = |m: &FracMatrix, v: &[Frac]| -> Vec<Frac> {
            m.iter().map(|row| row.iter().zip(v).fold(Frac::zero(nv), |acc, (x, y)| acc.add(&x.mul(y)))).collect()
        };
        let coad_h = combine(&gradient_h, &coad_basis, nv);
        let equilibrium_residual = apply(&coad_h, &self.equilibrium);
        let noise: Vec<FracMatrix> = self.noise.iter().map(|s| combine(s, &coad_basis, nv)).collect();
        let noise_residuals = noise.iter().map(|b| apply(b, &self.equilibrium)).collect();
        let lambda = combine(&self.equilibrium, &tensor_basis, nv);
        let a = mat_add(&mat_mul(&transpose(&lambda), &hessian_h), &coad_h);
        let inputs = std::iter::once(&self.hamiltonian)
            .chain(&self.casimirs)
            .chain(&self.first_integrals)
            .chain(&self.equilibrium)
            .chain(self.noise.iter().flatten());
        let mut input_denominators = common_denominator(inputs);
        for d in &self.divisors {
            if d.constant_value().is_none() && !input_denominators.iter().any(|(f, _)| f == d) {
                input_denominators.push((d.clone(), 1));
            }
        }
        Ok(Symbolic {
            n,
            np,
            gradient_h,
            hessian_h,
            gradients,
            hessians,
            equilibrium_residual,
            noise_residuals,
            a,
            noise,
            input_denominators,
        })
    }
}

/// A choice of the energy–Casimir functional for a sub-box, fixed at its
/// centre: the sign, the multipliers of the free conserved quantities
/// (`free`, kept at `multipliers[j]`), the rows of `G` that determine the
/// others, and the Hessian `M` of the Casimir function (`r x r`).
#[derive(Clone, Debug, PartialEq)]
pub struct BoxChoice {
    /// Whether `P` is positive or negative definite.
    pub sign: Sign,
    /// The multipliers at the centre.
    pub multipliers: Vec<Rational>,
    /// The conserved quantities whose multipliers stay fixed.
    pub free: Vec<usize>,
    /// The rows of `G` solved for the other multipliers.
    pub pivot_rows: Vec<usize>,
    /// `M`.
    pub m: Matrix,
}

/// `sign P` and `sign Q` as rational functions, with the multipliers.
#[derive(Clone, Debug)]
pub struct Forms {
    /// The multipliers `lambda(theta)`.
    pub multipliers: Vec<Frac>,
    /// `V = sign P`.
    pub v: FracMatrix,
    /// `sign Q`, `Q = P A~ + A~^T P + sum_i B_i^T P B_i`.
    pub q: FracMatrix,
    /// Whether `Q` is identically zero.
    pub q_zero: bool,
}

/// Why a choice does not give a functional critical for every parameter.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FormError {
    /// The solved multipliers leave `G lambda + Dh` nonzero somewhere.
    #[error("no multipliers of this form make mu_e critical for every parameter value in the box")]
    NotCritical,
    /// The chosen rows are singular for every parameter value.
    #[error("the multipliers' system is singular")]
    Singular,
    /// The choice does not match the system's sizes.
    #[error("the choice has the wrong sizes")]
    Shape,
}

impl Symbolic {
    /// Number of coordinates.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of box parameters.
    pub fn parameters(&self) -> usize {
        self.np
    }

    /// The inputs' denominator factors.
    pub fn input_denominators(&self) -> &[(Poly, u32)] {
        &self.input_denominators
    }

    /// Whether `mu_e` is an equilibrium for every parameter value.
    pub fn equilibrium_holds(&self) -> bool {
        self.equilibrium_residual.iter().all(Frac::is_zero)
    }

    /// The noise fields with a residual not identically zero.
    pub fn incompatible_noise(&self) -> Vec<usize> {
        (0..self.noise_residuals.len()).filter(|&i| self.noise_residuals[i].iter().any(|x| !x.is_zero())).collect()
    }

    /// The forms of a choice (see [`BoxChoice`]).
    pub fn forms(&self, choice: &BoxChoice) -> Result<Forms, FormError> {
        let n = self.n;
        let nv = n + self.np;
        let r = self.gradients.len();
        if choice.multipliers.len() != r
            || choice.m.nrows() != r
            || choice.m.ncols() != r
            || choice.free.iter().any(|&j| j >= r)
            || choice.pivot_rows.iter().any(|&i| i >= n)
        {
            return Err(FormError::Shape);
        }
        let solved: Vec<usize> = (0..r).filter(|j| !choice.free.contains(j)).collect();
        if solved.len() != choice.pivot_rows.len() {
            return Err(FormError::Shape);
        }
        let mut lambda: Vec<Frac> = (0..r).map(|_| Frac::zero(nv)).collect();
        for &j in &choice.free {
            lambda[j] = Frac::constant(nv, choice.multipliers[j].clone());
        }
        // The square system G[rows, solved] x = -Dh[rows] - G[rows, free] lambda_free.
        let k = solved.len();
        let mut aug: Vec<Vec<Frac>> = choice
            .pivot_rows
            .iter()
            .map(|&i| {
                let mut row: Vec<Frac> = solved.iter().map(|&j| self.gradients[j][i].clone()).collect();
                let mut rhs = self.gradient_h[i].neg();
                for &j in &choice.free {
                    rhs = rhs.sub(&self.gradients[j][i].mul(&lambda[j]));
                }
                row.push(rhs);
                row
            })
            .collect();
        // Gaussian elimination over the rational functions; every pivot's
        // factors end up in the multipliers' denominators, whose signs the
        // proof checks on each box.
        for c in 0..k {
            let p = (c..k).find(|&i| !aug[i][c].is_zero()).ok_or(FormError::Singular)?;
            aug.swap(c, p);
            let pivot = aug[c][c].clone();
            for i in 0..k {
                if i == c || aug[i][c].is_zero() {
                    continue;
                }
                let f = aug[i][c].div(&pivot).ok_or(FormError::Singular)?;
                for j in c..=k {
                    let t = aug[c][j].mul(&f);
                    aug[i][j] = aug[i][j].sub(&t);
                }
            }
        }
        for (c, &j) in solved.iter().enumerate() {
            lambda[j] = aug[c][k].div(&aug[c][c]).ok_or(FormError::Singular)?;
        }
        // Critical for every parameter: G lambda + Dh = 0 identically.
        for i in 0..n {
            let mut s = self.gradient_h[i].clone();
            for j in 0..r {
                s = s.add(&self.gradients[j][i].mul(&lambda[j]));
            }
            if !s.is_zero() {
                return Err(FormError::NotCritical);
            }
        }
        // P = D^2h + sum lambda_j D^2K_j + G M G^T.
        let mut p = self.hessian_h.clone();
        for (l, h) in lambda.iter().zip(&self.hessians) {
            if !l.is_zero() {
                p = mat_add(&p, &h.iter().map(|row| row.iter().map(|x| x.mul(l)).collect()).collect());
            }
        }
        if r > 0 {
            let g: FracMatrix = (0..n).map(|i| (0..r).map(|j| self.gradients[j][i].clone()).collect()).collect();
            let m: FracMatrix =
                (0..r).map(|i| (0..r).map(|j| Frac::constant(nv, choice.m[(i, j)].clone())).collect()).collect();
            p = mat_add(&p, &mat_mul(&mat_mul(&g, &m), &transpose(&g)));
        }
        let sign = Rational::from(choice.sign as i64);
        let v = mat_scale(&p, &sign);
        // Q = 2 sym(V A~) + sum B^T V B, A~ = A + 1/2 sum B^2, as
        // generator::generator_form: 2 sym(V A) + sum (B^T V B + sym(V B^2)).
        let two = Rational::from(2);
        let mut q = mat_scale(&symmetric_part(&mat_mul(&v, &self.a)), &two);
        for b in &self.noise {
            let vb = mat_mul(&v, b);
            q = mat_add(&q, &mat_mul(&transpose(b), &vb));
            q = mat_add(&q, &symmetric_part(&mat_mul(&vb, b)));
        }
        let q_zero = q.iter().flatten().all(Frac::is_zero);
        Ok(Forms { multipliers: lambda, v, q, q_zero })
    }
}

impl Symbolic {
    /// The characteristic polynomial `det(x I - A) = sum_i c_i x^i` of the
    /// linearised drift, its coefficients as rational functions of the
    /// parameters (Faddeev–LeVerrier: `M_k = A M_{k-1} + c_{n-k+1} I`,
    /// `c_{n-k} = -tr(A M_k) / k`, exact over the rationals).
    pub fn characteristic_polynomial(&self) -> Vec<Frac> {
        let n = self.n;
        let nv = n + self.np;
        let mut c = vec![Frac::zero(nv); n + 1];
        c[n] = Frac::constant(nv, Rational::one());
        let mut m = zero_matrix(nv, n);
        for k in 1..=n {
            let mut next = mat_mul(&self.a, &m);
            for (i, row) in next.iter_mut().enumerate() {
                row[i] = row[i].add(&c[n - k + 1]);
            }
            m = next;
            let am = mat_mul(&self.a, &m);
            let trace = (0..n).fold(Frac::zero(nv), |acc, i| acc.add(&am[i][i]));
            c[n - k] = trace.scale(&Rational::new((-1).into(), (k as i64).into()));
        }
        c
    }
}

/// `V` and `Q` (and any other functions) at parameters `theta`, exactly;
/// `None` where a denominator vanishes.
pub fn matrix_at(m: &FracMatrix, n: usize, theta: &[Rational]) -> Option<Matrix> {
    let rows: Option<Vec<Vec<Rational>>> =
        m.iter().map(|r| r.iter().map(|x| value_at(x, n, theta)).collect()).collect();
    rows.map(|r| Matrix::from_rows(&r))
}
