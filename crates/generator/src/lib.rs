//! The linearised stochastic dynamics and the growth constant `Sigma^2`.
//!
//! Steps 4–9 of the stochastic energy–Casimir method (docs/architecture.md §2):
//!
//! * [`linearise`]: `A` (the Jacobian of `mu -> ad*_{Dh(mu)} mu` at `mu_e`),
//!   `B_i = ad*_{sigma_i}` and the Itô drift `A~ = A + 1/2 sum B_i^2`, exactly;
//! * [`generator_form`]: for `f(x) = x^T P x` the Kolmogorov generator of
//!   `dx = A x dt + sum B_i x o dW^i` is `x^T Q x` with
//!   `Q = P A~ + A~^T P + sum_i B_i^T P B_i`; its drift part `P A + A^T P`
//!   vanishes for an energy–Casimir `P` (reported as a residual);
//! * [`growth_constant`]: `Sigma^2 = max(0, lambda_max(Q, P))` (with `(-Q, -P)`
//!   when `P < 0`), the sharpest constant in `L|x|_P^2 <= Sigma^2 |x|_P^2`, hence
//!   `E|x_t|_P^2 <= |x_0|_P^2 e^{Sigma^2 t}`;
//! * [`StoppingTime`]: `T(eps, delta) = ln(eps/delta)/Sigma^2`;
//! * [`find_instability`]: an eigenvalue of `A` with positive real part;
//! * [`SecondMoments`]: the exact second-moment equation, independent evidence;
//! * [`analyse`]: the whole pipeline and its [`Verdict`];
//! * [`closed_forms`]: `Sigma^2` for the rigid body and the heavy top, derived.
//!
//! ```
//! use algebra::builtin;
//! use casimir::System;
//! use exact::{parse_expression, Rational, Symbols};
//! use generator::{analyse, closed_forms, Settings, Verdict};
//! let se3 = builtin("se3").unwrap().algebra;
//! let s = Symbols::new(se3.coordinates());
//! // Heavy top, I = (1, 2, 3), mgl = 1, spinning about e3 with p = 4, noise 3/10 e3.
//! let h = parse_expression("Pi1^2/2 + Pi2^2/4 + Pi3^2/6 + Gamma3", &s).unwrap();
//! let cas = ["(Gamma1^2 + Gamma2^2 + Gamma3^2)/2", "Pi1*Gamma1 + Pi2*Gamma2 + Pi3*Gamma3"]
//!     .iter().map(|c| parse_expression(c, &s).unwrap()).collect();
//! let q = |n: i64, d: i64| Rational::new(n.into(), d.into());
//! let z = q(0, 1);
//! let system = System::new(se3, h, cas, vec![],
//!     vec![z.clone(), z.clone(), q(4, 1), z.clone(), z.clone(), q(1, 1)],
//!     vec![vec![z.clone(), z.clone(), q(3, 10), z.clone(), z.clone(), z.clone()]]).unwrap();
//! let a = analyse(&system, &Settings::default());
//! assert_eq!(a.verdict, Verdict::Stable);
//! let expected = closed_forms::heavy_top_sigma2(1.0, 2.0, 3.0, 1.0, 4.0, 0.3).unwrap();
//! assert!((a.sigma2().unwrap() - expected).abs() < 1e-12 * expected);
//! ```
#![warn(missing_docs)]

mod bound;
mod certify;
pub mod closed_forms;
mod form;
mod growth;
mod instability;
mod linearise;
mod moments;
mod numeric;
mod optimise;
mod pencil;
mod pipeline;
mod spectral;
mod stopping;

pub use bound::{family_lower_bound, InfimumWitness};
pub use certify::{certify_sigma2, sigma2_bound_holds, sigma2_gap, ExactSigma2};
pub use form::{generator_form, GeneratorForm};
pub use growth::{growth_constant, GrowthConstant, GrowthError};
pub use instability::{find_instability, instability_from_spectrum, spectrum, Instability, SpectrumError};
pub use linearise::{linearise, Linearisation};
pub use moments::SecondMoments;
pub use numeric::{analyse_numeric, NumericAnalysis, NumericRoute};
pub use optimise::{optimise_choice, OptimiseSettings, Optimum};
pub use pipeline::{analyse, Analysis, OptimumSummary, Settings, StableEvidence, Verdict};
pub use spectral::{exact_spectrum_test, SpectralProof};
pub use stopping::StoppingTime;
