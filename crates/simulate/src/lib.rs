//! Simulation of stochastic Lie–Poisson systems.
//!
//! The Stratonovich equation `d mu = ad*_{Dh(mu)} mu dt + sum_i ad*_{sigma_i} mu o dW^i`
//! moves `mu` on its coadjoint orbit. [`Scheme::LieHeun`] keeps it there to
//! round-off: every step is the coadjoint action of a group element,
//!
//! ```text
//! xi_1 = Dh(mu_n) dt + sum_i sigma_i dW_i,      mu* = mu_n + ad*_{xi_1} mu_n,
//! xi_2 = Dh(mu*) dt + sum_i sigma_i dW_i,       mu_{n+1} = exp(ad*_{(xi_1 + xi_2)/2}) mu_n,
//! ```
//!
//! a Heun (stochastic RKMK) step in the Lie algebra: it is consistent with
//! the Stratonovich equation (the average of the generators at the two
//! stages is the Stratonovich midpoint rule to the order that matters; the
//! predictor only enters through `Dh`, so an Euler predictor suffices), and
//! since the update is the coadjoint action of a group element it conserves
//! every Casimir exactly up to the round-off of the exponential.
//! The exponential has closed forms for `so3` (Rodrigues) and `se3`
//! (rotation plus the left Jacobian), and is a scaling-and-squaring matrix
//! exponential otherwise. [`Scheme::Heun`], the Stratonovich Heun scheme in
//! the vector space, is the reference; it drifts off the orbit.
//!
//! [`run_ensemble`] runs many paths in parallel (rayon) with one random
//! stream per path ([`path_rng`]: xoshiro256++ seeded from the seed and the
//! path index) and fixed-size blocks
//! reduced in order, so the numbers do not depend on the thread count; it
//! keeps only statistics at the output times. [`prepare`] and [`run`] make
//! a whole study of an analysed system from them (pilot run, both
//! ensembles, exact moments, exceedance against the certificate).
#![warn(missing_docs)]

mod ensemble;
mod exact_sum;
mod kernel;
mod model;
mod report;
mod scheme;
mod shard_file;
mod study;

pub use ensemble::{
    block_paths, path_rng, run_blocks_cancellable, run_ensemble, run_ensemble_cancellable, shard_blocks, EnsembleError,
    EnsembleSettings, EnsembleStats, EnsembleSums, Observable, Target, BLOCK,
};
pub use exact_sum::ExactSum;
pub use model::Model;
pub use report::study_report;
pub use scheme::{LinearModel, Scheme, Stepper};
pub use shard_file::{
    merge_shard_documents, shard_document, study_identity, MergeError, SHARD_ENGINE, SHARD_FORMAT, SHARD_KIND,
};
pub use study::{
    finish, prepare, run, run_cancellable, run_shard_cancellable, Exceedance, Prepared, Study, StudyError,
    StudySettings, StudyShard,
};
