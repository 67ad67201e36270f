//! Lie algebras given by sparse structure constants, validated exactly.

use crate::LargeError;
use exact::Rational;
use num_traits::Zero;
use std::collections::{BTreeMap, BTreeSet};

/// A Lie algebra with basis `e_0..e_{n-1}` and `[e_a, e_b] = sum_k c^k_ab e_k`,
/// stored sparsely (only the nonzero brackets, both orders).
///
/// ```
/// use large::algebra::SparseAlgebra;
/// use exact::Rational;
/// let one = Rational::from(1);
/// // two copies of so(3): [e0, e1] = e2 (cyclic) and [e3, e4] = e5 (cyclic)
/// let mut rows = vec![];
/// for o in [0usize, 3] {
///     rows.push((o, o + 1, o + 2, one.clone()));
///     rows.push((o + 1, o + 2, o, one.clone()));
///     rows.push((o + 2, o, o + 1, one.clone()));
/// }
/// let names: Vec<String> = (0..6).map(|i| format!("m{i}")).collect();
/// let g = SparseAlgebra::new(&names, &rows).unwrap();
/// assert_eq!(g.dim(), 6);
/// assert_eq!(g.bracket(4, 3), &[(5, Rational::from(-1))]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SparseAlgebra {
    names: Vec<String>,
    brackets: BTreeMap<(usize, usize), Vec<(usize, Rational)>>,
    /// For each `a`, the `b` with `[e_a, e_b] != 0`.
    partners: Vec<Vec<usize>>,
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Most triples the exact Jacobi check visits (each a handful of rational
/// operations): beyond, the algebra is too dense for this path.
const MAX_JACOBI_WORK: usize = 200_000_000;

impl SparseAlgebra {
    /// Build and validate: names, index ranges, antisymmetry and the Jacobi
    /// identity, exactly, visiting only the triples where some bracket is
    /// nonzero.
    pub fn new(names: &[String], rows: &[(usize, usize, usize, Rational)]) -> Result<Self, LargeError> {
        let n = names.len();
        if n == 0 {
            return Err(LargeError::Algebra("no coordinates".into()));
        }
        let mut seen = std::collections::HashSet::new();
        for (i, name) in names.iter().enumerate() {
            if !is_identifier(name) {
                return Err(LargeError::Algebra(format!(
                    "coordinate {i} '{}' is not a valid name",
                    exact::quote(name, 40)
                )));
            }
            if !seen.insert(name.as_str()) {
                return Err(LargeError::Algebra(format!("coordinate {i} '{}' appears twice", exact::quote(name, 40))));
            }
        }
        let mut table: BTreeMap<(usize, usize, usize), (Rational, usize)> = BTreeMap::new();
        for (row, (a, b, k, c)) in rows.iter().enumerate() {
            if *a >= n || *b >= n || *k >= n {
                return Err(LargeError::Algebra(format!("row {row}: index out of range (dimension {n})")));
            }
            if a == b {
                if !c.is_zero() {
                    return Err(LargeError::Algebra(format!("row {row}: c^{k}_{a}{a} must be 0 (antisymmetry)")));
                }
                continue;
            }
            for (x, y, v) in [(*a, *b, c.clone()), (*b, *a, -c.clone())] {
                match table.get(&(x, y, *k)) {
                    Some((old, earlier)) if *old != v => {
                        return Err(LargeError::Algebra(format!(
                            "row {row}: c^{k}_{a}{b} = {c} contradicts row {earlier}"
                        )))
                    }
                    Some(_) => {}
                    None => {
                        table.insert((x, y, *k), (v, row));
                    }
                }
            }
        }
        let mut brackets: BTreeMap<(usize, usize), Vec<(usize, Rational)>> = BTreeMap::new();
        for ((a, b, k), (c, _)) in table {
            if !c.is_zero() {
                brackets.entry((a, b)).or_default().push((k, c));
            }
        }
        let mut partners = vec![Vec::new(); n];
        for &(a, b) in brackets.keys() {
            partners[a].push(b);
        }
        let g = SparseAlgebra { names: names.to_vec(), brackets, partners };
        g.check_jacobi()?;
        Ok(g)
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.names.len()
    }

    /// The coordinate names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// `[e_a, e_b]` as `(k, c^k_ab)`, sorted by `k`.
    pub fn bracket(&self, a: usize, b: usize) -> &[(usize, Rational)] {
        self.brackets.get(&(a, b)).map_or(&[], Vec::as_slice)
    }

    /// Every nonzero `c^k_ab` as `(a, b, k, c)`.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, usize, &Rational)> {
        self.brackets.iter().flat_map(|(&(a, b), v)| v.iter().map(move |(k, c)| (a, b, k.to_owned(), c)))
    }

    /// The `b` with `[e_a, e_b] != 0`.
    pub fn partners(&self, a: usize) -> &[usize] {
        &self.partners[a]
    }

    /// `[[e_a, e_b], e_c]` as a sparse vector.
    fn double(&self, a: usize, b: usize, c: usize, out: &mut BTreeMap<usize, Rational>) {
        for (k, x) in self.bracket(a, b) {
            for (l, y) in self.bracket(*k, c) {
                let e = out.entry(*l).or_insert_with(Rational::zero);
                *e += x * y;
            }
        }
    }

    fn check_jacobi(&self) -> Result<(), LargeError> {
        let mut work = 0usize;
        for &(a, b) in self.brackets.keys() {
            if a > b {
                continue;
            }
            let mut candidates: BTreeSet<usize> = BTreeSet::new();
            candidates.extend(self.partners(a));
            candidates.extend(self.partners(b));
            for (k, _) in self.bracket(a, b) {
                candidates.extend(self.partners(*k));
            }
            work += candidates.len();
            if work > MAX_JACOBI_WORK {
                return Err(LargeError::Algebra(format!(
                    "the structure constants are too dense for the sparse Jacobi check (over {MAX_JACOBI_WORK} triples)"
                )));
            }
            for c in candidates {
                let mut sum = BTreeMap::new();
                self.double(a, b, c, &mut sum);
                self.double(b, c, a, &mut sum);
                self.double(c, a, b, &mut sum);
                if let Some((k, v)) = sum.iter().find(|(_, v)| !v.is_zero()) {
                    return Err(LargeError::Algebra(format!(
                        "the Jacobi identity fails for (e_{a}, e_{b}, e_{c}): component {k} of [[e_a,e_b],e_c] + [[e_b,e_c],e_a] + [[e_c,e_a],e_b] is {v}"
                    )));
                }
            }
        }
        Ok(())
    }
}
