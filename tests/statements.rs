//! Every statement a certificate makes is re-derived by `check` or declared
//! free text: the regressions of an adversarial round (a stopping time past
//! its proof, fields `check` never read), one test per thing that broke.

mod common;

use common::fixture_path;
use serde_json::{json, Value};
use spec::{check_certificate_value_in, CheckError};

fn committed(name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(fixture_path(name)).unwrap()).unwrap()
}

fn check(name: &str, cert: &Value) -> Result<spec::CheckReport, CheckError> {
    let base = fixture_path(name);
    check_certificate_value_in(cert, base.parent())
}

/// One certificate of every kind that states a finite stopping time.
const WITH_STOPPING_TIME: [&str; 4] = [
    "rigid-body-major-axis.cert.json",
    "fluids/channel-sin-walls.cert.json",
    "large/chain-30.cert.json",
    "zeitlin/energy-casimir-n32.cert.json",
];

/// `T` raised by a relative 5e-10 once passed the Zeitlin check (which
/// compared it within 1e-9) although it exceeded `ln(100)/sigma2_upper`.
/// One rule for every kind: `T` is the time the stated bound guarantees,
/// rounded down, never above it; lowered by more than 1e-12 it is not the
/// engine's statement either.
#[test]
fn a_stopping_time_past_its_proof_fails_for_every_kind() {
    for name in WITH_STOPPING_TIME {
        let cert = committed(name);
        assert!(check(name, &cert).is_ok(), "{name}: the committed certificate");
        let t = cert["stopping"]["T"].as_f64().unwrap_or_else(|| panic!("{name}: no finite T"));
        for factor in [1.0 + 5e-10, 1.0 - 5e-10, 1.0 + 1e-15 * 8.0] {
            let mut edited = cert.clone();
            edited["stopping"]["T"] = json!(t * factor);
            if edited["stopping"]["T"] == cert["stopping"]["T"] {
                continue;
            }
            match check(name, &edited) {
                Err(CheckError::Failed { path, .. }) if factor < 1.0 || path == "$.stopping.T" => {}
                Err(CheckError::Failed { path, message }) => {
                    panic!("{name}: T x {factor}: failed at {path} ({message}), not at $.stopping.T")
                }
                other => panic!("{name}: T x {factor} accepted: {other:?}"),
            }
        }
        for key in ["epsilon", "delta"] {
            let mut edited = cert.clone();
            let v = cert["stopping"][key].as_f64().unwrap();
            edited["stopping"][key] = json!(v * (1.0 + 1e-7));
            assert!(check(name, &edited).is_err(), "{name}: {key} edited by 1e-7 accepted");
        }
    }
}
