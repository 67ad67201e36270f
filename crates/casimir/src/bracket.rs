//! The Lie–Poisson bracket of polynomials.

use algebra::LieAlgebra;
use exact::Poly;

/// `{F, G}(mu) = <mu, [DF(mu), DG(mu)]> = sum_{a,b,k} c^k_ab mu_k ∂_a F ∂_b G`,
/// exactly.
///
/// With this sign, the stochastic Lie–Poisson flow
/// `d mu = ad*_{Dh} mu dt + ...` moves a function `F` by `dF = {h, F} dt + ...`.
///
/// ```
/// use algebra::builtin;
/// use casimir::lie_poisson_bracket;
/// use exact::{parse_expression, Symbols};
/// let so3 = builtin("so3").unwrap().algebra;
/// let s = Symbols::new(so3.coordinates());
/// let p1 = parse_expression("Pi1", &s).unwrap();
/// let p2 = parse_expression("Pi2", &s).unwrap();
/// // {Pi1, Pi2} = <mu, [e1, e2]> = Pi3
/// assert_eq!(lie_poisson_bracket(&so3, &p1, &p2), parse_expression("Pi3", &s).unwrap());
/// ```
///
/// The polynomials may have further variables after the coordinates (the
/// parameters of a box certificate): they are constants here, and the
/// bracket is in the same variables.
pub fn lie_poisson_bracket(algebra: &LieAlgebra, f: &Poly, g: &Poly) -> Poly {
    let n = algebra.dim();
    let nv = f.nvars();
    assert!(
        nv >= n && g.nvars() == nv,
        "polynomials must be in the algebra's coordinates (and the same further variables)"
    );
    let df: Vec<Poly> = (0..n).map(|a| f.derivative(a)).collect();
    let dg: Vec<Poly> = (0..n).map(|b| g.derivative(b)).collect();
    let mut out = Poly::zero(nv);
    for a in 0..n {
        if df[a].is_zero() {
            continue;
        }
        for b in 0..n {
            if dg[b].is_zero() {
                continue;
            }
            if let Some(lambda_ab) = poisson_tensor_entry(algebra, a, b, nv) {
                out = out.add(&df[a].mul(&dg[b]).mul(&lambda_ab));
            }
        }
    }
    out
}

/// The linear polynomial `Lambda_ab(mu) = c^k_ab mu_k`, or `None` when
/// `[e_a, e_b] = 0`, in `nv >= n` variables.
pub(crate) fn poisson_tensor_entry(algebra: &LieAlgebra, a: usize, b: usize, nv: usize) -> Option<Poly> {
    let bracket = algebra.bracket_of_basis(a, b);
    if bracket.is_empty() {
        return None;
    }
    let mut coefficients = vec![exact::Rational::from(0); nv];
    for (k, c) in bracket {
        coefficients[*k] = c.clone();
    }
    Some(Poly::linear(&coefficients))
}
