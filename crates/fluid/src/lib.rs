//! Stochastic 2D Euler about shear flows (the paper's §4.3).
#![warn(missing_docs)]

pub mod banded;
pub mod expr;
pub mod grid;
pub mod lanczos;
pub mod modes;
