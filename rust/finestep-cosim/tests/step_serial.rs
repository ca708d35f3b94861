//! Lockstep: the Verilated `step_serial` (the digit-serial step engine) against
//! `finestep_model::step_serial`, every output on every clock, in every Verilated variant
//! (axes, digit): random periods, records (up to one step per visit, so rate errors and
//! direction reversals), drive timings, output modes and inversions changed at round
//! starts, stops, runs dropped in the middle of a visit, halts and error clears. The
//! environment keeps the engine's contract: while running `inc` and `p_active` change only at round
//! starts (period boundaries), a stopped run zeroes `inc` (the period timer), a run starts only at a round start. A failure prints the
//! variant and the first cycle and output, and leaves a waveform in
//! target/cosim-failures/step_serial_lockstep.vcd.

use std::path::PathBuf;

use finestep_model::step_serial::{SerialInputs, SerialOutputs, SerialParams, StepSerial};
use finestep_rtl_sys::{serial_variants, RtlStepSerial};
use proptest::prelude::*;

/// One period of the run: its increments and what happens in it.
#[derive(Clone, Debug)]
struct Period {
    /// Per axis, a fraction of the largest increment `(V * 65536 - 1)`, in 1/1000.
    inc: [i16; 8],
    /// Whole rounds of stop before the period (0: back to back).
    stop: u8,
    /// The run drops at this clock of the period and stays low to its end.
    drop: Option<u16>,
    /// A halt pulse starting at this clock of the period, this many clocks long.
    halt: Option<(u16, u16)>,
    /// A clear_errors at this clock.
    clear: Option<u16>,
    /// New drive timings (index into the choices) for one axis at the period's start.
    timing: Option<(u8, [u8; 4], u8, u8)>,
}

#[derive(Clone, Debug)]
struct Run {
    visits: u32,
    timings: [[u8; 4]; 8],
    modes: [u8; 8],
    inverts: [u8; 8],
    enable: u8,
    periods: Vec<Period>,
}

fn period() -> impl Strategy<Value = Period> {
    let inc = prop_oneof![
        3 => -60i16..60,
        2 => -400i16..400,
        1 => -999i16..=999,
        1 => Just(0i16),
    ];
    (
        prop::array::uniform8(inc),
        prop_oneof![3 => Just(0u8), 1 => 1u8..4],
        prop::option::weighted(0.1, 0u16..2000),
        prop::option::weighted(0.05, (0u16..2000, 1u16..300)),
        prop::option::weighted(0.1, 0u16..2000),
        prop::option::weighted(0.1, (0u8..8, prop::array::uniform4(0u8..8), 0u8..4, 0u8..8)),
    )
        .prop_map(|(inc, stop, drop, halt, clear, timing)| Period { inc, stop, drop, halt, clear, timing })
}

fn run() -> impl Strategy<Value = Run> {
    (
        prop_oneof![3 => 1u32..8, 2 => 8u32..40, 1 => 40u32..200],
        prop::array::uniform8(prop::array::uniform4(0u8..8)),
        prop::array::uniform8(0u8..4),
        prop::array::uniform8(0u8..8),
        any::<u8>(),
        prop::collection::vec(period(), 1..24),
    )
        .prop_map(|(visits, timings, modes, inverts, enable, periods)| Run {
            visits,
            timings,
            modes,
            inverts,
            enable,
            periods,
        })
}

/// A drive timing in clocks from a choice: 0, 1, about one round, a few rounds.
fn timing(choice: u8, r: u32) -> u16 {
    let v = match choice {
        0 => 0,
        1 => 1,
        2 => r - 1,
        3 => r,
        4 => r + 1,
        5 => 2 * r + 3,
        6 => 3 * r - 1,
        _ => 5,
    };
    v.min(4095) as u16
}

/// The clock-by-clock inputs of a run for these parameters.
fn inputs_of(run: &Run, p: SerialParams) -> Vec<SerialInputs> {
    let r = p.round();
    let v = run.visits.min(p.max_visits()).max(1);
    let period_clocks = v * r;
    let m = i64::from(v) << 16;
    let mut base = SerialInputs {
        p_active: period_clocks,
        axis_enable: run.enable,
        out_mode: run.modes,
        invert: run.inverts,
        ..SerialInputs::default()
    };
    let set_timings = |base: &mut SerialInputs, a: usize, t: [u8; 4]| {
        base.step_len[a] = timing(t[0], r);
        base.step_space[a] = timing(t[1], r);
        base.dir_setup[a] = timing(t[2], r);
        base.dir_hold[a] = timing(t[3], r);
    };
    for a in 0..8 {
        set_timings(&mut base, a, run.timings[a]);
    }
    let mut out = Vec::new();
    for per in &run.periods {
        for _ in 0..u32::from(per.stop) * r {
            out.push(SerialInputs { run: false, ..base });
        }
        if let Some((a, t, mode, inv)) = per.timing {
            set_timings(&mut base, usize::from(a), t);
            base.out_mode[usize::from(a)] = mode;
            base.invert[usize::from(a)] = inv;
        }
        for a in 0..8 {
            base.inc[a] = ((m - 1) * i64::from(per.inc[a]) / 1000) as i32;
        }
        let mut running = true;
        for t in 0..period_clocks {
            let t16 = t.min(u32::from(u16::MAX)) as u16;
            let halt = per.halt.is_some_and(|(at, len)| t16 >= at && t16 < at.saturating_add(len));
            if halt || per.drop.is_some_and(|at| t16 >= at) {
                running = false;
            }
            // A stopped run: the period timer zeroes the increments (also in the middle of
            // a visit, which then makes no request).
            let inc = if running { base.inc } else { [0; 8] };
            out.push(SerialInputs { run: running, halt, clear_errors: per.clear == Some(t16), inc, ..base });
        }
    }
    // Drain: stopped rounds until every pulse is out.
    for _ in 0..(40 * r) {
        out.push(SerialInputs { run: false, ..base });
    }
    out
}

fn diff(e: &SerialOutputs, a: &SerialOutputs) -> Option<String> {
    let fields = [
        ("start_ok", u32::from(e.start_ok), u32::from(a.start_ok)),
        ("pin_a", u32::from(e.pin_a), u32::from(a.pin_a)),
        ("pin_b", u32::from(e.pin_b), u32::from(a.pin_b)),
        ("pin_en", u32::from(e.pin_en), u32::from(a.pin_en)),
        ("rate_error", u32::from(e.rate_error), u32::from(a.rate_error)),
        ("step_lost", u32::from(e.step_lost), u32::from(a.step_lost)),
        ("pos_digit", u32::from(e.pos_digit), u32::from(a.pos_digit)),
        ("pos_index", u32::from(e.pos_index), u32::from(a.pos_index)),
        ("pos_axis", u32::from(e.pos_axis), u32::from(a.pos_axis)),
    ];
    fields.iter().find(|(_, e, a)| e != a).map(|(name, e, a)| format!("{name}: expected {e:#x}, actual {a:#x}"))
}

/// Runs the stream on one variant; the first mismatch, with a waveform up to it.
fn lockstep(variant: usize, params: SerialParams, stream: &[SerialInputs]) -> Result<(u64, u32), String> {
    let mut model = StepSerial::new(params);
    let mut rtl = RtlStepSerial::new(variant);
    let mut edges = 0u32;
    let mut last_a = 0u8;
    for (cycle, inputs) in stream.iter().enumerate() {
        let expected = model.outputs();
        if let Some(what) = diff(&expected, &rtl.outputs()) {
            let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/cosim-failures");
            let _ = std::fs::create_dir_all(&dir);
            let path = dir.join("step_serial_lockstep.vcd");
            let mut again = RtlStepSerial::new(variant);
            if again.trace_open(&path).is_ok() {
                for inputs in &stream[..=cycle] {
                    again.step(inputs);
                }
                again.trace_close();
            }
            return Err(format!("variant {variant} {params:?}, cycle {cycle}: {what} (waveform {})", path.display()));
        }
        edges += (expected.pin_a ^ last_a).count_ones();
        last_a = expected.pin_a;
        model.step(inputs);
        rtl.step(inputs);
    }
    Ok((stream.len() as u64, edges))
}

#[test]
fn step_serial_is_bit_exact_with_the_model() {
    let variants = serial_variants();
    assert_eq!(variants.len(), 3);
    assert_eq!(variants.iter().map(|p| (p.n_axes, p.digit)).collect::<Vec<_>>(), vec![(4, 4), (3, 1), (2, 2)]);
    let mut runner = finestep_testkit::runner("step_serial_lockstep", 48);
    let clocks = std::cell::Cell::new(0u64);
    let edges = std::cell::Cell::new(0u64);
    runner
        .run(&run(), |run| {
            for (variant, params) in variants.iter().enumerate() {
                let stream = inputs_of(&run, *params);
                let (n, e) = lockstep(variant, *params, &stream).map_err(TestCaseError::fail)?;
                clocks.set(clocks.get() + n);
                edges.set(edges.get() + u64::from(e));
            }
            Ok(())
        })
        .unwrap();
    eprintln!("step_serial lockstep: {} clocks compared, {} pin A edges", clocks.get(), edges.get());
    // The runs moved the pins (a lockstep of idle pins proves little).
    assert!(edges.get() > 1000, "only {} pin A edges", edges.get());
}
