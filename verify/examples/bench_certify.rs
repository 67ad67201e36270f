//! Time the phases of `certify` on one spec, for the side-by-side comparison
//! with the numpy/scipy baseline (`bench/side_by_side.sh`) and for profilers.
//!
//! Usage: `bench_certify SPEC [REPS]` (`ONLY=analyse` times the analysis alone,
//! `ONLY=numeric` the numeric level). Prints one JSON line with microseconds
//! per certificate for: parsing the spec (JSON + exact polynomials + checks),
//! the analysis at the exact level (default), the numeric level in floating
//! point (`generator::analyse_numeric`, what `verify sweep --numeric`
//! runs: the scope of the numpy timing), the analysis with `exact = false`
//! (no rational Sigma^2, but `P` still proved definite and `P`, `Q` exact:
//! what a spec with `"settings": {"exact": false}` certifies), building the
//! certificate JSON, and the whole `certify` path end to end (spec text in,
//! certificate text out, as `verify certify` writes it).
use std::time::Instant;

// The same allocator as the `verify` binary (src/main.rs), so that the
// figures are those of the engine users run.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn per_call(reps: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm-up
    let t = Instant::now();
    for _ in 0..reps {
        f();
    }
    t.elapsed().as_secs_f64() * 1e6 / reps as f64
}

fn main() {
    let path = std::env::args().nth(1).expect("usage: bench_certify SPEC [REPS]");
    let reps: usize = std::env::args().nth(2).map_or(5000, |s| s.parse().expect("REPS"));
    let text = std::fs::read_to_string(&path).expect("read spec");
    let spec = spec::parse_spec(&text).expect("valid spec");
    let analysis = generator::analyse(&spec.system, &spec.settings.pipeline);
    let only = std::env::var("ONLY").unwrap_or_default();
    if only == "analyse" || only == "numeric" {
        // For profilers: the analysis alone (`numeric`: the numeric level).
        let settings = &spec.settings.pipeline;
        let us = if only == "analyse" {
            per_call(reps, || {
                std::hint::black_box(generator::analyse(&spec.system, settings));
            })
        } else {
            per_call(reps, || {
                std::hint::black_box(generator::analyse_numeric(&spec.system, settings));
            })
        };
        println!("{{\"name\": \"{}\", \"us_analyse\": {us:.2}}}", spec.name);
        return;
    }
    let parse = per_call(reps, || {
        std::hint::black_box(spec::parse_spec(&text).unwrap());
    });
    let analyse = per_call(reps, || {
        std::hint::black_box(generator::analyse(&spec.system, &spec.settings.pipeline));
    });
    let analyse_numeric = per_call(reps, || {
        std::hint::black_box(generator::analyse_numeric(&spec.system, &spec.settings.pipeline));
    });
    let mut inexact_spec = spec.clone();
    inexact_spec.settings.pipeline.exact = false;
    let analyse_inexact = per_call(reps, || {
        std::hint::black_box(generator::analyse(&inexact_spec.system, &inexact_spec.settings.pipeline));
    });
    let certificate = per_call(reps, || {
        std::hint::black_box(spec::certificate_json(&spec, &analysis));
    });
    let end_to_end = per_call(reps, || {
        // Spec text in, certificate text out: what `verify certify` writes.
        let s = spec::parse_spec(&text).unwrap();
        std::hint::black_box(spec::to_pretty_json(&spec::certify_lie(&s).json));
    });
    println!(
        "{{\"name\": \"{}\", \"reps\": {reps}, \"us_parse\": {parse:.2}, \"us_analyse\": {analyse:.2}, \"us_analyse_numeric\": {analyse_numeric:.2}, \"us_analyse_exact_false\": {analyse_inexact:.2}, \"us_certificate_json\": {certificate:.2}, \"us_end_to_end\": {end_to_end:.2}}}",
        spec.name
    );
}
