//! A parsed part program to period records: the path (lines, arcs, G64 corner blends,
//! see [`crate::geometry`]), look-ahead junction speeds ([`crate::lookahead`]), a
//! trapezoid or S-curve speed profile per element ([`crate::velocity`]) and time-division
//! interpolation across element boundaries ([`crate::interpolate`]).
//!
//! Cutter radius compensation (G41/G42, [`crate::cutter_comp`]) runs first, on the
//! canonical blocks, with the radii of the configuration's tool table.

use std::sync::{Arc, OnceLock};

use finestep_gcode::{GcodeError, Program};
use finestep_interface::PeriodRecord;

use crate::config::MachineConfig;
use crate::cutter_comp::{compensated, Compensating};
use crate::element::{Element, TimedEvent};
pub use crate::error::ProgramError;
use crate::geometry::{program_end, BlockSource, PathStream};
use crate::interpolate::Periods;

impl From<crate::cutter_comp::CompError> for ProgramError {
    fn from(e: crate::cutter_comp::CompError) -> Self {
        ProgramError::new(e.line, e.reason)
    }
}

/// A whole program's periods.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PlannedProgram {
    /// One record per period, in order.
    pub records: Vec<PeriodRecord>,
    /// The source line being executed at the end of each period.
    pub lines: Vec<usize>,
    /// Where the program ends, in axis units (X, Y, Z, A), on whole steps.
    pub end: [f64; 4],
    /// Path elements planned (programmed moves plus corner blends).
    pub elements: usize,
    /// What was adjusted or not carried out as programmed, for the report.
    pub notes: Vec<String>,
    /// The spindle and coolant changes (S, M3/M4/M5, M7/M8/M9) in program order, each at
    /// the record index where it takes effect: the record before it ends an exact stop
    /// at the point where the block is written (flagged block end).
    pub events: Vec<TimedEvent>,
}

/// A program's periods as a stream ([`Periods`]): records are produced as they are
/// consumed, and the path is read from the program as the look-ahead window reaches it,
/// so memory grows neither with the program's duration nor with its length (beyond the
/// parsed program itself, which [`plan_stream`]'s stream borrows; [`plan_blocks`] reads
/// the program as it goes).
#[derive(Debug)]
pub struct PlanStream<'p> {
    /// The records, each with the source line executed at the end of its period.
    pub periods: Periods<'p>,
    /// What was adjusted or not carried out as programmed, for the report.
    pub notes: Vec<String>,
    end: Arc<OnceLock<[f64; 4]>>,
}

impl PlanStream<'_> {
    /// Where the program ends, in axis units (X, Y, Z, A), on whole steps: known from
    /// the start for [`plan_stream`], once the path has been read to the program's end
    /// for [`plan_blocks`].
    pub fn end(&self) -> Option<[f64; 4]> {
        self.end.get().copied()
    }
}

/// An element the interpolation can follow: a finite length and positive, finite limits.
fn usable(e: Box<Element>) -> Result<Box<Element>, ProgramError> {
    if e.length.is_finite() && e.v_cap > 0.0 && e.v_cap.is_finite() && e.accel > 0.0 && e.jerk > 0.0 {
        Ok(e)
    } else {
        Err(ProgramError::new(e.line, format!("no usable speed limits for this move ({e:?})")))
    }
}

/// Plans `program` on the machine `config`, starting at rest at the origin: the
/// configuration is resolved and cutter compensation applied here (a program with
/// G41/G42 is compensated whole first), the program read up to its first move; the path,
/// the look-ahead and the periods run as the stream is read, and a block that cannot be
/// planned ends the stream with its error where the path reaches it.
pub fn plan_stream<'p>(config: &MachineConfig, program: &'p Program) -> Result<PlanStream<'p>, ProgramError> {
    let resolved = config.resolve()?;
    let program = compensated(program, &config.tool_table()).map_err(|e| ProgramError::new(e.line, e.reason))?;
    let end = Arc::new(OnceLock::from(program_end(&resolved, &program)));
    let notes = resolved.notes.clone();
    let path = PathStream::new(&resolved, program)?;
    let (dwell, events) = (path.leading_dwell(), path.leading_events().to_vec());
    let source = Box::new(path.map(|e| e.and_then(usable)));
    Ok(PlanStream { periods: Periods::from_source(resolved, source, dwell).with_leading_events(&events), notes, end })
}

/// [`plan_stream`] of a program read as it is planned: `blocks` gives its canonical
/// blocks as the parser executes them ([`finestep_gcode::stream_file`]), and they are read
/// only as the look-ahead window reaches them, so that neither the program's text nor
/// its blocks are held (cutter compensation runs on them as they are read,
/// [`Compensating`]). The records are those [`plan_stream`] gives for the program
/// collected; an error of the parser or of compensation ends the stream where the path
/// reaches it ([`ProgramError::located`] holds the parser's).
pub fn plan_blocks<'p>(
    config: &MachineConfig,
    blocks: impl Iterator<Item = Result<finestep_gcode::Block, GcodeError>> + Send + 'p,
) -> Result<PlanStream<'p>, ProgramError> {
    let resolved = config.resolve()?;
    let notes = resolved.notes.clone();
    let blocks = blocks.map(|b| b.map_err(|e| ProgramError::parse(&e)));
    let blocks: BlockSource<'p> = Box::new(Compensating::new(blocks, config.tool_table()));
    let path = PathStream::from_blocks(&resolved, blocks)?;
    let end = path.end();
    let (dwell, events) = (path.leading_dwell(), path.leading_events().to_vec());
    let source = Box::new(path.map(|e| e.and_then(usable)));
    Ok(PlanStream { periods: Periods::from_source(resolved, source, dwell).with_leading_events(&events), notes, end })
}

/// Plan and interpolate `program` on the machine `config`, starting at rest at the
/// origin, every record collected ([`plan_stream`] streams them instead).
pub fn plan_program(config: &MachineConfig, program: &Program) -> Result<PlannedProgram, ProgramError> {
    let mut stream = plan_stream(config, program)?;
    let mut records = Vec::new();
    let mut lines = Vec::new();
    for period in stream.periods.by_ref() {
        let (record, line) = period?;
        records.push(record);
        lines.push(line);
    }
    let events = stream.periods.take_events();
    let elements = stream.periods.elements_read();
    let end = stream.end().expect("known from the start");
    Ok(PlannedProgram { records, lines, end, elements, notes: stream.notes, events })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ProfileKind;

    fn totals(planned: &PlannedProgram) -> [i64; 4] {
        let mut sum = [0i64; 4];
        for record in &planned.records {
            for (axis, total) in sum.iter_mut().enumerate() {
                *total += i64::from(record.inc[axis].to_bits());
            }
        }
        sum
    }

    #[test]
    fn a_contour_with_arcs_ends_exactly_where_the_program_ends() {
        let source = "G21 G90 G17\nG0 X5 Y0 Z2\nG1 Z-1 F600\nG3 X0 Y5 I-5 J0\nG2 X-5 Y0 R5\nG18 G2 X-5 Z-3 I0 K-1\nG4 P0.01\nG1 X0 Y0 Z0 A90\nM2\n";
        let program = finestep_gcode::parse_str(source, "contour.ngc").unwrap();
        for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
            let config = MachineConfig { profile, ..MachineConfig::default() };
            let planned = plan_program(&config, &program).unwrap();
            assert_eq!(planned.end, [0.0, 0.0, 0.0, 90.0]);
            assert_eq!(totals(&planned), [0, 0, 0, (90 * 100) << 16]);
            // The dwell: ten idle periods on line 7.
            assert_eq!(planned.lines.iter().filter(|&&l| l == 7).count(), 10);
            assert!(planned.records.iter().filter(|r| r.flags & 1 != 0).count() >= 6);
        }
    }

    #[test]
    fn compensation_offsets_the_path_by_the_tool_radius() {
        // A 20 mm square cut counter-clockwise with the tool on the right of the path
        // (G42), i.e. outside, with tool 1 (r = 3 mm): the tool centre reaches x = 23 mm,
        // and leaves at the exit point.
        let source =
            "G21 G90 G17 F1200\nG0 X-10 Y-10\nG42 D1\nG1 X0 Y0\nG1 X20\nG1 Y20\nG1 X0\nG1 Y0\nG40\nG1 X-10 Y-10\nM2\n";
        let program = finestep_gcode::parse_str(source, "square.ngc").unwrap();
        let config = MachineConfig::default();
        let planned = plan_program(&config, &program).unwrap();
        let (mut x, mut y, mut max_x, mut min_y) = (0i64, 0i64, i64::MIN, i64::MAX);
        for record in &planned.records {
            x += i64::from(record.inc[0].to_bits());
            y += i64::from(record.inc[1].to_bits());
            max_x = max_x.max(x);
            min_y = min_y.min(y);
        }
        let steps = |mm: f64| (mm * 800.0) as i64 * 65536;
        assert_eq!(max_x, steps(23.0));
        assert_eq!(min_y, steps(-10.0).min(steps(-3.0)));
        assert_eq!((x, y), (steps(-10.0), steps(-10.0)));
        // The tool on the left of a counter-clockwise arc of r = 2 mm is inside it: gouge.
        let inside = "G21 G90 G17 F600\nG0 X0 Y0\nG41 D1\nG1 X10 Y0\nG3 X10 Y4 R2\nG40\nG1 X0 Y0\n";
        let error = plan_program(&config, &finestep_gcode::parse_str(inside, "pocket.ngc").unwrap()).unwrap_err();
        assert_eq!(error.line, 5, "{error}");
    }

    #[test]
    fn the_tool_table_comes_from_the_configuration() {
        let config = MachineConfig::from_toml_str("[[tools]]\nnumber = 7\nradius_mm = 2.5\n", "t.toml").unwrap();
        assert_eq!(config.tool_table().radius_mm(7), Some(2.5));
        assert_eq!(config.tool_table().radius_mm(1), None);
        let error = MachineConfig::from_toml_str("[[tools]]\nnumber = 7\nradius_mm = -1\n", "t.toml").unwrap_err();
        assert_eq!(error.key, "tools[0].radius_mm");
    }

    /// MSG and DEBUG are events at an exact stop where they are written (LinuxCNC's task
    /// sends an operator message once the motion before it has ended); PRINT is none and
    /// does not stop the path.
    #[test]
    fn msg_and_debug_stop_the_path_and_print_does_not() {
        use crate::element::IoAction;
        use finestep_gcode::MessageKind;
        let config = MachineConfig::default(); // X at 800 steps/mm, T = 1 ms
        let text = "G64\nG1 X1 F600\n(MSG, at one)\nG1 X2\n#1 = 3 (DEBUG, at two, #1)\nG1 X3\n(PRINT, p)\nG1 X4\nM2\n";
        let planned = plan_program(&config, &finestep_gcode::parse_str(text, "msg.ngc").unwrap()).unwrap();
        let x_after =
            |n: u64| -> i64 { planned.records[..n as usize].iter().map(|r| i64::from(r.inc[0].to_bits())).sum() };
        let x_inc = |i: u64| i64::from(planned.records[i as usize].inc[0].to_bits());
        let events: Vec<(u64, usize, IoAction)> =
            planned.events.iter().map(|e| (e.period, e.event.line, e.event.action.clone())).collect();
        let message = |kind, text: &str| IoAction::Message { kind, text: text.to_string() };
        assert_eq!(events.len(), 2, "{events:?}");
        assert_eq!((events[0].1, events[0].2.clone()), (3, message(MessageKind::Msg, " at one")));
        assert_eq!((events[1].1, events[1].2.clone()), (5, message(MessageKind::Debug, " at two, 3.000000")));
        let steps = |mm: i64| (mm * 800) << 16;
        for (p, mm) in [(events[0].0, 1), (events[1].0, 2)] {
            assert_eq!(x_after(p), steps(mm));
            assert!(planned.records[p as usize - 1].flags & 1 != 0);
            assert!(x_inc(p - 1).abs() < 1 << 16, "{}", x_inc(p - 1));
            assert!(x_inc(p).abs() < 1 << 16, "{}", x_inc(p));
        }
        // At X3 (the PRINT) the path goes on at speed: full feed is 8 steps per period.
        let at_three = (0..planned.records.len() as u64).find(|&n| x_after(n) >= steps(3)).unwrap();
        assert!(x_inc(at_three).abs() > 4 << 16, "{}", x_inc(at_three));
    }

    #[test]
    fn spindle_and_coolant_changes_stop_the_path_where_they_are_written() {
        use crate::element::IoAction;
        use finestep_gcode::SpindleRotation;
        let config = MachineConfig::default(); // X at 800 steps/mm, T = 1 ms
        let text = "G64\nG1 X1 F600\nM3 S1000\nG1 X2\nM8\nG1 X3\nM5 M9\nM2\n";
        let planned = plan_program(&config, &finestep_gcode::parse_str(text, "io.ngc").unwrap()).unwrap();
        let x_after =
            |n: u64| -> i64 { planned.records[..n as usize].iter().map(|r| i64::from(r.inc[0].to_bits())).sum() };
        let x_inc = |i: u64| i64::from(planned.records[i as usize].inc[0].to_bits());
        let events: Vec<(u64, usize, IoAction)> =
            planned.events.iter().map(|e| (e.period, e.event.line, e.event.action.clone())).collect();
        assert_eq!(events.len(), 4, "{events:?}");
        let on = IoAction::Spindle { rotation: SpindleRotation::Clockwise, rpm: 1000.0, fraction: 1000.0 / 24000.0 };
        let off = IoAction::Spindle { rotation: SpindleRotation::Off, rpm: 1000.0, fraction: 1000.0 / 24000.0 };
        assert_eq!((events[0].1, events[0].2.clone()), (3, on));
        assert_eq!((events[1].1, events[1].2.clone()), (5, IoAction::Coolant { mist: false, flood: true }));
        assert_eq!((events[2].1, events[2].2.clone()), (7, off.clone()));
        assert_eq!((events[3].1, events[3].2.clone()), (7, IoAction::Coolant { mist: false, flood: false }));
        let steps = |mm: i64| (mm * 800) << 16;
        for (event, mm) in [(events[0].clone(), 1), (events[1].clone(), 2), (events[2].clone(), 3)] {
            let p = event.0;
            // The program position at the event is the block's point, exactly on the step.
            assert_eq!(x_after(p), steps(mm), "{event:?}");
            // The record before it ends at rest (block end) and the path stops there: the
            // last increment before it and the first after it are below a speed of one
            // step per period (full feed is 8 steps per period).
            assert!(planned.records[p as usize - 1].flags & 1 != 0);
            assert!(x_inc(p - 1).abs() < 1 << 16, "{}", x_inc(p - 1));
            if p < planned.records.len() as u64 {
                assert!(x_inc(p).abs() < 1 << 16, "{}", x_inc(p));
            }
        }
        assert_eq!(events[3].0, planned.records.len() as u64);
        // The independent checker reads the M codes as exact stops too and finds all
        // three on their steps (X1, X2, X3 and the end).
        let report =
            crate::check_program(&config, &finestep_gcode::parse_str(text, "io.ngc").unwrap(), &planned.records)
                .unwrap();
        assert!(report.passed());
        assert_eq!(report.exact_stops, 3);
        // Without the M codes the collinear moves blend at full feed through X1 and X2.
        let plain = "G64\nG1 X1 F600\nG1 X2\nG1 X3\nM2\n";
        let blended = plan_program(&config, &finestep_gcode::parse_str(plain, "plain.ngc").unwrap()).unwrap();
        assert!(blended.events.is_empty());
        let mut x = 0i64;
        for r in &blended.records {
            let before = x;
            x += i64::from(r.inc[0].to_bits());
            if before < steps(1) && x >= steps(1) {
                assert!(i64::from(r.inc[0].to_bits()) > 7 << 16);
            }
        }
        assert!(blended.records.len() < planned.records.len());
        // Before any move the event is at record 0; an S over spindle.max_rpm is refused at its line.
        let first = plan_program(&config, &finestep_gcode::parse_str("M8\nG1 X1 F600\n", "m8.ngc").unwrap()).unwrap();
        assert_eq!(first.events[0].period, 0);
        // M2 turns off what the program left on, after the last move (LinuxCNC's M5 M9).
        let left = "M3 S1000\nM7\nG1 X1 F600\nM2\n";
        let left = plan_program(&config, &finestep_gcode::parse_str(left, "left.ngc").unwrap()).unwrap();
        let ends: Vec<(u64, usize, IoAction)> =
            left.events.iter().map(|e| (e.period, e.event.line, e.event.action.clone())).collect();
        let n = left.records.len() as u64;
        let on = IoAction::Spindle { rotation: SpindleRotation::Clockwise, rpm: 1000.0, fraction: 1000.0 / 24000.0 };
        assert_eq!(
            ends,
            vec![
                (0, 1, on),
                (0, 2, IoAction::Coolant { mist: true, flood: false }),
                (n, 4, off),
                (n, 4, IoAction::Coolant { mist: false, flood: false })
            ]
        );
        let error =
            plan_program(&config, &finestep_gcode::parse_str("G1 X1 F600\nM3 S30000\n", "s.ngc").unwrap()).unwrap_err();
        assert_eq!(error.line, 2, "{error}");
        assert!(error.reason.contains("spindle.max_rpm"), "{error}");
    }

    #[test]
    fn unconfigured_axes_may_not_move() {
        let config = MachineConfig::from_toml_str("[axes.X]\n[axes.Y]\n", "xy.toml").unwrap();
        let program = finestep_gcode::parse_str("G1 X1 Y1 F600\nG1 Z1\n", "z.ngc").unwrap();
        let error = plan_program(&config, &program).unwrap_err();
        assert_eq!((error.line, error.reason.as_str()), (2, "axis Z moves but is not configured"));
    }

    #[test]
    fn the_axes_b_c_u_v_w_are_interpreted_but_refused() {
        // The interpreter takes LinuxCNC's nine axes; the chip drives X Y Z A.
        let config = MachineConfig::default();
        for (axis, word) in [('B', "B10"), ('C', "C-1"), ('U', "U1"), ('V', "V1"), ('W', "W0.5")] {
            let source = format!("G0 X1 B0 C0 U0 V0 W0\nG1 {word} F600\n");
            let program = finestep_gcode::parse_str(&source, "b.ngc").unwrap();
            let error = plan_program(&config, &program).unwrap_err();
            assert_eq!(
                (error.line, error.reason.as_str()),
                (2, format!("axis {axis} moves, but the chip drives the axes X Y Z A (B C U V W are interpreted, not driven)").as_str()),
            );
        }
    }

    #[test]
    fn blending_keeps_speed_through_shallow_corners_and_exact_stop_does_not() {
        // A zig-zag of 40 short segments turning 10 degrees each way.
        let mut text = String::from("G21 G90 F3000\n");
        let (mut x, mut y) = (0.0f64, 0.0f64);
        for i in 0..40 {
            let angle = if i % 2 == 0 { 5.0f64 } else { -5.0 }.to_radians();
            x += 2.0 * angle.cos();
            y += 2.0 * angle.sin();
            text.push_str(&format!("G1 X{x:.4} Y{y:.4}\n"));
        }
        let blended = finestep_gcode::parse_str(&format!("G64 P0.01\n{text}"), "z.ngc").unwrap();
        let exact = finestep_gcode::parse_str(&format!("G61\n{text}"), "z.ngc").unwrap();
        // Trapezoid: blends at 10 degrees run at about sqrt(0.45 A R) = 34 mm/s. S-curve
        // is held back by the jerk where the blend's curvature starts, sqrt(0.25 J T R):
        // 8 mm/s at the default 1e5 mm/s^3, 26 mm/s at 1e6. The exact stops' lines take
        // the full limits (no junction of theirs jumps), the blended ones beside the
        // blends' curvature jumps the fixed shares (`element`): S-curve gains 1.37x
        // (1.9x while every line took the fixed shares: the exact stops got faster, the
        // blended run did not get slower). So the blended run is also held to its own
        // speed: on average at least the blends' speed above over the 80 mm.
        let path_mm = 80.0;
        for (profile, jerk, speed_up, blend_speed) in
            [(ProfileKind::Trapezoid, 1e5, 2.0, 34.0), (ProfileKind::SCurve, 1e6, 1.3, 26.0)]
        {
            let mut config = MachineConfig { profile, ..MachineConfig::default() };
            for axis in config.axes.values_mut() {
                axis.max_jerk = jerk;
            }
            let fast = plan_program(&config, &blended).unwrap();
            let slow = plan_program(&config, &exact).unwrap();
            assert_eq!(totals(&fast), totals(&slow));
            let (fast, slow) = (fast.records.len() as f64, slow.records.len() as f64);
            assert!(fast * speed_up < slow, "{profile:?}: {fast} vs {slow} periods");
            let period_s = config.period_ms * 1e-3;
            assert!(fast * period_s < path_mm / blend_speed, "{profile:?}: {fast} periods, below {blend_speed} mm/s");
        }
        // No period of the blended run is idle before the end.
        let fast = plan_program(&MachineConfig::default(), &blended).unwrap();
        let idle = fast.records.iter().filter(|r| r.inc.iter().all(|d| d.to_bits() == 0)).count();
        assert_eq!(idle, 0);
    }

    /// G96: each move runs at the speed of its point farthest from the spindle's axis
    /// (X 0 here), capped by D, set at an exact stop before it where it changes; moves
    /// whose farthest point keeps the speed keep their blends.
    #[test]
    fn constant_surface_speed_sets_each_moves_speed_at_a_stop_where_it_changes() {
        use crate::element::IoAction;
        use finestep_gcode::SpindleRotation::{Clockwise, Off};
        let config = MachineConfig::default(); // X at 800, Z at 400 steps/mm
        let text = "G18 G21 G90 G64 F300\nG0 X40 Z1\nG96 S100 D3000 M3\nG1 Z-10\nG1 X10\nG1 Z-20\nG1 X1\n\
                    G1 Z-25\nG97 S500\nG1 X5\nM2\n";
        let program = finestep_gcode::parse_str(text, "css.ngc").unwrap();
        let planned = plan_program(&config, &program).unwrap();
        let events: Vec<(u64, usize, IoAction)> =
            planned.events.iter().map(|e| (e.period, e.event.line, e.event.action.clone())).collect();
        let rpm = |r: f64| 100_000.0 / (std::f64::consts::TAU * r);
        let spindle = |rotation, rpm: f64| IoAction::Spindle { rotation, rpm, fraction: rpm / 24_000.0 };
        let expected = [
            (3, spindle(Clockwise, rpm(40.0))), // M3 at X40
            (6, spindle(Clockwise, rpm(10.0))), // G1 Z-20 at X10 (G1 X10 ran at X40's)
            (8, spindle(Clockwise, 3000.0)),    // G1 Z-25 at X1: 15 915 rev/min, D 3000
            (9, spindle(Clockwise, 500.0)),     // G97 S500
            (11, spindle(Off, 500.0)),          // M2
        ];
        let got: Vec<(usize, IoAction)> = events.iter().map(|e| (e.1, e.2.clone())).collect();
        assert_eq!(got.len(), expected.len(), "{got:?}");
        for ((line, action), (want_line, want)) in got.iter().zip(expected) {
            assert_eq!(*line, want_line);
            let (IoAction::Spindle { rpm: a, rotation: ra, .. }, IoAction::Spindle { rpm: b, rotation: rb, .. }) =
                (action, &want)
            else {
                panic!("{action:?}")
            };
            assert!(ra == rb && (a - b).abs() < 1e-9, "line {line}: {action:?} against {want:?}");
        }
        // The speed changes at rest where the move before it ends: X10 Z-10 for line 6.
        let at = |n: u64, axis: usize| -> i64 {
            planned.records[..n as usize].iter().map(|r| i64::from(r.inc[axis].to_bits())).sum()
        };
        let stop = events[1].0;
        assert_eq!((at(stop, 0), at(stop, 2)), ((10 * 800) << 16, -((10 * 400) << 16)));
        assert!(planned.records[stop as usize - 1].flags & 1 != 0);
        // The corner X40 Z-10 (lines 4-5) is blended: no record ends at rest there.
        let corner = (0..planned.records.len() as u64)
            .find(|&n| at(n, 0) == (40 * 800) << 16 && at(n, 2) == -((10 * 400) << 16));
        assert_eq!(corner, None, "an exact stop at the corner X40 Z-10");
        // G95 under G96 is refused (`unsupported`); G96 D0 runs as G97, as LinuxCNC's canon does.
        let refused = finestep_gcode::parse_str("G96 S100 D2000\nG95 F0.1\nG1 X1\n", "t.ngc").unwrap_err();
        assert!(refused.to_string().contains("unsupported: G95 in G96"), "{refused}");
        let d0 = finestep_gcode::parse_str("G96 S100 D0 M3\nG95 F0.1\nG1 X1\nM2\n", "t.ngc").unwrap();
        let d0 = plan_program(&config, &d0).unwrap();
        assert_eq!(d0.events[0].event.action, spindle(Clockwise, 100.0));
    }

    /// G38.x: the probe armed at an exact stop before the probe move, checked at the
    /// exact stop after it; the path goes on from the probe move's end (where a machine
    /// would be had the probe not tripped). M66-M68 are events at exact stops.
    #[test]
    fn probe_moves_and_inputs_are_events_at_exact_stops() {
        use crate::element::IoAction;
        use finestep_gcode::{Input, WaitMode};
        let config = MachineConfig::default(); // X at 800, Z at 400 steps/mm, T = 1 ms
        let text = "G64\nG1 X1 F600\nG38.2 Z-2 F60\nG1 X2 F600\nM66 P1 L3 Q2\nM68 E1 Q2.5\nG1 X3\nM2\n";
        let program = finestep_gcode::parse_str(text, "probe.ngc").unwrap();
        let planned = plan_program(&config, &program).unwrap();
        let events: Vec<(u64, usize, IoAction)> =
            planned.events.iter().map(|e| (e.period, e.event.line, e.event.action.clone())).collect();
        let at = |n: u64, axis: usize| -> i64 {
            planned.records[..n as usize].iter().map(|r| i64::from(r.inc[axis].to_bits())).sum()
        };
        assert_eq!(events.len(), 4, "{events:?}");
        assert_eq!((events[0].1, events[0].2.clone()), (3, IoAction::ProbeArm { on_contact: true, must_change: true }));
        assert_eq!((events[1].1, events[1].2.clone()), (3, IoAction::ProbeCheck { must_change: true }));
        assert_eq!(
            (events[2].1, events[2].2.clone()),
            (5, IoAction::WaitInput { input: Input::Digital(1), mode: WaitMode::High, timeout_s: 2.0 })
        );
        assert_eq!((events[3].1, events[3].2.clone()), (6, IoAction::AnalogOutput { index: 1, value: 2.5 }));
        // Armed at rest at X1 Z0, checked at rest at the probe's end Z-2 (not 0.254 mm
        // short: the machine's stop is where the probe trips, which the host reads).
        let (arm, check) = (events[0].0, events[1].0);
        assert_eq!((at(arm, 0), at(arm, 2)), ((800 << 16), 0));
        assert_eq!((at(check, 0), at(check, 2)), ((800 << 16), -(800 << 16)));
        for p in [arm, check] {
            assert!(planned.records[p as usize - 1].flags & 1 != 0);
        }
        // The probe move runs at its feed: 60 mm/min is 0.4 Z steps a period.
        let fastest = planned.records[arm as usize..check as usize]
            .iter()
            .map(|r| i64::from(r.inc[2].to_bits()).abs())
            .max()
            .unwrap();
        assert!(fastest <= (4 << 16) / 10 + 1, "{fastest}");
        // The checker holds the records to the program with the probe move's stops.
        let report = crate::check_program(&config, &program, &planned.records).unwrap();
        assert!(report.passed(), "{report:?}");
    }
}
