//! The build parameters a core is made with ([`CoreParams`] for `finestep_core`,
//! [`TopParams`] for `finestep_top`), their defaults and their legal ranges, from the
//! generated [`crate::params`]: the same ranges the RTL's elaboration checks enforce.

use crate::params::{finestep_core, finestep_top};

/// One build parameter's default and legal range (the constants of [`crate::params`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamRange {
    /// The Verilog module (`finestep_top`).
    pub module: &'static str,
    /// The Verilog parameter (`P_WIDTH`).
    pub name: &'static str,
    /// Its default in the Verilog.
    pub default: u32,
    /// Least legal value.
    pub min: u32,
    /// Greatest legal value.
    pub max: u32,
}

impl ParamRange {
    /// Whether `value` is legal.
    pub const fn contains(&self, value: u64) -> bool {
        self.min as u64 <= value && value <= self.max as u64
    }

    /// `Ok` when `value` is legal, else the error naming the parameter.
    pub fn check(&self, value: impl Into<u64>) -> Result<(), ParamError> {
        let value = value.into();
        if self.contains(value) {
            Ok(())
        } else {
            Err(ParamError { module: self.module, name: self.name, value, min: self.min, max: self.max, because: None })
        }
    }

    /// The error for `value` when another parameter's setting `because` narrows the
    /// legal range to `min..=max`.
    fn narrowed(&self, value: u64, min: u32, max: u32, because: &'static str) -> ParamError {
        ParamError { module: self.module, name: self.name, value, min, max, because: Some(because) }
    }
}

/// A build parameter outside what the core supports (the build the RTL's elaboration
/// check refuses), alone or given another parameter ([`ParamError::because`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{module}: {name} = {value} is outside {min}..={max}{}", because.map(|b| format!(" with {b}")).unwrap_or_default())]
pub struct ParamError {
    /// The module.
    pub module: &'static str,
    /// The parameter.
    pub name: &'static str,
    /// The value refused.
    pub value: u64,
    /// Least legal value.
    pub min: u32,
    /// Greatest legal value.
    pub max: u32,
    /// When the range is narrowed by another parameter: that parameter's setting
    /// (`"STEP_SHARED = 1 ..."`); `None` for the parameter's own range.
    pub because: Option<&'static str>,
}

fn low_ones(width: u32) -> u32 {
    if width >= u32::BITS {
        u32::MAX
    } else {
        (1u32 << width) - 1
    }
}

/// Design-time parameters of the core (`finestep_core`'s Verilog parameters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoreParams {
    /// `N_AXES`: number of axes ([`finestep_core::N_AXES`]).
    pub n_axes: usize,
    /// `P_WIDTH`: width of the period register in bits ([`finestep_core::P_WIDTH`]).
    pub p_width: u32,
    /// `TIMING_W`: width of the step timing settings and counters in bits
    /// ([`finestep_core::TIMING_W`]).
    pub timing_width: u32,
    /// `HAS_GANTRY`: the gantry block is built ([`finestep_core::HAS_GANTRY`]); without
    /// it the gantry inputs are ignored, its outputs read 0 and every axis takes its own
    /// DDA's requests.
    pub has_gantry: bool,
    /// `STEP_SHARED`: one DDA and one step shaper visit the axes in turn (the step
    /// engine, [`finestep_core::STEP_SHARED`]) instead of one of each per axis. No gantry
    /// block is built then, whatever `has_gantry` says (docs/spec/step_engine.md): see
    /// [`CoreParams::gantry_built`].
    pub step_shared: bool,
    /// `STEP_DIGIT`: with `step_shared`, 0 for the step engine (`step_engine`), or 1, 2,
    /// 4 or 8 for the digit-serial step engine (`step_serial`, docs/spec/step_serial.md)
    /// with that many bits a clock ([`finestep_core::STEP_DIGIT`]).
    pub step_digit: u32,
    /// `HAS_PBP`: the point-by-point comparison interpolator runs the records with the
    /// flag PBP on the axis pair they name ([`finestep_core::HAS_PBP`],
    /// docs/spec/pbp_interp.md#in-the-core); needs 4 axes and not the digit-serial engine.
    pub has_pbp: bool,
}

impl Default for CoreParams {
    /// The defaults of the Verilog.
    fn default() -> Self {
        CoreParams {
            n_axes: finestep_core::N_AXES.default as usize,
            p_width: finestep_core::P_WIDTH.default,
            timing_width: finestep_core::TIMING_W.default,
            has_gantry: finestep_core::HAS_GANTRY.default != 0,
            step_shared: finestep_core::STEP_SHARED.default != 0,
            step_digit: finestep_core::STEP_DIGIT.default,
            has_pbp: finestep_core::HAS_PBP.default != 0,
        }
    }
}

impl CoreParams {
    /// Checks the parameters are in the supported ranges, and that with the step engine
    /// (`STEP_SHARED = 1`) the period register holds the shortest period it runs,
    /// `S = 2^SL` clocks (`P_WIDTH > SL`), with the digit-serial one `R` clocks, and
    /// `TIMING_W` and `P_WIDTH` fit that engine's words: the constraints of
    /// hdl/interface.toml, which the RTL's elaboration checks state too.
    pub fn validate(&self) -> Result<(), ParamError> {
        finestep_core::N_AXES.check(self.n_axes as u64)?;
        finestep_core::P_WIDTH.check(self.p_width)?;
        finestep_core::TIMING_W.check(self.timing_width)?;
        finestep_core::HAS_GANTRY.check(self.has_gantry)?;
        finestep_core::STEP_SHARED.check(self.step_shared)?;
        finestep_core::STEP_DIGIT.check(self.step_digit)?;
        finestep_core::HAS_PBP.check(self.has_pbp)?;
        if self.has_pbp && (self.n_axes < 4 || self.step_serial()) {
            let because = "HAS_PBP needs N_AXES >= 4 and no digit-serial engine (STEP_SHARED = 0 or STEP_DIGIT = 0)";
            return Err(finestep_core::HAS_PBP.narrowed(1, 0, 0, because));
        }
        if !matches!(self.step_digit, 0 | 1 | 2 | 4 | 8) {
            let because = "STEP_DIGIT is 0, 1, 2, 4 or 8";
            return Err(finestep_core::STEP_DIGIT.narrowed(self.step_digit.into(), 0, 8, because));
        }
        let least_width = self.step_round_bits() + 1;
        // step_serial: at most 2^15 - 1 visits a period (M = V * 2^16 < 2^31).
        if self.step_serial() && self.p_width > self.step_round_bits() + 15 {
            let because = "STEP_DIGIT > 0 (at most 2^15 - 1 visits of R clocks a period)";
            let max = self.step_round_bits() + 15;
            return Err(finestep_core::P_WIDTH.narrowed(self.p_width.into(), least_width, max, because));
        }
        // step_serial: a shaper counter (TIMING_W - log2 R bits, at least 1) in half a word.
        if self.step_serial() && !(least_width..=16).contains(&self.timing_width) {
            let because = "STEP_DIGIT > 0 (a counter of TIMING_W - log2 R bits, 1 to 16 - log2 R)";
            return Err(finestep_core::TIMING_W.narrowed(self.timing_width.into(), least_width, 16, because));
        }
        if self.step_shared && self.p_width < least_width {
            let because = "STEP_SHARED = 1 (the shortest period, S = 2^SL clocks, must fit P_WIDTH bits)";
            let max = finestep_core::P_WIDTH.max;
            return Err(finestep_core::P_WIDTH.narrowed(self.p_width.into(), least_width, max, because));
        }
        Ok(())
    }

    /// Whether the gantry block is built: `has_gantry` without the step engine (with it
    /// the gantry inputs are ignored and its outputs read 0, docs/spec/step_engine.md).
    pub fn gantry_built(&self) -> bool {
        self.has_gantry && !self.step_shared
    }

    /// `SL`: the step engine's slot bits for `n_axes` axes (docs/spec/step_engine.md):
    /// 1 for up to 2 axes, 2 for up to 4, 3 for up to 8 (`ceil(log2(n_axes))`, at least
    /// 1). Defined whether or not the core is built with the engine (and, for any
    /// `n_axes`, at most 31).
    pub fn step_slot_bits(&self) -> u32 {
        let ceil_log2 = usize::BITS - (self.n_axes.max(2) - 1).leading_zeros();
        ceil_log2.min(31)
    }

    /// `S`, the clocks between two visits of an axis: `2^SL` with the step engine
    /// (`step_shared`), 1 with a DDA and a shaper per axis (every axis served every
    /// clock). The rated rate ([`crate::rate`]) and the step timing at the pins are in
    /// multiples of it.
    pub fn step_slots(&self) -> u32 {
        if self.step_shared {
            1 << self.step_round_bits()
        } else {
            1
        }
    }

    /// Whether the core is built with the digit-serial step engine (`step_shared` and
    /// `step_digit` > 0).
    pub fn step_serial(&self) -> bool {
        self.step_shared && self.step_digit != 0
    }

    /// `log2` of the clocks between two visits of an axis with the shared engines: `SL`
    /// with the step engine, `log2 R = SL + log2(32 / STEP_DIGIT)` with the digit-serial
    /// one (docs/spec/step_serial.md).
    pub fn step_round_bits(&self) -> u32 {
        if self.step_serial() {
            self.step_slot_bits() + 5 - self.step_digit.trailing_zeros()
        } else {
            self.step_slot_bits()
        }
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

    /// The effective period in clocks for a `period_clocks` input, the period the core
    /// runs: masked to `p_width` bits, 0 acting as 1; with the step engine rounded down
    /// to a multiple of [`Self::step_slots`] `S`, at least `S`
    /// (`Ps = max(P with its low SL bits cleared, S)`, docs/spec/period_timer.md).
    pub fn effective_period(&self, period_clocks: u32) -> u32 {
        let slots = self.step_slots();
        ((period_clocks & self.period_mask()) & !(slots - 1)).max(slots)
    }
}

/// Design-time parameters of the top (`finestep_top`'s Verilog parameters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopParams {
    /// `N_AXES`: number of axes ([`finestep_top::N_AXES`]).
    pub n_axes: usize,
    /// `P_WIDTH`: bits of the period, at most the width of `PERIOD_CLOCKS.CLOCKS`.
    pub p_width: u32,
    /// `TIMING_W`: bits of each step timing, at most the width of the timing fields.
    pub timing_w: u32,
    /// `FIFO_DEPTH_LOG2`: the FIFO holds `2^n` records; its full level fits `FIFO_LEVEL.LEVEL`.
    pub fifo_depth_log2: u32,
    /// `WD_W`: bits of the watchdog, at most the width of `WATCHDOG_TIMEOUT.CLOCKS`.
    pub wd_w: u32,
    /// `CLOCK_HZ`: the clock frequency, only reported in `CLOCK_HZ`.
    pub clock_hz: u32,
    /// `HAS_SPI`: the SPI slave is built.
    pub has_spi: bool,
    /// `HAS_PARALLEL`: the 8080/FSMC slave is built.
    pub has_parallel: bool,
    /// `N_ENC`: encoder channels ([`finestep_top::N_ENC`]).
    pub n_enc: usize,
    /// `HAS_MPG`: the hand wheel and the jog generator are built.
    pub has_mpg: bool,
    /// `STEP_SHARED`: the core's step engine (`CAPS.STEP_ROUND_LOG2` =
    /// [`CoreParams::step_round_bits`] of [`Self::core_params`]).
    pub step_shared: bool,
    /// `STEP_DIGIT`: with `step_shared`, 0 the step engine, 1, 2, 4 or 8 the digit-serial
    /// step engine with that many bits a clock ([`CoreParams::step_digit`]).
    pub step_digit: u32,
    /// `ONE_SNAPSHOT`: one position snapshot for the period latch and the probe: a probe
    /// event latches `POSITION` and `LATCH_TIME`, which hold it while `PROBE_STATUS.SEEN`;
    /// `PROBE_POSITION` and `PROBE_TIME` read them (docs/spec/register_file.md#one-snapshot).
    pub one_snapshot: bool,
    /// `INC_WRITE_ONLY`: `RECORD_INC` is write-only (reads 0); needs `READ_STORE` 0, which
    /// the model does not carry (no effect on behaviour).
    pub inc_write_only: bool,
    /// `AXIS_WRITE_ONLY`: `AXIS_TIMING_A/B` and `AXIS_MODE` are write-only (read 0);
    /// needs `READ_STORE` 0, as `inc_write_only`.
    pub axis_write_only: bool,
    /// `INC_DIRECT`: a `RECORD_INC` write goes straight into the FIFO's record being
    /// written (lost while full) and `RECORD_PUSH` queues it only when every axis's lane
    /// was written since the last push, flush or use of the FIFO's port by the SPI frame
    /// layer; no push sequence. Needs `INC_WRITE_ONLY` (an elaboration check, and
    /// [`Self::validate`]).
    pub inc_direct: bool,
    /// `ENC_COUNT_W`: bits of each encoder channel's count and edge time (16 or 32;
    /// `VERSION.ENC_COUNT_16`): 16 wraps the count at 2^16 and keeps `TIMESTAMP`'s low 16
    /// bits as the edge time, read extended (docs/spec/encoder_bank.md#narrow-words).
    pub enc_count_w: u32,
    /// `HAS_SPINDLE`: the spindle block (PWM or SPI DAC) is built.
    pub has_spindle: bool,
    /// `HAS_OUTPUTS`: the logic outputs and the interlock are built.
    pub has_outputs: bool,
    /// `N_GPIO`: general outputs (with `has_outputs`).
    pub n_gpio: usize,
    /// `HAS_PANEL`: the card's panel (keypad and LED menu) is built.
    pub has_panel: bool,
    /// `HAS_GANTRY`: the gantry pair is built where the core has a DDA and a shaper per
    /// axis ([`Self::gantry_built`]).
    pub has_gantry: bool,
    /// `HAS_PBP`: the core's point-by-point comparison interpolator
    /// ([`CoreParams::has_pbp`]; `VERSION.HAS_PBP`).
    pub has_pbp: bool,
}

impl Default for TopParams {
    /// The defaults of the Verilog.
    fn default() -> Self {
        TopParams {
            n_axes: finestep_top::N_AXES.default as usize,
            p_width: finestep_top::P_WIDTH.default,
            timing_w: finestep_top::TIMING_W.default,
            fifo_depth_log2: finestep_top::FIFO_DEPTH_LOG2.default,
            wd_w: finestep_top::WD_W.default,
            clock_hz: finestep_top::CLOCK_HZ.default,
            has_spi: finestep_top::HAS_SPI.default != 0,
            has_parallel: finestep_top::HAS_PARALLEL.default != 0,
            n_enc: finestep_top::N_ENC.default as usize,
            has_mpg: finestep_top::HAS_MPG.default != 0,
            step_shared: finestep_top::STEP_SHARED.default != 0,
            step_digit: finestep_top::STEP_DIGIT.default,
            one_snapshot: finestep_top::ONE_SNAPSHOT.default != 0,
            inc_write_only: finestep_top::INC_WRITE_ONLY.default != 0,
            axis_write_only: finestep_top::AXIS_WRITE_ONLY.default != 0,
            inc_direct: finestep_top::INC_DIRECT.default != 0,
            enc_count_w: finestep_top::ENC_COUNT_W.default,
            has_spindle: finestep_top::HAS_SPINDLE.default != 0,
            has_outputs: finestep_top::HAS_OUTPUTS.default != 0,
            n_gpio: finestep_top::N_GPIO.default as usize,
            has_panel: finestep_top::HAS_PANEL.default != 0,
            has_gantry: finestep_top::HAS_GANTRY.default != 0,
            has_pbp: finestep_top::HAS_PBP.default != 0,
        }
    }
}

impl TopParams {
    /// Checks the parameters are in the supported ranges (the first one outside is reported).
    pub fn validate(&self) -> Result<(), ParamError> {
        finestep_top::N_AXES.check(self.n_axes as u64)?;
        finestep_top::P_WIDTH.check(self.p_width)?;
        finestep_top::TIMING_W.check(self.timing_w)?;
        finestep_top::FIFO_DEPTH_LOG2.check(self.fifo_depth_log2)?;
        finestep_top::WD_W.check(self.wd_w)?;
        finestep_top::CLOCK_HZ.check(self.clock_hz)?;
        finestep_top::HAS_SPI.check(self.has_spi)?;
        finestep_top::HAS_PARALLEL.check(self.has_parallel)?;
        finestep_top::N_ENC.check(self.n_enc as u64)?;
        finestep_top::HAS_MPG.check(self.has_mpg)?;
        finestep_top::STEP_SHARED.check(self.step_shared)?;
        finestep_top::STEP_DIGIT.check(self.step_digit)?;
        finestep_top::ONE_SNAPSHOT.check(self.one_snapshot)?;
        finestep_top::INC_WRITE_ONLY.check(self.inc_write_only)?;
        finestep_top::AXIS_WRITE_ONLY.check(self.axis_write_only)?;
        finestep_top::INC_DIRECT.check(self.inc_direct)?;
        if self.inc_direct && !self.inc_write_only {
            let because = "INC_DIRECT needs INC_WRITE_ONLY = 1";
            return Err(finestep_top::INC_DIRECT.narrowed(1, 0, 0, because));
        }
        finestep_top::ENC_COUNT_W.check(self.enc_count_w)?;
        if self.enc_count_w != 16 && self.enc_count_w != 32 {
            let because = "ENC_COUNT_W 16 or 32 (VERSION.ENC_COUNT_16 tells one of the two)";
            return Err(finestep_top::ENC_COUNT_W.narrowed(u64::from(self.enc_count_w), 16, 32, because));
        }
        finestep_top::HAS_SPINDLE.check(self.has_spindle)?;
        finestep_top::HAS_OUTPUTS.check(self.has_outputs)?;
        finestep_top::N_GPIO.check(self.n_gpio as u64)?;
        finestep_top::HAS_PANEL.check(self.has_panel)?;
        finestep_top::HAS_GANTRY.check(self.has_gantry)?;
        finestep_top::HAS_PBP.check(self.has_pbp)?;
        self.core_params().validate()
    }

    /// The gantry pair is built: `HAS_GANTRY` with a DDA and a shaper per axis
    /// (`gantry_sync` is not in the step engine); `CAPS.HAS_GANTRY`.
    pub fn gantry_built(&self) -> bool {
        self.has_gantry && !self.step_shared
    }

    /// The parameters of the core inside (the gantry block where [`Self::gantry_built`]).
    pub fn core_params(&self) -> CoreParams {
        CoreParams {
            n_axes: self.n_axes,
            p_width: self.p_width,
            timing_width: self.timing_w,
            has_gantry: self.gantry_built(),
            step_shared: self.step_shared,
            step_digit: self.step_digit,
            has_pbp: self.has_pbp,
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
        let wide = CoreParams {
            n_axes: 8,
            p_width: 32,
            timing_width: 32,
            has_gantry: true,
            step_shared: false,
            step_digit: 0,
            has_pbp: false,
        };
        assert_eq!(wide.period_mask(), u32::MAX);
        assert!(wide.validate().is_ok());
    }

    #[test]
    fn step_engine_slots_and_period() {
        let slots =
            |n_axes, step_shared| CoreParams { n_axes, step_shared, has_gantry: false, ..CoreParams::default() };
        let want = [(1, 1, 2), (2, 1, 2), (3, 2, 4), (4, 2, 4), (5, 3, 8), (8, 3, 8)];
        for (n, sl, s) in want {
            assert_eq!(slots(n, true).step_slot_bits(), sl, "N_AXES {n}");
            assert_eq!(slots(n, true).step_slots(), s, "N_AXES {n}");
            assert_eq!(slots(n, false).step_slots(), 1, "per-axis: every clock");
        }
        let p = slots(3, true);
        // Ps = max(P with the low SL bits cleared, S).
        for (input, ps) in [(0, 4), (1, 4), (3, 4), (4, 4), (7, 4), (9, 8), (1003, 1000), (0x10_0006, 4)] {
            assert_eq!(p.effective_period(input), ps, "P = {input}");
        }
        assert_eq!(slots(3, false).effective_period(7), 7);
    }

    #[test]
    fn bad_params_are_refused_naming_the_parameter() {
        let bad = |p: CoreParams| p.validate().unwrap_err();
        assert_eq!(bad(CoreParams { n_axes: 9, ..CoreParams::default() }).name, "N_AXES");
        assert_eq!(bad(CoreParams { p_width: 0, ..CoreParams::default() }).name, "P_WIDTH");
        let e = bad(CoreParams { timing_width: 33, ..CoreParams::default() });
        assert_eq!(e.to_string(), "finestep_core: TIMING_W = 33 is outside 1..=32");
        let shared = CoreParams { step_shared: true, has_gantry: false, ..CoreParams::default() };
        assert!(shared.validate().is_ok());
        // No gantry with the engine, whatever HAS_GANTRY says.
        let with_gantry = CoreParams { has_gantry: true, ..shared };
        assert!(with_gantry.validate().is_ok() && !with_gantry.gantry_built());
        assert!(CoreParams::default().gantry_built());
        let e = bad(CoreParams { p_width: 2, n_axes: 3, ..shared });
        assert_eq!((e.name, e.value, e.min), ("P_WIDTH", 2, 3));
        assert!(e.to_string().starts_with("finestep_core: P_WIDTH = 2 is outside 3..=32 with STEP_SHARED = 1"), "{e}");
        assert!(CoreParams { p_width: 3, n_axes: 3, ..shared }.validate().is_ok());
        assert!(CoreParams { p_width: 2, n_axes: 2, ..shared }.validate().is_ok());
        let top = |p: TopParams| p.validate().unwrap_err().name;
        let d = TopParams::default();
        assert!(d.validate().is_ok());
        assert_eq!(top(TopParams { n_axes: 0, ..d }), "N_AXES");
        assert_eq!(top(TopParams { p_width: 25, ..d }), "P_WIDTH");
        assert_eq!(top(TopParams { timing_w: 17, ..d }), "TIMING_W");
        assert_eq!(top(TopParams { fifo_depth_log2: 16, ..d }), "FIFO_DEPTH_LOG2");
        assert_eq!(top(TopParams { wd_w: 0, ..d }), "WD_W");
        assert_eq!(top(TopParams { n_enc: 5, ..d }), "N_ENC");
        assert_eq!(top(TopParams { n_enc: 0, ..d }), "N_ENC");
        assert_eq!(top(TopParams { clock_hz: 0, ..d }), "CLOCK_HZ");
        assert!(TopParams { n_enc: 1, has_mpg: false, has_spi: false, ..d }.validate().is_ok());
    }
}
