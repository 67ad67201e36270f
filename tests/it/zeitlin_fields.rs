//! A Zeitlin spec's fields in quflow's layout (`spec::zeitlin_fields`): the
//! state round-trips through harmonics to the same certificate, an
//! unstable state's eigenvector satisfies the linearised equation formed
//! from the full matrices, and a tilted state's start is its zonal twin's
//! rotated.

use crate::common;
use nalgebra::{Complex, DMatrix};
use serde_json::{json, Value};
use zeitlin::analysis::hbar;
use zeitlin::laplacian::StreamSolver;
use zeitlin::sphere::from_harmonics;

type C = Complex<f64>;

fn spec_of(name: &str) -> spec::ZeitlinSpec {
    let path = common::fixture_path(&format!("zeitlin/{name}.json"));
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    spec::zeitlin_spec_from_value_in(v, path.parent()).unwrap()
}

/// The `[l, m, value]` rows of a quflow omega vector (index `l^2 + l + m`).
fn rows(omega: &[f64]) -> Vec<Value> {
    let n = (omega.len() as f64).sqrt().round() as usize;
    let mut out = vec![];
    for l in 1..n {
        for m in -(l as i64)..=(l as i64) {
            let x = omega[((l * l + l) as i64 + m) as usize];
            if x != 0.0 {
                out.push(json!([l, m, x]));
            }
        }
    }
    out
}

fn matrix(omega: &[f64]) -> DMatrix<C> {
    let n = (omega.len() as f64).sqrt().round() as usize;
    let mut entries = vec![];
    for l in 1..n {
        for m in -(l as i64)..=(l as i64) {
            entries.push((l, m, omega[((l * l + l) as i64 + m) as usize]));
        }
    }
    from_harmonics(n, &entries).unwrap()
}

#[test]
fn the_state_round_trips_to_the_same_certificate() {
    let original = spec_of("energy-casimir-n32");
    let fields = spec::zeitlin_fields(&original).unwrap();
    assert_eq!((fields.n, fields.state.len()), (32, 1024));
    let again = json!({
        "name": "round trip",
        "zeitlin": {"N": 32, "equilibrium": {"harmonics": rows(&fields.state)},
                    "noise": [{"harmonics": rows(&fields.noise[0])}]},
        "settings": {"casimir_momentum": false}
    });
    let a = spec::certify_zeitlin(&original);
    let b = spec::certify_zeitlin(&spec::zeitlin_spec_from_value(again).unwrap());
    assert_eq!(b["verdict"], "stable");
    let (sa, sb) = (a["sigma2"].as_f64().unwrap(), b["sigma2"].as_f64().unwrap());
    assert!((sa - sb).abs() <= 1e-9 * sa, "{sa} vs {sb}");
    // The zonal state's harmonics are its Legendre coefficients at m = 0:
    // a_1 = sqrt(3) (1/3 + 0.3/5), a_3 = sqrt(7) 0.3 (2/35) (z + 0.3 z^3).
    assert!((fields.state[2] - 3f64.sqrt() * (1.0 / 3.0 + 0.06)).abs() < 1e-12);
    assert!((fields.state[12] - 7f64.sqrt() * 0.3 * 2.0 / 35.0).abs() < 1e-12);
}

/// `X` and `Y` of the unstable mode satisfy `L X = a X + b Y` with `L X =
/// ([P_e, X] + [Delta^-1 X, W_e]) / hbar` formed from the full matrices (the
/// O(N^2) stream solve), `a + i b` the eigenvalue: the certificate's growth
/// rate.
#[test]
fn an_unstable_states_eigenvector_solves_the_linearised_equation() {
    let s = spec_of("jet-n64");
    let fields = spec::zeitlin_fields(&s).unwrap();
    let mode = fields.mode.expect("a mode");
    assert_eq!(mode.kind, "unstable_eigenvector");
    let cert = spec::certify_zeitlin(&s);
    let rate = cert["growth_rate"].as_f64().unwrap();
    assert!((mode.rate - rate).abs() <= 1e-6 * rate, "{} vs {rate}", mode.rate);
    let n = fields.n;
    let (w, x, y) = (matrix(&fields.state), matrix(&mode.real), matrix(&mode.imaginary));
    let stream = StreamSolver::new(n).unwrap();
    let p = stream.solve(&w).unwrap();
    let h = C::new(hbar(n), 0.0);
    let lx = (&p * &x - &x * &p + stream.solve(&x).unwrap() * &w - &w * stream.solve(&x).unwrap()) / h;
    let want = &x * C::new(mode.rate, 0.0) + &y * C::new(mode.frequency, 0.0);
    assert!((&lx - &want).norm() <= 1e-8 * lx.norm(), "residual {:e} of {:e}", (&lx - &want).norm(), lx.norm());
    // Confined to the azimuthal wavenumber of its block.
    let m = mode.block as i64;
    for l in 1..n {
        for mm in -(l as i64)..=(l as i64) {
            if mm.abs() != m {
                assert!(mode.real[((l * l + l) as i64 + mm) as usize].abs() < 1e-12 * x.norm());
            }
        }
    }
}

/// A tilted state's fastest-growing start is its zonal twin's, rotated: the
/// same rate (Sigma^2) and the same size; and it is tilted with the state
/// (not confined to one azimuthal wavenumber in the spec's frame).
#[test]
fn a_tilted_states_start_is_its_zonal_twins_rotated() {
    let tilted = spec::zeitlin_fields(&spec_of("tilted-energy-casimir-n32")).unwrap().mode.unwrap();
    let zonal = spec::zeitlin_fields(&spec_of("energy-casimir-n32")).unwrap().mode.unwrap();
    assert_eq!(tilted.kind, "fastest_growing_start");
    assert_eq!((tilted.block, zonal.block), (1, 1));
    assert!((tilted.rate - zonal.rate).abs() <= 1e-9 * zonal.rate);
    let size = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((size(&tilted.real) - size(&zonal.real)).abs() <= 1e-9 * size(&zonal.real));
    let off_block = |v: &[f64]| {
        (1..32usize)
            .flat_map(|l| (-(l as i64)..=(l as i64)).map(move |m| (l, m)))
            .filter(|(_, m)| m.abs() != 1)
            .map(|(l, m)| v[((l * l + l) as i64 + m) as usize].abs())
            .fold(0.0, f64::max)
    };
    assert!(off_block(&zonal.real) < 1e-12 * size(&zonal.real));
    assert!(off_block(&tilted.real) > 1e-3 * size(&tilted.real));
    // A state zonal in no frame has no mode; an equilibrium that is not one has none either.
    assert!(spec::zeitlin_fields(&spec_of("rossby-haurwitz-l2-n7")).unwrap().mode.is_none());
    assert!(spec::zeitlin_fields(&spec_of("mixed-degrees-n8")).unwrap().mode.is_none());
}
