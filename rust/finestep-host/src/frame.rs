//! The SPI frame format of `spi_frame` (docs/spec/spi_frame.md): building the bytes a
//! host sends and checking the bytes it gets back. The pure encode and decode are the
//! interface's ([`finestep_interface::frame`], from the codes of `hdl/interface.toml`);
//! this module adds the driver's view of a result byte ([`FrameResult`]) and its errors.
//!
//! ```
//! use finestep_host::frame::{self, Command};
//! let tx = frame::read_request(0x06, 1);
//! assert_eq!(&tx[..3], &[Command::Read.code(), 0x06, 1]);
//! assert_eq!(tx.len(), 3 + 4 + 2);
//! ```

pub use finestep_interface::frame::{
    fifo_request, read_request, write_request, Command, FrameError, ResultCode, FRAME_CRC, HEADER_BYTES, MAX_COUNT,
};
use finestep_interface::PeriodRecord;

use crate::BusError;

/// The byte a write frame answers with after its CRC.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameResult {
    /// Applied.
    Ack,
    /// The CRC did not match: nothing applied.
    CrcMismatch,
    /// Unknown command or a bad count: nothing applied.
    BadHeader,
    /// Not enough room in the FIFO for the frame's records: nothing queued.
    FifoRefused,
    /// The FIFO was flushed (command or halt) during the frame: nothing queued.
    Flushed,
    /// A byte that is none of the codes (the link is broken).
    Unknown(u8),
}

impl FrameResult {
    /// The result code `byte`.
    pub fn from_byte(byte: u8) -> FrameResult {
        match ResultCode::from_code(byte) {
            Some(ResultCode::Ack) => FrameResult::Ack,
            Some(ResultCode::CrcMismatch) => FrameResult::CrcMismatch,
            Some(ResultCode::BadCommand) => FrameResult::BadHeader,
            Some(ResultCode::FifoRefused) => FrameResult::FifoRefused,
            Some(ResultCode::FifoFlushed) => FrameResult::Flushed,
            None => FrameResult::Unknown(byte),
        }
    }
}

impl From<FrameError> for BusError {
    fn from(error: FrameError) -> Self {
        match error {
            FrameError::ShortAnswer { sent, received } => BusError::ShortAnswer { sent, received },
            FrameError::ReadCrc { expected, got } => BusError::ReadCrc { expected, got },
        }
    }
}

/// Bytes of one record on the wire for `n_axes` axes.
pub const fn record_bytes(n_axes: usize) -> usize {
    PeriodRecord::wire_bytes(n_axes)
}

/// The words of a READ frame's answer `rx` (as long as the request), after checking its
/// CRC, which covers the header as sent and the data as received: a header the core
/// misread makes the check fail too.
pub fn read_response(tx: &[u8], rx: &[u8]) -> Result<Vec<u32>, BusError> {
    Ok(finestep_interface::frame::read_response(tx, rx)?)
}

/// The result of a WRITE or FIFO frame from its answer: the last byte.
pub fn write_result(rx: &[u8]) -> FrameResult {
    rx.last().map_or(FrameResult::Unknown(0), |&b| FrameResult::from_byte(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_result_code_has_a_frame_result() {
        for code in ResultCode::ALL {
            assert!(!matches!(FrameResult::from_byte(code.code()), FrameResult::Unknown(_)), "{code:?}");
        }
        assert_eq!(FrameResult::from_byte(0xE3), FrameResult::FifoRefused);
        assert_eq!(write_result(&[0x42]), FrameResult::Unknown(0x42));
        assert_eq!(record_bytes(4), 17);
    }

    #[test]
    fn read_answers_fail_as_bus_errors() {
        let tx = read_request(0x10, 2);
        let rx = vec![0; tx.len()];
        assert!(matches!(read_response(&tx, &rx), Err(BusError::ReadCrc { .. })));
        assert!(matches!(read_response(&tx, &rx[1..]), Err(BusError::ShortAnswer { .. })));
    }
}
