//! finestep host driver: how a host talks to the core's register file and position
//! FIFO, over the SPI frame protocol or the 8080/FSMC parallel bus.
//!
//! - [`Bus`]: register reads and writes, record bursts into the FIFO, and waiting.
//!   [`SpiBus`] implements it over any [`SpiTransfer`] (the frames of [`frame`]);
//!   [`ParallelBus`] over the 8080 pins.
//! - Transports: [`PinHost`] drives a simulated core at its pins ([`PinTarget`]: the
//!   Verilated RTL, the reference model, or both in lockstep) with the SPI and 8080
//!   timing of the spec (docs/spec/); [`spidev::Spidev`] a real board over Linux spidev.
//! - [`Machine`]: identity check, configuration, faults, run, coherent positions; its
//!   [`feedback`] side: encoders, probe, hand wheel, jog, velocity estimation.
//! - [`stream`]: keeps the FIFO fed from an iterator of period records.

#![warn(missing_docs)]

pub mod feedback;
pub mod frame;
pub mod machine;
pub mod parallel;
pub mod pins;
pub mod spi;
#[cfg(all(target_os = "linux", feature = "spidev"))]
pub mod spidev;
pub mod stream;

pub use feedback::{
    CountMode, EncoderSetup, FeedbackError, FeedbackSnapshot, HandWheelState, JogMultiplier, JogSetup, JogState,
    ProbeHit, VelocityEstimator,
};
pub use finestep_interface::regs;
pub use machine::{AxisSetup, Caps, Machine, Positions};
pub use parallel::ParallelBus;
pub use pins::{PinHost, PinTarget, PinTiming};
pub use spi::{SpiBus, SpiTransfer};

use finestep_model::PeriodRecord;

/// Why a bus operation failed. Nothing is applied by a failed write.
#[derive(Debug, thiserror::Error)]
pub enum BusError {
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
    /// The core did not behave as the protocol says (e.g. no data on an 8080 read).
    #[error("protocol: {0}")]
    Protocol(String),
    /// The device at the other end is not a finestep core of a compatible version.
    #[error("not a compatible finestep core: {0}")]
    Identity(String),
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
