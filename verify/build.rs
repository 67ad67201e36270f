//! Empty. A build script is what makes Cargo build this package's
//! `[build-dependencies]`, and those exist only for feature unification
//! (verify/Cargo.toml): the proc-macros' `syn` gets the same features here as
//! in the Python extension's build, so the engine's crates built in release
//! for one are the ones the other uses.
fn main() {}
