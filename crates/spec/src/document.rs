//! The spec contract as typed documents: serde-derived structs for the
//! finite-dimensional spec ([`SpecDocument`]), the fluid spec
//! ([`FluidSpecDocument`]) and their sections, and the JSON Schema of both,
//! generated from these types (schemars).
//!
//! Reading a spec has two stages. First the JSON is deserialised into these
//! types, which rejects unknown fields, missing required fields and values
//! of the wrong type, every error named by its JSON path (serde_path_to_error
//! tracks the path). Then the parser turns the document into a validated
//! system: expressions are parsed, dimensions matched, ranges checked. A Rust
//! user can build a document directly and hand it to
//! [`Spec::from_document`](crate::Spec::from_document) or
//! [`FluidSpec::from_document`](crate::FluidSpec::from_document) without
//! writing JSON.
//!
//! ```
//! use spec::document::{AlgebraDoc, Expression, SpecDocument};
//! let doc = SpecDocument {
//!     name: "rigid body".into(),
//!     algebra: AlgebraDoc::Builtin("so3".into()),
//!     hamiltonian: Expression::from("Pi1^2/6 + Pi2^2/4 + Pi3^2/2"),
//!     equilibrium: vec!["1".into(), "0".into(), "0".into()],
//!     noise: vec![vec!["3/10".into(), "0".into(), "0".into()]],
//!     ..SpecDocument::default()
//! };
//! let spec = spec::Spec::from_document(&doc).unwrap();
//! // Major axis I1 = 3 > I2 = 2 > I3 = 1, noise about it: stable.
//! assert_eq!(spec::certify_lie(&spec).analysis.verdict, spec::Verdict::Stable);
//! ```

use crate::json::SpecError;
use exact::{parse_number, Rational};
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt;

/// An expression: a string such as `"Pi1^2/(2*I1)"` or a JSON number used
/// as a constant. Kept as text; the parser reads it.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Expression(pub String);

impl From<&str> for Expression {
    fn from(s: &str) -> Self {
        Expression(s.to_string())
    }
}

impl From<String> for Expression {
    fn from(s: String) -> Self {
        Expression(s)
    }
}

impl<'de> Deserialize<'de> for Expression {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // Through `Value`: with serde_json's arbitrary_precision a number
        // does not reach an ordinary visitor as a number.
        match Value::deserialize(d)? {
            Value::String(s) => Ok(Expression(s)),
            Value::Number(n) => Ok(Expression(n.to_string())),
            other => Err(de::Error::custom(format!(
                "expected an expression (a string or a number), found {}",
                crate::json::type_name(&other)
            ))),
        }
    }
}

impl JsonSchema for Expression {
    fn schema_name() -> Cow<'static, str> {
        "Expression".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "description": "An expression: a string (polynomial in the coordinates and parameters, + - * / ^ and parentheses; fluids also sin, cos, exp, sqrt, sinh, cosh, tanh, sech, pi and y) or a number.",
            "type": ["string", "number"]
        })
    }
}

/// An exact rational: a JSON number (read exactly from its decimal text) or
/// a string such as `"3/10"` or `"1e-3"`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Literal(pub Rational);

impl Default for Literal {
    fn default() -> Self {
        Literal(Rational::from_integer(0.into()))
    }
}

impl Serialize for Literal {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.0.to_string())
    }
}

/// The text of a number given as a JSON number or a string (read through
/// `Value`: with serde_json's arbitrary_precision a number does not reach an
/// ordinary visitor as a number).
pub(crate) fn number_text<'de, D: Deserializer<'de>>(d: D, expected: &str) -> Result<String, D::Error> {
    match Value::deserialize(d)? {
        Value::Number(n) => Ok(n.to_string()),
        Value::String(s) => Ok(s),
        other => Err(de::Error::custom(format!("expected {expected}, found {}", crate::json::type_name(&other)))),
    }
}

impl<'de> Deserialize<'de> for Literal {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = number_text(d, "a number or a rational string")?;
        parse_number(&text).map(Literal).map_err(de::Error::custom)
    }
}

impl JsonSchema for Literal {
    fn schema_name() -> Cow<'static, str> {
        "Literal".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "description": "An exact number: a JSON number (read exactly from its decimal text) or a string: an integer, a decimal such as \"0.3\" or \"1e-3\", or a rational such as \"3/10\".",
            "anyOf": [
                {"type": "number"},
                {"type": "string", "pattern": "^\\s*[-+]?[0-9]*\\.?[0-9]*([eE][-+]?[0-9]+)?\\s*(/\\s*[-+]?[0-9]+\\s*)?$"}
            ]
        })
    }
}

/// A non-negative integer, as a JSON number or a string (`3` or `"3"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Index(pub u64);

impl<'de> Deserialize<'de> for Index {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = Literal::deserialize(d)?.0;
        if !r.is_integer() || r < Rational::from_integer(0.into()) {
            return Err(de::Error::custom(format!("expected a non-negative integer, found {r}")));
        }
        num_traits::ToPrimitive::to_u64(&r.to_integer()).map(Index).ok_or_else(|| de::Error::custom("too large"))
    }
}

impl JsonSchema for Index {
    fn schema_name() -> Cow<'static, str> {
        "Index".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({
            "description": "A non-negative integer (a JSON number, or a string holding one).",
            "anyOf": [{"type": "integer", "minimum": 0}, {"type": "string", "pattern": "^\\s*\\+?[0-9]+\\s*$"}]
        })
    }
}

/// A non-negative integer given as a JSON number (`64`, not `"64"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Count(pub u64);

impl<'de> Deserialize<'de> for Count {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        v.as_u64().map(Count).ok_or_else(|| {
            let found = match &v {
                Value::Number(n) => n.to_string(),
                other => crate::json::type_name(other).to_string(),
            };
            de::Error::custom(format!("expected a positive integer, found {found}"))
        })
    }
}

impl JsonSchema for Count {
    fn schema_name() -> Cow<'static, str> {
        "Count".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({"type": "integer", "minimum": 0})
    }
}

/// A double: a JSON number or a numeric string, read exactly and rounded
/// once to the nearest double.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Real(pub f64);

impl<'de> Deserialize<'de> for Real {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(Real(exact::rational_to_f64(&Literal::deserialize(d)?.0)))
    }
}

impl JsonSchema for Real {
    fn schema_name() -> Cow<'static, str> {
        "Real".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        Literal::json_schema(g)
    }
}

/// Objects only. serde's derived structs also accept a JSON array, read
/// positionally (`"stopping": [0.1, 0.001]` would be epsilon and delta);
/// the spec format is objects with named fields, so every struct-valued
/// field is read through these.
mod objects {
    use super::*;
    use std::marker::PhantomData;

    struct ObjectVisitor<T>(PhantomData<T>);

    impl<'de, T: Deserialize<'de>> Visitor<'de> for ObjectVisitor<T> {
        type Value = T;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an object")
        }
        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
            T::deserialize(de::value::MapAccessDeserializer::new(map))
        }
    }

    /// A struct from a JSON object (not an array).
    pub fn object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
        d.deserialize_map(ObjectVisitor(PhantomData))
    }

    struct OptionVisitor<T>(PhantomData<T>);

    impl<'de, T: Deserialize<'de>> Visitor<'de> for OptionVisitor<T> {
        type Value = Option<T>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an object")
        }
        fn visit_none<E: de::Error>(self) -> Result<Option<T>, E> {
            Ok(None)
        }
        fn visit_unit<E: de::Error>(self) -> Result<Option<T>, E> {
            Ok(None)
        }
        fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Option<T>, D::Error> {
            object(d).map(Some)
        }
    }

    /// An optional struct: absent or `null`, or a JSON object.
    pub fn optional_object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
        d.deserialize_option(OptionVisitor(PhantomData))
    }

    struct Object<T>(T);

    impl<'de, T: Deserialize<'de>> Deserialize<'de> for Object<T> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            object(d).map(Object)
        }
    }

    /// An optional list of structs, each a JSON object.
    pub fn optional_objects<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<Vec<T>>, D::Error> {
        let list: Option<Vec<Object<T>>> = Deserialize::deserialize(d)?;
        Ok(list.map(|v| v.into_iter().map(|o| o.0).collect()))
    }
}

/// A finite-dimensional spec: a Lie–Poisson system with its equilibrium and
/// noise (docs/architecture.md §4). Required: `name`, `algebra`, `hamiltonian`,
/// `equilibrium`, `noise`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: spec of a stochastic Lie-Poisson system")]
pub struct SpecDocument {
    /// The schema this file follows, for editors (`"$schema":
    /// "./schema/spec.schema.json"`); ignored by the engine.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// A non-empty name, used for output file names (sanitised).
    pub name: String,
    /// Free text, ignored by the engine.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// A builtin algebra's name (so3, se3, ...) or structure constants.
    pub algebra: AlgebraDoc,
    /// Named exact constants the expressions may use.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, Literal>,
    /// The Hamiltonian, a polynomial in the coordinates.
    pub hamiltonian: Expression,
    /// Casimirs; absent: the builtin algebra's, else discovered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub casimirs: Option<Vec<Expression>>,
    /// Further conserved quantities (checked to commute with the Hamiltonian).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_integrals: Option<Vec<Expression>>,
    /// The equilibrium, one constant per coordinate.
    pub equilibrium: Vec<Expression>,
    /// The noise fields `xi_k` in the algebra, one constant per coordinate
    /// each (at most 256 fields).
    pub noise: Vec<Vec<Expression>>,
    /// The stopping question.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub stopping: Option<StoppingDoc>,
    /// Engine settings; absent keys take their defaults (in the schema).
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub settings: Option<SettingsDoc>,
    /// Sweep annotations: ranges, boundaries, reference constants, domain.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub sweep: Option<SweepDoc>,
    /// A box of parameter values (docs/boxes.md): `certify` then proves
    /// the verdict and a bound on `Sigma^2` for every parameter in it, and
    /// writes a box certificate.
    #[serde(
        rename = "box",
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "objects::optional_object"
    )]
    pub parameter_box: Option<BoxDoc>,
}

/// A box of parameter values: an interval per named parameter, and the
/// bounds on the bisection.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BoxDoc {
    /// `NAME: [LO, HI]` with `LO < HI`, for parameters of the spec.
    pub parameters: BTreeMap<String, [Literal; 2]>,
    /// Largest number of bisections from the box to a sub-box (default 12, at most 40).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_depth: Option<u64>,
    /// Largest number of sub-boxes analysed (default 4096, at most 1000000).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_boxes: Option<u64>,
    /// The proved bound per sub-box is the largest sampled `Sigma^2` times
    /// `1 + margin` (default 1/1000; above 0, at most 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub margin: Option<Literal>,
    /// After the bisection, the stable sub-box with the largest bound is
    /// split (within `max_depth` and `max_boxes`) while its bound exceeds
    /// the pointwise `Sigma^2` at its worst sampled point by more than this
    /// relative amount (default 1/100; above 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sup_tolerance: Option<Literal>,
}

/// The algebra: a builtin name, or coordinates and structure constants.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum AlgebraDoc {
    /// A builtin algebra by name (`verify schema` lists them).
    Builtin(String),
    /// An algebra given by its structure constants.
    Custom(CustomAlgebra),
}

impl Default for AlgebraDoc {
    fn default() -> Self {
        AlgebraDoc::Builtin(String::new())
    }
}

impl<'de> Deserialize<'de> for AlgebraDoc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // A visitor rather than `#[serde(untagged)]`: untagged enums buffer
        // their input, which loses the JSON path of an error inside the
        // object and, with arbitrary_precision, every number.
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = AlgebraDoc;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a builtin name or an object")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<AlgebraDoc, E> {
                Ok(AlgebraDoc::Builtin(s.to_string()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<AlgebraDoc, A::Error> {
                CustomAlgebra::deserialize(de::value::MapAccessDeserializer::new(map)).map(AlgebraDoc::Custom)
            }
        }
        d.deserialize_any(V)
    }
}

impl JsonSchema for AlgebraDoc {
    fn schema_name() -> Cow<'static, str> {
        "Algebra".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let names: &[&str] = algebra::builtin_names();
        let custom = g.subschema_for::<CustomAlgebra>();
        json_schema!({
            "description": "A builtin algebra's name, or an object with coordinates and structure constants.",
            "anyOf": [{"type": "string", "enum": names}, custom]
        })
    }
}

/// An algebra given by structure constants `[e_a, e_b] = sum_k c e_k`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CustomAlgebra {
    /// A label for the algebra (default `custom`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Coordinate names (identifiers), one per basis element.
    pub coordinates: Vec<String>,
    /// Rows `[a, b, k, c]`: `c` is the coefficient of `e_k` in `[e_a, e_b]`
    /// (indices from 0; antisymmetry is implied).
    pub structure_constants: Vec<StructureRow>,
}

/// One structure constant `[a, b, k, c]`.
#[derive(Clone, Debug, PartialEq)]
pub struct StructureRow {
    /// Index of the first basis element.
    pub a: Index,
    /// Index of the second basis element.
    pub b: Index,
    /// Index of the element in the bracket.
    pub k: Index,
    /// The coefficient.
    pub c: Literal,
}

impl Serialize for StructureRow {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        (self.a, self.b, self.k, &self.c).serialize(s)
    }
}

impl<'de> Deserialize<'de> for StructureRow {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = StructureRow;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a row [a, b, k, c] of 4 entries")
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<StructureRow, A::Error> {
                let short = |n| de::Error::invalid_length(n, &"a row [a, b, k, c] of 4 entries");
                let a = seq.next_element()?.ok_or_else(|| short(0))?;
                let b = seq.next_element()?.ok_or_else(|| short(1))?;
                let k = seq.next_element()?.ok_or_else(|| short(2))?;
                let c = seq.next_element()?.ok_or_else(|| short(3))?;
                let mut extra = 4;
                while seq.next_element::<de::IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 4 {
                    return Err(short(extra));
                }
                Ok(StructureRow { a, b, k, c })
            }
        }
        d.deserialize_seq(V)
    }
}

impl JsonSchema for StructureRow {
    fn schema_name() -> Cow<'static, str> {
        "StructureRow".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let index = g.subschema_for::<Index>();
        let literal = g.subschema_for::<Literal>();
        json_schema!({
            "description": "[a, b, k, c]: c is the coefficient of e_k in [e_a, e_b].",
            "type": "array",
            "prefixItems": [index, index, index, literal],
            "items": false,
            "minItems": 4
        })
    }
}

/// The stopping question: the probability that `|dmu_t|_P^2` exceeds
/// `epsilon` before `T`, starting from `|dmu_0|_P^2 = delta`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StoppingDoc {
    /// Threshold on `|dmu_t|_P^2`; must exceed `delta`.
    pub epsilon: Literal,
    /// Initial size `|dmu_0|_P^2`; positive.
    pub delta: Literal,
}

/// Engine settings of a finite-dimensional spec. Every key is optional; the
/// schema gives each default and range, taken from the engine's own
/// `Default` and range table.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SettingsDoc {
    /// Smallest relative eigenvalue of `P` accepted as definite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub definiteness_tolerance: Option<Real>,
    /// Iterations of the search for a definite Casimir choice.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_iterations: Option<Index>,
    /// Times the search widens its range of `M`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_expansions: Option<Index>,
    /// Largest denominator when rounding the choice to rationals.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_denominator: Option<Index>,
    /// Real part above which an eigenvalue of `A` counts as unstable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instability_tolerance: Option<Real>,
    /// Highest degree searched when Casimirs are discovered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discovery_degree: Option<Index>,
    /// Largest number of unknowns per degree in Casimir discovery.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discovery_max_unknowns: Option<Index>,
    /// Optimise `Sigma^2` over the Casimir freedom.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimise: Option<bool>,
    /// Certify `Sigma^2` in exact rational arithmetic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exact: Option<bool>,
    /// Relative tolerance of the optimiser.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimisation_tolerance: Option<Real>,
    /// Iterations of the optimiser.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optimisation_iterations: Option<Index>,
}

/// The optional `sweep` section: what a sweep over the spec's parameters
/// draws and compares against.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepDoc {
    /// Default ranges, `NAME=LO:HI:N` (a grid) or `NAME=V1,V2,...`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ranges: Option<Vec<String>>,
    /// Curves where the verdict is expected to change (polynomials in the
    /// parameters, zero on the curve).
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_objects")]
    pub boundaries: Option<Vec<Annotation>>,
    /// Closed forms of `Sigma^2` to compare against.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_objects")]
    pub reference_sigma2: Option<Vec<Annotation>>,
    /// Polynomials that must be non-negative for a point to be physical.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<Vec<String>>,
}

/// A labelled polynomial in the parameters.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Annotation {
    /// The polynomial.
    pub expression: String,
    /// Its label in tables and plots (default: the expression).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
}

/// A fluid spec: 2D Euler about a shear flow `U(y)` in a periodic channel
/// (docs/fluid-guide.md, "Fluids"). Required: `name`, `fluid`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: spec of a stochastic shear flow")]
pub struct FluidSpecDocument {
    /// The schema this file follows, for editors (`"$schema":
    /// "./schema/fluid-spec.schema.json"`); ignored by the engine.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// A non-empty name.
    pub name: String,
    /// Free text, ignored by the engine.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Named constants (expressions evaluated in name order, each may use
    /// the ones before it).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, Expression>,
    /// The flow.
    #[serde(deserialize_with = "objects::object")]
    pub fluid: FluidDoc,
    /// The stopping question.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub stopping: Option<StoppingDoc>,
    /// Numerical settings; absent keys take their defaults.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub settings: Option<FluidSettingsDoc>,
    /// Sweep annotations.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub sweep: Option<SweepDoc>,
}

/// The fluid model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ModelName {
    /// Incompressible 2D Euler (vorticity).
    #[default]
    Incompressible,
    /// Compressible barotropic 2D Euler (needs `sound_speed`).
    Compressible,
}

/// The boundary in y.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryName {
    /// Rigid walls at both ends of the interval.
    #[default]
    Walls,
    /// A periodic interval.
    Periodic,
}

/// The flow: model, domain, shear flow, noise and discretisation.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FluidDoc {
    /// `incompressible` or `compressible`.
    pub model: ModelName,
    /// The period in x (a positive constant, e.g. `"2*pi"`).
    pub x_period: Expression,
    /// `[a, b]`, the interval in y.
    pub y_interval: Vec<Expression>,
    /// `walls` or `periodic`.
    pub boundary: BoundaryName,
    /// The shear flow `U(y)`.
    pub shear_flow: Expression,
    /// The sound speed of a compressible model (positive constant).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sound_speed: Option<Expression>,
    /// The noise fields (at most 256): a transport velocity `eta_k(y)`
    /// alone, or with a potential part for compressible flow.
    pub noise: Vec<NoiseEntry>,
    /// Grid points in y (16 to 4096; a multiple of the element degree, 8,
    /// on both boundaries).
    pub ny: Count,
    /// Number of x-modes `m = 1..x_modes` (1 to 2048).
    pub x_modes: Count,
}

/// One fluid noise field: the transport velocity `(eta(y), 0)` alone (a
/// string or number), or the pair `{"transport": eta, "potential": r}` of
/// the compressible semidirect-product algebra, where `r(y)` is a potential
/// (a stochastic potential force `-grad r`) or `"compatible"` for
/// `r = -int U eta' dy`, the completion that keeps the equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub enum NoiseEntry {
    /// Transport only.
    Transport(Expression),
    /// Transport with a potential part.
    WithPotential {
        /// `eta(y)`.
        transport: Expression,
        /// `r(y)`, or `"compatible"`.
        potential: Expression,
    },
}

impl NoiseEntry {
    /// The transport part.
    pub fn transport(&self) -> &Expression {
        match self {
            NoiseEntry::Transport(e) | NoiseEntry::WithPotential { transport: e, .. } => e,
        }
    }
}

impl From<&str> for NoiseEntry {
    fn from(s: &str) -> Self {
        NoiseEntry::Transport(Expression::from(s))
    }
}

/// The object form of a noise entry.
#[derive(Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
struct NoisePair {
    /// The transport velocity `eta(y)` (x-component of the noise field).
    transport: Expression,
    /// The potential `r(y)`, or `"compatible"` for `r = -int U eta' dy`.
    potential: Expression,
}

impl Serialize for NoiseEntry {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            NoiseEntry::Transport(e) => e.serialize(s),
            NoiseEntry::WithPotential { transport, potential } => {
                NoisePair { transport: transport.clone(), potential: potential.clone() }.serialize(s)
            }
        }
    }
}

impl<'de> Deserialize<'de> for NoiseEntry {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // A visitor, as for `AlgebraDoc`: the path of an error inside the
        // object is kept, and a number (arbitrary precision) is read through
        // `Value`.
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NoiseEntry;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an expression or an object {\"transport\", \"potential\"}")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<NoiseEntry, E> {
                Ok(NoiseEntry::Transport(Expression(s.to_string())))
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<NoiseEntry, E> {
                Ok(NoiseEntry::Transport(Expression(x.to_string())))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<NoiseEntry, E> {
                Ok(NoiseEntry::Transport(Expression(x.to_string())))
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<NoiseEntry, E> {
                Ok(NoiseEntry::Transport(Expression(x.to_string())))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<NoiseEntry, A::Error> {
                let (mut transport, mut potential) = (None, None);
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        // How serde_json (arbitrary_precision) hands over a number.
                        "$serde_json::private::Number" => {
                            return Ok(NoiseEntry::Transport(Expression(map.next_value::<String>()?)));
                        }
                        "transport" => transport = Some(map.next_value::<Expression>()?),
                        "potential" => potential = Some(map.next_value::<Expression>()?),
                        other => return Err(de::Error::unknown_field(other, &["transport", "potential"])),
                    }
                }
                let transport = transport.ok_or_else(|| de::Error::missing_field("transport"))?;
                let potential = potential.ok_or_else(|| de::Error::missing_field("potential"))?;
                Ok(NoiseEntry::WithPotential { transport, potential })
            }
        }
        d.deserialize_any(V)
    }
}

impl JsonSchema for NoiseEntry {
    fn schema_name() -> Cow<'static, str> {
        "NoiseEntry".into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let expression = g.subschema_for::<Expression>();
        let pair = g.subschema_for::<NoisePair>();
        json_schema!({
            "description": "A transport velocity eta(y), or {\"transport\": eta, \"potential\": r} with r(y) an expression or \"compatible\" (r = -int U eta' dy, which keeps a compressible equilibrium).",
            "anyOf": [expression, pair]
        })
    }
}

/// Numerical settings of a fluid spec.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FluidSettingsDoc {
    /// Relative tolerance of the Lanczos eigenvalue estimates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lanczos_tolerance: Option<Real>,
    /// Smallest `ny` of the convergence table.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convergence_from: Option<Count>,
    /// `ny` of the instability search.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instability_ny: Option<Count>,
}

/// A Zeitlin spec: the stochastic su(N) Zeitlin model of 2D Euler on the
/// sphere about a zonal equilibrium (docs/zeitlin.md). Required: `name`,
/// `zeitlin`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "verify: spec of a stochastic Zeitlin model")]
pub struct ZeitlinSpecDocument {
    /// The schema this file follows, for editors (`"$schema":
    /// "./schema/zeitlin-spec.schema.json"`); ignored by the engine.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema: Option<String>,
    /// A non-empty name.
    pub name: String,
    /// Free text, ignored by the engine.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Named constants (expressions evaluated in name order, each may use
    /// the ones before it).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, Expression>,
    /// The model.
    #[serde(deserialize_with = "objects::object")]
    pub zeitlin: ZeitlinDoc,
    /// The stopping question.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub stopping: Option<StoppingDoc>,
    /// Numerical settings; absent keys take their defaults.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub settings: Option<ZeitlinSettingsDoc>,
    /// Sweep annotations.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "objects::optional_object")]
    pub sweep: Option<SweepDoc>,
}

/// The Zeitlin model: `N`, the equilibrium and the noise.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinDoc {
    /// The matrix size `N` (2 to 4096): `W` in su(N), dimension `N^2 - 1`.
    #[serde(rename = "N")]
    pub n: Count,
    /// The vorticity: a zonal profile `omega(z)`, `z = cos(colatitude)` in
    /// `[-1, 1]`, quantised as quflow does (`W_e = sum_l a_l T_l0`, `a_l` its
    /// Legendre coefficients up to `l = N - 1`; the mean `a_0` is dropped:
    /// `W` is trace-free), or `{"harmonics": [[l, m, value], ...]}` in
    /// quflow's real spherical-harmonic basis (`W_e = sum value T_lm`), or
    /// `{"npy": "file.npy"}`, the matrix itself.
    pub equilibrium: ZeitlinField,
    /// Noise stream functions (at most 256), each a zonal profile `xi_i(z)`
    /// quantised the same way, `{"harmonics": ...}` or `{"npy": ...}`.
    pub noise: Vec<ZeitlinField>,
}

/// A field of the Zeitlin model: a zonal profile (an expression in `z`), or
/// quflow's real spherical-harmonic coefficients.
#[derive(Clone, Debug, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum ZeitlinField {
    /// A zonal profile `f(z)`.
    Profile(Expression),
    /// Spherical-harmonic coefficients.
    Harmonics(HarmonicsDoc),
    /// A matrix in a `.npy` file.
    Npy(NpyDoc),
}

/// A field read from a NumPy `.npy` file: an `N x N` complex128 array
/// (C or Fortran order), skew-Hermitian as quflow's `W`
/// (`numpy.save("W.npy", W)`). The path is relative to the spec's folder
/// (to the certificate's when a certificate is checked), without `..`,
/// and ends in `.npy`; the certificate records the file's SHA-256.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NpyDoc {
    /// The file.
    pub npy: String,
}

impl Default for ZeitlinField {
    fn default() -> Self {
        ZeitlinField::Profile(Expression::default())
    }
}

impl<'de> Deserialize<'de> for ZeitlinField {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // Through `Value`, so that the message says which forms are accepted
        // (an untagged enum only says that nothing matched).
        match Value::deserialize(d)? {
            Value::String(s) => Ok(ZeitlinField::Profile(Expression(s))),
            Value::Number(n) => Ok(ZeitlinField::Profile(Expression(n.to_string()))),
            Value::Object(map) if map.contains_key("npy") => serde_json::from_value::<NpyDoc>(Value::Object(map))
                .map(ZeitlinField::Npy)
                .map_err(|e| de::Error::custom(format!("in an npy object: {e}"))),
            v @ Value::Object(_) => serde_json::from_value::<HarmonicsDoc>(v)
                .map(ZeitlinField::Harmonics)
                .map_err(|e| de::Error::custom(format!("in a harmonics object: {e}"))),
            other => Err(de::Error::custom(format!(
                "expected a zonal profile (an expression in z), {{\"harmonics\": [[l, m, value], ...]}} or {{\"npy\": \"file.npy\"}}, found {}",
                crate::json::type_name(&other)
            ))),
        }
    }
}

/// quflow's real spherical-harmonic coefficients of a field: `W = sum value
/// T_lm` over rows `[l, m, value]` with `1 <= l <= N - 1`, `|m| <= l` (quflow's
/// `omega` vector holds `value` at index `l^2 + l + m`); `value` is an
/// expression in the parameters (a number, or a constant expression).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HarmonicsDoc {
    /// Rows `[l, m, value]` (at most 65536).
    pub harmonics: Vec<Vec<Expression>>,
}

/// Numerical settings of a Zeitlin spec.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ZeitlinSettingsDoc {
    /// Relative accuracy of each block's `lambda_max` (Lanczos), 1e-14 to 1e-3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<Real>,
    /// Whether the Casimir–momentum form alone (no energy) may be chosen
    /// (default true); false keeps the paper's `±H + C + beta J`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub casimir_momentum: Option<bool>,
    /// Largest `N` for which, without a definite form, the drift's
    /// eigenvalues are computed densely per block (2 to 512).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instability_max_n: Option<Count>,
    /// Largest `N` for which the energy–Casimir–momentum family is searched
    /// when the Casimir–momentum form is not definite (2 to 4096, default
    /// 1024; the search costs about 4x per doubling of N, some 10 s at
    /// N = 1024 and 40 s at N = 2048 on two cores).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_search_max_n: Option<Count>,
    /// Fields given by harmonics: largest relative `|[P_e, W_e]|` for an
    /// equilibrium, and relative off-diagonal part for a zonal frame (1e-15
    /// to 1e-3, default 1e-10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium_tolerance: Option<Real>,
    /// Fields given by harmonics: largest relative `|[X_i, W_e]|` for
    /// compatible noise (1e-15 to 1e-3, default 1e-10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_tolerance: Option<Real>,
    /// Fields given by harmonics: largest `N` for the dense analysis of a
    /// state zonal about no axis (2 to 48, default 32; `O(N^6)` work).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dense_max_n: Option<Count>,
    /// Fields given by harmonics: largest `N` for the matrix-free analysis
    /// of a state zonal about no axis above `dense_max_n` (2 to 1024,
    /// default 256; some 50 s at N = 256 on two cores, about 8x per
    /// doubling of N).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix_free_max_n: Option<Count>,
}

/// Deserialise a document from a JSON value, naming the JSON path of the
/// first error (`$.noise[0][1]`) in the engine's words.
///
/// ```
/// use spec::document::{from_value, SpecDocument};
/// let v = serde_json::json!({"name": "x", "algebra": "so3", "hamiltonian": 1,
///                            "equilibrium": [0, 0, 0], "noise": [[0, 0, {}]]});
/// let e = from_value::<SpecDocument>(&v).unwrap_err();
/// assert_eq!(e.path, "$.noise[0][2]");
/// assert!(e.message.contains("found an object"));
/// ```
pub fn from_value<T: de::DeserializeOwned>(value: &Value) -> Result<T, SpecError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let mut path = String::from("$");
        for segment in e.path().iter() {
            match segment {
                serde_path_to_error::Segment::Seq { index } => path.push_str(&format!("[{index}]")),
                serde_path_to_error::Segment::Map { key } => path.push_str(&format!(".{key}")),
                serde_path_to_error::Segment::Enum { variant } => path.push_str(&format!(".{variant}")),
                serde_path_to_error::Segment::Unknown => {}
            }
        }
        let (path, message) = in_our_words(path, &e.into_inner().to_string());
        SpecError::new(path, message)
    })
}

/// [`from_value`] for a value found at `path` (errors name paths below it).
pub fn from_value_at<T: de::DeserializeOwned>(value: &Value, path: &str) -> Result<T, SpecError> {
    from_value(value).map_err(|e| SpecError::new(format!("{path}{}", e.path.trim_start_matches('$')), e.message))
}

/// serde's messages rephrased the way the engine's own errors read
/// (`expected an array, found a string`), with the path moved to the field
/// for a missing or unknown field.
fn in_our_words(path: String, message: &str) -> (String, String) {
    let quoted = |s: &str| -> Option<String> {
        let start = s.find('`')? + 1;
        let len = s[start..].find('`')?;
        Some(s[start..start + len].to_string())
    };
    if let Some(rest) = message.strip_prefix("missing field ") {
        let field = quoted(rest).unwrap_or_default();
        return (format!("{path}.{field}"), "required field is missing".into());
    }
    if let Some(rest) = message.strip_prefix("unknown field ") {
        let field = quoted(rest).unwrap_or_default();
        if field == "$serde_json::private::Number" {
            return (path, "expected an object, found a number".into());
        }
        let allowed: Vec<String> = rest
            .split_once(", expected")
            .map(|(_, list)| list.split('`').skip(1).step_by(2).map(str::to_string).collect())
            .unwrap_or_default();
        let allowed = if allowed.is_empty() { "none".to_string() } else { allowed.join(", ") };
        // serde_path_to_error has already entered the key.
        let at = if path.ends_with(&format!(".{field}")) { path } else { format!("{path}.{field}") };
        return (at, format!("unknown field '{field}' (allowed here: {allowed})"));
    }
    if let Some(rest) = message.strip_prefix("unknown variant ") {
        let value = quoted(rest).unwrap_or_default();
        let allowed: Vec<String> = rest
            .split_once(", expected")
            .map(|(_, list)| list.split('`').skip(1).step_by(2).map(str::to_string).collect())
            .unwrap_or_default();
        let what = path.rsplit('.').next().unwrap_or("value").to_string();
        return (path, format!("unknown {what} '{value}' (expected {})", allowed.join(" or ")));
    }
    if let Some(rest) = message.strip_prefix("invalid type: ") {
        if let Some((found, expected)) = rest.split_once(", expected ") {
            return (path, format!("expected {}, found {}", expected_words(expected), found_words(found)));
        }
    }
    if let Some(rest) = message.strip_prefix("invalid length ") {
        if let Some((n, expected)) = rest.split_once(", expected ") {
            return (path, format!("expected {}, got {n} entries", expected_words(expected)));
        }
    }
    (path, message.to_string())
}

fn expected_words(expected: &str) -> String {
    if expected.starts_with("struct ") || expected == "a map" {
        "an object".into()
    } else if expected == "a sequence" {
        "an array".into()
    } else {
        expected.to_string()
    }
}

fn found_words(found: &str) -> &'static str {
    if found.starts_with("string") {
        "a string"
    } else if found.starts_with("integer") || found.starts_with("floating point") || found == "number" {
        "a number"
    } else if found.starts_with("boolean") {
        "a boolean"
    } else if found == "sequence" {
        "an array"
    } else if found == "map" {
        "an object"
    } else if found == "unit value" || found == "null" {
        "null"
    } else {
        "another type"
    }
}

/// The JSON Schema of finite-dimensional specs, generated from
/// [`SpecDocument`], with each setting's default and range filled in from
/// the engine (committed as `schema/spec.schema.json`).
pub fn spec_schema() -> Value {
    let mut schema = serde_json::to_value(schemars::schema_for!(SpecDocument)).unwrap_or(Value::Null);
    let defaults = serde_json::to_value(crate::settings::EngineSettings::default().to_document()).unwrap_or_default();
    if let Some(props) = schema.pointer_mut("/$defs/SettingsDoc/properties").and_then(Value::as_object_mut) {
        for (name, prop) in props.iter_mut() {
            if let Some(d) = defaults.get(name) {
                prop["default"] = d.clone();
            }
            if let Some((lo, hi)) = crate::settings::range_of(name) {
                prop["minimum"] = serde_json::json!(lo);
                prop["maximum"] = serde_json::json!(hi);
            }
        }
    }
    schema
}

/// The JSON Schema of fluid specs, generated from [`FluidSpecDocument`]
/// (committed as `schema/fluid-spec.schema.json`).
pub fn fluid_spec_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(FluidSpecDocument)).unwrap_or(Value::Null)
}

/// The JSON Schema of a Zeitlin spec.
pub fn zeitlin_spec_schema() -> Value {
    serde_json::to_value(schemars::schema_for!(ZeitlinSpecDocument)).unwrap_or(Value::Null)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn base() -> Value {
        json!({"name": "x", "algebra": "so3", "hamiltonian": "Pi1^2", "equilibrium": [1, 0, 0], "noise": [[0, 0, 0]]})
    }

    #[test]
    fn errors_name_the_field_in_the_engines_words() {
        let cases: Vec<(Value, &str, &str)> = vec![
            (
                {
                    let mut v = base();
                    v["nmae"] = json!(1);
                    v
                },
                "$.nmae",
                "unknown field 'nmae' (allowed here: $schema, name,",
            ),
            (
                {
                    let mut v = base();
                    v.as_object_mut().unwrap().remove("noise");
                    v
                },
                "$.noise",
                "required field is missing",
            ),
            (
                {
                    let mut v = base();
                    v["noise"] = json!("sigma");
                    v
                },
                "$.noise",
                "expected an array, found a string",
            ),
            (
                {
                    let mut v = base();
                    v["algebra"] = json!(3);
                    v
                },
                "$.algebra",
                "found a number",
            ),
            (
                {
                    let mut v = base();
                    v["algebra"] = json!({"coordinates": ["a"], "structure_constants": [[0, 1, 2]]});
                    v
                },
                "$.algebra.structure_constants[0]",
                "expected a row [a, b, k, c] of 4 entries, got 3 entries",
            ),
            (
                {
                    let mut v = base();
                    v["algebra"] = json!({"coordinates": ["a"], "structure_constants": [[0, 1, -2, 1]]});
                    v
                },
                "$.algebra.structure_constants[0][2]",
                "non-negative integer",
            ),
            (
                {
                    let mut v = base();
                    v["parameters"] = json!({"I": "1/0"});
                    v
                },
                "$.parameters.I",
                "",
            ),
            (
                {
                    let mut v = base();
                    v["settings"] = json!({"exact": 1});
                    v
                },
                "$.settings.exact",
                "expected a boolean, found a number",
            ),
            (
                {
                    let mut v = base();
                    v["stopping"] = json!({"epsilon": 1});
                    v
                },
                "$.stopping.delta",
                "required field is missing",
            ),
        ];
        for (v, path, words) in cases {
            let e = from_value::<SpecDocument>(&v).unwrap_err();
            assert_eq!(e.path, path, "{e}");
            assert!(e.message.contains(words), "{e}");
        }
    }

    /// Structs are objects: serde alone would read an array positionally.
    #[test]
    fn structs_must_be_objects_not_arrays() {
        let cases: Vec<(&str, Value, &str)> = vec![
            ("stopping", json!([0.1, 0.001]), "$.stopping"),
            ("settings", json!([]), "$.settings"),
            ("settings", json!(3), "$.settings"),
            ("sweep", json!({"boundaries": [["p", "q"]]}), "$.sweep.boundaries[0]"),
            ("sweep", json!([[]]), "$.sweep"),
        ];
        for (key, value, path) in cases {
            let mut v = base();
            v[key] = value;
            let e = from_value::<SpecDocument>(&v).unwrap_err();
            assert_eq!(e.path, path, "{e}");
            assert!(e.message.starts_with("expected an object, found"), "{e}");
        }
        let mut v = base();
        v["stopping"] = Value::Null;
        assert_eq!(from_value::<SpecDocument>(&v).unwrap().stopping, None);
        let fluid = json!({"name": "f", "fluid": []});
        assert_eq!(from_value::<FluidSpecDocument>(&fluid).unwrap_err().path, "$.fluid");
    }

    #[test]
    fn a_document_round_trips_through_json() {
        let v = json!({"name": "x", "algebra": {"coordinates": ["a", "b", "c"], "structure_constants": [[0, 1, 2, "3/2"]]},
                       "parameters": {"k": 0.25}, "hamiltonian": "a^2", "equilibrium": [1, 0, 0], "noise": [[0, 0, 0]],
                       "settings": {"exact": false, "search_iterations": 7}, "sweep": {"ranges": ["k=0:1:3"]}});
        let doc: SpecDocument = from_value(&v).unwrap();
        assert_eq!(doc.parameters["k"].0, parse_number("1/4").unwrap());
        let again: SpecDocument = from_value(&serde_json::to_value(&doc).unwrap()).unwrap();
        assert_eq!(doc, again);
    }
}
