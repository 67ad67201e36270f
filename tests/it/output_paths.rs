//! Where the CLI writes, under hostile input: a spec's or certificate's
//! `name` that is a path (`../escape`, `/tmp/abs`, `a/../../b`) never writes
//! outside `--out`; `-o` into a missing directory or onto a directory is bad
//! input (exit 2); a failed write leaves no partial file and keeps the old
//! certificate.

use crate::common;

use common::fixture_path;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn verify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).args(args).output().expect("run verify")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A new empty directory for one test.
fn fresh_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-output-paths-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every file under `dir`, recursively, relative to `dir`.
fn files_under(dir: &Path) -> BTreeSet<PathBuf> {
    let mut out = BTreeSet::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out
}

/// A copy of the JSON file `from` with its `name` replaced, written to `to`.
fn renamed(from: &Path, name: &str, to: &Path) -> PathBuf {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(from).unwrap()).unwrap();
    v["name"] = Value::from(name);
    std::fs::write(to, v.to_string()).unwrap();
    to.to_path_buf()
}

fn names(stem: &str, suffixes: &[&str]) -> BTreeSet<PathBuf> {
    suffixes.iter().map(|s| PathBuf::from(format!("{stem}{s}"))).collect()
}

/// Regression: `simulate`, `plot-fluid`, `plot-sweep` and `sweep --plot`
/// joined the name to the output directory, so `../escape` wrote beside it
/// and `/tmp/abs` wrote to /tmp, with exit status 0. Every file must now be
/// inside the chosen directory, under the sanitised stem, and nothing may
/// appear anywhere else in the parent.
#[test]
fn names_that_are_paths_stay_inside_the_output_directory() {
    let parent = fresh_dir("names");
    let inputs = parent.join("inputs");
    std::fs::create_dir_all(&inputs).unwrap();
    let absolute = format!("/tmp/verify-abs-{}", std::process::id());
    // (name, the stem verify::paths::file_stem gives: every character
    // outside [A-Za-z0-9._-] becomes '_', leading dots are dropped)
    let cases = [
        ("../escape".to_string(), "_escape".to_string()),
        (absolute.clone(), format!("_tmp_verify-abs-{}", std::process::id())),
        ("a/../../b".to_string(), "a_.._.._b".to_string()),
        ("..".to_string(), "unnamed".to_string()),
        ("..\\..\\win".to_string(), "_.._win".to_string()),
    ];
    let mut expected = BTreeSet::new();
    for (k, (name, stem)) in cases.iter().enumerate() {
        let out = parent.join("out").join(k.to_string());
        let out_s = out.to_str().unwrap();
        let rel = |files: BTreeSet<PathBuf>| -> BTreeSet<PathBuf> {
            files.into_iter().map(|f| PathBuf::from("out").join(k.to_string()).join(f)).collect()
        };

        let spec = renamed(&fixture_path("rigid-body-major-axis.json"), name, &inputs.join(format!("sim{k}.json")));
        let o = verify(&[
            "simulate",
            spec.to_str().unwrap(),
            "--paths",
            "40",
            "--t-end",
            "1",
            "--outputs",
            "10",
            "--out",
            out_s,
        ]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        assert!(stderr(&o).contains(&format!("file stem '{stem}'")), "{name}: {}", stderr(&o));
        expected
            .extend(rel(names(stem, &[".json", ".csv", "-density.svg", "-density.png", "-growth.svg", "-growth.png"])));

        let cert = renamed(
            &fixture_path("fluids/channel-sin-walls.cert.json"),
            name,
            &inputs.join(format!("fluid{k}.cert.json")),
        );
        let o = verify(&["plot-fluid", cert.to_str().unwrap(), "--out", out_s]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        // The channel certificate has a per-mode chart and a convergence
        // table (its shift curve has one point, so no shift chart).
        expected.extend(rel(names(stem, &["-modes.svg", "-modes.png", "-convergence.svg", "-convergence.png"])));

        let map_spec =
            renamed(&fixture_path("sweeps/lagrange-top-map.json"), name, &inputs.join(format!("map{k}.json")));
        // sweep --plot draws through the same code; its lines go to -o.
        let plot = out.join("swept");
        let lines = out.join("lines.jsonl");
        let o = verify(&[
            "sweep",
            map_spec.to_str().unwrap(),
            "--param",
            "p=0:4:3",
            "--param",
            "mgl=0:1:2",
            "-o",
            lines.to_str().unwrap(),
            "--plot",
            plot.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        expected.insert(PathBuf::from("out").join(k.to_string()).join("lines.jsonl"));

        // plot-sweep of those lines (the renamed spec's own: it refuses another spec's).
        let o = verify(&["plot-sweep", lines.to_str().unwrap(), "--spec", map_spec.to_str().unwrap(), "--out", out_s]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        expected.extend(rel(names(stem, &["-map.svg", "-map.png"])));
        expected.extend(rel(names(&format!("swept/{stem}"), &["-map.svg", "-map.png"])));
    }
    let inputs_written: BTreeSet<PathBuf> =
        files_under(&inputs).into_iter().map(|f| Path::new("inputs").join(f)).collect();
    let outputs: BTreeSet<PathBuf> = files_under(&parent).difference(&inputs_written).cloned().collect();
    assert_eq!(outputs, expected, "exactly the expected files, all inside --out");
    // Nothing at the absolute path the second name spelled.
    let stray: Vec<_> = std::fs::read_dir("/tmp")
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with(&format!("verify-abs-{}", std::process::id())))
        .collect();
    assert!(stray.is_empty(), "written outside --out: {stray:?}");
    std::fs::remove_dir_all(&parent).unwrap();
}

/// Regression: `-o` into a missing directory exited 1 after the work, as if
/// the engine had failed. It is bad input (exit 2), refused before any work,
/// naming the path; so is `-o` onto a directory, and an output directory
/// (`--out`, `--plot`) that cannot be created because a file is in the way.
#[test]
fn output_paths_that_cannot_be_written_are_bad_input() {
    let dir = fresh_dir("missing");
    let spec = fixture_path("rigid-body-major-axis.json");
    let spec = spec.to_str().unwrap();
    let missing = dir.join("no-such-dir").join("x.json");
    let missing_s = missing.to_str().unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "in the way").unwrap();
    let below_file = file.join("sub");
    let below = below_file.to_str().unwrap();
    let dir_s = dir.to_str().unwrap();
    let lines = dir.join("l.jsonl");
    let sweep = ["sweep", spec, "--param", "I2=1:2:3"];
    // (arguments, the path the message must name, what it must say)
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        (vec!["certify", spec, "-o", missing_s], missing_s, "does not exist"),
        ([&sweep[..], &["-o", missing_s]].concat(), missing_s, "does not exist"),
        (vec!["certify", spec, "-o", dir_s], dir_s, "is a directory"),
        ([&sweep[..], &["-o", dir_s]].concat(), dir_s, "is a directory"),
        (vec!["simulate", spec, "--paths", "10", "--out", below], below, "--out"),
        (vec!["plot-fluid", spec, "--out", below], below, "--out"),
        ([&sweep[..], &["-o", lines.to_str().unwrap(), "--plot", below]].concat(), below, "--plot"),
    ];
    for (args, path, message) in cases {
        let o = verify(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains(message) && err.contains(path), "{args:?}: {err}");
    }
    // Refused before any work: nothing was created (the --plot case is
    // checked before its -o file is opened).
    assert_eq!(files_under(&dir), BTreeSet::from([PathBuf::from("a-file")]));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `verify certify SPEC -o CERT` in a shell whose file-size limit is one
/// block, with SIGXFSZ ignored so that the write fails with EFBIG as a
/// full disk fails with ENOSPC (the signal disposition survives exec).
fn certify_with_tiny_file_limit(spec: &Path, cert: &Path) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("ulimit -f 1; trap '' XFSZ; exec \"$0\" certify \"$1\" -o \"$2\"")
        .arg(env!("CARGO_BIN_EXE_verify"))
        .arg(spec)
        .arg(cert)
        .output()
        .expect("run sh")
}

/// Regression: `certify -o` on a full disk left a 0-byte certificate (the
/// file was truncated, then the write failed). Writes now go to a temporary
/// file renamed into place: a failed write exits 1 with a message naming
/// the file, leaves no partial or temporary file, and keeps an existing
/// certificate byte for byte.
#[test]
fn a_failed_certificate_write_keeps_the_old_certificate() {
    let dir = fresh_dir("atomic");
    let spec = fixture_path("rigid-body-major-axis.json");
    let cert = dir.join("rb.cert.json");
    let o = verify(&["certify", spec.to_str().unwrap(), "-o", cert.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let before = std::fs::read(&cert).unwrap();
    // The certificate (about 4 KB) is larger than the limit (1 block of
    // 512 or 1024 bytes), so the write fails part way.
    assert!(before.len() > 2048, "{} bytes", before.len());

    let o = certify_with_tiny_file_limit(&spec, &cert);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("cannot write") && stderr(&o).contains(cert.to_str().unwrap()), "{}", stderr(&o));
    assert_eq!(std::fs::read(&cert).unwrap(), before, "the existing certificate is unchanged");
    let o = verify(&["check", cert.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "the kept certificate still checks: {}", stderr(&o));

    // A new certificate that fails to write leaves no file at all.
    let fresh = dir.join("new.cert.json");
    let o = certify_with_tiny_file_limit(&spec, &fresh);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(files_under(&dir), BTreeSet::from([PathBuf::from("rb.cert.json")]), "no partial or temporary file");

    // A device is written in place, never replaced: /dev/full fails
    // (ENOSPC) and stays a device.
    if Path::new("/dev/full").exists() {
        let o = verify(&["certify", spec.to_str().unwrap(), "-o", "/dev/full"]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains("/dev/full: cannot write"), "{}", stderr(&o));
        assert!(!std::fs::metadata("/dev/full").unwrap().is_file(), "/dev/full must stay a device");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
