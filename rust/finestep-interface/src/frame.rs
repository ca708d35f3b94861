//! The SPI frame format of `spi_frame` (docs/spec/spi_frame.md, docs/interface.md): the
//! bytes a host sends and the checks of the bytes it gets back. Pure functions, shared
//! by every SPI transport and by the tests that build frames by hand.
//!
//! ```
//! use finestep_interface::frame::{self, Command};
//! let tx = frame::read_request(0x06, 1);
//! assert_eq!(&tx[..3], &[Command::Read.code(), 0x06, 1]);
//! assert_eq!(tx.len(), 3 + 4 + 2);
//! ```

use crc::{Crc, CRC_16_IBM_3740};

pub use crate::spi::{Command, ResultCode, MAX_COUNT};
use crate::{regs, spi, PeriodRecord};

/// CRC-16/IBM-3740 (poly 0x1021, init 0xFFFF, MSB first, no final XOR), the frames' CRC.
pub const FRAME_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

// The catalogue CRC must be the one the interface description states.
const _: () = assert!(
    CRC_16_IBM_3740.width as u32 == spi::CRC_WIDTH
        && CRC_16_IBM_3740.poly == spi::CRC_POLYNOMIAL
        && CRC_16_IBM_3740.init == spi::CRC_INITIAL
        && !CRC_16_IBM_3740.refin
        && !CRC_16_IBM_3740.refout
        && CRC_16_IBM_3740.xorout == 0,
    "hdl/interface.toml's CRC is not CRC-16/IBM-3740"
);

/// Bytes of a frame header: command, address, count.
pub const HEADER_BYTES: usize = 3;

/// Why a READ frame's answer cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// The answer is not as long as the request.
    #[error("read frame of {sent} bytes answered with {received}")]
    ShortAnswer {
        /// Bytes sent.
        sent: usize,
        /// Bytes received.
        received: usize,
    },
    /// The answer failed its CRC (the header or the data was corrupted).
    #[error("read answer CRC mismatch: expected {expected:#06x}, got {got:#06x}")]
    ReadCrc {
        /// CRC computed over what was sent and received.
        expected: u16,
        /// CRC the core sent.
        got: u16,
    },
}

fn with_crc(mut bytes: Vec<u8>) -> Vec<u8> {
    let crc = FRAME_CRC.checksum(&bytes);
    bytes.extend_from_slice(&crc.to_be_bytes());
    bytes
}

fn address(addr: u8) -> u8 {
    addr & ((1u16 << regs::ADDRESS_BITS) - 1) as u8
}

/// The bytes of a READ frame for `count` words (1..=[`MAX_COUNT`]) from `addr`: the
/// header and the filler bytes during which the core answers.
pub fn read_request(addr: u8, count: usize) -> Vec<u8> {
    debug_assert!((1..=MAX_COUNT).contains(&count));
    let mut bytes = vec![Command::Read.code(), address(addr), count as u8];
    bytes.resize(HEADER_BYTES + 4 * count + 2, 0);
    bytes
}

/// The words of a READ frame's answer `rx` (as long as the request), after checking its
/// CRC, which covers the header as sent and the data as received: a header the core
/// misread makes the check fail too.
pub fn read_response(tx: &[u8], rx: &[u8]) -> Result<Vec<u32>, FrameError> {
    if rx.len() != tx.len() || tx.len() < HEADER_BYTES + 4 + 2 || (tx.len() - HEADER_BYTES - 2) & 3 != 0 {
        return Err(FrameError::ShortAnswer { sent: tx.len(), received: rx.len() });
    }
    let data = &rx[HEADER_BYTES..rx.len() - 2];
    let mut digest = FRAME_CRC.digest();
    digest.update(&tx[..HEADER_BYTES]);
    digest.update(data);
    let expected = digest.finalize();
    let got = u16::from_be_bytes([rx[rx.len() - 2], rx[rx.len() - 1]]);
    if expected != got {
        return Err(FrameError::ReadCrc { expected, got });
    }
    Ok(data.chunks_exact(4).map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]])).collect())
}

/// The bytes of a WRITE frame of `value` to `addr`, with its CRC and the result byte.
pub fn write_request(addr: u8, value: u32) -> Vec<u8> {
    let mut bytes = vec![Command::Write.code(), address(addr), 1];
    bytes.extend_from_slice(&value.to_be_bytes());
    let mut bytes = with_crc(bytes);
    bytes.push(0);
    bytes
}

/// The bytes of a FIFO frame queueing `records` (1..=[`MAX_COUNT`]) for a core of
/// `n_axes` axes, with its CRC and the result byte.
pub fn fifo_request(records: &[PeriodRecord], n_axes: usize) -> Vec<u8> {
    debug_assert!((1..=MAX_COUNT).contains(&records.len()));
    let mut bytes = Vec::with_capacity(HEADER_BYTES + records.len() * PeriodRecord::wire_bytes(n_axes) + 3);
    bytes.extend_from_slice(&[Command::Fifo.code(), 0, records.len() as u8]);
    for record in records {
        record.encode(n_axes, &mut bytes);
    }
    let mut bytes = with_crc(bytes);
    bytes.push(0);
    bytes
}

/// The result of a WRITE or FIFO frame from its answer (the last byte): the code, or
/// the byte when it is none (the link is broken; an empty answer reads as 0).
pub fn write_result(rx: &[u8]) -> Result<ResultCode, u8> {
    let byte = rx.last().copied().unwrap_or(0);
    ResultCode::from_code(byte).ok_or(byte)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_followed_by_its_crc_leaves_zero() {
        let frame = write_request(0x04, 0x1234_5678);
        let body = &frame[..frame.len() - 1];
        assert_eq!(FRAME_CRC.checksum(body), 0);
        assert_eq!(FRAME_CRC.checksum(b"123456789"), 0x29B1);
    }

    #[test]
    fn records_are_axis_major_big_endian_then_flags() {
        let record = PeriodRecord::from_raw(&[0x0102_0304, -1], 0x01);
        let frame = fifo_request(&[record], 2);
        assert_eq!(&frame[..3], &[0x03, 0, 1]);
        assert_eq!(&frame[3..12], &[1, 2, 3, 4, 0xFF, 0xFF, 0xFF, 0xFF, 0x01]);
        assert_eq!(frame.len(), 3 + 9 + 2 + 1);
    }

    #[test]
    fn a_read_answer_is_checked_over_header_and_data() {
        let tx = read_request(0x10, 2);
        let mut rx = vec![0x55, 0, 0, 0xDE, 0xAD, 0xBE, 0xEF, 0, 0, 0, 7];
        let crc = {
            let mut d = FRAME_CRC.digest();
            d.update(&tx[..3]);
            d.update(&rx[3..11]);
            d.finalize()
        };
        rx.extend_from_slice(&crc.to_be_bytes());
        assert_eq!(read_response(&tx, &rx).unwrap(), vec![0xDEAD_BEEF, 7]);
        rx[5] ^= 0x10;
        assert!(matches!(read_response(&tx, &rx), Err(FrameError::ReadCrc { .. })));
        assert_eq!(read_response(&tx, &rx[1..]), Err(FrameError::ShortAnswer { sent: 13, received: 12 }));
    }

    #[test]
    fn result_bytes() {
        assert_eq!(write_result(&[0, 0xA0]), Ok(ResultCode::Ack));
        assert_eq!(write_result(&[0xE3]), Ok(ResultCode::FifoRefused));
        assert_eq!(write_result(&[0x42]), Err(0x42));
        assert_eq!(write_result(&[]), Err(0));
    }
}
