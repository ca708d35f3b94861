//! The step pins' drive timing measured on a simulated chip: [`PinMonitor`] wraps any
//! [`PinTarget`] whose configuration it can read ([`ChipConfig`]: the lockstep pair, the
//! model alone) and hands every change of every axis's step and direction pins, on the
//! cycle it happens, to the one pin-timing check ([`StepDirMonitor`]), against the drive
//! timing the chip's registers hold at that moment (the timing the host wrote). With the
//! lockstep pair the pins are the Verilated RTL's (equal to the model's, compared every
//! clock); with the model alone, the per-clock model's. Every clock is simulated either
//! way: the target runs to each output change ([`PinTarget::drive_to_change`]).

use finestep_host::pins::layout::{OUT_PIN_A0, OUT_PIN_B0};
use finestep_host::{BusError, PinTarget};
use finestep_interface::pin_timing::{AxisPinTiming, PinTimingReport, StepDirMonitor};
use finestep_interface::{invert, out_mode};
use finestep_model::{AxisConfig, Top};

use crate::{ModelPins, PlantLoop, TopLockstep};

/// A simulated chip whose configuration can be read as its registers hold it: the
/// model's view of the chip (with the lockstep pair, equal to the RTL's: every register
/// read is compared).
pub trait ChipConfig {
    /// The model chip whose registers and build parameters are read.
    fn model_chip(&self) -> &Top;
    /// Axes the chip has.
    fn n_axes(&self) -> usize {
        self.model_chip().params().n_axes
    }
    /// The core clock, Hz.
    fn clock_hz(&self) -> u32 {
        self.model_chip().params().clock_hz
    }
    /// The settings of `axis` (timing, output mode, inversion) as the registers hold them.
    fn axis_config(&self, axis: usize) -> AxisConfig {
        self.model_chip().registers().axis_config(axis)
    }
}

impl ChipConfig for ModelPins {
    fn model_chip(&self) -> &Top {
        &self.0
    }
}

impl ChipConfig for TopLockstep {
    fn model_chip(&self) -> &Top {
        self.model()
    }
}

impl<T: PinTarget + ChipConfig> ChipConfig for PlantLoop<T> {
    fn model_chip(&self) -> &Top {
        self.target().model_chip()
    }
}

struct Axis {
    monitor: StepDirMonitor,
    /// The output mode and inversion the monitor's levels were read with.
    meaning: Option<(u8, u8)>,
    step_dir: bool,
}

/// A [`PinTarget`] whose step pins are measured every clock (see the module).
pub struct PinMonitor<T> {
    target: T,
    cycle: u64,
    outputs: u64,
    axes: Vec<Axis>,
}

/// Whether output mode `mode` is step/dir (the unnamed fourth value acts as it).
fn is_step_dir(mode: u8) -> bool {
    !matches!(mode, out_mode::UP_DOWN | out_mode::QUADRATURE)
}

impl<T: PinTarget + ChipConfig> PinMonitor<T> {
    /// Measures `target` from now on.
    pub fn new(target: T) -> PinMonitor<T> {
        let axes = (0..target.n_axes())
            .map(|axis| Axis {
                monitor: StepDirMonitor::new(target.axis_config(axis).timing),
                meaning: None,
                step_dir: true,
            })
            .collect();
        let outputs = target.outputs();
        let mut monitor = PinMonitor { target, cycle: 0, outputs, axes };
        for axis in 0..monitor.axes.len() {
            monitor.observe_axis(axis);
        }
        monitor
    }

    /// The target.
    pub fn target(&self) -> &T {
        &self.target
    }

    /// The figures so far.
    pub fn report(&self) -> PinTimingReport {
        PinTimingReport {
            clock_hz: self.target.clock_hz(),
            clocks: self.cycle,
            axes: self
                .axes
                .iter()
                .map(|a| AxisPinTiming { step_dir: a.step_dir, figures: a.monitor.figures() })
                .collect(),
        }
    }

    fn observe_axis(&mut self, axis: usize) {
        let config = self.target.axis_config(axis);
        let a = &mut self.axes[axis];
        let meaning = (config.mode, config.invert);
        if a.meaning != Some(meaning) {
            a.monitor.restart();
            a.meaning = Some(meaning);
        }
        a.monitor.set_timing(config.timing);
        let level = |bit: u32, inverted: u8| (self.outputs >> bit & 1 == 1) ^ (config.invert & inverted != 0);
        let step = level(OUT_PIN_A0 + axis as u32, invert::PIN_A);
        let dir = level(OUT_PIN_B0 + axis as u32, invert::PIN_B);
        if is_step_dir(config.mode) {
            a.monitor.observe(self.cycle, step, dir);
        } else {
            a.step_dir = false;
        }
    }

    /// Hands the axes whose step or direction pin changed to their monitors.
    fn observe(&mut self) {
        let outputs = self.target.outputs();
        let changed = outputs ^ self.outputs;
        self.outputs = outputs;
        for axis in 0..self.axes.len() {
            if (changed >> (OUT_PIN_A0 + axis as u32) | changed >> (OUT_PIN_B0 + axis as u32)) & 1 != 0 {
                self.observe_axis(axis);
            }
        }
    }
}

impl<T: PinTarget + ChipConfig> PinTarget for PinMonitor<T> {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        let mut left = cycles;
        while left > 0 {
            let ran = self.target.drive_to_change(inputs, left)?;
            self.cycle += ran;
            left -= ran;
            self.observe();
        }
        Ok(())
    }

    fn drive_to_change(&mut self, inputs: u64, cycles: u64) -> Result<u64, BusError> {
        let ran = self.target.drive_to_change(inputs, cycles)?;
        self.cycle += ran;
        self.observe();
        Ok(ran)
    }

    fn outputs(&self) -> u64 {
        self.target.outputs()
    }

    fn pin_timing(&self) -> Option<PinTimingReport> {
        Some(self.report())
    }
}

impl<T: PinTarget + ChipConfig> ChipConfig for PinMonitor<T> {
    fn model_chip(&self) -> &Top {
        self.target.model_chip()
    }
}
