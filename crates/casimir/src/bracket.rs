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
pub fn lie_poisson_bracket(algebra: &LieAlgebra, f: &Poly, g: &Poly) -> Poly {
    let n = algebra.dim();
    assert!(f.nvars() == n && g.nvars() == n, "polynomials must be in the algebra's coordinates");
    let df = f.gradient();
    let dg = g.gradient();
    let mut out = Poly::zero(n);
    for a in 0..n {
        if df[a].is_zero() {
            continue;
        }
        for b in 0..n {
            if dg[b].is_zero() {
                continue;
            }
            let bracket = algebra.bracket_of_basis(a, b);
            if bracket.is_empty() {
                continue;
            }
            let coefficients: Vec<_> = (0..n)
                .map(|k| {
                    bracket.iter().find(|(kk, _)| *kk == k).map_or_else(num_traits::Zero::zero, |(_, c)| c.clone())
                })
                .collect();
            let lambda_ab = Poly::linear(&coefficients);
            out = out.add(&df[a].mul(&dg[b]).mul(&lambda_ab));
        }
    }
    out
}
