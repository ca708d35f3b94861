//! [`DriveTiming`] (generated from the `[[timing]]` fields of `hdl/interface.toml`): one
//! axis's step and direction timing in clocks, how it is built from nanoseconds, masked
//! to a core's `TIMING_W` and written to the timing registers.

use crate::{DriveTiming, Field};

/// One field of [`DriveTiming`], as the interface description states it.
#[derive(Clone, Copy, Debug)]
pub struct TimingField {
    /// The Rust field name (`step_len`).
    pub name: &'static str,
    /// The letter of the specification (`L`).
    pub symbol: &'static str,
    /// The per-axis register holding it (`AXIS_TIMING_A`).
    pub register: &'static str,
    /// Its bits in that register.
    pub field: Field,
    /// The register's word address for an axis.
    pub addr: fn(usize) -> u8,
    /// Its value after reset.
    pub reset: u32,
}

/// A drive timing in nanoseconds that no core clock count can hold.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("{field}: {ns} ns is not within 0..={max_clocks} clocks")]
pub struct TimingError {
    /// The field (`step_len`).
    pub field: &'static str,
    /// The value asked for, ns.
    pub ns: f64,
    /// The most clocks allowed.
    pub max_clocks: u32,
}

impl DriveTiming {
    /// The timing every axis has after reset (the timing registers' reset values).
    pub const RESET: DriveTiming = {
        let mut values = [0; DriveTiming::COUNT];
        let mut index = 0;
        while index < DriveTiming::COUNT {
            values[index] = DriveTiming::FIELDS[index].reset;
            index += 1;
        }
        DriveTiming::from_array(values)
    };

    /// The timing in clocks of a `clock_hz` core for values in nanoseconds (in the order
    /// of [`DriveTiming::FIELDS`]): each rounded up to whole clocks, ignoring the
    /// floating-point dust of exact multiples, and at most `max_clocks`.
    pub fn from_ns(ns: [f64; DriveTiming::COUNT], clock_hz: f64, max_clocks: u32) -> Result<DriveTiming, TimingError> {
        let mut clocks = [0; DriveTiming::COUNT];
        for ((slot, ns), field) in clocks.iter_mut().zip(ns).zip(DriveTiming::FIELDS) {
            let exact = ns * 1e-9 * clock_hz * (1.0 - 1e-12);
            let rounded = exact.ceil();
            if !(ns.is_finite() && ns >= 0.0 && rounded <= f64::from(max_clocks)) {
                return Err(TimingError { field: field.name, ns, max_clocks });
            }
            *slot = rounded as u32;
        }
        Ok(DriveTiming::from_array(clocks))
    }

    /// The values as a core with `TIMING_W = timing_width` uses them: their low
    /// `timing_width` bits.
    pub fn masked(&self, timing_width: u32) -> DriveTiming {
        let mask = if timing_width >= u32::BITS { u32::MAX } else { (1 << timing_width) - 1 };
        DriveTiming::from_array(self.to_array().map(|value| value & mask))
    }

    /// The first field above `max_clocks`, as `(name, value)`.
    pub fn first_above(&self, max_clocks: u32) -> Option<(&'static str, u32)> {
        DriveTiming::FIELDS.iter().zip(self.to_array()).find(|(_, value)| *value > max_clocks).map(|(f, v)| (f.name, v))
    }

    /// The register writes that give `axis` this timing, as `(word address, word)` in
    /// the order of the fields' registers (fields sharing a register share its word).
    pub fn register_words(&self, axis: usize) -> Vec<(u8, u32)> {
        let mut words: Vec<(u8, u32)> = Vec::new();
        for (field, value) in DriveTiming::FIELDS.iter().zip(self.to_array()) {
            let addr = (field.addr)(axis);
            match words.iter_mut().find(|(a, _)| *a == addr) {
                Some((_, word)) => *word = field.field.set(*word, value & field.field.max()),
                None => words.push((addr, field.field.set(0, value & field.field.max()))),
            }
        }
        words
    }

    /// The timing of `axis` as its registers hold it; `read` gives a word address's value.
    pub fn from_registers(axis: usize, read: impl Fn(u8) -> u32) -> DriveTiming {
        DriveTiming::from_array(DriveTiming::FIELDS.map(|field| field.field.get(read((field.addr)(axis)))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regs::{axis_timing_a, axis_timing_b};

    #[test]
    fn nanoseconds_round_up_to_whole_clocks() {
        let t = DriveTiming::from_ns([2000.0, 2001.0, 5000.0, 0.0], 50e6, 4095).unwrap();
        assert_eq!(t, DriveTiming::new(100, 101, 250, 0));
        let e = DriveTiming::from_ns([2000.0, 2000.0, 1e6, 0.0], 50e6, 4095).unwrap_err();
        assert_eq!((e.field, e.max_clocks), ("dir_setup", 4095));
        assert!(DriveTiming::from_ns([-1.0, 0.0, 0.0, 0.0], 50e6, 4095).is_err());
        assert!(DriveTiming::from_ns([f64::NAN, 0.0, 0.0, 0.0], 50e6, 4095).is_err());
    }

    #[test]
    fn registers_round_trip() {
        let t = DriveTiming::new(3, 4, 5, 6);
        let words = t.register_words(2);
        assert_eq!(words, [(axis_timing_a::addr(2), 3 | 4 << 16), (axis_timing_b::addr(2), 5 | 6 << 16)]);
        let read = |addr: u8| words.iter().find(|(a, _)| *a == addr).map_or(0, |(_, w)| *w);
        assert_eq!(DriveTiming::from_registers(2, read), t);
        assert_eq!(DriveTiming::RESET, DriveTiming::new(1, 1, 1, 1));
    }

    #[test]
    fn masked_to_the_core_width() {
        let t = DriveTiming::new(16, 17, 15, 0x1_0003).masked(4);
        assert_eq!(t, DriveTiming::new(0, 1, 15, 3));
        assert_eq!(DriveTiming::new(7, 0, 0, 0).first_above(6), Some(("step_len", 7)));
        assert_eq!(t.first_above(15), None);
    }
}
