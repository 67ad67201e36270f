//! The [`LieAlgebra`] type: structure constants, validation, ad and ad*.

use crate::error::AlgebraError;
use exact::{Matrix, Rational};
use num_traits::{One, Zero};

/// Largest dimension accepted for a finite-dimensional algebra.
///
/// The Jacobi check is `O(n^4)` exact operations and the engine's matrices are
/// dense; 64 keeps every step well under a second. Discretised fluids have
/// their own path and do not go through this type.
pub const MAX_DIMENSION: usize = 64;

/// A finite-dimensional real Lie algebra with a basis and exact structure
/// constants, validated on construction.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LieAlgebra {
    name: String,
    coordinates: Vec<String>,
    /// `brackets[a * n + b]` lists the nonzero `(k, c^k_ab)`, sorted by `k`.
    brackets: Vec<Vec<(usize, Rational)>>,
}

/// Whether a string is a valid coordinate / parameter identifier.
pub(crate) fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

impl LieAlgebra {
    /// Build and validate an algebra from rows `(a, b, k, c)` meaning
    /// `c^k_ab = c` (0-based); the antisymmetric partner `c^k_ba = -c` is
    /// implied, and may also be listed if consistent.
    ///
    /// Checks: coordinate names, index ranges, antisymmetry (no `c^k_aa`, no
    /// contradicting rows), and the Jacobi identity, exactly.
    ///
    /// ```
    /// use algebra::{AlgebraError, LieAlgebra};
    /// use exact::Rational;
    /// let one = Rational::from_integer(1.into());
    /// // [e0, e1] = e2, [e1, e2] = e0, [e2, e0] = e1 is so(3).
    /// let rows = vec![(0, 1, 2, one.clone()), (1, 2, 0, one.clone()), (2, 0, 1, one.clone())];
    /// assert!(LieAlgebra::from_structure_constants("so3", &["x", "y", "z"], &rows).is_ok());
    /// // [e0, e1] = e1, [e0, e2] = e1, [e1, e2] = e0 breaks Jacobi:
    /// // [[e0,e1],e2] + [[e1,e2],e0] + [[e2,e0],e1] = e0.
    /// let rows = vec![(0, 1, 1, one.clone()), (0, 2, 1, one.clone()), (1, 2, 0, one)];
    /// let err = LieAlgebra::from_structure_constants("bad", &["x", "y", "z"], &rows).unwrap_err();
    /// assert!(matches!(err, AlgebraError::Jacobi { a: 0, b: 1, c: 2, k: 0, .. }));
    /// ```
    pub fn from_structure_constants<S: AsRef<str>>(
        name: &str,
        coordinates: &[S],
        rows: &[(usize, usize, usize, Rational)],
    ) -> Result<Self, AlgebraError> {
        let n = coordinates.len();
        if n == 0 {
            return Err(AlgebraError::Empty);
        }
        if n > MAX_DIMENSION {
            return Err(AlgebraError::TooLarge { dim: n, max: MAX_DIMENSION });
        }
        let coordinates: Vec<String> = coordinates.iter().map(|s| s.as_ref().to_string()).collect();
        for (index, c) in coordinates.iter().enumerate() {
            if !is_identifier(c) {
                return Err(AlgebraError::InvalidCoordinateName { index, name: c.clone() });
            }
            if coordinates[..index].contains(c) {
                return Err(AlgebraError::DuplicateCoordinate { index, name: c.clone() });
            }
        }
        // value and the row that set it, for (a, b, k)
        let mut table: Vec<Option<(Rational, usize)>> = vec![None; n * n * n];
        let idx = |a: usize, b: usize, k: usize| (a * n + b) * n + k;
        for (row, (a, b, k, c)) in rows.iter().enumerate() {
            for &index in [a, b, k] {
                if index >= n {
                    return Err(AlgebraError::IndexOutOfRange { row, index, dim: n });
                }
            }
            let (a, b, k) = (*a, *b, *k);
            if a == b {
                if !c.is_zero() {
                    return Err(AlgebraError::DiagonalEntry { row, a, k, value: c.to_string() });
                }
                continue;
            }
            for (aa, bb, value) in [(a, b, c.clone()), (b, a, -c.clone())] {
                let slot = &mut table[idx(aa, bb, k)];
                match slot {
                    Some((existing, earlier_row)) if *existing != value => {
                        let implied = if aa == a { existing.clone() } else { -existing.clone() };
                        return Err(AlgebraError::Inconsistent {
                            row,
                            earlier_row: *earlier_row,
                            a,
                            b,
                            k,
                            value: c.to_string(),
                            implied: implied.to_string(),
                        });
                    }
                    Some(_) => {}
                    None => *slot = Some((value, row)),
                }
            }
        }
        let mut brackets = vec![Vec::new(); n * n];
        for a in 0..n {
            for b in 0..n {
                for k in 0..n {
                    if let Some((c, _)) = &table[idx(a, b, k)] {
                        if !c.is_zero() {
                            brackets[a * n + b].push((k, c.clone()));
                        }
                    }
                }
            }
        }
        let algebra = LieAlgebra { name: name.to_string(), coordinates, brackets };
        algebra.check_jacobi()?;
        Ok(algebra)
    }

    /// The algebra's name (builtin name or the spec's label).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.coordinates.len()
    }

    /// Names of the dual coordinates `mu_k`.
    pub fn coordinates(&self) -> &[String] {
        &self.coordinates
    }

    /// The nonzero `(k, c^k_ab)` of `[e_a, e_b]`.
    pub fn bracket_of_basis(&self, a: usize, b: usize) -> &[(usize, Rational)] {
        &self.brackets[a * self.dim() + b]
    }

    /// `c^k_ab`.
    pub fn structure_constant(&self, a: usize, b: usize, k: usize) -> Rational {
        self.bracket_of_basis(a, b).iter().find(|(kk, _)| *kk == k).map_or_else(Rational::zero, |(_, c)| c.clone())
    }

    /// All nonzero structure constants as rows `(a, b, k, c)` with `a < b`.
    pub fn structure_constant_rows(&self) -> Vec<(usize, usize, usize, Rational)> {
        let n = self.dim();
        let mut rows = Vec::new();
        for a in 0..n {
            for b in (a + 1)..n {
                for (k, c) in self.bracket_of_basis(a, b) {
                    rows.push((a, b, *k, c.clone()));
                }
            }
        }
        rows
    }

    /// `[x, y]` in components.
    pub fn bracket(&self, x: &[Rational], y: &[Rational]) -> Vec<Rational> {
        let n = self.dim();
        assert!(x.len() == n && y.len() == n, "vector length");
        let mut out = vec![Rational::zero(); n];
        for a in 0..n {
            if x[a].is_zero() {
                continue;
            }
            for b in 0..n {
                if y[b].is_zero() {
                    continue;
                }
                let xy = &x[a] * &y[b];
                for (k, c) in self.bracket_of_basis(a, b) {
                    out[*k] += c * &xy;
                }
            }
        }
        out
    }

    /// Visit `(k, b, c^k_ab xi^a)` for every nonzero structure constant.
    fn for_each_ad_entry(&self, xi: &[Rational], mut visit: impl FnMut(usize, usize, Rational)) {
        let n = self.dim();
        assert_eq!(xi.len(), n, "vector length");
        for a in 0..n {
            if xi[a].is_zero() {
                continue;
            }
            for b in 0..n {
                for (k, c) in self.bracket_of_basis(a, b) {
                    visit(*k, b, c * &xi[a]);
                }
            }
        }
    }

    /// The matrix of `ad_xi`: `(ad_xi)_{k b} = c^k_ab xi^a`.
    pub fn ad_matrix(&self, xi: &[Rational]) -> Matrix {
        let mut m = Matrix::zeros(self.dim(), self.dim());
        self.for_each_ad_entry(xi, |k, b, v| m[(k, b)] += v);
        m
    }

    /// The matrix of `ad*_xi` acting on `mu`: `(ad*_xi)_{b k} = c^k_ab xi^a`,
    /// i.e. the transpose of [`Self::ad_matrix`].
    pub fn coad_matrix(&self, xi: &[Rational]) -> Matrix {
        let mut m = Matrix::zeros(self.dim(), self.dim());
        self.for_each_ad_entry(xi, |k, b, v| m[(b, k)] += v);
        m
    }

    /// `ad*_xi mu`.
    pub fn coad(&self, xi: &[Rational], mu: &[Rational]) -> Vec<Rational> {
        self.coad_matrix(xi).mul_vec(mu)
    }

    /// The Lie–Poisson tensor `Lambda(mu)_ab = c^k_ab mu_k` (antisymmetric);
    /// `ad*_xi mu = Lambda(mu)^T xi` and `{F, G}(mu) = DF^T Lambda(mu) DG`.
    pub fn poisson_tensor(&self, mu: &[Rational]) -> Matrix {
        let n = self.dim();
        assert_eq!(mu.len(), n, "vector length");
        Matrix::from_fn(n, n, |a, b| {
            let mut s = Rational::zero();
            for (k, c) in self.bracket_of_basis(a, b) {
                if !mu[*k].is_zero() {
                    s += c * &mu[*k];
                }
            }
            s
        })
    }

    /// A basis of the isotropy algebra `g_mu = {xi : ad*_xi mu = 0}`.
    pub fn isotropy_basis(&self, mu: &[Rational]) -> Vec<Vec<Rational>> {
        self.poisson_tensor(mu).transpose().null_space()
    }

    fn check_jacobi(&self) -> Result<(), AlgebraError> {
        let n = self.dim();
        let basis = |i: usize| {
            let mut v = vec![Rational::zero(); n];
            v[i] = Rational::one();
            v
        };
        // Precompute [e_a, e_b] as dense vectors.
        let br: Vec<Vec<Rational>> = (0..n * n)
            .map(|ab| {
                let mut v = vec![Rational::zero(); n];
                for (k, c) in &self.brackets[ab] {
                    v[*k] = c.clone();
                }
                v
            })
            .collect();
        for a in 0..n {
            for b in (a + 1)..n {
                for c in (b + 1)..n {
                    let t1 = self.bracket(&br[a * n + b], &basis(c));
                    let t2 = self.bracket(&br[b * n + c], &basis(a));
                    let t3 = self.bracket(&br[c * n + a], &basis(b));
                    for k in 0..n {
                        let value = &t1[k] + &t2[k] + &t3[k];
                        if !value.is_zero() {
                            return Err(AlgebraError::Jacobi { a, b, c, k, value: value.to_string() });
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// The same algebra in the rescaled basis `e'_a = s_a e_a`
    /// (`c'^k_ab = s_a s_b / s_k c^k_ab`), with the same coordinate names.
    ///
    /// # Panics
    /// If a scale is zero or the length is wrong.
    pub fn rescaled(&self, scales: &[Rational]) -> LieAlgebra {
        let n = self.dim();
        assert_eq!(scales.len(), n);
        assert!(scales.iter().all(|s| !s.is_zero()), "zero scale");
        let brackets = (0..n * n)
            .map(|ab| {
                let (a, b) = (ab / n, ab % n);
                self.brackets[ab].iter().map(|(k, c)| (*k, c * &scales[a] * &scales[b] / &scales[*k])).collect()
            })
            .collect();
        LieAlgebra { name: format!("{} (rescaled)", self.name), coordinates: self.coordinates.clone(), brackets }
    }

    /// The semidirect product `g ⋉ V` for a representation `rho` of `g` on
    /// `V = R^m`: `[(xi, u), (eta, v)] = ([xi, eta], rho(xi) v - rho(eta) u)`.
    ///
    /// `rho[a]` is the `m × m` matrix of `rho(e_a)`; it is checked that
    /// `[rho_a, rho_b] = c^k_ab rho_k`. The basis is `e_0..e_{n-1}` followed by
    /// `f_0..f_{m-1}`, the coordinates are `g`'s followed by `vector_coordinates`.
    /// With `g = so3` and `rho(xi) v = xi x v` this is `se3`.
    pub fn semidirect<S: AsRef<str>>(
        &self,
        name: &str,
        rho: &[Matrix],
        vector_coordinates: &[S],
    ) -> Result<LieAlgebra, AlgebraError> {
        let n = self.dim();
        let m = vector_coordinates.len();
        if rho.len() != n {
            return Err(AlgebraError::WrongCount { what: "representation matrices", expected: n, got: rho.len() });
        }
        for (index, r) in rho.iter().enumerate() {
            if r.nrows() != m || r.ncols() != m {
                return Err(AlgebraError::RepresentationShape { index, rows: r.nrows(), cols: r.ncols(), dim: m });
            }
        }
        for a in 0..n {
            for b in (a + 1)..n {
                let lhs = rho[a].mul(&rho[b]).sub(&rho[b].mul(&rho[a]));
                let mut rhs = Matrix::zeros(m, m);
                for (k, c) in self.bracket_of_basis(a, b) {
                    rhs.add_scaled_assign(c, &rho[*k]);
                }
                if lhs != rhs {
                    return Err(AlgebraError::NotARepresentation { a, b });
                }
            }
        }
        let dim = n + m;
        let mut rows = Vec::new();
        for (a, b, k, c) in self.structure_constant_rows() {
            rows.push((a, b, k, c));
        }
        // [e_a, f_i] = rho(e_a) f_i = sum_j rho_a[j][i] f_j
        for a in 0..n {
            for i in 0..m {
                for j in 0..m {
                    let c = &rho[a][(j, i)];
                    if !c.is_zero() {
                        rows.push((a, n + i, n + j, c.clone()));
                    }
                }
            }
        }
        let coordinates: Vec<String> =
            self.coordinates.iter().cloned().chain(vector_coordinates.iter().map(|s| s.as_ref().to_string())).collect();
        if dim > MAX_DIMENSION {
            return Err(AlgebraError::TooLarge { dim, max: MAX_DIMENSION });
        }
        LieAlgebra::from_structure_constants(name, &coordinates, &rows)
    }

    /// The direct sum `g1 ⊕ g2` (block-diagonal brackets); coordinates are
    /// concatenated and must be distinct.
    pub fn direct_sum(&self, other: &LieAlgebra, name: &str) -> Result<LieAlgebra, AlgebraError> {
        let n = self.dim();
        let mut rows = self.structure_constant_rows();
        for (a, b, k, c) in other.structure_constant_rows() {
            rows.push((a + n, b + n, k + n, c));
        }
        let coordinates: Vec<String> = self.coordinates.iter().chain(other.coordinates.iter()).cloned().collect();
        LieAlgebra::from_structure_constants(name, &coordinates, &rows)
    }

    /// Rename the coordinates (same length, valid, distinct names).
    pub fn with_coordinates<S: AsRef<str>>(self, coordinates: &[S]) -> Result<Self, AlgebraError> {
        if coordinates.len() != self.dim() {
            return Err(AlgebraError::WrongCount {
                what: "coordinate names",
                expected: self.dim(),
                got: coordinates.len(),
            });
        }
        let rows = self.structure_constant_rows();
        LieAlgebra::from_structure_constants(&self.name, coordinates, &rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64) -> Rational {
        Rational::from_integer(n.into())
    }

    #[test]
    fn diagonal_entry_is_rejected() {
        let err = LieAlgebra::from_structure_constants("x", &["a", "b"], &[(1, 1, 0, q(1))]).unwrap_err();
        assert!(matches!(err, AlgebraError::DiagonalEntry { row: 0, a: 1, k: 0, .. }));
    }

    #[test]
    fn contradicting_partner_row_is_rejected() {
        let rows = [(0, 1, 0, q(1)), (1, 0, 0, q(1))];
        let err = LieAlgebra::from_structure_constants("x", &["a", "b"], &rows).unwrap_err();
        assert!(matches!(err, AlgebraError::Inconsistent { row: 1, earlier_row: 0, .. }), "{err}");
        // The consistent partner is accepted.
        let rows = [(0, 1, 0, q(1)), (1, 0, 0, q(-1))];
        assert!(LieAlgebra::from_structure_constants("x", &["a", "b"], &rows).is_ok());
    }

    #[test]
    fn out_of_range_and_names() {
        let err = LieAlgebra::from_structure_constants("x", &["a", "b"], &[(0, 2, 0, q(1))]).unwrap_err();
        assert!(matches!(err, AlgebraError::IndexOutOfRange { row: 0, index: 2, dim: 2 }));
        let err = LieAlgebra::from_structure_constants("x", &["a", "a"], &[]).unwrap_err();
        assert!(matches!(err, AlgebraError::DuplicateCoordinate { index: 1, .. }));
        let err = LieAlgebra::from_structure_constants("x", &["1a"], &[]).unwrap_err();
        assert!(matches!(err, AlgebraError::InvalidCoordinateName { index: 0, .. }));
        let none: [&str; 0] = [];
        assert!(matches!(LieAlgebra::from_structure_constants("x", &none, &[]), Err(AlgebraError::Empty)));
    }

    #[test]
    fn jacobi_failure_names_the_triple() {
        // [e0,e1] = e1, [e0,e2] = e1, [e1,e2] = e0: Jacobi fails on (0,1,2).
        let rows = [(0, 1, 1, q(1)), (0, 2, 1, q(1)), (1, 2, 0, q(1))];
        let err = LieAlgebra::from_structure_constants("x", &["a", "b", "c"], &rows).unwrap_err();
        assert!(matches!(err, AlgebraError::Jacobi { a: 0, b: 1, c: 2, .. }), "{err}");
    }
}
