//! Certificates from Rust, without writing JSON: a [`System`] built in code
//! becomes a [`Spec`] ([`spec_of_system`]) whose embedded document is the
//! system written out in the contract's terms (structure constants or the
//! builtin name, exact polynomials as expressions, rational equilibrium and
//! noise), so the certificate re-checks like one made from a file.
//!
//! [`certify_system`] shows a heavy top certified in twelve lines.

use crate::certificate::{certify_lie, verification_level, Certificate};
use crate::check::{check_certificate_value, CheckError, CheckReport};
use crate::json::{Result, SpecError};
use crate::parse::{spec_from_value, Spec, Stopping};
use crate::settings::EngineSettings;
use casimir::System;
use exact::Rational;
use outcome::{Verdict, VerificationLevel};
use serde_json::{json, Value};

/// The spec document of a system built in code: the algebra by its builtin
/// name when it is one (same coordinates and structure constants), else by
/// its structure constants; the Hamiltonian, Casimirs and first integrals as
/// exact expressions; no parameters. Reading it back must give the same
/// system, which is checked.
///
/// ```
/// use exact::{parse_expression, Rational, Symbols};
/// let so3 = algebra::builtin("so3").unwrap().algebra;
/// let s = Symbols::new(so3.coordinates());
/// let h = parse_expression("Pi1^2/6 + Pi2^2/4 + Pi3^2/2", &s).unwrap();
/// let c = parse_expression("(Pi1^2 + Pi2^2 + Pi3^2)/2", &s).unwrap();
/// let q = |n: i64| Rational::from(n);
/// let system = casimir::System::new(so3, h, vec![c], vec![], vec![q(1), q(0), q(0)], vec![]).unwrap();
/// let spec = spec::spec_of_system("rb", &system, &spec::EngineSettings::default(), None).unwrap();
/// assert_eq!(spec.raw["algebra"], "so3");
/// assert_eq!(spec.system.hamiltonian(), system.hamiltonian());
/// assert!(spec::spec_of_system("", &system, &spec::EngineSettings::default(), None).is_err()); // a name is required
/// ```
pub fn spec_of_system(
    name: &str,
    system: &System,
    settings: &EngineSettings,
    stopping: Option<Stopping>,
) -> Result<Spec> {
    let algebra = system.algebra();
    let coords = algebra.coordinates();
    let same_as_builtin = algebra::builtin(algebra.name()).is_some_and(|b| {
        b.algebra.coordinates() == coords && b.algebra.structure_constant_rows() == algebra.structure_constant_rows()
    });
    let algebra_json = if same_as_builtin {
        Value::from(algebra.name())
    } else {
        let rows: Vec<Value> = algebra
            .structure_constant_rows()
            .into_iter()
            .filter(|(a, b, _, _)| a < b)
            .map(|(a, b, k, c)| json!([a, b, k, c.to_string()]))
            .collect();
        json!({ "coordinates": coords, "structure_constants": rows })
    };
    let text = |p: &exact::Poly| Value::from(p.to_string_with(coords));
    let rationals = |v: &[Rational]| Value::Array(v.iter().map(|x| Value::from(x.to_string())).collect());
    let mut doc = json!({
        "name": name,
        "algebra": algebra_json,
        "hamiltonian": text(system.hamiltonian()),
        "casimirs": system.casimirs().iter().map(text).collect::<Vec<_>>(),
        "first_integrals": system.first_integrals().iter().map(text).collect::<Vec<_>>(),
        "equilibrium": rationals(system.equilibrium()),
        "noise": system.noise().iter().map(|v| rationals(v)).collect::<Vec<_>>(),
        "settings": settings.to_json(),
    });
    if let Some(st) = stopping {
        doc["stopping"] = json!({ "epsilon": st.epsilon, "delta": st.delta });
    }
    let spec = spec_from_value(doc)?;
    let s = &spec.system;
    let same = s.hamiltonian() == system.hamiltonian()
        && s.casimirs() == system.casimirs()
        && s.first_integrals() == system.first_integrals()
        && s.equilibrium() == system.equilibrium()
        && s.noise() == system.noise();
    if !same {
        return Err(SpecError::new("$", "the system did not survive being written as a spec and read back"));
    }
    Ok(spec)
}

/// Certify a system built in code: [`spec_of_system`] then [`crate::certify_lie`].
///
/// The sleeping heavy top, `I = (1, 2, 3)`, `mgl = 1`, `p = 4`, noise
/// `(3/10) e3`, in twelve lines:
///
/// ```
/// use exact::{parse_expression, parse_number as q, Symbols};
/// let se3 = algebra::builtin("se3").unwrap().algebra;
/// let s = Symbols::new(se3.coordinates());
/// let e = |t: &str| parse_expression(t, &s).unwrap();
/// let h = e("Pi1^2/2 + Pi2^2/4 + Pi3^2/6 + Gamma3");
/// let casimirs = vec![e("(Gamma1^2 + Gamma2^2 + Gamma3^2)/2"), e("Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3")];
/// let mu_e = ["0", "0", "4", "0", "0", "1"].map(|x| q(x).unwrap()).to_vec();
/// let noise = vec![["0", "0", "3/10", "0", "0", "0"].map(|x| q(x).unwrap()).to_vec()];
/// let system = casimir::System::new(se3, h, casimirs, vec![], mu_e, noise).unwrap();
/// let cert = spec::certify_system("heavy-top", &system, &spec::EngineSettings::default(), None).unwrap();
/// // Sigma^2 = sigma^2 (|I1 - I2| / I_min) I3 (p^2 - mgl I3) / (p^2 (I3 - I_max) - mgl I3^2) = 0.09 * 39/7
/// assert_eq!(cert.verdict(), spec::Verdict::Stable);
/// assert_eq!(cert.sigma2_exact().unwrap(), q("351/700").unwrap());
/// assert_eq!(cert.check().unwrap().level, Some(spec::VerificationLevel::Exact));
/// ```
pub fn certify_system(
    name: &str,
    system: &System,
    settings: &EngineSettings,
    stopping: Option<Stopping>,
) -> Result<Certificate> {
    Ok(certify_lie(&spec_of_system(name, system, settings, stopping)?))
}

impl Certificate {
    /// The certificate, typed (the JSON is written from this type, so it
    /// reads back; `None` would mean a bug, not bad input).
    pub fn document(&self) -> Option<crate::record::CertificateDocument> {
        crate::document::from_value(&self.json).ok()
    }

    /// The verdict.
    pub fn verdict(&self) -> Verdict {
        self.analysis.verdict
    }

    /// The verification level the certificate states.
    pub fn level(&self) -> VerificationLevel {
        verification_level(&self.analysis)
    }

    /// `Sigma^2` when stable (the certified value, as a double).
    pub fn sigma2(&self) -> Option<f64> {
        self.analysis.sigma2()
    }

    /// The certified rational `Sigma^2` when stable at the exact level.
    pub fn sigma2_exact(&self) -> Option<Rational> {
        self.analysis.stable.as_ref().and_then(|s| s.exact.as_ref()).map(|e| e.value.clone())
    }

    /// Re-check the certificate on the checker's own path, as `verify check`
    /// does with the file.
    pub fn check(&self) -> std::result::Result<CheckReport, CheckError> {
        check_certificate_value(&self.json)
    }
}
