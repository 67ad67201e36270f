//! One-dimensional minimisation by golden section.
//!
//! Written here rather than taken from a crate: `argmin` offers golden
//! section behind a solver/executor framework with its own problem traits;
//! the engine needs the plain twenty-line iteration on a closure, for the
//! fluid Galilean shift and the Zeitlin momentum coefficient.

/// Minimise a unimodal (for example quasiconvex) `f` on `[a, b]` by `steps`
/// golden-section steps; returns the better interior point and its value.
///
/// ```
/// let (x, fx) = fluid::minimise::golden_section(|x| (x - 0.3) * (x - 0.3) + 1.0, 0.0, 1.0, 60);
/// assert!((x - 0.3).abs() < 1e-7 && (fx - 1.0).abs() < 1e-14);
/// ```
pub fn golden_section(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, steps: usize) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..steps {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2);
        }
    }
    if f1 <= f2 {
        (x1, f1)
    } else {
        (x2, f2)
    }
}
