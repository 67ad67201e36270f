//! Fixed-size kernels of the Lie–Heun step for `so3` and `se3` with a
//! quadratic Hamiltonian: the same arithmetic as [`crate::Stepper`], on
//! arrays, with the coadjoint action written out, so that the compiler can
//! keep everything in registers (about twice the throughput of the generic
//! stepper, which the ensemble benchmark needs).

use crate::model::{cross, rodrigues, rotate_back};

/// Which closed-form group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fixed {
    So3,
    Se3,
}

/// A kernel for dimension `N` (3 for `so3`, 6 for `se3`).
#[derive(Clone, Debug)]
pub(crate) struct Kernel<const N: usize> {
    pub(crate) group: Fixed,
    pub(crate) h: [[f64; N]; N],
    /// `Some(diag H)` when `H` is diagonal (principal axes), which saves
    /// most of the multiplications of the gradient.
    pub(crate) diagonal: Option<[f64; N]>,
    pub(crate) b: [f64; N],
    pub(crate) noise: Vec<[f64; N]>,
}

impl<const N: usize> Kernel<N> {
    #[inline(always)]
    fn gradient(&self, mu: &[f64; N]) -> [f64; N] {
        let mut g = self.b;
        match &self.diagonal {
            Some(d) => {
                for i in 0..N {
                    g[i] += d[i] * mu[i];
                }
            }
            None => {
                for i in 0..N {
                    for j in 0..N {
                        g[i] += self.h[i][j] * mu[j];
                    }
                }
            }
        }
        g
    }

    /// `ad*_xi mu`: `mu x xi` for so3; `(Pi x xi + Gamma x u, Gamma x xi)` for se3.
    #[inline(always)]
    fn coad(&self, xi: &[f64; N], mu: &[f64; N]) -> [f64; N] {
        let mut out = [0.0; N];
        match self.group {
            Fixed::So3 => out[..3].copy_from_slice(&cross(&mu[..3], &xi[..3])),
            Fixed::Se3 => {
                let a = cross(&mu[..3], &xi[..3]);
                let b = cross(&mu[3..6], &xi[3..6]);
                let c = cross(&mu[3..6], &xi[..3]);
                out[..3].copy_from_slice(&[a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
                out[3..6].copy_from_slice(&c);
            }
        }
        out
    }

    #[inline(always)]
    fn exp_coad(&self, xi: &[f64; N], mu: &[f64; N]) -> [f64; N] {
        let mut out = [0.0; N];
        let w = &xi[..3];
        let (a, b, c) = rodrigues(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        match self.group {
            Fixed::So3 => out[..3].copy_from_slice(&rotate_back(w, &mu[..3], a, b)),
            Fixed::Se3 => {
                let u = &xi[3..6];
                let wu = cross(w, u);
                let wwu = cross(w, &wu);
                let t = [u[0] + b * wu[0] + c * wwu[0], u[1] + b * wu[1] + c * wwu[1], u[2] + b * wu[2] + c * wwu[2]];
                let tg = cross(&t, &mu[3..6]);
                let shifted = [mu[0] - tg[0], mu[1] - tg[1], mu[2] - tg[2]];
                out[..3].copy_from_slice(&rotate_back(w, &shifted, a, b));
                out[3..6].copy_from_slice(&rotate_back(w, &mu[3..6], a, b));
            }
        }
        out
    }

    /// One Lie–Heun step (see [`crate::Stepper::step`]).
    #[inline(always)]
    pub(crate) fn step(&self, mu: &mut [f64; N], dt: f64, dw: &[f64]) {
        let mut noise = [0.0; N];
        for (sigma, w) in self.noise.iter().zip(dw) {
            for i in 0..N {
                noise[i] += sigma[i] * w;
            }
        }
        let g = self.gradient(mu);
        let mut xi = [0.0; N];
        for i in 0..N {
            xi[i] = g[i] * dt + noise[i];
        }
        let f = self.coad(&xi, mu);
        let mut stage = *mu;
        for i in 0..N {
            stage[i] += f[i];
        }
        let g2 = self.gradient(&stage);
        for i in 0..N {
            xi[i] = 0.5 * (g[i] + g2[i]) * dt + noise[i];
        }
        *mu = self.exp_coad(&xi, mu);
    }
}
