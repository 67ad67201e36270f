//! Discovery of polynomial Casimirs by exact linear algebra.
//!
//! A polynomial `C` is a Casimir iff `{C, mu_j} = 0` for every coordinate.
//! The bracket with a linear function preserves the degree, so homogeneous
//! components of a Casimir are Casimirs and the search runs degree by degree:
//! the unknowns are the coefficients of the degree-`d` monomials and every
//! coefficient of every `{C, mu_j}` is one linear equation. Solutions that are
//! products of Casimirs found at lower degree are dropped, so what is returned
//! generates the Casimirs up to the degree searched.

use crate::bracket::lie_poisson_bracket;
use algebra::LieAlgebra;
use exact::{monomial_count, monomials_of_degree, Monomial, Poly, Rational};
use num_traits::Zero;
use std::collections::BTreeMap;

/// What a discovery run found and how far it looked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DiscoveryReport {
    /// Generators found, lowest degree first.
    pub casimirs: Vec<Poly>,
    /// Highest degree fully searched.
    pub degree_searched: u32,
    /// Degrees skipped because they needed more unknowns than allowed.
    pub skipped_degrees: Vec<u32>,
}

/// Sparse row reduction: keep rows in echelon form keyed by leading column.
///
/// Written by hand because the equation rows are very sparse (a handful of
/// structure constants each) and exact, which dense float libraries cannot
/// exploit or provide; dense exact elimination made discovery on a
/// 20-dimensional algebra take minutes.
struct Echelon {
    rows: BTreeMap<usize, BTreeMap<usize, Rational>>,
}

impl Echelon {
    fn new() -> Self {
        Echelon { rows: BTreeMap::new() }
    }

    /// Reduce `row` against the pivots and keep it if anything is left;
    /// returns whether it was independent of the rows already held.
    fn insert(&mut self, mut row: BTreeMap<usize, Rational>) -> bool {
        row.retain(|_, v| !v.is_zero());
        loop {
            let Some((&lead, lead_value)) = row.iter().next() else { return false };
            let lead_value = lead_value.clone();
            match self.rows.get(&lead) {
                Some(pivot) => {
                    let factor = &lead_value / &pivot[&lead];
                    for (c, v) in pivot {
                        let entry = row.entry(*c).or_insert_with(Rational::zero);
                        *entry -= &factor * v;
                        if entry.is_zero() {
                            row.remove(c);
                        }
                    }
                }
                None => {
                    self.rows.insert(lead, row);
                    return true;
                }
            }
        }
    }

    /// Basis of the null space of the rows held, over `ncols` unknowns, by a
    /// sparse reduction to reduced row echelon form.
    fn null_space(mut self, ncols: usize) -> Vec<BTreeMap<usize, Rational>> {
        let leads: Vec<usize> = self.rows.keys().rev().copied().collect();
        for &lead in &leads {
            // Normalise the pivot row, then clear its column from rows with a
            // smaller lead (rows with a larger lead cannot contain it).
            let mut pivot = self.rows.remove(&lead).expect("lead present");
            let inv = pivot[&lead].recip();
            for v in pivot.values_mut() {
                *v *= &inv;
            }
            for (_, row) in self.rows.range_mut(..lead) {
                let Some(f) = row.get(&lead).cloned() else { continue };
                for (c, v) in &pivot {
                    let entry = row.entry(*c).or_insert_with(Rational::zero);
                    *entry -= &f * v;
                    if entry.is_zero() {
                        row.remove(c);
                    }
                }
            }
            self.rows.insert(lead, pivot);
        }
        let mut null: BTreeMap<usize, BTreeMap<usize, Rational>> = (0..ncols)
            .filter(|c| !self.rows.contains_key(c))
            .map(|c| (c, BTreeMap::from([(c, Rational::from(1))])))
            .collect();
        for (lead, row) in &self.rows {
            for (c, v) in row {
                if c != lead {
                    if let Some(vec) = null.get_mut(c) {
                        vec.insert(*lead, -v.clone());
                    }
                }
            }
        }
        null.into_values().collect()
    }
}

/// Discover polynomial Casimirs of degree `1..=max_degree`.
///
/// Degrees needing more than `max_unknowns` monomials are skipped (and
/// reported), so the run time stays bounded on large algebras.
///
/// ```
/// use algebra::builtin;
/// use casimir::discover_casimirs;
/// use exact::{parse_expression, Symbols};
/// let so3 = builtin("so3").unwrap().algebra;
/// let report = discover_casimirs(&so3, 4, 1000);
/// // Exactly one generator, |Pi|^2 (up to scale); |Pi|^4 is a product.
/// assert_eq!(report.casimirs.len(), 1);
/// let s = Symbols::new(so3.coordinates());
/// let expected = parse_expression("Pi1^2 + Pi2^2 + Pi3^2", &s).unwrap();
/// let c = &report.casimirs[0];
/// let ratio = c.coefficient(&[2, 0, 0]);
/// assert_eq!(c, &expected.scale(&ratio));
/// ```
pub fn discover_casimirs(algebra: &LieAlgebra, max_degree: u32, max_unknowns: usize) -> DiscoveryReport {
    let n = algebra.dim();
    let mut found: Vec<Poly> = Vec::new();
    let mut skipped = Vec::new();
    let mut degree_searched = 0;
    for d in 1..=max_degree {
        // Count before enumerating: a 60-dimensional algebra has C(67, 8),
        // about 6.6e9, monomials of degree 8, which took more than 4 GB to list.
        if monomial_count(n, d) > max_unknowns as u128 {
            skipped.push(d);
            continue;
        }
        let monomials = monomials_of_degree(n, d as u16);
        // Column j: the brackets {x^m_j, mu_i} for all i; equation rows are
        // indexed by (i, monomial of the result).
        let mut rows: BTreeMap<(usize, Monomial), BTreeMap<usize, Rational>> = BTreeMap::new();
        for (j, m) in monomials.iter().enumerate() {
            let xm = Poly::monomial(Rational::from_integer(1.into()), m.clone());
            for i in 0..n {
                let b = lie_poisson_bracket(algebra, &xm, &Poly::var(n, i));
                for (mono, c) in b.terms() {
                    rows.entry((i, mono.clone())).or_default().insert(j, c.clone());
                }
            }
        }
        // Multi-modular first (exact and complete when it answers, see
        // exact::sparse_null_space); rational elimination otherwise.
        let sparse: Vec<exact::SparseRow> =
            rows.values().map(|r| r.iter().map(|(c, v)| (*c, v.clone())).collect()).collect();
        let solutions: Vec<BTreeMap<usize, Rational>> = match exact::sparse_null_space(&sparse, monomials.len()) {
            Some(null) => {
                null.into_iter().map(|v| v.into_iter().enumerate().filter(|(_, x)| !x.is_zero()).collect()).collect()
            }
            None => {
                let mut echelon = Echelon::new();
                for (_, row) in rows {
                    echelon.insert(row);
                }
                echelon.null_space(monomials.len())
            }
        };
        if !solutions.is_empty() {
            // Keep only solutions independent of the products of earlier
            // generators of total degree d.
            let index: BTreeMap<&[u16], usize> = monomials.iter().enumerate().map(|(i, m)| (m.as_slice(), i)).collect();
            let mut span = Echelon::new();
            for p in products_of_degree(&found, d) {
                span.insert(p.terms().filter_map(|(m, c)| Some((*index.get(m.as_slice())?, c.clone()))).collect());
            }
            for v in solutions {
                if span.insert(v.clone()) {
                    let mut p = Poly::zero(n);
                    for (i, c) in &v {
                        p = p.add(&Poly::monomial(c.clone(), monomials[*i].clone()));
                    }
                    found.push(normalise(p));
                    if found.len() > max_unknowns {
                        break;
                    }
                }
            }
        }
        degree_searched = d;
    }
    DiscoveryReport { casimirs: found, degree_searched, skipped_degrees: skipped }
}

/// Scale so that coefficients are coprime integers with a positive leading one.
fn normalise(p: Poly) -> Poly {
    let coefficients: Vec<Rational> = p.terms().map(|(_, c)| c.clone()).collect();
    let mut s = exact::integer_scale(&coefficients);
    if coefficients.first().is_some_and(Rational::is_negative) {
        s = -s;
    }
    p.scale(&s)
}

fn products_of_degree(generators: &[Poly], d: u32) -> Vec<Poly> {
    // All products of generators (with repetition) of total degree exactly d.
    fn rec(gens: &[(Poly, u32)], start: usize, remaining: u32, cur: Poly, out: &mut Vec<Poly>) {
        if remaining == 0 {
            out.push(cur);
            return;
        }
        for i in start..gens.len() {
            let (g, deg) = &gens[i];
            if *deg <= remaining && *deg > 0 {
                rec(gens, i, remaining - deg, cur.mul(g), out);
            }
        }
    }
    let Some(first) = generators.first() else { return Vec::new() };
    let n = first.nvars();
    let gens: Vec<(Poly, u32)> = generators.iter().map(|g| (g.clone(), g.total_degree())).collect();
    let mut out = Vec::new();
    rec(&gens, 0, d, Poly::constant(n, Rational::from_integer(1.into())), &mut out);
    // A product equal to a single generator of degree d is the generator
    // itself: only genuine products (two or more factors) are wanted, and the
    // recursion produces a single factor only when a generator has degree d,
    // which cannot happen because generators of degree d are being searched.
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_algebra_skips_large_degrees_quickly() {
        // Regression: a 60-dimensional abelian algebra with discovery_degree 8
        // listed billions of monomials (over 4 GB). Degree 1 has 60 unknowns
        // (every coordinate is a Casimir of an abelian algebra), degree 2 has
        // C(61, 2) = 1830, and from degree 3 on (C(62, 3) = 37820) all are skipped.
        let names: Vec<String> = (0..60).map(|i| format!("x{i}")).collect();
        let algebra = LieAlgebra::from_structure_constants("abelian", &names, &[]).unwrap();
        let report = discover_casimirs(&algebra, 8, 2000);
        assert_eq!(report.skipped_degrees, vec![3, 4, 5, 6, 7, 8]);
        assert_eq!(report.casimirs.len(), 60);
    }
}
