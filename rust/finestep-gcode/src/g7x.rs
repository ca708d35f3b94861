//! The lathe cycles G70 (finishing) and G71/G72 (roughing, with their .1 and .2
//! variants) as LinuxCNC 2.9 defines them: the geometry of the profile and the moves
//! each cycle makes of it.
//!
//! The profile is the motion of the Q subroutine in the XZ plane (program frame and
//! units), read into [`Segment`]s instead of moving (see `program.rs`). A point is a
//! [`Pt`] with `z` along the spindle and `x` across it, as LinuxCNC's own cycle code
//! holds it (Z the real part, X the imaginary one of a complex number), so that its
//! rotations and flips are the same arithmetic:
//!
//! - The profile is turned to one canonical quadrant (X and Z both decreasing along it;
//!   G72 first rotates it by 90 degrees so that it faces instead of turning), the moves
//!   are computed there and turned back as they are emitted.
//! - D (G71/G72: stock to leave; G70: distance of the first pass, E of the last) offsets
//!   the profile: each segment moves along its normal in steps of at most half the
//!   shortest segment, corners opened by the step are closed with an arc, segments that
//!   vanish or turn back are dropped and neighbours re-intersected.
//! - Roughing cuts layers I deep parallel to Z, each ended by a retract R at 45 degrees
//!   and a rapid back; where the profile dives, the tool follows it down, and a pocket
//!   (the profile climbing again) is cut after its layers, unless .1 (no pockets); .2
//!   cuts only the pockets .1 left.
//! - A and C after a profile move round (fillet of radius A) or chamfer (C) the corner.
//!
//! Errors are LinuxCNC's: the profile must be monotonic in the canonical quadrant ("Not
//! monotonic"), and so on, with the same words.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// Positions closer than this are the same (program units), as in LinuxCNC's cycle code.
const TOLERANCE: f64 = 1e-6;

/// A cycle makes at most this many moves (a depth of cut or a pass count far too
/// small for the profile is refused rather than run for ever).
pub(crate) const MAX_MOVES: usize = 1_000_000;

fn check_size(out: &[Move]) -> Result<()> {
    if out.len() > MAX_MOVES {
        return fail(format!("the cycle makes more than {MAX_MOVES} moves (I or P too small for the profile?)"));
    }
    Ok(())
}

/// A point of the XZ plane: `z` along the spindle (the real part), `x` across it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Pt {
    pub z: f64,
    pub x: f64,
}

impl Pt {
    pub(crate) const fn new(z: f64, x: f64) -> Pt {
        Pt { z, x }
    }
    fn conj(self) -> Pt {
        Pt::new(self.z, -self.x)
    }
    fn norm(self) -> f64 {
        self.z * self.z + self.x * self.x
    }
    fn abs(self) -> f64 {
        self.z.hypot(self.x)
    }
    fn scale(self, f: f64) -> Pt {
        Pt::new(self.z * f, self.x * f)
    }
    fn div_real(self, f: f64) -> Pt {
        Pt::new(self.z / f, self.x / f)
    }
    /// Multiplied by i (a quarter turn counter-clockwise).
    fn times_i(self) -> Pt {
        Pt::new(-self.x, self.z)
    }
}

impl Add for Pt {
    type Output = Pt;
    fn add(self, o: Pt) -> Pt {
        Pt::new(self.z + o.z, self.x + o.x)
    }
}
impl Sub for Pt {
    type Output = Pt;
    fn sub(self, o: Pt) -> Pt {
        Pt::new(self.z - o.z, self.x - o.x)
    }
}
impl Neg for Pt {
    type Output = Pt;
    fn neg(self) -> Pt {
        Pt::new(-self.z, -self.x)
    }
}
/// The complex product.
impl Mul for Pt {
    type Output = Pt;
    fn mul(self, o: Pt) -> Pt {
        Pt::new(self.z * o.z - self.x * o.x, self.z * o.x + self.x * o.z)
    }
}
/// The complex quotient, by Smith's algorithm as the C library LinuxCNC is built with
/// computes it (libgcc's `__divdc3`): the cycle tests the sign of a quotient's
/// imaginary part that is zero but for rounding (which way to offset a profile whose
/// lead-in runs along its first segment), so the rounding must be the same.
impl Div for Pt {
    type Output = Pt;
    fn div(self, o: Pt) -> Pt {
        let (a, b, c, d) = (self.z, self.x, o.z, o.x);
        if c.abs() < d.abs() {
            let ratio = c / d;
            let denom = c * ratio + d;
            Pt::new((a * ratio + b) / denom, (b * ratio - a) / denom)
        } else {
            let ratio = d / c;
            let denom = d * ratio + c;
            Pt::new((b * ratio + a) / denom, (b - a * ratio) / denom)
        }
    }
}

/// How a segment moves.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    Straight,
    Arc { ccw: bool, centre: Pt },
}

/// A corner rounding (A) or chamfer (C) not yet fitted between its neighbours.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Corner {
    Fillet,
    Chamfer,
}

/// One move of the profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Segment {
    start: Pt,
    end: Pt,
    shape: Shape,
    /// The corner's size (A or C), while `corner` is set and for a chamfer after.
    finish: f64,
    corner: Option<Corner>,
}

/// One move of a cycle's output, in the program frame and units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Move {
    Rapid(Pt),
    Feed(Pt),
    Arc { ccw: bool, centre: Pt, end: Pt },
}

/// A lathe cycle (G70, G71, G72 and their .1 .2) waiting for its profile: its words and
/// start point in the program frame and units (X a radius).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LatheCycle {
    /// G70 is 700, G71.1 711, ...
    pub code: u32,
    /// The column of the G word.
    pub column: usize,
    /// The Q word: the profile's subroutine, and its column.
    pub q: (f64, usize),
    pub start: Pt,
    pub d: f64,
    pub e: f64,
    pub i: f64,
    pub p: f64,
    pub r: f64,
    pub u: f64,
    pub w: f64,
}

/// The profile of a lathe cycle being read: the motion of its Q subroutine, made into
/// segments instead of moves (LinuxCNC reads only the motion words there).
#[derive(Debug, Clone)]
pub(crate) struct ProfileReader {
    pub segments: Vec<Segment>,
    /// Where the profile is (program frame and units).
    pub at: Pt,
    /// The motion mode in the profile (G0 at first: the cycle's move to its start).
    pub(crate) motion: u32,
}

impl ProfileReader {
    pub(crate) fn new(start: Pt) -> ProfileReader {
        ProfileReader { segments: Vec::new(), at: start, motion: 0 }
    }
}

/// The moves of `cycle` made of its profile `segments`. (LinuxCNC's later versions
/// close a profile that ends short of the start point with one more segment before
/// offsetting it; 2.9's, which finestep follows, closes it in the canonical quadrant
/// only, after the offset: [`Profile::g71`].)
pub(crate) fn cycle_moves(cycle: &LatheCycle, segments: Vec<Segment>) -> Result<Vec<Move>> {
    if segments.len() <= 1 {
        return Ok(Vec::new());
    }
    let start = cycle.start;
    let sub = (cycle.code % 10) as u8;
    let shift = Pt::new(cycle.w, cycle.u);
    let profile = Profile::new(segments);
    let moves = match cycle.code / 10 {
        70 => profile.g70(start, cycle.d, cycle.e, cycle.p),
        71 => profile.g71(false, sub, start, shift, cycle.d, cycle.i, cycle.r),
        _ => profile.g71(true, sub, start, shift, cycle.d, cycle.i, cycle.r),
    }?;
    let finite = |p: Pt| p.z.is_finite() && p.x.is_finite();
    let all_finite = moves.iter().all(|m| match *m {
        Move::Rapid(p) | Move::Feed(p) => finite(p),
        Move::Arc { centre, end, .. } => finite(centre) && finite(end),
    });
    if !all_finite {
        return fail("the profile's geometry degenerates (an arc whose R is shorter than half its chord?)");
    }
    Ok(moves)
}

/// A cycle that cannot be made of its profile; the message is LinuxCNC's.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CycleError(pub String);

type Result<T> = std::result::Result<T, CycleError>;

fn fail<T>(message: impl Into<String>) -> Result<T> {
    Err(CycleError(message.into()))
}

impl Segment {
    pub(crate) fn straight(start: Pt, end: Pt) -> Segment {
        Segment { start, end, shape: Shape::Straight, finish: 0.0, corner: None }
    }
    pub(crate) fn arc(ccw: bool, start: Pt, centre: Pt, end: Pt) -> Segment {
        Segment { start, end, shape: Shape::Arc { ccw, centre }, finish: 0.0, corner: None }
    }
    /// A rounding of radius `r` of the corner at `at` (A on a profile move).
    pub(crate) fn fillet(r: f64, at: Pt) -> Segment {
        Segment {
            start: at,
            end: at,
            shape: Shape::Arc { ccw: false, centre: at },
            finish: r,
            corner: Some(Corner::Fillet),
        }
    }
    /// A chamfer of size `c` of the corner at `at` (C on a profile move).
    pub(crate) fn chamfer(c: f64, at: Pt) -> Segment {
        Segment { start: at, end: at, shape: Shape::Straight, finish: c, corner: Some(Corner::Chamfer) }
    }

    fn radius(&self) -> f64 {
        match self.shape {
            Shape::Straight => (self.start - self.end).abs(),
            Shape::Arc { centre, .. } => (self.start - self.end).abs().min((self.start - centre).abs()),
        }
    }

    /// Whether the segment keeps going the canonical way (Z decreasing; an arc also
    /// on one side of its centre).
    fn monotonic(&self) -> bool {
        match self.shape {
            Shape::Straight => (self.end - self.start).z <= 1e-3,
            Shape::Arc { ccw, centre } => {
                if self.finish != 0.0 {
                    return true;
                }
                let entry = (self.start - centre).x;
                let exit = (self.end - centre).x;
                let dz = (self.end - self.start).z;
                if ccw {
                    entry >= -1e-3 && exit >= -1e-3 && dz <= -1e-3
                } else {
                    entry <= 1e-3 && exit <= 1e-3 && dz <= -1e-3
                }
            }
        }
    }

    fn map(&mut self, f: impl Fn(Pt) -> Pt, mirror: bool) {
        self.start = f(self.start);
        self.end = f(self.end);
        if let Shape::Arc { ccw, centre } = self.shape {
            self.shape = Shape::Arc { ccw: ccw != mirror, centre: f(centre) };
        }
    }
    fn flip_x(&mut self) {
        self.map(Pt::conj, true)
    }
    fn flip_z(&mut self) {
        self.map(|p| -p.conj(), true)
    }
    fn rotate(&mut self) {
        self.map(|p| -p.times_i(), false)
    }
    fn shift(&mut self, d: Pt) {
        self.map(|p| p + d, false)
    }

    /// Moves the segment `distance` along its normal (an arc: its radius grows by it
    /// when counter-clockwise, shrinks when clockwise).
    fn offset(&mut self, distance: f64) {
        match self.shape {
            Shape::Straight => {
                let d = ((self.start - self.end) * Pt::new(0.0, distance)).div_real((self.start - self.end).abs());
                self.start = self.start + d;
                self.end = self.end + d;
            }
            Shape::Arc { ccw, centre } => {
                let r = (self.start - centre).abs();
                let factor = (r + if ccw { distance } else { -distance }) / r;
                self.start = (self.start - centre).scale(factor) + centre;
                self.end = (self.end - centre).scale(factor) + centre;
            }
        }
    }

    /// Whether `p` lies within the arc's sweep.
    fn on_arc(&self, ccw: bool, centre: Pt, p: Pt) -> bool {
        let from_start = ((self.start - centre).conj() * (p - centre)).x;
        let from_end = ((self.end - centre).conj() * (p - centre)).x;
        if ccw {
            from_start >= -TOLERANCE && from_end <= TOLERANCE
        } else {
            from_start <= TOLERANCE && from_end >= -TOLERANCE
        }
    }

    /// The Z where the segment crosses the line at height `x` (both ends of a
    /// segment lying on it).
    fn crossings(&self, x: f64) -> Vec<f64> {
        let mut out = Vec::new();
        match self.shape {
            Shape::Straight => {
                let (s, e) = (self.start, self.end);
                if s.x.min(e.x) > x + TOLERANCE || s.x.max(e.x) < x - TOLERANCE {
                    return out;
                }
                if (s - e).x.abs() < TOLERANCE {
                    out.push(s.z);
                    out.push(e.z);
                } else {
                    out.push((x - s.x) / (e.x - s.x) * (e.z - s.z) + s.z);
                }
            }
            Shape::Arc { ccw, centre } => {
                let r = (self.start - centre).abs();
                let mut s = -(x - r - centre.x) * (x + r - centre.x);
                if s < -TOLERANCE {
                    return out;
                }
                if s < 0.0 {
                    s = 0.0;
                }
                let s = s.sqrt();
                for z in [centre.z + s, centre.z - s] {
                    if self.on_arc(ccw, centre, Pt::new(z, x)) {
                        out.push(z);
                    }
                }
            }
        }
        out
    }

    fn draw(&self, out: &mut Vec<Move>) {
        out.push(match self.shape {
            Shape::Straight => Move::Feed(self.end),
            Shape::Arc { ccw, centre } => Move::Arc { ccw, centre, end: self.end },
        })
    }

    /// Follows the profile up (X increasing) from `location`; true when the segment
    /// does not climb (a pocket's far wall has ended).
    fn climb(&self, location: &mut Pt, out: &mut Vec<Move>) -> Result<bool> {
        match self.shape {
            Shape::Straight => {
                if self.end.x + TOLERANCE < self.start.x {
                    return Ok(true);
                }
                if (*location - self.start).abs() > TOLERANCE {
                    return fail("How did we get here?");
                }
                out.push(Move::Feed(self.end));
                *location = self.end;
                Ok(false)
            }
            Shape::Arc { ccw: false, centre } => {
                if location.z > centre.z {
                    return Ok(true);
                }
                if (*location - self.end).abs() > 1e-3 {
                    out.push(Move::Arc { ccw: false, centre, end: self.end });
                }
                *location = self.end;
                Ok(false)
            }
            Shape::Arc { ccw: true, centre } => {
                if location.z < centre.z {
                    return Ok(true);
                }
                let top = self.climb_top(centre);
                if (*location - top).abs() > 1e-3 {
                    out.push(Move::Arc { ccw: true, centre, end: top });
                }
                *location = top;
                Ok(true)
            }
        }
    }

    /// Where a counter-clockwise arc stops climbing: its end, or its top.
    fn climb_top(&self, centre: Pt) -> Pt {
        if self.end.z < centre.z {
            Pt::new(centre.z, centre.x + (self.start - centre).abs())
        } else {
            self.end
        }
    }

    /// Climbs from the layer at `location` only (cycle .1: no pockets).
    fn climb_only(&self, location: &mut Pt, out: &mut Vec<Move>) {
        let is = self.crossings(location.x);
        if is.is_empty() {
            return;
        }
        match self.shape {
            Shape::Straight => {
                if self.end.x < self.start.x {
                    return;
                }
                location.z = is[0];
                out.push(Move::Feed(*location));
                out.push(Move::Feed(self.end));
                *location = self.end;
            }
            Shape::Arc { ccw: false, centre } => {
                let last = *is.last().expect("a crossing");
                if last > centre.z {
                    return;
                }
                location.z = last;
                out.push(Move::Feed(*location));
                if (*location - self.end).abs() > 1e-3 {
                    out.push(Move::Arc { ccw: false, centre, end: self.end });
                }
                *location = self.end;
            }
            Shape::Arc { ccw: true, centre } => {
                if is[0] < centre.z {
                    return;
                }
                location.z = is[0];
                out.push(Move::Feed(*location));
                let top = self.climb_top(centre);
                if (*location - top).abs() > 1e-3 {
                    out.push(Move::Arc { ccw: true, centre, end: top });
                }
                *location = top;
            }
        }
    }

    /// Follows the profile down to the layer at `x` (a rapid along the first segment
    /// when `fast`); true when the segment does not dive.
    fn dive(&self, location: &mut Pt, x: f64, out: &mut Vec<Move>, fast: bool) -> Result<bool> {
        match self.shape {
            Shape::Straight => {
                if self.start.x <= self.end.x + TOLERANCE {
                    return Ok(true);
                }
                let to = if x < self.end.x {
                    self.end
                } else {
                    match self.crossings(x).first() {
                        Some(&z) => Pt::new(z, x),
                        None => return fail("x too large in straight dive"),
                    }
                };
                out.push(if fast { Move::Rapid(to) } else { Move::Feed(to) });
                *location = to;
                Ok(false)
            }
            Shape::Arc { ccw, centre } => {
                if (*location - self.end).abs() < TOLERANCE || (*location - self.end).z <= TOLERANCE {
                    *location = self.end;
                    return Ok(false);
                }
                let mut is = self.crossings(x);
                if is.is_empty() {
                    is = self.crossings(x - TOLERANCE);
                }
                if ccw {
                    if location.z - TOLERANCE > centre.z {
                        return Ok(true);
                    }
                    match is.last() {
                        Some(&z) if z <= centre.z => {
                            let to = Pt::new(z, x);
                            out.push(Move::Arc { ccw, centre, end: to });
                            *location = to;
                        }
                        _ => {
                            out.push(Move::Arc { ccw, centre, end: self.end });
                            *location = self.end;
                        }
                    }
                } else {
                    if location.z <= centre.z {
                        return Ok(true);
                    }
                    match is.first() {
                        None => {
                            out.push(Move::Arc { ccw, centre, end: self.end });
                            *location = self.end;
                        }
                        // Crossed on the far side only: the layer steps down.
                        Some(&z) if z < centre.z => {}
                        Some(&z) => {
                            let to = Pt::new(z, x);
                            out.push(Move::Arc { ccw, centre, end: to });
                            *location = to;
                        }
                    }
                }
                Ok(false)
            }
        }
    }
}

/// Corrects the end of `p` and the start of `n` to where the two meet.
fn intersect(p: &mut Segment, n: &mut Segment) -> Result<()> {
    match (p.shape, n.shape) {
        (Shape::Straight, Shape::Straight) => {
            let rot = (n.start - n.end).conj().div_real((n.start - n.end).abs());
            let ps = (p.start - n.end) * rot;
            let pe = (p.end - n.end) * rot;
            if (ps - pe).x == 0.0 {
                return fail("Cannot intersect parallel lines");
            }
            let f = ps.x / (ps - pe).x;
            let is = (ps + (pe - ps).scale(f)) / rot + n.end;
            n.start = is;
            p.end = is;
        }
        (Shape::Arc { centre, .. }, Shape::Straight) => {
            if (n.start - p.end).abs() < TOLERANCE {
                return Ok(());
            }
            let is = line_circle(n.start, n.end, n.end, p.end, centre, n.start);
            n.start = is;
            p.end = is;
        }
        (Shape::Straight, Shape::Arc { centre, .. }) => {
            if (n.start - p.end).abs() < TOLERANCE {
                return Ok(());
            }
            let is = line_circle(p.start, p.end, p.end, n.end, centre, n.start);
            n.start = is;
            p.end = is;
        }
        (Shape::Arc { centre: pc, .. }, Shape::Arc { centre: nc, .. }) => {
            let a = (n.start - nc).abs();
            let b = (p.start - pc).abs();
            let c = (nc - pc).abs();
            let cos_b = (c * c + a * a - b * b) / 2.0 / a / c;
            let cos_b2 = (cos_b * cos_b).min(1.0);
            let rot = Pt::new(cos_b, (1.0 - cos_b2).sqrt());
            let is = (rot * (pc - nc)).div_real(c).scale(a) + nc;
            p.end = is;
            n.start = is;
        }
    }
    Ok(())
}

/// Where the line through `from`-`to` meets the circle about `centre` through
/// `on_circle`, of the two crossings the nearer to `near` (the line's frame is at
/// `origin`, on it).
fn line_circle(from: Pt, to: Pt, origin: Pt, on_circle: Pt, centre: Pt, near: Pt) -> Pt {
    let rot = (from - to).conj().div_real((from - to).abs());
    let pe = (on_circle - origin) * rot;
    let pc = (centre - origin) * rot;
    let b = (pc - pe).norm() - pc.x * pc.x;
    let b = if b < 0.0 { 0.0 } else { b.sqrt() };
    let s1 = Pt::new(pc.z + b, 0.0) / rot + origin;
    let s2 = Pt::new(pc.z - b, 0.0) / rot + origin;
    if (near - s1).abs() < (near - s2).abs() {
        s1
    } else {
        s2
    }
}

/// A profile being turned into a cycle's moves.
#[derive(Debug, Clone)]
pub(crate) struct Profile {
    segments: Vec<Segment>,
    /// Bit 0: Z flipped, bit 1: X flipped, bit 2: rotated (LinuxCNC's `flip_state`).
    flip: u8,
    delta: f64,
    escape: Pt,
    pocket_starts: Vec<Pt>,
}

impl Profile {
    /// The profile of `segments`, the first of which leads from the cycle's start point
    /// to the profile.
    pub(crate) fn new(segments: Vec<Segment>) -> Profile {
        Profile { segments, flip: 0, delta: 0.5, escape: Pt::new(0.3, 0.3), pocket_starts: Vec::new() }
    }

    fn rotate(&mut self) {
        self.segments.iter_mut().for_each(Segment::rotate);
        self.flip ^= 4;
    }

    /// Flips the profile so that X and Z decrease along it.
    fn swap(&mut self) {
        let (first, last) = (self.segments[0].end, self.segments[self.segments.len() - 1].end);
        let dir = first - last;
        if dir.x > 0.0 {
            self.segments.iter_mut().for_each(Segment::flip_x);
            self.flip ^= 2;
        }
        if dir.z < 0.0 {
            self.segments.iter_mut().for_each(Segment::flip_z);
            self.flip ^= 1;
        }
    }

    /// A move of the canonical quadrant back in the program's.
    fn unflip(&self, m: Move) -> Move {
        let f = |p: Pt| match self.flip {
            0 => p,
            1 => -p.conj(),
            2 => p.conj(),
            3 => -p,
            4 => p.times_i(),
            5 => p.times_i().conj(),
            6 => -p.times_i().conj(),
            _ => -p.times_i(),
        };
        let mirror = matches!(self.flip, 1 | 2 | 5 | 6);
        match m {
            Move::Rapid(p) => Move::Rapid(f(p)),
            Move::Feed(p) => Move::Feed(f(p)),
            Move::Arc { ccw, centre, end } => Move::Arc { ccw: ccw != mirror, centre: f(centre), end: f(end) },
        }
    }

    fn check_monotonic(&mut self) -> Result<()> {
        // The corners' fitting drops segments shorter than the tolerance: a profile of
        // such moves alone has nothing left to cut.
        let Some(first) = self.segments.first_mut() else {
            return fail("the profile has no move longer than the tolerance");
        };
        if (first.end - first.start).z > 0.0 {
            first.start.z = first.end.z;
        }
        if self.segments.iter().all(Segment::monotonic) {
            Ok(())
        } else {
            fail("Not monotonic")
        }
    }

    /// Fits the corner roundings and chamfers between their neighbours.
    fn finish_corners(&mut self) -> Result<()> {
        let s = &mut self.segments;
        for h in 1..s.len().saturating_sub(1) {
            let Some(corner) = s[h].corner else { continue };
            let (mut prev, mut next) = (s[h - 1], s[h + 1]);
            let mut finish = s[h].finish;
            let try_offset = |finish: f64, prev: &mut Segment, next: &mut Segment| {
                *prev = s[h - 1];
                *next = s[h + 1];
                prev.offset(finish);
                next.offset(finish);
                (prev.end - next.start).z > 1e-2
            };
            if try_offset(finish, &mut prev, &mut next) {
                finish = -finish;
                if try_offset(finish, &mut prev, &mut next) {
                    let at = s[h - 1].end;
                    return fail(format!("Corner finish failed at ({},{})", at.z, at.x));
                }
            }
            intersect(&mut prev, &mut next)?;
            let centre = (prev.end + next.start).scale(0.5);
            prev.offset(-finish);
            next.offset(-finish);
            s[h].start = prev.end;
            s[h - 1].end = prev.end;
            s[h].end = next.start;
            s[h + 1].start = next.start;
            match corner {
                Corner::Fillet => {
                    let ccw = (s[h].start - centre).x > 0.0 || (s[h].end - centre).x > 0.0;
                    s[h].shape = Shape::Arc { ccw, centre };
                    s[h].finish = 0.0;
                }
                Corner::Chamfer => s[h].finish = finish,
            }
            s[h].corner = None;
        }
        let mut p = 0;
        while p < s.len() {
            if s[p].radius() < 1e-3 {
                s.remove(p);
            } else {
                p += 1;
            }
        }
        Ok(())
    }

    /// Offsets the profile (all but its lead-in) by `distance`, away from the stock.
    fn add_distance(&mut self, distance: f64) -> Result<()> {
        let s = &mut self.segments;
        let v1 = s[0].end - s[0].start;
        let v2 = s[s.len() - 1].start - s[0].start;
        let mut distance = distance;
        if (v1 / v2).x < 0.0 {
            distance = -distance;
        }
        let mut lead = s.remove(0);
        let mut current = 0.0;
        let mut rounds = 0;
        while current != distance {
            rounds += 1;
            if rounds > 100_000 || s.is_empty() {
                return fail("the profile cannot be offset");
            }
            let mut step = s.iter().map(|p| p.radius() / 2.0).fold(1e9, f64::min);
            step = step.min((distance - current).abs());
            if distance < 0.0 {
                step = -step;
            }
            s.iter_mut().for_each(|p| p.offset(step));
            s.retain(|p| p.radius() >= 1e-3);
            // Corners the step opened: closed with an arc about the old corner.
            let mut p = 0;
            while p + 1 < s.len() {
                if (s[p].end - s[p + 1].start).z > 1e-2 {
                    let (mut a, mut b) = (s[p], s[p + 1]);
                    a.offset(-step);
                    b.offset(-step);
                    let centre = (a.end + b.start).scale(0.5);
                    let arc = Segment::arc(distance > 0.0, s[p].end, centre, s[p + 1].start);
                    s.insert(p + 1, arc);
                    p += 1;
                }
                p += 1;
            }
            let mut p = 0;
            while p + 1 < s.len() {
                if !s[p].monotonic() {
                    if p == 0 || s[p].radius() < s[p - 1].radius() {
                        s.remove(p);
                    } else {
                        s.remove(p - 1);
                    }
                    p = 0;
                    if p + 1 >= s.len() {
                        break;
                    }
                }
                if s[p].radius() < 1e-3 {
                    s.remove(p);
                    p = 0;
                } else {
                    let (a, b) = s.split_at_mut(p + 1);
                    intersect(&mut a[p], &mut b[0])?;
                }
                p += 1;
            }
            current += step;
        }
        for p in 0..s.len().saturating_sub(1) {
            let mid = (s[p].end + s[p + 1].start).scale(0.5);
            s[p].end = mid;
            s[p + 1].start = mid;
        }
        lead.end = s.first().map_or(lead.end, |f| f.start);
        s.insert(0, lead);
        Ok(())
    }

    /// G70: `passes` passes along the profile, from `d` away from it to `e`, each from
    /// the start point `start` (the first a rapid).
    pub(crate) fn g70(mut self, start: Pt, d: f64, e: f64, passes: f64) -> Result<Vec<Move>> {
        self.segments[0].start = start;
        let mut probe = self.clone();
        probe.segments.remove(0);
        if probe.segments.is_empty() {
            return Ok(Vec::new());
        }
        probe.swap();
        if !probe.segments.iter().all(Segment::monotonic) {
            probe.rotate();
            probe.swap();
        }
        probe.check_monotonic()?;
        if probe.flip & 4 != 0 {
            self.rotate();
        }
        self.swap();
        self.finish_corners()?;
        self.check_monotonic()?;
        let mut out = Vec::new();
        let mut pass = passes as i64;
        while pass > 0 {
            let distance = (pass - 1) as f64 * (d - e) / passes + e;
            let mut path = self.clone();
            path.add_distance(distance)?;
            out.push(Move::Rapid(path.segments[0].start));
            out.push(Move::Rapid(path.segments[0].end));
            for s in &path.segments[1..] {
                s.draw(&mut out);
            }
            check_size(&out)?;
            pass -= 1;
        }
        Ok(out.into_iter().map(|m| self.unflip(m)).collect())
    }

    /// G71 (G72 when `facing`): roughing from `start` in layers `i` deep, leaving `d`,
    /// retracting `r`; `cycle` 0 with pockets, 1 without, 2 the pockets only. `shift`
    /// is (W, U).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn g71(
        mut self,
        facing: bool,
        cycle: u8,
        start: Pt,
        shift: Pt,
        d: f64,
        i: f64,
        r: f64,
    ) -> Result<Vec<Move>> {
        self.segments[0].start = start;
        if facing {
            self.rotate();
        }
        self.swap();
        self.finish_corners()?;
        self.check_monotonic()?;
        self.add_distance(d)?;
        self.segments.iter_mut().for_each(|s| s.shift(shift));
        self.delta = i.max(2.0 * TOLERANCE);
        self.escape = Pt::new(r, r);
        let mut out = vec![Move::Rapid(self.segments[0].start)];
        let first = self.segments[0].start;
        let last = self.segments[self.segments.len() - 1].end;
        if last.x < first.x {
            self.segments.push(Segment::straight(last, Pt::new(last.z, first.x)));
        }
        self.pocket_starts.push(first);
        self.pocket(cycle, first, 0, &mut out)?;
        Ok(out.into_iter().map(|m| self.unflip(m)).collect())
    }

    fn pocket(&mut self, mut cycle: u8, mut location: Pt, mut p: usize, out: &mut Vec<Move>) -> Result<()> {
        let mut x = self.pocket_starts.last().expect("a pocket start").x;
        let n = self.segments.len();
        if cycle == 2 {
            // The first roughing pass was cycle 1's: follow the profile down only.
            while p < n {
                if self.segments[p].dive(&mut location, -1e9, out, p == 0)? {
                    break;
                }
                p += 1;
            }
            cycle = 3;
        }
        let mut guard = 0u64;
        // The state one pass of the loop starts from: a pass that leaves it as it was
        // (no move made, neither the segment nor the layer advanced) repeats for ever.
        let mut before: Option<(usize, f64, Pt, usize)> = None;
        while p < n {
            guard += 1;
            let state = (p, x, location, out.len());
            if guard > 10_000_000 || before == Some(state) {
                return fail("the roughing cycle does not end");
            }
            before = Some(state);
            check_size(out)?;
            // Down to the layer at the location: one layer a pass, so more layers than
            // the cycle may make moves cannot be cut (and a location far below, e.g.
            // where a dive followed the profile down without end, would take for ever).
            if (x - TOLERANCE - location.x) / self.delta > MAX_MOVES as f64 {
                return fail(format!(
                    "the roughing needs more than {MAX_MOVES} layers from X{x:.3} down to X{:.3} (I too small for the profile?)",
                    location.x
                ));
            }
            while x - TOLERANCE > location.x {
                x -= self.delta;
            }
            if self.segments[p].dive(&mut location, x, out, p == 0)? {
                if cycle == 1 {
                    // After the roughing pass, along the final contour and done.
                    for s in &self.segments[p..] {
                        s.climb_only(&mut location, out);
                    }
                } else {
                    // Along the contour until a pocket, which is cut next.
                    while p < n {
                        if self.segments[p].climb(&mut location, out)? {
                            if cycle == 3 {
                                let top = self.pocket_starts.last().expect("a pocket start").x;
                                if location.x > top && self.pocket_starts.len() > 1 {
                                    self.pocket_starts.pop();
                                }
                                if self.pocket_starts.len() == 1 {
                                    self.pocket_starts.push(location);
                                }
                            }
                            return self.pocket(cycle, location, p, out);
                        }
                        p += 1;
                    }
                }
                return Ok(());
            }
            if (location.x - x).abs() > TOLERANCE {
                // The layer is below this segment: on to the next.
                p += 1;
                continue;
            }
            for ip in p..n {
                let is = self.segments[ip].crossings(location.x);
                if is.is_empty() {
                    continue;
                }
                // The diving segment itself may be hit again, if it is an arc.
                let destination = if ip != p { is[0] } else { *is.last().expect("a crossing") };
                let distance = (destination - location.z).abs();
                if destination - TOLERANCE > location.z {
                    continue;
                }
                if distance < TOLERANCE {
                    if p == ip {
                        continue;
                    } else if (location - self.segments[ip].start).abs() < TOLERANCE {
                        p = ip;
                        break;
                    } else {
                        x -= self.delta;
                        break;
                    }
                }
                let mut dest = Pt::new(destination, location.x);
                out.push(Move::Feed(dest));
                // The escape shrinks when the cut is shorter than twice it.
                let scale = (distance / 2.0 / self.escape.z).min(1.0);
                dest = dest + self.escape.scale(scale);
                out.push(Move::Rapid(dest));
                out.push(Move::Rapid(location - self.escape.scale(scale).conj()));
                out.push(if p == 0 { Move::Rapid(location) } else { Move::Feed(location) });
                x -= self.delta;
                break;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cycle(code: u32, d: f64, i: f64) -> LatheCycle {
        LatheCycle {
            code,
            column: 1,
            q: (1.0, 1),
            start: Pt::new(2.0, 12.0),
            d,
            e: 0.0,
            i,
            p: 2.0,
            r: 0.3,
            u: 0.0,
            w: 0.0,
        }
    }

    #[test]
    fn a_straight_profile_is_finished_and_roughed_where_rs274_puts_it() {
        // G70 at D 0 follows the profile itself: rapid to the start, to the first
        // point, then feed along it.
        let corners = [Pt::new(2.0, 12.0), Pt::new(0.0, 2.0), Pt::new(-5.0, 4.0), Pt::new(-8.0, 6.0)];
        let segments: Vec<Segment> = corners.windows(2).map(|w| Segment::straight(w[0], w[1])).collect();
        let mut c = cycle(700, 0.0, 1.0);
        c.p = 1.0;
        let moves = cycle_moves(&c, segments.clone()).unwrap();
        assert_eq!(
            moves,
            [
                Move::Rapid(Pt::new(2.0, 12.0)),
                Move::Rapid(Pt::new(0.0, 2.0)),
                Move::Feed(Pt::new(-5.0, 4.0)),
                Move::Feed(Pt::new(-8.0, 6.0))
            ]
        );
        // G71 cuts its layers at X 12, 11, ... 3 (rs274 -g on the same profile), each fed
        // along Z to the profile (or to the closing line at its end, Z -8) and left by
        // the 45-degree retract R.
        let moves = cycle_moves(&cycle(710, 0.0, 1.0), segments).unwrap();
        assert_eq!(moves[0], Move::Rapid(Pt::new(2.0, 12.0)));
        let layers: Vec<(f64, f64)> = moves
            .windows(2)
            .filter_map(|w| match (w[0], w[1]) {
                (Move::Feed(a), Move::Rapid(b)) if (b.x - a.x - 0.3).abs() < 1e-9 => Some((a.x, a.z)),
                _ => None,
            })
            .collect();
        let expected = [(12.0, -8.0), (11.0, -8.0), (10.0, -8.0), (9.0, -8.0), (8.0, -8.0), (7.0, -8.0), (6.0, -8.0)];
        assert_eq!(layers[..7], expected);
        assert_eq!(layers.len(), 10);
        for ((x, z), (ex, ez)) in layers[7..].iter().zip([(5.0, -6.5), (4.0, -5.0), (3.0, -2.5)]) {
            assert!((x - ex).abs() < 1e-9 && (z - ez).abs() < 1e-9, "layer at X {x} ends at Z {z}");
        }
        // Then along the profile and its closing line back to the start's X.
        assert_eq!(moves[moves.len() - 1], Move::Feed(Pt::new(-8.0, 12.0)));
    }
}
