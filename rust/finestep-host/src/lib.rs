//! finestep host driver: how a host talks to the core's register file and position
//! FIFO, over the SPI frame protocol or the 8080/FSMC parallel bus.
//!
//! - [`Bus`]: register reads and writes, record bursts into the FIFO, and waiting.
//!   [`SpiBus`] implements it over any [`SpiTransfer`] (the frames of [`frame`]);
//!   [`ParallelBus`] over the 8080 pins.
//! - Transports: [`PinHost`] drives a simulated core at its pins ([`PinTarget`]: the
//!   Verilated RTL, the reference model, or both in lockstep) with the SPI and 8080
//!   timing of the spec (docs/spec/); [`spidev::Spidev`] a real board over Linux spidev;
//!   [`sim_link::SimSocket`] a simulated chip served on a Unix socket (`finestep sim-chip`).
//! - [`Machine`]: identity check, configuration, faults, run, coherent positions; its
//!   [`feedback`] side: encoders, probe, hand wheel, jog, velocity estimation.
//! - [`stream`]: runs period records: pre-fills the FIFO, starts, keeps it fed in bursts
//!   and waits for the end, with an observer called while it waits.

#![warn(missing_docs)]

pub mod feedback;
pub mod frame;
pub mod machine;
pub mod machine_io;
pub mod machine_panel;
pub mod parallel;
pub mod pins;
#[cfg(unix)]
pub mod sim_link;
pub mod spi;
#[cfg(all(target_os = "linux", feature = "spidev"))]
pub mod spidev;
pub mod stream;

pub use feedback::{
    count_delta, CountExtender, CountMode, EdgeTimeExtender, EncoderSetup, FeedbackError, FeedbackSnapshot,
    HandWheelState, JogMultiplier, JogSetup, JogState, ProbeHit, VelocityEstimator,
};
pub use finestep_interface::regs;
pub use machine::{AxisSetup, Caps, Machine, Positions};
pub use machine_io::{InterlockSetup, Outputs, SpindleSetup, SpindleStatus};
pub use machine_panel::{GantrySetup, GantryStatus, PanelDisplay, PanelKeys, PanelMenu, PanelScan};
pub use parallel::ParallelBus;
pub use pins::{PinHost, PinTarget, PinTiming};
pub use spi::{SpiBus, SpiTransfer};

pub use finestep_interface::pin_timing::PinTimingReport;
pub use finestep_interface::{DriveTiming, Increment, OutMode, PbpLanes, PeriodRecord};

/// Why a bus operation failed. Nothing is applied by a failed write.
#[derive(Debug, thiserror::Error)]
pub enum BusError {
    /// The core was built without the block a call needs (its `CAPS` bit is 0).
    #[error("the core has no {0} (CAPS)")]
    NotBuilt(&'static str),
    /// A write or FIFO frame was answered with this result instead of ACK.
    #[error("frame refused by the core: {0:?}")]
    Refused(frame::FrameResult),
    /// A read answer failed its CRC (the header or the data was corrupted).
    #[error("read answer CRC mismatch: expected {expected:#06x}, got {got:#06x}")]
    ReadCrc {
        /// CRC computed over what was sent and received.
        expected: u16,
        /// CRC the core sent.
        got: u16,
    },
    /// A read frame's answer is not as long as the request.
    #[error("read frame of {sent} bytes answered with {received}")]
    ShortAnswer {
        /// Bytes sent.
        sent: usize,
        /// Bytes received.
        received: usize,
    },
    /// An 8080 read strobe found the bus not driven by the core.
    #[error("8080 read of halfword {halfword:#04x}: the core did not drive the bus")]
    NotDriven {
        /// The halfword address read.
        halfword: u8,
    },
    /// The device at the other end does not answer ID with the finestep magic.
    #[error("not a finestep core: ID reads {found:#010x}, not {expected:#010x}")]
    NotFinestep {
        /// What ID read.
        found: u32,
        /// The finestep magic.
        expected: u32,
    },
    /// The core speaks another major version of the register map.
    #[error("not a compatible finestep core: register map version {found}.x, this driver speaks {driver}.x")]
    MapVersion {
        /// The core's major version.
        found: u32,
        /// The driver's major version.
        driver: u32,
    },
    /// `CAPS` or `CLOCK_HZ` describe no build the RTL accepts (the link is broken, or
    /// this is not a finestep core).
    #[error("CAPS reads {word:#010x} and CLOCK_HZ {clock_hz}: {error}")]
    Caps {
        /// The CAPS word read.
        word: u32,
        /// The CLOCK_HZ word read.
        clock_hz: u32,
        /// The first parameter outside its range.
        error: finestep_interface::ParamError,
    },
    /// `CAPS.STEP_ROUND_LOG2` is not a round a step engine for `CAPS.N_AXES` axes has (its
    /// slots, or its slots times 32 / STEP_DIGIT with the digit-serial engine; the link is
    /// broken, or this is not a finestep core).
    #[error(
        "CAPS reads {word:#010x}: a step round of {found} clocks (CAPS.STEP_ROUND_LOG2), but that build has {built}"
    )]
    StepSlots {
        /// The CAPS word read.
        word: u32,
        /// The slots CAPS reports.
        found: u32,
        /// The slots of the build CAPS otherwise describes.
        built: u32,
    },
    /// A point-by-point record the core cannot run as meant ([`Machine::pbp_record`]).
    #[error("point-by-point record refused: {why}")]
    PbpRecord {
        /// Why.
        why: String,
    },
    /// An axis the core was not built with (`CAPS.N_AXES`).
    #[error("axis {axis}: the core has {n_axes} axes (CAPS.N_AXES)")]
    NoSuchAxis {
        /// The axis asked for.
        axis: usize,
        /// Axes the core has.
        n_axes: usize,
    },
    /// A drive timing wider than the core's timing counters (`CAPS.TIMING_W`).
    #[error("axis {axis}: {field} = {value} clocks exceeds the core's {max} (CAPS.TIMING_W)")]
    TimingRange {
        /// The axis.
        axis: usize,
        /// The timing field (`step_len`, `step_space`, `dir_setup`, `dir_hold`).
        field: &'static str,
        /// The value asked for, clocks.
        value: u32,
        /// The largest the core holds, clocks.
        max: u32,
    },
    /// A period the core's period counter cannot hold (`CAPS.P_WIDTH`).
    #[error("a period of {clocks} clocks is outside the core's 1..={max} (CAPS.P_WIDTH)")]
    PeriodRange {
        /// The period asked for, clocks.
        clocks: u32,
        /// The longest period the core holds, clocks.
        max: u32,
    },
    /// A period that is not a multiple of the step engine's round (`CAPS.STEP_ROUND_LOG2`).
    #[error("a period of {clocks} clocks is not a multiple of the core's step round of {slots} clocks (CAPS.STEP_ROUND_LOG2)")]
    PeriodSlots {
        /// The period asked for, clocks.
        clocks: u32,
        /// The step engine's slots.
        slots: u32,
    },
    /// A setting too large for its register field.
    #[error("{what} = {value} does not fit its register field (at most {max})")]
    SettingRange {
        /// The setting.
        what: &'static str,
        /// What was asked for.
        value: u32,
        /// The field's largest value.
        max: u32,
    },
    /// More records than one FIFO frame carries.
    #[error("{records} records in one burst (at most {max})")]
    BurstTooLong {
        /// Records in the burst.
        records: usize,
        /// Records a frame carries at most.
        max: usize,
    },
    /// `POSITION` holds the probe event's snapshot, not the period latch's (a core with
    /// `VERSION.ONE_SNAPSHOT` and `PROBE_STATUS.SEEN`): `Machine::release_probe_snapshot`
    /// hands it back to the latch.
    #[error("POSITION holds the probe's snapshot (ONE_SNAPSHOT, PROBE_STATUS.SEEN): arm the probe to resume the period latch")]
    ProbeHoldsPositions,
    /// The position latch moved during every attempt at a coherent read.
    #[error("the latch kept moving during {attempts} attempts to read the {what}")]
    LatchMoving {
        /// Attempts made.
        attempts: usize,
        /// What was being read.
        what: &'static str,
    },
    /// The core still had records to run (or was still streaming) after the wait.
    #[error("still streaming after {clocks} clocks")]
    StillStreaming {
        /// Clocks waited.
        clocks: u64,
    },
    /// The core halted (E-stop, watchdog or the gantry's alarm: `STATUS.HALT`) while
    /// records were being streamed or run: the FIFO was flushed and `RUN` cleared, so
    /// nothing more will run until the fault is cleared and the run requested again.
    #[error("the core halted while streaming (STATUS {status:#06x}: E-stop, watchdog or the gantry's alarm)")]
    Halted {
        /// `STATUS` as read.
        status: u32,
    },
    /// The FIFO took no record for `clocks` clocks while records were waiting to be
    /// queued, and the core is not halted (`RUN` cleared by the host, or a record that
    /// runs longer than the streamer was told).
    #[error("the core took no record for {clocks} clocks (STATUS {status:#06x})")]
    Stalled {
        /// Clocks waited without room appearing.
        clocks: u64,
        /// `STATUS` as read.
        status: u32,
    },
    /// A feedback request the core cannot carry out (refused before anything was written).
    #[error(transparent)]
    Feedback(#[from] FeedbackError),
    /// An SCK faster than the core's synchronisers follow ([`spi::CLOCKS_PER_SCK_MIN`]).
    #[error("SCK {sck_hz} Hz is over the core's limit of {max_hz} Hz ({core_clock_hz} Hz core clock / {ratio})", ratio = spi::CLOCKS_PER_SCK_MIN)]
    SckTooFast {
        /// The SCK asked for.
        sck_hz: u32,
        /// The fastest SCK the core follows.
        max_hz: u32,
        /// The core clock.
        core_clock_hz: u32,
    },
    /// The transport failed (an I/O error, or a co-simulation mismatch).
    #[error("transport: {0}")]
    Transport(Box<dyn std::error::Error + Send + Sync>),
}

/// Register and FIFO access to one core.
pub trait Bus {
    /// Reads `out.len()` consecutive registers starting at word address `addr`.
    fn read(&mut self, addr: u8, out: &mut [u32]) -> Result<(), BusError>;
    /// Writes `value` to the register at `addr`.
    fn write(&mut self, addr: u8, value: u32) -> Result<(), BusError>;
    /// Queues `records` in the position FIFO (at most [`frame::MAX_COUNT`] per call).
    /// Over SPI a call is all or nothing.
    fn push_records(&mut self, records: &[PeriodRecord]) -> Result<(), BusError>;
    /// Lets `clocks` core clocks pass (a simulated core runs them; a board sleeps).
    fn wait(&mut self, clocks: u64) -> Result<(), BusError>;

    /// Reads one register.
    fn read_one(&mut self, addr: u8) -> Result<u32, BusError> {
        let mut word = [0];
        self.read(addr, &mut word)?;
        Ok(word[0])
    }
}
