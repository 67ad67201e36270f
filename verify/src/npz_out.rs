//! `.npz` output (numpy's archive of arrays) for `simulate --npz` and
//! `merge --npz`: `numpy.load(FILE)` gives the arrays by name.

use serde_json::Value;
use std::path::Path;

/// A rectangular array of numbers in `v` (a number, a list of numbers, a
/// list of equal-length lists of numbers): `(shape, values)`.
fn numeric(v: &Value) -> Option<(Vec<u64>, Vec<f64>)> {
    match v {
        Value::Number(n) => Some((vec![], vec![n.as_f64()?])),
        Value::Array(items) if items.iter().all(Value::is_number) && !items.is_empty() => {
            Some((vec![items.len() as u64], items.iter().map(|x| x.as_f64()).collect::<Option<_>>()?))
        }
        Value::Array(rows) if !rows.is_empty() => {
            let inner: Vec<(Vec<u64>, Vec<f64>)> = rows.iter().map(numeric).collect::<Option<_>>()?;
            let shape = &inner[0].0;
            if shape.len() != 1 || inner.iter().any(|(s, _)| s != shape) {
                return None;
            }
            let mut out_shape = vec![rows.len() as u64];
            out_shape.extend_from_slice(shape);
            Some((out_shape, inner.into_iter().flat_map(|(_, d)| d).collect()))
        }
        _ => None,
    }
}

/// Every numeric array of a JSON report, named by its key path joined with
/// `_` (`nonlinear_norm_mean_over_delta`, `histogram_counts`), as `f64`;
/// strings, nulls and ragged lists are left out (they stay in the JSON).
pub fn write_json_arrays(path: &Path, report: &Value) -> std::io::Result<()> {
    let mut out = npz::NpzWriter::create(path)?;
    let mut stack = vec![(String::new(), report)];
    while let Some((prefix, v)) = stack.pop() {
        if let Some((shape, data)) = numeric(v) {
            if !prefix.is_empty() {
                out.add_f64(&prefix, &shape, &data)?;
            }
            continue;
        }
        if let Value::Object(map) = v {
            for (k, child) in map.iter().rev() {
                let name = if prefix.is_empty() { k.clone() } else { format!("{prefix}_{k}") };
                stack.push((name, child));
            }
        }
    }
    out.finish().map(|_| ())
}

/// A sweep's lines (in index order) as columns in an `.npz` archive:
/// `index`, one array per parameter, `sigma2`, `T` (NaN where absent, inf
/// for an infinite `T`) and `verdict_code` (0 stable, 1 linearly_unstable,
/// 2 inconclusive, 3 not_an_equilibrium, 4 noise_incompatible, -1 invalid).
/// `path` `-` is standard output (the archive is built in memory first: a
/// ZIP file is written with seeks).
pub fn write_sweep_columns<'a>(
    path: &std::path::Path,
    names: &[String],
    lines: impl Iterator<Item = &'a str>,
) -> std::io::Result<()> {
    if crate::paths::is_stdout(path) {
        let archive = npz::NpzWriter::new(std::io::Cursor::new(Vec::new()));
        let bytes = sweep_columns(archive, names, lines)?.into_inner();
        return crate::paths::write_output(path, &bytes);
    }
    sweep_columns(npz::NpzWriter::create(path)?, names, lines).map(|_| ())
}

fn sweep_columns<'a, W: std::io::Write + std::io::Seek>(
    mut out: npz::NpzWriter<W>,
    names: &[String],
    lines: impl Iterator<Item = &'a str>,
) -> std::io::Result<W> {
    const VERDICTS: [&str; 5] =
        ["stable", "linearly_unstable", "inconclusive", "not_an_equilibrium", "noise_incompatible"];
    let number = |v: Option<&Value>| match v {
        Some(Value::String(s)) if s == "infinity" => f64::INFINITY,
        Some(v) => v.as_f64().unwrap_or(f64::NAN),
        None => f64::NAN,
    };
    let (mut index, mut sigma2, mut t, mut code) = (vec![], vec![], vec![], vec![]);
    let mut params: Vec<Vec<f64>> = vec![vec![]; names.len()];
    for line in lines {
        let r: Value = serde_json::from_str(line).unwrap_or_default();
        index.push(r["index"].as_i64().unwrap_or(-1));
        for (column, name) in params.iter_mut().zip(names) {
            column.push(number(r["parameters"].get(name)));
        }
        sigma2.push(number(r.get("sigma2")));
        t.push(number(r.get("T")));
        let verdict = r["verdict"].as_str().unwrap_or("");
        code.push(VERDICTS.iter().position(|v| *v == verdict).map_or(-1, |k| k as i64));
    }
    let n = [index.len() as u64];
    out.add_i64("index", &n, &index)?;
    for (column, name) in params.iter().zip(names) {
        out.add_f64(name, &n, column)?;
    }
    out.add_f64("sigma2", &n, &sigma2)?;
    out.add_f64("T", &n, &t)?;
    out.add_i64("verdict_code", &n, &code)?;
    out.finish()
}
