//! The G-code front end of finestep: a LinuxCNC-compatible part program to a typed
//! sequence of canonical blocks, with the modal state tracked and resolved away.
//!
//! Every position in the output is absolute and in millimetres (A in degrees),
//! whatever G20/G21 and G90/G91 said; arcs carry their centre and have been checked.
//! Cutter compensation is not applied here (it is kept as a [`BlockKind::CutterComp`]
//! value for the stage after this one), nor is any planning or interpolation.
//!
//! ```
//! use finestep_gcode::{parse_str, BlockKind, Point};
//! let source = "G20 G91 F10\n#<dy> = -0.25\nG1 X1 Y[2 * #<dy>] (inches, incremental)\nM2\n";
//! let program = parse_str(source, "part.ngc").unwrap();
//! let BlockKind::Linear { to, feed_mm_per_min } = program.blocks[0].kind else { panic!() };
//! assert_eq!(to, Point { x_mm: 25.4, y_mm: -12.7, ..Point::default() });
//! // As in LinuxCNC, F is read before G20 acts on its block: 10 mm/min.
//! assert_eq!(feed_mm_per_min, 10.0);
//! assert_eq!(program.blocks[0].line, 3);
//!
//! let err = parse_str("G0 X1 X2\n", "part.ngc").unwrap_err();
//! assert_eq!(err.to_string(), "part.ngc:1:7: word X appears twice");
//! ```
//!
//! # Dialect
//!
//! - Words: a letter (any case) and a value: a number (optional sign, digits, at most one
//!   decimal point, no exponent, magnitude at most 1e9), `[expression]`, `#parameter`
//!   or a function, with an optional sign; spaces and tabs anywhere outside comments,
//!   also inside numbers. Comments `( ... )` (one line, not nested) and after `;`;
//!   `(MSG, text)`, `(DEBUG, text)` (parameters substituted: `#1`, `#<name>`, `%d`
//!   `%f` `%.Nf`), `(PRINT, text)`, `(LOG, text)`, `(LOGOPEN, file)`, `(LOGAPPEND, file)`
//!   and `(LOGCLOSE)` give [`BlockKind::Message`] ([`LogFile`] writes the log), `(ABORT,
//!   text)` refuses the program there with its text, as LinuxCNC 2.9. `N` line number (integer, first
//!   word). A leading `/` (block delete) is ignored and the block runs. A line holding
//!   only `%` opens the program if it is the first non-blank line; any later `%` line
//!   ends it. Lines after M2/M30 are not read. An empty program is refused.
//! - Expressions as LinuxCNC's: `**`; `*` `/` `MOD`; `+` `-`; `EQ` `NE` `GT` `GE` `LT`
//!   `LE`; `AND` `OR` `XOR` (that precedence, left to right), ABS ACOS ASIN COS EXP FIX
//!   FUP ROUND LN SIN SQRT TAN (degrees), `ATAN[y]/[x]`, `EXISTS[#<name>]`.
//! - Parameters: `#1`-`#5601` (`#5220` coordinate system 1, `#5400` tool, `#5420`-`#5423`
//!   position), local `#<name>` (per subroutine call) and global `#<_name>` (reading one
//!   never set is an error, as in rs274; `#<_value>`, `#<_call_level>` ... are defined), LinuxCNC's predefined `#<_x>`, `#<_metric>`, ...
//!   (read-only; `#<_ini[...]>` and `#<_hal[...]>` are refused). `#n = value` on a line
//!   takes effect after the whole line is read. A parameter file ([`Parameters`], given
//!   in [`Options::parameters`]) sets parameters and the offsets in force before the
//!   first line; [`parse_file_with_parameters`] gives the persistent ones back.
//! - O-words: `sub`/`endsub`/`call [args]`/`return [value]` (`#1`-`#30` local to the
//!   call, the value in `#<_value>`), `if`/`elseif`/`else`/`endif`, `while`/`endwhile`,
//!   `do`/`while`, `repeat`/`endrepeat`, `break`/`continue`; `o<name> call` of a
//!   subroutine the file does not define loads `name.ngc` from the program's folder or
//!   [`Options::subroutine_path`]. At most [`MAX_CALL_DEPTH`] nested calls,
//!   [`MAX_ITERATIONS`] loop passes and calls in all, and [`MAX_REPEATED_LINES`] lines
//!   run again by loops and calls (each an error at the line that reaches it).
//! - G0 G1 G2 G3 G4 G5.1 G5.2 G5.3 G10 L1/L2/L10/L11/L20 G17 G18 G19 G20 G21 G28 G28.1 G30 G30.1 G38.2-G38.5 G40
//!   G41 G42 G43 G43.1 G43.2 G49 G53 G54-G59.3 G61 G64 G70 G71 G71.1 G71.2 G72 G72.1 G72.2 G73 G80 G81 G82 G83 G85 G86 G89 G90 G91
//!   G90.1 G91.1 G92 G92.1 G92.2 G92.3 G93 G94 G95 G96 G97 G8 G98 G99 G61.1; M0 M1 M2 M3 M4 M5 M6 M7 M8 M9 M30
//!   M48-M53 M61 M62-M68 M70 M71 M72 M73; E F S T D H P Q R I J K L, polar `@ ^` (G17); axes X Y Z A B C U V W. What LinuxCNC has
//!   beyond that is refused as `unsupported: <what> (<why>)` at its word (`unsupported:
//!   G33 (spindle-synchronised motion ...)`, `unsupported: M101 (...)`).
//! - Positions come out in the machine frame: the program's coordinates through the G92
//!   offset, the XY rotation (G10 L2 R), the G54-G59.3 offset and the tool length
//!   offset (G43), as LinuxCNC's canonical layer applies them. The offset parameters
//!   (#5161-#5389) are in [`Options::machine_unit_mm`] and act when a code loads them.
//! - Canned cycles in G17 with G98/G99 (G99 at the start, as rs274), L repeats, R Z P Q
//!   kept while the cycle stays the motion mode; M70/M73 save and M72 (or the return
//!   after M73) restores units, plane, distance modes, feed, speed, spindle, coolant,
//!   path control and retract mode.
//! - NURBS blocks (G5.2 ... G5.3, G17 only): see [`BlockKind::Nurbs`].
//! - Lathe cycles G70-G72 (G18 only): the Q subroutine's motion is read as the profile
//!   (not run) and the cycle's moves come out as rapid, linear and arc blocks of the
//!   cycle's line, as LinuxCNC 2.9 makes them (docs/gcode.md, "Lathe cycles").
//! - Execution order in a block is LinuxCNC's: F, S, T, M6 (which stops the spindle),
//!   M3-M5, M7-M9, G4, G17-G19, G20/G21, G40-G42, G61/G64, G90/G91, motion, M0/M2/M30.
//! - Start state: G17 G21 G90 G91.1 G40 G49 G54 G64 G80 G94 G99, no motion mode, at the origin, no feed
//!   rate, spindle off at 0 rpm, coolant off, tool 0.
//!
//! See [`BlockKind`] for what each block means and [`GcodeError`] for the error format.

pub mod conformance;
mod error;
mod expr;
mod g7x;
mod interp;
mod lexer;
mod message;
mod persistent;
mod program;
pub mod unsupported;

use std::path::Path;

pub use error::GcodeError;
pub use persistent::{required_parameters, ParameterFileError, Parameters};
pub use program::{MAX_CALL_DEPTH, MAX_ITERATIONS, MAX_REPEATED_LINES};

/// A position: named axis fields whose names carry their units. Linear axes (X Y Z U V
/// W) are in millimetres, the rotary axes A B C in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point {
    /// X in mm.
    pub x_mm: f64,
    /// Y in mm.
    pub y_mm: f64,
    /// Z in mm.
    pub z_mm: f64,
    /// A (rotary) in degrees.
    pub a_deg: f64,
    /// B (rotary) in degrees.
    pub b_deg: f64,
    /// C (rotary) in degrees.
    pub c_deg: f64,
    /// U (linear, parallel to X) in mm.
    pub u_mm: f64,
    /// V (linear, parallel to Y) in mm.
    pub v_mm: f64,
    /// W (linear, parallel to Z) in mm.
    pub w_mm: f64,
}

/// The axes LinuxCNC's interpreter knows, in its order: X Y Z A B C U V W.
pub const AXIS_LETTERS: [char; 9] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'];

impl Point {
    fn from_array([x_mm, y_mm, z_mm, a_deg, b_deg, c_deg, u_mm, v_mm, w_mm]: [f64; 9]) -> Self {
        Point { x_mm, y_mm, z_mm, a_deg, b_deg, c_deg, u_mm, v_mm, w_mm }
    }

    /// Every axis in LinuxCNC's order ([`AXIS_LETTERS`]).
    pub fn to_array(&self) -> [f64; 9] {
        [self.x_mm, self.y_mm, self.z_mm, self.a_deg, self.b_deg, self.c_deg, self.u_mm, self.v_mm, self.w_mm]
    }

    /// The first of the axes B C U V W away from 0 (the machine's start), if any: the
    /// planner refuses them, the chip drives X Y Z A.
    pub fn extra_axis_away(&self) -> Option<char> {
        let a = self.to_array();
        (4..9).find(|&i| a[i] != 0.0).map(|i| AXIS_LETTERS[i])
    }
}

/// The arc plane, named by its in-plane axes in right-handed order (the first axis
/// turned a quarter turn counter-clockwise, seen from the positive normal axis, is the
/// second).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// G17: X and Y, normal Z; centre offsets I and J.
    Xy,
    /// G18: Z and X, normal Y; centre offsets K and I.
    Zx,
    /// G19: Y and Z, normal X; centre offsets J and K.
    Yz,
}

/// Which side of the path the cutter is kept on (G40/G41/G42).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompSide {
    /// G40: compensation off.
    Off,
    /// G41: tool to the left of the path.
    Left,
    /// G42: tool to the right of the path.
    Right,
}

/// Path control mode (G61/G64).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathControl {
    /// G61: follow the programmed path exactly.
    ExactPath,
    /// G64: blend corners, within the tolerance when `P` is given (converted to mm).
    Blend {
        /// The path tolerance from `P`, in mm.
        tolerance_mm: Option<f64>,
    },
}

/// Spindle rotation (M3/M4/M5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpindleRotation {
    /// M5.
    Off,
    /// M3.
    Clockwise,
    /// M4.
    CounterClockwise,
}

/// The override switches M48-M53 set (LinuxCNC's `#<_feed_override>`,
/// `#<_speed_override>`, `#<_adaptive_feed>`, `#<_feed_hold>`). finestep has no override
/// inputs, adaptive feed or feed-hold input yet: they are carried as state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Overrides {
    /// The feed override may act (M48, M50; on at the start).
    pub feed: bool,
    /// The spindle speed override may act (M48, M51; on at the start).
    pub speed: bool,
    /// Adaptive feed (M52; off at the start).
    pub adaptive_feed: bool,
    /// The feed-hold input may act (M53; on at the start).
    pub feed_hold: bool,
}

/// One control point of a NURBS: its position in the XY plane and its weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NurbsPoint {
    /// X in mm.
    pub x_mm: f64,
    /// Y in mm.
    pub y_mm: f64,
    /// Weight (positive).
    pub weight: f64,
}

/// The clamped uniform knot vector LinuxCNC gives a NURBS of `count` control points
/// and order `order` (`count >= order >= 1`): `order` zeros, then 1, 2, ...,
/// `count - order`, then `order` times `count - order + 1` (`count + order` knots).
pub fn nurbs_knots(count: usize, order: usize) -> Vec<f64> {
    let last = (count - order + 1) as f64;
    (0..count + order)
        .map(|i| {
            if i < order {
                0.0
            } else if i < count {
                (i + 1 - order) as f64
            } else {
                last
            }
        })
        .collect()
}

/// How far short of its end a probe move counts as stopped in a program interpreted at
/// once, mm: LinuxCNC's batch interpreter backs off 0.254 mm (0.01 inch) from the probe
/// point towards the start, in X Y Z.
pub const PROBE_BACKOFF_MM: f64 = 0.254;

/// The input M66 reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// P: digital input 0 to 63.
    Digital(u32),
    /// E: analog input 0 to 63.
    Analog(u32),
}

/// M66's L: what to wait for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaitMode {
    /// L0: read the input at once.
    Immediate,
    /// L1: a rising edge.
    Rise,
    /// L2: a falling edge.
    Fall,
    /// L3: the input high.
    High,
    /// L4: the input low.
    Low,
}

/// One canonical operation. A source block may give several, in LinuxCNC's order of
/// execution: tool select, tool change, spindle, coolant, dwell, cutter compensation,
/// path control, motion, stop.
#[derive(Debug, Clone, PartialEq)]
pub enum BlockKind {
    /// G0: a rapid move to `to`.
    Rapid {
        /// End point.
        to: Point,
    },
    /// G1: a straight feed move to `to`.
    Linear {
        /// End point.
        to: Point,
        /// Feed rate in mm/min (in G20 the programmed inch/min times 25.4).
        feed_mm_per_min: f64,
    },
    /// G2/G3: an arc (or helix) from the previous end point to `to` around `centre`.
    ///
    /// The in-plane coordinates of `centre` are the arc's centre; its normal-axis and A
    /// coordinates are those of the start point. The normal axis and A move linearly
    /// with the angle (a helix). When `to` equals the start in the plane the arc is a
    /// full circle. The end radius may differ from the start radius by up to
    /// 0.002 mm or 0.1 % (whichever is larger); the centre is kept as programmed.
    Arc {
        /// End point.
        to: Point,
        /// Centre (see above).
        centre: Point,
        /// The plane (G17/G18/G19).
        plane: Plane,
        /// G2 (clockwise seen from the positive normal axis) or G3.
        clockwise: bool,
        /// Full turns in addition to the programmed arc: `P` minus 1, else 0.
        extra_turns: u32,
        /// Feed rate in mm/min.
        feed_mm_per_min: f64,
    },
    /// G5.2 ... G5.3: a NURBS curve in the XY plane (G17) from the previous end point
    /// to `to`, emitted on the G5.3 line.
    ///
    /// As in LinuxCNC, the first control point is always the current position (the
    /// previous end point): the `X Y` of the `G5.2` line is the *second* control point.
    /// `G5.2 P-` without `X Y` sets the weight of that first point; `G5.2 X- Y- P- L-`
    /// sets the second point and its weight; each following line `X- Y- <P->` adds a
    /// control point; `G5.3` ends the block. Weights default to 1 and must be positive;
    /// the order `L` defaults to 3 (quadratic). The knots are LinuxCNC's clamped uniform
    /// vector ([`nurbs_knots`]), so the curve starts at the current position and ends
    /// at the last control point, tangent to the control polygon at both ends. In G91
    /// every control point is relative to the start of the NURBS (LinuxCNC updates the
    /// current position only at G5.3). Z and A do not move. Differences from LinuxCNC:
    /// `L2` gives order 2 (LinuxCNC silently keeps 3 for `L` below 4), and a weight left
    /// out on a later line is 1 (as LinuxCNC's documentation says; its interpreter
    /// refuses it).
    Nurbs {
        /// End point: the last control point, with the start's Z and A.
        to: Point,
        /// Control points, the first being the start point.
        control_points: Vec<NurbsPoint>,
        /// Order k (degree k - 1), at least 2 and at most the number of control points.
        order: u32,
        /// Knot vector, `control_points.len() + order` values ([`nurbs_knots`]).
        knots: Vec<f64>,
        /// Feed rate in mm/min.
        feed_mm_per_min: f64,
    },
    /// G4: wait.
    Dwell {
        /// Time in seconds.
        seconds: f64,
    },
    /// M3/M4/M5, S, G96 or G97: the spindle's state after the block.
    Spindle {
        /// Rotation.
        rotation: SpindleRotation,
        /// The last S as programmed: the speed in revolutions per minute, or in G96
        /// (`css`) the surface speed in program units (m/min in G21, ft/min in G20), as
        /// LinuxCNC's interpreter keeps it (`#<_rpm>`).
        rpm: f64,
        /// G96: constant surface speed, the speed following X; `None` in G97.
        css: Option<SurfaceSpeed>,
    },
    /// M7/M8/M9: the coolant's state after the block.
    Coolant {
        /// Mist (M7) on.
        mist: bool,
        /// Flood (M8) on.
        flood: bool,
    },
    /// T: select the tool for the next M6.
    ToolSelect {
        /// Tool number.
        tool: u32,
    },
    /// M6: change to the selected tool.
    ToolChange {
        /// Tool number (the last T, 0 if none).
        tool: u32,
    },
    /// G40/G41/G42: cutter radius compensation (applied by a later stage).
    CutterComp {
        /// Side, or off.
        side: CompSide,
        /// The tool number from `D`, if given.
        tool: Option<u32>,
        /// The plane compensated in: G17, or G18 (as LinuxCNC, for lathes); the plane
        /// does not change while compensation is on.
        plane: Plane,
    },
    /// G41.1/G42.1: cutter radius compensation with the radius given in the block (half
    /// its `D`, the tool's diameter: LinuxCNC's dynamic compensation; a negative `D`
    /// takes the other side), applied by a later stage like [`BlockKind::CutterComp`].
    CutterCompRadius {
        /// Side ([`CompSide::Left`] or [`CompSide::Right`]).
        side: CompSide,
        /// The tool radius, mm (not negative).
        radius_mm: f64,
        /// The plane compensated in, as for [`BlockKind::CutterComp`].
        plane: Plane,
        /// `L`, a lathe tool's orientation (G18 only; 0 without `L`): LinuxCNC's numbering
        /// 0-9, where 1-8 name the quadrant or side of the tool's nose the imaginary tool
        /// tip lies on and 0 and 9 (as any other number) mean the nose's centre. The
        /// compensated path, of the nose's centre, is shifted by the radius in X and/or Z
        /// to the imaginary tip (LinuxCNC's `latheorigin_x`/`_z`).
        orientation: u32,
    },
    /// M19 with R or P: orient the spindle to `angle_deg` (LinuxCNC's `ORIENT_SPINDLE`);
    /// the spindle counts as stopped after it. (A bare M19 stops the spindle in the
    /// interpreter's state and emits nothing, as in rs274.)
    SpindleOrient {
        /// The angle from the spindle's index, 0 to 360 degrees (R, default 0).
        angle_deg: f64,
        /// P: 0 the shorter way, 1 clockwise, 2 counter-clockwise.
        direction: u32,
        /// Q: how long to wait for the orientation to complete, seconds.
        timeout_s: Option<f64>,
    },
    /// G61/G64.
    PathControl(PathControl),
    /// M48-M53: the override switches after the block.
    Overrides(Overrides),
    /// M62/M64 (on) and M63/M65 (off): a digital output.
    DigitalOutput {
        /// The output (P), 0 to 63.
        index: u32,
        /// On or off.
        on: bool,
    },
    /// G38.2-G38.5: a straight probe move to `to` at `feed_mm_per_min`, the probe armed.
    /// On a machine the move stops where the probe changes (G38.2/G38.3 when it makes
    /// contact, G38.4/G38.5 when it loses it), #5061-#5069 take the position latched
    /// there and #5070 says whether it changed; a program interpreted at once cannot know
    /// that position, so it goes on as LinuxCNC's batch interpreter (`rs274`) does: the
    /// probe counts as stopped `PROBE_BACKOFF_MM` short of `to` (`resume`), #5061-#5069
    /// hold `to` and #5070 is 0 (docs/gcode.md, "Probing").
    Probe {
        /// The end of the probe move (where it stops if the probe does not change).
        to: Point,
        /// mm/min.
        feed_mm_per_min: f64,
        /// G38.2/G38.3: stop when the probe makes contact; G38.4/G38.5: when it loses it.
        on_contact: bool,
        /// G38.2/G38.4: ending the move without the probe changing is an error.
        must_change: bool,
        /// Where the interpretation goes on from: `to` backed off by
        /// [`PROBE_BACKOFF_MM`] towards the start in X Y Z, as rs274 does.
        resume: Point,
    },
    /// M66: wait for an input (or, `WaitMode::Immediate`, read it at once); the value
    /// goes to #5399. rs274 reads no input: #5399 keeps its value (a digital one as 0 or
    /// 1), and finestep does the same.
    WaitInput {
        /// P (a digital input) or E (an analog one).
        input: Input,
        /// L: what to wait for.
        mode: WaitMode,
        /// Q: the longest wait, seconds (0 with `WaitMode::Immediate`).
        timeout_s: f64,
    },
    /// M100-M199: LinuxCNC's user M-code, the executable file `M1nn` found in
    /// [`Options::user_m_path`], run with P and Q as its two arguments; the machine waits,
    /// at rest, until it has finished.
    UserMCode {
        /// The M number, 100 to 199.
        code: u32,
        /// P (0 when absent).
        p: f64,
        /// Q (0 when absent).
        q: f64,
    },
    /// M67 (with the next move) and M68 (at once): analog output `index` set to `value`.
    AnalogOutput {
        /// E: the output, 0 to 63.
        index: u32,
        /// Q: the value.
        value: f64,
        /// M67: synchronised with the motion (LinuxCNC sets it as the next move starts);
        /// M68: at once.
        synchronised: bool,
    },
    /// `(MSG, text)`, `(DEBUG, text)`, `(PRINT, text)` or one of the log comments: a
    /// message, before the rest of its block, as LinuxCNC 2.9 gives it (docs/gcode.md,
    /// "Messages"). MSG and DEBUG go to the operator once the motion before them has
    /// ended (LinuxCNC's task waits for it: an exact stop); PRINT goes to standard error
    /// and the log comments to their file as the program is interpreted ([`LogFile`]).
    /// DEBUG, PRINT and LOG have their parameters substituted; a DEBUG while #5599 is 0
    /// or less gives nothing.
    Message {
        /// Which comment.
        kind: MessageKind,
        /// The text after the keyword's comma, as written (its leading blank too), with
        /// the parameters substituted for DEBUG, PRINT and LOG; the file name for
        /// LOGOPEN and LOGAPPEND; empty for LOGCLOSE.
        text: String,
    },
    /// M0: pause until resumed.
    Pause,
    /// M2/M30: end of program.
    End,
}

/// Which message comment a [`BlockKind::Message`] comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageKind {
    /// `(MSG, text)`: shown to the operator as written.
    Msg,
    /// `(DEBUG, text)`: shown to the operator, parameters substituted, when #5599 > 0.
    Debug,
    /// `(PRINT, text)`: written to standard error, parameters substituted.
    Print,
    /// `(LOG, text)`: written as a line to the log file open (if one is), parameters
    /// substituted.
    Log,
    /// `(LOGOPEN, file)`: the log file opened, emptied if it exists (another one open is
    /// closed first).
    LogOpen,
    /// `(LOGAPPEND, file)`: the log file opened to append to it.
    LogAppend,
    /// `(LOGCLOSE)`: the log file closed.
    LogClose,
}

/// The log file of a program's `(LOGOPEN, ...)`, `(LOGAPPEND, ...)`, `(LOG, ...)` and
/// `(LOGCLOSE)` comments, written as LinuxCNC's task writes it (emccanon.cc `LOGOPEN`,
/// `LOGAPPEND`, `LOG`, `LOGCLOSE`): when the interpreter reaches them, not in step with
/// the motion; the file name as written (relative to the working directory, a leading
/// blank kept, as LinuxCNC's `fopen` takes it); a LOG with no file open writes nothing.
/// Unlike LinuxCNC, which goes on without its log, a file that cannot be opened or
/// written is an error.
///
/// ```
/// use finestep_gcode::{LogFile, MessageKind};
/// let path = std::env::temp_dir().join(format!("finestep-log-doc-{}.txt", std::process::id()));
/// let mut log = LogFile::default();
/// log.apply(MessageKind::LogOpen, path.to_str().unwrap()).unwrap();
/// log.apply(MessageKind::Log, " x 2.500000").unwrap();
/// log.apply(MessageKind::LogClose, "").unwrap();
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), " x 2.500000\n");
/// # std::fs::remove_file(&path).unwrap();
/// ```
#[derive(Debug, Default)]
pub struct LogFile {
    file: Option<std::io::BufWriter<std::fs::File>>,
}

impl LogFile {
    /// Does what a message block of `kind` with `text` does to the log; other kinds do
    /// nothing. The error names the file for LOGOPEN and LOGAPPEND.
    pub fn apply(&mut self, kind: MessageKind, text: &str) -> std::io::Result<()> {
        use std::io::Write as _;
        match kind {
            MessageKind::LogOpen | MessageKind::LogAppend => {
                self.close()?;
                let file = std::fs::OpenOptions::new()
                    .write(true)
                    .create(true)
                    .append(kind == MessageKind::LogAppend)
                    .truncate(kind == MessageKind::LogOpen)
                    .open(text)
                    .map_err(|e| std::io::Error::new(e.kind(), format!("log file {text:?}: {e}")))?;
                self.file = Some(std::io::BufWriter::new(file));
            }
            MessageKind::Log => {
                if let Some(file) = &mut self.file {
                    writeln!(file, "{text}")?;
                }
            }
            MessageKind::LogClose => self.close()?,
            MessageKind::Msg | MessageKind::Debug | MessageKind::Print => {}
        }
        Ok(())
    }

    /// Closes the log file open, if any (also done when the program ends: call it to see
    /// an error).
    pub fn close(&mut self) -> std::io::Result<()> {
        use std::io::Write as _;
        match self.file.take() {
            Some(mut file) => file.flush(),
            None => Ok(()),
        }
    }
}

/// G96 (constant surface speed) as LinuxCNC's motion controller runs it: the spindle
/// turns at `mm_per_min / (2 pi r)` rev/min, r the distance of the tool from the spindle's
/// axis along X (`|X - axis_x_mm|` in the machine frame), at most `max_rpm`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceSpeed {
    /// The surface speed, mm/min (S m/min in G21, S ft/min in G20).
    pub mm_per_min: f64,
    /// D: the highest speed, rev/min; `None` without D (LinuxCNC's 1e30).
    pub max_rpm: Option<f64>,
    /// The machine X of the spindle's axis: the X offsets (G5x, G92, tool length) in
    /// force when the block was run, as LinuxCNC's canon takes them with the speed.
    pub axis_x_mm: f64,
}

impl SurfaceSpeed {
    /// The speed at machine X `x_mm`, rev/min: at the axis itself D (unbounded without
    /// D), as LinuxCNC's motion controller does.
    pub fn rpm_at(&self, x_mm: f64) -> f64 {
        let r = (x_mm - self.axis_x_mm).abs();
        let max = self.max_rpm.unwrap_or(f64::INFINITY);
        if r > 0.0 {
            (self.mm_per_min / (std::f64::consts::TAU * r)).min(max)
        } else {
            max
        }
    }
}

/// One canonical operation and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// 1-based source line.
    pub line: usize,
    /// The block's `N` number, if any.
    pub n: Option<u32>,
    /// What to do.
    pub kind: BlockKind,
}

/// A parsed part program.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Program {
    /// The canonical blocks in order.
    pub blocks: Vec<Block>,
}

/// What the machine configuration tells the interpreter.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Millimetres per machine length unit: the unit of the offset parameters
    /// (#5161-#5389, as LinuxCNC keeps them). 1 for a machine in mm (the default), 25.4
    /// in inches (rs274 without an INI file).
    pub machine_unit_mm: f64,
    /// Folders searched, after the program's own folder, for `NAME.ngc` when
    /// `o<NAME> call` names a subroutine the program does not define (LinuxCNC's
    /// SUBROUTINE_PATH).
    pub subroutine_path: Vec<std::path::PathBuf>,
    /// Tool length offsets by tool number (X Y Z A B C U V W: mm, rotary ones in
    /// degrees), for G43.
    pub tools: std::collections::HashMap<u32, [f64; 9]>,
    /// Numbered parameters set before the program runs, as LinuxCNC's parameter file
    /// gives them ([`Parameters::read`]; lengths in the machine unit). The coordinate
    /// system #5220, its offsets and the G92 offsets (when #5210 is set) are in force from
    /// the first line, as in LinuxCNC. [`parse_file_with_parameters`] gives them back as
    /// the program leaves them, to be written to the file.
    pub parameters: Parameters,
    /// The machine's INI file for `#<_ini[section]name>` ([`Options::read_ini`]):
    /// (section, name) to the value's text, as written. LinuxCNC looks a parameter up
    /// with its section and name in upper case (so `#<_ini[traj]max_velocity>` reads
    /// `[TRAJ]MAX_VELOCITY`), and a value that is not a number is not found; a parameter
    /// not found is not defined, as any other. Read-only: assigning one is an error.
    pub ini: std::collections::BTreeMap<(String, String), String>,
    /// Folders searched, in order, for the executable file `M1nn` of a user M-code
    /// M100-M199 (LinuxCNC's `[RS274NGC]USER_M_PATH`). A program naming one that is in
    /// none of them is refused where it names it, as LinuxCNC refuses it (`Unknown M code
    /// used`).
    pub user_m_path: Vec<std::path::PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            machine_unit_mm: 1.0,
            subroutine_path: Vec::new(),
            tools: std::collections::HashMap::new(),
            parameters: Parameters::default(),
            ini: std::collections::BTreeMap::new(),
            user_m_path: Vec::new(),
        }
    }
}

impl Options {
    /// The entries of an INI file: `[SECTION]` lines, then `NAME = value` lines (blanks
    /// around both trimmed); lines starting with `#` or `;` and lines without `=` are
    /// skipped, as LinuxCNC's reader skips them. The first entry of a name in a section
    /// wins, as LinuxCNC's `IniFile::Find` (and `inivar`) returns the first. Read whatever
    /// `[RS274NGC] FEATURES` says: as a configuration with its INI_VARS bit (4) set.
    pub fn read_ini(text: &str) -> std::collections::BTreeMap<(String, String), String> {
        let mut entries = std::collections::BTreeMap::new();
        let mut section = String::new();
        for line in text.lines().map(str::trim) {
            if line.starts_with('#') || line.starts_with(';') {
                continue;
            }
            if let Some(name) = line.strip_prefix('[').and_then(|l| l.split_once(']')).map(|(name, _)| name) {
                section = name.trim().to_string();
            } else if let Some((name, value)) = line.split_once('=') {
                entries.entry((section.clone(), name.trim().to_string())).or_insert_with(|| value.trim().to_string());
            }
        }
        entries
    }

    /// Reads the tool lengths of a LinuxCNC tool table (`T1 P1 Z0.511 D0.125 ;comment`
    /// lines) whose lengths are in `mm_per_unit` millimetres (25.4 for inches).
    pub fn read_tool_table(text: &str, mm_per_unit: f64) -> Result<std::collections::HashMap<u32, [f64; 9]>, String> {
        let mut tools = std::collections::HashMap::new();
        for (index, line) in text.lines().enumerate() {
            let line = line.split(';').next().unwrap_or("");
            let mut tool = None;
            let mut offset = [0.0; 9];
            for word in line.split_whitespace() {
                let (letter, number) = word.split_at(1);
                let value =
                    number.parse::<f64>().map_err(|_| format!("tool table line {}: bad word {word:?}", index + 1))?;
                let letter = letter.to_ascii_uppercase();
                if letter == "T" {
                    tool = Some(value as u32);
                } else if let Some(axis) = AXIS_LETTERS.iter().position(|&l| letter.starts_with(l)) {
                    offset[axis] = if (3..6).contains(&axis) { value } else { value * mm_per_unit };
                }
            }
            if let Some(tool) = tool {
                tools.insert(tool, offset);
            }
        }
        Ok(tools)
    }
}

/// A part program executed as its blocks are read: an [`Iterator`] of [`Block`]s that
/// reads, lexes and executes the program's lines only as far as the blocks asked for
/// need (the O-word structure is matched by a scan ahead of execution, to a structure's
/// end when it is entered and to the file's end for a subroutine not defined before),
/// so that memory does not grow with the program's length: a file is read through a
/// buffer, neither its text nor its blocks are held. The blocks and the errors are those
/// of [`parse_file_with`] (which collects this stream); the first error ends the stream.
///
/// ```
/// use finestep_gcode::{stream_str, Options};
/// let mut blocks = stream_str("G1 X1 F100\nG1 X1 X2\n", "part.ngc", &Options::default()).unwrap();
/// assert_eq!(blocks.next().unwrap().unwrap().line, 1);
/// assert_eq!(blocks.next().unwrap().unwrap_err().to_string(), "part.ngc:2:7: word X appears twice");
/// assert!(blocks.next().is_none());
/// ```
pub struct BlockStream<'t> {
    runner: program::Runner<'t>,
}

impl BlockStream<'_> {
    /// The persistent parameters as the program leaves them (once the stream has ended):
    /// see [`parse_str_with_parameters`].
    pub fn parameters(&self) -> Parameters {
        self.runner.parameters()
    }
}

impl Iterator for BlockStream<'_> {
    type Item = Result<Block, GcodeError>;

    fn next(&mut self) -> Option<Self::Item> {
        self.runner.next_block()
    }
}

impl std::fmt::Debug for BlockStream<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("BlockStream")
    }
}

/// The blocks of a part program held in memory, as a stream ([`BlockStream`]);
/// `file_name` is only used in errors, subroutine files are searched in the
/// [`Options::subroutine_path`] only. The parameters given are checked and an empty
/// program refused here.
pub fn stream_str<'t>(source: &'t str, file_name: &str, options: &Options) -> Result<BlockStream<'t>, GcodeError> {
    Ok(BlockStream { runner: program::Runner::in_memory(source, file_name, None, options)? })
}

/// The blocks of a part program file, as a stream ([`BlockStream`]) reading the file as
/// it goes; errors name the file as `path` displays, subroutine files are searched in
/// the program's folder first.
pub fn stream_file(path: impl AsRef<Path>, options: &Options) -> Result<BlockStream<'static>, GcodeError> {
    Ok(BlockStream { runner: program::Runner::file(path.as_ref(), options)? })
}

/// The whole stream collected, and the parameters it leaves.
fn collect(mut stream: BlockStream<'_>) -> Result<(Program, Parameters), GcodeError> {
    let blocks = stream.by_ref().collect::<Result<Vec<Block>, GcodeError>>()?;
    Ok((Program { blocks }, stream.parameters()))
}

/// Parses a part program held in memory. `file_name` is only used in errors;
/// subroutine files are searched in the [`Options::subroutine_path`] only.
pub fn parse_str(source: &str, file_name: &str) -> Result<Program, GcodeError> {
    parse_str_with(source, file_name, &Options::default())
}

/// [`parse_str`] with the machine configuration's [`Options`].
pub fn parse_str_with(source: &str, file_name: &str, options: &Options) -> Result<Program, GcodeError> {
    parse_str_with_parameters(source, file_name, options).map(|(program, _)| program)
}

/// [`parse_str_with`] that also gives the persistent parameters as the program leaves
/// them: LinuxCNC's [`required_parameters`] and every parameter
/// [`Options::parameters`] held, to be written back to the parameter file
/// ([`Parameters::to_text`]) as LinuxCNC does when it shuts down.
pub fn parse_str_with_parameters(
    source: &str,
    file_name: &str,
    options: &Options,
) -> Result<(Program, Parameters), GcodeError> {
    collect(stream_str(source, file_name, options)?)
}

/// Parses raw bytes. Bytes that are not UTF-8 are refused where they stand outside a
/// comment (as an unexpected character `'\u{fffd}'`) and ignored inside one.
pub fn parse_bytes(source: &[u8], file_name: &str) -> Result<Program, GcodeError> {
    parse_str(&String::from_utf8_lossy(source), file_name)
}

/// Reads and parses a part program file; errors name the file as `path` displays.
/// Subroutine files are searched in the program's folder first.
pub fn parse_file(path: impl AsRef<Path>) -> Result<Program, GcodeError> {
    parse_file_with(path, &Options::default())
}

/// [`parse_file`] with the machine configuration's [`Options`].
pub fn parse_file_with(path: impl AsRef<Path>, options: &Options) -> Result<Program, GcodeError> {
    parse_file_with_parameters(path, options).map(|(program, _)| program)
}

/// [`parse_file_with`] that also gives the persistent parameters as the program leaves
/// them (see [`parse_str_with_parameters`]).
pub fn parse_file_with_parameters(
    path: impl AsRef<Path>,
    options: &Options,
) -> Result<(Program, Parameters), GcodeError> {
    collect(stream_file(path, options)?)
}

#[cfg(test)]
mod tests;
