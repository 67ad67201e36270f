//! The verified check of one x-mode on a walls grid, in `O(ny)` work and
//! memory: `V ≻ 0` and `bar V - Q ≻ 0` for the pencil of [`crate::modes`],
//! proved without forming the dense `K = M L^-1 M`.
//!
//! **Lifting.** With `K = M L^-1 M` (`L` the stiffness plus `k^2 M`,
//! symmetric positive definite and banded), `V = s (M diag(w) + K)`,
//! `Q = -(k^2/2) s sum_j [E_j, [E_j, K]]`, `E_j = diag(eta_j)`,
//! `S2 = sum_j E_j^2`, `rho = bar / k^2` and any scalar `t > 0`,
//!
//! ```text
//! (bar V - Q) / k^2 = s (rho M diag(w) + rho K + (1/2)(S2 K + K S2) - sum_j E_j K E_j)
//!   = D + sum_i g_i U_i^T L^-1 U_i,   D = s rho M diag(w),
//! (g_i, U_i) = (s/(4t), M (S2 + t + rho)), (-s/(4t), M (S2 - t + rho)), (-s, M E_j)   (j = 1..J),
//! ```
//!
//! using `rho K + (1/2)(S2 K + K S2) = ((S2 + a) K (S2 + a) - (S2 - b) K (S2 - b)) / (4t)`
//! with `a + b = 2t` and `a - b = 2 rho` (expand: the `S2 K S2` cancel, the
//! cross terms give `(a + b)/(4t) = 1/2`, the `K` terms `(a^2 - b^2)/(4t) =
//! rho`), i.e. `a = t + rho`, `b = t - rho`; `t` is a power of two near the
//! larger of `max S2` and `rho`, so no term is much larger than the sum.
//! (Without noise the single Gram `(s rho, M)` is used.) That is the Schur
//! complement of the lower block in the banded
//!
//! ```text
//! B = [[D, U_1^T, U_2^T, ...], [U_1, -L/g_1, 0, ...], [U_2, 0, -L/g_2, ...], ...],
//! ```
//!
//! and by Haynsworth's inertia additivity `inertia(B) = inertia(lower) +
//! inertia(bar V - Q)`, with `inertia(-L/g_i)` all positive for `g_i < 0` and
//! all negative for `g_i > 0` (`L ≻ 0`, proved by a verified banded Cholesky
//! of the stored `L`). So `bar V - Q ≻ 0` iff `B` has
//! exactly `n + n #{g_i < 0}` positive and `n #{g_i > 0}` negative
//! eigenvalues, proved by the verified inertia test
//! [`crate::banded::SymBanded::verified_inertia_within`]. In the same way `V ≻ 0` iff
//! `[[s M diag(w), M], [M, -s L]]` has inertia `(n + n [s < 0], n [s > 0])`.
//!
//! **`omega` eliminated exactly first.** `D` is diagonal, so by Haynsworth
//! again `inertia(B) = inertia(D) + inertia(S)` with the Schur complement
//! `S = lower - U D^-1 U^T`, `U = [U_1; U_2; ...]`. `U D^-1 U^T` couples
//! only the lifted unknowns of one node (`U_i` are diagonal), so with the
//! lifted unknowns interleaved per node `S` has the bandwidth
//! `(J + 2)(p + 1) - 1` and the work is `O(n J^3 p^2)`, linear in `ny`.
//! Each entry `(U_i / D_a) U_j` is formed with its rounding bounded: the
//! roundings of both factors, twice those of `D_a` (a quotient), two of its
//! own, and one more where it is subtracted from `L`'s diagonal. `D_a` must
//! be a normal number (its sign is then exact), and so must the quotient;
//! otherwise nothing is proved. Against keeping `omega_a` as an unknown of
//! `B` (last within its node, bandwidth `(J + 3)(p + 1) - 1`), the
//! factorisation's flops fall by `(4/5)(35/44)^2 = 0.51` for `J = 2`,
//! `p = 8`. Measured (`fluid_mode` with one banded check at `3e-7`, best of
//! 20, mode 1 of `bench/cubic-walls.json`): the check takes 5.3 ms instead
//! of 7.8 ms at ny = 1024, 11 instead of 17 ms at ny = 2048. The margins
//! proved (`walls_margins`, 32 modes, ny = 1024 and 2048): the same for most
//! modes; for `U = y^3 + y/2` (`s = +1`) six modes prove a narrower rung and
//! none a wider one; for `channel-sin-walls` (`s = -1`) seven modes prove a
//! narrower rung and six a wider one (mode 7 at ny = 1024: `9e-6` instead
//! of `3e-7`).
//!
//! **Why this lifting.** `J + 2` Grams are the fewest for this form: in the
//! basis `(1, E_1, .., E_J, S2)` its coefficient matrix has the block
//! `[[rho, 1/2], [1/2, 0]]` on `(1, S2)` and `-1` on each `E_j`, rank
//! `J + 2`. A Gram of its own for `rho K` (`(s rho, M)`, and the squares
//! `M (S2 +- t)`) would add one unknown per node; without it the checks are
//! about 1.5 times faster (1.1 to 2.1 over the modes at ny = 1024 to 4096,
//! `J = 2`, both versions timed in turn on the same modes with another job
//! running; the flops fall by `(5/6)^3`) and prove the same margins or
//! tighter ones, never looser (`walls_margins` on
//! `bench/cubic-walls.json` and `channel-sin-walls` at ny = 1024, 2048 and
//! 4096; e.g. mode 1 of the cubic profile at ny = 1024: `3e-7` instead of
//! `9e-6`). Two other liftings were tried and measured against the
//! dense eigenvalue (docs/fluids.md §6). The congruence to stream-function
//! coordinates (`psi = L^-1 M omega`), which leaves a single dense term and
//! a positive definite Schur form, squares the condition of `L`: it failed
//! at ny = 512 on margins of 1e-5 that the dense test proves at 1e-9.
//! Lifting `rho K + (1/2)(S2 K + K S2)` as one completed square cancels
//! terms of size `S2^2 / rho`. This one is limited by the componentwise
//! condition of `L` itself (a smooth vector `y` has `y^T L y` about `h^2`
//! times `y^T |L| y`, `h` the smallest node spacing), so the margin it
//! proves grows like `h^-2`: 1e-8 at ny = 96, 1e-7 at 512, 1e-5 at 4096 for
//! `s = +1`. For `s = -1` the unpivoted `L D L^T` of the indefinite `B`
//! shows growth and proves only margins of 1e-5 to 1e-2 at ny = 1024,
//! sometimes none; [`crate::modes::Mode::verify`] then falls back to the
//! dense test up to ny = 1024.
//!
//! **What is proved.** The claim is about the exact pencil built from the
//! stored `L`, the weights `m`, the weight `w` and the noise values `eta_j`
//! at the nodes: every entry of `B` is formed in floating point with its
//! rounding bounded entrywise; `rho` is rounded downwards, which only
//! weakens the claim because `V ≻ 0` is proved first; each noise field's
//! mean `mu_j` is subtracted (`[E - mu, [E - mu, K]] = [E, [E, K]]`
//! exactly, and the expansion above is an identity in `E`), its rounding
//! counted like any other. The entrywise bounds become a 2-norm radius after
//! an exact power-of-two equilibration ([`crate::banded::SymBanded::power_of_two_scaled`]).

use crate::banded::Bounded;
use crate::grid::YGrid;
use crate::modes::{Coefficients, Form};
use numerics::definite::{positive_definite, Symmetric};

/// The matrix the check factors for `noise_fields` non-constant noise
/// fields on a grid of `n` unknowns whose stiffness has bandwidth `p`:
/// `(rows, bandwidth) = (n g, g (p + 1) - 1)` with `g = J + 2` Grams per
/// node (one without noise; module docs). Each of its factorisations costs
/// about `rows (bandwidth + 1)^2` flops and stores `rows (bandwidth + 1)`
/// doubles, so a check grows like `J^3` in time and `J^2` in memory: the
/// spec layer's limits (`spec::fluid`) are computed from this size.
///
/// ```
/// use fluid::walls_check::lifted_size;
/// assert_eq!(lifted_size(1023, 8, 2), (4092, 35));
/// assert_eq!(lifted_size(1023, 8, 0), (1023, 8));
/// ```
pub fn lifted_size(n: usize, p: usize, noise_fields: usize) -> (usize, usize) {
    let grams = if noise_fields > 0 { noise_fields + 2 } else { 1 };
    (n * grams, grams * (p + 1) - 1)
}

/// `(V ≻ 0, bar V - Q ≻ 0)` for mode `k` of a walls grid, proved as the
/// module docs say; `(false, false)` when nothing could be proved.
///
/// ```
/// use fluid::{grid::{Boundary, YGrid}, modes::{Coefficients, Form, Mode}, walls_check::verify_walls, Sign};
/// // U = y^2/2 on [0, 1]: U'' = 1, w = U + 1 > 0; noise eta = y
/// let g = YGrid::new(Boundary::Walls, 0.0, 1.0, 64);
/// let y = g.nodes();
/// let coef = Coefficients { u: y.iter().map(|y| y * y / 2.0).collect(), upp: vec![1.0; g.n()], eta: vec![y.to_vec()] };
/// let form = Form { energy: 1.0, w: coef.u.iter().map(|u| u + 1.0).collect(), sign: Sign::Positive };
/// let s = Mode::new(&g, 2.0).sigma2(&form, &coef, 1e-12).unwrap().lambda_max;
/// assert_eq!(verify_walls(&g, 2.0, &form, &coef, s * (1.0 + 1e-6)), (true, true));
/// assert_eq!(verify_walls(&g, 2.0, &form, &coef, s * (1.0 - 1e-4)), (true, false));
/// ```
pub fn verify_walls(grid: &YGrid, k: f64, form: &Form, coef: &Coefficients, bar: f64) -> (bool, bool) {
    if !(bar.is_finite() && bar >= 0.0) {
        return (false, false);
    }
    let n = grid.n();
    if form.w.len() != n || coef.eta.iter().any(|e| e.len() != n) {
        return (false, false);
    }
    // node data in the grid's banded order (walls: the node order; periodic:
    // interleaved, grid docs): a permutation of the unknowns, which keeps
    // every inertia
    let m = &grid.to_banded(grid.weights());
    let w = &grid.to_banded(&form.w);
    let s = form.sign.as_f64();
    if form.energy == 0.0 {
        // V = s M diag(w) is diagonal (the sign of a product of doubles is
        // exact unless it underflows to 0, which fails the test) and Q = 0,
        // so bar V - Q ⪰ 0 for every bar >= 0 (as the dense check says).
        let definite = (0..n).all(|a| s * w[a] * m[a] > 0.0);
        return (definite, definite);
    }
    // The liftings below are for V = s (M diag(w) + K): energy 1 (the
    // pipeline builds 0 or 1).
    if form.energy != 1.0 {
        return (false, false);
    }
    let l = grid.helmholtz(k);
    if w.iter().chain(m).any(|x| !x.is_finite()) || (0..n).any(|i| !l.get(i, i).is_finite()) {
        return (false, false);
    }
    // Haynsworth's count needs the stored L ≻ 0 (module docs): proved, not
    // assumed (a banded Cholesky of bandwidth p, cheap beside the rest).
    if !positive_definite(Symmetric::Banded(&l), 0.0).proved {
        return (false, false);
    }

    // The two tests are independent: run side by side (rayon), the second
    // one's answer used only if V ≻ 0 is proved.
    let (definite, below) =
        rayon::join(|| form_definite(&l, s, (m, w)), || below_bar(grid, &l, k, s, (m, w), coef, bar));
    (definite, definite && below)
}

/// `V ≻ 0` by the lifting of the module docs: `[[s M diag(w), M], [M, -s L]]`
/// has the inertia `(n + n [s < 0], n [s > 0])`, with `omega` eliminated
/// exactly first as in [`below_bar`]. Its block `D = s M diag(w)` is
/// diagonal, so by Haynsworth the inertia is `D`'s plus that of the Schur
/// complement `-s L - M D^-1 M`, of `L`'s bandwidth `p` on the `n` nodes.
/// Factoring the whole `2n x 2n` matrix (bandwidth `2p + 1`) would take
/// about eight times the flops for the same pivots in exact arithmetic (its
/// `L D L^T` takes the `omega` pivots first, node by node).
/// Each diagonal entry `(m_a / D_a) m_a` is formed with its rounding
/// bounded as in [`below_bar`]: `D_a` a product of three doubles (two
/// roundings, counted twice in a quotient), the quotient's and the
/// product's own, and one more where it is subtracted; `D_a` and the
/// quotient must be normal numbers, or nothing is proved. `m` and `w` in
/// the banded order.
fn form_definite(l: &crate::banded::SymBanded, s: f64, (m, w): (&[f64], &[f64])) -> bool {
    let n = m.len();
    let p = l.bandwidth();
    let u = f64::EPSILON / 2.0;
    let mut sc = Bounded::new(n, p);
    let mut d_pos = 0;
    for a in 0..n {
        let Some(d) = crate::banded::product_without_early_underflow(&[s, m[a], w[a]]) else {
            return false;
        };
        if !(d.is_finite() && d.abs() >= f64::MIN_POSITIVE) {
            return false;
        }
        d_pos += usize::from(d > 0.0);
        for b in a.saturating_sub(p)..a {
            sc.set(a, b, -s * l.get(a, b), 0);
        }
        let ratio = m[a] / d;
        if (ratio != 0.0 && ratio.abs() < f64::MIN_POSITIVE) || (ratio == 0.0 && m[a] != 0.0) {
            return false;
        }
        let q = ratio * m[a];
        if !q.is_finite() {
            return false;
        }
        // the weights m are exact inputs: the quotient carries twice D's two
        // roundings and its own, the product one more
        let q_rounds = 2 * 2 + 2;
        let lv = -s * l.get(a, a);
        let scale = (lv.abs() + q.abs()) * (1.0 + 2.0 * u);
        sc.set_with_error(a, a, lv - q, scale, q_rounds + 1);
    }
    // the target (n + n [s < 0], n [s > 0]) less D's inertia (d_pos, n - d_pos)
    let target = if s > 0.0 { (n, n) } else { (2 * n, 0) };
    let (Some(tp), Some(tn)) = (target.0.checked_sub(d_pos), target.1.checked_sub(n - d_pos)) else {
        return false;
    };
    sc.inertia() == Some((tp, tn))
}

/// `rho = bar / k^2` rounded down (module docs), `0` below the normal
/// range; `None` when `k^2` or the quotient is not a finite normal number.
fn rounded_rho(bar: f64, k: f64) -> Option<f64> {
    let u = f64::EPSILON / 2.0;
    let k2 = k * k;
    if !(k2.is_finite() && k2 >= f64::MIN_POSITIVE) {
        return None;
    }
    let rho0 = bar / k2;
    if !rho0.is_finite() {
        return None;
    }
    Some(if rho0 < f64::MIN_POSITIVE { 0.0 } else { rho0 * (1.0 - 4.0 * u) })
}

/// What every node of the lifting of the module docs shares: the sign `s`,
/// `rho`, the power of two `t`, the centred noise `eta_j` and `S2`, in the
/// banded order.
struct Lifting {
    s: f64,
    rho: f64,
    t: f64,
    eta: Vec<Vec<f64>>,
    s2: Vec<f64>,
}

/// One entry of `U` at a node: `(value, scale, rounds)` with
/// `|exact - value| <= gamma_rounds scale`.
type Entry = (f64, f64, usize);

impl Lifting {
    /// The number of non-constant noise fields `J`.
    fn fields(&self) -> usize {
        self.eta.len()
    }

    /// The lower block `-L / g_c` at an entry `lab` of `L`, for Gram `c`,
    /// with its roundings.
    fn lower(&self, c: usize, lab: f64) -> (f64, usize) {
        let (s, t, rho) = (self.s, self.t, self.rho);
        if self.fields() > 0 {
            // a power of two times lab: exact unless it lands below the
            // normal range (a tiny t), where one rounding is counted
            let v = 4.0 * t * s * lab;
            let r = usize::from(lab != 0.0 && v.abs() < f64::MIN_POSITIVE);
            match c {
                0 => (-v, r),
                1 => (v, r),
                _ => (s * lab, 0),
            }
        } else {
            (-s * lab / rho, 1)
        }
    }

    /// `U`'s entries at node `a` (weight `m_a`), one per Gram:
    /// `M (S2 + t + rho)`, `M (S2 - t + rho)`, `M E_j` with noise, `M`
    /// without; `false` where one proves nothing (below the normal range,
    /// not finite, or underflowed to 0).
    fn gram_entries(&self, a: usize, m_a: f64, u_vals: &mut Vec<Entry>) -> bool {
        let (nj, eta, s2, t, rho) = (self.fields(), &self.eta, &self.s2, self.t, self.rho);
        u_vals.clear();
        if nj > 0 {
            let plus = m_a * ((s2[a] + t) + rho);
            u_vals.push((plus, plus.abs(), 2 * nj + 5));
            u_vals.push((m_a * ((s2[a] - t) + rho), plus.abs(), 2 * nj + 5));
            for e in eta {
                let v = e[a] * m_a;
                u_vals.push((v, v.abs(), 2));
            }
        } else {
            u_vals.push((m_a, m_a.abs(), 0));
        }
        if u_vals.iter().any(|(v, sc, _)| (*v != 0.0 && v.abs() < f64::MIN_POSITIVE) || !sc.is_finite()) {
            return false;
        }
        // nor one that underflowed to 0 from nonzero terms (its absolute
        // error, up to 2^-1075, is divided by D_a below, which the counted
        // roundings do not cover)
        let underflowed_to_zero = if nj > 0 {
            u_vals[0].0 == 0.0
                || (u_vals[1].0 == 0.0 && (s2[a] - t) + rho != 0.0)
                || eta.iter().zip(&u_vals[2..]).any(|(e, (v, _, _))| *v == 0.0 && e[a] != 0.0)
        } else {
            false
        };
        !underflowed_to_zero
    }

    /// Node `a`'s own block of the Schur complement, `lower(a, a) - U_c U_e / D_a`
    /// for the Grams `c >= e` (`laa` = `L_aa`, first row `first`), set in
    /// `sc` with its rounding; `false` where a quotient proves nothing.
    fn node_block(&self, sc: &mut Bounded, first: usize, d: f64, laa: f64, u_vals: &[Entry]) -> bool {
        let grams = u_vals.len();
        // node a's own block: lower(a, a) - U_c U_e / D_a. The quotient
        // carries the roundings of both factors, twice those of D_a (a
        // quotient: 1 / (1 - gamma_r) <= 1 + gamma_2r), and its own two;
        // the difference one more, relative to the sum of magnitudes.
        let u = f64::EPSILON / 2.0;
        for c in 0..grams {
            for e in 0..=c {
                let (uc, sc_c, rc) = u_vals[c];
                let (ue, sc_e, re) = u_vals[e];
                // (U_c / D_a) U_e: the quotient first, so that its size is
                // that of the entries of L (the squares U_c U_e alone would
                // underflow for noise near 2^-400); a quotient below the
                // normal range proves nothing, the last product may underflow
                let ratio = uc / d;
                if (ratio != 0.0 && ratio.abs() < f64::MIN_POSITIVE) || (ratio == 0.0 && uc != 0.0) {
                    return false;
                }
                let q = ratio * ue;
                // an upper bound on sc_c sc_e / |D_a| (two roundings)
                let q_scale = ((sc_c / d.abs()) * sc_e) * (1.0 + 4.0 * u);
                if !(q.is_finite() && q_scale.is_finite()) {
                    return false;
                }
                let q_rounds = rc + re + 2 * 2 + 2;
                if c == e {
                    let (lv, lr) = self.lower(c, laa);
                    let scale = (lv.abs() + q_scale) * (1.0 + 2.0 * u);
                    sc.set_with_error(first + c, first + e, lv - q, scale, q_rounds.max(lr) + 1);
                } else {
                    sc.set_with_error(first + c, first + e, -q, q_scale, q_rounds);
                }
            }
        }
        true
    }
}

/// `bar V - Q ≻ 0` by the lifting of the module docs (`V ≻ 0` proved apart).
/// `m` and `w` in the banded order.
fn below_bar(
    grid: &YGrid,
    l: &crate::banded::SymBanded,
    k: f64,
    s: f64,
    (m, w): (&[f64], &[f64]),
    coef: &Coefficients,
    bar: f64,
) -> bool {
    let n = grid.n();
    let p = l.bandwidth();

    // rho = bar / k^2, rounded down (module docs).
    let Some(rho) = rounded_rho(bar, k) else {
        return false;
    };

    // The noise fields that are not constant, each less its mean (its
    // rounding is counted in the entries' bounds below).
    let (eta, s2) = coef.centred_noise();
    let (eta, s2): (Vec<Vec<f64>>, Vec<f64>) = (eta.iter().map(|e| grid.to_banded(e)).collect(), grid.to_banded(&s2));
    let nj = eta.len();
    if s2.iter().any(|x| !x.is_finite()) {
        return false;
    }
    if rho == 0.0 {
        // bar V - Q ≻ 0 at bar = 0 is not attempted (the lifting divides by rho)
        return false;
    }
    // t: a power of two near the larger of max S2 and rho (exact, so 4t is
    // too): the two squares are then of the size of their difference.
    let s2max = s2.iter().fold(0.0f64, |a, x| a.max(*x));
    let t = numerics::scaling::nearest_power_of_two(s2max.max(rho));
    let lifting = Lifting { s, rho, t, eta, s2 };
    // The lifted unknowns per node: with noise y+, y-, y1..yJ; without, y0.
    // omega is eliminated exactly first (its block D is diagonal), so the
    // matrix factored is the Schur complement S = lower - U D^-1 U^T
    // (module docs), of bandwidth (J + 2)(p + 1) - 1.
    let (rows, width) = lifted_size(n, p, nj);
    let grams = rows / n;
    let idx = |a: usize, c: usize| a * grams + c;
    // U's entries at node a, Gram c: (value, scale, rounds) with
    // |exact - value| <= gamma_rounds scale (the counts of the lifting
    // above); a nonzero value below the normal range proves nothing.
    let mut u_vals: Vec<Entry> = Vec::with_capacity(grams);
    let mut sc = Bounded::new(rows, width);
    let mut d_pos = 0;
    for a in 0..n {
        // D_a = s rho m w (two roundings): normal and nonzero, so that its
        // sign is exact and its error relative
        let Some(d) = crate::banded::product_without_early_underflow(&[s * rho, m[a], w[a]]) else {
            return false;
        };
        if !(d.is_finite() && d.abs() >= f64::MIN_POSITIVE) {
            return false;
        }
        d_pos += usize::from(d > 0.0);
        if !lifting.gram_entries(a, m[a], &mut u_vals) {
            return false;
        }
        // the lower block -L / g_c at (a, b), with its roundings
        for b in a.saturating_sub(p)..a {
            let lab = l.get(a, b);
            for c in 0..grams {
                let (v, r) = lifting.lower(c, lab);
                sc.set(idx(a, c), idx(b, c), v, r);
            }
        }
        if !lifting.node_block(&mut sc, idx(a, 0), d, l.get(a, a), &u_vals) {
            return false;
        }
    }
    // the lifted matrix's inertia for bar V - Q ≻ 0, less D's (Haynsworth)
    let (neg_grams, pos_grams) = (1, if nj > 0 { 1 + nj } else { 0 });
    let target = if s > 0.0 { (n + n * pos_grams, n * neg_grams) } else { (n + n * neg_grams, n * pos_grams) };
    let (Some(tp), Some(tn)) = (target.0.checked_sub(d_pos), target.1.checked_sub(n - d_pos)) else {
        return false;
    };
    sc.inertia() == Some((tp, tn))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Boundary;
    use crate::modes::Mode;
    use nalgebra::SymmetricEigen;
    use outcome::Sign;

    /// The largest generalised eigenvalue of the dense `(Q, V)` by
    /// nalgebra's symmetric eigensolver: independent of the banded code.
    fn dense_lambda(mode: &Mode, form: &Form, coef: &Coefficients) -> f64 {
        let v = mode.form_matrix(form);
        let q = mode.generator_matrix(form, coef);
        let l = nalgebra::Cholesky::new(v).unwrap().l();
        let li = l.try_inverse().unwrap();
        let t = &li * q * li.transpose();
        SymmetricEigen::new((&t + t.transpose()) * 0.5).eigenvalues.max()
    }

    fn channel(ny: usize, shift: f64, sign: Sign) -> (YGrid, Coefficients, Form) {
        channel_on(Boundary::Walls, ny, shift, sign)
    }

    /// [`channel`]'s profile, noise and form on either boundary (the data
    /// need not be periodic: the checks are about the pencil of node values).
    fn channel_on(boundary: Boundary, ny: usize, shift: f64, sign: Sign) -> (YGrid, Coefficients, Form) {
        let g = YGrid::new(boundary, 0.0, std::f64::consts::PI, ny);
        let y = g.nodes();
        let coef = Coefficients {
            // U = y^2/2 + sin(y)/10, U'' = 1 - sin(y)/10 > 0
            u: y.iter().map(|y| 0.5 * y * y + 0.1 * y.sin()).collect(),
            upp: y.iter().map(|y| 1.0 - 0.1 * y.sin()).collect(),
            eta: vec![
                y.iter().map(|y| 0.4 * (2.0 * y).sin() + 3.0).collect(),
                y.iter().map(|y| 0.1 * y).collect(),
                vec![0.7; g.n()],
            ],
        };
        let w = coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + shift) / p).collect();
        (g, coef, Form { energy: 1.0, w, sign })
    }

    #[test]
    fn never_proves_a_bound_below_the_dense_eigenvalue_and_proves_one_above() {
        // s = +1: w = U + 2 > 0; s = -1: w = (U - 40)/U'' < 0, and
        // -(K + M w) ≻ 0 because |w| m dominates K. The eigenvalue is
        // nalgebra's dense symmetric eigensolver on the formed pencil.
        for (shift, sign) in [(2.0, Sign::Positive), (-40.0, Sign::Negative)] {
            for ny in [32, 96] {
                let (g, coef, form) = channel(ny, shift, sign);
                for k in [0.5, 1.5, 4.0] {
                    let mode = Mode::new(&g, k);
                    let lam = dense_lambda(&mode, &form, &coef);
                    assert!(lam > 0.0, "{lam}");
                    for f in [0.5, 0.999, 1.0 - 1e-5] {
                        assert_eq!(
                            verify_walls(&g, k, &form, &coef, lam * f),
                            (true, false),
                            "{sign:?} ny {ny} k {k} f {f}"
                        );
                    }
                    // the margins the analysis tries (constants::VERIFY_*)
                    let proved = [1e-8, 3e-7, 9e-6, 2.7e-4, 8.1e-3]
                        .iter()
                        .find(|e| verify_walls(&g, k, &form, &coef, lam * (1.0 + *e)) == (true, true));
                    match sign {
                        Sign::Positive => {
                            assert!(proved.is_some_and(|e| *e <= 3e-7), "{sign:?} ny {ny} k {k}: {proved:?}")
                        }
                        Sign::Negative => assert!(proved.is_some(), "{sign:?} ny {ny} k {k}"),
                    }
                }
            }
        }
    }

    #[test]
    fn random_pencils_are_never_proved_below_their_eigenvalue() {
        // Random smooth profiles, weights of either sign and one to three
        // noise fields: a bound 1e-6 below the dense eigenvalue is never
        // proved, whatever the lifting does. Both boundaries: a periodic
        // grid runs the same check on its interleaved order (grid docs).
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(13);
        for boundary in [Boundary::Walls, Boundary::Periodic] {
            let mut proved_above = 0;
            for case in 0..24 {
                let ny = [16, 32, 48][case % 3];
                let g = YGrid::new(boundary, -1.0, 1.0 + rng.random_range(0.0..2.0), ny);
                let y = g.nodes().to_vec();
                let nf = 1 + case % 3;
                let eta: Vec<Vec<f64>> = (0..nf)
                    .map(|_| {
                        let (a, b, c) =
                            (rng.random_range(-1.0..1.0), rng.random_range(-2.0..2.0), rng.random_range(-3.0..3.0));
                        y.iter().map(|y| a * (b * y).sin() + 0.3 * c * y).collect()
                    })
                    .collect();
                let sign = if case % 2 == 0 { Sign::Positive } else { Sign::Negative };
                let w: Vec<f64> = y
                    .iter()
                    .map(|y| {
                        let base = 1.0 + 0.5 * (3.0 * y).cos();
                        if sign == Sign::Positive {
                            base
                        } else {
                            -20.0 * base
                        }
                    })
                    .collect();
                let coef = Coefficients { u: vec![0.0; g.n()], upp: vec![1.0; g.n()], eta };
                let form = Form { energy: 1.0, w, sign };
                let k = rng.random_range(0.3..5.0);
                let mode = Mode::new(&g, k);
                let lam = dense_lambda(&mode, &form, &coef);
                assert_eq!(
                    verify_walls(&g, k, &form, &coef, lam * (1.0 - 1e-6) - 1e-300),
                    (true, false),
                    "{boundary:?} case {case}"
                );
                if verify_walls(&g, k, &form, &coef, lam * (1.0 + 1e-4) + 1e-300) == (true, true) {
                    proved_above += 1;
                }
            }
            // and it is useful: most bounds 1e-4 above are proved
            assert!(proved_above >= 20, "{boundary:?}: {proved_above} of 24");
        }
    }

    #[test]
    fn random_pencils_are_never_proved_below_their_dense_eigenvalue() {
        // The elimination of omega (module docs) on random profiles, noise
        // fields, wavenumbers and both signs, against nalgebra's dense
        // eigenvalue of the formed pencil: a bound 1e-6 below it must fail;
        // for s = +1 one 1e-4 above it must pass (at these sizes the check
        // proves 3e-7 or better, docs/fluids.md §2). Walls, then periodic
        // grids (their interleaved order, grid docs).
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(28);
        for (case, boundary) in (0..36).map(|c| (c, if c < 18 { Boundary::Walls } else { Boundary::Periodic })) {
            let ny = [24, 32, 48][case % 3];
            let g = YGrid::new(boundary, 0.0, std::f64::consts::PI, ny);
            let y = g.nodes();
            let a1: f64 = rng.random_range(-0.5..0.5);
            let fields = 1 + case % 3;
            let eta: Vec<Vec<f64>> = (0..fields)
                .map(|_| {
                    let (c0, c1, c2, f) = (
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(0.5..3.0),
                    );
                    y.iter().map(|y| c0 + c1 * y + c2 * (f * y).sin()).collect()
                })
                .collect();
            let coef = Coefficients {
                u: y.iter().map(|y| 0.5 * y * y + a1 * y.sin()).collect(),
                upp: y.iter().map(|y| 1.0 - a1 * y.sin()).collect(),
                eta,
            };
            let sign = if case % 2 == 0 { Sign::Positive } else { Sign::Negative };
            let shift = match sign {
                Sign::Positive => rng.random_range(1.0..4.0),
                Sign::Negative => -rng.random_range(40.0..60.0),
            };
            let w = coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + shift) / p).collect();
            let form = Form { energy: 1.0, w, sign };
            let k = rng.random_range(0.3..5.0);
            let mode = Mode::new(&g, k);
            let lam = dense_lambda(&mode, &form, &coef);
            assert!(lam > 0.0, "case {case}: {lam}");
            let below = verify_walls(&g, k, &form, &coef, lam * (1.0 - 1e-6));
            assert!(!below.1, "case {case} ({boundary:?}, {sign:?}, ny {ny}, k {k}): proved below the eigenvalue");
            if sign == Sign::Positive {
                assert_eq!(verify_walls(&g, k, &form, &coef, lam * (1.0 + 1e-4)), (true, true), "case {case}");
            }
        }
    }

    #[test]
    fn a_quotient_that_underflows_to_zero_proves_nothing() {
        // Noise near 1e-302 and a bound near 1e30 (rho = bar / k^2 huge)
        // make U_c / D_a underflow to exactly 0 while U_c is not, and the
        // entry's bound would then miss the true (U_c / D_a) U_e. The field
        // alternates in sign from node to node, so its centred values stay
        // near its size and every U_c = eta m is a normal number. Such a
        // check proves nothing; with the noise at ordinary size the same
        // bound is proved.
        let (g, coef, form) = channel(16, 2.0, Sign::Positive);
        let field = |f: f64| -> Coefficients {
            let eta = vec![(0..g.n()).map(|a| if a % 2 == 0 { f } else { -f }).collect()];
            Coefficients { eta, ..coef.clone() }
        };
        assert_eq!(verify_walls(&g, 1.5, &form, &field(1e-302), 1e30), (true, false));
        assert_eq!(verify_walls(&g, 1.5, &form, &field(1.0), 1e30), (true, true));
    }

    #[test]
    fn noise_scaled_towards_underflow_is_never_proved_below_its_eigenvalue() {
        // Noise times 2^-e multiplies Q, so the eigenvalue, by exactly
        // 2^-2e: towards the bottom of the double range a bound just below
        // the scaled eigenvalue must still fail (one above may pass or
        // fail). This does not reach the subnormal lifted entries 4 t L
        // (counted as one rounding): instrumented for e = 500 to 515, rho
        // leaves the normal range (no claim) before any 4 t L_ab does.
        let (g, coef, form) = channel(32, 2.0, Sign::Positive);
        let mode = Mode::new(&g, 1.5);
        let lam = dense_lambda(&mode, &form, &coef);
        for e in [400, 480, 500, 505, 508, 510, 511, 515] {
            let f = numerics::scaling::pow2(-e);
            let small = Coefficients {
                eta: coef.eta.iter().map(|x| x.iter().map(|v| v * f).collect()).collect(),
                ..coef.clone()
            };
            let scaled = lam * f * f;
            let below = verify_walls(&g, 1.5, &form, &small, scaled * (1.0 - 1e-6));
            assert!(!below.1, "2^-{e}: proved below the eigenvalue");
            let above = verify_walls(&g, 1.5, &form, &small, scaled * (1.0 + 1e-4));
            if e <= 480 {
                assert_eq!(above, (true, true), "2^-{e}");
            }
        }
    }

    #[test]
    fn random_noise_rescalings_move_the_bound_with_the_eigenvalue_on_both_boundaries() {
        // Noise times f (not a power of two, so every entry rounds anew)
        // multiplies Q, so the eigenvalue, by f^2: the dense eigenvalue of the
        // rescaled pencil (nalgebra, independent of the banded code) must be
        // f^2 times the first one, a bound 1e-6 below it must fail and the
        // margin ladder must prove the same rung as without rescaling.
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(2811);
        // the analysis's ladder (constants::VERIFY_*)
        let ladder: Vec<f64> = (0..crate::constants::VERIFY_ATTEMPTS).map(crate::constants::ladder_margin).collect();
        for boundary in [Boundary::Walls, Boundary::Periodic] {
            // s = +1 and s = -1 (the constant third noise field drops out of Q)
            for (shift, sign) in [(2.0, Sign::Positive), (-40.0, Sign::Negative)] {
                let (g, coef, form) = channel_on(boundary, 48, shift, sign);
                let k = 1.5;
                let mode = Mode::new(&g, k);
                let lam = dense_lambda(&mode, &form, &coef);
                let rung = |c: &Coefficients, lam: f64| {
                    ladder.iter().position(|e| verify_walls(&g, k, &form, c, lam * (1.0 + e)) == (true, true))
                };
                let base = rung(&coef, lam);
                assert!(base.is_some(), "{boundary:?} {sign:?}");
                for _ in 0..6 {
                    let f = 10f64.powf(rng.random_range(-3.0..3.0));
                    let scaled = Coefficients {
                        eta: coef.eta.iter().map(|x| x.iter().map(|v| v * f).collect()).collect(),
                        ..coef.clone()
                    };
                    let lam_f = dense_lambda(&mode, &form, &scaled);
                    assert!((lam_f / (lam * f * f) - 1.0).abs() < 1e-9, "{boundary:?} {sign:?} f {f}");
                    let below = verify_walls(&g, k, &form, &scaled, lam_f * (1.0 - 1e-6));
                    assert_eq!(below, (true, false), "{boundary:?} {sign:?} f {f}");
                    assert_eq!(rung(&scaled, lam_f), base, "{boundary:?} {sign:?} f {f}");
                }
            }
        }
    }

    #[test]
    fn an_entry_whose_product_underflows_midway_proves_nothing_false() {
        // On an interval of length 1e-14 (weights m near 1e-15) with w near
        // 1e277 and Sigma^2 near 3e-307, rho m falls below the normal range
        // and rounds by up to 4.6%, which the factor w carries into the
        // entry `s rho m w`; unguarded, that proves bounds 0.3% below the
        // eigenvalue. The truth is decided here in exact
        // rationals on the stored L, m, w and eta (k = 1, energy 1, s = +1).
        let lg = 1e-14;
        let g = YGrid::new(Boundary::Walls, 0.0, lg, 16);
        let y = g.nodes().to_vec();
        let n = g.n();
        let eta: Vec<f64> = y.iter().map(|v| (2.0 * std::f64::consts::PI * v / lg).sin() + 0.3 * (v / lg)).collect();
        let w: Vec<f64> = y.iter().map(|v| 1e277 * (1.0 + 0.5 * (3.0 * v / lg).cos())).collect();
        let coef = Coefficients { u: vec![0.0; n], upp: vec![1.0; n], eta: vec![eta.clone()] };
        let form = Form { energy: 1.0, w: w.clone(), sign: Sign::Positive };
        let q = |x: f64| exact::Rational::from_float(x).unwrap();
        let l = g.helmholtz(1.0);
        let p = l.bandwidth();
        let l_exact = exact::Matrix::from_fn(n, n, |a, b| if a.abs_diff(b) <= p { q(l.get(a, b)) } else { q(0.0) });
        let diag = |d: &[f64]| exact::Matrix::from_fn(n, n, |a, b| if a == b { q(d[a]) } else { q(0.0) });
        let (mm, ww, ee) = (diag(g.weights()), diag(&w), diag(&eta));
        let kk = mm.mul(&l_exact.inverse().unwrap()).mul(&mm);
        let v = mm.mul(&ww).add(&kk);
        // Q = -(k^2/2) [E, [E, K]] = -(1/2)(E^2 K - 2 E K E + K E^2)
        let ek = ee.mul(&kk);
        let comm2 = ee.mul(&ek).sub(&ek.mul(&ee).scale(&q(2.0))).add(&kk.mul(&ee).mul(&ee));
        let qq = comm2.scale(&q(-0.5));
        let definite = |bar: f64| v.scale(&q(bar)).sub(&qq).inertia().positive == n;
        // lambda_max(Q, V) by mpmath (60 digits) on the same stored data,
        // 3.0692868451655490e-307; the exact inertias pin it within 0.3%.
        let lam = 3.069286845165549e-307;
        assert!(definite(lam * 1.001));
        // 0.3% below: not definite, and not proved
        assert!(!definite(lam * 0.997));
        assert!(!verify_walls(&g, 1.0, &form, &coef, lam * 0.997).1, "proved a bound below the eigenvalue");
    }

    #[test]
    fn many_noise_fields_on_a_coarse_walls_grid_use_the_dense_check_alone() {
        // 20 fields at ny = 256 (255 unknowns): the banded check would
        // factor 255 * 22 rows of bandwidth 197, work 255 * 22 * 198^2 =
        // 2.2e8 > 1e8 and 13 n^3 (crate::modes::dense_check_preferred), so
        // the mode goes to the dense check alone; with 2 fields it keeps
        // the banded one. The bound proved is the narrowest rung's, above
        // nalgebra's dense eigenvalue of the formed pencil.
        let g = YGrid::new(Boundary::Walls, 0.0, std::f64::consts::PI, 256);
        let y = g.nodes();
        let many: Vec<Vec<f64>> =
            (1..=20).map(|j| y.iter().map(|y| 0.1 * (j as f64 * y + j as f64 / 7.0).sin()).collect()).collect();
        let coef = Coefficients {
            u: y.iter().map(|y| 0.5 * y * y + 0.1 * y.sin()).collect(),
            upp: y.iter().map(|y| 1.0 - 0.1 * y.sin()).collect(),
            eta: many.clone(),
        };
        let form = Form {
            energy: 1.0,
            w: coef.u.iter().zip(&coef.upp).map(|(u, p)| (u + 2.0) / p).collect(),
            sign: Sign::Positive,
        };
        let few = Coefficients { eta: many[..2].to_vec(), ..coef.clone() };
        let mode = Mode::new(&g, 1.5);
        assert!(mode.prefers_dense(&coef));
        assert!(!mode.prefers_dense(&few));
        let s = mode.sigma2(&form, &coef, 1e-12).unwrap();
        let exact = dense_lambda(&mode, &form, &coef);
        assert!((s.lambda_max - exact).abs() <= 1e-9 * exact, "{} {exact}", s.lambda_max);
        let (bound, definite) = crate::analysis::verified_mode_bound(&mode, &form, &coef, s.lambda_max, &s.ritz);
        let bound = bound.expect("the dense check proves the narrowest rung");
        assert!(definite && bound >= exact && bound <= exact * (1.0 + 1e-7), "{bound} {exact}");
        for bar in [exact * (1.0 - 1e-6), bound] {
            assert_eq!(mode.verify(&form, &coef, bar), mode.verify_dense(&form, &coef, bar), "{bar}");
        }
        assert_eq!(mode.verify(&form, &coef, exact * (1.0 - 1e-6)), (true, false));
    }

    #[test]
    fn no_dense_fallback_on_periodic_grids() {
        // On a periodic grid the stiffness has the constants in its
        // kernel, so at small k L the computed K is far from M L^-1 M of
        // the stored L, and the dense check (a claim about the computed
        // matrices) proves bounds below the stored pencil's eigenvalue
        // (ny = 16, k L = 3.7e-6: a bound 0.12% below the eigenvalue that
        // mpmath computes to 60 digits).
        // Mode::verify therefore answers with the banded check alone on
        // periodic grids: here, where the dense check proves bounds the
        // banded one does not, the two answers must still be the banded ones.
        let len = 5.278;
        let g = YGrid::new(Boundary::Periodic, 0.0, len, 16);
        let n = g.n();
        let k = 7.03e-7;
        let y = g.nodes();
        let two_pi = 2.0 * std::f64::consts::PI;
        let eta: Vec<f64> = y.iter().map(|v| 0.3 * (two_pi * v / len).sin()).collect();
        let w: Vec<f64> = y.iter().map(|v| 1.0 + 0.5 * (two_pi * v / len).cos()).collect();
        let coef = Coefficients { u: vec![0.0; n], upp: vec![1.0; n], eta: vec![eta] };
        let form = Form { energy: 1.0, w, sign: Sign::Positive };
        let mode = Mode::new(&g, k);
        assert!(!mode.dense_fallback());
        let lam = mode.sigma2(&form, &coef, 1e-12).unwrap().lambda_max;
        let mut dense_only = 0;
        for e in [-1e-2, -1e-3, -1e-4, 0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0] {
            let bar = lam * (1.0 + e);
            let banded = verify_walls(&g, k, &form, &coef, bar);
            assert_eq!(mode.verify(&form, &coef, bar), banded, "e = {e}");
            if mode.verify_dense(&form, &coef, bar).1 && !banded.1 {
                dense_only += 1;
            }
        }
        // the fallback would have changed answers here
        assert!(dense_only > 0);
        // and on a walls grid of the same size it is taken
        assert!(Mode::new(&YGrid::new(Boundary::Walls, 0.0, len, 16), k).dense_fallback());
    }

    #[test]
    fn a_form_with_an_energy_other_than_one_is_not_claimed() {
        // The liftings are for V = s (M diag(w) + K): another energy
        // coefficient proves nothing (the pipeline builds 0 or 1).
        let (g, coef, mut form) = channel(32, 2.0, Sign::Positive);
        let lam = dense_lambda(&Mode::new(&g, 1.0), &form, &coef);
        assert_eq!(verify_walls(&g, 1.0, &form, &coef, lam * 2.0), (true, true));
        form.energy = 2.0;
        assert_eq!(verify_walls(&g, 1.0, &form, &coef, lam * 2.0), (false, false));
    }

    #[test]
    fn an_indefinite_form_is_refused() {
        // w changes sign: V is indefinite for some mode; never (true, _).
        let (g, coef, mut form) = channel(64, 2.0, Sign::Positive);
        for (a, y) in g.nodes().iter().enumerate() {
            if *y > 2.0 {
                form.w[a] = -5.0;
            }
        }
        assert_eq!(verify_walls(&g, 1.0, &form, &coef, 1e6), (false, false));
        form.sign = Sign::Negative;
        assert_eq!(verify_walls(&g, 1.0, &form, &coef, 1e6), (false, false));
    }

    #[test]
    fn the_form_test_agrees_with_the_dense_eigenvalues_of_v() {
        // Weights of both signs, so that V = s (M diag(w) + K) is definite
        // in some cases and not in others: V ≻ 0 is claimed only where
        // nalgebra's dense eigensolver finds lambda_min(V) > 0 (sound), and
        // claimed wherever lambda_min exceeds 1e-8 of ||V|| (sharp), on
        // both boundaries and both signs; both outcomes occur.
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(29);
        let (mut claimed, mut refused) = (0, 0);
        for boundary in [Boundary::Walls, Boundary::Periodic] {
            for case in 0..40 {
                let ny = [24, 40][case % 2];
                let (g, coef, mut form) = channel_on(boundary, ny, 2.0, Sign::Positive);
                let sign = if case % 4 < 2 { Sign::Positive } else { Sign::Negative };
                form.sign = sign;
                let (amp, k) = (rng.random_range(0.0..0.5), rng.random_range(0.3..3.0));
                // s = -1 needs w below -(M^-1 K)'s largest eigenvalue, at
                // most 1/k^2 (L ⪰ k^2 M): shifts around it
                let shift = match sign {
                    Sign::Positive => rng.random_range(-0.3..0.6),
                    Sign::Negative => rng.random_range(0.3..1.5) / (k * k),
                };
                let s = sign.as_f64();
                for (a, y) in g.nodes().iter().enumerate() {
                    form.w[a] = s * (shift + amp * (3.0 * y).sin());
                }
                let v = Mode::new(&g, k).form_matrix(&form);
                let norm = v.iter().fold(0.0f64, |m, x| m.max(x.abs())) * v.nrows() as f64;
                let lmin = SymmetricEigen::new(v).eigenvalues.min();
                let definite = verify_walls(&g, k, &form, &coef, 1e6).0;
                if definite {
                    assert!(lmin > 0.0, "{boundary:?} case {case}: claimed with lambda_min {lmin:e}");
                    claimed += 1;
                } else {
                    assert!(lmin <= 1e-8 * norm, "{boundary:?} case {case}: refused with lambda_min {lmin:e}");
                    refused += 1;
                }
            }
        }
        assert!(claimed >= 10 && refused >= 10, "{claimed} claimed, {refused} refused");
    }

    #[test]
    fn agrees_with_the_dense_check() {
        // The dense check of modes.rs (generator crate's verified Cholesky
        // on the formed K) and this one on a ladder of bounds around the
        // eigenvalue: they may differ only within the rounding margin.
        let (g, coef, form) = channel(48, 2.0, Sign::Positive);
        let mode = Mode::new(&g, 1.0);
        let lam = dense_lambda(&mode, &form, &coef);
        for f in [0.5, 0.99, 0.9999, 1.001, 1.01, 2.0] {
            let banded = verify_walls(&g, 1.0, &form, &coef, lam * f);
            let dense = mode.verify_dense(&form, &coef, lam * f);
            assert_eq!(banded, dense, "factor {f}");
        }
    }
}
