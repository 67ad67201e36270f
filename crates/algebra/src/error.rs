//! Errors raised while building a Lie algebra.

/// Why a structure-constant table or a construction is not a Lie algebra.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum AlgebraError {
    /// No coordinates.
    #[error("the algebra has no coordinates")]
    Empty,
    /// More coordinates than the engine handles densely.
    #[error("dimension {dim} exceeds the limit {max} for finite-dimensional algebras")]
    TooLarge {
        /// Requested dimension.
        dim: usize,
        /// Limit.
        max: usize,
    },
    /// A coordinate name that is not an identifier.
    #[error("coordinate {index} ('{name}') is not a valid name (letters, digits and '_', not starting with a digit)")]
    InvalidCoordinateName {
        /// Position in the list.
        index: usize,
        /// The name.
        name: String,
    },
    /// Two coordinates with the same name.
    #[error("coordinate {index} ('{name}') repeats an earlier name")]
    DuplicateCoordinate {
        /// Position of the repeat.
        index: usize,
        /// The name.
        name: String,
    },
    /// An index in a row is not below the dimension.
    #[error("row {row}: index {index} is out of range for dimension {dim}")]
    IndexOutOfRange {
        /// Row of the table.
        row: usize,
        /// The index.
        index: usize,
        /// The dimension.
        dim: usize,
    },
    /// `c^k_aa != 0`: breaks antisymmetry.
    #[error("row {row}: c^{k}_({a},{a}) = {value} is not zero, which breaks antisymmetry [e_a, e_a] = 0")]
    DiagonalEntry {
        /// Row of the table.
        row: usize,
        /// The repeated index.
        a: usize,
        /// Output index.
        k: usize,
        /// The value given.
        value: String,
    },
    /// Two rows disagree about `c^k_ab` (directly, or via antisymmetry).
    #[error("row {row} gives c^{k}_({a},{b}) = {value}, but row {earlier_row} implies {implied} (antisymmetry c^k_ab = -c^k_ba)")]
    Inconsistent {
        /// The later row.
        row: usize,
        /// The earlier row it contradicts.
        earlier_row: usize,
        /// First index.
        a: usize,
        /// Second index.
        b: usize,
        /// Output index.
        k: usize,
        /// Value in the later row.
        value: String,
        /// Value implied by the earlier row.
        implied: String,
    },
    /// The Jacobi identity fails.
    #[error("the Jacobi identity fails for (e_{a}, e_{b}, e_{c}): component {k} of [[e_a,e_b],e_c] + [[e_b,e_c],e_a] + [[e_c,e_a],e_b] is {value}")]
    Jacobi {
        /// First index.
        a: usize,
        /// Second index.
        b: usize,
        /// Third index.
        c: usize,
        /// Component that is nonzero.
        k: usize,
        /// Its value.
        value: String,
    },
    /// A representation matrix has the wrong size.
    #[error("representation matrix {index} is {rows}x{cols}, expected {dim}x{dim}")]
    RepresentationShape {
        /// Which basis element.
        index: usize,
        /// Rows found.
        rows: usize,
        /// Columns found.
        cols: usize,
        /// Expected size.
        dim: usize,
    },
    /// The matrices do not satisfy `[rho_a, rho_b] = c^k_ab rho_k`.
    #[error("not a representation: [rho_{a}, rho_{b}] != c^k_ab rho_k")]
    NotARepresentation {
        /// First index.
        a: usize,
        /// Second index.
        b: usize,
    },
    /// Wrong number of representation matrices or names.
    #[error("expected {expected} {what}, got {got}")]
    WrongCount {
        /// What was counted.
        what: &'static str,
        /// Expected count.
        expected: usize,
        /// Count found.
        got: usize,
    },
}
