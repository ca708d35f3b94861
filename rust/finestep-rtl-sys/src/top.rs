//! The Verilated `finestep_top`: the core behind its host interface, driven and
//! observed at its pins as packed 64-bit words (layout in `sim/finestep_top_sim.h`,
//! mirrored by `finestep_model::top_pins`).

use std::marker::PhantomData;
use std::path::Path;
use std::ptr::NonNull;

use crate::{ffi, TraceDepth};

/// Which Verilation of `finestep_top`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TopVariant {
    /// `finestep_top`'s defaults (`hdl/interface.toml`): the spindle and the logic
    /// outputs built.
    #[default]
    Full,
    /// The motion chip every board top builds: without the spindle and the logic outputs
    /// (`HAS_SPINDLE = HAS_OUTPUTS = N_GPIO = 0`); what the motion tests and the bench run.
    /// Verilated without tracing (no waveform of a mismatch). A netlist build has one top,
    /// the default's: this is that top too.
    Motion,
    /// The motion chip without the hand wheel and the jog too (`HAS_MPG = 0`, as the
    /// HX8K and MachXO3 boards build it): what the motion tests that turn no wheel and
    /// the bench run (the two blocks cost about a third of the chip's simulation time).
    /// Verilated without tracing, as [`TopVariant::Motion`]; a netlist build's default top.
    MotionNoMpg,
    /// The motion chip with the core's digit-serial step engine (`STEP_DIGIT` > 0, as the
    /// CPLD board tops build it; [`TopBuild::step_digit`]). Verilated without tracing, as
    /// [`TopVariant::Motion`]; a netlist build's default top (with the step engine then).
    MotionSerial,
}

impl TopVariant {
    fn raw(self) -> u32 {
        match self {
            TopVariant::Full => ffi::FT_VARIANT_FULL,
            TopVariant::Motion => ffi::FT_VARIANT_MOTION,
            TopVariant::MotionNoMpg => ffi::FT_VARIANT_MOTION_NO_MPG,
            TopVariant::MotionSerial => ffi::FT_VARIANT_MOTION_SERIAL,
        }
    }
}

/// The parameters the Verilated top was built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopBuild {
    /// Step/dir axes.
    pub n_axes: usize,
    /// Width of the period register.
    pub p_width: u32,
    /// Width of the step timing settings.
    pub timing_width: u32,
    /// The position FIFO holds `2^fifo_depth_log2` records.
    pub fifo_depth_log2: u32,
    /// Encoder channels.
    pub n_enc: usize,
    /// The hand wheel and the jog generator are built.
    pub has_mpg: bool,
    /// The core's step engine is built (`STEP_SHARED`).
    pub step_shared: bool,
    /// `STEP_DIGIT`: 0 the step engine, else the digit-serial one with that many bits a
    /// clock.
    pub step_digit: u32,
    /// `ONE_SNAPSHOT`: the probe's snapshot is the position latch.
    pub one_snapshot: bool,
    /// `INC_WRITE_ONLY`: `RECORD_INC` reads 0.
    pub inc_write_only: bool,
    /// `AXIS_WRITE_ONLY`: `AXIS_TIMING_A/B` and `AXIS_MODE` read 0.
    pub axis_write_only: bool,
    /// `INC_DIRECT`: a `RECORD_INC` write goes straight into the FIFO's record.
    pub inc_direct: bool,
    /// `ENC_COUNT_W`: bits of the encoders' counts and edge times (16 or 32).
    pub enc_count_w: u32,
    /// The spindle block is built (`HAS_SPINDLE`).
    pub has_spindle: bool,
    /// The logic outputs and the interlock input are built (`HAS_OUTPUTS`).
    pub has_outputs: bool,
    /// General outputs (`N_GPIO`).
    pub n_gpio: usize,
    /// The core's point-by-point comparison interpolator is built (`HAS_PBP`: the
    /// default top's; the motion chips are built without it, as the board tops).
    pub has_pbp: bool,
}

/// The build parameters of the Verilated top with `finestep_top`'s defaults.
pub fn top_build() -> TopBuild {
    top_build_of(TopVariant::Full)
}

/// The build parameters of the Verilated top `variant`.
pub fn top_build_of(variant: TopVariant) -> TopBuild {
    let v = variant.raw();
    // SAFETY: pure functions returning build-time constants.
    unsafe {
        TopBuild {
            n_axes: ffi::ft_n_axes() as usize,
            p_width: ffi::ft_p_width(),
            timing_width: ffi::ft_timing_width(),
            fifo_depth_log2: ffi::ft_fifo_depth_log2(),
            n_enc: ffi::ft_n_enc() as usize,
            has_mpg: ffi::ft_has_mpg(v) != 0,
            step_shared: ffi::ft_step_shared() != 0,
            step_digit: ffi::ft_step_digit(v),
            one_snapshot: ffi::ft_one_snapshot(v) != 0,
            inc_write_only: ffi::ft_inc_write_only(v) != 0,
            axis_write_only: ffi::ft_axis_write_only(v) != 0,
            inc_direct: ffi::ft_inc_direct(v) != 0,
            enc_count_w: ffi::ft_enc_count_w(v),
            has_spindle: ffi::ft_has_spindle(v) != 0,
            has_outputs: ffi::ft_has_outputs(v) != 0,
            n_gpio: ffi::ft_n_gpio(v) as usize,
            has_pbp: ffi::ft_has_pbp(v) != 0,
        }
    }
}

/// An output change: the packed outputs from cycle `cycle` on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinEvent {
    /// The cycle whose outputs these are (after the edge ending cycle `cycle - 1`).
    pub cycle: u64,
    /// Packed outputs.
    pub outputs: u64,
}

/// One Verilated `finestep_top` with its own clock, all state zero at construction
/// (drive `rst` for at least 2 cycles first). Not `Send`.
pub struct RtlTop {
    sim: NonNull<ffi::ft_sim>,
    variant: TopVariant,
    events: Vec<ffi::ft_event>,
    _not_send: PhantomData<*const ()>,
}

impl Default for RtlTop {
    fn default() -> Self {
        Self::new()
    }
}

impl RtlTop {
    /// A top with `finestep_top`'s defaults, without waveform support (fast).
    pub fn new() -> RtlTop {
        Self::of(TopVariant::Full)
    }

    /// A top of `variant` without waveform support (fast).
    pub fn of(variant: TopVariant) -> RtlTop {
        // SAFETY: ft_new returns a valid owned pointer (null for a variant a minimal build lacks), freed in Drop.
        Self::from_raw(unsafe { ffi::ft_new(variant.raw()) }, variant)
    }

    /// A top with `finestep_top`'s defaults that can write waveforms
    /// ([`RtlTop::trace_open`]).
    pub fn new_traced() -> RtlTop {
        Self::traced_of(TopVariant::Full)
    }

    /// A top of `variant` that can write waveforms ([`RtlTop::trace_open`]);
    /// the motion variants are Verilated without tracing: their `trace_open` fails.
    pub fn traced_of(variant: TopVariant) -> RtlTop {
        // SAFETY: ft_new_traced returns a valid owned pointer (null for a variant a minimal build lacks), freed in Drop.
        Self::from_raw(unsafe { ffi::ft_new_traced(variant.raw()) }, variant)
    }

    fn from_raw(sim: *mut ffi::ft_sim, variant: TopVariant) -> RtlTop {
        let sim = NonNull::new(sim).expect(crate::ABSENT);
        RtlTop { sim, variant, events: Vec::new(), _not_send: PhantomData }
    }

    /// Edges run since construction.
    pub fn cycle(&self) -> u64 {
        // SAFETY: self.sim is valid for our lifetime.
        unsafe { ffi::ft_cycle(self.sim.as_ptr()) }
    }

    /// The packed outputs in the current cycle.
    pub fn outputs(&self) -> u64 {
        // SAFETY: as above.
        unsafe { ffi::ft_outputs(self.sim.as_ptr()) }
    }

    /// `cycles` edges with the packed `inputs` held; appends an event for every cycle
    /// whose outputs changed.
    pub fn run(&mut self, inputs: u64, cycles: u64, events: &mut Vec<PinEvent>) {
        const BATCH: usize = 4096;
        self.events.resize(BATCH, ffi::ft_event::default());
        let mut ran = 0;
        while ran < cycles {
            let mut stored = 0usize;
            // SAFETY: the event buffer holds BATCH entries.
            ran += unsafe {
                ffi::ft_run(self.sim.as_ptr(), inputs, cycles - ran, self.events.as_mut_ptr(), BATCH, &mut stored)
            };
            events.extend(self.events[..stored].iter().map(|e| PinEvent { cycle: e.cycle, outputs: e.outputs }));
        }
    }

    /// Up to `cycles` edges with the packed `inputs` held, stopping right after the first
    /// edge that changes the outputs. Returns the edges run.
    pub fn run_to_change(&mut self, inputs: u64, cycles: u64) -> u64 {
        let mut event = ffi::ft_event::default();
        let mut stored = 0usize;
        // SAFETY: room for exactly one event.
        unsafe { ffi::ft_run(self.sim.as_ptr(), inputs, cycles, &mut event, 1, &mut stored) }
    }

    /// Start writing a waveform of every following cycle (a top from
    /// [`RtlTop::new_traced`] or [`RtlTop::traced_of`] `(TopVariant::Full)` only).
    /// A netlist build (`crate::TOP_IS_NETLIST`) is Verilated without tracing: this fails.
    pub fn trace_open(&mut self, path: &Path, depth: TraceDepth) -> std::io::Result<()> {
        let maker = if crate::TOP_IS_NETLIST {
            "RtlTop::new_traced on an RTL build; the netlist build has no tracing"
        } else if self.variant != TopVariant::Full {
            "RtlTop::traced_of(TopVariant::Full); the motion variants have no traced build: rerun the case on it"
        } else {
            "RtlTop::new_traced"
        };
        crate::open_trace(path, depth, maker, |c_path, levels| {
            // SAFETY: c_path is a valid NUL-terminated string for the call.
            unsafe { ffi::ft_trace_open(self.sim.as_ptr(), c_path, levels) }
        })
    }

    /// Flush and close the waveform, if one is open.
    pub fn trace_close(&mut self) {
        // SAFETY: closing with no trace open is a no-op.
        unsafe { ffi::ft_trace_close(self.sim.as_ptr()) }
    }
}

impl Drop for RtlTop {
    fn drop(&mut self) {
        // SAFETY: we own the pointer and never use it again.
        unsafe { ffi::ft_free(self.sim.as_ptr()) }
    }
}
