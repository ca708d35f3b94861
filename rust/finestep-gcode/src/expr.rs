//! Values, parameters and expressions as LinuxCNC's rs274ngc reads them: a word's value is
//! a number, `[expression]`, `#parameter` or a unary function, with an optional sign;
//! binary operators by LinuxCNC's precedence (`**`; `*` `/` `MOD`; `+` `-`; `EQ` `NE`
//! `GT` `GE` `LT` `LE`; `AND` `OR` `XOR`), left to right within a level.

use crate::error::LineError;

/// The largest magnitude a literal number in the program may have.
pub(crate) const MAX_NUMBER: f64 = 1e9;
pub(crate) use crate::persistent::MAX_PARAMETER;
/// Two values are EQ when closer than this (LinuxCNC's TOLERANCE_EQUAL).
const TOLERANCE_EQUAL: f64 = 0.0001;
/// Expressions nest at most this deep (a stack guard for hostile input).
const MAX_DEPTH: usize = 64;

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Op {
    Power,
    Times,
    Divide,
    Mod,
    Plus,
    Minus,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    fn precedence(self) -> u8 {
        match self {
            Op::And | Op::Or | Op::Xor => 2,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 3,
            Op::Plus | Op::Minus => 4,
            Op::Times | Op::Divide | Op::Mod => 5,
            Op::Power => 6,
        }
    }
}

/// A unary function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Func {
    Abs,
    Acos,
    Asin,
    Cos,
    Exp,
    Fix,
    Fup,
    Round,
    Ln,
    Sin,
    Sqrt,
    Tan,
}

const FUNCS: [(&str, Func); 12] = [
    ("abs", Func::Abs),
    ("acos", Func::Acos),
    ("asin", Func::Asin),
    ("cos", Func::Cos),
    ("exp", Func::Exp),
    ("fix", Func::Fix),
    ("fup", Func::Fup),
    ("round", Func::Round),
    ("ln", Func::Ln),
    ("sin", Func::Sin),
    ("sqrt", Func::Sqrt),
    ("tan", Func::Tan),
];

/// A value to compute when its block executes. `column` fields point into the source
/// line (1-based) for errors.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Expr {
    Num(f64),
    /// `#expr`: a numbered parameter.
    Param(Box<Expr>, usize),
    /// `#<name>` (lower case, blanks removed).
    Named(Box<str>, usize),
    Neg(Box<Expr>),
    Func(Func, Box<Expr>, usize),
    /// `ATAN[y]/[x]`, in degrees.
    Atan(Box<Expr>, Box<Expr>, usize),
    /// `EXISTS[#<name>]`.
    Exists(Box<str>),
    /// `a op b`: the operator's column, and the column of the `[` when the operation is
    /// the whole of a `[bracket]` standing as a value (an operand, a word's value), else
    /// 0. Such a value must be a finite number, as rs274 checks every value it reads (an
    /// operation inside one expression may give NaN: `[1 GT 2 MOD 0]` is 0, no error).
    /// Columns are u32 to keep the node small; a column beyond that saturates.
    Binary(Op, Box<Expr>, Box<Expr>, u32, u32),
}

/// Where an expression reads its parameters.
pub(crate) trait Params {
    /// `#n`, 1 <= n <= [`MAX_PARAMETER`].
    fn numbered(&self, n: usize) -> f64;
    /// `#<name>`, or None when it is not defined.
    fn named(&self, name: &str) -> Option<f64>;
    /// Whether `#<name>` is defined, for `EXISTS`.
    fn exists(&self, name: &str) -> bool;
}

/// Parameters for lexer tests: none defined, all zero.
#[cfg(test)]
pub(crate) struct NoParams;

#[cfg(test)]
impl Params for NoParams {
    fn numbered(&self, _: usize) -> f64 {
        0.0
    }
    fn named(&self, _: &str) -> Option<f64> {
        None
    }
    fn exists(&self, _: &str) -> bool {
        false
    }
}

impl Expr {
    /// The value, reading parameters from `params`.
    pub(crate) fn eval(&self, params: &dyn Params) -> Result<f64, LineError> {
        Ok(match self {
            Expr::Num(v) => *v,
            Expr::Param(index, column) => {
                let n = index.eval(params)?;
                params.numbered(parameter_index(n, *column)?)
            }
            Expr::Named(name, column) => params
                .named(name)
                .ok_or_else(|| LineError::new(*column, format!("named parameter #<{name}> is not defined")))?,
            Expr::Neg(e) => -e.eval(params)?,
            Expr::Func(f, e, column) => finite(apply(*f, e.eval(params)?, *column)?, *column)?,
            Expr::Atan(y, x, column) => finite(y.eval(params)?.atan2(x.eval(params)?).to_degrees(), *column)?,
            Expr::Exists(name) => f64::from(u8::from(params.exists(name))),
            Expr::Binary(op, a, b, column, group) => {
                let v = binary(*op, a.eval(params)?, b.eval(params)?, *column as usize)?;
                if *group != 0 {
                    finite(v, *group as usize)?
                } else {
                    v
                }
            }
        })
    }
}

/// A column as stored in [`Expr::Binary`] (saturating; columns start at 1, so 0 is free).
fn small(column: usize) -> u32 {
    u32::try_from(column).unwrap_or(u32::MAX)
}

/// rs274's check of every value it reads: NaN or an infinity is an error.
fn finite(v: f64, column: usize) -> Result<f64, LineError> {
    if v.is_nan() {
        Err(LineError::new(column, "calculation resulted in 'not a number'"))
    } else if v.is_infinite() {
        Err(LineError::new(column, "calculation resulted in an infinite value"))
    } else {
        Ok(v)
    }
}

/// A numbered parameter's index from its computed value.
pub(crate) fn parameter_index(value: f64, column: usize) -> Result<usize, LineError> {
    let rounded = value.round();
    if (value - rounded).abs() > 0.0001 || !(1.0..=MAX_PARAMETER as f64).contains(&rounded) {
        return Err(LineError::new(column, format!("parameter number {value} out of range (1 to {MAX_PARAMETER})")));
    }
    Ok(rounded as usize)
}

fn apply(f: Func, v: f64, column: usize) -> Result<f64, LineError> {
    let domain = |ok: bool, what: &str| {
        if ok {
            Ok(())
        } else {
            Err(LineError::new(column, format!("{what} of {v} is undefined")))
        }
    };
    Ok(match f {
        Func::Abs => v.abs(),
        Func::Acos => {
            domain((-1.0..=1.0).contains(&v), "ACOS")?;
            v.acos().to_degrees()
        }
        Func::Asin => {
            domain((-1.0..=1.0).contains(&v), "ASIN")?;
            v.asin().to_degrees()
        }
        Func::Cos => v.to_radians().cos(),
        Func::Exp => v.exp(),
        Func::Fix => v.floor(),
        Func::Fup => v.ceil(),
        // LinuxCNC rounds halves away from zero.
        Func::Round => v.round(),
        Func::Ln => {
            domain(v > 0.0, "LN")?;
            v.ln()
        }
        Func::Sin => v.to_radians().sin(),
        Func::Sqrt => {
            domain(v >= 0.0, "SQRT")?;
            v.sqrt()
        }
        Func::Tan => v.to_radians().tan(),
    })
}

fn truth(v: f64) -> bool {
    v != 0.0
}

fn binary(op: Op, a: f64, b: f64, column: usize) -> Result<f64, LineError> {
    let flag = |c: bool| f64::from(u8::from(c));
    Ok(match op {
        Op::Power => {
            if a < 0.0 && b.fract() != 0.0 {
                return Err(LineError::new(column, "attempt to raise a negative number to a non-integer power"));
            }
            a.powf(b)
        }
        Op::Times => a * b,
        Op::Divide if b == 0.0 => return Err(LineError::new(column, "attempt to divide by zero")),
        // rs274: fmod by zero is NaN, an error only if it reaches a value (see Binary).
        Op::Mod if b == 0.0 => f64::NAN,
        Op::Divide => a / b,
        Op::Mod => {
            let m = a % b;
            if m < 0.0 {
                m + b.abs()
            } else {
                m
            }
        }
        Op::Plus => a + b,
        Op::Minus => a - b,
        Op::Eq => flag((a - b).abs() < TOLERANCE_EQUAL),
        Op::Ne => flag((a - b).abs() >= TOLERANCE_EQUAL),
        Op::Gt => flag(a > b),
        Op::Ge => flag(a >= b),
        Op::Lt => flag(a < b),
        Op::Le => flag(a <= b),
        Op::And => flag(truth(a) && truth(b)),
        Op::Or => flag(truth(a) || truth(b)),
        Op::Xor => flag(truth(a) != truth(b)),
    })
}

/// A line with blanks and comments removed and letters in lower case, each character
/// with its 1-based column in the source line.
pub(crate) struct Chars<'a> {
    pub chars: &'a [char],
    pub columns: &'a [usize],
    pub i: usize,
}

impl Chars<'_> {
    pub(crate) fn peek(&self) -> Option<char> {
        self.chars.get(self.i).copied()
    }
    pub(crate) fn peek_at(&self, ahead: usize) -> Option<char> {
        self.chars.get(self.i + ahead).copied()
    }
    /// The source column of the current character (one past the end at the end).
    pub(crate) fn column(&self) -> usize {
        match self.columns.get(self.i) {
            Some(&c) => c,
            None => self.columns.last().map_or(1, |&c| c + 1),
        }
    }
    pub(crate) fn starts_with(&self, word: &str) -> bool {
        let n = word.len();
        self.chars.len() >= self.i + n && word.chars().zip(&self.chars[self.i..self.i + n]).all(|(w, &c)| w == c)
    }
    fn expect(&mut self, c: char, what: &str) -> Result<(), LineError> {
        if self.peek() == Some(c) {
            self.i += 1;
            Ok(())
        } else {
            Err(LineError::new(self.column(), format!("expected {c:?} {what}")))
        }
    }
}

/// What a value is read for, named in errors: `word X`, `the expression`.
#[derive(Debug, Clone, Copy)]
pub(crate) enum What {
    Word(char),
    Named(&'static str),
}

impl std::fmt::Display for What {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            What::Word(letter) => write!(f, "word {letter}"),
            What::Named(what) => f.write_str(what),
        }
    }
}

/// Reads a real value: an optional sign and a number, `[expression]`, `#parameter` or a
/// function. `word` names what is being read, for errors (`word X`).
pub(crate) fn read_value(s: &mut Chars, word: What, depth: usize) -> Result<Expr, LineError> {
    if depth > MAX_DEPTH {
        return Err(LineError::new(s.column(), "expression nested too deeply"));
    }
    let column = s.column();
    match s.peek() {
        None => Err(LineError::new(column, format!("missing value for {word}"))),
        Some('-') => {
            s.i += 1;
            // A negative literal folds to a number (the common case stays a plain value).
            match read_value(s, word, depth + 1)? {
                Expr::Num(v) => Ok(Expr::Num(-v)),
                e => Ok(Expr::Neg(Box::new(e))),
            }
        }
        Some('+') => {
            s.i += 1;
            read_value(s, word, depth + 1)
        }
        Some('[') => {
            s.i += 1;
            match read_expression(s, depth + 1)? {
                Expr::Binary(op, a, b, op_column, _) => Ok(Expr::Binary(op, a, b, op_column, small(column))),
                e => Ok(e),
            }
        }
        Some('#') => {
            s.i += 1;
            if s.peek() == Some('<') {
                let name = read_parameter_name(s, column)?;
                Ok(Expr::Named(name.into(), column))
            } else {
                let index = read_value(s, What::Named("parameter number"), depth + 1)?;
                if let Expr::Num(n) = index {
                    parameter_index(n, column)?;
                }
                Ok(Expr::Param(Box::new(index), column))
            }
        }
        Some(c) if c.is_ascii_digit() || c == '.' => read_number(s, word).map(Expr::Num),
        Some(c) if c.is_ascii_alphabetic() => read_function(s, depth),
        Some(c) => Err(LineError::new(column, format!("unexpected character {c:?} in the value of {word}"))),
    }
}

/// `<name>` of a named parameter, after its `#` (which stands at `column`): as
/// [`read_name`], with LinuxCNC's `#<_hal[pin]>` refused (it reads the machine's HAL
/// pins, which a part program alone lacks). `#<_ini[section]name>` reads the machine's
/// INI file ([`crate::Options::ini`]).
pub(crate) fn read_parameter_name(s: &mut Chars, column: usize) -> Result<String, LineError> {
    let name = read_name(s)?;
    if name.starts_with("_hal[") {
        return Err(LineError::new(column, format!("unsupported: #<_hal[...]> ({})", crate::unsupported::HAL)));
    }
    Ok(name)
}

/// `<name>` after `#` or in `EXISTS[#<name>]`: lower case, blanks already removed.
pub(crate) fn read_name(s: &mut Chars) -> Result<String, LineError> {
    let column = s.column();
    s.expect('<', "to open a parameter name")?;
    let mut name = String::new();
    loop {
        match s.peek() {
            Some('>') => {
                s.i += 1;
                break;
            }
            Some(c) if c.is_ascii_graphic() => {
                name.push(c);
                s.i += 1;
            }
            Some(c) => return Err(LineError::new(s.column(), format!("character {c:?} in a parameter name"))),
            None => return Err(LineError::new(column, "parameter name not closed with '>'")),
        }
    }
    if name.is_empty() {
        return Err(LineError::new(column, "empty parameter name"));
    }
    Ok(name)
}

fn read_number(s: &mut Chars, word: What) -> Result<f64, LineError> {
    let column = s.column();
    let start = s.i;
    let (mut digits, mut points) = (0usize, 0usize);
    while let Some(c) = s.peek() {
        if c.is_ascii_digit() {
            digits += 1;
        } else if c == '.' {
            points += 1;
        } else {
            break;
        }
        s.i += 1;
    }
    if digits == 0 || points > 1 {
        return Err(LineError::new(column, format!("bad number for {word}")));
    }
    // `X1e308` written as one word reads as an exponent; `X1 E5`, with a blank between,
    // is the word E (M66-M68's analog channel).
    let adjacent = s.i > 0 && s.columns.get(s.i).is_some_and(|&c| c == s.columns[s.i - 1] + 1);
    if adjacent && s.peek() == Some('e') && s.peek_at(1).is_some_and(|c| c.is_ascii_digit() || c == '-' || c == '+') {
        return Err(LineError::new(
            s.column(),
            format!("unsupported: exponent in the number of {word} ({})", crate::unsupported::EXPONENT),
        ));
    }
    // Digits and the point are ASCII: a short number parses from a stack buffer.
    let mut buffer = [0u8; 64];
    let n = s.i - start;
    let parsed = if n <= buffer.len() {
        for (b, &c) in buffer.iter_mut().zip(&s.chars[start..s.i]) {
            *b = c as u8;
        }
        std::str::from_utf8(&buffer[..n]).map_or(Ok(f64::NAN), str::parse::<f64>)
    } else {
        s.chars[start..s.i].iter().collect::<String>().parse::<f64>()
    };
    match parsed {
        Ok(value) if value.is_finite() && value.abs() <= MAX_NUMBER => Ok(value),
        _ => Err(LineError::new(column, format!("number out of range for {word}"))),
    }
}

fn read_function(s: &mut Chars, depth: usize) -> Result<Expr, LineError> {
    let column = s.column();
    if s.starts_with("atan") {
        s.i += 4;
        s.expect('[', "after ATAN")?;
        let y = read_expression(s, depth + 1)?;
        s.expect('/', "between ATAN's [y] and [x]")?;
        s.expect('[', "for ATAN's [x]")?;
        let x = read_expression(s, depth + 1)?;
        return Ok(Expr::Atan(Box::new(y), Box::new(x), column));
    }
    if s.starts_with("exists") {
        s.i += 6;
        s.expect('[', "after EXISTS")?;
        let hash = s.column();
        s.expect('#', "in EXISTS[#<name>]")?;
        let name = read_parameter_name(s, hash)?;
        s.expect(']', "to close EXISTS[...]")?;
        return Ok(Expr::Exists(name.into()));
    }
    for (name, f) in FUNCS {
        if s.starts_with(name) && s.peek_at(name.len()) == Some('[') {
            s.i += name.len() + 1;
            let e = read_expression(s, depth + 1)?;
            return Ok(Expr::Func(f, Box::new(e), column));
        }
    }
    let word: String = s.chars[s.i..].iter().take_while(|c| c.is_ascii_alphabetic()).collect();
    Err(LineError::new(column, format!("unknown function or operator {:?}", word.to_uppercase())))
}

fn read_operator(s: &mut Chars) -> Result<Option<Op>, LineError> {
    let column = s.column();
    let ops: [(&str, Op); 15] = [
        ("**", Op::Power),
        ("*", Op::Times),
        ("/", Op::Divide),
        ("mod", Op::Mod),
        ("+", Op::Plus),
        ("-", Op::Minus),
        ("eq", Op::Eq),
        ("ne", Op::Ne),
        ("gt", Op::Gt),
        ("ge", Op::Ge),
        ("lt", Op::Lt),
        ("le", Op::Le),
        ("and", Op::And),
        ("or", Op::Or),
        ("xor", Op::Xor),
    ];
    if s.peek() == Some(']') {
        s.i += 1;
        return Ok(None);
    }
    for (text, op) in ops {
        if s.starts_with(text) {
            s.i += text.len();
            return Ok(Some(op));
        }
    }
    match s.peek() {
        None => Err(LineError::new(column, "expression not closed with ']'")),
        Some(c) => Err(LineError::new(column, format!("unknown operator at {c:?}"))),
    }
}

/// Reads an expression after its `[`, through its `]`.
pub(crate) fn read_expression(s: &mut Chars, depth: usize) -> Result<Expr, LineError> {
    if depth > MAX_DEPTH {
        return Err(LineError::new(s.column(), "expression nested too deeply"));
    }
    let mut values = vec![read_value(s, What::Named("the expression"), depth + 1)?];
    let mut ops: Vec<(Op, usize)> = Vec::new();
    let reduce = |values: &mut Vec<Expr>, ops: &mut Vec<(Op, usize)>| {
        let (op, column) = ops.pop().expect("operator");
        let b = values.pop().expect("operand");
        let a = values.pop().expect("operand");
        values.push(Expr::Binary(op, Box::new(a), Box::new(b), small(column), 0));
    };
    loop {
        let column = s.column();
        let next = read_operator(s)?;
        while let Some(&(top, _)) = ops.last() {
            if next.is_some_and(|n| n.precedence() > top.precedence()) {
                break;
            }
            reduce(&mut values, &mut ops);
        }
        match next {
            None => break,
            Some(op) => {
                ops.push((op, column));
                values.push(read_value(s, What::Named("the expression"), depth + 1)?);
            }
        }
    }
    Ok(values.pop().expect("one value"))
}
