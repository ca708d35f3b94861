//! Lockstep co-simulation of `finestep_top` at its pins: the Verilated RTL and the
//! reference model get the same pin inputs every clock and must drive the same outputs
//! every clock. [`TopLockstep`] is a [`PinTarget`], so the host driver's SPI and 8080
//! masters (and everything built on them: register reads, record streaming) run on
//! both at once, and every register read the host makes is compared on the way.

use std::fmt;
use std::path::PathBuf;

use finestep_host::{BusError, PinTarget};
use finestep_model::top::{top_pins, Top, TopInputs, TopParams};
use finestep_rtl_sys::{top_build_of, PinEvent, RtlTop, TopVariant, TraceDepth};

use crate::mismatch::WaveformError;

/// Cycles of waveform after the mismatch.
const WINDOW_AFTER: u64 = 16;

/// The RTL and the model disagreed at the pins.
#[derive(Debug)]
pub struct TopMismatch {
    /// The test (or run) that failed; names the waveform.
    pub test: String,
    /// The first cycle whose outputs differ.
    pub cycle: u64,
    /// The model's packed outputs.
    pub expected: u64,
    /// The RTL's packed outputs.
    pub actual: u64,
    /// The packed inputs held in that cycle.
    pub inputs: u64,
    /// The waveform of the whole run up to the mismatch, or why it could not be written.
    pub waveform: Result<PathBuf, WaveformError>,
}

/// The name of bit `index` of the packed outputs.
fn output_name(index: u32) -> String {
    use top_pins::output as o;
    match index {
        0..=7 => format!("pin_a[{index}]"),
        8..=15 => format!("pin_b[{}]", index - 8),
        16..=23 => format!("pin_en[{}]", index - 16),
        o::SPI_MISO => "spi_miso".into(),
        o::SPI_MISO_OE => "spi_miso_oe".into(),
        o::IRQ => "irq".into(),
        o::BUS_AD_OE => "bus_ad_oe".into(),
        o::COOLANT_MIST => "coolant_mist".into(),
        o::COOLANT_FLOOD => "coolant_flood".into(),
        o::LIGHT => "light".into(),
        32..=47 => format!("bus_ad_out[{}]", index - o::BUS_AD_OUT),
        o::SPINDLE_PWM => "spindle_pwm".into(),
        o::SPINDLE_DIR => "spindle_dir".into(),
        o::SPINDLE_EN => "spindle_en".into(),
        o::DAC_CS_N => "dac_cs_n".into(),
        o::DAC_SCK => "dac_sck".into(),
        o::DAC_SDI => "dac_sdi".into(),
        56..=63 => format!("gpio[{}]", index - o::GPIO),
        _ => format!("outputs bit {index}"),
    }
}

impl fmt::Display for TopMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // The Verilated top is the RTL or, with a netlist feature, a synthesised netlist.
        let side = if finestep_rtl_sys::TOP_IS_NETLIST { "netlist" } else { "RTL" };
        writeln!(f, "{}: {side} and model differ at the pins in cycle {}", self.test, self.cycle)?;
        if finestep_rtl_sys::TOP_IS_NETLIST {
            writeln!(f, "  top under test: {}", finestep_rtl_sys::TOP_SOURCE)?;
        }
        let differ = self.expected ^ self.actual;
        for bit in (0..64).filter(|b| differ >> b & 1 != 0) {
            writeln!(
                f,
                "  {}: model {}, {side} {}",
                output_name(bit),
                self.expected >> bit & 1,
                self.actual >> bit & 1
            )?;
        }
        writeln!(f, "  inputs {:?}", TopInputs::unpack(self.inputs))?;
        match &self.waveform {
            Ok(path) => write!(f, "  waveform (every signal): {}", path.display()),
            Err(why) => write!(f, "  no waveform: {why}"),
        }
    }
}

impl std::error::Error for TopMismatch {}

/// The Verilated top and the model side by side, compared every clock.
pub struct TopLockstep {
    name: String,
    variant: TopVariant,
    rtl: RtlTop,
    model: Top,
    /// Every drive since construction, run-length merged (for waveform replay).
    log: Vec<(u64, u64)>,
    events: Vec<PinEvent>,
    cycle: u64,
    outputs: u64,
    /// With `FINESTEP_PIN_RECORD_DIR` set: written with `log` to `<dir>/<name>.pins` on drop.
    record: Option<PinRecord>,
}

/// The outputs of a recorded run: at power-on and every change since (cycle, outputs).
struct PinRecord {
    path: PathBuf,
    outputs0: u64,
    changes: Vec<(u64, u64)>,
}

/// The model parameters of the Verilated top with `finestep_top`'s defaults.
pub fn rtl_top_params() -> TopParams {
    rtl_top_params_of(TopVariant::Full)
}

/// The model parameters of the Verilated top `variant`.
pub fn rtl_top_params_of(variant: TopVariant) -> TopParams {
    let build = top_build_of(variant);
    TopParams {
        n_axes: build.n_axes,
        p_width: build.p_width,
        timing_w: build.timing_width,
        fifo_depth_log2: build.fifo_depth_log2,
        n_enc: build.n_enc,
        has_mpg: build.has_mpg,
        step_shared: build.step_shared,
        step_digit: build.step_digit,
        one_snapshot: build.one_snapshot,
        inc_write_only: build.inc_write_only,
        axis_write_only: build.axis_write_only,
        inc_direct: build.inc_direct,
        enc_count_w: build.enc_count_w,
        has_spindle: build.has_spindle,
        has_outputs: build.has_outputs,
        n_gpio: build.n_gpio,
        has_pbp: build.has_pbp,
        ..TopParams::default()
    }
}

impl TopLockstep {
    /// Both sides at power-on, with `finestep_top`'s defaults; drive `rst` first.
    /// `name` names the failure waveform.
    pub fn new(name: &str) -> TopLockstep {
        Self::of(TopVariant::Full, name)
    }

    /// The motion chip every board top builds (no spindle, no logic outputs): what the
    /// motion tests that turn the hand wheel run.
    pub fn motion(name: &str) -> TopLockstep {
        Self::of(TopVariant::Motion, name)
    }

    /// The motion chip without the hand wheel and the jog (`HAS_MPG = 0`): what the
    /// motion tests that turn no wheel and the bench run.
    pub fn motion_no_mpg(name: &str) -> TopLockstep {
        Self::of(TopVariant::MotionNoMpg, name)
    }

    /// The motion chip with the core's digit-serial step engine, as the CPLD board tops
    /// build it (`STEP_DIGIT` > 0).
    pub fn motion_serial(name: &str) -> TopLockstep {
        Self::of(TopVariant::MotionSerial, name)
    }

    /// Both sides of `variant` at power-on; drive `rst` first.
    pub fn of(variant: TopVariant, name: &str) -> TopLockstep {
        let rtl = RtlTop::of(variant);
        let outputs = rtl.outputs();
        let record = std::env::var_os(RECORD_DIR_VAR).map(|dir| PinRecord {
            path: PathBuf::from(dir).join(format!("{name}.pins")),
            outputs0: outputs,
            changes: Vec::new(),
        });
        TopLockstep {
            name: name.to_string(),
            variant,
            rtl,
            model: Top::new(rtl_top_params_of(variant)),
            log: Vec::new(),
            events: Vec::new(),
            cycle: 0,
            outputs,
            record,
        }
    }

    /// The pin record (`FINESTEP_PIN_RECORD_DIR`): a header, the inputs as run-length
    /// `I <cycles> <inputs hex>` lines in order, and the outputs as `O <cycle> <outputs hex>`
    /// at power-on (cycle 0) and at every change, both packed as `top_pins` packs them. The
    /// second simulator (`scripts/icarus_replay.py`) replays it clock by clock.
    fn write_record(&self, path: &std::path::Path, outputs0: u64, changes: &[(u64, u64)]) -> std::io::Result<()> {
        use std::io::Write;
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
        let variant = match self.variant {
            TopVariant::Full => "full",
            TopVariant::Motion => "motion",
            TopVariant::MotionNoMpg => "motion-no-mpg",
            TopVariant::MotionSerial => "motion-serial",
        };
        writeln!(out, "# finestep_top pins of {}, {} clocks; {}", self.name, self.cycle, finestep_rtl_sys::TOP_SOURCE)?;
        writeln!(out, "variant {variant}")?;
        for &(inputs, cycles) in &self.log {
            writeln!(out, "I {cycles} {inputs:016x}")?;
        }
        writeln!(out, "O 0 {outputs0:016x}")?;
        for &(cycle, outputs) in changes {
            writeln!(out, "O {cycle} {outputs:016x}")?;
        }
        out.flush()
    }

    /// The model (for assertions on internal state in tests).
    pub fn model(&self) -> &Top {
        &self.model
    }

    /// Cycles run.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    fn mismatch(&self, cycle: u64, expected: u64, actual: u64, inputs: u64) -> TopMismatch {
        TopMismatch {
            test: self.name.clone(),
            cycle,
            expected,
            actual,
            inputs,
            waveform: self.failure_waveform(cycle + WINDOW_AFTER),
        }
    }

    fn failure_waveform(&self, until: u64) -> Result<PathBuf, WaveformError> {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/cosim-failures");
        std::fs::create_dir_all(&dir).map_err(WaveformError::at(&dir))?;
        let extension = if finestep_rtl_sys::trace_is_fst() { "fst" } else { "vcd" };
        let path = dir.join(format!("{}.{extension}", self.name));
        self.write_waveform(&path, TraceDepth::Everything, until)?;
        Ok(path)
    }

    /// Replays the run so far on a traced RTL from power-on up to cycle `until` and
    /// writes its waveform to `path`.
    pub fn write_waveform(&self, path: &std::path::Path, depth: TraceDepth, until: u64) -> Result<(), WaveformError> {
        let mut rtl = RtlTop::traced_of(self.variant);
        rtl.trace_open(path, depth).map_err(WaveformError::at(path))?;
        let mut scratch = Vec::new();
        let mut ran = 0;
        for &(inputs, cycles) in &self.log {
            let cycles = cycles.min(until.saturating_sub(ran));
            if cycles == 0 {
                break;
            }
            rtl.run(inputs, cycles, &mut scratch);
            scratch.clear();
            ran += cycles;
        }
        rtl.trace_close();
        Ok(())
    }
}

impl TopLockstep {
    fn log_inputs(&mut self, inputs: u64, cycles: u64) {
        match self.log.last_mut() {
            Some((last, run)) if *last == inputs => *run += cycles,
            _ => self.log.push((inputs, cycles)),
        }
    }

    /// Steps the model `cycles` times with `inputs` and compares it on every cycle with
    /// the RTL's outputs, which changed only at `self.events`.
    fn compare_model(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        let model_inputs = TopInputs::unpack(inputs);
        let mut rtl_outputs = self.outputs;
        let mut next_event = 0;
        for offset in 1..=cycles {
            self.model.step(&model_inputs);
            let cycle = self.cycle + offset;
            while next_event < self.events.len() && self.events[next_event].cycle == cycle {
                rtl_outputs = self.events[next_event].outputs;
                next_event += 1;
                if let Some(record) = &mut self.record {
                    record.changes.push((cycle, rtl_outputs));
                }
            }
            let expected = self.model.outputs().pack();
            if expected != rtl_outputs {
                return Err(BusError::Transport(Box::new(self.mismatch(cycle, expected, rtl_outputs, inputs))));
            }
        }
        self.cycle += cycles;
        self.outputs = rtl_outputs;
        Ok(())
    }
}

/// The directory [`TopLockstep`] writes each run's pin record to, when set.
pub const RECORD_DIR_VAR: &str = "FINESTEP_PIN_RECORD_DIR";

impl Drop for TopLockstep {
    fn drop(&mut self) {
        if let Some(record) = self.record.take() {
            if let Err(e) = self.write_record(&record.path, record.outputs0, &record.changes) {
                eprintln!("{}: cannot write the pin record {}: {e}", self.name, record.path.display());
            }
        }
    }
}

impl PinTarget for TopLockstep {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        self.log_inputs(inputs, cycles);
        self.events.clear();
        self.rtl.run(inputs, cycles, &mut self.events);
        self.compare_model(inputs, cycles)
    }

    fn drive_to_change(&mut self, inputs: u64, cycles: u64) -> Result<u64, BusError> {
        // The RTL finds the first change; the model runs as many cycles, compared on each.
        let ran = self.rtl.run_to_change(inputs, cycles);
        self.log_inputs(inputs, ran);
        self.events.clear();
        let outputs = self.rtl.outputs();
        if outputs != self.outputs {
            self.events.push(PinEvent { cycle: self.cycle + ran, outputs });
        }
        self.compare_model(inputs, ran)?;
        Ok(ran)
    }

    fn outputs(&self) -> u64 {
        self.outputs
    }
}

/// The reference model alone at its pins.
pub struct ModelPins(pub Top);

impl ModelPins {
    /// Clock edges run since the model was made.
    pub fn cycle(&self) -> u64 {
        self.0.cycle()
    }
}

impl PinTarget for ModelPins {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        let inputs = TopInputs::unpack(inputs);
        for _ in 0..cycles {
            self.0.step(&inputs);
        }
        Ok(())
    }

    fn drive_to_change(&mut self, inputs: u64, cycles: u64) -> Result<u64, BusError> {
        let inputs = TopInputs::unpack(inputs);
        let before = self.0.outputs().pack();
        for ran in 1..=cycles {
            self.0.step(&inputs);
            if self.0.outputs().pack() != before {
                return Ok(ran);
            }
        }
        Ok(cycles)
    }

    fn outputs(&self) -> u64 {
        self.0.outputs().pack()
    }
}

/// The Verilated RTL alone at its pins.
pub struct RtlPins {
    rtl: RtlTop,
    scratch: Vec<PinEvent>,
}

impl RtlPins {
    /// A Verilated top with `finestep_top`'s defaults at power-on.
    pub fn new() -> RtlPins {
        Self::of(TopVariant::Full)
    }

    /// A Verilated top of `variant` at power-on.
    pub fn of(variant: TopVariant) -> RtlPins {
        RtlPins { rtl: RtlTop::of(variant), scratch: Vec::new() }
    }

    /// Clock edges run since construction.
    pub fn cycle(&self) -> u64 {
        self.rtl.cycle()
    }
}

impl Default for RtlPins {
    fn default() -> Self {
        Self::new()
    }
}

impl PinTarget for RtlPins {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        self.rtl.run(inputs, cycles, &mut self.scratch);
        self.scratch.clear();
        Ok(())
    }

    fn drive_to_change(&mut self, inputs: u64, cycles: u64) -> Result<u64, BusError> {
        Ok(self.rtl.run_to_change(inputs, cycles))
    }

    fn outputs(&self) -> u64 {
        self.rtl.outputs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use finestep_host::pins::layout::IDLE_INPUTS;
    use finestep_model::top::top_pins::output as o;

    /// A wrong output on the RTL's side is reported at its cycle, with its pin named and
    /// the model's and the RTL's levels: the comparison must fail when a pin differs.
    #[test]
    fn a_wrong_pin_is_named_at_its_cycle() {
        let mut lockstep = TopLockstep::motion("a_wrong_pin_is_named_at_its_cycle");
        lockstep.drive(IDLE_INPUTS | 1, 4).expect("reset in lockstep");
        lockstep.drive(IDLE_INPUTS, 20).expect("idle in lockstep");
        let start = lockstep.cycle();
        let good = lockstep.outputs();
        // The RTL runs 10 more cycles; then one of its output changes is forged: the IRQ
        // pin flips from cycle start + 7 on.
        lockstep.events.clear();
        lockstep.rtl.run(IDLE_INPUTS, 10, &mut lockstep.events);
        assert!(lockstep.events.is_empty(), "an idle chip changes no pin");
        lockstep.events.push(PinEvent { cycle: start + 7, outputs: good ^ 1 << o::IRQ });
        let error = lockstep.compare_model(IDLE_INPUTS, 10).expect_err("a flipped pin must fail the comparison");
        let BusError::Transport(error) = error else { panic!("not a transport error: {error:?}") };
        let mismatch = error.downcast_ref::<TopMismatch>().expect("a TopMismatch");
        assert_eq!(mismatch.cycle, start + 7);
        assert_eq!(mismatch.expected, good);
        assert_eq!(mismatch.actual, good ^ 1 << o::IRQ);
        let report = mismatch.to_string();
        assert!(report.contains(&format!("in cycle {}", start + 7)), "{report}");
        assert!(
            report.contains(&format!("irq: model {}, RTL {}", good >> o::IRQ & 1, !good >> o::IRQ & 1)),
            "{report}"
        );
        assert_eq!(report.matches(": model ").count(), 1, "only the flipped pin is named: {report}");
    }
}
