//! The watchdog and the E-stop halting `finestep_top` in the middle of a move, through
//! the pins: halted within the latencies of docs/spec/safety_monitor.md, no runt pulse
//! (every step high phase lasts exactly `L`, rounded up to whole visits with the step
//! engine), no new pulse and no direction change after the halt, enables
//! inactive from the clock after it, the FIFO flushed, `CONTROL.RUN` cleared, and a
//! fault that cannot be cleared while its cause persists.

mod host;

use finestep_interface::regs;
use finestep_model::top::TopParams;
use finestep_model::PeriodRecord;
use host::*;
use proptest::prelude::*;

const N_AXES: usize = 2;
const PERIOD: u32 = 400;

#[derive(Clone, Debug)]
struct Case {
    /// Built with the step engine (`STEP_SHARED`, `S` = 2 slots for 2 axes).
    step_shared: bool,
    /// Step high time `L` per axis.
    step_len: [u32; N_AXES],
    /// Halt by the watchdog (else by the E-stop pin).
    watchdog: bool,
    /// Clocks after the run starts at which the E-stop is pressed.
    estop_after: u64,
    /// Watchdog timeout in clocks.
    timeout: u32,
    /// ESTOP_FILTER.
    filter: u32,
    /// Raw increments of the records, signed (reversals included).
    records: Vec<[i32; N_AXES]>,
}

/// The step engine's slots for [`N_AXES`] axes (docs/spec/step_engine.md), 1 without it.
fn slots(step_shared: bool) -> u32 {
    if step_shared {
        2
    } else {
        1
    }
}

/// The step high time the pins show: `L` rounded up to whole visits of `S` clocks
/// (docs/spec/step_engine.md#what-sharing-changes-at-the-pins; `S` = 1: `L`).
fn high_time(step_len: u32, step_shared: bool) -> u32 {
    let s = slots(step_shared);
    step_len.max(1).div_ceil(s) * s
}

fn case() -> impl Strategy<Value = Case> {
    (prop::array::uniform2(1..40u32), any::<bool>(), prop::bool::ANY, 0..6000u64, 1500..6000u32, 0..20u32)
        .prop_flat_map(|(step_len, step_shared, watchdog, estop_after, timeout, filter)| {
            // Within the rated rate with S = U = H = 1 (docs/spec/rated_rate.md): |D| *
            // 2 * (L + 1) <= P, in visits of S clocks with the step engine.
            let s = slots(step_shared);
            let max = |l: u32| (i64::from(PERIOD / (2 * (high_time(l, step_shared) + s))) << 16) as i32;
            let (m0, m1) = (max(step_len[0]), max(step_len[1]));
            let records = prop::collection::vec((-m0..=m0, -m1..=m1).prop_map(|(a, b)| [a, b]), 20..40);
            (Just(step_len), Just(step_shared), Just(watchdog), Just(estop_after), Just(timeout), Just(filter), records)
        })
        .prop_map(|(step_len, step_shared, watchdog, estop_after, timeout, filter, records)| Case {
            step_shared,
            step_len,
            watchdog,
            estop_after,
            timeout,
            filter,
            records,
        })
}

/// The lengths of the complete high phases of bit `axis` of `pin_a` in the trace.
fn high_phases(trace: &[Sample], axis: usize) -> Vec<(usize, usize)> {
    let mut phases = vec![];
    let mut rise = None;
    for (i, s) in trace.iter().enumerate() {
        match (s.outputs.pin_a(axis), rise) {
            (true, None) => rise = Some(i),
            (false, Some(r)) => {
                phases.push((r, i - r));
                rise = None;
            }
            _ => {}
        }
    }
    assert!(rise.is_none(), "trace ends in a high phase");
    phases
}

#[test]
fn halt_stops_pulses_cleanly_and_in_time() {
    let mut runner = finestep_testkit::runner("safety_halt_stops_pulses_cleanly", 96);
    runner
        .run(&case(), |case| {
            let p = TopParams { n_axes: N_AXES, step_shared: case.step_shared, has_pbp: false, ..TopParams::default() };
            let bus = ParallelMaster::default();
            let spi = SpiMaster::default();
            let mut bench = Bench::new(p);
            bench.bring_up(&bus);
            bus.write32(&mut bench, regs::period_clocks::ADDR, PERIOD);
            bus.write32(&mut bench, regs::estop_filter::ADDR, case.filter);
            bus.write32(&mut bench, regs::watchdog_timeout::ADDR, case.timeout);
            for axis in 0..N_AXES {
                bus.write32(&mut bench, regs::axis_timing_a::addr(axis), timing_a(case.step_len[axis], 1));
                bus.write32(&mut bench, regs::axis_timing_b::addr(axis), timing_b(1, 1));
            }
            bus.write32(&mut bench, regs::axis_enable::ADDR, 0b11);
            let records: Vec<PeriodRecord> = case.records.iter().map(|raw| record(raw, 0, N_AXES)).collect();
            prop_assert_eq!(spi.fifo(&mut bench, &records, N_AXES).1, ACK);
            bench.trace = Some(vec![]);
            let mut control = regs::control::RUN.set(regs::control::reset_word(), 1);
            control = regs::control::WATCHDOG_ENABLE.set(control, u32::from(case.watchdog));
            // The last write: from here on no kick comes.
            bus.write32(&mut bench, regs::control::ADDR, control);
            let mut pressed_at = None;
            if !case.watchdog {
                bench.clock(case.estop_after);
                bench.pins.estop_pin = true;
                pressed_at = Some(bench.since_reset);
            }
            bench.clock(u64::from(case.timeout) + 2000);
            let trace = bench.trace.take().unwrap();
            let origin = trace[0].cycle;
            let at = |cycle: u64| (cycle - origin) as usize;

            let h = trace.iter().position(|s| s.halt).expect("never halted");
            if let Some(pressed) = pressed_at {
                let latency = h - at(pressed);
                prop_assert!(latency <= 3 + case.filter.max(1) as usize, "E-stop halted after {} clocks", latency);
            } else {
                let last_kick = trace.iter().rposition(|s| s.kick).expect("no kick seen");
                prop_assert_eq!(h - last_kick, case.timeout as usize + 2, "watchdog latency from the last kick");
            }
            prop_assert!(trace[h..].iter().all(|s| s.halt), "the fault is sticky");
            for axis in 0..N_AXES {
                let l = high_time(case.step_len[axis], case.step_shared) as usize;
                for (rise, len) in high_phases(&trace, axis) {
                    prop_assert_eq!(len, l, "axis {} high phase from {} (halt at {})", axis, rise, h);
                    prop_assert!(rise <= h + 1, "axis {} rose at {} after the halt at {}", axis, rise, h);
                }
                let dir = trace[h + 2].outputs.pin_b(axis);
                prop_assert!(trace[h + 2..].iter().all(|s| s.outputs.pin_b(axis) == dir), "axis {} dir changed", axis);
            }
            for s in &trace[h + 1..] {
                prop_assert_eq!(s.outputs.pin_en, 0, "enables inactive from the clock after the halt");
                prop_assert!(!s.run_bit && !s.core_run, "RUN cleared");
                prop_assert_eq!((s.fifo_level, s.fifo_staged), (0, 0), "FIFO flushed");
            }
            let end = trace.last().unwrap();
            prop_assert_eq!(end.positions, trace[h + 1 + 64].positions, "positions hold after the halt");

            // The E-stop fault cannot be cleared while the E-stop is held.
            if !case.watchdog {
                bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_FAULTS.set(0, 1));
                bench.clock(4);
                prop_assert!(bench.top.halt(), "cleared while the E-stop is held");
                bench.pins.estop_pin = false;
                bench.clock(30);
            }
            bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_FAULTS.set(0, 1));
            bench.clock(4);
            prop_assert!(!bench.top.halt(), "cause gone, fault cleared");
            Ok(())
        })
        .unwrap();
}
