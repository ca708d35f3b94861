//! The spindle, the logic outputs and the interlock on a [`Machine`]
//! (docs/spec/spindle.md, docs/spec/logic_outputs.md): what S, M3/M4/M5, M7/M8/M9 and
//! M62-M65 become on the chip.

use crate::regs::{
    interlock, outputs, outputs_safe, spindle_control, spindle_level, spindle_period, spindle_ramp, spindle_status,
};
use crate::{Bus, BusError, Machine};

/// How the spindle's level reaches the drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpindleSetup {
    /// The period in clocks: the PWM period, the DAC frame interval, the ramp interval.
    pub period_clocks: u16,
    /// The most the level moves per period (0: no limit).
    pub ramp_step: u16,
    /// The 12-bit SPI DAC instead of the PWM pin.
    pub dac: bool,
    /// The DAC's SCK stays high and low `dac_div + 1` clocks each (0..=15).
    pub dac_div: u8,
}

impl Default for SpindleSetup {
    /// The reset values of the registers.
    fn default() -> Self {
        SpindleSetup {
            period_clocks: spindle_period::CLOCKS_RESET as u16,
            ramp_step: spindle_ramp::STEP_RESET as u16,
            dac: spindle_control::DAC_RESET != 0,
            dac_div: spindle_control::DAC_DIV_RESET as u8,
        }
    }
}

impl SpindleSetup {
    /// The level of full speed: the period's clocks (PWM always high), or the DAC's 4095.
    pub fn full_scale(&self) -> u16 {
        if self.dac {
            4095
        } else {
            self.period_clocks.max(1)
        }
    }

    /// The level for `fraction` of full speed (clamped to 0..=1), rounded to the nearest.
    pub fn level_for(&self, fraction: f64) -> u16 {
        let fraction = if fraction.is_nan() { 0.0 } else { fraction.clamp(0.0, 1.0) };
        (fraction * f64::from(self.full_scale())).round() as u16
    }
}

/// The spindle's output as the chip reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpindleStatus {
    /// The ramped level now.
    pub level: u16,
    /// The level has reached its target.
    pub at_speed: bool,
    /// The enable pin is active.
    pub enabled: bool,
}

/// The logic outputs (`OUTPUTS` and `OUTPUTS_SAFE`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// Mist coolant (M7).
    pub mist: bool,
    /// Flood coolant (M8).
    pub flood: bool,
    /// The work light.
    pub light: bool,
    /// General outputs, bit `i` for output `i` (M62-M65 P`i`).
    pub gpio: u8,
}

impl Outputs {
    fn word(&self) -> u32 {
        let word = outputs::MIST.set(0, u32::from(self.mist));
        let word = outputs::FLOOD.set(word, u32::from(self.flood));
        let word = outputs::LIGHT.set(word, u32::from(self.light));
        outputs::GPIO.set(word, u32::from(self.gpio))
    }

    fn from_word(word: u32) -> Outputs {
        Outputs {
            mist: outputs::MIST.get(word) != 0,
            flood: outputs::FLOOD.get(word) != 0,
            light: outputs::LIGHT.get(word) != 0,
            gpio: outputs::GPIO.get(word) as u8,
        }
    }
}

/// The interlock input's configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InterlockSetup {
    /// The interlock holds the FIFO gate shut while active.
    pub enable: bool,
    /// The pin is active high.
    pub active_high: bool,
    /// Samples of the other level in a row before the filtered input changes (0 acts as
    /// 1).
    pub filter_samples: u8,
    /// The filter samples every `prescale + 1` clocks (14 bits): a change shorter than
    /// `(filter_samples - 1) * (prescale + 1)` clocks never shows, one of
    /// `filter_samples * (prescale + 1)` always does.
    pub prescale: u16,
}

impl<B: Bus> Machine<B> {
    fn need(&self, built: bool, what: &'static str) -> Result<(), BusError> {
        if built {
            Ok(())
        } else {
            Err(BusError::NotBuilt(what))
        }
    }

    /// Writes the spindle's period, ramp and output selection (the spindle keeps its
    /// enable, direction and level).
    pub fn configure_spindle(&mut self, setup: &SpindleSetup) -> Result<(), BusError> {
        self.need(self.caps.has_spindle, "spindle")?;
        self.bus.write(spindle_period::ADDR, spindle_period::CLOCKS.set(0, u32::from(setup.period_clocks)))?;
        self.bus.write(spindle_ramp::ADDR, spindle_ramp::STEP.set(0, u32::from(setup.ramp_step)))?;
        self.spindle = *setup;
        self.set_spindle(false, false, 0)
    }

    /// The spindle on (M3, or M4 with `reverse`) at `level` (from
    /// [`SpindleSetup::level_for`]), or off (M5: `on` false, the level ramps to 0). The
    /// level is written first, so the enable never meets a stale level.
    pub fn set_spindle(&mut self, on: bool, reverse: bool, level: u16) -> Result<(), BusError> {
        self.need(self.caps.has_spindle, "spindle")?;
        self.bus.write(spindle_level::ADDR, spindle_level::LEVEL.set(0, u32::from(level)))?;
        let word = spindle_control::ENABLE.set(0, u32::from(on));
        let word = spindle_control::DIR.set(word, u32::from(reverse));
        let word = spindle_control::DAC.set(word, u32::from(self.spindle.dac));
        let word = spindle_control::DAC_DIV.set(word, u32::from(self.spindle.dac_div) & spindle_control::DAC_DIV.max());
        self.bus.write(spindle_control::ADDR, word)
    }

    /// The spindle's ramped level and pins.
    pub fn spindle_status(&mut self) -> Result<SpindleStatus, BusError> {
        self.need(self.caps.has_spindle, "spindle")?;
        let word = self.bus.read_one(spindle_status::ADDR)?;
        Ok(SpindleStatus {
            level: spindle_status::LEVEL.get(word) as u16,
            at_speed: spindle_status::AT_SPEED.get(word) != 0,
            enabled: spindle_status::ENABLED.get(word) != 0,
        })
    }

    /// Drives the logic outputs (coolant, light, general outputs).
    pub fn set_outputs(&mut self, value: &Outputs) -> Result<(), BusError> {
        self.need(self.caps.has_outputs, "logic outputs")?;
        self.bus.write(outputs::ADDR, value.word())
    }

    /// The logic outputs as the chip holds them (the safe levels after a halt).
    pub fn outputs(&mut self) -> Result<Outputs, BusError> {
        self.need(self.caps.has_outputs, "logic outputs")?;
        Ok(Outputs::from_word(self.bus.read_one(outputs::ADDR)?))
    }

    /// The levels the outputs take when the machine halts.
    pub fn set_safe_outputs(&mut self, value: &Outputs) -> Result<(), BusError> {
        self.need(self.caps.has_outputs, "logic outputs")?;
        debug_assert_eq!(outputs::GPIO, outputs_safe::GPIO);
        self.bus.write(outputs_safe::ADDR, value.word())
    }

    /// Configures the interlock input.
    pub fn configure_interlock(&mut self, setup: &InterlockSetup) -> Result<(), BusError> {
        self.need(self.caps.has_outputs, "interlock")?;
        let prescale = u32::from(setup.prescale);
        if prescale > interlock::PRESCALE.max() {
            return Err(BusError::SettingRange {
                what: "interlock prescale",
                value: prescale,
                max: interlock::PRESCALE.max(),
            });
        }
        let word = interlock::ENABLE.set(0, u32::from(setup.enable));
        let word = interlock::ACTIVE_HIGH.set(word, u32::from(setup.active_high));
        let word = interlock::FILTER.set(word, u32::from(setup.filter_samples));
        self.bus.write(interlock::ADDR, interlock::PRESCALE.set(word, prescale))
    }

    /// The interlock: (active now, BLOCKED: a start was held since the last CLEAR_ERRORS).
    pub fn interlock(&mut self) -> Result<(bool, bool), BusError> {
        self.need(self.caps.has_outputs, "interlock")?;
        let word = self.bus.read_one(interlock::ADDR)?;
        Ok((interlock::ACTIVE.get(word) != 0, interlock::BLOCKED.get(word) != 0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_scale_to_the_output() {
        let pwm = SpindleSetup { period_clocks: 1000, ..SpindleSetup::default() };
        assert_eq!((pwm.level_for(0.5), pwm.level_for(1.5), pwm.level_for(-1.0)), (500, 1000, 0));
        let dac = SpindleSetup { dac: true, ..pwm };
        assert_eq!((dac.level_for(1.0), dac.level_for(0.25), dac.level_for(f64::NAN)), (4095, 1024, 0));
        let word = Outputs { mist: true, light: true, gpio: 0x5, flood: false }.word();
        assert_eq!(word, 0b101 | 0x5 << 8);
        assert_eq!(Outputs::from_word(word).gpio, 5);
    }
}
