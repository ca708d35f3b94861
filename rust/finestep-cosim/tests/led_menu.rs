//! Lockstep: the Verilated `led_menu` (both builds: 8 digits active high, 5 digits
//! active low) against `finestep_model::led_menu`, every output on every clock, over
//! random streams of key events (the menu's keys and the others), a sync error that
//! walks and jumps to the 16-bit ends, alarm flags rising and falling, host reads of
//! every register and writes to each, and refresh periods changed mid-run. Then the
//! card alone: the Verilated `keypad_scan` feeding the Verilated `led_menu`, a bounced
//! '#' press selecting the synchronised mode, against the two models chained the same
//! way. A failure prints the seed (rerun with FINESTEP_SEED), the first cycle, signal,
//! expected and actual value, and leaves a waveform in
//! target/cosim-failures/led_menu_lockstep.vcd.

use std::path::PathBuf;

use finestep_model::keypad_scan::{Keypad, KeypadInputs, KeypadScan};
use finestep_model::led_menu::{LedInputs, LedMenu, LedOutputs, KEY_ACT, KEY_NEXT, KEY_PREV};
use finestep_rtl_sys::{keypad_params, led_variants, RtlKeypadScan, RtlLedMenu};
use proptest::prelude::*;

/// What happens in one clock, drawn per clock.
#[derive(Clone, Copy, Debug)]
enum Act {
    Idle,
    Key(u8),
    Err(i16),
    Alarm(u8),
    Write(u8, u16),
    Refresh(u32),
}

fn act() -> impl Strategy<Value = Act> {
    prop_oneof![
        30 => Just(Act::Idle),
        4 => prop_oneof![Just(KEY_NEXT), Just(KEY_PREV), Just(KEY_ACT), 0u8..16].prop_map(Act::Key),
        3 => prop_oneof![Just(i16::MIN), Just(i16::MAX), Just(0i16), Just(-1i16), any::<i16>(), -200i16..200]
            .prop_map(Act::Err),
        1 => (0u8..16).prop_map(Act::Alarm),
        1 => (0u8..4, prop_oneof![any::<u16>(), 0u16..32]).prop_map(|(a, d)| Act::Write(a, d)),
        1 => prop_oneof![0u32..4, Just(0xffff)].prop_map(Act::Refresh),
    ]
}

/// The inputs of every clock: each act held for `hold` clocks (a key for one).
fn inputs_of(acts: &[(Act, u8)]) -> Vec<LedInputs> {
    let mut state = LedInputs { refresh_div: 1, ..LedInputs::default() };
    let mut out = Vec::new();
    for (i, &(act, hold)) in acts.iter().enumerate() {
        let mut once = state;
        match act {
            Act::Idle => {}
            Act::Key(code) => {
                once.key_valid = true;
                once.key_code = code;
            }
            Act::Err(v) => state.sync_err = v,
            Act::Alarm(flags) => state.alarm_in = flags,
            Act::Write(addr, data) => {
                once.host_wr = true;
                once.host_addr = addr;
                once.host_wdata = data;
            }
            Act::Refresh(div) => state.refresh_div = div,
        }
        // The read address wanders.
        state.host_addr = (i % 4) as u8;
        once.refresh_div = state.refresh_div;
        once.sync_err = state.sync_err;
        once.alarm_in = state.alarm_in;
        if !once.host_wr {
            once.host_addr = state.host_addr;
        }
        out.push(once);
        for _ in 1..hold {
            out.push(state);
        }
    }
    out
}

/// The first output that differs.
fn diff(e: &LedOutputs, a: &LedOutputs) -> Option<String> {
    let fields = [
        ("host_rdata", u32::from(e.host_rdata), u32::from(a.host_rdata)),
        ("seg", u32::from(e.seg), u32::from(a.seg)),
        ("dig", u32::from(e.dig), u32::from(a.dig)),
        ("sync_mode", u32::from(e.sync_mode), u32::from(a.sync_mode)),
        ("alarm_pending", u32::from(e.alarm_pending), u32::from(a.alarm_pending)),
        ("page", u32::from(e.page), u32::from(a.page)),
    ];
    fields.iter().find(|(_, e, a)| e != a).map(|(name, e, a)| format!("{name}: expected {e:#x}, actual {a:#x}"))
}

/// Runs the stream on both builds; the first mismatch, with a waveform up to it.
fn lockstep(stream: &[LedInputs]) -> Result<(), String> {
    for (variant, params) in led_variants().into_iter().enumerate() {
        let mut model = LedMenu::new(params);
        let mut rtl = RtlLedMenu::new(variant);
        for (cycle, inputs) in stream.iter().enumerate() {
            if let Some(what) = diff(&model.outputs(), &rtl.outputs()) {
                let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/cosim-failures");
                let _ = std::fs::create_dir_all(&dir);
                let path = dir.join("led_menu_lockstep.vcd");
                let mut again = RtlLedMenu::new(variant);
                if again.trace_open(&path).is_ok() {
                    for inputs in &stream[..=cycle] {
                        again.step(inputs);
                    }
                    again.trace_close();
                }
                return Err(format!(
                    "variant {variant} {params:?}, cycle {cycle}: {what} (waveform {})",
                    path.display()
                ));
            }
            model.step(inputs);
            rtl.step(inputs);
        }
    }
    Ok(())
}

#[test]
fn led_menu_is_bit_exact_with_the_model() {
    let variants = led_variants();
    assert_eq!(variants.len(), 2);
    assert_eq!((variants[0].n_dig, variants[1].n_dig), (8, 5));
    let mut runner = finestep_testkit::runner("led_menu_lockstep", 128);
    let clocks = std::cell::Cell::new(0u64);
    runner
        .run(&prop::collection::vec((act(), 1u8..40), 50..400), |acts| {
            let stream = inputs_of(&acts);
            clocks.set(clocks.get() + 2 * stream.len() as u64);
            lockstep(&stream).map_err(TestCaseError::fail)
        })
        .unwrap();
    eprintln!("led_menu lockstep: {} clocks compared", clocks.get());
}

#[test]
fn the_card_alone_selects_sync_mode_with_a_bounced_key() {
    // keypad_scan's events into led_menu, RTL against the models chained the same way:
    // '#' (row 3, column 2) pressed with bounce on the mode page, then 'A' twice.
    let (scan_div, deb) = (3u32, 2u32);
    let mut kp_model = KeypadScan::new(keypad_params());
    let mut kp_rtl = RtlKeypadScan::new();
    let params = led_variants()[0];
    let mut menu_model = LedMenu::new(params);
    let mut menu_rtl = RtlLedMenu::new(0);
    let mut presses = Vec::new();
    let bounce = [0usize, 3, 5, 9, 12, 20];
    for (t0, key) in [(100usize, KEY_ACT), (900, KEY_NEXT), (1700, KEY_NEXT)] {
        presses.push((t0, key));
    }
    let mut modes = Vec::new();
    for t in 0..2600usize {
        let mut closed = 0u16;
        for &(t0, key) in &presses {
            // Closed from t0 with bounce in the first 20 clocks, released at t0 + 300
            // with bounce in the next 20.
            let close = t >= t0 && t < t0 + 320 && {
                let rel = t - t0;
                if rel < 20 {
                    bounce.iter().filter(|&&b| b <= rel).count() % 2 == 1
                } else if rel >= 300 {
                    bounce.iter().filter(|&&b| b <= rel - 300).count() % 2 == 0
                } else {
                    true
                }
            };
            if close {
                closed |= 1 << key;
            }
        }
        let ko = kp_model.outputs();
        assert_eq!(ko, kp_rtl.outputs(), "keypad, clock {t}");
        let mo = menu_model.outputs();
        assert_eq!(mo, menu_rtl.outputs(), "menu, clock {t}");
        modes.push((mo.sync_mode, mo.page));
        let kin = KeypadInputs { scan_div, deb_scans: deb, row_n: Keypad { closed }.rows(ko.col_drive) };
        let min = LedInputs {
            refresh_div: 0,
            key_valid: ko.key_valid,
            key_code: ko.key_code,
            sync_err: -1234,
            ..LedInputs::default()
        };
        kp_model.step(&kin);
        kp_rtl.step(&kin);
        menu_model.step(&min);
        menu_rtl.step(&min);
    }
    // Forward and the mode page, then synchronised; then the error page, the alarm page.
    assert_eq!(modes[50], (false, 0));
    assert_eq!(modes[800], (true, 0));
    assert_eq!(modes[1600], (true, 1));
    assert_eq!(modes[2500], (true, 2));
    // One change of each: no bounce made a second press.
    let changes = modes.windows(2).filter(|w| w[0] != w[1]).count();
    assert_eq!(changes, 3);
}
