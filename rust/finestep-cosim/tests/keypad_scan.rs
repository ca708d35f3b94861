//! Lockstep: the Verilated `keypad_scan` against `finestep_model::keypad_scan`, every
//! output on every clock, with a diode-less 4x4 matrix between the column outputs and
//! the row inputs: random presses of random keys with bounce at both edges (within the
//! debounce bound and beyond it), overlapping presses (lockout, ghosts), glitches on the
//! rows, and scan periods and debounce counts changed mid-run. A failure prints the seed
//! (rerun with FINESTEP_SEED), the first cycle, signal, expected and actual value, and
//! leaves a waveform in target/cosim-failures/keypad_scan_lockstep.vcd.

use std::path::PathBuf;

use finestep_model::keypad_scan::{bounce_bound, frame_clocks, Keypad, KeypadInputs, KeypadOutputs, KeypadScan};
use finestep_rtl_sys::{keypad_params, RtlKeypadScan};
use proptest::prelude::*;

/// One press: its key, when, its bounces and hold.
#[derive(Clone, Debug)]
struct Press {
    key: u8,
    /// Clocks after the previous press started (overlaps when short).
    after: u32,
    /// Edge offsets of the closing and the opening bursts, in units of the bound / 8.
    closing: Vec<u8>,
    opening: Vec<u8>,
    /// The hold, in frames.
    hold: u32,
}

/// A run: settings and presses, glitches, changes of the settings.
#[derive(Clone, Debug)]
struct Run {
    scan_div: u32,
    deb: u32,
    presses: Vec<Press>,
    /// (clock, row mask) one-clock glitches pulling rows low.
    glitches: Vec<(u32, u8)>,
    /// (clock, scan_div, deb) changes.
    changes: Vec<(u32, u32, u32)>,
}

fn press() -> impl Strategy<Value = Press> {
    (
        0u8..16,
        prop_oneof![3 => 200u32..3000, 1 => 0u32..200],
        prop::collection::vec(0u8..12, 0..6),
        prop::collection::vec(0u8..12, 0..6),
        1u32..24,
    )
        .prop_map(|(key, after, closing, opening, hold)| Press { key, after, closing, opening, hold })
}

fn run() -> impl Strategy<Value = Run> {
    (
        prop_oneof![Just(0u32), 0u32..12, Just(150)],
        prop_oneof![3 => 0u32..4, 1 => 4u32..16],
        prop::collection::vec(press(), 1..10),
        prop::collection::vec((0u32..20_000, 1u8..16), 0..6),
        prop::collection::vec((0u32..20_000, 0u32..12, 0u32..16), 0..3),
    )
        .prop_map(|(scan_div, deb, presses, glitches, changes)| Run { scan_div, deb, presses, glitches, changes })
}

/// A burst's level `t` clocks after its first edge: `to` at the first edge, toggled at
/// each later offset, and `to` from the last offset on.
fn burst_level(t: usize, offsets: &[usize], to: bool) -> bool {
    let last = offsets.iter().copied().max().unwrap_or(0);
    if t >= last {
        return to;
    }
    let toggles = offsets.iter().filter(|&&o| o > 0 && o <= t).count();
    to ^ (toggles % 2 == 1)
}

/// The keys closed at each clock (the contact levels), up to `clocks`: each press a
/// closing burst with edges up to 1.5 debounce bounds apart (some beyond the bound), a
/// hold, an opening burst.
fn contacts(run: &Run, clocks: usize) -> Vec<u16> {
    let scan_div = run.scan_div;
    let f = frame_clocks(scan_div) as usize;
    let bound = (bounce_bound(scan_div, run.deb) as usize).max(8);
    let mut closed = vec![0u16; clocks];
    let mut start = 0usize;
    for p in &run.presses {
        start += p.after as usize;
        let bit = 1u16 << p.key;
        let span = 2 * bound;
        let hold = p.hold as usize * f;
        let bursts = [(start, &p.closing, true, span + hold), (start + span + hold, &p.opening, false, span)];
        for (from, edges, to, len) in bursts {
            let offsets: Vec<usize> = edges.iter().map(|&e| usize::from(e) * bound / 8).collect();
            let end = (from + len).min(clocks);
            for (rel, keys) in closed.get_mut(from..end).unwrap_or(&mut []).iter_mut().enumerate() {
                if burst_level(rel, &offsets, to) {
                    *keys |= bit;
                } else {
                    *keys &= !bit;
                }
            }
        }
    }
    closed
}

/// The first output that differs.
fn diff(e: &KeypadOutputs, a: &KeypadOutputs) -> Option<String> {
    let fields = [
        ("col_drive", u32::from(e.col_drive), u32::from(a.col_drive)),
        ("key_valid", u32::from(e.key_valid), u32::from(a.key_valid)),
        ("key_code", u32::from(e.key_code), u32::from(a.key_code)),
        ("key_down", u32::from(e.key_down), u32::from(a.key_down)),
    ];
    fields.iter().find(|(_, e, a)| e != a).map(|(name, e, a)| format!("{name}: expected {e:#x}, actual {a:#x}"))
}

/// The inputs of every clock: the rows as the matrix reads them from the columns the
/// model drives (the same as the RTL's while they agree), glitches, settings.
fn lockstep(run: &Run) -> Result<(u64, u64), String> {
    let clocks = 20_000usize;
    let closed = contacts(run, clocks);
    let mut model = KeypadScan::new(keypad_params());
    let mut rtl = RtlKeypadScan::new();
    let (mut scan_div, mut deb) = (run.scan_div, run.deb);
    let mut stream = Vec::with_capacity(clocks);
    let mut events = 0u64;
    for (t, &keys) in closed.iter().enumerate() {
        for &(at, s, d) in &run.changes {
            if at as usize == t {
                scan_div = s;
                deb = d;
            }
        }
        let expected = model.outputs();
        let mut row_n = Keypad { closed: keys }.rows(expected.col_drive);
        for &(at, rows) in &run.glitches {
            if at as usize == t {
                row_n &= !rows;
            }
        }
        let inputs = KeypadInputs { scan_div, deb_scans: deb, row_n };
        if let Some(what) = diff(&expected, &rtl.outputs()) {
            let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/cosim-failures");
            let _ = std::fs::create_dir_all(&dir);
            let path = dir.join("keypad_scan_lockstep.vcd");
            let mut again = RtlKeypadScan::new();
            if again.trace_open(&path).is_ok() {
                for inputs in &stream {
                    again.step(inputs);
                }
                again.step(&inputs);
                again.trace_close();
            }
            return Err(format!("cycle {t}: {what} (waveform {})", path.display()));
        }
        events += u64::from(expected.key_valid);
        stream.push(inputs);
        model.step(&inputs);
        rtl.step(&inputs);
    }
    Ok((clocks as u64, events))
}

#[test]
fn keypad_scan_is_bit_exact_with_the_model() {
    assert_eq!((keypad_params().pre_w, keypad_params().deb_w), (16, 4));
    let mut runner = finestep_testkit::runner("keypad_scan_lockstep", 48);
    let total = std::cell::Cell::new((0u64, 0u64));
    runner
        .run(&run(), |run| match lockstep(&run) {
            Ok((clocks, events)) => {
                let (c, e) = total.get();
                total.set((c + clocks, e + events));
                Ok(())
            }
            Err(mismatch) => Err(TestCaseError::fail(mismatch)),
        })
        .unwrap();
    let (clocks, events) = total.get();
    eprintln!("keypad_scan lockstep: {clocks} clocks, {events} key events compared");
    assert!(events > 0, "the runs pressed no key");
}

#[test]
fn a_bounced_press_of_every_key_is_bit_exact_and_one_event() {
    let presses = (0..16u8)
        .map(|key| Press { key, after: 1200, closing: vec![1, 2, 4, 5], opening: vec![2, 3], hold: 4 })
        .collect();
    let run = Run { scan_div: 3, deb: 2, presses, glitches: vec![(100, 0xf)], changes: vec![] };
    let (_, events) = lockstep(&run).unwrap();
    assert_eq!(events, 16);
}
