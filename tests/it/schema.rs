//! The JSON Schemas of specs (`schema/*.schema.json`) are generated from the
//! typed documents (`spec::document`) and committed so that editors can
//! validate and complete a spec. These tests keep the committed files in
//! step with the types, and check with an independent JSON Schema validator
//! (the `jsonschema` crate) that the schema and the engine agree: every
//! fixture is valid, and malformed specs the engine rejects as bad input are
//! invalid.

use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn committed(name: &str) -> Value {
    let path = root().join("schema").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// Fails when a document type changed without `verify schema` being re-run:
/// `cargo run -p verify -- schema spec > schema/spec.schema.json` (and
/// `fluid-spec` for the fluid schema).
#[test]
fn committed_schemas_match_the_types() {
    let generated = [
        ("spec", spec::document::spec_schema()),
        ("fluid-spec", spec::document::fluid_spec_schema()),
        ("certificate", spec::record::certificate_schema()),
        ("fluid-certificate", spec::record::fluid_certificate_schema()),
        ("zeitlin-spec", spec::document::zeitlin_spec_schema()),
        ("zeitlin-certificate", spec::record::zeitlin_certificate_schema()),
        ("large-certificate", spec::record::large_certificate_schema()),
        ("box-certificate", spec::box_cert::box_certificate_schema()),
    ];
    for (name, schema) in generated {
        // Not assert_eq: the two values are thousands of characters.
        assert!(
            committed(&format!("{name}.schema.json")) == schema,
            "schema/{name}.schema.json differs from the types: cargo run -p verify -- schema {name} > schema/{name}.schema.json"
        );
    }
}

/// The kind of a spec: `spec` (finite-dimensional), `fluid-spec`,
/// `zeitlin-spec` or `large-spec` (above 64 coordinates).
fn kind(spec: &Value) -> &'static str {
    if spec::is_fluid_spec(spec) {
        "fluid-spec"
    } else if spec::is_zeitlin_spec(spec) {
        "zeitlin-spec"
    } else if spec::is_large_spec(spec) {
        "large-spec"
    } else if spec.get("box").is_some() {
        "box-spec"
    } else {
        "spec"
    }
}

/// Reads a certificate into its typed document and writes it back (the
/// error when it does not read).
fn round_trip(kind: &str, v: &Value) -> Result<Value, spec::SpecError> {
    Ok(match kind {
        "fluid-spec" => serde_json::to_value(spec::document::from_value::<spec::record::FluidCertificateDocument>(v)?),
        "zeitlin-spec" => {
            serde_json::to_value(spec::document::from_value::<spec::record::ZeitlinCertificateDocument>(v)?)
        }
        "large-spec" => serde_json::to_value(spec::document::from_value::<spec::record::LargeCertificateDocument>(v)?),
        "box-spec" => serde_json::to_value(spec::document::from_value::<spec::box_cert::BoxCertificateDocument>(v)?),
        _ => serde_json::to_value(spec::document::from_value::<spec::record::CertificateDocument>(v)?),
    }
    .unwrap())
}

/// Every committed certificate is valid against its certificate schema
/// and reads into its typed document, which writes it back unchanged; an
/// added field makes it invalid for both.
#[test]
fn fixture_certificates_match_the_certificate_types() {
    let schema_of = |kind: &str| {
        let name = kind.replace("spec", "certificate");
        jsonschema::validator_for(&committed(&format!("{name}.schema.json"))).unwrap()
    };
    let validators: BTreeMap<&str, _> = ["spec", "fluid-spec", "zeitlin-spec", "large-spec", "box-spec"]
        .into_iter()
        .map(|k| (k, schema_of(k)))
        .collect();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let mut dirs = vec![root().join("fixtures")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            if !path.to_string_lossy().ends_with(".cert.json") {
                continue;
            }
            let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            let kind = kind(&v["spec"]);
            *counts.entry(kind).or_default() += 1;
            let schema = &validators[kind];
            let errors: Vec<String> = schema.iter_errors(&v).map(|e| e.to_string()).collect();
            assert!(errors.is_empty(), "{}: {errors:?}", path.display());
            assert_eq!(round_trip(kind, &v).unwrap(), v, "{}", path.display());
            let mut extra = v.clone();
            extra["growth_bonus"] = json!(1);
            assert!(!schema.is_valid(&extra));
            assert_eq!(round_trip(kind, &extra).unwrap_err().path, "$.growth_bonus");
        }
    }
    assert!(
        counts.get("spec") >= Some(&5)
            && counts.get("fluid-spec") >= Some(&2)
            && counts.get("zeitlin-spec") >= Some(&2)
            && counts.get("large-spec") >= Some(&2)
            && counts.get("box-spec") >= Some(&3),
        "{counts:?}"
    );
}

fn fixtures() -> Vec<(PathBuf, Value)> {
    let mut out = Vec::new();
    let mut dirs = vec![root().join("fixtures")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if path.is_dir() {
                dirs.push(path);
            } else if name.ends_with(".json") && !name.ends_with(".cert.json") {
                let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
                out.push((path, v));
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

#[test]
fn every_fixture_is_valid_against_its_schema() {
    let kinds = ["spec", "fluid-spec", "zeitlin-spec"];
    let validators: BTreeMap<&str, _> = kinds
        .into_iter()
        .map(|k| (k, jsonschema::validator_for(&committed(&format!("{k}.schema.json"))).unwrap()))
        .collect();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for (path, v) in &fixtures() {
        // A spec above 64 coordinates has the finite-dimensional spec's format.
        let kind = match kind(v) {
            "large-spec" | "box-spec" => "spec",
            k => k,
        };
        let errors: Vec<String> = validators[kind].iter_errors(v).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "{}: {errors:?}", path.display());
        // Each fixture is valid for exactly one of the schemas.
        for other in kinds.iter().filter(|k| **k != kind) {
            assert!(!validators[other].is_valid(v), "{} is also a valid {other}", path.display());
        }
        *counts.entry(kind).or_default() += 1;
    }
    assert!(
        counts.get("spec") >= Some(&5)
            && counts.get("fluid-spec") >= Some(&2)
            && counts.get("zeitlin-spec") >= Some(&2),
        "{counts:?}"
    );
}

/// Structural mistakes: the engine refuses them as bad input (naming the
/// path) and the schema marks them invalid.
#[test]
fn structural_mistakes_are_invalid_for_both() {
    let finite = jsonschema::validator_for(&committed("spec.schema.json")).unwrap();
    let good = json!({"name": "rb", "algebra": "so3", "parameters": {"s": "3/10"},
                      "hamiltonian": "Pi1^2/6 + Pi2^2/4 + Pi3^2/2", "equilibrium": [1, 0, 0],
                      "noise": [["s", 0, 0]], "settings": {"exact": true}});
    assert!(finite.is_valid(&good));
    spec::spec_from_value(good.clone()).unwrap();
    // An editor's "$schema" key is allowed and ignored.
    let mut tagged = good.clone();
    tagged["$schema"] = json!("../schema/spec.schema.json");
    assert!(finite.is_valid(&tagged));
    let (a, b) = (spec::spec_from_value(good.clone()).unwrap(), spec::spec_from_value(tagged).unwrap());
    assert_eq!(spec::certify_lie(&a).json["sigma2_exact"], spec::certify_lie(&b).json["sigma2_exact"]);
    type Edit = Box<dyn Fn(&mut Value)>;
    let edits: Vec<(&str, Edit)> = vec![
        ("$.nmae", Box::new(|v| v["nmae"] = json!("x"))),
        ("$.noise", Box::new(|v| v["noise"] = json!("s"))),
        (
            "$.noise",
            Box::new(|v| {
                v.as_object_mut().unwrap().remove("noise");
            }),
        ),
        ("$.algebra", Box::new(|v| v["algebra"] = json!(3))),
        ("$.algebra", Box::new(|v| v["algebra"] = json!("so5"))),
        ("$.settings.exact", Box::new(|v| v["settings"]["exact"] = json!("yes"))),
        ("$.settings.search_expansions", Box::new(|v| v["settings"]["search_expansions"] = json!(11))),
        ("$.settings.max_doublings", Box::new(|v| v["settings"]["max_doublings"] = json!(3))),
        ("$.stopping.delta", Box::new(|v| v["stopping"] = json!({"epsilon": 1}))),
        ("$.equilibrium[1]", Box::new(|v| v["equilibrium"][1] = json!([0]))),
    ];
    for (path, edit) in edits {
        let mut v = good.clone();
        edit(&mut v);
        assert!(!finite.is_valid(&v), "{path}: the schema accepts {v}");
        let e = spec::spec_from_value(v).unwrap_err();
        assert_eq!(e.path, path, "{e}");
    }
}

/// Exact arithmetic writes rationals that no double holds (an equilibrium at
/// -1e308 gives `M` entries of 600 digits); the certificate type reads them
/// exactly, so the engine's own certificate checks (found by the fuzz run).
#[test]
fn certificates_with_huge_exact_entries_read_into_the_type_and_check() {
    let v = json!({"name": "rb", "algebra": "so3", "casimirs": ["(Pi1^2 + Pi2^2 + Pi3^2)/2"],
                   "equilibrium": [-1e308, 0, 0], "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
                   "noise": [["sigma", 0, 0]], "parameters": {"I1": 3, "I2": 2, "I3": 1, "sigma": "3/10"}});
    let cert = spec::certify_lie(&spec::spec_from_value(v).unwrap());
    let longest = cert.json.to_string().split('"').map(str::len).max().unwrap();
    assert!(longest > 300, "expected an entry beyond any double, longest {longest}");
    let doc: spec::record::CertificateDocument = spec::document::from_value(&cert.json).unwrap();
    assert_eq!(serde_json::to_value(&doc).unwrap(), cert.json);
    spec::check_certificate(&cert.json.to_string()).unwrap();
}

/// Every committed certificate embeds exactly the spec file beside it: an
/// edited spec whose certificate was not rewritten (`verify --write`) would
/// otherwise still pass `verify check`, which re-derives from the embedded
/// copy.
#[test]
fn committed_certificates_embed_the_spec_beside_them() {
    let mut seen = 0;
    for (path, spec) in fixtures() {
        let cert_path = path.with_extension("cert.json");
        let Ok(text) = std::fs::read_to_string(&cert_path) else { continue };
        let cert: Value = serde_json::from_str(&text).unwrap();
        assert!(cert["spec"] == spec, "{}: re-run verify --write", cert_path.display());
        seen += 1;
    }
    assert!(seen >= 20, "{seen} certificates");
}
