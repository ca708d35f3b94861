//! `keypad_scan` against the ideal statement of its debounce (docs/spec/keypad_scan.md):
//! a key whose contact's edges come in bursts, each spanning at most
//! `deb_scans * F` clocks (first edge to last, `F = 4 * max(scan_div, 3) + 4`) and at
//! least `(deb_scans + 1) * F` clocks apart, changes its debounced state exactly once
//! for a burst that changes the level and never for a burst that returns to it; so each
//! press (a closing burst, a hold, an opening burst) makes exactly one event, with the
//! key's code. Exhaustively over every burst of span up to the bound at one setting and
//! every phase against the scan, by proptest over settings, keys and press trains; the
//! bound is shown tight (a glitch one clock longer can make a second press). The scan
//! itself, the lockout and the ghosting rule are checked on a diode-less matrix.

use finestep_model::keypad_scan::{
    bounce_bound, frame_clocks, Keypad, KeypadInputs, KeypadOutputs, KeypadParams, KeypadScan,
};
use proptest::prelude::*;

/// Runs the block for one clock with the keys `closed`, the rows read through the
/// matrix from the driven column; returns the outputs before the edge.
fn clock(k: &mut KeypadScan, pad: Keypad, scan_div: u32, deb: u32) -> KeypadOutputs {
    let o = k.outputs();
    let row_n = pad.rows(o.col_drive);
    k.step(&KeypadInputs { scan_div, deb_scans: deb, row_n });
    o
}

/// What one key saw over a level trace: events with its code, and changes of its bit.
#[derive(Debug, Default, PartialEq, Eq)]
struct Seen {
    events: u32,
    other_events: u32,
    changes: u32,
    down: bool,
}

/// Drives `key`'s contact with `levels` (one per clock, true = closed) from `k`'s state.
fn drive(k: &mut KeypadScan, key: u32, levels: &[bool], scan_div: u32, deb: u32) -> Seen {
    let mut seen = Seen { down: (k.outputs().key_down >> key) & 1 != 0, ..Seen::default() };
    let mut was = seen.down;
    let mut run = |o: KeypadOutputs, seen: &mut Seen| {
        if o.key_valid {
            if u32::from(o.key_code) == key {
                seen.events += 1;
            } else {
                seen.other_events += 1;
            }
        }
        let now = (o.key_down >> key) & 1 != 0;
        if now != was {
            seen.changes += 1;
            was = now;
        }
        seen.down = now;
    };
    for &closed in levels {
        let pad = Keypad { closed: u16::from(closed) << key };
        let o = clock(k, pad, scan_div, deb);
        run(o, &mut seen);
    }
    // The last edge's effect (the outputs after the last clock).
    let o = k.outputs();
    run(o, &mut seen);
    seen
}

#[test]
fn every_burst_within_the_bound_changes_the_state_at_most_once_exhaustive() {
    // scan_div 3 (P = 4, F = 16), deb_scans 1: bound 16 clocks. Every burst: an edge at
    // clock 0 of the window, any levels in clocks 1..=16 (so the last edge at most 16
    // later), from either level, at every phase of the scan; before it a stable stretch
    // of (deb + 1) F clocks (plus the phase), after it one of (deb + 1) F + 4.
    let (scan_div, deb) = (3u32, 1u32);
    let f = frame_clocks(scan_div) as usize;
    let bound = bounce_bound(scan_div, deb) as usize;
    assert_eq!((f, bound), (16, 16));
    let stretch = (deb as usize + 1) * f;
    let key = 6; // row 1, column 2
    let mut cases = 0u64;
    for from_closed in [false, true] {
        for phase in 0..f {
            let mut base = KeypadScan::new(KeypadParams::default());
            // Settle at the starting level (a press first when it is closed).
            let settle = vec![from_closed; 2 * stretch + phase];
            let s = drive(&mut base, key, &settle, scan_div, deb);
            assert_eq!(s.down, from_closed);
            for pattern in 0u32..(1 << bound) {
                let mut k = base.clone();
                let mut levels = Vec::with_capacity(bound + 1 + stretch + 4);
                levels.push(!from_closed);
                levels.extend((0..bound).map(|i| (pattern >> i) & 1 != 0));
                let last = *levels.last().unwrap();
                levels.extend(std::iter::repeat_n(last, stretch + 4));
                let s = drive(&mut k, key, &levels, scan_div, deb);
                let changed = last != from_closed;
                assert_eq!(s.down, last, "phase {phase} pattern {pattern:#x} from {from_closed}");
                assert_eq!(s.changes, u32::from(changed), "phase {phase} pattern {pattern:#x} from {from_closed}");
                assert_eq!(s.events, u32::from(changed && last), "phase {phase} pattern {pattern:#x}");
                assert_eq!(s.other_events, 0);
                cases += 1;
            }
        }
    }
    assert_eq!(cases, 2 * 16 * 65536);
}

#[test]
fn the_bound_is_tight_a_glitch_one_clock_longer_can_press_twice() {
    // Held closed, an open glitch of deb * F + 1 clocks: at some phase the scan samples
    // it deb + 1 times (a release) and the hold after it presses again.
    for (scan_div, deb) in [(3u32, 1u32), (5, 2), (3, 3)] {
        let f = frame_clocks(scan_div) as usize;
        let bound = bounce_bound(scan_div, deb) as usize;
        let stretch = (deb as usize + 1) * f;
        let mut double = 0;
        let mut within = 0;
        for phase in 0..f {
            for glitch in [bound, bound + 1] {
                let mut k = KeypadScan::new(KeypadParams::default());
                let mut levels = vec![false; stretch + phase];
                levels.extend(std::iter::repeat_n(true, 2 * stretch));
                levels.extend(std::iter::repeat_n(false, glitch));
                levels.extend(std::iter::repeat_n(true, 2 * stretch));
                let s = drive(&mut k, 9, &levels, scan_div, deb);
                if glitch == bound {
                    within += usize::from(s.events != 1);
                } else if s.events == 2 {
                    double += 1;
                }
            }
        }
        assert_eq!(within, 0, "a glitch of the bound never presses twice (scan_div {scan_div}, deb {deb})");
        assert!(
            double > 0,
            "a glitch one clock over the bound presses twice at some phase (scan_div {scan_div}, deb {deb})"
        );
    }
}

/// A train of presses of one key: per press, the closing burst's edges (offsets within
/// the bound), the hold, the opening burst and the rest.
#[derive(Clone, Debug)]
struct Press {
    closing: Vec<u32>,
    hold_extra: u32,
    glitch: Option<(u32, u32)>,
    opening: Vec<u32>,
    rest_extra: u32,
}

/// A burst's levels: `from` before, toggled at each edge offset (sorted, the first at
/// 0, all within `span`), ending at `to` (an extra edge at the last offset if needed).
fn burst(from: bool, to: bool, offsets: &[u32], span: u32) -> Vec<bool> {
    let mut edges: Vec<u32> = offsets.iter().map(|o| o % (span + 1)).collect();
    edges.push(0);
    edges.sort_unstable();
    edges.dedup();
    let flips = edges.len() % 2 == 1;
    if (from != to) != flips {
        // One edge too many or too few: drop the last (not the first), or add one.
        if edges.len() > 1 {
            edges.pop();
        } else {
            edges.push(span.max(1));
            if span == 0 {
                // No room for a second edge: a single edge is the only burst.
                edges.pop();
            }
        }
    }
    let len = edges.last().copied().unwrap_or(0) as usize + 1;
    let mut level = from;
    let mut out = Vec::with_capacity(len);
    for t in 0..len as u32 {
        if edges.contains(&t) {
            level = !level;
        }
        out.push(level);
    }
    out
}

fn press() -> impl Strategy<Value = Press> {
    (
        prop::collection::vec(any::<u32>(), 0..8),
        0u32..40,
        prop::option::of((any::<u32>(), any::<u32>())),
        prop::collection::vec(any::<u32>(), 0..8),
        0u32..40,
    )
        .prop_map(|(closing, hold_extra, glitch, opening, rest_extra)| Press {
            closing,
            hold_extra,
            glitch,
            opening,
            rest_extra,
        })
}

#[test]
fn each_press_with_bounce_within_the_bound_is_one_event() {
    let mut runner = finestep_testkit::runner("keypad_scan_presses", 256);
    runner
        .run(&(0u32..10, 0u32..5, 0u32..16, prop::collection::vec(press(), 1..5)), |(scan_div, deb, key, presses)| {
            let f = frame_clocks(scan_div) as u32;
            let bound = bounce_bound(scan_div, deb) as u32;
            let stretch = (deb + 1) * f;
            let mut levels = vec![false; stretch as usize];
            let mut want = 0u32;
            for p in &presses {
                let closing = burst(false, true, &p.closing, bound);
                let opening = burst(true, false, &p.opening, bound);
                if closing.len() as u32 > bound + 1 || opening.len() as u32 > bound + 1 {
                    // A burst of two edges does not fit a bound of 0.
                    continue;
                }
                levels.extend(closing);
                levels.extend(std::iter::repeat_n(true, (stretch + p.hold_extra) as usize));
                if let Some((at, len)) = p.glitch {
                    // An open glitch within the hold, shorter than the bound, then a hold.
                    if bound > 0 {
                        let g = burst(true, true, &[0, 1 + at % bound], bound);
                        levels.extend(g);
                        levels.extend(std::iter::repeat_n(true, (stretch + len % 7) as usize));
                    }
                }
                levels.extend(opening);
                levels.extend(std::iter::repeat_n(false, (stretch + p.rest_extra) as usize));
                want += 1;
            }
            // The latency: the synchroniser's two clocks and the state's register.
            levels.extend([false; 3]);
            let mut k = KeypadScan::new(KeypadParams::default());
            let s = drive(&mut k, key, &levels, scan_div, deb);
            prop_assert_eq!(s.events, want);
            prop_assert_eq!(s.changes, 2 * want);
            prop_assert_eq!(s.other_events, 0);
            prop_assert!(!s.down);
            Ok(())
        })
        .unwrap();
}

#[test]
fn the_scan_drives_one_column_at_a_time_for_its_step() {
    for scan_div in [0u32, 1, 2, 3, 4, 9] {
        let mut k = KeypadScan::new(KeypadParams::default());
        let step = scan_div.max(3) as usize + 1;
        let mut last = 0u8;
        let mut run = 0usize;
        let mut runs = Vec::new();
        for _ in 0..(step * 12) {
            let o = clock(&mut k, Keypad::default(), scan_div, 0);
            assert_eq!(o.col_drive.count_ones(), 1);
            if o.col_drive == last {
                run += 1;
            } else {
                if last != 0 {
                    assert_eq!(o.col_drive, ((last << 1) | (last >> 3)) & 0xf);
                    runs.push(run);
                }
                last = o.col_drive;
                run = 1;
            }
        }
        assert!(runs.iter().all(|&r| r == step), "scan_div {scan_div}: {runs:?}");
    }
}

#[test]
fn every_key_reports_its_code_and_lockout_and_ghosts_make_no_event() {
    let (scan_div, deb) = (3u32, 2u32);
    let stretch = (2 * (deb + 1) * frame_clocks(scan_div) as u32) as usize;
    for key in 0..16u32 {
        let mut k = KeypadScan::new(KeypadParams::default());
        let mut events = Vec::new();
        for closed in [1u16 << key, 0] {
            for _ in 0..stretch {
                let o = clock(&mut k, Keypad { closed }, scan_div, deb);
                if o.key_valid {
                    events.push(o.key_code);
                }
                assert_eq!(o.key_down & !(1 << key), 0);
            }
        }
        assert_eq!(events, vec![key as u8], "key {key}");
    }
    // Two keys: the first pressed is an event, the second (pressed while the first is
    // down) is not; three keys of a rectangle show a ghost in the bitmap, no event.
    let mut k = KeypadScan::new(KeypadParams::default());
    let mut events = Vec::new();
    let mut bitmap = 0;
    for closed in [1u16, 1 | (1 << 5), 1 | (1 << 1) | (1 << 5), 0, 1 << 5] {
        for _ in 0..stretch {
            let o = clock(&mut k, Keypad { closed }, scan_div, deb);
            if o.key_valid {
                events.push(o.key_code);
            }
            bitmap = o.key_down;
        }
        if closed == 1 | (1 << 1) | (1 << 5) {
            // Keys 0, 1, 5 and the ghost 4 (row 1, column 0).
            assert_eq!(bitmap, 1 | (1 << 1) | (1 << 4) | (1 << 5));
        }
    }
    assert_eq!(events, vec![0, 5]);
    assert_eq!(bitmap, 1 << 5);
}
