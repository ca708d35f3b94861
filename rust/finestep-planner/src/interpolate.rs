//! Time-division interpolation of the planned path: at the end of every period T the
//! position on the path is taken from the elements' speed profiles (a period may
//! straddle several elements), quantised to the core's Q16.16 step grid from its exact
//! value, and differenced into per-period increments; no rounding accumulates. At an
//! exact stop the period ends on the stop point snapped to whole steps (the vertices
//! are on whole steps already), so the increments sum exactly to it, and the next move
//! starts with the next period. Every record is checked against the drive's rated rate
//! ([`RateChecker`]) before it is emitted.
//!
//! NURBS sub-pieces are interpolated directly: a [`NurbsCursor`] carries the curve
//! parameter from period to period and steps it by the arc length the profile asks
//! for (second-order Taylor step and Newton correction, [`crate::nurbs`]).

use finestep_interface::rate::RateChecker;
use finestep_interface::{Increment, PeriodRecord};

use crate::config::{Resolved, AXIS_NAMES};
use crate::element::{Element, Shape};
use crate::error::ProgramError;
use crate::lookahead::element_limits;
use crate::nurbs::NurbsCursor;
use crate::vec4::Vec4;
use crate::velocity::Profile;
use finestep_interface::flags::BLOCK_END;

/// Periods and where they came from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Interpolated {
    /// One record per period.
    pub records: Vec<PeriodRecord>,
    /// The source line being executed at the end of each period.
    pub lines: Vec<usize>,
}

struct Emitter<'a> {
    config: &'a Resolved,
    checker: RateChecker,
    last: [i64; 4],
    out: Interpolated,
}

/// The most periods one program may take (about 5.5 hours at 1 ms), so that a program
/// asking for absurd times is refused instead of exhausting memory.
pub const MAX_PERIODS: usize = 20_000_000;

impl Emitter<'_> {
    fn emit(&mut self, grid: [i64; 4], flags: u8, line: usize) -> Result<(), ProgramError> {
        if self.out.records.len() >= MAX_PERIODS {
            return Err(ProgramError { line, reason: format!("the program takes more than {MAX_PERIODS} periods") });
        }
        let mut record = PeriodRecord { flags, ..PeriodRecord::default() };
        for a in 0..4 {
            let delta = grid[a] - self.last[a];
            let raw = i32::try_from(delta).map_err(|_| ProgramError {
                line,
                reason: format!("axis {} would move {} steps in one period", AXIS_NAMES[a], delta as f64 / 65536.0),
            })?;
            record.inc[a] = Increment::from_bits(raw);
        }
        self.checker.check(&record).map_err(|(axis, why)| ProgramError {
            line,
            reason: format!("axis {}: {why} (planner bug: refusing to emit)", AXIS_NAMES.get(axis).unwrap_or(&"?")),
        })?;
        self.last = grid;
        self.out.records.push(record);
        self.out.lines.push(line);
        Ok(())
    }

    fn grid(&self, p: Vec4) -> [i64; 4] {
        let mut g = [0i64; 4];
        for (a, axis) in self.config.axes.iter().enumerate() {
            g[a] = (p[a] * axis.steps_per_unit * 65536.0).round() as i64;
        }
        g
    }

    fn grid_exact(&self, p: Vec4) -> [i64; 4] {
        let mut g = [0i64; 4];
        for (a, axis) in self.config.axes.iter().enumerate() {
            g[a] = ((p[a] * axis.steps_per_unit).round() as i64) << 16;
        }
        g
    }
}

/// Periods for `elements` run at junction speeds `speeds` (`elements.len() + 1` of them),
/// after `leading_dwell` idle periods, starting at the origin.
pub fn interpolate(
    config: &Resolved,
    elements: &[Element],
    speeds: &[f64],
    leading_dwell: u64,
) -> Result<Interpolated, ProgramError> {
    let mut emitter = Emitter {
        config,
        checker: RateChecker::new(config.period_clocks, &config.timing),
        last: [0; 4],
        out: Interpolated::default(),
    };
    let idle = |emitter: &mut Emitter, periods: u64, line: usize| -> Result<(), ProgramError> {
        for _ in 0..periods {
            emitter.emit(emitter.last, 0, line)?;
        }
        Ok(())
    };
    idle(&mut emitter, leading_dwell, elements.first().map_or(0, |e| e.line))?;
    let profile_of = |i: usize| {
        let e = &elements[i];
        Profile::new(&element_limits(config, e), e.length, speeds[i], speeds[i + 1], e.v_cap)
    };
    let period = config.period_s;
    let mut index = 0;
    if elements.is_empty() {
        return Ok(emitter.out);
    }
    let mut profile = profile_of(0);
    let mut t = 0.0;
    let mut cursor = NurbsCursor::new(usize::MAX, 0.0);
    'periods: loop {
        t += period;
        let mut flags = 0;
        while t >= profile.duration {
            let element = &elements[index];
            if element.block_end {
                flags |= BLOCK_END;
            }
            if element.stop_after {
                let grid = emitter.grid_exact(element.end);
                emitter.emit(grid, flags, element.line)?;
                idle(&mut emitter, element.dwell_periods, element.dwell_line)?;
                index += 1;
                if index == elements.len() {
                    break 'periods;
                }
                profile = profile_of(index);
                t = 0.0;
                continue 'periods;
            }
            t -= profile.duration;
            index += 1;
            if index == elements.len() {
                // Unreachable: the last element always stops; end on it all the same.
                let grid = emitter.grid_exact(element.end);
                emitter.emit(grid, flags, element.line)?;
                break 'periods;
            }
            profile = profile_of(index);
        }
        let element = &elements[index];
        let s = profile.distance_at(t);
        let point = match element.shape {
            Shape::Nurbs { ref curve, u0, u1 } => {
                if cursor.element != index {
                    cursor = NurbsCursor::new(index, u0);
                }
                if s >= element.length {
                    element.end
                } else {
                    curve.point(cursor.advance(curve, u1, s))
                }
            }
            _ => element.position(s),
        };
        let grid = emitter.grid(point);
        emitter.emit(grid, flags, element.line)?;
    }
    Ok(emitter.out)
}
