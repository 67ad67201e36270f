//! The Zeitlin contract: a spec of the stochastic su(N) Zeitlin model about
//! a zonal equilibrium (`"zeitlin": {...}`), its certificate, and the
//! re-check (docs/zeitlin.md).
//!
//! ```
//! let text = r#"{"name": "monotone", "zeitlin": {"N": 32, "equilibrium": "z + 0.3*z^3", "noise": ["0.1*z^2"]},
//!                "stopping": {"epsilon": 0.1, "delta": 0.001}}"#;
//! let spec = spec::parse_zeitlin_spec(text).unwrap();
//! let cert = spec::certify_zeitlin(&spec);
//! assert_eq!(cert["verdict"], "stable");
//! assert_eq!(cert["sigma2"], 0.0); // the Casimir–momentum form is conserved pathwise
//! assert_eq!(cert["level"], "exact_structure");
//! assert_eq!(cert["stopping"]["T"], "infinity");
//! assert_eq!(spec::check_certificate_value(&cert).unwrap().verdict, spec::Verdict::Stable);
//! ```

use crate::certificate::{spec_digest, stopping_record, CERTIFICATE_VERSION, ENGINE_VERSION};
use crate::check::{compare_with, fail, CheckError, CheckReport};
use crate::document::{Count, Expression, HarmonicsDoc, Real, ZeitlinField, ZeitlinSettingsDoc, ZeitlinSpecDocument};
use crate::json::{as_object, child, index, required, type_name, Result, SpecError};
use crate::parse::Stopping;
use crate::record::{
    Engine, Float, LevelOrNone, ZeitlinBlockRecord, ZeitlinCertificateDocument, ZeitlinDenseRecord, ZeitlinFileRecord,
    ZeitlinFormRecord, ZeitlinFrameRecord, ZeitlinMatrixFreeRecord, ZeitlinModelRecord, ZeitlinPerQtimeRecord,
    ZeitlinResidualsRecord, ZeitlinTimeRecord,
};
use outcome::{Cancelled, Progress, Verdict, VerificationLevel};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use zeitlin::analysis::{analyse_with, hbar, ZeitlinAnalysis, ZeitlinError, ZeitlinProblem, ZeitlinSettings};
use zeitlin::general::{analyse_general_with, Frame, GeneralAnalysis, GeneralProblem, GeneralSettings};
use zeitlin::zonal::quantise;

/// Smallest and largest accepted `N`.
pub const N_RANGE: (usize, usize) = (2, 4096);

/// Relative tolerance when re-checking the floating-point fields of a
/// Zeitlin certificate (bisection estimates, the momentum coefficient found by
/// golden section): the computation is deterministic, so this only absorbs
/// another CPU's rounding.
pub const ZEITLIN_TOLERANCE: f64 = 1e-9;

/// Most Legendre coefficients of the equilibrium that a certificate lists.
const LISTED_COEFFICIENTS: usize = 64;

/// A parsed Zeitlin spec.
#[derive(Clone, Debug)]
pub struct ZeitlinSpec {
    /// `name`.
    pub name: String,
    /// The spec as given.
    pub raw: Value,
    /// The problem: `N`, the equilibrium and the noise.
    pub input: ZeitlinInput,
    /// The equilibrium's Legendre coefficients `a_0..a_{N-1}` (quflow's
    /// normalisation; `a_0` is dropped from the matrix).
    pub coefficients: Vec<f64>,
    /// Each noise field's Legendre coefficients, likewise.
    pub noise_coefficients: Vec<Vec<f64>>,
    /// The stopping question.
    pub stopping: Option<Stopping>,
    /// Numerical settings (the zonal pipeline's in `settings.zonal`).
    pub settings: GeneralSettings,
    /// The optional `sweep` section.
    pub sweep: crate::sweep::SweepSection,
    /// The folder `.npy` paths are relative to (the current folder when
    /// `None`).
    pub base_dir: Option<PathBuf>,
    /// The `.npy` files read.
    pub files: Vec<ZeitlinFileRecord>,
}

/// What a Zeitlin spec gives.
#[derive(Clone, Debug)]
pub enum ZeitlinInput {
    /// Every field a zonal profile: the zonal pipeline.
    Zonal(ZeitlinProblem),
    /// Some field given by harmonics: matrices, and the general pipeline
    /// (which takes a state zonal in some frame to the zonal one).
    General(GeneralProblem),
}

impl ZeitlinInput {
    /// `N`.
    pub fn n(&self) -> usize {
        match self {
            ZeitlinInput::Zonal(p) => p.n,
            ZeitlinInput::General(p) => p.n,
        }
    }
}

/// Largest `N` for fields given by harmonics (dense `N x N` complex
/// matrices, `O(N^3)` products: about 3 s at N = 1024).
pub const HARMONICS_MAX_N: usize = 1024;

/// Most rows of a harmonics list.
const MAX_HARMONIC_ROWS: usize = 1 << 20;

/// Parse a Zeitlin spec from text.
pub fn parse_zeitlin_spec(text: &str) -> Result<ZeitlinSpec> {
    let value: Value = crate::json::parse_json(text)?;
    zeitlin_spec_from_value(value)
}

fn constant(e: &Expression, path: &str, params: &BTreeMap<String, f64>) -> Result<f64> {
    let text = &e.0;
    let parsed = fluid::expr::parse_in(text, "z", params)
        .map_err(|err| SpecError::new(path, format!("in '{}': {err}", exact::quote(text, 60))))?;
    let x = parsed.constant().ok_or_else(|| SpecError::new(path, "must be a constant (it may not depend on z)"))?;
    if !x.is_finite() {
        return Err(SpecError::new(path, format!("is not finite ({x})")));
    }
    Ok(x)
}

/// Quantise the zonal function at `path` on `N`: `(diagonal, coefficients)`.
fn zonal(e: &Expression, path: &str, n: usize, params: &BTreeMap<String, f64>) -> Result<(Vec<f64>, Vec<f64>)> {
    let text = &e.0;
    let f = fluid::expr::parse_in(text, "z", params)
        .map_err(|err| SpecError::new(path, format!("in '{}': {err}", exact::quote(text, 60))))?;
    // A singular profile must not slip between the quadrature nodes: it is
    // evaluated on a fine uniform sample of the closed interval as well.
    const SAMPLES: usize = 4097;
    if let Some(z) =
        (0..SAMPLES).map(|i| -1.0 + 2.0 * i as f64 / (SAMPLES - 1) as f64).find(|z| !f.eval(*z).is_finite())
    {
        return Err(SpecError::new(path, format!("is not finite at z = {z} (it must be finite on [-1, 1])")));
    }
    let q = quantise(n, |z| f.eval(z));
    if let Some(l) = q.coefficients.iter().position(|x| !x.is_finite()) {
        return Err(SpecError::new(
            path,
            format!("is not finite on [-1, 1]: its Legendre coefficient a_{l} is {} (a singularity, or values beyond the range of doubles, at a quadrature node)", q.coefficients[l]),
        ));
    }
    if q.diagonal.iter().any(|x| !x.is_finite()) {
        return Err(SpecError::new(path, "its quantised matrix overflows the range of doubles: rescale it"));
    }
    Ok((q.diagonal, q.coefficients))
}

/// The matrix of a field given by harmonics: rows `[l, m, value]`.
fn harmonics(
    h: &HarmonicsDoc,
    path: &str,
    n: usize,
    params: &BTreeMap<String, f64>,
) -> Result<nalgebra::DMatrix<nalgebra::Complex<f64>>> {
    let hpath = child(path, "harmonics");
    if h.harmonics.len() > MAX_HARMONIC_ROWS {
        return Err(SpecError::new(hpath, format!("at most {MAX_HARMONIC_ROWS} rows")));
    }
    let mut seen = std::collections::BTreeSet::new();
    let mut rows = Vec::with_capacity(h.harmonics.len());
    for (r, row) in h.harmonics.iter().enumerate() {
        let rpath = index(&hpath, r);
        if row.len() != 3 {
            return Err(SpecError::new(&rpath, format!("expected [l, m, value], got {} entries", row.len())));
        }
        let integer = |e: &Expression, at: usize| -> Result<i64> {
            let epath = index(&rpath, at);
            let x = constant(e, &epath, params)?;
            if x.fract() != 0.0 || x.abs() > 1e6 {
                return Err(SpecError::new(epath, format!("must be an integer, got {x}")));
            }
            Ok(x as i64)
        };
        let (l, m) = (integer(&row[0], 0)?, integer(&row[1], 1)?);
        if l < 1 || l >= n as i64 {
            return Err(SpecError::new(
                index(&rpath, 0),
                format!(
                    "l must be between 1 and N - 1 = {} (l = 0 is the trace, which su(N) leaves out), got {l}",
                    n - 1
                ),
            ));
        }
        if m.abs() > l {
            return Err(SpecError::new(index(&rpath, 1), format!("|m| must be at most l = {l}, got {m}")));
        }
        if !seen.insert((l, m)) {
            return Err(SpecError::new(&rpath, format!("(l, m) = ({l}, {m}) appears twice")));
        }
        let v = constant(&row[2], &index(&rpath, 2), params)?;
        rows.push((l as usize, m, v));
    }
    let w = zeitlin::sphere::from_harmonics(n, &rows).map_err(|e| SpecError::new(&hpath, e.to_string()))?;
    if w.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
        return Err(SpecError::new(hpath, "its matrix overflows the range of doubles: rescale it"));
    }
    Ok(w)
}

/// Largest size of a `.npy` file a spec may name: an `N x N` complex128
/// array at N = [`HARMONICS_MAX_N`], plus its header.
const MAX_NPY_BYTES: u64 = 16 * (HARMONICS_MAX_N as u64) * (HARMONICS_MAX_N as u64) + 65536;

/// The matrix of a field given as a `.npy` file, and the file's record.
fn read_npy(
    text: &str,
    path: &str,
    n: usize,
    base: Option<&Path>,
) -> Result<(nalgebra::DMatrix<nalgebra::Complex<f64>>, ZeitlinFileRecord)> {
    use sha2::{Digest, Sha256};
    let npath = child(path, "npy");
    let rel = Path::new(text);
    let shown = exact::quote(text, 80);
    let relative = !text.is_empty()
        && text.len() <= 1024
        && rel.extension().is_some_and(|e| e == "npy")
        && rel.components().all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    if !relative {
        return Err(SpecError::new(
            npath,
            format!("{shown} must be a relative path to a .npy file, inside the spec's folder (no '..', not absolute)"),
        ));
    }
    let full = base.unwrap_or(Path::new(".")).join(rel);
    let folder = match base {
        Some(dir) if !dir.as_os_str().is_empty() => {
            format!("the spec's folder {}", exact::quote(&dir.display().to_string(), 200))
        }
        Some(_) => "the spec's folder, the current one".to_string(),
        None => "the current folder: the spec came as text, with no folder of its own".to_string(),
    };
    let meta = std::fs::metadata(&full)
        .map_err(|e| SpecError::new(&npath, format!("cannot read {shown} (relative to {folder}): {e}")))?;
    if !meta.is_file() {
        return Err(SpecError::new(npath, format!("{shown} is not a file")));
    }
    if meta.len() > MAX_NPY_BYTES {
        return Err(SpecError::new(
            npath,
            format!("{shown} has {} bytes, more than an N x N complex128 array at N = {HARMONICS_MAX_N}", meta.len()),
        ));
    }
    let bytes = std::fs::read(&full).map_err(|e| SpecError::new(&npath, format!("cannot read {shown}: {e}")))?;
    let sha256: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
    let file = npyz::NpyFile::new(&bytes[..])
        .map_err(|e| SpecError::new(&npath, format!("{shown} is not a .npy file: {e}")))?;
    let shape = file.shape().to_vec();
    if shape != [n as u64, n as u64] {
        return Err(SpecError::new(npath, format!("{shown} has shape {shape:?}, expected [{n}, {n}] (N x N)")));
    }
    let fortran = file.order() == npyz::Order::Fortran;
    let data: Vec<nalgebra::Complex<f64>> = file.into_vec().map_err(|e| {
        SpecError::new(&npath, format!("{shown} must hold complex128 numbers ('<c16', as quflow's W): {e}"))
    })?;
    if data.len() != n * n {
        return Err(SpecError::new(npath, format!("{shown} holds {} numbers, expected {}", data.len(), n * n)));
    }
    let w = nalgebra::DMatrix::from_fn(n, n, |i, j| if fortran { data[j * n + i] } else { data[i * n + j] });
    if let Some(k) = w.iter().position(|z| !(z.re.is_finite() && z.im.is_finite())) {
        return Err(SpecError::new(npath, format!("{shown}: entry ({}, {}) is not finite", k % n, k / n)));
    }
    let hermitian = (&w + w.adjoint()).norm() / 2.0;
    if hermitian > 1e-12 * w.norm() {
        return Err(SpecError::new(
            npath,
            format!(
                "{shown} is not skew-Hermitian (relative Hermitian part {:.3e}): su(N) states and noise are skew-Hermitian, as quflow's W",
                hermitian / w.norm()
            ),
        ));
    }
    Ok((w, ZeitlinFileRecord { field: path.to_string(), path: text.to_string(), sha256 }))
}

/// Parse a Zeitlin spec from a JSON value (`.npy` paths relative to the
/// current folder).
pub fn zeitlin_spec_from_value(value: Value) -> Result<ZeitlinSpec> {
    zeitlin_spec_from_value_in(value, None)
}

/// Parse a Zeitlin spec from a JSON value, with `.npy` paths relative to
/// `base` (the spec's folder; the current folder when `None`).
pub fn zeitlin_spec_from_value_in(value: Value, base: Option<&Path>) -> Result<ZeitlinSpec> {
    let root = "$";
    if !value.is_object() {
        return Err(SpecError::new(root, format!("expected an object, found {}", type_name(&value))));
    }
    let doc: ZeitlinSpecDocument = crate::document::from_value(&value)?;
    let name = doc.name.clone();
    if name.trim().is_empty() {
        return Err(SpecError::new(child(root, "name"), "must not be empty"));
    }
    let mut params = BTreeMap::new();
    let ppath = child(root, "parameters");
    for (key, v) in &doc.parameters {
        let kpath = child(&ppath, key);
        let valid = key.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid || ["z", "pi"].contains(&key.as_str()) || fluid::expr::FUNCTIONS.contains(&key.as_str()) {
            return Err(SpecError::new(
                kpath,
                format!(
                    "'{}' is not a valid parameter name (letters, digits, '_'; not z, pi or a function)",
                    exact::quote(key, 40)
                ),
            ));
        }
        let x = constant(v, &kpath, &params)?;
        params.insert(key.clone(), x);
    }
    let zpath = child(root, "zeitlin");
    let z = &doc.zeitlin;
    let npath = child(&zpath, "N");
    let n = usize::try_from(z.n.0).map_err(|_| SpecError::new(&npath, "too large"))?;
    if !(N_RANGE.0..=N_RANGE.1).contains(&n) {
        return Err(SpecError::new(npath, format!("must be between {} and {}, got {n}", N_RANGE.0, N_RANGE.1)));
    }
    let noise_path = child(&zpath, "noise");
    if z.noise.len() > crate::parse::MAX_NOISE_FIELDS {
        return Err(SpecError::new(
            &noise_path,
            format!("at most {} noise fields are supported", crate::parse::MAX_NOISE_FIELDS),
        ));
    }
    let fields: Vec<(&ZeitlinField, String)> = std::iter::once((&z.equilibrium, child(&zpath, "equilibrium")))
        .chain(z.noise.iter().enumerate().map(|(i, f)| (f, index(&noise_path, i))))
        .collect();
    let is_matrix = |f: &ZeitlinField| matches!(f, ZeitlinField::Harmonics(_) | ZeitlinField::Npy(_));
    let general = fields.iter().any(|(f, _)| is_matrix(f));
    if general && n > HARMONICS_MAX_N {
        let (_, path) = fields.iter().find(|(f, _)| is_matrix(f)).expect("one");
        return Err(SpecError::new(
            path,
            format!("fields given by harmonics or .npy files are supported up to N = {HARMONICS_MAX_N} (dense N x N matrices), got N = {n}"),
        ));
    }
    let mut matrices = Vec::new();
    let mut zonal_parts = Vec::new();
    let mut files = Vec::new();
    for (field, path) in &fields {
        match field {
            ZeitlinField::Profile(e) => {
                let (d, a) = zonal(e, path, n, &params)?;
                if general {
                    matrices.push(zeitlin::isospectral::zonal_state(&d));
                }
                zonal_parts.push((d, a));
            }
            ZeitlinField::Harmonics(h) => {
                matrices.push(harmonics(h, path, n, &params)?);
                zonal_parts.push((vec![], vec![]));
            }
            ZeitlinField::Npy(d) => {
                let (w, record) = read_npy(&d.npy, path, n, base)?;
                matrices.push(w);
                files.push(record);
                zonal_parts.push((vec![], vec![]));
            }
        }
    }
    let (input, coefficients, noise_coefficients) = if general {
        let w = matrices.remove(0);
        (ZeitlinInput::General(GeneralProblem { n, w, noise: matrices }), vec![], vec![])
    } else {
        let mut parts = zonal_parts.into_iter();
        let (omega, coefficients) = parts.next().expect("the equilibrium");
        let (noise, noise_coefficients): (Vec<Vec<f64>>, Vec<Vec<f64>>) = parts.unzip();
        (ZeitlinInput::Zonal(ZeitlinProblem { n, omega, noise }), coefficients, noise_coefficients)
    };
    let stopping =
        doc.stopping.as_ref().map(|s| crate::parse::read_stopping(s, &child(root, "stopping"))).transpose()?;
    let settings = match &doc.settings {
        Some(s) => read_settings(s, &child(root, "settings"))?,
        None => GeneralSettings::default(),
    };
    let names: Vec<String> = params.keys().cloned().collect();
    let sweep = crate::sweep::read_sweep_section(doc.sweep.as_ref(), &child(root, "sweep"), &names)?;
    Ok(ZeitlinSpec {
        name,
        raw: value,
        input,
        coefficients,
        noise_coefficients,
        stopping,
        settings,
        sweep,
        base_dir: base.map(Path::to_path_buf),
        files,
    })
}

fn read_settings(doc: &ZeitlinSettingsDoc, path: &str) -> Result<GeneralSettings> {
    let mut g = GeneralSettings::default();
    for (key, value, slot) in [
        ("equilibrium_tolerance", doc.equilibrium_tolerance, &mut g.equilibrium_tolerance),
        ("noise_tolerance", doc.noise_tolerance, &mut g.noise_tolerance),
    ] {
        if let Some(Real(x)) = value {
            if !(1e-15..=1e-3).contains(&x) {
                return Err(SpecError::new(child(path, key), format!("must be between 1e-15 and 1e-3, got {x}")));
            }
            *slot = x;
        }
    }
    if let Some(Count(m)) = doc.dense_max_n {
        if !(2..=48).contains(&m) {
            return Err(SpecError::new(child(path, "dense_max_n"), format!("must be between 2 and 48, got {m}")));
        }
        g.dense_max_n = m as usize;
    }
    if let Some(Count(m)) = doc.matrix_free_max_n {
        if !(2..=1024).contains(&m) {
            return Err(SpecError::new(
                child(path, "matrix_free_max_n"),
                format!("must be between 2 and 1024, got {m}"),
            ));
        }
        g.matrix_free_max_n = m as usize;
    }
    g.zonal = read_zonal_settings(doc, path)?;
    Ok(g)
}

fn read_zonal_settings(doc: &ZeitlinSettingsDoc, path: &str) -> Result<ZeitlinSettings> {
    let mut s = ZeitlinSettings::default();
    if let Some(Real(x)) = doc.tolerance {
        if !(1e-14..=1e-3).contains(&x) {
            return Err(SpecError::new(child(path, "tolerance"), format!("must be between 1e-14 and 1e-3, got {x}")));
        }
        s.tolerance = x;
    }
    if let Some(b) = doc.casimir_momentum {
        s.casimir_momentum = b;
    }
    if let Some(Count(m)) = doc.instability_max_n {
        let p = child(path, "instability_max_n");
        if !(2..=512).contains(&m) {
            return Err(SpecError::new(p, format!("must be between 2 and 512, got {m}")));
        }
        s.instability_max_n = m as usize;
    }
    if let Some(Count(m)) = doc.energy_search_max_n {
        let p = child(path, "energy_search_max_n");
        if !(2..=N_RANGE.1 as u64).contains(&m) {
            return Err(SpecError::new(p, format!("must be between 2 and {}, got {m}", N_RANGE.1)));
        }
        s.energy_search_max_n = m as usize;
    }
    Ok(s)
}

/// The settings as the certificate records them (all keys; those of the
/// general pipeline only where it ran, and `matrix_free_max_n` only where
/// it matters, above `dense_max_n`, so certificates written before it
/// existed still check).
fn settings_document(g: &GeneralSettings, general: bool, n: usize) -> ZeitlinSettingsDoc {
    let s = &g.zonal;
    ZeitlinSettingsDoc {
        tolerance: Some(Real(s.tolerance)),
        casimir_momentum: Some(s.casimir_momentum),
        instability_max_n: Some(Count(s.instability_max_n as u64)),
        energy_search_max_n: Some(Count(s.energy_search_max_n as u64)),
        equilibrium_tolerance: general.then_some(Real(g.equilibrium_tolerance)),
        noise_tolerance: general.then_some(Real(g.noise_tolerance)),
        dense_max_n: general.then_some(Count(g.dense_max_n as u64)),
        matrix_free_max_n: (general && n > g.dense_max_n).then_some(Count(g.matrix_free_max_n as u64)),
    }
}

/// The analysis of a Zeitlin spec: the zonal pipeline's, or the general one's.
#[derive(Clone, Debug)]
pub enum ZeitlinOutcome {
    /// Zonal profiles.
    Zonal(std::result::Result<ZeitlinAnalysis, ZeitlinError>),
    /// Fields given by harmonics (boxed: it holds a zonal analysis too).
    General(Box<std::result::Result<GeneralAnalysis, ZeitlinError>>),
}

/// Run the pipeline the spec's input calls for.
pub fn analyse_zeitlin(spec: &ZeitlinSpec) -> ZeitlinOutcome {
    analyse_zeitlin_with(spec, &Progress::new())
}

/// [`analyse_zeitlin`] with progress and cancellation (a cancelled run's
/// outcome holds [`ZeitlinError::Cancelled`]).
pub(crate) fn analyse_zeitlin_with(spec: &ZeitlinSpec, progress: &Progress) -> ZeitlinOutcome {
    match &spec.input {
        ZeitlinInput::Zonal(p) => ZeitlinOutcome::Zonal(analyse_with(p, &spec.settings.zonal, progress)),
        ZeitlinInput::General(p) => {
            ZeitlinOutcome::General(Box::new(analyse_general_with(p, &spec.settings, progress)))
        }
    }
}

/// Run the Zeitlin pipeline and build the certificate JSON.
pub fn certify_zeitlin(spec: &ZeitlinSpec) -> Value {
    zeitlin_certificate_value(spec, &analyse_zeitlin(spec))
}

/// [`certify_zeitlin`] with progress; `Err` when it was cancelled (no
/// certificate is built from a cancelled run).
pub(crate) fn certify_zeitlin_with(spec: &ZeitlinSpec, progress: &Progress) -> std::result::Result<Value, Cancelled> {
    let analysis = analyse_zeitlin_with(spec, progress);
    progress.check()?;
    Ok(zeitlin_certificate_value(spec, &analysis))
}

fn zeitlin_certificate_value(spec: &ZeitlinSpec, analysis: &ZeitlinOutcome) -> Value {
    serde_json::to_value(zeitlin_certificate_document(spec, analysis)).unwrap_or_default()
}

/// Largest degree `l` of the harmonics a certificate lists.
const LISTED_DEGREE: usize = 128;

/// The harmonics `[l, m, value]` of a matrix (quflow's order) up to
/// `l = 128`, keeping those above 1e-13 of the largest, at most 4096 of them.
fn harmonics_record(w: &nalgebra::DMatrix<nalgebra::Complex<f64>>) -> Vec<(u64, i64, Float)> {
    let n = w.nrows();
    let all = zeitlin::sphere::to_harmonics(w, n.saturating_sub(1).min(LISTED_DEGREE)).unwrap_or_default();
    let top = all.iter().fold(0.0f64, |a, (_, _, v)| a.max(v.abs()));
    all.into_iter()
        .filter(|(_, _, v)| v.abs() > 1e-13 * top)
        .take(4096)
        .map(|(l, m, v)| (l as u64, m, Float(v)))
        .collect()
}

/// The typed certificate of a Zeitlin spec from its analysis (an analysis
/// error gives an `inconclusive` certificate that says why).
pub fn zeitlin_certificate_document(spec: &ZeitlinSpec, outcome: &ZeitlinOutcome) -> ZeitlinCertificateDocument {
    let n = spec.input.n();
    let general = matches!(spec.input, ZeitlinInput::General(_));
    // a_1..a_L, up to the last one above 1e-14 of the largest, at most 64.
    let listed = |a: &[f64]| -> Vec<Float> {
        let scale = a.iter().skip(1).fold(0.0f64, |m, x| m.max(x.abs()));
        let last = a.iter().rposition(|x| x.abs() > 1e-14 * scale).unwrap_or(0);
        a.iter().take(last + 1).skip(1).take(LISTED_COEFFICIENTS).map(|x| Float(*x)).collect()
    };
    let model = ZeitlinModelRecord {
        n: n as u64,
        dimension: (n * n - 1) as u64,
        hbar: Float(hbar(n)),
        formulation: if general {
            "dW = [P, W]/hbar dt + sum_i [X_i, W]/hbar o dB^i, Delta_N P = W (Hoppe–Yau Laplacian, eigenvalues -l(l+1)), hbar = 2/sqrt(N^2 - 1), <A, B> = Re tr(A B*)/N; W_e and X_i skew-Hermitian matrices".into()
        } else {
            "dW = [P, W]/hbar dt + sum_i [X_i, W]/hbar o dB^i, Delta_N P = W (Hoppe–Yau Laplacian, eigenvalues -l(l+1)), hbar = 2/sqrt(N^2 - 1), <A, B> = Re tr(A B*)/N; W_e = i diag(omega) zonal, X_i = i diag(xi_i) zonal; a perturbation splits by its off-diagonal m = 1..N-1 into independent blocks".into()
        },
        quantisation: if general {
            "fields given by harmonics: W = sum value T_lm in quflow's real spherical-harmonic basis (shr2mat: T_lm from the eigenvectors of the Laplacian block on diagonal |m|); fields given by .npy files: the matrix itself (files records their SHA-256); zonal profiles as quflow quantises them (a_l by Gauss–Legendre on 2N + 32 nodes, W = sum a_l T_l0, a_0 dropped)".into()
        } else {
            "quflow's: a_l = 1/2 int_{-1}^{1} f(z) sqrt(2l+1) P_l(z) dz by Gauss–Legendre on 2N + 32 nodes, W = sum_{l=1}^{N-1} a_l T_l0, T_l0 = i sqrt(N) diag(u_l) with u_l the l-th eigenvector of the zonal Laplacian block (last entry positive); a_0 (the mean) is dropped".into()
        },
        equilibrium_coefficients: listed(&spec.coefficients),
        noise_coefficients: spec.noise_coefficients.iter().map(|a| listed(a)).collect(),
        files: spec.files.clone(),
    };
    let mut doc = ZeitlinCertificateDocument {
        certificate_version: CERTIFICATE_VERSION,
        engine: Engine { name: "verify".into(), version: ENGINE_VERSION.into() },
        name: spec.name.clone(),
        kind: outcome::CertificateKind::Zeitlin,
        verdict: Verdict::Inconclusive,
        reason: String::new(),
        level: LevelOrNone(None),
        theorem: crate::theorem::nothing(crate::theorem::ZEITLIN_NOT_CHECKED),
        checks: BTreeMap::new(),
        sigma2: None,
        sigma2_upper: None,
        stopping: None,
        time: time_record(n, None, None, None, None),
        spec_sha256: spec_digest(&spec.raw),
        model,
        form: None,
        blocks: vec![],
        residuals: ZeitlinResidualsRecord { equilibrium: Float(0.0), noise: Float(0.0), drift: Float(0.0) },
        growth_rate: None,
        frame: None,
        compatible_noise: vec![],
        dense: None,
        matrix_free: None,
        settings: settings_document(&spec.settings, general, n),
        spec: spec.raw.clone(),
    };
    let mut checks = BTreeMap::new();
    checks.insert(
        "discretisation".to_string(),
        "the claims are about the Zeitlin model at this N (a finite-dimensional Lie–Poisson system in its own right), not about the continuum Euler equations".to_string(),
    );
    match outcome {
        ZeitlinOutcome::Zonal(Err(e)) => {
            doc.reason = format!("the analysis could not run: {e}");
        }
        ZeitlinOutcome::General(g) => match g.as_ref() {
            Err(e) => doc.reason = format!("the analysis could not run: {e}"),
            Ok(g) => fill_general(&mut doc, &mut checks, spec, g),
        },
        ZeitlinOutcome::Zonal(Ok(a)) => {
            checks.insert(
                "equilibrium".to_string(),
                "W_e and P_e = Delta_N^-1 W_e are diagonal, so [P_e, W_e] = 0; zonal noise commutes with W_e: compatible"
                    .to_string(),
            );
            doc.residuals = ZeitlinResidualsRecord {
                equilibrium: Float(a.equilibrium_residual),
                noise: Float(a.noise_residual),
                drift: Float(a.drift_residual),
            };
            fill_zonal(&mut doc, &mut checks, spec, a);
        }
    }
    doc.checks = checks;
    doc.time = time_record(
        n,
        doc.sigma2.map(|x| x.0),
        doc.sigma2_upper.map(|x| x.0),
        doc.growth_rate.map(|x| x.0),
        doc.stopping.as_ref().map(|s| s.t.0),
    );
    let subject = crate::theorem::zeitlin_subject(
        &spec.name,
        n,
        spec.raw.pointer("/zeitlin/equilibrium").and_then(Value::as_str).unwrap_or("the spec's equilibrium"),
        spec.noise_coefficients
            .len()
            .max(spec.raw.pointer("/zeitlin/noise").and_then(Value::as_array).map_or(0, Vec::len)),
    );
    doc.theorem = crate::theorem::from_doubles(
        &subject,
        doc.verdict,
        doc.level.0,
        doc.sigma2_upper.map(|x| x.0),
        doc.sigma2.map(|x| x.0),
        doc.stopping.as_ref(),
        doc.growth_rate.map(|x| x.0),
    );
    doc
}

/// The certificate's rates and stopping time per unit `qtime = t / hbar`
/// beside the ones per unit `t`. Bounds are moved outward by a relative
/// 1e-15 (over 4 ulps), more than the rounding of `hbar = 2 / sqrt(N^2 -
/// 1)` (two correctly rounded operations on an exact `N^2 - 1`) and of the
/// product: a bound per `qtime` is still a bound.
fn time_record(
    n: usize,
    sigma2: Option<f64>,
    sigma2_upper: Option<f64>,
    growth_rate: Option<f64>,
    stopping_time: Option<f64>,
) -> ZeitlinTimeRecord {
    let h = hbar(n);
    let outward = 1e-15_f64;
    ZeitlinTimeRecord {
        unit: "t".into(),
        meaning: format!(
            "sigma2, sigma2_upper, growth_rate and stopping.T are per unit of the model's time t, quflow's time dataset (dW/dt = [P, W]/hbar); quflow's integrators step in qtime = t/hbar, hbar = 2/sqrt(N^2 - 1) = {h:e}, so per unit qtime a rate is hbar times the rate per unit t and a time 1/hbar times the time in t: per_qtime (bounds rounded outward)"
        ),
        per_qtime: ZeitlinPerQtimeRecord {
            sigma2: sigma2.map(|s| Float(s * h)),
            sigma2_upper: sigma2_upper.map(|s| Float(s * h * (1.0 + outward.copysign(s)))),
            growth_rate: growth_rate.map(|g| Float(g * h)),
            // (a finite T whose quotient overflows is kept finite: an
            // infinite T would claim the bound for all time)
            stopping_time: stopping_time.map(|t| {
                let q = t / h * (1.0 - outward);
                Float(if t.is_finite() && !q.is_finite() { f64::MAX } else { q })
            }),
        },
    }
}

/// The verdict and its evidence from a general analysis.
fn fill_general(
    doc: &mut ZeitlinCertificateDocument,
    checks: &mut BTreeMap<String, String>,
    spec: &ZeitlinSpec,
    g: &GeneralAnalysis,
) {
    doc.verdict = g.verdict;
    doc.reason = g.reason.clone();
    // `inconclusive` claims nothing (as the zonal pipeline's certificates say).
    doc.level = LevelOrNone((g.verdict != Verdict::Inconclusive).then_some(g.level));
    doc.residuals = ZeitlinResidualsRecord {
        equilibrium: Float(g.equilibrium_residual),
        noise: Float(g.noise_residuals.iter().fold(0.0f64, |a, x| a.max(*x))),
        drift: Float(0.0),
    };
    checks.insert(
        "equilibrium".to_string(),
        format!(
            "numerical: |[P_e, W_e]|_F / (|P_e|_F |W_e|_F) = residuals.equilibrium against settings.equilibrium_tolerance = {:e}, with P_e from the O(N^2) stream solve; |[X_i, W_e]|_F / (|X_i|_F |W_e|_F) against settings.noise_tolerance = {:e} (residuals.noise, the largest)",
            spec.settings.equilibrium_tolerance, spec.settings.noise_tolerance
        ),
    );
    match g.verdict {
        Verdict::NotAnEquilibrium => return,
        Verdict::NoiseIncompatible => {
            doc.compatible_noise = g.compatible_noise.iter().map(harmonics_record).collect();
            checks.insert(
                "compatible_noise".to_string(),
                "each field's projection onto the matrices that commute with W_e (in W_e's eigenbasis, the entries between equal eigenvalues), as [l, m, value] rows (up to l = 128, those above 1e-13 of the largest) to paste into the spec's noise as {\"harmonics\": ...}".to_string(),
            );
            return;
        }
        _ => {}
    }
    match &g.frame {
        Some(Frame::Zonal) | Some(Frame::Rotated { .. }) => {
            let r = g.zonal.as_ref().expect("a zonal frame has its reduction");
            let (kind, axis, meaning) = match &g.frame {
                Some(Frame::Rotated { axis }) => (
                    "rotated",
                    Some(axis.map(Float)),
                    "W_e commutes with a.S for a spin axis a (the null vector of the Gram matrix of [S_a, W_e], measured directly); frame.axis is a in quflow's frame, (-a_1, -a_2, a_3) scaled to unit length with its largest component positive: the direction of the l = 1 harmonic coefficients (omega_{1,1}, omega_{1,-1}, omega_{1,0}) of a state zonal about it, the frame of quflow.geometry.rotate (quflow's shr2fun pictures mirror y). V = exp(-i theta u.S) takes a to the pole and V^* W_e V is diagonal up to off_diagonal (dropped). The Laplacian and the inner product commute with Ad_V, so the rotated system is the same stochastic system: the zonal pipeline's claims below are about the rotated, diagonal problem as stored",
                ),
                _ => ("zonal", None, "W_e and the noise are diagonal as given (up to off_diagonal, dropped): the zonal pipeline's claims below are about the diagonal problem as stored"),
            };
            doc.frame = Some(ZeitlinFrameRecord {
                kind: kind.into(),
                axis,
                off_diagonal: Some(Float(r.off_diagonal)),
                meaning: meaning.into(),
            });
            doc.residuals.drift = Float(r.analysis.drift_residual);
            fill_zonal(doc, checks, spec, &r.analysis);
            doc.reason = g.reason.clone();
        }
        Some(Frame::General) => {
            doc.frame = Some(ZeitlinFrameRecord {
                kind: "general".into(),
                axis: None,
                off_diagonal: None,
                meaning: if g.matrix_free.is_some() {
                    "W_e commutes with n.S for no axis n: it is zonal in no frame, and above dense_max_n the analysis runs matrix-free (operators applied to N x N matrices): Lanczos on the restricted Hessian of H + C_Phi, then a search for growing eigenvalues of the drift (no momentum multiplier: criticality would need [n.S, W_e] = 0)".into()
                } else {
                    "W_e commutes with n.S for no axis n: it is zonal in no frame, and the energy–Casimir method runs densely in real orthonormal coordinates of su(N) in W_e's eigenbasis (no momentum multiplier: criticality would need [n.S, W_e] = 0)".into()
                },
            });
            if let Some(m) = &g.matrix_free {
                fill_matrix_free(doc, checks, g.verdict, m);
            }
            if let Some(d) = &g.dense {
                fill_dense(doc, checks, spec, g.verdict, d);
            }
        }
        None => {}
    }
}

/// A general state's matrix-free analysis (above `dense_max_n`).
fn fill_matrix_free(
    doc: &mut ZeitlinCertificateDocument,
    checks: &mut BTreeMap<String, String>,
    verdict: Verdict,
    m: &zeitlin::matrix_free::MatrixFreeAnalysis,
) {
    doc.residuals.drift = Float(m.drift_residual);
    doc.matrix_free = Some(ZeitlinMatrixFreeRecord {
        dimension: m.dimension as u64,
        distinct_eigenvalues: m.distinct_eigenvalues,
        restricted_ritz: m.restricted_ritz.map(|(lo, hi)| [Float(lo), Float(hi)]),
        indefinite: m.indefinite,
        drift_residual: Float(m.drift_residual),
        drift_norm: Float(m.drift_norm),
        eigenvalue: m.eigenvalue.map(|(re, im)| [Float(re), Float(im)]),
        backward_error: m.backward_error.map(Float),
        best: m
            .best
            .filter(|(re, _, _)| *re > m.resolution && m.eigenvalue.is_none())
            .map(|(re, im, e)| [Float(re), Float(im), Float(e)]),
        resolution: Float(m.resolution),
    });
    if verdict == Verdict::LinearlyUnstable {
        doc.growth_rate = m.eigenvalue.map(|(re, _)| Float(re));
        checks.insert(
            "instability".to_string(),
            "numerical: an eigenpair (lambda, v) of the drift found matrix-free (Arnoldi on a Strang-split propagator exp(tau A), then Davidson on A preconditioned by the transport), accepted when its backward error |A v - lambda v|_F / |v|_F, computed with A in the spin basis, is at most 1e-6 of |A|_est and 1e-3 of Re lambda: lambda is an exact eigenvalue of A + E with |E|_F that small (evidence, not a proof, for a non-normal A)".to_string(),
        );
    }
}

/// A general state's dense analysis in real coordinates of su(N).
fn fill_dense(
    doc: &mut ZeitlinCertificateDocument,
    checks: &mut BTreeMap<String, String>,
    spec: &ZeitlinSpec,
    verdict: Verdict,
    d: &zeitlin::general::DenseAnalysis,
) {
    doc.residuals.drift = Float(d.drift_residual);
    doc.dense = Some(ZeitlinDenseRecord {
        dimension: d.dimension as u64,
        distinct_eigenvalues: d.distinct_eigenvalues,
        restricted_margin: d.restricted_margin.is_finite().then_some(Float(d.restricted_margin)),
        energy_coefficient: Float(d.energy),
        infimum: d.infimum.map(Float),
        condition_number: d.condition_number.map(Float),
        drift_residual: Float(d.drift_residual),
    });
    doc.growth_rate = d.growth_rate.filter(|_| verdict == Verdict::LinearlyUnstable).map(Float);
    match verdict {
        Verdict::Stable => {
            doc.sigma2 = d.sigma2.map(Float);
            checks.insert(
                "sigma2".to_string(),
                "numerical: lambda_max(Q, P) by a dense generalized eigenproblem at a Casimir Hessian built for a target just above the infimum over it (dense.infimum)".to_string(),
            );
            doc.stopping = stopping_record(
                spec.stopping,
                d.sigma2,
                "P(|dW_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dW_0|_P^2 = delta, with the numerical Sigma^2: an estimate, not a guarantee",
            );
        }
        Verdict::LinearlyUnstable => {
            checks.insert(
                "instability".to_string(),
                "numerical: the eigenvalues of the dense drift (dimension N^2 - 1, faer), and the largest real part exceeds 1e-6 of the largest modulus".to_string(),
            );
        }
        _ => {}
    }
}

/// The verdict and its evidence from the zonal pipeline's analysis.
fn fill_zonal(
    doc: &mut ZeitlinCertificateDocument,
    checks: &mut BTreeMap<String, String>,
    spec: &ZeitlinSpec,
    a: &ZeitlinAnalysis,
) {
    doc.verdict = a.verdict;
    doc.reason = a.reason.clone();
    // Below the instability threshold the rate is rounding (an imaginary
    // eigenvalue moved off the axis by about sqrt(eps) |A|): it differs
    // between machines and is not recorded; the reason says what it shows.
    doc.growth_rate = a.growth_rate.filter(|_| a.verdict == Verdict::LinearlyUnstable).map(Float);
    match a.verdict {
        Verdict::Stable => {
            let choice = a.choice.as_ref();
            let exact_structure = choice.is_some_and(|c| c.energy == 0.0);
            // Q = 0 identically for the Casimir–momentum form (diagonal P
            // commutes with diagonal noise) and P's definiteness is verified:
            // Sigma^2 = 0 follows from the structure. Otherwise Sigma^2 is a
            // bisection estimate and sigma2_upper, when proved, a bound.
            let level = if exact_structure { VerificationLevel::ExactStructure } else { a.level };
            let proved = !exact_structure && level == VerificationLevel::VerifiedFloat;
            doc.level = LevelOrNone(Some(level));
            checks.insert(
                "form".to_string(),
                "P_m = eps G_m + D_c (G_m = -Delta_m^-1) is shown definite per block by a verified (rounding-aware) Cholesky of the pentadiagonal Delta_m P_m Delta_m".to_string(),
            );
            checks.insert(
                "sigma2".to_string(),
                if exact_structure {
                    "exact structure: the Casimir–momentum form is diagonal in every block and the noise is diagonal, so Q = 0 identically and Sigma^2 = 0".to_string()
                } else if proved {
                    "verified_float: per block, s P_m - Q_m ≻ 0 at s = sigma2_upper, by a verified (rounding-aware) L D L^T inertia test of a banded lifting (the Schur complement of its lower block is s P_m - Q_m; Haynsworth), for the floating-point c, Delta_m and noise values as stored (P_e from a tridiagonal solve, its conservation measured by residuals.drift); sigma2 and the blocks' lambda_max are the upper ends of floating-point bisection brackets (estimates)".to_string()
                } else {
                    "numerical: per block, lambda_max(Q_m, P_m) by bisection on the floating-point inertia of a banded lifting (an estimate; the verified test did not prove a bound)".to_string()
                },
            );
            doc.sigma2 = a.sigma2.map(Float);
            doc.sigma2_upper = if proved { a.sigma2_upper.map(Float) } else { None };
            let (bound, s) = if exact_structure {
                ("P(|dW_t|_P^2 > epsilon) <= delta/epsilon for all t when |dW_0|_P^2 = delta (Sigma^2 = 0: the form is conserved along every path)", a.sigma2)
            } else if proved {
                ("P(|dW_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dW_0|_P^2 = delta, with Sigma^2 = sigma2_upper (proved)", a.sigma2_upper)
            } else {
                ("P(|dW_t|_P^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dW_0|_P^2 = delta, with the estimated Sigma^2: an estimate, not a guarantee (Sigma^2 is not proved)", a.sigma2)
            };
            doc.stopping = stopping_record(spec.stopping, s, bound);
            doc.form = choice.map(|c| ZeitlinFormRecord {
                family: format!(
                    "eps H + tr Phi(W)/N + beta J with eps in {{{}}} (P is defined up to a positive factor), beta by golden section on the definite interval, Phi'' fixed by the first variation on distinct eigenvalues of W_e",
                    if spec.settings.zonal.casimir_momentum { "0, +1, -1; eps = 0 first" } else { "+1, -1" }
                ),
                energy_coefficient: Float(c.energy),
                momentum_coefficient: Float(c.momentum),
                free_curvature: Float(c.free_curvature),
                attained: a.attained,
            });
            // Under exact structure every block's lambda_max is 0 by Q = 0:
            // nothing to list (N - 1 zeros at N = 2048).
            if !exact_structure {
                doc.blocks = a
                    .blocks
                    .iter()
                    .map(|b| ZeitlinBlockRecord { m: b.m as u64, lambda_max: Float(b.lambda_max) })
                    .collect();
            }
        }
        Verdict::LinearlyUnstable => {
            doc.level = LevelOrNone(Some(a.level));
            checks.insert(
                "instability".to_string(),
                "numerical: the eigenvalues of each block's drift (i/hbar)(D_dpi + D_domega G_m), dense, and the largest real part exceeds 1e-6 of the drift's scale".to_string(),
            );
        }
        _ => {}
    }
}

/// Re-check a Zeitlin certificate: its shape, the embedded spec and
/// settings, the digest, then re-derivation and comparison (floating-point
/// fields to [`ZEITLIN_TOLERANCE`]), with `.npy` paths relative to `base`
/// (the certificate's folder), progress and cancellation.
pub(crate) fn check_zeitlin_certificate_with(
    cert: &Value,
    base: Option<&Path>,
    progress: &Progress,
) -> std::result::Result<CheckReport, CheckError> {
    let map = as_object(cert, "$").map_err(CheckError::BadInput)?;
    let spec_value = required(map, "spec", "$").map_err(CheckError::BadInput)?.clone();
    crate::check::check_engine(map)?;
    crate::document::from_value::<ZeitlinCertificateDocument>(cert)
        .map_err(|e| fail(&e.path, format!("not a certificate as this engine writes them: {}", e.message)))?;
    let mut spec = zeitlin_spec_from_value_in(spec_value, base).map_err(|e| {
        fail(
            &format!("$.spec{}", e.path.trim_start_matches('$')),
            format!("the embedded spec is not valid: {}", e.message),
        )
    })?;
    spec.settings = match map.get("settings") {
        None => GeneralSettings::default(),
        Some(v) => crate::document::from_value_at::<ZeitlinSettingsDoc>(v, "$.settings")
            .and_then(|d| read_settings(&d, "$.settings"))
            .map_err(|e| fail(&e.path, format!("the recorded settings are not valid: {}", e.message)))?,
    };
    if cert.get("spec_sha256").and_then(Value::as_str) != Some(spec_digest(&spec.raw).as_str()) {
        return Err(fail("$.spec_sha256", "does not match the embedded spec".into()));
    }
    // A file the spec reads that no longer matches its recorded hash is the
    // cause of whatever else differs: said first.
    let recorded = cert.pointer("/model/files").and_then(Value::as_array).cloned().unwrap_or_default();
    for (i, f) in spec.files.iter().enumerate() {
        let then = recorded.get(i).and_then(|r| r.get("sha256")).and_then(Value::as_str);
        if then != Some(f.sha256.as_str()) {
            return Err(fail(
                &format!("$.model.files[{i}].sha256"),
                format!(
                    "the file {} ({}) is not the one certified: its SHA-256 is now {}",
                    exact::quote(&f.path, 80),
                    f.field,
                    f.sha256
                ),
            ));
        }
    }
    let analysis = analyse_zeitlin_with(&spec, progress);
    progress.check()?;
    let expected = serde_json::to_value(zeitlin_certificate_document(&spec, &analysis)).unwrap_or_default();
    compare_with(&expected, cert, "$", 0.0, ZEITLIN_TOLERANCE)?;
    // T by the one rule, at the stated bound (proved, or the estimate the
    // certificate says it is).
    let bound = cert.get("sigma2_upper").or(cert.get("sigma2")).and_then(Value::as_f64);
    crate::check::check_stopping(cert, spec.stopping, bound)?;
    let level = expected.get("level").and_then(Value::as_str).and_then(|s| s.parse::<VerificationLevel>().ok());
    let (verdict, sigma2) = match &analysis {
        ZeitlinOutcome::Zonal(Ok(a)) => (a.verdict, a.sigma2),
        ZeitlinOutcome::General(g) => match g.as_ref() {
            Ok(g) => (
                g.verdict,
                g.zonal.as_ref().and_then(|r| r.analysis.sigma2).or(g.dense.as_ref().and_then(|d| d.sigma2)),
            ),
            Err(_) => (Verdict::Inconclusive, None),
        },
        _ => (Verdict::Inconclusive, None),
    };
    Ok(CheckReport { name: spec.name.clone(), verdict, level, sigma2 })
}
