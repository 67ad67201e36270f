//! Box certificates (docs/boxes.md) through the spec and the CLI: every
//! verdict, the closed forms, tampering, bad input, invariance and
//! determinism.

use serde_json::{json, Value};
use std::process::Command;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn verify(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).current_dir(ROOT).args(args).output().expect("run verify")
}

fn fixture(name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(format!("{ROOT}/fixtures/{name}")).unwrap()).unwrap()
}

fn certify(spec: Value) -> Value {
    let spec = spec::spec_from_value(spec).unwrap();
    spec::box_cert::certify_box_spec(&spec)
}

fn q(text: &str) -> f64 {
    exact::rational_to_f64(&exact::parse_number(text).unwrap())
}

fn rigid_body_box(i2: [&str; 2], i3: [&str; 2]) -> Value {
    let mut v = fixture("rigid-body-major-axis.json");
    v["box"] = json!({"parameters": {"I2": i2, "I3": i3}});
    v
}

/// The rigid body's closed form, `sigma^2 (b/a - 1)` with `a = 1/I2 -
/// 1/I1`, `b = 1/I3 - 1/I1` (`b > a` on these boxes), `I1 = 3`, `sigma^2
/// = 9/100`.
fn rigid_body_sigma2(i2: f64, i3: f64) -> f64 {
    let (a, b) = (1.0 / i2 - 1.0 / 3.0, 1.0 / i3 - 1.0 / 3.0);
    0.09 * (a.max(b) / a.min(b) - 1.0)
}

#[test]
fn the_committed_box_fixtures_check() {
    for name in ["rigid-body-inertia-box", "lagrange-top-fluctuating-gravity-box", "lagrange-top-stability-map"] {
        let out = verify(&["check", &format!("fixtures/boxes/{name}.cert.json")]);
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(String::from_utf8_lossy(&out.stdout).contains(" box "), "{name}");
    }
}

/// Stable whole, with the closed form's sup (at the corner (5/2, 4/5):
/// 1.1475) within the margin, and `check` confirms it.
#[test]
fn a_rigid_body_box_is_stable_with_the_closed_form_sup() {
    let cert = certify(rigid_body_box(["3/2", "5/2"], ["4/5", "6/5"]));
    assert_eq!(cert["verdict"], "stable", "{}", cert["reason"]);
    let sup = cert["sup_sigma2"].as_f64().unwrap();
    let truth = rigid_body_sigma2(2.5, 0.8);
    assert!(sup >= truth && sup <= truth * 1.0011, "sup {sup} against {truth}");
    assert_eq!(cert["sampled_max"]["at"], json!(["5/2", "4/5"]));
    assert_eq!(cert["undecided_fraction"], 0.0);
    let report = spec::check_certificate_value(&cert).unwrap();
    assert_eq!(report.verdict, spec::Verdict::Stable);
}

/// Across `I2 = I1` the axis turns intermediate: partly stable, and no
/// stable sub-box reaches `I2 >= 3`; the pointwise verdicts of a grid
/// inside the stable sub-boxes (the sweep's) are stable with `Sigma^2`
/// below their sub-box's bound.
#[test]
fn a_rigid_body_box_across_i2_equal_i1_is_partly_stable_and_consistent_with_points() {
    let mut spec = rigid_body_box(["2", "4"], ["4/5", "6/5"]);
    spec["box"]["max_depth"] = json!(8);
    let cert = certify(spec.clone());
    assert_eq!(cert["verdict"], "partly_stable", "{}", cert["reason"]);
    let parsed = spec::spec_from_value(spec).unwrap();
    let mut points = 0;
    for sub in cert["sub_boxes"].as_array().unwrap() {
        let hi: Vec<f64> = sub["hi"].as_array().unwrap().iter().map(|x| q(x.as_str().unwrap())).collect();
        if sub["verdict"] != "stable" {
            continue;
        }
        assert!(hi[0] < 3.0, "a stable sub-box reaches I2 = I1: {sub}");
        // the sub-box's centre, certified pointwise
        let centre: Vec<String> = (0..2)
            .map(|i| {
                let (a, b) = (&sub["lo"][i], &sub["hi"][i]);
                let mid = (exact::parse_number(a.as_str().unwrap()).unwrap()
                    + exact::parse_number(b.as_str().unwrap()).unwrap())
                    / exact::Rational::from(2);
                mid.to_string()
            })
            .collect();
        let point = parsed
            .with_parameters(&[
                ("I2".into(), exact::parse_number(&centre[0]).unwrap()),
                ("I3".into(), exact::parse_number(&centre[1]).unwrap()),
            ])
            .unwrap();
        let c = spec::certify_lie(&point).json;
        assert_eq!(c["verdict"], "stable");
        let bound = q(sub["sigma2_upper"].as_str().unwrap());
        assert!(c["sigma2"].as_f64().unwrap() <= bound, "{c} above {bound}");
        points += 1;
    }
    assert!(points > 10);
    for sub in cert["sub_boxes"].as_array().unwrap() {
        if sub["verdict"] == "linearly_unstable" {
            // I2 > I1: the intermediate axis; I2 = I1 itself is not unstable
            assert!(q(sub["lo"][0].as_str().unwrap()) > 3.0, "{sub}");
        }
    }
    let undecided = cert["undecided_fraction"].as_f64().unwrap();
    let unstable = cert["unstable_fraction"].as_f64().unwrap();
    // depth 8: 4 halvings per side; the sub-boxes touching I2 = 3 (a strip
    // of width 2 * 2/16) stay undecided, the rest is proved on each side
    assert_eq!((undecided, unstable), (0.125, 0.4375));
    assert!(spec::check_certificate_value(&cert).is_ok());
}

/// The heavy top (Lagrange, noise about the symmetry axis) over `p` and
/// `mgl`: stable exactly where `p^2 > 4 mgl I1`, linearly unstable (a
/// complex quadruple) where `p^2 < 4 mgl I1`. Every stable sub-box lies
/// strictly on the first side and every unstable one on the second; the
/// undecided sub-boxes form a band along the curve, each at most 1/100 of
/// the box's side (depth 14: 1/128). The unstable area is
/// `int_{1/2}^{3/2} (2 sqrt(m) - 1) dm / 2 = 0.489043` (by hand).
#[test]
fn the_heavy_top_map_resolves_the_stability_boundary_to_one_percent() {
    let mut spec = fixture("lagrange-top-fast.json");
    spec["box"] = json!({"parameters": {"p": ["1", "3"], "mgl": ["1/2", "3/2"]}, "max_depth": 14});
    let cert = certify(spec);
    assert_eq!(cert["verdict"], "partly_stable");
    let unstable_area = (4.0 / 3.0 * (1.5f64.powf(1.5) - 0.5f64.powf(1.5)) - 1.0) / 2.0;
    assert!((unstable_area - 0.489043).abs() < 1e-6);
    let undecided = cert["undecided_fraction"].as_f64().unwrap();
    let unstable = cert["unstable_fraction"].as_f64().unwrap();
    assert!(unstable < unstable_area && unstable + undecided > unstable_area, "{unstable} + {undecided}");
    assert!(undecided < 0.02, "{undecided}");
    // order: (mgl, p) by name
    let r = |v: &Value| exact::parse_number(v.as_str().unwrap()).unwrap();
    let four = exact::Rational::from(4);
    for sub in cert["sub_boxes"].as_array().unwrap() {
        let (mgl_lo, mgl_hi, p_lo, p_hi) = (r(&sub["lo"][0]), r(&sub["hi"][0]), r(&sub["lo"][1]), r(&sub["hi"][1]));
        match sub["verdict"].as_str().unwrap() {
            "stable" => assert!(&p_lo * &p_lo > &four * &mgl_hi, "{sub}"),
            "linearly_unstable" => assert!(&p_hi * &p_hi < &four * &mgl_lo, "{sub}"),
            // the band along the curve: sides of 1/128 of the box's, under 1%
            _ => {
                assert!((&p_hi - &p_lo) * exact::Rational::from(100) <= exact::Rational::from(2), "{sub}");
                assert!((&mgl_hi - &mgl_lo) * exact::Rational::from(100) <= exact::Rational::from(1), "{sub}");
            }
        }
    }
}

/// The fluctuating-gravity top with a corner near `p^2 = 4 mgl`: the
/// closed form's sup at (mgl, p) = (1, 201/100) is `0.36 / 0.0401 =
/// 8.9776`; with depth to spare, the bisection and the tightening bring
/// the proved bound within the default 1% of it.
#[test]
fn the_sup_near_the_stability_boundary_is_tight() {
    let mut v = fixture("lagrange-top-fluctuating-gravity.json");
    v["box"] = json!({"parameters": {"p": ["201/100", "3"], "mgl": ["1/2", "1"]}, "max_depth": 24});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "stable", "{}", cert["reason"]);
    let truth = 0.36 / (2.01f64 * 2.01 - 4.0);
    assert!((truth - 8.977556).abs() < 1e-6);
    let sup = cert["sup_sigma2"].as_f64().unwrap();
    assert!(sup >= truth && sup <= truth * 1.01, "{sup} against {truth}");
    assert_eq!(cert["sampled_max"]["at"], json!(["1", "201/100"]));
    assert!(spec::check_certificate_value(&cert).is_ok());
}

/// `Sigma^2 <= S` fails when `S` is edited below the truth by 1e-7, and
/// any change to the partition, a choice or a derived number fails too.
#[test]
fn an_edited_box_certificate_fails_its_check() {
    let cert = certify(rigid_body_box(["3/2", "5/2"], ["4/5", "6/5"]));
    let truth = exact::parse_number("1.1475").unwrap();
    type Edit = Box<dyn Fn(&mut Value)>;
    let edits: Vec<(&str, Edit)> = vec![
        (
            "S below the sup by 1e-7",
            Box::new(move |c| {
                let s = &truth * &exact::parse_number("0.9999999").unwrap();
                c["sub_boxes"][0]["sigma2_upper"] = json!(s.to_string());
                c["sup_sigma2_exact"] = json!(s.to_string());
                c["sup_sigma2"] = json!(exact::rational_to_f64_up(&s));
            }),
        ),
        ("sup edited", Box::new(|c| c["sup_sigma2_exact"] = json!("1"))),
        ("sign flipped", Box::new(|c| c["sub_boxes"][0]["sign"] = json!(-1))),
        ("verdict", Box::new(|c| c["verdict"] = json!("partly_stable"))),
        ("a side shrunk", Box::new(|c| c["sub_boxes"][0]["hi"][0] = json!("12/5"))),
        ("the box widened", Box::new(|c| c["spec"]["box"]["parameters"]["I2"][1] = json!("3"))),
        ("an undecided remainder hidden", Box::new(|c| c["undecided_fraction"] = json!(0.5))),
        ("stable called unstable", Box::new(|c| c["sub_boxes"][0]["verdict"] = json!("linearly_unstable"))),
        // a solved multiplier (-1/I1 = -1/3) is not an input of the proof,
        // but a number the certificate states: found by the fuzzer
        ("a solved multiplier by 1e-7", Box::new(|c| c["sub_boxes"][0]["multipliers"][0] = json!("-3333333/10000000"))),
    ];
    for (what, edit) in edits {
        let mut c = cert.clone();
        edit(&mut c);
        assert!(spec::check_certificate_value(&c).is_err(), "{what}: accepted");
    }
    // through the CLI: exit 1
    let dir = std::env::temp_dir().join(format!("boxes-tamper-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("edited.cert.json");
    let mut c = cert.clone();
    c["sub_boxes"][0]["sign"] = json!(-1);
    std::fs::write(&path, c.to_string()).unwrap();
    let out = verify(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A box about the intermediate axis is `linearly_unstable` throughout;
/// its unstable sub-box called stable, or the criterion edited, fails.
#[test]
fn a_box_about_the_intermediate_axis_is_linearly_unstable() {
    let mut v = fixture("rigid-body-intermediate-axis.json");
    // I = (2, 3, 1): I2 in [5/2, 7/2] stays above I1 = 2
    v["box"] = json!({"parameters": {"I2": ["5/2", "7/2"]}});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "linearly_unstable", "{}", cert["reason"]);
    assert_eq!(cert["unstable_fraction"], 1.0);
    assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::LinearlyUnstable);
    let mut forged = cert.clone();
    forged["sub_boxes"][0]["verdict"] = json!("undecided");
    assert!(spec::check_certificate_value(&forged).is_err());
    let mut forged = cert.clone();
    forged["sub_boxes"][0]["reason"] = json!("by inspection");
    assert!(spec::check_certificate_value(&forged).is_err());
    // across I2 = I1 = 2 no sub-box is unstable at I2 <= 2
    let mut v = fixture("rigid-body-intermediate-axis.json");
    v["box"] = json!({"parameters": {"I2": ["1", "3"]}, "max_depth": 6});
    let cert = certify(v);
    for sub in cert["sub_boxes"].as_array().unwrap() {
        if sub["verdict"] == "linearly_unstable" {
            assert!(q(sub["lo"][0].as_str().unwrap()) > 2.0, "{sub}");
        }
    }
}

/// `partly_unstable`: the rigid body (I = (3, I2, 1)) for I2 in [3, 4],
/// from the degenerate I2 = I1 (no sub-box touching it is proved) to the
/// intermediate axis (proved unstable); nothing is stable.
#[test]
fn a_box_from_i2_equal_i1_upwards_is_partly_unstable() {
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["I2"] = json!(4);
    v["box"] = json!({"parameters": {"I2": ["3", "4"]}, "max_depth": 6});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "partly_unstable", "{}", cert["reason"]);
    // depth 6 halves the side 6 times: the sub-box [3, 3 + 1/64] stays undecided
    assert_eq!(cert["undecided_fraction"], 1.0 / 64.0);
    assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Inconclusive);
}

/// The closed sub-box `sub` (one parameter) as `(lo, hi)`.
fn side(sub: &Value) -> (f64, f64) {
    (q(sub["lo"][0].as_str().unwrap()), q(sub["hi"][0].as_str().unwrap()))
}

/// A residual that vanishes at one parameter of the box: the verdict is
/// about part of the box, never stated for all of it from one witness (a
/// box certificate once said `not_an_equilibrium (for every parameter in
/// the box)` for `mu_e = (1, I2 - 2, 0)` on `I2` in [3/2, 5/2], where
/// `I2 = 2`, the spec's own value, is a stable equilibrium). The residual
/// `Pi x Omega` at `(1, I2 - 2, 0)` has third component
/// `(I2 - 2) (1/I1 - 1/I2)`, zero only at `I2 = 2` in the box (I1 = 3):
/// every sub-box proved is off `I2 = 2`, every undecided one touches it.
#[test]
fn a_box_verdict_is_never_stated_for_the_whole_box_from_one_witness() {
    let mut v = fixture("rigid-body-major-axis.json");
    v["equilibrium"] = json!([1, "I2-2", 0]);
    v["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    let cert = certify(v.clone());
    assert_eq!(cert["verdict"], "partly_not_an_equilibrium", "{}", cert["reason"]);
    let reason = cert["reason"].as_str().unwrap();
    assert!(
        reason.contains("nothing is claimed on the other") && !reason.contains("every parameter in the box"),
        "{reason}"
    );
    let (mut proved, mut open) = (0, 0);
    for sub in cert["sub_boxes"].as_array().unwrap() {
        let (lo, hi) = side(sub);
        match sub["verdict"].as_str().unwrap() {
            "not_an_equilibrium" => {
                assert!(lo > 2.0 || hi < 2.0, "proved across I2 = 2: {sub}");
                proved += 1;
            }
            "undecided" => {
                assert!(lo <= 2.0 && 2.0 <= hi, "undecided away from I2 = 2: {sub}");
                open += 1;
            }
            other => panic!("{other}: {sub}"),
        }
    }
    // depth 12 by default: the two sub-boxes touching I2 = 2 are 2^-12 of
    // the box each
    assert_eq!((open, cert["undecided_fraction"].as_f64().unwrap()), (2, 2.0 / 4096.0));
    assert_eq!(cert["excluded_fraction"].as_f64().unwrap(), 1.0 - 2.0 / 4096.0);
    assert_eq!(cert["limit"], "max_depth");
    assert!(proved > 0);
    // check names nothing for the spec's own point, which is stable
    assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Inconclusive);
    let own = spec::certify_lie(&spec::spec_from_value(fixture("rigid-body-major-axis.json")).unwrap());
    let mut at_own = v.clone();
    at_own.as_object_mut().unwrap().remove("box");
    assert_eq!(spec::certify_lie(&spec::spec_from_value(at_own).unwrap()).analysis.verdict, own.analysis.verdict);
    // forged: the whole box called not an equilibrium; an undecided
    // sub-box (it holds I2 = 2) called proved; the reason replaced
    let mut forged = cert.clone();
    forged["verdict"] = json!("not_an_equilibrium");
    assert!(spec::check_certificate_value(&forged).is_err());
    let mut forged = cert.clone();
    let k = cert["sub_boxes"].as_array().unwrap().iter().position(|s| s["verdict"] == "undecided").unwrap();
    forged["sub_boxes"][k]["verdict"] = json!("not_an_equilibrium");
    forged["sub_boxes"][k]["reason"] = cert["sub_boxes"][0]["reason"].clone();
    assert!(spec::check_certificate_value(&forged).is_err());
    let mut forged = cert.clone();
    forged["reason"] = json!(
        "ad*_{Dh(mu_e)} mu_e is proved nonzero on every sub-box: mu_e is an equilibrium for no parameter in the box"
    );
    assert!(spec::check_certificate_value(&forged).is_err());

    // The same residual on a box that misses its zeros I2 = 2 and I2 = I1
    // = 3: not an equilibrium for every parameter, and the spec's own
    // point agrees.
    let mut v = fixture("rigid-body-major-axis.json");
    v["equilibrium"] = json!([1, "I2-2", 0]);
    v["parameters"]["I2"] = json!("5/2");
    v["box"] = json!({"parameters": {"I2": ["9/4", "11/4"]}});
    let cert = certify(v.clone());
    assert_eq!(cert["verdict"], "not_an_equilibrium", "{}", cert["reason"]);
    assert_eq!(cert["excluded_fraction"], 1.0);
    assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::NotAnEquilibrium);
    v.as_object_mut().unwrap().remove("box");
    assert_eq!(spec::certify_lie(&spec::spec_from_value(v).unwrap()).analysis.verdict, spec::Verdict::NotAnEquilibrium);

    // Noise (sigma, I2 - 2, 0) keeps (1, 0, 0) only at I2 = 2.
    let mut v = fixture("rigid-body-major-axis.json");
    v["noise"] = json!([["sigma", "I2-2", 0]]);
    v["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "partly_noise_incompatible", "{}", cert["reason"]);
    for sub in cert["sub_boxes"].as_array().unwrap() {
        let (lo, hi) = side(sub);
        assert_eq!(sub["verdict"] == "undecided", lo <= 2.0 && 2.0 <= hi, "{sub}");
    }
    assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Inconclusive);
    let mut forged = cert.clone();
    forged["verdict"] = json!("noise_incompatible");
    assert!(spec::check_certificate_value(&forged).is_err());

    // A zero at a corner of the box (e = 0 in [0, 1/10]).
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["e"] = json!(0);
    v["equilibrium"] = json!([1, "e", 0]);
    v["box"] = json!({"parameters": {"e": ["0", "1/10"]}});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "partly_not_an_equilibrium", "{}", cert["reason"]);
    assert_eq!(cert["undecided_fraction"].as_f64().unwrap(), 1.0 / 4096.0);
    assert!(spec::check_certificate_value(&cert).is_ok());
}

/// What `check` reports under the spec's name holds for the spec itself:
/// for every box certificate here whose verdict covers the whole box, the
/// pointwise pipeline at the spec's own values (a point of the box) gives
/// the same verdict, and a stable one a `Sigma^2` within the box's bound.
#[test]
fn what_check_reports_under_the_spec_name_holds_for_the_spec_itself() {
    let mut certs: Vec<Value> =
        ["rigid-body-inertia-box", "lagrange-top-fluctuating-gravity-box", "lagrange-top-stability-map"]
            .iter()
            .map(|n| fixture(&format!("boxes/{n}.cert.json")))
            .collect();
    let mut intermediate = fixture("rigid-body-intermediate-axis.json");
    intermediate["box"] = json!({"parameters": {"I2": ["5/2", "7/2"]}});
    certs.push(certify(intermediate));
    let mut nowhere = fixture("rigid-body-major-axis.json");
    nowhere["equilibrium"] = json!([1, 1, 0]);
    nowhere["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    certs.push(certify(nowhere));
    let mut moved = fixture("rigid-body-major-axis.json");
    moved["noise"] = json!([["sigma", "I2", 0]]);
    moved["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    certs.push(certify(moved));
    let mut seen = std::collections::BTreeSet::new();
    for cert in &certs {
        let report = spec::check_certificate_value(cert).unwrap();
        let mut own = cert["spec"].clone();
        own.as_object_mut().unwrap().remove("box");
        let point = spec::certify_lie(&spec::spec_from_value(own).unwrap());
        seen.insert(format!("{:?}", report.verdict));
        if report.verdict == spec::Verdict::Inconclusive {
            continue;
        }
        assert_eq!(point.analysis.verdict, report.verdict, "{}", cert["name"]);
        if let Some(s) = report.sigma2 {
            assert!(point.analysis.sigma2().unwrap() <= s, "{}", cert["name"]);
        }
    }
    // every whole-box verdict was tried
    for v in ["Stable", "LinearlyUnstable", "NotAnEquilibrium", "NoiseIncompatible", "Inconclusive"] {
        assert!(seen.contains(v), "{v} not tried: {seen:?}");
    }
}

/// A Casimir that is one only at the spec's value of a box parameter: the
/// box is undecided with the reason, not certified.
#[test]
fn a_casimir_that_depends_on_a_box_parameter_is_not_trusted() {
    let mut v = fixture("rigid-body-major-axis.json");
    v["casimirs"] = json!(["(Pi1^2 + Pi2^2 + Pi3^2)/2 + (I2 - 2)*Pi1"]);
    v["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "undecided");
    assert!(cert["reason"].as_str().unwrap().contains("not a Casimir for every parameter"), "{}", cert["reason"]);
}

/// The verdict and the sup do not depend on the scale or sign of the
/// Casimir (random rescalings), and two runs write the same bytes.
#[test]
fn rescaled_casimirs_give_the_same_box_and_runs_repeat() {
    let base = certify(rigid_body_box(["3/2", "5/2"], ["4/5", "6/5"]));
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..4 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let k = (state % 2000) as i64 - 1000;
        let k = if k == 0 { 7 } else { k };
        let d = 1 + (state >> 20) % 97;
        let mut v = rigid_body_box(["3/2", "5/2"], ["4/5", "6/5"]);
        v["casimirs"] = json!([format!("({k}/{d})*(Pi1^2 + Pi2^2 + Pi3^2)")]);
        let c = certify(v);
        assert_eq!(c["verdict"], base["verdict"], "k = {k}/{d}");
        assert_eq!(c["sup_sigma2_exact"], base["sup_sigma2_exact"], "k = {k}/{d}");
    }
    // and by 1e6 and 1e-6 exactly
    for k in ["1000000", "1/1000000"] {
        let mut v = rigid_body_box(["3/2", "5/2"], ["4/5", "6/5"]);
        v["casimirs"] = json!([format!("{k}*(Pi1^2 + Pi2^2 + Pi3^2)")]);
        let c = certify(v);
        assert_eq!(c["sup_sigma2_exact"], base["sup_sigma2_exact"], "k = {k}");
    }
    let again = certify(rigid_body_box(["3/2", "5/2"], ["4/5", "6/5"]));
    assert_eq!(spec::to_pretty_json(&again), spec::to_pretty_json(&base));
}

/// Bad input exits 2 and names the field.
#[test]
fn bad_box_input_names_the_field() {
    let spec = "fixtures/rigid-body-major-axis.json";
    for (args, field) in [
        (vec!["--param", "J=1:2"], "$.box.parameters.J"),
        (vec!["--param", "I2=3:2"], "$.box.parameters.I2"),
        (vec!["--param", "I2=1:1"], "$.box.parameters.I2"),
        (vec!["--param", "I2=a:2"], "$.box.parameters.I2"),
        (vec!["--param", "I2=1:2", "--max-depth", "41"], "$.box.max_depth"),
        (vec!["--param", "I2=1:2", "--max-boxes", "0"], "$.box.max_boxes"),
    ] {
        let mut all = vec!["certify-box", spec];
        all.extend(args.iter().copied());
        let out = verify(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(field), "{args:?}: {err}");
    }
    let out = verify(&["certify-box", spec, "--param", "I2"]);
    assert_eq!(out.status.code(), Some(2));
    let out = verify(&["certify-box", "fixtures/fluids/channel-sin-walls.json", "--param", "a=1:2"]);
    assert_eq!(out.status.code(), Some(2));
    // a spec's own box section: the same checks
    let mut v = fixture("rigid-body-major-axis.json");
    v["box"] = json!({"parameters": {"I2": ["2", "1"]}});
    assert_eq!(spec::spec_from_value(v).unwrap_err().path, "$.box.parameters.I2");
    let mut v = fixture("rigid-body-major-axis.json");
    v["box"] = json!({"parameters": {"I2": ["1", "2"]}, "margin": "0"});
    assert_eq!(spec::spec_from_value(v).unwrap_err().path, "$.box.margin");
    let mut v = fixture("rigid-body-major-axis.json");
    v["box"] = json!({"parameters": {"I2": ["1", "2"]}, "sup_tolerance": -1});
    assert_eq!(spec::spec_from_value(v).unwrap_err().path, "$.box.sup_tolerance");
}

/// The review's cases: the spec's own value must lie in its box (the CLI
/// moves it to the centre); a divisor that cancels (`q/q`) still makes the
/// system undefined where it vanishes; a sub-box is never proved where
/// the system is undefined; a refused system's `undecided` certificate checks; at most
/// 8 box parameters.
#[test]
fn a_box_is_about_its_spec_and_never_where_it_is_undefined() {
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["I2"] = json!(4);
    v["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    let err = spec::spec_from_value(v).unwrap_err();
    assert_eq!(err.path, "$.box.parameters.I2");
    assert!(err.message.contains("outside"), "{err}");
    let dir = std::env::temp_dir().join(format!("boxes-own-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rb.json");
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["I2"] = json!(4);
    std::fs::write(&path, v.to_string()).unwrap();
    let out = verify(&["certify-box", path.to_str().unwrap(), "--param", "I2=3/2:5/2"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cert: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(cert["spec"]["parameters"]["I2"], "2");
    // named after the move: check reports under this name what holds for it
    assert_eq!(cert["name"], "rigid-body-major-axis (I2 = 2)");
    assert!(String::from_utf8_lossy(&out.stderr).contains("note: I2 = 4 lies outside"));
    std::fs::remove_dir_all(&dir).unwrap();

    // sigma*q/q is sigma except at q = 0, where the spec divides by zero
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["q"] = json!("1/2");
    v["noise"] = json!([["sigma*q/q", 0, 0]]);
    v["box"] = json!({"parameters": {"q": ["-1", "1"]}, "max_depth": 6});
    let cert = certify(v);
    assert_ne!(cert["verdict"], "stable");
    for sub in cert["sub_boxes"].as_array().unwrap() {
        if sub["verdict"] == "stable" {
            let (lo, hi) = (q(sub["lo"][0].as_str().unwrap()), q(sub["hi"][0].as_str().unwrap()));
            assert!(lo > 0.0 || hi < 0.0, "a stable sub-box contains q = 0: {sub}");
        }
    }
    // not an equilibrium (mu_e = (1, 1, 0)); the noise is undefined at I2 = 2
    let mut v = fixture("rigid-body-major-axis.json");
    v["equilibrium"] = json!([1, 1, 0]);
    v["noise"] = json!([["sigma/(I2 - 2)", 0, 0]]);
    v["parameters"]["I2"] = json!("9/4");
    v["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "partly_not_an_equilibrium", "{}", cert["reason"]);
    for sub in cert["sub_boxes"].as_array().unwrap() {
        let (lo, hi) = side(sub);
        assert_eq!(sub["verdict"] == "undecided", lo <= 2.0 && 2.0 <= hi, "{sub}");
    }
    assert!(spec::check_certificate_value(&cert).is_ok());
    // a sub-box across I2 = 2, where the system is undefined, called proved
    let mut forged = cert.clone();
    let k = cert["sub_boxes"].as_array().unwrap().iter().position(|s| s["verdict"] == "undecided").unwrap();
    forged["sub_boxes"][k]["verdict"] = json!("not_an_equilibrium");
    forged["sub_boxes"][k]["reason"] = cert["sub_boxes"][0]["reason"].clone();
    assert!(spec::check_certificate_value(&forged).is_err());

    // a refused system: undecided, and that certificate checks
    let mut v = fixture("rigid-body-major-axis.json");
    v["casimirs"] = json!(["(Pi1^2 + Pi2^2 + Pi3^2)/2 + (I2 - 2)*Pi1"]);
    v["box"] = json!({"parameters": {"I2": ["3/2", "5/2"]}});
    let cert = certify(v);
    assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Inconclusive);
    let mut forged = cert.clone();
    forged["verdict"] = json!("stable");
    assert!(spec::check_certificate_value(&forged).is_err());

    // nine box parameters
    let mut v = fixture("rigid-body-major-axis.json");
    let mut sides = serde_json::Map::new();
    for k in 0..9 {
        v["parameters"][format!("d{k}")] = json!(0);
        sides.insert(format!("d{k}"), json!(["-1", "1"]));
    }
    v["box"] = json!({ "parameters": sides });
    assert_eq!(spec::spec_from_value(v).unwrap_err().path, "$.box.parameters");
}

/// Boxes at the ends of the doubles. A noise amplitude from 1e-150 to
/// 2e-150 gives `Sigma^2` about 1e-300, certified with a positive bound;
/// from 1e-308 to 2e-308 `Sigma^2` (about 1e-616) has no double, the
/// pointwise engine says `inconclusive` and so nothing is certified (never
/// a bound rounded to 0). A side up to 1e308 (an inertia) is certified
/// exactly, and a box that reaches `I3 = 0` (where `h` is undefined) is
/// never stable there.
#[test]
fn extreme_boxes_stay_exact() {
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["sigma"] = json!("1.5e-150");
    v["box"] = json!({"parameters": {"sigma": ["1e-150", "2e-150"]}});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "stable", "{}", cert["reason"]);
    // Sigma^2 = 3 sigma^2 at I = (3, 2, 1): at most 1.2e-299
    let sup = cert["sup_sigma2"].as_f64().unwrap();
    assert!((1.2e-299..1.3e-299).contains(&sup), "{sup}");
    assert!(spec::check_certificate_value(&cert).is_ok());
    let mut v = fixture("rigid-body-major-axis.json");
    v["parameters"]["sigma"] = json!("1.5e-308");
    v["box"] = json!({"parameters": {"sigma": ["1e-308", "2e-308"]}, "max_depth": 2});
    let cert = certify(v);
    assert_eq!(cert["verdict"], "undecided", "{}", cert["reason"]);
    assert!(cert.get("sup_sigma2").is_none());
    assert!(spec::check_certificate_value(&cert).is_ok());
    let mut v = fixture("rigid-body-major-axis.json");
    v["box"] = json!({"parameters": {"I1": ["3", "1e308"]}, "max_depth": 4});
    let cert = certify(v);
    assert_ne!(cert["verdict"], "undecided", "{}", cert["reason"]);
    assert!(spec::check_certificate_value(&cert).is_ok());
    let mut v = fixture("rigid-body-major-axis.json");
    v["box"] = json!({"parameters": {"I3": ["0", "1"]}, "max_depth": 6});
    let cert = certify(v);
    assert_ne!(cert["verdict"], "stable");
    for sub in cert["sub_boxes"].as_array().unwrap() {
        if sub["verdict"] == "stable" {
            assert_ne!(sub["lo"][0], "0", "a stable sub-box contains I3 = 0");
        }
    }
}

/// `plot-sweep --box`: the map with the sub-boxes under a sweep's points,
/// after checking that every point inside a stable sub-box is stable within
/// its bound; a sweep line edited to contradict the box fails (exit 1).
#[test]
fn plot_sweep_draws_a_box_and_checks_the_points_against_it() {
    let dir = std::env::temp_dir().join(format!("boxes-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lines = dir.join("map.jsonl");
    let out = verify(&[
        "sweep",
        "fixtures/lagrange-top-fast.json",
        "--param",
        "mgl=0.5:1.5:11",
        "--param",
        "p=1:3:11",
        "-o",
        lines.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cert = "fixtures/boxes/lagrange-top-stability-map.cert.json";
    let plot = |lines: &std::path::Path| {
        verify(&[
            "plot-sweep",
            lines.to_str().unwrap(),
            "--spec",
            "fixtures/lagrange-top-fast.json",
            "--box",
            cert,
            "--out",
            dir.join("plots").to_str().unwrap(),
        ])
    };
    let out = plot(&lines);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let said = String::from_utf8_lossy(&out.stderr);
    let inside: usize = said.split("checked; ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(inside > 20, "{said}");
    assert!(dir.join("plots/lagrange-top-fast-map.png").is_file());
    // (mgl, p) = (0.5, 3): deep in a stable sub-box; claim growth there
    let text = std::fs::read_to_string(&lines).unwrap();
    let edited: Vec<String> = text
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            if v["exact_parameters"] == json!({"mgl": "1/2", "p": "3"}) {
                v["sigma2"] = json!(0.5);
            }
            v.to_string()
        })
        .collect();
    let bad = dir.join("edited.jsonl");
    std::fs::write(&bad, edited.join("\n")).unwrap();
    let out = plot(&bad);
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("lies in a stable sub-box"));
    std::fs::remove_dir_all(&dir).unwrap();
}
