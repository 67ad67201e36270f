//! Fluid specs (`"fluid": {...}`): 2D Euler about a shear flow, and their
//! certificates.
//!
//! ```
//! let text = r#"{
//!   "name": "channel",
//!   "fluid": {"model": "incompressible", "x_period": "2*pi", "y_interval": [0, "pi"],
//!             "boundary": "walls", "shear_flow": "sin(y)", "noise": ["0.3*cos(y)"],
//!             "ny": 64, "x_modes": 4}
//! }"#;
//! let spec = spec::parse_fluid_spec(text).unwrap();
//! let cert = spec::certify_fluid(&spec);
//! assert_eq!(cert["verdict"], "stable");
//! spec::check_certificate_value(&cert).unwrap();
//! let bad = text.replace("\"ny\": 64", "\"ny\": 60");
//! assert_eq!(spec::parse_fluid_spec(&bad).unwrap_err().path, "$.fluid.ny");
//! ```

use crate::certificate::{spec_digest, CERTIFICATE_VERSION, ENGINE_VERSION};
use crate::check::{compare_with, fail, CheckError, CheckReport};
use crate::document::{
    BoundaryName, Count, Expression, FluidSettingsDoc, FluidSpecDocument, ModelName, NoiseEntry, Real,
};
use crate::json::{as_object, child, index, required, type_name, Result, SpecError};
use crate::parse::Stopping;
use crate::record::{
    CompressibleRecord, ConvergenceRecord, DefectPoint, DiscretePseudomomentumRecord, DiscreteSdeRecord,
    DiscretisationRecord, Engine, Float, FluidCertificateDocument, FluidFormRecord, FluidOptimisationRecord,
    GeneratorRecord, LevelOrNone, ModeRecord, ModeSearchRecord, PaperRecord, PseudomomentumRowRecord,
    SearchedGridRecord, ShiftPoint, UnstableModeRecord,
};
use fluid::analysis::{
    analyse, analyse_with, prove_mode_bounds, table_resolutions, FluidAnalysis, FluidModel, FluidProblem, FluidSettings,
};
use fluid::expr::{parse, Expr};
use fluid::grid::{Boundary, ELEMENT_DEGREE};
use fluid::profile::{Potential, Profile, ProfileError};
use outcome::{Cancelled, Progress, Sign, Verdict, VerificationLevel};
use serde_json::Value;
use std::collections::BTreeMap;

/// Relative tolerance when re-checking the floating-point fields of a fluid
/// certificate that are estimates (Lanczos values, the convergence table,
/// the shift curve): the computations are deterministic, so this only
/// absorbs another CPU's rounding. The claims are not compared but proved:
/// a per-mode `sigma2_upper` below the re-derived one must pass the verified
/// Cholesky test at the stated value, and `T` may not exceed the stopping
/// time of the stated (proved) `sigma2_upper`.
pub const FLUID_TOLERANCE: f64 = 1e-9;

/// Largest `|a|`, `|b|` of the y-interval, and the bounds on `k L` (`L` the
/// interval's length, `k = 2 pi m / x_period` the wavenumbers): outside
/// them the discrete operators (`k^2` against `1/h^2`) leave the range of
/// doubles.
pub const MAX_COORDINATE: f64 = 1e100;

/// Bounds on `k L` for the wavenumbers of the spec (see [`MAX_COORDINATE`]).
pub const KL_RANGE: (f64, f64) = (1e-100, 1e100);

/// Smallest and largest accepted `ny`.
pub const NY_RANGE: (usize, usize) = (16, 4096);

/// Largest accepted number of x-modes.
pub const MAX_X_MODES: usize = 2048;

/// Largest accepted work of the dense verified checks (`2 x_modes ny^3 / 3`).
pub const MAX_DENSE_FLOPS: f64 = 1e12;

/// Largest accepted size of one copy of the matrix the banded verified
/// check of a mode factors (`rows (bandwidth + 1)` doubles; both models:
/// the compressible one runs the incompressible analysis first;
/// [`fluid::walls_check::lifted_size`]), in bytes: 256 MiB. A check keeps
/// about six such copies and two modes ran at once on the 2-core machine,
/// so the peak was about 3 GiB (measured: 28 noise fields at
/// `ny = 4096`, 265 MB a copy, peak 3.18 GB); on more cores
/// `fluid::analysis::check_threads` keeps the modes at once within 4 GiB.
pub const MAX_BANDED_BYTES: f64 = 268_435_456.0;

/// Largest accepted work of the banded verified checks, `x_modes rows
/// (bandwidth + 1)^2` ([`fluid::walls_check::lifted_size`]): about four
/// minutes on two cores (measured: 4 modes of 28 noise fields
/// at `ny = 4096`, work 3.6e10, took 11 s).
pub const MAX_BANDED_WORK: f64 = 1e12;

/// The spec field a work limit names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LimitedField {
    /// `fluid.x_modes`.
    XModes,
    /// `fluid.noise`.
    Noise,
}

/// The work limits of the verified checks for `x_modes` modes of a grid of
/// `ny` with `noise_fields` noise fields, both models (the compressible one
/// runs the incompressible analysis first, `fluid::analysis::analyse_with`):
/// the field to name and the message when one is passed. Also called by
/// `verify simulate`, whose `--ny` re-runs the analysis at another grid.
///
/// * The dense verified check costs about `n^3/3` multiply-adds per matrix,
///   two matrices per mode: work that would run for hours is refused. It
///   runs as the fallback on walls grids up to `DENSE_FALLBACK_UNKNOWNS`
///   unknowns, and alone where `fluid::modes::dense_check_preferred`.
/// * The banded check of a mode factors a matrix of `J + 2` unknowns per
///   node (`fluid::walls_check::lifted_size`): its time grows like `J^3`
///   and its memory like `J^2`, so many noise fields on a fine grid are
///   refused rather than run out of memory. `J` counts every field given
///   (constant ones are dropped when the modes are built: an upper bound;
///   with fewer fields a mode may run the banded check where this assumed
///   the dense one, at a cost below the dense one's by that choice's
///   definition). Where the dense check is preferred the banded one does
///   not run.
pub(crate) fn work_limits(
    boundary: Boundary,
    ny: usize,
    x_modes: usize,
    noise_fields: usize,
) -> std::result::Result<(), (LimitedField, String)> {
    let unknowns = fluid::grid::unknowns(boundary, ny);
    let dense_n =
        if boundary == Boundary::Walls && unknowns <= fluid::modes::DENSE_FALLBACK_UNKNOWNS { unknowns } else { 0 };
    let n = dense_n as f64;
    let flops = 2.0 * x_modes as f64 * n * n * n / 3.0;
    if flops > MAX_DENSE_FLOPS {
        return Err((
            LimitedField::XModes,
            format!(
                "x_modes = {x_modes} at ny = {ny} needs about {flops:.0e} floating-point operations for the dense verified checks (limit {MAX_DENSE_FLOPS:.0e}, roughly ten minutes on two cores): reduce x_modes or ny"
            ),
        ));
    }
    if fluid::modes::dense_check_preferred(boundary, unknowns, noise_fields) {
        return Ok(());
    }
    let (rows, width) =
        fluid::walls_check::lifted_size(unknowns, fluid::grid::stiffness_bandwidth(boundary), noise_fields);
    let copy = rows as f64 * (width + 1) as f64;
    let bytes = 8.0 * copy;
    if bytes > MAX_BANDED_BYTES {
        return Err((
            LimitedField::Noise,
            format!(
                "{noise_fields} noise fields at ny = {ny} make the banded verified check factor a matrix of {rows} rows and bandwidth {width}: {:.0} MiB a copy, and a check holds about six (limit {:.0} MiB a copy): give fewer noise fields or a smaller ny",
                bytes / 1048576.0,
                MAX_BANDED_BYTES / 1048576.0
            ),
        ));
    }
    let work = x_modes as f64 * copy * (width + 1) as f64;
    if work > MAX_BANDED_WORK {
        return Err((
            LimitedField::XModes,
            format!(
                "x_modes = {x_modes} with {noise_fields} noise fields at ny = {ny} needs about {work:.1e} floating-point operations for the banded verified checks (limit {MAX_BANDED_WORK:.0e}, a few minutes on two cores): reduce x_modes, the noise fields or ny"
            ),
        ));
    }
    Ok(())
}

/// A parsed fluid spec.
#[derive(Clone, Debug)]
pub struct FluidSpec {
    /// `name`.
    pub name: String,
    /// The spec as given.
    pub raw: Value,
    /// The problem.
    pub problem: FluidProblem,
    /// The stopping question.
    pub stopping: Option<Stopping>,
    /// Numerical settings.
    pub settings: FluidSettings,
    /// The optional `sweep` section.
    pub sweep: crate::sweep::SweepSection,
}

/// Parse a fluid spec from text.
pub fn parse_fluid_spec(text: &str) -> Result<FluidSpec> {
    let value: Value = crate::json::parse_json(text)?;
    fluid_spec_from_value(value)
}

fn expr(e: &Expression, path: &str, params: &BTreeMap<String, f64>) -> Result<Expr> {
    let text = &e.0;
    parse(text, params).map_err(|err| SpecError::new(path, format!("in '{text}': {err}")))
}

fn constant(e: &Expression, path: &str, params: &BTreeMap<String, f64>) -> Result<f64> {
    let e = expr(e, path, params)?;
    let x = e.constant().ok_or_else(|| SpecError::new(path, "must be a constant (it may not depend on y)"))?;
    if !x.is_finite() {
        return Err(SpecError::new(path, format!("is not finite ({x})")));
    }
    Ok(x)
}

fn count(c: Count, path: &str) -> Result<usize> {
    usize::try_from(c.0).map_err(|_| SpecError::new(path, "too large"))
}

impl FluidSpec {
    /// A fluid spec from a document built in Rust (no JSON text); `raw` is
    /// the document as JSON.
    ///
    /// ```
    /// use spec::document::{BoundaryName, Count, FluidDoc, FluidSpecDocument, ModelName};
    /// let doc = FluidSpecDocument {
    ///     name: "channel".into(),
    ///     fluid: FluidDoc {
    ///         model: ModelName::Incompressible,
    ///         x_period: "2*pi".into(),
    ///         y_interval: vec!["0".into(), "pi".into()],
    ///         boundary: BoundaryName::Walls,
    ///         shear_flow: "sin(y)".into(),
    ///         noise: vec!["0.3*cos(y)".into()],
    ///         ny: Count(64),
    ///         x_modes: Count(2),
    ///         sound_speed: None,
    ///     },
    ///     ..Default::default()
    /// };
    /// let spec = spec::FluidSpec::from_document(&doc).unwrap();
    /// assert_eq!(spec.problem.ny, 64);
    /// ```
    pub fn from_document(doc: &FluidSpecDocument) -> Result<FluidSpec> {
        let value = serde_json::to_value(doc).map_err(|e| SpecError::new("$", e.to_string()))?;
        fluid_spec_from_value(value)
    }
}

/// Parse a fluid spec from a JSON value.
pub fn fluid_spec_from_value(value: Value) -> Result<FluidSpec> {
    let root = "$";
    if !value.is_object() {
        return Err(SpecError::new(root, format!("expected an object, found {}", type_name(&value))));
    }
    let doc: FluidSpecDocument = crate::document::from_value(&value)?;
    let name = doc.name.clone();
    if name.trim().is_empty() {
        return Err(SpecError::new(child(root, "name"), "must not be empty"));
    }
    let params = read_parameters(&doc.parameters, &child(root, "parameters"))?;
    let fpath = child(root, "fluid");
    let f = &doc.fluid;
    let model = read_model(f, &fpath, &params)?;
    let xpath = child(&fpath, "x_period");
    let x_period = constant(&f.x_period, &xpath, &params)?;
    if x_period <= 0.0 {
        return Err(SpecError::new(xpath, format!("must be positive, got {x_period}")));
    }
    let (a, b) = read_y_interval(&f.y_interval, &child(&fpath, "y_interval"), &params)?;
    let length = b - a;
    let boundary = match f.boundary {
        BoundaryName::Walls => Boundary::Walls,
        BoundaryName::Periodic => Boundary::Periodic,
    };
    let upath = child(&fpath, "shear_flow");
    let u = expr(&f.shear_flow, &upath, &params)?;
    let npath = child(&fpath, "noise");
    let (noise, potentials) = read_noise(&f.noise, &npath, &params)?;
    let (ny, x_modes) = read_grid(f, &fpath)?;
    let kpath = child(&fpath, "x_modes");
    // The wavenumbers against the interval: k^2 M beside the stiffness 1/h
    // must stay within the range of doubles.
    let two_pi = 2.0 * std::f64::consts::PI;
    let (k_lo, k_hi) = (two_pi / x_period * length, two_pi * x_modes as f64 / x_period * length);
    if !(k_lo >= KL_RANGE.0 && k_hi <= KL_RANGE.1) {
        return Err(SpecError::new(
            xpath,
            format!(
                "the wavenumbers k = 2 pi m / x_period times the interval length span [{k_lo:e}, {k_hi:e}], outside [{:e}, {:e}]: rescale x or y",
                KL_RANGE.0, KL_RANGE.1
            ),
        ));
    }
    work_limits(boundary, ny, x_modes, noise.len()).map_err(|(field, message)| {
        SpecError::new(
            match field {
                LimitedField::XModes => &kpath,
                LimitedField::Noise => &npath,
            },
            message,
        )
    })?;
    let profile = Profile::new(u, noise, (a, b), boundary).with_potentials(potentials);
    // Profile checks up front so the error names the spec field.
    profile.check(&[]).map_err(|e| profile_error(e, &fpath))?;
    let stopping =
        doc.stopping.as_ref().map(|s| crate::parse::read_stopping(s, &child(root, "stopping"))).transpose()?;
    let settings = match &doc.settings {
        Some(s) => read_settings(s, &child(root, "settings"))?,
        None => FluidSettings::default(),
    };
    let names: Vec<String> = params.keys().cloned().collect();
    let sweep = crate::sweep::read_sweep_section(doc.sweep.as_ref(), &child(root, "sweep"), &names)?;
    let problem = FluidProblem { model, profile, x_period, ny, x_modes };
    Ok(FluidSpec { name, raw: value, problem, stopping, settings, sweep })
}

/// The spec's parameters, in order, each a constant of the ones before it;
/// names that would shadow `y`, `pi`, a function or `compatible` refused.
fn read_parameters(
    given: &BTreeMap<String, crate::document::Expression>,
    ppath: &str,
) -> Result<BTreeMap<String, f64>> {
    let mut params = BTreeMap::new();
    for (key, v) in given {
        let kpath = child(ppath, key);
        let valid = key.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid || ["y", "pi", "compatible"].contains(&key.as_str()) || fluid::expr::FUNCTIONS.contains(&key.as_str())
        {
            return Err(SpecError::new(
                kpath,
                format!("'{key}' is not a valid parameter name (letters, digits, '_'; not y, pi, a function or 'compatible')"),
            ));
        }
        let x = constant(v, &kpath, &params)?;
        params.insert(key.clone(), x);
    }
    Ok(params)
}

/// The model, and the sound speed a compressible one needs.
fn read_model(f: &crate::document::FluidDoc, fpath: &str, params: &BTreeMap<String, f64>) -> Result<FluidModel> {
    let spath = child(fpath, "sound_speed");
    Ok(match f.model {
        ModelName::Incompressible => {
            if f.sound_speed.is_some() {
                return Err(SpecError::new(spath, "only a compressible model has a sound speed"));
            }
            FluidModel::Incompressible
        }
        ModelName::Compressible => {
            let speed = f.sound_speed.as_ref().ok_or_else(|| SpecError::new(&spath, "required field is missing"))?;
            let c = constant(speed, &spath, params)?;
            if c <= 0.0 {
                return Err(SpecError::new(spath, format!("must be positive, got {c}")));
            }
            FluidModel::Compressible { sound_speed: c }
        }
    })
}

/// The interval `[a, b]` of `y`: ordered, within the range the
/// discretisation keeps in doubles, and long enough for distinct nodes.
fn read_y_interval(
    iv: &[crate::document::Expression],
    ipath: &str,
    params: &BTreeMap<String, f64>,
) -> Result<(f64, f64)> {
    if iv.len() != 2 {
        return Err(SpecError::new(ipath, format!("expected [a, b], got {} entries", iv.len())));
    }
    let a = constant(&iv[0], &index(ipath, 0), params)?;
    let b = constant(&iv[1], &index(ipath, 1), params)?;
    if a >= b {
        return Err(SpecError::new(index(ipath, 1), format!("must exceed the left end {a}, got {b}")));
    }
    for (i, x) in [a, b].into_iter().enumerate() {
        if x.abs() > MAX_COORDINATE {
            return Err(SpecError::new(
                index(ipath, i),
                format!("|{x:e}| exceeds {MAX_COORDINATE:e}: rescale y (the discretisation would leave the range of doubles)"),
            ));
        }
    }
    let length = b - a;
    if length < 1e-10 * a.abs().max(b.abs()) || length < 1.0 / MAX_COORDINATE {
        return Err(SpecError::new(
            index(ipath, 1),
            format!("the interval [{a:e}, {b:e}] is too short for its position (length {length:e}; at least 1e-10 of max(|a|, |b|) and 1e-100): the grid nodes would not be distinct doubles"),
        ));
    }
    Ok((a, b))
}

/// The noise fields, each a transport field with an optional potential.
fn read_noise(
    entries: &[NoiseEntry],
    npath: &str,
    params: &BTreeMap<String, f64>,
) -> Result<(Vec<fluid::expr::Expr>, Vec<Potential>)> {
    if entries.len() > crate::parse::MAX_NOISE_FIELDS {
        return Err(SpecError::new(
            npath,
            format!("at most {} noise fields are supported", crate::parse::MAX_NOISE_FIELDS),
        ));
    }
    let mut noise = Vec::with_capacity(entries.len());
    let mut potentials = Vec::with_capacity(entries.len());
    for (i, entry) in entries.iter().enumerate() {
        let ipath = index(npath, i);
        match entry {
            NoiseEntry::Transport(e) => {
                noise.push(expr(e, &ipath, params)?);
                potentials.push(Potential::None);
            }
            NoiseEntry::WithPotential { transport, potential } => {
                noise.push(expr(transport, &child(&ipath, "transport"), params)?);
                potentials.push(if potential.0.trim() == "compatible" {
                    Potential::Compatible
                } else {
                    Potential::given(expr(potential, &child(&ipath, "potential"), params)?)
                });
            }
        }
    }
    Ok((noise, potentials))
}

/// The grid: `ny` (a multiple of the element degree, in range) and the
/// number of x-modes.
fn read_grid(f: &crate::document::FluidDoc, fpath: &str) -> Result<(usize, usize)> {
    let nypath = child(fpath, "ny");
    let ny = count(f.ny, &nypath)?;
    if ny < NY_RANGE.0 {
        return Err(SpecError::new(
            nypath,
            format!("ny = {ny} is too small: at least {} points are needed", NY_RANGE.0),
        ));
    }
    if ny > NY_RANGE.1 {
        return Err(SpecError::new(nypath, format!("ny = {ny} is too large (at most {})", NY_RANGE.1)));
    }
    if ny % ELEMENT_DEGREE != 0 {
        return Err(SpecError::new(
            nypath,
            format!("ny must be a multiple of the element degree {ELEMENT_DEGREE} (ny / {ELEMENT_DEGREE} spectral elements), got {ny}"),
        ));
    }
    let kpath = child(fpath, "x_modes");
    let x_modes = count(f.x_modes, &kpath)?;
    if x_modes == 0 || x_modes > MAX_X_MODES {
        return Err(SpecError::new(kpath, format!("must be between 1 and {MAX_X_MODES}, got {x_modes}")));
    }
    Ok((ny, x_modes))
}

fn profile_error(e: ProfileError, fpath: &str) -> SpecError {
    let field = |what: &str| -> String {
        let base = what.trim_end_matches('\'');
        if let Some(rest) = base.strip_prefix("noise[") {
            format!("{fpath}.noise[{}", rest)
        } else {
            format!("{fpath}.{base}")
        }
    };
    match &e {
        ProfileError::NotFinite { what, y } => {
            let derivative = what.matches('\'').count();
            let which =
                if derivative == 0 { String::new() } else { format!(" (its derivative of order {derivative})") };
            SpecError::new(field(what), format!("is not finite at y = {y}{which} on the interval"))
        }
        ProfileError::NotPeriodic { what, .. } => SpecError::new(field(what), e.to_string()),
        _ => SpecError::new(fpath, e.to_string()),
    }
}

fn read_settings(doc: &FluidSettingsDoc, path: &str) -> Result<FluidSettings> {
    let mut s = FluidSettings::default();
    if let Some(Real(x)) = doc.lanczos_tolerance {
        if !(1e-14..=1e-3).contains(&x) {
            return Err(SpecError::new(
                child(path, "lanczos_tolerance"),
                format!("must be between 1e-14 and 1e-3, got {x}"),
            ));
        }
        s.lanczos_tolerance = x;
    }
    if let Some(t) = doc.convergence_from {
        let p = child(path, "convergence_from");
        let n = count(t, &p)?;
        if !(16..=4096).contains(&n) || n % ELEMENT_DEGREE != 0 {
            return Err(SpecError::new(
                p,
                format!("must be a multiple of {ELEMENT_DEGREE} between 16 and 4096, got {n}"),
            ));
        }
        s.convergence_from = n;
    }
    if let Some(t) = doc.instability_ny {
        let p = child(path, "instability_ny");
        let n = count(t, &p)?;
        if !(32..=1024).contains(&n) || n % ELEMENT_DEGREE != 0 {
            return Err(SpecError::new(
                p,
                format!("must be a multiple of {ELEMENT_DEGREE} between 32 and 1024, got {n}"),
            ));
        }
        s.instability_ny = n;
    }
    Ok(s)
}

/// The recorded settings of a certificate, read as the spec's are.
fn recorded_settings(v: Option<&Value>, path: &str) -> Result<FluidSettings> {
    match v {
        None => Ok(FluidSettings::default()),
        Some(v) => read_settings(&crate::document::from_value_at(v, path)?, path),
    }
}

/// The settings as the certificate records them (all keys).
fn settings_document(s: &FluidSettings) -> FluidSettingsDoc {
    FluidSettingsDoc {
        lanczos_tolerance: Some(Real(s.lanczos_tolerance)),
        convergence_from: Some(Count(s.convergence_from as u64)),
        instability_ny: Some(Count(s.instability_ny as u64)),
    }
}

/// Run the fluid pipeline and build the certificate JSON.
pub fn certify_fluid(spec: &FluidSpec) -> Value {
    certify_fluid_spec(spec).json
}

/// A fluid certificate with the analysis behind it (the analysis is an
/// error when the profile cannot be discretised; the certificate then says
/// `inconclusive`).
#[derive(Clone, Debug)]
pub struct FluidCertificate {
    /// The certificate JSON.
    pub json: Value,
    /// The analysis, or why the profile could not be discretised.
    pub analysis: std::result::Result<FluidAnalysis, fluid::analysis::FluidError>,
}

impl FluidCertificate {
    /// The certificate, typed (the JSON is written from this type, so it
    /// reads back; `None` would mean a bug, not bad input).
    pub fn document(&self) -> Option<FluidCertificateDocument> {
        crate::document::from_value(&self.json).ok()
    }

    /// The verdict.
    pub fn verdict(&self) -> Verdict {
        self.analysis.as_ref().map_or(Verdict::Inconclusive, |a| a.verdict)
    }

    /// The verification level (`None`: no claim is made).
    pub fn level(&self) -> Option<VerificationLevel> {
        self.analysis.as_ref().ok().and_then(|a| a.verification)
    }

    /// `Sigma^2` (the largest over the x-modes), when stable.
    pub fn sigma2(&self) -> Option<f64> {
        self.analysis.as_ref().ok().and_then(|a| a.sigma2)
    }

    /// Re-check the certificate on the checker's own path.
    pub fn check(&self) -> std::result::Result<CheckReport, CheckError> {
        check_fluid_certificate(&self.json)
    }
}

/// Certify a fluid spec, keeping the analysis.
///
/// The Rayleigh-stable channel flow `U = -cos y` on `-1 < y < 1`: `U'' =
/// cos y > 0`, so the pseudomomentum `int omega^2 / U''` is conserved by the
/// drift and by every noise field `(eta(y), 0)`, and `Sigma^2 = 0` by the
/// structure of the form (docs/fluids.md):
///
/// ```
/// let text = r#"{"name": "rayleigh", "fluid": {"model": "incompressible", "x_period": "2*pi",
///   "y_interval": [-1, 1], "boundary": "walls", "shear_flow": "-cos(y)",
///   "noise": ["0.3*sin(y)"], "ny": 32, "x_modes": 2}}"#;
/// let cert = spec::certify_fluid_spec(&spec::parse_fluid_spec(text).unwrap());
/// assert_eq!(cert.verdict(), spec::Verdict::Stable);
/// assert_eq!(cert.level(), Some(spec::VerificationLevel::ExactStructure));
/// assert_eq!(cert.sigma2(), Some(0.0));
/// assert_eq!(cert.check().unwrap().verdict, spec::Verdict::Stable);
/// let doc = cert.document().unwrap();
/// assert_eq!(doc.modes.unwrap().len(), doc.discretisation.unwrap().x_modes as usize);
/// ```
pub fn certify_fluid_spec(spec: &FluidSpec) -> FluidCertificate {
    fluid_certificate(spec, analyse(&spec.problem, &spec.settings))
}

/// [`certify_fluid_spec`] with progress; `Err` when it was cancelled (no
/// certificate is built from a cancelled run).
pub(crate) fn certify_fluid_with(
    spec: &FluidSpec,
    progress: &Progress,
) -> std::result::Result<FluidCertificate, Cancelled> {
    let analysis = analyse_with(&spec.problem, &spec.settings, progress);
    progress.check()?;
    Ok(fluid_certificate(spec, analysis))
}

fn fluid_certificate(
    spec: &FluidSpec,
    analysis: std::result::Result<FluidAnalysis, fluid::analysis::FluidError>,
) -> FluidCertificate {
    let json = match &analysis {
        Ok(a) => fluid_certificate_json(spec, a),
        // The profile was checked at parse time on a fine sample; the grid
        // nodes are checked again here and can still hit a singularity.
        Err(e) => {
            let doc = FluidCertificateDocument {
                verdict: Verdict::Inconclusive,
                reason: format!("the profile cannot be discretised: {e}"),
                level: LevelOrNone(None),
                ..empty_document(spec)
            };
            serde_json::to_value(doc).unwrap_or_default()
        }
    };
    FluidCertificate { json, analysis }
}

/// The certificate JSON of an analysis.
pub fn fluid_certificate_json(spec: &FluidSpec, a: &FluidAnalysis) -> Value {
    serde_json::to_value(fluid_certificate_document(spec, a)).unwrap_or_default()
}

/// The spec's noise list with each incompatible field `i` replaced by
/// `{"transport": eta_i, "potential": "compatible"}` (`None` when every
/// field is compatible).
fn completion(raw: &Value, incompatible: &[usize]) -> Option<Vec<Value>> {
    if incompatible.is_empty() {
        return None;
    }
    let list = raw.pointer("/fluid/noise")?.as_array()?;
    Some(
        list.iter()
            .enumerate()
            .map(|(i, entry)| {
                if !incompatible.contains(&i) {
                    return entry.clone();
                }
                let transport = entry.get("transport").unwrap_or(entry).clone();
                serde_json::json!({"transport": transport, "potential": "compatible"})
            })
            .collect(),
    )
}

/// The parts of a fluid certificate that do not depend on the analysis.
fn empty_document(spec: &FluidSpec) -> FluidCertificateDocument {
    FluidCertificateDocument {
        certificate_version: CERTIFICATE_VERSION,
        engine: Engine { name: "verify".into(), version: ENGINE_VERSION.into() },
        name: spec.name.clone(),
        kind: outcome::CertificateKind::Fluid,
        verdict: Verdict::Inconclusive,
        reason: String::new(),
        level: LevelOrNone(None),
        theorem: crate::theorem::nothing(&crate::theorem::fluid_not_checked(spec.problem.x_modes)),
        checks: None,
        sigma2: None,
        sigma2_upper: None,
        stopping: None,
        spec_sha256: spec_digest(&spec.raw),
        model: None,
        formulation: None,
        discretisation: None,
        form: None,
        modes: None,
        convergence: None,
        paper: None,
        optimisation: None,
        drift_residual: None,
        instability: None,
        instability_search: None,
        compressible: None,
        settings: settings_document(&spec.settings),
        constants: fluid::constants::all().into_iter().map(|(k, v)| (k.to_string(), Float(v))).collect(),
        spec: spec.raw.clone(),
    }
}

/// Build the typed certificate of a fluid spec from its analysis.
pub fn fluid_certificate_document(spec: &FluidSpec, a: &FluidAnalysis) -> FluidCertificateDocument {
    let p = &spec.problem;
    let opt = |x: Option<f64>| x.map(Float);
    let checks = fluid_checks(p, a);
    // T is a guarantee: only a proved upper bound of Sigma^2 gives one (the
    // Lanczos value is a lower estimate).
    let stopping = crate::certificate::stopping_record(
        spec.stopping,
        a.sigma2_upper,
        "P(|dw_t|_V^2 > epsilon) <= (delta/epsilon) exp(Sigma^2 t) for |dw_0|_V^2 = delta, with Sigma^2 = sigma2_upper",
    );
    let formulation = match p.model {
        FluidModel::Incompressible => "vorticity: dw = -ik (U + U'' L^-1) w dt - sum_j ik eta_j w o dW^j per x-mode exp(ikx), L = k^2 - d^2/dy^2 with psi = 0 at walls",
        FluidModel::Compressible { .. } => "momentum-density m = rho u and density rho, noise acting by the coadjoint action (Lie derivative) of (eta_j(y), 0)",
    };
    let discretisation = discretisation_record(p);
    let form = FluidFormRecord {
        kind: a.form.kind.to_string(),
        energy_coefficient: Float(a.form.energy),
        galilean_shift: opt(a.form.galilean_shift),
        // 0 when there is no form (the contract's number, kept).
        sign: Float(a.form.sign.map_or(0.0, Sign::as_f64)),
        casimir_weight: a.form.casimir_weight.clone(),
    };
    let modes = a
        .modes
        .iter()
        .map(|m| ModeRecord {
            m: m.m as u64,
            k: Float(m.k),
            sigma2: Float(m.sigma2),
            sigma2_upper: opt(m.sigma2_upper),
            form_verified: m.form_verified,
            lanczos_iterations: m.iterations as u64,
        })
        .collect();
    let convergence = a
        .convergence
        .iter()
        .map(|r| ConvergenceRecord {
            ny: r.ny as u64,
            sigma2: opt(r.sigma2),
            sigma2_paper_choice: opt(r.sigma2_paper_choice),
        })
        .collect();
    let paper = PaperRecord {
        bound: opt(a.paper_bound),
        bound_formula: "sup_y sum_k eta_k'(y)^2 (the paper's eq. (eta-bound))".into(),
        choice_sigma2: opt(a.paper_choice_sigma2),
        choice: "energy + Casimir with Phi'' = U/U'' (no Galilean shift, c = 0), when that form is definite".into(),
    };
    let optimisation = optimisation_record(spec, a);
    let instability = a.instability.as_ref().map(|u| UnstableModeRecord {
        m: u.m as u64,
        k: Float(u.k),
        growth_rate: Float(u.growth_rate),
        growth_rate_half_resolution: Float(u.growth_rate_coarse),
        ny: u.ny as u64,
    });
    let instability_search = instability_search_records(a);
    let compressible = a.compressible.as_ref().map(|cr| compressible_record(spec, cr));
    let subject = crate::theorem::fluid_subject(
        &spec.name,
        matches!(p.model, FluidModel::Compressible { .. }),
        spec.raw.pointer("/fluid/shear_flow").and_then(Value::as_str).unwrap_or("the spec's profile"),
        match p.profile.boundary {
            Boundary::Walls => "between walls",
            Boundary::Periodic => "periodic in y",
        },
        p.ny,
        p.x_modes,
        a.instability.as_ref().map(|u| (u.m, u.k, u.ny)),
    );
    let theorem = crate::theorem::from_doubles(
        &subject,
        a.verdict,
        a.verification,
        a.sigma2_upper,
        a.sigma2,
        stopping.as_ref(),
        a.instability.as_ref().map(|u| u.growth_rate),
    );
    FluidCertificateDocument {
        verdict: a.verdict,
        reason: a.reason.clone(),
        level: LevelOrNone(a.verification),
        theorem,
        checks: Some(checks),
        sigma2: a.sigma2.map(Float),
        sigma2_upper: a.sigma2_upper.map(Float),
        stopping,
        model: Some(p.model.as_str().to_string()),
        formulation: Some(formulation.into()),
        discretisation: Some(discretisation),
        form: Some(form),
        modes: Some(modes),
        convergence: Some(convergence),
        paper: Some(paper),
        optimisation: Some(optimisation),
        drift_residual: a.drift_residual.map(Float),
        instability,
        instability_search,
        compressible,
        ..empty_document(spec)
    }
}

/// What each part of a fluid verdict rests on.
fn fluid_checks(p: &FluidProblem, a: &FluidAnalysis) -> BTreeMap<String, String> {
    let sigma2_check = match a.verification {
        Some(VerificationLevel::ExactStructure) => "exact: the form is diagonal (a Casimir-momentum or enstrophy form) or the noise is a multiple of the identity, so Q = 0 identically for the discretised operators",
        Some(VerificationLevel::VerifiedFloat) if p.model == FluidModel::Incompressible => "verified_float: at the finest grid, per x-mode, V and sigma2_upper V - Q are positive definite, proved with rounding accounted for by the inertia of a banded lifted matrix (for the exact pencil of the stored stiffness, weights, Casimir weight and noise values) or, for a mode on a grid of at most 1023 unknowns where that proves nothing, by a dense floating-point Cholesky (Rump-style, for the floating-point matrices as computed); sigma2 (the Lanczos Ritz value, a Rayleigh quotient) is a lower estimate",
        Some(VerificationLevel::VerifiedFloat) => "verified_float: at the finest grid, per x-mode, V and sigma2_upper V - Q are positive definite by a floating-point Cholesky with rounding accounted for (Rump-style), for the floating-point matrices as computed; sigma2 (the Lanczos Ritz value, a Rayleigh quotient) is a lower estimate",
        Some(VerificationLevel::Float) => "floating point only: the verified check did not pass",
        _ => "no claim is made",
    };
    [
        ("sigma2", sigma2_check),
        (
            "discretisation",
            if a.compressible.as_ref().is_some_and(|c| c.generator.is_some()) {
                "Q is the continuum generator form evaluated on the discrete space (compressible.generator): the claims are about that quotient with the discrete form K; the convergence table shows how they move under refinement, and compressible.generator.casimir_defect how far the pointwise noise on the discrete K is from it"
            } else {
                "the claims are about the discretised linear SDE; the convergence table shows how they move under refinement"
            },
        ),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect()
}

/// The discretisation: the x-modes, the spectral elements in y, the grid.
fn discretisation_record(p: &FluidProblem) -> DiscretisationRecord {
    let unknowns = match p.profile.boundary {
        Boundary::Walls => p.ny - 1,
        Boundary::Periodic => p.ny,
    };
    DiscretisationRecord {
        x: format!("Fourier modes m = 1..{} (k = 2 pi m / x_period); m = 0 is frozen (A = B = 0)", p.x_modes),
        y: match p.profile.boundary {
            Boundary::Walls => format!(
                "continuous Galerkin spectral elements of degree {ELEMENT_DEGREE} with Gauss-Lobatto-Legendre quadrature, {} elements",
                p.ny / ELEMENT_DEGREE
            ),
            Boundary::Periodic => format!(
                "continuous Galerkin spectral elements of degree {ELEMENT_DEGREE} with Gauss-Lobatto-Legendre quadrature, {} elements around the periodic interval",
                p.ny / ELEMENT_DEGREE
            ),
        },
        ny: p.ny as u64,
        unknowns_per_mode: unknowns as u64,
        x_modes: p.x_modes as u64,
    }
}

/// The optimisation of `Sigma^2` over the Galilean shift and the energy
/// coefficient, and the discrete pseudomomentum where it applies.
fn optimisation_record(spec: &FluidSpec, a: &FluidAnalysis) -> FluidOptimisationRecord {
    let (p, opt) = (&spec.problem, |x: Option<f64>| x.map(Float));
    FluidOptimisationRecord {
        over: "the Galilean (momentum) multiplier c and the energy coefficient e of e H + C_Phi + c M, with the Casimir weight Phi''(omega_e) = (e U + c)/U'' bounded on the closed interval (a form with a continuum limit)".into(),
        shift_curve: a.shift_curve.iter().map(|(c, s)| ShiftPoint { c: Float(*c), sigma2: Float(*s) }).collect(),
        infimum: opt(a.sigma2),
        attained_by: a.form.kind.to_string(),
        discrete_pseudomomentum: (a.verdict == Verdict::Stable)
            .then(|| fluid::analysis::discrete_pseudomomentum(p, &spec.settings))
            .flatten()
            .map(|d| DiscretePseudomomentumRecord {
                meaning: format!(
                    "U'' vanishes only at the walls (y = {}), which carry no unknowns, so on this grid V = diag(m_a / |U''(y_a)|) is definite and conserved by the discretised drift and by every noise field (Q = 0, Sigma^2 = 0 for the discretised linear SDE). It is not the headline: its weight 1/U'' is unbounded in the continuum, cond(V) grows with ny and the V-norm of a perturbation that does not vanish at a wall (norm_of_one, for omega = 1) grows without bound (docs/fluids.md §3, case 3)",
                    d.zeros.iter().map(|z| format!("{z:.6}")).collect::<Vec<_>>().join(", ")
                ),
                sigma2: Float(0.0),
                rows: d
                    .rows
                    .iter()
                    .map(|r| PseudomomentumRowRecord {
                        ny: r.ny as u64,
                        condition_number: Float(r.condition_number),
                        norm_of_one: Float(r.norm_of_one),
                    })
                    .collect(),
            }),
    }
}

/// The search for an unstable mode, per x-mode and grid (absent when none ran).
fn instability_search_records(a: &FluidAnalysis) -> Option<Vec<ModeSearchRecord>> {
    let opt = |x: Option<f64>| x.map(Float);
    (!a.instability_search.is_empty()).then(|| {
        a.instability_search
            .iter()
            .map(|s| ModeSearchRecord {
                m: s.m as u64,
                k: Float(s.k),
                floor: Float(s.floor),
                grids: s
                    .grids
                    .iter()
                    .map(|g| SearchedGridRecord {
                        ny: g.ny as u64,
                        growth_rate: opt(g.growth_rate),
                        phase_speed: opt(g.phase_speed),
                        tracked: g.tracked,
                    })
                    .collect(),
                outcome: s.outcome.as_str().to_string(),
            })
            .collect()
    })
}

/// The compressible model's noise-compatibility test and generator form.
fn compressible_record(spec: &FluidSpec, cr: &fluid::analysis::CompressibleReport) -> CompressibleRecord {
    let opt = |x: Option<f64>| x.map(Float);
    CompressibleRecord {
        sound_speed: Float(cr.sound_speed),
        noise_residuals: cr.noise_residuals.iter().map(|x| Float(*x)).collect(),
        noise_residual_formula: "sup_y |U eta_k' + r_k'|: the y-momentum (grad sigma)^T m + rho grad r put into the equilibrium by noise field k = ((eta_k, 0), r_k)".into(),
        compatible_noise: "eta constant wherever U != 0, or any eta with the potential r' = -U eta' ({\"transport\": eta, \"potential\": \"compatible\"})".into(),
        compatible_completion: completion(&spec.raw, &cr.incompatible),
        galilean_shift_interval: cr.shift_interval.map(|(lo, hi)| vec![Float(lo), Float(hi)]),
        incompressible_verdict: cr.incompressible_verdict,
        incompressible_sigma2: opt(cr.incompressible_sigma2),
        generator: cr.generator.as_ref().map(|g| GeneratorRecord {
            formulation: "g* coordinates (dm1, dm2, drho) on the spectral-element nodes (dm2 = 0 at the walls); K = int |dm1 + c drho|^2 + |dm2|^2 + (c_s^2 - (U + c)^2)|drho|^2 + w |dq|^2, dq = ik dm2 - dm1' + U drho' + 2U' drho, w = (U + c)/U''; the noise ((eta, 0), r) with r' = -U eta' transports dq, so the Casimir part contributes nothing and Q = sum_j int eta_j'^2 |dm1 - U drho|^2 (the continuum generator form on the discrete space); Sigma^2 = lambda_max(Q, K)".into(),
            galilean_shift: Float(g.shift),
            continuum_bound: opt(g.continuum_bound),
            continuum_bound_formula: "sup_y sum_j eta_j'(y)^2 c_s^2 / (c_s^2 - (U(y) + c)^2), enclosed by interval arithmetic: Q <= that times the acoustic part of K, and the Casimir part is >= 0".into(),
            casimir_defect_meaning: "|lambda|_max(Q_B - Q, K) of the gravest mode, Q_B the generator form of the pointwise noise on the discrete K: the discrete error of B dq = -ik eta dq, zero in the continuum".into(),
            casimir_defect: g.casimir_defect.iter().map(|(ny, d)| DefectPoint { ny: *ny as u64, defect: Float(*d) }).collect(),
            discrete_sde: g.discrete_sde.map(|(m, s)| DiscreteSdeRecord {
                meaning: "the discretised linear SDE dX = A X dt + sum_j B_j X o dW_j with the pointwise noise B_j: d E V/dt = E X^H Q_B X (Ito), Q_B = K A~ + A~^H K + sum_j B_j^H K B_j, so E V(t) <= exp(sigma2 t) V(0) for every x-mode at this ny and every start, with sigma2 = max over the modes of lambda_max(Q_B, K) (a Lanczos estimate, float, not verified). Q_B - Q is the Casimir defect: it tends to 0 under refinement at fixed k and grows with k, so on a given grid the shortest waves of the discrete SDE can outgrow the certified Sigma^2 (docs/fluids.md §1b)".into(),
                ny: spec.problem.ny as u64,
                m: m as u64,
                sigma2: Float(s),
            }),
            drift_residual: opt(g.drift_residual),
        }),
    }
}

/// Re-check a fluid certificate: independent claims, then re-derivation and
/// comparison (floating-point fields to [`FLUID_TOLERANCE`]).
pub(crate) fn check_fluid_certificate(cert: &Value) -> std::result::Result<CheckReport, CheckError> {
    check_fluid_certificate_with(cert, &Progress::new())
}

/// [`check_fluid_certificate`] with progress and cancellation.
pub(crate) fn check_fluid_certificate_with(
    cert: &Value,
    progress: &Progress,
) -> std::result::Result<CheckReport, CheckError> {
    let map = as_object(cert, "$").map_err(CheckError::BadInput)?;
    let spec_value = required(map, "spec", "$").map_err(CheckError::BadInput)?.clone();
    crate::check::check_engine(map)?;
    // The shape first: every field of the certificate type, no other.
    crate::document::from_value::<FluidCertificateDocument>(cert)
        .map_err(|e| fail(&e.path, format!("not a certificate as this engine writes them: {}", e.message)))?;
    // A certificate whose embedded spec or settings the engine rejects fails
    // (exit 1); only a file that is not a certificate is bad input.
    let mut spec = fluid_spec_from_value(spec_value).map_err(|e| {
        fail(
            &format!("$.spec{}", e.path.trim_start_matches('$')),
            format!("the embedded spec is not valid: {}", e.message),
        )
    })?;
    spec.settings = recorded_settings(map.get("settings"), "$.settings")
        .map_err(|e| fail(&e.path, format!("the recorded settings are not valid: {}", e.message)))?;
    // Independent claims first.
    if cert.get("spec_sha256").and_then(Value::as_str) != Some(spec_digest(&spec.raw).as_str()) {
        return Err(fail("$.spec_sha256", "does not match the embedded spec".into()));
    }
    if let (Some(s), Some(u)) =
        (cert.get("sigma2").and_then(Value::as_f64), cert.get("sigma2_upper").and_then(Value::as_f64))
    {
        if s > u {
            return Err(fail("$.sigma2_upper", format!("is below sigma2 ({u} < {s})")));
        }
    }
    if let Some(table) = cert.get("convergence").and_then(Value::as_array) {
        let expected = table_resolutions(spec.problem.ny, spec.settings.convergence_from);
        let found: Vec<u64> = table.iter().filter_map(|r| r.get("ny").and_then(Value::as_u64)).collect();
        if !found.is_empty() && found != expected.iter().map(|n| *n as u64).collect::<Vec<_>>() {
            return Err(fail("$.convergence", format!("resolutions {found:?} are not the table's {expected:?}")));
        }
    }
    let analysis = analyse_with(&spec.problem, &spec.settings, progress);
    progress.check()?;
    let analysis = analysis.map_err(|e| fail("$.spec.fluid", e.to_string()))?;
    prove_stated_bounds(&spec, &analysis, cert)?;
    // `compare_with` skips the top-level `engine`: a newer engine may re-check an older certificate.
    let expected = fluid_certificate_json(&spec, &analysis);
    compare_with(&expected, cert, "$", 0.0, FLUID_TOLERANCE)?;
    Ok(CheckReport {
        name: spec.name.clone(),
        verdict: analysis.verdict,
        level: analysis.verification,
        sigma2: analysis.sigma2,
    })
}

/// The claims of a fluid certificate that are proved rather than compared:
///
/// * each per-mode `sigma2_upper`: at or above the re-derived verified bound
///   it holds because `V ≻ 0` (`(b' - b) V ⪰ 0` for `b' >= b`); below it, it
///   must itself pass the verified Cholesky test
///   ([`fluid::analysis::prove_mode_bounds`]), or it is rejected, however
///   small the difference;
/// * the overall `sigma2_upper` is at least every per-mode one;
/// * `T` follows the one rule of every kind
///   ([`crate::check::check_stopping`]) at the stated `sigma2_upper`.
fn prove_stated_bounds(
    spec: &FluidSpec,
    analysis: &FluidAnalysis,
    cert: &Value,
) -> std::result::Result<(), CheckError> {
    let stated_modes = cert.get("modes").and_then(Value::as_array);
    let mut largest = 0.0f64;
    if let Some(stated_modes) = stated_modes {
        let mut to_prove = Vec::new();
        for (i, mode) in stated_modes.iter().enumerate() {
            let path = format!("$.modes[{i}].sigma2_upper");
            let Some(stated) = mode.get("sigma2_upper").and_then(Value::as_f64) else { continue };
            if !(stated.is_finite() && stated >= 0.0) {
                return Err(fail(&path, format!("{stated} is not a bound")));
            }
            largest = largest.max(stated);
            let m = mode.get("m").and_then(Value::as_u64).unwrap_or(0) as usize;
            let rederived = analysis.modes.iter().find(|r| r.m == m).and_then(|r| r.sigma2_upper);
            match rederived {
                Some(r) if stated >= r => {}
                Some(r) if analysis.verification == Some(VerificationLevel::VerifiedFloat) => {
                    to_prove.push((i, m, stated, r))
                }
                Some(r) => {
                    return Err(fail(&path, format!("{stated:e} is below the structural bound {r:e}")));
                }
                None => {} // nothing re-derived: the comparison below reports it
            }
        }
        let bounds: Vec<(usize, f64)> = to_prove.iter().map(|&(_, m, b, _)| (m, b)).collect();
        let proved = prove_mode_bounds(&spec.problem, analysis.form.galilean_shift, &bounds);
        for ((i, _, stated, r), ok) in to_prove.iter().zip(proved) {
            if !ok {
                return Err(fail(
                    &format!("$.modes[{i}].sigma2_upper"),
                    format!("{stated:e} is not proved: sigma2_upper V - Q is not verified positive semidefinite there (the engine proves {r:e})"),
                ));
            }
        }
    }
    let overall = cert.get("sigma2_upper").and_then(Value::as_f64);
    if let Some(u) = overall {
        if u < largest {
            return Err(fail("$.sigma2_upper", format!("{u:e} is below the per-mode bound {largest:e}")));
        }
    }
    // T by the one rule, at the stated (proved) bound: only a proved
    // sigma2_upper gives a stopping time.
    crate::check::check_stopping(cert, spec.stopping, overall)?;
    Ok(())
}
