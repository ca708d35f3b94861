//! Point-by-point records for straight and circular moves in one plane
//! (docs/spec/pbp_interp.md#in-the-core): the host's emission for a core that reports
//! `VERSION.HAS_PBP`. A line becomes records of `|Xe|, |Ye| < 2^23` steps each (split
//! evenly); an arc becomes one record per turn or part of a turn with its decision count
//! from `arc_steps`, its centre on the step grid and its end moved onto the path (the
//! path point nearest the programmed end: where the move really ends, which the caller
//! takes as the next move's start). Whether a part whose end lands on its start's path
//! point is a whole turn or nothing is the caller's to say from the program (its sweep),
//! never read from steps: an arc shorter than a step sends nothing, a full circle or an
//! arc a step short of one a whole turn. The rate of decisions follows the feed.
//!
//! ```
//! use finestep_planner::pbp::{arc_records, line_records};
//! let lines = line_records((0, 0), (20_000_000, -3), 9);
//! assert_eq!(lines.len(), 3);
//! let arc = arc_records((1000, 0), (0, 0), (0, 1000), false, 0, false, 9).unwrap();
//! assert_eq!(arc.end, (0, 1000));
//! ```

use finestep_interface::pbp::{arc_steps, ArcError, PbpLanes};

/// Why a move cannot be sent as pbp records.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PbpError {
    /// The arc's start is too near its centre, or no path point lies near the end.
    #[error("arc: {0}")]
    Arc(#[from] ArcError),
    /// The arc's start is `2^23` steps or more from its centre on an axis.
    #[error("arc radius ({0}, {1}) steps does not fit the record's 24-bit coordinates")]
    TooLarge(i64, i64),
}

/// The records of a straight move from `from` to `to` (steps on the pair's X and Y): as
/// few pieces as keep `|Xe|, |Ye| < 2^23`, the `k`-th ending at `floor(d * k / n)` (so
/// the pieces sum to `d` exactly); none for a move of zero steps.
pub fn line_records(from: (i64, i64), to: (i64, i64), tick_div: u16) -> Vec<PbpLanes> {
    let d = (to.0 - from.0, to.1 - from.1);
    let limit = (1u64 << (PbpLanes::COORD_W - 1)) - 1;
    let n = d.0.unsigned_abs().div_ceil(limit).max(d.1.unsigned_abs().div_ceil(limit)) as i64;
    let mut out = Vec::new();
    let mut done = (0i64, 0i64);
    for k in 1..=n {
        let at = (
            (i128::from(d.0) * i128::from(k)).div_euclid(i128::from(n)) as i64,
            (i128::from(d.1) * i128::from(k)).div_euclid(i128::from(n)) as i64,
        );
        let piece = PbpLanes { x: (at.0 - done.0) as i32, y: (at.1 - done.1) as i32, tick_div, ..PbpLanes::default() };
        debug_assert!(piece.fits());
        out.push(piece);
        done = at;
    }
    out
}

/// An arc's records and where it really ends.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArcRecords {
    /// One record per whole turn (`extra_turns`), then the programmed part.
    pub records: Vec<PbpLanes>,
    /// The end point on the path (steps), nearest the programmed end.
    pub end: (i64, i64),
}

/// The records of an arc from `start` around `centre` to `end` (steps on the pair's X and
/// Y; the centre rounded to the step grid), clockwise or not: `extra_turns` whole turns,
/// then the part to the end. The end is moved to the nearest point of the path within two
/// steps of it (the path stays within one step of the circle). A part whose end lands on
/// the start's point is a whole turn if `closed_is_turn` (the caller's, from the program:
/// a programmed sweep of more than half a turn, e.g. a full circle, G2/G3 ending where it
/// starts), else empty (no record: an arc shorter than a step).
pub fn arc_records(
    start: (i64, i64),
    centre: (i64, i64),
    end: (i64, i64),
    cw: bool,
    extra_turns: u32,
    closed_is_turn: bool,
    tick_div: u16,
) -> Result<ArcRecords, PbpError> {
    let s = (start.0 - centre.0, start.1 - centre.1);
    let e = (end.0 - centre.0, end.1 - centre.1);
    let lanes =
        |steps: u64| PbpLanes { arc: true, cw, x: s.0 as i32, y: s.1 as i32, steps, tick_div, ..PbpLanes::default() };
    if !lanes(0).fits() {
        return Err(PbpError::TooLarge(s.0, s.1));
    }
    let turn = arc_steps(s, s, cw)?;
    // The nearest path point to the programmed end: squared distance, then the earlier
    // point along the path.
    let mut best: Option<(i64, u64, (i64, i64))> = None;
    for dx in -2..=2 {
        for dy in -2..=2 {
            let c = (e.0 + dx, e.1 + dy);
            if let Ok(count) = arc_steps(s, c, cw) {
                let key = (dx * dx + dy * dy, count, c);
                match best {
                    Some(b) if (b.0, b.1) <= (key.0, key.1) => {}
                    _ => best = Some(key),
                }
            }
        }
    }
    let (_, count, on_path) = best.ok_or(ArcError::NotOnPath(e.0, e.1))?;
    let mut records: Vec<PbpLanes> = (0..extra_turns).map(|_| lanes(turn)).collect();
    // arc_steps counts a whole turn for an end at the start.
    if on_path != s || closed_is_turn {
        records.push(lanes(count));
    }
    Ok(ArcRecords { records, end: (centre.0 + on_path.0, centre.1 + on_path.1) })
}

/// The decision divider that spreads `decisions` over `seconds` at `clock_hz`:
/// `round(clock_hz * seconds / decisions) - 1`, at least `min_tick` (the drive timing's
/// `L + max(S, H + U) - 1`) and at most `u16::MAX`.
pub fn tick_div(clock_hz: f64, seconds: f64, decisions: u64, min_tick: u16) -> u16 {
    if decisions == 0 {
        return min_tick;
    }
    let clocks = (clock_hz * seconds / decisions as f64).round() - 1.0;
    clocks.clamp(f64::from(min_tick), f64::from(u16::MAX)) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum(records: &[PbpLanes]) -> (i64, i64) {
        records.iter().fold((0, 0), |(x, y), r| (x + i64::from(r.x), y + i64::from(r.y)))
    }

    #[test]
    fn lines_split_below_2_pow_23_and_sum_exactly() {
        let limit = (1i64 << 23) - 1;
        for (from, to, pieces) in [
            ((0, 0), (5, -7), 1),
            ((3, 3), (3, 3), 0),
            ((0, 0), (limit, -limit), 1),
            ((0, 0), (limit + 1, 2), 2),
            ((-10, 4), (30_000_000, -9_000_001), 4),
            ((0, 0), (-1, -100_000_000), 12),
        ] {
            let records = line_records(from, to, 5);
            assert_eq!(records.len(), pieces, "{from:?} -> {to:?}");
            assert_eq!(sum(&records), (to.0 - from.0, to.1 - from.1));
            for r in &records {
                assert!(r.fits() && !r.arc && r.tick_div == 5, "{r:?}");
                assert!(i64::from(r.x).abs() <= limit && i64::from(r.y).abs() <= limit);
            }
        }
    }

    #[test]
    fn an_arc_ends_on_its_path_nearest_the_programmed_end() {
        // A quarter from (1000, 0) to (0, 1000) CCW: both ends lie on the path.
        let q = arc_records((1000, 0), (0, 0), (0, 1000), false, 0, false, 7).unwrap();
        assert_eq!(q.end, (0, 1000));
        assert_eq!(q.records.len(), 1);
        assert_eq!(q.records[0].steps, arc_steps((1000, 0), (0, 1000), false).unwrap());
        // An end off the grid's path point (cos 30 deg * 1000 = 866.03): moved onto the
        // path, within two steps, and the count is the path's to that point.
        let ideal = (10_866, 5_500);
        let a = arc_records((11_000, 5_000), (10_000, 5_000), ideal, false, 0, false, 7).unwrap();
        assert!((a.end.0 - ideal.0).abs() <= 2 && (a.end.1 - ideal.1).abs() <= 2, "{a:?}");
        let rel = (a.end.0 - 10_000, a.end.1 - 5_000);
        assert_eq!(a.records[0].steps, arc_steps((1000, 0), rel, false).unwrap());
        let r2 = rel.0 * rel.0 + rel.1 * rel.1;
        assert!((r2 as f64).sqrt() - 1000.0 <= 1.0 && 1000.0 - (r2 as f64).sqrt() <= 1.0);
        assert_eq!((a.records[0].x, a.records[0].y), (1000, 0), "start relative to the centre");
    }

    #[test]
    fn whole_turns_and_refusals() {
        let full = arc_records((0, -50), (0, 0), (0, -50), true, 2, true, 3).unwrap();
        let turn = arc_steps((0, -50), (0, -50), true).unwrap();
        assert_eq!(full.records.iter().map(|r| r.steps).collect::<Vec<_>>(), vec![turn; 3]);
        assert_eq!(full.end, (0, -50));
        assert!(full.records.iter().all(|r| r.cw && r.arc));
        assert_eq!(arc_records((1, 0), (0, 0), (0, 1), false, 0, false, 3), Err(PbpError::Arc(ArcError::TooSmall(1))));
        assert_eq!(
            arc_records((1 << 23, 0), (0, 0), (0, 1 << 23), false, 0, false, 3),
            Err(PbpError::TooLarge(1 << 23, 0))
        );
        // An end far off the circle.
        assert!(matches!(arc_records((100, 0), (0, 0), (40, 40), false, 0, false, 3), Err(PbpError::Arc(_))));
    }

    /// An arc shorter than a step (its end's nearest path point is the start's) sends
    /// nothing and ends where it started: not a whole turn unless the caller says the
    /// program's sweep closes the circle (an arc a step short of a whole one).
    #[test]
    fn an_arc_shorter_than_a_step_sends_nothing() {
        for (start, end, cw) in
            [((1000, 0), (1000, 0), false), ((1000, 0), (1001, 0), true), ((0, 700), (0, 700), true)]
        {
            let a = arc_records(start, (0, 0), end, cw, 0, false, 3).unwrap();
            assert!(a.records.is_empty(), "{start:?} -> {end:?}: {a:?}");
            assert_eq!(a.end, start);
            let closed = arc_records(start, (0, 0), end, cw, 0, true, 3).unwrap();
            let turn = arc_steps((start.0, start.1), (start.0, start.1), cw).unwrap();
            assert_eq!(closed.records.iter().map(|r| r.steps).collect::<Vec<_>>(), [turn], "{start:?} -> {end:?}");
            assert_eq!(closed.end, start);
        }
        // A step along the path is a part of its own (one decision or two).
        let short = arc_records((1000, 0), (0, 0), (1000, 1), false, 0, true, 3).unwrap();
        assert_eq!(short.records.len(), 1);
        assert!(short.records[0].steps >= 1 && short.records[0].steps <= 2, "{short:?}");
    }

    #[test]
    fn the_divider_spreads_the_decisions_over_the_time() {
        // 1000 decisions in 10 ms at 50 MHz: 500 clocks each.
        assert_eq!(tick_div(50e6, 0.01, 1000, 3), 499);
        assert_eq!(tick_div(50e6, 1e-6, 1000, 3), 3, "at least the drive timing's");
        assert_eq!(tick_div(50e6, 100.0, 10, 3), u16::MAX);
        assert_eq!(tick_div(50e6, 1.0, 0, 4), 4);
    }
}
