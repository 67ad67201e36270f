//! `verify sweep` and `verify plot-sweep` end to end: the Lagrange-top map's
//! boundary against the fast-top threshold, the rigid-body triangle against
//! the closed form, resume after a real kill, shards, random sampling, bad
//! ranges, and the charts.

use crate::common;

use common::fixture_path;
use exact::{parse_number, Rational};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn verify(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_verify")).args(args).output().expect("run verify")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("verify-sweep-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn lines_of(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path).unwrap().lines().map(str::to_string).collect()
}

fn records(path: &Path) -> Vec<Value> {
    lines_of(path).iter().map(|l| serde_json::from_str(l).unwrap()).collect()
}

fn exact_param(r: &Value, name: &str) -> Rational {
    parse_number(r["exact_parameters"][name].as_str().unwrap()).unwrap()
}

fn q(n: i64, d: i64) -> Rational {
    Rational::new(n.into(), d.into())
}

fn sweep_to(spec: &str, out: &Path, extra: &[&str]) -> Output {
    let spec = fixture_path(spec);
    let mut args = vec!["sweep", spec.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    verify(&args)
}

/// The fast-top threshold: every grid point with p^2 > 4 mgl I1 is stable
/// with the closed-form Sigma^2 = 4 sigma^2/(p^2 - 4 mgl I1) (derived in
/// generator::closed_forms), every point below it is linearly unstable, and
/// points exactly on it are inconclusive; so along every row of constant mgl
/// the verdict changes within one grid step of p = 2 sqrt(mgl I1).
#[test]
fn lagrange_map_boundary_is_the_fast_top_threshold() {
    let out = tmp("lagrange.jsonl");
    let o = sweep_to("sweeps/lagrange-top-map.json", &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let recs = records(&out);
    assert_eq!(recs.len(), 41 * 41);
    let i1 = Rational::from_integer(1.into());
    let mut rows: BTreeMap<String, Vec<(f64, &str)>> = BTreeMap::new();
    let mut on_boundary = 0;
    for r in &recs {
        let (p, mgl) = (exact_param(r, "p"), exact_param(r, "mgl"));
        let d = &(&p * &p) - &(&(&q(4, 1) * &mgl) * &i1);
        let verdict = r["verdict"].as_str().unwrap();
        if d.is_positive() {
            assert_eq!(verdict, "stable", "{r}");
            assert_eq!(r["level"], "exact", "{r}");
            let (pf, mf) = (spec::to_f64(&p), spec::to_f64(&mgl));
            let expected = generator::closed_forms::lagrange_top_fluctuating_gravity_sigma2(1.0, mf, pf, 0.3).unwrap();
            let got = r["sigma2"].as_f64().unwrap();
            assert!((got - expected).abs() <= 1e-9 * expected.max(1e-300), "{r}: closed form {expected}");
        } else if d.is_negative() {
            assert_eq!(verdict, "linearly_unstable", "{r}");
            assert_eq!(r["level"], "exact", "{r}");
        } else {
            on_boundary += 1;
            assert_eq!(verdict, "inconclusive", "{r}");
        }
        rows.entry(mgl.to_string()).or_default().push((spec::to_f64(&p), r["verdict"].as_str().unwrap()));
    }
    // p = 0 at mgl = 0 and p = 2 at mgl = 1 lie on the threshold.
    assert_eq!(on_boundary, 2);
    let step = 0.1;
    let mut rows_crossing = 0;
    for (mgl, row) in &rows {
        let mgl: f64 = spec::to_f64(&parse_number(mgl).unwrap());
        let last_unstable =
            row.iter().filter(|(_, v)| *v == "linearly_unstable").map(|(p, _)| *p).fold(f64::NAN, f64::max);
        let first_stable = row.iter().filter(|(_, v)| *v == "stable").map(|(p, _)| *p).fold(f64::NAN, f64::min);
        if mgl <= 0.0 {
            assert!(last_unstable.is_nan(), "mgl = {mgl}: no unstable points expected");
            continue;
        }
        let pc = 2.0 * mgl.sqrt();
        if pc > 4.0 {
            assert!(first_stable.is_nan(), "mgl = {mgl}: threshold {pc} beyond the grid");
            continue;
        }
        rows_crossing += 1;
        assert!(last_unstable < pc && pc < first_stable, "mgl = {mgl}: {last_unstable} < {pc} < {first_stable}");
        assert!(first_stable - last_unstable <= 2.0 * step + 1e-12, "mgl = {mgl}: the change spans more than the grid");
    }
    assert_eq!(rows_crossing, 30, "rows with 0 < mgl <= 3 whose threshold lies in 0 < p <= 4");
}

/// The rigid body over the inertia triangle: stable exactly where e1 is the
/// largest or the smallest axis, with Sigma^2 from the closed form
/// (generator::closed_forms::rigid_body_sigma2), unstable where it is the
/// intermediate axis, inconclusive only on the lines I1 = I2 and I1 = I3.
#[test]
fn rigid_body_triangle_matches_the_closed_form() {
    let out = tmp("triangle.jsonl");
    let o = sweep_to("sweeps/rigid-body-triangle.json", &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let recs = records(&out);
    assert!(recs.len() > 1000);
    let (mut above_paper, mut closed_form_above) = (0, 0);
    for r in &recs {
        let (i1, i2) = (exact_param(r, "I1"), exact_param(r, "I2"));
        let i3 = &(&Rational::from_integer(1.into()) - &i1) - &i2;
        assert!(
            !(&(&i1 + &i2) - &q(1, 2)).is_negative() && !(&i3 - &q(1, 100)).is_negative(),
            "outside the domain: {r}"
        );
        let (a, b, c) = (spec::to_f64(&i1), spec::to_f64(&i2), spec::to_f64(&i3));
        let verdict = r["verdict"].as_str().unwrap();
        if i1 == i2 || i1 == i3 {
            assert_eq!(verdict, "inconclusive", "{r}");
            continue;
        }
        let intermediate = (i1 > i2) != (i1 > i3);
        if intermediate {
            assert_eq!(verdict, "linearly_unstable", "{r}");
        } else {
            assert_eq!(verdict, "stable", "{r}");
            let expected = generator::closed_forms::rigid_body_sigma2(a, b, c, 0.3).unwrap();
            let got = r["sigma2"].as_f64().unwrap();
            assert!((got - expected).abs() <= 1e-9 * expected.max(1e-12), "{r}: closed form {expected}");
            above_paper += usize::from(got > 0.09 * (1.0 + 1e-9));
            closed_form_above += usize::from(expected > 0.09 * (1.0 + 1e-9));
        }
    }
    // The paper's sigma^2 = 0.09 is below the sharp constant on part of the
    // stable set: on exactly the points where the closed form says so.
    assert_eq!(above_paper, closed_form_above);
    assert!(above_paper > 0);
}

fn index_set(path: &Path) -> Vec<u64> {
    let mut v: Vec<u64> = records(path).iter().map(|r| r["index"].as_u64().unwrap()).collect();
    v.sort_unstable();
    v
}

fn line_set(paths: &[&Path]) -> BTreeSet<String> {
    paths.iter().flat_map(|p| lines_of(p)).collect()
}

/// Kill a sweep while it runs (SIGKILL, no chance to clean up), resume it,
/// and get exactly the lines of an uninterrupted run.
#[test]
fn resume_after_a_kill_gives_the_same_lines() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let params = ["--param", "I2=1/10:29/10:200", "--param", "I3=1/10:29/10:200"];
    let full = tmp("full.jsonl");
    let mut args = vec!["sweep", spec.to_str().unwrap()];
    args.extend_from_slice(&params);
    let mut with_out = args.clone();
    with_out.extend_from_slice(&["-o", full.to_str().unwrap()]);
    let o = verify(&with_out);
    assert!(o.status.success(), "{}", stderr(&o));
    let total = lines_of(&full).len();
    assert_eq!(total, 200 * 200);

    let partial = tmp("partial.jsonl");
    let mut child = Command::new(env!("CARGO_BIN_EXE_verify"))
        .args(&args)
        .args(["-o", partial.to_str().unwrap()])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let started = Instant::now();
    loop {
        let n = std::fs::read_to_string(&partial).map(|t| t.lines().count()).unwrap_or(0);
        if n >= 2000 || started.elapsed() > Duration::from_secs(120) {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = std::fs::read_to_string(&partial).unwrap();
    let kept_lines = kept.lines().count();
    assert!(kept_lines >= 2000 && kept_lines < total, "killed with {kept_lines} of {total} lines");
    // Simulate a write cut short: a partial last line must be dropped.
    std::fs::write(&partial, format!("{kept}{{\"sweep\":\"trunc")).unwrap();

    let mut resume = with_out.clone();
    let pos = resume.iter().position(|a| *a == full.to_str().unwrap()).unwrap();
    resume[pos] = partial.to_str().unwrap();
    resume.push("--resume");
    let o = verify(&resume);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("incomplete last line"), "{}", stderr(&o));
    let resumed = index_set(&partial);
    assert_eq!(resumed.len(), total, "no point twice, none missing");
    assert_eq!(line_set(&[&partial]), line_set(&[&full]));

    // Resuming a finished sweep computes nothing and changes nothing.
    let before = std::fs::read_to_string(&partial).unwrap();
    let o = verify(&resume);
    assert!(o.status.success());
    assert_eq!(std::fs::read_to_string(&partial).unwrap(), before);
}

#[test]
fn shards_concatenate_to_the_whole_sweep_and_random_samples_repeat() {
    let spec = "sweeps/lagrange-top-map.json";
    let small = ["--param", "p=0:4:9", "--param", "mgl=-1:3:9"];
    let whole = tmp("whole.jsonl");
    assert!(sweep_to(spec, &whole, &small).status.success());
    let shards: Vec<PathBuf> = (0..3).map(|k| tmp(&format!("shard{k}.jsonl"))).collect();
    for (k, path) in shards.iter().enumerate() {
        let shard = format!("{k}/3");
        let mut args = small.to_vec();
        args.extend_from_slice(&["--shard", &shard]);
        let o = sweep_to(spec, path, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(index_set(path).iter().all(|i| i % 3 == k as u64));
    }
    let parts: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    assert_eq!(line_set(&parts), line_set(&[&whole]));
    assert_eq!(lines_of(&whole).len(), 81);

    let random = |seed: &str, name: &str| {
        let path = tmp(name);
        let o = sweep_to(spec, &path, &["--random", "40", "--seed", seed, "--numeric"]);
        assert!(o.status.success(), "{}", stderr(&o));
        line_set(&[&path])
    };
    let (a, b, c) = (random("5", "r1.jsonl"), random("5", "r2.jsonl"), random("6", "r3.jsonl"));
    assert_eq!(a.len(), 40);
    assert_eq!(a, b);
    assert!(a.is_disjoint(&c), "another seed is another sweep (another id)");
    for line in &a {
        let r: Value = serde_json::from_str(line).unwrap();
        let (p, mgl) = (r["parameters"]["p"].as_f64().unwrap(), r["parameters"]["mgl"].as_f64().unwrap());
        assert!((0.0..=4.0).contains(&p) && (-1.0..=3.0).contains(&mgl), "{r}");
        assert_eq!(r["level"], "numerical", "{r}");
    }
}

/// Shards run as separate processes (as Slurm array tasks would), then
/// `verify merge`: one file in index order with exactly the lines of the
/// unsharded sweep. The rigid-body triangle has a sweep domain, so the
/// completeness check must skip the points outside it. A missing shard, a
/// line of another plan and two different results for one point are
/// refused (exit 1); the same shard given twice is harmless.
#[test]
fn merge_checks_identity_duplicates_and_completeness() {
    let spec = fixture_path("sweeps/rigid-body-triangle.json");
    let spec_s = spec.to_str().unwrap();
    let small = ["--param", "I1=1/100:1/2:12", "--param", "I2=1/100:1/2:12", "--numeric"];
    let whole = tmp("triangle-whole.jsonl");
    assert!(sweep_to("sweeps/rigid-body-triangle.json", &whole, &small).status.success());
    let shards: Vec<PathBuf> = (0..3).map(|k| tmp(&format!("triangle{k}.jsonl"))).collect();
    let children: Vec<_> = shards
        .iter()
        .enumerate()
        .map(|(k, path)| {
            let shard = format!("{k}/3");
            let mut args = vec!["sweep", spec_s, "-o", path.to_str().unwrap(), "--shard", &shard];
            args.extend_from_slice(&small);
            Command::new(env!("CARGO_BIN_EXE_verify")).args(&args).stderr(Stdio::null()).spawn().unwrap()
        })
        .collect();
    for mut c in children {
        assert!(c.wait().unwrap().success());
    }
    let merge = |files: &[&Path], out: &Path, extra: &[&str]| -> Output {
        let mut args = vec!["merge", spec_s, "-o", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        args.push("--lines");
        args.extend(files.iter().map(|f| f.to_str().unwrap()));
        verify(&args)
    };
    let parts: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    let merged = tmp("triangle-merged.jsonl");
    let o = merge(&parts, &merged, &small);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(line_set(&[&merged]), line_set(&[&whole]));
    let indices: Vec<u64> = records(&merged).iter().map(|r| r["index"].as_u64().unwrap()).collect();
    assert!(indices.windows(2).all(|w| w[0] < w[1]), "index order");
    assert!(indices.len() < 144, "the domain leaves some of the 12 x 12 points out");

    // The same shard twice: dropped, same output.
    let twice = tmp("triangle-twice.jsonl");
    let o = merge(&[parts[0], parts[1], parts[2], parts[2]], &twice, &small);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("repeated lines dropped"), "{}", stderr(&o));
    assert_eq!(lines_of(&twice), lines_of(&merged));

    // A missing shard.
    let o = merge(&parts[..2], &tmp("triangle-missing.jsonl"), &small);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("incomplete"), "{}", stderr(&o));
    assert!(!tmp("triangle-missing.jsonl").exists(), "no output for an incomplete merge");

    // Another plan (the exact level is another sweep id).
    let o = merge(&parts, &tmp("triangle-exact.jsonl"), &small[..4]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("belongs to sweep"), "{}", stderr(&o));

    // Two different results for one point.
    let forged = tmp("triangle-forged.jsonl");
    let mut lines = lines_of(parts[0]);
    let mut r: Value = serde_json::from_str(&lines[0]).unwrap();
    r["verdict"] = "inconclusive".into();
    lines.push(r.to_string());
    std::fs::write(&forged, lines.join("\n") + "\n").unwrap();
    let o = merge(&[&forged, parts[1], parts[2]], &tmp("triangle-conflict.jsonl"), &small);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("two different results"), "{}", stderr(&o));

    // A line moved to another index (here 0: outside the triangle's domain)
    // is not this sweep's point.
    let moved = tmp("triangle-moved.jsonl");
    let mut lines = lines_of(parts[0]);
    let mut r: Value = serde_json::from_str(&lines[0]).unwrap();
    r["index"] = 0.into();
    lines[0] = r.to_string();
    std::fs::write(&moved, lines.join("\n") + "\n").unwrap();
    let o = merge(&[&moved, parts[1], parts[2]], &tmp("triangle-moved-out.jsonl"), &small);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("not the point the line states"), "{}", stderr(&o));

    // A CRLF copy of a shard is the same shard.
    let crlf = tmp("triangle-crlf.jsonl");
    std::fs::write(&crlf, lines_of(parts[2]).join("\r\n") + "\r\n").unwrap();
    let o = merge(&[parts[0], parts[1], parts[2], &crlf], &tmp("triangle-crlf-out.jsonl"), &small);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(lines_of(&tmp("triangle-crlf-out.jsonl")), lines_of(&merged));

    // A JSON line that is not a sweep record is bad input.
    let foreign = tmp("triangle-foreign.jsonl");
    std::fs::write(&foreign, "{\"index\": 3}\n").unwrap();
    let o = merge(&[parts[0], parts[1], parts[2], &foreign], &tmp("triangle-foreign-out.jsonl"), &small);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));

    // --npz naming a file the merge reads or writes is refused before
    // anything is written (the shard stays as it was).
    let before = std::fs::read_to_string(parts[1]).unwrap();
    let o =
        merge(&parts, &tmp("triangle-npz-out.jsonl"), &[&small[..], &["--npz", parts[1].to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("the same file as --lines"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(parts[1]).unwrap(), before);
    let same = tmp("triangle-same.jsonl");
    let o =
        sweep_to("sweeps/rigid-body-triangle.json", &same, &[&small[..], &["--npz", same.to_str().unwrap()]].concat());
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("the same file as -o"), "{}", stderr(&o));

    // A truncated last line (an interrupted shard) is bad input.
    let cut = tmp("triangle-cut.jsonl");
    let text = std::fs::read_to_string(parts[0]).unwrap();
    std::fs::write(&cut, &text[..text.len() - 20]).unwrap();
    let o = merge(&[&cut, parts[1], parts[2]], &tmp("triangle-cut-out.jsonl"), &small);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--resume"), "{}", stderr(&o));

    // A byte-order mark at the start of a shard (an editor's) is not an
    // interrupted shard: the merge is the same.
    let bom = tmp("triangle-bom.jsonl");
    std::fs::write(&bom, format!("\u{feff}{}", std::fs::read_to_string(parts[0]).unwrap())).unwrap();
    let o = merge(&[&bom, parts[1], parts[2]], &tmp("triangle-bom-out.jsonl"), &small);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(lines_of(&tmp("triangle-bom-out.jsonl")), lines_of(&merged));
    // A malformed line in the middle is not called a partial last line.
    let middle = tmp("triangle-middle.jsonl");
    let mut lines = lines_of(parts[0]);
    lines[1].truncate(10);
    std::fs::write(&middle, lines.join("\n") + "\n").unwrap();
    let o = merge(&[&middle, parts[1], parts[2]], &tmp("triangle-middle-out.jsonl"), &small);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(":2: not a sweep line") && !stderr(&o).contains("--resume"), "{}", stderr(&o));
}

/// Merged results were passed through unverified: a shard line edited
/// from `linearly_unstable` to `stable` merged with exit 0, and a line
/// whose float `parameters` disagree with its `exact_parameters` was
/// passed on. Now every line must be what `verify sweep` writes for its
/// plan point (its parameters the exact ones rounded); the summary says the
/// verdicts are the shards' data; `--recheck` certifies each point again
/// and refuses the edited verdict (exit 1, naming the point and the key).
#[test]
fn merge_never_passes_an_edited_result_as_checked() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let spec_s = spec.to_str().unwrap();
    // I2 in [2, 4] with I1 = 3: stable below I1, the intermediate axis above
    let plan = ["--param", "I2=2:4:5"];
    let shards: Vec<PathBuf> = (0..2).map(|k| tmp(&format!("axis{k}.jsonl"))).collect();
    for (k, path) in shards.iter().enumerate() {
        let shard = format!("{k}/2");
        let mut args = vec!["sweep", spec_s, "-o", path.to_str().unwrap(), "--shard", &shard];
        args.extend_from_slice(&plan);
        assert!(verify(&args).status.success());
    }
    let merge = |files: &[&Path], out: &Path, extra: &[&str]| -> Output {
        let mut args = vec!["merge", spec_s, "-o", out.to_str().unwrap()];
        args.extend_from_slice(&plan);
        args.extend_from_slice(extra);
        args.push("--lines");
        args.extend(files.iter().map(|f| f.to_str().unwrap()));
        verify(&args)
    };
    let parts: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    let o = merge(&parts, &tmp("axis-merged.jsonl"), &["--recheck"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("certified again here"), "{}", stderr(&o));
    let o = merge(&parts, &tmp("axis-merged.jsonl"), &[]);
    assert!(stderr(&o).contains("not re-derived"), "{}", stderr(&o));

    // I2 = 4 (index 4, shard 0) is the intermediate axis: call it stable.
    let edit = |f: &dyn Fn(&mut Value)| -> PathBuf {
        let path = tmp("axis-edited.jsonl");
        let lines: Vec<String> = lines_of(parts[0])
            .iter()
            .map(|l| {
                let mut v: Value = serde_json::from_str(l).unwrap();
                if v["index"] == 4 {
                    f(&mut v);
                }
                v.to_string()
            })
            .collect();
        std::fs::write(&path, lines.join("\n") + "\n").unwrap();
        path
    };
    let stable = edit(&|v| {
        assert_eq!(v["verdict"], "linearly_unstable", "{v}");
        v["verdict"] = "stable".into();
        v.as_object_mut().unwrap().remove("growth_rate");
        v["sigma2"] = 0.1.into();
    });
    let o = merge(&[&stable, parts[1]], &tmp("axis-out.jsonl"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("not re-derived"), "{}", stderr(&o));
    let o = merge(&[&stable, parts[1]], &tmp("axis-out.jsonl"), &["--recheck"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("point 4") && stderr(&o).contains("\"verdict\""), "{}", stderr(&o));

    // float parameters that are not the exact ones rounded
    let shifted = edit(&|v| v["parameters"]["I2"] = 4.5.into());
    let o = merge(&[&shifted, parts[1]], &tmp("axis-out.jsonl"), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("float parameters are not the exact ones rounded"), "{}", stderr(&o));
    // an unknown verdict, a key the engine never writes
    for f in [
        &(|v: &mut Value| v["verdict"] = "very_stable".into()) as &dyn Fn(&mut Value),
        &|v: &mut Value| v["note"] = "checked by hand".into(),
        &|v: &mut Value| v["spec"] = "0000000000000000".into(),
    ] {
        let o = merge(&[&edit(f), parts[1]], &tmp("axis-out.jsonl"), &[]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    }
}

/// The numeric level gives the same verdicts and Sigma^2 (to 1e-9, or
/// rounding near 0) as the exact level, and says `numerical`.
#[test]
fn numeric_and_exact_levels_agree() {
    let spec = "rigid-body-major-axis.json";
    let grid = ["--param", "I2=1/2:5:10", "--param", "I3=1/2:5:10"];
    let (e, n) = (tmp("exact.jsonl"), tmp("numeric.jsonl"));
    assert!(sweep_to(spec, &e, &grid).status.success());
    let mut args = grid.to_vec();
    args.push("--numeric");
    assert!(sweep_to(spec, &n, &args).status.success());
    let by_index = |p: &Path| -> BTreeMap<u64, Value> {
        records(p).into_iter().map(|r| (r["index"].as_u64().unwrap(), r)).collect()
    };
    let (e, n) = (by_index(&e), by_index(&n));
    assert_eq!(e.len(), 100);
    let mut kinds = BTreeSet::new();
    for (i, re) in &e {
        let rn = &n[i];
        assert_eq!(re["verdict"], rn["verdict"], "{re} vs {rn}");
        kinds.insert(re["verdict"].as_str().unwrap().to_string());
        if re["verdict"] == "stable" {
            assert_eq!(re["level"], "exact");
            assert_eq!(rn["level"], "numerical");
            let (a, b) = (re["sigma2"].as_f64().unwrap(), rn["sigma2"].as_f64().unwrap());
            // The numeric level (floating point throughout) does not floor a
            // rounding-size lambda_max to 0: where I2 = I3 the exact value is
            // 0 and floating point gives about 1e-17 (noise sigma^2 = 0.09).
            assert!((a - b).abs() <= 1e-9 * a.abs() + 1e-15, "{re} vs {rn}");
        }
    }
    // I1 = 3 is the largest, the intermediate or the smallest axis somewhere on this grid.
    assert!(kinds.contains("stable") && kinds.contains("linearly_unstable"), "{kinds:?}");
}

#[test]
fn bad_ranges_and_options_are_refused_with_exit_status_2() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let spec = spec.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--param", "I2=1:2:0"], "COUNT must be at least 1"),
        (&["--param", "I2=3:1:5"], "START (3) exceeds STOP (1)"),
        (&["--param", "J=1:2:3"], "unknown parameter 'J'"),
        (&["--param", "I2=1:2"], "NAME=START:STOP:COUNT"),
        (&["--param", "I2=a:2:3"], "START 'a' is not a number"),
        (&["--param", "I2=1:2:x"], "COUNT 'x' is not a positive integer"),
        (&["--param", "I2=1:1:3"], "COUNT must be 1"),
        (&["--param", "I2=1:2:3", "--param", "I2=1:2:3"], "swept twice"),
        (&["--param", "I2=1:2:3", "--shard", "3/3"], "--shard"),
        (&["--param", "I2=1:2:3", "--random", "0"], "at least one point"),
        (&[], "nothing to sweep"),
    ];
    for (args, message) in cases {
        let mut all = vec!["sweep", spec];
        all.extend_from_slice(args);
        let o = verify(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(message), "{args:?}: expected '{message}' in {}", stderr(&o));
    }
    // --resume needs an output file (clap refuses it: exit 2).
    let o = verify(&["sweep", spec, "--param", "I2=1:2:3", "--resume"]);
    assert_eq!(o.status.code(), Some(2));
    // Resuming into the lines of another sweep is refused.
    let out = tmp("other.jsonl");
    assert!(verify(&["sweep", spec, "--param", "I2=1:2:3", "-o", out.to_str().unwrap()]).status.success());
    let o = verify(&["sweep", spec, "--param", "I2=1:2:4", "-o", out.to_str().unwrap(), "--resume"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("another sweep"), "{}", stderr(&o));
    // A point where the spec breaks (I2 = 0 divides by zero) is recorded
    // with the field and the run exits 2.
    let o = verify(&["sweep", spec, "--param", "I2=0:1:2", "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let recs = records(&out);
    let broken: Vec<&Value> = recs.iter().filter(|r| r.get("error").is_some()).collect();
    assert_eq!(broken.len(), 1);
    assert!(broken[0]["error"].as_str().unwrap().starts_with("$.hamiltonian"), "{}", broken[0]);
}

#[test]
fn bad_sweep_sections_name_the_field() {
    let base: Value = serde_json::from_str(&common::fixture("sweeps/lagrange-top-map.json")).unwrap();
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(Edit, &str)> = vec![
        (Box::new(|v| v["sweep"]["ranges"][0] = "q=0:1:2".into()), "$.sweep.ranges[0]"),
        (Box::new(|v| v["sweep"]["ranges"][0] = "p=0:1:0".into()), "$.sweep.ranges[0]"),
        (
            Box::new(|v| v["sweep"]["boundaries"][0]["expression"] = "p^2/mgl".into()),
            "$.sweep.boundaries[0].expression",
        ),
        (
            Box::new(|v| v["sweep"]["boundaries"][0]["expression"] = "Pi1 + p".into()),
            "$.sweep.boundaries[0].expression",
        ),
        (Box::new(|v| v["sweep"]["colour"] = "red".into()), "$.sweep.colour"),
        (Box::new(|v| v["sweep"]["domain"] = 3.into()), "$.sweep.domain"),
    ];
    for (edit, path) in cases {
        let mut v = base.clone();
        edit(&mut v);
        let file = tmp("bad-section.json");
        std::fs::write(&file, v.to_string()).unwrap();
        for cmd in [&["certify", file.to_str().unwrap()][..], &["sweep", file.to_str().unwrap()][..]] {
            let o = verify(cmd);
            assert_eq!(o.status.code(), Some(2), "{cmd:?}");
            assert!(stderr(&o).contains(path), "expected {path} in {}", stderr(&o));
        }
    }
}

#[test]
fn charts_are_drawn_for_one_and_two_parameters() {
    let dir = tmp("charts");
    let lines = tmp("heavy.jsonl");
    let o = sweep_to("sweeps/heavy-top-gravity.json", &lines, &["--plot", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "heavy-top-gravity-sigma2.png",
        "heavy-top-gravity-sigma2.svg",
        "heavy-top-gravity-T.png",
        "heavy-top-gravity-T.svg",
    ] {
        assert!(std::fs::metadata(dir.join(f)).map(|m| m.len() > 1000).unwrap_or(false), "{f}");
    }
    let map_lines = tmp("map.jsonl");
    assert!(sweep_to("sweeps/lagrange-top-map.json", &map_lines, &["--param", "p=0:4:5", "--param", "mgl=-1:3:5"])
        .status
        .success());
    let spec = fixture_path("sweeps/lagrange-top-map.json");
    let o = verify(&[
        "plot-sweep",
        map_lines.to_str().unwrap(),
        "--spec",
        spec.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::metadata(dir.join("lagrange-top-map-map.svg")).unwrap().len() > 1000);
    // Lines of two different sweeps are not drawn together.
    let o = verify(&[
        "plot-sweep",
        map_lines.to_str().unwrap(),
        lines.to_str().unwrap(),
        "--spec",
        spec.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// The committed sweep outputs under fixtures/sweeps reproduce exactly.
#[test]
fn committed_sweep_lines_reproduce() {
    for name in ["lagrange-top-map", "rigid-body-triangle", "heavy-top-gravity"] {
        let committed = fixture_path(&format!("sweeps/{name}.jsonl"));
        let out = tmp(&format!("{name}.jsonl"));
        let o = sweep_to(&format!("sweeps/{name}.json"), &out, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(line_set(&[&out]), line_set(&[&committed]), "{name}");
    }
}

/// The sweep's short path (system rebuilt from the expressions, record from
/// the analysis) gives the record a full certificate gives, and the
/// certificate of a swept point passes `check`.
#[test]
fn short_path_records_match_full_certificates() {
    let mut verdicts = BTreeSet::new();
    for (name, ranges) in [
        ("sweeps/lagrange-top-map.json", vec!["p=0:4:5", "mgl=-1:3:5"]),
        ("sweeps/rigid-body-triangle.json", vec!["I1=1/4:1/2:4", "I2=1/8:3/8:3"]),
        ("heavy-top-asymmetric.json", vec!["mgl=-1:3:9"]),
        ("rigid-body-not-equilibrium.json", vec!["sigma=0:1:3"]),
        // sigma = 0 turns the isotropic noise off (stable); otherwise noise_incompatible.
        ("rigid-body-isotropic-noise.json", vec!["sigma=0:1:3"]),
    ] {
        let text = common::fixture(name);
        let any = spec::parse_any_spec(&text).unwrap();
        let spec::AnySpec::Lie(lie) = &any else { panic!("{name}") };
        let ranges: Vec<spec::ParamRange> = ranges.iter().map(|r| spec::ParamRange::parse(r).unwrap()).collect();
        let names: Vec<String> = ranges.iter().map(|r| r.name.clone()).collect();
        let plan = sweep::Plan::new(ranges, sweep::Sampling::Grid).unwrap();
        let ev = sweep::Evaluator::new(any.clone(), names.clone(), sweep::Level::Spec).unwrap();
        for i in 0..plan.len() {
            let values = plan.point(i);
            let short = ev.evaluate(&values);
            let changes: Vec<(String, Rational)> = names.iter().cloned().zip(values.iter().cloned()).collect();
            let full = lie.with_parameters(&changes).unwrap();
            let cert = spec::certify_lie(&full).json;
            assert_eq!(short, sweep::outcome_from_certificate(&cert), "{name} at {changes:?}");
            spec::check_certificate(&cert.to_string()).unwrap_or_else(|e| panic!("{name} at {changes:?}: {e}"));
            verdicts.insert(short.verdict.unwrap().as_str());
        }
    }
    // Every verdict path goes through the short path.
    assert_eq!(verdicts.len(), sweep::Verdict::ALL.len(), "{verdicts:?}");
}

/// Fluid specs sweep through their JSON: each line matches the certificate
/// of the spec with that parameter value.
#[test]
fn fluid_specs_can_be_swept() {
    let mut v: Value = serde_json::from_str(&common::fixture("fluids/channel-sin-walls.json")).unwrap();
    v["fluid"]["ny"] = 32.into();
    v["fluid"]["x_modes"] = 2.into();
    let spec_path = tmp("fluid-small.json");
    std::fs::write(&spec_path, v.to_string()).unwrap();
    let out = tmp("fluid.jsonl");
    let o = verify(&["sweep", spec_path.to_str().unwrap(), "--param", "a=1/10:1/2:2", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let recs = records(&out);
    assert_eq!(recs.len(), 2);
    for r in &recs {
        let mut w = v.clone();
        w["parameters"]["a"] = r["exact_parameters"]["a"].clone();
        let cert = spec::certify_fluid(&spec::fluid_spec_from_value(w).unwrap());
        assert_eq!(r["verdict"], cert["verdict"]);
        assert_eq!(r["level"], cert["level"]);
        assert!(r["sigma2"].as_f64().is_some_and(|s| s > 0.0), "{r}");
        assert_eq!(r["sigma2"].as_f64(), cert["sigma2"].as_f64());
    }
}

/// Regression: a fluid sweep read the level back from the certificate as a
/// string and recorded everything but `exact` and `verified_float` as
/// `numerical`, so points proved by the structure of the form
/// (`exact_structure`: the pseudomomentum makes `Q = 0` identically) were
/// silently downgraded. The level is now the typed one the certificate
/// states, here for the Rayleigh-stable `U = -cos y` with a swept noise
/// amplitude (`Sigma^2 = 0` at every amplitude: the pseudomomentum is
/// conserved by every noise field `(eta(y), 0)`).
#[test]
fn fluid_sweeps_keep_the_exact_structure_level() {
    let mut v: Value = serde_json::from_str(&common::fixture("fluids/rayleigh-cos-walls.json")).unwrap();
    v["parameters"] = serde_json::json!({"s": "3/10"});
    v["fluid"]["noise"] = serde_json::json!(["s*sin(y)", "0.1*y"]);
    v["fluid"]["ny"] = 32.into();
    v["fluid"]["x_modes"] = 2.into();
    let any = spec::parse_any_spec(&v.to_string()).unwrap();
    let ev = sweep::Evaluator::new(any, vec!["s".into()], sweep::Level::Spec).unwrap();
    for s in ["1/10", "1", "5"] {
        let out = ev.evaluate(&[exact::parse_number(s).unwrap()]);
        assert_eq!(out.verdict, Some(sweep::Verdict::Stable), "s = {s}");
        assert_eq!(out.level, Some(sweep::VerificationLevel::ExactStructure), "s = {s}");
        assert_eq!(out.sigma2, Some(0.0), "s = {s}");
    }
    // Through the CLI the record says so too.
    let spec_path = tmp("fluid-exact-structure.json");
    std::fs::write(&spec_path, v.to_string()).unwrap();
    let out = tmp("fluid-exact-structure.jsonl");
    let o = verify(&["sweep", spec_path.to_str().unwrap(), "--param", "s=1/10:1:2", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let recs = records(&out);
    assert_eq!(recs.len(), 2);
    for r in &recs {
        assert_eq!(r["level"], "exact_structure", "{r}");
    }
}

/// Regression: two sweeps on one output file (fresh or `--resume`) both
/// exited 0 and left garbled, missing and repeated lines; the second even
/// truncated the first's lines on opening. The first now holds an exclusive
/// lock: the others exit 2 naming the file as in use, without touching it,
/// and the first's output has every point exactly once.
#[test]
fn a_second_sweep_on_the_same_file_is_refused() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let out = tmp("contended.jsonl");
    let _ = std::fs::remove_file(&out);
    // 300 x 300 = 90 000 exact points: about 3 s for this test build on 2
    // cores (1 s in release with nothing else running), against a few
    // milliseconds for each refused run.
    let (n, args) = (300u64 * 300, ["--param", "I2=1/10:6:300", "--param", "I3=1/10:6:300"]);
    let mut all = vec!["sweep", spec.to_str().unwrap()];
    all.extend_from_slice(&args);
    all.extend_from_slice(&["-o", out.to_str().unwrap()]);
    let mut first = Command::new(env!("CARGO_BIN_EXE_verify")).args(&all).stderr(Stdio::null()).spawn().unwrap();
    // The first line is written after the lock is taken.
    let started = Instant::now();
    while std::fs::metadata(&out).map(|m| m.len()).unwrap_or(0) == 0 {
        assert!(started.elapsed() < Duration::from_secs(120), "the first sweep wrote nothing");
        std::thread::sleep(Duration::from_millis(5));
    }
    let mut resume = all.clone();
    resume.push("--resume");
    for second in [&all, &resume] {
        let o = verify(second);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{second:?}: {err}");
        assert!(err.contains(out.to_str().unwrap()) && err.contains("in use by another sweep"), "{err}");
    }
    // The refusals are only meaningful while the first still runs.
    assert!(first.try_wait().unwrap().is_none(), "the first sweep finished too soon to test the lock");
    assert!(first.wait().unwrap().success());
    let lines = lines_of(&out);
    assert_eq!(lines.len() as u64, n, "one line per point");
    assert_eq!(index_set(&out), (0..n).collect::<Vec<_>>(), "every index exactly once");
}

/// Lines drawn under another spec are refused, even when the parameter names fit.
#[test]
fn plot_sweep_refuses_lines_of_another_spec() {
    // heavy-top-gravity sweeps mgl; lagrange-top-map has a parameter mgl too.
    let lines = fixture_path("sweeps/heavy-top-gravity.jsonl");
    let other = fixture_path("sweeps/lagrange-top-map.json");
    let dir = tmp("other-spec");
    let o = verify(&[
        "plot-sweep",
        lines.to_str().unwrap(),
        "--spec",
        other.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("a sweep of another spec"), "{}", stderr(&o));
    // With the spec that was swept, the same lines draw.
    let own = fixture_path("sweeps/heavy-top-gravity.json");
    let o = verify(&[
        "plot-sweep",
        lines.to_str().unwrap(),
        "--spec",
        own.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A review found lines that contradict themselves merging without
/// `--recheck` (a negative T, T infinite with Sigma^2 > 0, T far past its
/// own Sigma^2's time, a negative Sigma^2), a duplicated key read as its
/// last value, CR-only line ends and a cut multi-byte character called
/// other things, and a byte-order mark mid-file (`cat` of two shards)
/// refused.
#[test]
fn merge_refuses_lines_that_contradict_themselves() {
    let spec = fixture_path("rigid-body-major-axis.json");
    let spec_s = spec.to_str().unwrap();
    let plan = ["--param", "I2=2:4:5"];
    let whole = tmp("self-whole.jsonl");
    let mut args = vec!["sweep", spec_s, "-o", whole.to_str().unwrap()];
    args.extend_from_slice(&plan);
    assert!(verify(&args).status.success());
    let merge = |file: &Path| -> Output {
        let out = tmp("self-out.jsonl");
        let mut args = vec!["merge", spec_s, "-o", out.to_str().unwrap()];
        args.extend_from_slice(&plan);
        args.push("--lines");
        args.push(file.to_str().unwrap());
        verify(&args)
    };
    let lines = lines_of(&whole);
    let stable = lines.iter().position(|l| l.contains("\"verdict\":\"stable\"")).unwrap();
    let edit = |f: &dyn Fn(&mut Value)| -> PathBuf {
        let mut l = lines.clone();
        let mut v: Value = serde_json::from_str(&l[stable]).unwrap();
        f(&mut v);
        l[stable] = v.to_string();
        let p = tmp("self-edited.jsonl");
        std::fs::write(&p, l.join("\n") + "\n").unwrap();
        p
    };
    for (what, f) in [
        ("T negative", &(|v: &mut Value| v["T"] = serde_json::json!(-5.0)) as &dyn Fn(&mut Value)),
        ("T infinite", &|v: &mut Value| v["T"] = serde_json::json!("infinity")),
        ("T past its own Sigma^2", &|v: &mut Value| v["T"] = serde_json::json!(1e6)),
        ("Sigma^2 negative", &|v: &mut Value| v["sigma2"] = serde_json::json!(-1.0)),
    ] {
        let o = merge(&edit(f));
        assert_eq!(o.status.code(), Some(1), "{what}: {}", stderr(&o));
        assert!(stderr(&o).contains("contradicts itself"), "{what}: {}", stderr(&o));
    }
    // a duplicated key
    let mut l = lines.clone();
    l[stable] = l[stable].replacen("{\"sweep\"", "{\"verdict\":\"linearly_unstable\",\"sweep\"", 1);
    let dup = tmp("self-dup.jsonl");
    std::fs::write(&dup, l.join("\n") + "\n").unwrap();
    let o = merge(&dup);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("verdict"), "{}", stderr(&o));
    // CR-only line ends
    let cr = tmp("self-cr.jsonl");
    std::fs::write(&cr, lines.join("\r") + "\r").unwrap();
    let o = merge(&cr);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("CR alone"), "{}", stderr(&o));
    // a byte-order mark at the start of the second half (cat of two shards)
    let mid = tmp("self-bom.jsonl");
    let (a, b) = lines.split_at(2);
    std::fs::write(&mid, format!("{}\n\u{feff}{}\n", a.join("\n"), b.join("\n"))).unwrap();
    assert!(merge(&mid).status.success(), "{}", stderr(&merge(&mid)));
    // cut inside a multi-byte character: an interrupted shard
    let cut = tmp("self-cut.jsonl");
    let mut bytes = (lines.join("\n") + "\n{\"sweep\":\"é").into_bytes();
    bytes.pop();
    std::fs::write(&cut, bytes).unwrap();
    let o = merge(&cut);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("interrupted shard"), "{}", stderr(&o));
}
