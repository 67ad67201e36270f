//! The central-cut ellipsoid method, shared by the search for a definite
//! choice (maximising a concave function) and the minimisation of `Sigma^2`
//! (a quasi-convex function, in the `generator` crate).

use nalgebra::{DMatrix, DVector};

/// An ellipsoid `{x : (x - c)^T E^{-1} (x - c) <= 1}` that shrinks by
/// central cuts; in one dimension it is an interval that halves.
#[derive(Clone, Debug)]
pub struct Ellipsoid {
    centre: Vec<f64>,
    shape: DMatrix<f64>,
}

impl Ellipsoid {
    /// The ball of the given radius around `centre`, enclosed (the ellipsoid
    /// starts with semi-axes `radius * sqrt(d)`).
    pub fn ball(centre: &[f64], radius: f64) -> Self {
        let d = centre.len();
        Ellipsoid { centre: centre.to_vec(), shape: DMatrix::identity(d, d) * (radius * radius * d as f64) }
    }

    /// The current centre.
    pub fn centre(&self) -> &[f64] {
        &self.centre
    }

    /// Keep the half `{x : g . (x - c) >= 0}` and replace the ellipsoid by
    /// the smallest one containing it. Returns `false` (and leaves the
    /// ellipsoid unchanged) when `g` is zero or not finite, or the cut is
    /// numerically degenerate: the method has converged.
    ///
    /// ```
    /// use casimir::Ellipsoid;
    /// // Find the maximum of -(x - 0.3)^2 on [-1, 1] by cuts along its gradient.
    /// let mut e = Ellipsoid::ball(&[0.0], 1.0);
    /// for _ in 0..60 {
    ///     let x = e.centre()[0];
    ///     if !e.cut(&[-2.0 * (x - 0.3)]) { break; }
    /// }
    /// assert!((e.centre()[0] - 0.3).abs() < 1e-12);
    /// ```
    pub fn cut(&mut self, g: &[f64]) -> bool {
        let d = self.centre.len();
        let gn = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        if d == 0 || gn == 0.0 || !gn.is_finite() {
            return false;
        }
        let a = DVector::from_iterator(d, g.iter().map(|x| -x / gn));
        let ea = &self.shape * &a;
        let aea = a.dot(&ea);
        if aea <= 0.0 || !aea.is_finite() {
            return false;
        }
        let at = ea / aea.sqrt();
        if d == 1 {
            self.centre[0] -= at[0] / 2.0;
            self.shape *= 0.25;
        } else {
            let nf = d as f64;
            for i in 0..d {
                self.centre[i] -= at[i] / (nf + 1.0);
            }
            self.shape = (&self.shape - (&at * at.transpose()) * (2.0 / (nf + 1.0))) * (nf * nf / (nf * nf - 1.0));
        }
        true
    }

    /// The largest semi-axis bound `sqrt(max_i E_ii)`.
    pub fn size(&self) -> f64 {
        self.shape.diagonal().iter().fold(0.0f64, |m, &x| m.max(x)).sqrt()
    }
}
