//! The differential check against LinuxCNC: a program's motion as a list of canonical
//! events, from finestep's [`Program`] ([`events_of`]) or from the output of LinuxCNC's
//! standalone interpreter `rs274 -g` ([`rs274_events`]), and their comparison
//! ([`compare`]).
//!
//! Both sides are brought to one form: positions in the machine frame in millimetres
//! (rs274 prints them in program units in the current coordinate system; its
//! `SET_G5X_OFFSET`, `SET_G92_OFFSET`, `SET_XY_ROTATION`, `USE_TOOL_LENGTH_OFFSET` and
//! `USE_LENGTH_UNITS` calls are applied as LinuxCNC's canonical layer applies them),
//! feed rates in mm/min, and the spindle and coolant state each move runs under (so the
//! order in which one block's spindle calls are printed does not matter). rs274 prints
//! four decimals in program units: values agree when within half a printed digit
//! (5e-5 program units, 1.27e-3 mm in G20) plus 1e-6 mm. Straight moves that end where
//! they start are left out on both sides (rs274 prints one for a bare `G0`).

use std::fmt;

use crate::{BlockKind, MessageKind, Plane, Program, SpindleRotation};

/// Millimetres per inch.
const MM_PER_INCH: f64 = 25.4;
/// The highest speed LinuxCNC gives G96 without D (`SET_SPINDLE_MODE(0 1e30)`).
const LINUXCNC_NO_MAX_RPM: f64 = 1e30;

/// The words of a line outside its comments: (start, end, upper-case letter, value; None
/// for an expression or parameter).
fn words(line: &str) -> Vec<(usize, usize, u8, Option<f64>)> {
    let mut words = Vec::new();
    let bytes = line.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'(' => i += line[i..].find(')').map_or(bytes.len() - i, |e| e + 1),
            // A parameter's name is no word.
            b'#' if bytes.get(i + 1) == Some(&b'<') => i += line[i..].find('>').map_or(bytes.len() - i, |e| e + 1),
            b';' => break,
            c if c.is_ascii_alphabetic() => {
                let start = i;
                i += 1;
                let digits =
                    line[i..].find(|c: char| !(c.is_ascii_digit() || "+-. ".contains(c))).unwrap_or(line.len() - i);
                let value: Option<f64> = line[i..i + digits].replace(' ', "").parse().ok();
                i += digits;
                words.push((start, i, c.to_ascii_uppercase(), value));
            }
            _ => i += 1,
        }
    }
    words
}

/// `source` with every line that holds both a tool change (M6) and a length offset
/// (G43, G43.1, G43.2, G49 with its H) split in two: the line without the offset, then
/// the offset on a line of its own. LinuxCNC runs both forms alike (its task re-reads the
/// position after the M6 block through the canonical layer, which takes every offset off);
/// rs274's stand-alone canon re-reads the last position it printed, without the offset
/// set in the block (saicanon.cc, `GET_EXTERNAL_POSITION_Z`), so only the split form
/// runs there as it runs on a machine. None when no line has both (or one has them among
/// parameters or expressions, which this does not rewrite).
pub fn split_length_offset(source: &str) -> Option<String> {
    let mut out = String::with_capacity(source.len() + 64);
    let mut split = false;
    for line in source.split_inclusive('\n') {
        let words = words(line);
        let has = |letter: u8, values: &[f64]| {
            words.iter().any(|&(_, _, l, v)| l == letter && v.is_some_and(|v| values.contains(&v)))
        };
        if !(has(b'M', &[6.0]) && has(b'G', &[43.0, 43.1, 43.2, 49.0])) {
            out.push_str(line);
            continue;
        }
        if line.contains(['[', '#']) {
            return None;
        }
        let offset = |&&(_, _, l, v): &&(usize, usize, u8, Option<f64>)| {
            l == b'H' || (l == b'G' && v.is_some_and(|v| [43.0, 43.1, 43.2, 49.0].contains(&v)))
        };
        let (mut kept, mut moved, mut at) = (String::new(), String::new(), 0);
        for word in words.iter().filter(offset) {
            kept.push_str(&line[at..word.0]);
            moved.push_str(line[word.0..word.1].trim());
            moved.push(' ');
            at = word.1;
        }
        kept.push_str(&line[at..]);
        let kept = kept.trim_end_matches(['\r', '\n']);
        out.push_str(&format!("{kept}\n{}\n", moved.trim_end()));
        split = true;
    }
    split.then_some(out)
}

/// `source` with every `M61 Q<tool>` (the tool number set without a change) given as
/// `M6 T<tool>`, the Q's value or expression kept; then, where a line now holds M6 and a
/// length offset, split as [`split_length_offset`] splits it. LinuxCNC loads the tool's
/// table entry into the spindle's (index 0) for both: for M61 its iocontrol
/// (`EMC_TOOL_SET_NUMBER`: `load_tool`), after which the interpreter re-reads the table
/// (`read_inputs`, `load_tool_table`, `set_tool_parameters`), so #5400-#5409 and G43
/// without H name the new tool. rs274's stand-alone canon does that for M6
/// (saicanon.cc `CHANGE_TOOL` copies the slot to index 0) but not for M61
/// (`CHANGE_TOOL_NUMBER` records the slot only): only the M6 form runs there as M61
/// runs on a machine. None when no line has an `M61` with a literal number.
pub fn m61_as_m6(source: &str) -> Option<String> {
    let mut out = String::with_capacity(source.len() + 16);
    let mut changed = false;
    for line in source.split_inclusive('\n') {
        let words = words(line);
        let m61 = words.iter().find(|&&(_, _, l, v)| l == b'M' && v == Some(61.0));
        let q = words.iter().find(|&&(_, _, l, _)| l == b'Q');
        let (Some(&(m_start, m_end, ..)), Some(&(q_start, ..))) = (m61, q) else {
            out.push_str(line);
            continue;
        };
        // The M word's span takes the blanks after its number: keep one.
        let m6 = if line[m_start..m_end].ends_with(' ') { "M6 " } else { "M6" };
        for (i, c) in line.char_indices() {
            match i {
                _ if i == m_start => out.push_str(m6),
                _ if (m_start..m_end).contains(&i) => {}
                _ if i == q_start => out.push('T'),
                _ => out.push(c),
            }
        }
        changed = true;
    }
    changed.then(|| split_length_offset(&out).unwrap_or(out))
}

/// `source` with the G41 or G42 of line `line` (1-based) turned into G41.1 or G42.1 with
/// the tool's diameter in the block, `diameter_inch` inches (a LinuxCNC tool table read
/// without an INI file) as an expression exact in the program's units (`#<_metric>`);
/// the line's D word goes. rs274's stand-alone canon reads the table's diameter through
/// a rounded unit (`0.03937007874016` inch/mm, saicanon.cc `GET_EXTERNAL_LENGTH_UNITS`),
/// a radius 6.4e-14 short of the table's; given in the block it reads it exact. None if
/// that line has no G41 or G42 with a number.
pub fn diameter_in_block(source: &str, line: usize, diameter_inch: f64) -> Option<String> {
    let mut variant = String::with_capacity(source.len() + 64);
    for (n, text) in source.split_inclusive('\n').enumerate() {
        if n + 1 != line {
            variant.push_str(text);
            continue;
        }
        let words = words(text);
        let &(start, end, _, g) =
            words.iter().find(|&&(_, _, l, v)| l == b'G' && matches!(v, Some(v) if v == 41.0 || v == 42.0))?;
        let mut kept = String::new();
        let mut at = 0;
        for &(s, e, l, _) in &words {
            if (s, e) == (start, end) || l == b'D' {
                kept.push_str(&text[at..s]);
                at = e;
            }
        }
        kept.push_str(&text[at..]);
        let kept = kept.trim_end_matches(['\r', '\n']);
        variant.push_str(&format!("{kept} G{}.1 D[{diameter_inch} * [1 + 24.4 * #<_metric>]]\n", g.unwrap_or(41.0)));
    }
    Some(variant)
}

/// The spindle and coolant state a move runs under.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Machine {
    /// Rotation: -1 counter-clockwise, 0 off, 1 clockwise.
    pub rotation: i8,
    /// The last S: speed in rpm, or in G96 the surface speed in program units a minute.
    pub rpm: f64,
    /// G96's highest speed, rev/min, as rs274's `SET_SPINDLE_MODE` prints it: D, 1e30
    /// without D, 0 in G97.
    pub css_max: f64,
    /// Mist coolant on.
    pub mist: bool,
    /// Flood coolant on.
    pub flood: bool,
}

impl Default for Machine {
    fn default() -> Self {
        Machine { rotation: 0, rpm: 0.0, css_max: 0.0, mist: false, flood: false }
    }
}

/// One canonical event, positions in the machine frame in mm (A B C in degrees).
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A rapid move.
    Traverse {
        /// End X Y Z A B C U V W.
        to: [f64; 9],
    },
    /// A straight feed move.
    Feed {
        /// End X Y Z A B C U V W.
        to: [f64; 9],
        /// mm/min.
        feed: f64,
        /// Spindle and coolant.
        machine: Machine,
    },
    /// An arc or helix.
    Arc {
        /// End X Y Z A B C U V W.
        to: [f64; 9],
        /// The centre's in-plane coordinates, in rs274's order (G17 X Y, G18 Z X, G19 Y Z).
        centre: [f64; 2],
        /// 17, 18 or 19.
        plane: u8,
        /// LinuxCNC's turn: 1 for one counter-clockwise turn or part of one, -1 clockwise;
        /// each extra full turn adds one in its direction.
        turn: i32,
        /// mm/min.
        feed: f64,
        /// Spindle and coolant.
        machine: Machine,
    },
    /// A NURBS (G5, G5.1, G5.2/G5.3), compared by its number of control points and its
    /// end point where both sides know it: rs274 prints `NURBS_FEED(4, ...)` with the
    /// count and without the points.
    Nurbs {
        /// End X Y Z A B C U V W, if known.
        to: Option<[f64; 9]>,
        /// The number of control points, the start included (rs274 prints it first).
        points: usize,
    },
    /// A straight probe move (G38.2-G38.5), compared by its end in X Y Z A B C (rs274
    /// prints those six) and its feed.
    Probe {
        /// End X Y Z A B C U V W.
        to: [f64; 9],
        /// mm/min.
        feed: f64,
    },
    /// M67 (synchronised with the motion) or M68 (at once): an analog output set.
    AnalogOutput {
        /// The output (E).
        index: u32,
        /// The value (Q).
        value: f64,
        /// M67.
        synchronised: bool,
    },
    /// A dwell.
    Dwell {
        /// Seconds.
        seconds: f64,
    },
    /// A tool change (M6).
    ToolChange {
        /// The tool number.
        tool: u32,
    },
    /// M19: the spindle oriented (and stopped).
    SpindleOrient {
        /// Degrees from the index.
        angle: f64,
        /// 0 the shorter way, 1 clockwise, 2 counter-clockwise.
        direction: u32,
    },
    /// M0 (rs274 also prints M1 as an optional stop, and M60 as a pallet shuttle and a
    /// stop).
    Pause,
    /// M2/M30.
    End,
    /// `MESSAGE(text)`: a MSG comment, or a DEBUG one with its parameters substituted
    /// (rs274 prints a PRINT comment's text bare, not as a call: not compared).
    Message(String),
    /// A log comment's call as rs274 prints it: `LOG("text")` (parameters substituted),
    /// `LOGOPEN("file")`, `LOGAPPEND("file")`, `LOGCLOSE()`.
    Log(String),
    /// A call finestep does not produce (probing, threading, ...): it cannot agree.
    Other(String),
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // B C U V W only when one is away from 0.
        let p = |v: &[f64]| {
            let shown = if v.len() == 9 && v[4..].iter().all(|&x| x == 0.0) { &v[..4] } else { v };
            shown.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(", ")
        };
        let m = |m: &Machine| {
            format!(
                "spindle {} {:.1} {}{}{}",
                m.rotation,
                m.rpm,
                if m.css_max == 0.0 { "rpm".to_string() } else { format!("surface speed D{:.1}", m.css_max) },
                if m.mist { " mist" } else { "" },
                if m.flood { " flood" } else { "" }
            )
        };
        match self {
            Event::Traverse { to } => write!(f, "TRAVERSE({})", p(to)),
            Event::Feed { to, feed, machine } => write!(f, "FEED({}) F{feed:.4} {}", p(to), m(machine)),
            Event::Arc { to, centre, plane, turn, feed, machine } => {
                write!(f, "ARC({}) centre ({}) G{plane} turn {turn} F{feed:.4} {}", p(to), p(centre), m(machine))
            }
            Event::Nurbs { to: Some(to), points } => write!(f, "NURBS({points}; {})", p(to)),
            Event::Nurbs { to: None, points } => write!(f, "NURBS({points}; ...)"),
            Event::Probe { to, feed } => write!(f, "PROBE({}) F{feed:.4}", p(&to[..6])),
            Event::AnalogOutput { index, value, synchronised } => {
                write!(f, "ANALOG_OUTPUT({index}, {value:.4}){}", if *synchronised { " with motion" } else { "" })
            }
            Event::Dwell { seconds } => write!(f, "DWELL({seconds:.4})"),
            Event::ToolChange { tool } => write!(f, "TOOL_CHANGE({tool})"),
            Event::SpindleOrient { angle, direction } => write!(f, "ORIENT_SPINDLE({angle:.4}, {direction})"),
            Event::Pause => write!(f, "PAUSE"),
            Event::End => write!(f, "END"),
            Event::Message(text) => write!(f, "MESSAGE(\"{text}\")"),
            Event::Log(call) => write!(f, "{call}"),
            Event::Other(call) => write!(f, "{call}"),
        }
    }
}

fn point(p: crate::Point) -> [f64; 9] {
    p.to_array()
}

/// finestep's canonical events for `program`.
pub fn events_of(program: &Program) -> Vec<Event> {
    let mut machine = Machine::default();
    let mut events = Vec::new();
    for block in &program.blocks {
        match &block.kind {
            BlockKind::Rapid { to } => events.push(Event::Traverse { to: point(*to) }),
            BlockKind::Linear { to, feed_mm_per_min } => {
                events.push(Event::Feed { to: point(*to), feed: *feed_mm_per_min, machine })
            }
            BlockKind::Arc { to, centre, plane, clockwise, extra_turns, feed_mm_per_min } => {
                let (centre, plane) = match plane {
                    Plane::Xy => ([centre.x_mm, centre.y_mm], 17),
                    Plane::Zx => ([centre.z_mm, centre.x_mm], 18),
                    Plane::Yz => ([centre.y_mm, centre.z_mm], 19),
                };
                let turns = 1 + *extra_turns as i32;
                let turn = if *clockwise { -turns } else { turns };
                events.push(Event::Arc { to: point(*to), centre, plane, turn, feed: *feed_mm_per_min, machine });
            }
            BlockKind::Nurbs { to, control_points, .. } => {
                events.push(Event::Nurbs { to: Some(point(*to)), points: control_points.len() })
            }
            BlockKind::Dwell { seconds } => events.push(Event::Dwell { seconds: *seconds }),
            BlockKind::Probe { to, feed_mm_per_min, .. } => {
                events.push(Event::Probe { to: point(*to), feed: *feed_mm_per_min })
            }
            BlockKind::AnalogOutput { index, value, synchronised } => {
                events.push(Event::AnalogOutput { index: *index, value: *value, synchronised: *synchronised })
            }
            BlockKind::Spindle { rotation, rpm, css } => {
                // rs274's `SET_SPINDLE_MODE`: D, 1e30 without it, 0 in G97.
                machine.css_max = css.map_or(0.0, |css| css.max_rpm.unwrap_or(LINUXCNC_NO_MAX_RPM));
                machine.rotation = match rotation {
                    SpindleRotation::Off => 0,
                    SpindleRotation::Clockwise => 1,
                    SpindleRotation::CounterClockwise => -1,
                };
                machine.rpm = *rpm;
            }
            BlockKind::Coolant { mist, flood } => (machine.mist, machine.flood) = (*mist, *flood),
            BlockKind::ToolChange { tool } => events.push(Event::ToolChange { tool: *tool }),
            BlockKind::SpindleOrient { angle_deg, direction, .. } => {
                machine.rotation = 0;
                events.push(Event::SpindleOrient { angle: *angle_deg, direction: *direction });
            }
            BlockKind::Pause => events.push(Event::Pause),
            BlockKind::End => events.push(Event::End),
            BlockKind::Message { kind: MessageKind::Msg | MessageKind::Debug, text } => {
                events.push(Event::Message(text.clone()))
            }
            BlockKind::Message { kind: kind @ (MessageKind::Log | MessageKind::LogOpen | MessageKind::LogAppend), text } => {
                let name = match kind {
                    MessageKind::LogOpen => "LOGOPEN",
                    MessageKind::LogAppend => "LOGAPPEND",
                    _ => "LOG",
                };
                events.push(Event::Log(format!("{name}(\"{text}\")")))
            }
            BlockKind::Message { kind: MessageKind::LogClose, .. } => events.push(Event::Log("LOGCLOSE()".into())),
            BlockKind::ToolSelect { .. }
            | BlockKind::CutterComp { .. }
            | BlockKind::CutterCompRadius { .. }
            | BlockKind::PathControl(_)
            | BlockKind::Overrides(_)
            | BlockKind::DigitalOutput { .. }
            // rs274 prints nothing for M66 (its canon reads no input).
            | BlockKind::WaitInput { .. }
            // rs274 refuses every user M-code (its canon has none: `Unknown m code used`).
            | BlockKind::UserMCode { .. }
            // rs274 writes a PRINT's text to its standard output, not as a call.
            | BlockKind::Message { kind: MessageKind::Print, .. } => {}
        }
    }
    events
}

/// rs274's output read into events, with the tolerance each event's values carry (in mm).
#[derive(Debug, Clone, Default)]
pub struct Rs274Output {
    /// The events in order.
    pub events: Vec<Event>,
    /// Per event, half a printed digit in mm (5e-5 program units) plus 1e-6.
    pub tolerance: Vec<f64>,
}

/// The interpreter state rs274's calls set, to bring its values to the machine frame.
struct Canon {
    scale: f64,
    g5x: [f64; 9],
    g92: [f64; 9],
    tool: [f64; 9],
    rotation_deg: f64,
    feed: f64,
    /// G95: the feed rate is per spindle revolution (`SET_FEED_MODE(spindle, 1)`).
    per_rev: bool,
    plane: u8,
    machine: Machine,
}

/// The numbers in a call's argument list (commas and blanks separate them).
fn numbers(args: &str) -> Result<Vec<f64>, String> {
    args.split([',', ' '])
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().map_err(|_| format!("bad number {s:?}")))
        .collect()
}

impl Canon {
    /// A position in program units (x y z a b c, and u v w when rs274 prints them) to
    /// the machine frame in mm (A B C in degrees).
    fn machine(&self, v: &[f64]) -> Result<[f64; 9], String> {
        if v.len() != 6 && v.len() != 9 {
            return Err(format!("expected 6 or 9 coordinates, got {}", v.len()));
        }
        let mut p = [0.0; 9];
        for (axis, value) in v.iter().enumerate() {
            p[axis] = if (3..6).contains(&axis) { *value } else { value * self.scale } + self.g92[axis];
        }
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        (p[0], p[1]) = (p[0] * c - p[1] * s, p[0] * s + p[1] * c);
        for (axis, value) in p.iter_mut().enumerate() {
            *value += self.g5x[axis] + self.tool[axis];
        }
        Ok(p)
    }

    /// The feed rate of a move, mm/min: in G95 the rate per revolution times the speed.
    fn feed_now(&self) -> f64 {
        if self.per_rev {
            self.feed * self.machine.rpm
        } else {
            self.feed
        }
    }

    /// Offsets given in program units (x y z a b c, then u v w if given), stored in mm
    /// (rotary ones in degrees).
    fn offsets(&self, v: &[f64]) -> [f64; 9] {
        let mut out = [0.0; 9];
        for (i, value) in v.iter().take(9).enumerate() {
            out[i] = if (3..6).contains(&i) { *value } else { value * self.scale };
        }
        out
    }
}

/// Reads rs274's standard output (its numbered `N..... CALL(args)` lines).
pub fn rs274_events(output: &str) -> Result<Rs274Output, String> {
    let mut canon = Canon {
        scale: 1.0,
        g5x: [0.0; 9],
        g92: [0.0; 9],
        tool: [0.0; 9],
        rotation_deg: 0.0,
        feed: 0.0,
        per_rev: false,
        plane: 17,
        machine: Machine::default(),
    };
    let mut out = Rs274Output::default();
    for (index, line) in output.lines().enumerate() {
        let at = |e: String| format!("rs274 output line {}: {e}: {line}", index + 1);
        let mut fields = line.trim_start().splitn(3, ' ');
        let (Some(counter), Some(_n), Some(call)) = (fields.next(), fields.next(), fields.next()) else { continue };
        if counter.parse::<u64>().is_err() {
            continue;
        }
        let call = call.trim();
        let (name, args) = match call.split_once('(') {
            Some((name, rest)) => (name, rest.strip_suffix(')').unwrap_or(rest)),
            None => (call, ""),
        };
        let nums = || numbers(args).map_err(at);
        let event = match name {
            "USE_LENGTH_UNITS" => {
                canon.scale = if args.contains("INCHES") { MM_PER_INCH } else { 1.0 };
                None
            }
            "SET_G5X_OFFSET" => {
                let v = nums()?;
                canon.g5x = canon.offsets(v.get(1..).unwrap_or(&[]));
                None
            }
            "SET_G92_OFFSET" => {
                canon.g92 = canon.offsets(&nums()?);
                None
            }
            "SET_XY_ROTATION" => {
                canon.rotation_deg = nums()?.first().copied().unwrap_or(0.0);
                None
            }
            "USE_TOOL_LENGTH_OFFSET" => {
                canon.tool = canon.offsets(&nums()?);
                None
            }
            "SET_FEED_MODE" => {
                canon.per_rev = nums()?.get(1).copied() == Some(1.0);
                None
            }
            "SET_FEED_RATE" => {
                canon.feed = nums()?.first().copied().unwrap_or(0.0) * canon.scale;
                None
            }
            "SELECT_PLANE" => {
                canon.plane = match args {
                    "CANON_PLANE_XZ" => 18,
                    "CANON_PLANE_YZ" => 19,
                    _ => 17,
                };
                None
            }
            // SET_SPINDLE_MODE(spindle css_max): G96's D (1e30 without it), 0 for G97.
            "SET_SPINDLE_MODE" => {
                canon.machine.css_max = nums()?.get(1).copied().unwrap_or(0.0);
                None
            }
            "SET_SPINDLE_SPEED" => {
                canon.machine.rpm = nums()?.get(1).copied().unwrap_or(0.0);
                None
            }
            "START_SPINDLE_CLOCKWISE" => {
                canon.machine.rotation = 1;
                None
            }
            "START_SPINDLE_COUNTERCLOCKWISE" => {
                canon.machine.rotation = -1;
                None
            }
            "STOP_SPINDLE_TURNING" => {
                canon.machine.rotation = 0;
                None
            }
            // ORIENT_SPINDLE(spindle, angle, direction): the spindle is held at the angle.
            "ORIENT_SPINDLE" => {
                let v = nums()?;
                canon.machine.rotation = 0;
                Some(Event::SpindleOrient {
                    angle: v.get(1).copied().unwrap_or(0.0),
                    direction: v.get(2).copied().unwrap_or(0.0) as u32,
                })
            }
            "MIST_ON" | "MIST_OFF" => {
                canon.machine.mist = name == "MIST_ON";
                None
            }
            "FLOOD_ON" | "FLOOD_OFF" => {
                canon.machine.flood = name == "FLOOD_ON";
                None
            }
            "STRAIGHT_TRAVERSE" => Some(Event::Traverse { to: canon.machine(&nums()?).map_err(at)? }),
            "STRAIGHT_FEED" => Some(Event::Feed {
                to: canon.machine(&nums()?).map_err(at)?,
                feed: canon.feed_now(),
                machine: canon.machine,
            }),
            "ARC_FEED" => {
                let v = nums()?;
                if v.len() < 9 {
                    return Err(at("ARC_FEED with fewer than 9 values".into()));
                }
                // first end, second end, first centre, second centre, turn, axis end, a b c
                // (and u v w when rs274 prints them)
                let n = if v.len() >= 12 { 9 } else { 6 };
                let (mut e, mut c) = (vec![0.0; n], vec![0.0; n]);
                let (first, second, normal) = match canon.plane {
                    18 => (2, 0, 1),
                    19 => (1, 2, 0),
                    _ => (0, 1, 2),
                };
                e[first] = v[0];
                e[second] = v[1];
                e[normal] = v[5];
                e[3..n].copy_from_slice(&v[6..n + 3]);
                c[first] = v[2];
                c[second] = v[3];
                c[normal] = v[5];
                let to = canon.machine(&e).map_err(at)?;
                let centre3 = canon.machine(&c).map_err(at)?;
                let centre = [centre3[first], centre3[second]];
                Some(Event::Arc {
                    to,
                    centre,
                    plane: canon.plane,
                    turn: v[4] as i32,
                    feed: canon.feed_now(),
                    machine: canon.machine,
                })
            }
            "DWELL" => Some(Event::Dwell { seconds: nums()?.first().copied().unwrap_or(0.0) }),
            "CHANGE_TOOL" => Some(Event::ToolChange { tool: nums()?.first().copied().unwrap_or(0.0) as u32 }),
            "PROGRAM_STOP" | "OPTIONAL_PROGRAM_STOP" => Some(Event::Pause),
            "PROGRAM_END" => Some(Event::End),
            // MESSAGE("text"), the text as it is (rs274 escapes nothing).
            "MESSAGE" => Some(Event::Message(
                args.strip_prefix('"')
                    .and_then(|a| a.strip_suffix('"'))
                    .ok_or_else(|| at("MESSAGE without its quoted text".into()))?
                    .to_string(),
            )),
            // LOG("text"), LOGOPEN("file"), LOGAPPEND("file"), LOGCLOSE(): compared whole.
            "LOG" | "LOGOPEN" | "LOGAPPEND" | "LOGCLOSE" => Some(Event::Log(call.to_string())),
            "NURBS_FEED" => {
                let count = args.split(',').next().and_then(|n| n.trim().parse::<usize>().ok());
                Some(Event::Nurbs { to: None, points: count.ok_or_else(|| at("NURBS_FEED without its count".into()))? })
            }
            "STRAIGHT_PROBE" => Some(Event::Probe { to: canon.machine(&nums()?).map_err(at)?, feed: canon.feed_now() }),
            // SET_MOTION_OUTPUT_VALUE(index,value) for M67, SET_AUX_OUTPUT_VALUE for M68.
            "SET_MOTION_OUTPUT_VALUE" | "SET_AUX_OUTPUT_VALUE" => {
                let v = nums()?;
                let [index, value] = v[..] else { return Err(at("expected an index and a value".into())) };
                Some(Event::AnalogOutput {
                    index: index as u32,
                    value,
                    synchronised: name == "SET_MOTION_OUTPUT_VALUE",
                })
            }
            "RIGID_TAP" | "START_SPEED_FEED_SYNCH" | "SPINDLE_RETRACT_TRAVERSE" => Some(Event::Other(call.to_string())),
            _ => None,
        };
        if let Some(event) = event {
            out.tolerance.push(5e-5 * canon.scale + 1e-6);
            out.events.push(event);
        }
    }
    Ok(out)
}

fn close(a: &[f64], b: &[f64], tolerance: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tolerance)
}

fn machine_close(a: &Machine, b: &Machine) -> bool {
    a.rotation == b.rotation
        && (a.rpm - b.rpm).abs() <= 5e-5
        && (a.css_max - b.css_max).abs() <= 5e-5 * a.css_max.abs().max(1.0)
        && a.mist == b.mist
        && a.flood == b.flood
}

/// Whether finestep's event `ours` agrees with rs274's `theirs` within `tolerance` mm.
pub fn agrees(ours: &Event, theirs: &Event, tolerance: f64) -> bool {
    // Feed rates are printed with four decimals in program units per minute too.
    let feed_ok = |a: f64, b: f64| (a - b).abs() <= tolerance;
    match (ours, theirs) {
        (Event::Traverse { to: a }, Event::Traverse { to: b }) => close(a, b, tolerance),
        (Event::Feed { to: a, feed: fa, machine: ma }, Event::Feed { to: b, feed: fb, machine: mb }) => {
            close(a, b, tolerance) && feed_ok(*fa, *fb) && machine_close(ma, mb)
        }
        (
            Event::Arc { to: a, centre: ca, plane: pa, turn: ta, feed: fa, machine: ma },
            Event::Arc { to: b, centre: cb, plane: pb, turn: tb, feed: fb, machine: mb },
        ) => {
            close(a, b, tolerance)
                && close(ca, cb, tolerance)
                && pa == pb
                && ta == tb
                && feed_ok(*fa, *fb)
                && machine_close(ma, mb)
        }
        (Event::Nurbs { to: Some(a), points: na }, Event::Nurbs { to: Some(b), points: nb }) => {
            na == nb && close(a, b, tolerance)
        }
        (Event::Nurbs { points: na, .. }, Event::Nurbs { points: nb, .. }) => na == nb,
        (Event::Probe { to: a, feed: fa }, Event::Probe { to: b, feed: fb }) => {
            close(&a[..6], &b[..6], tolerance) && feed_ok(*fa, *fb)
        }
        (
            Event::AnalogOutput { index: ia, value: va, synchronised: sa },
            Event::AnalogOutput { index: ib, value: vb, synchronised: sb },
        ) => ia == ib && sa == sb && (va - vb).abs() <= 5e-7 * va.abs().max(1.0),
        (Event::Dwell { seconds: a }, Event::Dwell { seconds: b }) => (a - b).abs() <= 5e-5,
        (Event::ToolChange { tool: a }, Event::ToolChange { tool: b }) => a == b,
        (Event::SpindleOrient { angle: a, direction: da }, Event::SpindleOrient { angle: b, direction: db }) => {
            (a - b).abs() <= 5e-5 && da == db
        }
        (Event::Pause, Event::Pause) | (Event::End, Event::End) => true,
        (Event::Message(a), Event::Message(b)) | (Event::Log(a), Event::Log(b)) => a == b,
        _ => false,
    }
}

/// A point's in-plane coordinates in rs274's order (G17 X Y, G18 Z X, G19 Y Z).
fn in_plane(p: &[f64; 9], plane: u8) -> [f64; 2] {
    match plane {
        18 => [p[2], p[0]],
        19 => [p[1], p[2]],
        _ => [p[0], p[1]],
    }
}

/// The events without moves that do not move (rs274 prints a straight one for a `G0` or
/// a canned cycle's step that stays where it is, and an arc of radius zero for a
/// compensated concave arc as small as the tool; finestep does not).
fn moving(events: &[Event], tolerance: impl Fn(usize) -> f64) -> Vec<(usize, &Event)> {
    // Both start at the origin.
    let mut at: Option<[f64; 9]> = Some([0.0; 9]);
    let mut out = Vec::new();
    for (i, e) in events.iter().enumerate() {
        let to = match e {
            Event::Traverse { to } | Event::Feed { to, .. } => Some(*to),
            // An arc of radius zero where the tool is (rs274's compensated concave arc as
            // small as the tool) does not move either.
            Event::Arc { to, centre, plane, .. }
                if at.is_some_and(|from| close(to, &from, tolerance(i)))
                    && close(centre, &in_plane(to, *plane), tolerance(i)) =>
            {
                continue;
            }
            Event::Arc { to, .. } | Event::Nurbs { to: Some(to), .. } => {
                at = Some(*to);
                out.push((i, e));
                continue;
            }
            // The interpretation goes on from where the probe stopped, which neither side's
            // event says.
            Event::Nurbs { to: None, .. } | Event::Probe { .. } => {
                at = None;
                out.push((i, e));
                continue;
            }
            _ => None,
        };
        match (to, at) {
            (Some(to), Some(from)) if close(&to, &from, tolerance(i)) => {}
            (Some(to), _) => {
                at = Some(to);
                out.push((i, e));
            }
            (None, _) => out.push((i, e)),
        }
    }
    out
}

/// The first difference between finestep's events and rs274's, as a short unified
/// listing around it; `None` when they agree.
pub fn compare(ours: &[Event], theirs: &Rs274Output) -> Option<String> {
    let ours: Vec<Event> = moving(ours, |_| 1e-9).into_iter().map(|(_, e)| e.clone()).collect();
    let kept = moving(&theirs.events, |i| theirs.tolerance[i]);
    let theirs = Rs274Output {
        events: kept.iter().map(|(_, e)| (*e).clone()).collect(),
        tolerance: kept.iter().map(|(i, _)| theirs.tolerance[*i]).collect(),
    };
    let n = ours.len().max(theirs.events.len());
    let first = (0..n).find(|&i| match (ours.get(i), theirs.events.get(i)) {
        (Some(a), Some(b)) => !agrees(a, b, theirs.tolerance[i]),
        _ => true,
    })?;
    let mut text = format!(
        "first difference at event {} (finestep {} events, rs274 {} events)\n",
        first + 1,
        ours.len(),
        theirs.events.len()
    );
    for i in first.saturating_sub(3)..(first + 4).min(n) {
        let show = |e: Option<&Event>| e.map_or("-".to_string(), Event::to_string);
        let mark = if i == first { ">" } else { " " };
        text.push_str(&format!("{mark} {:>5} finestep: {}\n", i + 1, show(ours.get(i))));
        text.push_str(&format!("{mark} {:>5} rs274:    {}\n", i + 1, show(theirs.events.get(i))));
    }
    Some(text)
}

#[cfg(test)]
mod variant_tests {
    use super::*;

    #[test]
    fn a_tool_change_with_a_length_offset_is_split_in_two_lines() {
        let source = "G20\nN80 T1 M06 G43 H1 (get its length)\nG0 X1\nG40 T2M6G43\nM2\n";
        assert_eq!(
            split_length_offset(source).as_deref(),
            Some("G20\nN80 T1 M06 (get its length)\nG43 H1\nG0 X1\nG40 T2M6\nG43\nM2\n")
        );
        // Nothing to split, or an expression it does not rewrite.
        assert_eq!(split_length_offset("T1 M6\nG43 H1\n"), None);
        assert_eq!(split_length_offset("T1 M6 G43 H#1\n"), None);
        // A G43 in a comment or after `;` is not a word.
        assert_eq!(split_length_offset("T1 M6 (G43 H1) ; G49\n"), None);
    }

    #[test]
    fn m61_is_given_as_m6_with_its_q_as_t() {
        // offsets.ngc's line, and a literal Q with the offset to split off.
        assert_eq!(
            m61_as_m6("#<n> = 1\nM61Q#<n>G43\n(debug, #5403)\n").as_deref(),
            Some("#<n> = 1\nM6T#<n>G43\n(debug, #5403)\n")
        );
        assert_eq!(m61_as_m6("G0 X1\nm61 q2 G43 (tool 2)\n").as_deref(), Some("G0 X1\nM6 T2 (tool 2)\nG43\n"));
        assert_eq!(m61_as_m6("M61 Q[1 + 2]\n").as_deref(), Some("M6 T[1 + 2]\n"));
        // No M61 (a name or a comment is no word), or one with an expression.
        assert_eq!(m61_as_m6("T1 M6\n#<m61> = 2 (M61 Q1)\n"), None);
        assert_eq!(m61_as_m6("M[61] Q1\n"), None);
    }

    #[test]
    fn the_compensation_of_a_line_takes_the_diameter_in_the_block() {
        let source = "G20\ng41 g1 y4 d4\ng1 x1\n";
        assert_eq!(
            diameter_in_block(source, 2, 2.0).as_deref(),
            Some("G20\ng1 y4  G41.1 D[2 * [1 + 24.4 * #<_metric>]]\ng1 x1\n")
        );
        assert_eq!(
            diameter_in_block("G42 X1\n", 1, 0.5).as_deref(),
            Some("X1 G42.1 D[0.5 * [1 + 24.4 * #<_metric>]]\n")
        );
        assert_eq!(diameter_in_block("G1 X1\n", 1, 0.5), None);
    }
}

#[cfg(test)]
mod message_tests {
    use super::*;

    /// rs274's `MESSAGE` calls are events compared by their text: `(MSG, hello)` then
    /// `G0 X1` agree with rs274's `MESSAGE(" hello")` and `STRAIGHT_TRAVERSE(1, ...)`,
    /// and not with another text; PRINT's bare line in rs274's output is no event.
    #[test]
    fn messages_are_compared_by_their_text() {
        let ours = events_of(&crate::parse_str("(MSG, hello)\n(PRINT, x)\nG0 X1\nM2\n", "m.ngc").unwrap());
        let rs274 = |text: &str| {
            rs274_events(&format!(
                "    7 N..... MESSAGE(\"{text}\")\n x\n    8 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n    9 N..... PROGRAM_END()\n"
            ))
            .unwrap()
        };
        assert_eq!(ours[0], Event::Message(" hello".into()));
        assert_eq!(compare(&ours, &rs274(" hello")), None);
        assert!(compare(&ours, &rs274(" hullo")).is_some());
    }
}
