//! The Verilated `finestep_top` built as the gantry card's chip: the panel and the gantry
//! pair (`HAS_PANEL = HAS_GANTRY = 1`, `STEP_SHARED = 0`), its other parameters the
//! default top's ([`top_build_of`](crate::top_build_of)`(TopVariant::Full)`). Driven one
//! clock at a time with the packed inputs of `finestep_model::top_pins` (the keypad rows
//! in bits 59..62); its outputs in that packed word and the panel's pins apart.

use std::marker::PhantomData;
use std::path::Path;
use std::ptr::NonNull;

use crate::{ffi, open_trace, TraceDepth};

/// The panel's pins in [`RtlPanelChip::panel`]'s word: columns in bits 0..3, segments
/// 8..15, digits 16..23 (mirrors `PC_PANEL_*` of `sim/panel_chip_sim.h` bit for bit, as
/// `finestep_model::top_pins` mirrors `finestep_top_sim.h`).
pub mod panel_bits {
    /// Lowest bit of `panel_col`.
    pub const COL: u32 = 0;
    /// Lowest bit of `panel_seg`.
    pub const SEG: u32 = 8;
    /// Lowest bit of `panel_dig`.
    pub const DIG: u32 = 16;
}

/// One Verilated gantry-card chip with its own clock, every register 0 at construction
/// (drive `rst` for at least 2 cycles first); built with waveform support. Not `Send`.
pub struct RtlPanelChip {
    sim: NonNull<ffi::pc_sim>,
    _not_send: PhantomData<*const ()>,
}

impl Default for RtlPanelChip {
    fn default() -> Self {
        Self::new()
    }
}

impl RtlPanelChip {
    /// A chip at power-on.
    pub fn new() -> Self {
        // SAFETY: pc_new returns a fresh object, or null in a minimal build.
        let sim = NonNull::new(unsafe { ffi::pc_new() }).expect(crate::ABSENT);
        RtlPanelChip { sim, _not_send: PhantomData }
    }

    /// One rising edge with the packed `inputs`.
    pub fn step(&mut self, inputs: u64) {
        // SAFETY: self.sim is live.
        unsafe { ffi::pc_step(self.sim.as_ptr(), inputs) }
    }

    /// The packed outputs in the current cycle.
    pub fn outputs(&self) -> u64 {
        // SAFETY: self.sim is live.
        unsafe { ffi::pc_outputs(self.sim.as_ptr()) }
    }

    /// The panel's pins in the current cycle ([`panel_bits`]).
    pub fn panel(&self) -> u32 {
        // SAFETY: self.sim is live.
        unsafe { ffi::pc_panel(self.sim.as_ptr()) }
    }

    /// Clock edges run.
    pub fn cycle(&self) -> u64 {
        // SAFETY: self.sim is live.
        unsafe { ffi::pc_cycle(self.sim.as_ptr()) }
    }

    /// Writes a waveform of every signal to `path` from now until [`Self::trace_close`].
    pub fn trace_open(&mut self, path: &Path) -> std::io::Result<()> {
        let sim = self.sim.as_ptr();
        // SAFETY: sim is live; the C string lives across the call.
        open_trace(path, TraceDepth::Everything, "RtlPanelChip::new", |p, _| unsafe { ffi::pc_trace_open(sim, p) })
    }

    /// Closes the waveform.
    pub fn trace_close(&mut self) {
        // SAFETY: self.sim is live.
        unsafe { ffi::pc_trace_close(self.sim.as_ptr()) }
    }
}

impl Drop for RtlPanelChip {
    fn drop(&mut self) {
        // SAFETY: the pointer came from pc_new and is freed once.
        unsafe { ffi::pc_free(self.sim.as_ptr()) }
    }
}
