//! The chip in a closed loop with a simulated machine: [`PlantLoop`] puts a
//! [`Plant`] (drives, encoders and gratings, a probe, a hand wheel) on the feedback pins
//! of any [`PinTarget`] (the lockstep pair, the RTL or the model alone) and is itself a
//! `PinTarget`, so the host driver runs on it unchanged: the host's pins come from the
//! host, the feedback pins from the plant (ORed with any the caller drives itself), and
//! the plant sees every step-pin change of the chip on the cycle it happens.

use finestep_host::pins::layout::{
    IN_ENC_A0, IN_ENC_B0, IN_ENC_Z0, IN_MPG_A, IN_MPG_B, IN_PROBE, OUT_PIN_A0, OUT_PIN_B0,
};
use finestep_host::{BusError, PinTarget};
use finestep_plant::{Plant, PlantPins};

/// Packs the plant's pins into the chip's input word.
pub fn pack_plant_pins(pins: &PlantPins) -> u64 {
    u64::from(pins.enc_a) << IN_ENC_A0
        | u64::from(pins.enc_b) << IN_ENC_B0
        | u64::from(pins.enc_z) << IN_ENC_Z0
        | u64::from(pins.probe) << IN_PROBE
        | u64::from(pins.mpg_a) << IN_MPG_A
        | u64::from(pins.mpg_b) << IN_MPG_B
}

/// A chip with a plant on its pins.
pub struct PlantLoop<T> {
    target: T,
    plant: Plant,
    cycle: u64,
    step_pins: u64,
}

impl<T: PinTarget> PlantLoop<T> {
    /// `target` and `plant` both at cycle 0.
    pub fn new(target: T, plant: Plant) -> PlantLoop<T> {
        let step_pins = target.outputs();
        PlantLoop { target, plant, cycle: 0, step_pins }
    }

    /// The plant.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The plant, to script the hand wheel.
    pub fn plant_mut(&mut self) -> &mut Plant {
        &mut self.plant
    }

    /// The chip.
    pub fn target(&self) -> &T {
        &self.target
    }

    /// Cycles run.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// Hands the chip's step pins to the plant when they changed.
    fn feed_plant(&mut self) {
        let outputs = self.target.outputs();
        let changed = (outputs ^ self.step_pins) & 0xFFFF;
        if changed == 0 {
            return;
        }
        self.step_pins = outputs;
        for axis in 0..self.plant.drives().len() {
            let (a, b) = (OUT_PIN_A0 + axis as u32, OUT_PIN_B0 + axis as u32);
            if (changed >> a | changed >> b) & 1 != 0 {
                self.plant.set_step_pins(self.cycle, axis, outputs >> a & 1 == 1, outputs >> b & 1 == 1);
            }
        }
    }
}

impl<T: PinTarget> PinTarget for PlantLoop<T> {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        let end = self.cycle + cycles;
        while self.cycle < end {
            // The plant's pins hold until its next change; the chip runs to that or to its
            // own next output change, whichever comes first.
            let until = self.plant.next_change().map_or(end, |t| t.min(end));
            let pins = inputs | pack_plant_pins(&self.plant.pins());
            let ran = self.target.drive_to_change(pins, until - self.cycle)?;
            self.cycle += ran;
            self.plant.advance_to(self.cycle);
            self.feed_plant();
        }
        Ok(())
    }

    fn outputs(&self) -> u64 {
        self.target.outputs()
    }

    fn pin_timing(&self) -> Option<finestep_interface::pin_timing::PinTimingReport> {
        self.target.pin_timing()
    }
}
