//! The active comments, as LinuxCNC 2.9's interpreter reads them (`convert_comment`,
//! `convert_param_comment` in interp_convert.cc): `(MSG, ...)`, `(DEBUG, ...)`,
//! `(PRINT, ...)`, `(LOG, ...)`, `(LOGOPEN, ...)`, `(LOGAPPEND, ...)`, `(LOGCLOSE)` and
//! `(ABORT, ...)`; `(PY, ...)`, `(PYRUN, ...)` and `(PYRELOAD` (LinuxCNC's embedded
//! Python) are refused as unsupported.
//!
//! A comment is active when, after its leading blanks, it starts with the keyword and
//! its comma in any case (no blank before the comma: `(MSG ,x)` is a plain comment);
//! `LOGCLOSE` must be all the comment holds, `PYRELOAD` only starts it. The text is
//! everything after the comma, kept as written (its leading blank too). Only a line's
//! last parenthesised comment counts, and only on an ordinary block (not after `;`, not
//! on an O-word line): the lexer ([`crate::lexer`]) finds it.
//!
//! DEBUG, PRINT, LOG and ABORT texts have their parameters substituted when the block
//! executes (after the line's assignments): `#n` (digits; #0-#5601) and `#<name>` (blanks
//! inside left out, any case) become the value with six decimals (`%lf`), `######` when the
//! parameter is not defined (a name never set, a number beyond 5601) or when the value
//! takes 30 characters or more; a value within 0.0001 of zero is written as zero. A
//! format before a parameter changes how it and every later one in the comment are
//! written: `%d` no decimals, `%f` four, `%.Nf` N (one digit). A `%` before a `.` that
//! does not make `%.Nf` is dropped; any other `%` is kept. A `#` followed by neither a
//! digit nor `<` is kept. LOGOPEN and LOGAPPEND take their file name as written.
//!
//! Where rs274 reads past the text (a `#` ending it, or `#<` without its `>`), it shows
//! what its buffer held before (the previous expansion's tail); finestep ends the text
//! there instead (after the `#` for the first, before the `#<` for the second).

use crate::expr::Params;
use crate::MessageKind;

/// What an active comment does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Active {
    /// A [`crate::BlockKind::Message`] of this kind.
    Message(MessageKind),
    /// `(ABORT, text)`: the program stops there with the text as its error.
    Abort,
    /// `(PY, ...)`, `(PYRUN, ...)`, `(PYRELOAD`: refused.
    Python,
}

/// An active comment as lexed: what it does, its text after the keyword's comma
/// (unexpanded), and the 1-based column of its `(`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LexedMessage {
    pub kind: Active,
    pub text: Box<str>,
    pub column: usize,
}

/// The keywords in LinuxCNC's order of testing (`convert_comment`): each the start of
/// the comment, lower case.
const KEYWORDS: [(&str, Active); 10] = [
    ("msg,", Active::Message(MessageKind::Msg)),
    ("debug,", Active::Message(MessageKind::Debug)),
    ("print,", Active::Message(MessageKind::Print)),
    ("log,", Active::Message(MessageKind::Log)),
    ("logopen,", Active::Message(MessageKind::LogOpen)),
    ("logappend,", Active::Message(MessageKind::LogAppend)),
    ("py,", Active::Python),
    ("pyrun,", Active::Python),
    ("pyreload", Active::Python),
    ("abort,", Active::Abort),
];

/// The active comment `comment` (the text between the parentheses, its `(` at
/// `column`) is, if any.
pub(crate) fn classify(comment: &str, column: usize) -> Option<LexedMessage> {
    // C's isspace: blank, tab, newline, vertical tab, form feed, carriage return.
    let body = comment.trim_start_matches([' ', '\t', '\n', '\x0b', '\x0c', '\r']);
    let keyword =
        |word: &str| body.get(..word.len()).filter(|head| head.eq_ignore_ascii_case(word)).map(|_| &body[word.len()..]);
    let found = KEYWORDS.into_iter().find_map(|(word, kind)| keyword(word).map(|text| (kind, text)));
    // `LOGCLOSE` is compared whole (`streq`), after the other keywords.
    let found =
        found.or_else(|| body.eq_ignore_ascii_case("logclose").then_some((Active::Message(MessageKind::LogClose), "")));
    found.map(|(kind, text)| LexedMessage { kind, text: text.into(), column })
}

/// How a substituted value is written.
#[derive(Debug, Clone, Copy)]
enum Format {
    /// `%lf`, the start: six decimals.
    Default,
    /// `%d`: no decimals (rounded, half to even, as C's printf).
    Integer,
    /// `%f` (4) or `%.Nf`.
    Decimals(usize),
}

/// rs274's `VAL_LEN`: a value written with this many characters or more is `######`.
const VALUE_LENGTH: usize = 30;
/// rs274's `equal` tolerance: a value closer to 0 than this is written as 0.
const ZERO_TOLERANCE: f64 = 0.0001;
/// What an undefined parameter (or a value too long) is written as.
const UNDEFINED: &str = "######";

fn write_value(out: &mut String, value: Option<f64>, format: Format) {
    let Some(value) = value else {
        out.push_str(UNDEFINED);
        return;
    };
    let value = if value.abs() < ZERO_TOLERANCE { 0.0 } else { value };
    let text = match format {
        Format::Default => format!("{value:.6}"),
        Format::Integer => format!("{value:.0}"),
        Format::Decimals(n) => format!("{value:.n$}"),
    };
    out.push_str(if text.len() >= VALUE_LENGTH { UNDEFINED } else { &text });
}

/// `text` with its parameters substituted, as a DEBUG or PRINT comment shows it.
pub(crate) fn expand(text: &str, params: &impl Params) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len() + 16);
    let mut format = Format::Default;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' => match (bytes.get(i + 1), bytes.get(i + 2), bytes.get(i + 3)) {
                (Some(b'd'), ..) => {
                    format = Format::Integer;
                    i += 2;
                }
                (Some(b'f'), ..) => {
                    format = Format::Decimals(4);
                    i += 2;
                }
                (Some(b'.'), Some(&digit), Some(b'f')) if digit.is_ascii_digit() => {
                    format = Format::Decimals(usize::from(digit - b'0'));
                    i += 4;
                }
                (Some(b'.'), ..) => i += 1,
                _ => {
                    out.push('%');
                    i += 1;
                }
            },
            b'#' => {
                i += 1;
                match bytes.get(i) {
                    None => {
                        out.push('#');
                        break;
                    }
                    Some(c) if c.is_ascii_digit() => {
                        let start = i;
                        while bytes.get(i).is_some_and(u8::is_ascii_digit) {
                            i += 1;
                        }
                        // At most 5601 (rs274's RS274NGC_MAX_PARAMETERS is 5602); #0 is 0.
                        let n = text[start..i].parse::<usize>().ok().filter(|&n| n <= crate::expr::MAX_PARAMETER);
                        write_value(&mut out, n.map(|n| if n == 0 { 0.0 } else { params.numbered(n) }), format);
                    }
                    Some(b'<') => {
                        i += 1;
                        let Some(length) = text[i..].find('>') else { break };
                        let name: String = text[i..i + length]
                            .chars()
                            .filter(|c| !c.is_ascii_whitespace())
                            .map(|c| c.to_ascii_lowercase())
                            .collect();
                        i += length + 1;
                        write_value(&mut out, params.named(&name), format);
                    }
                    Some(_) => out.push('#'),
                }
            }
            _ => {
                let start = i;
                while i < bytes.len() && !matches!(bytes[i], b'%' | b'#') {
                    i += 1;
                }
                out.push_str(&text[start..i]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// #1 = 2.5, #2 = -0.4, #3 = 1.5, #4 = 0.00005, #7 = 1.2e29; `#<foo>` = 3, `#<_x>` = 1.
    struct Values;

    impl Params for Values {
        fn numbered(&self, n: usize) -> f64 {
            match n {
                1 => 2.5,
                2 => -0.4,
                3 => 1.5,
                4 => 0.00005,
                7 => 1.2345e29,
                _ => 0.0,
            }
        }
        fn named(&self, name: &str) -> Option<f64> {
            match name {
                "foo" => Some(3.0),
                "_x" => Some(1.0),
                _ => None,
            }
        }
        fn exists(&self, name: &str) -> bool {
            self.named(name).is_some()
        }
    }

    fn x(text: &str) -> String {
        expand(text, &Values)
    }

    #[test]
    fn keywords_in_any_case_after_blanks_and_only_before_a_comma() {
        let m = |c: &str| classify(c, 1).map(|m| (m.kind, m.text.to_string()));
        let message = |kind, text: &str| Some((Active::Message(kind), text.to_string()));
        assert_eq!(m("MSG, hello World"), message(MessageKind::Msg, " hello World"));
        assert_eq!(m("msg,lower case"), message(MessageKind::Msg, "lower case"));
        assert_eq!(m(" \tDeBuG, #1"), message(MessageKind::Debug, " #1"));
        assert_eq!(m("print,"), message(MessageKind::Print, ""));
        assert_eq!(m("  MSG , spaced"), None);
        assert_eq!(m("MSGX hi"), None);
        assert_eq!(m("message"), None);
        assert_eq!(m("inline"), None);
    }

    /// rs274 (LinuxCNC 2.9) with #1 = 2.5, #<foo> = 3, after G0 X1:
    /// `(DEBUG, one #1 foo #<foo> x)` gives `MESSAGE(" one 2.500000 foo 3.000000 x")`,
    /// `(DEBUG, unknown #<nope> end)` `MESSAGE(" unknown ###### end")`,
    /// `(DEBUG, num #5 end)` `MESSAGE(" num 0.000000 end")`,
    /// `(DEBUG, #<_x> done)` `MESSAGE(" 1.000000 done")`,
    /// `(DEBUG, name #<  F o O  > z)` (#<foo> = 3) `MESSAGE(" name 3.000000 z")` (blanks
    /// and case in the name do not count), `(DEBUG, #1.5 #01 #5600 #5601 #5602 #99999)`
    /// `MESSAGE(" 2.500000.5 2.500000 0.000000 0.000000 ###### ######")`.
    #[test]
    fn parameters_are_substituted_with_six_decimals() {
        assert_eq!(x(" one #1 foo #<foo> x"), " one 2.500000 foo 3.000000 x");
        assert_eq!(x(" unknown #<nope> end"), " unknown ###### end");
        assert_eq!(x(" num #5 end"), " num 0.000000 end");
        assert_eq!(x(" #<_x> done"), " 1.000000 done");
        assert_eq!(x(" name #<  F o O  > z"), " name 3.000000 z");
        assert_eq!(x(" #1.5 #01 #5600 #5601 #5602 #99999"), " 2.500000.5 2.500000 0.000000 0.000000 ###### ######");
    }

    /// rs274 with #1 = 2.5 (DEBUG, texts as below):
    /// `a %d#1 b %f#1 c %.2f#1 d %lf#1 e #1` gives `" a 2 b 2.5000 c 2.50 d %lf2.50 e 2.50"`,
    /// `x %d3#1 y %f3#1 z %lf3#1 w %5.1f#1` `" x 32 y 32.5000 z %lf32.5000 w %5.1f2.5000"`,
    /// `f %d3 #1 %lf2 #<foo>` `" f 3 2 %lf2 3"`; with #1 = 3.5:
    /// `A%.1x#1 B%.#1 C%5#1 D% d#1 E%D#1 F%F#1 G%.2F#1` `" A.1x3.500000 B.3.500000
    /// C%53.500000 D% d3.500000 E%D3.500000 F%F3.500000 G.2F3.500000"`,
    /// `%x#1 %%#1 %.f#1 %.10f#1 %f` `" %x3.500000 %%3.500000 .f3.500000 .10f3.500000 "`,
    /// `%)` (a `%` at the end) `" %"`, `%%d#1` `" %4"`;
    /// #2 = -0.4, #3 = 0.5 (here 1.5): `%d#2` `"-0"`, `%d` of 0.5 `"0"`, of 1.5 `"2"`;
    /// 0.00005 with `%.9f` `"0.000000000"`; 1.2345e29 with `%f` `"######"`.
    #[test]
    fn formats_act_on_every_later_parameter() {
        assert_eq!(x(" a %d#1 b %f#1 c %.2f#1 d %lf#1 e #1"), " a 2 b 2.5000 c 2.50 d %lf2.50 e 2.50");
        assert_eq!(x(" x %d3#1 y %f3#1 z %lf3#1 w %5.1f#1"), " x 32 y 32.5000 z %lf32.5000 w %5.1f2.5000");
        assert_eq!(x(" f %d3 #1 %lf2 #<foo>"), " f 3 2 %lf2 3");
        assert_eq!(
            x(" A%.1x#1 B%.#1 C%5#1 D% d#1 E%D#1 F%F#1 G%.2F#1"),
            " A.1x2.500000 B.2.500000 C%52.500000 D% d2.500000 E%D2.500000 F%F2.500000 G.2F2.500000"
        );
        assert_eq!(x(" %x#1 %%#1 %.f#1 %.10f#1 %f"), " %x2.500000 %%2.500000 .f2.500000 .10f2.500000 ");
        assert_eq!(x(" %"), " %");
        assert_eq!(x(" %%d#1"), " %2");
        assert_eq!(x("%d#2 %d#3 %.9f#4 %.1f#2"), "-0 2 0.000000000 -0.4");
        assert_eq!(x("%f#7 #7"), "###### ######");
    }

    /// rs274: `(DEBUG, hash # alone)` keeps the `#` (`" hash # alone"`); a `#` ending the
    /// text or `#<` without `>` make it show stale bytes, where finestep stops.
    #[test]
    fn a_lone_hash_is_kept_and_an_unfinished_one_ends_the_text() {
        assert_eq!(x(" hash # alone"), " hash # alone");
        assert_eq!(x(" end #"), " end #");
        assert_eq!(x(" a #<foo b"), " a ");
    }
}
