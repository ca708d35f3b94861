//! The chip over SPI, RTL and model in lockstep, with the plant on its pins: the machine
//! the feedback and jog tests share (4 axes configured, period `PERIOD`, start level 4).

#![allow(dead_code)]

use finestep_cosim::{PlantLoop, TopLockstep};
use finestep_host::{AxisSetup, Machine, PinHost, PinTiming, SpiBus};
use finestep_model::DriveTiming;
use finestep_plant::Plant;

pub type Chip = Machine<SpiBus<PinHost<PlantLoop<TopLockstep>>>>;

pub const PERIOD: u32 = 2000;

/// The period of the digit-serial chip: a multiple of its round R = 32.
pub const PERIOD_SERIAL: u32 = 2048;

/// A connected machine named `name` (its waveform and logs) with `plant` on the pins.
pub fn connect(name: &str, plant: Plant) -> Chip {
    connect_to(TopLockstep::motion(name), plant, PERIOD)
}

/// The same with the digit-serial chip (`TopLockstep::motion_serial`: the CPLD's step
/// engine and the MAX II's storage shapes), period `PERIOD_SERIAL`.
pub fn connect_serial(name: &str, plant: Plant) -> Chip {
    connect_to(TopLockstep::motion_serial(name), plant, PERIOD_SERIAL)
}

fn connect_to(chip: TopLockstep, plant: Plant, period: u32) -> Chip {
    let mut host = PinHost::new(PlantLoop::new(chip, plant), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(8).unwrap();
    let mut machine = Machine::connect(SpiBus::new(host, 4)).unwrap();
    let axis = AxisSetup { timing: DriveTiming::new(20, 20, 10, 10), ..AxisSetup::default() };
    for i in 0..machine.caps().n_axes {
        machine.configure_axis(i, &axis).unwrap();
    }
    machine.enable_axes(0xF).unwrap();
    machine.set_period(period).unwrap();
    machine.set_start_level(4).unwrap();
    machine.clear_faults_and_errors().unwrap();
    machine
}

pub fn plant_of(machine: &Chip) -> &Plant {
    machine.bus_ref().link().target().plant()
}

/// Turns the plant's hand wheel by `detents`, one edge every `cycles_per_edge`.
pub fn turn(machine: &mut Chip, detents: i64, cycles_per_edge: u64) {
    let wheel = machine.bus().link_mut().target_mut().plant_mut().hand_wheel_mut().unwrap();
    wheel.turn(detents, cycles_per_edge).unwrap();
}
