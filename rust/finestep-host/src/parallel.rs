//! [`Bus`] over the 8080/FSMC parallel bus, at its pins.

use finestep_interface::PeriodRecord;

use crate::pins::{PinHost, PinTarget};
use crate::regs::{record_inc, record_push};
use crate::{Bus, BusError};

/// [`Bus`] over the 8080 pins of a [`PinHost`]: every 32-bit access is two 16-bit ones,
/// low half first (the core latches the high half on a low-half read and applies a
/// write only with its high half).
pub struct ParallelBus<T> {
    host: PinHost<T>,
    n_axes: usize,
}

impl<T: PinTarget> ParallelBus<T> {
    /// A bus to a core with `n_axes` axes.
    pub fn new(host: PinHost<T>, n_axes: usize) -> ParallelBus<T> {
        ParallelBus { host, n_axes }
    }

    /// The pin-level host.
    pub fn host_mut(&mut self) -> &mut PinHost<T> {
        &mut self.host
    }

    /// Sets the axis count used to push records.
    pub fn set_n_axes(&mut self, n_axes: usize) {
        self.n_axes = n_axes;
    }
}

impl<T: PinTarget> Bus for ParallelBus<T> {
    fn read(&mut self, addr: u8, out: &mut [u32]) -> Result<(), BusError> {
        for (offset, word) in out.iter_mut().enumerate() {
            let register = addr.wrapping_add(offset as u8) & 0x7F;
            let low = self.host.parallel_read16(register << 1)?;
            let high = self.host.parallel_read16(register << 1 | 1)?;
            *word = u32::from(high) << 16 | u32::from(low);
        }
        Ok(())
    }

    fn write(&mut self, addr: u8, value: u32) -> Result<(), BusError> {
        let register = addr & 0x7F;
        self.host.parallel_write16(register << 1, value as u16)?;
        self.host.parallel_write16(register << 1 | 1, (value >> 16) as u16)
    }

    fn push_records(&mut self, records: &[PeriodRecord]) -> Result<(), BusError> {
        for record in records {
            for (axis, inc) in record.inc[..self.n_axes].iter().enumerate() {
                self.write(record_inc::addr(axis), inc.to_bits() as u32)?;
            }
            self.write(record_push::ADDR, record_push::FLAGS.set(0, u32::from(record.flags)))?;
        }
        Ok(())
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        self.host.idle(clocks)
    }
}
