//! The Verilated `step_serial` alone (the digit-serial step engine), in the model's types
//! ([`finestep_model::step_serial`]) so the two run side by side: built in a few
//! variants of axes and digit ([`serial_variants`]).

use std::marker::PhantomData;
use std::path::Path;
use std::ptr::NonNull;

use finestep_model::step_serial::{SerialInputs, SerialOutputs, SerialParams};

use crate::{ffi, open_trace, TraceDepth};

/// The parameters of each Verilated build, by variant number.
pub fn serial_variants() -> Vec<SerialParams> {
    // SAFETY: pure functions returning build-time constants; raw is a valid out-pointer.
    let count = unsafe { ffi::ss_variants() };
    (0..count)
        .map(|variant| {
            let mut raw = ffi::ss_params::default();
            unsafe { ffi::ss_variant_params(variant, &mut raw) };
            SerialParams { n_axes: raw.n_axes as usize, p_width: raw.p_width, timing_w: raw.timing_w, digit: raw.digit }
        })
        .collect()
}

/// One Verilated `step_serial` with its own clock; built with waveform support. Not
/// `Send`: a Verilated model belongs to the thread that made it.
pub struct RtlStepSerial {
    sim: NonNull<ffi::ss_sim>,
    _not_send: PhantomData<*const ()>,
}

impl RtlStepSerial {
    /// A block of build `variant` (an index into [`serial_variants`]) fresh out of reset
    /// (one clock with `rst`), at cycle 0.
    pub fn new(variant: usize) -> Self {
        let variant = u32::try_from(variant).expect("a variant number");
        // SAFETY: ss_new returns a fresh object, or null for an unknown variant or in a minimal build.
        let sim = NonNull::new(unsafe { ffi::ss_new(variant) }).unwrap_or_else(|| {
            panic!("{}", if crate::MINIMAL { crate::ABSENT } else { "no such step_serial variant" })
        });
        RtlStepSerial { sim, _not_send: PhantomData }
    }

    /// One clock with `rst` high; the cycle count restarts and a waveform is closed.
    pub fn reset(&mut self) {
        // SAFETY: self.sim is live and owned.
        unsafe { ffi::ss_reset(self.sim.as_ptr()) }
    }

    /// The clocks since the last reset.
    pub fn cycle(&self) -> u64 {
        // SAFETY: self.sim is live.
        unsafe { ffi::ss_cycle(self.sim.as_ptr()) }
    }

    /// One rising edge with these inputs.
    pub fn step(&mut self, inputs: &SerialInputs) {
        let raw = ffi::ss_inputs {
            run: u8::from(inputs.run),
            p_active: inputs.p_active,
            inc: inputs.inc,
            axis_enable: inputs.axis_enable,
            step_len: inputs.step_len,
            step_space: inputs.step_space,
            dir_setup: inputs.dir_setup,
            dir_hold: inputs.dir_hold,
            out_mode: inputs.out_mode,
            invert: inputs.invert,
            clear_errors: u8::from(inputs.clear_errors),
            halt: u8::from(inputs.halt),
        };
        // SAFETY: self.sim is live; raw lives across the call.
        unsafe { ffi::ss_step(self.sim.as_ptr(), &raw) }
    }

    /// The outputs in the current cycle.
    pub fn outputs(&self) -> SerialOutputs {
        let mut raw = ffi::ss_outputs::default();
        // SAFETY: self.sim is live; raw is a valid out-pointer.
        unsafe { ffi::ss_read_outputs(self.sim.as_ptr(), &mut raw) };
        SerialOutputs {
            start_ok: raw.start_ok != 0,
            pin_a: raw.pin_a,
            pin_b: raw.pin_b,
            pin_en: raw.pin_en,
            rate_error: raw.rate_error,
            step_lost: raw.step_lost,
            pos_digit: raw.pos_digit,
            pos_index: raw.pos_index,
            pos_axis: raw.pos_axis,
        }
    }

    /// Writes a waveform of every signal to `path` from now until [`Self::trace_close`].
    pub fn trace_open(&mut self, path: &Path) -> std::io::Result<()> {
        let sim = self.sim.as_ptr();
        // SAFETY: sim is live; the C string lives across the call.
        open_trace(path, TraceDepth::Everything, "RtlStepSerial::new", |p, _| unsafe { ffi::ss_trace_open(sim, p) })
    }

    /// Closes the waveform.
    pub fn trace_close(&mut self) {
        // SAFETY: self.sim is live.
        unsafe { ffi::ss_trace_close(self.sim.as_ptr()) }
    }
}

impl Drop for RtlStepSerial {
    fn drop(&mut self) {
        // SAFETY: the pointer came from ss_new and is freed once.
        unsafe { ffi::ss_free(self.sim.as_ptr()) }
    }
}
