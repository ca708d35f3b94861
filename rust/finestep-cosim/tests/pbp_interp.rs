//! Lockstep: the Verilated `pbp_interp` against `finestep_model::pbp_interp`, every
//! output on every clock, over random streams of line and arc records (small and to the
//! coordinate width's ends, arcs crossing quadrants, counts the host would not send),
//! random tick dividers changed mid-record, idle gaps and halts. A failure prints the
//! seed (rerun with FINESTEP_SEED), the first cycle, signal, expected and actual value,
//! and leaves a waveform in target/cosim-failures/pbp_interp_lockstep.vcd.

use std::path::PathBuf;

use finestep_model::pbp_interp::{arc_steps, PbpInputs, PbpInterp, PbpOutputs, PbpRecord};
use finestep_rtl_sys::{pbp_params, RtlPbpInterp};
use proptest::prelude::*;

/// One record and how it is run.
#[derive(Clone, Debug)]
struct Job {
    rec: PbpRecord,
    tick_div: u32,
    /// Clocks before the record is offered.
    gap: u32,
    /// Halt after this many clocks of the record (None: run to done).
    halt_after: Option<u32>,
    /// Change tick_div to this after a third of the record.
    retick: Option<u32>,
}

fn record() -> impl Strategy<Value = PbpRecord> {
    let w = 1i64 << 23;
    prop_oneof![
        // Small lines.
        (-40i64..=40, -40i64..=40).prop_map(|(x, y)| PbpRecord::line(x, y)),
        // Lines to the width's ends (halted or long): the extreme -2^23 included.
        (prop_oneof![Just(-w), -w..w], -w..w).prop_map(|(x, y)| PbpRecord::line(x, y)),
        // Arcs of radius up to 30 to a point of their path (in a quadrant, across, full).
        (-30i64..=30, -30i64..=30, any::<bool>(), 0.0f64..1.0).prop_filter_map("R^2 >= 2", |(x, y, cw, t)| {
            let full = arc_steps((x, y), (x, y), cw).ok()?;
            let k = ((full as f64 * t) as u64).max(1);
            Some(PbpRecord { arc: true, cw, x, y, steps: k })
        }),
        // Big arcs near an axis: a prefix of up to 3000 decisions crosses it.
        (-w..w, -1500i64..1500, any::<bool>(), any::<bool>(), 1u64..3000).prop_map(|(a, b, swap, cw, k)| {
            let (x, y) = if swap { (b, a) } else { (a, b) };
            PbpRecord { arc: true, cw, x, y, steps: k }
        }),
        // Anything: counts the host would not send, R^2 < 2, zero counts.
        (-3i64..=3, -3i64..=3, any::<bool>(), 0u64..40).prop_map(|(x, y, cw, steps)| PbpRecord {
            arc: true,
            cw,
            x,
            y,
            steps
        }),
    ]
}

fn job() -> impl Strategy<Value = Job> {
    (
        record(),
        prop_oneof![Just(0u32), Just(1), Just(3), 0u32..20, Just(0xffff)],
        0u32..5,
        prop_oneof![3 => Just(None), 1 => (0u32..400).prop_map(Some)],
        prop_oneof![3 => Just(None), 1 => (0u32..6).prop_map(Some)],
    )
        .prop_map(|(rec, tick_div, gap, halt_after, retick)| Job { rec, tick_div, gap, halt_after, retick })
}

/// The inputs of every clock of a stream of jobs. A record that would run longer than
/// 20 000 clocks is halted.
fn inputs_of(jobs: &[Job]) -> Vec<PbpInputs> {
    let mut model = PbpInterp::new(pbp_params());
    model.reset();
    let mut out = Vec::new();
    for job in jobs {
        let mut inputs = PbpInputs { tick_div: job.tick_div, ..PbpInputs::default() };
        for _ in 0..job.gap {
            out.push(inputs);
            model.step(&inputs);
        }
        // Offer until taken (the block is ready unless a record runs).
        inputs.rec_valid = true;
        inputs.rec = job.rec;
        while !model.outputs().rec_ready {
            out.push(inputs);
            model.step(&inputs);
        }
        out.push(inputs);
        model.step(&inputs);
        inputs.rec_valid = false;
        let mut clocks = 0u32;
        while model.outputs().busy {
            clocks += 1;
            if Some(clocks) == job.halt_after.map(|h| h + 1) || clocks >= 20_000 {
                inputs.halt = true;
            }
            if let Some(t) = job.retick {
                if clocks == 30 {
                    inputs.tick_div = t;
                }
            }
            out.push(inputs);
            model.step(&inputs);
            inputs.halt = false;
        }
        // A few idle clocks, one of them halted.
        for halt in [false, true, false] {
            out.push(PbpInputs { halt, ..inputs });
            model.step(&PbpInputs { halt, ..inputs });
        }
    }
    out
}

/// The first output that differs.
fn diff(expected: &PbpOutputs, actual: &PbpOutputs) -> Option<String> {
    let fields = [
        ("rec_ready", expected.rec_ready, actual.rec_ready),
        ("busy", expected.busy, actual.busy),
        ("done", expected.done, actual.done),
        ("req_valid[0]", expected.req_valid[0], actual.req_valid[0]),
        ("req_valid[1]", expected.req_valid[1], actual.req_valid[1]),
        ("req_negative[0]", expected.req_negative[0], actual.req_negative[0]),
        ("req_negative[1]", expected.req_negative[1], actual.req_negative[1]),
        ("move_up[0]", expected.move_up[0], actual.move_up[0]),
        ("move_up[1]", expected.move_up[1], actual.move_up[1]),
        ("move_down[0]", expected.move_down[0], actual.move_down[0]),
        ("move_down[1]", expected.move_down[1], actual.move_down[1]),
    ];
    fields.iter().find(|(_, e, a)| e != a).map(|(name, e, a)| format!("{name}: expected {e}, actual {a}"))
}

/// Runs the stream on both; the first mismatch, with a waveform of the run up to it.
fn lockstep(stream: &[PbpInputs]) -> Result<u64, String> {
    let mut model = PbpInterp::new(pbp_params());
    model.reset();
    let mut rtl = RtlPbpInterp::new();
    let mut requests = 0u64;
    for (cycle, inputs) in stream.iter().enumerate() {
        if let Some(what) = diff(&model.outputs(), &rtl.outputs()) {
            let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/cosim-failures");
            let _ = std::fs::create_dir_all(&dir);
            let path = dir.join("pbp_interp_lockstep.vcd");
            let mut again = RtlPbpInterp::new();
            if again.trace_open(&path).is_ok() {
                for inputs in &stream[..cycle] {
                    again.step(inputs);
                }
                again.step(&stream[cycle.min(stream.len() - 1)]);
                again.trace_close();
            }
            return Err(format!("cycle {cycle}: {what} (waveform {})", path.display()));
        }
        let o = model.outputs();
        requests += u64::from(o.req_valid[0]) + u64::from(o.req_valid[1]);
        model.step(inputs);
        rtl.step(inputs);
    }
    Ok(requests)
}

#[test]
fn pbp_interp_is_bit_exact_with_the_model() {
    assert_eq!(pbp_params().coord_w, 24);
    let mut runner = finestep_testkit::runner("pbp_interp_lockstep", 256);
    let total = std::cell::Cell::new((0u64, 0u64));
    runner
        .run(&prop::collection::vec(job(), 1..12), |jobs| {
            let stream = inputs_of(&jobs);
            match lockstep(&stream) {
                Ok(requests) => {
                    let (clocks, steps) = total.get();
                    total.set((clocks + stream.len() as u64, steps + requests));
                    Ok(())
                }
                Err(mismatch) => Err(TestCaseError::fail(mismatch)),
            }
        })
        .unwrap();
    let (clocks, steps) = total.get();
    eprintln!("pbp_interp lockstep: {clocks} clocks, {steps} step requests compared");
}

#[test]
fn a_full_circle_and_a_line_at_the_width_limit_are_bit_exact() {
    let w = 1i64 << 23;
    let jobs = [
        Job {
            rec: PbpRecord::arc((7, -4), (7, -4), true).unwrap(),
            tick_div: 1,
            gap: 0,
            halt_after: None,
            retick: None,
        },
        Job { rec: PbpRecord::line(-w, w - 1), tick_div: 0, gap: 2, halt_after: Some(5000), retick: None },
        Job {
            rec: PbpRecord::arc((-w, -w), (-w, -w), false).unwrap(),
            tick_div: 0,
            gap: 1,
            halt_after: Some(3000),
            retick: None,
        },
    ];
    let stream = inputs_of(&jobs);
    lockstep(&stream).unwrap();
}
