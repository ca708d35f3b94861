//! `spindle`: the spindle's PWM or SPI DAC output, its ramp, enable and direction.
//!
//! Specification: docs/spec/spindle.md
//!
//! One level drives the output. A period is `max(SPINDLE_PERIOD, 1)` clocks; the PWM pin
//! is high in the first `min(level, period)` of them. In DAC mode every period's first
//! clock starts (when no frame runs) a 16-bit MCP4921 frame carrying
//! `0x3000 | min(level, 4095)`: CS_n low for 33 ticks of `DAC_DIV + 1` clocks, bit
//! `15 - t / 2` on SDI in tick `t`, SCK high in the odd ticks. At each period's end the
//! level moves toward its target (`SPINDLE_LEVEL` while `ENABLE`, else 0) by at most
//! `SPINDLE_RAMP.STEP` (0: all the way). A halt zeroes the level at once, drops the
//! enable and PWM pins the next clock, aborts a frame and restarts the period.
//!
//! The configuration comes from the register file (its `rw` store): [`SpindleConfig`].
//! [`Spindle::pins`] is a function of the state and the configuration after the edge.

/// The register fields the spindle runs on, as the register file holds them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpindleConfig {
    /// `SPINDLE_CONTROL.ENABLE`.
    pub enable: bool,
    /// `SPINDLE_CONTROL.DIR`.
    pub dir: bool,
    /// `SPINDLE_CONTROL.DAC`: the DAC, not the PWM pin.
    pub dac: bool,
    /// `SPINDLE_CONTROL.DAC_DIV`: SCK half period - 1, in clocks.
    pub dac_div: u32,
    /// `SPINDLE_PERIOD.CLOCKS` (0 acts as 1).
    pub period: u32,
    /// `SPINDLE_LEVEL.LEVEL`: the commanded level.
    pub command: u32,
    /// `SPINDLE_RAMP.STEP` (0: no limit).
    pub ramp: u32,
}

impl SpindleConfig {
    /// The level the ramp moves toward.
    pub fn target(&self) -> u32 {
        if self.enable {
            self.command
        } else {
            0
        }
    }
}

/// The spindle's pins in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpindlePins {
    /// PWM.
    pub pwm: bool,
    /// Direction.
    pub dir: bool,
    /// Enable.
    pub en: bool,
    /// DAC chip select, active low.
    pub cs_n: bool,
    /// DAC clock.
    pub sck: bool,
    /// DAC data.
    pub sdi: bool,
}

/// The DAC's code: the level, saturated at full scale.
pub const DAC_FULL_SCALE: u32 = 4095;
/// The frame's upper nibble: DAC A, unbuffered, gain 1x, output active.
pub const DAC_CONFIG: u16 = 0x3000;
/// The ticks of a frame with CS_n low (0..=32).
pub const FRAME_TICKS: u32 = 33;

/// The 16-bit frame that commands `level`.
pub fn dac_word(level: u32) -> u16 {
    DAC_CONFIG | level.min(DAC_FULL_SCALE) as u16
}

/// `level` moved toward `target` by at most `step` (0: no limit).
pub fn ramp_toward(level: u32, target: u32, step: u32) -> u32 {
    if step == 0 || level.abs_diff(target) <= step {
        target
    } else if level < target {
        level + step
    } else {
        level - step
    }
}

/// A DAC frame in flight.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Frame {
    /// The word it carries.
    pub word: u16,
    /// The tick, 0..=32.
    pub tick: u32,
    /// Clocks spent in this tick so far.
    pub clocks: u32,
}

/// The spindle's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Spindle {
    count: u32,
    level: u32,
    halt_prev: bool,
    frame: Option<Frame>,
}

impl Default for Spindle {
    /// The reset state (reset counts as halted before, so a halt out of reset is not a
    /// new one).
    fn default() -> Self {
        Spindle { count: 0, level: 0, halt_prev: true, frame: None }
    }
}

impl Spindle {
    /// The ramped level now.
    pub fn level(&self) -> u32 {
        self.level
    }

    /// The clock within the period.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The frame in flight.
    pub fn frame(&self) -> Option<Frame> {
        self.frame
    }

    /// The pins, given the configuration now (after the last edge).
    pub fn pins(&self, config: &SpindleConfig) -> SpindlePins {
        let running = !self.halt_prev;
        let (cs_n, sck, sdi) = match self.frame {
            None => (true, false, false),
            Some(f) => {
                let bit = 15i32 - (f.tick / 2) as i32;
                (false, f.tick % 2 == 1, bit >= 0 && f.word >> bit & 1 != 0)
            }
        };
        SpindlePins {
            pwm: running && !config.dac && self.count < self.level,
            dir: config.dir,
            en: running && config.enable,
            cs_n,
            sck,
            sdi,
        }
    }

    /// One rising clock edge with this cycle's configuration and halt.
    pub fn step(&mut self, config: &SpindleConfig, halt: bool) {
        let period = config.period.max(1);
        let period_end = self.count + 1 >= period;
        let halt_rise = halt && !self.halt_prev;
        self.frame = if halt_rise || !config.dac {
            None
        } else {
            match self.frame {
                None => (self.count == 0).then(|| Frame { word: dac_word(self.level), tick: 0, clocks: 0 }),
                Some(f) if f.clocks < config.dac_div => Some(Frame { clocks: f.clocks + 1, ..f }),
                Some(f) if f.tick + 1 == FRAME_TICKS => None,
                Some(f) => Some(Frame { tick: f.tick + 1, clocks: 0, ..f }),
            }
        };
        self.level = if halt {
            0
        } else if period_end {
            ramp_toward(self.level, config.target(), config.ramp)
        } else {
            self.level
        };
        self.count = if period_end || halt_rise { 0 } else { self.count + 1 };
        self.halt_prev = halt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(period: u32, command: u32, ramp: u32) -> SpindleConfig {
        SpindleConfig { enable: true, period, command, ramp, dac_div: 1, ..SpindleConfig::default() }
    }

    /// Runs `cycles` clocks, returning the pins after each edge.
    fn run(spindle: &mut Spindle, config: &SpindleConfig, halt: bool, cycles: usize) -> Vec<SpindlePins> {
        (0..cycles)
            .map(|_| {
                spindle.step(config, halt);
                spindle.pins(config)
            })
            .collect()
    }

    #[test]
    fn pwm_high_time_and_period_are_exact_for_every_level() {
        // The ideal: with no ramp, after the first period every period of P clocks is high
        // for exactly min(level, P) clocks, starting at the period's first clock.
        for period in [1u32, 2, 3, 7, 16] {
            for level in 0..=period + 2 {
                let c = config(period, level, 0);
                let mut s = Spindle::default();
                run(&mut s, &c, false, period as usize);
                let pins = run(&mut s, &c, false, 5 * period as usize);
                let starts: Vec<usize> = (0..pins.len()).filter(|&i| s_count_at(i, period) == 0).collect();
                for &start in starts.iter().take(4) {
                    let window = &pins[start..start + period as usize];
                    let high = window.iter().filter(|p| p.pwm).count() as u32;
                    assert_eq!(high, level.min(period), "period {period} level {level}");
                    assert!(window.iter().take(high as usize).all(|p| p.pwm), "high first");
                    assert!(window.iter().all(|p| p.en && p.cs_n));
                }
            }
        }
    }

    /// The count after edge `i` of the second run (the first ran a whole period).
    fn s_count_at(i: usize, period: u32) -> u32 {
        (i as u32 + 1) % period
    }

    #[test]
    fn the_ramp_moves_at_most_one_step_a_period_and_never_overshoots() {
        let mut s = Spindle::default();
        let up = config(10, 95, 7);
        let mut levels = vec![s.level()];
        for _ in 0..200 {
            s.step(&up, false);
            levels.push(s.level());
        }
        let down = config(10, 3, 7);
        for _ in 0..200 {
            s.step(&down, false);
            levels.push(s.level());
        }
        let changes: Vec<(usize, u32, u32)> =
            levels.windows(2).enumerate().filter(|(_, w)| w[0] != w[1]).map(|(i, w)| (i, w[0], w[1])).collect();
        for &(_, from, to) in &changes {
            assert!(from.abs_diff(to) <= 7);
        }
        // Up 0 -> 95 in ceil(95 / 7) = 14 changes, down to 3 in ceil(92 / 7) = 14, ten clocks apart.
        assert_eq!(changes.len(), 28);
        assert!(changes.windows(2).all(|w| w[1].0 - w[0].0 >= 10), "one change a period at most");
        assert_eq!(*levels.last().unwrap(), 3);
        assert!(levels.iter().all(|&l| l <= 95));
    }

    #[test]
    fn a_dac_frame_is_sixteen_rising_edges_of_the_word() {
        let c = SpindleConfig { dac: true, dac_div: 2, ..config(200, 1234, 0) };
        let mut s = Spindle::default();
        let pins = run(&mut s, &c, false, 600);
        // Decode as the DAC does: bits at rising SCK while CS_n is low; latch at CS_n's rise.
        let mut words = Vec::new();
        let (mut bits, mut n, mut prev) = (0u32, 0, SpindlePins { cs_n: true, ..SpindlePins::default() });
        for p in &pins {
            if !p.cs_n && p.sck && !prev.sck {
                bits = bits << 1 | u32::from(p.sdi);
                n += 1;
            }
            if p.cs_n && !prev.cs_n {
                assert_eq!(n, 16);
                words.push(bits);
                bits = 0;
                n = 0;
            }
            assert!(!p.cs_n || (!p.sck && !p.sdi));
            if prev.sck && p.sck {
                assert_eq!(prev.sdi, p.sdi, "SDI stable while SCK is high");
            }
            prev = *p;
        }
        // The first period's frame carries level 0; the next ones 1234.
        assert_eq!(words[0], 0x3000);
        assert!(words[1..].iter().all(|&w| w == 0x3000 | 1234));
        assert!(words.len() >= 3);
        let low = pins.iter().take_while(|p| p.cs_n).count();
        let frame_clocks = pins[low..].iter().take_while(|p| !p.cs_n).count() as u32;
        assert_eq!(frame_clocks, FRAME_TICKS * 3, "33 ticks of DAC_DIV + 1 = 3 clocks");
        assert!(pins.iter().all(|p| !p.pwm), "the PWM pin stays low in DAC mode");
    }

    #[test]
    fn a_halt_turns_everything_off_in_one_clock_and_sends_zero() {
        let mut c = SpindleConfig { dac: true, ..config(100, 3000, 0) };
        let mut s = Spindle::default();
        run(&mut s, &c, false, 230);
        assert!(s.frame().is_some() && s.level() == 3000);
        s.step(&c, true);
        c.enable = false; // the register file clears ENABLE at the same edge
        let p = s.pins(&c);
        assert!(!p.en && !p.pwm && p.cs_n && !p.sck && s.level() == 0 && s.count() == 0);
        s.step(&c, true);
        assert_eq!(s.frame().map(|f| f.word), Some(0x3000), "the next clock starts a frame of 0");
        let mut pwm = SpindleConfig { enable: true, ..config(4, 4, 0) };
        let mut s = Spindle::default();
        run(&mut s, &pwm, false, 9);
        assert!(s.pins(&pwm).pwm && s.pins(&pwm).en);
        s.step(&pwm, true);
        pwm.enable = false;
        assert!(!s.pins(&pwm).pwm && !s.pins(&pwm).en);
    }
}
