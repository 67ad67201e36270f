//! `verify simulate --shard K/N` and `--merge`: an ensemble split into
//! shards, each run as its own process (as Slurm array tasks would), merges
//! into exactly the outputs of one unsharded run, byte for byte; and the
//! merge refuses what is not exactly that study (another seed or spec, a
//! missing shard, two different copies of one shard, a malformed file).

use crate::common;

use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("verify-shards-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The common options: 1100 paths make 5 blocks of 256 (the last short).
fn options(extra: &[&str]) -> Vec<String> {
    let spec = fixture_path("heavy-top-asymmetric.json");
    let mut v: Vec<String> =
        [spec.to_str().unwrap(), "--paths", "1100", "--dt", "0.02", "--t-end", "4", "--outputs", "40"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    v.extend(extra.iter().map(|s| s.to_string()));
    v
}

fn run(args: &[String], threads: &str) -> Output {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    simulate(&refs, threads)
}

fn shard_files(d: &Path) -> Vec<String> {
    let mut files: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path().to_string_lossy().into_owned())
        .filter(|p| p.contains(".shard-"))
        .collect();
    files.sort();
    files
}

/// Run `count` shards as separate processes into `d`.
fn run_shards(d: &Path, count: u64, extra: &[&str]) {
    for k in 0..count {
        let shard = format!("{k}/{count}");
        let mut args = options(extra);
        args.extend(["--out".into(), d.to_string_lossy().into_owned(), "--shard".into(), shard.clone()]);
        let o = run(&args, "1");
        assert_eq!(o.status.code(), Some(0), "shard {shard}: {}", stderr(&o));
    }
}

fn merge(out: &Path, files: &[String], extra: &[&str]) -> Output {
    let mut args = options(extra);
    args.extend(["--out".into(), out.to_string_lossy().into_owned(), "--merge".into()]);
    args.extend(files.iter().cloned());
    run(&args, "2")
}

/// Three shards (and seven, more shards than blocks, some of them empty)
/// merge into the unsharded run's JSON report, CSV and charts byte for byte
/// (the report's `threads` aside: the merge and the whole run use 2).
#[test]
fn shards_merge_into_exactly_the_unsharded_run() {
    let whole = dir("whole");
    let mut args = options(&[]);
    args.extend(["--out".into(), whole.to_string_lossy().into_owned()]);
    let o = run(&args, "2");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for count in [3u64, 7] {
        let parts = dir(&format!("parts{count}"));
        run_shards(&parts, count, &[]);
        let files = shard_files(&parts);
        assert_eq!(files.len(), count as usize);
        let merged = dir(&format!("merged{count}"));
        let o = merge(&merged, &files, &[]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        for f in [".json", ".csv", "-growth.svg", "-density.svg"] {
            let name = format!("heavy-top-asymmetric{f}");
            let (a, b) = (std::fs::read(whole.join(&name)).unwrap(), std::fs::read(merged.join(&name)).unwrap());
            assert!(a == b, "{count} shards: {name} differs from the unsharded run's");
        }
        // The same shard given twice is harmless.
        let mut twice = files.clone();
        twice.push(files[0].clone());
        let again = dir(&format!("again{count}"));
        let o = merge(&again, &twice, &[]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    // The report is a real ensemble of 1100 paths of both ensembles.
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("heavy-top-asymmetric.json")).unwrap()).unwrap();
    assert_eq!(report["parameters"]["paths"], 1100);
    let counts = report["histogram"]["counts"].as_array().unwrap();
    // Every path lands in the histogram at t = 0 (all start at one point).
    assert_eq!(counts[0].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).sum::<u64>(), 1100);
}

/// What is not exactly the study is refused: a missing shard and a shard of
/// another seed or split (exit 1, naming what differs), two different
/// copies of one shard (exit 1), a malformed or edited file (exit 2, naming
/// the JSON path), and a bad `--shard` (exit 2).
#[test]
fn the_merge_refuses_what_is_not_the_study() {
    let parts = dir("refuse-parts");
    run_shards(&parts, 3, &[]);
    let files = shard_files(&parts);
    let out = dir("refuse-out");

    let o = merge(&out, &files[..2], &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("incomplete: 1 of the 3 shards are missing (2)"), "{}", stderr(&o));

    // The merge is asked for another seed than the shards ran with.
    let o = merge(&out, &files, &["--seed", "2"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("$.study.seed"), "{}", stderr(&o));

    // A shard of another seed among the others.
    let other = dir("refuse-other");
    run_shards(&other, 3, &["--seed", "2"]);
    let mut mixed = files[..2].to_vec();
    mixed.push(shard_files(&other)[2].clone());
    let o = merge(&out, &mixed, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("$.study.seed"), "{}", stderr(&o));

    // A shard of another split.
    let split = dir("refuse-split");
    run_shards(&split, 2, &[]);
    let mut mixed = files[..2].to_vec();
    mixed.push(shard_files(&split)[1].clone());
    let o = merge(&out, &mixed, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("shards of different splits do not merge"), "{}", stderr(&o));

    // Shard 0 edited: one exact sum changed by one unit in the last place of
    // its numerator, so the two copies of shard 0 disagree.
    let text = std::fs::read_to_string(&files[0]).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    let sum = v["shard"]["nonlinear"]["norm_sum"][5].as_str().unwrap().to_string();
    let (p, q) = sum.split_once('/').unwrap();
    // The numerator is odd (the fraction is reduced, q a power of two):
    // another odd last digit keeps it a valid, different, exact sum.
    let last = p.chars().last().unwrap().to_digit(10).unwrap();
    let p = format!("{}{}", &p[..p.len() - 1], (last + 2) % 10);
    v["shard"]["nonlinear"]["norm_sum"][5] = Value::from(format!("{p}/{q}"));
    let edited = parts.join("edited.json");
    std::fs::write(&edited, v.to_string()).unwrap();
    let mut both = files.clone();
    both.push(edited.to_string_lossy().into_owned());
    let o = merge(&out, &both, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("shard 0 of 3 is given twice with different numbers"), "{}", stderr(&o));

    // Malformed: not an exact sum of doubles, a wrong path count, not JSON.
    for (what, edit, expected) in [
        ("a third", Value::from("1/3"), "$.shard.nonlinear.norm_sum[5]"),
        ("a float", Value::from(0.5), "$.shard.nonlinear.norm_sum[5]"),
    ] {
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v["shard"]["nonlinear"]["norm_sum"][5] = edit;
        let bad = parts.join("bad.json");
        std::fs::write(&bad, v.to_string()).unwrap();
        let o = merge(&out, &[bad.to_string_lossy().into_owned()], &[]);
        assert_eq!(o.status.code(), Some(2), "{what}: {}", stderr(&o));
        assert!(stderr(&o).contains(expected), "{what}: {}", stderr(&o));
    }
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["shard"]["nonlinear"]["paths"] = Value::from(5000);
    let bad = parts.join("bad-paths.json");
    std::fs::write(&bad, v.to_string()).unwrap();
    let o = merge(&out, &[bad.to_string_lossy().into_owned()], &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("$.shard.nonlinear.paths"), "{}", stderr(&o));
    let truncated = parts.join("truncated.json");
    std::fs::write(&truncated, &text[..text.len() / 2]).unwrap();
    let o = merge(&out, &[truncated.to_string_lossy().into_owned()], &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not JSON"), "{}", stderr(&o));

    // Counts above the paths summed (a merge would overflow or report an
    // exceedance above 1).
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["shard"]["nonlinear"]["histogram"][0][0] = Value::from(u64::MAX);
    let bad = parts.join("bad-counts.json");
    std::fs::write(&bad, v.to_string()).unwrap();
    let o = merge(&out, &[bad.to_string_lossy().into_owned()], &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("$.shard.nonlinear.histogram[0]"), "{}", stderr(&o));

    // Another histogram range (the pilot of another engine): not added.
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&files[2]).unwrap()).unwrap();
    let lo = v["shard"]["histogram_range"][0].as_f64().unwrap();
    v["shard"]["histogram_range"][0] = Value::from(lo - 1e-9);
    let moved = parts.join("moved-range.json");
    std::fs::write(&moved, v.to_string()).unwrap();
    let mut mixed = files[..2].to_vec();
    mixed.push(moved.to_string_lossy().into_owned());
    let o = merge(&out, &mixed, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("$.shard.histogram_range"), "{}", stderr(&o));

    // A shard written by another engine version.
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["engine"] = Value::from("0.0.1");
    let old = parts.join("old-engine.json");
    std::fs::write(&old, v.to_string()).unwrap();
    let o = merge(&out, &[old.to_string_lossy().into_owned()], &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("$.engine"), "{}", stderr(&o));

    // A split into 10^18 shards: shard 0 has no paths; the merge counts the
    // missing ones instead of listing them all (it used to loop 10^18 times).
    let huge = dir("refuse-huge");
    let mut args = options(&["--shard", "0/1000000000000000000"]);
    args.extend(["--out".into(), huge.to_string_lossy().into_owned()]);
    let o = run(&args, "1");
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = merge(&out, &shard_files(&huge), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("incomplete: 999999999999999999 of the 1000000000000000000 shards are missing (1, 2, 3"),
        "{}",
        stderr(&o)
    );

    for shard in ["3/3", "1/0", "x", "1/2/3"] {
        let mut args = options(&["--shard", shard]);
        args.extend(["--out".into(), out.to_string_lossy().into_owned()]);
        let o = run(&args, "1");
        assert_eq!(o.status.code(), Some(2), "--shard {shard}: {}", stderr(&o));
        assert!(stderr(&o).contains("--shard"), "--shard {shard}: {}", stderr(&o));
    }
}
