//! Coarse interpolation: from a programmed move to one [`PeriodRecord`] per period.
//!
//! This first part implements seed 000's time-division (data-sampling) linear
//! interpolation: for a line O->P of length L at feed V_i in period i, every axis moves
//! dx_i = V_i * T * (x_e - x_o) / L, with the feed raised every period from a start
//! speed to the programmed feed and lowered again to stop. Positions are quantised to
//! the core's Q16.16 step grid from the exact cumulative position, so the increments of
//! a move sum exactly to its endpoint in steps and no rounding error accumulates.
//!
//! ```
//! use finestep_planner::{Machine, LineMove, interpolate_line};
//! let machine = Machine::new(vec![1000.0, 1000.0], 0.001); // 1000 steps/mm, T = 1 ms
//! let line = LineMove { from_mm: vec![0.0, 0.0], to_mm: vec![3.0, 4.0], feed_mm_s: 50.0,
//!                       start_speed_mm_s: 1.0, accel_mm_s2: 500.0 };
//! let records = interpolate_line(&machine, &line).unwrap();
//! let total: i64 = records.iter().map(|r| r.inc[1].to_bits() as i64).sum();
//! assert_eq!(total, 4000 << 16); // exactly 4 mm of steps on Y
//! ```

pub mod arc;
pub mod linear;
pub mod path;
pub mod program;
pub mod profile;

pub use arc::{interpolate_arc, ArcMove};
pub use linear::{interpolate_line, LineMove, Machine, PlanError};
pub use program::{plan_program, MotionLimits, PlannedBlock, PlannedProgram, ProgramError};
