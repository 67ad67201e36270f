//! The crate's integration tests, one binary (each module was its own test
//! file; one binary links the crate once).

mod block_sde;
mod blocks;
mod general;
mod isospectral;
mod sphere;
