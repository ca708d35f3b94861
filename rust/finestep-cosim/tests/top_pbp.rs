//! The simulated chip with the point-by-point comparison interpolator (`finestep_top`'s
//! default `HAS_PBP = 1`, docs/spec/pbp_interp.md#in-the-core) through SPI, RTL and
//! model in lockstep on every pin every clock: DDA records, a pbp line and a pbp arc,
//! DDA records. While the pbp records run (the core's `rec_ready` low) the host reads
//! `PERIOD_COUNT` and `POSITION`: both advance, the period timer's idle periods being
//! period boundaries (`period_boundary`), and the axes end exactly where the records
//! take them.

use finestep_cosim::TopLockstep;
use finestep_host::regs::{period_count, position, status, version};
use finestep_host::stream::{stream, wait_idle, StreamConfig};
use finestep_host::{AxisSetup, Bus, Machine, PinHost, PinTiming, SpiBus};
use finestep_interface::{flags, PbpLanes};
use finestep_model::pbp_interp::{arc_steps, ArcPath};
use finestep_model::{DriveTiming, PeriodRecord};

const PERIOD: u32 = 500;
/// A decision every 40 clocks (the step engine's visits, S = 4, keep the drive timing
/// with room): the line takes about 30 periods, the arc 8, so that the host's reads
/// (an SPI read of two words is about 900 clocks at SCK = clk / 8) see them under way.
const TICK_DIV: u32 = 39;

/// A DDA record moving only pair 1 (axes 2 and 3) by whole steps.
fn dda(steps: [i32; 2], flags: u8) -> PeriodRecord {
    PeriodRecord::from_raw(&[0, 0, steps[0] << 16, steps[1] << 16], flags)
}

#[test]
fn period_count_and_position_advance_through_pbp_records() {
    let mut host = PinHost::new(TopLockstep::new("top_pbp"), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(4).unwrap();
    let mut machine = Machine::connect(SpiBus::new(host, 4)).unwrap();
    assert_eq!(
        version::HAS_PBP.get(machine.bus().read_one(version::ADDR).unwrap()),
        1,
        "the default chip has the block"
    );
    let axis = AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), ..AxisSetup::default() };
    for i in 0..4 {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(PERIOD).unwrap();
    machine.set_start_level(2).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine.set_control(true, false, true).unwrap();

    // A line of 240 + 130 decisions on pair 0 (X rises to 240, Y falls to -130), then an
    // arc from (-60, 0) over 100 decisions (counter-clockwise, into the third quadrant:
    // X rises on from 240, Y falls on from -130).
    let line = PbpLanes { x: 240, y: -130, tick_div: TICK_DIV, ..PbpLanes::default() };
    let start = (-60, 0);
    let end = ArcPath::new(start.0, start.1, false).nth(99).unwrap().1;
    let steps = arc_steps(start, end, false).unwrap();
    let arc = PbpLanes { arc: true, x: start.0 as i32, y: start.1 as i32, steps, tick_div: TICK_DIV, ..line };
    assert!(line.fits() && arc.fits());
    let before = [dda([3, -2], 0), dda([1, 4], 0), dda([-2, 2], 0), dda([0, -1], 0)];
    let after = [dda([2, 2], 0), dda([-1, 3], 0), dda([4, 0], 0), dda([1, -1], flags::BLOCK_END)];
    let mut records = before.to_vec();
    records.push(PeriodRecord::pbp(&line, 0));
    records.push(PeriodRecord::pbp(&arc, 0));
    records.extend(after);
    let report = stream(machine.bus(), records.iter().copied(), StreamConfig::default()).unwrap();
    assert_eq!(report.records, records.len() as u64);

    // Poll PERIOD_COUNT and POSITION until the arc has ended.
    let want01 = [240 + (end.0 - start.0) as i32, -130 + (end.1 - start.1) as i32];
    let mut samples: Vec<(u32, [i32; 2])> = Vec::new();
    for _ in 0..400 {
        let bus = machine.bus();
        let count = bus.read_one(period_count::ADDR).unwrap();
        let mut words = [0u32; 2];
        bus.read(position::addr(0), &mut words).unwrap();
        let pos = words.map(|w| w as i32);
        samples.push((count, pos));
        if pos == want01 {
            break;
        }
        // An SPI read frame holds the latch (latch_hold): leave a period boundary free.
        bus.wait(u64::from(PERIOD) + 100).unwrap();
    }
    // During the line (axis 0 strictly between its start and its end): the latched
    // positions and the period count move on.
    let during: Vec<&(u32, [i32; 2])> = samples.iter().filter(|(_, p)| p[0] > 0 && p[0] < 240).collect();
    let mut distinct: Vec<i32> = during.iter().map(|(_, p)| p[0]).collect();
    distinct.dedup();
    // (a read of the count and two positions is a few thousand clocks: a few samples)
    assert!(distinct.len() >= 2, "POSITION[0] during the line: {distinct:?}");
    let counts: Vec<u32> = during.iter().map(|(c, _)| *c).collect();
    assert!(counts.windows(2).all(|w| w[0] <= w[1]), "PERIOD_COUNT never goes back: {counts:?}");
    assert!(counts.last().unwrap() > &counts[0], "PERIOD_COUNT during the line: {counts:?}");
    // ... and during the arc (past the line's end, not at the arc's).
    assert!(want01[0] > 240 && want01[1] < -130, "the arc's end {want01:?}");
    let in_arc = samples.iter().filter(|(_, p)| (p[0] > 240 || p[1] < -130) && *p != want01).count();
    assert!(in_arc >= 1, "POSITION during the arc: {samples:?}");

    wait_idle(machine.bus(), 1000, 40 * u64::from(PERIOD)).unwrap();
    machine.bus().wait(2 * u64::from(PERIOD)).unwrap();
    let positions = machine.positions().unwrap();
    let sum = |k: usize| before.iter().chain(&after).map(|r| r.inc[k].to_bits() >> 16).sum::<i32>();
    assert_eq!(positions.steps, vec![want01[0], want01[1], sum(2), sum(3)]);
    let status_word = machine.status().unwrap();
    assert_eq!(status::RECORD_ERROR.get(status_word), 0, "status {status_word:#x}");
    assert_eq!(report.underruns, 0);
}
