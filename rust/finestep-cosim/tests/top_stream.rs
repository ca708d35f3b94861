//! A long move streamed over SPI into the bus-level top, RTL and model in lockstep:
//! the host keeps the FIFO fed, the FIFO never runs dry, and every axis ends exactly
//! on the rounded sum of its increments.

use std::time::Instant;

use finestep_cosim::TopLockstep;
use finestep_host::regs::{status, underrun_count};
use finestep_host::stream::{stream, wait_idle, StreamConfig};
use finestep_host::{AxisSetup, Bus, Machine, PinHost, PinTiming, SpiBus};
use finestep_model::{DriveTiming, PeriodRecord, RateChecker};

const PERIOD: u32 = 2000;
const PERIODS: usize = 10_000;

/// A smooth reversing move: each axis follows `amplitude * sin(2 pi f k / N)` in steps
/// per period, quantised with the remainder carried so no fraction is lost.
fn long_move() -> Vec<PeriodRecord> {
    let amplitudes = [90.0, -60.0, 35.5, 7.25];
    let frequencies = [1.0, 3.0, 7.0, 0.5];
    let mut carried = [0i64; 4];
    let mut ideal = [0f64; 4];
    (0..PERIODS)
        .map(|k| {
            let mut raw = [0i32; 4];
            for axis in 0..4 {
                let phase = std::f64::consts::TAU * frequencies[axis] * k as f64 / PERIODS as f64;
                ideal[axis] += amplitudes[axis] * phase.sin();
                let target = (ideal[axis] * 65536.0).round() as i64;
                raw[axis] = (target - carried[axis]) as i32;
                carried[axis] = target;
            }
            let flags = if k + 1 == PERIODS { 1 } else { 0 };
            PeriodRecord::from_raw(&raw, flags)
        })
        .collect()
}

#[test]
fn ten_thousand_periods_over_spi_without_underrun() {
    let records = long_move();
    let timing = DriveTiming::new(3, 3, 2, 2);
    // The rated rate of the core the Verilated top is built with (its step engine's slots).
    let mut checker = RateChecker::for_core(
        &finestep_cosim::rtl_top_params_of(finestep_cosim::TopVariant::MotionNoMpg).core_params(),
        PERIOD,
        &[timing; 4],
    );
    for (k, record) in records.iter().enumerate() {
        checker.check(record).unwrap_or_else(|(axis, e)| panic!("record {k}, axis {axis} over the rated rate: {e}"));
    }

    let mut host = PinHost::new(TopLockstep::motion_no_mpg("ten_thousand_periods_over_spi"), PinTiming::default());
    host.reset(4).unwrap();
    let mut machine = Machine::connect(SpiBus::new(host, 4)).unwrap();
    let axis = AxisSetup { timing, ..AxisSetup::default() };
    for i in 0..4 {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(PERIOD).unwrap();
    machine.set_start_level(64).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine.set_control(true, false, true).unwrap();

    let started = Instant::now();
    let report = stream(
        machine.bus(),
        records.iter().copied(),
        StreamConfig { burst: 32, poll_clocks: 2000, ..StreamConfig::default() },
    )
    .unwrap();
    wait_idle(machine.bus(), 2000, 4 * u64::from(PERIOD) * 300).unwrap();
    machine.bus().wait(1000).unwrap();
    let elapsed = started.elapsed().as_secs_f64();

    assert_eq!(report.records, PERIODS as u64);
    assert_eq!(report.underruns, 0);
    let bus = machine.bus();
    assert_eq!(bus.read_one(underrun_count::ADDR).unwrap(), 0);
    let status_word = bus.read_one(status::ADDR).unwrap();
    assert_eq!(status::UNDERRUN.get(status_word) | status::RATE_ERROR.get(status_word), 0, "{status_word:#x}");
    let positions = machine.positions().unwrap();
    for axis in 0..4 {
        let total: i64 = records.iter().map(|r| i64::from(r.inc[axis].to_bits())).sum();
        let expected = ((total + (1 << 15)) >> 16) as i32;
        assert_eq!(positions.steps[axis], expected, "axis {axis}");
    }
    let cycles = machine.bus().link_mut().target().cycle();
    eprintln!(
        "streamed {} records in {} bursts ({} level polls) over SPI at clk/8: {cycles} clocks co-simulated in {elapsed:.1} s ({:.2} M clocks/s, {:.0} periods/s)",
        report.records,
        report.bursts,
        report.polls,
        cycles as f64 / elapsed / 1e6,
        PERIODS as f64 / elapsed
    );
}
