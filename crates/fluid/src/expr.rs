//! Expressions in one variable `y` with `sin cos exp sqrt`, the hyperbolic
//! `sinh cosh tanh sech` and the constant `pi`, compiled to a tape (a straight-line program in which every
//! operation refers to earlier slots) and evaluated in three arithmetics:
//!
//! * `f64`, for values;
//! * truncated Taylor series of order 3 ("jets"), for `U`, `U'`, `U''`, `U'''`
//!   and `eta'` to machine precision in one pass (forward-mode automatic
//!   differentiation). A symbolic derivative tree grows with every
//!   differentiation (a product of 30 factors, or `sin` nested 190 deep, blew
//!   up to gigabytes); a jet pass costs a fixed multiple of the tape length;
//! * jets of [`Interval`]s, for rigorous enclosures of those derivatives over
//!   a piece of the y-interval: what [`Derivative::sign_on`] uses to *prove*
//!   that `U''` has one sign, or vanishes identically.
//!
//! Jet recurrences (coefficients `t_k` of `f(y + h) = sum_k t_k h^k`, so the
//! k-th derivative is `k! t_k`), for `c = a b`, `a / b`, `exp a`, `sin a`,
//! `cos a`, `sqrt a` (Griewank & Walther, *Evaluating Derivatives*, §13.2),
//! and the hyperbolic functions by the same method (each is the solution
//! of a first-order ODE in `a`: `sinh' = cosh a'`, `cosh' = sinh a'`,
//! `tanh' = sech^2 a'`, `sech' = -sech tanh a'`; matching the coefficients
//! of `h^(k-1)` gives the `k`-th):
//!
//! ```text
//! (ab)_k  = sum_{j<=k} a_j b_{k-j}
//! (a/b)_k = (a_k - sum_{1<=j<=k} b_j c_{k-j}) / b_0
//! e_k     = (1/k) sum_{1<=j<=k} j a_j e_{k-j}                     e = exp a
//! s_k     = (1/k) sum j a_j c_{k-j},  c_k = -(1/k) sum j a_j s_{k-j}   s, c = sin a, cos a
//! r_k     = (a_k - sum_{1<=j<k} r_j r_{k-j}) / (2 r_0)             r = sqrt a
//! S_k     = (1/k) sum j a_j C_{k-j},  C_k = (1/k) sum j a_j S_{k-j}    S, C = sinh a, cosh a
//! T_k     = (1/k) sum j a_j W_{k-j},  W = sech^2 a = 1 - T^2:
//!           W_0 = sech(a_0)^2, W_k = -sum_{i<=k} T_i T_{k-i}           T = tanh a
//! H_k     = -(1/k) sum j a_j (HT)_{k-j}                           H = sech a
//! ```
//!
//! `W_0` is `sech(a_0)^2`, not `1 - tanh(a_0)^2`: at `a_0 = 20` the latter
//! cancels to 0 in doubles while the former is `1.7e-17`. The hyperbolic
//! functions of large arguments overflow (`cosh 711 = inf`): their jets
//! are then infinite or NaN in `f64` (a value, not a proof), and in
//! interval arithmetic infinite bounds, which prove nothing.
//!
//! Parameters are substituted by value and sub-expressions that do not
//! depend on `y` are folded to numbers when parsed, so [`Expr::constant`] is
//! a lookup.

use crate::interval::Interval;
use exact::syntax::{Op, Semantics, SyntaxError};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Longest expression text accepted, in bytes.
pub const MAX_LENGTH: usize = 10_000;

/// Deepest nesting of parentheses, calls, unary signs and powers.
pub const MAX_DEPTH: usize = 200;

/// The names of the functions allowed, as a spec writes them.
pub const FUNCTIONS: [&str; 8] = ["sin", "cos", "exp", "sqrt", "sinh", "cosh", "tanh", "sech"];

/// The functions allowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    /// `sin`.
    Sin,
    /// `cos`.
    Cos,
    /// `exp`.
    Exp,
    /// `sqrt`.
    Sqrt,
    /// `sinh`.
    Sinh,
    /// `cosh`.
    Cosh,
    /// `tanh`.
    Tanh,
    /// `sech = 1 / cosh`.
    Sech,
}

/// One slot of the tape; operands are indices of earlier slots.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Node {
    Num(f64),
    Y,
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Pow(u32, i32),
    Neg(u32),
    Call(Func, u32),
}

/// A compiled expression in `y`.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    nodes: Vec<Node>,
}

/// Why an expression is not accepted.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message} (at character {position})")]
pub struct ExprError {
    /// What is wrong.
    pub message: String,
    /// 0-based character offset.
    pub position: usize,
}

fn err<T>(message: impl Into<String>, position: usize) -> Result<T, ExprError> {
    Err(ExprError { message: message.into(), position })
}

/// The arithmetic a tape is evaluated in: the four operations and negation
/// through `std::ops`, and the functions below.
pub trait Scalar:
    Copy
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::Neg<Output = Self>
{
    /// A constant.
    fn constant(x: f64) -> Self;
    /// `(sin a, cos a)`.
    fn sin_cos(self) -> (Self, Self);
    /// `exp a`.
    fn exp(self) -> Self;
    /// `sqrt a`.
    fn sqrt(self) -> Self;
    /// `(sinh a, cosh a)`.
    fn sinh_cosh(self) -> (Self, Self);
    /// `(tanh a, sech a)`.
    fn tanh_sech(self) -> (Self, Self);
    /// `a^n`, `|n| <= 64`.
    fn powi(self, n: i32) -> Self;
}

impl Scalar for f64 {
    fn constant(x: f64) -> Self {
        x
    }
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    fn exp(self) -> Self {
        f64::exp(self)
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn sinh_cosh(self) -> (Self, Self) {
        (self.sinh(), self.cosh())
    }
    fn tanh_sech(self) -> (Self, Self) {
        (self.tanh(), sech(self))
    }
    fn powi(self, n: i32) -> Self {
        f64::powi(self, n)
    }
}

/// `sech x` in doubles: `1 / cosh x`, and `2 e^-|x|` past `|x| = 20`
/// (where `sech x = 2 e^-|x| / (1 + e^-2|x|)` differs from it by a
/// factor `1 - 4e-18`, below half an ulp), so that it does not drop to 0
/// where `cosh` overflows (`sech 720 = 4.1e-313`, a subnormal).
fn sech(x: f64) -> f64 {
    let a = x.abs();
    if a > 20.0 {
        2.0 * (-a).exp()
    } else {
        1.0 / a.cosh()
    }
}

impl Scalar for Interval {
    fn constant(x: f64) -> Self {
        Interval::point(x)
    }
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    fn exp(self) -> Self {
        Interval::exp(self)
    }
    fn sqrt(self) -> Self {
        Interval::sqrt(self)
    }
    fn sinh_cosh(self) -> (Self, Self) {
        (Interval::sinh(self), Interval::cosh(self))
    }
    fn tanh_sech(self) -> (Self, Self) {
        (Interval::tanh(self), Interval::sech(self))
    }
    fn powi(self, n: i32) -> Self {
        Interval::powi(self, n)
    }
}

/// A Taylor jet of order 3: `f(y + h) = t[0] + t[1] h + t[2] h^2 + t[3] h^3 + O(h^4)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet<T>(pub [T; 4]);

impl<T: Scalar> Jet<T> {
    fn c(x: f64) -> T {
        T::constant(x)
    }

    /// The Taylor coefficients of `(s, c) = (sin a, cos a)` or `(sinh a,
    /// cosh a)` from their values `s0`, `c0` at the point: `s' = c a'` and
    /// `c' = -s a'` (`negate`) or `c' = s a'`, coefficient by coefficient,
    /// `k s_k = sum_j j a_j c_(k-j)`.
    fn coupled_pair(a: [T; 4], s0: T, c0: T, negate: bool) -> (Self, Self) {
        let mut s = [s0; 4];
        let mut c = [c0; 4];
        for k in 1..4 {
            let (mut ss, mut cc) = (T::constant(0.0), T::constant(0.0));
            for j in 1..=k {
                let ja = a[j] * Self::c(j as f64);
                ss = ss + ja * c[k - j];
                cc = cc + ja * s[k - j];
            }
            s[k] = ss / Self::c(k as f64);
            c[k] = if negate { -(cc / Self::c(k as f64)) } else { cc / Self::c(k as f64) };
        }
        (Jet(s), Jet(c))
    }

    /// The k-th derivative, `k! t_k`.
    pub fn derivative(&self, k: usize) -> T {
        let factorial = [1.0, 1.0, 2.0, 6.0][k];
        if factorial == 1.0 {
            self.0[k]
        } else {
            self.0[k] * Self::c(factorial)
        }
    }
}

impl<T: Scalar> std::ops::Add for Jet<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Jet(std::array::from_fn(|k| self.0[k] + o.0[k]))
    }
}

impl<T: Scalar> std::ops::Sub for Jet<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Jet(std::array::from_fn(|k| self.0[k] - o.0[k]))
    }
}

impl<T: Scalar> std::ops::Mul for Jet<T> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        Jet(std::array::from_fn(|k| {
            let mut s = a[0] * b[k];
            for j in 1..=k {
                s = s + a[j] * b[k - j];
            }
            s
        }))
    }
}

impl<T: Scalar> std::ops::Div for Jet<T> {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        let mut c = [T::constant(0.0); 4];
        for k in 0..4 {
            let mut s = a[k];
            for j in 1..=k {
                s = s - b[j] * c[k - j];
            }
            c[k] = s / b[0];
        }
        Jet(c)
    }
}

impl<T: Scalar> std::ops::Neg for Jet<T> {
    type Output = Self;
    fn neg(self) -> Self {
        Jet(self.0.map(|x| -x))
    }
}

impl<T: Scalar> Scalar for Jet<T> {
    fn constant(x: f64) -> Self {
        let z = T::constant(0.0);
        Jet([T::constant(x), z, z, z])
    }
    fn sin_cos(self) -> (Self, Self) {
        let (s0, c0) = self.0[0].sin_cos();
        Self::coupled_pair(self.0, s0, c0, true)
    }
    fn exp(self) -> Self {
        let a = self.0;
        let mut e = [a[0].exp(); 4];
        for k in 1..4 {
            let mut s = T::constant(0.0);
            for j in 1..=k {
                s = s + a[j] * Self::c(j as f64) * e[k - j];
            }
            e[k] = s / Self::c(k as f64);
        }
        Jet(e)
    }
    fn sqrt(self) -> Self {
        let a = self.0;
        let mut r = [a[0].sqrt(); 4];
        let two_r0 = r[0] * Self::c(2.0);
        for k in 1..4 {
            let mut s = a[k];
            for j in 1..k {
                s = s - r[j] * r[k - j];
            }
            r[k] = s / two_r0;
        }
        Jet(r)
    }
    fn sinh_cosh(self) -> (Self, Self) {
        let (s0, c0) = self.0[0].sinh_cosh();
        Self::coupled_pair(self.0, s0, c0, false)
    }
    fn tanh_sech(self) -> (Self, Self) {
        let a = self.0;
        let (t0, h0) = a[0].tanh_sech();
        // t = tanh a, w = 1 - t^2 = sech^2 a, h = sech a, u = h t
        let mut t = [t0; 4];
        let mut w = [h0.powi(2); 4];
        let mut h = [h0; 4];
        let mut u = [h0 * t0; 4];
        for k in 1..4 {
            let (mut tt, mut hh) = (T::constant(0.0), T::constant(0.0));
            for j in 1..=k {
                let ja = a[j] * Self::c(j as f64);
                tt = tt + ja * w[k - j];
                hh = hh + ja * u[k - j];
            }
            t[k] = tt / Self::c(k as f64);
            h[k] = -(hh / Self::c(k as f64));
            // w_k = -(t t)_k and u_k = (h t)_k, now that t_k and h_k are known
            let (mut tt2, mut ht) = (t[0] * t[k], h[0] * t[k]);
            for i in 1..=k {
                tt2 = tt2 + t[i] * t[k - i];
                ht = ht + h[i] * t[k - i];
            }
            w[k] = -tt2;
            u[k] = ht;
        }
        (Jet(t), Jet(h))
    }
    fn powi(self, n: i32) -> Self {
        // Repeated squaring (at most 12 products for |n| <= 64): exact zeros
        // stay zeros, so y^2 has third derivative 0, not 0 * y^-1.
        if n < 0 {
            return Self::constant(1.0) / self.powi(-n);
        }
        let mut acc = Self::constant(1.0);
        let mut base = self;
        let mut e = n as u32;
        while e > 0 {
            if e & 1 == 1 {
                acc = acc * base;
            }
            e >>= 1;
            if e > 0 {
                base = base * base;
            }
        }
        acc
    }
}

/// The language of functions of `y`: numbers and parameters are doubles,
/// `y` and `pi` are known, `sin cos exp sqrt sinh cosh tanh sech` may be
/// called, exponents are
/// constant integers in `[-64, 64]`. Each construct becomes a slot of the
/// tape, folded to a number when its operands are numbers.
struct Tape<'a> {
    params: &'a BTreeMap<String, f64>,
    /// The name of the independent variable (`y` for shear flows).
    variable: &'a str,
    nodes: Vec<Node>,
}

/// Parse an expression in `y` (parameters are substituted by value); the
/// grammar is the one front end's, [`exact::syntax`].
///
/// ```
/// use fluid::expr::parse;
/// let e = parse("1 - cos(2*y)^2 + exp(-y)/2", &Default::default()).unwrap();
/// let y = 0.3f64;
/// assert!((e.eval(y) - (1.0 - (2.0 * y).cos().powi(2) + (-y).exp() / 2.0)).abs() < 1e-15);
/// // d/dy: 4 cos(2y) sin(2y) - exp(-y)/2
/// let d = e.derivatives(y)[1];
/// assert!((d - (4.0 * (2.0 * y).cos() * (2.0 * y).sin() - (-y).exp() / 2.0)).abs() < 1e-14);
/// assert!(parse("log(y)", &Default::default()).unwrap_err().message.contains("unknown function 'log'"));
/// // the hyperbolic functions: the Bickley jet sech(y)^2 is d/dy tanh(y)
/// let bickley = parse("sech(y)^2", &Default::default()).unwrap();
/// let tanh = parse("tanh(y)", &Default::default()).unwrap();
/// assert!((bickley.eval(y) - tanh.derivatives(y)[1]).abs() < 1e-15);
/// assert!((bickley.eval(y) - 4.0 / (y.exp() + (-y).exp()).powi(2)).abs() < 1e-15);
/// ```
pub fn parse(text: &str, params: &BTreeMap<String, f64>) -> Result<Expr, ExprError> {
    parse_in(text, "y", params)
}

/// Parse an expression in the variable `variable` (`z` for zonal profiles
/// on the sphere); [`Expr::eval`] evaluates it there.
///
/// ```
/// use fluid::expr::parse_in;
/// let e = parse_in("z^3 - z/2", "z", &Default::default()).unwrap();
/// assert_eq!(e.eval(0.5), 0.125 - 0.25);
/// assert!(parse_in("y", "z", &Default::default()).unwrap_err().message.contains("unknown symbol 'y' (known: z, pi)"));
/// ```
pub fn parse_in(text: &str, variable: &str, params: &BTreeMap<String, f64>) -> Result<Expr, ExprError> {
    let mut tape = Tape { params, variable, nodes: Vec::new() };
    let root = exact::syntax::parse(text, &mut tape, MAX_DEPTH, MAX_LENGTH)?;
    Ok(Expr { nodes: compact(tape.nodes, root) })
}

/// Keep only the slots the root depends on, renumbered in order.
fn compact(nodes: Vec<Node>, root: u32) -> Vec<Node> {
    let mut live = vec![false; nodes.len()];
    live[root as usize] = true;
    for i in (0..nodes.len()).rev() {
        if !live[i] {
            continue;
        }
        match nodes[i] {
            Node::Add(a, b) | Node::Sub(a, b) | Node::Mul(a, b) | Node::Div(a, b) => {
                live[a as usize] = true;
                live[b as usize] = true;
            }
            Node::Pow(a, _) | Node::Neg(a) | Node::Call(_, a) => live[a as usize] = true,
            Node::Num(_) | Node::Y => {}
        }
    }
    let mut map = vec![0u32; nodes.len()];
    let mut out = Vec::new();
    for (i, n) in nodes.into_iter().enumerate() {
        if !live[i] {
            continue;
        }
        let r = |x: u32| map[x as usize];
        let m = match n {
            Node::Add(a, b) => Node::Add(r(a), r(b)),
            Node::Sub(a, b) => Node::Sub(r(a), r(b)),
            Node::Mul(a, b) => Node::Mul(r(a), r(b)),
            Node::Div(a, b) => Node::Div(r(a), r(b)),
            Node::Pow(a, k) => Node::Pow(r(a), k),
            Node::Neg(a) => Node::Neg(r(a)),
            Node::Call(f, a) => Node::Call(f, r(a)),
            other => other,
        };
        map[i] = out.len() as u32;
        out.push(m);
    }
    out
}

fn apply(f: Func, x: f64) -> f64 {
    match f {
        Func::Sin => x.sin(),
        Func::Cos => x.cos(),
        Func::Exp => x.exp(),
        Func::Sqrt => x.sqrt(),
        Func::Sinh => x.sinh(),
        Func::Cosh => x.cosh(),
        Func::Tanh => x.tanh(),
        Func::Sech => sech(x),
    }
}

impl Tape<'_> {
    fn num(&self, i: u32) -> Option<f64> {
        match self.nodes[i as usize] {
            Node::Num(v) => Some(v),
            _ => None,
        }
    }

    /// Push a node, folding it to a number when its operands are numbers.
    fn push(&mut self, n: Node) -> u32 {
        let folded = match n {
            Node::Add(a, b) => self.num(a).zip(self.num(b)).map(|(x, y)| x + y),
            Node::Sub(a, b) => self.num(a).zip(self.num(b)).map(|(x, y)| x - y),
            Node::Mul(a, b) => self.num(a).zip(self.num(b)).map(|(x, y)| x * y),
            Node::Div(a, b) => self.num(a).zip(self.num(b)).map(|(x, y)| x / y),
            Node::Pow(a, k) => self.num(a).map(|x| x.powi(k)),
            Node::Neg(a) => self.num(a).map(|x| -x),
            Node::Call(f, a) => self.num(a).map(|x| apply(f, x)),
            other => return self.push_raw(other),
        };
        match folded {
            Some(v) => self.push_raw(Node::Num(v)),
            None => self.push_raw(n),
        }
    }

    fn push_raw(&mut self, n: Node) -> u32 {
        self.nodes.push(n);
        (self.nodes.len() - 1) as u32
    }
}

impl From<SyntaxError> for ExprError {
    fn from(e: SyntaxError) -> Self {
        ExprError { message: e.kind.to_string(), position: e.position }
    }
}

impl Semantics for Tape<'_> {
    type Value = u32;
    type Function = Func;
    type Error = ExprError;

    fn syntax(&self, e: SyntaxError) -> ExprError {
        e.into()
    }

    fn number(&mut self, text: &str, at: usize) -> Result<u32, ExprError> {
        let v = exact::parse_number(text).map_err(|e| ExprError { message: e.to_string(), position: at })?;
        Ok(self.push_raw(Node::Num(exact::rational_to_f64(&v))))
    }

    fn symbol(&mut self, name: &str, at: usize) -> Result<u32, ExprError> {
        match name {
            _ if name == self.variable => Ok(self.push_raw(Node::Y)),
            "pi" => Ok(self.push_raw(Node::Num(std::f64::consts::PI))),
            _ => match self.params.get(name) {
                Some(v) => Ok(self.push_raw(Node::Num(*v))),
                None => {
                    let known: Vec<&str> =
                        [self.variable, "pi"].into_iter().chain(self.params.keys().map(String::as_str)).collect();
                    err(format!("unknown symbol '{}' (known: {})", exact::quote(name, 40), known.join(", ")), at)
                }
            },
        }
    }

    fn function(&mut self, name: &str, at: usize) -> Result<Func, ExprError> {
        match name {
            "sin" => Ok(Func::Sin),
            "cos" => Ok(Func::Cos),
            "exp" => Ok(Func::Exp),
            "sqrt" => Ok(Func::Sqrt),
            "sinh" => Ok(Func::Sinh),
            "cosh" => Ok(Func::Cosh),
            "tanh" => Ok(Func::Tanh),
            "sech" => Ok(Func::Sech),
            _ => err(format!("unknown function '{}' (allowed: {})", exact::quote(name, 40), FUNCTIONS.join(", ")), at),
        }
    }

    fn call(&mut self, f: Func, arg: u32, _: usize) -> Result<u32, ExprError> {
        Ok(self.push(Node::Call(f, arg)))
    }

    fn binary(&mut self, op: Op, a: u32, b: u32, _: usize, _: usize) -> Result<u32, ExprError> {
        Ok(self.push(match op {
            Op::Add => Node::Add(a, b),
            Op::Sub => Node::Sub(a, b),
            Op::Mul => Node::Mul(a, b),
            Op::Div => Node::Div(a, b),
        }))
    }

    fn negate(&mut self, a: u32, _: usize) -> Result<u32, ExprError> {
        Ok(self.push(Node::Neg(a)))
    }

    fn power(&mut self, base: u32, exponent: u32, _: usize, at: usize) -> Result<u32, ExprError> {
        let v = self
            .num(exponent)
            .ok_or_else(|| ExprError { message: "the exponent must be a constant integer".into(), position: at })?;
        if v.fract() != 0.0 || v.abs() > 64.0 {
            return err("the exponent must be an integer between -64 and 64", at);
        }
        Ok(self.push(Node::Pow(base, v as i32)))
    }
}

impl Expr {
    /// The value if the expression does not depend on `y`.
    pub fn constant(&self) -> Option<f64> {
        match self.nodes.last() {
            Some(Node::Num(v)) => Some(*v),
            _ => None,
        }
    }

    /// Number of operations on the tape (the cost of one evaluation).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tape is empty (never, for a parsed expression).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Evaluate with `y` given in the arithmetic `T`.
    pub fn evaluate<T: Scalar>(&self, y: T) -> T {
        let mut v: Vec<T> = Vec::with_capacity(self.nodes.len());
        for n in &self.nodes {
            let x = match *n {
                Node::Num(c) => T::constant(c),
                Node::Y => y,
                Node::Add(a, b) => v[a as usize] + v[b as usize],
                Node::Sub(a, b) => v[a as usize] - v[b as usize],
                Node::Mul(a, b) => v[a as usize] * v[b as usize],
                Node::Div(a, b) => v[a as usize] / v[b as usize],
                Node::Pow(a, k) => v[a as usize].powi(k),
                Node::Neg(a) => -v[a as usize],
                Node::Call(f, a) => {
                    let x = v[a as usize];
                    match f {
                        Func::Sin => x.sin_cos().0,
                        Func::Cos => x.sin_cos().1,
                        Func::Exp => x.exp(),
                        Func::Sqrt => x.sqrt(),
                        Func::Sinh => x.sinh_cosh().0,
                        Func::Cosh => x.sinh_cosh().1,
                        Func::Tanh => x.tanh_sech().0,
                        Func::Sech => x.tanh_sech().1,
                    }
                }
            };
            v.push(x);
        }
        *v.last().expect("a parsed expression has at least one slot")
    }

    /// Value at `y`.
    pub fn eval(&self, y: f64) -> f64 {
        self.evaluate(y)
    }

    /// `[f, f', f'', f''']` at `y`, by one jet pass.
    pub fn derivatives(&self, y: f64) -> [f64; 4] {
        let j = self.evaluate(Jet([y, 1.0, 0.0, 0.0]));
        std::array::from_fn(|k| j.derivative(k))
    }

    /// Enclosures of `[f, f', f'', f''']` over all `y` in `ys` (rigorous: the
    /// jet recurrences run in interval arithmetic).
    pub fn enclose(&self, ys: Interval) -> [Interval; 4] {
        let one = Interval::point(1.0);
        let zero = Interval::point(0.0);
        let j = self.evaluate(Jet([ys, one, zero, zero]));
        std::array::from_fn(|k| j.derivative(k))
    }
}

/// One derivative (`order` 0 to 3) of a shared expression, times a
/// constant factor (a power of two when the pipeline normalises the noise,
/// so that the scaling is exact).
#[derive(Clone, Debug, PartialEq)]
pub struct Derivative {
    expr: Arc<Expr>,
    order: usize,
    factor: f64,
}

/// What interval arithmetic proved about the sign of a function on a closed interval.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SignProof {
    /// Strictly positive everywhere.
    Positive,
    /// Strictly negative everywhere.
    Negative,
    /// Identically zero.
    Zero,
    /// Positive somewhere and negative somewhere (so it vanishes in between).
    Changes,
    /// Nothing proved within the budget (a zero, a touching zero, or an
    /// enclosure too loose).
    Unproved,
}

impl Derivative {
    /// The `order`-th derivative of `expr` (`order <= 3`).
    pub fn new(expr: Arc<Expr>, order: usize) -> Self {
        assert!(order <= 3, "jets carry derivatives up to order 3");
        Derivative { expr, order, factor: 1.0 }
    }

    /// The same derivative times `factor`.
    pub fn times(&self, factor: f64) -> Self {
        Derivative { factor: self.factor * factor, ..self.clone() }
    }

    /// The expression differentiated.
    pub fn expr(&self) -> &Expr {
        &self.expr
    }

    /// The order of the derivative.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Value at `y`.
    pub fn eval(&self, y: f64) -> f64 {
        let v = if self.order == 0 { self.expr.eval(y) } else { self.expr.derivatives(y)[self.order] };
        if self.factor == 1.0 {
            v
        } else {
            v * self.factor
        }
    }

    /// A rigorous enclosure over `[lo, hi]`: the natural interval extension
    /// intersected with the mean-value form `f(m) + f'([lo, hi]) ([lo, hi] - m)`
    /// (at order 3 only the natural one: jets stop at the third derivative).
    pub fn enclose(&self, lo: f64, hi: f64) -> Interval {
        let e = self.enclose_unscaled(lo, hi);
        if self.factor == 1.0 {
            e
        } else {
            e * Interval::point(self.factor)
        }
    }

    fn enclose_unscaled(&self, lo: f64, hi: f64) -> Interval {
        let ys = Interval::new(lo, hi);
        let e = self.expr.enclose(ys);
        let natural = e[self.order];
        if self.order == 3 || lo == hi {
            return natural;
        }
        let m = 0.5 * (lo + hi);
        let at_m = self.expr.enclose(Interval::point(m))[self.order];
        let slope = e[self.order + 1];
        let mean_value = at_m + slope * (ys - Interval::point(m));
        natural.intersect(&mean_value)
    }

    /// Prove the sign of this derivative on the closed interval `[a, b]` by
    /// bisection, with at most `budget` tape operations (each enclosure
    /// costs about `40 len` of them) and pieces no shorter than `2^-40 (b - a)`.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use fluid::expr::{parse, Derivative, SignProof};
    /// let p = |s: &str| Arc::new(parse(s, &Default::default()).unwrap());
    /// let second = |s: &str| Derivative::new(p(s), 2);
    /// assert_eq!(second("y^2 + sin(y)/10").sign_on(0.0, 3.0, 1e6), SignProof::Positive); // 2 - sin(y)/10 > 0
    /// assert_eq!(second("3*y - 1e13*y").sign_on(0.0, 3.0, 1e6), SignProof::Zero);         // affine: U'' = 0 exactly
    /// assert_eq!(second("sin(y) + 1e13*y").sign_on(0.0, 3.14159, 1e6), SignProof::Unproved); // -sin y vanishes at 0
    /// assert_eq!(second("sin(y)").sign_on(1.0, 6.0, 1e6), SignProof::Changes);
    /// ```
    pub fn sign_on(&self, a: f64, b: f64, budget: f64) -> SignProof {
        if !(a.is_finite() && b.is_finite() && a <= b) {
            return SignProof::Unproved;
        }
        let cost = 40.0 * self.expr.len() as f64;
        let min_width = (b - a) * 2f64.powi(-40);
        let mut spent = 0.0;
        let (mut positive, mut negative, mut zero, mut undecided) = (false, false, false, false);
        let mut stack = vec![(a, b)];
        while let Some((lo, hi)) = stack.pop() {
            spent += cost;
            let e = self.enclose(lo, hi);
            if e.lo > 0.0 {
                positive = true;
            } else if e.hi < 0.0 {
                negative = true;
            } else if e.is_zero() {
                zero = true;
            } else {
                if spent > budget {
                    return if positive && negative { SignProof::Changes } else { SignProof::Unproved };
                }
                let mid = 0.5 * (lo + hi);
                if hi - lo <= min_width || !(mid > lo && mid < hi) {
                    // A zero (or a loose enclosure) here: undecided, but keep
                    // going, a sign change elsewhere may still be proved.
                    undecided = true;
                    continue;
                }
                stack.push((mid, hi));
                stack.push((lo, mid));
            }
            if positive && negative {
                return SignProof::Changes;
            }
        }
        match (positive, negative, zero, undecided) {
            (true, false, false, false) => SignProof::Positive,
            (false, true, false, false) => SignProof::Negative,
            (false, false, true, false) => SignProof::Zero,
            _ => SignProof::Unproved,
        }
    }

    /// A rigorous enclosure of the range over `[a, b]` from `pieces` equal
    /// pieces (the hull of their enclosures).
    pub fn range_on(&self, a: f64, b: f64, pieces: usize) -> Interval {
        if !(a.is_finite() && b.is_finite() && a <= b) {
            return Interval::ENTIRE;
        }
        let n = pieces.max(1);
        let mut out: Option<Interval> = None;
        for i in 0..n {
            let lo = if i == 0 { a } else { a + (b - a) * (i as f64 / n as f64) };
            let hi = if i + 1 == n { b } else { a + (b - a) * ((i + 1) as f64 / n as f64) };
            // Overlap the rounded cut points by one ulp so no y is missed.
            let e = self.enclose(if i == 0 { lo } else { lo.next_down() }, hi);
            out = Some(out.map_or(e, |o| o.hull(&e)));
        }
        out.unwrap_or(Interval::ENTIRE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One front end: a syntax error reads the same, at the same place, in
    /// the polynomial language of finite-dimensional specs and in this one.
    #[test]
    fn both_languages_share_their_syntax_errors() {
        let symbols = exact::Symbols::new(&["y"]);
        let nested = format!("{}y{}", "(".repeat(250), ")".repeat(250));
        for text in ["1 +", "(y", "y)", "y ** 2", "y @ 2", "", "2 y", "*y", "(y))", &nested, "y + é"] {
            let a = exact::parse_expression(text, &symbols).unwrap_err();
            let b = parse(text, &BTreeMap::new()).unwrap_err();
            assert_eq!(a.position, b.position, "{text}");
            assert_eq!(a.kind.to_string(), b.message, "{text}");
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let p = BTreeMap::new();
        for text in ["sin(y)^3 * exp(y/2)", "sqrt(1 + y^2) / cos(y)", "y^-2 + 3*y^4", "exp(-(y - 1)^2)"] {
            let e = parse(text, &p).unwrap();
            for y in [0.3, 0.9, 1.4] {
                let [_, d, dd, _] = e.derivatives(y);
                let h = 1e-5;
                let fd = (e.eval(y + h) - e.eval(y - h)) / (2.0 * h);
                assert!((fd - d).abs() < 1e-8 * (1.0 + fd.abs()), "{text}: {fd} vs {d}");
                let fd2 = (e.eval(y + h) - 2.0 * e.eval(y) + e.eval(y - h)) / (h * h);
                assert!((fd2 - dd).abs() < 1e-4 * (1.0 + fd2.abs()), "{text}: {fd2} vs {dd}");
                // the third derivative against a difference of second derivatives
                let fd3 = (e.derivatives(y + h)[2] - e.derivatives(y - h)[2]) / (2.0 * h);
                assert!((fd3 - e.derivatives(y)[3]).abs() < 1e-6 * (1.0 + fd3.abs()), "{text}");
            }
        }
    }

    #[test]
    fn third_derivatives_in_closed_form() {
        // d^3/dy^3 sin(2y) = -8 cos(2y); d^3/dy^3 exp(y^2) = (8y^3 + 12y) exp(y^2);
        // d^3/dy^3 sqrt(y) = (3/8) y^(-5/2); d^3/dy^3 1/y = -6/y^4.
        let p = BTreeMap::new();
        let y = 0.7f64;
        let cases: [(&str, f64); 4] = [
            ("sin(2*y)", -8.0 * (2.0 * y).cos()),
            ("exp(y^2)", (8.0 * y.powi(3) + 12.0 * y) * (y * y).exp()),
            ("sqrt(y)", 0.375 * y.powf(-2.5)),
            ("1/y", -6.0 / y.powi(4)),
        ];
        for (text, want) in cases {
            let got = parse(text, &p).unwrap().derivatives(y)[3];
            assert!((got - want).abs() < 1e-13 * want.abs().max(1.0), "{text}: {got} vs {want}");
        }
    }

    /// The hyperbolic functions and their first three derivatives against
    /// closed forms derived by hand from `s' = c`, `c' = s`, `t' = h^2`,
    /// `h' = -h t` (`s, c, t, h` = sinh, cosh, tanh, sech of `y`):
    /// `t'' = -2 h^2 t`, `t''' = 4 h^2 t^2 - 2 h^4`, `h'' = h (t^2 - h^2)`,
    /// `h''' = h t (5 h^2 - t^2)`, and for the Bickley profile `h^2 = t'`:
    /// `(h^2)''' = t'''' = 16 h^4 t - 8 h^2 t^3`.
    #[test]
    fn hyperbolic_functions_and_derivatives_in_closed_form() {
        let p = BTreeMap::new();
        for y in [-3.1f64, -0.4, 0.0, 0.7, 2.5, 19.0] {
            let (s, c, t, h) = (y.sinh(), y.cosh(), y.tanh(), 1.0 / y.cosh());
            // each closed form, with the size of the terms it is made of
            // (the tolerance is relative to that)
            let cases: [(&str, [f64; 4], f64); 5] = [
                ("sinh(y)", [s, c, s, c], c),
                ("cosh(y)", [c, s, c, s], c),
                ("tanh(y)", [t, h * h, -2.0 * h * h * t, 4.0 * h * h * t * t - 2.0 * h.powi(4)], h * h),
                ("sech(y)", [h, -h * t, h * (t * t - h * h), h * t * (5.0 * h * h - t * t)], h),
                (
                    "sech(y)^2",
                    [
                        h * h,
                        -2.0 * h * h * t,
                        4.0 * h * h * t * t - 2.0 * h.powi(4),
                        16.0 * h.powi(4) * t - 8.0 * h * h * t.powi(3),
                    ],
                    h * h,
                ),
            ];
            for (text, want, size) in cases {
                let got = parse(text, &p).unwrap().derivatives(y);
                for k in 0..4 {
                    assert!(
                        (got[k] - want[k]).abs() <= 1e-13 * (want[k].abs() + size),
                        "{text} order {k} at {y}: {} vs {}",
                        got[k],
                        want[k]
                    );
                }
            }
            // sech = 1/cosh = 2/(e^y + e^-y): the Bickley profile's two spellings
            let a = parse("sech(y)^2", &p).unwrap().derivatives(y);
            let b = parse("4/(exp(y) + exp(-y))^2", &p).unwrap().derivatives(y);
            for k in 0..4 {
                assert!((a[k] - b[k]).abs() <= 1e-13 * (a[k].abs() + h * h), "{y} {k}: {a:?} vs {b:?}");
            }
        }
        // the chain rule: d/dy tanh(2y) = 2 sech(2y)^2
        let y = 0.3f64;
        let d = parse("tanh(2*y)", &p).unwrap().derivatives(y)[1];
        assert!((d - 2.0 / (2.0 * y).cosh().powi(2)).abs() < 1e-15);
        // functions of constants fold to their values
        assert_eq!(parse("tanh(0) + sinh(0) + cosh(0) + sech(0)", &p).unwrap().constant(), Some(2.0));
        // the perturbed claim fails: tanh' is sech^2, not sech
        let t1 = parse("tanh(y)", &p).unwrap().derivatives(0.7)[1];
        assert!((t1 - 1.0 / 0.7f64.cosh()).abs() > 0.1);
        // the allowed list names them
        assert!(parse("coth(y)", &p)
            .unwrap_err()
            .message
            .contains("allowed: sin, cos, exp, sqrt, sinh, cosh, tanh, sech"));
    }

    /// Far out the functions saturate or overflow as doubles do: `tanh` is
    /// ±1 with derivatives 0 (not NaN from `inf / inf`), `sech` a positive
    /// subnormal where `cosh` overflows, `sinh` and `cosh` infinite.
    #[test]
    fn hyperbolic_functions_far_out() {
        let p = BTreeMap::new();
        for y in [700.0f64, -700.0, 720.0, 1e308, -1e308] {
            let t = parse("tanh(y)", &p).unwrap().derivatives(y);
            assert_eq!(t[0], y.signum());
            assert!(t[1..].iter().all(|d| d.abs() < 1e-300), "{y}: {t:?}");
            let h = parse("sech(y)", &p).unwrap().derivatives(y);
            assert!(h.iter().all(|d| d.is_finite() && d.abs() < 1e-300), "{y}: {h:?}");
            assert!(h[0] >= 0.0);
        }
        // sech 720 = 2 e^-720 = 4.06e-313 (a subnormal), not 0
        let h = parse("sech(y)", &p).unwrap().eval(720.0);
        assert!(h > 4.0e-313 && h < 4.1e-313, "{h}");
        assert_eq!(parse("cosh(y)", &p).unwrap().eval(1e308), f64::INFINITY);
        assert_eq!(parse("sinh(y)", &p).unwrap().eval(-1e308), f64::NEG_INFINITY);
    }

    /// Interval jets of the hyperbolic functions enclose the `f64` jets at
    /// sampled points (orders 0 to 3): near 0, straddling it, and far out.
    #[test]
    fn hyperbolic_enclosures_hold_values_and_derivatives() {
        let p = BTreeMap::new();
        for text in ["tanh(y)", "sech(y)^2", "sinh(y) - cosh(y/2)", "sech(3*y) * tanh(y - 1)", "sech(y)"] {
            let e = Arc::new(parse(text, &p).unwrap());
            for (lo, hi) in [(-0.25, 0.3), (1e-300, 2e-300), (-1e-9, 1e-9), (2.0, 2.5), (-6.0, -5.0), (698.0, 700.0)] {
                for order in 0..4 {
                    let d = Derivative::new(e.clone(), order);
                    let enc = d.enclose(lo, hi);
                    for i in 0..=20 {
                        let y = lo + (hi - lo) * i as f64 / 20.0;
                        let v = d.eval(y);
                        let slack = 1e-12 * v.abs().max(1.0);
                        assert!(
                            enc.lo - slack <= v && v <= enc.hi + slack,
                            "{text} order {order} at {y}: {v} not in {enc:?}"
                        );
                    }
                }
            }
        }
        // U'' of the Bickley jet U = sech^2 y is 4 h^2 t^2 - 2 h^4 =
        // 2 h^2 (3 t^2 - 1) (above), zero at tanh^2 y = 1/3, y = atanh(1/sqrt 3)
        // = 0.6585: proved negative inside, positive outside, changing across.
        let bickley = Arc::new(parse("sech(y)^2", &p).unwrap());
        let second = Derivative::new(bickley, 2);
        assert_eq!(second.sign_on(-0.65, 0.65, 1e7), SignProof::Negative);
        assert_eq!(second.sign_on(0.67, 8.0, 1e7), SignProof::Positive);
        assert_eq!(second.sign_on(0.0, 8.0, 1e7), SignProof::Changes);
    }

    #[test]
    fn repeated_derivatives_of_powers_are_finite_at_zero() {
        // y^2: third derivative 0, not 0 * y^-1 = NaN at y = 0 (regression)
        let e = parse("y^2 + y", &BTreeMap::new()).unwrap();
        assert_eq!(e.derivatives(0.0), [0.0, 1.0, 2.0, 0.0]);
    }

    #[test]
    fn cost_grows_with_size_not_nesting() {
        // Regression: a product of 30 factors took 20 s and sin nested 190
        // deep or 300 sin factors took over 4 GB with symbolic derivatives.
        let p = BTreeMap::new();
        let product = vec!["y"; 30].join("*");
        let nested = "sin(".repeat(190) + "y" + &")".repeat(190);
        let factors = vec!["sin(y)"; 300].join("*");
        for text in [product, nested, factors] {
            let e = parse(&text, &p).unwrap();
            assert!(e.len() <= text.len(), "tape of {} slots for {} bytes", e.len(), text.len());
            assert!(e.derivatives(0.4).iter().all(|x| x.is_finite()));
        }
        let e = parse(&vec!["y"; 30].join("*"), &p).unwrap();
        // d^3/dy^3 y^30 = 30 * 29 * 28 y^27
        let y = 1.01f64;
        assert!((e.derivatives(y)[3] - 24360.0 * y.powi(27)).abs() < 1e-10 * 24360.0 * y.powi(27));
    }

    #[test]
    fn constants_are_folded() {
        let mut p = BTreeMap::new();
        p.insert("a".to_string(), 0.5);
        assert_eq!(parse("2*a + sin(0)", &p).unwrap().constant(), Some(1.0));
        assert_eq!(parse("2*a*y", &p).unwrap().constant(), None);
        assert_eq!(parse("(y - y) + 1", &p).unwrap().constant(), None); // depends on y syntactically
    }

    #[test]
    fn errors_name_the_problem() {
        let p = BTreeMap::new();
        assert!(parse("tan(y)", &p).unwrap_err().message.contains("unknown function"));
        assert!(parse("z + 1", &p).unwrap_err().message.contains("unknown symbol 'z'"));
        assert!(parse("y^y", &p).unwrap_err().message.contains("exponent"));
        assert!(parse("(y", &p).unwrap_err().message.contains("unexpected end of expression"));
        assert!(parse("", &p).unwrap_err().message.contains("empty"));
        // power towers and unary chains count towards the depth (no stack overflow)
        let tower = vec!["2"; 5000].join("^");
        assert!(parse(&tower, &p).unwrap_err().message.contains("nested too deeply"));
        let minus = "-".repeat(5000) + "y";
        assert!(parse(&minus, &p).unwrap_err().message.contains("nested too deeply"));
        let long_name = "x".repeat(5000);
        assert!(parse(&long_name, &p).unwrap_err().message.len() < 200);
    }

    #[test]
    fn enclosures_hold_values_and_derivatives() {
        let p = BTreeMap::new();
        let e = Arc::new(parse("sin(3*y) * exp(-y^2) + sqrt(2 + y)", &p).unwrap());
        for order in 0..4 {
            let d = Derivative::new(e.clone(), order);
            let (lo, hi) = (0.2, 0.45);
            let enc = d.enclose(lo, hi);
            for i in 0..=50 {
                let y = lo + (hi - lo) * i as f64 / 50.0;
                let v = d.eval(y);
                // the float value is within rounding of the exact one, which the enclosure holds
                let slack = 1e-12 * v.abs().max(1.0);
                assert!(enc.lo - slack <= v && v <= enc.hi + slack, "order {order} at {y}: {v} not in {enc:?}");
            }
            if order < 3 {
                // the mean-value form keeps these tight (order 3 has only the natural extension)
                assert!(enc.hi - enc.lo < 10.0, "order {order}: enclosure {enc:?} too loose to be useful");
            }
        }
    }
}
