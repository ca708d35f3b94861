//! The host's side of the point-by-point comparison interpolator
//! (docs/spec/pbp_interp.md): what a record with the flag PBP carries ([`PbpLanes`],
//! built into a record by [`crate::PeriodRecord::pbp`]) and an arc's decision count from
//! its end point ([`arc_steps`]), which `finestep_model::pbp_interp` checks against the
//! decisions themselves.

/// Why an arc record cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ArcError {
    /// `R^2 = x^2 + y^2 < 2`: a decision could reach the centre.
    #[error("arc radius squared {0} is below 2")]
    TooSmall(i64),
    /// The end point is not a point of the start's path.
    #[error("end point ({0}, {1}) is not on the arc's path")]
    NotOnPath(i64, i64),
}

/// The smallest `k >= 0` with `k^2 >= v` (0 for `v <= 0`).
pub fn ceil_sqrt(v: i64) -> i64 {
    if v <= 0 {
        return 0;
    }
    let mut k = (v as f64).sqrt() as i64;
    while k * k < v {
        k += 1;
    }
    while k > 0 && (k - 1) * (k - 1) >= v {
        k -= 1;
    }
    k
}

/// The point in the frame where the arc moves CCW in quadrant 1 (`u > 0, v >= 0`, steps
/// `-u` inward and `+v` outward), and that quadrant's index 0..3 in the frame's order.
fn canonical(x: i64, y: i64, cw: bool) -> (usize, i64, i64) {
    // CW is CCW in the mirror image across y = x.
    let (x, y) = if cw { (y, x) } else { (x, y) };
    if x > 0 && y >= 0 {
        (0, x, y)
    } else if x <= 0 && y > 0 {
        (1, y, -x)
    } else if x < 0 && y <= 0 {
        (2, -x, -y)
    } else {
        (3, -y, x)
    }
}

/// The number of decisions that take the arc from `start` (relative to the centre,
/// `R^2 = |start|^2`) to `end`, the first time it is reached after at least one decision
/// (`end == start` is the full circle). In closed form, quadrant by quadrant: in the
/// canonical frame a quadrant entered at `(u0, v0)` visits in column `u` (from `u0`
/// down to 1) the rows `lo(u) ..= hi(u)`, `hi(u) = max(v0, ceil_sqrt(R^2 - u^2))`,
/// `lo(u0) = v0`, `lo(u) = hi(u + 1)`, and leaves at `(0, hi(1))`, which is the next
/// quadrant's entry `(hi(1), 0)` in its own frame.
pub fn arc_steps(start: (i64, i64), end: (i64, i64), cw: bool) -> Result<u64, ArcError> {
    let r2 = start.0 * start.0 + start.1 * start.1;
    if r2 < 2 {
        return Err(ArcError::TooSmall(r2));
    }
    let (mut q, mut u0, mut v0) = canonical(start.0, start.1, cw);
    let (qe, ue, ve) = canonical(end.0, end.1, cw);
    let hi = |u: i64, v0: i64| v0.max(ceil_sqrt(r2 - u * u));
    let mut total: i64 = 0;
    for segment in 0..5 {
        if qe == q && ue <= u0 && ve >= v0 {
            let lo = if ue == u0 { v0 } else { hi(ue + 1, v0) };
            let steps = (u0 - ue) + (ve - v0);
            if ve >= lo && ve <= hi(ue, v0) && (steps > 0 || segment > 0) {
                return Ok((total + steps) as u64);
            }
        }
        let exit = hi(1, v0);
        total += u0 + (exit - v0);
        q = (q + 1) % 4;
        u0 = exit;
        v0 = 0;
    }
    Err(ArcError::NotOnPath(end.0, end.1))
}

/// What a record with the flag PBP carries ([`crate::PeriodRecord::pbp`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PbpLanes {
    /// A circular arc (else a line).
    pub arc: bool,
    /// The arc turns clockwise.
    pub cw: bool,
    /// The axis pair: X is axis `2 * pair`, Y `2 * pair + 1` (0..=3).
    pub pair: u8,
    /// Line: the end point's X relative to the start; arc: the start's X relative to the
    /// centre. Signed, [`PbpLanes::COORD_W`] bits.
    pub x: i32,
    /// The same for Y.
    pub y: i32,
    /// Arc: its decision count (`pbp_interp::arc_steps`); a line: ignored.
    pub steps: u64,
    /// One decision every `tick_div + 1` clocks ([`PbpLanes::DIV_W`] bits).
    pub tick_div: u32,
}

impl PbpLanes {
    /// Lane 0's `PBP_RECORD` bits start at this bit (hdl/interface.toml `[pbp]`).
    pub const TOP: u32 = crate::pbp_lanes::BITS_LSB;
    /// Bits of a coordinate (`pbp_interp`'s `COORD_W` in the core).
    pub const COORD_W: u32 = crate::pbp_lanes::X_WIDTH;
    /// Bits of an arc's decision count (`COORD_W + 3`).
    pub const COUNT_W: u32 = crate::pbp_lanes::COUNT_WIDTH;
    /// Bits of the decision divider (`pbp_interp`'s `DIV_W` in the core).
    pub const DIV_W: u32 = crate::pbp_lanes::TICK_DIV_WIDTH;

    /// Whether the coordinates, the count, the pair and the divider fit the record's
    /// fields: a line's `|x|, |y| < 2^23` (so `|x| + |y|` decisions fit), an arc's start
    /// within `-2^23..2^23`, its count below `2^27`, `tick_div` below `2^DIV_W`.
    pub fn fits(&self) -> bool {
        let half = 1i64 << (Self::COORD_W - 1);
        let coord = |c: i32| if self.arc { (-half..half).contains(&i64::from(c)) } else { i64::from(c).abs() < half };
        coord(self.x)
            && coord(self.y)
            && self.pair <= 3
            && self.steps < (1 << Self::COUNT_W)
            && u64::from(self.tick_div) < (1 << Self::DIV_W)
    }
}
