//! One x-mode of a fluid spec, for the side-by-side benchmark with scipy
//! (`bench/fluid_side_by_side.sh`): times the engine's Lanczos estimate of
//! Sigma^2, its verified bound as the analysis first finds it
//! (`fluid::analysis::verified_mode_bound`: the widest rung of the margin
//! ladder of `fluid::constants`, one banded verified check, with the dense
//! check only for a walls mode the banded one does not prove; best of the
//! repetitions, like the Lanczos time), the narrowing a mode that sets the
//! overall bound goes through afterwards (`narrow_ms`:
//! `fluid::analysis::tighten_overall_bound`), and the dense verified
//! check at `1e-8` for comparison (up to 2047 unknowns), and writes the
//! dense `V` and `Q` of that mode (row-major little-endian f64) for scipy
//! to solve.
//!
//! `cargo run --release -p verify --example fluid_mode -- SPEC M OUTDIR [REPS] [NY]`
//! (`NO_DENSE=1`: the Lanczos estimate and the verified bound alone, for
//! profilers: no dense check, no matrices written; `ONLY_LANCZOS=1`: the
//! Lanczos estimate and its step count alone).

use fluid::analysis::chosen_form;
use fluid::modes::Mode;
use std::io::Write;
use std::time::Instant;

fn write_matrix(path: &std::path::Path, m: &nalgebra::DMatrix<f64>) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            f.write_all(&m[(i, j)].to_le_bytes())?;
        }
    }
    Ok(())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: fluid_mode SPEC M OUTDIR [REPS]");
        std::process::exit(2);
    }
    let text = std::fs::read_to_string(&args[1]).expect("read spec");
    let mut spec = spec::parse_fluid_spec(&text).unwrap_or_else(|e| panic!("{e}"));
    if let Some(ny) = args.get(5) {
        spec.problem.ny = ny.parse().expect("ny");
    }
    let m: usize = args[2].parse().expect("mode index");
    let out = std::path::PathBuf::from(&args[3]);
    let reps: usize = args.get(4).map_or(20, |r| r.parse().expect("reps"));
    std::fs::create_dir_all(&out).expect("out dir");
    let problem = &spec.problem;
    let (grid, coef, form) = chosen_form(problem).expect("the spec admits a form");
    let k = 2.0 * std::f64::consts::PI * m as f64 / problem.x_period;
    let mode = Mode::new(&grid, k);
    // Lanczos (the engine's method), best of `reps`
    let mut best = f64::INFINITY;
    let mut value = 0.0;
    let mut iterations = 0;
    let mut ritz = None;
    for _ in 0..reps {
        let t = Instant::now();
        let s = mode.sigma2(&form, &coef, spec.settings.lanczos_tolerance).expect("definite");
        best = best.min(t.elapsed().as_secs_f64());
        value = s.lambda_max;
        iterations = s.ritz.iterations;
        ritz = Some(s.ritz);
    }
    let ritz = ritz.expect("at least one repetition");
    if std::env::var_os("ONLY_LANCZOS").is_some() {
        println!("{{\"n\": {}, \"lanczos_ms\": {:.4}, \"iterations\": {iterations}}}", grid.n(), best * 1e3);
        return;
    }
    // the verified bound as the analysis finds it
    // (`fluid::analysis::verified_mode_bound`; best of `reps`, like the
    // Lanczos time); its margin is reported as the relative excess over
    // the Lanczos value
    let mut check = f64::INFINITY;
    let mut first = (None, false);
    for _ in 0..reps {
        let t = Instant::now();
        first = fluid::analysis::verified_mode_bound(&mode, &form, &coef, value, &ritz);
        check = check.min(t.elapsed().as_secs_f64());
    }
    let proved = first.0.map(|u| (u - value) / value);
    // the narrowing a mode that sets the overall bound goes through after
    // that (`fluid::analysis::tighten_overall_bound`: the ladder again from
    // `first_rung`, the banded check), best of `reps`
    let mut narrow = f64::INFINITY;
    let mut narrowed = None;
    for _ in 0..reps {
        let mut one = [fluid::analysis::ModeResult {
            m,
            k,
            sigma2: value,
            sigma2_upper: first.0,
            form_verified: first.1,
            iterations,
        }];
        let t = Instant::now();
        fluid::analysis::tighten_overall_bound(
            &mut one,
            &[ritz],
            fluid::analysis::first_rung(grid.n()),
            &fluid::analysis::Progress::new(),
            |_, bar| fluid::walls_check::verify_walls(&grid, k, &form, &coef, bar).1,
        );
        narrow = narrow.min(t.elapsed().as_secs_f64());
        narrowed = one[0].sigma2_upper.map(|u| (u - value) / value);
    }
    let margin = |m: Option<f64>| m.map_or("null".to_string(), |m| format!("{m:.2e}"));
    // the dense verified check at the tightest margin, where affordable
    let dense_check = if grid.n() < 2048 && std::env::var_os("NO_DENSE").is_none() {
        let t = Instant::now();
        let _ = mode.verify_dense(&form, &coef, value * (1.0 + 1e-8) + 1e-300);
        t.elapsed().as_secs_f64() * 1e3
    } else {
        -1.0
    };
    if std::env::var_os("NO_DENSE").is_some() {
        // For profilers: the Lanczos estimate and the verified bound alone.
        println!(
            "{{\"n\": {}, \"lanczos_ms\": {:.4}, \"check_ms\": {:.2}, \"margin\": {}, \"narrow_ms\": {:.2}, \"narrowed\": {}}}",
            grid.n(),
            best * 1e3,
            check * 1e3,
            margin(proved),
            narrow * 1e3,
            margin(narrowed)
        );
        return;
    }
    let v = mode.form_matrix(&form);
    let q = mode.generator_matrix(&form, &coef);
    write_matrix(&out.join("V.f64"), &v).expect("write V");
    write_matrix(&out.join("Q.f64"), &q).expect("write Q");
    println!(
        "{{\"n\": {}, \"k\": {k}, \"sigma2\": {value:.17e}, \"lanczos_ms\": {:.4}, \"lanczos_iterations\": {iterations}, \"check_ms\": {:.2}, \"margin\": {}, \"narrow_ms\": {:.2}, \"narrowed\": {}, \"dense_check_ms\": {dense_check:.2}}}",
        grid.n(),
        best * 1e3,
        check * 1e3,
        margin(proved),
        narrow * 1e3,
        margin(narrowed)
    );
}
