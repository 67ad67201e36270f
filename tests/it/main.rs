//! The workspace's integration tests, one binary: each module was once its
//! own test file, and one binary links the engine once instead of 33 times.
//!
//! Run one module with a filter, e.g. `cargo test -p verify --test it boxes::`.
//! The heavy run, `VERIFY_HEAVY_TESTS=1 cargo test -p verify --test it --
//! --include-ignored` (CI's heavy stage), takes the long property runs'
//! heavy case counts and runs the tests marked `ignore = "heavy..."`;
//! docs/architecture.md has the developer's loop.

mod common;
#[path = "common/su_n.rs"]
mod su_n;

mod barotropic;
mod bases;
mod boxes;
mod charts;
mod cli;
mod closed_forms;
mod degenerate;
mod docs;
mod envelope;
mod fluid;
mod fluid_cli;
mod fluid_scale;
mod large;
mod library;
mod moments;
mod newcomer;
mod no_panic;
mod numeric_level;
mod output_paths;
mod potential_noise;
mod progress;
mod properties;
mod random_systems;
mod report;
mod schema;
mod sharpness;
mod simulate_shards;
mod simulation;
mod statements;
mod sweep_cli;
mod tamper;
mod trust;
mod zeitlin_cli;
mod zeitlin_fields;
mod zeitlin_generic;
mod zeitlin_harmonics;
mod zeitlin_su_n;
