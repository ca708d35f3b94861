//! `led_menu`: the gantry card's multiplexed 7-segment display and its menu (seed 001),
//! working without the host.
//!
//! Specification: docs/spec/led_menu.md
//!
//! [`LedMenu`] is the cycle model of `hdl/led_menu.v` (bit-exact: the RTL's registers).
//! Pages: MODE (forward or synchronised, `'#'` toggles), ERROR (the signed sync error in
//! decimal or hex, `'#'` toggles), ALARM (the latched flags, `'#'` acknowledges); `'A'`
//! next page, `'B'` previous. A new alarm flag shows the alarm page. The host has four
//! registers (mode and its override, page and the display override, the override's
//! value, the alarm flags). The text is 8 characters of [`Glyph`] codes; the display
//! shows character `i` on digit `i` (0 the rightmost), one digit at a time.

/// A key code (`4 * row + column`) of a keypad labelled `1 2 3 A / 4 5 6 B / 7 8 9 C /
/// * 0 # D`: `'A'`, next page.
pub const KEY_NEXT: u8 = 3;
/// `'B'`: previous page.
pub const KEY_PREV: u8 = 7;
/// `'#'`: the page's action.
pub const KEY_ACT: u8 = 14;

/// The pages.
pub const PAGE_MODE: u8 = 0;
/// The sync error.
pub const PAGE_ERR: u8 = 1;
/// The alarm flags.
pub const PAGE_ALARM: u8 = 2;

/// Glyph codes: 0..=15 the hexadecimal digits, then these.
pub mod glyph {
    /// All segments off.
    pub const BLANK: u8 = 16;
    /// Segment g.
    pub const MINUS: u8 = 17;
    /// `r`.
    pub const R: u8 = 18;
    /// `n`.
    pub const N: u8 = 19;
    /// `y`.
    pub const Y: u8 = 20;
    /// `c`.
    pub const C: u8 = 21;
    /// `h`.
    pub const H: u8 = 22;
    /// `L`.
    pub const L: u8 = 23;
}

/// Segments a..g (bits 0..6) of a glyph code (the RTL's table; codes 24..31 blank).
pub fn segments(glyph: u8) -> u8 {
    const HEX: [u8; 16] =
        [0x3f, 0x06, 0x5b, 0x4f, 0x66, 0x6d, 0x7d, 0x07, 0x7f, 0x6f, 0x77, 0x7c, 0x39, 0x5e, 0x79, 0x71];
    match glyph {
        0..=15 => HEX[usize::from(glyph)],
        glyph::MINUS => 0x40,
        glyph::R => 0x50,
        glyph::N => 0x54,
        glyph::Y => 0x6e,
        glyph::C => 0x58,
        glyph::H => 0x74,
        glyph::L => 0x38,
        _ => 0,
    }
}

/// The block's parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LedParams {
    /// `N_DIG`: digits, 1..=8.
    pub n_dig: u32,
    /// `PRE_W`: `refresh_div`.
    pub pre_w: u32,
    /// `SEG_ACTIVE_LOW`.
    pub seg_active_low: bool,
    /// `DIG_ACTIVE_LOW`.
    pub dig_active_low: bool,
}

impl Default for LedParams {
    /// `hdl/led_menu.v`'s defaults: 8 digits, `PRE_W = 16`, active high.
    fn default() -> Self {
        LedParams { n_dig: 8, pre_w: 16, seg_active_low: false, dig_active_low: false }
    }
}

/// The block's inputs in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LedInputs {
    /// Each digit shown `refresh_div + 1` clocks (`PRE_W` bits).
    pub refresh_div: u32,
    /// `keypad_scan`'s event.
    pub key_valid: bool,
    /// Its key code (4 bits).
    pub key_code: u8,
    /// The gantry's sync error (signed 16 bits).
    pub sync_err: i16,
    /// Alarm flags (levels, 4 bits).
    pub alarm_in: u8,
    /// A host register write.
    pub host_wr: bool,
    /// Its address (2 bits), also the register read.
    pub host_addr: u8,
    /// Its data.
    pub host_wdata: u16,
}

/// The block's outputs in one cycle (all registered).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LedOutputs {
    /// The register at last clock's `host_addr`.
    pub host_rdata: u16,
    /// Segments a..g, dp (bits 0..7), at their active level.
    pub seg: u8,
    /// Digit enables (`N_DIG` bits), at their active level.
    pub dig: u8,
    /// 1 synchronised, 0 forward.
    pub sync_mode: bool,
    /// An alarm flag is latched.
    pub alarm_pending: bool,
    /// The page.
    pub page: u8,
}

/// The block's state (the RTL's registers).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LedMenu {
    params: LedParams,
    page: u8,
    card_mode: bool,
    ovr_en: bool,
    ovr_mode: bool,
    disp_en: bool,
    disp_hex: bool,
    err_hex: bool,
    disp_val: u16,
    latched: u8,
    sync_mode: bool,
    pending: bool,
    rdata: u16,
    ref_cnt: u32,
    dig_idx: u8,
    seg: u8,
    dig: u8,
    conv_step: u8,
    conv_bin: u16,
    conv_bcd: u32,
    conv_neg: bool,
    bcd: u32,
    neg: bool,
}

/// The BCD word's double-dabble step: 3 added to each digit of 5 or more (20 bits).
fn bcd_adjust(bcd: u32) -> u32 {
    let mut out = bcd;
    for n in 0..5 {
        let d = (bcd >> (4 * n)) & 0xf;
        if d >= 5 {
            out = (out & !(0xf << (4 * n))) | (((d + 3) & 0xf) << (4 * n));
        }
    }
    out
}

impl LedMenu {
    /// The reset state.
    pub fn new(params: LedParams) -> Self {
        assert!((1..=8).contains(&params.n_dig) && (1..=32).contains(&params.pre_w));
        Self::reset_state(params)
    }

    /// The state every register takes at a clock edge with `rst` high.
    fn reset_state(params: LedParams) -> Self {
        LedMenu {
            params,
            page: PAGE_MODE,
            card_mode: false,
            ovr_en: false,
            ovr_mode: false,
            disp_en: false,
            disp_hex: false,
            err_hex: false,
            disp_val: 0,
            latched: 0,
            sync_mode: false,
            pending: false,
            rdata: 0,
            ref_cnt: 0,
            dig_idx: 0,
            seg: if params.seg_active_low { 0xff } else { 0 },
            dig: if params.dig_active_low { Self::digits(params) } else { 0 },
            conv_step: 0,
            conv_bin: 0,
            conv_bcd: 0,
            conv_neg: false,
            bcd: 0,
            neg: false,
        }
    }

    /// One bit per digit of the build.
    fn digits(params: LedParams) -> u8 {
        ((1u16 << params.n_dig) - 1) as u8
    }

    fn dig_mask(&self) -> u8 {
        Self::digits(self.params)
    }

    /// The outputs in this cycle.
    pub fn outputs(&self) -> LedOutputs {
        LedOutputs {
            host_rdata: self.rdata,
            seg: self.seg,
            dig: self.dig,
            sync_mode: self.sync_mode,
            alarm_pending: self.pending,
            page: self.page,
        }
    }

    /// One clock edge with `rst` high.
    pub fn reset(&mut self) {
        *self = Self::reset_state(self.params);
    }

    /// The effective gantry mode (the override's, else the card's): true synchronised.
    pub fn effective_mode(&self) -> bool {
        if self.ovr_en {
            self.ovr_mode
        } else {
            self.card_mode
        }
    }

    fn value(&self, sync_err: i16) -> u16 {
        if self.disp_en {
            self.disp_val
        } else {
            sync_err as u16
        }
    }

    /// The text shown now, characters 0 (rightmost) to 7, as glyph codes.
    pub fn text(&self, sync_err: i16) -> [u8; 8] {
        use glyph::*;
        let value = self.value(sync_err);
        let hex = if self.disp_en { self.disp_hex } else { self.err_hex };
        let mut num = [BLANK; 7];
        if hex {
            for (i, c) in num.iter_mut().take(4).enumerate() {
                *c = ((value >> (4 * i)) & 0xf) as u8;
            }
            num[4] = H;
        } else {
            let d = |i: u32| ((self.bcd >> (4 * i)) & 0xf) as u8;
            // zero_from[i]: digits i..4 are all zero.
            let zero_from = |i: u32| (i..5).all(|j| d(j) == 0);
            num[0] = d(0);
            for i in 1..5u32 {
                num[i as usize] = if !zero_from(i) {
                    d(i)
                } else if self.neg && (i == 1 || !zero_from(i - 1)) {
                    MINUS
                } else {
                    BLANK
                };
            }
            num[5] = if self.neg && !zero_from(4) { MINUS } else { BLANK };
        }
        let mut text = [BLANK; 8];
        if self.disp_en {
            text[..7].copy_from_slice(&num);
            return text;
        }
        match self.page {
            PAGE_MODE => {
                let word: &[u8] = if self.effective_mode() { &[C, N, Y, 5] } else { &[13, R, 15] };
                text[..word.len()].copy_from_slice(word);
                if self.ovr_en {
                    text[7] = H;
                }
            }
            PAGE_ERR => {
                text[..7].copy_from_slice(&num);
                text[7] = 14;
            }
            PAGE_ALARM => {
                for (i, c) in text.iter_mut().take(4).enumerate() {
                    *c = (self.latched >> i) & 1;
                }
                text[7] = 10;
                text[6] = L;
            }
            _ => {}
        }
        text
    }

    /// One rising edge.
    pub fn step(&mut self, i: &LedInputs) {
        let pre_mask = if self.params.pre_w >= 32 { u32::MAX } else { (1u32 << self.params.pre_w) - 1 };
        let refresh_div = i.refresh_div & pre_mask;
        let key_code = i.key_code & 0xf;
        let alarm_in = i.alarm_in & 0xf;
        let addr = i.host_addr & 3;
        let key = |code: u8| i.key_valid && key_code == code;
        let (key_next, key_prev, key_act) = (key(KEY_NEXT), key(KEY_PREV), key(KEY_ACT));
        let (wr_mode, wr_page, wr_val, wr_alarm) =
            (i.host_wr && addr == 0, i.host_wr && addr == 1, i.host_wr && addr == 2, i.host_wr && addr == 3);
        let ack = (if key_act && self.page == PAGE_ALARM && !self.disp_en { 0xf } else { 0 })
            | (if wr_alarm { (i.host_wdata & 0xf) as u8 } else { 0 });
        let new_alarm = alarm_in & !self.latched != 0;
        let eff_mode = self.effective_mode();

        // The combinational parts from the current state.
        let value = self.value(i.sync_err);
        let value_abs = if value & 0x8000 != 0 { (!value).wrapping_add(1) } else { value };
        let text = self.text(i.sync_err);
        let glyph = text[usize::from(self.dig_idx)];
        let dp = self.pending && self.dig_idx == 0;
        let seg_on = segments(glyph) | (u8::from(dp) << 7);
        let dig_on = (1u8 << self.dig_idx) & self.dig_mask();
        let rdata = match addr {
            0 => {
                u16::from(self.card_mode)
                    | (u16::from(self.ovr_en) << 1)
                    | (u16::from(self.ovr_mode) << 2)
                    | (u16::from(eff_mode) << 3)
            }
            1 => {
                u16::from(self.page)
                    | (u16::from(self.disp_en) << 2)
                    | (u16::from(self.disp_hex) << 3)
                    | (u16::from(self.err_hex) << 4)
            }
            2 => self.disp_val,
            _ => u16::from(self.latched) | (u16::from(alarm_in) << 4),
        };

        let old = self.clone();
        if !old.disp_en {
            if key_next {
                self.page = if old.page == PAGE_ALARM { PAGE_MODE } else { (old.page + 1) & 3 };
            }
            if key_prev {
                self.page = if old.page == PAGE_MODE { PAGE_ALARM } else { old.page.wrapping_sub(1) & 3 };
            }
            if key_act && old.page == PAGE_MODE && !old.ovr_en {
                self.card_mode = !old.card_mode;
            }
            if key_act && old.page == PAGE_ERR {
                self.err_hex = !old.err_hex;
            }
        }
        let w = i.host_wdata;
        if wr_mode {
            self.card_mode = w & 1 != 0;
            self.ovr_en = w & 2 != 0;
            self.ovr_mode = w & 4 != 0;
        }
        if wr_page {
            if w & 3 != 3 {
                self.page = (w & 3) as u8;
            }
            self.disp_en = w & 4 != 0;
            self.disp_hex = w & 8 != 0;
            self.err_hex = w & 16 != 0;
        }
        if wr_val {
            self.disp_val = w;
        }
        self.latched = (old.latched & !ack) | alarm_in;
        if new_alarm {
            self.page = PAGE_ALARM;
        }
        self.sync_mode = eff_mode;
        self.pending = old.latched != 0;
        self.rdata = rdata;

        if old.conv_step == 0 {
            self.conv_bin = value_abs;
            self.conv_neg = value & 0x8000 != 0;
            self.conv_bcd = 0;
            self.conv_step = 1;
        } else {
            let shifted = ((bcd_adjust(old.conv_bcd) << 1) | u32::from(old.conv_bin >> 15)) & 0xf_ffff;
            self.conv_bin = old.conv_bin << 1;
            self.conv_bcd = shifted;
            if old.conv_step == 16 {
                self.conv_step = 0;
                self.bcd = shifted;
                self.neg = old.conv_neg;
            } else {
                self.conv_step = old.conv_step + 1;
            }
        }

        self.seg = if self.params.seg_active_low { !seg_on } else { seg_on };
        self.dig = if self.params.dig_active_low { !dig_on & self.dig_mask() } else { dig_on };
        if old.ref_cnt >= refresh_div {
            self.ref_cnt = 0;
            self.dig_idx = if u32::from(old.dig_idx) >= self.params.n_dig - 1 { 0 } else { old.dig_idx + 1 };
        } else {
            self.ref_cnt = (old.ref_cnt + 1) & pre_mask;
        }
    }
}
