//! Which verified bounds the banded walls check proves, mode by mode: for
//! each x-mode of a fluid spec (at the spec's or a given `ny`), the Lanczos
//! `Sigma^2_k` and a row of `+` (proved) and `.` (not proved) for the bounds
//! `Sigma^2_k (1 + m)`, `m` every rung of the margin ladder
//! (`fluid::constants`: `1e-8` to `8.1e-3`; the analysis proves the widest
//! first and narrows the modes that set the overall bound from
//! `fluid::analysis::first_rung`, `fluid::analysis::tighten_overall_bound`)
//! and then `1, 9, 29, 99` (2, 10, 30 and 100 times `Sigma^2_k`). The measurements behind
//! `fluid::analysis::prove_remaining_modes` and docs/fluids.md §2
//! came from it.
//!
//! `cargo run --release -p verify --example walls_margins -- SPEC [NY] [FIRST_MODE]`

use fluid::analysis::chosen_form;
use fluid::constants::{ladder_margin, VERIFY_ATTEMPTS};
use fluid::modes::Mode;
use fluid::walls_check::verify_walls;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 2 {
        eprintln!("usage: walls_margins SPEC [NY] [FIRST_MODE]");
        std::process::exit(2);
    }
    let text = std::fs::read_to_string(&args[1]).expect("read spec");
    let mut spec = spec::parse_fluid_spec(&text).unwrap_or_else(|e| panic!("{e}"));
    if let Some(ny) = args.get(2) {
        spec.problem.ny = ny.parse().expect("ny");
    }
    let first: usize = args.get(3).map_or(1, |m| m.parse().expect("first mode"));
    let problem = &spec.problem;
    let (grid, coef, form) = chosen_form(problem).expect("the spec admits a form");
    let ladder: Vec<f64> = (0..VERIFY_ATTEMPTS).map(ladder_margin).collect();
    let wide = [1.0, 9.0, 29.0, 99.0];
    println!("ny {} sign {:?}; margins {ladder:?} | {wide:?}", problem.ny, form.sign);
    for m in first..=problem.x_modes {
        let k = 2.0 * std::f64::consts::PI * m as f64 / problem.x_period;
        let mode = Mode::new(&grid, k);
        let s = mode.sigma2(&form, &coef, spec.settings.lanczos_tolerance).expect("definite").lambda_max;
        let row = |margins: &[f64]| -> String {
            margins
                .iter()
                .map(|e| if verify_walls(&grid, k, &form, &coef, s * (1.0 + e)).1 { '+' } else { '.' })
                .collect()
        };
        println!("m {m:3}  Sigma^2_k {s:.10e}  {}|{}", row(&ladder), row(&wide));
    }
}
