//! Certificates over a whole parameter box: "stable for every parameter
//! in this box", with a certified bound on `Sigma^2` (docs/boxes.md).
//!
//! The exact pipeline proves stability at one parameter point. Here the
//! parameters named by the user stay symbolic:
//!
//! * [`parse`]: the spec's expressions with the box parameters as
//!   variables, into rational functions ([`Frac`]);
//! * [`symbolic`]: `Dh`, `D^2h`, the conserved gradients and Hessians, the
//!   linearised drift and the noise at `mu_e(theta)`, all rational
//!   functions of the parameters, and for a choice fixed at a sub-box's
//!   centre, the multipliers `lambda(theta)` and the forms `V = sign P`
//!   and `sign Q`;
//! * [`bernstein`]: exact Bernstein expansions on boxes, which prove a
//!   polynomial's sign or a polynomial matrix's definiteness on a whole
//!   box;
//! * [`certify`]: bisection of the box, the choice at each sub-box's
//!   centre by the exact pipeline, and the proof over the sub-box.

#![warn(missing_docs)]

pub mod bernstein;
pub mod certify;
pub mod frac;
pub mod parse;
pub mod symbolic;

pub use bernstein::ParamBox;
pub use certify::{
    certify_box, prove_excluded, prove_leaf, verdict_of, BoxReport, BoxSettings, BoxVerdict, Leaf, LeafCounts,
    LeafOutcome,
};
pub use frac::Frac;
pub use parse::{parse_box_expression, parse_box_expression_with_divisors, BoxSymbols};
pub use symbolic::{BoxChoice, BoxSystem, BoxSystemError, Symbolic};
