//! `led_menu` against statements written apart from the model: the digits read back
//! from the multiplexed pins (one digit enabled at a time, each for refresh_div + 1
//! clocks) and decoded with a segment table written from the usual a..g map of a
//! 7-segment digit (a top, b upper right, c lower right, d bottom, e lower left, f upper
//! left, g middle) must spell what `format!` writes: every signed 16-bit sync error in
//! decimal, values in hex, the mode words, the alarm flags; the menu's keys, the alarm
//! latch and acknowledgement and the host registers against their spec.

use finestep_model::led_menu::{LedInputs, LedMenu, LedParams, KEY_ACT, KEY_NEXT, KEY_PREV};
use proptest::prelude::*;

/// The segments of a character, from the letters of the lit segments.
fn segments_of(c: char) -> u8 {
    let lit = match c {
        '0' => "abcdef",
        '1' => "bc",
        '2' => "abdeg",
        '3' => "abcdg",
        '4' => "bcfg",
        '5' | 'S' => "acdfg",
        '6' => "acdefg",
        '7' => "abc",
        '8' => "abcdefg",
        '9' => "abcdfg",
        'A' => "abcefg",
        'B' | 'b' => "cdefg", // drawn lower-case
        'C' => "adef",
        'D' | 'd' => "bcdeg", // drawn lower-case
        'E' => "adefg",
        'F' => "aefg",
        '-' => "g",
        'r' => "eg",
        'n' => "ceg",
        'y' => "bcdfg",
        'c' => "deg",
        'h' => "cefg",
        'L' => "def",
        ' ' => "",
        other => panic!("no glyph for {other:?}"),
    };
    lit.chars().fold(0, |acc, s| acc | (1 << (s as u8 - b'a')))
}

/// Reads the 8 digits from the pins over one full refresh (digit 7 first: the text as
/// written), and whether digit 0's dp is lit; checks one digit at a time and the dwell.
fn read_display(m: &mut LedMenu, i: &LedInputs) -> (Vec<u8>, bool) {
    let p = LedParams::default();
    let n = p.n_dig as usize;
    let dwell = i.refresh_div as usize + 1;
    let mut seg = vec![None; n];
    let mut dp = false;
    let mut last_digit = None;
    let mut run = 0;
    for _ in 0..(n * dwell * 2 + 2) {
        let o = m.outputs();
        assert!(o.dig.count_ones() <= 1, "one digit at a time: {:#x}", o.dig);
        if o.dig != 0 {
            let d = o.dig.trailing_zeros() as usize;
            seg[d] = Some(o.seg & 0x7f);
            if d == 0 {
                dp = o.seg & 0x80 != 0;
            }
            if last_digit == Some(d) {
                run += 1;
            } else {
                if let Some(l) = last_digit {
                    assert_eq!(d, (l + 1) % n);
                }
                run = 1;
                last_digit = Some(d);
            }
            assert!(run <= dwell);
        }
        m.step(i);
    }
    (seg.into_iter().rev().map(|s| s.expect("every digit shown")).collect(), dp)
}

fn spelled(text: &str) -> Vec<u8> {
    assert_eq!(text.chars().count(), 8, "{text:?}");
    text.chars().map(segments_of).collect()
}

fn settle(m: &mut LedMenu, i: &LedInputs, clocks: usize) {
    for _ in 0..clocks {
        m.step(i);
    }
}

fn key(m: &mut LedMenu, base: &LedInputs, code: u8) {
    m.step(&LedInputs { key_valid: true, key_code: code, ..*base });
}

fn host(m: &mut LedMenu, base: &LedInputs, addr: u8, data: u16) {
    m.step(&LedInputs { host_wr: true, host_addr: addr, host_wdata: data, ..*base });
}

fn read(m: &mut LedMenu, base: &LedInputs, addr: u8) -> u16 {
    m.step(&LedInputs { host_addr: addr, ..*base });
    m.outputs().host_rdata
}

#[test]
fn every_sync_error_is_spelled_in_decimal_on_the_error_page() {
    let mut m = LedMenu::new(LedParams::default());
    let mut i = LedInputs::default();
    key(&mut m, &i, KEY_NEXT);
    assert_eq!(m.outputs().page, 1);
    for v in i16::MIN..=i16::MAX {
        i.sync_err = v;
        // Two conversions of 17 clocks: the text shows the value.
        settle(&mut m, &i, 34);
        let (digits, _) = read_display(&mut m, &i);
        assert_eq!(digits, spelled(&format!("E{v:>7}")), "sync error {v}");
    }
}

#[test]
fn values_in_hex_the_override_and_slow_refresh() {
    let mut runner = finestep_testkit::runner("led_menu_hex", 256);
    runner
        .run(&(any::<i16>(), any::<u16>(), 0u32..4), |(err, shown, refresh_div)| {
            let mut m = LedMenu::new(LedParams::default());
            let i = LedInputs { sync_err: err, refresh_div, ..LedInputs::default() };
            key(&mut m, &i, KEY_NEXT);
            key(&mut m, &i, KEY_ACT); // hex on the error page
            settle(&mut m, &i, 20);
            let (digits, _) = read_display(&mut m, &i);
            prop_assert_eq!(digits, spelled(&format!("E  h{:04X}", err as u16)));
            // The host's value over every page, decimal then hex.
            host(&mut m, &i, 2, shown);
            host(&mut m, &i, 1, 0b0_0100);
            settle(&mut m, &i, 34);
            let (digits, _) = read_display(&mut m, &i);
            prop_assert_eq!(digits, spelled(&format!(" {:>7}", shown as i16)));
            host(&mut m, &i, 1, 0b0_1100);
            settle(&mut m, &i, 2);
            let (digits, _) = read_display(&mut m, &i);
            prop_assert_eq!(digits, spelled(&format!("   h{shown:04X}")));
            prop_assert_eq!(read(&mut m, &i, 2), shown);
            Ok(())
        })
        .unwrap();
}

#[test]
fn the_mode_is_chosen_at_the_card_and_overridden_by_the_host() {
    let mut m = LedMenu::new(LedParams::default());
    let i = LedInputs::default();
    settle(&mut m, &i, 2);
    assert!(!m.outputs().sync_mode);
    assert_eq!(read_display(&mut m, &i).0, spelled("     Frd"));
    key(&mut m, &i, KEY_ACT);
    settle(&mut m, &i, 2);
    assert!(m.outputs().sync_mode);
    assert_eq!(read_display(&mut m, &i).0, spelled("    Sync"));
    // Keys that are not the page's action change nothing.
    for code in 0..16u8 {
        if code != KEY_ACT && code != KEY_NEXT && code != KEY_PREV {
            key(&mut m, &i, code);
        }
    }
    settle(&mut m, &i, 2);
    assert!(m.outputs().sync_mode);
    assert_eq!(m.outputs().page, 0);
    // The host overrides to forward: 'h' shown, '#' ignored; the card's mode stays.
    host(&mut m, &i, 0, 0b011);
    key(&mut m, &i, KEY_ACT);
    settle(&mut m, &i, 2);
    assert!(!m.outputs().sync_mode);
    assert_eq!(read_display(&mut m, &i).0, spelled("h    Frd"));
    assert_eq!(read(&mut m, &i, 0), 0b0011);
    host(&mut m, &i, 0, 0b001);
    settle(&mut m, &i, 2);
    assert!(m.outputs().sync_mode);
    assert_eq!(read(&mut m, &i, 0), 0b1001);
}

#[test]
fn pages_follow_the_keys_and_alarms_latch_until_acknowledged() {
    let mut m = LedMenu::new(LedParams::default());
    let mut i = LedInputs { sync_err: -42, ..LedInputs::default() };
    let mut pages = Vec::new();
    for code in [KEY_NEXT, KEY_NEXT, KEY_NEXT, KEY_PREV, KEY_PREV, KEY_PREV] {
        key(&mut m, &i, code);
        pages.push(m.outputs().page);
    }
    assert_eq!(pages, vec![1, 2, 0, 2, 1, 0]);
    key(&mut m, &i, KEY_NEXT);
    settle(&mut m, &i, 34);
    assert_eq!(read_display(&mut m, &i).0, spelled("E    -42"));
    // Flag 2 rises: the alarm page, latched after the input drops, dp lit.
    i.alarm_in = 0b0100;
    settle(&mut m, &i, 1);
    assert_eq!(m.outputs().page, 2);
    i.alarm_in = 0;
    settle(&mut m, &i, 3);
    assert!(m.outputs().alarm_pending);
    let (digits, dp) = read_display(&mut m, &i);
    assert_eq!(digits, spelled("AL  0100"));
    assert!(dp);
    assert_eq!(read(&mut m, &i, 3), 0b0100);
    // Leave the page: still latched. '#' on the mode page toggles the mode, not the alarm.
    key(&mut m, &i, KEY_NEXT);
    key(&mut m, &i, KEY_ACT);
    settle(&mut m, &i, 2);
    assert!(m.outputs().alarm_pending);
    // Acknowledged on the alarm page while flag 0 is still active: flag 0 stays.
    i.alarm_in = 0b0001;
    settle(&mut m, &i, 1);
    assert_eq!(m.outputs().page, 2);
    key(&mut m, &i, KEY_ACT);
    settle(&mut m, &i, 2);
    assert_eq!(read_display(&mut m, &i).0, spelled("AL  0001"));
    i.alarm_in = 0;
    key(&mut m, &i, KEY_ACT);
    settle(&mut m, &i, 2);
    assert!(!m.outputs().alarm_pending);
    let (digits, dp) = read_display(&mut m, &i);
    assert_eq!(digits, spelled("AL  0000"));
    assert!(!dp);
    // The host acknowledges with write-1-to-clear; a page write of 3 is ignored.
    i.alarm_in = 0b1010;
    settle(&mut m, &i, 1);
    i.alarm_in = 0;
    host(&mut m, &i, 3, 0b0010);
    assert_eq!(read(&mut m, &i, 3), 0b1000);
    host(&mut m, &i, 1, 0b00001);
    assert_eq!(m.outputs().page, 1);
    host(&mut m, &i, 1, 0b00011);
    assert_eq!(m.outputs().page, 1);
    assert_eq!(read(&mut m, &i, 1), 0b00001);
}

#[test]
fn active_low_levels_and_fewer_digits() {
    let p = LedParams { n_dig: 5, pre_w: 16, seg_active_low: true, dig_active_low: true };
    let mut m = LedMenu::new(p);
    let i = LedInputs { refresh_div: 2, ..LedInputs::default() };
    settle(&mut m, &i, 1);
    let mut shown = [None; 5];
    for _ in 0..40 {
        let o = m.outputs();
        let on = !o.dig & 0x1f;
        assert_eq!(on.count_ones(), 1);
        assert_eq!(o.dig & !0x1f, 0);
        shown[on.trailing_zeros() as usize] = Some(!o.seg & 0x7f);
        m.step(&i);
    }
    let want: Vec<u8> = "  Frd".chars().rev().map(segments_of).collect();
    assert_eq!(shown.iter().map(|s| s.unwrap()).collect::<Vec<_>>(), want);
}
