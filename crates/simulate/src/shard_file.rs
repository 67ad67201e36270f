//! Shard files of a study: what `verify simulate --shard K/N` writes and
//! `--merge` reads (and the Python package's `simulate(shard=...)` and
//! `merge_shards`), so that a study split over a job array merges into
//! exactly the numbers of an unsharded run.
//!
//! A shard file is `{"kind": "simulate-shard", "format": 1, "engine":
//! VERSION, "study": IDENTITY, "shard": SUMS}`: `IDENTITY` is everything that
//! fixes the study's numbers (the spec's digest and name, and every option,
//! [`study_identity`]), and `SUMS` the shard's exact sums
//! ([`StudyShard::to_json`]). [`merge_shard_documents`] merges a set only
//! when together the files are exactly that study.

use crate::study::{Prepared, StudySettings, StudyShard};
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// The `kind` of a shard file.
pub const SHARD_KIND: &str = "simulate-shard";
/// The format version of a shard file.
pub const SHARD_FORMAT: u64 = 1;
/// The engine version written into shard files; only shards of this
/// version merge (another may integrate or bin differently).
pub const SHARD_ENGINE: &str = env!("CARGO_PKG_VERSION");

/// Why a set of shard files does not merge.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MergeError {
    /// A file is not a shard file (bad input: the message names the file and
    /// the JSON path).
    #[error("{0}")]
    BadInput(String),
    /// The files are shards, but not exactly the whole study: another
    /// study's, another engine's, two different shards with one index, or
    /// some missing.
    #[error("{0}")]
    Mismatch(String),
}

/// Everything that fixes the numbers of a study: shards of one study carry
/// the same identity, and merging insists on it. `coordinates` names the
/// observable.
pub fn study_identity(
    spec_digest: &str,
    name: &str,
    settings: &StudySettings,
    prepared: &Prepared<'_>,
    coordinates: &[String],
) -> Value {
    json!({
        "spec_digest": spec_digest,
        "name": name,
        "paths": settings.paths,
        "dt": settings.dt,
        "t_end": prepared.ensemble.t_end,
        "outputs": settings.outputs,
        "seed": settings.seed,
        "bins": settings.bins,
        "scheme": settings.scheme.as_str(),
        "observable": coordinates.get(prepared.observable).cloned().unwrap_or_default(),
        "epsilon": prepared.epsilon,
        "delta": prepared.delta,
    })
}

/// The shard file of `sums`, a shard of the study `identity`.
pub fn shard_document(identity: &Value, sums: &StudyShard) -> Value {
    json!({
        "kind": SHARD_KIND,
        "format": SHARD_FORMAT,
        "engine": SHARD_ENGINE,
        "study": identity,
        "shard": sums.to_json(),
    })
}

fn quote(v: Option<&Value>) -> String {
    exact::quote(&v.map_or("nothing".to_string(), Value::to_string), 60)
}

/// Merge the shard files `files` (each a label for messages, usually its
/// path, and its parsed JSON) of the study `identity`, after checking that
/// together they are exactly that study: every file is a shard of it (same
/// spec digest and options) written by this engine, all ran the same pilot
/// (one histogram range) and the same split, no index is given twice with
/// different contents (the same shard twice is harmless), and every index
/// of `0..N` is there. Returns the merged sums, which
/// [`crate::finish`] turns into the study an unsharded run gives.
pub fn merge_shard_documents(
    files: &[(String, Value)],
    identity: &Value,
    prepared: &Prepared<'_>,
) -> Result<StudyShard, MergeError> {
    let bad = MergeError::BadInput;
    let mismatch = MergeError::Mismatch;
    let mut shards: BTreeMap<u64, (StudyShard, String)> = BTreeMap::new();
    let mut count: Option<(u64, String)> = None;
    let mut range: Option<((f64, f64), String)> = None;
    for (at, v) in files {
        let at = exact::quote(at, 500);
        if v.get("kind").and_then(Value::as_str) != Some(SHARD_KIND) {
            return Err(bad(format!("{at}: $.kind: not a shard of `verify simulate --shard`")));
        }
        if v.get("format").and_then(Value::as_u64) != Some(SHARD_FORMAT) {
            return Err(bad(format!("{at}: $.format: expected {SHARD_FORMAT}")));
        }
        let stated = v.get("study").ok_or_else(|| bad(format!("{at}: $.study: missing")))?;
        if stated != identity {
            let key = identity
                .as_object()
                .and_then(|m| m.iter().find(|(k, want)| stated.get(k.as_str()) != Some(*want)).map(|(k, _)| k.clone()))
                .unwrap_or_else(|| "study".into());
            return Err(mismatch(format!(
                "{at}: $.study.{key}: the shard belongs to another study (another spec or other options: {} here, {} in the file); give the options the shards ran with",
                quote(identity.get(&key)),
                quote(stated.get(&key)),
            )));
        }
        let shard_json = v.get("shard").ok_or_else(|| bad(format!("{at}: $.shard: missing")))?;
        let shard = StudyShard::from_json(shard_json, "$.shard", prepared).map_err(|m| bad(format!("{at}: {m}")))?;
        let engine = v.get("engine").and_then(Value::as_str).unwrap_or_default();
        if engine != SHARD_ENGINE {
            return Err(mismatch(format!(
                "{at}: $.engine: written by engine {}, not this one ({SHARD_ENGINE}); rerun the shard",
                exact::quote(engine, 40),
            )));
        }
        match &range {
            Some((r, first)) if *r != shard.histogram_range => {
                return Err(mismatch(format!(
                    "{at}: $.shard.histogram_range: {:?}, but {first} has {r:?}: the shards' pilot runs differ",
                    shard.histogram_range
                )))
            }
            Some(_) => {}
            None => range = Some((shard.histogram_range, at.clone())),
        }
        match &count {
            Some((n, first)) if *n != shard.count => {
                return Err(mismatch(format!(
                "{at}: a shard of {} shards, but {first} is a shard of {n}: shards of different splits do not merge",
                shard.count
            )))
            }
            Some(_) => {}
            None => count = Some((shard.count, at.clone())),
        }
        match shards.get(&shard.index) {
            Some((seen, _)) if *seen == shard => {} // the same shard twice: harmless
            Some((_, first)) => {
                return Err(mismatch(format!(
                    "shard {} of {} is given twice with different numbers: {first} and {at} (runs of different engines or seeds?)",
                    shard.index, shard.count
                )))
            }
            None => {
                shards.insert(shard.index, (shard, at));
            }
        }
    }
    let n = count.map_or(0, |(n, _)| n);
    // Counted, not listed: N comes from the files and may be huge. The first
    // ten missing indices lie below the number of shards given plus ten.
    let missing = n - shards.len() as u64;
    if missing > 0 {
        let shown: Vec<String> = (0..n).filter(|k| !shards.contains_key(k)).take(10).map(|k| k.to_string()).collect();
        return Err(mismatch(format!(
            "incomplete: {missing} of the {n} shards are missing ({}{}); run them (`verify simulate --shard K/{n}`, or shard=(K, {n}) in Python)",
            shown.join(", "),
            if missing > 10 { ", ..." } else { "" }
        )));
    }
    let mut all = shards.into_values().map(|(s, _)| s);
    let mut total = all.next().ok_or_else(|| bad("no shard files".into()))?;
    for s in all {
        total.merge(&s);
    }
    Ok(total)
}
