//! Lockstep co-simulation: the Verilated core and the reference model get the same
//! inputs and must produce the same outputs, every pin and every status bit, on every
//! clock.
//!
//! Both sides run the same chunks of cycles with constant inputs and report an event for
//! every cycle whose outputs changed; equal event lists mean equal outputs on every
//! cycle, at the cost of comparing only the cycles where something happens. On the first
//! difference, [`Mismatch`] names the cycle, the signal, the expected (model) and actual
//! (RTL) values and the last events of both, and a waveform window of the RTL around it
//! is written to `target/cosim-failures/<test name>.vcd`.
//!
//! ```no_run
//! use finestep_cosim::{Harness, ModelPath};
//! use finestep_model::{CoreInputs, PeriodRecord};
//! let mut harness = Harness::new("doc_example", ModelPath::PerClock);
//! let mut inputs = CoreInputs { run: true, period_clocks: 100, ..Default::default() };
//! harness.feed(&mut inputs, std::iter::repeat(PeriodRecord::default()).take(10)).unwrap();
//! ```

pub mod gantry_pair;
mod mismatch;
pub mod panel_chip;
pub mod pin_monitor;
pub mod plant_loop;
pub mod top_lockstep;

use std::collections::VecDeque;
use std::path::PathBuf;

use finestep_model::{pins, ChunkEnd, Core, CoreInputs, CoreOutputs, Event, PeriodRecord, MAX_AXES};
use finestep_rtl_sys::Rtl;
pub use finestep_rtl_sys::{TopVariant, TraceDepth};

pub use gantry_pair::GantryPair;
pub use mismatch::{describe_difference, Mismatch, WaveformError};
pub use panel_chip::{
    acknowledge_power_up, panel_chip_params, read_display, DisplayReading, GantryPlant, PanelChipLockstep,
    PanelChipMismatch, PanelMachine, SlaveLoad,
};
pub use pin_monitor::{ChipConfig, PinMonitor};
pub use plant_loop::PlantLoop;
pub use top_lockstep::{rtl_top_params, rtl_top_params_of, ModelPins, RtlPins, TopLockstep, TopMismatch};

/// Which model path runs against the RTL.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelPath {
    /// The model's per-clock `step()`: the definition.
    PerClock,
    /// The model's event-driven fast path, proven identical to the per-clock path.
    Fast,
}

/// How many events of each side a mismatch report shows.
const HISTORY: usize = 12;
/// Waveform window before the mismatch, in cycles.
const WINDOW_BEFORE: u64 = 256;
/// Waveform window after the mismatch, in cycles.
const WINDOW_AFTER: u64 = 16;

/// The RTL and the model side by side.
pub struct Harness {
    name: String,
    path: ModelPath,
    rtl: Rtl,
    model: Core,
    /// Every chunk run since reset: its inputs and the cycles it ran (for waveform replay).
    log: Vec<(CoreInputs, u64)>,
    rtl_events: Vec<Event>,
    model_events: Vec<Event>,
    history: VecDeque<Event>,
    outputs: CoreOutputs,
    pulses: [u64; MAX_AXES],
}

impl Harness {
    /// Both sides fresh out of reset, without the gantry block (the gantry inputs are
    /// ignored). `name` names the waveform of a failure.
    pub fn new(name: &str, path: ModelPath) -> Harness {
        Harness::for_params(name, path, finestep_rtl_sys::params())
    }

    /// Both sides fresh out of reset, with the digit-serial step engine
    /// ([`finestep_rtl_sys::serial_params`]).
    pub fn serial(name: &str, path: ModelPath) -> Harness {
        Harness::for_params(name, path, finestep_rtl_sys::serial_params())
    }

    /// Both sides fresh out of reset, with the gantry block.
    pub fn with_gantry(name: &str, path: ModelPath) -> Harness {
        Harness::for_params(name, path, finestep_rtl_sys::gantry_params())
    }

    /// Both sides fresh out of reset, with the point-by-point comparison interpolator
    /// ([`finestep_rtl_sys::core_pbp_params`]; the RTL side is the traced Verilation).
    pub fn with_pbp(name: &str, path: ModelPath) -> Harness {
        Harness::for_params(name, path, finestep_rtl_sys::core_pbp_params())
    }

    /// Both sides fresh out of reset, with the point-by-point comparison interpolator and
    /// the step engine ([`finestep_rtl_sys::core_pbp_shared_params`]; traced RTL).
    pub fn with_pbp_shared(name: &str, path: ModelPath) -> Harness {
        Harness::for_params(name, path, finestep_rtl_sys::core_pbp_shared_params())
    }

    fn for_params(name: &str, path: ModelPath, params: finestep_model::CoreParams) -> Harness {
        let rtl = Rtl::for_params(&params, false);
        let model = Core::new(params);
        let outputs = model.outputs();
        // Change lists are only equal outputs if both sides start equal.
        assert_eq!(rtl.outputs(), outputs, "RTL and model differ out of reset");
        Harness {
            name: name.to_string(),
            path,
            rtl,
            model,
            log: Vec::new(),
            rtl_events: Vec::new(),
            model_events: Vec::new(),
            history: VecDeque::with_capacity(HISTORY),
            outputs,
            pulses: [0; MAX_AXES],
        }
    }

    /// Clock edges since reset.
    pub fn cycle(&self) -> u64 {
        self.model.cycle()
    }

    /// The outputs in the current cycle (equal on both sides).
    pub fn outputs(&self) -> CoreOutputs {
        self.outputs
    }

    /// Rising edges seen on each axis's pin A since reset (steps, in step/dir mode).
    pub fn pulses(&self) -> [u64; MAX_AXES] {
        self.pulses
    }

    /// Replay everything run so far on a traced RTL and write the waveform of cycles
    /// `from..to` to `path` (VCD, or FST with the -sys crate's feature `fst`).
    pub fn write_waveform(
        &self,
        path: &std::path::Path,
        depth: TraceDepth,
        from: u64,
        to: u64,
    ) -> Result<(), WaveformError> {
        let mut rtl = Rtl::for_params(&self.model.params(), true);
        let mut scratch = Vec::new();
        let mut tracing = false;
        for (inputs, cycles) in &self.log {
            let mut left = *cycles;
            while left > 0 && rtl.cycle() < to {
                if !tracing && rtl.cycle() >= from {
                    rtl.trace_open(path, depth).map_err(WaveformError::at(path))?;
                    tracing = true;
                }
                let stop = if tracing { to } else { from };
                scratch.clear();
                let end = rtl.run_chunk(inputs, left.min(stop - rtl.cycle()), &mut scratch);
                left -= end.cycles;
                if end.consumed || end.cycles == 0 {
                    break;
                }
            }
        }
        rtl.trace_close();
        Ok(())
    }

    /// The reference model (read-only).
    pub fn model(&self) -> &Core {
        &self.model
    }

    /// Up to `max_cycles` cycles with constant `inputs` on both sides, stopping after a
    /// consumed record; every cycle's outputs compared.
    pub fn run_chunk(&mut self, inputs: &CoreInputs, max_cycles: u64) -> Result<ChunkEnd, Box<Mismatch>> {
        self.rtl_events.clear();
        self.model_events.clear();
        let start_cycle = self.model.cycle();
        let before = self.outputs;
        let rtl_end = self.rtl.run_chunk(inputs, max_cycles, &mut self.rtl_events);
        let model_end = match self.path {
            ModelPath::PerClock => self.model.run_chunk(inputs, max_cycles, &mut self.model_events),
            ModelPath::Fast => self.model.run_chunk_fast(inputs, max_cycles, &mut self.model_events),
        };
        self.log.push((*inputs, rtl_end.cycles.max(model_end.cycles)));
        if rtl_end != model_end || self.rtl_events != self.model_events || self.rtl.outputs() != self.model.outputs() {
            return Err(Box::new(self.report(start_cycle, before, rtl_end, model_end)));
        }
        let mut previous = self.outputs.pins;
        for event in &self.model_events {
            let rising = event.outputs.pins & !previous;
            for (axis, count) in self.pulses.iter_mut().enumerate() {
                *count += (rising >> pins::pin_a(axis)) & 1;
            }
            previous = event.outputs.pins;
        }
        if let Some(last) = self.model_events.last() {
            self.outputs = last.outputs;
        }
        for event in &self.model_events[self.model_events.len().saturating_sub(HISTORY)..] {
            if self.history.len() == HISTORY {
                self.history.pop_front();
            }
            self.history.push_back(*event);
        }
        Ok(model_end)
    }

    /// Offer each record on the record port until it is consumed, with `inputs` as the
    /// rest of the inputs (its `rec_valid` and `record` are overwritten).
    pub fn feed(
        &mut self,
        inputs: &mut CoreInputs,
        records: impl IntoIterator<Item = PeriodRecord>,
    ) -> Result<(), Box<Mismatch>> {
        inputs.rec_valid = true;
        for record in records {
            inputs.record = record;
            let limit = u64::from(self.model.params().effective_period(inputs.period_clocks)) + 8;
            let mut waited = 0;
            loop {
                let end = self.run_chunk(inputs, limit)?;
                waited += end.cycles;
                if end.consumed {
                    break;
                }
                assert!(inputs.run || waited < 16 * limit, "record never consumed: core stopped");
            }
        }
        inputs.rec_valid = false;
        Ok(())
    }

    /// Run `cycles` cycles with constant inputs (a record offered is consumed at most once).
    pub fn idle(&mut self, inputs: &CoreInputs, cycles: u64) -> Result<(), Box<Mismatch>> {
        let mut done = 0;
        while done < cycles {
            done += self.run_chunk(inputs, cycles - done)?.cycles;
        }
        Ok(())
    }

    fn report(&mut self, start: u64, before: CoreOutputs, rtl_end: ChunkEnd, model_end: ChunkEnd) -> Mismatch {
        let (cycle, expected, actual) =
            mismatch::first_difference(start, before, &self.model_events, &self.rtl_events, model_end, rtl_end);
        let mut recent_model: Vec<Event> = self.history.iter().copied().collect();
        let mut recent_rtl = recent_model.clone();
        recent_model.extend(self.model_events.iter().filter(|e| e.cycle <= cycle + 2));
        recent_rtl.extend(self.rtl_events.iter().filter(|e| e.cycle <= cycle + 2));
        let keep = |v: &mut Vec<Event>| {
            let skip = v.len().saturating_sub(HISTORY);
            v.drain(..skip);
        };
        keep(&mut recent_model);
        keep(&mut recent_rtl);
        let waveform = self.write_window(cycle);
        Mismatch {
            test: self.name.clone(),
            cycle,
            expected,
            actual,
            model_end,
            rtl_end,
            recent_model,
            recent_rtl,
            waveform,
        }
    }

    /// The waveform window around a mismatch at `cycle`, named after the test.
    fn write_window(&self, cycle: u64) -> Result<PathBuf, WaveformError> {
        let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../target/cosim-failures"));
        std::fs::create_dir_all(&dir).map_err(WaveformError::at(&dir))?;
        let suffix = if finestep_rtl_sys::trace_is_fst() { "fst" } else { "vcd" };
        let path = dir.join(format!("{}.{suffix}", self.name));
        self.write_waveform(&path, TraceDepth::Everything, cycle.saturating_sub(WINDOW_BEFORE), cycle + WINDOW_AFTER)?;
        Ok(path)
    }
}
