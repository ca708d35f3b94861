//! `finestep sim-chip SOCKET` end to end: the host driver on a [`SimSocket`] (the
//! `SpiTransfer` a spidev board is driven through) reads the identity and CAPS and
//! streams records with exactly the results of the same driver on the in-process chip.

mod common;

use finestep_cosim::TopLockstep;
use finestep_host::sim_link::SimSocket;
use finestep_host::stream::{self, RunReport, StreamConfig};
use finestep_host::{AxisSetup, Bus, DriveTiming, Machine, PeriodRecord, PinHost, PinTiming, SpiBus, SpiTransfer};

use common::serve;

fn connect<T: SpiTransfer>(link: T) -> Machine<SpiBus<T>> {
    let mut machine = Machine::connect(SpiBus::new(link, 1)).unwrap();
    let n_axes = machine.caps().n_axes;
    machine.bus().set_n_axes(n_axes);
    machine
}

/// A short reversing move on every axis, configured and streamed as `finestep run` does
/// (T = 0.1 ms: a burst of 32 records takes about 7 periods on the wire at clk/8).
fn run_move<T: SpiTransfer>(machine: &mut Machine<SpiBus<T>>) -> (RunReport, u32) {
    let n = machine.caps().n_axes;
    let timing = DriveTiming::new(3, 3, 2, 2);
    for axis in 0..n {
        machine.configure_axis(axis, &AxisSetup { timing, ..AxisSetup::default() }).unwrap();
    }
    machine.enable_axes((1 << n) - 1).unwrap();
    machine.set_period(5_000).unwrap();
    machine.set_start_level(1).unwrap();
    machine.clear_faults_and_errors().unwrap();
    let records: Vec<PeriodRecord> = (0..200)
        .map(|k: i32| {
            let raw: Vec<i32> = (0..4).map(|a| (k % 40 - 20) * (a + 1) * 9_000).collect();
            PeriodRecord::from_raw(&raw, u8::from(k == 199))
        })
        .collect();
    let config = StreamConfig { burst: 32, poll_clocks: 2_500, prefill: 64, ..StreamConfig::default() };
    let report = match stream::run(machine, records, &config, |_, _| Ok(())) {
        Ok(report) => report,
        Err(e) => panic!("{e}: STATUS {:#x}, FIFO {:?}", machine.status().unwrap(), machine.fifo().unwrap()),
    };
    let status = machine.status().unwrap();
    (report, status)
}

#[test]
fn a_client_on_the_socket_gets_exactly_what_the_in_process_bus_gets() {
    let server = serve("lockstep", &["--once"]);
    let mut remote = connect(SimSocket::connect(&server.socket).unwrap());
    let mut host = PinHost::new(TopLockstep::new("sim_chip_in_process"), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(8).unwrap();
    let mut local = connect(host);
    assert_eq!(remote.caps(), local.caps());
    assert_eq!(remote.caps().n_axes, 4, "{:?}", remote.caps());
    let mut id = [0u32; 4];
    let mut local_id = [0u32; 4];
    remote.bus().read(finestep_host::regs::id::ADDR, &mut id).unwrap();
    local.bus().read(finestep_host::regs::id::ADDR, &mut local_id).unwrap();
    assert_eq!(id, local_id);
    let (remote_report, remote_status) = run_move(&mut remote);
    let (local_report, local_status) = run_move(&mut local);
    assert_eq!(remote_report, local_report);
    assert_eq!(remote_status, local_status);
    assert_eq!(remote_report.stream.records, 200);
    assert!(remote_report.end.steps.iter().any(|&s| s != 0), "{remote_report:?}");
    assert_eq!(remote.bus().last_status(), local.bus().last_status());
    // The server measured the Verilated pins every clock: every pulse within the timing
    // the driver wrote (L 3, S 3, U 2, H 2), one rise a step.
    let pins = remote.bus().link_mut().pin_timing().unwrap().expect("sim-chip measures its pins");
    assert_eq!(pins.violations(), 0, "{pins:?}");
    assert_eq!(pins.axes.len(), 4);
    for (axis, a) in pins.axes.iter().enumerate() {
        let f = &a.figures;
        assert!(a.step_dir, "axis {axis}");
        assert_eq!(f.timing, DriveTiming::new(3, 3, 2, 2), "axis {axis}");
        assert!(f.steps > 0, "axis {axis}: {f:?}");
        assert!(f.high_min >= Some(3) && f.low_min >= Some(3), "axis {axis}: {f:?}");
        assert!(f.setup_min >= Some(2) && f.hold_min >= Some(2), "axis {axis}: reverses: {f:?}");
    }
    assert!(pins.clocks > 200 * 5_000, "{pins:?}");
}

#[test]
fn the_model_alone_serves_the_same_chip_and_keeps_its_state_across_clients() {
    let server = serve("model", &["--target", "model"]);
    let caps = {
        let mut first = connect(SimSocket::connect(&server.socket).unwrap());
        // A multiple of the step engine's slots (777 is refused: see the test below).
        first.set_period(776).unwrap();
        first.caps()
    };
    let mut second = connect(SimSocket::connect(&server.socket).unwrap());
    assert_eq!(second.caps(), caps);
    let period = second.bus().read_one(finestep_host::regs::period_clocks::ADDR).unwrap();
    assert_eq!(period, 776);
}

#[test]
fn a_server_with_a_wrong_identity_is_refused_naming_what_id_read() {
    let server = serve("wrong-id", &["--target", "model", "--fault", "wrong-identity"]);
    let link = SimSocket::connect(&server.socket).unwrap();
    let err = Machine::connect(SpiBus::new(link, 4)).err().expect("refused").to_string();
    assert!(err.contains("ID reads 0xdeadbeef"), "{err}");
}

#[test]
fn a_step_engine_build_reports_its_slots_and_refuses_a_period_off_them() {
    use finestep_cosim::{rtl_top_params, ModelPins};
    use finestep_host::BusError;
    use finestep_model::top::Top;
    // The model of a chip built with STEP_SHARED = 1 (4 axes: S = 4 slots).
    let mut params = rtl_top_params();
    params.step_shared = true;
    let mut host = PinHost::new(ModelPins(Top::new(params)), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(8).unwrap();
    let mut machine = connect(host);
    assert_eq!(machine.caps().step_slots, 4, "{:?}", machine.caps());
    // The core would run 777 clocks as 776: refused before anything is written.
    match machine.set_period(777) {
        Err(BusError::PeriodSlots { clocks: 777, slots: 4 }) => {}
        other => panic!("a period of 777 clocks on 4 slots: {other:?}"),
    }
    let before = machine.bus().read_one(finestep_host::regs::period_clocks::ADDR).unwrap();
    assert_ne!(before, 777);
    machine.set_period(776).unwrap();
    assert_eq!(machine.bus().read_one(finestep_host::regs::period_clocks::ADDR).unwrap(), 776);
}
