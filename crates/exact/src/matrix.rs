//! Dense matrices of exact rationals with Gaussian elimination.
//!
//! The engine's matrices are small (the dimension of the Lie algebra), so a
//! dense row-major `Vec` is the right shape; what matters is exactness, which
//! floating-point libraries such as nalgebra cannot give. That is why this
//! small hand-written module exists.

use crate::number::{rational_to_f64, Rational};
use num_traits::{One, Zero};
use outcome::Sign;
use std::fmt;

/// A dense `rows × cols` matrix of rationals, row-major.
#[derive(Clone, PartialEq, Eq)]
pub struct Matrix {
    rows: usize,
    cols: usize,
    data: Vec<Rational>,
}

/// The solution set `{x0 + N t}` of a linear system `A x = b`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AffineSolution {
    /// One particular solution (free variables set to zero).
    pub particular: Vec<Rational>,
    /// A basis of the null space of `A`, one vector per free direction.
    pub directions: Vec<Vec<Rational>>,
}

impl fmt::Debug for Matrix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "Matrix {}x{} [", self.rows, self.cols)?;
        for i in 0..self.rows {
            let row: Vec<String> = (0..self.cols).map(|j| self[(i, j)].to_string()).collect();
            writeln!(f, "  [{}]", row.join(", "))?;
        }
        write!(f, "]")
    }
}

impl std::ops::Index<(usize, usize)> for Matrix {
    type Output = Rational;
    fn index(&self, (i, j): (usize, usize)) -> &Rational {
        &self.data[i * self.cols + j]
    }
}

impl std::ops::IndexMut<(usize, usize)> for Matrix {
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut Rational {
        &mut self.data[i * self.cols + j]
    }
}

impl Matrix {
    /// The zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        // An iterator, not `vec![zero; n]`: that clones the element n times.
        Matrix { rows, cols, data: std::iter::repeat_with(|| Rational::ZERO).take(rows * cols).collect() }
    }

    /// The identity matrix.
    pub fn identity(n: usize) -> Self {
        let mut m = Self::zeros(n, n);
        for i in 0..n {
            m[(i, i)] = Rational::one();
        }
        m
    }

    /// Build from rows; all rows must have the same length.
    ///
    /// # Panics
    /// If the rows have different lengths (a programming error, not input).
    pub fn from_rows(rows: &[Vec<Rational>]) -> Self {
        let r = rows.len();
        let c = rows.first().map_or(0, |x| x.len());
        assert!(rows.iter().all(|x| x.len() == c), "ragged rows");
        Matrix { rows: r, cols: c, data: rows.iter().flatten().cloned().collect() }
    }

    /// Build a matrix whose columns are the given vectors (`n` rows).
    pub fn from_columns(n: usize, columns: &[Vec<Rational>]) -> Self {
        let mut m = Self::zeros(n, columns.len());
        for (j, col) in columns.iter().enumerate() {
            assert_eq!(col.len(), n, "column length");
            for i in 0..n {
                m[(i, j)] = col[i].clone();
            }
        }
        m
    }

    /// Build from a function of the indices.
    pub fn from_fn(rows: usize, cols: usize, mut f: impl FnMut(usize, usize) -> Rational) -> Self {
        let mut data = Vec::with_capacity(rows * cols);
        for i in 0..rows {
            for j in 0..cols {
                data.push(f(i, j));
            }
        }
        Matrix { rows, cols, data }
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.cols
    }

    /// Row `i` as a vector.
    pub fn row(&self, i: usize) -> Vec<Rational> {
        self.data[i * self.cols..(i + 1) * self.cols].to_vec()
    }

    /// Column `j` as a vector.
    pub fn column(&self, j: usize) -> Vec<Rational> {
        (0..self.rows).map(|i| self[(i, j)].clone()).collect()
    }

    /// All rows.
    pub fn to_rows(&self) -> Vec<Vec<Rational>> {
        (0..self.rows).map(|i| self.row(i)).collect()
    }

    /// The transpose.
    pub fn transpose(&self) -> Self {
        Self::from_fn(self.cols, self.rows, |i, j| self[(j, i)].clone())
    }

    /// Whether every entry is zero.
    pub fn is_zero(&self) -> bool {
        self.data.iter().all(Zero::is_zero)
    }

    /// Whether the matrix equals its transpose.
    pub fn is_symmetric(&self) -> bool {
        self.rows == self.cols && (0..self.rows).all(|i| (0..i).all(|j| self[(i, j)] == self[(j, i)]))
    }

    /// `(self + selfᵀ)/2`.
    pub fn symmetric_part(&self) -> Self {
        assert_eq!(self.rows, self.cols);
        let half = Rational::new_small(1, 2);
        let mut out = self.clone();
        for i in 0..self.rows {
            for j in i + 1..self.cols {
                if self[(i, j)] != self[(j, i)] {
                    let v = (&self[(i, j)] + &self[(j, i)]) * &half;
                    out[(j, i)] = v.clone();
                    out[(i, j)] = v;
                }
            }
        }
        out
    }

    /// Matrix product.
    ///
    /// # Panics
    /// On a dimension mismatch.
    pub fn mul(&self, other: &Matrix) -> Matrix {
        assert_eq!(self.cols, other.rows, "dimension mismatch in product");
        let mut out = Matrix::zeros(self.rows, other.cols);
        for i in 0..self.rows {
            for k in 0..self.cols {
                let a = &self[(i, k)];
                if a.is_zero() {
                    continue;
                }
                for j in 0..other.cols {
                    let b = &other[(k, j)];
                    if !b.is_zero() {
                        out[(i, j)] += a * b;
                    }
                }
            }
        }
        out
    }

    /// Matrix–vector product.
    pub fn mul_vec(&self, v: &[Rational]) -> Vec<Rational> {
        assert_eq!(self.cols, v.len());
        (0..self.rows)
            .map(|i| {
                let mut s = Rational::zero();
                for j in 0..self.cols {
                    let a = &self[(i, j)];
                    if !a.is_zero() && !v[j].is_zero() {
                        s += a * &v[j];
                    }
                }
                s
            })
            .collect()
    }

    /// Entrywise sum.
    pub fn add(&self, other: &Matrix) -> Matrix {
        assert_eq!((self.rows, self.cols), (other.rows, other.cols));
        Matrix {
            rows: self.rows,
            cols: self.cols,
            data: self.data.iter().zip(&other.data).map(|(a, b)| a + b).collect(),
        }
    }

    /// Entrywise difference.
    pub fn sub(&self, other: &Matrix) -> Matrix {
        assert_eq!((self.rows, self.cols), (other.rows, other.cols));
        Matrix {
            rows: self.rows,
            cols: self.cols,
            data: self.data.iter().zip(&other.data).map(|(a, b)| a - b).collect(),
        }
    }

    /// Multiply every entry by `s`.
    pub fn scale(&self, s: &Rational) -> Matrix {
        Matrix { rows: self.rows, cols: self.cols, data: self.data.iter().map(|a| a * s).collect() }
    }

    /// `self += s * other`.
    pub fn add_scaled_assign(&mut self, s: &Rational, other: &Matrix) {
        assert_eq!((self.rows, self.cols), (other.rows, other.cols));
        if s.is_zero() {
            return;
        }
        for (a, b) in self.data.iter_mut().zip(&other.data) {
            if !b.is_zero() {
                *a += s * b;
            }
        }
    }

    /// The nearest double of each entry, row-major.
    pub fn to_f64_vec(&self) -> Vec<f64> {
        self.data.iter().map(rational_to_f64).collect()
    }

    /// As an nalgebra matrix of doubles.
    pub fn to_dmatrix(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::from_fn(self.rows, self.cols, |i, j| rational_to_f64(&self[(i, j)]))
    }

    /// Reduced row echelon form; returns the pivot columns.
    fn rref_in_place(&mut self) -> Vec<usize> {
        let mut pivots = Vec::new();
        let mut r = 0;
        for c in 0..self.cols {
            if r == self.rows {
                break;
            }
            let Some(p) = (r..self.rows).find(|&i| !self[(i, c)].is_zero()) else {
                continue;
            };
            if p != r {
                for j in 0..self.cols {
                    self.data.swap(p * self.cols + j, r * self.cols + j);
                }
            }
            let inv = self[(r, c)].recip();
            for j in c..self.cols {
                let v = &self[(r, j)] * &inv;
                self[(r, j)] = v;
            }
            for i in 0..self.rows {
                if i == r || self[(i, c)].is_zero() {
                    continue;
                }
                let f = self[(i, c)].clone();
                for j in c..self.cols {
                    if !self[(r, j)].is_zero() {
                        let v = &self[(r, j)] * &f;
                        self[(i, j)] -= v;
                    }
                }
            }
            pivots.push(c);
            r += 1;
        }
        pivots
    }

    /// The rank.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// let q = |n: i64| Rational::from_integer(n.into());
    /// let m = Matrix::from_rows(&[vec![q(1), q(2)], vec![q(2), q(4)]]);
    /// assert_eq!(m.rank(), 1);
    /// ```
    pub fn rank(&self) -> usize {
        self.clone().rref_in_place().len()
    }

    /// Indices of a maximal set of linearly independent columns (the pivot
    /// columns of the row echelon form), in increasing order.
    pub fn pivot_columns(&self) -> Vec<usize> {
        self.clone().rref_in_place()
    }

    /// A basis of the null space `{x : A x = 0}`.
    pub fn null_space(&self) -> Vec<Vec<Rational>> {
        let mut m = self.clone();
        let pivots = m.rref_in_place();
        let free: Vec<usize> = (0..self.cols).filter(|c| !pivots.contains(c)).collect();
        free.iter()
            .map(|&f| {
                let mut v = vec![Rational::zero(); self.cols];
                v[f] = Rational::one();
                for (r, &pc) in pivots.iter().enumerate() {
                    v[pc] = -m[(r, f)].clone();
                }
                v
            })
            .collect()
    }

    /// A basis of the null space `{x : A x = 0}` with bounded coefficients:
    /// like [`Self::null_space`] (one vector `e_f - sum_i c_if e_{p_i}` per
    /// free column `f`, `p_i` the pivot columns), but with the pivot columns
    /// chosen so that every coefficient satisfies `|c_if| <= 1`.
    ///
    /// The pivots of the row echelon form are the first independent
    /// columns, and the coefficients can be as large as the rows are badly
    /// scaled: the null space of `(a, 1, 1)` comes out as `(-1/a, 1, 0)`,
    /// `(-1/a, 0, 1)`, nearly parallel, with the Gram matrix
    /// `1/a^2 + [[1, 0], [0, 1]]` that rounds to a singular matrix of doubles
    /// once `1/a^2 >= 2^53`. Here, while some `|c_if| > 1`, the free column
    /// `f` replaces the pivot `p_i` (the largest such coefficient first): each
    /// exchange multiplies the magnitude of the determinant of the pivot
    /// columns of `A` by `|c_if| > 1`, so the exchanges end, at a choice of
    /// pivots of locally maximal volume. The basis matrix is then
    /// `Z = [I; -C]` up to a permutation of the rows, with `|C| <= 1`
    /// entrywise, so the eigenvalues of `Z^T Z = I + C^T C` lie in
    /// `[1, 1 + rank * nullity]`: well conditioned, whatever the scale of
    /// `A`'s rows (which does not change the basis: neither does any
    /// invertible combination of the rows), and as sparse as the echelon
    /// basis.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// let q = |n: i64| Rational::from(n);
    /// let a = Rational::new_small(1, 1_000_000_000);
    /// let g = Matrix::from_rows(&[vec![a.clone(), q(1), q(1)]]);
    /// assert_eq!(g.null_space()[0], vec![q(-1_000_000_000), q(1), q(0)]);
    /// let basis = g.bounded_null_space();
    /// assert_eq!(basis, vec![vec![q(1), -a.clone(), q(0)], vec![q(0), q(-1), q(1)]]);
    /// ```
    pub fn bounded_null_space(&self) -> Vec<Vec<Rational>> {
        let mut m = self.clone();
        let mut pivots = m.rref_in_place();
        let rank = pivots.len();
        let one = Rational::one();
        loop {
            // The largest coefficient above 1 in magnitude, if any.
            let mut best: Option<(usize, usize, Rational)> = None;
            for (i, _) in pivots.iter().enumerate() {
                for j in (0..self.cols).filter(|j| !pivots.contains(j)) {
                    let v = m[(i, j)].abs();
                    if v > one && best.as_ref().is_none_or(|(_, _, b)| &v > b) {
                        best = Some((i, j, v));
                    }
                }
            }
            let Some((i, j, _)) = best else { break };
            // Gauss–Jordan step on (i, j): column j becomes the pivot of row i.
            let inv = m[(i, j)].recip();
            for c in 0..self.cols {
                if !m[(i, c)].is_zero() {
                    let v = &m[(i, c)] * &inv;
                    m[(i, c)] = v;
                }
            }
            for r in (0..rank).filter(|&r| r != i) {
                let f = m[(r, j)].clone();
                if f.is_zero() {
                    continue;
                }
                for c in 0..self.cols {
                    if !m[(i, c)].is_zero() {
                        let v = &m[(i, c)] * &f;
                        m[(r, c)] -= v;
                    }
                }
            }
            pivots[i] = j;
        }
        (0..self.cols)
            .filter(|c| !pivots.contains(c))
            .map(|f| {
                let mut v = vec![Rational::zero(); self.cols];
                v[f] = Rational::one();
                for (r, &pc) in pivots.iter().enumerate() {
                    v[pc] = -m[(r, f)].clone();
                }
                v
            })
            .collect()
    }

    /// All solutions of `A x = b`, or `None` when the system is inconsistent.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// let q = |n: i64| Rational::from_integer(n.into());
    /// // x + y = 2 has the solutions (2, 0) + t (-1, 1).
    /// let a = Matrix::from_rows(&[vec![q(1), q(1)]]);
    /// let s = a.solve_affine(&[q(2)]).unwrap();
    /// assert_eq!(s.particular, vec![q(2), q(0)]);
    /// assert_eq!(s.directions, vec![vec![q(-1), q(1)]]);
    /// ```
    pub fn solve_affine(&self, b: &[Rational]) -> Option<AffineSolution> {
        assert_eq!(b.len(), self.rows);
        let mut aug = Matrix::zeros(self.rows, self.cols + 1);
        for i in 0..self.rows {
            for j in 0..self.cols {
                aug[(i, j)] = self[(i, j)].clone();
            }
            aug[(i, self.cols)] = b[i].clone();
        }
        let pivots = aug.rref_in_place();
        if pivots.contains(&self.cols) {
            return None;
        }
        let mut particular = vec![Rational::zero(); self.cols];
        for (r, &pc) in pivots.iter().enumerate() {
            particular[pc] = aug[(r, self.cols)].clone();
        }
        Some(AffineSolution { particular, directions: self.null_space() })
    }

    /// Inverse of a square matrix, or `None` if singular.
    pub fn inverse(&self) -> Option<Matrix> {
        assert_eq!(self.rows, self.cols);
        let n = self.rows;
        if n == 0 {
            return Some(Matrix::zeros(0, 0));
        }
        let mut aug = Matrix::zeros(n, 2 * n);
        for i in 0..n {
            for j in 0..n {
                aug[(i, j)] = self[(i, j)].clone();
            }
            aug[(i, n + i)] = Rational::one();
        }
        let pivots = aug.rref_in_place();
        if pivots.len() < n || pivots[n - 1] != n - 1 {
            return None;
        }
        Some(Matrix::from_fn(n, n, |i, j| aug[(i, n + j)].clone()))
    }

    /// Exact symmetric LDLᵀ inertia test: `Some(+1)` if positive definite,
    /// `Some(-1)` if negative definite, `None` otherwise.
    ///
    /// Uses exact Gaussian elimination without pivoting: a symmetric matrix is
    /// positive definite iff all its leading pivots are positive (Sylvester's
    /// criterion in its elimination form); negative definite iff `-A` is
    /// positive definite.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// let q = |n: i64| Rational::from_integer(n.into());
    /// let a = Matrix::from_rows(&[vec![q(2), q(1)], vec![q(1), q(2)]]);
    /// assert_eq!(a.definiteness(), Some(outcome::Sign::Positive));
    /// assert_eq!(a.scale(&q(-1)).definiteness(), Some(outcome::Sign::Negative));
    /// let b = Matrix::from_rows(&[vec![q(1), q(2)], vec![q(2), q(1)]]);
    /// assert_eq!(b.definiteness(), None);
    /// ```
    pub fn definiteness(&self) -> Option<Sign> {
        assert!(self.is_symmetric(), "definiteness of a non-symmetric matrix");
        if self.rows == 0 {
            return None;
        }
        if positive_definite_exact(self) {
            Some(Sign::Positive)
        } else if positive_definite_exact(&self.scale(&-Rational::one())) {
            Some(Sign::Negative)
        } else {
            None
        }
    }
}

impl Matrix {
    /// Whether `self` (or `-self` for a negative sign) is positive definite,
    /// exactly. One LDLᵀ pass instead of the two [`Self::definiteness`] may take.
    pub fn is_definite_with_sign(&self, sign: Sign) -> bool {
        assert!(self.is_symmetric(), "definiteness of a non-symmetric matrix");
        if self.rows == 0 {
            return false;
        }
        if sign.is_positive() {
            positive_definite_exact(self)
        } else {
            positive_definite_exact(&self.scale(&-Rational::one()))
        }
    }

    /// Exact positive-semidefiniteness test for a symmetric matrix.
    ///
    /// Symmetric elimination with diagonal pivoting: a negative diagonal entry
    /// proves indefiniteness; a positive one is eliminated (the matrix is PSD
    /// iff the Schur complement is); when every remaining diagonal entry is
    /// zero the matrix is PSD iff the remaining block is zero. This handles
    /// singular matrices (shared null directions) exactly, without tolerance.
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// let q = |n: i64| Rational::from(n);
    /// // [[1, 1], [1, 1]] is PSD and singular; [[0, 1], [1, 0]] is indefinite.
    /// assert!(Matrix::from_rows(&[vec![q(1), q(1)], vec![q(1), q(1)]]).is_positive_semidefinite());
    /// assert!(!Matrix::from_rows(&[vec![q(0), q(1)], vec![q(1), q(0)]]).is_positive_semidefinite());
    /// assert!(Matrix::zeros(3, 3).is_positive_semidefinite());
    /// ```
    pub fn is_positive_semidefinite(&self) -> bool {
        assert!(self.is_symmetric(), "semidefiniteness of a non-symmetric matrix");
        let n = self.rows;
        let mut m = self.clone();
        let mut active: Vec<usize> = (0..n).collect();
        while !active.is_empty() {
            if active.iter().any(|&i| m[(i, i)].is_negative()) {
                return false;
            }
            let Some(pos) = active.iter().position(|&i| m[(i, i)].is_positive()) else {
                // All remaining diagonal entries are zero: PSD iff the block is zero.
                return active.iter().all(|&i| active.iter().all(|&j| m[(i, j)].is_zero()));
            };
            let p = active.swap_remove(pos);
            eliminate(&mut m, &active, p);
        }
        true
    }
}

/// One step of symmetric Gaussian elimination on a nonzero diagonal pivot
/// `p`: the rows and columns in `active` become the Schur complement of
/// `m[(p, p)]` (only the entries within `active` are updated).
fn eliminate(m: &mut Matrix, active: &[usize], p: usize) {
    let pivot = m[(p, p)].clone();
    for &i in active {
        if m[(i, p)].is_zero() {
            continue;
        }
        let f = &m[(i, p)] / &pivot;
        for &j in active {
            if !m[(p, j)].is_zero() {
                let v = &f * &m[(p, j)];
                m[(i, j)] -= v;
            }
        }
    }
}

/// The inertia of a symmetric matrix: how many eigenvalues are positive,
/// negative and zero (Sylvester's law: congruence preserves these counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inertia {
    /// Positive eigenvalues.
    pub positive: usize,
    /// Negative eigenvalues.
    pub negative: usize,
    /// Zero eigenvalues.
    pub zero: usize,
}

/// An exact congruence `P = L D L^T` (`L` unit lower triangular, `D`
/// diagonal and positive) applied to a second symmetric matrix:
/// `C = L^{-1} Q L^{-T}`. The generalized eigenvalues of `(Q, P)` are the
/// eigenvalues of `D^{-1/2} C D^{-1/2}`, which floating point resolves to
/// round-off in `|l_max|` however ill-conditioned `P` is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Congruence {
    /// The pivots `D`.
    pub d: Vec<Rational>,
    /// The factor `L`.
    pub l: Matrix,
    /// `L^{-1} Q L^{-T}`.
    pub c: Matrix,
}

impl Matrix {
    /// The exact inertia of a symmetric matrix, by symmetric elimination
    /// with diagonal pivots, and `2 × 2` pivots `[[0, b], [b, 0]]` (one
    /// positive and one negative eigenvalue) when every remaining diagonal
    /// entry is zero.
    ///
    /// ```
    /// use exact::{Inertia, Matrix, Rational};
    /// let q = |n: i64| Rational::from(n);
    /// // [[0, 1, 0], [1, 0, 0], [0, 0, 0]]: eigenvalues 1, -1, 0.
    /// let m = Matrix::from_rows(&[vec![q(0), q(1), q(0)], vec![q(1), q(0), q(0)], vec![q(0), q(0), q(0)]]);
    /// assert_eq!(m.inertia(), Inertia { positive: 1, negative: 1, zero: 1 });
    /// ```
    pub fn inertia(&self) -> Inertia {
        assert!(self.is_symmetric(), "inertia of a non-symmetric matrix");
        let mut m = self.clone();
        let mut active: Vec<usize> = (0..self.rows).collect();
        let mut inertia = Inertia { positive: 0, negative: 0, zero: 0 };
        while !active.is_empty() {
            if let Some(pos) = active.iter().position(|&i| !m[(i, i)].is_zero()) {
                let p = active.swap_remove(pos);
                if m[(p, p)].is_positive() {
                    inertia.positive += 1;
                } else {
                    inertia.negative += 1;
                }
                eliminate(&mut m, &active, p);
                continue;
            }
            // Every remaining diagonal entry is zero.
            let pair = active
                .iter()
                .enumerate()
                .find_map(|(a, &i)| active.iter().position(|&j| !m[(i, j)].is_zero()).map(|b| (a, b)));
            let Some((a, b)) = pair else {
                inertia.zero += active.len();
                break;
            };
            let (i, j) = (active[a], active[b]);
            active.retain(|&k| k != i && k != j);
            inertia.positive += 1;
            inertia.negative += 1;
            // Eliminate with the pivot block E = [[0, e], [e, 0]],
            // E^{-1} = [[0, 1/e], [1/e, 0]]: M -= C E^{-1} C^T.
            let e_inv = m[(i, j)].recip();
            for &r in &active {
                for &c in &active {
                    let v = (&m[(r, i)] * &m[(j, c)] + &m[(r, j)] * &m[(i, c)]) * &e_inv;
                    if !v.is_zero() {
                        m[(r, c)] -= v;
                    }
                }
            }
        }
        inertia
    }

    /// `P = L D L^T` exactly (no pivoting) and `C = L^{-1} Q L^{-T}`, or
    /// `None` unless every pivot is positive (`P` positive definite).
    ///
    /// ```
    /// use exact::{Matrix, Rational};
    /// let q = |n: i64| Rational::from(n);
    /// let p = Matrix::from_rows(&[vec![q(2), q(1)], vec![q(1), q(1)]]);
    /// let qm = Matrix::from_rows(&[vec![q(1), q(0)], vec![q(0), q(0)]]);
    /// let c = p.congruence(&qm).unwrap();
    /// // L D L^T = P and L C L^T = Q, exactly.
    /// let d = Matrix::from_fn(2, 2, |i, j| if i == j { c.d[i].clone() } else { q(0) });
    /// assert_eq!(c.l.mul(&d).mul(&c.l.transpose()), p);
    /// assert_eq!(c.l.mul(&c.c).mul(&c.l.transpose()), qm);
    /// ```
    pub fn congruence(&self, q: &Matrix) -> Option<Congruence> {
        let n = self.rows;
        assert!(self.is_symmetric() && q.is_symmetric() && q.rows == n, "congruence of non-matching matrices");
        let (d, l) = ldl_positive(self)?;
        // X = L^{-1} Q (forward substitution on each column), C = L^{-1} X^T.
        let forward = |b: &Matrix| -> Matrix {
            let mut x = b.clone();
            for i in 0..n {
                for k in 0..i {
                    if l[(i, k)].is_zero() {
                        continue;
                    }
                    for j in 0..n {
                        if !x[(k, j)].is_zero() {
                            let v = &l[(i, k)] * &x[(k, j)];
                            x[(i, j)] -= v;
                        }
                    }
                }
            }
            x
        };
        let c = forward(&forward(q).transpose());
        Some(Congruence { d, l, c })
    }
}

fn positive_definite_exact(a: &Matrix) -> bool {
    ldl_positive(a).is_some()
}

/// `A = L D L^T` by exact elimination without pivoting: the pivots `D` and
/// the unit lower factor `L`, or `None` at the first pivot that is not
/// positive (then `A` is not positive definite, by Sylvester's criterion).
fn ldl_positive(a: &Matrix) -> Option<(Vec<Rational>, Matrix)> {
    let n = a.rows;
    let mut m = a.clone();
    let mut l = Matrix::identity(n);
    let mut d = Vec::with_capacity(n);
    for k in 0..n {
        let pivot = m[(k, k)].clone();
        if !pivot.is_positive() {
            return None;
        }
        for i in (k + 1)..n {
            if m[(i, k)].is_zero() {
                continue;
            }
            let f = &m[(i, k)] / &pivot;
            for j in (k + 1)..n {
                if !m[(k, j)].is_zero() {
                    let v = &f * &m[(k, j)];
                    m[(i, j)] -= v;
                }
            }
            l[(i, k)] = f;
        }
        d.push(pivot);
    }
    Some((d, l))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(n: i64) -> Rational {
        Rational::from_integer(n.into())
    }

    #[test]
    fn null_space_vectors_are_annihilated() {
        let a = Matrix::from_rows(&[vec![q(1), q(2), q(3)], vec![q(2), q(4), q(6)], vec![q(0), q(1), q(1)]]);
        let ns = a.null_space();
        assert_eq!(ns.len(), 1);
        for v in &ns {
            assert!(a.mul_vec(v).iter().all(Zero::is_zero));
        }
    }

    #[test]
    fn inconsistent_system_has_no_solution() {
        let a = Matrix::from_rows(&[vec![q(1), q(1)], vec![q(1), q(1)]]);
        assert!(a.solve_affine(&[q(1), q(2)]).is_none());
    }

    #[test]
    fn inverse_times_matrix_is_identity() {
        let a = Matrix::from_rows(&[vec![q(2), q(1)], vec![q(7), q(4)]]);
        let inv = a.inverse().unwrap();
        assert_eq!(a.mul(&inv), Matrix::identity(2));
        let singular = Matrix::from_rows(&[vec![q(1), q(2)], vec![q(2), q(4)]]);
        assert!(singular.inverse().is_none());
        // Regression: the empty matrix (no independent conserved gradient at
        // mu_e = 0) panicked with an index underflow.
        assert_eq!(Matrix::zeros(0, 0).inverse(), Some(Matrix::zeros(0, 0)));
    }

    #[test]
    fn semidefinite_test_pairs() {
        // diag(1, 0) with a coupling: [[1, 2], [2, 4]] is PSD (rank 1), but
        // [[1, 2], [2, 3.99]] is not; [[0, 0], [0, -1]] is not.
        let a = Matrix::from_rows(&[vec![q(1), q(2)], vec![q(2), q(4)]]);
        assert!(a.is_positive_semidefinite());
        let mut b = a.clone();
        b[(1, 1)] = Rational::new_small(399, 100);
        assert!(!b.is_positive_semidefinite());
        let c = Matrix::from_rows(&[vec![q(0), q(0)], vec![q(0), q(-1)]]);
        assert!(!c.is_positive_semidefinite());
        // A zero diagonal with a nonzero off-diagonal in the same row is indefinite.
        let d = Matrix::from_rows(&[vec![q(1), q(0), q(0)], vec![q(0), q(0), q(1)], vec![q(0), q(1), q(0)]]);
        assert!(!d.is_positive_semidefinite());
    }

    #[test]
    fn bounded_null_space_has_coefficients_at_most_one() {
        let tiny = Rational::new(1.into(), num_bigint::BigInt::from(10).pow(300));
        let third = Rational::new_small(1, 3);
        // Two rows whose echelon pivots (columns 0 and 1) give coefficients
        // of size 1e300 and 3e300; the row scales differ by 1e300 too.
        let a = Matrix::from_rows(&[
            vec![tiny.clone(), q(0), q(1), q(2), third.clone()],
            vec![q(0), tiny.recip(), tiny.recip() * q(3), q(-1), q(7)],
        ]);
        let basis = a.bounded_null_space();
        assert_eq!(basis.len(), 3);
        for v in &basis {
            assert!(a.mul_vec(v).iter().all(Zero::is_zero));
            assert!(v.iter().all(|x| x.abs() <= q(1)), "{v:?}");
        }
        assert_eq!(Matrix::from_rows(&basis).rank(), 3);
        // Invariant under scaling and combining the rows.
        let b = Matrix::from_rows(&[
            a.row(0).iter().map(|x| x * &tiny).collect(),
            a.row(1).iter().zip(a.row(0)).map(|(x, y)| x + &y * q(5)).collect(),
        ]);
        assert_eq!(b.bounded_null_space(), basis);
        // Already bounded: the echelon basis is kept.
        let c = Matrix::from_rows(&[vec![q(1), q(1), q(-1)]]);
        assert_eq!(c.bounded_null_space(), c.null_space());
        assert_eq!(Matrix::zeros(1, 2).bounded_null_space(), Matrix::zeros(1, 2).null_space());
    }

    #[test]
    fn semidefinite_is_not_definite() {
        let a = Matrix::from_rows(&[vec![q(1), q(0)], vec![q(0), q(0)]]);
        assert_eq!(a.definiteness(), None);
    }
}
