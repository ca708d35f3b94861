//! `panel`: the gantry card's panel on the chip's register bus (seed 001), the
//! [`KeypadScan`] on the matrix pins and the [`LedMenu`] on the 7-segment pins, with the
//! registers `PANEL_SCAN` (held by the register file), `PANEL_KEYS` and `PANEL_MENU`.
//!
//! Specification: docs/spec/finestep_top.md#panel-and-gantry
//!
//! The menu takes one of its four 16-bit registers a clock: a selector counts 0..3 every
//! clock; a `PANEL_MENU` write marks all four pending with its word, and each goes to the
//! menu in the clock the selector names it (a later write replacing the word and marking
//! all four again); the menu's registered read of the selector is copied into a shadow
//! of that register the clock after, and `PANEL_MENU` reads the shadows.

use crate::keypad_scan::{KeypadInputs, KeypadParams, KeypadScan};
use crate::led_menu::{LedInputs, LedMenu, LedParams};
use finestep_interface::regs;

/// The panel's digits in the chip (`panel_dig` is 8 pins).
pub const N_DIG: u32 = 8;

/// The menu's host registers, by `host_addr`.
const M_MODE: u8 = 0;
const M_PAGE: u8 = 1;
const M_VALUE: u8 = 2;

/// The panel's output pins in one cycle (all registers).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PanelPins {
    /// `panel_col`: one-hot, the column driven low.
    pub col: u8,
    /// `panel_seg`: segments a..g in bits 0..6, dp in bit 7, active high.
    pub seg: u8,
    /// `panel_dig`: the digit lit, active high.
    pub dig: u8,
}

/// What the panel sees in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PanelInputs {
    /// `PANEL_SCAN` as the register file holds it.
    pub scan: u32,
    /// The word of a `PANEL_MENU` write served in this cycle.
    pub menu_write: Option<u32>,
    /// `panel_row_n` (4 bits, pulled up).
    pub row_n: u8,
    /// The gantry's error saturated to 16 bits.
    pub sync_err: i16,
    /// `{watchdog fault, E-stop fault, gantry refused, gantry alarm}` (bits 3..0).
    pub alarm_in: u8,
}

/// The cycle model of `hdl/panel.v`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Panel {
    keypad: KeypadScan,
    menu: LedMenu,
    key_count: u8,
    sel: u8,
    sel_prev: u8,
    pend: u8,
    pend_word: u32,
    sh_mode: u8,
    sh_page: u8,
    sh_value: u16,
    sh_alarm: u8,
}

impl Default for Panel {
    fn default() -> Self {
        Panel {
            keypad: KeypadScan::new(KeypadParams { pre_w: 16, deb_w: 4 }),
            menu: LedMenu::new(LedParams { n_dig: N_DIG, pre_w: 16, seg_active_low: false, dig_active_low: false }),
            key_count: 0,
            sel: 0,
            sel_prev: 0,
            pend: 0,
            pend_word: 0,
            sh_mode: 0,
            sh_page: 0,
            sh_value: 0,
            sh_alarm: 0,
        }
    }
}

impl Panel {
    /// The pins in this cycle.
    pub fn pins(&self) -> PanelPins {
        let menu = self.menu.outputs();
        PanelPins { col: self.keypad.outputs().col_drive, seg: menu.seg, dig: menu.dig }
    }

    /// The menu's mode, to the gantry: true synchronised.
    pub fn sync_mode(&self) -> bool {
        self.menu.outputs().sync_mode
    }

    /// The keypad scan.
    pub fn keypad(&self) -> &KeypadScan {
        &self.keypad
    }

    /// The LED menu.
    pub fn menu(&self) -> &LedMenu {
        &self.menu
    }

    /// `PANEL_KEYS` in this cycle.
    pub fn keys_word(&self) -> u32 {
        use regs::panel_keys as k;
        let out = self.keypad.outputs();
        let word = k::KEY_DOWN.set(0, u32::from(out.key_down));
        let word = k::LAST_KEY.set(word, u32::from(out.key_code));
        k::KEY_COUNT.set(word, u32::from(self.key_count))
    }

    /// `PANEL_MENU` in this cycle (the shadows).
    pub fn menu_word(&self) -> u32 {
        use regs::panel_menu as m;
        let bit = |word: u8, i: u32| u32::from(word >> i & 1);
        let word = m::CARD_MODE.set(0, bit(self.sh_mode, 0));
        let word = m::OVR_EN.set(word, bit(self.sh_mode, 1));
        let word = m::OVR_MODE.set(word, bit(self.sh_mode, 2));
        let word = m::MODE.set(word, bit(self.sh_mode, 3));
        let word = m::PAGE.set(word, u32::from(self.sh_page & 3));
        let word = m::DISP_EN.set(word, bit(self.sh_page, 2));
        let word = m::DISP_HEX.set(word, bit(self.sh_page, 3));
        let word = m::ERR_HEX.set(word, bit(self.sh_page, 4));
        let word = m::ALARM.set(word, u32::from(self.sh_alarm));
        m::VALUE.set(word, u32::from(self.sh_value))
    }

    /// The pending word's field for the menu's register `sel`.
    fn menu_wdata(&self, sel: u8) -> u16 {
        use regs::panel_menu as m;
        let w = self.pend_word;
        match sel {
            M_MODE => (m::CARD_MODE.get(w) | m::OVR_EN.get(w) << 1 | m::OVR_MODE.get(w) << 2) as u16,
            M_PAGE => {
                (m::PAGE.get(w) | m::DISP_EN.get(w) << 2 | m::DISP_HEX.get(w) << 3 | m::ERR_HEX.get(w) << 4) as u16
            }
            M_VALUE => m::VALUE.get(w) as u16,
            _ => m::ALARM.get(w) as u16,
        }
    }

    /// One rising edge.
    pub fn step(&mut self, i: &PanelInputs) {
        use regs::panel_scan as s;
        let keys = self.keypad.outputs();
        let menu_out = self.menu.outputs();
        let sel = self.sel;
        let host_wr = self.pend >> sel & 1 != 0;
        let host_wdata = self.menu_wdata(sel);
        self.keypad.step(&KeypadInputs {
            scan_div: s::SCAN_DIV.get(i.scan),
            deb_scans: s::DEB_SCANS.get(i.scan),
            row_n: i.row_n & 0xf,
        });
        self.menu.step(&LedInputs {
            refresh_div: s::REFRESH_DIV.get(i.scan) << 4 | 0xf,
            key_valid: keys.key_valid,
            key_code: keys.key_code,
            sync_err: i.sync_err,
            alarm_in: i.alarm_in & 0xf,
            host_wr,
            host_addr: sel,
            host_wdata,
        });
        if keys.key_valid {
            self.key_count = self.key_count.wrapping_add(1);
        }
        let rdata = menu_out.host_rdata;
        match self.sel_prev {
            M_MODE => self.sh_mode = (rdata & 0xf) as u8,
            M_PAGE => self.sh_page = (rdata & 0x1f) as u8,
            M_VALUE => self.sh_value = rdata,
            _ => self.sh_alarm = (rdata & 0xf) as u8,
        }
        match i.menu_write {
            Some(word) => {
                self.pend = 0xf;
                self.pend_word = word;
            }
            None => self.pend &= !(1 << sel),
        }
        self.sel_prev = sel;
        self.sel = (sel + 1) & 3;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn idle(scan: u32) -> PanelInputs {
        PanelInputs { scan, menu_write: None, row_n: 0xf, sync_err: 0, alarm_in: 0 }
    }

    /// A PANEL_MENU write reaches the menu within 4 clocks at every phase of the
    /// selector, and the word (the effective mode too) reads back 7 clocks later; a
    /// second write within the 4 clocks wins whole.
    #[test]
    fn menu_writes_arrive_within_four_clocks_and_read_back() {
        use regs::panel_menu as m;
        let scan = regs::panel_scan::SCAN_DIV.set(0, 3);
        for phase in 0..4 {
            let mut panel = Panel::default();
            for _ in 0..phase {
                panel.step(&idle(scan));
            }
            let first = m::VALUE.set(m::OVR_EN.set(0, 1), 0x1234);
            let word = m::VALUE.set(m::DISP_EN.set(m::OVR_MODE.set(m::OVR_EN.set(0, 1), 1), 1), 0xBEEF);
            panel.step(&PanelInputs { menu_write: Some(first), ..idle(scan) });
            panel.step(&PanelInputs { menu_write: Some(word), ..idle(scan) });
            for _ in 0..4 {
                panel.step(&idle(scan));
            }
            assert!(panel.menu().effective_mode(), "phase {phase}: the override's mode");
            // The effective mode follows the override a clock later; the shadows take a
            // register at its next turn of the selector and the clock after.
            for _ in 0..7 {
                panel.step(&idle(scan));
            }
            let read = panel.menu_word();
            assert_eq!(m::VALUE.get(read), 0xBEEF, "phase {phase}");
            assert_eq!(m::MODE.get(read), 1, "phase {phase}");
            assert_eq!((m::OVR_EN.get(read), m::OVR_MODE.get(read), m::DISP_EN.get(read)), (1, 1, 1));
            assert!(panel.sync_mode());
        }
    }
}
