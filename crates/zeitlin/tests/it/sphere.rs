//! The spherical-harmonic basis against quflow's own `shr2mat` output
//! (`tests/data/quflow_shr2mat.json`, written by quflow at commit b0e6589 for
//! random coefficient vectors at N = 2, 3, 5, 8), and rotations against the
//! Laplacian's invariance.

use nalgebra::{Complex, DMatrix};
use zeitlin::laplacian::StreamSolver;
use zeitlin::sphere::{from_harmonics, rotation, rotation_to_axis, spin, to_harmonics};

type C = Complex<f64>;

/// quflow's index `l^2 + l + m` back to `(l, m)`.
fn elm(ind: usize) -> (usize, i64) {
    let l = (ind as f64).sqrt().floor() as usize;
    (l, ind as i64 - (l * l + l) as i64)
}

#[test]
fn the_basis_is_quflows_shr2mat() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/quflow_shr2mat.json")).unwrap();
    let data: serde_json::Value = serde_json::from_str(&text).unwrap();
    for case in data["cases"].as_array().unwrap() {
        let n = case["N"].as_u64().unwrap() as usize;
        let omega: Vec<f64> = case["omega"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
        let want = DMatrix::from_fn(n, n, |i, j| {
            C::new(case["W_re"][i][j].as_f64().unwrap(), case["W_im"][i][j].as_f64().unwrap())
        });
        // l = 0 (T_00 = i I, the trace) is part of quflow's vector.
        let mut w = DMatrix::from_diagonal_element(n, n, C::new(0.0, omega[0]));
        let coefficients: Vec<(usize, i64, f64)> =
            omega.iter().enumerate().skip(1).map(|(k, &v)| (elm(k).0, elm(k).1, v)).collect();
        w += from_harmonics(n, &coefficients).unwrap();
        let err = (&w - &want).norm() / want.norm();
        assert!(err < 1e-13, "N = {n}: relative difference {err:e}");
        // And back: the coefficients of the trace-free part.
        let back = to_harmonics(&(w - DMatrix::from_diagonal_element(n, n, C::new(0.0, omega[0]))), n - 1).unwrap();
        for (l, m, v) in back {
            let k = l * l + l;
            let k = (k as i64 + m) as usize;
            assert!((v - omega[k]).abs() < 1e-12, "N = {n}, (l, m) = ({l}, {m}): {v} vs {}", omega[k]);
        }
    }
}

/// Each `T_lm` is an eigenvector of the Laplacian for `-l (l + 1)`, built
/// here from the spin matrices: `-sum_a [S_a, [S_a, T]]`.
#[test]
fn each_harmonic_is_an_eigenvector_of_the_spin_laplacian() {
    for n in [3usize, 6, 9] {
        let s = spin(n);
        for l in 1..n {
            for m in -(l as i64)..=(l as i64) {
                let t = zeitlin::sphere::harmonic(n, l, m).unwrap();
                let mut lap = DMatrix::zeros(n, n);
                for sa in &s {
                    let inner = sa * &t - &t * sa;
                    lap -= sa * &inner - &inner * sa;
                }
                let lambda = -((l * (l + 1)) as f64);
                let err = (&lap - &t * C::new(lambda, 0.0)).norm() / (lambda.abs() * t.norm());
                assert!(err < 1e-12, "N = {n}, (l, m) = ({l}, {m}): {err:e}");
            }
        }
    }
}

/// The Laplacian commutes with rotations: `Delta(V^* W V) = V^* Delta(W) V`
/// for `V = exp(-i theta u.S)`, and a rotation keeps each `l` (a degree-`l`
/// harmonic stays of degree `l`).
#[test]
fn rotations_commute_with_the_laplacian_and_keep_the_degree() {
    let n = 7;
    let solver = StreamSolver::new(n).unwrap();
    let v = rotation(n, [0.48, -0.6, 0.64], 1.1).unwrap();
    assert!((&v * v.adjoint() - DMatrix::<C>::identity(n, n)).norm() < 1e-13);
    let w = from_harmonics(n, &[(1, 1, 0.7), (2, -2, 1.3), (3, 0, -0.4), (6, 5, 0.2)]).unwrap();
    let rotated = v.adjoint() * &w * &v;
    let lhs = solver.laplacian(&rotated).unwrap();
    let rhs = v.adjoint() * solver.laplacian(&w).unwrap() * &v;
    assert!((&lhs - &rhs).norm() < 1e-12 * rhs.norm());
    // The energy in each degree is kept.
    let degree_energy = |w: &DMatrix<C>| {
        let mut e = [0.0; 7];
        for (l, _, x) in to_harmonics(w, n - 1).unwrap() {
            e[l] += x * x;
        }
        e
    };
    let (before, after) = (degree_energy(&w), degree_energy(&rotated));
    for l in 1..n {
        assert!((before[l] - after[l]).abs() < 1e-12, "l = {l}: {} vs {}", before[l], after[l]);
    }
    // A zonal state about an axis becomes diagonal in the frame of that axis.
    let axis = [0.3, -0.4, (1.0f64 - 0.25).sqrt()];
    let to_pole = rotation_to_axis(n, axis).unwrap();
    let zonal = from_harmonics(n, &[(1, 0, 1.0), (3, 0, 0.5)]).unwrap();
    let tilted = &to_pole * &zonal * to_pole.adjoint();
    assert!(tilted.iter().enumerate().any(|(k, z)| k % (n + 1) != 0 && z.norm() > 1e-3), "tilted is not diagonal");
    let back = to_pole.adjoint() * &tilted * &to_pole;
    assert!((back - zonal).norm() < 1e-12);
}
