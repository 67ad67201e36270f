//! Linearisation of the stochastic Lie–Poisson equation at `mu_e`.

use casimir::System;
use exact::{Matrix, Rational};

/// The linear Stratonovich SDE `dx = A x dt + sum_i B_i x o dW^i` satisfied by
/// a small perturbation `x = mu - mu_e`, and its Itô drift.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Linearisation {
    /// `A = Lambda(mu_e)^T D^2h(mu_e) + ad*_{Dh(mu_e)}`: the Jacobian of
    /// `mu -> ad*_{Dh(mu)} mu` at `mu_e`.
    pub a: Matrix,
    /// `B_i = ad*_{sigma_i}` as matrices.
    pub noise: Vec<Matrix>,
    /// The Itô drift `A~ = A + 1/2 sum_i B_i^2`.
    pub a_tilde: Matrix,
}

/// Linearise the system at its equilibrium, exactly.
///
/// The drift is `f(mu)_b = c^k_ab ∂_a h(mu) mu_k`, so
/// `∂f_b/∂mu_j = c^k_ab H_aj mu_k + c^j_ab ∂_a h`, i.e.
/// `A = Lambda(mu_e)^T H + ad*_{Dh(mu_e)}` with `H = D^2h(mu_e)`.
///
/// ```
/// use algebra::builtin;
/// use casimir::System;
/// use exact::{parse_expression, Rational, Symbols};
/// use generator::linearise;
/// let so3 = builtin("so3").unwrap().algebra;
/// let s = Symbols::new(so3.coordinates());
/// let h = parse_expression("Pi1^2/2 + Pi2^2/4 + Pi3^2/6", &s).unwrap();
/// let q = |n: i64| Rational::from_integer(n.into());
/// let system = System::new(so3, h, vec![], vec![], vec![q(1), q(0), q(0)], vec![vec![q(1), q(0), q(0)]]).unwrap();
/// let lin = linearise(&system);
/// // B = ad*_{e1}: x -> x × e1 = (0, x3, -x2)
/// assert_eq!(lin.noise[0][(1, 2)], q(1));
/// assert_eq!(lin.noise[0][(2, 1)], q(-1));
/// // Ito correction 1/2 B^2 = -1/2 on the (2,3) block
/// assert_eq!(&lin.a_tilde[(1, 1)] - &lin.a[(1, 1)], Rational::new((-1).into(), 2.into()));
/// ```
pub fn linearise(system: &System) -> Linearisation {
    let algebra = system.algebra();
    let lambda = algebra.poisson_tensor(system.equilibrium());
    let a =
        lambda.transpose().mul(system.hamiltonian_hessian()).add(&algebra.coad_matrix(system.hamiltonian_gradient()));
    let noise: Vec<Matrix> = system.noise().iter().map(|s| algebra.coad_matrix(s)).collect();
    let half = Rational::new_small(1, 2);
    let mut a_tilde = a.clone();
    for b in &noise {
        a_tilde.add_scaled_assign(&half, &b.mul(b));
    }
    Linearisation { a, noise, a_tilde }
}
