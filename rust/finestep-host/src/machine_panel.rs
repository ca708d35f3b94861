//! The gantry card's panel and the gantry pair on a [`Machine`] (seed 001;
//! docs/spec/finestep_top.md#panel-and-gantry, docs/spec/keypad_scan.md,
//! docs/spec/led_menu.md, docs/spec/gantry_sync.md): the keys pressed at the card, the
//! LED menu's mode, page, display and alarms, the forward or synchronised mode chosen by
//! the host, and the gantry's configuration and status.

use crate::regs::{gantry_control, gantry_limits, gantry_status, panel_keys, panel_menu, panel_scan};
use crate::{Bus, BusError, Machine};

/// The keypad's scan and the display's refresh (`PANEL_SCAN`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PanelScan {
    /// A column is driven `max(scan_div, 3) + 1` clocks; every key is sampled every 4 of
    /// those steps.
    pub scan_div: u16,
    /// A key changes state after `deb_scans + 1` equal samples in a row (0..=15).
    pub deb_scans: u8,
    /// Each digit is lit `refresh_div * 16 + 16` clocks (0..=4095).
    pub refresh_div: u16,
}

impl Default for PanelScan {
    /// The reset values (1 ms steps, 5 + 1 samples, 1 ms a digit at 50 MHz).
    fn default() -> Self {
        PanelScan {
            scan_div: panel_scan::SCAN_DIV_RESET as u16,
            deb_scans: panel_scan::DEB_SCANS_RESET as u8,
            refresh_div: panel_scan::REFRESH_DIV_RESET as u16,
        }
    }
}

/// The keypad as the chip reports it (`PANEL_KEYS`). Key `4 * row + column` on the
/// legend `1 2 3 A / 4 5 6 B / 7 8 9 C / * 0 # D`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PanelKeys {
    /// The debounced keys down, bit per key.
    pub down: u16,
    /// The key of the last press event.
    pub last: u8,
    /// Press events since reset, wrapping at 256: new presses are
    /// `count.wrapping_sub(earlier count)`.
    pub count: u8,
}

/// What the display shows instead of the menu's pages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PanelDisplay {
    /// The value (shown as signed decimal, or as 4 hex digits).
    pub value: u16,
    /// Hex instead of signed decimal.
    pub hex: bool,
}

/// The LED menu as the chip reports it (`PANEL_MENU`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PanelMenu {
    /// The mode chosen at the card (true synchronised).
    pub card_mode: bool,
    /// The host's override of the mode, if any.
    pub host_mode: Option<bool>,
    /// The effective mode driving the gantry.
    pub mode: bool,
    /// The page shown: 0 MODE, 1 ERROR, 2 ALARM.
    pub page: u8,
    /// The display's override, if on.
    pub display: Option<PanelDisplay>,
    /// The ERROR page in hex.
    pub err_hex: bool,
    /// Latched alarms: bit 3 watchdog, 2 E-stop, 1 gantry refused, 0 gantry alarm.
    pub alarms: u8,
}

/// The gantry pair's configuration (`GANTRY_CONTROL` but ENABLE and SYNC, `GANTRY_LIMITS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GantrySetup {
    /// The master axis.
    pub master: u8,
    /// The slave axis (takes the master's steps).
    pub slave: u8,
    /// The encoder channel on the master's side.
    pub enc_master: u8,
    /// The encoder channel on the slave's side.
    pub enc_slave: u8,
    /// A correction is decided at most every `tick * 16 + 15` clocks.
    pub tick: u16,
    /// No correction while `|error| <= deadband` counts.
    pub deadband: u16,
    /// The alarm when `|error| > limit` counts.
    pub limit: u16,
}

impl Default for GantrySetup {
    /// The reset values of the registers.
    fn default() -> Self {
        GantrySetup {
            master: gantry_control::MASTER_RESET as u8,
            slave: gantry_control::SLAVE_RESET as u8,
            enc_master: gantry_control::ENC_MASTER_RESET as u8,
            enc_slave: gantry_control::ENC_SLAVE_RESET as u8,
            tick: gantry_control::TICK_RESET as u16,
            deadband: gantry_limits::DEADBAND_RESET as u16,
            limit: gantry_limits::LIMIT_RESET as u16,
        }
    }
}

/// The gantry as the chip reports it (`GANTRY_STATUS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GantryStatus {
    /// Master minus slave counts since engagement, saturated to 16 bits.
    pub error: i16,
    /// Net corrections applied, the low 12 bits of a wrapping count.
    pub corrections: u16,
    /// The slave follows the master.
    pub engaged: bool,
    /// Sticky: the error passed the limit (corrections stopped).
    pub alarm: bool,
    /// Sticky: an enable with an invalid pair.
    pub refused: bool,
    /// The gantry runs synchronised (else forward).
    pub sync: bool,
}

impl PanelMenu {
    fn from_word(word: u32) -> PanelMenu {
        let flag = |field: finestep_interface::Field| field.get(word) != 0;
        PanelMenu {
            card_mode: flag(panel_menu::CARD_MODE),
            host_mode: flag(panel_menu::OVR_EN).then(|| flag(panel_menu::OVR_MODE)),
            mode: flag(panel_menu::MODE),
            page: panel_menu::PAGE.get(word) as u8,
            display: flag(panel_menu::DISP_EN)
                .then(|| PanelDisplay { value: panel_menu::VALUE.get(word) as u16, hex: flag(panel_menu::DISP_HEX) }),
            err_hex: flag(panel_menu::ERR_HEX),
            alarms: panel_menu::ALARM.get(word) as u8,
        }
    }
}

/// `PANEL_MENU`'s write of `menu`'s settings: the page left as it is (a write of 3), no
/// alarm cleared but `clear`.
fn menu_word(menu: &PanelMenu, clear: u8) -> u32 {
    let word = panel_menu::CARD_MODE.set(0, u32::from(menu.card_mode));
    let word = panel_menu::OVR_EN.set(word, u32::from(menu.host_mode.is_some()));
    let word = panel_menu::OVR_MODE.set(word, u32::from(menu.host_mode.unwrap_or(false)));
    let word = panel_menu::PAGE.set(word, panel_menu::PAGE.max());
    let display = menu.display.unwrap_or(PanelDisplay { value: 0, hex: false });
    let word = panel_menu::DISP_EN.set(word, u32::from(menu.display.is_some()));
    let word = panel_menu::DISP_HEX.set(word, u32::from(display.hex));
    let word = panel_menu::ERR_HEX.set(word, u32::from(menu.err_hex));
    let word = panel_menu::ALARM.set(word, u32::from(clear) & panel_menu::ALARM.max());
    panel_menu::VALUE.set(word, u32::from(display.value))
}

impl<B: Bus> Machine<B> {
    fn need_built(&self, built: bool, what: &'static str) -> Result<(), BusError> {
        if built {
            Ok(())
        } else {
            Err(BusError::NotBuilt(what))
        }
    }

    /// Sets the keypad's scan and debounce and the display's refresh.
    pub fn configure_panel(&mut self, scan: &PanelScan) -> Result<(), BusError> {
        self.need_built(self.caps.has_panel, "panel")?;
        for (what, value, field) in [
            ("panel deb_scans", u32::from(scan.deb_scans), panel_scan::DEB_SCANS),
            ("panel refresh_div", u32::from(scan.refresh_div), panel_scan::REFRESH_DIV),
        ] {
            if value > field.max() {
                return Err(BusError::SettingRange { what, value, max: field.max() });
            }
        }
        let word = panel_scan::SCAN_DIV.set(0, u32::from(scan.scan_div));
        let word = panel_scan::DEB_SCANS.set(word, u32::from(scan.deb_scans));
        self.bus.write(panel_scan::ADDR, panel_scan::REFRESH_DIV.set(word, u32::from(scan.refresh_div)))
    }

    /// The keys down, the last press and the count of presses.
    pub fn panel_keys(&mut self) -> Result<PanelKeys, BusError> {
        self.need_built(self.caps.has_panel, "panel")?;
        let word = self.bus.read_one(panel_keys::ADDR)?;
        Ok(PanelKeys {
            down: panel_keys::KEY_DOWN.get(word) as u16,
            last: panel_keys::LAST_KEY.get(word) as u8,
            count: panel_keys::KEY_COUNT.get(word) as u8,
        })
    }

    /// The LED menu's mode, page, display override and latched alarms (as they were at
    /// most 5 clocks before the read).
    pub fn panel_menu(&mut self) -> Result<PanelMenu, BusError> {
        self.need_built(self.caps.has_panel, "panel")?;
        Ok(PanelMenu::from_word(self.bus.read_one(panel_menu::ADDR)?))
    }

    /// Read-modify-write of the menu's settings (the page left as the card has it).
    fn update_menu(&mut self, change: impl FnOnce(&mut PanelMenu), clear: u8) -> Result<(), BusError> {
        let mut menu = self.panel_menu()?;
        change(&mut menu);
        self.bus.write(panel_menu::ADDR, menu_word(&menu, clear))
    }

    /// The display shows `display` instead of the menu's pages (the keys do nothing
    /// then), or the pages again (`None`).
    pub fn set_panel_display(&mut self, display: Option<PanelDisplay>) -> Result<(), BusError> {
        self.update_menu(|menu| menu.display = display, 0)
    }

    /// Clears the latched alarms of `mask` (bit 3 watchdog, 2 E-stop, 1 gantry refused,
    /// 0 gantry alarm) whose inputs are low.
    pub fn clear_panel_alarms(&mut self, mask: u8) -> Result<(), BusError> {
        self.update_menu(|_| {}, mask)
    }

    /// The gantry's mode from the host: `Some(true)` synchronised, `Some(false)` forward,
    /// `None` the card's choice (with a panel; without one, forward). With the panel
    /// this is the menu's override (its MODE page shows it); without, `GANTRY_CONTROL.SYNC`.
    pub fn set_gantry_mode(&mut self, mode: Option<bool>) -> Result<(), BusError> {
        if self.caps.has_panel {
            return self.update_menu(|menu| menu.host_mode = mode, 0);
        }
        self.need_built(self.caps.has_gantry, "gantry")?;
        let word = self.bus.read_one(gantry_control::ADDR)?;
        self.bus.write(gantry_control::ADDR, gantry_control::SYNC.set(word, u32::from(mode.unwrap_or(false))))
    }

    /// Configures the gantry pair (disengaged: ENABLE written 0; engage with
    /// [`Machine::enable_gantry`] with both axes at rest).
    pub fn configure_gantry(&mut self, setup: &GantrySetup) -> Result<(), BusError> {
        self.need_built(self.caps.has_gantry, "gantry")?;
        for (what, value, field) in [
            ("gantry master", setup.master, gantry_control::MASTER),
            ("gantry slave", setup.slave, gantry_control::SLAVE),
            ("gantry enc_master", setup.enc_master, gantry_control::ENC_MASTER),
            ("gantry enc_slave", setup.enc_slave, gantry_control::ENC_SLAVE),
        ] {
            if u32::from(value) > field.max() {
                return Err(BusError::SettingRange { what, value: u32::from(value), max: field.max() });
            }
        }
        let limits = gantry_limits::DEADBAND.set(0, u32::from(setup.deadband));
        self.bus.write(gantry_limits::ADDR, gantry_limits::LIMIT.set(limits, u32::from(setup.limit)))?;
        let sync = gantry_control::SYNC.get(self.bus.read_one(gantry_control::ADDR)?);
        let word = gantry_control::SYNC.set(0, sync);
        let word = gantry_control::MASTER.set(word, u32::from(setup.master));
        let word = gantry_control::SLAVE.set(word, u32::from(setup.slave));
        let word = gantry_control::ENC_MASTER.set(word, u32::from(setup.enc_master));
        let word = gantry_control::ENC_SLAVE.set(word, u32::from(setup.enc_slave));
        self.bus.write(gantry_control::ADDR, gantry_control::TICK.set(word, u32::from(setup.tick)))
    }

    /// Engages (at the next clock with both axes at rest) or disengages the gantry.
    pub fn enable_gantry(&mut self, on: bool) -> Result<(), BusError> {
        self.need_built(self.caps.has_gantry, "gantry")?;
        let word = self.bus.read_one(gantry_control::ADDR)?;
        self.bus.write(gantry_control::ADDR, gantry_control::ENABLE.set(word, u32::from(on)))
    }

    /// The gantry's error, corrections, state and mode.
    pub fn gantry_status(&mut self) -> Result<GantryStatus, BusError> {
        self.need_built(self.caps.has_gantry, "gantry")?;
        let word = self.bus.read_one(gantry_status::ADDR)?;
        Ok(GantryStatus {
            error: gantry_status::ERROR.get(word) as u16 as i16,
            corrections: gantry_status::CORRECTIONS.get(word) as u16,
            engaged: gantry_status::ENGAGED.get(word) != 0,
            alarm: gantry_status::ALARM.get(word) != 0,
            refused: gantry_status::REFUSED.get(word) != 0,
            sync: gantry_status::SYNC.get(word) != 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn menu_words_round_trip_and_leave_the_page() {
        let menu = PanelMenu {
            card_mode: true,
            host_mode: Some(false),
            mode: false,
            page: 1,
            display: Some(PanelDisplay { value: 0xBEEF, hex: true }),
            err_hex: true,
            alarms: 0,
        };
        let word = menu_word(&menu, 0b0101);
        assert_eq!(panel_menu::PAGE.get(word), 3, "a write of page 3 leaves the page");
        assert_eq!(panel_menu::ALARM.get(word), 0b0101);
        let back = PanelMenu::from_word(panel_menu::PAGE.set(panel_menu::ALARM.set(word, 0), 1));
        assert_eq!(back, PanelMenu { alarms: 0, ..menu });
        let none = menu_word(&PanelMenu::default(), 0);
        assert_eq!(none, panel_menu::PAGE.set(0, 3));
    }
}
