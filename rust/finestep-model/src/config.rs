//! Design parameters and the control inputs of the core, and how they are masked to
//! their port widths before use.

use crate::record::PeriodRecord;
use crate::MAX_AXES;

/// Design-time parameters of the core (the Verilog module parameters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoreParams {
    /// `N_AXES`: number of axes, 1 ..= [`MAX_AXES`].
    pub n_axes: usize,
    /// `P_WIDTH`: width of the period register in bits, 1 ..= 32.
    pub p_width: u32,
    /// `TIMING_W`: width of the step timing settings and counters in bits, 1 ..= 32.
    pub timing_width: u32,
}

impl Default for CoreParams {
    /// The defaults of the Verilog: 4 axes, `P_WIDTH = 20`, `TIMING_W = 12`.
    fn default() -> Self {
        CoreParams { n_axes: 4, p_width: 20, timing_width: 12 }
    }
}

/// A [`CoreParams`] value outside what the core supports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ParamsError {
    /// `n_axes` is 0 or above [`MAX_AXES`].
    #[error("n_axes = {0} is outside 1..={MAX_AXES}")]
    Axes(usize),
    /// `p_width` is 0 or above 32.
    #[error("p_width = {0} is outside 1..=32")]
    PeriodWidth(u32),
    /// `timing_width` is 0 or above 32.
    #[error("timing_width = {0} is outside 1..=32")]
    TimingWidth(u32),
}

impl CoreParams {
    /// Checks the parameters are in the supported ranges.
    pub fn validate(&self) -> Result<(), ParamsError> {
        if !(1..=MAX_AXES).contains(&self.n_axes) {
            return Err(ParamsError::Axes(self.n_axes));
        }
        if !(1..=32).contains(&self.p_width) {
            return Err(ParamsError::PeriodWidth(self.p_width));
        }
        if !(1..=32).contains(&self.timing_width) {
            return Err(ParamsError::TimingWidth(self.timing_width));
        }
        Ok(())
    }

    /// All ones in the low `p_width` bits: the largest period in clocks.
    pub fn period_mask(&self) -> u32 {
        low_ones(self.p_width)
    }

    /// All ones in the low `timing_width` bits: the largest timing value, and the value
    /// at which the shaper's `cnt` and `dcnt` saturate (`sat`).
    pub fn timing_mask(&self) -> u32 {
        low_ones(self.timing_width)
    }

    /// The effective period in clocks for a `period_clocks` input: masked to `p_width`
    /// bits, 0 acting as 1.
    pub fn effective_period(&self, period_clocks: u32) -> u32 {
        (period_clocks & self.period_mask()).max(1)
    }
}

fn low_ones(width: u32) -> u32 {
    if width >= 32 {
        u32::MAX
    } else {
        (1u32 << width) - 1
    }
}

/// Per-axis settings (the per-axis slices of the Verilog's packed input ports).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct AxisConfig {
    /// `L`: clocks the step level stays high (0 acts as 1).
    pub step_len: u32,
    /// `S`: minimum clocks the step level stays low between pulses (0 acts as 1).
    pub step_space: u32,
    /// `U`: minimum clocks from a direction change to the next rising edge (0 acts as 1).
    pub dir_setup: u32,
    /// `H`: minimum clocks from a falling edge to a direction change (0 acts as 1).
    pub dir_hold: u32,
    /// Output mode (2 bits): 0 step/dir, 1 up/down, 2 quadrature, 3 acts as 0.
    pub mode: u8,
    /// Inversion (3 bits): bit 0 pin A, bit 1 pin B, bit 2 the enable pin.
    pub invert: u8,
    /// Drive enable (`axis_enable[i]`).
    pub enable: bool,
}

/// Output mode values of [`AxisConfig::mode`].
pub mod mode {
    /// Step on pin A, direction on pin B (1 = positive).
    pub const STEP_DIR: u8 = 0;
    /// Up pulses on pin A, down pulses on pin B (CW/CCW).
    pub const UP_DOWN: u8 = 1;
    /// Quadrature A/B, A leading B when moving positive.
    pub const QUADRATURE: u8 = 2;
}

/// Bits of [`AxisConfig::invert`].
pub mod invert {
    /// Inverts pin A.
    pub const PIN_A: u8 = 1 << 0;
    /// Inverts pin B.
    pub const PIN_B: u8 = 1 << 1;
    /// Inverts the enable pin.
    pub const PIN_EN: u8 = 1 << 2;
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
    pub(crate) l: u32,
    pub(crate) s: u32,
    pub(crate) u: u32,
    pub(crate) h: u32,
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
            l: cfg.step_len & timing_mask,
            s: cfg.step_space & timing_mask,
            u: cfg.dir_setup & timing_mask,
            h: cfg.dir_hold & timing_mask,
            mode: cfg.mode & 0b11,
            invert: cfg.invert & 0b111,
            enable: cfg.enable && !halt,
            halt,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_follow_the_widths() {
        let p = CoreParams::default();
        assert_eq!(p.period_mask(), 0xF_FFFF);
        assert_eq!(p.timing_mask(), 0xFFF);
        assert_eq!(p.effective_period(0), 1);
        assert_eq!(p.effective_period(0x10_0005), 5);
        let wide = CoreParams { n_axes: 8, p_width: 32, timing_width: 32 };
        assert_eq!(wide.period_mask(), u32::MAX);
        assert!(wide.validate().is_ok());
    }

    #[test]
    fn bad_params_are_refused() {
        let p = CoreParams { n_axes: 9, ..CoreParams::default() };
        assert_eq!(p.validate(), Err(ParamsError::Axes(9)));
        let p = CoreParams { p_width: 0, ..CoreParams::default() };
        assert_eq!(p.validate(), Err(ParamsError::PeriodWidth(0)));
        let p = CoreParams { timing_width: 33, ..CoreParams::default() };
        assert_eq!(p.validate(), Err(ParamsError::TimingWidth(33)));
    }

    #[test]
    fn settings_are_masked() {
        let cfg = AxisConfig {
            step_len: 0x1_0003,
            step_space: 0xFFFF_FFFF,
            dir_setup: 16,
            dir_hold: 17,
            mode: 0xFE,
            invert: 0xFF,
            enable: true,
        };
        let s = AxisSettings::masked(&cfg, 0xF, false);
        assert_eq!((s.l, s.s, s.u, s.h), (3, 15, 0, 1));
        assert_eq!((s.mode, s.invert, s.enable), (2, 7, true));
        let halted = AxisSettings::masked(&cfg, 0xF, true);
        assert!(halted.halt && !halted.enable, "halt drops the enable");
    }
}
