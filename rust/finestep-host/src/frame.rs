//! The SPI frame format of `spi_frame` (docs/spec/spi_frame.md): building the bytes a
//! host sends and checking the bytes it gets back. Pure functions, shared by every SPI
//! transport.
//!
//! ```
//! use finestep_host::frame::{self, Command};
//! let tx = frame::read_request(0x06, 1);
//! assert_eq!(&tx[..3], &[Command::Read as u8, 0x06, 1]);
//! assert_eq!(tx.len(), 3 + 4 + 2);
//! ```

use crc::{Crc, CRC_16_IBM_3740};
use finestep_model::PeriodRecord;

use crate::BusError;

/// CRC-16/IBM-3740 (poly 0x1021, init 0xFFFF, MSB first, no final XOR), the frames' CRC.
pub const FRAME_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

/// Most words of one READ frame and most records of one FIFO frame.
pub const MAX_COUNT: usize = 255;

/// The command byte.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Command {
    /// Read `count` words.
    Read = 0x01,
    /// Write one word.
    Write = 0x02,
    /// Queue `count` period records.
    Fifo = 0x03,
}

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
        match byte {
            0xA0 => FrameResult::Ack,
            0xE1 => FrameResult::CrcMismatch,
            0xE2 => FrameResult::BadHeader,
            0xE3 => FrameResult::FifoRefused,
            0xE4 => FrameResult::Flushed,
            other => FrameResult::Unknown(other),
        }
    }
}

/// Bytes of one record on the wire for `n_axes` axes.
pub const fn record_bytes(n_axes: usize) -> usize {
    4 * n_axes + 1
}

fn with_crc(mut bytes: Vec<u8>) -> Vec<u8> {
    let crc = FRAME_CRC.checksum(&bytes);
    bytes.extend_from_slice(&crc.to_be_bytes());
    bytes
}

/// The bytes of a READ frame for `count` words (1..=255) from `addr`: the header and
/// the filler bytes during which the core answers.
pub fn read_request(addr: u8, count: usize) -> Vec<u8> {
    debug_assert!((1..=MAX_COUNT).contains(&count));
    let mut bytes = vec![Command::Read as u8, addr & 0x7F, count as u8];
    bytes.resize(3 + 4 * count + 2, 0);
    bytes
}

/// The words of a READ frame's answer `rx` (as long as the request), after checking its
/// CRC, which covers the header as sent and the data as received: a header the core
/// misread makes the check fail too.
pub fn read_response(tx: &[u8], rx: &[u8]) -> Result<Vec<u32>, BusError> {
    if rx.len() != tx.len() || tx.len() < 9 || (tx.len() - 5) & 3 != 0 {
        return Err(BusError::ShortAnswer { sent: tx.len(), received: rx.len() });
    }
    let data = &rx[3..rx.len() - 2];
    let mut digest = FRAME_CRC.digest();
    digest.update(&tx[..3]);
    digest.update(data);
    let expected = digest.finalize();
    let got = u16::from_be_bytes([rx[rx.len() - 2], rx[rx.len() - 1]]);
    if expected != got {
        return Err(BusError::ReadCrc { expected, got });
    }
    Ok(data.chunks_exact(4).map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]])).collect())
}

/// The bytes of a WRITE frame of `value` to `addr`, with its CRC and the result byte.
pub fn write_request(addr: u8, value: u32) -> Vec<u8> {
    let mut bytes = vec![Command::Write as u8, addr & 0x7F, 1];
    bytes.extend_from_slice(&value.to_be_bytes());
    let mut bytes = with_crc(bytes);
    bytes.push(0);
    bytes
}

/// The bytes of a FIFO frame queueing `records` (1..=255) for a core of `n_axes` axes.
pub fn fifo_request(records: &[PeriodRecord], n_axes: usize) -> Vec<u8> {
    debug_assert!((1..=MAX_COUNT).contains(&records.len()));
    let mut bytes = Vec::with_capacity(3 + records.len() * record_bytes(n_axes) + 3);
    bytes.extend_from_slice(&[Command::Fifo as u8, 0, records.len() as u8]);
    for record in records {
        for inc in &record.inc[..n_axes] {
            bytes.extend_from_slice(&inc.to_bits().to_be_bytes());
        }
        bytes.push(record.flags);
    }
    let mut bytes = with_crc(bytes);
    bytes.push(0);
    bytes
}

/// The result of a WRITE or FIFO frame from its answer: the last byte.
pub fn write_result(rx: &[u8]) -> FrameResult {
    rx.last().map_or(FrameResult::Unknown(0), |&b| FrameResult::from_byte(b))
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
        assert!(matches!(read_response(&tx, &rx), Err(BusError::ReadCrc { .. })));
    }
}
