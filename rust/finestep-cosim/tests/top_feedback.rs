//! The feedback blocks at the chip's pins with the plant in the loop: streamed motion
//! drives lagging axes whose encoders and gratings feed the counters back; the hand wheel
//! moves an axis through the jog; faults outside the filter's specification are flagged.

use finestep_cosim::{PlantLoop, TopLockstep};
use finestep_host::stream::{stream, wait_idle, StreamConfig};
use finestep_host::{AxisSetup, Bus, EncoderSetup, Machine, PinHost, PinTarget, PinTiming, SpiBus};
use finestep_model::PeriodRecord;
use finestep_plant::{
    ChannelConfig, CountsPerStep, DriveConfig, EncoderConfig, Mechanics, Plant, PlantConfig,
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
