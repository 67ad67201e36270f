//! Tamper tests: for every fixture certificate, a family of single-number
//! alterations (Sigma^2 lowered by a relative 1e-9, a matrix entry changed, a
//! multiplier changed, M changed, the verdict flipped, the spec changed) each
//! fails `check` with a `Failed` error naming a field; the untouched
//! certificate passes.

use crate::common;

use common::*;
use exact::{parse_number, Rational};
use serde_json::Value;
use spec::{check_certificate_value, CheckError};

fn committed_certificate(name: &str) -> Value {
    let path = fixture_path(&name.replace(".json", ".cert.json"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn at<'a>(v: &'a mut Value, path: &[&str]) -> Option<&'a mut Value> {
    let mut cur = v;
    for p in path {
        cur = match p.parse::<usize>() {
            Ok(i) => cur.get_mut(i)?,
            Err(_) => cur.get_mut(*p)?,
        };
    }
    Some(cur)
}

/// Add `delta` to a rational string.
fn bump_rational(v: &mut Value, delta: &Rational) {
    let r = parse_number(v.as_str().unwrap()).unwrap();
    *v = Value::String((r + delta).to_string());
}

fn expect_failure(what: &str, name: &str, cert: &Value) {
    match check_certificate_value(cert) {
        Err(CheckError::Failed { path, .. }) => assert!(path.starts_with("$."), "{name}: {what}: path {path}"),
        other => panic!("{name}: {what}: expected a failed check, got {other:?}"),
    }
}

#[test]
fn every_fixture_rejects_single_number_alterations() {
    let small = Rational::new_small(1, 1000);
    for name in fixture_specs() {
        let cert = committed_certificate(&name);
        assert!(check_certificate_value(&cert).is_ok(), "{name}: the untouched certificate must pass");
        let verdict = cert["verdict"].as_str().unwrap().to_string();
        let mut family: Vec<(String, Value)> = Vec::new();

        // The verdict flipped.
        let mut c = cert.clone();
        c["verdict"] = Value::from(if verdict == "stable" { "inconclusive" } else { "stable" });
        family.push(("verdict flipped".into(), c));

        // The spec changed: the first parameter, or else the equilibrium.
        let mut c = cert.clone();
        let params = c["spec"]["parameters"].as_object_mut().unwrap();
        let key = params.keys().next().unwrap().clone();
        let old = parse_number(params[&key].to_string().trim_matches('"')).unwrap();
        params.insert(key.clone(), Value::String((old + &small).to_string()));
        family.push((format!("spec parameter {key}"), c));

        if verdict == "stable" {
            // Sigma^2 lowered by a relative 1e-9, in the exact and the float field.
            let s = parse_number(cert["sigma2_exact"].as_str().unwrap()).unwrap();
            if !num_traits::Zero::is_zero(&s) {
                let mut c = cert.clone();
                let lowered = &s * &Rational::new_small(999_999_999, 1_000_000_000);
                c["sigma2_exact"] = Value::String(lowered.to_string());
                c["sigma2"] = Value::from(exact::rational_to_f64(&lowered));
                family.push(("sigma2 lowered by 1e-9 (both fields)".into(), c));
                let mut c = cert.clone();
                c["sigma2"] = Value::from(cert["sigma2"].as_f64().unwrap() * (1.0 - 1e-9));
                family.push(("sigma2 float lowered by 1e-9".into(), c));
            } else {
                // Sigma^2 = 0 cannot be lowered; raise it instead (not tight).
                let mut c = cert.clone();
                c["sigma2_exact"] = Value::String("1/1000000000".into());
                c["sigma2"] = Value::from(1e-9);
                family.push(("sigma2 raised from 0".into(), c));
            }
            for (m, path) in
                [("P", vec!["P", "1", "1"]), ("Q", vec!["Q", "1", "1"]), ("M", vec!["casimir_choice", "M", "0", "0"])]
            {
                let mut c = cert.clone();
                bump_rational(at(&mut c, &path).unwrap(), &small);
                family.push((format!("{m} entry"), c));
            }
            let mut c = cert.clone();
            bump_rational(at(&mut c, &["casimir_choice", "multipliers", "0"]).unwrap(), &small);
            family.push(("multiplier".into(), c));
        } else {
            let mut c = cert.clone();
            if let Some(a) = at(&mut c, &["linearisation", "A", "0", "1"]) {
                bump_rational(a, &small);
                family.push(("A entry".into(), c));
            }
            let mut c = cert.clone();
            bump_rational(at(&mut c, &["equilibrium", "residual", "0"]).unwrap(), &small);
            family.push(("equilibrium residual".into(), c));
            let mut c = cert.clone();
            bump_rational(at(&mut c, &["equilibrium", "point", "0"]).unwrap(), &small);
            family.push(("equilibrium point".into(), c));
            let mut c = cert.clone();
            if let Some(r) = at(&mut c, &["noise", "residuals", "0", "1"]) {
                bump_rational(r, &small);
                family.push(("noise residual".into(), c));
            }
        }
        for (what, c) in &family {
            expect_failure(what, &name, c);
        }
        assert!(family.len() >= 5, "{name}: only {} alterations", family.len());
    }
}

/// The exact claims fail for a certificate whose numbers were all rewritten
/// consistently by hand except the one thing that makes the claim true: a
/// Sigma^2 below lambda_max with matching float and exact fields and a
/// recomputed stopping time still fails the exact semidefiniteness claim.
#[test]
fn consistent_but_false_sigma2_fails_the_exact_claim() {
    let cert = committed_certificate("rigid-body-major-axis.json");
    let mut c = cert.clone();
    c["sigma2_exact"] = Value::String("269/1000".into());
    c["sigma2"] = Value::from(0.269);
    c["stopping"]["T"] = Value::from((100f64).ln() / 0.269);
    match check_certificate_value(&c) {
        Err(CheckError::Failed { path, message }) => {
            assert_eq!(path, "$.sigma2_exact");
            assert!(message.contains("not positive semidefinite"), "{message}");
        }
        other => panic!("expected the exact claim to fail, got {other:?}"),
    }
}
