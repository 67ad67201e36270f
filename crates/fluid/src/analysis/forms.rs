//! The functional a profile admits and its form `V` per mode: the choice's
//! form and the sentence why it is stable, the Galilean-shifted forms, and
//! `Sigma^2` over all modes at one resolution by Lanczos.

use super::*;

pub(super) fn form_for(choice: &Choice, profile: &Profile, coef: &Coefficients, grid: &YGrid) -> Option<Form> {
    match choice {
        Choice::Pseudomomentum { sign } => {
            Some(Form { energy: 0.0, w: coef.upp.iter().map(|p| 1.0 / p).collect(), sign: *sign })
        }
        Choice::Enstrophy => Some(Form { energy: 0.0, w: vec![1.0; grid.n()], sign: Sign::Positive }),
        Choice::Forced { shift, zeros, sign } => Some(Form {
            energy: 1.0,
            w: grid.nodes().iter().map(|y| casimir_weight(profile, 1.0, *shift, zeros, *y)).collect(),
            sign: *sign,
        }),
        Choice::NoForm { .. } => None,
    }
}

/// The form of a choice and the sentence saying why it gives stability, or
/// why there is no form (`Err`, with the choice's own reason).
pub(super) fn form_and_reason(
    choice: &Choice,
    profile: &Profile,
    coef: &Coefficients,
    grid: &YGrid,
    summary: &FormSummary,
) -> Result<(Form, String), String> {
    let reason = match choice {
        Choice::Pseudomomentum { .. } => "U'' has one sign (Rayleigh): the pseudomomentum int omega^2/U'' (Casimir plus x-momentum, the limit |c| -> infinity of energy + Casimir + c momentum) is conserved by the drift and by every noise field (eta(y), 0), so Sigma^2 = 0".to_string(),
        Choice::Enstrophy => "U'' = 0: the enstrophy int omega^2 is conserved by the drift and the noise, so Sigma^2 = 0".to_string(),
        Choice::Forced { .. } => format!("{}; the form is definite for every x-mode and Sigma^2 is the largest generalised eigenvalue of (Q, V) over the modes", summary.casimir_weight),
        Choice::NoForm { reason } => return Err(reason.clone()),
    };
    let form = form_for(choice, profile, coef, grid).ok_or("no form could be built for the chosen functional")?;
    Ok((form, reason))
}

/// The grid at the problem's `ny`, the coefficients, and the form the
/// pipeline uses (`None` when the profile admits none): for benchmarks and
/// for users who want the per-mode operators themselves.
///
/// ```
/// use fluid::{analysis::{chosen_form, FluidModel, FluidProblem}, expr::parse, grid::Boundary, profile::Profile, modes::Mode};
/// let p = |s: &str| parse(s, &Default::default()).unwrap();
/// let profile = Profile::new(p("sin(y)"), vec![p("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
/// let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 32, x_modes: 1 };
/// let (grid, coef, form) = chosen_form(&problem).unwrap();
/// let s = Mode::new(&grid, 1.0).sigma2(&form, &coef, 1e-12).unwrap();
/// assert!((s.lambda_max - 0.0142173139187).abs() < 1e-10); // the sine-Galerkin value (tests/it/fluid.rs)
/// ```
pub fn chosen_form(problem: &FluidProblem) -> Option<(YGrid, Coefficients, Form)> {
    let profile = &problem.profile;
    let grid = YGrid::new(profile.boundary, profile.interval.0, profile.interval.1, problem.ny);
    let coef = profile.coefficients(&grid);
    let form = form_for(&choose(profile), profile, &coef, &grid)?;
    Some((grid, coef, form))
}

/// The energy–Casimir–momentum form with Galilean shift `c`, if its weight
/// `(U + c)/U''` has one sign at the nodes (`U''` must not vanish there).
pub(super) fn shifted_form(coef: &Coefficients, shift: f64) -> Option<Form> {
    let w: Vec<f64> = coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + shift) / p).collect();
    if w.iter().any(|x| !x.is_finite()) {
        return None;
    }
    if w.iter().all(|x| *x > 0.0) {
        Some(Form { energy: 1.0, w, sign: Sign::Positive })
    } else if w.iter().all(|x| *x < 0.0) {
        Some(Form { energy: 1.0, w, sign: Sign::Negative })
    } else {
        None
    }
}

/// Sigma^2 (max over modes) of a form at one resolution, by Lanczos; `None`
/// if the form is not definite for some mode.
pub(super) fn sigma2_all_modes(
    grid: &YGrid,
    coef: &Coefficients,
    form: &Form,
    ks: &[(usize, f64)],
    tol: f64,
    progress: &Progress,
) -> Option<f64> {
    let values: Vec<Option<f64>> = ks
        .par_iter()
        .map(|(_, k)| {
            mode_step(progress, || Mode::new(grid, *k).sigma2(form, coef, tol).ok().map(|s| s.lambda_max.max(0.0)))
        })
        .collect();
    values.into_iter().try_fold(0.0f64, |acc, v| v.map(|v| acc.max(v)))
}
