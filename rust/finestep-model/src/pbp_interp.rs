//! `pbp_interp`: the point-by-point comparison interpolator (the F-function method) of
//! one axis pair, lines and circular arcs, in all four quadrants, CW and CCW.
//!
//! Specification: docs/spec/pbp_interp.md
//!
//! One decision per tick (every `tick_div + 1` clocks) steps exactly one axis by one
//! step. Lines (end point `(Xe, Ye)` relative to the start, magnitudes `a = |Xe|`,
//! `b = |Ye|`, steps taken `i` along X and `j` along Y): `F = a*j - b*i`; `F >= 0` and
//! `a != 0` steps X (`F -= b`), else Y (`F += a`); `a + b` decisions. Arcs (start
//! `(x, y)` relative to the centre, `R^2 = x^2 + y^2`): `F = x^2 + y^2 - R^2`; the quadrant
//! (the position's signs, an axis point belonging to the quadrant the motion enters)
//! and the direction give the sign of each axis's step and which axis is *inward*
//! (its step moves toward the centre); `F >= 0` steps the inward axis, `F < 0` the other;
//! a step by `s = +-1` on coordinate `c` makes `F += 2*s*c + 1`. The arc's decision count
//! comes with the record: the host computes it with [`arc_steps`] from the end point.
//!
//! [`PbpInterp`] is the cycle model of the block (bit-exact with `hdl/pbp_interp.v`:
//! registers of the RTL's widths, two's complement wrap); [`line_decision`],
//! [`arc_decision`], [`LinePath`] and [`ArcPath`] are the method itself, on unbounded
//! integers, and what the geometric tests walk.

/// The block's widths (the RTL's parameters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PbpParams {
    /// `COORD_W`: the record's signed coordinates.
    pub coord_w: u32,
    /// `DIV_W`: the tick divider.
    pub div_w: u32,
}

impl Default for PbpParams {
    /// `COORD_W = 24`, `DIV_W = 16`: `hdl/pbp_interp.v`'s defaults.
    fn default() -> Self {
        PbpParams { coord_w: 24, div_w: 16 }
    }
}

impl PbpParams {
    /// The widths `finestep_core` builds the block with: its record's fields
    /// (hdl/interface.toml `[pbp]`: `COORD_W` the X field's width, `DIV_W` TICK_DIV's).
    pub fn core() -> Self {
        use finestep_interface::pbp_lanes;
        PbpParams { coord_w: pbp_lanes::X_WIDTH, div_w: pbp_lanes::TICK_DIV_WIDTH }
    }

    /// `POS_W = COORD_W + 1`: an arc's position (up to `R + 1 < 2^COORD_W` in magnitude).
    pub fn pos_w(&self) -> u32 {
        self.coord_w + 1
    }
    /// `F_W = COORD_W + 3`: `|F| <= 2R + 1 < 2^(COORD_W + 1) + 1` for arcs, `|F| <= 2^(COORD_W-1)`
    /// for lines, and a decision's `F +- (2|c| + 1)` on the way.
    pub fn f_w(&self) -> u32 {
        self.coord_w + 3
    }
    /// `COUNT_W = COORD_W + 3`: a line's `|Xe| + |Ye| <= 2^COORD_W`, an arc's at most
    /// `8R + 8 < 2^(COORD_W + 3)` decisions.
    pub fn count_w(&self) -> u32 {
        self.coord_w + 3
    }
}

/// `v` wrapped to a `w`-bit two's complement value.
fn wrap(v: i64, w: u32) -> i64 {
    let shift = 64 - w;
    (v << shift) >> shift
}

/// `v` wrapped to a `w`-bit unsigned value.
fn wrap_u(v: i64, w: u32) -> i64 {
    v & ((1i64 << w) - 1)
}

/// One decision: the axis stepped (0 = X, 1 = Y) and the step's sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Decision {
    /// 0: X, 1: Y.
    pub axis: usize,
    /// The step is -1.
    pub negative: bool,
}

/// A line's decision from the magnitudes `a = |Xe|`, `b = |Ye|` and `F`: X when
/// `F >= 0` and `a != 0`, else Y. The sign is the end point's on that axis.
pub fn line_decision(a: i64, f: i64) -> usize {
    if f >= 0 && a != 0 {
        0
    } else {
        1
    }
}

/// The step signs and the inward axis of an arc at `(x, y)`: `(x_negative, y_negative,
/// inward_is_x)`. CCW steps along `(-y, x)`, CW along `(y, -x)`; on an axis the sign of
/// the zero coordinate's neighbour decides (the quadrant the motion enters).
pub fn arc_signs(x: i64, y: i64, cw: bool) -> (bool, bool, bool) {
    let (x_negative, y_negative) = if cw {
        // CW: X+ in the upper half plane (and on the negative X axis), Y- right of the
        // Y axis (and on the positive Y axis).
        (!(y > 0 || (y == 0 && x < 0)), x > 0 || (x == 0 && y > 0))
    } else {
        // CCW: X- in the upper half plane (and on the positive X axis), Y+ right of the
        // Y axis (and on the negative Y axis).
        (y > 0 || (y == 0 && x > 0), !(x > 0 || (x == 0 && y < 0)))
    };
    let inward_x = (x > 0 && x_negative) || (x < 0 && !x_negative);
    (x_negative, y_negative, inward_x)
}

/// An arc's decision at `(x, y)` with `F`: the inward axis when `F >= 0`, else the other.
pub fn arc_decision(x: i64, y: i64, f: i64, cw: bool) -> Decision {
    let (x_negative, y_negative, inward_x) = arc_signs(x, y, cw);
    let step_x = if f >= 0 { inward_x } else { !inward_x };
    if step_x {
        Decision { axis: 0, negative: x_negative }
    } else {
        Decision { axis: 1, negative: y_negative }
    }
}

/// `F` after a step of sign `negative` on coordinate `c`: `F + 2*s*c + 1`.
pub fn arc_f_next(f: i64, c: i64, negative: bool) -> i64 {
    if negative {
        f - 2 * c + 1
    } else {
        f + 2 * c + 1
    }
}

/// The points a line's decisions visit, after each decision: `|Xe| + |Ye|` of them.
#[derive(Clone, Debug)]
pub struct LinePath {
    a: i64,
    b: i64,
    sx: i64,
    sy: i64,
    /// Steps taken along X and Y (magnitudes).
    pub i: i64,
    /// See `i`.
    pub j: i64,
    /// `a*j - b*i`.
    pub f: i64,
    left: i64,
}

impl LinePath {
    /// The line from the origin to `(xe, ye)`.
    pub fn new(xe: i64, ye: i64) -> Self {
        let (a, b) = (xe.abs(), ye.abs());
        LinePath { a, b, sx: xe.signum(), sy: ye.signum(), i: 0, j: 0, f: 0, left: a + b }
    }
    /// The position relative to the start.
    pub fn point(&self) -> (i64, i64) {
        (self.sx * self.i, self.sy * self.j)
    }
}

impl Iterator for LinePath {
    type Item = (Decision, (i64, i64));
    fn next(&mut self) -> Option<Self::Item> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let axis = line_decision(self.a, self.f);
        let negative = if axis == 0 {
            self.i += 1;
            self.f -= self.b;
            self.sx < 0
        } else {
            self.j += 1;
            self.f += self.a;
            self.sy < 0
        };
        Some((Decision { axis, negative }, self.point()))
    }
}

/// The points an arc's decisions visit, without end: stop it after [`arc_steps`].
#[derive(Clone, Debug)]
pub struct ArcPath {
    /// The position relative to the centre.
    pub x: i64,
    /// See `x`.
    pub y: i64,
    /// `x^2 + y^2 - R^2`.
    pub f: i64,
    cw: bool,
}

impl ArcPath {
    /// The arc from `(x, y)` (relative to the centre), `R^2 = x^2 + y^2`.
    pub fn new(x: i64, y: i64, cw: bool) -> Self {
        ArcPath { x, y, f: 0, cw }
    }
}

impl Iterator for ArcPath {
    type Item = (Decision, (i64, i64));
    fn next(&mut self) -> Option<Self::Item> {
        let d = arc_decision(self.x, self.y, self.f, self.cw);
        let s = if d.negative { -1 } else { 1 };
        if d.axis == 0 {
            self.f = arc_f_next(self.f, self.x, d.negative);
            self.x += s;
        } else {
            self.f = arc_f_next(self.f, self.y, d.negative);
            self.y += s;
        }
        Some((d, (self.x, self.y)))
    }
}

// The host's arithmetic of an arc's decision count lives with the record layout in
// `finestep_interface::pbp` (the host computes it; the tests here check it against the
// decisions).
pub use finestep_interface::pbp::{arc_steps, ceil_sqrt, ArcError};

/// A record as it reaches the block's ports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PbpRecord {
    /// 1: a circular arc; 0: a line.
    pub arc: bool,
    /// The arc turns clockwise.
    pub cw: bool,
    /// Line: `Xe` (end relative to the start); arc: the start's `x` relative to the centre.
    pub x: i64,
    /// Line: `Ye`; arc: the start's `y`.
    pub y: i64,
    /// Arc: the number of decisions ([`arc_steps`]); ignored for a line.
    pub steps: u64,
}

impl PbpRecord {
    /// A line to `(xe, ye)`.
    pub fn line(xe: i64, ye: i64) -> Self {
        PbpRecord { arc: false, cw: false, x: xe, y: ye, steps: 0 }
    }
    /// An arc from `start` to `end` (relative to the centre).
    pub fn arc(start: (i64, i64), end: (i64, i64), cw: bool) -> Result<Self, ArcError> {
        let steps = arc_steps(start, end, cw)?;
        Ok(PbpRecord { arc: true, cw, x: start.0, y: start.1, steps })
    }
}

/// The block's inputs in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PbpInputs {
    /// Abort the record; no step.
    pub halt: bool,
    /// A decision every `tick_div + 1` clocks.
    pub tick_div: u32,
    /// A record is offered.
    pub rec_valid: bool,
    /// The record offered.
    pub rec: PbpRecord,
}

/// The block's outputs in one cycle (all registered).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PbpOutputs {
    /// A record is taken when offered (`!busy`).
    pub rec_ready: bool,
    /// A record is being interpolated.
    pub busy: bool,
    /// Pulse: the record's last step is requested in this cycle (or its zero steps ended).
    pub done: bool,
    /// A step request to axis 0 (X) and 1 (Y), as `dda_axis`'s `req_valid`.
    pub req_valid: [bool; 2],
    /// Its direction is negative.
    pub req_negative: [bool; 2],
    /// While busy, the direction the next step on axis 0 (X) and 1 (Y) would take: +1
    /// (a line's coordinate's sign, an arc's quadrant direction); neither on a line's
    /// axis of zero coordinate, and neither while not busy (for the gantry).
    pub move_up: [bool; 2],
    /// See `move_up`: -1.
    pub move_down: [bool; 2],
}

/// The block's state (the RTL's registers).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PbpInterp {
    params: PbpParams,
    busy: bool,
    arc: bool,
    cw: bool,
    /// Arc: the position; line: `|Xe|`, `|Ye|`.
    x: i64,
    y: i64,
    /// Line: the end point's signs.
    x_negative: bool,
    y_negative: bool,
    f: i64,
    count: i64,
    div: i64,
    done: bool,
    req_valid: [bool; 2],
    req_negative: [bool; 2],
}

impl PbpInterp {
    /// The reset state.
    pub fn new(params: PbpParams) -> Self {
        PbpInterp {
            params,
            busy: false,
            arc: false,
            cw: false,
            x: 0,
            y: 0,
            x_negative: false,
            y_negative: false,
            f: 0,
            count: 0,
            div: 0,
            done: false,
            req_valid: [false; 2],
            req_negative: [false; 2],
        }
    }

    /// The outputs in this cycle.
    pub fn outputs(&self) -> PbpOutputs {
        // The directions of the two axes: a line's signs, an arc's quadrant's.
        let negative = if self.arc {
            let (x, y, _) = arc_signs(self.x, self.y, self.cw);
            [x, y]
        } else {
            [self.x_negative, self.y_negative]
        };
        let moves = [self.busy && (self.arc || self.x != 0), self.busy && (self.arc || self.y != 0)];
        PbpOutputs {
            move_up: [moves[0] && !negative[0], moves[1] && !negative[1]],
            move_down: [moves[0] && negative[0], moves[1] && negative[1]],
            rec_ready: !self.busy,
            busy: self.busy,
            done: self.done,
            req_valid: self.req_valid,
            req_negative: self.req_negative,
        }
    }

    /// `F` (for tests).
    pub fn f(&self) -> i64 {
        self.f
    }

    /// Decisions left.
    pub fn count(&self) -> i64 {
        self.count
    }

    /// Arc: the position; line: `(|Xe|, |Ye|)`.
    pub fn xy(&self) -> (i64, i64) {
        (self.x, self.y)
    }

    /// One clock edge with `rst` high.
    pub fn reset(&mut self) {
        self.busy = false;
        self.done = false;
        self.req_valid = [false; 2];
        self.req_negative = [false; 2];
        self.div = 0;
    }

    /// One rising edge.
    pub fn step(&mut self, inputs: &PbpInputs) {
        let p = self.params;
        let (pos_w, f_w, count_w, div_w) = (p.pos_w(), p.f_w(), p.count_w(), p.div_w);
        self.done = false;
        self.req_valid = [false; 2];
        self.req_negative = [false; 2];
        if !self.busy {
            if inputs.rec_valid {
                let r = &inputs.rec;
                let xe = wrap(r.x, p.coord_w);
                let ye = wrap(r.y, p.coord_w);
                self.arc = r.arc;
                self.cw = r.cw;
                self.f = 0;
                self.div = 0;
                self.x_negative = xe < 0;
                self.y_negative = ye < 0;
                let steps;
                if r.arc {
                    self.x = xe;
                    self.y = ye;
                    steps = wrap_u(r.steps as i64, count_w);
                } else {
                    self.x = xe.abs();
                    self.y = ye.abs();
                    steps = xe.abs() + ye.abs();
                }
                self.count = steps;
                self.busy = steps != 0;
                self.done = steps == 0;
            }
        } else if self.div >= i64::from(inputs.tick_div) {
            self.div = 0;
            let d = if self.arc {
                let d = arc_decision(self.x, self.y, self.f, self.cw);
                let s = if d.negative { -1 } else { 1 };
                if d.axis == 0 {
                    self.f = wrap(arc_f_next(self.f, self.x, d.negative), f_w);
                    self.x = wrap(self.x + s, pos_w);
                } else {
                    self.f = wrap(arc_f_next(self.f, self.y, d.negative), f_w);
                    self.y = wrap(self.y + s, pos_w);
                }
                d
            } else {
                let axis = line_decision(self.x, self.f);
                self.f = wrap(if axis == 0 { self.f - self.y } else { self.f + self.x }, f_w);
                Decision { axis, negative: if axis == 0 { self.x_negative } else { self.y_negative } }
            };
            self.req_valid[d.axis] = true;
            self.req_negative[d.axis] = d.negative;
            self.count -= 1;
            if self.count == 0 {
                self.busy = false;
                self.done = true;
            }
        } else {
            self.div = wrap_u(self.div + 1, div_w);
        }
        if inputs.halt {
            self.busy = false;
            self.done = false;
            self.req_valid = [false; 2];
            self.req_negative = [false; 2];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_of_radius_5_takes_40_decisions() {
        assert_eq!(arc_steps((5, 0), (5, 0), false), Ok(40));
        assert_eq!(arc_steps((5, 0), (0, 5), false), Ok(10));
        assert_eq!(arc_steps((5, 0), (0, 5), true), Ok(30));
        assert_eq!(arc_steps((1, 1), (1, 1), true), Ok(8));
        assert_eq!(arc_steps((1, 0), (0, 1), false), Err(ArcError::TooSmall(1)));
        assert_eq!(arc_steps((5, 0), (5, 5), false), Err(ArcError::NotOnPath(5, 5)));
    }

    /// The block's requests through two step shapers (the DDA's hand-off): every step
    /// reaches the pins and the shapers end at the end point; with decisions at least
    /// `L + max(S, H + U)` clocks apart the shapers never fall behind, faster they do.
    #[test]
    fn requests_drive_two_step_shapers_to_the_end_point() {
        use crate::config::{AxisConfig, AxisSettings};
        use crate::step_shaper::StepShaper;
        use crate::DriveTiming;
        let counter_max = 4095;
        let cfg = AxisConfig { timing: DriveTiming::new(10, 10, 5, 5), enable: true, ..AxisConfig::default() };
        let set = AxisSettings::masked(&cfg, counter_max, false);
        let run = |rec: PbpRecord, tick_div: u32| {
            let mut block = PbpInterp::new(PbpParams::default());
            let mut shapers = [StepShaper::new(counter_max); 2];
            block.step(&PbpInputs { tick_div, rec_valid: true, rec, ..PbpInputs::default() });
            let idle = PbpInputs { tick_div, ..PbpInputs::default() };
            for _ in 0..200_000 {
                let o = block.outputs();
                for (axis, shaper) in shapers.iter_mut().enumerate() {
                    let r = if !o.req_valid[axis] {
                        0
                    } else if o.req_negative[axis] {
                        -1
                    } else {
                        1
                    };
                    shaper.step(r, &set, counter_max, false);
                }
                block.step(&idle);
            }
            assert!(!block.outputs().busy);
            let position = |s: &StepShaper| s.position() as i32 as i64;
            ((position(&shapers[0]), position(&shapers[1])), shapers[0].rate_error() || shapers[1].rate_error())
        };
        let (start, end) = ((30, -41), (-50, 7));
        let arc = PbpRecord::arc(start, end, true).unwrap();
        assert_eq!(run(arc, 19), ((end.0 - start.0, end.1 - start.1), false));
        assert_eq!(run(PbpRecord::line(-300, 171), 19), ((-300, 171), false));
        // Decisions every 10 clocks: the shapers fall behind (rate_error) yet lose no step.
        assert_eq!(run(arc, 9), ((end.0 - start.0, end.1 - start.1), true));
    }

    #[test]
    fn a_line_record_runs_at_the_tick_rate() {
        let mut block = PbpInterp::new(PbpParams::default());
        let inputs = PbpInputs { tick_div: 2, rec_valid: true, rec: PbpRecord::line(3, -2), ..PbpInputs::default() };
        block.step(&inputs);
        let idle = PbpInputs { tick_div: 2, ..PbpInputs::default() };
        let mut steps = Vec::new();
        for cycle in 1..20 {
            let o = block.outputs();
            if o.req_valid[0] || o.req_valid[1] {
                steps.push((cycle, o.req_valid[1], o.req_negative[0] || o.req_negative[1], o.done));
            }
            block.step(&idle);
        }
        // Decisions at the edges ending cycles 3, 6, ...: requests in cycles 4, 7, ...
        assert_eq!(
            steps,
            vec![
                (4, false, false, false),
                (7, true, true, false),
                (10, false, false, false),
                (13, true, true, false),
                (16, false, false, true)
            ]
        );
    }
}
