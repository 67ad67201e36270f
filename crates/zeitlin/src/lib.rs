//! The stochastic Zeitlin model: the su(N) truncation of 2D Euler on the
//! sphere (Zeitlin 1991; Modin & Viviani 2020; quflow) with stochastic
//! transport noise, and the stochastic energy–Casimir method for its zonal
//! equilibria.
//!
//! * [`laplacian`]: the Hoppe–Yau Laplacian on one off-diagonal (tridiagonal), and
//!   the `O(N^2)` stream solve `P = Delta_N^{-1} W` ([`laplacian::StreamSolver`]);
//! * [`zonal`]: zonal harmonics `T_{l0}` and the quantisation of a profile `omega(z)`;
//! * [`general`]: equilibria and noise given as matrices: the checks, the zonal frame of a
//!   tilted zonal state, and a dense analysis of states zonal in no frame;
//! * [`matrix_free`]: the analysis of states zonal in no frame at large N, without forming
//!   any `(N^2 - 1)`-square matrix;
//! * [`sphere`]: quflow's real spherical-harmonic basis `T_lm`, spin matrices and rotations;
//! * [`analysis`]: the per-block energy–Casimir–momentum form, `Q`, and `Sigma^2`;
//! * [`block_sde`]: one azimuthal block of the linearised SDE about a zonal
//!   state, its Monte Carlo and its exact second moment;
//! * [`isospectral`]: Monte Carlo of the full nonlinear model with the
//!   Casimir-preserving stochastic isospectral midpoint.
//!
//! The modules are the crate's namespaces (one concern each); the
//! eigen-solvers they share are private.
//!
//! Conventions are quflow's: `<A, B> = Re tr(A B^*) / N`, the bracket
//! `[A, B] / hbar` with `hbar = 2 / sqrt(N^2 - 1)`, `W = i diag(omega)` for a
//! zonal state with the north pole last. See `docs/zeitlin.md`.
#![warn(missing_docs)]

pub mod analysis;
pub mod block_sde;
mod eigen;
pub mod general;
pub mod isospectral;
pub mod laplacian;
pub mod matrix_free;
pub mod sphere;
pub mod zonal;
