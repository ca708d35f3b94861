//! Design parameters and the control inputs of the core, and how they are masked to
//! their port widths before use.

use crate::record::PeriodRecord;
use crate::{DriveTiming, MAX_AXES};
pub use finestep_interface::{CoreParams, ParamError};

/// Per-axis settings (the per-axis slices of the Verilog's packed input ports).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct AxisConfig {
    /// `L, S, U, H`: the drive timing in clocks (`step_len`, `step_space`, `dir_setup`,
    /// `dir_hold`; each 0 acts as 1), masked to `TIMING_W` bits by the core.
    pub timing: DriveTiming,
    /// Output mode (2 bits, see [`mode`]): 0 step/dir, 1 up/down, 2 quadrature, 3 acts as 0.
    pub mode: u8,
    /// Inversion (3 bits, see [`invert`]): bit 0 pin A, bit 1 pin B, bit 2 the enable pin.
    pub invert: u8,
    /// Drive enable (`axis_enable[i]`).
    pub enable: bool,
}

/// Output mode values of [`AxisConfig::mode`] (the interface's `OUT_MODE`).
pub mod mode {
    pub use finestep_interface::out_mode::*;
}

/// Bits of [`AxisConfig::invert`] (the interface's `INVERT`).
pub mod invert {
    pub use finestep_interface::invert::*;
}

/// Everything presented on the core's input ports in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct CoreInputs {
    /// `run`: 1 periods run, 0 stopped.
    pub run: bool,
    /// `period_clocks`: the period `P` in clocks (masked to `p_width`; 0 acts as 1),
    /// sampled only while stopped.
    pub period_clocks: u32,
    /// `clear_errors`: clears every sticky flag (a flag set in the same cycle stays set).
    pub clear_errors: bool,
    /// Per-axis settings; entries at and above `n_axes` are ignored.
    pub axes: [AxisConfig; MAX_AXES],
    /// `rec_valid`: a record is offered.
    pub rec_valid: bool,
    /// `rec_inc` and `rec_flags`: the record offered.
    pub record: PeriodRecord,
    /// `halt` (the safety monitor's): every step shaper stops starting pulses and
    /// changing direction, drops its pending steps and drives its enable pin inactive; a
    /// high step level still lasts its full `L`. It goes to the step shapers only: the
    /// period timer and DDAs follow `run`, which `finestep_top` holds low while halted.
    pub halt: bool,
    /// The gantry pair's inputs (`gantry_sync`).
    pub gantry: GantryInputs,
}

/// The inputs of the gantry synchronisation (`gantry_sync`): one master and one slave
/// axis, the two channel counts, and the correction settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct GantryInputs {
    /// `enable`: engage the pair (refused when `master`/`slave` are not valid); 0
    /// disengages it.
    pub enable: bool,
    /// `sync`: 0 forward (the slave copies the master's requests), 1 synchronised
    /// (plus one correction step per tick when the error passes the deadband).
    pub sync: bool,
    /// `master`: the master axis (3 bits), sampled at engagement.
    pub master: u8,
    /// `slave`: the slave axis (3 bits), sampled at engagement.
    pub slave: u8,
    /// `tick`: clocks between correction decisions (`TICK_W = 24` bits used; 0 acts as 1).
    pub tick: u32,
    /// `deadband`: the error, in counts, within which no correction is made.
    pub deadband: u16,
    /// `limit`: the error, in counts, past which `alarm` is set.
    pub limit: u16,
    /// `enc_master`: the count of the master side's channel (wraps).
    pub enc_master: u32,
    /// `enc_slave`: the count of the slave side's channel (wraps).
    pub enc_slave: u32,
    /// `clear_counters`: zeroes the `corrections` counter (wins over a correction in the
    /// same cycle).
    pub clear_counters: bool,
}

/// One axis's settings masked to the port widths, as the blocks use them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) struct AxisSettings {
    /// `L, S, U, H`, masked to `TIMING_W` bits.
    pub(crate) timing: DriveTiming,
    pub(crate) mode: u8,
    pub(crate) invert: u8,
    /// `axis_enable & !halt`: the enable the pins show.
    pub(crate) enable: bool,
    /// The core's `halt` input.
    pub(crate) halt: bool,
}

impl AxisSettings {
    #[inline]
    pub(crate) fn masked(cfg: &AxisConfig, timing_mask: u32, halt: bool) -> Self {
        AxisSettings {
            timing: DriveTiming::from_array(cfg.timing.to_array().map(|value| value & timing_mask)),
            mode: cfg.mode & ((1 << mode::WIDTH) - 1),
            invert: cfg.invert & invert::ALL,
            enable: cfg.enable && !halt,
            halt,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_masked() {
        let cfg = AxisConfig {
            timing: DriveTiming::new(0x1_0003, 0xFFFF_FFFF, 16, 17),
            mode: 0xFE,
            invert: 0xFF,
            enable: true,
        };
        let s = AxisSettings::masked(&cfg, 0xF, false);
        assert_eq!(s.timing, DriveTiming::new(3, 15, 0, 1));
        assert_eq!((s.mode, s.invert, s.enable), (2, 7, true));
        let halted = AxisSettings::masked(&cfg, 0xF, true);
        assert!(halted.halt && !halted.enable, "halt drops the enable");
    }
}
