//! Cycle-accurate reference model of the finestep motion core and its host-interface
//! top.
//!
//! The FPGA core takes one [`PeriodRecord`] of per-axis increments (I16F16 steps per
//! period) per interpolation period, spreads each increment evenly over the period's
//! clocks with a DDA per axis, and turns the DDA's step requests into step/direction,
//! up/down or quadrature pulses with the drive's timing. This crate is an independent
//! implementation of the specification in the repository's `docs/spec/` (one file per
//! block), against which the Verilog is checked bit for bit in co-simulation.
//!
//! Modules mirror the HDL blocks: [`period_timer`], [`dda_axis`], [`step_shaper`],
//! [`gantry_sync`] (a slave axis following a master, with encoder corrections),
//! [`step_engine`] (with `CoreParams::step_shared`: one DDA and one shaper visiting the
//! axes in turn instead of one of each per axis) and [`core`](mod@core)
//! (`finestep_core`, their composition). [`Core::step`] is one clock
//! edge and is the definition; [`Core::run_chunk`] runs many edges with the same inputs
//! and reports output changes, and [`Core::run_chunk_fast`] gives the same results by
//! skipping quiet cycles ([`fast`]).
//!
//! What the model shares with the RTL, the host and the planner (the register map, the
//! [`PeriodRecord`], the field values, [`DriveTiming`], the build parameters and the rated
//! rate) is the `finestep_interface` crate, generated from the interface description;
//! this crate re-exports those types ([`limits`] is the interface's rated rate, the
//! increments within which the pulse train follows the ideal position to within one step).
//!
//! The host-interface top [`top`] (`finestep_top`) is modelled per clock by
//! [`top::Top::step`] with the pins of [`top::TopInputs`]: [`spi_slave_phy`] and
//! [`spi_frame`] (the SPI link, with [`crc16_byte`]), [`parallel_bus_slave`] (the
//! 8080/FSMC link), [`register_file`] (register bus, registers from the generated
//! register map `finestep_interface::regs`, counters, interrupt, position latch, FIFO write
//! port), [`position_fifo`], [`motion_control`], [`safety_monitor`] and the core.
//!
//! The feedback blocks: [`input_filter`] (sampling prescaler, synchroniser and glitch
//! filter rule), [`quadrature_channel`] (one visit of a channel: filters, decoder,
//! counter, index), [`encoder_bank`] (the channels served in turn by one shared decoder,
//! the probe, and the copies of counts and edge times), [`hand_wheel`] (the MPG) and
//! [`jog_generator`] (moves an axis after the wheel through the core), all in the top.
//!
//! # Example
//!
//! Move axis 0 by 2.5 steps in one period of 1000 clocks, then let the pulses drain:
//!
//! ```
//! use finestep_model::{AxisConfig, Core, CoreInputs, CoreParams, DriveTiming, Increment, MAX_AXES};
//!
//! let mut core = Core::new(CoreParams::default());
//! let axis = AxisConfig { timing: DriveTiming::new(10, 10, 5, 5), enable: true, ..AxisConfig::default() };
//! let mut inputs = CoreInputs { period_clocks: 1000, axes: [axis; MAX_AXES],
//!                               ..CoreInputs::default() };
//! let mut events = Vec::new();
//! core.run_chunk(&inputs, 1, &mut events); // stopped: samples P
//! inputs.run = true;
//! inputs.rec_valid = true;
//! inputs.record.inc[0] = Increment::from_num(2.5);
//! let end = core.run_chunk_fast(&inputs, u64::MAX, &mut events);
//! assert!(end.consumed);
//! inputs.rec_valid = false;
//! core.run_chunk_fast(&inputs, 5000, &mut events);
//! // 2.5 steps round half up to 3 whole steps.
//! assert_eq!(core.outputs().position(0), 3);
//! ```

#![warn(missing_docs)]

pub mod config;
pub mod core;
pub mod crc16_byte;
pub mod dda_axis;
pub mod encoder_bank;
pub mod fast;
pub mod gantry_link;
pub mod gantry_sync;
pub mod hand_wheel;
pub mod input_filter;
pub mod jog_generator;
pub mod keypad_scan;
pub mod led_menu;
pub mod limits;
pub mod logic_outputs;
pub mod motion_control;
pub mod panel;
pub mod parallel_bus_slave;
pub mod pbp_interp;
pub mod period_timer;
pub mod position_fifo;
pub mod quadrature_channel;
pub mod record;
pub mod register_bus;
pub mod register_file;
pub mod safety_monitor;
pub mod spi_frame;
pub mod spi_slave_phy;
pub mod spindle;
pub mod step_engine;
pub mod step_serial;
pub mod step_shaper;
pub mod top;

pub use crate::config::{AxisConfig, CoreInputs, GantryInputs};
pub use crate::core::{pins, ChunkEnd, Core, CoreOutputs, Event};
pub use crate::gantry_sync::GantrySync;
pub use crate::top::{top_pins, Top, TopInputs, TopOutputs};
pub use finestep_interface::rate::{RateChecker, RateError};
pub use finestep_interface::{regs, CoreParams, DriveTiming, Increment, ParamError, PeriodRecord, TopParams, MAX_AXES};
