//! The feedback blocks at the chip's pins with the plant in the loop: streamed motion
//! drives lagging axes whose encoders and gratings feed the counters back; the hand wheel
//! moves an axis through the jog; faults outside the filter's specification are flagged.

use finestep_cosim::{PlantLoop, TopLockstep};
use finestep_host::stream::{stream, wait_idle, StreamConfig};
use finestep_host::{
    AxisSetup, Bus, EncoderSetup, JogMultiplier, JogSetup, Machine, PinHost, PinTarget, PinTiming, SpiBus,
};
use finestep_model::{Increment, PeriodRecord};
use finestep_plant::{
    Bounce, ChannelConfig, CountsPerStep, DriveConfig, EncoderConfig, HandWheelConfig, Mechanics, Plant,
    PlantConfig,
};

type Chip<T> = Machine<SpiBus<PinHost<PlantLoop<T>>>>;

fn connect<T: PinTarget>(target: T, plant: Plant) -> Chip<T> {
    let mut host = PinHost::new(PlantLoop::new(target, plant), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(8).unwrap();
    Machine::connect(SpiBus::new(host, 4)).unwrap()
}

fn start<B: Bus>(machine: &mut Machine<B>, period: u32) {
    let axis = AxisSetup { step_len: 20, step_space: 20, dir_setup: 10, dir_hold: 10, ..AxisSetup::default() };
    for i in 0..machine.caps().n_axes {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(period).unwrap();
    machine.set_start_level(4).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine.set_control(true, false, true).unwrap();
}

fn two_axis_plant(tau: u64) -> Plant {
    let mechanics = if tau == 0 { Mechanics::Ideal } else { Mechanics::Lag { tau } };
    let drive = DriveConfig { mechanics, ..DriveConfig::default() };
    Plant::new(
        PlantConfig {
            drives: vec![drive, drive],
            channels: vec![
                ChannelConfig { axis: 0, encoder: EncoderConfig::rotary(CountsPerStep::integer(4).unwrap(), 2000, 7) },
                ChannelConfig {
                    axis: 1,
                    encoder: EncoderConfig::linear_grating(CountsPerStep::new(5, 2).unwrap(), None),
                },
            ],
            probe: None,
            hand_wheel: None,
        },
        1,
    )
    .unwrap()
}

fn run_moves<T: PinTarget>(machine: &mut Chip<T>) {
    let records: Vec<PeriodRecord> = (0..40)
        .map(|k| {
            let flags = if k == 39 { 1 } else { 0 };
            PeriodRecord::from_raw(&[3 << 15, -(5 << 14), 0, 0], flags)
        })
        .collect();
    stream(machine.bus(), records, StreamConfig::default()).unwrap();
    wait_idle(machine.bus(), 1000, 400_000).unwrap();
    machine.bus().wait(20_000).unwrap();
}

#[test]
fn rtl_encoders_follow_the_plant() {
    let mut machine = connect(finestep_cosim::RtlPins::new(), two_axis_plant(300));
    start(&mut machine, 2000);
    machine.configure_encoder(1, &EncoderSetup { filter: 3, ..EncoderSetup::default() }).unwrap();
    run_moves(&mut machine);
    let snapshot = machine.feedback().unwrap();
    assert_eq!(&snapshot.steps[..2], &[60, -50]);
    eprintln!("{snapshot:?}");
    for c in 0..2 {
        let ideal = machine.bus().link().target().plant().encoder(c).ideal_count();
        assert_eq!(i64::from(snapshot.counts[c]), ideal, "channel {c}: {snapshot:?}");
        assert_eq!(machine.encoder_errors(c).unwrap(), (false, 0));
    }
}

fn wheel_plant() -> Plant {
    Plant::new(
        PlantConfig {
            drives: vec![DriveConfig::default(); 2],
            channels: vec![],
            probe: None,
            hand_wheel: Some(HandWheelConfig { rest_phase: 0, bounce: Some(Bounce { extra: 2, within: 20 }) }),
        },
        2,
    )
    .unwrap()
}

fn jog_setup() -> JogSetup {
    JogSetup {
        axis: 0,
        multiplier: JogMultiplier::X10,
        follow: true,
        scale: Increment::from_num(1),
        vmax: Increment::from_num(4),
        accel: Increment::from_num(0.25),
        window: 100,
    }
}

#[test]
fn rtl_jog_follows_the_wheel() {
    let mut machine = connect(finestep_cosim::RtlPins::new(), wheel_plant());
    let axis = AxisSetup { step_len: 20, step_space: 20, dir_setup: 10, dir_hold: 10, ..AxisSetup::default() };
    machine.configure_axis(0, &axis).unwrap();
    machine.enable_axes(0x1).unwrap();
    machine.set_period(2000).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine.configure_hand_wheel(9, 3).unwrap();
    let setup = jog_setup();
    machine.configure_jog(&setup).unwrap();
    machine.enable_jog(&setup, true).unwrap();
    machine.bus().wait(100).unwrap();
    assert!(machine.jog().unwrap().engaged, "{:?}", machine.jog().unwrap());
    machine.bus().link_mut().target_mut().plant_mut().hand_wheel_mut().unwrap().turn(7, 400).unwrap();
    machine.bus().wait(300_000).unwrap();
    let jog = machine.jog().unwrap();
    assert_eq!(machine.hand_wheel().unwrap().detents, 7);
    assert_eq!((jog.remaining, jog.velocity), (0, Increment::ZERO), "{jog:?}");
    assert_eq!(machine.positions().unwrap().steps[0], 70);
    machine.bus().link_mut().target_mut().plant_mut().hand_wheel_mut().unwrap().turn(-3, 400).unwrap();
    machine.bus().wait(300_000).unwrap();
    assert_eq!(machine.positions().unwrap().steps[0], 40);
    assert_eq!(machine.bus().link().target().plant().drive(0).commanded(), 40);
    machine.enable_jog(&setup, false).unwrap();
    machine.bus().wait(10_000).unwrap();
    assert!(!machine.jog().unwrap().engaged);
}
