//! Two motors on one gantry axis, the core's RTL and model in lockstep: axis 0 (the
//! master) and axis 1 (the slave) drive the two sides, each side read by an encoder of
//! [`GantryPair::COUNTS_PER_STEP`] counts a motor step, the counts sampled once a period
//! (a feedback path a period slow). The master moves at a steady speed; the caller says
//! how many steps the slave's motor has lost (a stall: its pulses did not move it).
//!
//! The gantry lockstep tests and `finestep bench`'s gantry figure both run this set-up.

use finestep_model::{AxisConfig, CoreInputs, CoreOutputs, DriveTiming, GantryInputs, Increment, PeriodRecord};

use crate::{Harness, Mismatch, ModelPath};

/// The master's axis.
pub const MASTER: usize = 0;
/// The slave's axis.
pub const SLAVE: usize = 1;

/// A gantry pair in lockstep (see the module's description).
pub struct GantryPair {
    /// The RTL and the model side by side.
    pub harness: Harness,
    /// The core's inputs; the encoder counts are set by [`GantryPair::feed_period`].
    pub inputs: CoreInputs,
    /// The record fed every period (the master's increment; change it to stop).
    pub record: PeriodRecord,
}

impl GantryPair {
    /// Encoder counts a motor step.
    pub const COUNTS_PER_STEP: i64 = 4;

    /// A fresh pair out of reset: periods of `period` clocks, the master at `speed` steps a
    /// period, the gantry engaged in synchronised (`sync`) or forward mode with a
    /// correction at most every other period, `deadband` and `limit` in counts. `name`
    /// names the waveform of a failure.
    pub fn new(
        name: &str,
        path: ModelPath,
        sync: bool,
        period: u32,
        speed: f64,
        deadband: u16,
        limit: u16,
    ) -> GantryPair {
        let harness = Harness::with_gantry(name, path);
        let axis = AxisConfig { timing: DriveTiming::new(2, 2, 2, 2), mode: 0, invert: 0, enable: true };
        let mut inputs = CoreInputs { run: true, period_clocks: period, ..Default::default() };
        inputs.axes[MASTER] = axis;
        inputs.axes[SLAVE] = axis;
        inputs.gantry = GantryInputs {
            enable: true,
            sync,
            master: MASTER as u8,
            slave: SLAVE as u8,
            tick: 2 * period,
            deadband,
            limit,
            ..Default::default()
        };
        let mut record = PeriodRecord::default();
        record.inc[MASTER] = Increment::from_num(speed);
        GantryPair { harness, inputs, record }
    }

    /// Samples both encoders (the slave's motor `slave_lost` steps short of its commanded
    /// position) and runs one period. Returns the error the chip sees for that period:
    /// the master side's count less the slave side's.
    pub fn feed_period(&mut self, slave_lost: i64) -> Result<i64, Box<Mismatch>> {
        let positions = self.harness.outputs().positions;
        let master = Self::COUNTS_PER_STEP * i64::from(positions[MASTER] as i32);
        let slave = Self::COUNTS_PER_STEP * (i64::from(positions[SLAVE] as i32) - slave_lost);
        self.inputs.gantry.enc_master = master as u32;
        self.inputs.gantry.enc_slave = slave as u32;
        self.harness.feed(&mut self.inputs, [self.record])?;
        Ok(master - slave)
    }

    /// The core's outputs now.
    pub fn outputs(&self) -> CoreOutputs {
        self.harness.outputs()
    }
}
