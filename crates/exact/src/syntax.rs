//! The one front end of the engine's expression languages: the tokenizer
//! and the grammar, shared by the exact polynomials of finite-dimensional
//! specs ([`crate::parse_expression`]) and the floating-point functions of
//! `y` of fluid specs (`fluid::expr::parse`).
//!
//! Grammar (usual precedence, `^` binds tightest and is right-associative,
//! unary minus binds looser than `^`, so `-x^2 = -(x^2)`):
//!
//! ```text
//! expr   := term (('+' | '-') term)*
//! term   := unary (('*' | '/') unary)*
//! unary  := ('+' | '-') unary | power
//! power  := atom ('^' unary)?
//! atom   := number | identifier | identifier '(' expr ')' | '(' expr ')'
//! ```
//!
//! The parser calls a [`Semantics`] for every construct as soon as it is
//! recognised, bottom-up, with the character positions: a language gives
//! the meaning (an exact polynomial, checked against its size limits before
//! each product is formed; or a node of a floating-point tape, folded when
//! constant) and refuses what it does not allow (a function call in a
//! polynomial, an unknown symbol) at the right position. No syntax tree is
//! built, so nothing is kept or dropped recursively, and the nesting depth
//! is bounded before the recursion goes deeper.
//!
//! ```
//! use exact::syntax::{parse, Op, Semantics, SyntaxError};
//! /// Counts the operations of an expression.
//! struct Count;
//! impl Semantics for Count {
//!     type Value = usize;
//!     type Function = ();
//!     type Error = SyntaxError;
//!     fn syntax(&self, e: SyntaxError) -> SyntaxError { e }
//!     fn number(&mut self, _: &str, _: usize) -> Result<usize, SyntaxError> { Ok(0) }
//!     fn symbol(&mut self, _: &str, _: usize) -> Result<usize, SyntaxError> { Ok(0) }
//!     fn function(&mut self, _: &str, _: usize) -> Result<(), SyntaxError> { Ok(()) }
//!     fn call(&mut self, _: (), a: usize, _: usize) -> Result<usize, SyntaxError> { Ok(a + 1) }
//!     fn binary(&mut self, _: Op, a: usize, b: usize, _: usize, _: usize) -> Result<usize, SyntaxError> { Ok(a + b + 1) }
//!     fn negate(&mut self, a: usize, _: usize) -> Result<usize, SyntaxError> { Ok(a + 1) }
//!     fn power(&mut self, a: usize, b: usize, _: usize, _: usize) -> Result<usize, SyntaxError> { Ok(a + b + 1) }
//! }
//! assert_eq!(parse("-x^2 + sin(2*y)", &mut Count, 200, 1000), Ok(5));
//! assert_eq!(parse("(x", &mut Count, 200, 1000).unwrap_err().position, 2);
//! ```

/// A binary operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
}

/// What is wrong with the syntax of an expression.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SyntaxErrorKind {
    /// A character that is not part of the grammar.
    #[error("unexpected character '{0}'")]
    UnexpectedChar(char),
    /// The text ended where more was expected.
    #[error("unexpected end of expression")]
    UnexpectedEnd,
    /// A token in the wrong place.
    #[error("unexpected '{0}'")]
    UnexpectedToken(String),
    /// Nesting beyond the depth limit.
    #[error("expression nested too deeply (limit {0})")]
    TooDeep(usize),
    /// Text beyond the length limit.
    #[error("expression longer than {0} bytes")]
    TooLong(usize),
    /// An empty expression.
    #[error("empty expression")]
    Empty,
}

/// A syntax error and the 0-based character position where it was found.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{kind} (at character {position})")]
pub struct SyntaxError {
    /// What is wrong.
    pub kind: SyntaxErrorKind,
    /// 0-based character offset.
    pub position: usize,
}

/// The meaning a language gives to what the grammar recognises. Every
/// method receives the character position of its construct (for binary
/// operations and powers also that of the right operand), so a refusal
/// names the place.
pub trait Semantics {
    /// What an expression evaluates to.
    type Value;
    /// A function the language allows.
    type Function;
    /// The language's error.
    type Error;
    /// A syntax error in the language's error type.
    fn syntax(&self, e: SyntaxError) -> Self::Error;
    /// A number literal (`3`, `0.25`, `1e-3`).
    fn number(&mut self, text: &str, at: usize) -> Result<Self::Value, Self::Error>;
    /// An identifier not followed by `(`.
    fn symbol(&mut self, name: &str, at: usize) -> Result<Self::Value, Self::Error>;
    /// An identifier followed by `(`: called before the argument is read.
    fn function(&mut self, name: &str, at: usize) -> Result<Self::Function, Self::Error>;
    /// The call of a function on its argument.
    fn call(&mut self, f: Self::Function, arg: Self::Value, at: usize) -> Result<Self::Value, Self::Error>;
    /// `a op b`; `at` is the operator's position, `rhs_at` that of `b`.
    fn binary(
        &mut self,
        op: Op,
        a: Self::Value,
        b: Self::Value,
        at: usize,
        rhs_at: usize,
    ) -> Result<Self::Value, Self::Error>;
    /// `-a`.
    fn negate(&mut self, a: Self::Value, at: usize) -> Result<Self::Value, Self::Error>;
    /// `base ^ exponent`; `at` is the `^`, `exponent_at` the exponent.
    fn power(
        &mut self,
        base: Self::Value,
        exponent: Self::Value,
        at: usize,
        exponent_at: usize,
    ) -> Result<Self::Value, Self::Error>;
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Token<'t> {
    Number(&'t str),
    Ident(&'t str),
    Op(char),
}

fn token_text(t: &Token) -> String {
    match t {
        Token::Number(s) | Token::Ident(s) => crate::quote(s, 40),
        Token::Op(c) => c.to_string(),
    }
}

/// Split into tokens borrowing from the text (no allocation per token).
/// Positions are byte offsets; the grammar is ASCII, so they equal character
/// offsets up to the first non-ASCII character, which is itself an error.
fn tokenize(text: &str) -> Result<Vec<(Token<'_>, usize)>, SyntaxError> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len() / 2 + 1);
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || (c == b'.' && bytes.get(i + 1).is_some_and(|d| d.is_ascii_digit())) {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                i += 1;
            }
            if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                let mut j = i + 1;
                if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                    j += 1;
                }
                if j < bytes.len() && bytes[j].is_ascii_digit() {
                    while j < bytes.len() && bytes[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            out.push((Token::Number(&text[start..i]), start));
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            out.push((Token::Ident(&text[start..i]), start));
        } else if b"+-*/^()".contains(&c) {
            out.push((Token::Op(c as char), i));
            i += 1;
        } else {
            let position = text[..i].chars().count();
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(SyntaxError { kind: SyntaxErrorKind::UnexpectedChar(ch), position });
        }
    }
    Ok(out)
}

/// Parse `text`, calling `semantics` for every construct. `max_depth`
/// bounds the nesting of parentheses, calls, unary signs and powers;
/// `max_length` the text in bytes.
pub fn parse<S: Semantics>(
    text: &str,
    semantics: &mut S,
    max_depth: usize,
    max_length: usize,
) -> Result<S::Value, S::Error> {
    let fail = |s: &S, kind, position| s.syntax(SyntaxError { kind, position });
    if text.len() > max_length {
        return Err(fail(semantics, SyntaxErrorKind::TooLong(max_length), 0));
    }
    let tokens = tokenize(text).map_err(|e| semantics.syntax(e))?;
    if tokens.is_empty() {
        return Err(fail(semantics, SyntaxErrorKind::Empty, 0));
    }
    let mut p = Parser { tokens, pos: 0, end: text.len(), depth: 0, max_depth, semantics };
    let value = p.expr()?;
    if let Some((tok, at)) = p.tokens.get(p.pos) {
        return Err(fail(p.semantics, SyntaxErrorKind::UnexpectedToken(token_text(tok)), *at));
    }
    Ok(value)
}

struct Parser<'a, 't, S: Semantics> {
    tokens: Vec<(Token<'t>, usize)>,
    pos: usize,
    end: usize,
    depth: usize,
    max_depth: usize,
    semantics: &'a mut S,
}

impl<S: Semantics> Parser<'_, '_, S> {
    fn peek(&self) -> Option<Token<'_>> {
        self.tokens.get(self.pos).map(|(t, _)| *t)
    }

    fn here(&self) -> usize {
        self.tokens.get(self.pos).map_or(self.end, |(_, p)| *p)
    }

    fn fail<T>(&self, kind: SyntaxErrorKind, position: usize) -> Result<T, S::Error> {
        Err(self.semantics.syntax(SyntaxError { kind, position }))
    }

    fn enter(&mut self) -> Result<(), S::Error> {
        self.depth += 1;
        if self.depth > self.max_depth {
            return self.fail(SyntaxErrorKind::TooDeep(self.max_depth), self.here());
        }
        Ok(())
    }

    fn expr(&mut self) -> Result<S::Value, S::Error> {
        self.enter()?;
        let mut acc = self.term()?;
        while let Some(Token::Op(c @ ('+' | '-'))) = self.peek() {
            let at = self.here();
            self.pos += 1;
            let rhs_at = self.here();
            let rhs = self.term()?;
            let op = if c == '+' { Op::Add } else { Op::Sub };
            acc = self.semantics.binary(op, acc, rhs, at, rhs_at)?;
        }
        self.depth -= 1;
        Ok(acc)
    }

    fn term(&mut self) -> Result<S::Value, S::Error> {
        let mut acc = self.unary()?;
        while let Some(Token::Op(c @ ('*' | '/'))) = self.peek() {
            let at = self.here();
            self.pos += 1;
            let rhs_at = self.here();
            let rhs = self.unary()?;
            let op = if c == '*' { Op::Mul } else { Op::Div };
            acc = self.semantics.binary(op, acc, rhs, at, rhs_at)?;
        }
        Ok(acc)
    }

    fn unary(&mut self) -> Result<S::Value, S::Error> {
        match self.peek() {
            Some(Token::Op(c @ ('-' | '+'))) => {
                let at = self.here();
                self.pos += 1;
                self.enter()?;
                let v = self.unary()?;
                self.depth -= 1;
                if c == '-' {
                    self.semantics.negate(v, at)
                } else {
                    Ok(v)
                }
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<S::Value, S::Error> {
        let base = self.atom()?;
        if let Some(Token::Op('^')) = self.peek() {
            let at = self.here();
            self.pos += 1;
            let exponent_at = self.here();
            self.enter()?;
            let exponent = self.unary()?;
            self.depth -= 1;
            return self.semantics.power(base, exponent, at, exponent_at);
        }
        Ok(base)
    }

    /// `)` after a parenthesised expression or a call's argument.
    fn close(&mut self) -> Result<(), S::Error> {
        match self.peek() {
            Some(Token::Op(')')) => {
                self.pos += 1;
                Ok(())
            }
            Some(t) => {
                let t = token_text(&t);
                self.fail(SyntaxErrorKind::UnexpectedToken(t), self.here())
            }
            None => self.fail(SyntaxErrorKind::UnexpectedEnd, self.end),
        }
    }

    fn atom(&mut self) -> Result<S::Value, S::Error> {
        let at = self.here();
        let Some((tok, _)) = self.tokens.get(self.pos).copied() else {
            return self.fail(SyntaxErrorKind::UnexpectedEnd, self.end);
        };
        self.pos += 1;
        match tok {
            Token::Number(s) => self.semantics.number(s, at),
            Token::Ident(name) => {
                if let Some(Token::Op('(')) = self.peek() {
                    let f = self.semantics.function(name, at)?;
                    self.pos += 1;
                    let arg = self.expr()?;
                    self.close()?;
                    return self.semantics.call(f, arg, at);
                }
                self.semantics.symbol(name, at)
            }
            Token::Op('(') => {
                let v = self.expr()?;
                self.close()?;
                Ok(v)
            }
            Token::Op(c) => self.fail(SyntaxErrorKind::UnexpectedToken(c.to_string()), at),
        }
    }
}
