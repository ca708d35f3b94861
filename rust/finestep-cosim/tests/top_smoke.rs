//! The bus-level top in lockstep: the host driver over SPI and over the 8080 bus.

use finestep_cosim::TopLockstep;
use finestep_host::regs::{command, control, fifo_level, status};
use finestep_host::stream::{self, stream, wait_idle, StreamConfig, StreamEvent};
use finestep_host::{AxisSetup, Bus, Machine, ParallelBus, PinHost, PinTiming, SpiBus};
use finestep_model::{DriveTiming, PeriodRecord};

fn spi_machine(name: &str) -> Machine<SpiBus<PinHost<TopLockstep>>> {
    let mut host = PinHost::new(TopLockstep::new(name), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(4).unwrap();
    Machine::connect(SpiBus::new(host, 4)).unwrap()
}

/// Over the 8080 bus, the motion chip (no spindle, no logic outputs) as the boards
/// build it; over SPI, `finestep_top`'s defaults: both Verilated variants are smoked.
fn parallel_machine(name: &str) -> Machine<ParallelBus<TopLockstep>> {
    let mut host = PinHost::new(TopLockstep::motion(name), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(4).unwrap();
    Machine::connect(ParallelBus::new(host, 4)).unwrap()
}

fn start<B: Bus>(machine: &mut Machine<B>, period: u32) {
    let axis = AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), ..AxisSetup::default() };
    for i in 0..machine.caps().n_axes {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(period).unwrap();
    machine.set_start_level(4).unwrap();
    machine.clear_faults_and_errors().unwrap();
    let status_word = machine.status().unwrap();
    assert_eq!(status::HALT.get(status_word), 0, "status {status_word:#x}");
    machine.set_control(true, false, true).unwrap();
}

fn moves(n: usize) -> Vec<PeriodRecord> {
    (0..n)
        .map(|k| {
            let flags = if k + 1 == n { 1 } else { 0 };
            PeriodRecord::from_raw(&[3 << 15, -(5 << 14), (k as i32) << 12, 0], flags)
        })
        .collect()
}

fn expected_steps(records: &[PeriodRecord], axis: usize) -> i32 {
    let total: i64 = records.iter().map(|r| i64::from(r.inc[axis].to_bits())).sum();
    // Round half up, as the DDA does.
    ((total + (1 << 15)) >> 16) as i32
}

#[test]
fn spi_identity_and_registers() {
    let mut machine = spi_machine("spi_identity_and_registers");
    assert_eq!(machine.caps().n_axes, 4);
    assert_eq!(machine.caps().fifo_depth, 256);
    let bus = machine.bus();
    assert_eq!(control::ESTOP_ACTIVE_HIGH.get(bus.read_one(control::ADDR).unwrap()), 1);
    bus.write(fifo_level::ADDR + 1, 17).unwrap();
    assert_eq!(bus.read_one(fifo_level::ADDR + 1).unwrap(), 17);
    let status_word = bus.read_one(status::ADDR).unwrap();
    assert_eq!(status::HALT.get(status_word), 1, "the core starts halted");
    bus.write(command::ADDR, command::CLEAR_FAULTS.set(0, 1)).unwrap();
    assert_eq!(status::HALT.get(bus.read_one(status::ADDR).unwrap()), 0);
}

/// Right after reset every register whose fields the map fixes (reset values of `rw`
/// fields, fixed values of `ro` ones, 0 for `pulse`) reads exactly that word, every
/// element of every array the build has (per axis up to CAPS.N_AXES, per encoder up to
/// CAPS.N_ENC; the elements past them are unmapped and read 0; the panel's and the
/// gantry's registers read 0 where CAPS says they are not built): the map's `reset_word`,
/// RTL and model in lockstep on each read (a mutation of a reset value in the RTL
/// survived every other test). Every other register (one with a hardware field, such as
/// INTERLOCK's ACTIVE beside its `rw` reset values) is read too, every element, RTL and
/// model in lockstep on the word (mutant 82 of the 5c605a1 draw, INTERLOCK.PRESCALE
/// resetting to 4487, survived while these were skipped).
#[test]
fn every_register_reads_its_reset_word() {
    let mut machine = spi_machine("every_register_reads_its_reset_word");
    let caps = machine.caps();
    let mut checked = 0;
    let mut hardware = 0;
    for register in finestep_host::regs::REGISTERS {
        let Some(word) = register.reset_word else {
            for index in 0..register.count() {
                machine.bus().read_one(register.addr_of(index).unwrap()).unwrap();
                hardware += 1;
            }
            continue;
        };
        let built = match register.name {
            n if n.starts_with("AXIS_") => caps.n_axes,
            "POSITION" | "RECORD_INC" | "PROBE_POSITION" => caps.n_axes,
            n if n.starts_with("ENC_") => caps.n_enc,
            // Blocks this build may leave out read 0.
            n if n.starts_with("PANEL_") => usize::from(caps.has_panel),
            n if n.starts_with("GANTRY_") => usize::from(caps.has_gantry),
            _ => register.count(),
        };
        for index in 0..register.count() {
            let addr = register.addr_of(index).unwrap();
            let read = machine.bus().read_one(addr).unwrap();
            let word = if index < built { word } else { 0 };
            assert_eq!(
                read, word,
                "{}[{index}] at {addr:#04x}: {read:#010x}, the map says {word:#010x}",
                register.name
            );
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked} words");
    assert!(hardware > 20, "{hardware} words with a hardware field");
}

#[test]
fn spi_stream_moves_exactly() {
    let mut machine = spi_machine("spi_stream_moves_exactly");
    start(&mut machine, 2000);
    let records = moves(40);
    let report = stream(machine.bus(), records.clone(), StreamConfig::default()).unwrap();
    assert_eq!(report.records, 40);
    wait_idle(machine.bus(), 1000, 200_000).unwrap();
    // POSITION is latched at period boundaries: two more periods for the last steps.
    let settle = 2 * u64::from(machine.period_clocks());
    machine.bus().wait(settle).unwrap();
    let positions = machine.positions().unwrap();
    for axis in 0..4 {
        assert_eq!(positions.steps[axis], expected_steps(&records, axis), "axis {axis}");
    }
    assert_eq!(report.underruns, 0);
    // Stopped, the latch follows the pins every clock; the read still settles.
    machine.set_control(false, false, true).unwrap();
    assert_eq!(machine.positions().unwrap().steps, positions.steps);
}

/// The whole run as the CLI does it: pre-fill, start, feed, wait, with an observer that
/// follows the queue and samples the latched positions while the streamer waits.
#[test]
fn spi_run_prefills_starts_and_reports() {
    let mut machine = spi_machine("spi_run_prefills_starts_and_reports");
    let axis = AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), ..AxisSetup::default() };
    for i in 0..4 {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(2000).unwrap();
    machine.set_start_level(1).unwrap();
    machine.clear_faults_and_errors().unwrap();
    let records = moves(300);
    let config = StreamConfig { poll_clocks: 1000, ..StreamConfig::default() };
    let (mut queued, mut samples) = (Vec::new(), Vec::new());
    let report = stream::run(&mut machine, records.iter().copied(), &config, |machine, event| {
        match event {
            StreamEvent::Queued { queued: n } => queued.push(n),
            StreamEvent::Waited => samples.push(machine.positions()?),
        }
        Ok(())
    })
    .unwrap();
    // The pre-fill (two bursts) is one event, then a burst at a time up to the last record.
    assert_eq!(queued.first(), Some(&64));
    assert_eq!(queued.last(), Some(&300));
    assert!(queued.windows(2).all(|w| w[0] < w[1] && w[1] - w[0] <= 32), "{queued:?}");
    assert_eq!((report.stream.records, report.stream.underruns), (300, 0));
    assert_eq!(report.stream.bursts, queued.len() as u64 + 1);
    for axis in 0..4 {
        assert_eq!(report.end.steps[axis], expected_steps(&records, axis), "axis {axis}");
    }
    // The samples (one per wait) move forward in time from the first boundary on, and
    // the run took at least its 300 periods.
    assert!(!samples.is_empty());
    assert!(samples.windows(2).all(|w| w[1].latch_time.wrapping_sub(w[0].latch_time) < 1 << 31));
    assert!(samples.iter().all(|s| s.latch_time.wrapping_sub(report.first_boundary) < 1 << 31));
    assert!(report.cycles >= 300 * 2000, "{}", report.cycles);
}

#[test]
fn parallel_stream_moves_exactly() {
    let mut machine = parallel_machine("parallel_stream_moves_exactly");
    let caps = machine.caps();
    // (A netlist build has one top, the default's, for both variants.)
    let motion = !finestep_rtl_sys::TOP_IS_NETLIST;
    assert!(!motion || !caps.has_spindle && !caps.has_outputs, "the motion chip reports neither in CAPS: {caps:?}");
    start(&mut machine, 3000);
    let records = moves(12);
    stream(machine.bus(), records.clone(), StreamConfig::default()).unwrap();
    wait_idle(machine.bus(), 1000, 200_000).unwrap();
    // POSITION is latched at period boundaries: two more periods for the last steps.
    let settle = 2 * u64::from(machine.period_clocks());
    machine.bus().wait(settle).unwrap();
    let positions = machine.positions().unwrap();
    for axis in 0..4 {
        assert_eq!(positions.steps[axis], expected_steps(&records, axis), "axis {axis}");
    }
}

/// START_LEVEL's edges (docs/spec/motion_control.md: the gate opens when FIFO_LEVEL >=
/// max(START_LEVEL, 1)). START_LEVEL 0 acts as 1: with RUN and an empty FIFO the gate stays
/// shut (STATUS.STREAMING 0, read several times), then queued records run and land; at
/// START_LEVEL 512, more than the FIFO holds, one queued record never runs (STREAMING 0,
/// FIFO_LEVEL 1, the axes where they were). RTL and model in lockstep on every read.
/// (No test wrote START_LEVEL 0 or 512: mutants 92, 93 and 99 of the 5c605a1 draw, a
/// threshold of 513 or 0 for START_LEVEL 0 and of 1 for 512, survived.)
#[test]
fn start_level_zero_and_beyond_the_fifo() {
    let mut machine = spi_machine("start_level_zero_and_beyond_the_fifo");
    start(&mut machine, 600);
    machine.set_control(false, false, true).unwrap();
    machine.set_start_level(0).unwrap();
    machine.set_control(true, false, true).unwrap();
    for _ in 0..4 {
        machine.bus().wait(450).unwrap();
        let word = machine.status().unwrap();
        assert_eq!(status::STREAMING.get(word), 0, "START_LEVEL 0, nothing queued: {word:#x}");
    }
    let records = moves(6);
    machine.bus().push_records(&records).unwrap();
    wait_idle(machine.bus(), 500, 100_000).unwrap();
    machine.bus().wait(2 * 600).unwrap();
    let positions = machine.positions().unwrap();
    for axis in 0..4 {
        assert_eq!(positions.steps[axis], expected_steps(&records, axis), "axis {axis}");
    }
    assert_eq!(machine.fifo().unwrap().0, 0);
    // Beyond the FIFO's 256 records: the gate never opens.
    machine.set_control(false, false, true).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine.set_start_level(512).unwrap();
    machine.bus().push_records(&moves(1)).unwrap();
    machine.set_control(true, false, true).unwrap();
    for _ in 0..4 {
        machine.bus().wait(1000).unwrap();
        let word = machine.status().unwrap();
        assert_eq!(status::STREAMING.get(word), 0, "START_LEVEL 512, one record queued: {word:#x}");
    }
    assert_eq!(machine.fifo().unwrap().0, 1, "the record stays queued");
    assert_eq!(machine.positions().unwrap().steps, positions.steps);
}
