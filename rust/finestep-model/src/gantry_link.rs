//! `gantry_link`: the gantry pair on the chip's register bus (seed 001). `GANTRY_CONTROL`
//! and `GANTRY_LIMITS` (held by the register file) configure the core's
//! [`GantrySync`](crate::GantrySync); `GANTRY_STATUS` reads it. The two channels it
//! compares are decoded x4 by two [`HandWheel`] decoders of the link's own on the pins of
//! the encoder channels `ENC_MASTER` and `ENC_SLAVE` (sampled on `ENC_PRESCALE`,
//! filtered by the channel's `ENC_CONTROL.FILTER`). The mode is the panel's (with
//! `HAS_PANEL`) or `GANTRY_CONTROL.SYNC`.
//!
//! Specification: docs/spec/finestep_top.md#panel-and-gantry

use crate::config::GantryInputs;
use crate::gantry_sync::GantrySync;
use crate::hand_wheel::{HandWheel, HandWheelInputs};
use finestep_interface::regs;

/// The gantry's 32-bit error saturated to a signed 16-bit value (`GANTRY_STATUS.ERROR`,
/// the panel's number).
pub fn saturate(error: u32) -> i16 {
    (error as i32).clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16
}

/// What the link's decoders see in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GantryLinkInputs {
    /// `GANTRY_CONTROL` as the register file holds it.
    pub control: u32,
    /// The encoder A pins (bits at and above `N_ENC` read low).
    pub enc_a: u8,
    /// The encoder B pins.
    pub enc_b: u8,
    /// `ENC_PRESCALE.PRESCALE`.
    pub prescale: u16,
    /// `ENC_CONTROL.FILTER` of channels 0..3 (0 for a channel not built).
    pub filters: [u8; 4],
    /// `clear_errors` pulse.
    pub clear_errors: bool,
    /// `clear_counters` pulse.
    pub clear_counters: bool,
}

/// The cycle model of `hdl/gantry_link.v` (its decoders; the registers are the register
/// file's).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GantryLink {
    master: HandWheel,
    slave: HandWheel,
}

impl GantryLink {
    /// The master side's decoder.
    pub fn master(&self) -> &HandWheel {
        &self.master
    }

    /// The slave side's decoder.
    pub fn slave(&self) -> &HandWheel {
        &self.slave
    }

    /// The core's gantry inputs in this cycle: `control` and `limits` the registers,
    /// `sync` the effective mode.
    pub fn gantry_inputs(&self, control: u32, limits: u32, sync: bool, clear_counters: bool) -> GantryInputs {
        use regs::gantry_control as c;
        use regs::gantry_limits as l;
        GantryInputs {
            enable: c::ENABLE.get(control) != 0,
            sync,
            master: c::MASTER.get(control) as u8,
            slave: c::SLAVE.get(control) as u8,
            tick: c::TICK.get(control) << 4 | 0xf,
            deadband: l::DEADBAND.get(limits) as u16,
            limit: l::LIMIT.get(limits) as u16,
            enc_master: self.master.count(),
            enc_slave: self.slave.count(),
            clear_counters,
        }
    }

    /// `GANTRY_STATUS` of `gantry` running in mode `sync`.
    pub fn status_word(gantry: &GantrySync, sync: bool) -> u32 {
        use regs::gantry_status as s;
        let word = s::ERROR.set(0, u32::from(saturate(gantry.error()) as u16));
        let word = s::CORRECTIONS.set(word, u32::from(gantry.corrections()) & s::CORRECTIONS.max());
        let word = s::ENGAGED.set(word, u32::from(gantry.engaged()));
        let word = s::ALARM.set(word, u32::from(gantry.alarm()));
        let word = s::REFUSED.set(word, u32::from(gantry.refused()));
        s::SYNC.set(word, u32::from(sync))
    }

    /// One rising edge.
    pub fn step(&mut self, i: &GantryLinkInputs) {
        use regs::gantry_control as c;
        let m = c::ENC_MASTER.get(i.control) as usize;
        let s = c::ENC_SLAVE.get(i.control) as usize;
        let pins = |channel: usize| HandWheelInputs {
            mpg_a: i.enc_a >> channel & 1 != 0,
            mpg_b: i.enc_b >> channel & 1 != 0,
            prescale: i.prescale,
            filter: i.filters[channel],
            clear_errors: i.clear_errors,
            clear_counters: i.clear_counters,
        };
        self.master.step(&pins(m));
        self.slave.step(&pins(s));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_saturates_to_16_bits() {
        for (error, shown) in [(0i32, 0i16), (32767, 32767), (32768, 32767), (-32768, -32768), (-32769, -32768)] {
            assert_eq!(saturate(error as u32), shown);
        }
        assert_eq!(saturate(i32::MIN as u32), i16::MIN);
        assert_eq!(saturate(i32::MAX as u32), i16::MAX);
    }
}
