//! The outcome vocabulary shared by every pipeline (finite-dimensional,
//! fluid, sweeps): what was concluded ([`Verdict`]), how firmly
//! ([`VerificationLevel`]), and the sign of a definite conserved form
//! ([`Sign`]); for a box of parameters, [`BoxVerdict`]; and what a
//! certificate is about ([`CertificateKind`]).
//!
//! [`Progress`] carries the progress of a long analysis and a request to
//! stop it (module [`progress`]).
//!
//! Each type has one name per value, the one certificates use (serde
//! renames them, and [`Verdict::as_str`] / [`Verdict::from_name`] give the
//! same names without serde), so no code compares outcome strings.
//!
//! ```
//! use outcome::{Sign, VerificationLevel, Verdict};
//! assert_eq!(Verdict::from_name("linearly_unstable"), Some(Verdict::LinearlyUnstable));
//! assert_eq!(serde_json::to_string(&VerificationLevel::ExactStructure).unwrap(), "\"exact_structure\"");
//! assert!(VerificationLevel::Exact.is_proof() && !VerificationLevel::Numerical.is_proof());
//! assert_eq!(Sign::Negative.as_f64() * 2.0, -2.0);
//! ```

pub mod progress;
pub use progress::{Cancelled, Phase, Progress};

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// An unknown name for a [`Verdict`], [`VerificationLevel`] or [`Sign`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {kind} '{name}' (expected one of: {expected})")]
pub struct UnknownName {
    /// What was being parsed (`verdict`, `verification level`, `sign`).
    pub kind: &'static str,
    /// The name given.
    pub name: String,
    /// The names accepted, comma-separated.
    pub expected: String,
}

/// Names, parsing and display for a closed set of values.
macro_rules! named {
    ($ty:ident, $kind:literal, [$($variant:ident => $name:literal),+ $(,)?]) => {
        impl $ty {
            /// Every value, in declaration order.
            pub const ALL: &'static [$ty] = &[$($ty::$variant),+];

            /// The name used in certificates and records.
            pub fn as_str(&self) -> &'static str {
                match self {
                    $($ty::$variant => $name),+
                }
            }

            /// The value with this certificate name.
            pub fn from_name(name: &str) -> Option<Self> {
                match name {
                    $($name => Some($ty::$variant),)+
                    _ => None,
                }
            }
        }

        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl FromStr for $ty {
            type Err = UnknownName;
            fn from_str(s: &str) -> Result<Self, UnknownName> {
                $ty::from_name(s).ok_or_else(|| UnknownName {
                    kind: $kind,
                    name: s.to_string(),
                    expected: [$($name),+].join(", "),
                })
            }
        }
    };
}

/// What the engine concluded about an equilibrium and its noise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// A definite energy–Casimir form exists: nonlinearly (formally)
    /// stable, and stable in probability up to the stopping time set by
    /// `Sigma^2`.
    Stable,
    /// The linearised drift has an eigenvalue with positive real part.
    LinearlyUnstable,
    /// Neither a definite form nor an unstable eigenvalue was found.
    Inconclusive,
    /// The state is not an equilibrium of the drift.
    NotAnEquilibrium,
    /// Some noise field moves the equilibrium.
    NoiseIncompatible,
}

named!(Verdict, "verdict", [
    Stable => "stable",
    LinearlyUnstable => "linearly_unstable",
    Inconclusive => "inconclusive",
    NotAnEquilibrium => "not_an_equilibrium",
    NoiseIncompatible => "noise_incompatible",
]);

/// How firmly a verdict's claims are established (docs/architecture.md §3).
///
/// Strongest first: [`VerificationLevel::Exact`] and
/// [`VerificationLevel::ExactStructure`] are proofs in exact arithmetic,
/// [`VerificationLevel::VerifiedFloat`] is a rigorous floating-point
/// criterion, and the last two are floating point without proof. The
/// derived order is this one: `Exact < ExactStructure < ... < Float`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum VerificationLevel {
    /// Rational data, exact claims: `P` definite and `Sigma^2 P - Q`
    /// semidefinite by exact LDL^T, or an exact Sturm-sequence proof.
    Exact,
    /// A fluid form whose claims follow exactly from its structure (a
    /// diagonal form, or noise that makes `Q = 0` identically).
    ExactStructure,
    /// Floating-point matrices checked by a rigorous rounding-aware test
    /// (Rump-style Cholesky).
    VerifiedFloat,
    /// Finite-dimensional floating-point eigenvalues only, no proof of
    /// `Sigma^2` (the exact structure of `P` may still be proved).
    Numerical,
    /// Fluid floating-point results without a verified bound.
    Float,
}

named!(VerificationLevel, "verification level", [
    Exact => "exact",
    ExactStructure => "exact_structure",
    VerifiedFloat => "verified_float",
    Numerical => "numerical",
    Float => "float",
]);

impl VerificationLevel {
    /// Whether the level is a proof (exact or verified floating point).
    pub fn is_proof(&self) -> bool {
        matches!(self, VerificationLevel::Exact | VerificationLevel::ExactStructure | VerificationLevel::VerifiedFloat)
    }

    /// The name of an optional level: `none` when there is no claim.
    ///
    /// ```
    /// use outcome::VerificationLevel;
    /// assert_eq!(VerificationLevel::name_of(None), "none");
    /// assert_eq!(VerificationLevel::name_of(Some(VerificationLevel::Float)), "float");
    /// ```
    pub fn name_of(level: Option<VerificationLevel>) -> &'static str {
        level.map_or("none", |l| l.as_str())
    }
}

/// The sign of a definite conserved form: `s P` is positive definite.
///
/// The discriminants are `+1` and `-1`, so even an `as` cast gives the
/// number certificates write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
#[repr(i8)]
pub enum Sign {
    /// `P` is positive definite.
    Positive = 1,
    /// `P` is negative definite.
    Negative = -1,
}

named!(Sign, "sign", [
    Positive => "positive",
    Negative => "negative",
]);

impl Sign {
    /// `+1.0` or `-1.0`, to multiply floating-point forms by.
    pub fn as_f64(self) -> f64 {
        match self {
            Sign::Positive => 1.0,
            Sign::Negative => -1.0,
        }
    }

    /// `+1` or `-1`, as certificates write it.
    pub fn as_i8(self) -> i8 {
        match self {
            Sign::Positive => 1,
            Sign::Negative => -1,
        }
    }

    /// The sign written as `1` or `-1` (`None` for anything else).
    ///
    /// ```
    /// use outcome::Sign;
    /// assert_eq!(Sign::from_i64(-1), Some(Sign::Negative));
    /// assert_eq!(Sign::from_i64(0), None);
    /// ```
    pub fn from_i64(s: i64) -> Option<Sign> {
        match s {
            1 => Some(Sign::Positive),
            -1 => Some(Sign::Negative),
            _ => None,
        }
    }

    /// Whether this is [`Sign::Positive`].
    pub fn is_positive(self) -> bool {
        self == Sign::Positive
    }

    /// The other sign.
    pub fn flip(self) -> Sign {
        match self {
            Sign::Positive => Sign::Negative,
            Sign::Negative => Sign::Positive,
        }
    }
}

/// The verdict of a certificate about a whole box of parameters: the
/// pointwise verdicts, proved on every sub-box of a bisection or on part of
/// them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BoxVerdict {
    /// Every sub-box is proved stable.
    Stable,
    /// Some sub-boxes are proved stable, the others linearly unstable or
    /// undecided.
    PartlyStable,
    /// Every sub-box is proved linearly unstable.
    LinearlyUnstable,
    /// No sub-box is proved stable; some are proved linearly unstable.
    PartlyUnstable,
    /// Nothing is proved on any sub-box.
    Undecided,
    /// `mu_e` is proved not an equilibrium on every sub-box: for no
    /// parameter in the box.
    NotAnEquilibrium,
    /// Some sub-boxes are proved not to hold an equilibrium, the others
    /// are undecided (they contain the parameters where `mu_e` may be one).
    PartlyNotAnEquilibrium,
    /// `mu_e` is an equilibrium for every parameter and the noise is
    /// proved to move it on every sub-box.
    NoiseIncompatible,
    /// Some sub-boxes are proved noise-incompatible, the others undecided.
    PartlyNoiseIncompatible,
}

named!(BoxVerdict, "box verdict", [
    Stable => "stable",
    PartlyStable => "partly_stable",
    LinearlyUnstable => "linearly_unstable",
    PartlyUnstable => "partly_unstable",
    Undecided => "undecided",
    NotAnEquilibrium => "not_an_equilibrium",
    PartlyNotAnEquilibrium => "partly_not_an_equilibrium",
    NoiseIncompatible => "noise_incompatible",
    PartlyNoiseIncompatible => "partly_noise_incompatible",
]);

impl BoxVerdict {
    /// What the verdict claims of the spec's own parameter point (which
    /// lies in the box): the pointwise verdict it implies, or `None` when
    /// it implies none (only part of the box is proved).
    pub fn at_every_point(self) -> Option<Verdict> {
        match self {
            BoxVerdict::Stable => Some(Verdict::Stable),
            BoxVerdict::LinearlyUnstable => Some(Verdict::LinearlyUnstable),
            BoxVerdict::NotAnEquilibrium => Some(Verdict::NotAnEquilibrium),
            BoxVerdict::NoiseIncompatible => Some(Verdict::NoiseIncompatible),
            _ => None,
        }
    }
}

/// What a certificate is about, and so which pipeline wrote it and which
/// checker re-derives it. Box, fluid, Zeitlin and large certificates write
/// it as their `kind` field; a finite-dimensional certificate at one
/// parameter point has no `kind` field (its format predates the field) and
/// reads as [`CertificateKind::LiePoisson`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CertificateKind {
    /// A finite-dimensional Lie–Poisson system at one parameter point,
    /// certified in exact arithmetic (up to 64 coordinates).
    LiePoisson,
    /// A finite-dimensional system over a box of parameters.
    Box,
    /// A shear flow of 2D Euler (incompressible or compressible).
    Fluid,
    /// The stochastic Zeitlin model on the sphere.
    Zeitlin,
    /// A finite-dimensional system above 64 coordinates (sparse floating point).
    Large,
}

named!(CertificateKind, "certificate kind", [
    LiePoisson => "lie_poisson",
    Box => "box",
    Fluid => "fluid",
    Zeitlin => "zeitlin",
    Large => "large",
]);

#[cfg(test)]
mod tests {
    use super::*;

    /// The serde names, the `as_str` names and `FromStr` agree for every
    /// value of every type, and unknown names are refused with the list.
    #[test]
    fn names_agree_everywhere() {
        fn check<T>(all: &[T])
        where
            T: Serialize + for<'de> Deserialize<'de> + fmt::Display + FromStr + PartialEq + fmt::Debug + Copy,
            <T as FromStr>::Err: fmt::Debug,
        {
            for &v in all {
                let json = serde_json::to_string(&v).unwrap();
                assert_eq!(json, format!("\"{v}\""));
                assert_eq!(serde_json::from_str::<T>(&json).unwrap(), v);
                assert_eq!(v.to_string().parse::<T>().unwrap(), v);
            }
        }
        check(Verdict::ALL);
        check(VerificationLevel::ALL);
        check(Sign::ALL);
        check(BoxVerdict::ALL);
        check(CertificateKind::ALL);
        let e = "stabel".parse::<Verdict>().unwrap_err();
        assert!(e.to_string().contains("stable, linearly_unstable"), "{e}");
        assert!(serde_json::from_str::<VerificationLevel>("\"none\"").is_err());
    }

    #[test]
    fn sign_arithmetic() {
        for s in Sign::ALL {
            assert_eq!(Sign::from_i64(s.as_i8() as i64), Some(*s));
            assert_eq!(*s as i64, s.as_i8() as i64);
            assert_eq!(s.as_f64(), s.as_i8() as f64);
            assert_eq!(s.flip().flip(), *s);
            assert_ne!(s.flip(), *s);
        }
    }
}
