//! Lexing one source line into words (a letter and a number).
//!
//! As in LinuxCNC, spaces and tabs may appear anywhere outside comments, also inside a
//! number (`G 1 X 1 0 . 5` is `G1 X10.5`). Letters are case-insensitive. Comments are
//! `( ... )` (not nested, closed on the same line) and everything after `;`. A leading
//! `/` (block delete) is accepted and ignored: the block runs, as with LinuxCNC's
//! block-delete switch off. Numbers are an optional sign, digits and at most one
//! decimal point (no exponent, at least one digit). Expressions `[...]`, parameters
//! `#` and any other character are errors.

use crate::error::LineError;

/// The largest magnitude a number in the program may have.
pub(crate) const MAX_NUMBER: f64 = 1e9;

/// One word: an upper-case letter, its value, and the 1-based column of the letter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Word {
    pub letter: char,
    pub value: f64,
    pub column: usize,
}

fn is_blank(c: char) -> bool {
    c == ' ' || c == '\t'
}

fn skip_blanks(chars: &[char], i: &mut usize) {
    while chars.get(*i).is_some_and(|&c| is_blank(c)) {
        *i += 1;
    }
}

/// Lexes one line (without its line terminator) into words.
pub(crate) fn lex_line(line: &str) -> Result<Vec<Word>, LineError> {
    let chars: Vec<char> = line.chars().collect();
    let mut words = Vec::new();
    let mut i = 0;
    skip_blanks(&chars, &mut i);
    if chars.get(i) == Some(&'/') {
        i += 1;
    }
    loop {
        skip_blanks(&chars, &mut i);
        let Some(&c) = chars.get(i) else { break };
        match c {
            '(' => i = skip_comment(&chars, i)?,
            ';' => break,
            c if c.is_ascii_alphabetic() => {
                let column = i + 1;
                let letter = c.to_ascii_uppercase();
                i += 1;
                let value = lex_number(&chars, &mut i, letter, column)?;
                words.push(Word { letter, value, column });
            }
            '#' => return Err(LineError::new(i + 1, "parameters (#) are not supported")),
            '[' => return Err(LineError::new(i + 1, "expressions ([...]) are not supported")),
            c => return Err(LineError::new(i + 1, format!("unexpected character {c:?}"))),
        }
    }
    Ok(words)
}

/// Skips the comment opening at `open`, returning the index after its `)`.
fn skip_comment(chars: &[char], open: usize) -> Result<usize, LineError> {
    for (j, &c) in chars.iter().enumerate().skip(open + 1) {
        match c {
            ')' => return Ok(j + 1),
            '(' => return Err(LineError::new(j + 1, "nested comment")),
            _ => {}
        }
    }
    Err(LineError::new(open + 1, "unclosed comment"))
}

/// Lexes the number after a word's letter, with blanks allowed anywhere in it.
fn lex_number(chars: &[char], i: &mut usize, letter: char, column: usize) -> Result<f64, LineError> {
    let mut text = String::new();
    skip_blanks(chars, i);
    if let Some(&sign) = chars.get(*i).filter(|&&c| c == '+' || c == '-') {
        text.push(sign);
        *i += 1;
    }
    let (mut digits, mut points) = (0usize, 0usize);
    while let Some(&c) = chars.get(*i) {
        if c.is_ascii_digit() {
            digits += 1;
            text.push(c);
        } else if c == '.' {
            points += 1;
            text.push(c);
        } else if !is_blank(c) {
            break;
        }
        *i += 1;
    }
    if digits == 0 && points == 0 && text.is_empty() {
        return Err(LineError::new(column, format!("missing value for word {letter}")));
    }
    if digits == 0 || points > 1 {
        return Err(LineError::new(column, format!("bad number for word {letter}")));
    }
    match text.parse::<f64>() {
        Ok(value) if value.is_finite() && value.abs() <= MAX_NUMBER => Ok(value),
        _ => Err(LineError::new(column, format!("number out of range for word {letter}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(line: &str) -> Vec<(char, f64, usize)> {
        lex_line(line).unwrap().into_iter().map(|w| (w.letter, w.value, w.column)).collect()
    }

    #[test]
    fn spaces_anywhere_and_lower_case() {
        assert_eq!(words("G 1 x 1 0 . 5"), vec![('G', 1.0, 1), ('X', 10.5, 5)]);
        assert_eq!(words("g1x-.5Y+2."), vec![('G', 1.0, 1), ('X', -0.5, 3), ('Y', 2.0, 7)]);
        assert_eq!(words("X - 5"), vec![('X', -5.0, 1)]);
        assert_eq!(words("\tG0\t"), vec![('G', 0.0, 2)]);
        // No exponent: `e5` is a word of its own (refused later as unknown).
        assert_eq!(words("X1e5"), vec![('X', 1.0, 1), ('E', 5.0, 3)]);
    }

    #[test]
    fn comments_block_delete_and_blank() {
        assert_eq!(words("(hello) G0 (x) X1 ; G1 X2 (unclosed"), vec![('G', 0.0, 9), ('X', 1.0, 16)]);
        assert_eq!(words(" / G0"), vec![('G', 0.0, 4)]);
        assert_eq!(words(""), vec![]);
        assert_eq!(words("   ; only comment"), vec![]);
    }

    #[test]
    fn lexical_errors_point_at_the_place() {
        let err = |s: &str| lex_line(s).unwrap_err();
        assert_eq!(err("G1 (abc"), LineError::new(4, "unclosed comment"));
        assert_eq!(err("G1 (a(b))"), LineError::new(6, "nested comment"));
        assert_eq!(err("G1 X"), LineError::new(4, "missing value for word X"));
        assert_eq!(err("G1 X-"), LineError::new(4, "bad number for word X"));
        assert_eq!(err("G1 X."), LineError::new(4, "bad number for word X"));
        assert_eq!(err("G1 X1.2.3"), LineError::new(4, "bad number for word X"));
        assert_eq!(err("G1 #1=2"), LineError::new(4, "parameters (#) are not supported"));
        assert_eq!(err("G1 X1 [1]"), LineError::new(7, "expressions ([...]) are not supported"));
        assert_eq!(err("G1 X#1"), LineError::new(4, "missing value for word X"));
        assert_eq!(err("G1 X1 *"), LineError::new(7, "unexpected character '*'"));
        assert_eq!(err("G1 X1 %"), LineError::new(7, "unexpected character '%'"));
        assert_eq!(err("G1 X1000000001"), LineError::new(4, "number out of range for word X"));
        let huge = format!("X1{}", "0".repeat(400));
        assert_eq!(err(&huge), LineError::new(1, "number out of range for word X"));
    }

    #[test]
    fn long_fraction_is_fine() {
        let tiny = format!("X0.{}1", "0".repeat(10_000));
        assert_eq!(words(&tiny), vec![('X', 0.0, 1)]);
    }
}
