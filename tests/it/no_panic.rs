//! No input makes the engine panic or hang: random text, and random mutations
//! of a valid spec, go through parsing and (when valid) certification.

use crate::common;

use common::*;
use proptest::prelude::*;
use serde_json::Value;

fn leaf() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        (-1000i64..1000).prop_map(Value::from),
        "[-+*/^()a-zA-Z0-9_. ]{0,24}".prop_map(Value::String),
        Just(Value::String("Pi1^64*Pi2^64".into())),
        Just(Value::String("1e400".into())),
        Just(Value::Array(vec![])),
        Just(serde_json::json!([0, 0, 0])),
        Just(serde_json::json!({})),
    ]
}

/// Replace the value at a pseudo-randomly chosen position of the tree.
fn mutate(v: &mut Value, choice: &mut u64, replacement: &Value) -> bool {
    *choice = choice.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let here = (*choice >> 33) % 4 == 0;
    match v {
        Value::Object(map) => {
            let keys: Vec<String> = map.keys().cloned().collect();
            for k in keys {
                if here || mutate(map.get_mut(&k).unwrap(), choice, replacement) {
                    if here {
                        map.insert(k, replacement.clone());
                    }
                    return true;
                }
            }
            false
        }
        Value::Array(items) => {
            for item in items.iter_mut() {
                if mutate(item, choice, replacement) {
                    return true;
                }
            }
            if here && !items.is_empty() {
                items[0] = replacement.clone();
                return true;
            }
            false
        }
        _ => false,
    }
}

proptest! {
    #![proptest_config(proptest_config(300, 10_000, module_path!()))]

    #[test]
    fn random_text_never_panics(text in ".{0,200}") {
        let _ = spec::parse_spec(&text);
        let _ = spec::check_certificate(&text);
        let s = exact::Symbols::new(&["x", "y"]);
        let _ = exact::parse_expression(&text, &s);
    }

    #[test]
    fn random_expressions_never_panic(text in "[-+*/^()xy0-9. e]{0,60}") {
        let s = exact::Symbols::new(&["x", "y"]);
        let _ = exact::parse_expression(&text, &s);
    }

    #[test]
    fn mutated_specs_never_panic(which in 0usize..64, seed in any::<u64>(), replacement in leaf()) {
        let names = fixture_specs();
        let mut v: Value = serde_json::from_str(&fixture(&names[which % names.len()])).unwrap();
        let mut choice = seed;
        mutate(&mut v, &mut choice, &replacement);
        if let Ok(spec) = spec::spec_from_value(v) {
            let cert = spec::certify_lie(&spec);
            // Whatever the verdict, the certificate re-checks.
            prop_assert!(spec::check_certificate_value(&cert.json).is_ok());
        }
    }

    #[test]
    fn random_fluid_expressions_never_panic(text in "[-+*/^()y0-9. e]{0,40}|(sin|cos|exp|sqrt|tan)\\([-+*/^y0-9. ]{0,20}\\)") {
        if let Ok(e) = fluid::expr::parse(&text, &Default::default()) {
            let _ = (e.eval(0.5), e.derivatives(-0.5));
            let d = std::sync::Arc::new(e);
            let _ = fluid::expr::Derivative::new(d, 2).sign_on(-1.0, 1.0, 1e5);
        }
    }

    #[test]
    fn mutated_fluid_specs_never_panic(seed in any::<u64>(), replacement in fluid_leaf()) {
        let mut v: Value = serde_json::from_str(SMALL_FLUID).unwrap();
        let mut choice = seed;
        mutate(&mut v, &mut choice, &replacement);
        if let Ok(spec) = spec::fluid_spec_from_value(v) {
            let cert = spec::certify_fluid(&spec);
            prop_assert!(spec::check_certificate_value(&cert).is_ok(), "{}", cert);
        }
    }
}

/// A small fluid spec for the mutation test.
const SMALL_FLUID: &str = r#"{"name": "t", "parameters": {"a": 0.3},
  "fluid": {"model": "incompressible", "x_period": "2*pi", "y_interval": [0, "pi"], "boundary": "walls",
            "shear_flow": "sin(y)", "noise": ["a*cos(y)", "0.1"], "ny": 16, "x_modes": 2},
  "stopping": {"epsilon": 0.1, "delta": 0.001}}"#;

fn fluid_leaf() -> impl Strategy<Value = Value> {
    prop_oneof![
        leaf(),
        Just(Value::from("compressible")),
        Just(Value::from("periodic")),
        Just(Value::from("y^3 - y/4")),
        Just(Value::from("exp(y)")),
        Just(Value::from("1/(y - 1)")),
        Just(Value::from("sqrt(y - 1)")),
        Just(Value::from(1e-300)),
        Just(Value::from(1e300)),
        Just(Value::from(256)),
        Just(Value::from(24)),
        Just(serde_json::json!([0, 1e-12])),
        Just(serde_json::json!(["-pi", "pi"])),
    ]
}
