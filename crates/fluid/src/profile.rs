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
    /// The potential part of each noise element (compressible flow only).
    pub potential: Vec<Potential>,
}

/// The potential part `r(y)` of a noise element `((eta(y), 0), r(y))` of the
/// compressible semidirect-product algebra (vector fields acting on
/// densities). In the paper's convention
/// `ad*_{(u, f)} (m, rho) = -((u . grad) m + m (grad u)^T + m div u + rho grad f, div(rho u))`,
/// the pair acts on the equilibrium `(m_e, rho_e) = ((U(y), 0), 1)` by
/// `-(0, U eta' + r')` on the momentum and `0` on the density, so it leaves
/// the equilibrium fixed exactly when `r' = -U eta'` (docs/fluids.md). In
/// incompressible flow a potential force is a gradient, absorbed by the
/// pressure: it does not act on the vorticity.
#[derive(Clone, Debug)]
pub enum Potential {
    /// No potential part: `r = 0`.
    None,
    /// The compatible completion `r = -int U eta' dy` (up to a constant), so
    /// `r' = -U eta'` exactly.
    Compatible,
    /// A given `r(y)` and its derivative.
    Given([Derivative; 2]),
}

impl Potential {
    /// A given potential `r(y)` with its derivative (by Taylor jets).
    pub fn given(r: Expr) -> Potential {
        let r = Arc::new(r);
        Potential::Given([Derivative::new(r.clone(), 0), Derivative::new(r, 1)])
    }

    /// `r'(y)`, given `U(y)` and `eta'(y)` there.
    pub fn gradient(&self, y: f64, u: f64, eta_prime: f64) -> f64 {
        match self {
            Potential::None => 0.0,
            Potential::Compatible => -(u * eta_prime),
            Potential::Given([_, d]) => d.eval(y),
        }
    }

    fn times(&self, factor: f64) -> Potential {
        match self {
            Potential::Given([r, d]) => Potential::Given([r.times(factor), d.times(factor)]),
            other => other.clone(),
        }
    }
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
        let eta: Vec<[Derivative; 2]> = eta
            .into_iter()
            .map(|e| {
                let e = Arc::new(e);
                [Derivative::new(e.clone(), 0), Derivative::new(e, 1)]
            })
            .collect();
        let potential = vec![Potential::None; eta.len()];
        Profile { u: std::array::from_fn(|k| Derivative::new(u.clone(), k)), eta, interval, boundary, potential }
    }

    /// The same profile with a potential part for each noise field (one
    /// per field; a shorter list leaves the rest without).
    pub fn with_potentials(mut self, potentials: Vec<Potential>) -> Profile {
        for (slot, p) in self.potential.iter_mut().zip(potentials) {
            *slot = p;
        }
        self
    }

    /// The same profile with every noise field multiplied by `factor` (a
    /// power of two: then exactly).
    pub fn with_noise_factor(&self, factor: f64) -> Profile {
        Profile {
            eta: self.eta.iter().map(|[e, d]| [e.times(factor), d.times(factor)]).collect(),
            potential: self.potential.iter().map(|p| p.times(factor)).collect(),
            ..self.clone()
        }
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
            for (i, p) in self.potential.iter().enumerate() {
                if let Potential::Given([r, d]) = p {
                    if !r.eval(*y).is_finite() {
                        return Err(ProfileError::NotFinite { what: format!("noise[{i}].potential"), y: *y });
                    }
                    if !d.eval(*y).is_finite() {
                        return Err(ProfileError::NotFinite { what: format!("noise[{i}].potential'"), y: *y });
                    }
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
            // Only r' acts (rho_e r' on the momentum): r itself may grow
            // linearly, a uniform force.
            for (i, p) in self.potential.iter().enumerate() {
                if let Potential::Given([_, d]) = p {
                    quantities.push((format!("noise[{i}].potential'"), d));
                }
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
