//! The same system written with a builtin algebra, with its structure
//! constants, and in a rescaled basis gives the same verdict and Sigma^2.
//!
//! Rescaling e'_a = s_a e_a gives c'^k_ab = s_a s_b / s_k c^k_ab, coordinates
//! mu'_a = s_a mu_a (so h'(mu') = h(mu'/s)) and noise components
//! sigma'^a = sigma^a / s_a. P and Q transform by congruence, so the
//! generalized eigenvalues, hence Sigma^2, are invariant.

use crate::common;

use common::*;

fn certify(text: &str) -> (String, Option<f64>) {
    let cert = spec::certify_lie(&spec::parse_spec(text).unwrap());
    (cert.json["verdict"].as_str().unwrap().to_string(), cert.analysis.sigma2())
}

fn rows_json(algebra: &algebra::LieAlgebra) -> String {
    let rows: Vec<String> =
        algebra.structure_constant_rows().iter().map(|(a, b, k, c)| format!("[{a}, {b}, {k}, \"{c}\"]")).collect();
    format!("[{}]", rows.join(", "))
}

#[test]
fn rigid_body_builtin_structure_constants_and_rescaled_agree() {
    let builtin = fixture("rigid-body-major-axis.json");
    let (v0, s0) = certify(&builtin);
    assert_eq!(v0, "stable");

    let so3 = algebra::builtin("so3").unwrap().algebra;
    let explicit = builtin.replace(
        r#""algebra": "so3""#,
        &format!(r#""algebra": {{"coordinates": ["Pi1", "Pi2", "Pi3"], "structure_constants": {}}}"#, rows_json(&so3)),
    );
    let (v1, s1) = certify(&explicit);

    // Rescale by s = (2, 3, 5).
    let s = [q(2, 1), q(3, 1), q(5, 1)];
    let scaled = so3.rescaled(&s);
    let rescaled = format!(
        r#"{{"name": "rb-rescaled",
             "algebra": {{"coordinates": ["Pi1", "Pi2", "Pi3"], "structure_constants": {}}},
             "parameters": {{"I1": 3, "I2": 2, "I3": 1, "sigma": "3/10"}},
             "hamiltonian": "(Pi1/2)^2/(2*I1) + (Pi2/3)^2/(2*I2) + (Pi3/5)^2/(2*I3)",
             "casimirs": ["((Pi1/2)^2 + (Pi2/3)^2 + (Pi3/5)^2)/2"],
             "equilibrium": [2, 0, 0],
             "noise": [["sigma/2", 0, 0]]}}"#,
        rows_json(&scaled)
    );
    let (v2, s2) = certify(&rescaled);
    assert_eq!((v1.as_str(), v2.as_str()), ("stable", "stable"));
    let (s0, s1, s2) = (s0.unwrap(), s1.unwrap(), s2.unwrap());
    assert!(rel(s0, s1) < 1e-13 && rel(s0, s2) < 1e-13, "{s0} {s1} {s2}");
    // Sigma^2 = 3 sigma^2 (closed form, generator::closed_forms)
    assert!(rel(s0, 0.27) < 1e-13);
}

#[test]
fn heavy_top_builtin_structure_constants_and_rescaled_agree() {
    let builtin = fixture("heavy-top-asymmetric.json");
    let (v0, s0) = certify(&builtin);
    let se3 = algebra::builtin("se3").unwrap().algebra;
    let coords = r#"["Pi1", "Pi2", "Pi3", "Gamma1", "Gamma2", "Gamma3"]"#;
    let explicit = builtin.replace(
        r#""algebra": "se3","#,
        &format!(
            r#""algebra": {{"coordinates": {coords}, "structure_constants": {}}},
               "casimirs": ["(Gamma1^2 + Gamma2^2 + Gamma3^2)/2", "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"],"#,
            rows_json(&se3)
        ),
    );
    let (v1, s1) = certify(&explicit);
    // Rescale by s = (1, 2, 1/2, 3, 1, 2): substitute Pi_i -> Pi_i/s_i etc.
    let s = [q(1, 1), q(2, 1), q(1, 2), q(3, 1), q(1, 1), q(2, 1)];
    let scaled = se3.rescaled(&s);
    let rescaled = format!(
        r#"{{"name": "ht-rescaled",
             "algebra": {{"coordinates": {coords}, "structure_constants": {}}},
             "parameters": {{"I1": 1, "I2": 2, "I3": 3, "mgl": 1, "p": 4, "sigma": "3/10"}},
             "hamiltonian": "Pi1^2/(2*I1) + (Pi2/2)^2/(2*I2) + (2*Pi3)^2/(2*I3) + mgl*Gamma3/2",
             "casimirs": ["((Gamma1/3)^2 + Gamma2^2 + (Gamma3/2)^2)/2", "Pi1*Gamma1/3 + Pi2/2*Gamma2 + 2*Pi3*Gamma3/2"],
             "equilibrium": [0, 0, "p/2", 0, 0, 2],
             "noise": [[0, 0, "2*sigma", 0, 0, 0]]}}"#,
        rows_json(&scaled)
    );
    let (v2, s2) = certify(&rescaled);
    assert_eq!((v0.as_str(), v1.as_str(), v2.as_str()), ("stable", "stable", "stable"));
    let (s0, s1, s2) = (s0.unwrap(), s1.unwrap(), s2.unwrap());
    assert!(rel(s0, s1) < 1e-13 && rel(s0, s2) < 1e-13, "{s0} {s1} {s2}");
    // 39/7 sigma^2 (closed form)
    assert!(rel(s0, 0.09 * 39.0 / 7.0) < 1e-13);
}

#[test]
fn unstable_verdict_is_basis_independent() {
    let builtin = fixture("rigid-body-intermediate-axis.json");
    let so3 = algebra::builtin("so3").unwrap().algebra;
    let scaled = so3.rescaled(&[q(1, 3), q(7, 1), q(2, 1)]);
    let rescaled = format!(
        r#"{{"name": "rb-int-rescaled",
             "algebra": {{"coordinates": ["Pi1", "Pi2", "Pi3"], "structure_constants": {}}},
             "parameters": {{"I1": 2, "I2": 3, "I3": 1, "sigma": "3/10"}},
             "hamiltonian": "(3*Pi1)^2/(2*I1) + (Pi2/7)^2/(2*I2) + (Pi3/2)^2/(2*I3)",
             "casimirs": ["((3*Pi1)^2 + (Pi2/7)^2 + (Pi3/2)^2)/2"],
             "equilibrium": ["1/3", 0, 0],
             "noise": [["3*sigma", 0, 0]]}}"#,
        rows_json(&scaled)
    );
    assert_eq!(certify(&builtin).0, "linearly_unstable");
    assert_eq!(certify(&rescaled).0, "linearly_unstable");
}
