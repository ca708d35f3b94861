//! The Verilated `keypad_scan` alone (the gantry card's 4x4 keypad scan with debounce),
//! in the model's types ([`finestep_model::keypad_scan`]) so the two run side by side.

use std::marker::PhantomData;
use std::path::Path;
use std::ptr::NonNull;

use finestep_model::keypad_scan::{KeypadInputs, KeypadOutputs, KeypadParams};

use crate::{ffi, open_trace, TraceDepth};

/// The parameters the block was Verilated with.
pub fn keypad_params() -> KeypadParams {
    // SAFETY: pure functions returning build-time constants.
    unsafe { KeypadParams { pre_w: ffi::kp_pre_width(), deb_w: ffi::kp_deb_width() } }
}

/// One Verilated `keypad_scan` with its own clock; built with waveform support. Not
/// `Send`: a Verilated model belongs to the thread that made it.
pub struct RtlKeypadScan {
    sim: NonNull<ffi::kp_sim>,
    _not_send: PhantomData<*const ()>,
}

impl Default for RtlKeypadScan {
    fn default() -> Self {
        Self::new()
    }
}

impl RtlKeypadScan {
    /// A block fresh out of reset (one clock with `rst`), at cycle 0.
    pub fn new() -> Self {
        // SAFETY: kp_new returns a fresh object, or null in a minimal build.
        let sim = NonNull::new(unsafe { ffi::kp_new() }).expect(crate::ABSENT);
        RtlKeypadScan { sim, _not_send: PhantomData }
    }

    /// One clock with `rst` high; the cycle count restarts and a waveform is closed.
    pub fn reset(&mut self) {
        // SAFETY: self.sim is live and owned.
        unsafe { ffi::kp_reset(self.sim.as_ptr()) }
    }

    /// The clocks since the last reset.
    pub fn cycle(&self) -> u64 {
        // SAFETY: self.sim is live.
        unsafe { ffi::kp_cycle(self.sim.as_ptr()) }
    }

    /// One rising edge with these inputs.
    pub fn step(&mut self, inputs: &KeypadInputs) {
        let raw = ffi::kp_inputs { scan_div: inputs.scan_div, deb_scans: inputs.deb_scans, row_n: inputs.row_n };
        // SAFETY: self.sim is live; raw lives across the call.
        unsafe { ffi::kp_step(self.sim.as_ptr(), &raw) }
    }

    /// The outputs in the current cycle.
    pub fn outputs(&self) -> KeypadOutputs {
        let mut raw = ffi::kp_outputs::default();
        // SAFETY: self.sim is live; raw is a valid out-pointer.
        unsafe { ffi::kp_read_outputs(self.sim.as_ptr(), &mut raw) };
        KeypadOutputs {
            col_drive: raw.col_drive,
            key_valid: raw.key_valid != 0,
            key_code: raw.key_code,
            key_down: raw.key_down,
        }
    }

    /// Writes a waveform of every signal to `path` from now until [`Self::trace_close`].
    pub fn trace_open(&mut self, path: &Path) -> std::io::Result<()> {
        let sim = self.sim.as_ptr();
        // SAFETY: sim is live; the C string lives across the call.
        open_trace(path, TraceDepth::Everything, "RtlKeypadScan::new", |p, _| unsafe { ffi::kp_trace_open(sim, p) })
    }

    /// Closes the waveform.
    pub fn trace_close(&mut self) {
        // SAFETY: self.sim is live.
        unsafe { ffi::kp_trace_close(self.sim.as_ptr()) }
    }
}

impl Drop for RtlKeypadScan {
    fn drop(&mut self) {
        // SAFETY: the pointer came from kp_new and is freed once.
        unsafe { ffi::kp_free(self.sim.as_ptr()) }
    }
}
