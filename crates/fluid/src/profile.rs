//! The shear flow `U(y)` and the noise amplitudes `eta_k(y)` as compiled
//! expressions with their derivatives, and the checks made before any
//! discretisation: finite on the interval, periodic when the boundary is.

use crate::expr::{Derivative, Expr};
use crate::grid::{Boundary, YGrid};
use crate::modes::Coefficients;
use std::sync::Arc;

/// The profile, the noise and the domain.
#[derive(Clone, Debug)]
pub struct Profile {
    /// `U` and its first three derivatives.
    pub u: [Derivative; 4],
    /// `eta_k` and `eta_k'`.
    pub eta: Vec<[Derivative; 2]>,
    /// The y-interval `[a, b]`.
    pub interval: (f64, f64),
    /// The boundary condition in y.
    pub boundary: Boundary,
}

/// A profile that cannot be used, with the quantity at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ProfileError {
    /// A value is not finite somewhere on the interval.
    #[error("{what} is not finite at y = {y}")]
    NotFinite {
        /// `"shear_flow"`, `"noise[i]"`, or a derivative of them.
        what: String,
        /// Where.
        y: f64,
    },
    /// A periodic boundary with data that does not match at the two ends.
    #[error("{what} is not periodic on the interval: {left} at y = a but {right} at y = b")]
    NotPeriodic {
        /// The quantity.
        what: String,
        /// Value (or derivative) at `a`.
        left: f64,
        /// At `b`.
        right: f64,
    },
}

impl Profile {
    /// `U` and the noise, with their derivatives (by Taylor jets: see [`crate::expr`]).
    pub fn new(u: Expr, eta: Vec<Expr>, interval: (f64, f64), boundary: Boundary) -> Self {
        let u = Arc::new(u);
        let eta = eta
            .into_iter()
            .map(|e| {
                let e = Arc::new(e);
                [Derivative::new(e.clone(), 0), Derivative::new(e, 1)]
            })
            .collect();
        Profile { u: std::array::from_fn(|k| Derivative::new(u.clone(), k)), eta, interval, boundary }
    }

    /// The same profile with every noise field multiplied by `factor` (a
    /// power of two: then exactly).
    pub fn with_noise_factor(&self, factor: f64) -> Profile {
        Profile { eta: self.eta.iter().map(|[e, d]| [e.times(factor), d.times(factor)]).collect(), ..self.clone() }
    }

    /// Sample points on the closed interval (`count + 1` of them, uniform).
    pub fn samples(&self, count: usize) -> Vec<f64> {
        let (a, b) = self.interval;
        (0..=count).map(|i| a + (b - a) * i as f64 / count as f64).collect()
    }

    /// Reject non-finite values (of `U`, `U'`, `U''`, `U'''`, `eta`, `eta'`)
    /// on a fine sample and at the grid nodes, and non-periodic data on a
    /// periodic interval. The field names are those of the spec.
    pub fn check(&self, extra_points: &[f64]) -> Result<(), ProfileError> {
        let mut points = self.samples(crate::constants::PROFILE_SAMPLES);
        points.extend_from_slice(extra_points);
        let names = ["shear_flow", "shear_flow'", "shear_flow''", "shear_flow'''"];
        for y in &points {
            for (e, name) in self.u.iter().zip(names) {
                if !e.eval(*y).is_finite() {
                    return Err(ProfileError::NotFinite { what: name.into(), y: *y });
                }
            }
            for (i, [e, d]) in self.eta.iter().enumerate() {
                if !e.eval(*y).is_finite() {
                    return Err(ProfileError::NotFinite { what: format!("noise[{i}]"), y: *y });
                }
                if !d.eval(*y).is_finite() {
                    return Err(ProfileError::NotFinite { what: format!("noise[{i}]'"), y: *y });
                }
            }
        }
        if self.boundary == Boundary::Periodic {
            let (a, b) = self.interval;
            let mut quantities: Vec<(String, &Derivative)> =
                names.iter().zip(&self.u).take(3).map(|(n, e)| (n.to_string(), e)).collect();
            for (i, [e, d]) in self.eta.iter().enumerate() {
                quantities.push((format!("noise[{i}]"), e));
                quantities.push((format!("noise[{i}]'"), d));
            }
            for (what, e) in quantities {
                let (l, r) = (e.eval(a), e.eval(b));
                let scale = 1.0 + l.abs().max(r.abs());
                if (l - r).abs() > 1e-9 * scale {
                    return Err(ProfileError::NotPeriodic { what, left: l, right: r });
                }
            }
        }
        Ok(())
    }

    /// `U`, `U''` and the noise at the nodes of `grid`.
    pub fn coefficients(&self, grid: &YGrid) -> Coefficients {
        let y = grid.nodes();
        Coefficients {
            u: y.iter().map(|y| self.u[0].eval(*y)).collect(),
            upp: y.iter().map(|y| self.u[2].eval(*y)).collect(),
            eta: self.eta.iter().map(|[e, _]| y.iter().map(|y| e.eval(*y)).collect()).collect(),
        }
    }

    /// The paper's constant `sup_y sum_k eta_k'(y)^2` (its eq. (eta-bound)),
    /// on a fine sample of the closed interval.
    pub fn paper_bound(&self) -> f64 {
        self.samples(crate::constants::FINE_SAMPLES)
            .iter()
            .map(|y| self.eta.iter().map(|[_, d]| d.eval(*y).powi(2)).sum::<f64>())
            .fold(0.0, f64::max)
    }
}
