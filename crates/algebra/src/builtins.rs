//! Builtin Lie algebras with their coordinate names and polynomial Casimirs.

use crate::lie::LieAlgebra;
use exact::{Matrix, Rational};

/// A builtin algebra together with a generating set of its polynomial
/// Casimirs, written in the algebra's coordinates (the engine re-checks them
/// exactly before use).
#[derive(Clone, Debug)]
pub struct Builtin {
    /// The algebra.
    pub algebra: LieAlgebra,
    /// Casimirs as expressions in the coordinates.
    pub casimirs: Vec<&'static str>,
    /// One line saying what it is.
    pub description: &'static str,
}

/// Names accepted by [`builtin`].
pub fn builtin_names() -> &'static [&'static str] {
    &["so3", "se3", "sl2", "se2", "heisenberg"]
}

fn q(n: i64) -> Rational {
    Rational::from_integer(n.into())
}

/// `eps_abk` rows for a 3-dimensional block starting at `offset`.
fn cross_rows(offset: usize) -> Vec<(usize, usize, usize, Rational)> {
    vec![
        (offset, offset + 1, offset + 2, q(1)),
        (offset + 1, offset + 2, offset, q(1)),
        (offset + 2, offset, offset + 1, q(1)),
    ]
}

/// The matrices of `v -> e_a x v` on `R^3`: `(rho_a)_{ji} = eps_{a i j}`.
fn cross_product_representation() -> Vec<Matrix> {
    (0..3)
        .map(|a| {
            Matrix::from_fn(3, 3, |j, i| {
                // eps_{a i j}
                let perm = [a, i, j];
                if perm[0] == perm[1] || perm[1] == perm[2] || perm[0] == perm[2] {
                    q(0)
                } else if [(0, 1, 2), (1, 2, 0), (2, 0, 1)].contains(&(a, i, j)) {
                    q(1)
                } else {
                    q(-1)
                }
            })
        })
        .collect()
}

/// A builtin algebra by name, or `None`.
///
/// * `so3`: coordinates `Pi1 Pi2 Pi3`, `[e_a, e_b] = eps_abk e_k`; Casimir `|Pi|^2/2`.
/// * `se3`: `so3 ⋉ R^3`, coordinates `Pi1 Pi2 Pi3 Gamma1 Gamma2 Gamma3`,
///   `[(xi,u),(eta,v)] = (xi x eta, xi x v - eta x u)`; Casimirs `|Gamma|^2/2`, `Pi.Gamma`.
/// * `sl2`: basis `H, E, F` with `[H,E] = 2E`, `[H,F] = -2F`, `[E,F] = H`
///   (non-compact), coordinates `muH muE muF`; Casimir `muH^2 + 4 muE muF`.
/// * `se2`: `so2 ⋉ R^2`, basis `J, P1, P2` with `[J,P1] = P2`, `[J,P2] = -P1`,
///   coordinates `M P1 P2`; Casimir `P1^2 + P2^2`.
/// * `heisenberg`: basis `X, Y, Z` with `[X,Y] = Z`, coordinates `muX muY muZ`;
///   Casimir `muZ`.
///
/// ```
/// let se3 = algebra::builtin("se3").unwrap();
/// assert_eq!(se3.algebra.dim(), 6);
/// assert_eq!(se3.casimirs.len(), 2);
/// assert!(algebra::builtin("so4").is_none());
/// ```
pub fn builtin(name: &str) -> Option<Builtin> {
    // Built (and Jacobi-checked) once per process; clones are cheap.
    static CACHE: std::sync::OnceLock<Vec<(&'static str, Builtin)>> = std::sync::OnceLock::new();
    let cache = CACHE.get_or_init(|| builtin_names().iter().filter_map(|n| Some((*n, build(n)?))).collect());
    cache.iter().find(|(n, _)| *n == name).map(|(_, b)| b.clone())
}

fn build(name: &str) -> Option<Builtin> {
    let b = match name {
        "so3" => Builtin {
            algebra: LieAlgebra::from_structure_constants("so3", &["Pi1", "Pi2", "Pi3"], &cross_rows(0)).ok()?,
            casimirs: vec!["(Pi1^2 + Pi2^2 + Pi3^2)/2"],
            description: "rotations: the free rigid body, [e_a, e_b] = eps_abk e_k",
        },
        "se3" => {
            let so3 = LieAlgebra::from_structure_constants("so3", &["Pi1", "Pi2", "Pi3"], &cross_rows(0)).ok()?;
            Builtin {
                algebra: so3
                    .semidirect("se3", &cross_product_representation(), &["Gamma1", "Gamma2", "Gamma3"])
                    .ok()?,
                casimirs: vec!["(Gamma1^2 + Gamma2^2 + Gamma3^2)/2", "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"],
                description: "so3 ⋉ R^3: the heavy top, (Pi, Gamma)",
            }
        }
        "sl2" => Builtin {
            algebra: LieAlgebra::from_structure_constants(
                "sl2",
                &["muH", "muE", "muF"],
                &[(0, 1, 1, q(2)), (0, 2, 2, q(-2)), (1, 2, 0, q(1))],
            )
            .ok()?,
            casimirs: vec!["muH^2 + 4*muE*muF"],
            description: "sl(2,R), non-compact: [H,E] = 2E, [H,F] = -2F, [E,F] = H",
        },
        "se2" => Builtin {
            algebra: LieAlgebra::from_structure_constants(
                "se2",
                &["M", "P1", "P2"],
                &[(0, 1, 2, q(1)), (0, 2, 1, q(-1))],
            )
            .ok()?,
            casimirs: vec!["P1^2 + P2^2"],
            description: "so2 ⋉ R^2: [J,P1] = P2, [J,P2] = -P1",
        },
        "heisenberg" => Builtin {
            algebra: LieAlgebra::from_structure_constants("heisenberg", &["muX", "muY", "muZ"], &[(0, 1, 2, q(1))])
                .ok()?,
            casimirs: vec!["muZ"],
            description: "Heisenberg algebra: [X,Y] = Z",
        },
        _ => return None,
    };
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn se3_matches_the_design_convention() {
        // docs/architecture.md §1: ad*_(xi,u)(Pi,Gamma) = (Pi x xi + Gamma x u, Gamma x xi).
        let se3 = builtin("se3").unwrap().algebra;
        let xi_u = [q(1), q(2), q(3), q(-1), q(4), q(2)];
        let mu = [q(2), q(-1), q(5), q(3), q(1), q(-2)];
        let cross = |a: &[Rational], b: &[Rational]| {
            vec![&a[1] * &b[2] - &a[2] * &b[1], &a[2] * &b[0] - &a[0] * &b[2], &a[0] * &b[1] - &a[1] * &b[0]]
        };
        let (xi, u) = xi_u.split_at(3);
        let (pi, gamma) = mu.split_at(3);
        let top: Vec<Rational> = cross(pi, xi).iter().zip(cross(gamma, u)).map(|(a, b)| a + b).collect();
        let bottom = cross(gamma, xi);
        let expected: Vec<Rational> = top.into_iter().chain(bottom).collect();
        assert_eq!(se3.coad(&xi_u, &mu), expected);
    }

    #[test]
    fn every_builtin_builds() {
        for name in builtin_names() {
            assert!(builtin(name).is_some(), "{name}");
        }
    }
}
