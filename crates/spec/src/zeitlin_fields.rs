//! A Zeitlin spec's fields in quflow's layout, to write back into quflow's
//! files: the state and the noise as quflow's `omega` vectors (real
//! spherical-harmonic coefficients at index `l^2 + l + m`), and, for a state
//! zonal in some frame, the perturbation a certificate is about: the
//! fastest-growing eigenvector of a linearly unstable state, or the start
//! whose `E|dW|_P^2` grows fastest for a stable one
//! ([`zeitlin::block_sde::BlockSde::top`]). A tilted state's mode is formed
//! in its zonal frame and rotated back, so every field is in the spec's own
//! frame.

use crate::zeitlin::{analyse_zeitlin, ZeitlinInput, ZeitlinOutcome, ZeitlinSpec};
use nalgebra::{Complex, DMatrix};
use outcome::Verdict;
use zeitlin::block_sde::BlockSde;
use zeitlin::isospectral::{diagonal_perturbation, zonal_state, ZeitlinModel};
use zeitlin::sphere::{rotation_to_axis, to_harmonics};

type C = Complex<f64>;

/// `N` at most for [`zeitlin_fields`]: every harmonic of an `N x N` matrix
/// is formed (`O(N^3)`), and the unstable mode's search is `O(N^4)`.
pub const ZEITLIN_FIELDS_MAX_N: usize = 256;

/// The perturbation a certificate is about, as quflow fields.
#[derive(Clone, Debug, PartialEq)]
pub struct ZeitlinMode {
    /// `unstable_eigenvector` (a linearly unstable state's fastest-growing
    /// eigenvector, `dW(t) = Re(e^{mu t} (real + i imaginary))` in the
    /// sense below) or `fastest_growing_start` (a stable state's start whose
    /// `E|dW|_P^2` grows at `Sigma^2`).
    pub kind: &'static str,
    /// The diagonal `m` in the zonal frame (the azimuthal wavenumber).
    pub block: usize,
    /// `Re mu` (the growth rate), or `lambda_max(Q_m, P_m)` for a start.
    pub rate: f64,
    /// `Im mu` (0 for a start).
    pub frequency: f64,
    /// quflow's `omega` of the perturbation `X` (unit length in `<A, B> =
    /// Re tr(A B^*)/N` up to the block's normalisation).
    pub real: Vec<f64>,
    /// quflow's `omega` of the quarter-period partner `Y`: the linearised
    /// drift maps `X` to `Re(mu) X + Im(mu) Y` (zero for a start).
    pub imaginary: Vec<f64>,
}

/// A Zeitlin spec's fields as quflow's `omega` vectors.
#[derive(Clone, Debug, PartialEq)]
pub struct ZeitlinFields {
    /// `N`.
    pub n: usize,
    /// `W_e` (length `N^2`).
    pub state: Vec<f64>,
    /// Each noise field's stream matrix `X_i`.
    pub noise: Vec<Vec<f64>>,
    /// The certificate's perturbation, when the state is zonal in some frame
    /// and stable with a conserved form or linearly unstable.
    pub mode: Option<ZeitlinMode>,
}

/// Why the fields could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ZeitlinFieldsError {
    /// `N` above [`ZEITLIN_FIELDS_MAX_N`].
    #[error("N = {0}: the fields are formed up to N = {ZEITLIN_FIELDS_MAX_N}")]
    TooLarge(usize),
    /// A numerical step failed.
    #[error("{0}")]
    Failed(String),
}

fn fail(e: impl std::fmt::Display) -> ZeitlinFieldsError {
    ZeitlinFieldsError::Failed(e.to_string())
}

/// quflow's `omega` (index `l^2 + l + m`, `l = 0..N-1`) of a matrix.
fn omega_of(w: &DMatrix<C>) -> Result<Vec<f64>, ZeitlinFieldsError> {
    let n = w.nrows();
    let mut out = vec![0.0; n * n];
    for (l, m, x) in to_harmonics(w, n - 1).map_err(fail)? {
        let index = (l * l + l) as i64 + m;
        out[index as usize] = x;
    }
    Ok(out)
}

/// The fields of `spec` (see the module docs).
pub fn zeitlin_fields(spec: &ZeitlinSpec) -> Result<ZeitlinFields, ZeitlinFieldsError> {
    let n = spec.input.n();
    if n > ZEITLIN_FIELDS_MAX_N {
        return Err(ZeitlinFieldsError::TooLarge(n));
    }
    let (w, noise): (DMatrix<C>, Vec<DMatrix<C>>) = match &spec.input {
        ZeitlinInput::Zonal(p) => (zonal_state(&p.omega), p.noise.iter().map(|x| zonal_state(x)).collect()),
        ZeitlinInput::General(p) => (p.w.clone(), p.noise.clone()),
    };
    let state = omega_of(&w)?;
    let noise_fields = noise.iter().map(omega_of).collect::<Result<Vec<_>, _>>()?;
    let mode = match analyse_zeitlin(spec) {
        ZeitlinOutcome::Zonal(Ok(a)) => match &spec.input {
            ZeitlinInput::Zonal(p) => zonal_mode(&p.omega, &p.noise, &a, None)?,
            ZeitlinInput::General(_) => None,
        },
        ZeitlinOutcome::General(g) => match g.as_ref() {
            Ok(g) => match (&g.zonal, &g.frame) {
                (Some(r), Some(zeitlin::general::Frame::Zonal)) => zonal_mode(&r.omega, &r.noise, &r.analysis, None)?,
                (Some(_), Some(zeitlin::general::Frame::Rotated { axis })) => {
                    // The zonal frame of the engine's own rotation, formed
                    // again here so the mode can be rotated back by it.
                    let spin = zeitlin::sphere::quflow_axis(*axis);
                    let v = rotation_to_axis(n, spin).map_err(fail)?;
                    let rotate = |m: &DMatrix<C>| v.adjoint() * m * &v;
                    let diagonal = |m: &DMatrix<C>| (0..n).map(|j| m[(j, j)].im).collect::<Vec<f64>>();
                    let omega = diagonal(&rotate(&w));
                    let xi: Vec<Vec<f64>> = noise.iter().map(|x| diagonal(&rotate(x))).collect();
                    let settings = spec.settings.zonal.clone();
                    let a = zeitlin::analysis::analyse(
                        &zeitlin::analysis::ZeitlinProblem { n, omega: omega.clone(), noise: xi.clone() },
                        &settings,
                    )
                    .map_err(fail)?;
                    zonal_mode(&omega, &xi, &a, Some(&v))?
                }
                _ => None,
            },
            Err(_) => None,
        },
        ZeitlinOutcome::Zonal(Err(_)) => None,
    };
    Ok(ZeitlinFields { n, state, noise: noise_fields, mode })
}

/// The mode of a zonal problem, rotated back by `v` (`X -> V X V^*`).
fn zonal_mode(
    omega: &[f64],
    noise: &[Vec<f64>],
    analysis: &zeitlin::analysis::ZeitlinAnalysis,
    v: Option<&DMatrix<C>>,
) -> Result<Option<ZeitlinMode>, ZeitlinFieldsError> {
    let n = omega.len();
    let back = |x: DMatrix<C>| match v {
        Some(v) => v * x * v.adjoint(),
        None => x,
    };
    let field = |block: usize, z: &[C]| -> Result<Vec<f64>, ZeitlinFieldsError> {
        omega_of(&back(diagonal_perturbation(n, block, z).map_err(fail)?))
    };
    match (analysis.verdict, analysis.choice) {
        (Verdict::LinearlyUnstable, _) => {
            let model = ZeitlinModel::new(n, noise.to_vec()).map_err(fail)?;
            let g = model.fastest_growing_mode(omega).map_err(fail)?;
            let quarter: Vec<C> = g.vector.iter().map(|z| z * C::new(0.0, 1.0)).collect();
            Ok(Some(ZeitlinMode {
                kind: "unstable_eigenvector",
                block: g.m,
                rate: g.rate,
                frequency: g.frequency,
                real: field(g.m, &g.vector)?,
                imaginary: field(g.m, &quarter)?,
            }))
        }
        (Verdict::Stable, Some(choice)) => {
            let lambda = |m: usize| analysis.blocks.iter().find(|b| b.m == m).map_or(0.0, |b| b.lambda_max);
            let block = (1..n).fold(1, |best, m| if lambda(m) > lambda(best) { m } else { best });
            let sde = BlockSde::new(omega, noise, &choice, block).map_err(fail)?;
            let (rate, start) = sde.top().ok_or_else(|| fail("the block's top direction"))?;
            let z: Vec<C> = start.iter().map(|x| C::new(*x, 0.0)).collect();
            Ok(Some(ZeitlinMode {
                kind: "fastest_growing_start",
                block,
                rate,
                frequency: 0.0,
                real: field(block, &z)?,
                imaginary: vec![0.0; n * n],
            }))
        }
        _ => Ok(None),
    }
}
