//! The modal interpreter: one block of words at a time, against the modal state, to
//! canonical blocks with positions resolved to absolute millimetres.

use crate::error::LineError;
use crate::g7x::{LatheCycle, Move, ProfileReader, Pt, Segment};
use crate::lexer::Word;
use crate::unsupported;
use crate::{
    nurbs_knots, BlockKind, CompSide, Input, NurbsPoint, Overrides, PathControl, Plane, Point, SpindleRotation,
    SurfaceSpeed, WaitMode, PROBE_BACKOFF_MM,
};

/// Millimetres per inch.
const MM_PER_INCH: f64 = 25.4;
/// G96's S: millimetres per metre (G21) and per foot (G20).
const METRES_TO_MM: f64 = 1000.0;
const FEET_TO_MM: f64 = 12.0 * MM_PER_INCH;
/// Largest absolute coordinate a resolved position may have, in mm (or degrees).
const MAX_POSITION: f64 = 1e10;
/// A centre-form arc is refused when its start and end radii differ by more than this
/// absolute amount AND by more than [`ARC_RELATIVE_TOLERANCE`] of the start radius
/// (LinuxCNC's rule).
pub(crate) const ARC_ABSOLUTE_TOLERANCE_MM: f64 = 0.002;
/// See [`ARC_ABSOLUTE_TOLERANCE_MM`].
pub(crate) const ARC_RELATIVE_TOLERANCE: f64 = 0.001;
/// Lengths below this are zero (end equal to start, zero radius).
const ZERO_MM: f64 = 1e-9;

/// LinuxCNC's axes X Y Z A B C U V W.
const N_AXES: usize = 9;
/// A value per axis, in LinuxCNC's order (mm for X Y Z U V W, degrees for A B C).
type Axes = [f64; N_AXES];

/// Whether axis `axis` (LinuxCNC's order) is rotary (A B C, in degrees, not scaled by
/// the units).
fn rotary(axis: usize) -> bool {
    (3..6).contains(&axis)
}

/// A G code in tenths: G90.1 is 901.
type Code = u32;

/// G5.2 (open a NURBS block) and G5.3 (close it), in tenths.
const G5_2: Code = 52;
const G5_3: Code = 53;
/// LinuxCNC's default NURBS order (quadratic).
const NURBS_DEFAULT_ORDER: u32 = 3;
/// The highest NURBS order accepted.
const NURBS_MAX_ORDER: u32 = 16;

/// A NURBS block between its G5.2 and G5.3.
#[derive(Debug, Clone)]
struct OpenNurbs {
    /// Where the G5.2 word stands (line, column), for an unclosed block.
    opened_at: (usize, usize),
    points: Vec<NurbsPoint>,
    order: u32,
}

/// The modal state between blocks.
#[derive(Debug, Clone)]
pub(crate) struct State {
    /// Folders searched for user M-code programs (M100-M199).
    user_m_path: Vec<std::path::PathBuf>,
    position: Axes,
    motion: Option<Code>,
    plane: Plane,
    inches: bool,
    incremental: bool,
    arc_incremental: bool,
    comp: CompSide,
    feed_mm_per_min: Option<f64>,
    /// G93: F is the inverse of a move's time in minutes, given on every feed move.
    inverse_time: bool,
    /// G95: F is a length per spindle revolution (`feed_mm_per_min` then holds mm per
    /// revolution), fed at F times the programmed speed S, as LinuxCNC's interpreter
    /// computes it.
    per_rev: bool,
    /// The F of the block being executed in G93 (1/min), none without one.
    inverse_f: Option<f64>,
    /// M48-M53: the override switches.
    overrides: Overrides,
    rotation: SpindleRotation,
    rpm: f64,
    /// G96: constant surface speed with D (`Some(None)` without D); `None` in G97.
    css: Option<Option<f64>>,
    mist: bool,
    flood: bool,
    tool: u32,
    tool_in_spindle: u32,
    nurbs: Option<OpenNurbs>,
    /// Numbered parameters #0-#5601 (#0 unused); those the fields below hold are
    /// computed from them when read.
    params: Vec<f64>,
    /// G54-G59.3 offsets (mm, A in degrees) and XY rotations (degrees).
    g5x: [Axes; 9],
    rotation_deg: [f64; 9],
    /// The coordinate system in use, 0 (G54) to 8 (G59.3).
    system: usize,
    /// The G92 offsets as #5211-#5214 hold them (mm), and whether they apply (#5210).
    g92: Axes,
    g92_on: bool,
    /// The offsets in force: G5x and its rotation, G92 (the parameters above act only
    /// when a code loads them, as in LinuxCNC).
    active_g5x: Axes,
    active_rotation_deg: f64,
    active_g92: Axes,
    /// Millimetres per machine unit, the unit of the offset parameters (#5161-#5389).
    machine_unit_mm: f64,
    /// The tool length offset in force (G43), mm.
    tool_offset: Axes,
    /// Tool lengths from the tool table, mm.
    tools: std::collections::HashMap<u32, Axes>,
    /// G28 and G30 positions (machine frame, mm).
    home: [Axes; 2],
    /// G99 (retract to R) rather than G98.
    retract_to_r: bool,
    /// The path control mode in force (G61/G64).
    path: PathControl,
    /// The sticky words of a canned cycle: R, Z (program frame, mm), P, Q (mm).
    cycle: CycleWords,
    /// G7 (lathe diameter mode): X words are diameters, halved as they are read.
    diameter_mode: bool,
    /// G5 without I J: the first control point's offset from the start, in program
    /// units, the negated P Q of the last G5 (rs274's `cycle_i`, `cycle_j`; 0 at first).
    g5_next_ij: [f64; 2],
    /// The 1-based source line being executed (set by the caller).
    pub(crate) line: usize,
}

impl Default for State {
    /// G17 G21 G90 G91.1 G40 G64, no motion mode, at the origin, no feed, spindle off
    /// at 0 rpm, coolant off, tool 0.
    fn default() -> Self {
        State {
            user_m_path: Vec::new(),
            position: [0.0; N_AXES],
            motion: None,
            plane: Plane::Xy,
            inches: false,
            incremental: false,
            arc_incremental: true,
            comp: CompSide::Off,
            feed_mm_per_min: None,
            inverse_time: false,
            per_rev: false,
            inverse_f: None,
            overrides: Overrides { feed: true, speed: true, adaptive_feed: false, feed_hold: true },
            rotation: SpindleRotation::Off,
            rpm: 0.0,
            css: None,
            mist: false,
            flood: false,
            tool: 0,
            tool_in_spindle: 0,
            nurbs: None,
            params: default_parameters(),
            g5x: [[0.0; N_AXES]; 9],
            rotation_deg: [0.0; 9],
            system: 0,
            g92: [0.0; N_AXES],
            g92_on: false,
            active_g5x: [0.0; N_AXES],
            active_rotation_deg: 0.0,
            active_g92: [0.0; N_AXES],
            machine_unit_mm: 1.0,
            tool_offset: [0.0; N_AXES],
            tools: std::collections::HashMap::new(),
            home: [[0.0; N_AXES]; 2],
            // rs274 starts in G99.
            retract_to_r: true,
            path: PathControl::Blend { tolerance_mm: None },
            cycle: CycleWords::default(),
            g5_next_ij: [0.0; 2],
            diameter_mode: false,
            line: 0,
        }
    }
}

/// The words a canned cycle keeps from block to block.
#[derive(Debug, Clone, Copy, Default)]
struct CycleWords {
    /// Z where the cycle began (program frame, mm): G98 retracts to it.
    old_z: Option<f64>,
    r: Option<f64>,
    z: Option<f64>,
    p: Option<f64>,
    q: Option<f64>,
    /// G87's I J (program units) and K (program frame, mm).
    i: Option<f64>,
    j: Option<f64>,
    k: Option<f64>,
}

/// #5061-#5069: where the last probe move (G38.x) stopped, program frame and units.
const PARAM_PROBE: usize = 5061;
/// #5070: whether the last probe move's probe changed (1) or not (0).
const PARAM_PROBE_TRIPPED: usize = 5070;
/// #5399: the value M66 read.
const PARAM_INPUT: usize = 5399;
/// #5220, the coordinate system in use (1 = G54).
const PARAM_COORD_SYSTEM: usize = 5220;
/// #5400, the tool in the spindle.
const PARAM_TOOL: usize = 5400;
/// #5420-#5425: the current position X Y Z A B C in program units.
const PARAM_POSITION: usize = 5420;

/// #5599: DEBUG comments are shown while it is above 0 (1 at the start, as in rs274).
pub(crate) const PARAM_DEBUG: usize = 5599;

fn default_parameters() -> Vec<f64> {
    let mut params = vec![0.0; crate::expr::MAX_PARAMETER + 1];
    params[PARAM_COORD_SYSTEM] = 1.0;
    params[PARAM_DEBUG] = 1.0;
    params
}

/// (x, y) turned by `degrees` counter-clockwise.
fn rotate(x: f64, y: f64, degrees: f64) -> (f64, f64) {
    if degrees == 0.0 {
        return (x, y);
    }
    let (s, c) = degrees.to_radians().sin_cos();
    (x * c - y * s, x * s + y * c)
}

/// Modal groups of the supported codes (LinuxCNC's numbering in comments).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Group {
    NonModal,    // G group 0: G4 G10 G28 G28.1 G30 G30.1 G53 G92 G92.1 G92.2 G92.3
    Motion,      // G group 1: G0 G1 G2 G3 G5 G5.1 G5.2 G5.3 G38.2-G38.5 G73 G80 G81 G82 G83 G85 G86 G87 G89
    Plane,       // G group 2: G17 G18 G19
    Distance,    // G group 3: G90 G91
    ArcDistance, // G group 4: G90.1 G91.1
    Units,       // G group 6: G20 G21
    Comp,        // G group 7: G40 G41 G41.1 G42 G42.1
    FeedMode,    // G group 5: G93 G94 G95
    SpindleMode, // G group 14: G96 G97
    LatheMode,   // G group 15: G7 G8
    ToolLength,  // G group 8: G43 G43.1 G43.2 G49
    ReturnMode,  // G group 10: G98 G99
    Coord,       // G group 12: G54-G59.3
    Path,        // G group 13: G61 G61.1 G64
    Stop,        // M group 4: M0 M1 M2 M30 M60
    ToolChange,  // M group 6: M6 M61
    Spindle,     // M group 7: M3 M4 M5 M19
    Coolant,     // M group 8: M7 M8 M9
    ModalState,  // M group 10: M70 M71 M72 M73
    Override,    // M group 9: M48 M49 M50 M51 M52 M53
    Io,          // M group 5: M62 M63 M64 M65 M66 M67 M68
    User,        // M group 10 in LinuxCNC's table too: M100-M199
}

const GROUPS: usize = 22;

/// The canned cycles implemented (in tenths).
const CYCLES: [Code; 8] = [730, 810, 820, 830, 850, 860, 870, 890];

fn g_group(code: Code) -> Option<Group> {
    Some(match code {
        40 | 100 | 280 | 281 | 300 | 301 | 530 | 920 | 921 | 922 | 923 => Group::NonModal,
        0 | 10 | 20 | 30 | 50 | 51 | G5_2 | G5_3 | 800 | 700 | 710 | 711 | 712 | 720 | 721 | 722 | 730 | 810 | 820
        | 830 | 850 | 860 | 870 | 890 => Group::Motion,
        382..=385 => Group::Motion,
        430 | 431 | 432 | 490 => Group::ToolLength,
        930 | 940 | 950 => Group::FeedMode,
        960 | 970 => Group::SpindleMode,
        70 | 80 => Group::LatheMode,
        980 | 990 => Group::ReturnMode,
        540 | 550 | 560 | 570 | 580 | 590 | 591 | 592 | 593 => Group::Coord,
        170 | 180 | 190 => Group::Plane,
        900 | 910 => Group::Distance,
        901 | 911 => Group::ArcDistance,
        200 | 210 => Group::Units,
        400 | 410 | 411 | 420 | 421 => Group::Comp,
        610 | 611 | 640 => Group::Path,
        _ => return None,
    })
}

fn m_group(code: u32) -> Option<Group> {
    Some(match code {
        0 | 1 | 2 | 30 | 60 => Group::Stop,
        6 | 61 => Group::ToolChange,
        3..=5 | 19 => Group::Spindle,
        7..=9 => Group::Coolant,
        70..=73 => Group::ModalState,
        48..=53 => Group::Override,
        62..=68 => Group::Io,
        100..=199 => Group::User,
        _ => return None,
    })
}

/// The slowest feed a G93 move gets, in program units (or degrees) a minute: rs274 feeds
/// `max(0.1, length * F)` (F0 included).
const INVERSE_TIME_MIN_RATE: f64 = 0.1;

/// A straight move's length for G93, as LinuxCNC's `find_straight_length`: X Y Z U V W
/// in mm, or the turn of A B C (degrees) when those stand still; and whether it is the
/// linear axes'.
fn straight_length(from: Axes, to: Axes) -> (f64, bool) {
    let norm = |axes: &[usize]| axes.iter().map(|&a| (to[a] - from[a]).powi(2)).sum::<f64>().sqrt();
    let linear = norm(&[0, 1, 2, 6, 7, 8]);
    if linear > 0.0 {
        (linear, true)
    } else {
        (norm(&[3, 4, 5]), false)
    }
}

/// An arc's (helix's) length for G93, as LinuxCNC's `find_arc_length`: the in-plane arc
/// (radius at the start times the swept angle, full turns included) and the normal
/// axis's travel, at right angles.
fn arc_length(from: Axes, to: Axes, centre: Axes, plane: Plane, clockwise: bool, extra_turns: u32) -> f64 {
    let (a, b, n) = match plane {
        Plane::Xy => (0, 1, 2),
        Plane::Zx => (2, 0, 1),
        Plane::Yz => (1, 2, 0),
    };
    let start = (from[b] - centre[b]).atan2(from[a] - centre[a]);
    let end = (to[b] - centre[b]).atan2(to[a] - centre[a]);
    let tau = std::f64::consts::TAU;
    let mut swept = if clockwise { start - end } else { end - start };
    swept = swept.rem_euclid(tau);
    if swept <= 1e-12 {
        swept += tau;
    }
    swept += tau * f64::from(extra_turns);
    let radius = (from[a] - centre[a]).hypot(from[b] - centre[b]);
    (radius * swept).hypot(to[n] - from[n])
}

/// `G2`, `G90.1`: a code in tenths as written.
fn g_name(code: Code) -> String {
    match (code / 10, code % 10) {
        (whole, 0) => format!("G{whole}"),
        (whole, tenth) => format!("G{whole}.{tenth}"),
    }
}

/// The squared length of a chord.
fn chord_norm(p: Pt) -> f64 {
    p.z * p.z + p.x * p.x
}

/// A non-negative integral value as u32.
fn as_u32(value: f64) -> Option<u32> {
    (value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX)).then_some(value as u32)
}

/// The parameter letters a block may carry once each (besides G, M and N).
const PARAMS: &str = "ABCDEFHIJKLPQRSTUVWXYZ@^";
const AXES: [char; N_AXES] = crate::AXIS_LETTERS;

/// The words of one block, sorted by meaning.
#[derive(Default)]
struct Words {
    n: Option<u32>,
    /// Per group: the code and its column. The coolant group may hold M7 and M8.
    groups: [Option<(Code, usize)>; GROUPS],
    mist_and_flood: Option<usize>,
    params: [Option<(f64, usize)>; 28],
}

impl Words {
    fn param(&self, letter: char) -> Option<(f64, usize)> {
        self.params.get(letter_index(letter)).copied().flatten()
    }
    fn group(&self, group: Group) -> Option<(Code, usize)> {
        self.groups[group as usize]
    }
    fn has(&self, group: Group, code: Code) -> bool {
        self.group(group).is_some_and(|(c, _)| c == code)
    }
}

/// The slot of a parameter letter: A-Z, then the polar words `@` (26) and `^` (27).
fn letter_index(letter: char) -> usize {
    match letter {
        '@' => 26,
        '^' => 27,
        l => (l as usize).wrapping_sub('A' as usize),
    }
}

fn sort_words(words: &[Word]) -> Result<Words, LineError> {
    let mut out = Words::default();
    for (index, word) in words.iter().enumerate() {
        let Word { letter, value, column } = *word;
        let coded = match letter {
            'N' => {
                if out.n.is_some() {
                    return Err(LineError::new(column, "word N appears twice"));
                }
                if index != 0 {
                    return Err(LineError::new(column, "N word must come first in the block"));
                }
                let n = as_u32(value).ok_or_else(|| LineError::new(column, "N word must be a non-negative integer"))?;
                out.n = Some(n);
                continue;
            }
            'G' => {
                let tenths = value * 10.0;
                let code = (tenths.round() == tenths).then(|| as_u32(tenths)).flatten();
                let group = code.and_then(|c| g_group(c).map(|g| (c, g)));
                group.ok_or_else(|| LineError::new(column, unsupported::g_code(value)))?
            }
            'M' => {
                let group = as_u32(value).and_then(|c| m_group(c).map(|g| (c * 10, g)));
                group.ok_or_else(|| LineError::new(column, unsupported::m_code(value)))?
            }
            l if PARAMS.contains(l) => {
                let slot = &mut out.params[letter_index(l)];
                if slot.is_some() {
                    return Err(LineError::new(column, format!("word {l} appears twice")));
                }
                *slot = Some((value, column));
                continue;
            }
            l => return Err(LineError::new(column, format!("unknown word {l}"))),
        };
        let (code, group) = coded;
        let slot = &mut out.groups[group as usize];
        match *slot {
            None => *slot = Some((code, column)),
            // M7 and M8 together turn both coolants on, as in LinuxCNC.
            Some((other, _)) if group == Group::Coolant && other + code == 150 && out.mist_and_flood.is_none() => {
                out.mist_and_flood = Some(column);
            }
            Some((other, _)) => {
                let name = |c: Code| {
                    if letter == 'M' {
                        format!("M{}", c / 10)
                    } else {
                        g_name(c)
                    }
                };
                return Err(LineError::new(
                    column,
                    format!("{} and {} are in the same modal group", name(other), name(code)),
                ));
            }
        }
    }
    Ok(out)
}

/// The result of one block: what it emits, its line number, and whether it ends the
/// program.
pub(crate) struct Executed {
    pub n: Option<u32>,
    pub kinds: Vec<BlockKind>,
    pub end: bool,
    /// M70-M73: what the block does with the saved modal state (for the caller, which
    /// keeps one per call level).
    pub modal: Option<ModalOp>,
    /// G70-G72: the cycle whose profile (the Q subroutine) the caller reads next.
    pub lathe: Option<LatheCycle>,
}

/// M70 (save), M71 (forget), M72 (restore), M73 (save, restored when the subroutine
/// returns).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ModalOp {
    Save,
    Forget,
    Restore,
    SaveUntilReturn,
}

/// The modal state M70/M73 save and M72 restores (LinuxCNC's list, as far as finestep
/// has it): units, plane, distance modes, feed, speed, spindle, coolant, path control,
/// retract mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Modal {
    inches: bool,
    plane: Plane,
    incremental: bool,
    arc_incremental: bool,
    feed_mm_per_min: Option<f64>,
    inverse_time: bool,
    per_rev: bool,
    rpm: f64,
    /// G96 (without its D: rs274's M72 restores G96 with none, `SET_SPINDLE_MODE(0 1e30)`).
    css: bool,
    rotation: SpindleRotation,
    mist: bool,
    flood: bool,
    path: PathControl,
    retract_to_r: bool,
}

impl State {
    /// The modal state M70/M73 save.
    pub(crate) fn save_modal(&self) -> Modal {
        Modal {
            inches: self.inches,
            plane: self.plane,
            incremental: self.incremental,
            arc_incremental: self.arc_incremental,
            feed_mm_per_min: self.feed_mm_per_min,
            inverse_time: self.inverse_time,
            per_rev: self.per_rev,
            rpm: self.rpm,
            css: self.css.is_some(),
            rotation: self.rotation,
            mist: self.mist,
            flood: self.flood,
            path: self.path,
            retract_to_r: self.retract_to_r,
        }
    }

    /// M72 (or a return after M73): the saved modal state back, with the blocks that
    /// change the machine (spindle, coolant, path control) where it differs.
    pub(crate) fn restore_modal(&mut self, saved: &Modal) -> Vec<BlockKind> {
        let mut kinds = Vec::new();
        let css = if saved.css == self.css.is_some() { self.css } else { saved.css.then_some(None) };
        if (saved.rotation, saved.rpm, css) != (self.rotation, self.rpm, self.css) {
            (self.rotation, self.rpm, self.css) = (saved.rotation, saved.rpm, css);
            kinds.push(self.spindle_block(self.rotation));
        }
        if (saved.mist, saved.flood) != (self.mist, self.flood) {
            kinds.push(BlockKind::Coolant { mist: saved.mist, flood: saved.flood });
        }
        if saved.path != self.path {
            kinds.push(BlockKind::PathControl(saved.path));
        }
        self.inches = saved.inches;
        self.plane = saved.plane;
        self.incremental = saved.incremental;
        self.arc_incremental = saved.arc_incremental;
        self.feed_mm_per_min = saved.feed_mm_per_min;
        self.inverse_time = saved.inverse_time;
        self.per_rev = saved.per_rev;
        (self.rpm, self.rotation, self.mist, self.flood) = (saved.rpm, saved.rotation, saved.mist, saved.flood);
        self.path = saved.path;
        self.retract_to_r = saved.retract_to_r;
        kinds
    }

    /// `#n` (1 <= n <= 5601), with the predefined ones computed from the state.
    pub(crate) fn parameter(&self, n: usize) -> f64 {
        let user = |axis: usize, mm: f64| if rotary(axis) { mm } else { mm / self.machine_unit_mm };
        match n {
            5161..=5169 => user(n - 5161, self.home[0][n - 5161]),
            5181..=5189 => user(n - 5181, self.home[1][n - 5181]),
            5210 => f64::from(u8::from(self.g92_on)),
            5211..=5219 => user(n - 5211, self.g92[n - 5211]),
            PARAM_COORD_SYSTEM => (self.system + 1) as f64,
            5221..=5400 if (n - 5221) % 20 < 9 => user((n - 5221) % 20, self.g5x[(n - 5221) / 20][(n - 5221) % 20]),
            5221..=5400 if (n - 5221) % 20 == 9 => self.rotation_deg[(n - 5221) / 20],
            PARAM_TOOL => f64::from(self.tool_in_spindle),
            // LinuxCNC's `set_tool_parameters` (rs274ngc_pre.cc): the table entry of the
            // tool in the spindle (its `tool_table[0]`), in the table's (machine) unit,
            // whatever G20/G21 and G43 say; 0 with no tool in the spindle.
            5401..=5409 => self.spindle_tool_parameter(n - 5401),
            PARAM_POSITION..=5428 => self.program_position(n - PARAM_POSITION),
            _ => self.params.get(n).copied().unwrap_or(0.0),
        }
    }

    /// Sets `#n`; the offsets' parameters set the offsets, the computed read-only ones
    /// (tool, position) keep their values.
    pub(crate) fn set_parameter(&mut self, n: usize, value: f64) {
        let mm = |axis: usize| if rotary(axis) { value } else { value * self.machine_unit_mm };
        match n {
            5161..=5169 => self.home[0][n - 5161] = mm(n - 5161),
            5181..=5189 => self.home[1][n - 5181] = mm(n - 5181),
            5210 => self.g92_on = value != 0.0,
            5211..=5219 => self.g92[n - 5211] = mm(n - 5211),
            5221..=5400 if (n - 5221) % 20 < 9 => self.g5x[(n - 5221) / 20][(n - 5221) % 20] = mm((n - 5221) % 20),
            5221..=5400 if (n - 5221) % 20 == 9 => self.rotation_deg[(n - 5221) / 20] = value,
            _ => {
                if let Some(p) = self.params.get_mut(n) {
                    *p = value;
                }
            }
        }
    }

    /// The tool table's lengths (mm, per axis X Y Z A).
    pub(crate) fn set_tools(&mut self, tools: &std::collections::HashMap<u32, Axes>) {
        self.tools = tools.clone();
    }

    /// The folders searched for user M-code programs ([`crate::Options::user_m_path`]).
    pub(crate) fn set_user_m_path(&mut self, path: &[std::path::PathBuf]) {
        self.user_m_path = path.to_vec();
    }

    /// #5401-#5409 (`axis` 0-8): the tool table's offset of the tool in the spindle, in
    /// the machine unit (degrees for A B C), as LinuxCNC's `set_tool_parameters` copies
    /// `tool_table[0]` into them. M6 and M61 both load the spindle's entry: after M61,
    /// LinuxCNC's iocontrol (`EMC_TOOL_SET_NUMBER`: `load_tool`) copies the tool's entry
    /// to index 0 and the interpreter re-reads the table (`read_inputs`:
    /// `load_tool_table`) before the next line. G10 L1/L10/L11 on the loaded tool show
    /// at once, as LinuxCNC copies the changed entry to index 0.
    fn spindle_tool_parameter(&self, axis: usize) -> f64 {
        if self.tool_in_spindle == 0 {
            return 0.0;
        }
        let mm = self.tools.get(&self.tool_in_spindle).map_or(0.0, |entry| entry[axis]);
        if rotary(axis) {
            mm
        } else {
            mm / self.machine_unit_mm
        }
    }

    /// A length in mm (or an angle) in program units.
    fn user_units(&self, axis: usize, mm: f64) -> f64 {
        if !rotary(axis) && self.inches {
            mm / MM_PER_INCH
        } else {
            mm
        }
    }

    /// The G92 offsets in force.
    fn g92_now(&self) -> Axes {
        self.active_g92
    }

    /// Sets the unit of the offset parameters (25.4 for a machine in inches).
    pub(crate) fn set_machine_unit(&mut self, mm: f64) {
        self.machine_unit_mm = mm;
    }

    /// Sets the numbered parameters a parameter file held (machine units) before the
    /// program runs, and puts their offsets in force as LinuxCNC's interpreter does at
    /// start-up: the coordinate system #5220 with its offsets and rotation, and the G92
    /// offsets #5211-#5214 if #5210 is set. #5220 must be 1 to 9 (checked by the caller).
    pub(crate) fn load_parameters(&mut self, values: &std::collections::BTreeMap<usize, f64>) {
        let mut system = self.system;
        for (&n, &value) in values {
            if n == PARAM_COORD_SYSTEM {
                system = (value.round() as usize).clamp(1, 9) - 1;
            } else if !matches!(n, PARAM_TOOL | PARAM_POSITION..=5428 | 5401..=5413) {
                self.set_parameter(n, value);
            }
        }
        self.select_system(system);
        if self.g92_on {
            self.active_g92 = self.g92;
        }
    }

    /// Loads the coordinate system `system` as the one in force.
    fn select_system(&mut self, system: usize) {
        self.system = system;
        self.active_g5x = self.g5x[system];
        self.active_rotation_deg = self.rotation_deg[system];
    }

    /// A point in the program frame (mm) to the machine frame, as LinuxCNC's canonical
    /// layer does: G92, then the XY rotation, then the G5x and tool offsets.
    fn to_machine(&self, p: Axes) -> Axes {
        let g92 = self.g92_now();
        let o = self.active_g5x;
        let t = self.tool_offset;
        let (x, y) = rotate(p[0] + g92[0], p[1] + g92[1], self.active_rotation_deg);
        let mut m = [0.0; N_AXES];
        for axis in 0..N_AXES {
            m[axis] = if axis < 2 { [x, y][axis] } else { p[axis] + g92[axis] } + o[axis] + t[axis];
        }
        m
    }

    /// The inverse of [`State::to_machine`].
    fn to_program(&self, m: Axes) -> Axes {
        let g92 = self.g92_now();
        let o = self.active_g5x;
        let t = self.tool_offset;
        let (x, y) = rotate(m[0] - o[0] - t[0], m[1] - o[1] - t[1], -self.active_rotation_deg);
        let mut p = [0.0; N_AXES];
        for axis in 0..N_AXES {
            p[axis] = if axis < 2 { [x, y][axis] } else { m[axis] - o[axis] - t[axis] } - g92[axis];
        }
        p
    }

    /// G96's surface speed as LinuxCNC's canon takes it with a spindle call: S in m/min
    /// (G21) or ft/min (G20), D, and the X offsets in force (G96 D0 runs as G97 there:
    /// its canon reads a zero maximum as no surface speed).
    fn surface_speed(&self) -> Option<SurfaceSpeed> {
        let max_rpm = self.css?;
        if max_rpm == Some(0.0) {
            return None;
        }
        Some(SurfaceSpeed {
            mm_per_min: self.rpm * if self.inches { FEET_TO_MM } else { METRES_TO_MM },
            max_rpm,
            axis_x_mm: self.g92_now()[0] + self.active_g5x[0] + self.tool_offset[0],
        })
    }

    /// The spindle's block with `rotation`: the last S and the surface speed in force.
    fn spindle_block(&self, rotation: SpindleRotation) -> BlockKind {
        BlockKind::Spindle { rotation, rpm: self.rpm, css: self.surface_speed() }
    }

    /// The current position of axis `axis` (X Y Z A) in the program frame and units.
    fn program_position(&self, axis: usize) -> f64 {
        self.user_units(axis, self.to_program(self.position)[axis])
    }

    /// LinuxCNC's predefined named parameters (`#<_x>`, `#<_metric>`, ...), read-only.
    pub(crate) fn predefined(&self, name: &str) -> Option<f64> {
        let flag = |b: bool| f64::from(u8::from(b));
        Some(match name {
            // LinuxCNC reads its package version "2.9.0" as two numbers, "2.9" and ".0"
            // (LinuxCNC's documentation: 2.6.2 gives 2.6 and 0.2); rs274 2.9 prints
            // _vmajor 2.900000, _vminor 0.000000 (roparams.ngc, make conformance).
            "_vmajor" => 2.9,
            "_vminor" => 0.0,
            "_line" => self.line as f64,
            "_motion_mode" => f64::from(self.motion.unwrap_or(800)),
            "_plane" => match self.plane {
                Plane::Xy => 170.0,
                Plane::Zx => 180.0,
                Plane::Yz => 190.0,
            },
            "_ccomp" => match self.comp {
                CompSide::Off => 400.0,
                CompSide::Left => 410.0,
                CompSide::Right => 420.0,
            },
            "_metric" => flag(!self.inches),
            "_imperial" => flag(self.inches),
            "_absolute" => flag(!self.incremental),
            "_incremental" => flag(self.incremental),
            "_inverse_time" => flag(self.inverse_time),
            "_units_per_minute" => flag(!self.inverse_time && !self.per_rev),
            "_units_per_rev" => flag(self.per_rev),
            "_coord_system" => [540.0, 550.0, 560.0, 570.0, 580.0, 590.0, 591.0, 592.0, 593.0][self.system],
            "_ijk_absolute_mode" => flag(!self.arc_incremental),
            // A tool length offset in force (G43, G43.1, G43.2 with a non-zero offset).
            "_tool_offset" => flag(self.tool_offset.iter().any(|&o| o != 0.0)),
            "_retract_r_plane" => flag(self.retract_to_r),
            "_retract_old_z" => flag(!self.retract_to_r),
            "_lathe_diameter_mode" => flag(self.diameter_mode),
            "_lathe_radius_mode" => flag(!self.diameter_mode),
            "_spindle_on" => flag(self.rotation != SpindleRotation::Off),
            "_spindle_rpm_mode" => flag(self.css.is_none()),
            "_spindle_css_mode" => flag(self.css.is_some()),
            "_spindle_cw" => flag(self.rotation == SpindleRotation::Clockwise),
            "_mist" => flag(self.mist),
            "_flood" => flag(self.flood),
            "_feed_override" => flag(self.overrides.feed),
            "_speed_override" => flag(self.overrides.speed),
            "_adaptive_feed" => flag(self.overrides.adaptive_feed),
            "_feed_hold" => flag(self.overrides.feed_hold),
            "_feed" => self.feed_mm_per_min.map_or(0.0, |f| if self.inches { f / MM_PER_INCH } else { f }),
            "_rpm" => self.rpm,
            "_x" | "_abs_x" => self.program_position(0),
            "_y" | "_abs_y" => self.program_position(1),
            "_z" | "_abs_z" => self.program_position(2),
            "_a" | "_abs_a" => self.program_position(3),
            "_b" | "_abs_b" => self.program_position(4),
            "_c" | "_abs_c" => self.program_position(5),
            "_u" | "_abs_u" => self.program_position(6),
            "_v" | "_abs_v" => self.program_position(7),
            "_w" | "_abs_w" => self.program_position(8),
            "_current_tool" => f64::from(self.tool_in_spindle),
            "_current_pocket" => f64::from(self.tool_in_spindle),
            "_selected_tool" => f64::from(self.tool),
            "_selected_pocket" => f64::from(self.tool),
            "_task" => 0.0,
            _ => return None,
        })
    }

    /// The feed rate of a feed move now, mm/min: F, or in G95 F (mm per revolution)
    /// times the programmed speed S, as LinuxCNC's interpreter feeds it (S is what counts,
    /// whether the spindle turns or not).
    fn feed_now(&self) -> Option<f64> {
        self.feed_mm_per_min.map(|f| if self.per_rev { f * self.rpm } else { f })
    }

    fn length_mm(&self, value: f64) -> f64 {
        if self.inches {
            value * MM_PER_INCH
        } else {
            value
        }
    }

    /// Where the NURBS block still open was opened (line, column of its G5.2).
    pub(crate) fn open_nurbs(&self) -> Option<(usize, usize)> {
        self.nurbs.as_ref().map(|n| n.opened_at)
    }

    /// Executes one block (its values computed) in LinuxCNC's order.
    pub(crate) fn execute(&mut self, words: &[Word]) -> Result<Executed, LineError> {
        let mut w = sort_words(words)?;
        // G7/G8 first: in G7 every X word is a diameter (LinuxCNC halves it as it reads
        // it, for moves, G10, G28/G30, G43.1 and G92 alike; I and R are not halved).
        if let (None, Some((code, _))) = (&self.nurbs, w.group(Group::LatheMode)) {
            self.diameter_mode = code == 70;
        }
        if self.diameter_mode {
            if let Some((x, _)) = &mut w.params[letter_index('X')] {
                *x /= 2.0;
            }
        }
        if self.nurbs.is_some() && !w.has(Group::Motion, G5_3) {
            return self.nurbs_point_line(words, &w);
        }
        // G70-G72 take D E I P Q R U W as words of their own (out of the block here).
        let mut lathe_words = None;
        if let Some((code @ (700 | 710 | 711 | 712 | 720 | 721 | 722), column)) = w.group(Group::Motion) {
            let taken = ['D', 'E', 'I', 'P', 'Q', 'R', 'U', 'W'].map(|l| w.params[letter_index(l)].take());
            lathe_words = Some((code, column, taken));
        }
        let mut kinds = Vec::new();

        // What will move, to check that every parameter word has a user.
        let motion = w.group(Group::Motion).map(|(c, _)| c).or(self.motion);
        let non_modal = w.group(Group::NonModal).map(|(c, _)| c);
        let first_axis = AXES.iter().chain(&['@', '^']).filter_map(|&l| w.param(l)).map(|(_, c)| c).min();
        let polar = w.param('@').or(w.param('^'));
        if let Some((_, column)) = polar {
            if let Some((_, c)) = w.param('X').or(w.param('Y')) {
                return Err(LineError::new(c.max(column), "X or Y with polar coordinates @ ^ in one block"));
            }
            if self.plane != Plane::Xy {
                return Err(LineError::new(column, "polar coordinates @ ^ are for the G17 (XY) plane"));
            }
        }
        // G10, G28, G30, G92 and G43.1 take the axis words themselves.
        let axes_taken = matches!(non_modal, Some(100 | 280 | 300 | 920))
            || w.has(Group::ToolLength, 431)
            || w.has(Group::ToolLength, 432);
        let moving = first_axis.is_some() && !axes_taken;
        let motion_column = w.group(Group::Motion).map(|(_, c)| c).or(first_axis);
        let arc_mode = matches!(motion, Some(20 | 30));
        // G2/G3 with I/J/K and no axis word: a full circle where it stands, as in LinuxCNC.
        let full_circle = arc_mode
            && w.group(Group::Motion).is_some()
            && !moving
            && !axes_taken
            && ['I', 'J', 'K'].iter().any(|&l| w.param(l).is_some());
        let arc_move = arc_mode && (moving || full_circle);
        let cycle_mode = motion.is_some_and(|m| CYCLES.contains(&m));
        let cycle_move = cycle_mode && moving;
        let g10 = non_modal == Some(100);
        let no_axes = |column: usize| {
            let name = g_name(motion.unwrap_or(20));
            LineError::new(motion_column.unwrap_or(column), format!("{name} with no axis words"))
        };
        // G5 and G5.1 are not modal in rs274: their I J (and G5's P Q) need the G5 or
        // G5.1 word in the block.
        let spline_move = w.has(Group::Motion, 51) || w.has(Group::Motion, 50);
        let cubic_move = w.has(Group::Motion, 50);
        let back_boring = cycle_move && motion == Some(870);
        for letter in ['I', 'J', 'K'] {
            if let Some((_, column)) = w.param(letter) {
                if spline_move && letter != 'K' || back_boring {
                    continue;
                }
                if arc_mode && !arc_move {
                    return Err(no_axes(column));
                }
                if !arc_move {
                    return Err(LineError::new(column, format!("{letter} word with no G2 or G3 to use it")));
                }
            }
        }
        let orient_words = w.has(Group::Spindle, 190);
        if let Some((_, column)) = w.param('R') {
            if !(arc_move || cycle_move || g10 || orient_words) {
                if arc_mode {
                    return Err(no_axes(column));
                }
                return Err(LineError::new(column, "R word with no G2, G3, canned cycle, G10 or M19 to use it"));
            }
        }
        let dynamic_comp = w.has(Group::Comp, 411) || w.has(Group::Comp, 421);
        // M62-M68 (in tenths).
        let io = w.group(Group::Io).map(|(code, _)| code);
        if let Some((_, column)) = w.param('E') {
            if !matches!(io, Some(660..=680)) {
                return Err(LineError::new(column, "E word with no M66, M67 or M68 to use it"));
            }
        }
        if let Some((_, column)) = w.param('L') {
            if dynamic_comp {
                // The orientation of a lathe tool, for G18 only (read with the
                // compensation below).
                let g18 = w.group(Group::Plane).map_or(self.plane == Plane::Zx, |(code, _)| code == 180);
                if !g18 {
                    let name = w.group(Group::Comp).map_or(String::new(), |(code, _)| g_name(code));
                    return Err(LineError::new(column, format!("{name} with L word, but plane is not G18")));
                }
            } else if !(w.has(Group::Motion, G5_2) || g10 || cycle_move || io == Some(660)) {
                return Err(LineError::new(column, "L word with no G5.2, G10, canned cycle or M66 to use it"));
            }
        }
        if let Some((_, column)) = w.param('P') {
            let users = [
                non_modal == Some(40),
                w.has(Group::Path, 640),
                arc_move,
                w.has(Group::Motion, G5_2),
                cubic_move,
                g10,
                cycle_move && matches!(motion, Some(820 | 860 | 890)),
                w.group(Group::Override).is_some_and(|(code, _)| code >= 500),
                matches!(io, Some(620..=660)),
                orient_words,
                w.group(Group::User).is_some(),
            ];
            match users.iter().filter(|&&u| u).count() {
                0 => return Err(LineError::new(
                    column,
                    "P word with no G4, G64, G2, G3, G5, G5.2, G10, G82, G86, G89, M19, M50-M53, M62-M66 or M100-M199 to use it",
                )),
                1 => {}
                _ => return Err(LineError::new(column, "P word is used by more than one code")),
            }
        }
        if let Some((q, column)) = w.param('Q') {
            // G64's Q is LinuxCNC's naive-CAM tolerance (it merges nearly collinear
            // segments within Q): accepted and not used, every segment is followed.
            let g64 = w.has(Group::Path, 640);
            if g64 && q < 0.0 {
                return Err(LineError::new(column, "negative naive-CAM tolerance Q"));
            }
            if !(g64
                || cubic_move
                || orient_words
                || w.has(Group::ToolChange, 610)
                || matches!(io, Some(660..=680))
                || w.group(Group::User).is_some()
                || cycle_move && matches!(motion, Some(730 | 830)))
            {
                return Err(LineError::new(
                    column,
                    "Q word with no G5, G64, G73, G83, M19, M61, M66-M68 or M100-M199 to use it",
                ));
            }
        }
        if let Some((_, column)) = w.param('H') {
            if !(w.has(Group::ToolLength, 430) || w.has(Group::ToolLength, 432)) {
                return Err(LineError::new(column, "H word with no G43 or G43.2 to use it"));
            }
        }
        if let Some((_, column)) = w.param('D') {
            if !(w.has(Group::Comp, 410) || w.has(Group::Comp, 420) || dynamic_comp || w.has(Group::SpindleMode, 960)) {
                return Err(LineError::new(column, "D word with no G41, G41.1, G42, G42.1 or G96 to use it"));
            }
        }
        if let (true, Some(column), None | Some(800)) = (moving, first_axis, motion) {
            return Err(LineError::new(column, "axis word with no motion mode (G0, G1, G2, G3 or a cycle) to use it"));
        }
        let g53 = non_modal == Some(530);
        if let (true, Some((_, column))) = (g53, w.group(Group::NonModal)) {
            if !matches!(motion, Some(0 | 10)) || !moving {
                return Err(LineError::new(column, "G53 needs G0 or G1 and axis words"));
            }
            if self.incremental || w.has(Group::Distance, 910) {
                return Err(LineError::new(column, "G53 in incremental distance mode (G91)"));
            }
        }

        // Spindle mode (first, as LinuxCNC orders them): G96 S- D- (S the surface speed,
        // D the highest speed, its magnitude) or G97; the spindle block below carries it.
        let spindle_mode = w.group(Group::SpindleMode);
        if let Some((code, column)) = spindle_mode {
            self.css = if code == 960 {
                if w.param('S').is_none() {
                    return Err(LineError::new(column, "S word missing with G96"));
                }
                Some(w.param('D').map(|(d, _)| d.abs()))
            } else {
                None
            };
        }

        // Feed mode (before F, as LinuxCNC orders them): a change unsets the feed rate.
        if let Some((code, _)) = w.group(Group::FeedMode) {
            if (code == 930, code == 950) != (self.inverse_time, self.per_rev) {
                (self.inverse_time, self.per_rev) = (code == 930, code == 950);
                self.feed_mm_per_min = None;
            }
        }
        // Feed, speed, tool selection.
        self.inverse_f = None;
        if let Some((f, column)) = w.param('F') {
            if f < 0.0 {
                return Err(LineError::new(column, "negative feed rate"));
            }
            if self.inverse_time {
                // 1/min, for this block's move only; `#<_feed>` and F after G94 see none.
                self.inverse_f = Some(f);
            } else {
                self.feed_mm_per_min = Some(self.length_mm(f));
            }
        }
        if let Some((s, column)) = w.param('S') {
            if s < 0.0 {
                return Err(LineError::new(column, "negative spindle speed"));
            }
            self.rpm = s;
        }
        if let Some((t, column)) = w.param('T') {
            self.tool = as_u32(t).ok_or_else(|| LineError::new(column, "T word must be a non-negative integer"))?;
            kinds.push(BlockKind::ToolSelect { tool: self.tool });
        }
        if let Some((610, column)) = w.group(Group::ToolChange) {
            let (q, q_column) = w.param('Q').ok_or_else(|| LineError::new(column, "M61 needs a Q word (the tool)"))?;
            self.tool_in_spindle =
                as_u32(q).ok_or_else(|| LineError::new(q_column, "Q word must be a non-negative integer"))?;
        } else if w.group(Group::ToolChange).is_some() {
            // LinuxCNC stops the spindle for a tool change.
            self.rotation = SpindleRotation::Off;
            kinds.push(self.spindle_block(self.rotation));
            kinds.push(BlockKind::ToolChange { tool: self.tool });
            self.tool_in_spindle = self.tool;
        }

        // Spindle and coolant.
        // M19 with R or P orients the spindle (which stops it turning); a bare M19 sends
        // the machine nothing in LinuxCNC, and changes nothing here (rs274's
        // `#<_spindle_on>` reads 0 after it while the spindle runs on).
        let orient = w.has(Group::Spindle, 190);
        if let Some((code, _)) = w.group(Group::Spindle).filter(|_| !orient) {
            self.rotation = match code {
                30 => SpindleRotation::Clockwise,
                40 => SpindleRotation::CounterClockwise,
                _ => SpindleRotation::Off,
            };
        }
        if (w.group(Group::Spindle).is_some() && !orient) || w.param('S').is_some() || spindle_mode.is_some() {
            kinds.push(self.spindle_block(self.rotation));
        }
        if orient {
            if let Some(kind) = spindle_orient(&w)? {
                self.rotation = SpindleRotation::Off;
                kinds.push(kind);
            }
        }
        if let Some((code, _)) = w.group(Group::Coolant) {
            match code {
                70 => self.mist = true,
                80 => self.flood = true,
                _ => (self.mist, self.flood) = (false, false),
            }
            if w.mist_and_flood.is_some() {
                (self.mist, self.flood) = (true, true);
            }
            kinds.push(BlockKind::Coolant { mist: self.mist, flood: self.flood });
        }

        // Override switches (M48-M53), after the coolant as in LinuxCNC. M50-M53 without
        // P, or with a P other than 0, enable; P0 disables.
        if let Some((code, _)) = w.group(Group::Override) {
            let on = w.param('P').is_none_or(|(p, _)| p != 0.0);
            let o = &mut self.overrides;
            match code {
                480 => (o.feed, o.speed) = (true, true),
                490 => (o.feed, o.speed) = (false, false),
                500 => o.feed = on,
                510 => o.speed = on,
                520 => o.adaptive_feed = on,
                _ => o.feed_hold = on,
            }
            kinds.push(BlockKind::Overrides(self.overrides));
        }

        // Digital outputs (M62/M63 with the next move, M64/M65 at once: finestep sets
        // either at rest where it is written, so both act before the next move).
        if let Some((code @ 660..=680, column)) = w.group(Group::Io) {
            kinds.push(self.input_output(&w, code, column)?);
        } else if let Some((code, column)) = w.group(Group::Io) {
            let (p, p_column) =
                w.param('P').ok_or_else(|| LineError::new(column, format!("M{} with no P (the output)", code / 10)))?;
            let index = as_u32(p)
                .filter(|&i| i < 64)
                .ok_or_else(|| LineError::new(p_column, "digital output P must be an integer 0 to 63"))?;
            kinds.push(BlockKind::DigitalOutput { index, on: matches!(code, 620 | 640) });
        }

        // A user M-code (after the overrides, before the dwell, in LinuxCNC's order).
        if let Some((code, column)) = w.group(Group::User) {
            let code = code / 10;
            let name = format!("M{code}");
            if !self.user_m_path.iter().any(|dir| is_executable(&dir.join(&name))) {
                return Err(LineError::new(
                    column,
                    format!(
                        "Unknown M code used: {name} (no executable {name} in the user M-code path{})",
                        if self.user_m_path.is_empty() {
                            ", which the machine configuration does not give"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            let p = w.param('P').map_or(0.0, |(p, _)| p);
            let q = w.param('Q').map_or(0.0, |(q, _)| q);
            kinds.push(BlockKind::UserMCode { code, p, q });
        }

        // Dwell.
        if let Some((40, column)) = w.group(Group::NonModal) {
            let (p, p_column) = w.param('P').ok_or_else(|| LineError::new(column, "G4 with no P word"))?;
            if p < 0.0 {
                return Err(LineError::new(p_column, "negative dwell time"));
            }
            kinds.push(BlockKind::Dwell { seconds: p });
        }

        // Units, after F as in LinuxCNC (F is read in the units in force before the block).
        if let Some((code, _)) = w.group(Group::Units) {
            self.inches = code == 200;
        }

        // Plane and distance modes.
        if let Some((code, column)) = w.group(Group::Plane) {
            let plane = match code {
                170 => Plane::Xy,
                180 => Plane::Zx,
                _ => Plane::Yz,
            };
            // Compensation offsets in its plane; as in LinuxCNC, that plane stays.
            if plane != self.plane && self.comp != CompSide::Off {
                return Err(LineError::new(column, "Cannot change planes with cutter radius compensation on"));
            }
            self.plane = plane;
        }
        if let Some((code, _)) = w.group(Group::Distance) {
            self.incremental = code == 910;
        }
        if let Some((code, _)) = w.group(Group::ArcDistance) {
            self.arc_incremental = code == 911;
        }

        // Cutter compensation.
        if let Some((code, column)) = w.group(Group::Comp) {
            let mut side = match code {
                410 | 411 => CompSide::Left,
                420 | 421 => CompSide::Right,
                _ => CompSide::Off,
            };
            if side != CompSide::Off && self.comp != CompSide::Off {
                return Err(LineError::new(column, "cutter compensation is already on (G40 first)"));
            }
            if side != CompSide::Off && self.plane == Plane::Yz {
                return Err(LineError::new(column, "Cutter radius compensation allowed only in XY, XZ planes"));
            }
            if dynamic_comp {
                let (d, _) =
                    w.param('D').ok_or_else(|| LineError::new(column, format!("{} with no D word", g_name(code))))?;
                // A negative diameter takes the other side, as in LinuxCNC.
                if d < 0.0 {
                    side = if side == CompSide::Left { CompSide::Right } else { CompSide::Left };
                }
                // L: the lathe tool's orientation (G18 only, checked above).
                let orientation = match w.param('L') {
                    None => 0,
                    Some((l, l_column)) => as_u32(l).ok_or_else(|| {
                        LineError::new(l_column, "L (the lathe tool's orientation) must be a non-negative integer")
                    })?,
                };
                self.comp = side;
                let radius_mm = self.length_mm(d.abs()) / 2.0;
                kinds.push(BlockKind::CutterCompRadius { side, radius_mm, plane: self.plane, orientation });
            } else {
                let tool = match w.param('D') {
                    Some((d, d_column)) => Some(
                        as_u32(d).ok_or_else(|| LineError::new(d_column, "D word must be a non-negative integer"))?,
                    ),
                    None => None,
                };
                self.comp = side;
                kinds.push(BlockKind::CutterComp { side, tool, plane: self.plane });
            }
        }

        // Tool length offset.
        if let Some((code, column)) = w.group(Group::ToolLength) {
            self.tool_offset = match code {
                430 => {
                    let tool = match w.param('H') {
                        Some((h, c)) => {
                            as_u32(h).ok_or_else(|| LineError::new(c, "H word must be a non-negative integer"))?
                        }
                        None => self.tool_in_spindle,
                    };
                    if tool == 0 {
                        [0.0; N_AXES]
                    } else {
                        *self.tools.get(&tool).ok_or_else(|| {
                            LineError::new(column, format!("G43: tool {tool} is not in the tool table"))
                        })?
                    }
                }
                // G43.2: the offset in force plus tool H's, or plus the axis words (as
                // LinuxCNC's documentation says; rs274 2.9 refuses that form).
                432 => {
                    let axes = AXES.iter().filter_map(|&l| w.param(l).map(|(_, c)| c)).min();
                    let mut offset = self.tool_offset;
                    match (w.param('H'), axes) {
                        (Some(_), Some(c)) => {
                            return Err(LineError::new(c, "G43.2 with both H and axis words"));
                        }
                        (None, None) => return Err(LineError::new(column, "G43.2 with no H word and no axis words")),
                        (Some((h, c)), None) => {
                            let tool =
                                as_u32(h).ok_or_else(|| LineError::new(c, "H word must be a non-negative integer"))?;
                            if tool != 0 {
                                let add = self.tools.get(&tool).ok_or_else(|| {
                                    LineError::new(column, format!("G43.2: tool {tool} is not in the tool table"))
                                })?;
                                offset.iter_mut().zip(add).for_each(|(o, a)| *o += a);
                            }
                        }
                        (None, Some(_)) => {
                            for (axis, &letter) in AXES.iter().enumerate() {
                                if let Some((v, _)) = w.param(letter) {
                                    offset[axis] += if rotary(axis) { v } else { self.length_mm(v) };
                                }
                            }
                        }
                    }
                    offset
                }
                431 => {
                    let mut offset = [0.0; N_AXES];
                    for (axis, &letter) in AXES.iter().enumerate() {
                        if let Some((v, _)) = w.param(letter) {
                            offset[axis] = if rotary(axis) { v } else { self.length_mm(v) };
                        }
                    }
                    offset
                }
                _ => [0.0; N_AXES],
            };
        }

        // Coordinate system, return mode.
        if let Some((code, column)) = w.group(Group::Coord) {
            if self.comp != CompSide::Off {
                return Err(LineError::new(column, "coordinate system change with cutter compensation on"));
            }
            let system = match code {
                540 => 0,
                550 => 1,
                560 => 2,
                570 => 3,
                580 => 4,
                590 => 5,
                591 => 6,
                592 => 7,
                _ => 8,
            };
            // Selecting the system in use keeps its offsets (rs274: "continuing to use
            // same coordinate system"), even if its parameters changed.
            if system != self.system {
                self.select_system(system);
            }
        }
        if let Some((code, _)) = w.group(Group::ReturnMode) {
            self.retract_to_r = code == 990;
        }

        // G10, G28.1, G30.1, G92 family (G28/G30 move, below).
        match w.group(Group::NonModal) {
            Some((100, column)) => self.g10(&w, column)?,
            Some((281, _)) => self.home[0] = self.position,
            Some((301, _)) => self.home[1] = self.position,
            Some((920, column)) => {
                if first_axis.is_none() {
                    return Err(LineError::new(column, "G92 with no axis words"));
                }
                let mut g92 = self.g92_now();
                let here = self.to_program(self.position);
                for (axis, &letter) in AXES.iter().enumerate() {
                    if let Some((v, _)) = w.param(letter) {
                        let v = if rotary(axis) { v } else { self.length_mm(v) };
                        g92[axis] = here[axis] + g92[axis] - v;
                    }
                }
                (self.g92, self.g92_on, self.active_g92) = (g92, true, g92);
            }
            Some((921, _)) => (self.g92, self.g92_on, self.active_g92) = ([0.0; N_AXES], false, [0.0; N_AXES]),
            Some((922, _)) => (self.g92_on, self.active_g92) = (false, [0.0; N_AXES]),
            Some((923, _)) => (self.g92_on, self.active_g92) = (true, self.g92),
            _ => {}
        }

        // Path control.
        if let Some((code, _)) = w.group(Group::Path) {
            // G61.1 (exact stop) is G61 here: finestep's G61 already stops at the end of
            // every move, collinear or not, which is what G61.1 asks.
            let mode = if code == 610 || code == 611 {
                PathControl::ExactPath
            } else {
                let tolerance_mm = match w.param('P') {
                    Some((p, p_column)) if p < 0.0 => return Err(LineError::new(p_column, "negative path tolerance")),
                    Some((p, _)) => Some(self.length_mm(p)),
                    None => None,
                };
                PathControl::Blend { tolerance_mm }
            };
            self.path = mode;
            kinds.push(BlockKind::PathControl(mode));
        }

        // Motion.
        // A canned cycle keeps its R, Z, P and Q only while it stays the motion mode.
        if let Some((code, _)) = w.group(Group::Motion) {
            if self.motion != Some(code) {
                self.cycle = CycleWords::default();
            }
        }
        if let (true, Some((code @ (50 | 51 | G5_2), column))) = (self.inverse_time, w.group(Group::Motion)) {
            return Err(LineError::new(
                column,
                format!("unsupported: {} in G93 ({})", g_name(code), unsupported::INVERSE_TIME_SPLINE),
            ));
        }
        match w.group(Group::Motion) {
            Some((G5_2, column)) => {
                self.open_nurbs_block(&w, column)?;
                self.motion = None;
            }
            Some((G5_3, column)) => {
                kinds.push(self.close_nurbs_block(&w, column)?);
                self.motion = None;
            }
            Some((800, _)) => self.motion = None,
            Some((code @ (50 | 51 | 382..=385), column)) => {
                if !moving {
                    return Err(LineError::new(column, format!("{} with no axis words", g_name(code))));
                }
                self.motion = Some(code);
            }
            Some((code, _)) => self.motion = Some(code),
            None => {}
        }
        // G95 under G96: the feed per revolution would follow a speed that changes along
        // the move (rs274 multiplies F by the surface speed's S).
        let feeding = lathe_words.is_some()
            || ((moving || full_circle) && self.motion.is_some_and(|code| code != 0 && code != 800));
        if let (true, true, Some(column)) =
            (feeding, self.per_rev && self.surface_speed().is_some(), first_axis.or(motion_column))
        {
            return Err(LineError::new(column, format!("unsupported: G95 in G96 ({})", unsupported::FEED_PER_REV_CSS)));
        }
        let mut lathe = None;
        if let Some((code, column, taken)) = lathe_words {
            lathe = Some(self.lathe_cycle(&w, code, column, taken, &mut kinds)?);
        } else if let Some((code @ (280 | 300), _)) = w.group(Group::NonModal) {
            self.home_move(&w, if code == 280 { 0 } else { 1 }, first_axis.is_some(), &mut kinds)?;
        } else if let (Some(code), Some(column), None) = (self.motion, first_axis.or(motion_column), &self.nurbs) {
            if moving || full_circle {
                if CYCLES.contains(&code) {
                    self.canned_cycle(&w, code, column, &mut kinds)?;
                } else if (382..=385).contains(&code) {
                    kinds.push(self.probe(&w, code, column)?);
                } else if code == 51 || code == 50 {
                    kinds.push(self.spline(&w, code, column)?);
                    // Axis words alone do not continue a G5 or G5.1 (as in rs274).
                    self.motion = None;
                } else {
                    self.move_to(&w, code, column, g53, &mut kinds)?;
                }
            }
        }
        // Stops.
        let mut end = false;
        if let Some((code, _)) = w.group(Group::Stop) {
            if code == 0 || code == 10 || code == 600 {
                // M1 (optional stop) stops as M0: finestep has no optional-stop switch.
                // M60 (pallet change pause) stops as M0: finestep drives no pallet
                // shuttle, the operator changes the pallet before resuming.
                kinds.push(BlockKind::Pause);
            } else {
                kinds.push(BlockKind::End);
                end = true;
                // M2/M30 put G54 back in force (LinuxCNC's reset: #5220 is 1 in the
                // parameter file written after it), and G97 (its `SET_SPINDLE_MODE(0 0)`).
                self.select_system(0);
                self.css = None;
            }
        }
        let modal = w.group(Group::ModalState).map(|(code, _)| match code {
            700 => ModalOp::Save,
            710 => ModalOp::Forget,
            720 => ModalOp::Restore,
            _ => ModalOp::SaveUntilReturn,
        });
        Ok(Executed { n: w.n, kinds, end, modal, lathe })
    }

    /// G70-G72 (`code`, at `column`): checks the block as LinuxCNC does, makes the move
    /// to the start point (G0 to X Z), and gives the cycle back to the caller, which
    /// reads its profile from the Q subroutine.
    fn lathe_cycle(
        &mut self,
        w: &Words,
        code: Code,
        column: usize,
        taken: [Option<(f64, usize)>; 8],
        kinds: &mut Vec<BlockKind>,
    ) -> Result<LatheCycle, LineError> {
        let [d, e, i, p, q, r, u, ww] = taken;
        let name = g_name(code);
        let q =
            q.ok_or_else(|| LineError::new(column, format!("{name} requires a Q word (the profile's subroutine)")))?;
        if self.comp != CompSide::Off && code != 700 {
            return Err(LineError::new(column, format!("{name} cannot be used with cutter compensation enabled")));
        }
        if self.comp != CompSide::Off {
            // LinuxCNC 2.9 allows G70 here, but leaves its position at the profile's end
            // while reading the profile, so the compensated lead-in runs from there: a
            // rapid through the part (docs/gcode.md, "Lathe cycles G70, G71, G72").
            return Err(LineError::new(
                column,
                format!("unsupported: G70 with cutter compensation on ({})", unsupported::G70_COMPENSATED),
            ));
        }
        if self.plane != Plane::Zx {
            return Err(LineError::new(column, format!("{name} can only be used in XZ plane (G18)")));
        }
        if let Some((value, c)) = i {
            if value <= 0.0 {
                return Err(LineError::new(c, format!("{name}: I must be greater than zero")));
            }
        }
        // As in LinuxCNC, the move to the start takes X and Z as absolute even in G91,
        // while the cycle starts at them added to where the block began.
        let before = self.to_program(self.position);
        let incremental = self.incremental;
        self.incremental = false;
        let moved = self.move_to(w, 0, column, false, kinds);
        self.incremental = incremental;
        moved?;
        self.motion = Some(0);
        let here = self.to_program(self.position);
        let mut start = Pt::new(self.user_units(2, here[2]), self.user_units(0, here[0]));
        if incremental {
            let word = |letter: char| w.param(letter).map_or(0.0, |(v, _)| v);
            start = Pt::new(self.user_units(2, before[2]) + word('Z'), self.user_units(0, before[0]) + word('X'));
        }
        let value = |word: Option<(f64, usize)>, default: f64| word.map_or(default, |(v, _)| v);
        Ok(LatheCycle {
            code,
            column,
            q,
            start,
            d: value(d, 0.0),
            e: value(e, 0.0),
            i: value(i, 1.0),
            p: value(p, 1.0),
            r: value(r, 0.5),
            u: value(u, 0.0),
            w: value(ww, 0.0),
        })
    }

    /// One line of a lathe cycle's profile: its motion words (G0-G3, X Z or U W, I K or
    /// R, A or C for a corner) added to `reader` instead of moving; LinuxCNC reads nothing
    /// else there. The position (`#<_x>`, `#<_z>`) follows the profile.
    pub(crate) fn profile_line(&mut self, words: &[Word], reader: &mut ProfileReader) -> Result<(), LineError> {
        let w = sort_words(words)?;
        let start = reader.at;
        let mut end = if self.incremental { Pt::default() } else { start };
        let radius = |v: f64| if self.diameter_mode { v / 2.0 } else { v };
        for (relative, axis) in [('U', 'X'), ('W', 'Z')] {
            match (w.param(relative), w.param(axis)) {
                (Some((_, c)), _) if self.incremental => {
                    return Err(LineError::new(
                        c,
                        format!("G7x error: Cannot use {relative} in incremental mode (G91)"),
                    ))
                }
                (Some(_), Some((_, c))) => {
                    return Err(LineError::new(
                        c,
                        format!("G7x error: Cannot use {relative} and {axis} in the same block"),
                    ))
                }
                (Some((v, _)), None) if axis == 'X' => end.x += radius(v),
                (Some((v, _)), None) => end.z += v,
                (None, Some((v, _))) if axis == 'X' => end.x = radius(v),
                (None, Some((v, _))) => end.z = v,
                (None, None) => {}
            }
        }
        if self.incremental {
            end = end + start;
        }
        if let Some((code, _)) = w.group(Group::Motion) {
            reader.motion = code;
        }
        if end == start {
            return Ok(());
        }
        let column = w.group(Group::Motion).map(|(_, c)| c).or(w.param('X').map(|(_, c)| c)).unwrap_or(1);
        match reader.motion {
            0 | 10 => reader.segments.push(Segment::straight(start, end)),
            code @ (20 | 30) => {
                let ccw = code == 30;
                let centre = if let Some((r, c)) = w.param('R') {
                    if w.param('I').is_some() || w.param('K').is_some() {
                        return Err(LineError::new(c, "G7X error: both R and I or K flag used for arc"));
                    }
                    let chord = end - start;
                    let f = ((r * r - chord_norm(chord) / 4.0) / chord_norm(chord)).sqrt();
                    let d = Pt::new(-chord.x * f, chord.z * f);
                    let mid = Pt::new((start.z + end.z) / 2.0, (start.x + end.x) / 2.0);
                    if ccw {
                        mid + d
                    } else {
                        mid - d
                    }
                } else {
                    let (i, k) = (w.param('I'), w.param('K'));
                    if i.is_none() && k.is_none() {
                        return Err(LineError::new(column, "G7X error: either I or K must be present for arc"));
                    }
                    let c = Pt::new(k.map_or(0.0, |v| v.0), i.map_or(0.0, |v| v.0));
                    if self.arc_incremental {
                        c + start
                    } else {
                        c
                    }
                };
                reader.segments.push(Segment::arc(ccw, start, centre, end));
            }
            _ => {}
        }
        if matches!(reader.motion, 0 | 10 | 20 | 30) {
            match (w.param('A'), w.param('C')) {
                (Some(_), Some((_, c))) => {
                    return Err(LineError::new(c, "G7X error: Both A and C parameters on a corner"));
                }
                (Some((a, _)), None) => reader.segments.push(Segment::fillet(a, end)),
                (None, Some((c, _))) => reader.segments.push(Segment::chamfer(c, end)),
                (None, None) => {}
            }
        }
        reader.at = end;
        let mut p = self.to_program(self.position);
        p[0] = self.length_mm(end.x);
        p[2] = self.length_mm(end.z);
        self.position = self.to_machine(p);
        Ok(())
    }

    /// Puts the program's position (X, Z) back where a lathe cycle's profile started.
    pub(crate) fn profile_done(&mut self, at: Pt) {
        let mut p = self.to_program(self.position);
        p[0] = self.length_mm(at.x);
        p[2] = self.length_mm(at.z);
        self.position = self.to_machine(p);
    }

    /// The moves of a lathe cycle (program frame and units, X a radius) as blocks: each
    /// a G0, G1, G2 or G3 in absolute distance and centre modes, as LinuxCNC makes them.
    pub(crate) fn lathe_moves(&mut self, moves: &[Move], column: usize) -> Result<Vec<BlockKind>, LineError> {
        let saved = (self.incremental, self.arc_incremental);
        (self.incremental, self.arc_incremental) = (false, false);
        let mut kinds = Vec::new();
        let result = (|| {
            for m in moves {
                let word = |letter: char, value: f64| Word { letter, value, column };
                let diameter = |x: f64| if self.diameter_mode { 2.0 * x } else { x };
                let words = match *m {
                    Move::Rapid(p) | Move::Feed(p) => {
                        let g = if matches!(m, Move::Rapid(_)) { 0.0 } else { 1.0 };
                        vec![word('G', g), word('X', diameter(p.x)), word('Z', p.z)]
                    }
                    Move::Arc { ccw, centre, end } => {
                        // An arc that ends where it starts is left out (LinuxCNC's test).
                        let here = self.to_program(self.position);
                        let (x, z) = (self.user_units(0, here[0]), self.user_units(2, here[2]));
                        if (z - end.z).abs() < 1e-4 && (x - end.x).abs() < 1e-4 {
                            continue;
                        }
                        vec![
                            word('G', if ccw { 3.0 } else { 2.0 }),
                            word('X', diameter(end.x)),
                            word('Z', end.z),
                            word('I', centre.x),
                            word('K', centre.z),
                        ]
                    }
                };
                kinds.extend(self.execute(&words)?.kinds);
            }
            Ok(())
        })();
        (self.incremental, self.arc_incremental) = saved;
        result.map(|()| kinds)
    }

    /// A line inside an open NURBS block: `X- Y- <P->` adds a control point; nothing
    /// else may stand there.
    fn nurbs_point_line(&mut self, words: &[Word], w: &Words) -> Result<Executed, LineError> {
        for word in words {
            let message = match word.letter {
                'N' | 'X' | 'Y' | 'P' => continue,
                'Z' | 'A' | 'B' | 'C' | 'U' | 'V' | 'W' => {
                    format!("axis {} inside a NURBS block: only X and Y move in a NURBS (G17)", word.letter)
                }
                'G' => format!("G{} inside a NURBS block: only X, Y and P words until G5.3 closes it", word.value),
                letter => format!("{letter} word inside a NURBS block: only X, Y and P words until G5.3 closes it"),
            };
            return Err(LineError::new(word.column, message));
        }
        match (w.param('X'), w.param('Y')) {
            (Some(_), Some(_)) => {
                let (x, y) = self.nurbs_target(w)?;
                let weight = nurbs_weight(w)?;
                let nurbs = self.nurbs.as_mut().expect("open NURBS");
                nurbs.points.push(NurbsPoint { x_mm: x, y_mm: y, weight });
            }
            (Some((_, column)), None) | (None, Some((_, column))) => {
                return Err(LineError::new(column, "a NURBS control point needs both X and Y"));
            }
            (None, None) => {
                if let Some((_, column)) = w.param('P') {
                    return Err(LineError::new(
                        column,
                        "P without X and Y sets only the first control point's weight (on the G5.2 line)",
                    ));
                }
            }
        }
        Ok(Executed { n: w.n, kinds: Vec::new(), end: false, modal: None, lathe: None })
    }

    /// A control point's X and Y in mm: absolute, or in G91 relative to the start of the
    /// NURBS (the current position, which LinuxCNC updates only at G5.3).
    fn nurbs_target(&self, w: &Words) -> Result<(f64, f64), LineError> {
        let to = self.to_machine(self.target(w, self.to_program(self.position))?);
        Ok((to[0], to[1]))
    }

    /// G5.2: opens a NURBS block at the current position (LinuxCNC's first control point).
    fn open_nurbs_block(&mut self, w: &Words, column: usize) -> Result<(), LineError> {
        if self.plane != Plane::Xy {
            return Err(LineError::new(column, "G5.2 NURBS is supported in the G17 (XY) plane only"));
        }
        if self.comp != CompSide::Off {
            return Err(LineError::new(column, "G5.2 with cutter compensation on: a NURBS is not offset (G40 first)"));
        }
        if !self.feed_now().is_some_and(|f| f > 0.0) {
            return Err(LineError::new(column, "G5.2 with no feed rate"));
        }
        for letter in ['Z', 'A', 'B', 'C', 'U', 'V', 'W'] {
            if let Some((_, c)) = w.param(letter) {
                return Err(LineError::new(c, format!("axis {letter} in a NURBS: only X and Y move in a NURBS (G17)")));
            }
        }
        let order = match w.param('L') {
            None => NURBS_DEFAULT_ORDER,
            Some((l, c)) => match as_u32(l) {
                Some(k) if (2..=NURBS_MAX_ORDER).contains(&k) => k,
                _ => {
                    return Err(LineError::new(
                        c,
                        format!("NURBS order L must be an integer from 2 to {NURBS_MAX_ORDER}"),
                    ))
                }
            },
        };
        let weight = nurbs_weight(w)?;
        let start = NurbsPoint { x_mm: self.position[0], y_mm: self.position[1], weight: 1.0 };
        let mut nurbs = OpenNurbs { opened_at: (self.line, column), points: vec![start], order };
        match (w.param('X'), w.param('Y')) {
            (Some(_), Some(_)) => {
                let (x, y) = self.nurbs_target(w)?;
                nurbs.points.push(NurbsPoint { x_mm: x, y_mm: y, weight });
            }
            (Some((_, c)), None) | (None, Some((_, c))) => {
                return Err(LineError::new(c, "a NURBS control point needs both X and Y"));
            }
            // `G5.2 P-` alone: the weight of the first control point.
            (None, None) => nurbs.points[0].weight = weight,
        }
        self.nurbs = Some(nurbs);
        Ok(())
    }

    /// G5.3: closes the NURBS block and emits it.
    fn close_nurbs_block(&mut self, w: &Words, column: usize) -> Result<BlockKind, LineError> {
        for letter in AXES {
            if let Some((_, c)) = w.param(letter) {
                return Err(LineError::new(c, "G5.3 takes no axis words (control points go on the lines before it)"));
            }
        }
        let nurbs = self.nurbs.take().ok_or_else(|| LineError::new(column, "G5.3 without G5.2 first"))?;
        let count = nurbs.points.len();
        if count < nurbs.order as usize {
            return Err(LineError::new(
                column,
                format!(
                    "a NURBS of order {} needs at least {} control points, this one has {count}",
                    nurbs.order, nurbs.order
                ),
            ));
        }
        let feed_mm_per_min = match self.feed_now() {
            Some(f) if f > 0.0 => f,
            _ => return Err(LineError::new(column, "G5.3 with no feed rate")),
        };
        let last = nurbs.points[count - 1];
        let mut to = self.position;
        to[0] = last.x_mm;
        to[1] = last.y_mm;
        self.position = to;
        Ok(BlockKind::Nurbs {
            to: Point::from_array(to),
            knots: nurbs_knots(count, nurbs.order as usize),
            control_points: nurbs.points,
            order: nurbs.order,
            feed_mm_per_min,
        })
    }

    /// The block's end point in the program frame, absolute, in mm (and degrees for A),
    /// from `from` (the current position in the program frame).
    fn target(&self, w: &Words, from: Axes) -> Result<Axes, LineError> {
        let mut to = from;
        self.apply_xy(w, &mut to);
        for (axis, &letter) in AXES.iter().enumerate() {
            if let Some((value, column)) = w.param(letter) {
                if axis != 0 && axis != 1 {
                    let value = if rotary(axis) { value } else { self.length_mm(value) };
                    to[axis] = if self.incremental { to[axis] + value } else { value };
                }
                if to[axis].abs() > MAX_POSITION {
                    return Err(LineError::new(column, "position out of range"));
                }
            }
        }
        if let Some((_, column)) = w.param('@').or(w.param('^')) {
            if to[..2].iter().any(|v| v.is_nan() || v.abs() > MAX_POSITION) {
                return Err(LineError::new(column, "position out of range"));
            }
        }
        Ok(to)
    }

    /// X and Y from the block's X Y words, or from its polar words `@` (radius) and `^`
    /// (angle in degrees) around the program origin: in G90 each replaces the current
    /// radius or angle, in G91 each adds to it (LinuxCNC's rule).
    fn apply_xy(&self, w: &Words, p: &mut Axes) {
        if w.param('@').is_some() || w.param('^').is_some() {
            let (r, a) = (p[0].hypot(p[1]), p[1].atan2(p[0]).to_degrees());
            let (r, a) = match (self.incremental, w.param('@'), w.param('^')) {
                (false, at, caret) => (at.map_or(r, |(v, _)| self.length_mm(v)), caret.map_or(a, |(v, _)| v)),
                (true, at, caret) => {
                    (r + at.map_or(0.0, |(v, _)| self.length_mm(v)), a + caret.map_or(0.0, |(v, _)| v))
                }
            };
            let (sin, cos) = a.to_radians().sin_cos();
            (p[0], p[1]) = (r * cos, r * sin);
            return;
        }
        for (axis, letter) in [(0, 'X'), (1, 'Y')] {
            if let Some((v, _)) = w.param(letter) {
                let v = self.length_mm(v);
                p[axis] = if self.incremental { p[axis] + v } else { v };
            }
        }
    }

    /// The centre of an arc from the current position to `to`, and its extra turns.
    fn arc_centre(
        &self,
        w: &Words,
        from: Axes,
        to: Axes,
        name: String,
        column: usize,
    ) -> Result<(Axes, u32), LineError> {
        // In-plane axes (p, q) and normal, right-handed; the centre-offset letters of
        // p and q, and the letter of the normal axis.
        let (p, q, [lp, lq, ln], plane_code) = match self.plane {
            Plane::Xy => (0, 1, ['I', 'J', 'K'], 17),
            Plane::Zx => (2, 0, ['K', 'I', 'J'], 18),
            Plane::Yz => (1, 2, ['J', 'K', 'I'], 19),
        };
        if let Some((_, c)) = w.param(ln) {
            return Err(LineError::new(c, format!("{ln} word not allowed for an arc in the G{plane_code} plane")));
        }
        let ijk = w.param(lp).or(w.param(lq));
        let r = w.param('R');
        let mut centre = from;
        match (ijk, r) {
            (None, None) => {
                return Err(LineError::new(column, format!("{name} without I/J/K or R")));
            }
            (Some(_), Some((_, c))) => {
                return Err(LineError::new(c, format!("{name} with both R and I/J/K")));
            }
            (Some(_), None) => {
                for (axis, letter) in [(p, lp), (q, lq)] {
                    let offset = w.param(letter).map_or(0.0, |(v, _)| self.length_mm(v));
                    centre[axis] = if self.arc_incremental { from[axis] + offset } else { offset };
                }
                let radius = |point: Axes| (point[p] - centre[p]).hypot(point[q] - centre[q]);
                let (r_start, r_end) = (radius(from), radius(to));
                if r_start <= ZERO_MM {
                    return Err(LineError::new(column, "arc radius is zero"));
                }
                let differs = (r_end - r_start).abs();
                if !(differs <= ARC_ABSOLUTE_TOLERANCE_MM || differs <= ARC_RELATIVE_TOLERANCE * r_start) {
                    return Err(LineError::new(
                        column,
                        format!("arc end not on circle: radius differs by {differs:.3} mm"),
                    ));
                }
            }
            (None, Some((r, r_column))) => {
                let r = self.length_mm(r);
                let (dp, dq) = (to[p] - from[p], to[q] - from[q]);
                let chord = dp.hypot(dq);
                if chord <= ZERO_MM {
                    return Err(LineError::new(r_column, "R-form arc needs an end point different from its start"));
                }
                let half = chord / 2.0;
                if half - r.abs() > ARC_ABSOLUTE_TOLERANCE_MM {
                    return Err(LineError::new(
                        r_column,
                        format!("arc radius {:.3} mm is less than half the chord {half:.3} mm", r.abs()),
                    ));
                }
                // The centre is on the chord's bisector, at distance h; on the right of
                // the chord (start to end) for a clockwise short arc.
                let h = (r * r - half * half).max(0.0).sqrt();
                let clockwise = name == "G2";
                let side = if clockwise == (r > 0.0) { 1.0 } else { -1.0 };
                let (up, uq) = (dp / chord, dq / chord);
                centre[p] = from[p] + dp / 2.0 + side * h * uq;
                centre[q] = from[q] + dq / 2.0 - side * h * up;
            }
        }
        let extra_turns = match w.param('P') {
            Some((turns, c)) => match as_u32(turns) {
                Some(t) if t >= 1 => t - 1,
                _ => return Err(LineError::new(c, format!("P word for {name} must be a positive integer"))),
            },
            None => 0,
        };
        Ok((centre, extra_turns))
    }
}

impl State {
    /// A G0/G1/G2/G3 move (G53: to machine coordinates).
    fn move_to(
        &mut self,
        w: &Words,
        code: Code,
        column: usize,
        g53: bool,
        kinds: &mut Vec<BlockKind>,
    ) -> Result<(), LineError> {
        let from = self.to_program(self.position);
        let (to_program, to) = if g53 {
            let mut to = self.position;
            for (axis, &letter) in AXES.iter().enumerate() {
                if let Some((v, _)) = w.param(letter) {
                    to[axis] = if rotary(axis) { v } else { self.length_mm(v) };
                }
            }
            (self.to_program(to), to)
        } else {
            let p = self.target(w, from)?;
            (p, self.to_machine(p))
        };
        if to.iter().any(|v| v.abs() > MAX_POSITION) {
            return Err(LineError::new(column, "position out of range"));
        }
        let feed = || match self.feed_now() {
            Some(f) if f > 0.0 => Ok(f),
            Some(_) if self.per_rev && self.rpm == 0.0 => Err(LineError::new(
                column_of(w, column),
                format!("{} with zero spindle speed in feed per revolution (G95): S first", g_name(code)),
            )),
            _ => Err(LineError::new(column_of(w, column), format!("{} with no feed rate", g_name(code)))),
        };
        let from_machine = self.position;
        let kind = match code {
            0 => BlockKind::Rapid { to: Point::from_array(to) },
            10 if self.inverse_time => {
                let f = self.inverse_feed(w, code, column)?;
                let (length, linear) = straight_length(from_machine, to);
                let floor = if linear { self.length_mm(INVERSE_TIME_MIN_RATE) } else { INVERSE_TIME_MIN_RATE };
                BlockKind::Linear { to: Point::from_array(to), feed_mm_per_min: (length * f).max(floor) }
            }
            10 => BlockKind::Linear { to: Point::from_array(to), feed_mm_per_min: feed()? },
            _ => {
                let inverse = if self.inverse_time { Some(self.inverse_feed(w, code, column)?) } else { None };
                let feed_mm_per_min = if inverse.is_some() { 0.0 } else { feed()? };
                let (centre, extra_turns) = self.arc_centre(w, from, to_program, g_name(code), column_of(w, column))?;
                let centre_machine = self.to_machine(centre);
                let feed_mm_per_min = match inverse {
                    Some(f) => (f * arc_length(from_machine, to, centre_machine, self.plane, code == 20, extra_turns))
                        .max(self.length_mm(INVERSE_TIME_MIN_RATE)),
                    None => feed_mm_per_min,
                };
                BlockKind::Arc {
                    to: Point::from_array(to),
                    centre: Point::from_array(centre_machine),
                    plane: self.plane,
                    clockwise: code == 20,
                    extra_turns,
                    feed_mm_per_min,
                }
            }
        };
        kinds.push(kind);
        self.position = to;
        Ok(())
    }

    /// G38.2-G38.5 (`code` 382-385): a straight probe move, interpreted as LinuxCNC's
    /// batch interpreter runs it ([`BlockKind::Probe`]): the interpretation goes on from
    /// the end backed off by [`PROBE_BACKOFF_MM`] towards the start in X Y Z (A B C at
    /// the end, U V W where they were, as rs274's canon leaves them), #5061-#5066 hold the
    /// end in the program frame and units, #5067-#5069 and #5070 (tripped) are 0.
    fn probe(&mut self, w: &Words, code: Code, column: usize) -> Result<BlockKind, LineError> {
        let name = g_name(code);
        // Errors of the mode at the G38.x word (at the first axis word where it is modal).
        let word = w.group(Group::Motion).map_or(column, |(_, c)| c);
        if self.comp != CompSide::Off {
            return Err(LineError::new(word, format!("{name} with cutter radius compensation on (G40 first)")));
        }
        if self.inverse_time || self.per_rev {
            let mode = if self.inverse_time { "inverse-time feed (G93)" } else { "feed per revolution (G95)" };
            return Err(LineError::new(word, format!("{name} in {mode}: a probe move takes units per minute (G94)")));
        }
        let feed_mm_per_min = match self.feed_mm_per_min {
            Some(f) if f > 0.0 => f,
            _ => return Err(LineError::new(column_of(w, column), format!("{name} with no feed rate"))),
        };
        let from = self.position;
        let from_program = self.to_program(from);
        let to_program = self.target(w, from_program)?;
        let to = self.to_machine(to_program);
        if to.iter().any(|v| v.abs() > MAX_POSITION) {
            return Err(LineError::new(column, "position out of range"));
        }
        // G38.3 and G38.5 report a failure in #5070 instead of stopping; G38.2 and G38.4
        // need a move (rs274: `Start point too close to probe point`).
        let must_change = matches!(code, 382 | 384);
        if must_change && to_program == from_program {
            return Err(LineError::new(word, format!("{name} to the point where the probe is: nothing to probe")));
        }
        let delta = [from[0] - to[0], from[1] - to[1], from[2] - to[2]];
        let distance = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
        let mut resume = to;
        if distance != 0.0 {
            for axis in 0..3 {
                resume[axis] = to[axis] + PROBE_BACKOFF_MM * delta[axis] / distance;
            }
        }
        resume[6..].copy_from_slice(&from[6..]);
        for (axis, &value) in to_program.iter().enumerate().take(6) {
            self.set_parameter(PARAM_PROBE + axis, self.user_units(axis, value));
        }
        for n in PARAM_PROBE + 6..=PARAM_PROBE_TRIPPED {
            self.set_parameter(n, 0.0);
        }
        self.position = resume;
        Ok(BlockKind::Probe {
            to: Point::from_array(to),
            feed_mm_per_min,
            on_contact: code <= 383,
            must_change,
            resume: Point::from_array(resume),
        })
    }

    /// M66 (wait on an input, #5399 its value), M67/M68 (an analog output); `code` in
    /// tenths. Channels are 0 to 63, as for M62-M65.
    fn input_output(&mut self, w: &Words, code: Code, column: usize) -> Result<BlockKind, LineError> {
        let name = format!("M{}", code / 10);
        let channel = |letter: char| match w.param(letter) {
            None => Ok(None),
            Some((value, c)) => as_u32(value)
                .filter(|&i| i < 64)
                .map(Some)
                .ok_or_else(|| LineError::new(c, format!("{letter} word of {name} must be an integer 0 to 63"))),
        };
        if self.comp != CompSide::Off {
            return Err(LineError::new(column, format!("{name} with cutter radius compensation on (G40 first)")));
        }
        if code != 660 {
            let index =
                channel('E')?.ok_or_else(|| LineError::new(column, format!("{name} with no E (the analog output)")))?;
            let (value, _) =
                w.param('Q').ok_or_else(|| LineError::new(column, format!("{name} with no Q (the value)")))?;
            return Ok(BlockKind::AnalogOutput { index, value, synchronised: code == 670 });
        }
        let input = match (channel('P')?, channel('E')?) {
            (Some(_), Some(_)) => {
                let at = w.param('P').map_or(column, |(_, c)| c).max(w.param('E').map_or(column, |(_, c)| c));
                return Err(LineError::new(at, "M66 with both P (a digital input) and E (an analog one)"));
            }
            (Some(p), None) => Input::Digital(p),
            (None, Some(e)) => Input::Analog(e),
            (None, None) => return Err(LineError::new(column, "M66 with no P (a digital input) or E (an analog one)")),
        };
        let (mode, l_column) = match w.param('L') {
            None => (WaitMode::Immediate, column),
            Some((l, c)) => {
                let mode = match as_u32(l) {
                    Some(0) => WaitMode::Immediate,
                    Some(1) => WaitMode::Rise,
                    Some(2) => WaitMode::Fall,
                    Some(3) => WaitMode::High,
                    Some(4) => WaitMode::Low,
                    _ => {
                        return Err(LineError::new(
                            c,
                            "M66 L must be 0 (read at once), 1 (rise), 2 (fall), 3 (high) or 4 (low)",
                        ))
                    }
                };
                (mode, c)
            }
        };
        if mode != WaitMode::Immediate && matches!(input, Input::Analog(_)) {
            return Err(LineError::new(l_column, "M66 reads an analog input (E) at once only: L0"));
        }
        let timeout_s = match (mode, w.param('Q')) {
            (WaitMode::Immediate, _) => 0.0,
            (_, Some((q, _))) if q > 0.0 => q,
            (_, q) => {
                return Err(LineError::new(
                    q.map_or(column, |(_, c)| c),
                    "M66 waiting (L1-L4) needs a timeout Q above 0 seconds",
                ))
            }
        };
        // rs274 reads no input: a digital read leaves #5399 as 0 or 1, an analog one as
        // it was (finestep interprets the program before it runs, likewise).
        if let Input::Digital(_) = input {
            let value = f64::from(u8::from(self.parameter(PARAM_INPUT) != 0.0));
            self.set_parameter(PARAM_INPUT, value);
        }
        Ok(BlockKind::WaitInput { input, mode, timeout_s })
    }

    /// The F of a feed move's block in G93 (1/min): required on every such block, as in
    /// LinuxCNC.
    fn inverse_feed(&self, w: &Words, code: Code, column: usize) -> Result<f64, LineError> {
        match self.inverse_f {
            Some(f) => Ok(f),
            None => Err(LineError::new(
                column_of(w, column),
                format!("{} in inverse-time feed (G93) without F on its block", g_name(code)),
            )),
        }
    }

    /// G5.1: a quadratic B-spline in G17 from the current point to X Y, its control point
    /// at I J from the start; given as the equivalent NURBS of order 3. G5: a cubic
    /// B-spline (Bezier) from the current point to X Y, its first control point at I J
    /// from the start (without I J: the last G5's P Q negated, so that the curve goes on
    /// tangent to it), its second at P Q from the end; the NURBS of order 4. Both as
    /// LinuxCNC's `convert_spline`.
    fn spline(&mut self, w: &Words, code: Code, column: usize) -> Result<BlockKind, LineError> {
        let name = g_name(code);
        if self.plane != Plane::Xy {
            return Err(LineError::new(column, format!("{name} is for the G17 (XY) plane")));
        }
        if self.comp != CompSide::Off {
            return Err(LineError::new(column, format!("{name} with cutter compensation on")));
        }
        for letter in ['Z', 'A', 'B', 'C', 'U', 'V', 'W'] {
            if let Some((_, c)) = w.param(letter) {
                return Err(LineError::new(c, format!("axis {letter} in a {name} spline: only X and Y move")));
            }
        }
        let feed_mm_per_min = match self.feed_now() {
            Some(f) if f > 0.0 => f,
            _ => return Err(LineError::new(column_of(w, column), format!("{name} with no feed rate"))),
        };
        let from = self.to_program(self.position);
        let end = self.target(w, from)?;
        let offset = |base: Axes, (dx, dy): (f64, f64)| {
            let mut p = base;
            p[0] += self.length_mm(dx);
            p[1] += self.length_mm(dy);
            p
        };
        let mut program_points = vec![from];
        match (w.param('I'), w.param('J')) {
            (Some((i, _)), Some((j, _))) => program_points.push(offset(from, (i, j))),
            (Some((_, c)), None) | (None, Some((_, c))) if code == 50 => {
                return Err(LineError::new(c, "G5 needs both I and J, or neither"));
            }
            _ if code == 51 => return Err(LineError::new(column_of(w, column), "G5.1 needs both I and J")),
            _ => program_points.push(offset(from, (self.g5_next_ij[0], self.g5_next_ij[1]))),
        }
        if code == 50 {
            let (Some((p, _)), Some((q, _))) = (w.param('P'), w.param('Q')) else {
                return Err(LineError::new(column_of(w, column), "G5 needs both P and Q"));
            };
            program_points.push(offset(end, (p, q)));
            self.g5_next_ij = [-p, -q];
        }
        program_points.push(end);
        let to = self.to_machine(end);
        let control_points: Vec<NurbsPoint> = program_points
            .iter()
            .map(|&p| {
                let m = self.to_machine(p);
                NurbsPoint { x_mm: m[0], y_mm: m[1], weight: 1.0 }
            })
            .collect();
        if control_points.iter().any(|p| !(p.x_mm.abs() <= MAX_POSITION && p.y_mm.abs() <= MAX_POSITION))
            || to.iter().any(|v| v.is_nan() || v.abs() > MAX_POSITION)
        {
            return Err(LineError::new(column, "position out of range"));
        }
        self.position = to;
        let order = control_points.len();
        Ok(BlockKind::Nurbs {
            to: Point::from_array(to),
            knots: nurbs_knots(order, order),
            order: order as u32,
            control_points,
            feed_mm_per_min,
        })
    }

    /// G28/G30: through the axis words' point if any, then to the stored position (only
    /// the axes named, or all).
    fn home_move(
        &mut self,
        w: &Words,
        which: usize,
        through: bool,
        kinds: &mut Vec<BlockKind>,
    ) -> Result<(), LineError> {
        if through {
            let mid = self.to_machine(self.target(w, self.to_program(self.position))?);
            kinds.push(BlockKind::Rapid { to: Point::from_array(mid) });
            self.position = mid;
        }
        let mut end = self.to_program(self.position);
        let (o, g92) = (self.active_g5x, self.g92_now());
        for (axis, &letter) in AXES.iter().enumerate() {
            if !through || w.param(letter).is_some() {
                end[axis] = self.home[which][axis] - o[axis] - g92[axis];
            }
        }
        let end = self.to_machine(end);
        kinds.push(BlockKind::Rapid { to: Point::from_array(end) });
        self.position = end;
        Ok(())
    }

    /// G10 L1 (tool table), L2 (coordinate system offsets and R rotation), L20 (offsets
    /// that make the current position the given one).
    fn g10(&mut self, w: &Words, column: usize) -> Result<(), LineError> {
        let (l, l_column) = w.param('L').ok_or_else(|| LineError::new(column, "G10 with no L word"))?;
        let (p, p_column) = w.param('P').ok_or_else(|| LineError::new(column, "G10 with no P word"))?;
        let scale = if self.inches { MM_PER_INCH } else { 1.0 };
        let value = move |axis: usize, v: f64| if rotary(axis) { v } else { v * scale };
        match as_u32(l) {
            Some(1) => {
                let tool = as_u32(p).ok_or_else(|| LineError::new(p_column, "G10 L1 P must be a tool number"))?;
                let mut entry = self.tools.get(&tool).copied().unwrap_or_default();
                for (axis, &letter) in AXES.iter().enumerate() {
                    if let Some((v, _)) = w.param(letter) {
                        entry[axis] = value(axis, v);
                    }
                }
                self.tools.insert(tool, entry);
            }
            // L10: tool P's length such that the current position, in the coordinate
            // system and G92 offsets in force, reads the given values with it; L11: such
            // that it would read them in G59.3 without G92 (LinuxCNC's definitions).
            Some(k @ (10 | 11)) => {
                let tool =
                    as_u32(p).ok_or_else(|| LineError::new(p_column, format!("G10 L{k} P must be a tool number")))?;
                if tool == 0 {
                    return Err(LineError::new(p_column, format!("G10 L{k} P0: tool 0 is no tool")));
                }
                if self.active_rotation_deg != 0.0 && (w.param('X').is_some() || w.param('Y').is_some()) {
                    return Err(LineError::new(
                        column,
                        format!("unsupported: G10 L{k} X/Y under an XY rotation ({})", unsupported::G10_TOOL_ROTATION),
                    ));
                }
                let (origin, g92) =
                    if k == 10 { (self.active_g5x, self.g92_now()) } else { (self.g5x[8], [0.0; N_AXES]) };
                let mut entry = self.tools.get(&tool).copied().unwrap_or_default();
                for (axis, &letter) in AXES.iter().enumerate() {
                    if let Some((v, _)) = w.param(letter) {
                        entry[axis] = self.position[axis] - origin[axis] - g92[axis] - value(axis, v);
                    }
                }
                self.tools.insert(tool, entry);
            }
            Some(k @ (2 | 20)) => {
                let system = match as_u32(p) {
                    Some(0) => self.system,
                    Some(n @ 1..=9) => n as usize - 1,
                    _ => return Err(LineError::new(p_column, "G10 P must be 0 to 9 (0: the system in use)")),
                };
                let (g92, here) = (self.g92_now(), self.position);
                for (axis, &letter) in AXES.iter().enumerate() {
                    if let Some((v, _)) = w.param(letter) {
                        self.g5x[system][axis] = if k == 2 {
                            value(axis, v)
                        } else {
                            here[axis] - self.tool_offset[axis] - g92[axis] - value(axis, v)
                        };
                    }
                }
                if let Some((r, r_column)) = w.param('R') {
                    // LinuxCNC 2.9 refuses it too (its documentation lists R for L20).
                    if k == 20 {
                        return Err(LineError::new(r_column, "R not allowed in G10 L20"));
                    }
                    self.rotation_deg[system] = r;
                }
                if system == self.system {
                    self.select_system(system);
                }
            }
            _ => return Err(LineError::new(l_column, format!("unsupported: G10 L{l} ({})", unsupported::G10_L))),
        }
        Ok(())
    }

    /// G73 G81 G82 G83 G85 G89 in G17, with G98/G99 and L repeats, as LinuxCNC runs them.
    fn canned_cycle(
        &mut self,
        w: &Words,
        code: Code,
        column: usize,
        kinds: &mut Vec<BlockKind>,
    ) -> Result<(), LineError> {
        let name = g_name(code);
        // The drilling axis is the plane's normal (G17 Z, G18 Y, G19 X), its word the
        // depth; the other two place the hole, as rs274 runs them.
        let (drill, depth_letter, place) = match self.plane {
            Plane::Xy => (2, 'Z', [(0, 'X'), (1, 'Y')]),
            Plane::Zx => (1, 'Y', [(2, 'Z'), (0, 'X')]),
            Plane::Yz => (0, 'X', [(1, 'Y'), (2, 'Z')]),
        };
        if self.plane != Plane::Xy && code == 870 {
            return Err(LineError::new(
                column,
                format!("unsupported: {name} in G18/G19 ({})", unsupported::CYCLE_PLANE),
            ));
        }
        if self.comp != CompSide::Off {
            return Err(LineError::new(column, format!("{name} with cutter compensation on")));
        }
        if matches!(code, 860 | 870) && self.rotation == SpindleRotation::Off {
            return Err(LineError::new(column, format!("{name} with the spindle not turning (M3 or M4 first)")));
        }
        if self.inverse_time {
            // rs274 refuses it too (its feed rate is zero there).
            return Err(LineError::new(column, format!("{name} in inverse-time feed (G93): G94 first")));
        }
        let feed = match self.feed_now() {
            Some(f) if f > 0.0 => f,
            _ => return Err(LineError::new(column, format!("{name} with no feed rate"))),
        };
        if let Some((r, _)) = w.param('R') {
            self.cycle.r = Some(self.length_mm(r));
        }
        if let Some((z, _)) = w.param(depth_letter) {
            self.cycle.z = Some(self.length_mm(z));
        }
        if let Some((p, c)) = w.param('P') {
            if p < 0.0 {
                return Err(LineError::new(c, "negative dwell time"));
            }
            self.cycle.p = Some(p);
        }
        if let Some((q, c)) = w.param('Q') {
            if q <= 0.0 {
                return Err(LineError::new(c, format!("Q for {name} must be positive")));
            }
            self.cycle.q = Some(self.length_mm(q));
        }
        // G87's I J (also what a G5 without I J takes next, rs274's `cycle_i`, `cycle_j`)
        // and K.
        if code == 870 {
            if let Some((i, _)) = w.param('I') {
                self.cycle.i = Some(i);
                self.g5_next_ij[0] = i;
            }
            if let Some((j, _)) = w.param('J') {
                self.cycle.j = Some(j);
                self.g5_next_ij[1] = j;
            }
            if let Some((k, _)) = w.param('K') {
                self.cycle.k = Some(self.length_mm(k));
            }
        }
        let r_word = self.cycle.r.ok_or_else(|| LineError::new(column, format!("{name} with no R (retract plane)")))?;
        let z_word =
            self.cycle.z.ok_or_else(|| LineError::new(column, format!("{name} with no {depth_letter} (depth)")))?;
        let repeats = match w.param('L') {
            None => 1,
            Some((l, c)) => as_u32(l)
                .filter(|&l| l <= 10_000)
                .ok_or_else(|| LineError::new(c, "L for a canned cycle must be an integer from 0 to 10000"))?,
        };
        let mut cur = self.to_program(self.position);
        let start_z = cur[drill];
        let old_z = *self.cycle.old_z.get_or_insert(start_z);
        // In G91, R is relative to the Z the cycle began at (as rs274 does), Z to R.
        let (r, z) = if self.incremental { (old_z + r_word, old_z + r_word + z_word) } else { (r_word, z_word) };
        if z > r {
            return Err(LineError::new(column, format!("{name} with {depth_letter} above R")));
        }
        let dwell = match code {
            820 | 860 | 890 => {
                Some(self.cycle.p.ok_or_else(|| LineError::new(column, format!("{name} with no P (dwell)")))?)
            }
            _ => None,
        };
        let q = match code {
            730 | 830 => Some(self.cycle.q.ok_or_else(|| LineError::new(column, format!("{name} with no Q (peck)")))?),
            _ => None,
        };
        let back_bore = match code {
            870 => {
                let missing = |l: char| LineError::new(column, format!("G87 with no {l} (back boring)"));
                let (i, j) = (self.cycle.i.ok_or_else(|| missing('I'))?, self.cycle.j.ok_or_else(|| missing('J'))?);
                let k = self.cycle.k.ok_or_else(|| missing('K'))?;
                // In G91, K is relative to the bottom Z.
                Some((self.length_mm(i), self.length_mm(j), if self.incremental { z + k } else { k }))
            }
            _ => None,
        };
        /// LinuxCNC's rapid clearance above the last peck (0.010 in).
        const PECK_CLEARANCE_MM: f64 = 0.254;
        let restore = self.path;
        kinds.push(BlockKind::PathControl(PathControl::ExactPath));
        let mut out: Vec<BlockKind> = Vec::new();
        let rapid = |state: &Self, out: &mut Vec<BlockKind>, p: Axes| {
            out.push(BlockKind::Rapid { to: Point::from_array(state.to_machine(p)) })
        };
        let cut = |state: &Self, out: &mut Vec<BlockKind>, p: Axes| {
            out.push(BlockKind::Linear { to: Point::from_array(state.to_machine(p)), feed_mm_per_min: feed })
        };
        // As rs274 does: up to R first when the cycle began below it; across at the
        // clearance height or higher.
        if old_z < r && cur[drill] < r {
            cur[drill] = r;
            rapid(self, &mut out, cur);
        }
        let clear = if self.retract_to_r { r } else { old_z.max(r) };
        for _ in 0..repeats {
            if self.plane == Plane::Xy {
                self.apply_xy(w, &mut cur);
            } else {
                for (axis, letter) in place {
                    if let Some((v, _)) = w.param(letter) {
                        let v = self.length_mm(v);
                        cur[axis] = if self.incremental { cur[axis] + v } else { v };
                    }
                }
            }
            for axis in 3..N_AXES {
                if let Some((v, _)) = w.param(AXES[axis]) {
                    let v = if rotary(axis) { v } else { self.length_mm(v) };
                    cur[axis] = if self.incremental { cur[axis] + v } else { v };
                }
            }
            if cur.iter().any(|v| v.is_nan() || v.abs() > MAX_POSITION) {
                return Err(LineError::new(column, "position out of range"));
            }
            cur[drill] = cur[drill].max(clear);
            rapid(self, &mut out, cur);
            let at = |zz: f64| {
                let mut p = cur;
                p[drill] = zz;
                p
            };
            rapid(self, &mut out, at(r));
            if let Some((i, j, k)) = back_bore {
                // G87 as rs274 runs it: across to the offset at R, spindle stopped and
                // oriented (LinuxCNC passes its direction code, 2 clockwise, 3
                // counter-clockwise), down through the hole, back to the centre, spindle
                // on, cut up to K and back down to Z, stopped and oriented again, out at
                // the offset, up to the clearance height, back over the centre, spindle on.
                let off = |zz: f64| {
                    let mut p = cur;
                    (p[0], p[1], p[2]) = (cur[0] + i, cur[1] + j, zz);
                    p
                };
                if off(z).iter().any(|v| v.is_nan() || v.abs() > MAX_POSITION) {
                    return Err(LineError::new(column, "position out of range"));
                }
                let rotation = self.rotation;
                let orient = BlockKind::SpindleOrient {
                    angle_deg: 0.0,
                    direction: if rotation == SpindleRotation::Clockwise { 2 } else { 3 },
                    timeout_s: None,
                };
                let stop = self.spindle_block(SpindleRotation::Off);
                let turn = self.spindle_block(rotation);
                rapid(self, &mut out, off(r));
                out.extend([stop.clone(), orient.clone()]);
                rapid(self, &mut out, off(z));
                rapid(self, &mut out, at(z));
                out.push(turn.clone());
                cut(self, &mut out, at(k));
                cut(self, &mut out, at(z));
                out.extend([stop, orient]);
                rapid(self, &mut out, off(z));
                rapid(self, &mut out, off(clear));
                rapid(self, &mut out, at(clear));
                out.push(turn.clone());
                cur[drill] = clear;
                if out.len() > 1_000_000 {
                    return Err(LineError::new(column, format!("{name} makes more than 10^6 moves")));
                }
                continue;
            }
            match (code, q) {
                (830, Some(q)) | (730, Some(q)) => {
                    let mut depth = r - q;
                    while depth > z {
                        cut(self, &mut out, at(depth));
                        if code == 830 {
                            rapid(self, &mut out, at(r));
                        }
                        rapid(self, &mut out, at(depth + PECK_CLEARANCE_MM));
                        depth -= q;
                    }
                    cut(self, &mut out, at(z));
                }
                _ => cut(self, &mut out, at(z)),
            }
            if let Some(seconds) = dwell {
                out.push(BlockKind::Dwell { seconds });
            }
            if matches!(code, 850 | 890) {
                cut(self, &mut out, at(r));
            }
            // G86: the spindle stops at the bottom, the tool leaves at traverse and the
            // spindle starts again as it turned (rs274's order).
            if code == 860 {
                out.push(self.spindle_block(SpindleRotation::Off));
            }
            rapid(self, &mut out, at(clear));
            if code == 860 {
                out.push(self.spindle_block(self.rotation));
            }
            cur[drill] = clear;
            if out.len() > 1_000_000 {
                return Err(LineError::new(column, format!("{name} makes more than 10^6 moves")));
            }
        }
        kinds.append(&mut out);
        kinds.push(BlockKind::PathControl(restore));
        let to = self.to_machine(cur);
        if to.iter().any(|v| v.abs() > MAX_POSITION) {
            return Err(LineError::new(column, "position out of range"));
        }
        self.position = to;
        Ok(())
    }
}

/// The weight `P` of a NURBS control point: 1 when left out, else positive.
/// M19: the orientation event, if R or P asks for one (rs274 sends none for a bare
/// M19, which only stops the spindle).
fn spindle_orient(w: &Words) -> Result<Option<BlockKind>, LineError> {
    let angle_deg = match w.param('R') {
        Some((r, c)) if !(0.0..=360.0).contains(&r) => {
            return Err(LineError::new(c, "R value must be within 0..360 with M19"));
        }
        Some((r, _)) => r,
        None => 0.0,
    };
    let direction = match w.param('P') {
        Some((p, c)) => {
            as_u32(p).filter(|&d| d <= 2).ok_or_else(|| LineError::new(c, "P value must be 0, 1 or 2 with M19"))?
        }
        None => 0,
    };
    let timeout_s = match w.param('Q') {
        Some((q, c)) if q <= 0.0 => return Err(LineError::new(c, "Q value must be positive with M19")),
        q => q.map(|(q, _)| q),
    };
    if w.param('R').is_none() && w.param('P').is_none() {
        return Ok(None);
    }
    Ok(Some(BlockKind::SpindleOrient { angle_deg, direction, timeout_s }))
}

fn nurbs_weight(w: &Words) -> Result<f64, LineError> {
    match w.param('P') {
        None => Ok(1.0),
        Some((p, _)) if p > 0.0 => Ok(p),
        Some((_, c)) => Err(LineError::new(c, "NURBS weight P must be positive")),
    }
}

/// The column of a move's motion word: its G word if the block has one, else `axis`.
fn column_of(w: &Words, axis: usize) -> usize {
    w.group(Group::Motion).map_or(axis, |(_, c)| c)
}

/// Whether `path` is a file LinuxCNC would run as a user M-code: a regular file (on Unix,
/// with an execute bit set).
fn is_executable(path: &std::path::Path) -> bool {
    let Ok(meta) = std::fs::metadata(path) else { return false };
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        meta.is_file() && meta.permissions().mode() & 0o111 != 0
    }
    #[cfg(not(unix))]
    {
        meta.is_file()
    }
}
