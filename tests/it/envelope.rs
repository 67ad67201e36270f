//! One certificate type for every kind: the header of every fixture
//! certificate reads with the kind and verdict its pipeline wrote, `check`
//! through the envelope agrees with the file's own verdict, and malformed
//! headers are refused with the field's path.

use crate::common::fixture_path;
use serde_json::json;
use spec::{check, AnyCertificate, AnyVerdict, CertificateKind, CheckError, Options};

fn certificates(dir: &str) -> Vec<std::path::PathBuf> {
    let mut out: Vec<_> = std::fs::read_dir(fixture_path(dir))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".cert.json"))
        .collect();
    out.sort();
    out
}

/// Every fixture certificate's header: the kind follows the folder (and a
/// spec above 64 coordinates is `large`), the verdict and level are the
/// file's own strings, and the light ones pass `check` through the
/// envelope with that verdict.
#[test]
fn every_fixture_certificate_reads_into_the_envelope() {
    let expected = [
        (".", CertificateKind::LiePoisson),
        ("boxes", CertificateKind::Box),
        ("fluids", CertificateKind::Fluid),
        ("zeitlin", CertificateKind::Zeitlin),
        ("large", CertificateKind::Large),
        ("sweeps", CertificateKind::LiePoisson),
    ];
    let mut seen = 0;
    for (dir, kind) in expected {
        for path in certificates(dir) {
            let text = std::fs::read_to_string(&path).unwrap();
            let raw: serde_json::Value = serde_json::from_str(&text).unwrap();
            let cert = AnyCertificate::from_json(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(cert.kind(), kind, "{}", path.display());
            assert_eq!(cert.verdict().as_str(), raw["verdict"], "{}", path.display());
            assert_eq!(cert.header().name, raw["name"].as_str().unwrap());
            assert_eq!(cert.header().spec_sha256, raw["spec_sha256"].as_str().unwrap());
            match raw.get("level").and_then(|l| l.as_str()) {
                None | Some("none") => assert_eq!(cert.header().level, None),
                Some(l) => assert_eq!(cert.header().level.unwrap().as_str(), l),
            }
            assert_eq!(cert.json(), &raw);
            seen += 1;
        }
    }
    // 43 certificates: 12 + 4 + 10 + 12 + 2 + 3 (`ls fixtures/*/*.cert.json`).
    assert_eq!(seen, 43);
    for name in
        ["rigid-body-intermediate-axis.cert.json", "boxes/rigid-body-inertia-box.cert.json", "large/chain-30.cert.json"]
    {
        let path = fixture_path(name);
        let cert = AnyCertificate::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let dir = path.parent().unwrap();
        let report = check(&cert, &Options::default().with_base_dir(dir)).unwrap();
        if let Some(v) = cert.verdict().at_the_point() {
            assert_eq!(report.verdict, v, "{name}");
        }
    }
}

/// A box certificate's verdict is a box verdict, a point certificate's a
/// point verdict: `partly_stable` is not a verdict of one point.
#[test]
fn verdicts_are_read_by_kind() {
    let text = std::fs::read_to_string(fixture_path("boxes/rigid-body-inertia-box.cert.json")).unwrap();
    let cert = AnyCertificate::from_json(&text).unwrap();
    assert!(matches!(cert.verdict(), AnyVerdict::Box(_)));
    let mut point: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture_path("rigid-body-major-axis.cert.json")).unwrap())
            .unwrap();
    point["verdict"] = json!("partly_stable");
    let e = AnyCertificate::from_value(point).unwrap_err();
    assert!(matches!(&e, CheckError::BadInput(s) if s.path == "$.verdict"), "{e}");
}

/// Malformed headers are refused with the field's path, never a panic.
#[test]
fn malformed_headers_name_the_field() {
    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture_path("rigid-body-major-axis.cert.json")).unwrap())
            .unwrap();
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit); 8] = [
        ("$.kind", |c| c["kind"] = json!("lie_poisson")),
        ("$.kind", |c| c["kind"] = json!("../fluid")),
        ("$.kind", |c| c["kind"] = json!(7)),
        ("$.verdict", |c| c["verdict"] = json!(null)),
        ("$.level", |c| c["level"] = json!("provisional")),
        ("$.certificate_version", |c| c["certificate_version"] = json!(-4)),
        ("$.spec", |c| c["spec"] = json!("rigid body")),
        ("$.engine.version", |c| c["engine"] = json!({"name": "verify"})),
    ];
    for (path, edit) in cases {
        let mut c = good.clone();
        edit(&mut c);
        match AnyCertificate::from_value(c) {
            Err(CheckError::BadInput(e)) => assert_eq!(e.path, path, "{e}"),
            other => panic!("{path}: {other:?}"),
        }
    }
    assert!(matches!(AnyCertificate::from_json("[1, 2]"), Err(CheckError::BadInput(e)) if e.path == "$"));
    assert!(matches!(AnyCertificate::from_json("{"), Err(CheckError::BadInput(_))));
}

/// A header that reads is not a certificate that holds: an edited Sigma^2
/// fails `check` through the envelope, with its path.
#[test]
fn the_envelope_checks_every_claim() {
    let mut c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture_path("rigid-body-major-axis.cert.json")).unwrap())
            .unwrap();
    let s = c["sigma2"].as_f64().unwrap();
    c["sigma2"] = json!(s * (1.0 - 1e-7));
    let cert = AnyCertificate::from_value(c).unwrap();
    match check(&cert, &Options::default()) {
        Err(CheckError::Failed { path, .. }) => assert!(path.starts_with("$.sigma2"), "{path}"),
        other => panic!("{other:?}"),
    }
}

/// A certificate of another format (here the format before this one, as
/// every certificate written before the `route` record was) is refused at
/// `$.certificate_version`, with the way out: certify again.
#[test]
fn another_format_is_told_to_certify_again() {
    for name in
        ["rigid-body-major-axis.cert.json", "boxes/rigid-body-inertia-box.cert.json", "large/chain-30.cert.json"]
    {
        let mut c: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(fixture_path(name)).unwrap()).unwrap();
        let now = c["certificate_version"].as_u64().unwrap();
        c["certificate_version"] = json!(now - 1);
        match spec::check_json(&c.to_string(), &Options::default()) {
            Err(CheckError::Failed { path, message }) => {
                assert_eq!(path, "$.certificate_version", "{name}");
                assert!(
                    message.contains(&format!("format {}", now - 1)) && message.contains("certify the spec again"),
                    "{message}"
                );
            }
            other => panic!("{name}: {other:?}"),
        }
    }
}
