//! The crate's integration tests, one binary (each module was its own test
//! file; one binary links the crate once).

mod lagrange_top;
mod rigid_body;
