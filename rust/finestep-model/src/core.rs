//! `finestep_core`: the composition of one [`PeriodTimer`], per axis one [`DdaAxis`]
//! and one [`StepShaper`], and the [`GantrySync`] between the DDAs and the shapers, with
//! the packed outputs; or, built with `step_shared` (`STEP_SHARED = 1`), the period
//! timer and one [`StepEngine`] visiting the axes' DDA and shaper stores in turn.
//!
//! Specification: docs/spec/finestep_core.md, docs/spec/step_engine.md
//!
//! Latency: a DDA update in cycle `n` gives `req` in `n+1`, the earliest rise decision
//! in `n+1` (level and `position` in `n+2`) and the pin edge in `n+3`; with the step
//! engine a DDA visit in `n`, the rise decision in `n+1`, `position` and the pin edge
//! in `n+2`. Every output is a function of the state only.

use crate::config::{AxisSettings, CoreInputs, CoreParams, ParamError};
use crate::dda_axis::{DdaAxis, ONE_STEP};
use crate::gantry_sync::{ExtMotion, GantryContext, GantrySync};
use crate::pbp_interp::{PbpInputs, PbpInterp, PbpParams, PbpRecord};
use crate::period_timer::{PeriodTimer, TimerInputs};
use crate::record::PeriodRecord;
use crate::step_engine::{EngineInputs, StepEngine};
use crate::step_serial::{SerialInputs, SerialParams, StepSerial};
use crate::step_shaper::StepShaper;
use crate::MAX_AXES;

/// Bit positions in [`CoreOutputs::pins`] (the layout of the Verilator shim).
pub mod pins {
    /// Pin A of `axis` (step, up, or quadrature A).
    pub const fn pin_a(axis: usize) -> u32 {
        3 * axis as u32
    }
    /// Pin B of `axis` (direction, down, or quadrature B).
    pub const fn pin_b(axis: usize) -> u32 {
        3 * axis as u32 + 1
    }
    /// The enable pin of `axis`.
    pub const fn pin_en(axis: usize) -> u32 {
        3 * axis as u32 + 2
    }
    /// Sticky `rate_error` of `axis`.
    pub const fn rate_error(axis: usize) -> u32 {
        24 + axis as u32
    }
    /// Sticky `step_lost` of `axis`.
    pub const fn step_lost(axis: usize) -> u32 {
        32 + axis as u32
    }
    /// `rec_ready`.
    pub const REC_READY: u32 = 40;
    /// Sticky `record_error`.
    pub const RECORD_ERROR: u32 = 41;
    /// `block_end` pulse.
    pub const BLOCK_END: u32 = 42;
    /// `period_boundary`: the period timer's own boundary (`rec_ready` without the pbp
    /// block's hold).
    pub const PERIOD_BOUNDARY: u32 = 43;
    /// The mask of bit `index`.
    pub const fn bit(index: u32) -> u64 {
        1 << index
    }
}

/// Every output of the core in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct CoreOutputs {
    /// Pins and flags packed as in [`pins`]; the bits of axes at and above `n_axes` are 0.
    pub pins: u64,
    /// Each axis's `position` (two's complement steps); 0 for axes at and above `n_axes`.
    pub positions: [u32; MAX_AXES],
    /// The gantry's `error` (two's complement counts).
    pub gantry_error: u32,
    /// The gantry's `corrections` (net corrections applied, wrapping).
    pub gantry_corrections: u16,
    /// The gantry's flags: bit 0 `engaged`, bit 1 `alarm`, bit 2 `refused` (see
    /// [`crate::gantry_sync::flags`]).
    pub gantry_flags: u8,
}

impl CoreOutputs {
    /// Bit `index` of [`Self::pins`].
    pub fn bit(&self, index: u32) -> bool {
        self.pins & pins::bit(index) != 0
    }
    /// Pin A of `axis`.
    pub fn pin_a(&self, axis: usize) -> bool {
        self.bit(pins::pin_a(axis))
    }
    /// Pin B of `axis`.
    pub fn pin_b(&self, axis: usize) -> bool {
        self.bit(pins::pin_b(axis))
    }
    /// The enable pin of `axis`.
    pub fn pin_en(&self, axis: usize) -> bool {
        self.bit(pins::pin_en(axis))
    }
    /// `rate_error` of `axis`.
    pub fn rate_error(&self, axis: usize) -> bool {
        self.bit(pins::rate_error(axis))
    }
    /// `step_lost` of `axis`.
    pub fn step_lost(&self, axis: usize) -> bool {
        self.bit(pins::step_lost(axis))
    }
    /// `rec_ready`: this cycle is a period boundary.
    pub fn rec_ready(&self) -> bool {
        self.bit(pins::REC_READY)
    }
    /// `period_boundary`: a period of the timer ends in this cycle, also an idle period
    /// run while a pbp record holds `rec_ready` low.
    pub fn period_boundary(&self) -> bool {
        self.bit(pins::PERIOD_BOUNDARY)
    }
    /// `record_error`.
    pub fn record_error(&self) -> bool {
        self.bit(pins::RECORD_ERROR)
    }
    /// `block_end`.
    pub fn block_end(&self) -> bool {
        self.bit(pins::BLOCK_END)
    }
    /// The position of `axis` as a signed number of steps.
    pub fn position(&self, axis: usize) -> i32 {
        self.positions[axis] as i32
    }
}

/// A change of the outputs: `outputs` hold from cycle `cycle` on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event {
    /// The cycle (as [`Core::cycle`] after the edge) whose outputs differ from the
    /// cycle before.
    pub cycle: u64,
    /// The outputs in that cycle.
    pub outputs: CoreOutputs,
}

/// How a call of [`Core::run_chunk`] or [`Core::run_chunk_fast`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkEnd {
    /// Clock edges run in the call.
    pub cycles: u64,
    /// The last edge consumed the offered record (the call stopped there).
    pub consumed: bool,
}

/// The inputs of one cycle masked and decoded, shared by the per-clock and fast paths.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Settings {
    /// The period sampled: `max(period_clocks & P_MASK, 1)`, with the step engine
    /// `Ps = max(P with its low SL bits cleared, S)` ([`CoreParams::effective_period`]).
    pub(crate) period: u32,
    pub(crate) axes: [AxisSettings; MAX_AXES],
}

/// The cycle-accurate model of `finestep_core`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Core {
    pub(crate) params: CoreParams,
    /// Saturation value of the shaper counters, `2^TIMING_W - 1`.
    pub(crate) counter_max: u32,
    pub(crate) timer: PeriodTimer,
    pub(crate) dda: [DdaAxis; MAX_AXES],
    pub(crate) shaper: [StepShaper; MAX_AXES],
    pub(crate) gantry: GantrySync,
    /// The step engine's schedule when built with `step_shared`; the `dda` and `shaper`
    /// arrays are then its stores, visited in turn.
    pub(crate) engine: Option<StepEngine>,
    /// The digit-serial step engine when built with `step_digit` > 0.
    pub(crate) serial: Option<SerialCore>,
    /// The point-by-point comparison interpolator when built with `has_pbp`.
    pub(crate) pbp: Option<PbpCore>,
    pub(crate) cycle: u64,
}

/// The point-by-point comparison interpolator in the core
/// (docs/spec/pbp_interp.md#in-the-core): the block and the registers that hold a pbp
/// record's pair, decision divider and `BLOCK_END` while it runs, and the sticky refusal
/// of a record on a pair that is not built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct PbpCore {
    interp: PbpInterp,
    pair: usize,
    tick_div: u32,
    block_end: bool,
    refused: bool,
}

impl PbpCore {
    fn new() -> PbpCore {
        PbpCore { interp: PbpInterp::new(PbpParams::core()), pair: 0, tick_div: 0, block_end: false, refused: false }
    }

    /// Whether a record runs (the period timer is offered none meanwhile).
    fn busy(&self) -> bool {
        self.interp.outputs().busy
    }

    /// Whether the last edge left nothing for the next to settle: no `done` pulse, and no
    /// refusal for `clear_errors` to clear (the fast path's rule, with
    /// [`Core::pbp_waits`]).
    pub(crate) fn settled(&self, clear_errors: bool) -> bool {
        !(self.interp.outputs().done || self.refused && clear_errors)
    }

    /// The block's request on axis `i` in this cycle (+1, -1 or 0): its X and Y are the
    /// pair's axes `2 * pair` and `2 * pair + 1`.
    fn request(&self, i: usize) -> i8 {
        let out = self.interp.outputs();
        let k = i % 2;
        match (i / 2 == self.pair, out.req_valid[k], out.req_negative[k]) {
            (true, true, true) => -1,
            (true, true, false) => 1,
            _ => 0,
        }
    }

    /// The block's motion on axis `i` for the gantry: `busy` while a record runs on
    /// the pair holding it, and the direction of its next step there.
    fn motion(&self, i: usize) -> ExtMotion {
        let out = self.interp.outputs();
        let k = i % 2;
        let on = i / 2 == self.pair;
        ExtMotion { busy: on && out.busy, up: on && out.move_up[k], down: on && out.move_down[k] }
    }
}

/// The digit-serial step engine in the core (docs/spec/step_serial.md#in-the-core): the
/// engine and the `position` words collected from its digit stream.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct SerialCore {
    engine: StepSerial,
    /// The digits of the current visit so far, the newest on top.
    collect: u32,
    positions: [u32; MAX_AXES],
}

impl SerialCore {
    fn new(params: &CoreParams) -> SerialCore {
        SerialCore {
            engine: StepSerial::new(SerialParams {
                n_axes: params.n_axes,
                p_width: params.p_width,
                timing_w: params.timing_width,
                digit: params.step_digit,
            }),
            collect: 0,
            positions: [0; MAX_AXES],
        }
    }

    /// The position word a visit's last digit completes, written to its axis.
    fn collect_digit(&mut self) {
        let out = self.engine.outputs();
        let p = self.engine.params();
        let d = p.digit;
        let word = (u32::from(out.pos_digit) << (32 - d)) | (self.collect >> d);
        if u32::from(out.pos_index) == p.visit_clocks() - 1 && usize::from(out.pos_axis) < p.n_axes {
            self.positions[usize::from(out.pos_axis)] = word;
        }
        self.collect = word;
    }
}

impl Core {
    /// A core in its reset state at cycle 0.
    ///
    /// # Panics
    /// If `params` is outside the supported ranges (see [`CoreParams::validate`]);
    /// [`Core::try_new`] returns the error instead.
    pub fn new(params: CoreParams) -> Core {
        match Core::try_new(params) {
            Ok(core) => core,
            Err(e) => panic!("invalid core parameters: {e}"),
        }
    }

    /// A core in its reset state at cycle 0, or why `params` are not supported (see
    /// [`CoreParams::validate`]).
    ///
    /// With `params.step_shared` the core is built with the step engine
    /// (docs/spec/step_engine.md): one DDA and one shaper visiting the axes every
    /// `S = params.step_slots()` clocks, and no gantry block whatever `has_gantry` says
    /// (its inputs are ignored, its outputs read 0).
    pub fn try_new(params: CoreParams) -> Result<Core, ParamError> {
        params.validate()?;
        let counter_max = params.timing_mask();
        Ok(Core {
            params,
            counter_max,
            // p_act resets to S (1 without the engine).
            timer: PeriodTimer::with_reset_period(params.step_slots()),
            dda: [DdaAxis::default(); MAX_AXES],
            shaper: [StepShaper::new(counter_max); MAX_AXES],
            gantry: GantrySync::default(),
            engine: (params.step_shared && !params.step_serial()).then(|| StepEngine::new(params.step_slot_bits())),
            serial: params.step_serial().then(|| SerialCore::new(&params)),
            pbp: params.has_pbp.then(PbpCore::new),
            cycle: 0,
        })
    }

    /// Synchronous reset: every register to its reset state, cycle counter to 0.
    pub fn reset(&mut self) {
        *self = Core::new(self.params);
    }

    /// The design parameters.
    pub fn params(&self) -> CoreParams {
        self.params
    }

    /// Clock edges since reset (wrapping at 2^64).
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// The period timer's state.
    pub fn timer(&self) -> &PeriodTimer {
        &self.timer
    }

    /// The step engine's schedule (its `slot`), when built with `step_shared`.
    pub fn engine(&self) -> Option<&StepEngine> {
        self.engine.as_ref()
    }

    /// The DDA state of `axis` (with the step engine: the axis's DDA store).
    ///
    /// # Panics
    /// If `axis >= MAX_AXES`.
    pub fn dda(&self, axis: usize) -> &DdaAxis {
        &self.dda[axis]
    }

    /// The step shaper state of `axis` (with the step engine: the axis's shaper store).
    ///
    /// # Panics
    /// If `axis >= MAX_AXES`.
    pub fn shaper(&self, axis: usize) -> &StepShaper {
        &self.shaper[axis]
    }

    /// The drive pins of `axis` (A, B, enable) in the current cycle, from whichever step
    /// engine the core has (a function of the state only).
    pub fn drive_pins(&self, axis: usize) -> (bool, bool, bool) {
        match &self.serial {
            Some(serial) => {
                let o = serial.engine.outputs();
                let bit = |mask: u8| (mask >> axis) & 1 != 0;
                (bit(o.pin_a), bit(o.pin_b), bit(o.pin_en))
            }
            None => self.shaper[axis].pins(),
        }
    }

    /// The gantry synchronisation's state.
    pub fn gantry(&self) -> &GantrySync {
        &self.gantry
    }

    /// The outputs in the current cycle (a function of the state only).
    pub fn outputs(&self) -> CoreOutputs {
        let mut out = CoreOutputs::default();
        if let Some(serial) = &self.serial {
            let o = serial.engine.outputs();
            for i in 0..self.params.n_axes {
                let bit = |mask: u8| u64::from((mask >> i) & 1);
                out.pins |= bit(o.pin_a) << pins::pin_a(i)
                    | bit(o.pin_b) << pins::pin_b(i)
                    | bit(o.pin_en) << pins::pin_en(i)
                    | bit(o.rate_error) << pins::rate_error(i)
                    | bit(o.step_lost) << pins::step_lost(i);
                out.positions[i] = serial.positions[i];
            }
        }
        for (i, sh) in self.shaper[..self.params.n_axes].iter().enumerate() {
            if self.serial.is_some() {
                break;
            }
            out.pins |= u64::from(sh.pins) << pins::pin_a(i)
                | u64::from(sh.rate_error) << pins::rate_error(i)
                | u64::from(sh.step_lost) << pins::step_lost(i);
            out.positions[i] = sh.position;
        }
        // With the pbp block: no record is taken while its record runs; its refusals are
        // record errors, and its done ends a block as the timer's boundary does.
        let (refused, pbp_end) =
            self.pbp.as_ref().map_or((false, false), |p| (p.refused, p.interp.outputs().done && p.block_end));
        out.pins |= u64::from(self.rec_ready()) << pins::REC_READY
            | u64::from(self.timer.rec_ready()) << pins::PERIOD_BOUNDARY
            | u64::from(self.timer.record_error || refused) << pins::RECORD_ERROR
            | u64::from(self.timer.block_end || pbp_end) << pins::BLOCK_END;
        out.gantry_error = self.gantry.error;
        out.gantry_corrections = self.gantry.corrections;
        out.gantry_flags = self.gantry.flags();
        out
    }

    /// `rec_ready`: the period timer's, held low while a pbp record runs or a request of
    /// it waits for its axis's shaper visit.
    pub fn rec_ready(&self) -> bool {
        self.timer.rec_ready() && !self.pbp_waits()
    }

    /// The block's requests of this cycle, per axis (+1, -1 or 0; none without it).
    fn pbp_requests(&self) -> [i8; MAX_AXES] {
        let mut reqs = [0i8; MAX_AXES];
        if let Some(p) = &self.pbp {
            for (i, r) in reqs.iter_mut().enumerate().take(self.params.n_axes) {
                *r = p.request(i);
            }
        }
        reqs
    }

    /// The pbp block's motion per axis as the gantry sees it (`ext_busy`, `ext_up`,
    /// `ext_down`: docs/spec/pbp_interp.md#in-the-core); none without the block.
    pub fn pbp_motion(&self) -> [ExtMotion; MAX_AXES] {
        let mut ext = [ExtMotion::default(); MAX_AXES];
        if let Some(p) = &self.pbp {
            for (i, e) in ext.iter_mut().enumerate().take(self.params.n_axes) {
                *e = p.motion(i);
            }
        }
        ext
    }

    /// The pbp block holds the record port: its record runs, or (with the step engine)
    /// one of its requests has not reached its axis's shaper visit yet.
    #[inline]
    pub(crate) fn pbp_waits(&self) -> bool {
        // Without the block nothing is ever held (the engine holds only its requests).
        let Some(p) = &self.pbp else { return false };
        p.busy() || self.engine.as_ref().is_some_and(|e| e.ext_pending(&self.pbp_requests()))
    }

    /// The pbp block's edge (with the values of this cycle: the timer's boundary, `wait`
    /// = [`Self::pbp_waits`] before the edge) and the record the period timer is offered:
    /// none while the block waits; a pbp record as an idle period without `BLOCK_END`.
    /// `None` without the block: the timer is offered `inputs`' record as it is.
    fn pbp_edge(&mut self, inputs: &CoreInputs, wait: bool) -> Option<(bool, PeriodRecord)> {
        self.pbp.as_ref()?;
        let n = self.params.n_axes;
        let slots = self.params.step_slots();
        let timer_ready = self.timer.rec_ready();
        let p = self.pbp.as_mut()?;
        use finestep_interface::{flags, pbp_lanes as at, pbp_record};
        let record = &inputs.record;
        let offered = record.flags & flags::PBP != 0;
        let lane = |k: usize| record.inc[k].to_bits() as u32;
        // Field `lsb +: width` of lane `k` (hdl/interface.toml [pbp]).
        let field = |k: usize, lsb: u32, width: u32| (lane(k) >> lsb) & (u32::MAX >> (32 - width));
        let top = lane(at::BITS_LANE) >> at::BITS_LSB;
        let pair = ((top >> pbp_record::PAIR_0_BIT) & 0b11) as usize;
        let tick_div = field(at::TICK_DIV_LANE, at::TICK_DIV_LSB, at::TICK_DIV_WIDTH);
        // The pair is built, and the decisions are at least a visit of the step engine
        // apart (S clocks; 1 without it): one request per axis per visit.
        let pair_ok = 2 * pair + 1 < n && tick_div + 1 >= slots;
        let take = inputs.run && timer_ready && inputs.rec_valid && !wait && offered;
        // The lanes as they reach the block's ports (it keeps COORD_W and COUNT_W bits).
        let rec = PbpRecord {
            arc: top & u32::from(pbp_record::ARC) != 0,
            cw: top & u32::from(pbp_record::CW) != 0,
            x: i64::from(field(at::X_LANE, at::X_LSB, at::X_WIDTH)),
            y: i64::from(field(at::Y_LANE, at::Y_LSB, at::Y_WIDTH)),
            steps: u64::from(field(at::COUNT_LANE, at::COUNT_LSB, at::COUNT_WIDTH)),
        };
        p.interp.step(&PbpInputs {
            halt: inputs.halt || !inputs.run,
            tick_div: p.tick_div,
            rec_valid: take && pair_ok,
            rec,
        });
        if take {
            p.pair = pair;
            p.tick_div = tick_div;
            p.block_end = record.block_end();
        }
        if take && !pair_ok {
            p.refused = true;
        } else if inputs.clear_errors {
            p.refused = false;
        }
        Some(if offered {
            (inputs.rec_valid && !wait, PeriodRecord::from_raw(&[], record.flags & !flags::BLOCK_END))
        } else {
            (inputs.rec_valid && !wait, *record)
        })
    }

    /// The masked and decoded form of `inputs`.
    #[inline]
    pub(crate) fn settings(&self, inputs: &CoreInputs) -> Settings {
        let mut axes = [AxisSettings::default(); MAX_AXES];
        for (set, cfg) in axes.iter_mut().zip(&inputs.axes).take(self.params.n_axes) {
            *set = AxisSettings::masked(cfg, self.counter_max, inputs.halt);
        }
        Settings { period: self.params.effective_period(inputs.period_clocks), axes }
    }

    /// One rising clock edge with `inputs`; the cycle counter advances by 1.
    #[inline]
    pub fn step(&mut self, inputs: &CoreInputs) {
        let period = self.params.effective_period(inputs.period_clocks);
        let mask = self.counter_max;
        self.edge(inputs, period, |i| AxisSettings::masked(&inputs.axes[i], mask, inputs.halt));
    }

    /// One rising clock edge with decoded settings; returns whether an output changed.
    #[inline]
    pub(crate) fn step_with(&mut self, set: &Settings, inputs: &CoreInputs) -> bool {
        self.edge(inputs, set.period, |i| set.axes[i])
    }

    /// One rising clock edge; `axis(i)` gives axis `i`'s masked settings. Returns
    /// whether an output changed (exactly: the outputs after the edge differ from
    /// those before it).
    #[inline(always)]
    fn edge(&mut self, inputs: &CoreInputs, period: u32, axis: impl Fn(usize) -> AxisSettings) -> bool {
        // Without the pbp block none of its logic is compiled into the edge (`PBP`
        // false): the per-clock path of every other build pays nothing for it.
        if self.pbp.is_some() {
            self.edge_of::<true>(inputs, period, axis)
        } else {
            self.edge_of::<false>(inputs, period, axis)
        }
    }

    /// [`Self::edge`] for a core with (`PBP`) or without the pbp block.
    #[inline(always)]
    fn edge_of<const PBP: bool>(
        &mut self,
        inputs: &CoreInputs,
        period: u32,
        axis: impl Fn(usize) -> AxisSettings,
    ) -> bool {
        if let Some(engine) = self.engine {
            return self.engine_edge::<PBP>(engine, inputs, period, axis);
        }
        if self.serial.is_some() {
            return self.serial_edge(inputs, period, axis);
        }
        let n = self.params.n_axes;
        let m = i64::from(self.timer.p_act) * ONE_STEP;
        let mut changed = false;
        // With the pbp block its outputs change too: compared as a whole.
        let before = PBP.then(|| self.outputs());
        let wait = PBP && self.pbp_waits();
        // Each axis's own request of this cycle: the pbp block's where it requests (only
        // while its record runs, when the DDAs are idle), else its DDA's; the gantry sees
        // these and chooses among them.
        let pbp_reqs = if PBP { self.pbp_requests() } else { [0; MAX_AXES] };
        let mut reqs = [0i8; MAX_AXES];
        for ((r, dda), &p) in reqs.iter_mut().zip(&self.dda[..n]).zip(&pbp_reqs) {
            *r = if p != 0 { p } else { dda.req };
        }
        let gantry = self.gantry;
        let increments = self.timer.inc;
        let ext = if PBP { self.pbp_motion() } else { [ExtMotion::default(); MAX_AXES] };
        let axes = self.shaper[..n].iter_mut().zip(&mut self.dda[..n]).zip(&self.timer.inc[..n]).enumerate();
        // The DDAs hold their phase at M/2 until the period timer is running.
        let running = inputs.run && self.timer.active;
        if self.params.gantry_built() {
            for (i, ((shaper, dda), &d)) in axes {
                // The engaged slave takes the gantry's request only.
                let r = gantry.shaper_request(i, &reqs, &increments, &ext, &inputs.gantry);
                changed |= shaper.step(r, &axis(i), self.counter_max, inputs.clear_errors);
                dda.step(running, period, d, m);
            }
            changed |= self.gantry.step(
                &inputs.gantry,
                &GantryContext {
                    n_axes: n,
                    master_req: reqs[gantry.master()],
                    inc: increments,
                    ext,
                    halt: inputs.halt,
                    clear_errors: inputs.clear_errors,
                },
            );
        } else {
            // No gantry block: every axis its own request; the gantry stays in reset.
            for (i, ((shaper, dda), &d)) in axes {
                changed |= shaper.step(reqs[i], &axis(i), self.counter_max, inputs.clear_errors);
                dda.step(running, period, d, m);
            }
        }
        changed |= self.timer_edge::<PBP>(inputs, period, 0, 0, wait);
        before.map_or(changed, |before| self.outputs() != before)
    }

    /// One rising edge of a core with the step engine (`engine` is its schedule in this
    /// cycle): the engine's visits, then the period timer with this cycle's slot.
    #[inline(always)]
    fn engine_edge<const PBP: bool>(
        &mut self,
        mut engine: StepEngine,
        inputs: &CoreInputs,
        period: u32,
        axis: impl Fn(usize) -> AxisSettings,
    ) -> bool {
        let n = self.params.n_axes;
        let slot = engine.slot;
        // With the pbp block its outputs change too: compared as a whole. Its requests
        // reach the engine's shaper visits (held until then).
        let before = PBP.then(|| self.outputs());
        let wait = PBP && self.pbp_waits();
        let changed = engine.step::<PBP>(
            &EngineInputs {
                running: inputs.run && self.timer.active,
                p_act: self.timer.p_act,
                inc: &self.timer.inc,
                clear_errors: inputs.clear_errors,
                counter_max: self.counter_max,
                ext: if PBP { self.pbp_requests() } else { [0; MAX_AXES] },
            },
            axis,
            &mut self.dda[..n],
            &mut self.shaper[..n],
        );
        self.engine = Some(engine);
        let changed = changed | self.timer_edge::<PBP>(inputs, period, engine.slot_bits, slot, wait);
        before.map_or(changed, |before| self.outputs() != before)
    }

    /// One rising edge of a core with the digit-serial step engine: the engine's clock
    /// (with the timer's `run && active`, `p_act` and increments), the position words
    /// collected from its digit stream, then the period timer with `SL = log2 R` and the
    /// engine's `phase` as its slot.
    #[inline(always)]
    fn serial_edge(&mut self, inputs: &CoreInputs, period: u32, axis: impl Fn(usize) -> AxisSettings) -> bool {
        let n = self.params.n_axes;
        let before = self.outputs();
        let mut inp = SerialInputs {
            run: inputs.run && self.timer.active,
            p_active: self.timer.p_act,
            clear_errors: inputs.clear_errors,
            halt: inputs.halt,
            ..SerialInputs::default()
        };
        for i in 0..n {
            let set = axis(i);
            inp.inc[i] = self.timer.inc[i];
            inp.axis_enable |= u8::from(inputs.axes[i].enable) << i;
            let [len, space, setup, hold] = set.timing.to_array();
            inp.step_len[i] = len as u16;
            inp.step_space[i] = space as u16;
            inp.dir_setup[i] = setup as u16;
            inp.dir_hold[i] = hold as u16;
            inp.out_mode[i] = set.mode;
            inp.invert[i] = set.invert;
        }
        let serial = self.serial.as_mut().expect("built with the digit-serial engine");
        let phase = serial.engine.phase();
        // The digit the engine shows in this cycle is taken at this edge.
        serial.collect_digit();
        serial.engine.step(&inp);
        let bits = self.params.step_round_bits();
        // (no pbp block with the digit-serial engine: nothing waits)
        self.timer_edge::<false>(inputs, period, bits, phase, false);
        self.outputs() != before
    }

    /// The period timer's edge (with the engine's `SL` and this cycle's `slot`, 0 and 0
    /// without it; `pbp_wait`: [`Self::pbp_waits`] before the edge) and the cycle count;
    /// returns whether the timer's outputs changed. `PBP`: the core has the pbp block.
    #[inline(always)]
    fn timer_edge<const PBP: bool>(
        &mut self,
        inputs: &CoreInputs,
        period: u32,
        slot_bits: u32,
        slot: u32,
        pbp_wait: bool,
    ) -> bool {
        let timer_before = self.timer.output_bits();
        let offered = if PBP { self.pbp_edge(inputs, pbp_wait) } else { None };
        let (rec_valid, record) = offered.as_ref().map_or((inputs.rec_valid, &inputs.record), |(v, r)| (*v, r));
        self.timer.step(&TimerInputs {
            run: inputs.run,
            period,
            clear_errors: inputs.clear_errors,
            rec_valid,
            record,
            n_axes: self.params.n_axes,
            slot_bits,
            slot,
        });
        self.cycle = self.cycle.wrapping_add(1);
        self.timer.output_bits() != timer_before
    }

    /// One edge of a chunk: pushes an [`Event`] when the outputs change and returns
    /// whether the offered record was consumed at this edge.
    #[inline]
    pub(crate) fn chunk_edge(&mut self, set: &Settings, inputs: &CoreInputs, events: &mut Vec<Event>) -> bool {
        let consumed = self.rec_ready() && inputs.rec_valid;
        // The edge reports exactly whether the outputs differ from before it.
        if self.step_with(set, inputs) {
            events.push(Event { cycle: self.cycle, outputs: self.outputs() });
        }
        consumed
    }

    /// Runs up to `max_cycles` clock edges with the same `inputs`, one at a time,
    /// stopping after the edge that consumes the offered record. Every edge after which
    /// the outputs differ from before it pushes an [`Event`].
    pub fn run_chunk(&mut self, inputs: &CoreInputs, max_cycles: u64, events: &mut Vec<Event>) -> ChunkEnd {
        let set = self.settings(inputs);
        for ran in 1..=max_cycles {
            if self.chunk_edge(&set, inputs, events) {
                return ChunkEnd { cycles: ran, consumed: true };
            }
        }
        ChunkEnd { cycles: max_cycles, consumed: false }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::AxisConfig;
    use crate::record::PeriodRecord;
    use crate::DriveTiming;

    fn inputs(run: bool, period_clocks: u32) -> CoreInputs {
        let axis = AxisConfig { timing: DriveTiming::new(2, 2, 1, 1), enable: true, ..AxisConfig::default() };
        CoreInputs { run, period_clocks, axes: [axis; MAX_AXES], ..CoreInputs::default() }
    }

    #[test]
    fn reset_state_and_unused_axes_are_zero() {
        let params = CoreParams { n_axes: 2, ..CoreParams::default() };
        let mut core = Core::new(params);
        assert_eq!(core.cycle(), 0);
        assert_eq!(core.outputs(), CoreOutputs::default());
        core.step(&inputs(false, 10));
        let out = core.outputs();
        assert_eq!(out.pins, 0b110_110, "dir (pin B) and enable of axes 0 and 1 only");
        core.reset();
        assert_eq!(core, Core::new(params));
    }

    #[test]
    fn latency_from_record_to_pin_edge() {
        let mut core = Core::new(CoreParams::default());
        core.step(&inputs(false, 4));
        core.step(&inputs(true, 4));
        assert!(core.outputs().rec_ready());
        let b = core.cycle();
        let mut inp = inputs(true, 4);
        inp.rec_valid = true;
        // 3 steps in 4 clocks, with acc starting at M/2: first request after one update.
        inp.record = PeriodRecord::from_raw(&[3 << 16], 0);
        let mut events = vec![];
        let end = core.run_chunk(&inp, 10, &mut events);
        assert_eq!(end, ChunkEnd { cycles: 1, consumed: true });
        inp.rec_valid = false;
        let mut first_pos = None;
        let mut first_pin = None;
        for _ in 0..6 {
            core.step(&inp);
            let out = core.outputs();
            if out.position(0) == 1 && first_pos.is_none() {
                first_pos = Some(core.cycle());
            }
            if out.pin_a(0) && first_pin.is_none() {
                first_pin = Some(core.cycle());
            }
        }
        // DDA update in b+1, req in b+2, level and position in b+3, pin in b+4.
        assert_eq!(first_pos, Some(b + 3));
        assert_eq!(first_pin, Some(b + 4));
    }

    #[test]
    fn run_chunk_reports_changes_and_stops_at_consumption() {
        let mut core = Core::new(CoreParams::default());
        let mut events = vec![];
        let end = core.run_chunk(&inputs(false, 3), 5, &mut events);
        assert_eq!(end, ChunkEnd { cycles: 5, consumed: false });
        assert_eq!(events.len(), 1, "enable pins rise once");
        assert_eq!(events[0].cycle, 1);
        events.clear();
        let mut inp = inputs(true, 3);
        inp.rec_valid = true;
        let end = core.run_chunk(&inp, 100, &mut events);
        assert_eq!(end, ChunkEnd { cycles: 2, consumed: true });
        assert_eq!(events.len(), 2, "rec_ready rises, then falls");
        assert!(events[0].outputs.rec_ready() && !events[1].outputs.rec_ready());
    }

    #[test]
    fn a_correction_reaches_the_slave_shaper_the_cycle_after_its_tick() {
        let mut core = Core::new(CoreParams::default());
        let mut inp = inputs(false, 10);
        inp.gantry = crate::GantryInputs {
            master: 0,
            slave: 3,
            sync: true,
            tick: 5,
            deadband: 2,
            limit: 100,
            ..crate::GantryInputs::default()
        };
        for _ in 0..4 {
            core.step(&inp);
        }
        // Engaged at the edge of cycle e = 4 (square at counts 0); the count moves in the
        // next cycle, reaches diff one edge later and error one more.
        let e = core.cycle();
        inp.gantry.enable = true;
        let mut first = None;
        for k in 0..20 {
            if k == 1 {
                inp.gantry.enc_master = 8;
            }
            core.step(&inp);
            let out = core.outputs();
            assert_eq!(out.gantry_error, if core.cycle() >= e + 3 { 8 } else { 0 });
            if out.position(3) != 0 && first.is_none() {
                first = Some(core.cycle());
            }
        }
        // Ticks in e + 5, e + 10, ...: the tick at t = e + 5 sees error 8 > 2, the
        // slave's shaper takes the +1 in t + 1, and its position counts it in t + 2.
        assert_eq!(first, Some(e + 7));
        let out = core.outputs();
        // Without a plant the error stays: one step per tick, the ticks of e + 5, e + 10
        // and e + 15 applied by cycle e + 20 (that of e + 20 in e + 21).
        assert_eq!((out.position(0), out.position(3), out.gantry_corrections), (0, 3, 3));
        assert_eq!(out.gantry_flags, crate::gantry_sync::flags::ENGAGED);
    }

    #[test]
    fn bad_params_panic_or_error() {
        let params = CoreParams { n_axes: 0, ..CoreParams::default() };
        assert_eq!(Core::try_new(params).unwrap_err().name, "N_AXES");
        assert!(std::panic::catch_unwind(|| Core::new(params)).is_err());
        // The step engine needs P_WIDTH > SL; it builds no gantry, whatever HAS_GANTRY.
        let shared = CoreParams { step_shared: true, has_gantry: true, n_axes: 3, ..CoreParams::default() };
        let e = Core::try_new(CoreParams { p_width: 2, ..shared }).unwrap_err();
        assert_eq!((e.name, e.min), ("P_WIDTH", 3));
        let core = Core::try_new(shared).unwrap();
        assert_eq!(core.engine().map(|e| e.slots()), Some(4));
        assert_eq!(core.timer().p_act(), 4, "p_act resets to S");
        assert!(Core::new(CoreParams::default()).engine().is_none());
    }
}
