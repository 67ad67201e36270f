//! The discrete pseudomomentum of a profile whose `U''` vanishes only at the
//! walls (docs/fluids.md §3, case 3).
//!
//! When `U''` has one sign inside the channel and vanishes at a wall (`U =
//! sin y` on `(0, pi)`), the continuum pseudomomentum `int omega^2 / U''` has an
//! unbounded weight, so [`crate::choice::choose`] takes the forced
//! energy–Casimir form and the optimisation runs over the functionals with a
//! *bounded* Casimir weight. On the grid, though, the wall nodes carry no
//! unknowns, `U''` is nonzero at every node that does, and
//! `V = sign(U'') diag(m_a / U''(y_a))` is definite. It is conserved exactly
//! by the discretised drift (`V R = sign(U'') (diag(U m / U'') + K)` is
//! symmetric, `R = diag(U) + diag(U'' / m) K`) and by every noise field
//! (`V` and `diag(eta)` commute), so `Q = 0`: `Sigma^2 = 0` for the
//! discretised linear SDE at every `ny`. It is not the headline because it has
//! no continuum limit: its condition number grows with `ny`, and a smooth
//! perturbation that does not vanish at the wall has a norm that grows without
//! bound under refinement. The certificate reports it beside the headline.

use super::{table_resolutions, FluidModel, FluidProblem, FluidSettings};
use crate::choice::{choose, Choice, SIGN_PROOF_BUDGET};
use crate::expr::SignProof;
use crate::grid::{Boundary, YGrid};
use outcome::Sign;

/// The discrete pseudomomentum: `Sigma^2 = 0` with a form whose condition
/// number grows under refinement.
#[derive(Clone, Debug, PartialEq)]
pub struct DiscretePseudomomentum {
    /// The sign of `U''` at every node that carries an unknown.
    pub sign: Sign,
    /// The walls where `U''` vanishes.
    pub zeros: Vec<f64>,
    /// The form over the convergence table, coarsest first.
    pub rows: Vec<PseudomomentumRow>,
}

/// The discrete pseudomomentum `V = diag(m_a / |U''(y_a)|)` at one resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PseudomomentumRow {
    /// The resolution.
    pub ny: usize,
    /// `cond(V)`: `V` is diagonal, so the ratio of its extreme entries.
    pub condition_number: f64,
    /// `sum_a m_a / |U''(y_a)|`, the squared `V`-norm of the perturbation
    /// `omega = 1`: a quadrature of `int dy / |U''|`, which diverges at a
    /// wall where `U''` vanishes, so it grows without bound under refinement.
    pub norm_of_one: f64,
}

/// The discrete pseudomomentum of an incompressible walls problem whose
/// `U''` vanishes at a wall and nowhere inside, with its sign proved by
/// interval arithmetic on the closed interval spanned by the unknown nodes of
/// the finest grid (which contains the nodes of every coarser grid of the
/// table); `None` otherwise.
///
/// ```
/// use fluid::analysis::{discrete_pseudomomentum, FluidModel, FluidProblem, FluidSettings};
/// use fluid::grid::Boundary;
/// use fluid::expr::parse;
/// use fluid::profile::Profile;
/// let e = |s: &str| parse(s, &Default::default()).unwrap();
/// let profile = Profile::new(e("sin(y)"), vec![e("0.3*cos(y)")], (0.0, std::f64::consts::PI), Boundary::Walls);
/// let problem = FluidProblem { model: FluidModel::Incompressible, profile, x_period: 6.283185307179586, ny: 64, x_modes: 4 };
/// let settings = FluidSettings { convergence_from: 16, ..Default::default() };
/// let d = discrete_pseudomomentum(&problem, &settings).expect("U'' = -sin y vanishes only at the walls");
/// assert_eq!(d.rows.iter().map(|r| r.ny).collect::<Vec<_>>(), vec![16, 32, 64]);
/// // The form degenerates under refinement: its condition number grows, and
/// // so does the norm of the perturbation omega = 1 (int dy / sin y diverges).
/// assert!(d.rows.windows(2).all(|w| w[1].condition_number > 1.5 * w[0].condition_number));
/// assert!(d.rows.windows(2).all(|w| w[1].norm_of_one > w[0].norm_of_one + 1.0));
/// ```
pub fn discrete_pseudomomentum(problem: &FluidProblem, settings: &FluidSettings) -> Option<DiscretePseudomomentum> {
    let profile = &problem.profile;
    if problem.model != FluidModel::Incompressible || profile.boundary != Boundary::Walls {
        return None;
    }
    let Choice::Forced { zeros, .. } = choose(profile) else { return None };
    let (a, b) = profile.interval;
    let at_wall = |z: f64| (z - a).abs() <= 1e-9 * (b - a) || (z - b).abs() <= 1e-9 * (b - a);
    if zeros.is_empty() || !zeros.iter().all(|z| at_wall(*z)) {
        return None;
    }
    let fine = YGrid::new(profile.boundary, a, b, problem.ny);
    let (first, last) = (*fine.nodes().first()?, *fine.nodes().last()?);
    let sign = match profile.u[2].sign_on(first, last, SIGN_PROOF_BUDGET) {
        SignProof::Positive => Sign::Positive,
        SignProof::Negative => Sign::Negative,
        SignProof::Zero | SignProof::Changes | SignProof::Unproved => return None,
    };
    let rows = table_resolutions(problem.ny, settings.convergence_from)
        .into_iter()
        .map(|ny| {
            let grid = if ny == problem.ny { fine.clone() } else { YGrid::new(profile.boundary, a, b, ny) };
            // V_aa = m_a / |U''(y_a)|, positive by the sign proof.
            let v: Vec<f64> =
                grid.nodes().iter().zip(grid.weights()).map(|(y, m)| m / profile.u[2].eval(*y).abs()).collect();
            let (lo, hi) = v.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| (lo.min(*x), hi.max(*x)));
            PseudomomentumRow { ny, condition_number: hi / lo, norm_of_one: v.iter().sum() }
        })
        .collect();
    Some(DiscretePseudomomentum { sign, zeros, rows })
}
