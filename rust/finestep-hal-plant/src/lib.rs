//! The closed-loop machine of `finestep-plant` ([`PlantConfig::lagging`]: drives lagging
//! their step pins, a linear grating on each) as a LinuxCNC HAL component, `fsplant`
//! (`linuxcnc/fsplant.c`), so that LinuxCNC's own software `stepgen` drives the very plant
//! the simulated finestep chip drives (`finestep sim-chip --lag-clocks`): one plant
//! implementation, two step generators, and the following errors side by side
//! (docs/linuxcnc.md#closed-loop).
//!
//! # Time, exactly
//!
//! The plant counts core clock cycles. Base slot `i` (one call of stepgen's
//! `make-pulses`, framed by [`StepgenPlant::gate`] and [`StepgenPlant::sample`]) stands for
//! the cycles `i * B .. (i + 1) * B` (`B` = the base period in clocks), and servo period
//! `k` owns slots `k * M .. (k + 1) * M` (`M` = servo period / base period):
//! [`StepgenPlant::write`] releases a period's slots, [`StepgenPlant::read`] runs the plant
//! to the boundary `k * M * B` over the slots sampled and gives the encoder counts there.
//! `fsplant.c` makes every call from the servo thread (LinuxCNC's uspace build serialises
//! its threads without a real-time kernel, so a base thread could not wait for the servo
//! thread), so the waits below never wait there; they hold if the calls come from two
//! threads (the tests), and each servo period then runs exactly `M` base periods.
//!
//! A wait longer than [`SYNC_TIMEOUT`] lets the waiting thread go on and is counted
//! ([`StepgenPlant::sync_errors`]): the run's figures are then not exact, and the
//! comparison fails.
//!
//! # Example
//!
//! ```
//! use finestep_hal_plant::StepgenPlant;
//!
//! // One axis, tau 1 000 clocks, 1 count a step; base 500 clocks, 4 slots a servo period.
//! let plant = StepgenPlant::new(1, 1_000, 1, 500, 4).unwrap();
//! let mut counts = [0i64; 1];
//! for period in 0..50 {
//!     plant.read(&mut counts).unwrap();
//!     plant.write();
//!     for slot in 0..4 {
//!         plant.gate().unwrap();
//!         // A step pulse in the first slot of each of the first 10 periods, dir positive.
//!         let step = period < 10 && slot == 0;
//!         plant.sample(u32::from(step) | 0b10);
//!     }
//! }
//! plant.read(&mut counts).unwrap();
//! assert_eq!(counts[0], 10);
//! ```

#![warn(missing_docs)]

pub mod ffi;

use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

use finestep_plant::{CountsPerStep, Plant, PlantConfig, PlantError, LAGGING_SEED};

/// The longest either thread waits for the other, wall time: LinuxCNC's servo period has
/// taken up to 0.85 s on this project's loaded machine.
pub const SYNC_TIMEOUT: Duration = Duration::from_secs(5);

/// What the component cannot do.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The plant refused its configuration.
    #[error("plant: {0}")]
    Plant(#[from] PlantError),
    /// Bad settings.
    #[error("{0}")]
    Config(String),
    /// The other thread did not come within [`SYNC_TIMEOUT`]: the lock is broken.
    #[error("the base and servo threads lost their lockstep (a wait of over {SYNC_TIMEOUT:?})")]
    Sync,
}

/// The shared state of the two threads.
struct Shared {
    plant: Plant,
    /// Slots the base thread may run (the servo periods written, times M).
    released: u64,
    /// Slots sampled.
    sampled: u64,
    /// Slots sampled and not yet applied to the plant: (slot, packed pins) where the
    /// levels changed.
    pending: Vec<(u64, u32)>,
    /// The last levels sampled.
    levels: u32,
    /// Waits that timed out; from the first, neither thread waits.
    sync_errors: u32,
}

/// The plant between LinuxCNC's base and servo threads (see the crate documentation).
pub struct StepgenPlant {
    shared: Mutex<Shared>,
    turn: Condvar,
    axes: usize,
    slot_clocks: u64,
    slots_per_period: u64,
}

impl StepgenPlant {
    /// `axes` axes of [`PlantConfig::lagging`] (a grating on each) with time constant
    /// `tau` clocks and `counts_per_step`; a base period of `slot_clocks` clocks,
    /// `slots_per_period` of them a servo period.
    pub fn new(
        axes: usize,
        tau: u64,
        counts_per_step: u32,
        slot_clocks: u64,
        slots_per_period: u64,
    ) -> Result<StepgenPlant, Error> {
        if axes == 0 || axes > 16 {
            return Err(Error::Config(format!("{axes} axes: 1 to 16")));
        }
        if slot_clocks == 0 || slots_per_period == 0 {
            return Err(Error::Config("the base period and the slots a servo period must not be 0".into()));
        }
        let config = PlantConfig::lagging(axes, axes, tau, CountsPerStep::integer(counts_per_step)?);
        let plant = Plant::new(config, LAGGING_SEED)?;
        Ok(StepgenPlant {
            shared: Mutex::new(Shared {
                plant,
                released: 0,
                sampled: 0,
                pending: Vec::new(),
                levels: 0,
                sync_errors: 0,
            }),
            turn: Condvar::new(),
            axes,
            slot_clocks,
            slots_per_period,
        })
    }

    fn lock(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Waits until `ready` holds, at most [`SYNC_TIMEOUT`]; a timeout breaks the lock.
    fn wait_for<'a>(
        &'a self,
        mut shared: MutexGuard<'a, Shared>,
        ready: impl Fn(&Shared) -> bool,
    ) -> (MutexGuard<'a, Shared>, Result<(), Error>) {
        let (guard, timeout) = self
            .turn
            .wait_timeout_while(shared, SYNC_TIMEOUT, |s| !ready(s))
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        shared = guard;
        if timeout.timed_out() && !ready(&shared) {
            shared.sync_errors += 1;
            eprintln!(
                "fsplant: a wait of over {SYNC_TIMEOUT:?} (slots released {}, sampled {}): the threads lost their lockstep",
                shared.released, shared.sampled
            );
            self.turn.notify_all();
            return (shared, Err(Error::Sync));
        }
        (shared, Ok(()))
    }

    /// The base thread, before `stepgen.make-pulses`: waits until the servo thread has
    /// run the period this slot belongs to.
    pub fn gate(&self) -> Result<(), Error> {
        let shared = self.lock();
        self.wait_for(shared, |s| s.sampled < s.released).1
    }

    /// The base thread, after `stepgen.make-pulses`: the step pins of this slot, axis
    /// `a`'s step at bit `2a` and its direction at bit `2a + 1` (1 = positive, the
    /// plant's convention; stepgen's `dir` is high for negative steps, `fsplant.c`
    /// inverts it).
    pub fn sample(&self, levels: u32) {
        let mut shared = self.lock();
        let slot = shared.sampled;
        if levels != shared.levels {
            shared.levels = levels;
            shared.pending.push((slot, levels));
        }
        shared.sampled += 1;
        if shared.sampled >= shared.released {
            self.turn.notify_all();
        }
    }

    /// The servo thread, first: waits for the base thread's slots of the last period,
    /// runs the plant to the period's boundary and writes every grating's count there.
    pub fn read(&self, counts: &mut [i64]) -> Result<(), Error> {
        let shared = self.lock();
        let (mut shared, result) = self.wait_for(shared, |s| s.sampled >= s.released);
        let Shared { plant, pending, .. } = &mut *shared;
        for (slot, levels) in pending.drain(..) {
            let cycle = slot * self.slot_clocks;
            for axis in 0..self.axes {
                plant.set_step_pins(cycle, axis, levels >> (2 * axis) & 1 == 1, levels >> (2 * axis + 1) & 1 == 1);
            }
        }
        let boundary = shared.sampled * self.slot_clocks;
        shared.plant.advance_to(boundary);
        for (channel, count) in counts.iter_mut().enumerate().take(self.axes) {
            *count = shared.plant.encoder(channel).decoded().count;
        }
        result
    }

    /// The servo thread, last (after `stepgen.update-freq`): releases the next period's
    /// slots to the base thread.
    pub fn write(&self) {
        let mut shared = self.lock();
        shared.released = shared.sampled + self.slots_per_period;
        self.turn.notify_all();
    }

    /// Waits that timed out (0 in an exact run).
    pub fn sync_errors(&self) -> u32 {
        self.lock().sync_errors
    }

    /// Axis `axis`'s drive: its commanded position in steps (the step pulses it saw).
    pub fn commanded(&self, axis: usize) -> i64 {
        self.lock().plant.drive(axis).commanded()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step of 1 count every other slot from period 1 on; the count at each boundary.
    #[test]
    fn each_servo_period_runs_exactly_its_slots_from_two_threads() {
        let plant = std::sync::Arc::new(StepgenPlant::new(2, 50, 2, 100, 10).unwrap());
        let base = {
            let plant = plant.clone();
            std::thread::spawn(move || {
                for slot in 0..200u64 {
                    plant.gate().unwrap();
                    // Axis 0 steps up on even slots (a one-slot pulse), axis 1 down on slot 55.
                    let step0 = u32::from(slot % 2 == 0 && slot >= 10);
                    let step1 = u32::from(slot == 55) << 2;
                    plant.sample(step0 | 0b10 | step1);
                }
            })
        };
        let mut counts = [0i64; 2];
        let mut seen = Vec::new();
        for _ in 0..=20 {
            plant.read(&mut counts).unwrap();
            seen.push(counts);
            plant.write();
        }
        base.join().unwrap();
        // Period k's boundary is slot 10 k; steps in slots 10, 12, ... (5 a period),
        // seen by the drive a cycle later and by the lagging grating some clocks after.
        assert_eq!(seen[1], [0, 0]);
        assert_eq!(plant.commanded(0), 95);
        assert_eq!(plant.commanded(1), -1);
        assert_eq!(seen[20][1], -2, "the down step, settled");
        assert!(seen[20][0] > 2 * 90 && seen[20][0] <= 2 * 95, "{:?}", seen[20]);
        assert_eq!(plant.sync_errors(), 0);
    }

    #[test]
    fn a_thread_that_does_not_come_is_counted() {
        let plant = StepgenPlant::new(1, 50, 1, 100, 10).unwrap();
        plant.write();
        // The base thread never samples: the read times out and goes on.
        let mut counts = [0i64];
        assert!(matches!(plant.read(&mut counts), Err(Error::Sync)));
        assert_eq!(plant.sync_errors(), 1);
    }

    #[test]
    fn bad_settings_are_refused() {
        assert!(StepgenPlant::new(0, 50, 1, 100, 10).is_err());
        assert!(StepgenPlant::new(3, 0, 1, 100, 10).is_err());
        assert!(StepgenPlant::new(3, 50, 0, 100, 10).is_err());
        assert!(StepgenPlant::new(3, 50, 1, 0, 10).is_err());
    }
}
