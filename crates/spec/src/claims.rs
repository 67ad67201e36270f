//! The independent checker: verify a certificate's claims exactly, from the
//! embedded spec and the recorded Casimir choice, along a code path of its
//! own.
//!
//! Nothing here calls the pipeline (`generator::analyse`, the search, the
//! optimisation, `generator_form`): `P`, `A`, `B_i` and `Q` are rebuilt from
//! the polynomials and the structure constants with their textbook formulas,
//!
//! ```text
//! P = D^2h + sum_j lambda_j D^2K_j + G M G^T,      G = [DK_j(mu_e)],
//! A_bj = sum_{a,k} c^k_ab (D^2h_aj mu_k + delta_kj ∂_a h),   (B_i)_bk = sum_a c^k_ab sigma_i^a,
//! Q = P A~ + A~^T P + sum_i B_i^T P B_i,            A~ = A + 1/2 sum_i B_i^2,
//! ```
//!
//! and the claims are decided in exact rational arithmetic:
//!
//! * `stable`: the first variation `Dh + sum lambda_j DK_j = 0` at `mu_e`;
//!   `sP ≻ 0` (LDLᵀ); the drift part `P A + A^T P = 0` (the linear flow
//!   conserves `P`: formal stability); `S sP - sQ ⪰ 0` for the certified
//!   rational `S = sigma2_exact` (exact semidefiniteness), and not for
//!   `(1 - 1e-9) S` (tightness, also exact);
//!   the stored `P`, `Q` equal the rebuilt ones; every stored generalized
//!   eigenvalue of `(Q, P)` to `1e-9` of the largest (exact inertia counts);
//!   the certified lower bound on the `Sigma^2` of every choice with `P`
//!   definite of the certificate's sign, from its witness in `ker G^T` (a
//!   vector, or a matrix when the multipliers are free);
//! * `not_an_equilibrium`: `ad*_{Dh(mu_e)} mu_e` recomputed, nonzero, equal to
//!   the stored residual;
//! * `noise_incompatible`: the residuals `ad*_{sigma_i} mu_e` recomputed, one of
//!   them nonzero, equal to the stored ones, and each stored isotropy vector
//!   annihilates `mu_e`;
//! * `linearly_unstable`: the stored eigenpair satisfies `|A v - l v| <= 1e-8 |A|`
//!   for the rebuilt `A`, with `Re l > 0`.

use crate::parse::Spec;
use exact::{parse_certificate_rational, parse_number, Matrix, Poly, Rational};
use num_traits::Zero;
use outcome::{Sign, VerificationLevel};
use serde_json::Value;

/// A failed claim: the JSON path and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClaimFailure {
    /// Path of the field the claim is about.
    pub path: String,
    /// What does not hold.
    pub message: String,
}

type Claim<T> = Result<T, ClaimFailure>;

fn failure(path: &str, message: impl Into<String>) -> ClaimFailure {
    ClaimFailure { path: path.to_string(), message: message.into() }
}

fn get<'a>(cert: &'a Value, path: &[&str]) -> Claim<&'a Value> {
    let mut cur = cert;
    let mut p = String::from("$");
    for k in path {
        p.push('.');
        p.push_str(k);
        cur = cur.get(*k).ok_or_else(|| failure(&p, "missing"))?;
    }
    Ok(cur)
}

/// A rational written by the engine (`p/q` integers, any size up to
/// `exact::MAX_CERTIFICATE_DIGITS` digits): exact arithmetic produces entries
/// such as `1/10^600` that no double holds, and they must re-check.
fn rational(v: &Value, path: &str) -> Claim<Rational> {
    let text = match v {
        Value::String(s) => s.clone(),
        Value::Number(n) => n.to_string(),
        _ => return Err(failure(path, "expected a rational")),
    };
    parse_certificate_rational(&text).or_else(|_| parse_number(&text)).map_err(|e| failure(path, e.to_string()))
}

fn rational_vector(v: &Value, path: &str) -> Claim<Vec<Rational>> {
    v.as_array()
        .ok_or_else(|| failure(path, "expected an array"))?
        .iter()
        .enumerate()
        .map(|(i, x)| rational(x, &format!("{path}[{i}]")))
        .collect()
}

fn rational_matrix(v: &Value, path: &str) -> Claim<Matrix> {
    let rows: Vec<Vec<Rational>> = v
        .as_array()
        .ok_or_else(|| failure(path, "expected a matrix"))?
        .iter()
        .enumerate()
        .map(|(i, r)| rational_vector(r, &format!("{path}[{i}]")))
        .collect::<Claim<_>>()?;
    let cols = rows.first().map_or(0, Vec::len);
    if rows.iter().any(|r| r.len() != cols) {
        return Err(failure(path, "ragged matrix"));
    }
    Ok(Matrix::from_rows(&rows))
}

/// The rebuilt linearisation and second-variation ingredients.
struct Rebuilt {
    n: usize,
    gradient_h: Vec<Rational>,
    hessian_h: Matrix,
    a: Matrix,
    b: Vec<Matrix>,
}

fn rebuild(spec: &Spec) -> Rebuilt {
    let sys = &spec.system;
    let alg = sys.algebra();
    let n = alg.dim();
    let mu = sys.equilibrium();
    let gradient_h = sys.hamiltonian().gradient_at(mu);
    let hessian_h = Matrix::from_rows(&sys.hamiltonian().hessian_at(mu));
    // A_bj = sum_{a,k} c^k_ab (H_aj mu_k) + sum_a c^j_ab g_a
    let mut a = Matrix::zeros(n, n);
    for aa in 0..n {
        for bb in 0..n {
            for (k, c) in alg.bracket_of_basis(aa, bb) {
                if !mu[*k].is_zero() {
                    for j in 0..n {
                        if !hessian_h[(aa, j)].is_zero() {
                            let v = c * &hessian_h[(aa, j)] * &mu[*k];
                            a[(bb, j)] += v;
                        }
                    }
                }
                if !gradient_h[aa].is_zero() {
                    let v = c * &gradient_h[aa];
                    a[(bb, *k)] += v;
                }
            }
        }
    }
    let b = sys
        .noise()
        .iter()
        .map(|sigma| {
            let mut m = Matrix::zeros(n, n);
            for aa in 0..n {
                if sigma[aa].is_zero() {
                    continue;
                }
                for bb in 0..n {
                    for (k, c) in alg.bracket_of_basis(aa, bb) {
                        let v = c * &sigma[aa];
                        m[(bb, *k)] += v;
                    }
                }
            }
            m
        })
        .collect();
    Rebuilt { n, gradient_h, hessian_h, a, b }
}

fn conserved(spec: &Spec) -> Vec<&Poly> {
    spec.system.casimirs().iter().chain(spec.system.first_integrals().iter()).collect()
}

/// `ad*_{xi} mu` with explicit loops: `(ad*_xi mu)_b = sum c^k_ab xi^a mu_k`.
fn coadjoint(spec: &Spec, xi: &[Rational], mu: &[Rational]) -> Vec<Rational> {
    let alg = spec.system.algebra();
    let n = alg.dim();
    let mut out = vec![Rational::zero(); n];
    for a in 0..n {
        if xi[a].is_zero() {
            continue;
        }
        for b in 0..n {
            for (k, c) in alg.bracket_of_basis(a, b) {
                if !mu[*k].is_zero() {
                    out[b] += c * &xi[a] * &mu[*k];
                }
            }
        }
    }
    out
}

/// Verify the claims of a certificate against its (already parsed) spec.
/// Returns the verification level actually established.
pub fn verify_claims(spec: &Spec, cert: &Value) -> Claim<VerificationLevel> {
    let verdict = get(cert, &["verdict"])?.as_str().ok_or_else(|| failure("$.verdict", "expected a string"))?;
    let level = get(cert, &["level"])?.as_str().ok_or_else(|| failure("$.level", "expected a string"))?;
    let established = match verdict {
        "stable" => verify_stable(spec, cert, level)?,
        "not_an_equilibrium" => verify_not_equilibrium(spec, cert)?,
        "noise_incompatible" => verify_noise_incompatible(spec, cert)?,
        "linearly_unstable" => verify_unstable(spec, cert)?,
        "inconclusive" => VerificationLevel::Numerical,
        other => return Err(failure("$.verdict", format!("unknown verdict '{other}'"))),
    };
    if level == VerificationLevel::Exact.as_str() && established != VerificationLevel::Exact {
        return Err(failure("$.level", format!("claims 'exact' but only '{established}' could be established")));
    }
    Ok(established)
}

fn verify_stable(spec: &Spec, cert: &Value, level: &str) -> Claim<VerificationLevel> {
    let r = rebuild(spec);
    let n = r.n;
    let mu = spec.system.equilibrium();
    let ks = conserved(spec);
    let choice = get(cert, &["casimir_choice"])?;
    let Some(sign) = choice.get("sign").and_then(Value::as_i64).and_then(Sign::from_i64) else {
        return Err(failure("$.casimir_choice.sign", "expected 1 or -1"));
    };
    let lambda = rational_vector(get(choice, &["multipliers"])?, "$.casimir_choice.multipliers")?;
    if lambda.len() != ks.len() {
        return Err(failure(
            "$.casimir_choice.multipliers",
            format!("{} multipliers for {} conserved quantities", lambda.len(), ks.len()),
        ));
    }
    let m = rational_matrix(get(choice, &["M"])?, "$.casimir_choice.M")?;
    if m.nrows() != ks.len() || m.ncols() != ks.len() || !m.is_symmetric() {
        return Err(failure("$.casimir_choice.M", "expected a symmetric matrix, one row per conserved quantity"));
    }
    // First variation.
    let grads: Vec<Vec<Rational>> = ks.iter().map(|k| k.gradient_at(mu)).collect();
    let mut first = r.gradient_h.clone();
    for (l, g) in lambda.iter().zip(&grads) {
        for i in 0..n {
            first[i] += l * &g[i];
        }
    }
    if first.iter().any(|x| !x.is_zero()) {
        return Err(failure(
            "$.casimir_choice.multipliers",
            "the first variation Dh + sum lambda_j DK_j does not vanish at mu_e",
        ));
    }
    // P.
    let mut p = r.hessian_h.clone();
    for (l, k) in lambda.iter().zip(&ks) {
        p.add_scaled_assign(l, &Matrix::from_rows(&k.hessian_at(mu)));
    }
    let g = Matrix::from_columns(n, &grads);
    p = p.add(&g.mul(&m).mul(&g.transpose()));
    if !p.is_definite_with_sign(sign) {
        return Err(failure("$.casimir_choice", "the second variation P is not definite with the recorded sign"));
    }
    if rational_matrix(get(cert, &["P"])?, "$.P")? != p {
        return Err(failure("$.P", "differs from the P rebuilt from the spec and the Casimir choice"));
    }
    // Q = P A~ + A~^T P + sum B^T P B.
    let half = Rational::new_small(1, 2);
    let mut a_tilde = r.a.clone();
    for b in &r.b {
        a_tilde.add_scaled_assign(&half, &b.mul(b));
    }
    let form_of = |p: &Matrix| {
        let pa = p.mul(&a_tilde);
        let mut q = pa.add(&pa.transpose());
        for b in &r.b {
            q = q.add(&b.transpose().mul(p).mul(b));
        }
        q
    };
    let q = form_of(&p);
    if rational_matrix(get(cert, &["Q"])?, "$.Q")? != q {
        return Err(failure("$.Q", "differs from the Q rebuilt from the spec and the Casimir choice"));
    }
    let drift = p.mul(&r.a);
    if !drift.add(&drift.transpose()).is_zero() {
        return Err(failure("$.residuals.drift", "P A + A^T P is not zero: P is not conserved by the linear flow"));
    }
    let (sp, sq) = if sign.is_positive() {
        (p.clone(), q.clone())
    } else {
        (p.scale(&Rational::from(-1)), q.scale(&Rational::from(-1)))
    };
    verify_generalized_eigenvalues(&sp, &sq, cert)?;
    let hessians: Vec<Matrix> = ks.iter().map(|k| Matrix::from_rows(&k.hessian_at(mu))).collect();
    verify_infimum_bound(&r, &g, &sp, &sq, cert)?;
    verify_family_bound(&r, &g, &hessians, &form_of, &sp, &sq, cert)?;
    verify_sigma2_exact(&sp, &sq, n, cert, level)
}

/// `Sigma^2` as stated: the double nearest `sigma2_exact`, `S sP - sQ`
/// positive semidefinite (the bound holds), singular when claimed sharp,
/// and tight to 1e-9 (`0.999999999 S` no longer bounds `Q`), all exactly.
fn verify_sigma2_exact(sp: &Matrix, sq: &Matrix, n: usize, cert: &Value, level: &str) -> Claim<VerificationLevel> {
    let sigma2_float = get(cert, &["sigma2"])?.as_f64().ok_or_else(|| failure("$.sigma2", "expected a number"))?;
    let Some(exact_value) = cert.get("sigma2_exact") else {
        if level == VerificationLevel::Exact.as_str() {
            return Err(failure("$.sigma2_exact", "missing for an exact certificate"));
        }
        return Ok(VerificationLevel::Numerical);
    };
    let s = rational(exact_value, "$.sigma2_exact")?;
    // The double written is the nearest to the rational (or the one above).
    let (near, up) = (exact::rational_to_f64(&s), exact::rational_to_f64_up(&s));
    if sigma2_float != near && sigma2_float != up {
        return Err(failure("$.sigma2", format!("is not the double nearest sigma2_exact ({near:e})")));
    }
    if s.is_negative() {
        return Err(failure("$.sigma2_exact", "negative"));
    }
    let gap = sp.scale(&s).sub(sq);
    if !gap.is_positive_semidefinite() {
        return Err(failure("$.sigma2_exact", "sigma2 * sP - sQ is not positive semidefinite: the bound is false"));
    }
    if let Some(lb) = cert.get("optimisation").and_then(|o| o.get("infimum_lower_bound")) {
        if rational(lb, "$.optimisation.infimum_lower_bound")? > s {
            return Err(failure("$.optimisation.infimum_lower_bound", "exceeds the certified sigma2"));
        }
    }
    let singular = gap.rank() < n;
    if let Some(sharp) = cert.get("sigma2_sharp") {
        let claimed = sharp.as_bool().ok_or_else(|| failure("$.sigma2_sharp", "expected a boolean"))?;
        if claimed && !(singular || s.is_zero()) {
            return Err(failure("$.sigma2_sharp", "claimed sharp, but sigma2 * sP - sQ is not singular"));
        }
    }
    // Tightness, exactly: (1 - 1e-9) S must no longer bound Q, so S is within
    // a relative 1e-9 of lambda_max (floating point is not precise enough for
    // this when P is ill-conditioned).
    if !s.is_zero() {
        let lowered = &s * Rational::new_small(999_999_999, 1_000_000_000);
        if sp.scale(&lowered).sub(sq).is_positive_semidefinite() {
            return Err(failure(
                "$.sigma2_exact",
                "not tight: 0.999999999 sigma2 still bounds Q, so sigma2 is not sharp to 1e-9",
            ));
        }
    }
    // The stopping time: the one rule of every kind, applied by the
    // checker after this (crate::check::check_stopping).
    Ok(VerificationLevel::Exact)
}

fn verify_not_equilibrium(spec: &Spec, cert: &Value) -> Claim<VerificationLevel> {
    let mu = spec.system.equilibrium();
    let grad = spec.system.hamiltonian().gradient_at(mu);
    let residual = coadjoint(spec, &grad, mu);
    if residual.iter().all(Zero::is_zero) {
        return Err(failure("$.verdict", "ad*_{Dh(mu_e)} mu_e is zero: mu_e is an equilibrium"));
    }
    if rational_vector(get(cert, &["equilibrium", "residual"])?, "$.equilibrium.residual")? != residual {
        return Err(failure("$.equilibrium.residual", "differs from the recomputed residual"));
    }
    Ok(VerificationLevel::Exact)
}

fn verify_noise_incompatible(spec: &Spec, cert: &Value) -> Claim<VerificationLevel> {
    let mu = spec.system.equilibrium();
    let residuals: Vec<Vec<Rational>> = spec.system.noise().iter().map(|s| coadjoint(spec, s, mu)).collect();
    if residuals.iter().all(|r| r.iter().all(Zero::is_zero)) {
        return Err(failure("$.verdict", "every ad*_{sigma_i} mu_e is zero: the noise is compatible"));
    }
    let stored = get(cert, &["noise", "residuals"])?
        .as_array()
        .ok_or_else(|| failure("$.noise.residuals", "expected an array"))?
        .iter()
        .enumerate()
        .map(|(i, r)| rational_vector(r, &format!("$.noise.residuals[{i}]")))
        .collect::<Claim<Vec<_>>>()?;
    if stored != residuals {
        return Err(failure("$.noise.residuals", "differ from the recomputed residuals"));
    }
    let basis = get(cert, &["noise", "isotropy_basis"])?
        .as_array()
        .ok_or_else(|| failure("$.noise.isotropy_basis", "expected an array"))?;
    for (i, v) in basis.iter().enumerate() {
        let path = format!("$.noise.isotropy_basis[{i}]");
        let xi = rational_vector(v, &path)?;
        if xi.len() != mu.len() || coadjoint(spec, &xi, mu).iter().any(|x| !x.is_zero()) {
            return Err(failure(&path, "does not annihilate mu_e: not in the isotropy algebra"));
        }
    }
    Ok(VerificationLevel::Exact)
}

fn verify_unstable(spec: &Spec, cert: &Value) -> Claim<VerificationLevel> {
    let r = rebuild(spec);
    let proved = matches!(generator::exact_spectrum_test(&r.a), generator::SpectralProof::Unstable { .. });
    let Some(inst) = cert.get("instability") else {
        return if proved {
            Ok(VerificationLevel::Exact)
        } else {
            Err(failure("$.instability", "missing, and no exact proof of instability"))
        };
    };
    let ev = get(inst, &["eigenvalue"])?;
    let (re, im) = match (ev.get("re").and_then(Value::as_f64), ev.get("im").and_then(Value::as_f64)) {
        (Some(re), Some(im)) => (re, im),
        _ => return Err(failure("$.instability.eigenvalue", "expected {re, im}")),
    };
    if re <= 0.0 {
        return Err(failure("$.instability.eigenvalue", "real part is not positive"));
    }
    let v: Vec<(f64, f64)> = get(inst, &["eigenvector"])?
        .as_array()
        .ok_or_else(|| failure("$.instability.eigenvector", "expected an array"))?
        .iter()
        .map(|z| {
            (
                z.get("re").and_then(Value::as_f64).unwrap_or(f64::NAN),
                z.get("im").and_then(Value::as_f64).unwrap_or(f64::NAN),
            )
        })
        .collect();
    let a = r.a.to_dmatrix();
    let n = r.n;
    if v.len() != n || v.iter().any(|(x, y)| !x.is_finite() || !y.is_finite()) {
        return Err(failure("$.instability.eigenvector", format!("expected {n} finite complex components")));
    }
    let norm = v.iter().map(|(x, y)| x * x + y * y).sum::<f64>().sqrt();
    let mut residual = 0.0;
    for i in 0..n {
        let (mut x, mut y) = (0.0, 0.0);
        for j in 0..n {
            x += a[(i, j)] * v[j].0;
            y += a[(i, j)] * v[j].1;
        }
        x -= re * v[i].0 - im * v[i].1;
        y -= re * v[i].1 + im * v[i].0;
        residual += x * x + y * y;
    }
    let residual = residual.sqrt() / norm.max(f64::MIN_POSITIVE);
    if residual.is_nan() || residual > 1e-8 * a.norm().max(1.0) {
        return Err(failure(
            "$.instability",
            format!("|A v - l v| / |v| = {residual:e}: not an eigenpair of the rebuilt A"),
        ));
    }
    Ok(if proved { VerificationLevel::Exact } else { VerificationLevel::Numerical })
}

/// Each stored generalized eigenvalue `e_k` (ascending) of `(sQ, sP)` is
/// confirmed exactly to `1e-9` of the largest modulus `r`: by Sylvester's
/// law of inertia the number of eigenvalues below `x` is the number of
/// negative eigenvalues of `sQ - x sP` (`sP ≻ 0`), so
/// `#{l < e_k - 1e-9 r} <= k - 1` and `#{l <= e_k + 1e-9 r} >= k` are
/// exact statements, whatever floating point did to get `e_k`.
fn verify_generalized_eigenvalues(sp: &Matrix, sq: &Matrix, cert: &Value) -> Claim<()> {
    let path = "$.growth.generalized_eigenvalues";
    let Some(list) = cert.get("growth").and_then(|g| g.get("generalized_eigenvalues")) else {
        return Err(failure(path, "missing"));
    };
    let values: Vec<f64> = list
        .as_array()
        .ok_or_else(|| failure(path, "expected an array"))?
        .iter()
        .map(|x| x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| failure(path, "expected finite numbers")))
        .collect::<Claim<_>>()?;
    let n = sp.nrows();
    if values.len() != n {
        return Err(failure(path, format!("expected {n} eigenvalues, got {}", values.len())));
    }
    if values.windows(2).any(|w| w[0] > w[1]) {
        return Err(failure(path, "not in ascending order"));
    }
    let radius = values.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let delta = (1e-9 * radius).max(f64::MIN_POSITIVE);
    let below = |x: f64, inclusive: bool| -> Claim<usize> {
        let x = exact::rational_from_f64(x).ok_or_else(|| failure(path, "not a finite number"))?;
        let inertia = sq.sub(&sp.scale(&x)).inertia();
        Ok(inertia.negative + if inclusive { inertia.zero } else { 0 })
    };
    for (k, &e) in values.iter().enumerate() {
        if below(e - delta, false)? > k || below(e + delta, true)? < k + 1 {
            return Err(failure(
                &format!("{path}[{k}]"),
                format!(
                    "{e:e} is not the generalized eigenvalue #{k} of (Q, P) to within {delta:e} (exact inertia count)"
                ),
            ));
        }
    }
    let top = cert.get("growth").and_then(|g| g.get("largest_generalized_eigenvalue")).and_then(Value::as_f64);
    if n > 0 && top != values.last().copied() {
        return Err(failure("$.growth.largest_generalized_eigenvalue", "is not the last generalized eigenvalue"));
    }
    Ok(())
}

/// The bound over a family with free multipliers: a witness `X ⪰ 0`
/// (`optimisation.infimum_witness_matrix`) with `G^T X = 0` and
/// `G^T B_i X B_i^T G = 0` (so `<X, P>` and `<X, Q>` do not see `M`),
/// `<X, L(D)> = rho <X, D>` for every direction `D = sum_l v_l D^2K_l`,
/// `v` in `ker G` (so they do not see the multipliers either), and
/// `<X, sQ - rho sP> >= 0`: then every choice with `sP ≻ 0` (the
/// certificate's sign `s`; the other sign is not covered) has
/// `lambda_max(sQ, sP) >= <X, sQ> / <X, sP> >= rho` (see
/// `generator::family_lower_bound`).
fn verify_family_bound(
    r: &Rebuilt,
    g: &Matrix,
    hessians: &[Matrix],
    form_of: &dyn Fn(&Matrix) -> Matrix,
    sp: &Matrix,
    sq: &Matrix,
    cert: &Value,
) -> Claim<()> {
    let opt = cert.get("optimisation");
    let Some(witness) = opt.and_then(|o| o.get("infimum_witness_matrix")) else {
        return Ok(());
    };
    let wpath = "$.optimisation.infimum_witness_matrix";
    let path = "$.optimisation.infimum_lower_bound";
    let rho = rational(opt.and_then(|o| o.get("infimum_lower_bound")).ok_or_else(|| failure(path, "missing"))?, path)?;
    let x = rational_matrix(witness, wpath)?;
    if x.nrows() != r.n || x.ncols() != r.n || !x.is_symmetric() {
        return Err(failure(wpath, format!("expected a symmetric {} x {} matrix", r.n, r.n)));
    }
    if x.is_zero() || !x.is_positive_semidefinite() {
        return Err(failure(wpath, "not a non-zero positive semidefinite matrix"));
    }
    let gt = g.transpose();
    if !gt.mul(&x).is_zero() {
        return Err(failure(wpath, "its columns are not in ker G^T: <X, P> would depend on M"));
    }
    for b in &r.b {
        if !gt.mul(b).mul(&x).mul(&b.transpose()).mul(g).is_zero() {
            return Err(failure(wpath, "G^T B X B^T G is not zero: <X, Q> would depend on M"));
        }
    }
    let inner = |a: &Matrix, b: &Matrix| {
        let mut s = Rational::zero();
        for i in 0..a.nrows() {
            for j in 0..a.ncols() {
                s += &a[(i, j)] * &b[(i, j)];
            }
        }
        s
    };
    for (j, v) in g.null_space().iter().enumerate() {
        let mut d = Matrix::zeros(r.n, r.n);
        for (vl, h) in v.iter().zip(hessians) {
            if !vl.is_zero() {
                d.add_scaled_assign(vl, h);
            }
        }
        if inner(&x, &form_of(&d)) != &rho * &inner(&x, &d) {
            return Err(failure(
                path,
                format!("<X, L(D)> != rho <X, D> along free multiplier direction {j}: the bound would move with the multipliers"),
            ));
        }
    }
    if !inner(&x, sp).is_positive() {
        return Err(failure(wpath, "<X, sP> is not positive"));
    }
    if (inner(&x, sq) - &rho * &inner(&x, sp)).is_negative() {
        return Err(failure(path, "<X, sQ - rho sP> is negative: X does not prove the bound"));
    }
    Ok(())
}

/// The certified lower bound on `Sigma^2` for every Casimir choice: a
/// vector `x` with `G^T x = 0` (so `x^T P x` and `x^T Q x` do not depend
/// on `M`: `G M G^T x = 0`, and `x^T L(G M G^T) x = 0` when no conserved
/// quantity is moved by the noise, checked here) and no free multipliers
/// (`G` of full column rank), so every choice has
/// `lambda_max >= x^T sQ x / x^T sP x`.
fn verify_infimum_bound(r: &Rebuilt, g: &Matrix, sp: &Matrix, sq: &Matrix, cert: &Value) -> Claim<()> {
    let opt = cert.get("optimisation");
    let (Some(lb), witness) =
        (opt.and_then(|o| o.get("infimum_lower_bound")), opt.and_then(|o| o.get("infimum_witness")))
    else {
        return Ok(());
    };
    let path = "$.optimisation.infimum_lower_bound";
    if witness.is_none() && opt.and_then(|o| o.get("infimum_witness_matrix")).is_some() {
        return Ok(()); // the matrix witness: verify_family_bound
    }
    let lb = rational(lb, path)?;
    let x = rational_vector(
        witness.ok_or_else(|| failure("$.optimisation.infimum_witness", "missing"))?,
        "$.optimisation.infimum_witness",
    )?;
    if x.len() != r.n || g.transpose().mul_vec(&x).iter().any(|v| !v.is_zero()) {
        return Err(failure("$.optimisation.infimum_witness", "not a vector of ker G^T"));
    }
    if g.rank() < g.ncols() {
        return Err(failure(path, "the multipliers are not unique: the bound would hold for one choice only"));
    }
    // x^T L(G M G^T) x = sum_i (G^T B_i x)^T M (G^T B_i x) (the drift terms
    // vanish as G^T x = 0): zero for every M iff G^T B_i x = 0.
    for b in &r.b {
        if g.transpose().mul_vec(&b.mul_vec(&x)).iter().any(|v| !v.is_zero()) {
            return Err(failure(path, "the noise moves the witness off ker G^T: x^T Q x depends on M"));
        }
    }
    let quad = |m: &Matrix| x.iter().zip(m.mul_vec(&x)).fold(Rational::zero(), |acc, (a, b)| acc + a * b);
    let (px, qx) = (quad(sp), quad(sq));
    if !px.is_positive() {
        return Err(failure("$.optimisation.infimum_witness", "x^T sP x is not positive"));
    }
    let rho = qx / px;
    let expected = if rho.is_positive() { rho } else { Rational::zero() };
    if expected != lb {
        return Err(failure(path, "is not max(0, x^T sQ x / x^T sP x) for the witness x"));
    }
    Ok(())
}
