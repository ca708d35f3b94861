//! The gantry card's chip at its pins (seed 001): `finestep_top` with the panel and the
//! gantry pair, RTL and model in lockstep on every pin every clock
//! ([`PanelChipLockstep`]), driven through the host driver over SPI, with a diode-less
//! keypad matrix on the column and row pins (keys bounced at scheduled cycles) and a
//! gantry plant (two motors with encoders) on the step and encoder pins.
//!
//! Every expectation is stated here from the specs (docs/spec/keypad_scan.md,
//! docs/spec/led_menu.md, docs/spec/gantry_sync.md, docs/spec/finestep_top.md), not read
//! from the model: one press event per bounced press, the digits read back from the
//! segment and digit pins through the glyph table written as segment letters, the mode
//! chosen by '#' at the card and overridden by the host, corrections at the slave's step
//! pin closing the error, and the gantry's alarm latched and shown on the panel.

use finestep_cosim::{acknowledge_power_up, read_display, GantryPlant, PanelChipLockstep, PanelMachine as M};
use finestep_host::regs::{control, panel_menu, status};
use finestep_host::{AxisSetup, Bus, GantrySetup, Machine, PanelDisplay, PanelScan, PinHost, PinTiming, SpiBus};
use finestep_model::top::top_pins;
use finestep_model::{DriveTiming, PeriodRecord};

const KEY_NEXT: u8 = 3; // 'A'
const KEY_ACT: u8 = 14; // '#'
const KEY_5: u8 = 5;
const KEY_9: u8 = 10;

/// A scan step of 4 clocks (every key sampled every F = 16 clocks) and a change after 3
/// equal samples: bounce bound B = 2 * 16 = 32 clocks; a digit lit 16 clocks.
const SCAN: PanelScan = PanelScan { scan_div: 3, deb_scans: 2, refresh_div: 0 };
const F: u64 = 16;
const B: u64 = 2 * F;

fn ok<T, E: std::fmt::Display>(result: Result<T, E>) -> T {
    result.unwrap_or_else(|e| panic!("{e}"))
}

/// The display read from the LED pins: its text and digit 0's point.
fn display(m: &mut M) -> (String, bool) {
    let reading = ok(read_display(m, &SCAN));
    (reading.text, reading.point)
}

fn machine(name: &str) -> M {
    let mut host = PinHost::new(PanelChipLockstep::new(name), PinTiming::default());
    ok(host.reset(4));
    ok(host.idle(4));
    let mut m = ok(Machine::connect(SpiBus::new(host, 4)));
    assert!(m.caps().has_panel && m.caps().has_gantry, "the gantry card's chip builds both");
    assert_eq!(m.caps().step_slots, 1, "the gantry needs a DDA and a shaper per axis");
    ok(m.enable_axes(0b1111));
    ok(m.clear_faults_and_errors());
    assert_eq!(status::HALT.get(ok(m.status())), 0);
    ok(m.configure_panel(&SCAN));
    // The E-stop fault of power-up (cleared above) is latched in the menu, which shows
    // its ALARM page: the host acknowledges it and shows the MODE page.
    let menu = ok(acknowledge_power_up(&mut m));
    assert_eq!((menu.alarms, menu.page), (0b0100, 2), "the power-up E-stop fault on the panel");
    let menu = ok(m.panel_menu());
    assert_eq!((menu.alarms, menu.page), (0, 0));
    m
}

fn chip(m: &mut M) -> &mut PanelChipLockstep {
    m.bus().link_mut().target_mut()
}

/// Presses `key` from `at`: a closing burst of bounce (edges within `B` clocks), held
/// `hold` clocks, an opening burst; returns the cycle after the last edge.
fn press(m: &mut M, key: u8, at: u64, hold: u64, seed: u64) -> u64 {
    let bit = 1u16 << key;
    let c = chip(m);
    // Closing: closed, open, closed, ... at offsets within the bound.
    let offsets = [0, 3 + seed % 5, 9, 14 + seed % 7, B - 1];
    for (i, &o) in offsets.iter().enumerate() {
        c.schedule_keys(at + o, if i % 2 == 0 { bit } else { 0 });
    }
    let release = at + B + hold;
    let offsets = [0, 2 + seed % 3, 11, 20 + seed % 9, B];
    for (i, &o) in offsets.iter().enumerate() {
        c.schedule_keys(release + o, if i % 2 == 0 { 0 } else { bit });
    }
    release + B + 1
}

/// Idles the bus until every scheduled key change is made and the keys have settled
/// (the bound's (D + 1) * F + 3 clocks after the last edge).
fn settle(m: &mut M, until: u64) {
    let now = chip(m).cycle();
    let end = until + 3 * F + 3;
    if end > now {
        ok(m.bus().wait(end - now));
    }
    assert_eq!(chip(m).pending_keys(), 0);
}

/// The slave motor moved by hand `delta` counts, one count every 16 clocks (a jump of
/// two would be an illegal quadrature transition).
fn slip(m: &mut M, delta: i64) {
    for _ in 0..delta.abs() {
        chip(m).plant.as_mut().unwrap().position[1] += delta.signum();
        ok(m.bus().wait(16));
    }
}

/// Bounced presses through the matrix pins make one event each, read through the bus;
/// the display override's value is read back from the LED pins.
#[test]
fn panel_keys_bounced_and_display() {
    let mut m = machine("panel_keys_bounced_and_display");
    let before = ok(m.panel_keys());
    assert_eq!((before.down, before.count), (0, 0));
    let keys = [KEY_5, KEY_9, KEY_5, 0, 15];
    for (n, &key) in keys.iter().enumerate() {
        let at = chip(&mut m).cycle() + 10;
        // Held long enough to read it down over the bus (an SPI read is ~ 700 clocks).
        let end = press(&mut m, key, at, 3000, n as u64);
        ok(m.bus().wait(B + 4 * F));
        let held = ok(m.panel_keys());
        assert_eq!(held.down, 1 << key, "key {key} down while held");
        settle(&mut m, end);
        let after = ok(m.panel_keys());
        assert_eq!(after.down, 0);
        assert_eq!(after.last, key);
        assert_eq!(after.count, before.count.wrapping_add(n as u8 + 1), "one event per bounced press");
    }
    // A glitch shorter than the bound presses nothing.
    let at = chip(&mut m).cycle() + 5;
    chip(&mut m).schedule_keys(at, 1 << KEY_9);
    chip(&mut m).schedule_keys(at + B, 0);
    settle(&mut m, at + B);
    assert_eq!(ok(m.panel_keys()).count, keys.len() as u8);

    // The LED pins: the display override, decimal and hex; back to the MODE page.
    ok(m.set_panel_display(Some(PanelDisplay { value: (-1234i16) as u16, hex: false })));
    ok(m.bus().wait(8));
    assert_eq!(display(&mut m).0, "   -1234");
    ok(m.set_panel_display(Some(PanelDisplay { value: 0xBEEF, hex: true })));
    ok(m.bus().wait(8));
    assert_eq!(display(&mut m).0, "   hbEEF");
    ok(m.set_panel_display(None));
    ok(m.bus().wait(8));
    assert_eq!(display(&mut m), ("     Frd".to_string(), false));
}

/// The gantry engaged at rest with the slave 6 counts behind: forward mode leaves the
/// error; '#' pressed at the card (bounced) selects synchronised mode and the slave's
/// step pin inserts steps until the error is within the deadband; the host overrides
/// the mode (forward, the card's '#' ignored) and hands it back.
#[test]
fn gantry_mode_from_panel_and_host() {
    let mut m = machine("gantry_mode_from_panel_and_host");
    chip(&mut m).plant = Some(GantryPlant::new(0, 1, 0, 1));
    let setup = GantrySetup { master: 0, slave: 1, enc_master: 0, enc_slave: 1, tick: 31, deadband: 1, limit: 100 };
    ok(m.configure_gantry(&setup));
    ok(m.enable_gantry(true));
    ok(m.bus().wait(16));
    let s = ok(m.gantry_status());
    assert!(s.engaged && !s.sync && !s.alarm && s.error == 0, "{s:?}");

    // The slave slips 6 counts back (the encoder sees it); forward mode does nothing.
    slip(&mut m, -6);
    ok(m.bus().wait(4000));
    let s = ok(m.gantry_status());
    assert_eq!((s.error, s.corrections, s.sync), (6, 0, false), "forward: no correction");

    // '#' on the MODE page: synchronised. Corrections insert slave steps (+1 each).
    let at = chip(&mut m).cycle() + 5;
    let end = press(&mut m, KEY_ACT, at, 200, 7);
    settle(&mut m, end);
    let menu = ok(m.panel_menu());
    assert!(menu.card_mode && menu.mode && menu.host_mode.is_none(), "{menu:?}");
    ok(m.bus().wait(20_000));
    let s = ok(m.gantry_status());
    assert!(s.sync && s.engaged && !s.alarm, "{s:?}");
    assert!(s.error.abs() <= 1, "synchronised: the error within the deadband, {s:?}");
    let plant = chip(&mut m).plant.clone().unwrap();
    assert!((plant.position[0] - plant.position[1]).abs() <= 1, "the slave caught up: {:?}", plant.position);
    assert_eq!(i64::from(s.corrections), plant.position[1] + 6, "each correction one slave step");
    assert_eq!(plant.position[0], 0, "the master never moved");

    // The host forces forward mode: the card's '#' changes nothing.
    ok(m.set_gantry_mode(Some(false)));
    ok(m.bus().wait(8));
    assert!(!ok(m.gantry_status()).sync);
    let at = chip(&mut m).cycle() + 5;
    let end = press(&mut m, KEY_ACT, at, 200, 3);
    settle(&mut m, end);
    let menu = ok(m.panel_menu());
    assert_eq!((menu.card_mode, menu.host_mode, menu.mode), (true, Some(false), false));
    // Then synchronised from the host, and the card's choice again.
    ok(m.set_gantry_mode(Some(true)));
    ok(m.bus().wait(8));
    assert!(ok(m.gantry_status()).sync);
    ok(m.set_gantry_mode(None));
    ok(m.bus().wait(8));
    let menu = ok(m.panel_menu());
    assert_eq!((menu.host_mode, menu.mode), (None, true));
    assert!(ok(m.gantry_status()).sync);
}

/// The gantry's alarm reaches the panel: an error past the limit sets GANTRY_STATUS.ALARM,
/// the menu latches flag 0, shows the ALARM page on the LED pins with digit 0's point,
/// and the card's '#' acknowledges it once COMMAND.CLEAR_ERRORS has cleared the input.
#[test]
fn gantry_alarm_reaches_the_panel() {
    let mut m = machine("gantry_alarm_reaches_the_panel");
    chip(&mut m).plant = Some(GantryPlant::new(0, 1, 0, 1));
    let setup = GantrySetup { master: 0, slave: 1, enc_master: 0, enc_slave: 1, tick: 31, deadband: 1, limit: 4 };
    ok(m.configure_gantry(&setup));
    ok(m.enable_gantry(true));
    ok(m.bus().wait(16));
    assert_eq!(display(&mut m), ("     Frd".to_string(), false));
    // 'A' shows the ERROR page: "E      0".
    let at = chip(&mut m).cycle() + 5;
    let end = press(&mut m, KEY_NEXT, at, 100, 1);
    settle(&mut m, end);
    assert_eq!(display(&mut m).0, "E      0");

    // The slave is pushed 5 counts ahead: error -5, past the limit of 4.
    slip(&mut m, 5);
    ok(m.bus().wait(2000));
    let s = ok(m.gantry_status());
    assert!(s.alarm && s.error == -5, "{s:?}");
    let menu = ok(m.panel_menu());
    assert_eq!((menu.alarms, menu.page), (0b0001, 2), "flag 0 latched, the ALARM page shown");
    assert_eq!(display(&mut m), ("AL  0001".to_string(), true));

    // '#' while the alarm's input is still high: the flag stays.
    let at = chip(&mut m).cycle() + 5;
    let end = press(&mut m, KEY_ACT, at, 100, 2);
    settle(&mut m, end);
    assert_eq!(ok(m.panel_menu()).alarms, 0b0001);
    // The slave back in place, the alarm cleared by the host: '#' acknowledges.
    slip(&mut m, -5);
    ok(m.bus().wait(2000));
    ok(m.clear_faults_and_errors());
    ok(m.bus().wait(8));
    assert!(!ok(m.gantry_status()).alarm);
    let at = chip(&mut m).cycle() + 5;
    let end = press(&mut m, KEY_ACT, at, 100, 4);
    settle(&mut m, end);
    assert_eq!(ok(m.panel_menu()).alarms, 0);
    assert_eq!(display(&mut m), ("AL  0000".to_string(), false));
}

/// The gantry's alarm halts the machine as an E-stop does (docs/spec/finestep_top.md,
/// panel and gantry): the master runs half a step a period in forward mode while the
/// slave's motor stalls (every step lost), so the error grows a count a master step;
/// from the clock the alarm is raised (the error past the limit of 6) no step pin rises
/// again though the program had 20 steps, STATUS.HALT reads 1, RUN is cleared and the
/// enables drop; the gantry disengaged and CLEAR_ERRORS given, the machine runs again.
#[test]
fn gantry_alarm_halts_the_machine() {
    let mut m = machine("gantry_alarm_halts_the_machine");
    let mut plant = GantryPlant::new(0, 1, 0, 1);
    plant.stall_steps = u32::MAX;
    chip(&mut m).plant = Some(plant);
    let axis = AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), ..AxisSetup::default() };
    for i in 0..2 {
        ok(m.configure_axis(i, &axis));
    }
    const LIMIT: u16 = 6;
    let setup = GantrySetup { master: 0, slave: 1, enc_master: 0, enc_slave: 1, tick: 31, deadband: 1, limit: LIMIT };
    ok(m.configure_gantry(&setup));
    ok(m.enable_gantry(true));
    ok(m.bus().wait(16));
    assert!(ok(m.gantry_status()).engaged);
    ok(m.set_period(200));
    ok(m.set_start_level(1));
    // 40 periods of half a step on the master: 20 steps.
    let records: Vec<PeriodRecord> =
        (0..40).map(|k| PeriodRecord::from_raw(&[1 << 15, 0, 0, 0], u8::from(k == 39))).collect();
    for burst in records.chunks(20) {
        ok(m.bus().push_records(burst));
    }
    ok(m.set_control(true, false, true));
    ok(m.bus().wait(40 * 200 + 2000));

    let s = ok(m.gantry_status());
    assert!(s.alarm && !s.sync, "{s:?}");
    let word = ok(m.status());
    assert_eq!(status::HALT.get(word), 1, "STATUS {word:#x}");
    assert_eq!(control::RUN.get(ok(m.bus().read_one(control::ADDR))), 0, "RUN cleared by the halt");
    let c = chip(&mut m);
    let halted = c.halted_since.expect("halted");
    let last_rise = c.last_step_rise.expect("the master stepped");
    assert!(last_rise <= halted, "a step pin rose at cycle {last_rise}, after the halt at {halted}");
    let plant = c.plant.clone().unwrap();
    // The master stopped one step past the limit (error = master - slave, the slave at
    // 0), well before the program's 20 steps.
    assert_eq!(plant.position, [i64::from(LIMIT) + 1, 0], "lost {}", plant.lost);
    let outputs = c.outputs_now();
    for axis in 0..4 {
        assert_eq!(outputs >> top_pins::output::pin_en(axis) & 1, 0, "axis {axis}'s enable pin");
    }

    // Disengaged (the error reads 0 then) and cleared: the halt is gone.
    ok(m.enable_gantry(false));
    ok(m.bus().wait(8));
    ok(m.clear_faults_and_errors());
    ok(m.bus().wait(8));
    assert!(!ok(m.gantry_status()).alarm);
    assert_eq!(status::HALT.get(ok(m.status())), 0);
    assert!(chip(&mut m).halted_since.is_none());
}

/// Right after reset the panel's and the gantry's registers read the map's reset words
/// (PANEL_MENU but its ALARM flags and PAGE: the power-up E-stop fault is latched there
/// and shows the ALARM page).
#[test]
fn panel_and_gantry_registers_read_their_reset_words() {
    let mut host = PinHost::new(PanelChipLockstep::new("panel_and_gantry_reset_words"), PinTiming::default());
    ok(host.reset(4));
    ok(host.idle(4));
    let mut m = ok(Machine::connect(SpiBus::new(host, 4)));
    let mut checked = 0;
    for register in finestep_host::regs::REGISTERS {
        if !(register.name.starts_with("PANEL_") || register.name.starts_with("GANTRY_")) {
            continue;
        }
        let word = register.reset_word.unwrap_or(0);
        let mut read = ok(m.bus().read_one(register.addr));
        if register.name == "PANEL_MENU" {
            assert_eq!((panel_menu::ALARM.get(read), panel_menu::PAGE.get(read)), (0b0100, 2));
            read = panel_menu::PAGE.set(panel_menu::ALARM.set(read, 0), 0);
        }
        assert_eq!(read, word, "{} at {:#04x}: {read:#010x}, the map says {word:#010x}", register.name, register.addr);
        checked += 1;
    }
    assert_eq!(checked, 6);
}
