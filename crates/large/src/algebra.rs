//! Lie algebras given by sparse structure constants, validated exactly.

use crate::LargeError;
use exact::Rational;
use num_traits::Zero;
use std::collections::BTreeMap;

/// A Lie algebra with basis `e_0..e_{n-1}` and `[e_a, e_b] = sum_k c^k_ab e_k`,
/// stored sparsely (only the nonzero brackets, both orders).
///
/// ```
/// use large::SparseAlgebra;
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

/// Most candidate triples the exhaustive Jacobi check visits. Beyond (dense
/// brackets, as so(n) has: some 4e7 candidates at n = 64), the identity is
/// tested at random integer points instead ([`SparseAlgebra::jacobi_at_random_points`]).
const EXHAUSTIVE_JACOBI_WORK: usize = 4_000_000;

/// Random points of the randomized Jacobi test.
const JACOBI_TRIALS: usize = 3;

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
                    return Err(LargeError::Algebra(format!("row {row}: c^{k}_({a},{a}) must be 0 (antisymmetry)")));
                }
                continue;
            }
            for (x, y, v) in [(*a, *b, c.clone()), (*b, *a, -c.clone())] {
                match table.get(&(x, y, *k)) {
                    Some((old, earlier)) if *old != v => {
                        return Err(LargeError::Algebra(format!(
                            "row {row}: c^{k}_({a},{b}) = {c} contradicts row {earlier}"
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
        // The exhaustive check's work, bounded before it runs.
        let work: usize = g
            .brackets
            .iter()
            .filter(|((a, b), _)| a < b)
            .map(|((a, b), v)| {
                g.partners[*a].len() + g.partners[*b].len() + v.iter().map(|(k, _)| g.partners[*k].len()).sum::<usize>()
            })
            .sum();
        if work <= EXHAUSTIVE_JACOBI_WORK {
            g.check_jacobi()?;
        } else if !g.jacobi_at_random_points(rows) {
            return Err(LargeError::Algebra(
                "the Jacobi identity fails: [[x,y],z] + [[y,z],x] + [[z,x],y] is not zero at a random integer point (x, y, z)"
                    .into(),
            ));
        }
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

    /// Add `[[e_a, e_b], e_c]` to a short sparse vector (a handful of
    /// components: a linear search beats a map, and nothing is allocated
    /// per triple).
    fn double(&self, a: usize, b: usize, c: usize, out: &mut Vec<(usize, Rational)>) {
        for (k, x) in self.bracket(a, b) {
            for (l, y) in self.bracket(*k, c) {
                let v = x * y;
                match out.iter_mut().find(|(i, _)| i == l) {
                    Some((_, e)) => *e += v,
                    None => out.push((*l, v)),
                }
            }
        }
    }

    fn nonzero(&self, a: usize, b: usize) -> bool {
        self.brackets.contains_key(&(a, b))
    }

    /// Whether the pair `(x, y)` has a nonzero bracket and `w` is among its
    /// Jacobi candidates (a partner of `x`, of `y`, or of an index of
    /// `[e_x, e_y]`).
    fn reaches(&self, x: usize, y: usize, w: usize) -> bool {
        self.nonzero(x, y)
            && (self.nonzero(x, w) || self.nonzero(y, w) || self.bracket(x, y).iter().any(|(k, _)| self.nonzero(*k, w)))
    }

    /// `[x, y]` for coordinate vectors, over the nonzero brackets.
    fn bracket_of(&self, x: &[Rational], y: &[Rational]) -> Vec<Rational> {
        let mut out = vec![Rational::zero(); self.dim()];
        for (&(a, b), v) in &self.brackets {
            if x[a].is_zero() || y[b].is_zero() {
                continue;
            }
            let xy = &x[a] * &y[b];
            for (k, c) in v {
                out[*k] += &xy * c;
            }
        }
        out
    }

    /// The Jacobi identity at random integer points, exactly: `J(x, y, z) =
    /// [[x,y],z] + [[y,z],x] + [[z,x],y]` is trilinear, so if it is not
    /// identically zero it vanishes at a point with entries drawn from
    /// `2^21` integers with probability at most `3 / 2^21` (Schwartz–Zippel);
    /// three independent points leave at most `4e-18`. The points are drawn
    /// from a generator seeded by the rows themselves, so the test is
    /// reproducible and a table cannot be tuned to points it does not know.
    fn jacobi_at_random_points(&self, rows: &[(usize, usize, usize, Rational)]) -> bool {
        use std::hash::{Hash, Hasher};
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        for (a, b, k, c) in rows {
            (a, b, k, c.to_string()).hash(&mut hasher);
        }
        let mut state = hasher.finish() | 1;
        let mut draw = || {
            // xorshift64*
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let v = state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 43; // 21 bits
            Rational::from(v as i64 - (1 << 20))
        };
        let n = self.dim();
        (0..JACOBI_TRIALS).all(|_| {
            let x: Vec<Rational> = (0..n).map(|_| draw()).collect();
            let y: Vec<Rational> = (0..n).map(|_| draw()).collect();
            let z: Vec<Rational> = (0..n).map(|_| draw()).collect();
            let mut j = self.bracket_of(&self.bracket_of(&x, &y), &z);
            for (t, v) in j.iter_mut().zip(self.bracket_of(&self.bracket_of(&y, &z), &x)) {
                *t += v;
            }
            for (t, v) in j.iter_mut().zip(self.bracket_of(&self.bracket_of(&z, &x), &y)) {
                *t += v;
            }
            j.iter().all(Zero::is_zero)
        })
    }

    fn check_jacobi(&self) -> Result<(), LargeError> {
        let mut sum: Vec<(usize, Rational)> = Vec::new();
        let mut candidates: Vec<usize> = Vec::new();
        for &(a, b) in self.brackets.keys() {
            if a > b {
                continue;
            }
            candidates.clear();
            candidates.extend(self.partners(a));
            candidates.extend(self.partners(b));
            for (k, _) in self.bracket(a, b) {
                candidates.extend(self.partners(*k));
            }
            candidates.sort_unstable();
            candidates.dedup();
            for &c in &candidates {
                if c == a || c == b {
                    continue;
                }
                // J is totally antisymmetric: each triple {p < q < r} is
                // evaluated once, from the first of its pairs (p,q), (p,r),
                // (q,r) whose candidates hold the third index. A triple with
                // a nonzero term [[x,y],z] is reached from {x,y} (z is a
                // partner of some k in [e_x, e_y]), so none is missed.
                let mut t = [a, b, c];
                t.sort_unstable();
                let [p, q, r] = t;
                let first = [((p, q), r), ((p, r), q), ((q, r), p)]
                    .into_iter()
                    .find(|&((x, y), w)| self.reaches(x, y, w))
                    .map(|(pair, _)| pair);
                if first != Some((a, b)) {
                    continue;
                }
                sum.clear();
                self.double(p, q, r, &mut sum);
                self.double(q, r, p, &mut sum);
                self.double(r, p, q, &mut sum);
                if let Some((k, v)) = sum.iter().find(|(_, v)| !v.is_zero()) {
                    return Err(LargeError::Algebra(format!(
                        "the Jacobi identity fails for (e_{p}, e_{q}, e_{r}): component {k} of [[e_a,e_b],e_c] + [[e_b,e_c],e_a] + [[e_c,e_a],e_b] is {v}"
                    )));
                }
            }
        }
        Ok(())
    }
}
