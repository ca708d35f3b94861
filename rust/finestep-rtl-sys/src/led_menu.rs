//! The Verilated `led_menu` alone (the gantry card's multiplexed 7-segment display and
//! menu), in the model's types ([`finestep_model::led_menu`]) so the two run side by
//! side: built twice, with the module's defaults and with fewer digits and active-low
//! levels ([`led_variants`]).

use std::marker::PhantomData;
use std::path::Path;
use std::ptr::NonNull;

use finestep_model::led_menu::{LedInputs, LedOutputs, LedParams};

use crate::{ffi, open_trace, TraceDepth};

/// The parameters of each Verilated build, by variant number.
pub fn led_variants() -> Vec<LedParams> {
    // SAFETY: pure functions returning build-time constants; raw is a valid out-pointer.
    let count = unsafe { ffi::lm_variants() };
    (0..count)
        .map(|variant| {
            let mut raw = ffi::lm_params::default();
            unsafe { ffi::lm_variant_params(variant, &mut raw) };
            LedParams {
                n_dig: raw.n_dig,
                pre_w: raw.pre_w,
                seg_active_low: raw.seg_active_low != 0,
                dig_active_low: raw.dig_active_low != 0,
            }
        })
        .collect()
}

/// One Verilated `led_menu` with its own clock; built with waveform support. Not
/// `Send`: a Verilated model belongs to the thread that made it.
pub struct RtlLedMenu {
    sim: NonNull<ffi::lm_sim>,
    _not_send: PhantomData<*const ()>,
}

impl RtlLedMenu {
    /// A block of build `variant` (an index into [`led_variants`]) fresh out of reset
    /// (one clock with `rst`), at cycle 0.
    pub fn new(variant: usize) -> Self {
        let variant = u32::try_from(variant).expect("a variant number");
        // SAFETY: lm_new returns a fresh object, or null for an unknown variant or in a minimal build.
        let sim = NonNull::new(unsafe { ffi::lm_new(variant) })
            .unwrap_or_else(|| panic!("{}", if crate::MINIMAL { crate::ABSENT } else { "no such led_menu variant" }));
        RtlLedMenu { sim, _not_send: PhantomData }
    }

    /// One clock with `rst` high; the cycle count restarts and a waveform is closed.
    pub fn reset(&mut self) {
        // SAFETY: self.sim is live and owned.
        unsafe { ffi::lm_reset(self.sim.as_ptr()) }
    }

    /// The clocks since the last reset.
    pub fn cycle(&self) -> u64 {
        // SAFETY: self.sim is live.
        unsafe { ffi::lm_cycle(self.sim.as_ptr()) }
    }

    /// One rising edge with these inputs.
    pub fn step(&mut self, i: &LedInputs) {
        let raw = ffi::lm_inputs {
            refresh_div: i.refresh_div,
            key_valid: u8::from(i.key_valid),
            key_code: i.key_code,
            sync_err: i.sync_err,
            alarm_in: i.alarm_in,
            host_wr: u8::from(i.host_wr),
            host_addr: i.host_addr,
            host_wdata: i.host_wdata,
        };
        // SAFETY: self.sim is live; raw lives across the call.
        unsafe { ffi::lm_step(self.sim.as_ptr(), &raw) }
    }

    /// The outputs in the current cycle.
    pub fn outputs(&self) -> LedOutputs {
        let mut raw = ffi::lm_outputs::default();
        // SAFETY: self.sim is live; raw is a valid out-pointer.
        unsafe { ffi::lm_read_outputs(self.sim.as_ptr(), &mut raw) };
        LedOutputs {
            host_rdata: raw.host_rdata,
            seg: raw.seg,
            dig: raw.dig,
            sync_mode: raw.sync_mode != 0,
            alarm_pending: raw.alarm_pending != 0,
            page: raw.page,
        }
    }

    /// Writes a waveform of every signal to `path` from now until [`Self::trace_close`].
    pub fn trace_open(&mut self, path: &Path) -> std::io::Result<()> {
        let sim = self.sim.as_ptr();
        // SAFETY: sim is live; the C string lives across the call.
        open_trace(path, TraceDepth::Everything, "RtlLedMenu::new", |p, _| unsafe { ffi::lm_trace_open(sim, p) })
    }

    /// Closes the waveform.
    pub fn trace_close(&mut self) {
        // SAFETY: self.sim is live.
        unsafe { ffi::lm_trace_close(self.sim.as_ptr()) }
    }
}

impl Drop for RtlLedMenu {
    fn drop(&mut self) {
        // SAFETY: the pointer came from lm_new and is freed once.
        unsafe { ffi::lm_free(self.sim.as_ptr()) }
    }
}
