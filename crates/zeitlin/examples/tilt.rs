//! Tilt a zonal state to an axis and print its harmonics, ready for a spec's
//! `{"harmonics": ...}`:
//! `cargo run --release -p zeitlin --example tilt -- N AX AY AZ A1 A2 ...`
//! with `A_l` the zonal coefficients (`W = sum_l A_l T_l0` about the pole)
//! and `(AX, AY, AZ)` the new axis.
use zeitlin::sphere::{from_harmonics, rotation_to_axis, to_harmonics};

fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().expect("numbers")).collect();
    assert!(args.len() >= 5, "usage: tilt N AX AY AZ A1 [A2 ...]");
    let n = args[0] as usize;
    let axis = [args[1], args[2], args[3]];
    let zonal: Vec<(usize, i64, f64)> = args[4..].iter().enumerate().map(|(i, &a)| (i + 1, 0, a)).collect();
    let w = from_harmonics(n, &zonal).expect("valid harmonics");
    let v = rotation_to_axis(n, axis).expect("a rotation");
    let tilted = &v * w * v.adjoint();
    let lmax = zonal.len();
    let rows: Vec<String> = to_harmonics(&tilted, lmax)
        .expect("harmonics")
        .into_iter()
        .filter(|(_, _, x)| x.abs() > 1e-15)
        .map(|(l, m, x)| format!("[{l}, {m}, {x:e}]"))
        .collect();
    println!("[{}]", rows.join(", "));
}
