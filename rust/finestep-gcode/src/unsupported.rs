//! What finestep refuses of LinuxCNC's dialect, and why: every `unsupported: <what>
//! (<why>)` message the interpreter gives takes its reason from here, and the list in
//! docs/gcode.md ("What is refused") is held to this table by a test
//! (`tests/unsupported.rs`): each row of the list is refused with its exact message at
//! its `file:line:col`, and every reason here has a row.

/// G-codes LinuxCNC knows and finestep refuses, in tenths (G38.2 is 382), with why.
pub const G_CODES: &[(&[u32], &str)] = &[
    (&[330, 331, 740, 760, 840], "spindle-synchronised motion needs the spindle feedback finestep does not have yet"),
    (&[880], "the tool is left at the bottom for the operator to retract by hand during the stop, and finestep offers no hand moves in a program"),
];

/// Any other G number.
pub const G_OTHER: &str = "not a G-code finestep implements";

/// M-codes LinuxCNC knows and finestep refuses (first, last), with why.
pub const M_CODES: &[(u32, u32, &str)] = &[];

/// Any other M number.
pub const M_OTHER: &str = "not an M-code finestep implements";

/// `unsupported: $ spindle selection`.
pub const SPINDLE_SELECTION: &str = "finestep drives one spindle: leave $ out";
/// `unsupported: #<_hal[...]>`.
pub const HAL: &str = "finestep reads no HAL pins";
/// `unsupported: exponent in the number of ...`.
pub const EXPONENT: &str = "G-code numbers have no exponent: write the digits";
/// `unsupported: G87 in G18/G19`.
pub const CYCLE_PLANE: &str = "back boring is implemented in G17 only";
/// `unsupported: G5.1 in G93`, G5.2.
pub const INVERSE_TIME_SPLINE: &str = "inverse-time feed is implemented for G1, G2 and G3";
/// `unsupported: G10 L3` and every other L but 1, 2, 10, 11 and 20.
pub const G10_L: &str = "only L1, L2, L10, L11 and L20 are implemented";
/// `unsupported: G10 L10 X/Y under an XY rotation`.
pub const G10_TOOL_ROTATION: &str = "the tool table is set in the unrotated frame only";

/// `unsupported: G95 in G96`.
pub const FEED_PER_REV_CSS: &str =
    "feed per revolution under constant surface speed follows a spindle speed that changes along the move; finestep sets one speed per move";

/// `unsupported: (PY, ...)`, also `(PYRUN, ...)` and `(PYRELOAD`.
pub const PYTHON: &str = "finestep runs no embedded Python, the code LinuxCNC's PY comments execute";

/// `unsupported: G70 with cutter compensation on`.
pub const G70_COMPENSATED: &str = "LinuxCNC 2.9 starts the cycle with a rapid from the profile's end through the part";

/// Every reason above, once.
pub fn reasons() -> Vec<&'static str> {
    let mut all: Vec<&'static str> = G_CODES.iter().map(|&(_, why)| why).collect();
    all.extend(M_CODES.iter().map(|&(_, _, why)| why));
    all.extend([
        G_OTHER,
        M_OTHER,
        SPINDLE_SELECTION,
        HAL,
        EXPONENT,
        CYCLE_PLANE,
        G10_L,
        INVERSE_TIME_SPLINE,
        G10_TOOL_ROTATION,
        G70_COMPENSATED,
        FEED_PER_REV_CSS,
        PYTHON,
    ]);
    all
}

/// The message for a G number LinuxCNC knows or not.
pub(crate) fn g_code(value: f64) -> String {
    let tenths = (value * 10.0).round();
    let why = G_CODES
        .iter()
        .find(|(codes, _)| (value * 10.0 == tenths) && codes.iter().any(|&c| f64::from(c) == tenths))
        .map_or(G_OTHER, |&(_, why)| why);
    format!("unsupported: G{value} ({why})")
}

/// The message for an M number.
pub(crate) fn m_code(value: f64) -> String {
    let why = M_CODES
        .iter()
        .find(|&&(first, last, _)| value.fract() == 0.0 && (f64::from(first)..=f64::from(last)).contains(&value))
        .map_or(M_OTHER, |&(_, _, why)| why);
    format!("unsupported: M{value} ({why})")
}
