//! The Kolmogorov generator of the linearised SDE on quadratic forms.

use crate::linearise::Linearisation;
use exact::{Matrix, Rational};

/// The generator applied to `f(x) = x^T P x`, as a quadratic form `x^T Q x`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GeneratorForm {
    /// `Q = P A~ + A~^T P + sum_i B_i^T P B_i` (symmetric), so that
    /// `L (x^T P x) = x^T Q x` for the Itô generator `L`.
    pub q: Matrix,
    /// The drift part `P A + A^T P`: zero for an energy–Casimir `P`, because
    /// the deterministic linear flow conserves the second variation.
    pub drift_residual: Matrix,
    /// The paper's formula (3.3), `sum_i (B_i^T P B_i + sym(P B_i^2))`, i.e.
    /// `<D^2H_C ad*_s x + ad_s D^2H_C x, ad*_s x>` summed over the noise; it
    /// equals `Q` exactly when the drift residual vanishes.
    pub paper_formula: Matrix,
}

/// Form `Q` for a given `P`, exactly.
///
/// For `dx = A x dt + sum B_i x o dW^i` the Itô form is
/// `dx = A~ x dt + sum B_i x dW^i` with `A~ = A + 1/2 sum B_i^2`, and Itô's
/// formula gives `L(x^T P x) = 2 x^T P A~ x + sum_i x^T B_i^T P B_i x`.
///
/// ```
/// use exact::{Matrix, Rational};
/// use generator::{generator_form, Linearisation};
/// let q = |n: i64| Rational::from_integer(n.into());
/// // Kubo oscillator dx = B x o dW with B a rotation: |x|^2 is conserved.
/// let b = Matrix::from_rows(&[vec![q(0), q(1)], vec![q(-1), q(0)]]);
/// let half = Rational::new(1.into(), 2.into());
/// let lin = Linearisation { a: Matrix::zeros(2, 2), a_tilde: b.mul(&b).scale(&half), noise: vec![b] };
/// let form = generator_form(&lin, &Matrix::identity(2));
/// assert!(form.q.is_zero());
/// ```
pub fn generator_form(linearisation: &Linearisation, p: &Matrix) -> GeneratorForm {
    // 2 sym(P A~) = 2 sym(P A) + sum_i sym(P B_i^2), so Q = drift + paper formula.
    let two = Rational::from(2);
    let drift_residual = p.mul(&linearisation.a).symmetric_part().scale(&two);
    let mut paper_formula = Matrix::zeros(p.nrows(), p.ncols());
    for b in &linearisation.noise {
        let pb = p.mul(b);
        // B^T P B = (P B)^T B is not symmetric-by-construction in the code, so
        // form it from P B once and symmetrise the P B^2 term.
        let btpb = b.transpose().mul(&pb);
        paper_formula = paper_formula.add(&btpb).add(&pb.mul(b).symmetric_part());
    }
    let q = drift_residual.add(&paper_formula);
    GeneratorForm { q, drift_residual, paper_formula }
}
