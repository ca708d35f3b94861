//! The synthesised netlist in lockstep (docs/verification.md): built only with the
//! feature `netlist-ecp5` or `netlist-ice40`, which makes `finestep-rtl-sys` Verilate
//! `finestep_top` from the Yosys netlist (`scripts/netlist.sh`) with Yosys's cell models.
//! The pin-level tests of the RTL lockstep run here unchanged, as modules, against the
//! model every pin every clock: streaming (`top_smoke`, `top_stream`), faults
//! (`top_faults`) and feedback (`top_feedback`). `make netlist` runs them all for both
//! families; `make test` runs the quick slice (`scripts/netlist_check.sh --quick`).
//!
//! `netlist_lockstep_rate` prints the figure: clocks of netlist lockstep per second on a
//! fixed streamed move, and that it ended bit-exact.

use std::time::Instant;

use finestep_cosim::TopLockstep;
use finestep_host::regs::{status, underrun_count};
use finestep_host::stream::{stream, wait_idle, StreamConfig};
use finestep_host::{AxisSetup, Bus, Machine, PinHost, PinTiming, SpiBus};
use finestep_model::{DriveTiming, PeriodRecord};

// The jog's edge cases (the velocity cap, JOG_VMAX = 0, windows and scales): only for the
// RTL mutation build, whose top has the hand wheel and the jog (the shipped iCE40 build
// and its netlist leave them out).
#[cfg(feature = "netlist-mutants")]
#[path = "jog_edges.rs"]
mod jog_edges;
#[path = "top_faults.rs"]
mod top_faults;
#[path = "top_feedback.rs"]
mod top_feedback;
#[path = "top_smoke.rs"]
mod top_smoke;
// The spindle, the logic outputs and the interlock: only for the RTL mutation build
// (scripts/mutants_rtl.py), whose mutants of those blocks nothing else here drives.
#[cfg(feature = "netlist-mutants")]
#[path = "top_spindle.rs"]
mod top_spindle;
#[path = "top_stream.rs"]
mod top_stream;

/// Periods of the figure's move (`FINESTEP_NETLIST_PERIODS` to change).
const RATE_PERIODS: usize = 40;
const RATE_PERIOD_CLOCKS: u32 = 500;

// The feature wiring: this binary must never run on the RTL.
const _: () = assert!(finestep_rtl_sys::TOP_IS_NETLIST, "tests/netlist.rs built without a netlist feature");

/// A reversing move on four axes, every record within the rated rate at the timing used.
fn rate_move(periods: usize) -> Vec<PeriodRecord> {
    (0..periods)
        .map(|k| {
            let phase = (k % 200) as i32 - 100;
            let raw = [phase * 300, -phase * 170, 9000 - phase * 40, if k % 3 == 0 { 65536 } else { -20000 }];
            PeriodRecord::from_raw(&raw, u8::from(k + 1 == periods))
        })
        .collect()
}

#[test]
fn netlist_lockstep_rate() {
    let periods = std::env::var("FINESTEP_NETLIST_PERIODS")
        .ok()
        .map(|v| v.parse::<usize>().unwrap_or_else(|_| panic!("FINESTEP_NETLIST_PERIODS={v}: not a count")))
        .unwrap_or(RATE_PERIODS);
    let records = rate_move(periods);
    let timing = DriveTiming::new(3, 3, 2, 2);
    let mut host = PinHost::new(TopLockstep::new("netlist_lockstep_rate"), PinTiming::default());
    let started = Instant::now();
    host.reset(4).unwrap();
    let mut machine = Machine::connect(SpiBus::new(host, 4)).unwrap();
    let axis = AxisSetup { timing, ..AxisSetup::default() };
    for i in 0..4 {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(RATE_PERIOD_CLOCKS).unwrap();
    machine.set_start_level(periods.min(32) as u16).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine.set_control(true, false, true).unwrap();
    let report = stream(
        machine.bus(),
        records.iter().copied(),
        StreamConfig { burst: 16, poll_clocks: 500, ..StreamConfig::default() },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    wait_idle(machine.bus(), 500, 4 * u64::from(RATE_PERIOD_CLOCKS) * 100).unwrap_or_else(|e| panic!("{e}"));
    // POSITION is latched at period boundaries: two more periods for the last steps.
    machine.bus().wait(2 * u64::from(RATE_PERIOD_CLOCKS)).unwrap_or_else(|e| panic!("{e}"));
    let elapsed = started.elapsed().as_secs_f64();

    assert_eq!(report.records, periods as u64);
    let bus = machine.bus();
    assert_eq!(bus.read_one(underrun_count::ADDR).unwrap(), 0, "the FIFO ran dry");
    let status_word = bus.read_one(status::ADDR).unwrap();
    assert_eq!(status::RATE_ERROR.get(status_word), 0, "{status_word:#x}");
    let positions = machine.positions().unwrap();
    for axis in 0..4 {
        let total: i64 = records.iter().map(|r| i64::from(r.inc[axis].to_bits())).sum();
        assert_eq!(positions.steps[axis], ((total + (1 << 15)) >> 16) as i32, "axis {axis}");
    }
    let cycles = machine.bus().link_mut().target().cycle();
    eprintln!(
        "netlist lockstep: {}: {periods} periods of {RATE_PERIOD_CLOCKS} clocks streamed over SPI, {cycles} clocks bit-exact \
         at every pin in {elapsed:.1} s: {:.0} clocks/s",
        finestep_rtl_sys::TOP_SOURCE,
        cycles as f64 / elapsed
    );
}
