//! `keypad_scan`: the 4x4 matrix keypad scan with per-key debounce of seed 001's
//! gantry card.
//!
//! Specification: docs/spec/keypad_scan.md
//!
//! [`KeypadScan`] is the cycle model of `hdl/keypad_scan.v` (bit-exact: the RTL's
//! registers and widths). One column is driven at a time for a step of
//! `P = max(scan_div, 3) + 1` clocks; at the step's last clock the four keys of that
//! column are sampled from the synchronised rows (closed = row low) and the column moves
//! on, so a key is sampled every `F = 4 P` clocks. A key's debounced state takes a
//! sample's value after `deb_scans + 1` consecutive samples of it; an event
//! (`key_valid`, `key_code = 4 * row + column`) marks a rise after which that key is the
//! only one down. [`Keypad`] is the matrix the tests press (switches between rows and
//! columns, no diodes, columns driven low or released).

/// The block's widths (the RTL's parameters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KeypadParams {
    /// `PRE_W`: `scan_div` (at least 2).
    pub pre_w: u32,
    /// `DEB_W`: `deb_scans` and the per-key counters.
    pub deb_w: u32,
}

impl Default for KeypadParams {
    /// `PRE_W = 16`, `DEB_W = 4`: `hdl/keypad_scan.v`'s defaults.
    fn default() -> Self {
        KeypadParams { pre_w: 16, deb_w: 4 }
    }
}

/// The clocks of one scan step for `scan_div`: `max(scan_div, 3) + 1`.
pub fn step_clocks(scan_div: u32) -> u64 {
    u64::from(scan_div.max(3)) + 1
}

/// The clocks between two samples of one key: `F = 4 * step_clocks(scan_div)`.
pub fn frame_clocks(scan_div: u32) -> u64 {
    4 * step_clocks(scan_div)
}

/// The bounce bound: a key whose contact's edges all lie within this many clocks of each
/// other (first to last edge, at the row pin) changes its debounced state at most once:
/// `deb_scans * F`.
pub fn bounce_bound(scan_div: u32, deb_scans: u32) -> u64 {
    u64::from(deb_scans) * frame_clocks(scan_div)
}

/// The block's inputs in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KeypadInputs {
    /// A scan step every `max(scan_div, 3) + 1` clocks (masked to `PRE_W` bits).
    pub scan_div: u32,
    /// Consecutive equal samples minus one that change a key's state (`DEB_W` bits).
    pub deb_scans: u32,
    /// The row pins, bits 0..3 (pulled up: low = closed to the driven column).
    pub row_n: u8,
}

/// The block's outputs in one cycle (all registered).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KeypadOutputs {
    /// One-hot: the column driven low.
    pub col_drive: u8,
    /// One clock per debounced press (two-key lockout).
    pub key_valid: bool,
    /// `4 * row + column` of the last press event.
    pub key_code: u8,
    /// The debounced state, bit `4 * row + column`.
    pub key_down: u16,
}

/// The block's state (the RTL's registers).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KeypadScan {
    params: KeypadParams,
    sync1: u8,
    sync2: u8,
    div: u32,
    /// `scan_div` as it was one clock earlier: the step's end is decided on it.
    sd: u32,
    col: u8,
    col_drive: u8,
    down: u16,
    cnt: [u32; 16],
    valid: bool,
    code: u8,
}

impl KeypadScan {
    /// The reset state.
    pub fn new(params: KeypadParams) -> Self {
        assert!(params.pre_w >= 2 && params.pre_w <= 32 && params.deb_w >= 1 && params.deb_w <= 31);
        Self::reset_state(params)
    }

    /// The state every register takes at a clock edge with `rst` high.
    fn reset_state(params: KeypadParams) -> Self {
        KeypadScan {
            params,
            sync1: 0xf,
            sync2: 0xf,
            div: 0,
            sd: 0,
            col: 0,
            col_drive: 1,
            down: 0,
            cnt: [0; 16],
            valid: false,
            code: 0,
        }
    }

    /// The outputs in this cycle.
    pub fn outputs(&self) -> KeypadOutputs {
        KeypadOutputs { col_drive: self.col_drive, key_valid: self.valid, key_code: self.code, key_down: self.down }
    }

    /// The per-key counters (consecutive samples differing from the state).
    pub fn counters(&self) -> [u32; 16] {
        self.cnt
    }

    /// One clock edge with `rst` high.
    pub fn reset(&mut self) {
        *self = Self::reset_state(self.params);
    }

    /// One rising edge.
    pub fn step(&mut self, inputs: &KeypadInputs) {
        let pre_mask = mask(self.params.pre_w);
        let deb_mask = mask(self.params.deb_w);
        let scan_div = inputs.scan_div & pre_mask;
        let deb = inputs.deb_scans & deb_mask;
        let step_end = self.div >= self.sd && self.div >= 3;

        let mut down = self.down;
        let mut cnt = self.cnt;
        if step_end {
            for row in 0..4 {
                let k = row * 4 + usize::from(self.col);
                let sample = (self.sync2 >> row) & 1 == 0;
                let state = (self.down >> k) & 1 != 0;
                if sample != state {
                    if self.cnt[k] >= deb {
                        down = (down & !(1 << k)) | (u16::from(sample) << k);
                        cnt[k] = 0;
                    } else {
                        cnt[k] = (self.cnt[k] + 1) & deb_mask;
                    }
                } else {
                    cnt[k] = 0;
                }
            }
        }
        let rise = down & !self.down;
        let event = rise != 0 && down.count_ones() == 1;

        self.sync2 = self.sync1;
        self.sync1 = inputs.row_n & 0xf;
        self.sd = scan_div;
        self.valid = event;
        if event {
            self.code = down.trailing_zeros() as u8;
        }
        self.down = down;
        self.cnt = cnt;
        if step_end {
            self.div = 0;
            self.col = (self.col + 1) & 3;
            self.col_drive = ((self.col_drive << 1) | (self.col_drive >> 3)) & 0xf;
        } else {
            self.div = (self.div + 1) & pre_mask;
        }
    }
}

fn mask(w: u32) -> u32 {
    if w >= 32 {
        u32::MAX
    } else {
        (1u32 << w) - 1
    }
}

/// A 4x4 key matrix without diodes: a closed key joins its row and its column; a
/// driven column is low; the rows are pulled up. A row reads low when a path of closed
/// keys joins it to a driven column (through released columns and other rows: ghosting).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Keypad {
    /// Closed keys, bit `4 * row + column`.
    pub closed: u16,
}

impl Keypad {
    /// The row pins (bits 0..3, low = pulled down) with the columns of `col_drive` low.
    pub fn rows(&self, col_drive: u8) -> u8 {
        // Nodes 0..3 rows, 4..7 columns; flood from the driven columns.
        let mut low = (col_drive & 0xf) << 4;
        loop {
            let mut next = low;
            for k in 0..16 {
                if (self.closed >> k) & 1 != 0 {
                    let (r, c) = (k / 4, 4 + k % 4);
                    if (low >> r) & 1 != 0 || (low >> c) & 1 != 0 {
                        next |= (1 << r) | (1 << c);
                    }
                }
            }
            if next == low {
                break;
            }
            low = next;
        }
        !low & 0xf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_single_key_reads_low_only_on_its_column() {
        let pad = Keypad { closed: 1 << (2 * 4 + 1) };
        assert_eq!(pad.rows(0b0010), 0b1011);
        assert_eq!(pad.rows(0b0001), 0b1111);
        // Three keys of a rectangle make a ghost: (0,0), (0,1), (1,1) closed; driving
        // column 0 pulls row 1 low through (0,0)-(0,1)-(1,1).
        let pad = Keypad { closed: 1 | (1 << 1) | (1 << 5) };
        assert_eq!(pad.rows(0b0001), 0b1100);
    }

    #[test]
    fn the_scan_walks_the_columns_one_at_a_time() {
        let mut k = KeypadScan::new(KeypadParams::default());
        let mut seen = Vec::new();
        for _ in 0..40 {
            let o = k.outputs();
            assert_eq!(o.col_drive.count_ones(), 1);
            seen.push(o.col_drive);
            k.step(&KeypadInputs { scan_div: 4, deb_scans: 0, row_n: 0xf });
        }
        // Five clocks a column.
        assert_eq!(&seen[..11], &[1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 4]);
    }
}
