//! Expressions in one variable `y` with `sin cos exp sqrt` and the constant
//! `pi`: parsed to a tree, evaluated in floating point, and differentiated
//! symbolically (profiles `U(y)` and noise amplitudes `eta(y)` need their
//! first and second derivatives to machine precision, not by differences).

use std::collections::BTreeMap;
use std::fmt;

/// An expression tree.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A number.
    Num(f64),
    /// The variable `y`.
    Y,
    /// Sum.
    Add(Box<Expr>, Box<Expr>),
    /// Difference.
    Sub(Box<Expr>, Box<Expr>),
    /// Product.
    Mul(Box<Expr>, Box<Expr>),
    /// Quotient.
    Div(Box<Expr>, Box<Expr>),
    /// Integer power.
    Pow(Box<Expr>, i32),
    /// Negation.
    Neg(Box<Expr>),
    /// A function of one argument.
    Call(Func, Box<Expr>),
}

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

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    params: &'a BTreeMap<String, f64>,
    depth: usize,
}

/// Parse an expression in `y` (parameters are substituted by value).
///
/// ```
/// use fluid::expr::parse;
/// let e = parse("1 - cos(2*y)^2 + exp(-y)/2", &Default::default()).unwrap();
/// let y = 0.3f64;
/// assert!((e.eval(y) - (1.0 - (2.0 * y).cos().powi(2) + (-y).exp() / 2.0)).abs() < 1e-15);
/// // d/dy: 4 cos(2y) sin(2y) - exp(-y)/2
/// let d = e.derivative();
/// assert!((d.eval(y) - (4.0 * (2.0 * y).cos() * (2.0 * y).sin() - (-y).exp() / 2.0)).abs() < 1e-14);
/// assert!(parse("log(y)", &Default::default()).unwrap_err().message.contains("unknown function 'log'"));
/// ```
pub fn parse(text: &str, params: &BTreeMap<String, f64>) -> Result<Expr, ExprError> {
    if text.len() > 10_000 {
        return err("expression too long", 0);
    }
    if !text.is_ascii() {
        let pos = text.chars().position(|c| !c.is_ascii()).unwrap_or(0);
        return err("unexpected non-ASCII character", pos);
    }
    let mut p = Parser { s: text.as_bytes(), i: 0, params, depth: 0 };
    p.skip();
    if p.i == p.s.len() {
        return err("empty expression", 0);
    }
    let e = p.expr()?;
    p.skip();
    if p.i != p.s.len() {
        return err(format!("unexpected '{}'", p.s[p.i] as char), p.i);
    }
    Ok(e)
}

impl Parser<'_> {
    fn skip(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip();
        self.s.get(self.i).copied()
    }

    fn expr(&mut self) -> Result<Expr, ExprError> {
        self.depth += 1;
        if self.depth > 200 {
            return err("expression nested too deeply", self.i);
        }
        let mut acc = self.term()?;
        while let Some(c @ (b'+' | b'-')) = self.peek() {
            self.i += 1;
            let rhs = self.term()?;
            acc = if c == b'+' {
                Expr::Add(Box::new(acc), Box::new(rhs))
            } else {
                Expr::Sub(Box::new(acc), Box::new(rhs))
            };
        }
        self.depth -= 1;
        Ok(acc)
    }

    fn term(&mut self) -> Result<Expr, ExprError> {
        let mut acc = self.unary()?;
        while let Some(c @ (b'*' | b'/')) = self.peek() {
            self.i += 1;
            let rhs = self.unary()?;
            acc = if c == b'*' {
                Expr::Mul(Box::new(acc), Box::new(rhs))
            } else {
                Expr::Div(Box::new(acc), Box::new(rhs))
            };
        }
        Ok(acc)
    }

    fn unary(&mut self) -> Result<Expr, ExprError> {
        match self.peek() {
            Some(b'-') => {
                self.i += 1;
                self.depth += 1;
                if self.depth > 200 {
                    return err("expression nested too deeply", self.i);
                }
                let e = self.unary()?;
                self.depth -= 1;
                Ok(Expr::Neg(Box::new(e)))
            }
            Some(b'+') => {
                self.i += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Expr, ExprError> {
        let base = self.atom()?;
        if self.peek() == Some(b'^') {
            self.i += 1;
            let at = self.i;
            let e = self.unary()?;
            let v = e
                .constant()
                .ok_or_else(|| ExprError { message: "the exponent must be a constant integer".into(), position: at })?;
            if v.fract() != 0.0 || v.abs() > 64.0 {
                return err("the exponent must be an integer between -64 and 64", at);
            }
            return Ok(Expr::Pow(Box::new(base), v as i32));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Expr, ExprError> {
        let at = self.i;
        match self.peek() {
            None => err("unexpected end of expression", self.s.len()),
            Some(b'(') => {
                self.i += 1;
                let e = self.expr()?;
                if self.peek() != Some(b')') {
                    return err("missing ')'", self.i);
                }
                self.i += 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => {
                let start = self.i;
                while self.i < self.s.len() && (self.s[self.i].is_ascii_digit() || self.s[self.i] == b'.') {
                    self.i += 1;
                }
                if self.i < self.s.len() && (self.s[self.i] == b'e' || self.s[self.i] == b'E') {
                    let mut j = self.i + 1;
                    if j < self.s.len() && (self.s[j] == b'+' || self.s[j] == b'-') {
                        j += 1;
                    }
                    if j < self.s.len() && self.s[j].is_ascii_digit() {
                        while j < self.s.len() && self.s[j].is_ascii_digit() {
                            j += 1;
                        }
                        self.i = j;
                    }
                }
                let text = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
                let v = exact::parse_number(text).map_err(|e| ExprError { message: e.to_string(), position: start })?;
                Ok(Expr::Num(exact::rational_to_f64(&v)))
            }
            Some(c) if c.is_ascii_alphabetic() || c == b'_' => {
                let start = self.i;
                while self.i < self.s.len() && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == b'_') {
                    self.i += 1;
                }
                let name = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
                if self.peek() == Some(b'(') {
                    let f = match name {
                        "sin" => Func::Sin,
                        "cos" => Func::Cos,
                        "exp" => Func::Exp,
                        "sqrt" => Func::Sqrt,
                        _ => return err(format!("unknown function '{name}' (allowed: sin, cos, exp, sqrt)"), start),
                    };
                    self.i += 1;
                    let arg = self.expr()?;
                    if self.peek() != Some(b')') {
                        return err("missing ')'", self.i);
                    }
                    self.i += 1;
                    return Ok(Expr::Call(f, Box::new(arg)));
                }
                match name {
                    "y" => Ok(Expr::Y),
                    "pi" => Ok(Expr::Num(std::f64::consts::PI)),
                    _ => match self.params.get(name) {
                        Some(v) => Ok(Expr::Num(*v)),
                        None => {
                            let known: Vec<&str> =
                                ["y", "pi"].into_iter().chain(self.params.keys().map(String::as_str)).collect();
                            err(format!("unknown symbol '{name}' (known: {})", known.join(", ")), start)
                        }
                    },
                }
            }
            Some(c) => err(format!("unexpected '{}'", c as char), at),
        }
    }
}

impl Expr {
    /// The value if the expression does not depend on `y`.
    pub fn constant(&self) -> Option<f64> {
        if self.depends_on_y() {
            None
        } else {
            Some(self.eval(0.0))
        }
    }

    fn depends_on_y(&self) -> bool {
        match self {
            Expr::Num(_) => false,
            Expr::Y => true,
            Expr::Add(a, b) | Expr::Sub(a, b) | Expr::Mul(a, b) | Expr::Div(a, b) => {
                a.depends_on_y() || b.depends_on_y()
            }
            Expr::Pow(a, _) | Expr::Neg(a) | Expr::Call(_, a) => a.depends_on_y(),
        }
    }

    /// Value at `y`.
    pub fn eval(&self, y: f64) -> f64 {
        match self {
            Expr::Num(v) => *v,
            Expr::Y => y,
            Expr::Add(a, b) => a.eval(y) + b.eval(y),
            Expr::Sub(a, b) => a.eval(y) - b.eval(y),
            Expr::Mul(a, b) => a.eval(y) * b.eval(y),
            Expr::Div(a, b) => a.eval(y) / b.eval(y),
            Expr::Pow(a, n) => a.eval(y).powi(*n),
            Expr::Neg(a) => -a.eval(y),
            Expr::Call(f, a) => {
                let v = a.eval(y);
                match f {
                    Func::Sin => v.sin(),
                    Func::Cos => v.cos(),
                    Func::Exp => v.exp(),
                    Func::Sqrt => v.sqrt(),
                }
            }
        }
    }

    /// `d/dy`, symbolically.
    pub fn derivative(&self) -> Expr {
        use Expr::*;
        match self {
            Num(_) => Num(0.0),
            Y => Num(1.0),
            Add(x, z) => add(x.derivative(), z.derivative()),
            Sub(x, z) => sub(x.derivative(), z.derivative()),
            Mul(x, z) => add(mul(x.derivative(), (**z).clone()), mul((**x).clone(), z.derivative())),
            Div(x, z) => {
                div(sub(mul(x.derivative(), (**z).clone()), mul((**x).clone(), z.derivative())), pow((**z).clone(), 2))
            }
            // d/dy x^0 = 0 exactly (not 0 * x^-1, which is NaN at x = 0)
            Pow(x, n) => mul(mul(Num(*n as f64), pow((**x).clone(), n - 1)), x.derivative()),
            Neg(x) => neg(x.derivative()),
            Call(f, x) => {
                let outer = match f {
                    Func::Sin => Call(Func::Cos, x.clone()),
                    Func::Cos => neg(Call(Func::Sin, x.clone())),
                    Func::Exp => Call(Func::Exp, x.clone()),
                    Func::Sqrt => div(Num(0.5), Call(Func::Sqrt, x.clone())),
                };
                mul(outer, x.derivative())
            }
        }
    }
}

// Constructors that fold the zeros and ones derivatives produce, so that
// repeated derivatives stay small and never form `0 * x^-1`.
fn add(a: Expr, b: Expr) -> Expr {
    match (&a, &b) {
        (Expr::Num(x), _) if *x == 0.0 => b,
        (_, Expr::Num(y)) if *y == 0.0 => a,
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x + y),
        _ => Expr::Add(Box::new(a), Box::new(b)),
    }
}

fn sub(a: Expr, b: Expr) -> Expr {
    match (&a, &b) {
        (_, Expr::Num(y)) if *y == 0.0 => a,
        (Expr::Num(x), _) if *x == 0.0 => neg(b),
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x - y),
        _ => Expr::Sub(Box::new(a), Box::new(b)),
    }
}

fn mul(a: Expr, b: Expr) -> Expr {
    match (&a, &b) {
        (Expr::Num(x), _) | (_, Expr::Num(x)) if *x == 0.0 => Expr::Num(0.0),
        (Expr::Num(x), _) if *x == 1.0 => b,
        (_, Expr::Num(y)) if *y == 1.0 => a,
        (Expr::Num(x), Expr::Num(y)) => Expr::Num(x * y),
        _ => Expr::Mul(Box::new(a), Box::new(b)),
    }
}

fn div(a: Expr, b: Expr) -> Expr {
    match (&a, &b) {
        (Expr::Num(x), _) if *x == 0.0 => Expr::Num(0.0),
        (_, Expr::Num(y)) if *y == 1.0 => a,
        _ => Expr::Div(Box::new(a), Box::new(b)),
    }
}

fn pow(a: Expr, n: i32) -> Expr {
    match n {
        0 => Expr::Num(1.0),
        1 => a,
        _ => Expr::Pow(Box::new(a), n),
    }
}

fn neg(a: Expr) -> Expr {
    match a {
        Expr::Num(x) => Expr::Num(-x),
        Expr::Neg(inner) => *inner,
        other => Expr::Neg(Box::new(other)),
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Expr::Num(v) => write!(f, "{v}"),
            Expr::Y => write!(f, "y"),
            Expr::Add(a, b) => write!(f, "({a} + {b})"),
            Expr::Sub(a, b) => write!(f, "({a} - {b})"),
            Expr::Mul(a, b) => write!(f, "({a} * {b})"),
            Expr::Div(a, b) => write!(f, "({a} / {b})"),
            Expr::Pow(a, n) => write!(f, "({a})^{n}"),
            Expr::Neg(a) => write!(f, "-({a})"),
            Expr::Call(g, a) => write!(f, "{}({a})", format!("{g:?}").to_lowercase()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        let p = BTreeMap::new();
        for text in ["sin(y)^3 * exp(y/2)", "sqrt(1 + y^2) / cos(y)", "y^-2 + 3*y^4", "exp(-(y - 1)^2)"] {
            let e = parse(text, &p).unwrap();
            let d = e.derivative();
            let dd = d.derivative();
            for y in [0.3, 0.9, 1.4] {
                let h = 1e-5;
                let fd = (e.eval(y + h) - e.eval(y - h)) / (2.0 * h);
                assert!((fd - d.eval(y)).abs() < 1e-8 * (1.0 + fd.abs()), "{text}: {fd} vs {}", d.eval(y));
                let fd2 = (e.eval(y + h) - 2.0 * e.eval(y) + e.eval(y - h)) / (h * h);
                assert!((fd2 - dd.eval(y)).abs() < 1e-4 * (1.0 + fd2.abs()), "{text}: {fd2} vs {}", dd.eval(y));
            }
        }
    }

    #[test]
    fn repeated_derivatives_of_powers_are_finite_at_zero() {
        // y^2: third derivative 0, not 0 * y^-1 = NaN at y = 0 (regression)
        let e = parse("y^2 + y", &BTreeMap::new()).unwrap();
        let d3 = e.derivative().derivative().derivative();
        assert_eq!(d3.eval(0.0), 0.0);
        assert_eq!(e.derivative().derivative().eval(0.0), 2.0);
    }

    #[test]
    fn errors_name_the_problem() {
        let p = BTreeMap::new();
        assert!(parse("tan(y)", &p).unwrap_err().message.contains("unknown function"));
        assert!(parse("z + 1", &p).unwrap_err().message.contains("unknown symbol 'z'"));
        assert!(parse("y^y", &p).unwrap_err().message.contains("exponent"));
        assert!(parse("(y", &p).unwrap_err().message.contains("missing ')'"));
        assert!(parse("", &p).unwrap_err().message.contains("empty"));
    }
}
