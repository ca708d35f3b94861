//! A real board over Linux spidev: [`SpiTransfer`] by one full-duplex ioctl per frame.

use std::time::Duration;

use spidev::{SpiModeFlags, Spidev as Device, SpidevOptions, SpidevTransfer};

use crate::spi::SpiTransfer;
use crate::BusError;

/// `/dev/spidevB.C` in mode 0, MSB first, at a chosen SCK (at most the core clock / 8).
pub struct Spidev {
    device: Device,
    clock_hz: u32,
}

impl Spidev {
    /// Opens `path` with SCK at `sck_hz`; `core_clock_hz` converts waits into sleeps.
    /// An SCK over the core's limit ([`crate::spi::check_sck`]) is refused before the
    /// device is opened.
    pub fn open(path: &str, sck_hz: u32, core_clock_hz: u32) -> Result<Spidev, BusError> {
        crate::spi::check_sck(sck_hz, core_clock_hz)?;
        let mut device = Device::open(path).map_err(|e| BusError::Transport(Box::new(e)))?;
        let options = SpidevOptions::new().bits_per_word(8).max_speed_hz(sck_hz).mode(SpiModeFlags::SPI_MODE_0).build();
        device.configure(&options).map_err(|e| BusError::Transport(Box::new(e)))?;
        Ok(Spidev { device, clock_hz: core_clock_hz.max(1) })
    }
}

impl SpiTransfer for Spidev {
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        let mut rx = vec![0u8; tx.len()];
        let mut transfer = SpidevTransfer::read_write(tx, &mut rx);
        self.device.transfer(&mut transfer).map_err(|e| BusError::Transport(Box::new(e)))?;
        Ok(rx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        std::thread::sleep(Duration::from_nanos(clocks.saturating_mul(1_000_000_000) / u64::from(self.clock_hz)));
        Ok(())
    }
}
