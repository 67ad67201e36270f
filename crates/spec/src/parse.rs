//! Reading a spec: JSON in, a validated [`casimir::System`] out, and every
//! error named by its JSON path.

use crate::document::{AlgebraDoc, Expression, SpecDocument, StoppingDoc};
use crate::json::{child, index, type_name, Result, SpecError};
use crate::settings::EngineSettings;
use crate::sweep::{read_sweep_section, SweepSection};
use algebra::{builtin, builtin_names, AlgebraError, LieAlgebra};
use casimir::{discover_casimirs, DiscoveryReport, System, SystemError};
use exact::{parse_expression, Limits, Poly, Rational, Symbols};
use serde_json::Value;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Where a Casimir came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CasimirSource {
    /// Listed in the spec.
    Spec,
    /// The builtin algebra's generators.
    Builtin,
    /// Found by [`casimir::discover_casimirs`].
    Discovered,
}

impl CasimirSource {
    /// Name used in certificates.
    pub fn as_str(&self) -> &'static str {
        match self {
            CasimirSource::Spec => "spec",
            CasimirSource::Builtin => "builtin",
            CasimirSource::Discovered => "discovered",
        }
    }
}

/// The stopping question: `eps` and `delta` with `eps > delta > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stopping {
    /// Threshold on `|dmu_t|_P^2`.
    pub epsilon: f64,
    /// Initial size `|dmu_0|_P^2`.
    pub delta: f64,
}

/// A parsed, validated spec.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The spec's `name`.
    pub name: String,
    /// The spec exactly as given (embedded in certificates).
    pub raw: Value,
    /// The validated system.
    pub system: System,
    /// Where the Casimirs came from.
    pub casimir_source: CasimirSource,
    /// The discovery run, if Casimirs were discovered.
    pub discovery: Option<DiscoveryReport>,
    /// The builtin algebra's name, if one was used.
    pub builtin: Option<String>,
    /// Parameter values.
    pub parameters: BTreeMap<String, Rational>,
    /// The stopping question, if asked.
    pub stopping: Option<Stopping>,
    /// Settings in force.
    pub settings: EngineSettings,
    /// The optional `sweep` section (ranges, boundaries, reference constants).
    pub sweep: SweepSection,
    /// The optional `box` section: `certify` then certifies the whole box.
    pub parameter_box: Option<crate::box_cert::BoxSection>,
    shape: Arc<Shape>,
}

/// Largest number of noise fields accepted.
pub const MAX_NOISE_FIELDS: usize = 256;

/// Parse a spec from JSON text.
///
/// ```
/// let text = r#"{
///   "name": "rb", "algebra": "so3",
///   "parameters": {"I1": 3, "I2": 2, "I3": 1, "sigma": "3/10"},
///   "hamiltonian": "Pi1^2/(2*I1) + Pi2^2/(2*I2) + Pi3^2/(2*I3)",
///   "equilibrium": [1, 0, 0], "noise": [["sigma", 0, 0]]
/// }"#;
/// let spec = spec::parse_spec(text).unwrap();
/// assert_eq!(spec.system.dim(), 3);
/// let bad = text.replace("[\"sigma\", 0, 0]", "[\"sigma\", 0]");
/// let err = spec::parse_spec(&bad).unwrap_err();
/// assert_eq!(err.path, "$.noise[0]");
/// ```
pub fn parse_spec(text: &str) -> Result<Spec> {
    let value: Value = crate::json::parse_json(text)?;
    spec_from_value(value)
}

/// Parse a spec from a JSON value.
pub fn spec_from_value(value: Value) -> Result<Spec> {
    let shape = read_shape(&value)?;
    let system = build_system(&shape, &shape.parameters)?;
    let parameters = shape.parameters.clone();
    Ok(Spec {
        name: shape.name.clone(),
        raw: value,
        system,
        casimir_source: shape.casimir_source,
        discovery: shape.discovery.clone(),
        builtin: shape.builtin.clone(),
        parameters,
        stopping: shape.stopping,
        settings: shape.settings.clone(),
        sweep: shape.sweep.clone(),
        parameter_box: shape.parameter_box.clone(),
        shape: Arc::new(shape),
    })
}

impl Spec {
    /// A spec from a document built in Rust (no JSON text); `raw`, the
    /// JSON embedded in certificates, is the document serialised. See the
    /// example in [`crate::document`].
    pub fn from_document(doc: &SpecDocument) -> Result<Spec> {
        let value = serde_json::to_value(doc).map_err(|e| SpecError::new("$", e.to_string()))?;
        spec_from_value(value)
    }

    /// The system at other parameter values (every parameter of the spec
    /// must be present in `parameters`). The expressions are re-read with
    /// the new values and the system re-validated; the algebra, the settings
    /// and discovered Casimirs are reused. Errors name the JSON path, as
    /// when parsing.
    ///
    /// ```
    /// let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
    /// let spec = spec::parse_spec(&text).unwrap();
    /// let mut p = spec.parameters.clone();
    /// p.insert("I1".into(), exact::parse_number("0").unwrap());
    /// let err = spec.system_with(&p).unwrap_err();
    /// assert_eq!(err.path, "$.hamiltonian"); // Pi1^2/(2*I1) divides by zero
    /// ```
    pub fn system_with(&self, parameters: &BTreeMap<String, Rational>) -> Result<System> {
        build_system(&self.shape, parameters)
    }

    /// The spec with some parameters changed: the system, the parameters
    /// and the embedded JSON (`raw`) are all updated, so the result
    /// certifies and re-checks like a spec read from a file.
    ///
    /// ```
    /// let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/rigid-body-major-axis.json")).unwrap();
    /// let spec = spec::parse_spec(&text).unwrap();
    /// let two = exact::parse_number("2").unwrap();
    /// let changed = spec.with_parameters(&[("I3".to_string(), two)]).unwrap();
    /// assert_eq!(changed.raw["parameters"]["I3"], "2");
    /// assert!(spec.with_parameters(&[("J".to_string(), exact::parse_number("1").unwrap())]).is_err());
    /// ```
    pub fn with_parameters(&self, changes: &[(String, Rational)]) -> Result<Spec> {
        let mut parameters = self.parameters.clone();
        let mut raw = self.raw.clone();
        for (name, value) in changes {
            if !parameters.contains_key(name) {
                let names: Vec<String> = parameters.keys().cloned().collect();
                return Err(SpecError::new("$.parameters", crate::sweep::unknown_parameter(name, &names)));
            }
            parameters.insert(name.clone(), value.clone());
            raw["parameters"][name.as_str()] = Value::String(value.to_string());
        }
        let system = self.system_with(&parameters)?;
        Ok(Spec { raw, system, parameters, ..self.clone() })
    }
}

/// Everything read from a spec that does not depend on the parameter
/// values, so that a sweep reads the JSON once.
#[derive(Debug)]
struct Shape {
    name: String,
    settings: EngineSettings,
    algebra: LieAlgebra,
    parameters: BTreeMap<String, Rational>,
    hamiltonian: Expr,
    casimirs: Casimirs,
    first_integrals: Vec<Expr>,
    equilibrium: Vec<Expr>,
    noise: Vec<Vec<Expr>>,
    stopping: Option<Stopping>,
    casimir_source: CasimirSource,
    discovery: Option<DiscoveryReport>,
    builtin: Option<String>,
    sweep: SweepSection,
    parameter_box: Option<crate::box_cert::BoxSection>,
}

/// Casimirs as expressions (re-read per parameter set) or fixed polynomials.
#[derive(Debug)]
enum Casimirs {
    Given(Vec<Expr>),
    Fixed(Vec<Poly>),
}

/// An expression of the spec, with the names it mentions and its polynomial
/// at the spec's own parameter values, kept once computed: a sweep that does
/// not change any parameter an expression uses reuses it instead of parsing
/// again.
#[derive(Debug)]
struct Expr {
    text: String,
    names: Vec<String>,
    base: std::sync::OnceLock<Poly>,
}

impl Expr {
    fn new(text: String) -> Expr {
        // Every maximal run of letters, digits and '_' (and the run without
        // its leading digits): a superset of the identifiers the parser can
        // see, so a parameter an expression uses is never missed.
        let mut names = Vec::new();
        for run in text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
            let stripped = run.trim_start_matches(|c: char| c.is_ascii_digit());
            for n in [run, stripped] {
                if !n.is_empty() && !names.iter().any(|m: &String| m == n) {
                    names.push(n.to_string());
                }
            }
        }
        Expr { text, names, base: std::sync::OnceLock::new() }
    }
}

fn read_shape(value: &Value) -> Result<Shape> {
    let root = "$";
    if !value.is_object() {
        return Err(SpecError::new(root, format!("expected an object, found {}", type_name(value))));
    }
    let doc: SpecDocument = crate::document::from_value(value)?;
    let name = doc.name.clone();
    if name.trim().is_empty() {
        return Err(SpecError::new(child(root, "name"), "must not be empty"));
    }
    let settings = match &doc.settings {
        Some(s) => EngineSettings::from_document(s, &child(root, "settings"))?,
        None => EngineSettings::default(),
    };

    // Algebra.
    let algebra_path = child(root, "algebra");
    let (algebra, builtin_casimirs, builtin_name) = read_algebra(&doc.algebra, &algebra_path)?;
    let n = algebra.dim();

    let mut parameters = BTreeMap::new();
    let ppath = child(root, "parameters");
    for (key, v) in &doc.parameters {
        let kpath = child(&ppath, key);
        if !is_identifier(key) {
            return Err(SpecError::new(kpath, format!("'{key}' is not a valid parameter name (letters, digits, '_')")));
        }
        if algebra.coordinates().contains(key) {
            return Err(SpecError::new(kpath, format!("parameter '{key}' has the name of a coordinate")));
        }
        parameters.insert(key.clone(), v.0.clone());
    }
    let hamiltonian = Expr::new(doc.hamiltonian.0.clone());
    let texts = |list: &Vec<Expression>| list.iter().map(|e| Expr::new(e.0.clone())).collect::<Vec<_>>();
    let given_casimirs = doc.casimirs.as_ref().map(texts);
    let first_integrals = doc.first_integrals.as_ref().map(texts).unwrap_or_default();

    let epath = child(root, "equilibrium");
    if doc.equilibrium.len() != n {
        return Err(SpecError::new(
            &epath,
            format!("expected {n} components (the algebra's dimension), got {}", doc.equilibrium.len()),
        ));
    }
    let equilibrium = texts(&doc.equilibrium);

    let npath = child(root, "noise");
    if doc.noise.len() > MAX_NOISE_FIELDS {
        return Err(SpecError::new(&npath, format!("at most {MAX_NOISE_FIELDS} noise fields are supported")));
    }
    let mut noise = Vec::new();
    for (i, field) in doc.noise.iter().enumerate() {
        if field.len() != n {
            return Err(SpecError::new(
                index(&npath, i),
                format!("expected {n} components (the algebra's dimension), got {}", field.len()),
            ));
        }
        noise.push(texts(field));
    }

    let stopping = doc.stopping.as_ref().map(|s| read_stopping(s, &child(root, "stopping"))).transpose()?;
    let names: Vec<String> = parameters.keys().cloned().collect();
    let sweep = read_sweep_section(doc.sweep.as_ref(), &child(root, "sweep"), &names)?;
    let parameter_box = doc
        .parameter_box
        .as_ref()
        .map(|b| crate::box_cert::read_box_section(b, &child(root, "box"), &parameters))
        .transpose()?;

    // Casimirs: given, builtin, or discovered.
    let (casimirs, casimir_source, discovery) = match given_casimirs {
        Some(list) => (Casimirs::Given(list), CasimirSource::Spec, None),
        None => match builtin_casimirs {
            Some(texts) => {
                let s = Symbols::new(algebra.coordinates());
                let polys = texts
                    .iter()
                    .map(|t| {
                        parse_expression(t, &s)
                            .map_err(|e| SpecError::new(&algebra_path, format!("builtin Casimir '{t}': {e}")))
                    })
                    .collect::<Result<Vec<_>>>()?;
                (Casimirs::Fixed(polys), CasimirSource::Builtin, None)
            }
            None => {
                let report = discover_casimirs(&algebra, settings.discovery_degree, settings.discovery_max_unknowns);
                (Casimirs::Fixed(report.casimirs.clone()), CasimirSource::Discovered, Some(report))
            }
        },
    };
    Ok(Shape {
        name,
        settings,
        algebra,
        parameters,
        hamiltonian,
        casimirs,
        first_integrals,
        equilibrium,
        noise,
        stopping,
        casimir_source,
        discovery,
        builtin: builtin_name,
        sweep,
        parameter_box,
    })
}

/// Read the expressions at the given parameter values and validate the system.
fn build_system(shape: &Shape, parameters: &BTreeMap<String, Rational>) -> Result<System> {
    let root = "$";
    // Bounded so that derivatives of every expression stay cheap (a Hessian
    // costs dim^2 passes over the terms): degree 16 and 5000 terms are far
    // beyond mechanical Hamiltonians and Casimirs.
    let limits = Limits { max_degree: 16, max_terms: 5000, ..Limits::default() };
    let mut symbols = Symbols::new(shape.algebra.coordinates()).with_limits(limits);
    for (name, value) in parameters {
        if !shape.parameters.contains_key(name) {
            let names: Vec<String> = shape.parameters.keys().cloned().collect();
            return Err(SpecError::new(child(root, "parameters"), crate::sweep::unknown_parameter(name, &names)));
        }
        symbols.set_parameter(name, value.clone());
    }
    if let Some(missing) = shape.parameters.keys().find(|k| !parameters.contains_key(*k)) {
        return Err(SpecError::new(child(root, "parameters"), format!("parameter '{missing}' has no value")));
    }
    let poly = |e: &Expr, path: &str| -> Result<Poly> {
        let unchanged = e.names.iter().all(|n| parameters.get(n) == shape.parameters.get(n));
        if unchanged {
            if let Some(p) = e.base.get() {
                return Ok(p.clone());
            }
        }
        let text = &e.text;
        let p = parse_expression(text, &symbols).map_err(|err| SpecError::new(path, format!("in '{text}': {err}")))?;
        if unchanged {
            // Another thread may have set it first: the values are equal.
            let _ = e.base.set(p.clone());
        }
        Ok(p)
    };
    let constant = |text: &Expr, path: &str| -> Result<Rational> {
        let p = poly(text, path)?;
        p.constant_value()
            .ok_or_else(|| SpecError::new(path, "must be a constant (it may use parameters but not coordinates)"))
    };
    let Functions { hamiltonian, casimirs, first_integrals, equilibrium, noise } =
        read_functions(shape, poly, constant, Poly::clone)?;
    let (cpath, fpath) = (child(root, "casimirs"), child(root, "first_integrals"));
    let casimir_path = |i: usize| match shape.casimirs {
        Casimirs::Given(_) => index(&cpath, i),
        Casimirs::Fixed(_) if shape.casimir_source == CasimirSource::Builtin => child(root, "algebra"),
        Casimirs::Fixed(_) => cpath.clone(),
    };
    System::new(shape.algebra.clone(), hamiltonian, casimirs, first_integrals, equilibrium, noise).map_err(|e| match &e
    {
        SystemError::NotACasimir { index, .. } => SpecError::new(casimir_path(*index), e.to_string()),
        SystemError::ConstantQuantity { what: "casimir", index } => SpecError::new(casimir_path(*index), e.to_string()),
        SystemError::NotConserved { index: i, .. } | SystemError::ConstantQuantity { index: i, .. } => {
            SpecError::new(index(&fpath, *i), e.to_string())
        }
        _ => SpecError::new(root, e.to_string()),
    })
}

/// The spec's functions, each read at its JSON path: `h`, the Casimirs,
/// the first integrals (by `expr`), the equilibrium and the noise (by
/// `constant`); Casimirs fixed by the algebra (builtin or discovered) go
/// through `fixed`. One walk for the pointwise system and the box's.
struct Functions<P, C> {
    hamiltonian: P,
    casimirs: Vec<P>,
    first_integrals: Vec<P>,
    equilibrium: Vec<C>,
    noise: Vec<Vec<C>>,
}

fn read_functions<P, C>(
    shape: &Shape,
    expr: impl Fn(&Expr, &str) -> Result<P>,
    constant: impl Fn(&Expr, &str) -> Result<C>,
    fixed: impl Fn(&Poly) -> P,
) -> Result<Functions<P, C>> {
    let root = "$";
    let hamiltonian = expr(&shape.hamiltonian, &child(root, "hamiltonian"))?;
    let cpath = child(root, "casimirs");
    let casimirs = match &shape.casimirs {
        Casimirs::Given(texts) => {
            texts.iter().enumerate().map(|(i, t)| expr(t, &index(&cpath, i))).collect::<Result<Vec<_>>>()?
        }
        Casimirs::Fixed(polys) => polys.iter().map(fixed).collect(),
    };
    let fpath = child(root, "first_integrals");
    let first_integrals = shape
        .first_integrals
        .iter()
        .enumerate()
        .map(|(i, t)| expr(t, &index(&fpath, i)))
        .collect::<Result<Vec<_>>>()?;
    let epath = child(root, "equilibrium");
    let equilibrium = shape
        .equilibrium
        .iter()
        .enumerate()
        .map(|(i, t)| constant(t, &index(&epath, i)))
        .collect::<Result<Vec<_>>>()?;
    let npath = child(root, "noise");
    let noise = shape
        .noise
        .iter()
        .enumerate()
        .map(|(i, field)| {
            let p = index(&npath, i);
            field.iter().enumerate().map(|(j, t)| constant(t, &index(&p, j))).collect::<Result<Vec<_>>>()
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Functions { hamiltonian, casimirs, first_integrals, equilibrium, noise })
}

impl Spec {
    /// The system with the box parameters `names` kept symbolic (the
    /// other parameters at their values): the spec's expressions re-read
    /// as rational functions of those parameters. Errors name the JSON path.
    pub fn box_system(&self, names: &[String]) -> Result<boxes::BoxSystem> {
        let shape = &self.shape;
        let coordinates: Vec<String> = shape.algebra.coordinates().to_vec();
        let n = coordinates.len();
        let fixed: BTreeMap<String, Rational> =
            self.parameters.iter().filter(|(k, _)| !names.contains(k)).map(|(k, v)| (k.clone(), v.clone())).collect();
        let symbols = boxes::BoxSymbols::new(&coordinates, names, &fixed);
        let nv = symbols.nvars();
        let divisors = std::cell::RefCell::new(Vec::new());
        let read = |e: &Expr, path: &str| -> Result<boxes::Frac> {
            let (f, d) = boxes::parse_box_expression_with_divisors(&e.text, &symbols)
                .map_err(|err| SpecError::new(path, format!("in '{}' (box parameters symbolic): {err}", e.text)))?;
            divisors.borrow_mut().extend(d);
            Ok(f)
        };
        let constant = |e: &Expr, path: &str| -> Result<boxes::Frac> {
            let f = read(e, path)?;
            if boxes::parse::has_coordinates(f.num(), n) {
                return Err(SpecError::new(path, "must be a constant (it may use parameters but not coordinates)"));
            }
            Ok(f)
        };
        let extend = |p: &Poly| boxes::Frac::from_poly(boxes::symbolic::extend(p, nv));
        let Functions { hamiltonian, casimirs, first_integrals, equilibrium, noise } =
            read_functions(shape, read, constant, extend)?;
        Ok(boxes::BoxSystem {
            divisors: divisors.into_inner(),
            algebra: shape.algebra.clone(),
            parameters: names.to_vec(),
            hamiltonian,
            casimirs,
            first_integrals,
            equilibrium,
            noise,
        })
    }
}

pub(crate) fn is_identifier(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(x) if x.is_ascii_alphabetic() || x == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

type AlgebraRead = (LieAlgebra, Option<Vec<&'static str>>, Option<String>);

/// The rows `(a, b, k, c)` of a custom algebra's structure constants, with
/// indices as `usize` (`spath`: the JSON path of `structure_constants`).
pub(crate) fn structure_rows(
    custom: &crate::document::CustomAlgebra,
    spath: &str,
) -> Result<Vec<(usize, usize, usize, Rational)>> {
    let too_large = |i: usize, j: usize| SpecError::new(index(&index(spath, i), j), "index is too large");
    let mut rows = Vec::with_capacity(custom.structure_constants.len());
    for (i, r) in custom.structure_constants.iter().enumerate() {
        let a = usize::try_from(r.a.0).map_err(|_| too_large(i, 0))?;
        let b = usize::try_from(r.b.0).map_err(|_| too_large(i, 1))?;
        let k = usize::try_from(r.k.0).map_err(|_| too_large(i, 2))?;
        rows.push((a, b, k, r.c.0.clone()));
    }
    Ok(rows)
}

fn read_algebra(doc: &AlgebraDoc, path: &str) -> Result<AlgebraRead> {
    match doc {
        AlgebraDoc::Builtin(name) => match builtin(name) {
            Some(b) => Ok((b.algebra, Some(b.casimirs), Some(name.clone()))),
            None => Err(SpecError::new(
                path,
                format!("unknown algebra '{name}' (builtins: {}; or give an object with coordinates and structure_constants)", builtin_names().join(", ")),
            )),
        },
        AlgebraDoc::Custom(custom) => {
            let label = custom.name.clone().unwrap_or_else(|| "custom".to_string());
            let spath = child(path, "structure_constants");
            let max_rows = algebra::MAX_DIMENSION.pow(3);
            if custom.structure_constants.len() > max_rows {
                return Err(SpecError::new(&spath, format!("more than {max_rows} rows")));
            }
            let rows = structure_rows(custom, &spath)?;
            let algebra = LieAlgebra::from_structure_constants(&label, &custom.coordinates, &rows)
                .map_err(|e| algebra_error(e, path))?;
            Ok((algebra, None, None))
        }
    }
}

fn algebra_error(e: AlgebraError, path: &str) -> SpecError {
    let spath = child(path, "structure_constants");
    let cpath = child(path, "coordinates");
    let at = match &e {
        AlgebraError::IndexOutOfRange { row, .. }
        | AlgebraError::DiagonalEntry { row, .. }
        | AlgebraError::Inconsistent { row, .. } => index(&spath, *row),
        AlgebraError::InvalidCoordinateName { index: i, .. } | AlgebraError::DuplicateCoordinate { index: i, .. } => {
            index(&cpath, *i)
        }
        AlgebraError::Empty | AlgebraError::TooLarge { .. } => cpath,
        _ => spath,
    };
    SpecError::new(at, e.to_string())
}

pub(crate) fn read_stopping(doc: &StoppingDoc, path: &str) -> Result<Stopping> {
    let epsilon = exact::rational_to_f64(&doc.epsilon.0);
    let delta = exact::rational_to_f64(&doc.delta.0);
    if delta <= 0.0 {
        return Err(SpecError::new(child(path, "delta"), format!("must be positive, got {delta}")));
    }
    if epsilon <= delta {
        return Err(SpecError::new(
            child(path, "epsilon"),
            format!("must exceed delta ({delta}), got {epsilon}: the stopping time ln(epsilon/delta)/Sigma^2 would not be positive"),
        ));
    }
    Ok(Stopping { epsilon, delta })
}
