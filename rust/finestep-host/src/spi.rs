//! [`Bus`] over SPI frames.

use finestep_interface::pin_timing::PinTimingReport;
use finestep_interface::PeriodRecord;

use crate::frame::{self, FrameResult};
use crate::{Bus, BusError};

/// The core clock must be at least this many times SCK (docs/spec/spi_slave_phy.md:
/// SCK and MOSI pass two-flop synchronisers; 6.25 MHz SCK at 50 MHz).
pub const CLOCKS_PER_SCK_MIN: u32 = 8;

/// The fastest SCK a core clocked at `core_clock_hz` follows.
pub fn sck_max_hz(core_clock_hz: u32) -> u32 {
    core_clock_hz / CLOCKS_PER_SCK_MIN
}

/// Refuses an SCK the core at `core_clock_hz` cannot follow, before anything is sent.
pub fn check_sck(sck_hz: u32, core_clock_hz: u32) -> Result<(), BusError> {
    let max_hz = sck_max_hz(core_clock_hz);
    if sck_hz == 0 || sck_hz > max_hz {
        return Err(BusError::SckTooFast { sck_hz, max_hz, core_clock_hz });
    }
    Ok(())
}

/// One full-duplex SPI frame: chip select low, `tx` out, the same number of bytes in.
pub trait SpiTransfer {
    /// Sends `tx` in one frame and returns the bytes received meanwhile.
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError>;
    /// Lets `clocks` core clocks pass.
    fn wait(&mut self, clocks: u64) -> Result<(), BusError>;
    /// Drives the chip's E-stop input to `level` where the link can (a simulated chip);
    /// `Ok(false)` when it cannot (a board: the operator presses the button).
    fn drive_estop(&mut self, level: bool) -> Result<bool, BusError> {
        let _ = level;
        Ok(false)
    }
    /// Turns a simulated hand wheel by `edges` quadrature edges (4 a detent) while
    /// clocks pass; `Ok(false)` when the link cannot (a board: the operator turns it).
    fn turn_wheel(&mut self, edges: i64) -> Result<bool, BusError> {
        let _ = edges;
        Ok(false)
    }
    /// What a simulated chip measured at its step pins so far; `Ok(None)` when the link
    /// does not measure them (a board, a chip simulated without the measurement).
    fn pin_timing(&mut self) -> Result<Option<PinTimingReport>, BusError> {
        Ok(None)
    }
}

impl<T: SpiTransfer + ?Sized> SpiTransfer for Box<T> {
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        (**self).transfer(tx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        (**self).wait(clocks)
    }

    fn drive_estop(&mut self, level: bool) -> Result<bool, BusError> {
        (**self).drive_estop(level)
    }

    fn turn_wheel(&mut self, edges: i64) -> Result<bool, BusError> {
        (**self).turn_wheel(edges)
    }

    fn pin_timing(&mut self) -> Result<Option<PinTimingReport>, BusError> {
        (**self).pin_timing()
    }
}

/// [`Bus`] over an [`SpiTransfer`]: every access is one CRC-checked frame.
pub struct SpiBus<T> {
    link: T,
    n_axes: usize,
    last_status: u8,
}

impl<T: SpiTransfer> SpiBus<T> {
    /// A bus to a core with `n_axes` axes (`CAPS.N_AXES`; [`crate::Machine::connect`]
    /// reads it).
    pub fn new(link: T, n_axes: usize) -> SpiBus<T> {
        SpiBus { link, n_axes, last_status: 0 }
    }

    /// The status byte (`STATUS[7:0]`) the core sent at the start of the last frame.
    pub fn last_status(&self) -> u8 {
        self.last_status
    }

    /// The transport.
    pub fn link(&self) -> &T {
        &self.link
    }

    /// The transport, mutably.
    pub fn link_mut(&mut self) -> &mut T {
        &mut self.link
    }

    /// The transport, giving up the bus.
    pub fn into_link(self) -> T {
        self.link
    }

    /// Sets the axis count used to encode records.
    pub fn set_n_axes(&mut self, n_axes: usize) {
        self.n_axes = n_axes;
    }

    fn exchange(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        let rx = self.link.transfer(tx)?;
        if let Some(&status) = rx.first() {
            self.last_status = status;
        }
        Ok(rx)
    }

    fn checked_write(&mut self, tx: &[u8]) -> Result<(), BusError> {
        let rx = self.exchange(tx)?;
        match frame::write_result(&rx) {
            FrameResult::Ack => Ok(()),
            other => Err(BusError::Refused(other)),
        }
    }
}

impl<T: SpiTransfer> Bus for SpiBus<T> {
    fn read(&mut self, addr: u8, out: &mut [u32]) -> Result<(), BusError> {
        let mut addr = addr;
        for chunk in out.chunks_mut(frame::MAX_COUNT) {
            let tx = frame::read_request(addr, chunk.len());
            let rx = self.exchange(&tx)?;
            chunk.copy_from_slice(&frame::read_response(&tx, &rx)?);
            addr = addr.wrapping_add(chunk.len() as u8) & 0x7F;
        }
        Ok(())
    }

    fn write(&mut self, addr: u8, value: u32) -> Result<(), BusError> {
        self.checked_write(&frame::write_request(addr, value))
    }

    fn push_records(&mut self, records: &[PeriodRecord]) -> Result<(), BusError> {
        if records.is_empty() {
            return Ok(());
        }
        if records.len() > frame::MAX_COUNT {
            return Err(BusError::BurstTooLong { records: records.len(), max: frame::MAX_COUNT });
        }
        let tx = frame::fifo_request(records, self.n_axes);
        self.checked_write(&tx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        self.link.wait(clocks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sck_is_held_to_an_eighth_of_the_core_clock() {
        assert!(check_sck(6_250_000, 50_000_000).is_ok());
        let err = check_sck(6_250_001, 50_000_000).unwrap_err().to_string();
        assert_eq!(err, "SCK 6250001 Hz is over the core's limit of 6250000 Hz (50000000 Hz core clock / 8)");
        assert!(check_sck(0, 50_000_000).is_err());
    }
}
