//! Cutter radius compensation, C-type (G40/G41/G42), as a program-to-program pass.
//!
//! [`compensate`] takes the canonical program of `finestep-gcode` and returns one in
//! which every compensated move is replaced by the path of the tool centre, kept at the
//! tool radius to the left (G41) or right (G42) of the programmed path, with the
//! [`BlockKind::CutterComp`] blocks removed. The planner then runs it as any other
//! program.
//!
//! ```
//! use finestep_gcode::{parse_str, BlockKind};
//! use finestep_planner::cutter_comp::{compensate, ToolTable};
//!
//! // A 10 mm square cut on its outside with a 2 mm radius tool (tool 1).
//! let program = parse_str(
//!     "G0 X5 Y-5\nG42 D1\nG1 X5 Y0 F600\nG1 X10\nG1 Y10\nG1 X0\nG1 Y0\nG1 X5\nG40\nG0 X5 Y-5\nM2\n",
//!     "square.ngc",
//! )
//! .unwrap();
//! let tools = ToolTable::new().with_radius_mm(1, 2.0);
//! let cut = compensate(&program, &tools).unwrap();
//! // The side X10 is cut 2 mm further out, at X12 ...
//! assert!(cut.blocks.iter().any(|b| matches!(b.kind,
//!     BlockKind::Linear { to, .. } if to.x_mm == 12.0 && to.y_mm == 10.0)));
//! // ... and each outside corner is rounded by a 2 mm arc around the programmed corner.
//! assert!(cut.blocks.iter().any(|b| matches!(b.kind,
//!     BlockKind::Arc { to, centre, .. } if centre.x_mm == 10.0 && centre.y_mm == 10.0
//!         && to.x_mm == 10.0 && to.y_mm == 12.0)));
//!
//! // A tool that does not fit a concave arc is an error naming the arc's line.
//! let pocket = parse_str("G41 D1\nG1 X5 F600\nG3 X7 Y2 I0 J2\nG40\nG1 X0 Y0\n", "p.ngc").unwrap();
//! let err = compensate(&pocket, &ToolTable::new().with_radius_mm(1, 3.0)).unwrap_err();
//! assert_eq!(err.to_string(), "line 3: tool radius 3 mm is larger than the concave arc radius 2 mm");
//! ```
//!
//! # What it does
//!
//! - **Plane.** Compensation is in the plane G41/G42 (or G41.1/G42.1) was given in
//!   (their block carries it): G17, or G18 as LinuxCNC does for lathes, where Z and X
//!   take the places of X and Y (Z X Y is right-handed like X Y Z, so the sides and the
//!   arc directions mean the same). Below, X Y stand for the plane's axes. The third axis
//!   and A are carried along: a move's end keeps its programmed values, so helices and
//!   ramps work. An arc in another plane while compensation is on is an error.
//! - **Moves.** A line is offset by the radius along its left (G41) or right (G42)
//!   normal; an arc keeps its centre and its radius grows or shrinks by the tool radius
//!   (full circles and extra turns are kept). An arc whose radius would shrink below zero
//!   (a concave arc smaller than the tool) is an error; one that shrinks to zero (within
//!   [`JOIN_TOLERANCE_MM`]) is a pivot, the tool turning at the arc's centre, accepted
//!   where the offsets of both neighbours meet there (LinuxCNC prints an arc of radius
//!   zero; finestep a move of length zero), an error naming its line otherwise. Moves that
//!   do not move in XY (Z or A alone) keep the tool where it is in XY.
//! - **Corners**, between any two of lines and arcs, judged by the tangents at the
//!   programmed corner: tangent moves join directly; at an outside (convex) corner an
//!   arc of the tool radius around the programmed corner is inserted, as LinuxCNC does;
//!   at an inside (concave) corner both offset moves are cut back to where they
//!   intersect. A move whose offset would vanish or run backwards between its two
//!   corners, or two offsets that do not meet, is an error naming the move's line: the
//!   tool does not fit there. A corner that turns back exactly (180 degrees) is taken
//!   as outside. An inserted corner arc belongs to the move after the corner (its line
//!   and, for a feed move, its feed; after a rapid, the feed of the move before or the
//!   last programmed feed). With [`EntryExit::LinuxCnc`] the corners are LinuxCNC's: one
//!   turning by at most [`LINUXCNC_TANGENT_RAD`] (0.05 rad, either way) is left as it is
//!   (no arc, no cut-back: the next move runs from the last offset end to its own, a
//!   step of at most 0.05 of the radius off its offset), and the corner before a rapid
//!   is a rapid straight to the corner arc's end. At an inside corner before an arc the
//!   arc's offset circle is that of its end's radius (the radius at its start may differ
//!   by the front end's arc tolerance), and after a line the line ends where LinuxCNC's
//!   formula puts it on that circle (`linuxcnc_line_to_arc`), off the line's offset by
//!   as much as the two radii differ.
//! - **Lathe tools.** G41.1/G42.1 with L in G18 give a lathe tool's orientation
//!   (LinuxCNC's 1-8): the offset path is that of the nose's centre, and every
//!   compensated point is moved by the nose radius in X and/or Z to the imaginary tool
//!   tip, the point the machine's position refers to (as LinuxCNC's interpreter does
//!   when it hands the compensated moves on). The exit move ends on its programmed point.
//! - **Entry.** After G41/G42 the first move in XY (the entry move) must be a straight
//!   line longer than the tool radius. With [`EntryExit::Tangent`] (the default) it runs
//!   from the current (uncompensated) point along the tangent to the circle of the tool
//!   radius around its programmed end point, on the compensation side; it then joins the
//!   next move like any other corner: an entry that comes in from the compensation side
//!   (from outside for an outside contour) is cut back where it crosses the first offset
//!   move, one from the other side gets a corner arc.
//! - **Exit.** After G40 the first move in XY (the exit move) must be a straight line
//!   (with [`EntryExit::Tangent`] longer than the tool radius). With
//!   [`EntryExit::Tangent`] it is the mirror image of the entry: it leaves the circle of
//!   the tool radius around the last compensated point along the tangent through its
//!   programmed end point, which it reaches exactly, and joins the last compensated move
//!   like any other corner.
//! - **LinuxCNC's entry and exit** ([`EntryExit::LinuxCnc`], what LinuxCNC 2.9's
//!   interpreter does, `convert_straight_comp1` and the first move after G40): the entry
//!   ends at the programmed end point plus the tool radius along the normal of the
//!   *programmed* entry direction, and that end joins the next move as the end of the
//!   programmed line's offset would (at an inside corner it slides along that offset to
//!   the crossing, the entry itself being the straight line from the uncompensated
//!   start); the exit runs straight from the last offset end point to the programmed
//!   point. Both pass closer than the tool radius to the programmed corner they touch,
//!   so they can cut into the part (in `comp-g1.ngc`, LinuxCNC's own example, by about
//!   0.09 inch at the entry): the tangent lines are finestep's default.
//! - **Tools.** The radius comes from the [`ToolTable`] entry of the `D` word, or of the
//!   tool in the spindle (the last M6) when `D` is not given. A radius of zero leaves the
//!   path as programmed. A tool change (M6) while compensation is on is an error, as in
//!   LinuxCNC.
//! - **Program end.** If the program ends with compensation on, the last move ends at its
//!   offset end point.
//!
//! Only adjacent moves are compared: like every C-type control, this does not see a
//! gouge between moves that are not neighbours (a neck narrower than the tool between two
//! distant parts of the contour).
//!
//! The tolerances are stated as constants: [`JOIN_TOLERANCE_MM`],
//! [`EXTENSION_TOLERANCE_MM`] and [`SHORT_ARC_CHORD_MM`].

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};

use finestep_gcode::{Block, BlockKind, CompSide, Plane, Point, Program};

/// Offset end points closer than this are one point (tangent joins), and a corner may
/// cut a move back this far past its other end before the move counts as vanished, in
/// mm.
pub const JOIN_TOLERANCE_MM: f64 = 1e-9;

/// Arcs (inserted or cut back) whose chord is shorter than this, in mm, are emitted as
/// straight moves: such a chord of a 1 mm radius arc lies 1.25e-13 mm inside it, and
/// the planner is spared arcs far shorter than a step.
pub const SHORT_ARC_CHORD_MM: f64 = 1e-6;

/// How far the crossing of two offset moves at an inside corner may lie beyond their
/// offset end points, in mm: where the moves are nearly tangent the crossing is
/// ill-conditioned (its place along the moves is known to about 1e-8 of the radius).
pub const EXTENSION_TOLERANCE_MM: f64 = 1e-4;

/// With [`EntryExit::LinuxCnc`], corners turning by at most this (radians, either way)
/// count as tangent, as LinuxCNC's `TOLERANCE_CONCAVE_CORNER` makes them: no corner
/// arc, no cut-back (the next move runs from the last offset end to its own).
pub const LINUXCNC_TANGENT_RAD: f64 = 0.05;

/// A move shorter than this in XY is a move of Z or A alone, in mm.
const PLANAR_ZERO_MM: f64 = 1e-12;

/// Turns closer than this to exactly backwards (sine of the angle) count as reversals.
const REVERSAL_SINE: f64 = 1e-12;

/// How the entry move (the first XY move after G41/G42) and the exit move (the first
/// after G40) are laid out (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
pub enum EntryExit {
    /// Tangent lines to the circle of the tool radius around the programmed point they
    /// meet: they never come closer than the tool radius to it.
    #[default]
    #[serde(rename = "tangent")]
    Tangent,
    /// LinuxCNC 2.9's: the entry ends on the normal of the programmed entry line, the
    /// exit leaves straight from the last offset point; and LinuxCNC's corners: a
    /// corner turning by at most [`LINUXCNC_TANGENT_RAD`] either way is neither rounded
    /// nor cut back (each move ends at its own offset end), the corner before a rapid is
    /// a rapid straight to the corner arc's end, and an arc's inside corner is resolved
    /// on the circle of its end's radius, after a line by LinuxCNC's formula.
    #[serde(rename = "linuxcnc")]
    LinuxCnc,
}

/// Tool radii by tool number, in mm, and the layout of the entry and exit moves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ToolTable {
    radii_mm: BTreeMap<u32, f64>,
    entry_exit: EntryExit,
}

impl ToolTable {
    /// An empty table.
    pub fn new() -> ToolTable {
        ToolTable::default()
    }

    /// The table with tool `tool`'s radius set to `radius_mm`.
    pub fn with_radius_mm(mut self, tool: u32, radius_mm: f64) -> ToolTable {
        self.set_radius_mm(tool, radius_mm);
        self
    }

    /// Sets tool `tool`'s radius. It is checked (finite, not negative) when a program
    /// uses it, so that the error can name the line.
    pub fn set_radius_mm(&mut self, tool: u32, radius_mm: f64) {
        self.radii_mm.insert(tool, radius_mm);
    }

    /// Tool `tool`'s radius, if the table has the tool.
    pub fn radius_mm(&self, tool: u32) -> Option<f64> {
        self.radii_mm.get(&tool).copied()
    }

    /// The table with the entry and exit moves laid out as `entry_exit` says.
    pub fn with_entry_exit(mut self, entry_exit: EntryExit) -> ToolTable {
        self.entry_exit = entry_exit;
        self
    }

    /// How the entry and exit moves are laid out.
    pub fn entry_exit(&self) -> EntryExit {
        self.entry_exit
    }
}

/// Why a program cannot be compensated: the block's source line and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct CompError {
    /// 1-based source line of the block at fault.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// Why one move cannot be offset, before its line is attached ([`CompError`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum OffsetError {
    /// The tool does not fit inside a concave arc.
    #[error("tool radius {} mm {relation} the concave arc radius {} mm", mm(*radius), mm(*arc))]
    ConcaveArc {
        /// Tool radius, mm.
        radius: f64,
        /// `is larger than`, or `equals` (within the join tolerance).
        relation: &'static str,
        /// The arc's smaller radius, mm.
        arc: f64,
    },
    /// The entry or exit move is not longer than the tool radius.
    #[error("the {which} moves {} mm in XY; it must move more than the tool radius {} mm", mm(*length), mm(*radius))]
    TooShort {
        /// `entry move after G41/G42` or `exit move after G40`.
        which: &'static str,
        /// Its length in XY, mm.
        length: f64,
        /// Tool radius, mm.
        radius: f64,
    },
    /// The block is not a line or an arc.
    #[error("not a move")]
    NotAMove,
}

/// Resolves cutter radius compensation in `program` with the radii of `tools`.
///
/// The result has no [`BlockKind::CutterComp`] blocks; every other block is kept in
/// order, compensated moves are replaced by the tool-centre path (cut back, or with
/// corner arcs inserted, which carry the line of the move after the corner). See the
/// [module documentation](self) for the rules.
/// [`compensate`], without copying a program that has no G40/G41/G42 (compensation
/// changes nothing there): the program itself, borrowed.
pub fn compensated<'p>(program: &'p Program, tools: &ToolTable) -> Result<Cow<'p, Program>, CompError> {
    if program
        .blocks
        .iter()
        .any(|b| matches!(b.kind, BlockKind::CutterComp { .. } | BlockKind::CutterCompRadius { .. }))
    {
        compensate(program, tools).map(Cow::Owned)
    } else {
        Ok(Cow::Borrowed(program))
    }
}

pub fn compensate(program: &Program, tools: &ToolTable) -> Result<Program, CompError> {
    let mut pass = Pass::new(Cow::Borrowed(tools), program.blocks.len() + program.blocks.len() / 2);
    for block in &program.blocks {
        pass.feed(block)?;
    }
    pass.finish();
    Ok(Program { blocks: pass.pass.out })
}

/// The compensation pass over blocks given one at a time: a block handed out is final
/// (the pass only appends), so it can be handed on at once.
struct Pass<'a> {
    pass: Compensator<'a>,
    frame: Plane,
}

impl<'a> Pass<'a> {
    fn new(tools: Cow<'a, ToolTable>, capacity: usize) -> Pass<'a> {
        let pass = Compensator {
            tools,
            out: Vec::with_capacity(capacity),
            programmed: Point::default(),
            spindle_tool: 0,
            last_feed: None,
            mode: Mode::Off,
            tip: V2 { x: 0.0, y: 0.0 },
        };
        Pass { pass, frame: Plane::Xy }
    }

    /// The next block of the program.
    fn feed(&mut self, block: &Block) -> Result<(), CompError> {
        // Compensation in G18 runs in a frame where the plane's axes (Z, X) are (X, Y): the
        // pass works in XY, every block goes in mapped and comes out mapped back.
        let pass = &mut self.pass;
        if let (Mode::Off, BlockKind::CutterComp { plane, .. } | BlockKind::CutterCompRadius { plane, .. }) =
            (&pass.mode, &block.kind)
        {
            if *plane != self.frame {
                pass.programmed = to_frame(*plane, from_frame(self.frame, pass.programmed));
                self.frame = *plane;
            }
        }
        let start = pass.out.len();
        pass.block(&map_block(self.frame, block, true))?;
        for out in &mut pass.out[start..] {
            *out = map_block(self.frame, out, false);
        }
        if matches!(pass.mode, Mode::Off) && self.frame != Plane::Xy {
            pass.programmed = from_frame(self.frame, pass.programmed);
            self.frame = Plane::Xy;
        }
        Ok(())
    }

    /// The program has ended.
    fn finish(&mut self) {
        let start = self.pass.out.len();
        self.pass.flush();
        for out in &mut self.pass.out[start..] {
            *out = map_block(self.frame, out, false);
        }
    }
}

/// Compensation applied to blocks as they are read ([`compensate`] as a stream): each
/// block the pass gives is handed on as soon as it is final, so that only the moves the
/// offset is still resolving (around the corner being read) are held. The first error,
/// of the blocks read or of the compensation, ends the stream.
pub struct Compensating<'a, I> {
    blocks: I,
    pass: Pass<'a>,
    /// Blocks of the pass handed on so far.
    handed: usize,
    done: bool,
}

impl<'a, I> Compensating<'a, I> {
    /// `blocks` compensated with the radii of `tools`.
    pub fn new(blocks: I, tools: ToolTable) -> Compensating<'a, I> {
        Compensating { blocks, pass: Pass::new(Cow::Owned(tools), 0), handed: 0, done: false }
    }
}

impl<E: From<CompError>, I: Iterator<Item = Result<Block, E>>> Iterator for Compensating<'_, I> {
    type Item = Result<Block, E>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let out = &mut self.pass.pass.out;
            if self.handed < out.len() {
                let block = std::mem::replace(&mut out[self.handed], Block { line: 0, n: None, kind: BlockKind::End });
                self.handed += 1;
                if self.handed == out.len() {
                    out.clear();
                    self.handed = 0;
                }
                return Some(Ok(block));
            }
            if self.done {
                return None;
            }
            match self.blocks.next() {
                Some(Ok(block)) => {
                    if let Err(e) = self.pass.feed(&block) {
                        self.done = true;
                        self.pass.pass.out.clear();
                        return Some(Err(e.into()));
                    }
                }
                Some(Err(e)) => {
                    self.done = true;
                    self.pass.pass.out.clear();
                    return Some(Err(e));
                }
                None => {
                    self.done = true;
                    self.pass.finish();
                }
            }
        }
    }
}

/// A point of the machine in the frame of compensation in `plane`: G18's Z X Y as X Y Z
/// (right-handed, so sides and arc directions keep their meaning); G17 (and G19, which
/// is not compensated) as it is.
fn to_frame(plane: Plane, p: Point) -> Point {
    match plane {
        Plane::Zx => Point { x_mm: p.z_mm, y_mm: p.x_mm, z_mm: p.y_mm, ..p },
        Plane::Xy | Plane::Yz => p,
    }
}

/// The inverse of [`to_frame`].
fn from_frame(plane: Plane, p: Point) -> Point {
    match plane {
        Plane::Zx => Point { x_mm: p.y_mm, y_mm: p.z_mm, z_mm: p.x_mm, ..p },
        Plane::Xy | Plane::Yz => p,
    }
}

/// `block` with its points into `frame` ([`to_frame`], `into`) or back out of it
/// ([`from_frame`]), and an arc's plane with them: in G18's frame the ZX plane is the XY
/// plane (and XY, YZ follow the permutation).
fn map_block(frame: Plane, block: &Block, into: bool) -> Block {
    let mut block = block.clone();
    if frame == Plane::Xy {
        return block;
    }
    let map = if into { to_frame } else { from_frame };
    match &mut block.kind {
        BlockKind::Rapid { to } | BlockKind::Linear { to, .. } => *to = map(frame, *to),
        BlockKind::Arc { to, centre, plane, .. } => {
            *to = map(frame, *to);
            *centre = map(frame, *centre);
            *plane = match (*plane, into) {
                (Plane::Zx, true) | (Plane::Yz, false) => Plane::Xy,
                (Plane::Xy, true) | (Plane::Zx, false) => Plane::Yz,
                (Plane::Yz, true) | (Plane::Xy, false) => Plane::Zx,
            };
        }
        BlockKind::Nurbs { to, .. } => *to = map(frame, *to),
        _ => {}
    }
    block
}

/// A point or vector in the XY plane, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
struct V2 {
    x: f64,
    y: f64,
}

impl V2 {
    fn of(p: &Point) -> V2 {
        V2 { x: p.x_mm, y: p.y_mm }
    }
    fn add(self, o: V2) -> V2 {
        V2 { x: self.x + o.x, y: self.y + o.y }
    }
    fn sub(self, o: V2) -> V2 {
        V2 { x: self.x - o.x, y: self.y - o.y }
    }
    fn scale(self, k: f64) -> V2 {
        V2 { x: self.x * k, y: self.y * k }
    }
    fn dot(self, o: V2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    fn cross(self, o: V2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    fn unit(self) -> V2 {
        self.scale(1.0 / self.norm())
    }
    /// The vector turned a quarter turn counter-clockwise: the left normal of a direction.
    fn left(self) -> V2 {
        V2 { x: -self.y, y: self.x }
    }
    fn rotate(self, angle: f64) -> V2 {
        let (s, c) = angle.sin_cos();
        V2 { x: c * self.x - s * self.y, y: s * self.x + c * self.y }
    }
    fn angle(self) -> f64 {
        self.y.atan2(self.x)
    }
}

/// A length for messages, as a short decimal ("3", "2.5", "0.123457").
fn mm(value: f64) -> String {
    let text = format!("{value:.6}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

/// The angle swept from `start` to `end` (radians, positive), by the rule the front
/// end and the planner use: a full circle when the angles are equal, plus extra turns.
fn swept_angle(start: f64, end: f64, ccw: bool, extra_turns: u32) -> f64 {
    let ccw_angle = (end - start).rem_euclid(TAU);
    let base = if ccw { ccw_angle } else { (TAU - ccw_angle) % TAU };
    let base = if base == 0.0 { TAU } else { base };
    base + f64::from(extra_turns) * TAU
}

/// The geometry an offset move lies on. Positions along it are parameters: distance
/// from `origin` along a line, angle turned from `theta0` along an arc.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Line { origin: V2, dir: V2 },
    Arc { centre: V2, ccw: bool, theta0: f64 },
}

/// A move of the tool centre: its shape and its (possibly cut back) ends.
#[derive(Clone, Copy, Debug)]
struct Element {
    shape: Shape,
    start: V2,
    start_param: f64,
    end: V2,
    end_param: f64,
    /// Arcs: the radius at the start and at the end (they differ by the front end's
    /// arc tolerance at most); each corner uses the radius of its own end.
    radius_start: f64,
    radius_end: f64,
}

impl Element {
    fn line(start: V2, end: V2, dir: V2) -> Element {
        Element {
            shape: Shape::Line { origin: start, dir },
            start,
            start_param: 0.0,
            end,
            end_param: end.sub(start).dot(dir),
            radius_start: 0.0,
            radius_end: 0.0,
        }
    }

    /// A concave arc as small as the tool: the tool pivots at its centre.
    fn is_pivot(&self) -> bool {
        matches!(self.shape, Shape::Arc { .. }) && self.radius_start == 0.0 && self.radius_end == 0.0
    }

    /// Unit tangent in the direction of motion at `point` on the element.
    fn tangent_at(&self, point: V2) -> V2 {
        match self.shape {
            Shape::Line { dir, .. } => dir,
            Shape::Arc { centre, ccw, .. } => {
                let radial = point.sub(centre).unit().left();
                if ccw {
                    radial
                } else {
                    radial.scale(-1.0)
                }
            }
        }
    }

    /// `length_mm` along the element as a parameter difference.
    fn param_span(&self, length_mm: f64) -> f64 {
        match self.shape {
            Shape::Line { .. } => length_mm,
            Shape::Arc { .. } => length_mm / self.radius_start.min(self.radius_end),
        }
    }

    /// The parameter of `point` (on the element's line or circle); for arcs the turn
    /// nearest to `near`.
    fn param_of(&self, point: V2, near: f64) -> f64 {
        match self.shape {
            Shape::Line { origin, dir } => point.sub(origin).dot(dir),
            Shape::Arc { centre, ccw, theta0 } => {
                let turned = point.sub(centre).angle() - theta0;
                let turned = if ccw { turned } else { -turned };
                near + (turned - near + PI).rem_euclid(TAU) - PI
            }
        }
    }
}

/// How a move travels: rapid or at a feed (mm/min).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Travel {
    Rapid,
    Feed(f64),
}

/// A compensated move waiting for the next one, which decides where it ends.
#[derive(Clone, Debug)]
struct Pending {
    element: Element,
    /// The programmed point its end joins the next move at (XY).
    corner: V2,
    line: usize,
    n: Option<u32>,
    travel: Travel,
    /// The programmed start and end: the output keeps their Z and A.
    start: Point,
    end: Point,
    /// Blocks after it that do not move in XY, emitted after it at its final end.
    deferred: Vec<Block>,
}

/// Compensation state; `side` is +1 for G41 (left) and -1 for G42 (right), `radius`
/// the tool radius in mm.
#[derive(Clone, Debug)]
enum Mode {
    Off,
    /// G41/G42 read: the tool is still on the programmed path until the entry move.
    Starting {
        side: f64,
        radius: f64,
    },
    /// Compensating; `current` is the last move, its end not yet joined.
    On {
        side: f64,
        radius: f64,
        current: Box<Pending>,
    },
    /// G40 read while on: waiting for the exit move.
    Stopping {
        side: f64,
        radius: f64,
        current: Box<Pending>,
    },
}

/// The pass: the output so far and what it needs to know about the program so far.
struct Compensator<'a> {
    tools: Cow<'a, ToolTable>,
    out: Vec<Block>,
    /// The programmed (uncompensated) position.
    programmed: Point,
    /// The tool in the spindle (last M6), used when G41/G42 has no D word.
    spindle_tool: u32,
    /// The last programmed feed, mm/min, for corner arcs next to rapids.
    last_feed: Option<f64>,
    mode: Mode,
    /// From the tool nose's centre to the imaginary tool tip of a lathe tool (G41.1/G42.1
    /// L in G18), in the frame: added to every compensated point the pass emits.
    tip: V2,
}

/// Where a corner between two offset moves is resolved.
enum Join {
    /// The offsets meet (tangent moves, or both cut back to their intersection).
    Meet,
    /// An outside corner: an arc of the tool radius around the programmed corner.
    Arc { from: V2, to: V2 },
}

impl Compensator<'_> {
    fn comp_on(&self) -> bool {
        !matches!(self.mode, Mode::Off)
    }

    fn block(&mut self, block: &Block) -> Result<(), CompError> {
        match block.kind {
            BlockKind::CutterComp { side, tool, .. } => self.comp_change(block, side, tool, None, 0),
            BlockKind::CutterCompRadius { side, radius_mm, plane, orientation } => {
                // Only in G18: the interpreter refuses L in another plane.
                let orientation = if plane == Plane::Zx { orientation } else { 0 };
                self.comp_change(block, side, None, Some(radius_mm), orientation)
            }
            BlockKind::Rapid { .. } | BlockKind::Linear { .. } | BlockKind::Arc { .. } => self.motion(block),
            BlockKind::Nurbs { to, feed_mm_per_min, .. } => {
                if self.comp_on() {
                    return Err(CompError {
                        line: block.line,
                        reason: "NURBS (G5.2) with cutter compensation on: a NURBS is not offset (G40 and its exit move first)".into(),
                    });
                }
                self.programmed = to;
                self.last_feed = Some(feed_mm_per_min);
                self.out.push(block.clone());
                Ok(())
            }
            // The interpreter refuses a probe move with compensation on; the path goes on
            // from the probe move's end.
            BlockKind::Probe { to, feed_mm_per_min, .. } => {
                if !matches!(self.mode, Mode::Off) {
                    return Err(CompError {
                        line: block.line,
                        reason: "probe move (G38.x) before G40's exit move; move out of compensation first".into(),
                    });
                }
                self.programmed = to;
                self.last_feed = Some(feed_mm_per_min);
                self.out.push(block.clone());
                Ok(())
            }
            BlockKind::ToolChange { tool } => {
                if let Mode::Stopping { .. } = self.mode {
                    return Err(CompError {
                        line: block.line,
                        reason: "tool change (M6) after G40 before the exit move; move out of compensation first"
                            .into(),
                    });
                }
                if self.comp_on() {
                    return Err(CompError {
                        line: block.line,
                        reason: "tool change (M6) with cutter compensation on (G40 first)".into(),
                    });
                }
                self.spindle_tool = tool;
                self.out.push(block.clone());
                Ok(())
            }
            BlockKind::End => {
                self.flush();
                self.out.push(block.clone());
                Ok(())
            }
            _ => {
                match &mut self.mode {
                    Mode::On { current, .. } | Mode::Stopping { current, .. } => current.deferred.push(block.clone()),
                    Mode::Off | Mode::Starting { .. } => self.out.push(block.clone()),
                }
                Ok(())
            }
        }
    }

    /// G40, G41/G42 (the radius of tool `tool`, or of the tool in the spindle) or
    /// G41.1/G42.1 (`given_radius`, a lathe tool's `orientation` in G18).
    fn comp_change(
        &mut self,
        block: &Block,
        side: CompSide,
        tool: Option<u32>,
        given_radius: Option<f64>,
        orientation: u32,
    ) -> Result<(), CompError> {
        let fail = |reason: String| CompError { line: block.line, reason };
        let side = match side {
            CompSide::Off => {
                self.mode = match std::mem::replace(&mut self.mode, Mode::Off) {
                    Mode::On { side, radius, current } => Mode::Stopping { side, radius, current },
                    Mode::Off | Mode::Starting { .. } => Mode::Off,
                    stopping @ Mode::Stopping { .. } => stopping,
                };
                return Ok(());
            }
            CompSide::Left => 1.0,
            CompSide::Right => -1.0,
        };
        if matches!(self.mode, Mode::Starting { .. } | Mode::On { .. }) {
            return Err(fail("cutter compensation is already on (G40 first)".into()));
        }
        if let Mode::Stopping { .. } = self.mode {
            return Err(fail("G41/G42 after G40 before the exit move; move out of compensation first".into()));
        }
        let radius = match given_radius {
            Some(radius) => {
                if !(radius.is_finite() && radius >= 0.0) {
                    return Err(fail(format!("radius {radius} mm; a radius must be finite and not negative")));
                }
                radius
            }
            None => {
                let tool = tool.unwrap_or(self.spindle_tool);
                let radius =
                    self.tools.radius_mm(tool).ok_or_else(|| fail(format!("tool {tool} is not in the tool table")))?;
                if !(radius.is_finite() && radius >= 0.0) {
                    return Err(fail(format!(
                        "tool {tool} has radius {radius} mm; a radius must be finite and not negative"
                    )));
                }
                radius
            }
        };
        self.tip = lathe_tip(orientation, radius);
        self.mode = Mode::Starting { side, radius };
        Ok(())
    }

    fn motion(&mut self, block: &Block) -> Result<(), CompError> {
        let (to, travel) = match block.kind {
            BlockKind::Rapid { to } => (to, Travel::Rapid),
            BlockKind::Linear { to, feed_mm_per_min } | BlockKind::Arc { to, feed_mm_per_min, .. } => {
                (to, Travel::Feed(feed_mm_per_min))
            }
            _ => return Ok(()),
        };
        let from = self.programmed;
        let is_arc = matches!(block.kind, BlockKind::Arc { .. });
        let planar = is_arc || V2::of(&to).sub(V2::of(&from)).norm() > PLANAR_ZERO_MM;
        let feed_before = self.last_feed;
        if let Travel::Feed(feed) = travel {
            self.last_feed = Some(feed);
        }
        self.programmed = to;
        let fail = |reason: &str| CompError { line: block.line, reason: reason.into() };
        if let BlockKind::Arc { plane, .. } = block.kind {
            // (In the frame of the compensation's plane: see `compensate`.)
            if plane != Plane::Xy && self.comp_on() {
                return Err(fail("this arc is not in the plane cutter compensation was started in (G17 or G18)"));
            }
        }
        let (side, radius) = match self.mode {
            Mode::Off => {
                self.out.push(block.clone());
                return Ok(());
            }
            Mode::Starting { side, radius } | Mode::On { side, radius, .. } | Mode::Stopping { side, radius, .. } => {
                (side, radius)
            }
        };
        if radius == 0.0 {
            // A zero radius offsets nothing (the mode stays Starting): the path is the
            // programmed one.
            self.out.push(block.clone());
            return Ok(());
        }
        if !planar {
            match &mut self.mode {
                Mode::On { current, .. } | Mode::Stopping { current, .. } => current.deferred.push(block.clone()),
                _ => self.out.push(block.clone()),
            }
            return Ok(());
        }
        let pending = |element: Element, corner: V2| Pending {
            element,
            corner,
            line: block.line,
            n: block.n,
            travel,
            start: from,
            end: to,
            deferred: Vec::new(),
        };
        match std::mem::replace(&mut self.mode, Mode::Off) {
            // Handled above: the block was passed through.
            Mode::Off => {}
            Mode::Starting { .. } => {
                if is_arc {
                    return Err(fail("the entry move after G41/G42 must be a straight line (G0/G1), not an arc"));
                }
                let element = entry_element(V2::of(&from), V2::of(&to), side, radius, self.tools.entry_exit)
                    .map_err(|e| fail(&e.to_string()))?;
                let current = Box::new(pending(element, V2::of(&to)));
                self.mode = Mode::On { side, radius, current };
            }
            Mode::On { current, .. } => {
                let element = offset_element(block, &from, side, radius).map_err(|e| fail(&e.to_string()))?;
                let next = pending(element, V2::of(&to));
                let next = self.join_and_emit(*current, next, side, radius, feed_before)?;
                self.mode = Mode::On { side, radius, current: Box::new(next) };
            }
            Mode::Stopping { current, .. } => {
                if is_arc {
                    return Err(fail("the exit move after G40 must be a straight line (G0/G1), not an arc"));
                }
                if self.tools.entry_exit == EntryExit::LinuxCnc {
                    // Straight on from the last offset end point.
                    self.mode = Mode::Stopping { side, radius, current };
                    self.flush();
                    self.out.push(block.clone());
                    return Ok(());
                }
                let element =
                    exit_element(V2::of(&from), V2::of(&to), side, radius).map_err(|e| fail(&e.to_string()))?;
                let exit = pending(element, V2::of(&to));
                self.join_and_emit(*current, exit, side, radius, feed_before)?;
                // The exit line (its start possibly cut back, which does not change the
                // line) ends exactly on the programmed point.
                self.out.push(block.clone());
            }
        }
        Ok(())
    }

    /// Joins `current`'s end to `next`'s start, emits `current`, the blocks deferred
    /// after it and any corner arc, and returns `next` (its start possibly cut back).
    fn join_and_emit(
        &mut self,
        mut current: Pending,
        mut next: Pending,
        side: f64,
        radius: f64,
        feed_before: Option<f64>,
    ) -> Result<Pending, CompError> {
        let linuxcnc = self.tools.entry_exit == EntryExit::LinuxCnc;
        let join = join(&mut current, &mut next, side, radius, linuxcnc)?;
        let at = current.element.end.add(self.tip);
        self.emit(&current);
        for block in current.deferred.drain(..) {
            self.out.push(place_in_xy(block, at));
        }
        if let Join::Arc { from, to } = join {
            let feed = match (next.travel, current.travel, feed_before) {
                (Travel::Feed(f), _, _) | (Travel::Rapid, Travel::Feed(f), _) | (_, _, Some(f)) => f,
                _ => {
                    return Err(CompError {
                        line: next.line,
                        reason: "the corner arc before this rapid needs a feed rate; program a feed move (F) first"
                            .into(),
                    })
                }
            };
            let z_a = next.start;
            let tip = self.tip;
            let point = |p: V2| Point { x_mm: p.x + tip.x, y_mm: p.y + tip.y, ..z_a };
            let kind = if linuxcnc && next.travel == Travel::Rapid {
                // LinuxCNC rounds no corner at rapid: it goes straight to the arc's end.
                BlockKind::Rapid { to: point(to) }
            } else if to.sub(from).norm() < SHORT_ARC_CHORD_MM {
                BlockKind::Linear { to: point(to), feed_mm_per_min: feed }
            } else {
                BlockKind::Arc {
                    to: point(to),
                    centre: point(current.corner),
                    plane: Plane::Xy,
                    clockwise: side > 0.0,
                    extra_turns: 0,
                    feed_mm_per_min: feed,
                }
            };
            self.out.push(Block { line: next.line, n: next.n, kind });
        }
        Ok(next)
    }

    /// Emits a compensated move from wherever the tool is to its (final) end.
    fn emit(&mut self, pending: &Pending) {
        let element = &pending.element;
        let tip = self.tip;
        let end = element.end.add(tip);
        let to = Point { x_mm: end.x, y_mm: end.y, ..pending.end };
        let kind = match (element.shape, pending.travel) {
            // The tool stays at the centre: a move of length zero.
            (Shape::Arc { .. }, Travel::Feed(feed)) if element.is_pivot() => {
                BlockKind::Linear { to, feed_mm_per_min: feed }
            }
            (Shape::Line { .. }, Travel::Rapid) => BlockKind::Rapid { to },
            (Shape::Line { .. }, Travel::Feed(feed)) => BlockKind::Linear { to, feed_mm_per_min: feed },
            (Shape::Arc { centre, ccw, .. }, travel) => {
                let feed = match travel {
                    Travel::Feed(f) => f,
                    // Not reached (an arc is a feed move); a zero feed would be refused
                    // by the planner rather than run at a guessed speed.
                    Travel::Rapid => 0.0,
                };
                let sweep = element.end_param - element.start_param;
                if sweep < PI && element.end.sub(element.start).norm() < SHORT_ARC_CHORD_MM {
                    BlockKind::Linear { to, feed_mm_per_min: feed }
                } else {
                    let from_angle = element.start.sub(centre).angle();
                    let to_angle = element.end.sub(centre).angle();
                    let base = swept_angle(from_angle, to_angle, ccw, 0);
                    let extra = ((sweep - base) / TAU).round().max(0.0);
                    let centre = centre.add(tip);
                    BlockKind::Arc {
                        to,
                        centre: Point { x_mm: centre.x, y_mm: centre.y, ..pending.start },
                        plane: Plane::Xy,
                        clockwise: !ccw,
                        extra_turns: extra as u32,
                        feed_mm_per_min: feed,
                    }
                }
            }
        };
        self.out.push(Block { line: pending.line, n: pending.n, kind });
    }

    /// Ends compensation where the program ends: the last move stops at its offset end.
    fn flush(&mut self) {
        if let Mode::On { current, .. } | Mode::Stopping { current, .. } = std::mem::replace(&mut self.mode, Mode::Off)
        {
            let mut current = *current;
            let at = current.element.end.add(self.tip);
            self.emit(&current);
            for block in current.deferred.drain(..) {
                self.out.push(place_in_xy(block, at));
            }
        }
    }
}

/// A move of Z or A alone, moved to the tool's XY position `at`.
fn place_in_xy(mut block: Block, at: V2) -> Block {
    match &mut block.kind {
        BlockKind::Rapid { to } | BlockKind::Linear { to, .. } => {
            to.x_mm = at.x;
            to.y_mm = at.y;
        }
        _ => {}
    }
    block
}

/// From the centre of a lathe tool's nose of `radius` to its imaginary tool tip, for
/// LinuxCNC's tool `orientation` (1-8; 0, 9 and any other number: the centre itself),
/// in G18's frame (x is Z, y is X): X less the radius for 1, 2, 6, more for 3, 4, 8; Z
/// less for 2, 3, 7, more for 1, 4, 5 (`latheorigin_x`/`_z` in LinuxCNC's
/// interp_queue.cc). Compensation steers the nose's centre along the offset path, and the
/// machine's position is the imaginary tip's.
fn lathe_tip(orientation: u32, radius: f64) -> V2 {
    let x = match orientation {
        1 | 2 | 6 => -radius,
        3 | 4 | 8 => radius,
        _ => 0.0,
    };
    let z = match orientation {
        2 | 3 | 7 => -radius,
        1 | 4 | 5 => radius,
        _ => 0.0,
    };
    V2 { x: z, y: x }
}

/// The offset of a programmed line or arc from `from` (before any corner is cut back).
fn offset_element(block: &Block, from: &Point, side: f64, radius: f64) -> Result<Element, OffsetError> {
    let start = V2::of(from);
    match block.kind {
        BlockKind::Arc { to, centre, clockwise, extra_turns, .. } => {
            let (end, centre) = (V2::of(&to), V2::of(&centre));
            let ccw = !clockwise;
            let (r0, r1) = (start.sub(centre).norm(), end.sub(centre).norm());
            // Left of a counter-clockwise arc is towards its centre.
            let shrink = side * if ccw { 1.0 } else { -1.0 };
            let (r0_off, r1_off) = (r0 - shrink * radius, r1 - shrink * radius);
            // A concave arc as small as the tool: the tool pivots at its centre (LinuxCNC
            // prints an arc of radius zero), accepted where both neighbours meet there.
            let pivot = r0_off.abs() <= JOIN_TOLERANCE_MM && r1_off.abs() <= JOIN_TOLERANCE_MM && r0 > 0.0 && r1 > 0.0;
            if !pivot && (r0_off.min(r1_off) <= JOIN_TOLERANCE_MM || !(r0 > 0.0 && r1 > 0.0)) {
                let arc = r0.min(r1);
                let relation = if radius > arc + JOIN_TOLERANCE_MM { "is larger than" } else { "equals" };
                return Err(OffsetError::ConcaveArc { radius, relation, arc });
            }
            let theta0 = start.sub(centre).angle();
            let sweep = swept_angle(theta0, end.sub(centre).angle(), ccw, extra_turns);
            if pivot {
                return Ok(Element {
                    shape: Shape::Arc { centre, ccw, theta0 },
                    start: centre,
                    start_param: 0.0,
                    end: centre,
                    end_param: sweep,
                    radius_start: 0.0,
                    radius_end: 0.0,
                });
            }
            Ok(Element {
                shape: Shape::Arc { centre, ccw, theta0 },
                start: centre.add(start.sub(centre).scale(r0_off / r0)),
                start_param: 0.0,
                end: centre.add(end.sub(centre).scale(r1_off / r1)),
                end_param: sweep,
                radius_start: r0_off,
                radius_end: r1_off,
            })
        }
        BlockKind::Rapid { to } | BlockKind::Linear { to, .. } => {
            let end = V2::of(&to);
            let dir = end.sub(start).unit();
            let offset = dir.left().scale(side * radius);
            Ok(Element::line(start.add(offset), end.add(offset), dir))
        }
        _ => Err(OffsetError::NotAMove),
    }
}

/// The entry line from `from` (uncompensated): with [`EntryExit::Tangent`] to the
/// tangent point on the circle of `radius` around `to`, on the compensation side; with
/// [`EntryExit::LinuxCnc`] to `to` plus `radius` along the normal of `to - from`, its
/// shape (for the join with the next move) the offset of the programmed line through
/// that point.
fn entry_element(from: V2, to: V2, side: f64, radius: f64, style: EntryExit) -> Result<Element, OffsetError> {
    let length = to.sub(from).norm();
    if length <= radius + JOIN_TOLERANCE_MM {
        return Err(OffsetError::TooShort { which: "entry move after G41/G42", length, radius });
    }
    if style == EntryExit::LinuxCnc {
        let dir = to.sub(from).unit();
        let end = to.add(dir.left().scale(side * radius));
        return Ok(Element {
            shape: Shape::Line { origin: end, dir },
            start: from,
            start_param: from.sub(end).dot(dir),
            end,
            end_param: 0.0,
            radius_start: 0.0,
            radius_end: 0.0,
        });
    }
    let dir = to.sub(from).unit().rotate(side * (radius / length).asin());
    let end = to.add(dir.left().scale(side * radius));
    Ok(Element::line(from, end, dir))
}

/// The exit line from the tangent point on the circle of `radius` around `from` (on
/// the compensation side) to `to` exactly.
fn exit_element(from: V2, to: V2, side: f64, radius: f64) -> Result<Element, OffsetError> {
    let length = to.sub(from).norm();
    if length <= radius + JOIN_TOLERANCE_MM {
        return Err(OffsetError::TooShort { which: "exit move after G40", length, radius });
    }
    let dir = to.sub(from).unit().rotate(-side * (radius / length).asin());
    let start = from.add(dir.left().scale(side * radius));
    Ok(Element::line(start, to, dir))
}

/// Resolves the corner at `a.corner` between `a`'s end and `b`'s start: meet, cut both
/// back to their intersection, or leave them and insert an arc; with `linuxcnc`
/// ([`EntryExit::LinuxCnc`]) a corner within [`LINUXCNC_TANGENT_RAD`] of tangent is left
/// as it is.
fn join(a: &mut Pending, b: &mut Pending, side: f64, radius: f64, linuxcnc: bool) -> Result<Join, CompError> {
    let corner = a.corner;
    let (a_end, b_start) = (a.element.end, b.element.start);
    if a_end.sub(b_start).norm() <= JOIN_TOLERANCE_MM {
        b.element.start = a_end;
        return Ok(Join::Meet);
    }
    // A pivot (a concave arc as small as the tool) has no tangent: its neighbours must
    // meet at its centre.
    for (pending, other) in [(&*a, &*b), (&*b, &*a)] {
        if pending.element.is_pivot() {
            return Err(CompError {
                line: pending.line,
                reason: format!(
                    "tool radius {} mm equals this concave arc's radius: the tool can only pivot at its centre, and the move on line {} does not meet it there",
                    mm(radius),
                    other.line
                ),
            });
        }
    }
    let ta = a.element.tangent_at(a_end);
    let tb = b.element.tangent_at(b_start);
    let turn = ta.cross(tb);
    if linuxcnc && turn.atan2(ta.dot(tb)).abs() <= LINUXCNC_TANGENT_RAD {
        // LinuxCNC's nearly tangent corner: each move keeps its offset end.
        return Ok(Join::Meet);
    }
    let reversal = ta.dot(tb) < 0.0 && turn.abs() <= REVERSAL_SINE;
    if side * turn < 0.0 || reversal {
        return Ok(Join::Arc { from: a_end, to: b_start });
    }
    let too_large = |line: usize, what: &str| CompError {
        line,
        reason: format!("tool radius {} mm is too large here: {what}", mm(radius)),
    };
    let candidates = match (linuxcnc, a.element.shape, b.element.shape) {
        (true, Shape::Line { dir, .. }, Shape::Arc { centre, ccw, .. }) => {
            linuxcnc_line_to_arc(corner, dir, centre, ccw, b.element.radius_end, side, radius).into_iter().collect()
        }
        // LinuxCNC's arc after an arc: the second arc's offset circle has its end's radius.
        (true, Shape::Arc { .. }, Shape::Arc { .. }) => {
            let b_circle = Element { radius_start: b.element.radius_end, ..b.element };
            intersections(&a.element, &b_circle, corner, side, radius)
        }
        _ => intersections(&a.element, &b.element, corner, side, radius),
    };
    let meet = candidates
        .into_iter()
        .filter(|p| p.x.is_finite() && p.y.is_finite())
        .min_by(|p, q| {
            let cost = |v: &V2| v.sub(a_end).norm() + v.sub(b_start).norm();
            cost(p).total_cmp(&cost(q))
        })
        .ok_or_else(|| too_large(b.line, "the offset paths at the inside corner before this move do not meet"))?;

    // Cut back: the crossing must not lie before the start of the first move (its
    // offset would run backwards) nor after the end of the second. It may lie a little
    // beyond the first move's offset end or before the second's offset start, where
    // near-tangent crossings are ill-conditioned: that bit is still at least the tool
    // radius from both moves.
    let ea = &a.element;
    let new_end = ea.param_of(meet, ea.end_param);
    if new_end < ea.start_param - ea.param_span(JOIN_TOLERANCE_MM) {
        return Err(too_large(
            a.line,
            "the compensated path of this move vanishes between its corners (it would gouge)",
        ));
    }
    if new_end > ea.end_param + ea.param_span(EXTENSION_TOLERANCE_MM) {
        return Err(too_large(b.line, "the offset paths at the inside corner before this move do not meet"));
    }
    let eb = &b.element;
    let new_start = eb.param_of(meet, eb.start_param);
    if new_start > eb.end_param + eb.param_span(JOIN_TOLERANCE_MM) {
        return Err(too_large(
            b.line,
            "the compensated path of this move vanishes between its corners (it would gouge)",
        ));
    }
    if new_start < eb.start_param - eb.param_span(EXTENSION_TOLERANCE_MM) {
        return Err(too_large(b.line, "the offset paths at the inside corner before this move do not meet"));
    }
    a.element.end = meet;
    a.element.end_param = new_end.max(a.element.start_param);
    b.element.start = meet;
    b.element.start_param = new_start.min(b.element.end_param);
    Ok(Join::Meet)
}

/// Where LinuxCNC 2.9's interpreter ends a line at the inside corner before an arc
/// (`convert_arc_comp2`, line to arc): on the arc's offset circle (radius `offset_end`, the
/// offset radius at the arc's end) at the angle its formula gives from the line's
/// direction `dir`, the programmed `corner` and the arc's radius at its end. Where the
/// arc's radius at its start differs from its end's (by up to the front end's arc
/// tolerance) the point lies that much off the line's offset; otherwise it is their
/// crossing. `side` +1 for G41, -1 for G42; `radius` the tool's.
fn linuxcnc_line_to_arc(
    corner: V2,
    dir: V2,
    centre: V2,
    ccw: bool,
    offset_end: f64,
    side: f64,
    radius: f64,
) -> Option<V2> {
    use std::f64::consts::FRAC_PI_2;
    // The tool inside the arc (G41 and G3, G42 and G2): the offset circle is smaller.
    let inside = (side > 0.0) == ccw;
    let arc_radius = if inside { offset_end + radius } else { offset_end - radius };
    let theta = dir.angle();
    let delta = centre.sub(corner).angle();
    let alpha = if ccw { delta - FRAC_PI_2 } else { delta + FRAC_PI_2 };
    let beta = if side > 0.0 { theta - alpha } else { alpha - theta };
    let beta = if beta > 1.5 * PI {
        beta - TAU
    } else if beta < -FRAC_PI_2 {
        beta + TAU
    } else {
        beta
    };
    let along = arc_radius * (beta - FRAC_PI_2).sin();
    let (distance, angle) = if inside {
        let l = (along + radius) / offset_end;
        let turn = l.asin();
        (offset_end, if ccw { theta + turn } else { theta - turn })
    } else {
        let l = (along - radius) / offset_end;
        let turn = l.asin();
        (offset_end, if ccw { theta + PI - turn } else { theta + PI + turn })
    };
    let point = centre.add(V2 { x: angle.cos(), y: angle.sin() }.scale(distance));
    (point.x.is_finite() && point.y.is_finite()).then_some(point)
}

/// Where the lines and circles of two offset moves cross, near the corner.
fn intersections(a: &Element, b: &Element, corner: V2, side: f64, radius: f64) -> Vec<V2> {
    match (a.shape, b.shape) {
        (Shape::Line { dir: da, .. }, Shape::Line { dir: db, .. }) => {
            // Both lines are tangent to the circle of `radius` around the corner on the
            // compensation side; their crossing is on the bisector (well conditioned).
            let (na, nb) = (da.left(), db.left());
            let denominator = 1.0 + na.dot(nb);
            if denominator <= f64::EPSILON {
                return Vec::new();
            }
            vec![corner.add(na.add(nb).scale(side * radius / denominator))]
        }
        (Shape::Line { origin, dir }, Shape::Arc { centre, .. }) => line_circle(origin, dir, centre, b.radius_start),
        (Shape::Arc { centre, .. }, Shape::Line { origin, dir }) => line_circle(origin, dir, centre, a.radius_end),
        (Shape::Arc { centre: ca, .. }, Shape::Arc { centre: cb, .. }) => {
            circle_circle(ca, a.radius_end, cb, b.radius_start)
        }
    }
}

fn line_circle(origin: V2, dir: V2, centre: V2, radius: f64) -> Vec<V2> {
    let foot = origin.sub(dir.scale(origin.sub(centre).dot(dir)));
    let distance = foot.sub(centre).norm();
    if distance > radius + JOIN_TOLERANCE_MM {
        return Vec::new();
    }
    let half_chord = (radius * radius - distance * distance).max(0.0).sqrt();
    vec![foot.add(dir.scale(half_chord)), foot.sub(dir.scale(half_chord))]
}

fn circle_circle(c1: V2, r1: f64, c2: V2, r2: f64) -> Vec<V2> {
    let d = c2.sub(c1).norm();
    if d <= JOIN_TOLERANCE_MM || d > r1 + r2 + JOIN_TOLERANCE_MM || d < (r1 - r2).abs() - JOIN_TOLERANCE_MM {
        return Vec::new();
    }
    let u = c2.sub(c1).scale(1.0 / d);
    let along = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
    let half_chord = (r1 * r1 - along * along).max(0.0).sqrt();
    let mid = c1.add(u.scale(along));
    vec![mid.add(u.left().scale(half_chord)), mid.sub(u.left().scale(half_chord))]
}
