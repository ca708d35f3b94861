//! The finestep host<->core contract as Rust types and constants: what the planner, the
//! host driver, the reference model and the RTL -sys crate must agree on, generated from
//! the one description in `hdl/registers.toml` and `hdl/interface.toml`
//! (`rust/finestep-regmap` validates both and writes the Rust at build time).
//!
//! - [`regs`]: every register's address and fields ([`Field`]), reset values, and a table
//!   of the whole map;
//! - the period record: [`MAX_AXES`], [`Increment`] (I16F16), [`PeriodRecord`] with its
//!   [`flags`] and the core's acceptance rule, and its bytes in an SPI FIFO frame;
//! - the SPI frame layer: the command and result codes ([`spi`]) and the pure encode and
//!   decode of frames ([`frame`]);
//! - the register field values the RTL decodes: [`OutMode`], [`CountMode`],
//!   [`JogMultiplier`], and the [`invert`] bits;
//! - [`DriveTiming`], one axis's step and direction timing in clocks, built from
//!   nanoseconds with [`DriveTiming::from_ns`];
//! - the build parameters: their defaults and legal ranges ([`params`]) and the
//!   [`CoreParams`] / [`TopParams`] a core is built with;
//! - the rated rate ([`rate`]): the increments within which the pulse train follows the
//!   ideal position to within one step, which the planner keeps to and the host checks.
//!
//! The rated rate lives here rather than in the model: it is a promise of the core to
//! the planner (docs/spec/rated_rate.md), stated in terms of the record and the drive
//! timing only, and the product path (G-code -> planner -> host -> board) needs it
//! without the cycle-accurate model. The model does not use it to compute anything; its
//! tests check the model's pulse trains against it, so it stays an independent statement
//! of the specification.
//!
//! # Example
//!
//! ```
//! use finestep_interface::rate::{max_increment, RateChecker};
//! use finestep_interface::regs::axis_mode;
//! use finestep_interface::{DriveTiming, Increment, OutMode, PeriodRecord, MAX_AXES};
//!
//! // A drive needing 2.5 us pulses and 5 us direction setup, on a 50 MHz core.
//! let timing = DriveTiming::from_ns([2500.0, 2500.0, 5000.0, 5000.0], 50e6, 4095).unwrap();
//! assert_eq!(timing, DriveTiming::new(125, 125, 250, 250));
//! // The AXIS_MODE word for quadrature output.
//! assert_eq!(axis_mode::OUT_MODE.set(0, OutMode::Quadrature.bits().into()), 2);
//! // At most one step per 250 clocks: 200 steps in a 50 000-clock period.
//! assert_eq!(max_increment(&timing, 50_000, false), Increment::from_num(200));
//! let mut checker = RateChecker::new(50_000, &[timing]);
//! let mut record = PeriodRecord::default();
//! record.inc[0] = Increment::from_num(150);
//! assert!(checker.check(&record).is_ok());
//! assert_eq!(record.inc.len(), MAX_AXES);
//! ```

#![warn(missing_docs)]

mod build_params;
mod field;
pub mod frame;
mod info;
pub mod pbp;
pub mod pin_timing;
pub mod rate;
mod record;
mod timing;

pub use build_params::{CoreParams, ParamError, ParamRange, TopParams};
pub use field::Field;
pub use info::{ArrayInfo, FieldInfo, RegisterInfo};
pub use pbp::PbpLanes;
pub use record::{raw_acceptable, Increment, PeriodRecord};
pub use timing::{TimingError, TimingField};

/// The register map as Rust constants, generated from `hdl/registers.toml` at build time.
///
/// One module per register, named after it in lower case (`CONTROL` is
/// [`regs::control`]). Each module has `ADDR: u8`; an array register also has
/// `COUNT: usize`, `STRIDE: u8` and `const fn addr(index) -> u8`. Each field is a
/// [`Field`] constant named as in the map (`control::RUN`), with `<FIELD>_RESET: u32`
/// for an `rw` field and `<FIELD>_VALUE: u32` for an `ro` field the map fixes. A
/// register whose every field has a known value after reset has `const fn
/// reset_word() -> u32`. [`regs::REGISTERS`] lists the whole map as data.
///
/// ```
/// use finestep_interface::regs::{axis_mode, control};
///
/// // Request a run, keeping the other CONTROL fields at their reset values.
/// let word = control::RUN.set(control::reset_word(), 1);
/// assert_eq!(control::RUN.get(word), 1);
/// assert_eq!(control::ESTOP_ACTIVE_HIGH.get(word), control::ESTOP_ACTIVE_HIGH_RESET);
/// assert_eq!(axis_mode::addr(2), axis_mode::ADDR + 2 * axis_mode::STRIDE);
/// ```
pub mod regs {
    include!(concat!(env!("OUT_DIR"), "/registers.rs"));
}

include!(concat!(env!("OUT_DIR"), "/interface.rs"));
