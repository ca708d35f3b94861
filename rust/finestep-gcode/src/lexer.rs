//! Lexing one source line into its words, parameter assignments and O-word, with the
//! values still expressions (computed when the block executes).
//!
//! As in LinuxCNC, blanks (spaces and tabs) are removed everywhere outside comments,
//! also inside numbers and parameter names (`G 1 X 1 0 . 5` is `G1 X10.5`), and letters
//! are case-insensitive. Comments are `( ... )` (not nested, closed on the same line)
//! and everything after `;`; the last `( ... )` of a line is kept when it is an active
//! comment (`(MSG,` `(DEBUG,` `(PRINT,` `(LOG,` `(ABORT,` ..., [`crate::message`]). This
//! module is the one place that reads the comment syntax ([`walk`]). A leading `/`
//! (block delete) is accepted and ignored: the block runs, as with LinuxCNC's
//! block-delete switch off.

use crate::error::LineError;
use crate::expr::{read_expression, read_name, read_parameter_name, read_value, Chars, Expr, What};
use crate::message::{classify, LexedMessage};

/// One word with its value computed: an upper-case letter, its value, and the 1-based
/// column of the letter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Word {
    pub letter: char,
    pub value: f64,
    pub column: usize,
}

/// One word as written: its value an expression.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RawWord {
    pub letter: char,
    pub value: Expr,
    pub column: usize,
}

/// The parameter an assignment sets.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Target {
    /// `#expr = ...`
    Numbered(Expr),
    /// `#<name> = ...`
    Named(Box<str>),
}

/// `#... = value`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Assign {
    pub target: Target,
    pub value: Expr,
    pub column: usize,
}

/// What an O-word line does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum OKind {
    Sub,
    Endsub,
    Call,
    Return,
    If,
    Elseif,
    Else,
    Endif,
    While,
    Endwhile,
    Do,
    Repeat,
    Endrepeat,
    Break,
    Continue,
}

const O_KEYWORDS: [(&str, OKind); 15] = [
    ("endsub", OKind::Endsub),
    ("endif", OKind::Endif),
    ("endwhile", OKind::Endwhile),
    ("endrepeat", OKind::Endrepeat),
    ("elseif", OKind::Elseif),
    ("else", OKind::Else),
    ("sub", OKind::Sub),
    ("call", OKind::Call),
    ("return", OKind::Return),
    ("if", OKind::If),
    ("while", OKind::While),
    ("do", OKind::Do),
    ("repeat", OKind::Repeat),
    ("break", OKind::Break),
    ("continue", OKind::Continue),
];

/// An O-word statement: `o100 if [...]`, `o<name> call [1] [2]`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OWord {
    /// `100` or `<name>` (lower case).
    pub label: Box<str>,
    pub kind: OKind,
    /// The column of the `O`.
    pub column: usize,
    /// The bracketed expressions after the keyword.
    pub args: Vec<Expr>,
}

/// One lexed line.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Line {
    pub words: Vec<RawWord>,
    pub assigns: Vec<Assign>,
    pub oword: Option<OWord>,
    /// The line's last parenthesised comment, if that is an active one.
    pub message: Option<Box<LexedMessage>>,
}

/// Walks `line` as LinuxCNC reads it: `keep` gets every character outside comments
/// but blanks (spaces, tabs), with its 1-based column, up to a `;`; gives the text of
/// the last parenthesised comment and the column of its `(` (None if it has none). An
/// unclosed or nested comment is an error, as rs274's (`Unclosed comment found`,
/// `Nested comment found`).
fn walk(line: &str, mut keep: impl FnMut(char, usize)) -> Result<Option<(&str, usize)>, LineError> {
    let mut last = None;
    // The open comment: its column and the byte its text starts at.
    let mut comment_open: Option<(usize, usize)> = None;
    for (index, (byte, c)) in line.char_indices().enumerate() {
        let column = index + 1;
        if let Some((open, start)) = comment_open {
            match c {
                ')' => {
                    last = Some((&line[start..byte], open));
                    comment_open = None;
                }
                '(' => return Err(LineError::new(column, "nested comment")),
                _ => {}
            }
            continue;
        }
        match c {
            ' ' | '\t' => {}
            '(' => comment_open = Some((column, byte + 1)),
            ';' => break,
            c => keep(c, column),
        }
    }
    match comment_open {
        Some((open, _)) => Err(LineError::new(open, "unclosed comment")),
        None => Ok(last),
    }
}

/// Whether a line holds anything outside comments, and whether an `O` stands there: a
/// quick look (bytes, no errors) before a line is lexed; [`walk`] reads it in full.
pub(crate) fn scan(text: &str) -> (bool, bool) {
    let (mut content, mut o, mut comment) = (false, false, false);
    // Bytes will do: every character that matters here is ASCII.
    for &c in text.as_bytes() {
        match c {
            _ if comment => comment = c != b')',
            b'(' => comment = true,
            b';' => break,
            b' ' | b'\t' => {}
            b'o' | b'O' => (content, o) = (true, true),
            _ => content = true,
        }
    }
    (content, o)
}

/// The active comment of `line` (its last parenthesised comment, if that is one), for
/// a line without words, which is otherwise skipped; an error where the line's comments
/// do not lex.
pub(crate) fn line_message(line: &str) -> Result<Option<LexedMessage>, LineError> {
    Ok(walk(line, |_, _| {})?.and_then(|(text, column)| classify(text, column)))
}

/// Lexes one line (without its line terminator).
#[cfg(test)]
pub(crate) fn lex_line(line: &str) -> Result<Line, LineError> {
    lex_line_into(line, &mut Vec::new(), &mut Vec::new())
}

/// Lexes one line, with `chars` and `columns` as scratch space (reused across lines).
pub(crate) fn lex_line_into(line: &str, chars: &mut Vec<char>, columns: &mut Vec<usize>) -> Result<Line, LineError> {
    let mut out = Line::default();
    lex_into(line, chars, columns, &mut out)?;
    Ok(out)
}

/// Lexes one line into `out` (cleared first), with scratch space as [`lex_line_into`].
pub(crate) fn lex_into(
    line: &str,
    chars: &mut Vec<char>,
    columns: &mut Vec<usize>,
    out: &mut Line,
) -> Result<(), LineError> {
    out.words.clear();
    out.assigns.clear();
    out.oword = None;
    out.message = None;
    if lex_plain(line, out) {
        return Ok(());
    }
    out.words.clear();
    chars.clear();
    columns.clear();
    let last_comment = walk(line, |c, column| {
        chars.push(c.to_ascii_lowercase());
        columns.push(column);
    })?;
    out.message = last_comment.and_then(|(text, column)| classify(text, column)).map(Box::new);
    let (chars, columns) = (&chars[..], &columns[..]);
    let mut s = Chars { chars, columns, i: 0 };
    if s.peek() == Some('/') {
        s.i += 1;
    }
    while let Some(c) = s.peek() {
        let column = s.column();
        match c {
            'o' => {
                if !out.assigns.is_empty() || out.words.iter().any(|w| w.letter != 'N') || out.oword.is_some() {
                    return Err(LineError::new(column, "an O-word must stand alone on its line (after N at most)"));
                }
                s.i += 1;
                out.oword = Some(read_oword(&mut s, column)?);
            }
            c if c.is_ascii_alphabetic() => {
                if out.oword.is_some() {
                    return Err(LineError::new(column, "nothing may follow an O-word statement on its line"));
                }
                let letter = c.to_ascii_uppercase();
                s.i += 1;
                let value = read_value(&mut s, What::Word(letter), 0)?;
                out.words.push(RawWord { letter, value, column });
            }
            '#' => {
                if out.oword.is_some() {
                    return Err(LineError::new(column, "nothing may follow an O-word statement on its line"));
                }
                s.i += 1;
                let target = if s.peek() == Some('<') {
                    let name = read_parameter_name(&mut s, column)?;
                    if name.starts_with("_ini[") {
                        // rs274's words: an INI value is read-only.
                        return Err(LineError::new(column, format!("Cannot assign to read-only parameter #<{name}>")));
                    }
                    Target::Named(name.into())
                } else {
                    Target::Numbered(read_value(&mut s, What::Named("the parameter number"), 0)?)
                };
                if s.peek() != Some('=') {
                    return Err(LineError::new(
                        s.column(),
                        "expected '=' after a parameter at the start of an item (#n = value)",
                    ));
                }
                s.i += 1;
                let value = read_value(&mut s, What::Named("the parameter's value"), 0)?;
                out.assigns.push(Assign { target, value, column });
            }
            // The polar words: radius and angle.
            '@' | '^' => {
                if out.oword.is_some() {
                    return Err(LineError::new(column, "nothing may follow an O-word statement on its line"));
                }
                s.i += 1;
                let value = read_value(&mut s, What::Word(c), 0)?;
                out.words.push(RawWord { letter: c, value, column });
            }
            '$' => {
                return Err(LineError::new(
                    column,
                    format!("unsupported: $ spindle selection ({})", crate::unsupported::SPINDLE_SELECTION),
                ))
            }
            c => return Err(LineError::new(column, format!("unexpected character {c:?}"))),
        }
    }
    Ok(())
}

/// The fast path for the common line of plain words (`G1 X1.5 Y-2`): ASCII letters
/// other than `O` and `E`, each followed by an optional sign, digits and at most one
/// point, separated by blanks. Returns false, leaving `out` to be cleared, for
/// anything else (the full lexer then reads the line and reports any error).
fn lex_plain(line: &str, out: &mut Line) -> bool {
    let bytes = line.as_bytes();
    let mut i = 0;
    loop {
        while i < bytes.len() && (bytes[i] == b' ' || bytes[i] == b'\t') {
            i += 1;
        }
        if i == bytes.len() {
            return true;
        }
        let letter = bytes[i];
        if !letter.is_ascii_alphabetic() || matches!(letter, b'o' | b'O' | b'e' | b'E') {
            return false;
        }
        let column = i + 1;
        i += 1;
        let start = i;
        if i < bytes.len() && (bytes[i] == b'-' || bytes[i] == b'+') {
            i += 1;
        }
        let (mut digits, mut points) = (0, 0);
        while i < bytes.len() {
            match bytes[i] {
                b'0'..=b'9' => digits += 1,
                b'.' => points += 1,
                _ => break,
            }
            i += 1;
        }
        // The word must end at a blank or the end of the line.
        if digits == 0 || digits > 30 || points > 1 || (i < bytes.len() && bytes[i] != b' ' && bytes[i] != b'\t') {
            return false;
        }
        match line[start..i].parse::<f64>() {
            Ok(value) if value.abs() <= crate::expr::MAX_NUMBER => {
                out.words.push(RawWord { letter: letter.to_ascii_uppercase() as char, value: Expr::Num(value), column })
            }
            _ => return false,
        }
    }
}

fn read_oword(s: &mut Chars, column: usize) -> Result<OWord, LineError> {
    let label: Box<str> = match s.peek() {
        Some('<') => format!("<{}>", read_name(s)?).into(),
        Some(c) if c.is_ascii_digit() => {
            let start = s.i;
            while s.peek().is_some_and(|c| c.is_ascii_digit()) {
                s.i += 1;
            }
            let digits: String = s.chars[start..s.i].iter().collect();
            let trimmed = digits.trim_start_matches('0');
            (if trimmed.is_empty() { "0" } else { trimmed }).into()
        }
        _ => return Err(LineError::new(column, "O-word needs a number or a <name> (o100 sub, o<name> call)")),
    };
    let word: String = s.chars[s.i..].iter().take_while(|c| c.is_ascii_alphabetic()).collect();
    let Some(&(keyword, kind)) = O_KEYWORDS.iter().find(|(k, _)| *k == word) else {
        let what = if word.is_empty() {
            "O-word needs a keyword".to_string()
        } else {
            format!("unknown O-word keyword {:?}", word.to_uppercase())
        };
        return Err(LineError::new(
            s.column(),
            format!(
                "{what}: sub, endsub, call, return, if, elseif, else, endif, while, endwhile, do, repeat, \
                 endrepeat, break or continue"
            ),
        ));
    };
    s.i += keyword.len();
    let mut args = Vec::new();
    while s.peek() == Some('[') {
        s.i += 1;
        args.push(read_expression(s, 1)?);
    }
    if let Some(c) = s.peek() {
        return Err(LineError::new(s.column(), format!("unexpected character {c:?} after the O-word statement")));
    }
    let takes = match kind {
        OKind::Call => usize::MAX,
        OKind::If | OKind::Elseif | OKind::While | OKind::Repeat => 1,
        OKind::Return | OKind::Endsub => 1,
        _ => 0,
    };
    if args.len() > takes {
        return Err(LineError::new(column, format!("too many [expressions] for O-word {keyword}")));
    }
    if matches!(kind, OKind::If | OKind::Elseif | OKind::While | OKind::Repeat) && args.is_empty() {
        return Err(LineError::new(column, format!("O-word {keyword} needs a [condition]")));
    }
    Ok(OWord { label, kind, column, args })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(line: &str) -> Vec<(char, f64, usize)> {
        let params = crate::expr::NoParams;
        lex_line(line)
            .unwrap()
            .words
            .into_iter()
            .map(|w| (w.letter, w.value.eval(&params).unwrap(), w.column))
            .collect()
    }

    #[test]
    fn spaces_anywhere_and_lower_case() {
        assert_eq!(words("G 1 x 1 0 . 5"), vec![('G', 1.0, 1), ('X', 10.5, 5)]);
        assert_eq!(words("g1x-.5Y+2."), vec![('G', 1.0, 1), ('X', -0.5, 3), ('Y', 2.0, 7)]);
        assert_eq!(words("X - 5"), vec![('X', -5.0, 1)]);
        assert_eq!(words("\tG0\t"), vec![('G', 0.0, 2)]);
        assert_eq!(
            words("X[1 + 2 * 3] Y[2 ** 3 ** 2] Z[-7 MOD 3]"),
            vec![('X', 7.0, 1), ('Y', 64.0, 14), ('Z', 2.0, 29)]
        );
        assert_eq!(
            words("X[1 + 2 GT 2 AND 1] Ysqrt[16] Zatan[1]/[1]"),
            vec![('X', 1.0, 1), ('Y', 4.0, 21), ('Z', 45.0, 31)]
        );
    }

    #[test]
    fn comments_block_delete_and_blank() {
        assert_eq!(words("(hello) G0 (x) X1 ; G1 X2 (unclosed"), vec![('G', 0.0, 9), ('X', 1.0, 16)]);
        assert_eq!(words(" / G0"), vec![('G', 0.0, 4)]);
        assert_eq!(words(""), vec![]);
        assert_eq!(words("   ; only comment"), vec![]);
    }

    #[test]
    fn owords_and_assignments() {
        let line = lex_line("N10 o<My Sub> call [1] [#2]").unwrap();
        let o = line.oword.unwrap();
        assert_eq!((&*o.label, o.kind, o.column, o.args.len()), ("<mysub>", OKind::Call, 5, 2));
        let line = lex_line("o0100 endwhile").unwrap();
        assert_eq!(&*line.oword.unwrap().label, "100");
        let line = lex_line("#1 = 2 #<abc> = [#1 * 2]").unwrap();
        assert_eq!(line.assigns.len(), 2);
        assert_eq!(line.assigns[1].target, Target::Named("abc".into()));
    }

    #[test]
    fn lexical_errors_point_at_the_place() {
        let err = |s: &str| lex_line(s).unwrap_err();
        assert_eq!(err("G1 (abc"), LineError::new(4, "unclosed comment"));
        assert_eq!(err("G1 (a(b))"), LineError::new(6, "nested comment"));
        assert_eq!(err("G1 X"), LineError::new(5, "missing value for word X"));
        assert_eq!(err("G1 X-"), LineError::new(6, "missing value for word X"));
        assert_eq!(err("G1 X."), LineError::new(5, "bad number for word X"));
        assert_eq!(err("G1 X1.2.3"), LineError::new(5, "bad number for word X"));
        assert_eq!(
            err("G1 #1"),
            LineError::new(6, "expected '=' after a parameter at the start of an item (#n = value)")
        );
        assert_eq!(err("G1 X1 [1]"), LineError::new(7, "unexpected character '['"));
        assert_eq!(err("G1 X1 *"), LineError::new(7, "unexpected character '*'"));
        assert_eq!(err("G1 X1 %"), LineError::new(7, "unexpected character '%'"));
        assert_eq!(err("G1 X1000000001"), LineError::new(5, "number out of range for word X"));
        assert_eq!(err("G1 X[1"), LineError::new(7, "expression not closed with ']'"));
        assert_eq!(err("o100"), LineError::new(5, "O-word needs a keyword: sub, endsub, call, return, if, elseif, else, endif, while, endwhile, do, repeat, endrepeat, break or continue"));
        // nestedcall.ngc, which rs274 refuses too ("Unexpected character after O-word").
        assert_eq!(err("O<g20sub> callsub"), LineError::new(11, "unknown O-word keyword \"CALLSUB\": sub, endsub, call, return, if, elseif, else, endif, while, endwhile, do, repeat, endrepeat, break or continue"));
        assert!(err("X1e308").message.starts_with("unsupported: exponent"));
        let huge = format!("X1{}", "0".repeat(400));
        assert_eq!(err(&huge), LineError::new(2, "number out of range for word X"));
    }

    #[test]
    fn long_fraction_is_fine() {
        let tiny = format!("X0.{}1", "0".repeat(10_000));
        assert_eq!(words(&tiny), vec![('X', 0.0, 1)]);
    }
}
