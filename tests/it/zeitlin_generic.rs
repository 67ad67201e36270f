//! The Zeitlin model at N = 3 through the generic finite-dimensional
//! engine: su(3) given by its structure constants, the energy, the Casimirs
//! `tr W^2`, `Im tr W^3` and the momentum `J` written as polynomials with
//! rational coefficients (at N = 3 the Hoppe–Yau Laplacian is rational: its
//! ladder products are perfect squares), and the same equilibrium and
//! noise. The two engines share no code: the generic one checks the
//! Casimirs and the first integral and proves its `Sigma^2` in exact
//! arithmetic from the polynomials; the Zeitlin one uses its block formulas
//! in floating point. They must agree on the verdict and on what is known
//! of the infimum of `Sigma^2` (at N = 3 a monotone state's infimum over the
//! paper's family is 0, approached, not attained).
//!
//! The identification (docs/zeitlin.md, "Agreement with the generic
//! engine"): `mu_k = <W, e_k>` with the bi-invariant `<A, B> = Re tr(A B^*)/N`.
//! Then `<W, [xi, e_b]> = <[W, xi], e_b>` turns the Lie–Poisson equation
//! `mu' = ad*_{Dh} mu` into `W' = [W, Dh]`, which is Zeitlin's `[P, W]`
//! for `Dh = -P`, i.e. `h = -1/2 <W, P>` (time in units of `hbar`), and the
//! noise `ad*_sigma mu` into `[W, sigma]`, Zeitlin's `[X, W]/hbar` for
//! `sigma = -X/hbar`. The drift's time unit does not enter `Sigma^2` (the
//! drift keeps `P`); the noise's does, and is matched.

use exact::Rational;
use serde_json::json;
use spec::Verdict;
use zeitlin::analysis::{analyse, ZeitlinAnalysis, ZeitlinProblem, ZeitlinSettings};

const N: usize = 3;

/// Gaussian-integer matrices, `(re, im)` per entry.
type Z = [[(i64, i64); N]; N];

fn zero() -> Z {
    [[(0, 0); N]; N]
}

fn mul(a: &Z, b: &Z) -> Z {
    let mut c = zero();
    for i in 0..N {
        for j in 0..N {
            for k in 0..N {
                let (x, y) = (a[i][k], b[k][j]);
                c[i][j].0 += x.0 * y.0 - x.1 * y.1;
                c[i][j].1 += x.0 * y.1 + x.1 * y.0;
            }
        }
    }
    c
}

fn sub(a: &Z, b: &Z) -> Z {
    let mut c = zero();
    for i in 0..N {
        for j in 0..N {
            c[i][j] = (a[i][j].0 - b[i][j].0, a[i][j].1 - b[i][j].1);
        }
    }
    c
}

/// The basis of su(3): for `j < k`, `E_jk - E_kj` and `i (E_jk + E_kj)`,
/// then `i (E_00 - E_11)` and `i (E_11 - E_22)`.
fn basis() -> Vec<Z> {
    let mut out = Vec::new();
    for (j, k) in [(0, 1), (0, 2), (1, 2)] {
        let mut re = zero();
        re[j][k] = (1, 0);
        re[k][j] = (-1, 0);
        let mut im = zero();
        im[j][k] = (0, 1);
        im[k][j] = (0, 1);
        out.push(re);
        out.push(im);
    }
    for j in 0..2 {
        let mut d = zero();
        d[j][j] = (0, 1);
        d[j + 1][j + 1] = (0, -1);
        out.push(d);
    }
    out
}

/// Coordinates of a skew-Hermitian Gaussian-integer matrix in [`basis`].
fn coordinates(y: &Z) -> Vec<i64> {
    let mut v = Vec::new();
    for (j, k) in [(0, 1), (0, 2), (1, 2)] {
        v.push(y[j][k].0);
        v.push(y[j][k].1);
    }
    // i diag(d): d_0 = a, d_1 = b - a, d_2 = -b.
    v.push(y[0][0].1);
    v.push(-y[2][2].1);
    v
}

fn q(n: i64, d: i64) -> Rational {
    Rational::new_small(n, d)
}

/// Exact inverse of a small rational matrix (Gauss–Jordan).
fn inverse(m: &[Vec<Rational>]) -> Vec<Vec<Rational>> {
    let n = m.len();
    let mut a: Vec<Vec<Rational>> = m
        .iter()
        .enumerate()
        .map(|(i, r)| r.iter().cloned().chain((0..n).map(|j| q((i == j) as i64, 1))).collect())
        .collect();
    for col in 0..n {
        let p = (col..n).find(|&r| a[r][col] != q(0, 1)).expect("invertible");
        a.swap(col, p);
        let pivot = a[col][col].clone();
        for x in a[col].iter_mut() {
            *x = &*x / &pivot;
        }
        for r in 0..n {
            if r != col && a[r][col] != q(0, 1) {
                let f = a[r][col].clone();
                let row = a[col].clone();
                for (x, y) in a[r].iter_mut().zip(&row) {
                    *x = &*x - &(&f * y);
                }
            }
        }
    }
    a.into_iter().map(|r| r[n..].to_vec()).collect()
}

/// The Laplacian on one matrix: entries `P[j, j + m]` (and the lower
/// diagonal alike) by the tridiagonal block, with the exact integer
/// entries of `zeitlin::laplacian::block` (perfect squares under the root at N = 3).
fn laplacian(p: &Z) -> [[(Rational, Rational); N]; N] {
    let isqrt = |x: i64| {
        let r = (x as f64).sqrt().round() as i64;
        assert_eq!(r * r, x, "not a perfect square at N = 3");
        r
    };
    let mut out: [[(Rational, Rational); N]; N] = std::array::from_fn(|_| std::array::from_fn(|_| (q(0, 1), q(0, 1))));
    let n = N as i64;
    for m in 0..N as i64 {
        let len = n - m;
        let diag = |j: i64| -((n - 1) * (2 * j + 1 + m) - 2 * j * (j + m));
        let off = |j: i64| isqrt(j * (n - j) * (j + m) * (n - j - m)); // between j - 1 and j
        for upper in [true, false] {
            if m == 0 && !upper {
                continue;
            }
            let at = |j: i64| if upper { (j as usize, (j + m) as usize) } else { ((j + m) as usize, j as usize) };
            for j in 0..len {
                let mut acc = (q(0, 1), q(0, 1));
                let mut add = |c: i64, k: i64| {
                    let (r, i) = p[at(k).0][at(k).1];
                    acc.0 = &acc.0 + &q(c * r, 1);
                    acc.1 = &acc.1 + &q(c * i, 1);
                };
                add(diag(j), j);
                if j > 0 {
                    add(off(j), j - 1);
                }
                if j + 1 < len {
                    add(off(j + 1), j + 1);
                }
                out[at(j).0][at(j).1] = acc;
            }
        }
    }
    out
}

/// `Re tr(A B^*) / N` for Gaussian-integer matrices.
fn inner(a: &Z, b: &Z) -> Rational {
    let mut s = 0;
    for i in 0..N {
        for j in 0..N {
            s += a[i][j].0 * b[i][j].0 + a[i][j].1 * b[i][j].1;
        }
    }
    q(s, N as i64)
}

fn linear(coeffs: &[Rational], names: &[String]) -> String {
    let terms: Vec<String> =
        coeffs.iter().zip(names).filter(|(c, _)| **c != q(0, 1)).map(|(c, n)| format!("({c})*{n}")).collect();
    if terms.is_empty() {
        "0".into()
    } else {
        format!("({})", terms.join(" + "))
    }
}

/// The generic engine's certificate of the su(3) system about `W_e = i
/// diag(omega)` with noise `i diag(y)`, and the Zeitlin engine's analyses of
/// the same state (the paper's family, and with the Casimir–momentum form).
fn both(omega: [Rational; 3]) -> (serde_json::Value, ZeitlinAnalysis, ZeitlinAnalysis) {
    let e = basis();
    let d = e.len();
    let names: Vec<String> = (0..d).map(|k| format!("mu{k}")).collect();
    // Structure constants [e_a, e_b] = c^k_ab e_k (integers).
    let mut rows = Vec::new();
    for a in 0..d {
        for b in a + 1..d {
            let c = coordinates(&sub(&mul(&e[a], &e[b]), &mul(&e[b], &e[a])));
            for (k, x) in c.iter().enumerate() {
                if *x != 0 {
                    rows.push(json!([a, b, k, x]));
                }
            }
        }
    }
    // Gram matrix and x = G^-1 mu (W = sum x_a e_a).
    let g: Vec<Vec<Rational>> = (0..d).map(|a| (0..d).map(|b| inner(&e[a], &e[b])).collect()).collect();
    let g_inv = inverse(&g);
    let x: Vec<String> = (0..d).map(|a| linear(&g_inv[a], &names)).collect();
    // The Laplacian in the basis (Delta e_b = sum_a L_ab e_a), via the entries.
    let mut lap = vec![vec![q(0, 1); d]; d];
    for b in 0..d {
        let l = laplacian(&e[b]);
        // Coordinates of a rational skew-Hermitian matrix.
        let c: Vec<Rational> = {
            let mut v = Vec::new();
            for (j, k) in [(0, 1), (0, 2), (1, 2)] {
                v.push(l[j][k].0.clone());
                v.push(l[j][k].1.clone());
            }
            v.push(l[0][0].1.clone());
            v.push(-l[2][2].1.clone());
            v
        };
        for a in 0..d {
            lap[a][b] = c[a].clone();
        }
    }
    let lap_inv = inverse(&lap);
    // h = -1/2 <W, Delta^-1 W> = -1/2 x^T G L^-1 x.
    let gl: Vec<Vec<Rational>> = (0..d)
        .map(|a| (0..d).map(|b| (0..d).fold(q(0, 1), |s, k| &s + &(&g[a][k] * &lap_inv[k][b]))).collect())
        .collect();
    let mut h_terms = Vec::new();
    for a in 0..d {
        for b in 0..d {
            if gl[a][b] != q(0, 1) {
                h_terms.push(format!("({})*{}*{}", &gl[a][b] * &q(-1, 2), x[a], x[b]));
            }
        }
    }
    // Casimirs tr W^2 (real) and Im tr W^3, and J = <W, i diag(-1, 0, 1)>.
    let tr = |m: &Z| (0..N).fold((0, 0), |s, i| (s.0 + m[i][i].0, s.1 + m[i][i].1));
    let mut c2 = Vec::new();
    let mut c3 = Vec::new();
    for a in 0..d {
        for b in 0..d {
            let ab = mul(&e[a], &e[b]);
            let t = tr(&ab);
            if t.0 != 0 {
                c2.push(format!("({})*{}*{}", t.0, x[a], x[b]));
            }
            for c in 0..d {
                let t3 = tr(&mul(&ab, &e[c]));
                if t3.1 != 0 {
                    c3.push(format!("({})*{}*{}*{}", t3.1, x[a], x[b], x[c]));
                }
            }
        }
    }
    let mut tau = zero();
    tau[0][0] = (0, -1);
    tau[2][2] = (0, 1);
    let j_coeffs: Vec<Rational> = coordinates(&tau).iter().map(|&c| q(c, 1)).collect();
    // <W, E_tau> = sum_k t_k <W, e_k> = sum_k t_k mu_k.
    let j_expr = linear(&j_coeffs, &names);
    // The equilibrium W_e = i diag(omega);
    // noise X = hbar Y with Y = i diag(1, -2, 1)/10 (a degree-2 zonal field:
    // a degree-1 one is a rotation about the axis, which keeps every form), so sigma = -Y.
    let mu_e: Vec<String> = (0..d)
        .map(|k| {
            // <W_e, e_k> = Re tr(W_e e_k^*)/N with W_e = i diag(omega): only the diagonal e's.
            let ek = &e[k];
            let s = (0..N).fold(q(0, 1), |s, i| &s + &(&omega[i] * &q(ek[i][i].1, 1)));
            (&s / &q(N as i64, 1)).to_string()
        })
        .collect();
    let y = [q(1, 10), q(-2, 10), q(1, 10)];
    // sigma = -Y in the basis: i diag(d) = a i(E00 - E11) + b i(E11 - E22), a = d0, b = -d2.
    let mut sigma = vec!["0".to_string(); d];
    sigma[6] = (-&y[0]).to_string();
    sigma[7] = y[2].to_string();
    let spec = json!({
        "name": "zeitlin-su3-generic",
        "algebra": {"coordinates": names, "structure_constants": rows},
        "hamiltonian": h_terms.join(" + "),
        "casimirs": [c2.join(" + "), c3.join(" + ")],
        "first_integrals": [j_expr],
        "equilibrium": mu_e,
        "noise": [sigma],
    });
    let parsed = spec::parse_spec(&spec.to_string()).expect("the su(3) spec parses");
    let cert = spec::certify_lie(&parsed).json;
    // The Zeitlin engine on the same state, in its own units (hbar = 1/sqrt 2 at N = 3).
    let hbar = 2.0 / 8f64.sqrt();
    let problem = ZeitlinProblem {
        n: N,
        omega: omega.iter().map(exact::rational_to_f64).collect(),
        noise: vec![y.iter().map(|v| exact::rational_to_f64(v) * hbar).collect()],
    };
    let forced = analyse(&problem, &ZeitlinSettings { casimir_momentum: false, ..Default::default() }).unwrap();
    let free = analyse(&problem, &ZeitlinSettings::default()).unwrap();
    (cert, forced, free)
}

/// A monotone state: both engines find the energy–Casimir form definite.
/// The generic engine proves its `Sigma^2` exactly; the Zeitlin engine
/// bounds its own. Neither claims the infimum: over this family it is 0,
/// approached as the momentum multiplier grows (`P` tends to the
/// Casimir–momentum form, `Q` does not move; docs/zeitlin.md), which the
/// Zeitlin engine certifies exactly when that form is allowed. Both cut the
/// first definite choice's `Sigma^2` by more than a thousandfold, and the
/// generic engine finds no certified lower bound above 0.
#[test]
fn su3_monotone_state_agrees_with_the_generic_engine() {
    let (cert, forced, free) = both([q(-1, 1), q(1, 5), q(4, 5)]);
    assert_eq!(cert["verdict"], "stable", "{}", cert["reason"]);
    assert_eq!(cert["level"], "exact");
    assert_eq!(forced.verdict, Verdict::Stable);
    let generic = cert["sigma2"].as_f64().unwrap();
    let first = cert["optimisation"]["first_definite_sigma2"].as_f64().unwrap();
    let zs = forced.sigma2.unwrap();
    assert!(generic > 0.0 && zs > 0.0);
    assert!(generic < 1e-3 * first && zs < 1e-3 * first, "generic {generic:e}, zeitlin {zs:e}, first {first:e}");
    assert_eq!(cert["optimisation"]["attained"], false);
    assert!(!forced.attained);
    if let Some(lb) = cert["optimisation"].get("infimum_lower_bound") {
        assert_eq!(lb, "0", "a positive certified lower bound would contradict the infimum 0");
    }
    // The limit form itself: Sigma^2 = 0, exactly structured.
    assert_eq!(free.verdict, Verdict::Stable);
    assert_eq!(free.sigma2, Some(0.0));
    assert_eq!(free.choice.unwrap().energy, 0.0);
}

/// A state that is not monotone (`omega = (-1, 4/5, 1/5)`): neither engine
/// finds a definite form, and both find the spectrum on the imaginary axis
/// (the generic engine proves it exactly by a Sturm sequence).
#[test]
fn su3_non_monotone_state_is_inconclusive_in_both() {
    let (cert, forced, free) = both([q(-1, 1), q(4, 5), q(1, 5)]);
    assert_eq!(cert["verdict"], "inconclusive", "{}", cert["reason"]);
    assert!(cert["reason"].as_str().unwrap().contains("imaginary axis (proved exactly)"));
    for z in [forced, free] {
        assert_eq!(z.verdict, Verdict::Inconclusive, "{}", z.reason);
        assert!(z.reason.contains("imaginary axis"), "{}", z.reason);
    }
}
