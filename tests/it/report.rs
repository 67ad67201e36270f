//! `verify report`: one self-contained HTML page for certificates. Every
//! fixture certificate is in it with its verdict; nothing is fetched; every
//! string from a certificate is escaped; a certificate that fails its
//! re-check is marked and makes the exit status 1; a spec is refused
//! (exit 2). The page in a real browser: `tests/browser/report.sh` (run by
//! `./test.sh`).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn verify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).args(args).output().expect("run verify")
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn certificates(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            certificates(&p, out);
        } else if p.to_string_lossy().ends_with(".cert.json") {
            out.push(p);
        }
    }
}

/// Nothing in the page makes a browser fetch anything.
fn assert_self_contained(html: &str) {
    // (Data is escaped, so `src="` cannot come from a certificate's text.)
    for pattern in ["<script", "<link", "<img", "<iframe", "@import", "url(", "src=\"", "href=\""] {
        assert!(!html.contains(pattern), "the page contains {pattern:?}");
    }
}

#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn every_fixture_certificate_in_one_self_contained_page() {
    let mut certs = vec![];
    certificates(&Path::new(ROOT).join("fixtures"), &mut certs);
    assert!(certs.len() >= 30, "{}", certs.len());
    let out = temp_dir().join("all.html");
    let mut args: Vec<String> = vec!["report".into()];
    args.extend(certs.iter().map(|p| p.display().to_string()));
    args.extend(["-o".into(), out.display().to_string()]);
    let o = verify(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(&out).unwrap();
    assert_self_contained(&html);
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    assert_eq!(html.matches("<section>").count(), certs.len());
    assert!(!html.contains("Re-check FAILED"));
    for p in &certs {
        let cert: Value = serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
        let name = cert["name"].as_str().unwrap();
        assert!(html.contains(&format!("<h2>{name}</h2>")), "{name}");
    }
    // A fluid certificate's three charts and every stable one's guarantee are inline SVG.
    assert!(html.matches("<svg").count() >= 20, "{}", html.matches("<svg").count());
    assert!(html.contains("Sigma^2 per x-mode") && html.contains("the guarantee over time"));
}

#[test]
fn strings_from_a_certificate_are_escaped_and_a_failed_check_is_marked() {
    let text = std::fs::read_to_string(Path::new(ROOT).join("fixtures/rigid-body-major-axis.cert.json")).unwrap();
    let mut cert: Value = serde_json::from_str(&text).unwrap();
    cert["name"] = Value::from("<script>alert('x')</script> & co");
    cert["reason"] = Value::from("</p><img src=x onerror=alert(1)>");
    let dir = temp_dir();
    let path = dir.join("tampered.cert.json");
    std::fs::write(&path, cert.to_string()).unwrap();
    let out = dir.join("tampered.html");
    let o = verify(&["report", path.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(&out).unwrap();
    assert_self_contained(&html);
    assert!(html.contains("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; co"));
    assert!(html.contains("&lt;/p&gt;&lt;img src=x onerror=alert(1)&gt;"));
    assert!(html.contains("Re-check FAILED"), "the tampered name and reason fail the check");
}

#[test]
fn a_spec_or_bad_json_is_bad_input() {
    let dir = temp_dir();
    let out = dir.join("bad.html");
    let spec = Path::new(ROOT).join("fixtures/rigid-body-major-axis.json");
    let o = verify(&["report", spec.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("not a certificate") && err.contains("verify certify"), "{err}");
    let junk = dir.join("junk.json");
    std::fs::write(&junk, "{\"verdict\": ").unwrap();
    let o = verify(&["report", junk.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists(), "no page for bad input");
}

/// Certificates edited to the ends of the double range (Sigma^2 = 1e308
/// with T = 4.6e-308; Sigma^2 = 1e-308 with T = 1e308, whose chart would
/// span 2e308): the page is still written, each marked as failing its
/// re-check, and the run ends (it once hung drawing the second chart).
#[test]
fn certificates_at_the_ends_of_the_double_range_still_give_a_page() {
    let text = std::fs::read_to_string(Path::new(ROOT).join("fixtures/rigid-body-major-axis.cert.json")).unwrap();
    let dir = temp_dir();
    let mut args = vec!["report".to_string()];
    for (name, sigma2, t) in [("big", 1e308, 4.6e-308), ("tiny", 1e-308, 1e308)] {
        let mut cert: Value = serde_json::from_str(&text).unwrap();
        cert["sigma2"] = Value::from(sigma2);
        cert["stopping"]["T"] = Value::from(t);
        let path = dir.join(format!("{name}.cert.json"));
        std::fs::write(&path, cert.to_string()).unwrap();
        args.push(path.display().to_string());
    }
    let out = dir.join("edges.html");
    args.extend(["-o".into(), out.display().to_string()]);
    let o = verify(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(&out).unwrap();
    assert_eq!(html.matches("Re-check FAILED").count(), 2);
}

/// A box certificate's section said level "none (no claim needs a proof)"
/// for exact proofs, Sigma^2 "-" where `sup_sigma2` is certified,
/// "Inconclusive: nothing is claimed either way" for a `partly_stable` map
/// with hundreds of proved sub-boxes, and only `kind: box` as key numbers.
/// Now: the level is exact, the summary shows the proved sup, the words are
/// the certificate's own statement, and the key numbers hold the box, the
/// sup and where it is approached, the shares, and a map of the sub-boxes
/// (one rectangle each).
#[test]
fn a_box_certificate_reads_as_what_it_proves() {
    let cert_path = Path::new(ROOT).join("fixtures/boxes/lagrange-top-stability-map.cert.json");
    let cert: Value = serde_json::from_str(&std::fs::read_to_string(&cert_path).unwrap()).unwrap();
    let out = temp_dir().join("box.html");
    let o = verify(&["report", cert_path.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(&out).unwrap();
    assert_self_contained(&html);
    assert!(html.contains("level: exact (every claim is proved in exact rational arithmetic)"));
    assert!(!html.contains("no claim needs a proof"));
    assert!(!html.contains("Inconclusive: nothing is claimed"));
    assert!(html.contains("<td>partly_stable</td><td>exact</td><td>0</td>"), "the summary row");
    let statement = cert["theorem"]["statement"].as_str().unwrap();
    assert!(statement.starts_with("Proved (exact), in the box"));
    let escaped = statement
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;");
    assert!(html.contains(&escaped), "the statement, escaped");
    for row in [
        "box: mgl",
        "box: p",
        "sup Sigma^2 over the stable sub-boxes",
        "largest Sigma^2 sampled",
        "share of the box proved stable",
        "share proved linearly unstable",
        "share undecided",
        "bisection stopped by",
    ] {
        assert!(html.contains(row), "{row}");
    }
    // 229 of the 353 sub-boxes are stable: 45.99609% of the box
    assert!(html.contains("<td>45.99609%</td>"));
    let subs = cert["sub_boxes"].as_array().unwrap().len();
    let map_rects = html.matches("stroke=\"#fff\" stroke-width=\"0.4\"").count();
    assert_eq!(map_rects, subs, "one rectangle per sub-box");
}
