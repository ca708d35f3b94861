//! Coarse interpolation: from a parsed part program to one [`PeriodRecord`] per period T,
//! the per-axis fixed-point increments the core's DDAs fine-interpolate.
//!
//! The pipeline of [`plan_program`]:
//!
//! 1. [`config`]: the machine (axes, steps per unit, velocity, acceleration and jerk
//!    limits, T, the FPGA clock, drive timing, tolerances) from a TOML file or defaults.
//! 2. [`geometry`]: programmed lines and arcs with vertices on whole steps; in G64 each
//!    line-line corner becomes a blend arc within the path tolerance P (in S-curve mode
//!    a pair of clothoids, continuous in curvature), and in S-curve mode a run of short
//!    nearly collinear lines is first smoothed into one cubic B-spline within P
//!    ([`smooth`]); per-axis limits
//!    projected onto each element's direction give its speed, acceleration and jerk caps.
//!    A NURBS (G5.2/G5.3) becomes sub-pieces of the true curve with their own caps from
//!    its curvature ([`nurbs`]).
//! 3. [`lookahead`]: junction speeds from the corner criterion, backward and forward
//!    passes over a window of at least `lookahead_moves` moves.
//! 4. [`velocity`]: per element a trapezoid or S-curve profile, acceleration and
//!    deceleration halves planned separately (seed 002); in S-curve mode a run of NURBS
//!    sub-pieces whose junction speeds rise or fall all the way as one speed change
//!    over the run ([`velocity::run_profiles`]), the acceleration carried across them.
//! 5. [`interpolate`]: seed 000's time-division interpolation, a period straddling
//!    elements where the path flows on, positions quantised to the Q16.16 grid from their
//!    exact values so the increments sum exactly to every exact stop and the end; every
//!    record checked against the drive's rated rate before it is emitted. On a NURBS the
//!    curve parameter is stepped directly every period ([`nurbs::NurbsCursor`]).
//!
//! [`plan_stream`] gives the records as a stream ([`interpolate::Periods`]): the path
//! (steps 1-2, [`geometry::PathStream`]) is read from the program a move at a time as
//! the look-ahead window reaches it, the look-ahead runs a window at a time as the
//! records are read, elements the interpolation has left and records are not kept, so a
//! move or program of any duration or length plans in the same memory (no period cap,
//! at most a window of `4 * lookahead_moves` elements and two more, and in S-curve mode
//! up to [`velocity::MAX_RUN_ELEMENTS`] more where a run of curve pieces planned as one
//! speed change reaches past the window). [`plan_stream`]
//! borrows a parsed program ([`finestep_gcode::Program`], held whole, and copied whole
//! where cutter compensation is on); [`plan_blocks`] reads the program as the window
//! reaches it from the parser's stream ([`finestep_gcode::stream_file`]: the file read
//! through a buffer, only its O-word lines kept), compensation applied to the blocks as
//! they come ([`cutter_comp::Compensating`]), so that nothing grows with the program's
//! length, and gives the same records. A block that cannot be planned ends the stream
//! where the path reaches it. [`plan_program`] collects the stream.
//!
//! Spindle and coolant changes (S, M3/M4/M5, M7/M8/M9) take effect where they are
//! written, as in LinuxCNC: the path stops exactly there (no blending across them) and
//! the change is placed at that record index ([`PlannedProgram::events`],
//! [`TimedEvent`]), after the block-end record of the stop; the host applies it once the
//! chip has run the records before it. S maps linearly to the spindle level,
//! `S / spindle.max_rpm` of full scale; an S above `spindle.max_rpm` is refused at its
//! line. M62-M65 are refused by the parser (not implemented).
//!
//! [`checker`] checks the result independently, from the records and the program alone.
//!
//! ```
//! use finestep_planner::{check_program, plan_program, MachineConfig};
//! let program = finestep_gcode::parse_str("G64 P0.01\nG1 X10 F1200\nG1 Y10\nM2\n", "square.ngc").unwrap();
//! let config = MachineConfig::default(); // X, Y at 800 steps/mm, T = 1 ms
//! let planned = plan_program(&config, &program).unwrap();
//! let y: i64 = planned.records.iter().map(|r| i64::from(r.inc[1].to_bits())).sum();
//! assert_eq!(y, (10 * 800) << 16); // exactly 10 mm of steps on Y
//! let report = check_program(&config, &program, &planned.records).unwrap();
//! assert!(report.passed() && report.max_deviation <= 0.011);
//! ```
//!
//! # Limits of this planner
//!
//! - Each axis's acceleration and jerk are shared between speeding up along the path and
//!   turning by what each element needs ([`element`]): a line takes 98 % of them, a
//!   curve up to 90 % of the acceleration for turning and the rest along the path. The
//!   shares are fixed (50 % of the acceleration along the path, 45 % turning, the jerk
//!   in [`element`]) only beside a junction that jumps (a corner taken with a tangent
//!   jump, in S-curve mode also a curvature jump such as a line entering an arc).
//!   Each element keeps one tangential acceleration and jerk over its length (set
//!   at its speed cap), and an S-curve brings the acceleration to zero at every element's
//!   end (except inside a run of NURBS sub-pieces whose speeds rise or fall all the way,
//!   planned as one change held to each element's limits at the speed it has there,
//!   [`velocity::run_profiles`]),
//!   so the limits are reached where the path allows, not followed everywhere.
//! - [`bound`] gives an independent lower bound on the machining time, for figures.
//! - Only line-line corners are blended; where a line meets an arc, or two arcs meet,
//!   the junction speed comes from the tangent jump read over one period: full speed
//!   where they are tangent, nearly a stop where they are not.
//! - S-curve profiles bring the acceleration back to zero at every element junction
//!   (NURBS runs aside, above). Line-line corners are blended by clothoid pairs, whose
//!   curvature meets the lines' 0, so no curvature jumps there; their speed is capped by
//!   their own turning jerk `|k'| v^3` (`k' = phi / L^2`, L each clothoid's length;
//!   the blend reaches at most half of the shorter line): on short segments still well below the feed
//!   (the turning at every vertex, step rounding and a Z staircase included, is taken
//!   within the two segments around it), so in S-curve mode runs of short segments are
//!   smoothed across many segments instead ([`smooth`]); their speed is then capped by
//!   the curve's own curvature and its change, as on a NURBS. The jerk limit is also kept where the
//!   curvature jumps (a line entering an arc): about `sqrt(0.25 J T R)` there, slow at the default jerk
//!   (up to `sqrt(0.7 J T R)` where the elements around take less of the jerk
//!   for speeding up, [`element::jump_jerk_share`]). Around a
//!   line shorter than three periods' travel (short segments) the two jumps are read
//!   together ([`lookahead::pair_jerk_cap`]).
//! - G61 stops exactly at the end of every move (LinuxCNC's G61.1); the path tolerance
//!   at a corner is that of the move entering it. The feed applies to the length over
//!   all four axes, A in degrees. Arcs need a radius of at least
//!   [`geometry::MIN_ARC_RADIUS_STEPS`] steps.
//! - NURBS are not blended with their neighbours (their junctions take the junction
//!   criterion), are never offset by cutter compensation (refused), and a NURBS with a
//!   cusp (the curve stopping and turning back) is refused. A NURBS is many elements
//!   (one or more per knot span), so the look-ahead window, counted in elements, sees
//!   fewer programmed blocks ahead on NURBS than on lines.
//!
//! [`PeriodRecord`]: finestep_interface::PeriodRecord

pub mod bound;
pub mod checker;
pub mod config;
pub mod css;
pub mod cutter_comp;
pub mod element;
pub mod error;
pub mod figures;
pub mod geometry;
pub mod interpolate;
pub mod lookahead;
pub mod nurbs;
pub mod nurbs_pieces;
pub mod pbp;
pub mod program;
pub mod smooth;
pub mod vec4;
pub mod velocity;

pub use bound::time_lower_bound;
pub use checker::{check_program, CheckReport};
pub use config::{ConfigError, MachineConfig, MeasureConfig, ProfileKind, SpindleConfig};
pub use element::{IoAction, IoEvent, TimedEvent};
pub use program::{plan_blocks, plan_program, plan_stream, PlanStream, PlannedProgram, ProgramError};
