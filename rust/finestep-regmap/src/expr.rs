//! The integer expressions of `hdl/interface.toml`'s parameter constraints: a subset of
//! Verilog's constant expressions that reads the same in the Verilog checks, in Rust
//! and in the docs.
//!
//! Grammar (Verilog's precedence, lowest first): `c ? a : b`; `||`; `&&`; `==`, `!=`;
//! `<`, `<=`, `>`, `>=`; `+`, `-`; `*`; unary `!`, `-`; decimal integers, names
//! (UPPER_SNAKE: a build parameter or a derived value) and parentheses. A comparison or
//! a logical operator gives 1 or 0; `!` and the conditions take any nonzero value as
//! true. Values are 64-bit: the operands are Verilog integers, which cannot overflow
//! that here.

use std::collections::BTreeMap;
use std::fmt;

/// A parsed expression.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Expr {
    /// A decimal integer.
    Int(i64),
    /// A parameter or derived value.
    Name(String),
    /// `!e` or `-e`.
    Unary(char, Box<Expr>),
    /// `a op b`.
    Binary(&'static str, Box<Expr>, Box<Expr>),
    /// `c ? a : b`.
    Cond(Box<Expr>, Box<Expr>, Box<Expr>),
}

const LEVELS: [&[&str]; 6] = [&["||"], &["&&"], &["==", "!="], &["<=", ">=", "<", ">"], &["+", "-"], &["*"]];

impl Expr {
    /// Parses `text`; the error says what was expected where.
    pub fn parse(text: &str) -> Result<Expr, String> {
        let tokens = tokens(text)?;
        let mut parser = Parser { tokens: &tokens, at: 0 };
        let expr = parser.cond()?;
        match parser.tokens.get(parser.at) {
            None => Ok(expr),
            Some(token) => Err(format!("unexpected {token:?} in {text:?}")),
        }
    }

    /// The names it reads, each once, in order of first use.
    pub fn names(&self) -> Vec<&str> {
        let mut names = Vec::new();
        self.collect(&mut names);
        names
    }

    fn collect<'a>(&'a self, names: &mut Vec<&'a str>) {
        match self {
            Expr::Int(_) => {}
            Expr::Name(name) => {
                if !names.contains(&name.as_str()) {
                    names.push(name);
                }
            }
            Expr::Unary(_, e) => e.collect(names),
            Expr::Binary(_, a, b) => {
                a.collect(names);
                b.collect(names);
            }
            Expr::Cond(c, a, b) => {
                c.collect(names);
                a.collect(names);
                b.collect(names);
            }
        }
    }

    /// Its value with `values` for the names (`None` when a name has none).
    pub fn eval(&self, values: &BTreeMap<String, i64>) -> Option<i64> {
        Some(match self {
            Expr::Int(value) => *value,
            Expr::Name(name) => *values.get(name)?,
            Expr::Unary('!', e) => i64::from(e.eval(values)? == 0),
            Expr::Unary(_, e) => -e.eval(values)?,
            Expr::Binary(op, a, b) => {
                let (a, b) = (a.eval(values)?, b.eval(values)?);
                match *op {
                    "||" => i64::from(a != 0 || b != 0),
                    "&&" => i64::from(a != 0 && b != 0),
                    "==" => i64::from(a == b),
                    "!=" => i64::from(a != b),
                    "<=" => i64::from(a <= b),
                    ">=" => i64::from(a >= b),
                    "<" => i64::from(a < b),
                    ">" => i64::from(a > b),
                    "+" => a + b,
                    "-" => a - b,
                    _ => a * b,
                }
            }
            Expr::Cond(c, a, b) => {
                if c.eval(values)? != 0 {
                    a.eval(values)?
                } else {
                    b.eval(values)?
                }
            }
        })
    }

    /// As Verilog, fully parenthesised, each name through `rename`.
    pub fn verilog(&self, rename: &dyn Fn(&str) -> String) -> String {
        match self {
            Expr::Int(value) => value.to_string(),
            Expr::Name(name) => rename(name),
            Expr::Unary(op, e) => format!("{op}({})", e.verilog(rename)),
            Expr::Binary(op, a, b) => format!("({} {op} {})", a.verilog(rename), b.verilog(rename)),
            Expr::Cond(c, a, b) => {
                format!("({} ? {} : {})", c.verilog(rename), a.verilog(rename), b.verilog(rename))
            }
        }
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.verilog(&|name| name.to_string()))
    }
}

fn tokens(text: &str) -> Result<Vec<String>, String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push(chars[start..i].iter().collect());
        } else {
            let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
            if ["||", "&&", "==", "!=", "<=", ">="].contains(&two.as_str()) {
                out.push(two);
                i += 2;
            } else if "()?:!<>+-*".contains(c) {
                out.push(c.to_string());
                i += 1;
            } else {
                return Err(format!("unexpected character {c:?} in {text:?}"));
            }
        }
    }
    Ok(out)
}

struct Parser<'a> {
    tokens: &'a [String],
    at: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&str> {
        self.tokens.get(self.at).map(String::as_str)
    }

    fn expect(&mut self, token: &str) -> Result<(), String> {
        if self.peek() == Some(token) {
            self.at += 1;
            Ok(())
        } else {
            Err(format!("expected {token:?}, found {:?}", self.peek().unwrap_or("the end")))
        }
    }

    fn cond(&mut self) -> Result<Expr, String> {
        let c = self.binary(0)?;
        if self.peek() != Some("?") {
            return Ok(c);
        }
        self.at += 1;
        let a = self.cond()?;
        self.expect(":")?;
        let b = self.cond()?;
        Ok(Expr::Cond(Box::new(c), Box::new(a), Box::new(b)))
    }

    fn binary(&mut self, level: usize) -> Result<Expr, String> {
        if level == LEVELS.len() {
            return self.unary();
        }
        let mut left = self.binary(level + 1)?;
        while let Some(op) = LEVELS[level].iter().find(|op| self.peek() == Some(**op)) {
            self.at += 1;
            let right = self.binary(level + 1)?;
            left = Expr::Binary(op, Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn unary(&mut self) -> Result<Expr, String> {
        match self.peek() {
            Some(op @ ("!" | "-")) => {
                let op = op.chars().next().unwrap_or('!');
                self.at += 1;
                Ok(Expr::Unary(op, Box::new(self.unary()?)))
            }
            Some("(") => {
                self.at += 1;
                let e = self.cond()?;
                self.expect(")")?;
                Ok(e)
            }
            Some(token) if token.starts_with(|c: char| c.is_ascii_digit()) => {
                let value = token.parse().map_err(|_| format!("{token:?} is not a decimal integer"))?;
                self.at += 1;
                Ok(Expr::Int(value))
            }
            Some(token) if token.starts_with(|c: char| c.is_ascii_uppercase()) => {
                let name = token.to_string();
                self.at += 1;
                Ok(Expr::Name(name))
            }
            other => Err(format!("expected a value, found {:?}", other.unwrap_or("the end"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(text: &str, pairs: &[(&str, i64)]) -> i64 {
        let values = pairs.iter().map(|(n, v)| (n.to_string(), *v)).collect();
        Expr::parse(text).unwrap().eval(&values).unwrap()
    }

    #[test]
    fn precedence_is_verilogs() {
        assert_eq!(eval("1 + 2 * 3", &[]), 7);
        assert_eq!(eval("A - 1 <= 15 && !B", &[("A", 16), ("B", 0)]), 1);
        assert_eq!(eval("A - 1 <= 15 && !B", &[("A", 17), ("B", 0)]), 0);
        assert_eq!(eval("A <= 2 ? 1 : A <= 4 ? 2 : 3", &[("A", 3)]), 2);
        assert_eq!(eval("A <= 2 ? 1 : A <= 4 ? 2 : 3", &[("A", 8)]), 3);
        assert_eq!(eval("(1 || 0) == 1", &[]), 1);
        assert_eq!(eval("-A + 3", &[("A", 5)]), -2);
    }

    #[test]
    fn the_verilog_reads_the_same() {
        let e = Expr::parse("A <= 2 ? 1 : 2 + B * 3").unwrap();
        assert_eq!(e.verilog(&|n| format!("X_{n}")), "((X_A <= 2) ? 1 : (2 + (X_B * 3)))");
        assert_eq!(e.names(), ["A", "B"]);
    }

    #[test]
    fn broken_text_is_refused() {
        for text in ["1 +", "(A", "A $ B", "a", "A ? 1", "1 2"] {
            assert!(Expr::parse(text).is_err(), "{text}");
        }
    }
}
