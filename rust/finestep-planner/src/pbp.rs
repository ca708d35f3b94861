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

use finestep_gcode::{Block, BlockKind, CompSide, MessageKind, Point, Program};
use finestep_interface::pbp::{arc_steps, ArcError, PbpLanes};
use finestep_interface::{flags, PeriodRecord};

use crate::config::PBP_INTERVAL_MAX;
use crate::{IoAction, IoEvent, MachineConfig, PlannedProgram, ProgramError, TimedEvent};

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
pub fn line_records(from: (i64, i64), to: (i64, i64), tick_div: u32) -> Vec<PbpLanes> {
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
    tick_div: u32,
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
/// `L + max(S, H + U) - 1`) and at most `PBP_INTERVAL_MAX - 1` (the record's field).
pub fn tick_div(clock_hz: f64, seconds: f64, decisions: u64, min_tick: u32) -> u32 {
    if decisions == 0 {
        return min_tick;
    }
    let clocks = (clock_hz * seconds / decisions as f64).round() - 1.0;
    clocks.clamp(f64::from(min_tick), f64::from(PBP_INTERVAL_MAX - 1)) as u32
}

/// The decision interval (`tick_div + 1`, clocks) of a move of `decisions` decisions along
/// `length_mm` at `feed_mm_per_min` on a `clock_hz` core: the fewest whole clocks that keep
/// the move's mean path speed at or below the feed, `ceil(clock_hz * length / (feed / 60) /
/// decisions)` (rounded up: never faster than F), and at least `min_interval` (the
/// decision-rate limit and the drive timing); `None` when it is beyond the record's
/// [`PBP_INTERVAL_MAX`] (a feed too low for the record's divider).
pub fn decision_interval(
    clock_hz: f64,
    length_mm: f64,
    feed_mm_per_min: f64,
    decisions: u64,
    min_interval: u32,
) -> Option<u32> {
    if decisions == 0 {
        return Some(min_interval);
    }
    let exact = clock_hz * length_mm / (feed_mm_per_min / 60.0) / decisions as f64;
    // Up to whole clocks, ignoring the floating-point dust of exact quotients.
    let interval = (exact * (1.0 - 1e-12)).ceil().max(f64::from(min_interval));
    (interval <= f64::from(PBP_INTERVAL_MAX)).then_some(interval as u32)
}

/// The decisions of a record with the flag PBP (a line's `|x| + |y|`, an arc's count) and
/// its divider; `None` for any other record.
pub fn record_decisions(record: &PeriodRecord) -> Option<(u64, u32)> {
    let lanes = record.pbp_lanes()?;
    let decisions =
        if lanes.arc { lanes.steps } else { u64::from(lanes.x.unsigned_abs()) + u64::from(lanes.y.unsigned_abs()) };
    Some((decisions, lanes.tick_div))
}

/// The clocks a record runs: a point-by-point one `decisions * (tick_div + 1) + 1`
/// (docs/spec/pbp_interp.md#in-the-core), any other one period.
pub fn record_clocks(record: &PeriodRecord, period_clocks: u32) -> u64 {
    match record_decisions(record) {
        Some((decisions, tick_div)) => decisions * (u64::from(tick_div) + 1) + 1,
        None => u64::from(period_clocks),
    }
}

/// A program planned for point-by-point interpolation ([`plan_pbp`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PbpPlan {
    /// The records in the chip's axis order ([`Resolved::chip_axis`]): the DDA's period
    /// records for G0 and dwells, point-by-point records (flag PBP) for G1/G2/G3; events
    /// at their exact stops; `end` where the records end (on whole steps, X Y Z A).
    pub planned: PlannedProgram,
    /// Point-by-point records among them.
    pub pbp_records: usize,
    /// Their decisions.
    pub decisions: u64,
    /// The machining time, clocks: each point-by-point record's, a period per other one.
    pub clocks: u64,
    /// The shortest decision interval sent, clocks (`tick_div + 1`).
    pub min_interval: Option<u32>,
}

/// Plans `program` for point-by-point interpolation (`[interpolation] mode = "pbp"`;
/// docs/host.md, "Interpolation"): G1, G2 and G3 in the configured plane become
/// point-by-point records on the chip pair, each move from rest to rest at one decision
/// interval ([`decision_interval`]); an arc ends on the path point nearest its
/// programmed end ([`arc_records`]), where the next move starts. G0 becomes the DDA
/// planner's records of that one rapid, from rest to rest (trapezoid, the axes' limits),
/// moving any configured axis; a dwell idle periods. S, M3/M4/M5, M7/M8/M9, M62-M65 and
/// MSG/DEBUG are events at the exact stop where they are written. Refused at their line:
/// a G1/G2/G3 that moves an axis outside the plane (a helix, a third axis), an arc in
/// another plane, cutter compensation, G96, NURBS, probing, M66-M68, user M-codes,
/// spindle orientation, a feed too low for the divider.
pub fn plan_pbp(config: &MachineConfig, program: &Program) -> Result<PbpPlan, ProgramError> {
    let resolved = config.resolve().map_err(|e| ProgramError::new(0, e.to_string()))?;
    let Some(pbp) = resolved.pbp else {
        return Err(ProgramError::new(0, "[interpolation] mode is not \"pbp\""));
    };
    let spu: [f64; 4] = std::array::from_fn(|s| resolved.axes[s].steps_per_unit);
    let to_steps = |p: &Point| -> [i64; 4] {
        let mm = [p.x_mm, p.y_mm, p.z_mm, p.a_deg];
        std::array::from_fn(|s| if resolved.axes[s].present { (mm[s] * spu[s]).round() as i64 } else { 0 })
    };
    let [u, v] = pbp.slots;
    let names = crate::config::AXIS_NAMES;
    let plane_name = format!("{}{}", names[u], names[v]);
    let mut plan = PbpPlan {
        planned: PlannedProgram {
            records: Vec::new(),
            lines: Vec::new(),
            end: [0.0; 4],
            elements: 0,
            notes: Vec::new(),
            events: Vec::new(),
        },
        pbp_records: 0,
        decisions: 0,
        clocks: 0,
        min_interval: None,
    };
    // Where the records have taken the axes (steps, slot order), and the programmed
    // position (mm) the next arc starts from.
    let mut at = [0i64; 4];
    let mut at_mm = Point::default();
    let to_chip = |record: &PeriodRecord| -> PeriodRecord {
        let mut out = PeriodRecord { flags: record.flags, ..PeriodRecord::default() };
        for slot in 0..4 {
            out.inc[resolved.chip_axis[slot]] = record.inc[slot];
        }
        out
    };
    let push_pbp = |plan: &mut PbpPlan, lanes: Vec<PbpLanes>, line: usize| {
        for mut l in lanes {
            l.pair = pbp.pair;
            let (decisions, interval) =
                (if l.arc { l.steps } else { u64::from(l.x.unsigned_abs() + l.y.unsigned_abs()) }, l.tick_div + 1);
            plan.decisions += decisions;
            plan.clocks += decisions * u64::from(interval) + 1;
            plan.min_interval = Some(plan.min_interval.map_or(interval, |m| m.min(interval)));
            plan.pbp_records += 1;
            plan.planned.records.push(PeriodRecord::pbp(&l, flags::BLOCK_END));
            plan.planned.lines.push(line);
        }
    };
    let extra = |p: &Point| [p.b_deg, p.c_deg, p.u_mm, p.v_mm, p.w_mm];
    let mm_of = |p: &Point| [p.x_mm, p.y_mm, p.z_mm, p.a_deg];
    let off_plane = |block_line: usize, what: &str, from: &[i64; 4], to: &[i64; 4], p: &Point, prev: &Point| {
        if let Some(slot) = (0..4).find(|&s| !resolved.axes[s].present && mm_of(p)[s] != mm_of(prev)[s]) {
            return Err(ProgramError::new(
                block_line,
                format!("{what} moves {}, which is not configured in [axes]", names[slot]),
            ));
        }
        if let Some(slot) = (0..4).find(|&s| s != u && s != v && from[s] != to[s]) {
            return Err(ProgramError::new(
                block_line,
                format!(
                    "{what} moves {}, outside the point-by-point plane {plane_name} (interpolation.plane): only G0 may move it",
                    names[slot]
                ),
            ));
        }
        if extra(p) != extra(prev) {
            return Err(ProgramError::new(block_line, format!("{what} moves B, C, U, V or W: not on this machine")));
        }
        Ok(())
    };
    let feed_interval = |line: usize, length_mm: f64, feed: f64, decisions: u64| -> Result<u32, ProgramError> {
        if !(feed.is_finite() && feed > 0.0) {
            return Err(ProgramError::new(line, format!("feed F{feed}: a point-by-point move needs a positive feed")));
        }
        let interval = decision_interval(resolved.clock_hz, length_mm, feed, decisions, pbp.min_interval).ok_or_else(|| {
            let slowest = resolved.clock_hz * length_mm * 60.0 / (decisions as f64 * f64::from(PBP_INTERVAL_MAX));
            ProgramError::new(
                line,
                format!(
                    "F{feed} is too slow for the point-by-point divider (a decision every {} clocks at most): at least F{:.3} here",
                    PBP_INTERVAL_MAX, slowest
                ),
            )
        })?;
        Ok(interval - 1)
    };
    for block in &program.blocks {
        let line = block.line;
        let event = |action: IoAction| TimedEvent { period: 0, event: IoEvent { line, action } };
        let refuse = |what: &str| {
            Err(ProgramError::new(line, format!("{what}: not in point-by-point mode ([interpolation] mode = \"pbp\")")))
        };
        let mut events = Vec::new();
        match &block.kind {
            BlockKind::Rapid { to } => {
                let target = to_steps(to);
                if let Some(slot) = (0..4).find(|&s| !resolved.axes[s].present && mm_of(to)[s] != mm_of(&at_mm)[s]) {
                    return Err(ProgramError::new(
                        line,
                        format!("G0 moves {}, which is not configured in [axes]", names[slot]),
                    ));
                }
                if extra(to) != extra(&at_mm) {
                    return Err(ProgramError::new(line, "G0 moves B, C, U, V or W: not on this machine"));
                }
                if target != at {
                    // One rapid from rest to rest, planned from the origin by the DDA
                    // planner: its increments sum to the steps from here exactly.
                    let rel = |s: usize, mm: f64| {
                        if resolved.axes[s].present {
                            (target[s] - at[s]) as f64 / spu[s]
                        } else {
                            mm
                        }
                    };
                    let rel_to = Point {
                        x_mm: rel(0, to.x_mm),
                        y_mm: rel(1, to.y_mm),
                        z_mm: rel(2, to.z_mm),
                        a_deg: rel(3, to.a_deg),
                        ..Point::default()
                    };
                    let rapid =
                        Program { blocks: vec![Block { line, n: None, kind: BlockKind::Rapid { to: rel_to } }] };
                    let planned = crate::plan_program(config, &rapid).map_err(|e| ProgramError::new(line, e.reason))?;
                    let mut sum = [0i64; 4];
                    for record in &planned.records {
                        for (slot, total) in sum.iter_mut().enumerate() {
                            *total += i64::from(record.inc[slot].to_bits());
                        }
                        plan.planned.records.push(to_chip(record));
                        plan.planned.lines.push(line);
                        plan.clocks += u64::from(resolved.period_clocks);
                    }
                    let moved: [i64; 4] = std::array::from_fn(|s| target[s] - at[s]);
                    if sum.map(|d| d >> 16) != moved
                        || sum.iter().any(|d| d & 0xFFFF != 0)
                        || !planned.records.last().is_some_and(|r| r.block_end())
                    {
                        return Err(ProgramError::new(
                            line,
                            "G0: the DDA's records do not end at rest on the target (planner)",
                        ));
                    }
                    for note in planned.notes {
                        if !plan.planned.notes.contains(&note) {
                            plan.planned.notes.push(note);
                        }
                    }
                    plan.planned.elements += 1;
                    at = target;
                }
                at_mm = *to;
            }
            BlockKind::Linear { to, feed_mm_per_min } => {
                let target = to_steps(to);
                off_plane(line, "G1", &at, &target, to, &at_mm)?;
                let (du, dv) = (target[u] - at[u], target[v] - at[v]);
                let decisions = du.unsigned_abs() + dv.unsigned_abs();
                if decisions > 0 {
                    let length_mm = ((du * du + dv * dv) as f64).sqrt() / spu[u];
                    let tick_div = feed_interval(line, length_mm, *feed_mm_per_min, decisions)?;
                    push_pbp(&mut plan, line_records((at[u], at[v]), (target[u], target[v]), tick_div), line);
                    plan.planned.elements += 1;
                }
                at = target;
                at_mm = *to;
            }
            BlockKind::Arc { to, centre, plane, clockwise, extra_turns, feed_mm_per_min } => {
                if *plane != pbp.plane {
                    return Err(ProgramError::new(
                        line,
                        format!("an arc in {plane:?}, but the point-by-point pair is the plane {plane_name} (interpolation.plane)"),
                    ));
                }
                let target = to_steps(to);
                off_plane(line, "the arc (a helix)", &at, &target, to, &at_mm)?;
                let c = to_steps(centre);
                let cw = *clockwise != pbp.mirrored;
                // The programmed sweep on the pair (mm), for a closed arc's meaning.
                let mm = |p: &Point| [p.x_mm, p.y_mm, p.z_mm, p.a_deg];
                let (s_mm, e_mm, c_mm) = (mm(&at_mm), mm(to), mm(centre));
                let angle = |p: [f64; 4]| (p[v] - c_mm[v]).atan2(p[u] - c_mm[u]);
                let turn = std::f64::consts::TAU;
                let sweep = |from: f64, to: f64| {
                    let d = if cw { from - to } else { to - from };
                    d.rem_euclid(turn)
                };
                let programmed = sweep(angle(s_mm), angle(e_mm));
                let closed_is_turn = programmed == 0.0 || programmed > turn / 2.0;
                let arc = arc_records(
                    (at[u], at[v]),
                    (c[u], c[v]),
                    (target[u], target[v]),
                    cw,
                    *extra_turns,
                    closed_is_turn,
                    0,
                )
                .map_err(|e| ProgramError::new(line, format!("point-by-point arc: {e}")))?;
                if arc.end != (target[u], target[v]) {
                    plan.planned.notes.push(format!(
                        "line {line}: the arc ends on its path {} steps in {} and {} in {} from the programmed end",
                        arc.end.0 - target[u],
                        names[u],
                        arc.end.1 - target[v],
                        names[v]
                    ));
                }
                let decisions: u64 = arc.records.iter().map(|r| r.steps).sum();
                if decisions > 0 {
                    // The path's length on the pair: the radius (steps) times the sweep to
                    // where the records end, whole turns included.
                    let r = (((at[u] - c[u]).pow(2) + (at[v] - c[v]).pow(2)) as f64).sqrt();
                    let fa = |p: (i64, i64)| ((p.1 - c[v]) as f64).atan2((p.0 - c[u]) as f64);
                    let mut part = sweep(fa((at[u], at[v])), fa(arc.end));
                    if part == 0.0 && arc.records.len() > *extra_turns as usize {
                        part = turn;
                    }
                    let length_mm = r * (part + turn * f64::from(*extra_turns)) / spu[u];
                    let tick_div = feed_interval(line, length_mm, *feed_mm_per_min, decisions)?;
                    let lanes = arc.records.into_iter().map(|l| PbpLanes { tick_div, ..l }).collect();
                    push_pbp(&mut plan, lanes, line);
                    plan.planned.elements += 1;
                }
                at[u] = arc.end.0;
                at[v] = arc.end.1;
                at_mm = *to;
            }
            BlockKind::Dwell { seconds } => {
                let periods = (seconds / resolved.period_s).ceil().max(0.0) as usize;
                for k in 0..periods {
                    let flags = if k + 1 == periods { flags::BLOCK_END } else { 0 };
                    plan.planned.records.push(PeriodRecord { flags, ..PeriodRecord::default() });
                    plan.planned.lines.push(line);
                    plan.clocks += u64::from(resolved.period_clocks);
                }
            }
            BlockKind::Spindle { rotation, rpm, css } => {
                if css.is_some() {
                    return refuse("G96 (constant surface speed)");
                }
                let max = resolved.spindle_max_rpm;
                if !(0.0..=max).contains(rpm) {
                    return Err(ProgramError::new(
                        line,
                        format!("S{rpm} is outside 0..={max} rev/min (spindle.max_rpm)"),
                    ));
                }
                events.push(event(IoAction::Spindle { rotation: *rotation, rpm: *rpm, fraction: rpm / max }));
            }
            BlockKind::Coolant { mist, flood } => events.push(event(IoAction::Coolant { mist: *mist, flood: *flood })),
            BlockKind::DigitalOutput { index, on } => {
                if *index > 7 {
                    return Err(ProgramError::new(
                        line,
                        format!("digital output P{index}: the chip has outputs 0 to 7"),
                    ));
                }
                events.push(event(IoAction::Output { index: *index, on: *on }));
            }
            BlockKind::Message { kind: kind @ (MessageKind::Msg | MessageKind::Debug), text } => {
                events.push(event(IoAction::Message { kind: *kind, text: text.clone() }))
            }
            BlockKind::CutterComp { side: CompSide::Off, .. }
            | BlockKind::Message { .. }
            | BlockKind::ToolSelect { .. }
            | BlockKind::ToolChange { .. }
            | BlockKind::PathControl(_)
            | BlockKind::Overrides(_)
            | BlockKind::Pause
            | BlockKind::End => {}
            BlockKind::CutterComp { .. } | BlockKind::CutterCompRadius { .. } => return refuse("cutter compensation"),
            BlockKind::Nurbs { .. } => return refuse("G5.2/G5.3 (NURBS)"),
            BlockKind::Probe { .. } => return refuse("G38.x (probing)"),
            BlockKind::WaitInput { .. } => return refuse("M66"),
            BlockKind::AnalogOutput { .. } => return refuse("M67/M68"),
            BlockKind::UserMCode { code, .. } => return refuse(&format!("M{code} (a user M-code)")),
            BlockKind::SpindleOrient { .. } => return refuse("M19 (spindle orientation)"),
        }
        for mut timed in events {
            timed.period = plan.planned.records.len() as u64;
            plan.planned.events.push(timed);
        }
    }
    plan.planned.end = std::array::from_fn(|s| at[s] as f64 / spu[s]);
    Ok(plan)
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
        assert_eq!(tick_div(50e6, 100.0, 10, 3), PBP_INTERVAL_MAX - 1);
        assert_eq!(tick_div(50e6, 1.0, 0, 4), 4);
    }
}
