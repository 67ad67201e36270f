//! Stochastic 2D Euler about shear flows (the paper's §4.3), discretised and certified.
//!
//! The incompressible perturbation vorticity of x-mode `k` obeys
//! `dw = -ik (U + U'' L^-1) w dt - sum_j ik eta_j w o dW^j` (the vorticity
//! form, in which transport noise is exactly the coadjoint action and no
//! pressure appears). [`grid`] discretises `y` so that the energy is an exactly
//! symmetric form and multiplication by functions of `y` is diagonal;
//! [`modes`] builds the drift, the noise, the energy–Casimir–momentum form
//! `V` and the generator form `Q` of one mode; [`choice`] decides which
//! functional the profile admits; [`analysis`] runs the pipeline over modes
//! and resolutions and handles the compressible model.
//!
//! ```
//! use fluid::{analysis::{analyse, FluidModel, FluidProblem, FluidSettings, Verdict}, expr::parse, grid::Boundary, profile::Profile};
//! // U = sin y in a channel [0, pi] with noise eta = 0.3 cos y: U'' = -sin y
//! // vanishes at the walls, so c = 0 is forced and w = -1 (Arnold's second theorem).
//! let p = |s: &str| parse(s, &Default::default()).unwrap();
//! let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
//! let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 2.0 * std::f64::consts::PI, ny: 64, x_modes: 4 };
//! let a = analyse(&problem, &FluidSettings::default()).unwrap();
//! assert_eq!(a.verdict, Verdict::Stable);
//! assert!(a.sigma2.unwrap() > 0.0 && a.sigma2_upper.unwrap() >= a.sigma2.unwrap());
//! ```
#![warn(missing_docs)]

/// The verified numerics this crate was the home of, now the `numerics`
/// crate's (re-exported so that `fluid::banded` and the rest keep working).
pub use numerics::{banded, dense, interval, lanczos, minimise};
pub use outcome::{Sign, Verdict, VerificationLevel};

pub mod analysis;
pub mod barotropic;
pub mod barotropic_sde;
pub mod choice;
pub mod constants;
pub mod expr;
pub mod grid;
pub mod modes;
pub mod profile;
pub mod simulate;
pub mod walls_check;
