//! `crc16_serial`: CRC-16/IBM-3740 (polynomial 0x1021, initial 0xFFFF, MSB first, no
//! reflection, no final XOR), one bit per clock, as the SPI slave receives a frame.
//! A frame followed by its own CRC, most significant bit first, leaves zero.

/// The CRC register.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc16Serial {
    crc: u16,
}

const POLYNOMIAL: u16 = 0x1021;
const INITIAL: u16 = 0xFFFF;

impl Default for Crc16Serial {
    fn default() -> Self {
        Crc16Serial { crc: INITIAL }
    }
}

impl Crc16Serial {
    /// The register value.
    pub fn crc(&self) -> u16 {
        self.crc
    }

    /// Whether the register is zero (a frame with its CRC appended checks).
    pub fn zero(&self) -> bool {
        self.crc == 0
    }

    /// One clock edge: `init` restarts (and wins), else `bit` is shifted in if present.
    pub fn step(&mut self, init: bool, bit: Option<bool>) {
        if init {
            self.crc = INITIAL;
        } else if let Some(bit) = bit {
            let feedback = ((self.crc >> 15) != 0) ^ bit;
            self.crc = (self.crc << 1) ^ if feedback { POLYNOMIAL } else { 0 };
        }
    }

    /// Shift in a byte, most significant bit first (eight clocks with a bit each).
    pub fn push_byte(&mut self, byte: u8) {
        for i in (0..8).rev() {
            self.step(false, Some((byte >> i) & 1 != 0));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const REFERENCE: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);

    #[test]
    fn check_value_of_the_catalogue() {
        let mut crc = Crc16Serial::default();
        b"123456789".iter().for_each(|&b| crc.push_byte(b));
        assert_eq!(crc.crc(), 0x29B1);
    }

    #[test]
    fn equals_the_crc_crate_and_a_frame_with_its_crc_checks() {
        let mut runner = finestep_testkit::runner("crc16_equals_the_crc_crate", 512);
        runner
            .run(&proptest::collection::vec(any::<u8>(), 0..300), |frame| {
                let mut crc = Crc16Serial::default();
                frame.iter().for_each(|&b| crc.push_byte(b));
                prop_assert_eq!(crc.crc(), REFERENCE.checksum(&frame));
                let [high, low] = crc.crc().to_be_bytes();
                crc.push_byte(high);
                crc.push_byte(low);
                prop_assert!(crc.zero());
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn every_single_bit_error_is_detected() {
        let frame: Vec<u8> = (0..64u8).map(|b| b.wrapping_mul(37)).collect();
        let good = REFERENCE.checksum(&frame);
        for bit in 0..frame.len() * 8 {
            let mut bad = frame.clone();
            bad[bit / 8] ^= 0x80 >> (bit % 8);
            let mut crc = Crc16Serial::default();
            bad.iter().chain(&good.to_be_bytes()).for_each(|&b| crc.push_byte(b));
            assert!(!crc.zero(), "bit {bit} flipped went undetected");
        }
    }
}
