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
/// let (x, fx) = numerics::minimise::golden_section(|x| (x - 0.3) * (x - 0.3) + 1.0, 0.0, 1.0, 60);
/// assert!((x - 0.3).abs() < 1e-7 && (fx - 1.0).abs() < 1e-14);
/// ```
pub fn golden_section(f: impl Fn(f64) -> f64, a: f64, b: f64, steps: usize) -> (f64, f64) {
    golden_section_until(f, a, b, steps, |_, _| false)
}

/// [`golden_section`] that stops as soon as `done(x, f(x))` holds at a
/// point it evaluated, and returns that point: for searches that need a
/// good enough point (a definite form), not the best one.
///
/// ```
/// // the first evaluated point below 0.5 ends the search
/// let (x, fx) = numerics::minimise::golden_section_until(|x| (x - 0.3) * (x - 0.3), 0.0, 1.0, 60, |_, fx| fx < 0.5);
/// assert!(fx < 0.5 && (x - 0.3).abs() < 0.71);
/// ```
pub fn golden_section_until(
    f: impl Fn(f64) -> f64,
    mut a: f64,
    mut b: f64,
    steps: usize,
    mut done: impl FnMut(f64, f64) -> bool,
) -> (f64, f64) {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let mut f1 = f(x1);
    if done(x1, f1) {
        return (x1, f1);
    }
    let mut f2 = f(x2);
    if done(x2, f2) {
        return (x2, f2);
    }
    for _ in 0..steps {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1);
            if done(x1, f1) {
                return (x1, f1);
            }
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2);
            if done(x2, f2) {
                return (x2, f2);
            }
        }
    }
    if f1 <= f2 {
        (x1, f1)
    } else {
        (x2, f2)
    }
}

/// Minimise a unimodal `f` on `[a, b]`, first testing whether the minimum
/// lies within `rel (b - a)` of an end (four evaluations), and only then by
/// `steps` golden-section steps inside: when `f(a) <= f(a + d)`, unimodality
/// puts every value on `[a + d, b]` at or above `f(a)`. Searches whose
/// minimum sits at the end of the admissible range (an infimum approached,
/// not attained) then cost four evaluations instead of `steps + 2`.
///
/// ```
/// use numerics::minimise::golden_section_with_ends;
/// // decreasing on [0, 1]: the minimum is the end, found without the golden steps
/// let calls = std::cell::Cell::new(0);
/// let (x, fx) = golden_section_with_ends(|x| { calls.set(calls.get() + 1); 1.0 / (1.0 + x) }, 0.0, 1.0, 60, 1e-6);
/// assert_eq!((x, fx), (1.0, 0.5));
/// assert_eq!(calls.get(), 4);
/// // an interior minimum is found as by golden section
/// let (x, _) = golden_section_with_ends(|x| (x - 0.3) * (x - 0.3), 0.0, 1.0, 60, 1e-6);
/// assert!((x - 0.3).abs() < 1e-7);
/// ```
pub fn golden_section_with_ends(f: impl Fn(f64) -> f64, a: f64, b: f64, steps: usize, rel: f64) -> (f64, f64) {
    let d = rel * (b - a);
    if d.is_nan() || d <= 0.0 {
        return golden_section(f, a, b, steps);
    }
    let (fa, fa2) = (f(a), f(a + d));
    if fa <= fa2 {
        return (a, fa);
    }
    let (fb, fb2) = (f(b), f(b - d));
    if fb <= fb2 {
        return (b, fb);
    }
    golden_section(f, a + d, b - d, steps)
}
