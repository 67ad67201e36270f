//! Progress and cancellation of the long pipelines (fluids, the Zeitlin
//! model, large systems) through the spec API that `verify certify` and the
//! Python package call: counting changes no result, the counts only grow
//! and end at the total, and a cancelled run returns no certificate.

use outcome::Progress;
use spec::{AnySpec, CheckError};
use std::path::Path;
use std::time::Duration;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn load(rel: &str) -> AnySpec {
    let path = Path::new(ROOT).join(rel);
    let text = std::fs::read_to_string(&path).unwrap();
    spec::parse(&text, &spec::Options::relative_to(path.parent())).unwrap()
}

/// One spec of each long pipeline: an incompressible fluid, the
/// compressible generator (compatible noise), a zonal Zeitlin state, a
/// tilted one (the general pipeline), one zonal in no frame (the
/// matrix-free analysis), a large system.
const LONG: [&str; 6] = [
    "fixtures/fluids/tanh-mixing-layer.json",
    "fixtures/fluids/compressible-compatible-noise.json",
    "fixtures/zeitlin/energy-casimir-n32.json",
    "fixtures/zeitlin/tilted-energy-casimir-n32.json",
    "fixtures/zeitlin/rossby-haurwitz-l3-n64.json",
    "fixtures/large/chain-30.json",
];

/// The certificate with progress is the one without, byte for byte; the
/// counts polled from another thread never decrease nor pass the total,
/// and end at it.
#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn counting_changes_nothing_and_ends_at_the_total() {
    for rel in LONG {
        let spec = load(rel);
        let plain = spec::certify(&spec, &spec::Options::default()).unwrap().into_json();
        let progress = Progress::new();
        let mut seen = vec![];
        let counted = std::thread::scope(|s| {
            let worker = s.spawn(|| {
                spec::certify(&spec, &spec::Options::default().with_progress(&progress))
                    .map(spec::AnyCertificate::into_json)
            });
            while !worker.is_finished() {
                seen.push(progress.snapshot());
                std::thread::sleep(Duration::from_micros(200));
            }
            worker.join().unwrap()
        });
        assert_eq!(counted.as_ref(), Ok(&plain), "{rel}");
        let (done, total) = progress.snapshot();
        assert!(total > 1 && done == total, "{rel}: {done} of {total}");
        seen.push((done, total));
        for w in seen.windows(2) {
            assert!(w[0].0 <= w[1].0 && w[1].0 <= w[1].1, "{rel}: {:?} then {:?}", w[0], w[1]);
        }
    }
}

/// Cancelled before it starts: every pipeline returns at once with no
/// certificate, and so does the check of its certificate.
#[test]
#[ignore = "heavy: run by CI's heavy stage (VERIFY_HEAVY_TESTS=1 ... -- --include-ignored)"]
fn cancelled_before_the_start_gives_no_certificate() {
    for rel in LONG {
        let spec = load(rel);
        let cert = spec::certify(&spec, &spec::Options::default()).unwrap().to_pretty_json();
        let progress = Progress::new();
        progress.cancel();
        assert_eq!(
            spec::certify(&spec, &spec::Options::default().with_progress(&progress))
                .map(spec::AnyCertificate::into_json),
            Err(spec::CertifyError::Cancelled),
            "{rel}"
        );
        let base = Path::new(ROOT).join(rel);
        assert_eq!(
            spec::check_json(&cert, &spec::Options::relative_to(base.parent()).with_progress(&progress)),
            Err(CheckError::Cancelled),
            "{rel}"
        );
        // Not cancelled: the same check passes.
        assert!(spec::check_json(&cert, &spec::Options::relative_to(base.parent())).is_ok(), "{rel}");
    }
}

/// Cancelled part way through (as soon as the first step is counted): a
/// run that had not reached its total when the cancel came returns no
/// certificate. The Zeitlin energy search at N = 256 takes about 0.4 s in
/// release builds (far longer here), the 32-mode fluid some seconds.
#[test]
fn cancelled_part_way_gives_no_certificate() {
    let zeitlin = r#"{"name": "z", "zeitlin": {"N": 256, "equilibrium": "z + 0.3*z^3", "noise": ["0.1*z^2"]},
        "settings": {"casimir_momentum": false}}"#;
    for spec in [spec::parse_any_spec(zeitlin).unwrap(), load("bench/cubic-walls.json")] {
        let progress = Progress::new();
        let (out, at_cancel) = std::thread::scope(|s| {
            let worker = s.spawn(|| {
                spec::certify(&spec, &spec::Options::default().with_progress(&progress))
                    .map(spec::AnyCertificate::into_json)
            });
            while progress.snapshot().0 == 0 && !worker.is_finished() {
                std::thread::sleep(Duration::from_micros(100));
            }
            let at_cancel = progress.snapshot();
            progress.cancel();
            (worker.join().unwrap(), at_cancel)
        });
        assert!(at_cancel.0 < at_cancel.1, "the run was under way: {at_cancel:?}");
        assert_eq!(out, Err(spec::CertifyError::Cancelled));
    }
}
