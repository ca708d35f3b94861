//! The Verilated `pbp_interp` alone (the point-by-point comparison interpolator), in the
//! model's types ([`finestep_model::pbp_interp`]) so the two run side by side.

use std::marker::PhantomData;
use std::path::Path;
use std::ptr::NonNull;

use finestep_model::pbp_interp::{PbpInputs, PbpOutputs, PbpParams};

use crate::{ffi, open_trace, TraceDepth};

/// The parameters the block was Verilated with.
pub fn pbp_params() -> PbpParams {
    // SAFETY: pure functions returning build-time constants.
    unsafe { PbpParams { coord_w: ffi::pi_coord_width(), div_w: ffi::pi_div_width() } }
}

/// One Verilated `pbp_interp` with its own clock; built with waveform support. Not
/// `Send`: a Verilated model belongs to the thread that made it.
pub struct RtlPbpInterp {
    sim: NonNull<ffi::pi_sim>,
    _not_send: PhantomData<*const ()>,
}

impl Default for RtlPbpInterp {
    fn default() -> Self {
        Self::new()
    }
}

impl RtlPbpInterp {
    /// A block fresh out of reset (one clock with `rst`), at cycle 0.
    pub fn new() -> Self {
        // SAFETY: pi_new returns a fresh object, or null in a minimal build.
        let sim = NonNull::new(unsafe { ffi::pi_new() }).expect(crate::ABSENT);
        RtlPbpInterp { sim, _not_send: PhantomData }
    }

    /// One clock with `rst` high; the cycle count restarts and a waveform is closed.
    pub fn reset(&mut self) {
        // SAFETY: self.sim is live and owned.
        unsafe { ffi::pi_reset(self.sim.as_ptr()) }
    }

    /// The clocks since the last reset.
    pub fn cycle(&self) -> u64 {
        // SAFETY: self.sim is live.
        unsafe { ffi::pi_cycle(self.sim.as_ptr()) }
    }

    /// One rising edge with these inputs.
    pub fn step(&mut self, inputs: &PbpInputs) {
        let r = &inputs.rec;
        let raw = ffi::pi_inputs {
            halt: u8::from(inputs.halt),
            rec_valid: u8::from(inputs.rec_valid),
            rec_arc: u8::from(r.arc),
            rec_cw: u8::from(r.cw),
            tick_div: inputs.tick_div,
            rec_x: r.x as i32,
            rec_y: r.y as i32,
            rec_steps: r.steps as u32,
        };
        // SAFETY: self.sim is live; raw lives across the call.
        unsafe { ffi::pi_step(self.sim.as_ptr(), &raw) }
    }

    /// The outputs in the current cycle.
    pub fn outputs(&self) -> PbpOutputs {
        let mut raw = ffi::pi_outputs::default();
        // SAFETY: self.sim is live; raw is a valid out-pointer.
        unsafe { ffi::pi_read_outputs(self.sim.as_ptr(), &mut raw) };
        let bit = |v: u8, i: u32| (v >> i) & 1 != 0;
        PbpOutputs {
            rec_ready: raw.rec_ready != 0,
            busy: raw.busy != 0,
            done: raw.done != 0,
            req_valid: [bit(raw.req_valid, 0), bit(raw.req_valid, 1)],
            req_negative: [bit(raw.req_negative, 0), bit(raw.req_negative, 1)],
            move_up: [bit(raw.move_up, 0), bit(raw.move_up, 1)],
            move_down: [bit(raw.move_down, 0), bit(raw.move_down, 1)],
        }
    }

    /// Writes a waveform of every signal to `path` from now until [`Self::trace_close`].
    pub fn trace_open(&mut self, path: &Path) -> std::io::Result<()> {
        let sim = self.sim.as_ptr();
        // SAFETY: sim is live; the C string lives across the call.
        open_trace(path, TraceDepth::Everything, "RtlPbpInterp::new", |p, _| unsafe { ffi::pi_trace_open(sim, p) })
    }

    /// Closes the waveform.
    pub fn trace_close(&mut self) {
        // SAFETY: self.sim is live.
        unsafe { ffi::pi_trace_close(self.sim.as_ptr()) }
    }
}

impl Drop for RtlPbpInterp {
    fn drop(&mut self) {
        // SAFETY: the pointer came from pi_new and is freed once.
        unsafe { ffi::pi_free(self.sim.as_ptr()) }
    }
}
