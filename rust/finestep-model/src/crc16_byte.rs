//! `crc16_byte`: CRC-16/IBM-3740 (polynomial 0x1021, initial 0xFFFF, MSB first, no
//! reflection, no final XOR; check value of "123456789" is 0x29B1), one byte per clock:
//! the CRC after a byte from the CRC before it. A frame followed by its own CRC, high
//! byte first, leaves 0, which is how the SPI frame layer checks a frame.
//!
//! Specification: docs/spec/crc16_byte.md

/// The generator polynomial `x^16 + x^12 + x^5 + 1` without its top bit (the interface's).
pub const POLYNOMIAL: u16 = finestep_interface::spi::CRC_POLYNOMIAL;

/// The register value at the start of a frame (the interface's).
pub const INITIAL: u16 = finestep_interface::spi::CRC_INITIAL;

/// The CRC after `byte` (most significant bit first) from the CRC `crc` before it: the
/// combinational function of the HDL block.
pub const fn crc16_byte(crc: u16, byte: u8) -> u16 {
    let mut crc = crc ^ ((byte as u16) << 8);
    let mut bit = 0;
    while bit < 8 {
        crc = if crc & 0x8000 != 0 { (crc << 1) ^ POLYNOMIAL } else { crc << 1 };
        bit += 1;
    }
    crc
}

/// The CRC of a whole byte sequence from [`INITIAL`].
pub fn crc16(bytes: &[u8]) -> u16 {
    bytes.iter().fold(INITIAL, |crc, &b| crc16_byte(crc, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value_of_the_catalogue() {
        assert_eq!(crc16(b"123456789"), 0x29B1);
        assert_eq!(crc16(b""), INITIAL);
    }

    #[test]
    fn a_frame_followed_by_its_crc_leaves_zero() {
        let frame = b"finestep";
        let crc = crc16(frame);
        let [high, low] = crc.to_be_bytes();
        assert_eq!(crc16_byte(crc16_byte(crc, high), low), 0);
    }
}
