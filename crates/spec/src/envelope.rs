//! One certificate type for every kind of spec, and the three entry points
//! that serve them all: [`parse`], [`certify`] and [`check`], each taking
//! [`Options`] (progress and cancellation, the folder a spec's files are
//! relative to).
//!
//! Every certificate, whatever wrote it, opens with the same header
//! ([`Header`]): the format version, the engine, what it is about
//! ([`CertificateKind`]), the spec's name, the verdict ([`AnyVerdict`]),
//! the verification level, the SHA-256 of the embedded spec and the
//! settings used. [`AnyCertificate`] holds the header, read and typed, and
//! the certificate JSON as written. Reading a header checks only its
//! shape; [`check`] re-derives every claim.
//!
//! ```
//! use spec::{certify, check, parse, AnyVerdict, CertificateKind, Options, Verdict};
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/heavy-top-asymmetric.json");
//! let spec = parse(&std::fs::read_to_string(path).unwrap(), &Options::default()).unwrap();
//! let cert = certify(&spec, &Options::default()).unwrap();
//! assert_eq!(cert.header().kind, CertificateKind::LiePoisson);
//! assert_eq!(cert.header().verdict, AnyVerdict::Point(Verdict::Stable));
//! let report = check(&cert, &Options::default()).unwrap();
//! assert_eq!(report.verdict, Verdict::Stable);
//! // Written out and read back, it is the same certificate.
//! let again = spec::AnyCertificate::from_json(&cert.to_pretty_json()).unwrap();
//! assert_eq!(again, cert);
//! ```

use crate::check::{check_value_with, CheckError, CheckReport};
use crate::json::SpecError;
use crate::AnySpec;
use outcome::{BoxVerdict, Cancelled, CertificateKind, Progress, Verdict, VerificationLevel};
use serde_json::Value;
use std::fmt;
use std::path::Path;

/// How to parse, certify or check: the progress to report (and the way to
/// cancel), and the folder the files a spec names are relative to (a
/// Zeitlin field's `.npy`; the current folder when `None`).
///
/// ```
/// use spec::Options;
/// let progress = outcome::Progress::new();
/// let here = std::path::Path::new("fixtures");
/// let o = Options::default().with_progress(&progress).with_base_dir(here);
/// assert!(o.progress.is_some() && o.base_dir == Some(here));
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Options<'a> {
    /// Progress to report to, and to stop on ([`Progress::cancel`]).
    pub progress: Option<&'a Progress>,
    /// The folder a spec's files are relative to.
    pub base_dir: Option<&'a Path>,
}

impl<'a> Options<'a> {
    /// Options with a spec's files relative to `dir` (to the current
    /// folder when `None`): what a caller holding a file's
    /// `path.parent()` passes.
    pub fn relative_to(dir: Option<&'a Path>) -> Self {
        Options { base_dir: dir, ..Options::default() }
    }

    /// These options, reporting to `progress`.
    pub fn with_progress(self, progress: &'a Progress) -> Self {
        Options { progress: Some(progress), ..self }
    }

    /// These options, with a spec's files relative to `dir`.
    pub fn with_base_dir(self, dir: &'a Path) -> Self {
        Options { base_dir: Some(dir), ..self }
    }

    /// Run `f` with the progress given, or with a fresh one nobody watches.
    fn run<T>(&self, f: impl FnOnce(&Progress) -> T) -> T {
        match self.progress {
            Some(p) => f(p),
            None => f(&Progress::new()),
        }
    }
}

/// A certificate's verdict: about one parameter point, or about a box of
/// parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AnyVerdict {
    /// The verdict at the spec's parameter point.
    Point(Verdict),
    /// The verdict over the spec's box of parameters.
    Box(BoxVerdict),
}

impl AnyVerdict {
    /// The name certificates use.
    pub fn as_str(&self) -> &'static str {
        match self {
            AnyVerdict::Point(v) => v.as_str(),
            AnyVerdict::Box(v) => v.as_str(),
        }
    }

    /// The verdict it implies at the spec's own parameter point (a box
    /// verdict proved on part of the box implies none).
    pub fn at_the_point(&self) -> Option<Verdict> {
        match self {
            AnyVerdict::Point(v) => Some(*v),
            AnyVerdict::Box(v) => v.at_every_point(),
        }
    }
}

impl fmt::Display for AnyVerdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The fields every certificate shares, typed.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// The certificate format's version.
    pub certificate_version: u64,
    /// The engine's version (`engine.version`).
    pub engine_version: String,
    /// What the certificate is about.
    pub kind: CertificateKind,
    /// The spec's name.
    pub name: String,
    /// The verdict.
    pub verdict: AnyVerdict,
    /// The verification level (`None`: no claim is made, or a box
    /// certificate, whose sub-boxes are each proved exactly).
    pub level: Option<VerificationLevel>,
    /// SHA-256 of the embedded spec (`spec_sha256`).
    pub spec_sha256: String,
    /// The settings the pipeline ran with, as recorded (box and large
    /// certificates record theirs elsewhere or have none).
    pub settings: Option<Value>,
}

/// A certificate of any kind: its [`Header`], read and typed, and the
/// certificate JSON as written.
#[derive(Clone, Debug, PartialEq)]
pub struct AnyCertificate {
    header: Header,
    json: Value,
}

/// Why [`certify`] returned no certificate.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CertifyError {
    /// Stopped through [`Options::progress`] before it finished.
    #[error("cancelled before the certificate was finished")]
    Cancelled,
    /// The pipeline wrote a certificate whose header this engine cannot
    /// read: a bug in the engine, reported rather than hidden.
    #[error("internal error: the certificate written has no readable header: {0}")]
    Internal(String),
}

impl From<Cancelled> for CertifyError {
    fn from(_: Cancelled) -> Self {
        CertifyError::Cancelled
    }
}

fn bad(path: &str, message: impl Into<String>) -> CheckError {
    CheckError::BadInput(SpecError::new(path, message))
}

impl AnyCertificate {
    /// Read a certificate from JSON text (its header; [`check`] verifies
    /// the rest).
    pub fn from_json(text: &str) -> Result<Self, CheckError> {
        let value = crate::json::parse_json(text).map_err(CheckError::BadInput)?;
        AnyCertificate::from_value(value)
    }

    /// Read a certificate from a JSON value. The kind is the `kind` field
    /// (`box`, `fluid`, `zeitlin`, `large`), or `lie_poisson` for a
    /// certificate without one.
    pub fn from_value(json: Value) -> Result<Self, CheckError> {
        let map = json.as_object().ok_or_else(|| bad("$", "expected a JSON object (a certificate)"))?;
        let kind = match map.get("kind") {
            None => CertificateKind::LiePoisson,
            Some(Value::String(k)) => match CertificateKind::from_name(k) {
                Some(CertificateKind::LiePoisson) | None => {
                    return Err(bad("$.kind", format!("unknown certificate kind {}", exact::quote(k, 40))))
                }
                Some(kind) => kind,
            },
            Some(_) => return Err(bad("$.kind", "expected a string")),
        };
        let string = |key: &str| -> Result<String, CheckError> {
            map.get(key)
                .and_then(Value::as_str)
                .map(str::to_string)
                .ok_or_else(|| bad(&format!("$.{key}"), "missing or not a string"))
        };
        let certificate_version = map
            .get("certificate_version")
            .and_then(Value::as_u64)
            .ok_or_else(|| bad("$.certificate_version", "missing or not a nonnegative integer"))?;
        let engine_version = map
            .get("engine")
            .and_then(|e| e.get("version"))
            .and_then(Value::as_str)
            .ok_or_else(|| bad("$.engine.version", "missing or not a string"))?
            .to_string();
        let verdict_name = string("verdict")?;
        let verdict = if kind == CertificateKind::Box {
            BoxVerdict::from_name(&verdict_name).map(AnyVerdict::Box)
        } else {
            Verdict::from_name(&verdict_name).map(AnyVerdict::Point)
        }
        .ok_or_else(|| bad("$.verdict", format!("unknown verdict {}", exact::quote(&verdict_name, 40))))?;
        let level = match map.get("level") {
            None if kind == CertificateKind::Box => None,
            Some(Value::String(l)) if l == "none" => None,
            Some(Value::String(l)) => Some(
                VerificationLevel::from_name(l)
                    .ok_or_else(|| bad("$.level", format!("unknown level {}", exact::quote(l, 40))))?,
            ),
            _ => return Err(bad("$.level", "missing or not a string")),
        };
        if !map.get("spec").is_some_and(Value::is_object) {
            return Err(bad("$.spec", "missing or not an object (the embedded spec)"));
        }
        let header = Header {
            certificate_version,
            engine_version,
            kind,
            name: string("name")?,
            verdict,
            level,
            spec_sha256: string("spec_sha256")?,
            settings: map.get("settings").cloned(),
        };
        Ok(AnyCertificate { header, json })
    }

    /// The shared fields.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// What the certificate is about.
    pub fn kind(&self) -> CertificateKind {
        self.header.kind
    }

    /// The verdict.
    pub fn verdict(&self) -> AnyVerdict {
        self.header.verdict
    }

    /// The embedded spec, as given.
    pub fn spec(&self) -> &Value {
        &self.json["spec"]
    }

    /// The certificate JSON, as written.
    pub fn json(&self) -> &Value {
        &self.json
    }

    /// The certificate JSON, taken.
    pub fn into_json(self) -> Value {
        self.json
    }

    /// The certificate as the engine writes files: pretty-printed, with
    /// short arrays of numbers on one line ([`crate::to_pretty_json`]).
    pub fn to_pretty_json(&self) -> String {
        crate::to_pretty_json(&self.json)
    }
}

/// Parse a spec of any kind from JSON text: a top-level `fluid` object
/// selects the fluid pipeline, a `zeitlin` object the Zeitlin model, more
/// than 64 coordinates the large pipeline, and anything else the
/// finite-dimensional one. Files the spec names are relative to
/// [`Options::base_dir`]. Every error names the JSON path.
///
/// ```
/// // A finite-dimensional spec without its Hamiltonian:
/// let bad = spec::parse(r#"{"name": "x", "algebra": "so3"}"#, &spec::Options::default()).unwrap_err();
/// assert_eq!(bad.path, "$.hamiltonian");
/// ```
pub fn parse(text: &str, options: &Options<'_>) -> Result<AnySpec, SpecError> {
    crate::parse_any_spec_in(text, options.base_dir)
}

/// Run the pipeline that matches the spec and return its certificate,
/// reporting progress to [`Options::progress`] and stopping soon after it
/// is cancelled (then [`CertifyError::Cancelled`], and no certificate).
/// The fluid, Zeitlin and large pipelines count their steps (x-mode
/// solves, block operations, stages); a finite-dimensional system,
/// certified in micro- to milliseconds, is one step.
///
/// A shear flow, certified and checked:
///
/// ```
/// use spec::{certify, check, parse, CertificateKind, Options, Verdict};
/// let text = r#"{"name": "rayleigh", "fluid": {"model": "incompressible", "x_period": "2*pi",
///   "y_interval": [-1, 1], "boundary": "walls", "shear_flow": "-cos(y)",
///   "noise": ["0.3*sin(y)"], "ny": 32, "x_modes": 2}}"#;
/// let spec = parse(text, &Options::default()).unwrap();
/// let progress = outcome::Progress::new();
/// let cert = certify(&spec, &Options::default().with_progress(&progress)).unwrap();
/// assert_eq!((cert.kind(), cert.verdict().at_the_point()), (CertificateKind::Fluid, Some(Verdict::Stable)));
/// let (done, total) = progress.snapshot();
/// assert!(done > 1 && done == total);
/// assert_eq!(check(&cert, &Options::default()).unwrap().verdict, Verdict::Stable);
/// progress.cancel();
/// assert!(certify(&spec, &Options::default().with_progress(&progress)).is_err());
/// ```
///
/// A Zeitlin spec (the bundled quflow state, whose `.npy` files are
/// relative to the spec's folder):
///
/// ```
/// use spec::{certify, check, parse, CertificateKind, Options, Verdict};
/// let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/zeitlin"));
/// let text = std::fs::read_to_string(dir.join("quflow-tilted-n16.json")).unwrap();
/// let here = Options::default().with_base_dir(dir);
/// let cert = certify(&parse(&text, &here).unwrap(), &here).unwrap();
/// assert_eq!(cert.kind(), CertificateKind::Zeitlin);
/// let report = check(&cert, &here).unwrap();
/// assert_eq!(Some(report.verdict), cert.verdict().at_the_point());
/// ```
pub fn certify(spec: &AnySpec, options: &Options<'_>) -> Result<AnyCertificate, CertifyError> {
    let json = options.run(|progress| spec.certify_with(progress))?;
    AnyCertificate::from_value(json).map_err(|e| CertifyError::Internal(e.to_string()))
}

/// Re-derive every claim of a certificate from its embedded spec, with the
/// checker's own code path, and compare: `Ok` with what was established,
/// or the path of the first field that does not hold. Files the embedded
/// spec names are relative to [`Options::base_dir`].
pub fn check(certificate: &AnyCertificate, options: &Options<'_>) -> Result<CheckReport, CheckError> {
    options.run(|progress| check_value_with(&certificate.json, options.base_dir, progress))
}

/// [`check`] for a certificate given as JSON text, as read from a file:
/// the header is not read first, so a certificate whose header was edited
/// fails at the edited field like any other claim (a `verdict` of
/// `"stabel"` fails the check, it is not malformed input).
///
/// ```
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.cert.json");
/// let text = std::fs::read_to_string(path).unwrap();
/// assert_eq!(spec::check_json(&text, &spec::Options::default()).unwrap().verdict, spec::Verdict::Stable);
/// let edited = text.replacen("\"stable\"", "\"stabel\"", 1);
/// assert!(matches!(spec::check_json(&edited, &spec::Options::default()), Err(spec::CheckError::Failed { .. })));
/// ```
pub fn check_json(text: &str, options: &Options<'_>) -> Result<CheckReport, CheckError> {
    let value = crate::json::parse_json(text).map_err(CheckError::BadInput)?;
    options.run(|progress| check_value_with(&value, options.base_dir, progress))
}
