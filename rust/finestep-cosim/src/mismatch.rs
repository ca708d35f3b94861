//! The first difference between the RTL and the model, told so a person can act on it.

use std::fmt;
use std::path::PathBuf;

use finestep_model::{pins, ChunkEnd, CoreOutputs, Event, MAX_AXES};

/// The RTL and the model disagreed.
#[derive(Debug)]
pub struct Mismatch {
    /// The test (or run) that failed; names the waveform.
    pub test: String,
    /// The first cycle whose outputs differ.
    pub cycle: u64,
    /// The model's outputs in that cycle.
    pub expected: CoreOutputs,
    /// The RTL's outputs in that cycle.
    pub actual: CoreOutputs,
    /// How the model's chunk ended.
    pub model_end: ChunkEnd,
    /// How the RTL's chunk ended.
    pub rtl_end: ChunkEnd,
    /// The model's last events up to the mismatch.
    pub recent_model: Vec<Event>,
    /// The RTL's last events up to the mismatch.
    pub recent_rtl: Vec<Event>,
    /// The waveform window written around the mismatch, or why it could not be.
    pub waveform: Result<PathBuf, WaveformError>,
}

/// A waveform that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("writing the waveform {path}: {source}")]
pub struct WaveformError {
    /// The file (or the directory it goes in).
    pub path: PathBuf,
    /// What failed.
    #[source]
    pub source: std::io::Error,
}

impl WaveformError {
    /// A closure for `map_err` that names `path`.
    pub(crate) fn at(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> WaveformError + '_ {
        move |source| WaveformError { path: path.to_path_buf(), source }
    }
}

/// The outputs of one side at `cycle`, given its outputs before the chunk and its events.
fn outputs_at(before: CoreOutputs, events: &[Event], cycle: u64) -> CoreOutputs {
    events.iter().take_while(|e| e.cycle <= cycle).last().map_or(before, |e| e.outputs)
}

/// The first cycle at which the two event lists give different outputs, with the
/// (expected, actual) outputs there. If the outputs agree everywhere, the cycle after
/// the shorter chunk (the chunks ended differently).
pub(crate) fn first_difference(
    start: u64,
    before: CoreOutputs,
    model: &[Event],
    rtl: &[Event],
    model_end: ChunkEnd,
    rtl_end: ChunkEnd,
) -> (u64, CoreOutputs, CoreOutputs) {
    let mut cycles: Vec<u64> = model.iter().chain(rtl).map(|e| e.cycle).collect();
    cycles.sort_unstable();
    cycles.dedup();
    for cycle in cycles {
        let expected = outputs_at(before, model, cycle);
        let actual = outputs_at(before, rtl, cycle);
        if expected != actual {
            return (cycle, expected, actual);
        }
    }
    let cycle = start + model_end.cycles.min(rtl_end.cycles);
    (cycle, outputs_at(before, model, cycle), outputs_at(before, rtl, cycle))
}

/// The name of bit `index` of the packed pins word.
fn signal_name(index: u32) -> String {
    let axis = |base: u32| (index - base) as usize;
    match index {
        0..=23 => {
            let pin = ["pin_a", "pin_b", "pin_en"][(index % 3) as usize];
            format!("{pin}[{}]", index / 3)
        }
        24..=31 => format!("rate_error[{}]", axis(pins::rate_error(0))),
        32..=39 => format!("step_lost[{}]", axis(pins::step_lost(0))),
        pins::REC_READY => "rec_ready".to_string(),
        pins::RECORD_ERROR => "record_error".to_string(),
        pins::BLOCK_END => "block_end".to_string(),
        _ => format!("pins bit {index}"),
    }
}

/// Names and values of every signal that differs: `(signal, expected, actual)`.
pub fn describe_difference(expected: &CoreOutputs, actual: &CoreOutputs) -> Vec<(String, u64, u64)> {
    let mut out = Vec::new();
    let bit = |word: u64, b: u32| (word >> b) & 1;
    for b in 0..64 {
        if bit(expected.pins, b) != bit(actual.pins, b) {
            out.push((signal_name(b), bit(expected.pins, b), bit(actual.pins, b)));
        }
    }
    for axis in 0..MAX_AXES {
        if expected.positions[axis] != actual.positions[axis] {
            out.push((
                format!("position[{axis}]"),
                u64::from(expected.positions[axis]),
                u64::from(actual.positions[axis]),
            ));
        }
    }
    let gantry = [
        ("gantry_error", u64::from(expected.gantry_error), u64::from(actual.gantry_error)),
        ("gantry_corrections", u64::from(expected.gantry_corrections), u64::from(actual.gantry_corrections)),
        ("gantry_flags", u64::from(expected.gantry_flags), u64::from(actual.gantry_flags)),
    ];
    out.extend(gantry.into_iter().filter(|(_, e, a)| e != a).map(|(name, e, a)| (name.to_string(), e, a)));
    out
}

fn write_events(f: &mut fmt::Formatter<'_>, side: &str, events: &[Event]) -> fmt::Result {
    writeln!(f, "  last events of the {side}:")?;
    for event in events {
        let positions: Vec<i32> = event.outputs.positions.iter().map(|&p| p as i32).collect();
        writeln!(f, "    cycle {:>10}  pins {:#013x}  positions {:?}", event.cycle, event.outputs.pins, positions)?;
    }
    Ok(())
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}: RTL and model differ at cycle {}", self.test, self.cycle)?;
        for (signal, expected, actual) in describe_difference(&self.expected, &self.actual) {
            writeln!(f, "  {signal}: expected (model) {expected}, actual (RTL) {actual}")?;
        }
        if self.model_end != self.rtl_end {
            writeln!(f, "  chunk end: model {:?}, RTL {:?}", self.model_end, self.rtl_end)?;
        }
        write_events(f, "model", &self.recent_model)?;
        write_events(f, "RTL", &self.recent_rtl)?;
        match &self.waveform {
            Ok(path) => writeln!(f, "  waveform window: {}", path.display()),
            Err(why) => writeln!(f, "  no waveform window: {why}"),
        }
    }
}

impl std::error::Error for Mismatch {}
