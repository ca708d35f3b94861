//! The modal interpreter: one block of words at a time, against the modal state, to
//! canonical blocks with positions resolved to absolute millimetres.

use crate::error::LineError;
use crate::lexer::Word;
use crate::{nurbs_knots, BlockKind, CompSide, NurbsPoint, PathControl, Plane, Point, SpindleRotation};

/// Millimetres per inch.
const MM_PER_INCH: f64 = 25.4;
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
    position: [f64; 4],
    motion: Option<Code>,
    plane: Plane,
    inches: bool,
    incremental: bool,
    arc_incremental: bool,
    comp: CompSide,
    feed_mm_per_min: Option<f64>,
    rotation: SpindleRotation,
    rpm: f64,
    mist: bool,
    flood: bool,
    tool: u32,
    tool_in_spindle: u32,
    nurbs: Option<OpenNurbs>,
    /// Numbered parameters #0-#5601 (#0 unused).
    params: Vec<f64>,
    /// The 1-based source line being executed (set by the caller).
    pub(crate) line: usize,
}

impl Default for State {
    /// G17 G21 G90 G91.1 G40 G64, no motion mode, at the origin, no feed, spindle off
    /// at 0 rpm, coolant off, tool 0.
    fn default() -> Self {
        State {
            position: [0.0; 4],
            motion: None,
            plane: Plane::Xy,
            inches: false,
            incremental: false,
            arc_incremental: true,
            comp: CompSide::Off,
            feed_mm_per_min: None,
            rotation: SpindleRotation::Off,
            rpm: 0.0,
            mist: false,
            flood: false,
            tool: 0,
            tool_in_spindle: 0,
            nurbs: None,
            params: default_parameters(),
            line: 0,
        }
    }
}

/// #5220, the coordinate system in use (1 = G54).
const PARAM_COORD_SYSTEM: usize = 5220;
/// #5400, the tool in the spindle.
const PARAM_TOOL: usize = 5400;
/// #5420-#5425: the current position X Y Z A B C in program units.
const PARAM_POSITION: usize = 5420;

fn default_parameters() -> Vec<f64> {
    let mut params = vec![0.0; crate::expr::MAX_PARAMETER + 1];
    params[PARAM_COORD_SYSTEM] = 1.0;
    params
}

/// Modal groups of the supported codes (LinuxCNC's numbering in comments).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Group {
    NonModal,    // G group 0: G4
    Motion,      // G group 1: G0 G1 G2 G3
    Plane,       // G group 2: G17 G18 G19
    Distance,    // G group 3: G90 G91
    ArcDistance, // G group 4: G90.1 G91.1
    Units,       // G group 6: G20 G21
    Comp,        // G group 7: G40 G41 G42
    Path,        // G group 13: G61 G64
    Stop,        // M group 4: M0 M2 M30
    ToolChange,  // M group 6: M6
    Spindle,     // M group 7: M3 M4 M5
    Coolant,     // M group 8: M7 M8 M9
}

const GROUPS: usize = 12;

fn g_group(code: Code) -> Option<Group> {
    Some(match code {
        40 => Group::NonModal,
        0 | 10 | 20 | 30 | G5_2 | G5_3 => Group::Motion,
        170 | 180 | 190 => Group::Plane,
        900 | 910 => Group::Distance,
        901 | 911 => Group::ArcDistance,
        200 | 210 => Group::Units,
        400 | 410 | 420 => Group::Comp,
        610 | 640 => Group::Path,
        _ => return None,
    })
}

fn m_group(code: u32) -> Option<Group> {
    Some(match code {
        0 | 2 | 30 => Group::Stop,
        6 => Group::ToolChange,
        3..=5 => Group::Spindle,
        7..=9 => Group::Coolant,
        _ => return None,
    })
}

/// `G2`, `G90.1`: a code in tenths as written.
fn g_name(code: Code) -> String {
    match (code / 10, code % 10) {
        (whole, 0) => format!("G{whole}"),
        (whole, tenth) => format!("G{whole}.{tenth}"),
    }
}

/// A non-negative integral value as u32.
fn as_u32(value: f64) -> Option<u32> {
    (value >= 0.0 && value.fract() == 0.0 && value <= f64::from(u32::MAX)).then_some(value as u32)
}

/// The parameter letters a block may carry once each (besides G, M and N).
const PARAMS: &str = "ADFIJKLPRSTXYZ";
const AXES: [char; 4] = ['X', 'Y', 'Z', 'A'];

/// The words of one block, sorted by meaning.
#[derive(Default)]
struct Words {
    n: Option<u32>,
    /// Per group: the code and its column. The coolant group may hold M7 and M8.
    groups: [Option<(Code, usize)>; GROUPS],
    mist_and_flood: Option<usize>,
    params: [Option<(f64, usize)>; 26],
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

fn letter_index(letter: char) -> usize {
    (letter as usize).wrapping_sub('A' as usize)
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
                group.ok_or_else(|| LineError::new(column, format!("unsupported G-code G{value}")))?
            }
            'M' => {
                let group = as_u32(value).and_then(|c| m_group(c).map(|g| (c * 10, g)));
                group.ok_or_else(|| LineError::new(column, format!("unsupported M-code M{value}")))?
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
}

impl State {
    /// `#n` (1 <= n <= 5601), with the predefined ones computed from the state.
    pub(crate) fn parameter(&self, n: usize) -> f64 {
        match n {
            PARAM_TOOL => f64::from(self.tool_in_spindle),
            PARAM_POSITION..=5423 => self.program_position(n - PARAM_POSITION),
            5424..=5428 => 0.0,
            _ => self.params.get(n).copied().unwrap_or(0.0),
        }
    }

    /// Sets `#n`; the predefined read-only ones keep their computed values.
    pub(crate) fn set_parameter(&mut self, n: usize, value: f64) {
        if let Some(p) = self.params.get_mut(n) {
            *p = value;
        }
    }

    /// The current position of axis `axis` (X Y Z A) in program units.
    fn program_position(&self, axis: usize) -> f64 {
        let v = self.position[axis];
        if axis < 3 && self.inches {
            v / MM_PER_INCH
        } else {
            v
        }
    }

    /// LinuxCNC's predefined named parameters (`#<_x>`, `#<_metric>`, ...), read-only.
    pub(crate) fn predefined(&self, name: &str) -> Option<f64> {
        let flag = |b: bool| f64::from(u8::from(b));
        Some(match name {
            "_vmajor" => 2.0,
            "_vminor" => 9.0,
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
            "_inverse_time" => 0.0,
            "_units_per_minute" => 1.0,
            "_units_per_rev" => 0.0,
            "_coord_system" => 540.0,
            "_ijk_absolute_mode" => flag(!self.arc_incremental),
            "_lathe_diameter_mode" => 0.0,
            "_lathe_radius_mode" => 1.0,
            "_spindle_on" => flag(self.rotation != SpindleRotation::Off),
            "_spindle_cw" => flag(self.rotation == SpindleRotation::Clockwise),
            "_mist" => flag(self.mist),
            "_flood" => flag(self.flood),
            "_speed_override" | "_feed_override" => 1.0,
            "_adaptive_feed" | "_feed_hold" => 0.0,
            "_feed" => self.feed_mm_per_min.map_or(0.0, |f| if self.inches { f / MM_PER_INCH } else { f }),
            "_rpm" => self.rpm,
            "_x" | "_abs_x" => self.program_position(0),
            "_y" | "_abs_y" => self.program_position(1),
            "_z" | "_abs_z" => self.program_position(2),
            "_a" | "_abs_a" => self.program_position(3),
            "_b" | "_c" | "_u" | "_v" | "_w" | "_abs_b" | "_abs_c" | "_abs_u" | "_abs_v" | "_abs_w" => 0.0,
            "_current_tool" => f64::from(self.tool_in_spindle),
            "_current_pocket" => f64::from(self.tool_in_spindle),
            "_selected_tool" => f64::from(self.tool),
            "_selected_pocket" => f64::from(self.tool),
            "_task" => 0.0,
            _ => return None,
        })
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
        let w = sort_words(words)?;
        if self.nurbs.is_some() && !w.has(Group::Motion, G5_3) {
            return self.nurbs_point_line(words, &w);
        }
        let mut kinds = Vec::new();

        // What will move, to check that every parameter word has a user.
        let motion = w.group(Group::Motion).map(|(c, _)| c).or(self.motion);
        let first_axis = AXES.iter().filter_map(|&l| w.param(l)).map(|(_, c)| c).min();
        let motion_column = w.group(Group::Motion).map(|(_, c)| c).or(first_axis);
        let arc_mode = matches!(motion, Some(20 | 30));
        let arc_move = arc_mode && first_axis.is_some();
        for letter in ['I', 'J', 'K', 'R'] {
            if let Some((_, column)) = w.param(letter) {
                if arc_mode && !arc_move {
                    let name = g_name(motion.unwrap_or(20));
                    return Err(LineError::new(motion_column.unwrap_or(column), format!("{name} with no axis words")));
                }
                if !arc_move {
                    return Err(LineError::new(column, format!("{letter} word with no G2 or G3 to use it")));
                }
            }
        }
        if let Some((_, column)) = w.param('L') {
            if !w.has(Group::Motion, G5_2) {
                return Err(LineError::new(column, "L word with no G5.2 to use it"));
            }
        }
        if let Some((_, column)) = w.param('P') {
            let users =
                [w.group(Group::NonModal).is_some(), w.has(Group::Path, 640), arc_move, w.has(Group::Motion, G5_2)];
            match users.iter().filter(|&&u| u).count() {
                0 => return Err(LineError::new(column, "P word with no G4, G64, G2, G3 or G5.2 to use it")),
                1 => {}
                _ => return Err(LineError::new(column, "P word is used by more than one code")),
            }
        }
        if let Some((_, column)) = w.param('D') {
            if !(w.has(Group::Comp, 410) || w.has(Group::Comp, 420)) {
                return Err(LineError::new(column, "D word with no G41 or G42 to use it"));
            }
        }
        if let (Some(column), None) = (first_axis, motion) {
            return Err(LineError::new(column, "axis word with no motion mode (G0, G1, G2 or G3) to use it"));
        }

        // Feed, speed, tool selection.
        if let Some((f, column)) = w.param('F') {
            if f < 0.0 {
                return Err(LineError::new(column, "negative feed rate"));
            }
            self.feed_mm_per_min = Some(self.length_mm(f));
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
        if w.group(Group::ToolChange).is_some() {
            // LinuxCNC stops the spindle for a tool change.
            self.rotation = SpindleRotation::Off;
            kinds.push(BlockKind::Spindle { rotation: self.rotation, rpm: self.rpm });
            kinds.push(BlockKind::ToolChange { tool: self.tool });
            self.tool_in_spindle = self.tool;
        }

        // Spindle and coolant.
        if let Some((code, _)) = w.group(Group::Spindle) {
            self.rotation = match code {
                30 => SpindleRotation::Clockwise,
                40 => SpindleRotation::CounterClockwise,
                _ => SpindleRotation::Off,
            };
        }
        if w.group(Group::Spindle).is_some() || w.param('S').is_some() {
            kinds.push(BlockKind::Spindle { rotation: self.rotation, rpm: self.rpm });
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

        // Dwell.
        if let Some((_, column)) = w.group(Group::NonModal) {
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
            // Compensation offsets in XY; another plane would cut an uncompensated path.
            if plane != Plane::Xy && self.comp != CompSide::Off {
                return Err(LineError::new(column, "plane change while cutter compensation is on (G40 first)"));
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
            let side = match code {
                410 => CompSide::Left,
                420 => CompSide::Right,
                _ => CompSide::Off,
            };
            if side != CompSide::Off && self.comp != CompSide::Off {
                return Err(LineError::new(column, "cutter compensation is already on (G40 first)"));
            }
            if side != CompSide::Off && self.plane != Plane::Xy {
                return Err(LineError::new(column, "cutter compensation is supported in G17 (XY) only"));
            }
            let tool = match w.param('D') {
                Some((d, d_column)) => {
                    Some(as_u32(d).ok_or_else(|| LineError::new(d_column, "D word must be a non-negative integer"))?)
                }
                None => None,
            };
            self.comp = side;
            kinds.push(BlockKind::CutterComp { side, tool });
        }

        // Path control.
        if let Some((code, _)) = w.group(Group::Path) {
            let mode = if code == 610 {
                PathControl::ExactPath
            } else {
                let tolerance_mm = match w.param('P') {
                    Some((p, p_column)) if p < 0.0 => return Err(LineError::new(p_column, "negative path tolerance")),
                    Some((p, _)) => Some(self.length_mm(p)),
                    None => None,
                };
                PathControl::Blend { tolerance_mm }
            };
            kinds.push(BlockKind::PathControl(mode));
        }

        // Motion.
        match w.group(Group::Motion) {
            Some((G5_2, column)) => {
                self.open_nurbs_block(&w, column)?;
                self.motion = None;
            }
            Some((G5_3, column)) => {
                kinds.push(self.close_nurbs_block(&w, column)?);
                self.motion = None;
            }
            Some((code, _)) => self.motion = Some(code),
            None => {}
        }
        if let (Some(code), Some(column), None) = (self.motion, first_axis, &self.nurbs) {
            let to = self.target(&w)?;
            let feed = || match self.feed_mm_per_min {
                Some(f) if f > 0.0 => Ok(f),
                _ => Err(LineError::new(column_of(&w, column), format!("{} with no feed rate", g_name(code)))),
            };
            let kind = match code {
                0 => BlockKind::Rapid { to: Point::from_array(to) },
                10 => BlockKind::Linear { to: Point::from_array(to), feed_mm_per_min: feed()? },
                _ => {
                    let feed_mm_per_min = feed()?;
                    let clockwise = code == 20;
                    let (centre, extra_turns) = self.arc_centre(&w, to, g_name(code), column_of(&w, column))?;
                    BlockKind::Arc {
                        to: Point::from_array(to),
                        centre: Point::from_array(centre),
                        plane: self.plane,
                        clockwise,
                        extra_turns,
                        feed_mm_per_min,
                    }
                }
            };
            kinds.push(kind);
            self.position = to;
        }

        // Stops.
        let mut end = false;
        if let Some((code, _)) = w.group(Group::Stop) {
            if code == 0 {
                kinds.push(BlockKind::Pause);
            } else {
                kinds.push(BlockKind::End);
                end = true;
            }
        }
        Ok(Executed { n: w.n, kinds, end })
    }

    /// A line inside an open NURBS block: `X- Y- <P->` adds a control point; nothing
    /// else may stand there.
    fn nurbs_point_line(&mut self, words: &[Word], w: &Words) -> Result<Executed, LineError> {
        for word in words {
            let message = match word.letter {
                'N' | 'X' | 'Y' | 'P' => continue,
                'Z' | 'A' => format!("axis {} inside a NURBS block: only X and Y move in a NURBS (G17)", word.letter),
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
        Ok(Executed { n: w.n, kinds: Vec::new(), end: false })
    }

    /// A control point's X and Y in mm: absolute, or in G91 relative to the start of the
    /// NURBS (the current position, which LinuxCNC updates only at G5.3).
    fn nurbs_target(&self, w: &Words) -> Result<(f64, f64), LineError> {
        let to = self.target(w)?;
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
        if !self.feed_mm_per_min.is_some_and(|f| f > 0.0) {
            return Err(LineError::new(column, "G5.2 with no feed rate"));
        }
        for letter in ['Z', 'A'] {
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
        let feed_mm_per_min = match self.feed_mm_per_min {
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

    /// The block's end point, absolute, in mm (and degrees for A).
    fn target(&self, w: &Words) -> Result<[f64; 4], LineError> {
        let mut to = self.position;
        for (axis, &letter) in AXES.iter().enumerate() {
            if let Some((value, column)) = w.param(letter) {
                let value = if letter == 'A' { value } else { self.length_mm(value) };
                to[axis] = if self.incremental { to[axis] + value } else { value };
                if to[axis].abs() > MAX_POSITION {
                    return Err(LineError::new(column, "position out of range"));
                }
            }
        }
        Ok(to)
    }

    /// The centre of an arc from the current position to `to`, and its extra turns.
    fn arc_centre(&self, w: &Words, to: [f64; 4], name: String, column: usize) -> Result<([f64; 4], u32), LineError> {
        let from = self.position;
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
                let radius = |point: [f64; 4]| (point[p] - centre[p]).hypot(point[q] - centre[q]);
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

/// The weight `P` of a NURBS control point: 1 when left out, else positive.
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
