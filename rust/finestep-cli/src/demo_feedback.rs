//! Demo part 3, the feedback side of seed 000 with a simulated machine on the chip's
//! pins (drives that lag the step pins, gratings on the slides, a probe, a hand wheel):
//! - a grating measurement pass: the table (Z) traverses the roller while the probe
//!   touches marks on it; each touch latches both gratings and every axis's step
//!   position on one clock, and the table prints them with the following error they
//!   reveal;
//! - a hand-wheel jog: the wheel (100 detents a turn, contact bounce) is turned in
//!   bursts at x10 and x100; the FPGA's jog generator moves X after it within its
//!   velocity and acceleration limits and lands on every detent exactly.
//!
//! The chip is the Verilated RTL in lockstep with the reference model, every pin on
//! every clock; the host driver talks to it over SPI at its pins.

use anyhow::{bail, Context};
use finestep_cosim::{PlantLoop, TopLockstep};
use finestep_host::stream::{self, StreamEvent};
use finestep_host::{Bus, EncoderSetup, JogMultiplier, JogSetup, PinTarget};
use finestep_model::{Increment, PeriodRecord};
use finestep_planner::config::Resolved;
use finestep_planner::MachineConfig;
use finestep_plant::{
    Bounce, ChannelConfig, CountsPerStep, DriveConfig, EncoderConfig, HandWheel, HandWheelConfig, Mechanics, Plant,
    PlantConfig, ProbeConfig,
};

use crate::machine_setup::{self, Chip};

/// X (wheel slide, 1000 steps/mm) and Z (table, 400 steps/mm) as in part 1, in record
/// slots 0 and 1.
const STEPS_PER_MM: [f64; 2] = [1000.0, 400.0];
/// Grating resolution: X 1 um, Z 0.5 um (x4 counts).
const GRATING_COUNTS_PER_MM: [f64; 2] = [1000.0, 2000.0];
/// Probe marks along the roller, Z in mm.
const MARKS_MM: [f64; 4] = [2.0, 4.0, 6.0, 8.0];
/// The drives' time constant: 1 ms.
const DRIVE_TAU_CLOCKS: u64 = 50_000;

fn plant() -> anyhow::Result<Plant> {
    let drive = DriveConfig { mechanics: Mechanics::Lag { tau: DRIVE_TAU_CLOCKS }, ..DriveConfig::default() };
    let marks = MARKS_MM.iter().map(|z| {
        let steps = (z * STEPS_PER_MM[1]).round() as i64;
        steps..=steps + 20
    });
    let config = PlantConfig {
        drives: vec![drive, drive],
        channels: vec![
            ChannelConfig { axis: 0, encoder: EncoderConfig::linear_grating(CountsPerStep::integer(1)?, None) },
            ChannelConfig { axis: 1, encoder: EncoderConfig::linear_grating(CountsPerStep::integer(5)?, None) },
        ],
        probe: Some(ProbeConfig {
            axis: 1,
            counts_per_step: CountsPerStep::integer(1)?,
            touching: marks.collect(),
            active_high: true,
        }),
        hand_wheel: Some(HandWheelConfig { rest_phase: 0, bounce: Some(Bounce { extra: 3, within: 2_000 }) }),
    };
    Ok(Plant::new(config, 0xFEED)?)
}

/// The chip with the plant on its pins, configured as the demo's machine (T = 2 ms, X
/// and Z) resolved against its CAPS and clock, with the gratings and the hand wheel set up.
fn connect<T: PinTarget>(target: T) -> anyhow::Result<(Chip<PlantLoop<T>>, MachineConfig, Resolved)> {
    let mut machine = machine_setup::open(PlantLoop::new(target, plant()?))?;
    let core = machine_setup::chip_limits(&machine.caps());
    let (config, resolved) = machine_setup::resolve(machine_setup::demo_config(&STEPS_PER_MM), core, "<demo part 3>")?;
    machine_setup::configure(&mut machine, &resolved)?;
    for channel in 0..2 {
        machine.configure_encoder(channel, &EncoderSetup { filter: 3, ..EncoderSetup::default() })?;
    }
    // 20 us of contact bounce: sample every 10 us, 4 samples.
    let prescale = ((10e-6 * resolved.clock_hz).round() as u32).saturating_sub(1);
    machine.configure_hand_wheel(u16::try_from(prescale).context("the hand wheel's sample prescaler")?, 4)?;
    Ok((machine, config, resolved))
}

pub fn run() -> anyhow::Result<()> {
    println!();
    println!("finestep demo, part 3: feedback with a simulated machine on the pins (drives lagging 1 ms,");
    println!("  gratings X 1 um and Z 0.5 um, a probe, a hand wheel with contact bounce); RTL and model in lockstep");
    let (mut machine, config, resolved) = connect(TopLockstep::motion("demo-feedback"))?;
    grating_pass(&mut machine, &config, &resolved)?;
    jog(&mut machine, &resolved)?;
    Ok(())
}

/// Z traverses 10 mm at 40 mm/s; the probe touches four marks on the way.
fn grating_pass<T: PinTarget>(
    machine: &mut Chip<PlantLoop<T>>,
    config: &MachineConfig,
    resolved: &Resolved,
) -> anyhow::Result<()> {
    // Z is record slot 1.
    let records: Vec<PeriodRecord> = machine_setup::plan_line(config, [0.0, 10.0, 0.0, 0.0], 40.0)?;
    machine.arm_probe(true, 2)?;
    println!(
        "  grating pass: Z 0 -> 10 mm at 40 mm/s, {} periods of {} ms; probe hits:",
        records.len(),
        resolved.period_s * 1e3
    );
    println!("    mark   time ms   Z steps   Z by steps mm   Z grating mm   lag um   X grating um");
    // The host keeps the FIFO topped up and polls the probe while it waits.
    let config = machine_setup::stream_config(resolved);
    let config =
        stream::StreamConfig { poll_clocks: (resolved.period_clocks / 4).into(), prefill: 4 * config.burst, ..config };
    let mut hits = Vec::new();
    let report = stream::run(machine, records.iter().copied(), &config, |machine, event| {
        if event != StreamEvent::Waited {
            return Ok(());
        }
        if let Some(hit) = machine.probe_hit()? {
            let z_steps = f64::from(hit.steps[1]) / STEPS_PER_MM[1];
            let z_grating = f64::from(hit.counts[1]) / GRATING_COUNTS_PER_MM[1];
            let x_grating = f64::from(hit.counts[0]) / GRATING_COUNTS_PER_MM[0];
            println!(
                "    {:>4} {:>9.3} {:>9} {:>15.4} {:>14.4} {:>8.1} {:>14.1}",
                hits.len() + 1,
                f64::from(hit.time) / resolved.clock_hz * 1e3,
                hit.steps[1],
                z_steps,
                z_grating,
                (z_steps - z_grating) * 1e3,
                x_grating * 1e3
            );
            hits.push(hit);
            machine.arm_probe(true, 2)?;
        }
        Ok(())
    })?;
    if report.stream.underruns != 0 {
        bail!("{} FIFO underruns", report.stream.underruns);
    }
    if hits.len() != MARKS_MM.len() {
        bail!("{} probe hits, expected {}", hits.len(), MARKS_MM.len());
    }
    // The grating saw each mark where the plant put it: the probe follows the same
    // (lagging) table position the grating measures.
    for (hit, mark) in hits.iter().zip(MARKS_MM) {
        let z_grating = f64::from(hit.counts[1]) / GRATING_COUNTS_PER_MM[1];
        if (z_grating - mark).abs() > 0.01 {
            bail!("probe at Z = {z_grating} mm by the grating, the mark is at {mark} mm");
        }
    }
    // The lag decays as exp(-t / tau): after 30 tau it is below 2^-32 steps, at rest.
    machine.bus().wait(30 * DRIVE_TAU_CLOCKS)?;
    let snapshot = machine.feedback()?;
    let ideal = machine.bus().link().target().plant().encoder(1).ideal_count();
    println!(
        "    at rest: Z {} steps = {:.4} mm, grating {} counts = {:.4} mm (the plant's ideal count: {ideal})",
        snapshot.steps[1],
        f64::from(snapshot.steps[1]) / STEPS_PER_MM[1],
        snapshot.counts[1],
        f64::from(snapshot.counts[1]) / GRATING_COUNTS_PER_MM[1]
    );
    if i64::from(snapshot.counts[1]) != ideal {
        bail!("Z grating reads {}, the plant is at {ideal}", snapshot.counts[1]);
    }
    machine.set_control(false, false, true)?;
    Ok(())
}

/// The hand wheel moves X through the jog: bursts at x10 and x100, both ways.
fn jog<T: PinTarget>(machine: &mut Chip<PlantLoop<T>>, resolved: &Resolved) -> anyhow::Result<()> {
    let mut setup = JogSetup {
        axis: 0,
        multiplier: JogMultiplier::X10,
        follow: true,
        scale: Increment::from_num(1),   // 1 um of X per detent at x1
        vmax: Increment::from_num(20),   // 10 mm/s
        accel: Increment::from_num(0.4), // 100 mm/s^2
        window: 200,                     // drop mode: at most 0.2 mm behind the wheel
    };
    machine.configure_jog(&setup)?;
    machine.enable_jog(&setup, true)?;
    let start = machine.positions()?.steps[0];
    println!("  hand-wheel jog of X (1 um a detent at x1; vmax 10 mm/s, accel 100 mm/s^2):");
    println!(
        "    turn   detents/s   multiplier   mode     wheel detents   dropped   X target um   X at rest um   peak mm/s"
    );
    // (detents, rate, multiplier, follow): the last turn asks for 40 mm/s in drop mode.
    let turns: [(i64, u64, JogMultiplier, bool); 4] = [
        (12, 200, JogMultiplier::X10, true),
        (-5, 200, JogMultiplier::X10, true),
        (3, 100, JogMultiplier::X100, true),
        (-4, 400, JogMultiplier::X100, false),
    ];
    let mut target = 0i64;
    for (index, (detents, rate, multiplier, follow)) in turns.into_iter().enumerate() {
        if (multiplier, follow) != (setup.multiplier, setup.follow) {
            setup.multiplier = multiplier;
            setup.follow = follow;
            machine.enable_jog(&setup, true)?;
        }
        let dropped_before = machine.jog()?.dropped;
        let factor = i64::from(multiplier.factor());
        let per_edge = HandWheel::cycles_per_edge(resolved.clock_hz as u64, rate);
        let wheel = machine.bus().link_mut().target_mut().plant_mut().hand_wheel_mut().expect("the plant has a wheel");
        wheel.turn(detents, per_edge)?;
        let mut peak = Increment::ZERO;
        loop {
            machine.bus().wait(50_000)?;
            let state = machine.jog()?;
            peak = peak.max(state.velocity.abs());
            let loop_ = machine.bus().link().target();
            let wheel_busy = loop_.plant().hand_wheel().expect("wheel").script_end() > loop_.cycle();
            if !wheel_busy && state.remaining == 0 && state.velocity == Increment::ZERO {
                break;
            }
        }
        let wheel = machine.hand_wheel()?;
        let dropped = i64::from(machine.jog()?.dropped.wrapping_sub(dropped_before));
        target += (detents - detents.signum() * dropped) * factor;
        let at = machine.positions()?.steps[0] - start;
        println!(
            "    {:>4} {:>11} {:>12}   {:<6} {:>15} {:>9} {:>13} {:>14} {:>11.2}",
            index + 1,
            rate,
            format!("x{factor}"),
            if follow { "follow" } else { "drop" },
            wheel.detents,
            dropped,
            target,
            at,
            peak.to_num::<f64>() / resolved.axes[0].steps_per_unit / resolved.period_s
        );
        if i64::from(at) != target {
            bail!("X at {at} steps after turn {}, the wheel asks for {target}", index + 1);
        }
        if wheel.illegal {
            bail!("the hand wheel's filter let contact bounce through");
        }
    }
    machine.enable_jog(&setup, false)?;
    machine.bus().wait(200_000)?;
    if machine.jog()?.engaged {
        bail!("the jog did not disengage");
    }
    println!("    every followed detent landed exactly; the jog disengaged at rest; no illegal transition through the bounce");
    Ok(())
}
