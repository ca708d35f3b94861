//! The period record: every axis's increment for one period, and the flags
//! (docs/interface.md, "Period record").

use crate::pbp::PbpLanes;
use crate::{flags, pbp_record, record_layout, MAX_AXES};

/// An axis increment: signed steps per period in two's complement Q16.16.
pub type Increment = fixed::types::I16F16;

// The description states the format; `Increment` must be it.
const _: () = assert!(
    record_layout::INC_INT_BITS == 16 && record_layout::INC_FRAC_BITS == 16,
    "hdl/interface.toml changed the increment format: change `Increment` with it"
);
const _: () = assert!(record_layout::FLAGS_WIDTH <= u8::BITS, "the flags no longer fit a byte");

/// Bytes of one increment on the wire.
const INC_BYTES: usize = (record_layout::INC_WIDTH / 8) as usize;

/// One period record (`rec_inc`, `rec_flags`): axis `i` moves `inc[i]` steps in the
/// period. Entries at and above the core's `n_axes` are ignored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct PeriodRecord {
    /// Signed steps per period, I16F16.
    pub inc: [Increment; MAX_AXES],
    /// Flags, see [`flags`]; the bits it does not name are reserved and ignored.
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

    /// Whether [`flags::BLOCK_END`] is set: the last period of a block.
    pub fn block_end(&self) -> bool {
        self.flags & flags::BLOCK_END != 0
    }

    /// Whether the core accepts this record for a period of `p_act` clocks when it has
    /// `n_axes` axes: for every axis `floor(|d| / 65536) < p_act` (`|D| < P`, at most one
    /// step per clock).
    pub fn acceptable(&self, n_axes: usize, p_act: u32) -> bool {
        self.inc[..n_axes.min(MAX_AXES)].iter().all(|inc| raw_acceptable(inc.to_bits(), p_act))
    }

    /// A record with the flag PBP (docs/spec/pbp_interp.md#in-the-core): `pbp` on axis
    /// pair `pair` (axes `2 * pair`, `2 * pair + 1`), one decision every `tick_div + 1`
    /// clocks, with `flags` besides PBP. Lanes (hdl/interface.toml `[pbp]`,
    /// [`crate::pbp_lanes`]): lane 0 `{ARC, CW, PAIR}` in its top byte over `x` (24 bits),
    /// lane 1 `y` (24 bits), lane 2 the arc's decisions (27 bits), lane 3 `tick_div` (24
    /// bits); values are cut to those widths (the caller keeps them in range:
    /// [`PbpLanes::fits`]).
    pub fn pbp(pbp: &PbpLanes, flags: u8) -> Self {
        use crate::pbp_lanes as at;
        let top = (if pbp.arc { pbp_record::ARC } else { 0 })
            | (if pbp.cw { pbp_record::CW } else { 0 })
            | ((pbp.pair & 0b11) << pbp_record::PAIR_0_BIT);
        let mask = |width: u32| u32::MAX >> (32 - width);
        let mut raw = [0u32; 4];
        raw[at::BITS_LANE] |= u32::from(top) << at::BITS_LSB;
        raw[at::X_LANE] |= (pbp.x as u32 & mask(at::X_WIDTH)) << at::X_LSB;
        raw[at::Y_LANE] |= (pbp.y as u32 & mask(at::Y_WIDTH)) << at::Y_LSB;
        raw[at::COUNT_LANE] |= (pbp.steps as u32 & mask(at::COUNT_WIDTH)) << at::COUNT_LSB;
        raw[at::TICK_DIV_LANE] |= (pbp.tick_div & mask(at::TICK_DIV_WIDTH)) << at::TICK_DIV_LSB;
        PeriodRecord::from_raw(&raw.map(|w| w as i32), flags | flags::PBP)
    }

    /// The point-by-point lanes of a record with the flag PBP (the inverse of
    /// [`PeriodRecord::pbp`] for lanes that fit), `None` without the flag.
    pub fn pbp_lanes(&self) -> Option<PbpLanes> {
        if self.flags & flags::PBP == 0 {
            return None;
        }
        use crate::pbp_lanes as at;
        let lane = |i: usize| self.inc[i].to_bits() as u32;
        // The field of `width` bits at `lsb` of lane `i`, unsigned, and signed.
        let field = |i: usize, lsb: u32, width: u32| (lane(i) >> lsb) & (u32::MAX >> (32 - width));
        let signed = |i: usize, lsb: u32, width: u32| ((field(i, lsb, width) << (32 - width)) as i32) >> (32 - width);
        let top = field(at::BITS_LANE, at::BITS_LSB, pbp_record::WIDTH) as u8;
        Some(PbpLanes {
            arc: top & pbp_record::ARC != 0,
            cw: top & pbp_record::CW != 0,
            pair: (top >> pbp_record::PAIR_0_BIT) & 0b11,
            x: signed(at::X_LANE, at::X_LSB, at::X_WIDTH),
            y: signed(at::Y_LANE, at::Y_LSB, at::Y_WIDTH),
            steps: u64::from(field(at::COUNT_LANE, at::COUNT_LSB, at::COUNT_WIDTH)),
            tick_div: field(at::TICK_DIV_LANE, at::TICK_DIV_LSB, at::TICK_DIV_WIDTH),
        })
    }

    /// Bytes of one record in an SPI FIFO frame for a core of `n_axes` axes.
    pub const fn wire_bytes(n_axes: usize) -> usize {
        INC_BYTES * n_axes + (record_layout::FLAGS_WIDTH as usize).div_ceil(8)
    }

    /// Appends the record's bytes in an SPI FIFO frame for a core of `n_axes` axes: each
    /// axis's increment big-endian, axis 0 first, then the flags.
    pub fn encode(&self, n_axes: usize, out: &mut Vec<u8>) {
        for inc in &self.inc[..n_axes.min(MAX_AXES)] {
            out.extend_from_slice(&inc.to_bits().to_be_bytes());
        }
        out.push(self.flags);
    }
}

/// `floor(|d| / 65536) < p_act` for a raw increment `d`: whether the core accepts the
/// increment in a period of `p_act` clocks.
#[inline]
pub fn raw_acceptable(d: i32, p_act: u32) -> bool {
    (i64::from(d).unsigned_abs() >> record_layout::INC_FRAC_BITS) < u64::from(p_act)
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

    #[test]
    fn pbp_lanes_read_back_what_pbp_wrote() {
        let lanes = [
            PbpLanes {
                arc: true,
                cw: true,
                pair: 1,
                x: -(1 << 23),
                y: (1 << 23) - 1,
                steps: (1 << 27) - 1,
                tick_div: (1 << 24) - 1,
            },
            PbpLanes { arc: false, cw: false, pair: 0, x: 5, y: -7, steps: 0, tick_div: 9 },
            PbpLanes { arc: true, cw: false, pair: 3, x: 0, y: -1, steps: 12, tick_div: 0 },
        ];
        for l in lanes {
            let record = PeriodRecord::pbp(&l, flags::BLOCK_END);
            assert_eq!(record.pbp_lanes(), Some(l));
            assert!(record.block_end());
        }
        assert_eq!(PeriodRecord::from_raw(&[1, 2, 3, 4], 0).pbp_lanes(), None);
    }

    #[test]
    fn wire_bytes_are_axis_major_big_endian_then_flags() {
        let record = PeriodRecord::from_raw(&[0x0102_0304, -1], flags::BLOCK_END);
        let mut bytes = Vec::new();
        record.encode(2, &mut bytes);
        assert_eq!(bytes, [1, 2, 3, 4, 0xFF, 0xFF, 0xFF, 0xFF, 0x01]);
        assert_eq!(bytes.len(), PeriodRecord::wire_bytes(2));
        assert!(record.block_end());
    }
}
