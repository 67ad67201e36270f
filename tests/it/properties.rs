//! Structural identities, checked exactly over random inputs: antisymmetry and
//! Jacobi of every builtin and of random semidirect products and direct sums,
//! the ad/ad* duality, Casimirs Poisson-commuting, Casimir discovery, and
//! analytic derivatives against finite differences.

use crate::common;

use algebra::{builtin, builtin_names, LieAlgebra};
use casimir::{discover_casimirs, lie_poisson_bracket};
use common::*;
use exact::{parse_expression, Matrix, Poly, Rational, Symbols};
use num_traits::Zero;
use proptest::prelude::*;

fn small_rational() -> impl Strategy<Value = Rational> {
    (-20i64..=20, 1i64..=6).prop_map(|(n, d)| q(n, d))
}

fn vector(n: usize) -> impl Strategy<Value = Vec<Rational>> {
    proptest::collection::vec(small_rational(), n)
}

fn dot(a: &[Rational], b: &[Rational]) -> Rational {
    a.iter().zip(b).fold(Rational::zero(), |s, (x, y)| s + x * y)
}

/// The adjoint representation ad_{e_a} as matrices.
fn adjoint_rep(g: &LieAlgebra) -> Vec<Matrix> {
    (0..g.dim())
        .map(|a| {
            let mut e = vec![Rational::zero(); g.dim()];
            e[a] = q(1, 1);
            g.ad_matrix(&e)
        })
        .collect()
}

/// The coadjoint representation -ad_{e_a}^T.
fn coadjoint_rep(g: &LieAlgebra) -> Vec<Matrix> {
    adjoint_rep(g).iter().map(|m| m.transpose().scale(&q(-1, 1))).collect()
}

/// Builtins, plus constructions: g ⋉_ad g, g ⋉_ad* g*, direct sums, rescalings.
fn algebra_zoo() -> Vec<LieAlgebra> {
    let mut zoo: Vec<LieAlgebra> = builtin_names().iter().map(|n| builtin(n).unwrap().algebra).collect();
    for name in ["so3", "sl2", "heisenberg"] {
        let g = builtin(name).unwrap().algebra;
        let v: Vec<String> = (0..g.dim()).map(|i| format!("v{i}")).collect();
        zoo.push(g.semidirect(&format!("{name}-ad"), &adjoint_rep(&g), &v).unwrap());
        zoo.push(g.semidirect(&format!("{name}-coad"), &coadjoint_rep(&g), &v).unwrap());
    }
    let so3 = builtin("so3").unwrap().algebra;
    let sl2 = builtin("sl2").unwrap().algebra;
    zoo.push(so3.direct_sum(&sl2, "so3+sl2").unwrap());
    zoo.push(sl2.rescaled(&[q(2, 1), q(-3, 1), q(1, 5)]));
    zoo
}

#[test]
fn every_algebra_in_the_zoo_is_antisymmetric_and_satisfies_jacobi() {
    for g in algebra_zoo() {
        let n = g.dim();
        for a in 0..n {
            for b in 0..n {
                for k in 0..n {
                    assert_eq!(g.structure_constant(a, b, k), -g.structure_constant(b, a, k), "{}", g.name());
                }
            }
        }
        // Rebuilding from the table re-runs the exact Jacobi check.
        let rebuilt = LieAlgebra::from_structure_constants(g.name(), g.coordinates(), &g.structure_constant_rows());
        assert!(rebuilt.is_ok(), "{}: {:?}", g.name(), rebuilt.err());
    }
}

#[test]
fn a_perturbed_table_fails_jacobi() {
    // Perturb one structure constant of se3: Jacobi must fail (paired negative case).
    let se3 = builtin("se3").unwrap().algebra;
    let mut rows = se3.structure_constant_rows();
    rows[0].3 = &rows[0].3 + q(1, 2);
    let err = LieAlgebra::from_structure_constants("bad", se3.coordinates(), &rows).unwrap_err();
    assert!(matches!(err, algebra::AlgebraError::Jacobi { .. }), "{err}");
}

#[test]
fn a_wrong_representation_is_rejected() {
    let so3 = builtin("so3").unwrap().algebra;
    let mut rho = adjoint_rep(&so3);
    rho[0] = rho[0].scale(&q(2, 1));
    assert!(so3.semidirect("bad", &rho, &["a", "b", "c"]).is_err());
}

proptest! {
    #![proptest_config(proptest_config(64, 2048, module_path!()))]

    /// <ad*_xi mu, eta> = <mu, ad_xi eta> on every algebra of the zoo.
    #[test]
    fn coadjoint_is_dual_to_adjoint(seed in 0usize..1000, xs in vector(64), ms in vector(64), es in vector(64)) {
        let zoo = algebra_zoo();
        let g = &zoo[seed % zoo.len()];
        let n = g.dim();
        let (xi, mu, eta) = (&xs[..n], &ms[..n], &es[..n]);
        let lhs = dot(&g.coad(xi, mu), eta);
        let rhs = dot(mu, &g.bracket(xi, eta));
        prop_assert_eq!(lhs, rhs);
        // and ad_xi eta = [xi, eta]
        prop_assert_eq!(g.ad_matrix(xi).mul_vec(eta), g.bracket(xi, eta));
    }

    /// Builtin Casimirs Poisson-commute with every polynomial (checked on
    /// random quadratics), and the bracket is antisymmetric.
    #[test]
    fn builtin_casimirs_commute(seed in 0usize..100, coefficients in vector(64)) {
        let name = builtin_names()[seed % builtin_names().len()];
        let b = builtin(name).unwrap();
        let g = &b.algebra;
        let n = g.dim();
        let s = Symbols::new(g.coordinates());
        // A random quadratic F = sum c_ij x_i x_j.
        let mut f = Poly::zero(n);
        for i in 0..n {
            for j in i..n {
                let c = coefficients[(i * n + j) % coefficients.len()].clone();
                f = f.add(&Poly::var(n, i).mul(&Poly::var(n, j)).scale(&c));
            }
        }
        for c in &b.casimirs {
            let c = parse_expression(c, &s).unwrap();
            prop_assert!(lie_poisson_bracket(g, &c, &f).is_zero());
        }
        let x = Poly::var(n, seed % n);
        prop_assert_eq!(lie_poisson_bracket(g, &f, &x), lie_poisson_bracket(g, &x, &f).neg());
    }

    /// Exact Hessians agree with central finite differences of the value.
    #[test]
    fn hessians_match_finite_differences(cs in proptest::collection::vec(-9i64..=9, 10), point in proptest::collection::vec(-2.0f64..2.0, 3)) {
        let s = Symbols::new(&["x", "y", "z"]);
        let text = format!(
            "{}*x^3 + {}*x*y*z + {}*y^2*z + {}*z^4/3 + {}*x^2 + {}*y*z + {}*x + {}*(x - y)^3 + {}*x*z^2 + {}",
            cs[0], cs[1], cs[2], cs[3], cs[4], cs[5], cs[6], cs[7], cs[8], cs[9]
        );
        let p = parse_expression(&text, &s).unwrap();
        let hess = p.hessian();
        let grad = p.gradient();
        // The direct evaluations agree exactly with the symbolic derivatives.
        let xq: Vec<Rational> = point.iter().map(|&x| exact::rational_from_f64(x).unwrap()).collect();
        let hq = p.hessian_at(&xq);
        let gq = p.gradient_at(&xq);
        for i in 0..3 {
            prop_assert_eq!(&gq[i], &grad[i].eval(&xq));
            for j in 0..3 {
                prop_assert_eq!(&hq[i][j], &hess[i][j].eval(&xq));
            }
        }
        let h = 1e-4;
        for i in 0..3 {
            // gradient by central differences, error O(h^2 |p'''|)
            let mut xp = point.clone(); xp[i] += h;
            let mut xm = point.clone(); xm[i] -= h;
            let fd = (p.eval_f64(&xp) - p.eval_f64(&xm)) / (2.0 * h);
            let exact = grad[i].eval_f64(&point);
            prop_assert!((fd - exact).abs() <= 1e-5 * (1.0 + exact.abs()), "grad {}: {} vs {}", i, fd, exact);
            for j in 0..3 {
                let mut pp = point.clone(); pp[i] += h; pp[j] += h;
                let mut pm = point.clone(); pm[i] += h; pm[j] -= h;
                let mut mp = point.clone(); mp[i] -= h; mp[j] += h;
                let mut mm = point.clone(); mm[i] -= h; mm[j] -= h;
                let fd = (p.eval_f64(&pp) - p.eval_f64(&pm) - p.eval_f64(&mp) + p.eval_f64(&mm)) / (4.0 * h * h);
                let exact = hess[i][j].eval_f64(&point);
                prop_assert!((fd - exact).abs() <= 1e-3 * (1.0 + exact.abs()), "hess {}{}: {} vs {}", i, j, fd, exact);
            }
        }
    }
}

#[test]
fn discovery_finds_the_known_casimirs() {
    // so3: one generator |Pi|^2; se3: |Gamma|^2 and Pi.Gamma (degree 2, no
    // new ones up to 4); sl2: muH^2 + 4 muE muF; heisenberg: muZ;
    // so3 ⊕ sl2: one quadratic each.
    let cases: [(&str, Vec<&str>); 4] = [
        ("so3", vec!["Pi1^2 + Pi2^2 + Pi3^2"]),
        ("se3", vec!["Gamma1^2 + Gamma2^2 + Gamma3^2", "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"]),
        ("sl2", vec!["muH^2 + 4*muE*muF"]),
        ("heisenberg", vec!["muZ"]),
    ];
    for (name, expected) in cases {
        let g = builtin(name).unwrap().algebra;
        let report = discover_casimirs(&g, 4, 2000);
        assert_eq!(report.casimirs.len(), expected.len(), "{name}: {:?}", report.casimirs);
        let s = Symbols::new(g.coordinates());
        // Each expected Casimir is in the span of the discovered ones of its degree.
        for e in expected {
            let e = parse_expression(e, &s).unwrap();
            let same_degree: Vec<&Poly> =
                report.casimirs.iter().filter(|c| c.total_degree() == e.total_degree()).collect();
            let monomials: Vec<_> = e
                .terms()
                .map(|(m, _)| m.clone())
                .chain(same_degree.iter().flat_map(|c| c.terms().map(|(m, _)| m.clone())))
                .collect();
            let rows: Vec<Vec<Rational>> =
                same_degree.iter().map(|c| monomials.iter().map(|m| c.coefficient(m)).collect()).collect();
            let mut with_e = rows.clone();
            with_e.push(monomials.iter().map(|m| e.coefficient(m)).collect());
            assert_eq!(
                Matrix::from_rows(&rows).rank(),
                Matrix::from_rows(&with_e).rank(),
                "{name}: {e:?} not discovered"
            );
        }
        assert_eq!(report.degree_searched, 4);
    }
    let sum = builtin("so3").unwrap().algebra.direct_sum(&builtin("sl2").unwrap().algebra, "sum").unwrap();
    assert_eq!(discover_casimirs(&sum, 4, 2000).casimirs.len(), 2);
}

#[test]
fn discovery_reports_skipped_degrees() {
    let se3 = builtin("se3").unwrap().algebra;
    // 6 variables: 21 quadratic, 56 cubic monomials.
    let report = discover_casimirs(&se3, 3, 30);
    assert_eq!(report.skipped_degrees, vec![3]);
    assert_eq!(report.casimirs.len(), 2);
}

/// Regression: on an abelian algebra every coordinate is a Casimir, the
/// conserved gradients span g*, the restricted Hessian is 0×0, and the search
/// used to panic inside nalgebra's eigen-solver on the empty matrix. Discovery
/// on 20 coordinates also used to take minutes (dense exact elimination).
#[test]
fn regression_abelian_algebra_empty_restricted_hessian() {
    let coords: Vec<String> = (0..20).map(|i| format!("x{i}")).collect();
    let g = LieAlgebra::from_structure_constants("abelian", &coords, &[]).unwrap();
    let report = discover_casimirs(&g, 4, 2000);
    // 20 linear generators; every higher-degree polynomial is a product of them.
    assert_eq!(report.casimirs.len(), 20);
    assert!(report.casimirs.iter().all(|c| c.total_degree() == 1));
    assert_eq!(report.skipped_degrees, vec![4]); // C(23, 4) = 8855 monomials > 2000
    let spec = format!(
        r#"{{"name": "abelian", "algebra": {{"coordinates": {coords:?}, "structure_constants": []}},
             "hamiltonian": "{}", "equilibrium": [1{}], "noise": [[0, 1{}]]}}"#,
        coords.iter().map(|c| format!("{c}^2")).collect::<Vec<_>>().join(" + "),
        ", 0".repeat(19),
        ", 0".repeat(18)
    );
    let cert = spec::certify_lie(&spec::parse_spec(&spec).unwrap());
    // Every point is an equilibrium, the noise is trivial (ad* = 0), so the
    // norm is conserved: stable with Sigma^2 = 0.
    assert_eq!(cert.json["verdict"], "stable");
    assert_eq!(cert.analysis.sigma2(), Some(0.0));
}

/// The verified floating-point test never accepts an indefinite matrix and
/// accepts well-conditioned definite ones. Matrices Q diag(d) Q^T with a
/// known spectrum d (Q a product of Givens rotations), paired: the same
/// matrix with its smallest eigenvalue made -1e-10 (relative) must fail.
#[test]
fn verified_positive_definiteness_pairs() {
    use nalgebra::DMatrix;
    use numerics::definite::verified_positive_definite;
    let build = |d: &[f64], seed: u64| -> DMatrix<f64> {
        let n = d.len();
        let mut q = DMatrix::<f64>::identity(n, n);
        let mut s = seed;
        for i in 0..n {
            for j in (i + 1)..n {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let th = (s >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
                let (c, sn) = (th.cos(), th.sin());
                for k in 0..n {
                    let (a, b) = (q[(k, i)], q[(k, j)]);
                    q[(k, i)] = c * a - sn * b;
                    q[(k, j)] = sn * a + c * b;
                }
            }
        }
        let m = &q * DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(d)) * q.transpose();
        (&m + m.transpose()) * 0.5
    };
    for seed in 0..50u64 {
        let n = 2 + (seed as usize % 7);
        let mut d: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        assert!(verified_positive_definite(&build(&d, seed)), "seed {seed}: well-conditioned SPD not verified");
        d[0] = -1e-10;
        assert!(!verified_positive_definite(&build(&d, seed)), "seed {seed}: indefinite matrix verified");
        d[0] = 0.0;
        assert!(!verified_positive_definite(&build(&d, seed)), "seed {seed}: singular matrix verified");
    }
}
