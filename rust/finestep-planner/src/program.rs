//! A parsed part program to period records, block by block, in exact-stop mode: every
//! move accelerates from and decelerates to the start/stop speed on its own (G61).
//! Look-ahead with blended corners (G64) and cutter compensation are not implemented
//! yet: a program asking for compensation is refused rather than cut uncompensated, and
//! G64 runs as exact stop (reported in [`PlannedProgram::notes`]).

use finestep_gcode::{BlockKind, CompSide, PathControl, Plane, Point, Program};
use finestep_model::PeriodRecord;

use crate::arc::{interpolate_arc, ArcMove};
use crate::linear::{interpolate_line, LineMove, Machine, PlanError};

/// Feed limits of a machine with axes X, Y, Z (mm) and A (degrees), in that order.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionLimits {
    /// Feed of G0 rapids, units/s.
    pub rapid_mm_s: f64,
    /// Start and stop speed of every move, units/s.
    pub start_speed_mm_s: f64,
    /// Path acceleration, units/s^2.
    pub accel_mm_s2: f64,
    /// Largest distance between an arc's chords and the circle, mm.
    pub chord_tolerance_mm: f64,
}

/// The records of one program block.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedBlock {
    /// 1-based source line.
    pub line: usize,
    /// The block's periods.
    pub records: Vec<PeriodRecord>,
}

/// A whole program's periods, block by block.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PlannedProgram {
    /// Blocks that move or wait, in order.
    pub blocks: Vec<PlannedBlock>,
    /// Where the program ends, in axis units (X, Y, Z, A).
    pub end: [f64; 4],
    /// What was not carried out as programmed, for the report.
    pub notes: Vec<String>,
}

/// Why a program cannot be planned: the block's line and the reason.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("line {line}: {reason}")]
pub struct ProgramError {
    /// 1-based source line.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

fn coords(p: &Point) -> [f64; 4] {
    [p.x_mm, p.y_mm, p.z_mm, p.a_deg]
}

/// Plan `program` for a machine with four axes X, Y, Z, A (`machine.steps_per_unit` has
/// four entries), starting at the origin.
pub fn plan_program(machine: &Machine, limits: &MotionLimits, program: &Program) -> Result<PlannedProgram, ProgramError> {
    if machine.steps_per_unit.len() != 4 {
        return Err(ProgramError { line: 0, reason: "the machine must have the four axes X, Y, Z, A".into() });
    }
    let mut planned = PlannedProgram::default();
    let mut at = [0.0; 4];
    let mut warned_blend = false;
    for block in &program.blocks {
        let fail = |e: PlanError| ProgramError { line: block.line, reason: e.to_string() };
        let records = match block.kind {
            BlockKind::Rapid { to } | BlockKind::Linear { to, .. } => {
                let feed = match block.kind {
                    BlockKind::Linear { feed_mm_per_min, .. } => feed_mm_per_min / 60.0,
                    _ => limits.rapid_mm_s,
                };
                let line = LineMove {
                    from_mm: at.to_vec(),
                    to_mm: coords(&to).to_vec(),
                    feed_mm_s: feed,
                    start_speed_mm_s: limits.start_speed_mm_s,
                    accel_mm_s2: limits.accel_mm_s2,
                };
                at = coords(&to);
                interpolate_line(machine, &line).map_err(fail)?
            }
            BlockKind::Arc { to, centre, plane, clockwise, extra_turns, feed_mm_per_min } => {
                // Plane axes ordered so that counter-clockwise turns from the first to the second.
                let (first, second) = match plane {
                    Plane::Xy => (0, 1),
                    Plane::Zx => (2, 0),
                    Plane::Yz => (1, 2),
                };
                let c = coords(&centre);
                let arc = ArcMove {
                    from_mm: at.to_vec(),
                    to_mm: coords(&to).to_vec(),
                    plane: (first, second),
                    centre_mm: (c[first], c[second]),
                    clockwise,
                    extra_turns,
                    feed_mm_s: feed_mm_per_min / 60.0,
                    start_speed_mm_s: limits.start_speed_mm_s,
                    accel_mm_s2: limits.accel_mm_s2,
                    chord_tolerance_mm: limits.chord_tolerance_mm,
                };
                at = coords(&to);
                interpolate_arc(machine, &arc).map_err(fail)?
            }
            BlockKind::Dwell { seconds } => {
                let periods = (seconds / machine.period_s).ceil();
                if !(0.0..=1e9).contains(&periods) {
                    return Err(ProgramError { line: block.line, reason: format!("dwell of {seconds} s is out of range") });
                }
                vec![PeriodRecord::default(); periods as usize]
            }
            BlockKind::CutterComp { side: CompSide::Left | CompSide::Right, .. } => {
                return Err(ProgramError {
                    line: block.line,
                    reason: "cutter radius compensation (G41/G42) is not implemented yet; refusing to cut uncompensated".into(),
                });
            }
            BlockKind::PathControl(PathControl::Blend { .. }) => {
                if !warned_blend {
                    planned.notes.push(format!("line {}: G64 blending runs as exact stop (no look-ahead yet)", block.line));
                    warned_blend = true;
                }
                continue;
            }
            BlockKind::End => break,
            _ => continue,
        };
        planned.blocks.push(PlannedBlock { line: block.line, records });
    }
    planned.end = at;
    Ok(planned)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> MotionLimits {
        MotionLimits { rapid_mm_s: 50.0, start_speed_mm_s: 1.0, accel_mm_s2: 500.0, chord_tolerance_mm: 0.001 }
    }

    fn machine() -> Machine {
        Machine::new(vec![800.0, 800.0, 400.0, 100.0], 0.001)
    }

    fn totals(planned: &PlannedProgram) -> [i64; 4] {
        let mut sum = [0i64; 4];
        for block in &planned.blocks {
            for record in &block.records {
                for (axis, total) in sum.iter_mut().enumerate() {
                    *total += i64::from(record.inc[axis].to_bits());
                }
            }
        }
        sum
    }

    #[test]
    fn a_contour_with_arcs_ends_exactly_where_the_program_ends() {
        let source = "G21 G90 G17\nG0 X5 Y0 Z2\nG1 Z-1 F600\nG3 X0 Y5 I-5 J0\nG2 X-5 Y0 R5\nG18 G2 X-5 Z-3 I0 K-1\nG4 P0.01\nG1 X0 Y0 Z0 A90\nM2\n";
        let program = finestep_gcode::parse_str(source, "contour.ngc").unwrap();
        let planned = plan_program(&machine(), &limits(), &program).unwrap();
        assert_eq!(planned.end, [0.0, 0.0, 0.0, 90.0]);
        assert_eq!(totals(&planned), [0, 0, 0, (90 * 100) << 16]);
        assert_eq!(planned.blocks.iter().find(|b| b.line == 7).map(|b| b.records.len()), Some(10));
    }

    #[test]
    fn compensation_is_refused_and_blending_noted() {
        let program = finestep_gcode::parse_str("G64 P0.01\nG41 D1\nG1 X1 F100\n", "comp.ngc").unwrap();
        let error = plan_program(&machine(), &limits(), &program).unwrap_err();
        assert_eq!(error.line, 2);
        assert!(error.reason.contains("not implemented"), "{error}");
        let program = finestep_gcode::parse_str("G64 P0.01\nG1 X1 F100\n", "blend.ngc").unwrap();
        let planned = plan_program(&machine(), &limits(), &program).unwrap();
        assert_eq!(planned.notes.len(), 1);
    }
}
