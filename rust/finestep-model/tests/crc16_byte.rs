//! `crc16_byte` against the `crc` crate's CRC-16/IBM-3740, the catalogue's definition.

use finestep_model::crc16_byte::{crc16, crc16_byte, INITIAL};
use proptest::prelude::*;

const REFERENCE: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);

#[test]
fn every_single_byte_step_equals_the_crc_crate() {
    // All 2^24 (register, byte) pairs would be slow; every byte from a spread of
    // registers, each register reached as the CRC of some prefix.
    for prefix_len in 0..64u8 {
        let prefix: Vec<u8> = (0..prefix_len).map(|i| i.wrapping_mul(151).wrapping_add(7)).collect();
        let before = REFERENCE.checksum(&prefix);
        for byte in 0..=255u8 {
            let mut whole = prefix.clone();
            whole.push(byte);
            assert_eq!(crc16_byte(before, byte), REFERENCE.checksum(&whole), "prefix {prefix_len}, byte {byte:#04x}");
        }
    }
}

#[test]
fn frames_equal_the_crc_crate_and_check_with_their_crc() {
    let mut runner = finestep_testkit::runner("crc16_frames_equal_the_crc_crate", 1000);
    runner
        .run(&proptest::collection::vec(any::<u8>(), 0..300), |frame| {
            let crc = crc16(&frame);
            prop_assert_eq!(crc, REFERENCE.checksum(&frame));
            let [high, low] = crc.to_be_bytes();
            prop_assert_eq!(crc16_byte(crc16_byte(crc, high), low), 0);
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
        let residue = bad.iter().chain(&good.to_be_bytes()).fold(INITIAL, |c, &b| crc16_byte(c, b));
        assert_ne!(residue, 0, "bit {bit} flipped went undetected");
    }
}
