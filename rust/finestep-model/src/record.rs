//! The period record: every axis's increment for one period, and the flags.

use crate::{Increment, MAX_AXES};

/// Bits of [`PeriodRecord::flags`] (`rec_flags`).
pub mod flags {
    /// Bit 0: this is the last period of a block (`block_end` pulses after it).
    pub const BLOCK_END: u8 = 1 << 0;
}

/// One period record (`rec_inc`, `rec_flags`): axis `i` moves `inc[i]` steps in the
/// period. Entries at and above the core's `n_axes` are ignored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PeriodRecord {
    /// Signed steps per period, I16F16.
    pub inc: [Increment; MAX_AXES],
    /// Flags, see [`flags`]; bits 7:1 are reserved and ignored.
    pub flags: u8,
}

impl PeriodRecord {
    /// A record from raw I16F16 increments (`d = D * 65536`), the rest zero.
    pub fn from_raw(raw: &[i32], flags: u8) -> Self {
        let mut inc = [Increment::ZERO; MAX_AXES];
        for (slot, &d) in inc.iter_mut().zip(raw) {
            *slot = Increment::from_bits(d);
        }
        PeriodRecord { inc, flags }
    }

    /// Whether the core accepts this record for a period of `p_act` clocks when it has
    /// `n_axes` axes: for every axis `floor(|d| / 65536) < p_act` (`|D| < P`, at most one
    /// step per clock).
    pub fn acceptable(&self, n_axes: usize, p_act: u32) -> bool {
        self.inc[..n_axes.min(MAX_AXES)].iter().all(|inc| raw_acceptable(inc.to_bits(), p_act))
    }
}

/// `floor(|d| / 65536) < p_act` for a raw increment `d`.
#[inline]
pub(crate) fn raw_acceptable(d: i32, p_act: u32) -> bool {
    (i64::from(d).unsigned_abs() >> 16) < u64::from(p_act)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acceptance_is_whole_steps_below_the_period() {
        assert!(raw_acceptable(0, 1));
        assert!(raw_acceptable(65535, 1));
        assert!(raw_acceptable(-65535, 1));
        assert!(!raw_acceptable(65536, 1));
        assert!(!raw_acceptable(-65536, 1));
        assert!(raw_acceptable(2 * 65536 - 1, 2));
        assert!(!raw_acceptable(i32::MIN, 32768));
        assert!(raw_acceptable(i32::MIN, 32769));
        assert!(raw_acceptable(i32::MAX, 32768));
    }

    #[test]
    fn only_the_core_axes_are_looked_at() {
        let r = PeriodRecord::from_raw(&[0, 0, 1 << 20], 0);
        assert!(r.acceptable(2, 1));
        assert!(!r.acceptable(3, 1));
    }
}
