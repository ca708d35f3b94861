//! `register_file`: the register bus (arbiter, `rdata`), the registers of
//! `hdl/registers.toml`, the per-cycle bookkeeping (timestamp, position latch, period
//! count, interrupt, sticky flags, error counters) and the position FIFO's write-port
//! multiplexer.
//!
//! Specification: docs/spec/register_file.md and docs/spec/feedback_registers.md
//!
//! Addresses, field positions, access types and reset values come from the generated
//! register map ([`finestep_interface::regs`]); the `rw` bits live in one word per address,
//! masked on every write to the bits this build implements (timing fields to
//! `TIMING_W`, `PERIOD_CLOCKS` to `P_WIDTH`, `WATCHDOG_TIMEOUT` to `WD_W`, per-axis
//! registers and bits to `N_AXES`).
//!
//! Latency: a request granted in cycle `g` goes into the bus stage and is served in
//! cycle `n = g + 1` (the `served` input of [`RegisterFile::step`]; the stage is kept by
//! `top`): a read's value (from the state of cycle `n`) is in `rdata` in `n+1`; a write's
//! `rw` bits hold from `n+1`, and its pulses (`COMMAND`, `RECORD_PUSH`, the encoder and
//! probe arms, the watchdog kick) are high in `n+1` only.
//!
//! The feedback registers (encoders, probe, hand wheel, jog) read the blocks' state
//! through [`FeedbackStatus`]; their settings are `rw` bits here like any other.

use finestep_interface::regs;
use finestep_interface::{invert, Access, CountMode, DriveTiming, Field};

use crate::encoder_bank::{ChannelConfig, EncoderBankStatus, ProbeConfig, MAX_CHANNELS};
use crate::hand_wheel::HandWheelStatus;
use crate::jog_generator::{JogInputs, JogStatus};
use crate::logic_outputs::InterlockConfig;
use crate::position_fifo::FifoInputs;
use crate::record::PeriodRecord;
pub use crate::register_bus::BusRequest;
use crate::spi_frame::{SpiFifoPort, SpiFrameEvents};
use crate::spindle::SpindleConfig;
use crate::TopParams;
use crate::{Increment, MAX_AXES};

/// Number of word addresses on the register bus (7-bit addresses).
pub const ADDRESSES: usize = 1 << regs::ADDRESS_BITS;

/// Which master the register bus serves in a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grant {
    /// The SPI frame layer (it has priority).
    Spi,
    /// The parallel slave.
    Parallel,
}

/// The arbiter: the SPI frame layer if it requests, else the parallel slave if it does;
/// while a push holds the bus (`hold`, [`RegisterFile::bus_hold`]) a request that
/// touches the push ([`touches_push`]) is not granted (its master keeps it) and the
/// others are, in the same order.
pub fn arbitrate(spi: Option<BusRequest>, parallel: Option<BusRequest>, hold: bool) -> Option<(Grant, BusRequest)> {
    let grantable = |request: &BusRequest| !(hold && touches_push(request));
    match (spi.filter(grantable), parallel.filter(grantable)) {
        (Some(request), _) => Some((Grant::Spi, request)),
        (None, Some(request)) => Some((Grant::Parallel, request)),
        (None, None) => None,
    }
}

/// A request that a push's hold keeps waiting: a read of the axis block
/// (`AXIS_TIMING_A/B`, `AXIS_MODE`: the 32 words from `AXIS_TIMING_A`) or of the 8 words
/// of `RECORD_INC` (the register file's readback store answers them, and the push reads
/// that store), and a write of `RECORD_INC` or `RECORD_PUSH` (the pushed record is
/// `RECORD_INC` as written before the push; one push at a time).
pub fn touches_push(request: &BusRequest) -> bool {
    let addr = request.addr & (ADDRESSES - 1) as u8;
    let in_inc = addr >> 3 == regs::record_inc::ADDR >> 3;
    if request.write {
        in_inc || addr == regs::record_push::ADDR
    } else {
        in_inc || addr >> 5 == regs::axis_timing_a::ADDR >> 5
    }
}

/// The hardware values a register read shows, from the other blocks in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HardwareStatus {
    /// The core's run, `(CONTROL.RUN || jog engaged) && !halt` (`STATUS.RUNNING`; the
    /// boundary, the position latch and `PERIOD` follow it).
    pub core_run: bool,
    /// Motion control's gate (`STATUS.STREAMING`).
    pub gate: bool,
    /// The machine's `halt`: the safety monitor's, or the gantry's alarm.
    pub halt: bool,
    /// Sticky E-stop fault.
    pub fault_estop: bool,
    /// Sticky watchdog fault.
    pub fault_watchdog: bool,
    /// The filtered E-stop is active.
    pub estop_active: bool,
    /// Motion control's sticky `UNDERRUN`.
    pub underrun: bool,
    /// The core's sticky `record_error`.
    pub record_error: bool,
    /// Per-axis `rate_error`, bit `i` for axis `i`.
    pub rate_error: u8,
    /// Per-axis `step_lost`, bit `i` for axis `i`.
    pub step_lost: u8,
    /// The FIFO's committed records.
    pub fifo_level: usize,
    /// The FIFO's free room: depth - committed - staged.
    pub fifo_free: usize,
    /// The encoders, probe, hand wheel and jog.
    pub feedback: FeedbackStatus,
    /// The spindle and the interlock: what a read of their registers shows, so `top`
    /// fills it only in a cycle that serves a read (all 0 otherwise).
    pub io: IoStatus,
}

/// The spindle's and the logic outputs' register view in one cycle (0 for blocks not built).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IoStatus {
    /// `SPINDLE_STATUS.LEVEL`.
    pub spindle_level: u32,
    /// `SPINDLE_STATUS.AT_SPEED`.
    pub spindle_at_speed: bool,
    /// `SPINDLE_STATUS.ENABLED`: the enable pin.
    pub spindle_enabled: bool,
    /// `INTERLOCK.ACTIVE`.
    pub interlock_active: bool,
    /// `INTERLOCK.BLOCKED`.
    pub interlock_blocked: bool,
    /// `PANEL_KEYS` (with `HAS_PANEL`).
    pub panel_keys: u32,
    /// `PANEL_MENU` (with `HAS_PANEL`): the menu's shadows, not a stored word.
    pub panel_menu: u32,
    /// `GANTRY_STATUS` (where the gantry is built).
    pub gantry_status: u32,
}

/// The feedback blocks' register view in one cycle (all 0 for blocks not built).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FeedbackStatus {
    /// The encoder channels and the probe: only what a read of their registers shows, so
    /// `top` fills it only in a cycle that serves a read (all 0 otherwise).
    pub encoders: EncoderBankStatus,
    /// Some encoder channel's `ILLEGAL` (every cycle: `STATUS` and the interrupt use it).
    pub encoder_illegal: bool,
    /// The hand wheel.
    pub hand_wheel: HandWheelStatus,
    /// The jog generator.
    pub jog: JogStatus,
}

impl FeedbackStatus {
    /// `STATUS.FEEDBACK_ERROR`: some channel's or the hand wheel's `ILLEGAL`.
    pub fn feedback_error(&self) -> bool {
        self.encoder_illegal || self.hand_wheel.illegal
    }
}

/// Whether `POSITION` (and with it `LATCH_TIME`) is latched at this edge, `latch_now`:
/// `!latch_hold && (boundary || !running)`, with `running` the core's run. It also asks
/// the encoder bank for this cycle's `ENC_COUNT` and `ENC_EDGE_TIME`, copied at each
/// channel's next visit.
pub fn position_latch(core_run: bool, period_boundary: bool, latch_hold: bool) -> bool {
    // `boundary || !running` with `boundary = running && period_boundary`.
    !latch_hold && (period_boundary || !core_run)
}

/// Everything the register file sees in one cycle besides its own state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RegisterFileInputs {
    /// The request served at this edge, if any.
    pub served: Option<BusRequest>,
    /// Hardware values of this cycle.
    pub hw: HardwareStatus,
    /// The core's `period_boundary` (its period timer's boundary, also the idle periods
    /// a pbp record runs while `rec_ready` is low).
    pub period_boundary: bool,
    /// The core's `block_end`.
    pub block_end: bool,
    /// The core's `position` of every axis.
    pub positions: [u32; MAX_AXES],
    /// The SPI frame layer's `latch_hold`.
    pub latch_hold: bool,
    /// The probe's event in this cycle (the encoder bank's): with `ONE_SNAPSHOT` it takes
    /// the position latch.
    pub probe_event: bool,
    /// `PROBE_STATUS.SEEN` before this edge: with `ONE_SNAPSHOT` the period latch leaves
    /// the position latch alone while it is set.
    pub probe_seen: bool,
    /// The SPI frame layer's error events.
    pub spi: SpiFrameEvents,
    /// A parallel error.
    pub parallel_error: bool,
    /// Motion control counted an underrun.
    pub underrun: bool,
    /// The FIFO port refused a `push` (see [`RegisterFile::fifo_port`]).
    pub push_refused: bool,
    /// The FIFO is flushed in this cycle (a push in flight is dropped).
    pub fifo_flush: bool,
    /// The FIFO is full in this cycle (`INC_DIRECT`: a `RECORD_INC` write is lost).
    pub fifo_full: bool,
    /// The SPI frame layer uses the FIFO's write port in this cycle
    /// ([`SpiFifoPort::owns_port`]; `INC_DIRECT`: a `RECORD_INC` write is lost and the
    /// lanes written are forgotten).
    pub spi_fifo_in_use: bool,
}

/// State of the register file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RegisterFile {
    params: TopParams,
    /// The `rw` bits of every address.
    rw: [u32; ADDRESSES],
    /// The `rw` bits this build implements at every address.
    write_mask: [u32; ADDRESSES],
    rdata: u32,
    clear_errors: bool,
    clear_faults: bool,
    flush_cmd: bool,
    clear_counters: bool,
    push: bool,
    push_flags: u8,
    /// The push sequence: `k` in the `k`-th cycle after the cycle serving a `RECORD_PUSH`
    /// write (`1..=N_AXES`), 0 when idle. The register file reads `RECORD_INC[k]` from
    /// its store in cycle `k` (no grant in cycles `0..N_AXES`) and writes it into the
    /// FIFO's record in cycle `k + 1`.
    push_seq: usize,
    /// The push accepted in cycle 1 goes on (no flush since).
    push_active: bool,
    /// The record being pushed (`RECORD_INC` and the flags as of cycle 1).
    push_flight: PeriodRecord,
    /// The record a push wrote (staged) in the previous cycle: committed in this one.
    push_commit: bool,
    /// `INC_DIRECT`: bit `i` set when `RECORD_INC[i]` was written into the FIFO's record
    /// (the FIFO not full, its port not the SPI frame layer's) since the last push, flush
    /// or use of the port by the SPI frame layer.
    inc_written: u8,
    kick: bool,
    /// `ENC_CONTROL.ARM_INDEX_LATCH` pulses, bit `c` for channel `c`.
    arm_index_latch: u8,
    /// `ENC_CONTROL.ARM_INDEX_CLEAR` pulses.
    arm_index_clear: u8,
    /// `PROBE_CONTROL.ARM` pulse.
    probe_arm: bool,
    timestamp: u32,
    latch_time: u32,
    period_count: u32,
    positions: [u32; MAX_AXES],
    irq_period: bool,
    irq_block_end: bool,
    irq: bool,
    overflow: bool,
    bus_error: bool,
    underrun_count: u16,
    crc_error_count: u16,
    frame_error_count: u16,
    parallel_error_count: u16,
    refused_record_count: u16,
    halt_prev: bool,
    /// [`RegisterFile::axis_config`] of every axis, a function of `rw` kept beside it
    /// (refreshed whenever a write is served: the core reads it every clock).
    axis_configs: [crate::AxisConfig; MAX_AXES],
}

/// Element `i` of the register array at `base` with `stride`, if `addr` is one of its
/// first `count` elements (the axes or channels this build has).
fn element_index(addr: u8, base: u8, stride: u8, count: usize) -> Option<usize> {
    let offset = addr.checked_sub(base)?;
    if offset % stride != 0 {
        return None;
    }
    let index = usize::from(offset / stride);
    (index < count).then_some(index)
}

/// `field` narrowed to its low `width` bits (no narrower than it is).
fn narrowed(field: Field, width: u32) -> Field {
    Field { lsb: field.lsb, width: field.width.min(width) }
}

/// The register arrays with one element per axis.
const PER_AXIS_ARRAYS: [u8; 5] = [
    regs::axis_timing_a::ADDR,
    regs::axis_timing_b::ADDR,
    regs::axis_mode::ADDR,
    regs::position::ADDR,
    regs::record_inc::ADDR,
];

/// The register arrays with one element per encoder channel.
const PER_CHANNEL_ARRAYS: [u8; 6] = [
    regs::enc_count::ADDR,
    regs::enc_index_latch::ADDR,
    regs::enc_probe_latch::ADDR,
    regs::enc_edge_time::ADDR,
    regs::enc_control::ADDR,
    regs::enc_status::ADDR,
];

/// The registers of the hand wheel and the jog: absent, reading 0, without `HAS_MPG`.
const HAND_WHEEL_REGISTERS: [u8; 12] = [
    regs::mpg_status::ADDR,
    regs::mpg_count::ADDR,
    regs::mpg_detents::ADDR,
    regs::mpg_control::ADDR,
    regs::jog_control::ADDR,
    regs::jog_scale::ADDR,
    regs::jog_vmax::ADDR,
    regs::jog_accel::ADDR,
    regs::jog_window::ADDR,
    regs::jog_status::ADDR,
    regs::jog_remaining::ADDR,
    regs::jog_velocity::ADDR,
];

/// The spindle's registers: absent, reading 0, without `HAS_SPINDLE`.
const SPINDLE_REGISTERS: [u8; 5] = [
    regs::spindle_control::ADDR,
    regs::spindle_period::ADDR,
    regs::spindle_level::ADDR,
    regs::spindle_ramp::ADDR,
    regs::spindle_status::ADDR,
];

/// The logic outputs' and the interlock's registers: absent without `HAS_OUTPUTS`.
const OUTPUT_REGISTERS: [u8; 3] = [regs::outputs::ADDR, regs::outputs_safe::ADDR, regs::interlock::ADDR];

/// The panel's registers: absent without `HAS_PANEL`.
const PANEL_REGISTERS: [u8; 3] = [regs::panel_scan::ADDR, regs::panel_keys::ADDR, regs::panel_menu::ADDR];

/// The gantry pair's registers: absent where it is not built.
const GANTRY_REGISTERS: [u8; 3] = [regs::gantry_control::ADDR, regs::gantry_limits::ADDR, regs::gantry_status::ADDR];

/// The `rw` bits this build implements, per address, and their reset values.
fn implemented_rw(params: &TopParams) -> ([u32; ADDRESSES], [u32; ADDRESSES]) {
    let mut mask = [0u32; ADDRESSES];
    let mut reset = [0u32; ADDRESSES];
    for register in regs::REGISTERS {
        let per_axis = PER_AXIS_ARRAYS.contains(&register.addr);
        let per_channel = PER_CHANNEL_ARRAYS.contains(&register.addr);
        if !params.has_mpg && HAND_WHEEL_REGISTERS.contains(&register.addr) {
            continue;
        }
        if !params.has_spindle && SPINDLE_REGISTERS.contains(&register.addr) {
            continue;
        }
        if !params.has_outputs && OUTPUT_REGISTERS.contains(&register.addr) {
            continue;
        }
        // PANEL_MENU's fields are the menu's (read through its shadows), not stored here.
        if (!params.has_panel && PANEL_REGISTERS.contains(&register.addr)) || register.addr == regs::panel_menu::ADDR {
            continue;
        }
        if !params.gantry_built() && GANTRY_REGISTERS.contains(&register.addr) {
            continue;
        }
        for index in 0..register.count() {
            if (per_axis && index >= params.n_axes) || (per_channel && index >= params.n_enc) {
                continue;
            }
            let Some(addr) = register.addr_of(index) else { continue };
            for info in register.fields.iter().filter(|f| f.access == Access::ReadWrite) {
                let width = match register.addr {
                    regs::axis_timing_a::ADDR | regs::axis_timing_b::ADDR => params.timing_w,
                    regs::period_clocks::ADDR => params.p_width,
                    regs::watchdog_timeout::ADDR => params.wd_w,
                    regs::axis_enable::ADDR => params.n_axes as u32,
                    regs::outputs::ADDR | regs::outputs_safe::ADDR if info.field == regs::outputs::GPIO => {
                        params.n_gpio as u32
                    }
                    _ => info.field.width,
                };
                let field = narrowed(info.field, width);
                mask[usize::from(addr)] |= field.mask();
                reset[usize::from(addr)] |= field.set(0, info.reset.unwrap_or(0) & field.max());
            }
        }
    }
    (mask, reset)
}

impl RegisterFile {
    /// The reset state for a build with `params`.
    pub fn new(params: &TopParams) -> Self {
        let (write_mask, rw) = implemented_rw(params);
        let mut file = RegisterFile {
            params: *params,
            rw,
            write_mask,
            rdata: 0,
            clear_errors: false,
            clear_faults: false,
            flush_cmd: false,
            clear_counters: false,
            push: false,
            push_flags: 0,
            push_seq: 0,
            push_active: false,
            push_flight: PeriodRecord::default(),
            push_commit: false,
            inc_written: 0,
            kick: false,
            arm_index_latch: 0,
            arm_index_clear: 0,
            probe_arm: false,
            timestamp: 0,
            latch_time: 0,
            period_count: 0,
            positions: [0; MAX_AXES],
            irq_period: false,
            irq_block_end: false,
            irq: false,
            overflow: false,
            bus_error: false,
            underrun_count: 0,
            crc_error_count: 0,
            frame_error_count: 0,
            parallel_error_count: 0,
            refused_record_count: 0,
            // The power-on halt must not flush an empty FIFO a second time.
            halt_prev: true,
            axis_configs: [crate::AxisConfig::default(); MAX_AXES],
        };
        file.refresh_axis_configs();
        file
    }

    fn refresh_axis_configs(&mut self) {
        self.axis_configs = std::array::from_fn(|axis| self.axis_config_of_rw(axis));
    }

    /// The `rw` bits of the register at `addr` as they are held now.
    pub fn word(&self, addr: u8) -> u32 {
        self.rw[usize::from(addr) & (ADDRESSES - 1)]
    }

    fn rw_field(&self, addr: u8, field: Field) -> u32 {
        field.get(self.rw[usize::from(addr)])
    }

    /// `rdata`: the value of the last read served.
    pub fn rdata(&self) -> u32 {
        self.rdata
    }

    /// The spindle's configuration (`SPINDLE_*`).
    pub fn spindle_config(&self) -> SpindleConfig {
        use regs::spindle_control as c;
        let control = self.rw[usize::from(c::ADDR)];
        SpindleConfig {
            enable: c::ENABLE.get(control) != 0,
            dir: c::DIR.get(control) != 0,
            dac: c::DAC.get(control) != 0,
            dac_div: c::DAC_DIV.get(control),
            period: self.rw_field(regs::spindle_period::ADDR, regs::spindle_period::CLOCKS),
            command: self.rw_field(regs::spindle_level::ADDR, regs::spindle_level::LEVEL),
            ramp: self.rw_field(regs::spindle_ramp::ADDR, regs::spindle_ramp::STEP),
        }
    }

    /// The `OUTPUTS` word (mist, flood, light, the general outputs at their fields).
    pub fn outputs(&self) -> u32 {
        self.rw[usize::from(regs::outputs::ADDR)]
    }

    /// The interlock's configuration (`INTERLOCK`).
    pub fn interlock_config(&self) -> InterlockConfig {
        use regs::interlock as i;
        let word = self.rw[usize::from(i::ADDR)];
        InterlockConfig {
            enable: i::ENABLE.get(word) != 0,
            active_high: i::ACTIVE_HIGH.get(word) != 0,
            filter: i::FILTER.get(word),
            prescale: i::PRESCALE.get(word) as u16,
        }
    }

    /// `CONTROL.RUN`.
    pub fn run(&self) -> bool {
        self.rw_field(regs::control::ADDR, regs::control::RUN) != 0
    }

    /// `CONTROL.WATCHDOG_ENABLE`.
    pub fn watchdog_enable(&self) -> bool {
        self.rw_field(regs::control::ADDR, regs::control::WATCHDOG_ENABLE) != 0
    }

    /// `CONTROL.ESTOP_ACTIVE_HIGH`.
    pub fn estop_active_high(&self) -> bool {
        self.rw_field(regs::control::ADDR, regs::control::ESTOP_ACTIVE_HIGH) != 0
    }

    /// `WATCHDOG_TIMEOUT` in clocks.
    pub fn watchdog_timeout(&self) -> u32 {
        self.rw_field(regs::watchdog_timeout::ADDR, regs::watchdog_timeout::CLOCKS)
    }

    /// `ESTOP_FILTER` in samples.
    pub fn estop_filter(&self) -> u32 {
        self.rw_field(regs::estop_filter::ADDR, regs::estop_filter::SAMPLES)
    }

    /// `START_LEVEL` in records.
    pub fn start_level(&self) -> u32 {
        self.rw_field(regs::start_level::ADDR, regs::start_level::LEVEL)
    }

    /// `PERIOD_CLOCKS` (masked to `P_WIDTH`).
    pub fn period_clocks(&self) -> u32 {
        self.rw_field(regs::period_clocks::ADDR, regs::period_clocks::CLOCKS)
    }

    /// The enable of `axis` (`AXIS_ENABLE`).
    pub fn axis_enable(&self, axis: usize) -> bool {
        let enables = self.rw_field(regs::axis_enable::ADDR, regs::axis_enable::ENABLE);
        axis < MAX_AXES && enables >> axis & 1 != 0
    }

    /// The step-shaper settings of `axis` from `AXIS_TIMING_A`/`_B`, `AXIS_MODE` and
    /// `AXIS_ENABLE` (all zero for an axis this build does not have).
    pub fn axis_config(&self, axis: usize) -> crate::AxisConfig {
        self.axis_configs.get(axis).copied().unwrap_or_default()
    }

    fn axis_config_of_rw(&self, axis: usize) -> crate::AxisConfig {
        if axis >= self.params.n_axes {
            return crate::AxisConfig::default();
        }
        use regs::axis_mode as m;
        let mode = self.rw[usize::from(m::addr(axis))];
        crate::AxisConfig {
            timing: DriveTiming::from_registers(axis, |addr| self.rw[usize::from(addr)]),
            mode: m::OUT_MODE.get(mode) as u8,
            invert: [(m::INVERT_A, invert::PIN_A), (m::INVERT_B, invert::PIN_B), (m::INVERT_EN, invert::PIN_EN)]
                .iter()
                .filter(|(field, _)| field.get(mode) != 0)
                .fold(0, |bits, (_, pin)| bits | pin),
            enable: self.axis_enable(axis),
        }
    }

    /// `INC_DIRECT`: every axis's `RECORD_INC` was written into the FIFO's record since the
    /// last push or flush (a push is accepted only then).
    fn inc_complete(&self) -> bool {
        let all = (1u16 << self.params.n_axes) - 1;
        u16::from(self.inc_written) == all
    }

    /// The record `RECORD_PUSH` queues: `RECORD_INC[0..N_AXES)` and `flags`.
    pub fn push_record(&self, flags: u8) -> PeriodRecord {
        let mut record = PeriodRecord { flags, ..PeriodRecord::default() };
        for (axis, inc) in record.inc[..self.params.n_axes].iter_mut().enumerate() {
            let word = self.rw[usize::from(regs::record_inc::addr(axis))];
            *inc = Increment::from_bits(regs::record_inc::INC.get(word) as i32);
        }
        record
    }

    /// `clear_errors` pulse (from `COMMAND.CLEAR_ERRORS`), high in this cycle.
    pub fn clear_errors(&self) -> bool {
        self.clear_errors
    }

    /// `clear_faults` pulse, high in this cycle.
    pub fn clear_faults(&self) -> bool {
        self.clear_faults
    }

    /// `clear_counters` pulse, high in this cycle.
    pub fn clear_counters(&self) -> bool {
        self.clear_counters
    }

    /// `TIMESTAMP` in this cycle.
    pub fn timestamp(&self) -> u32 {
        self.timestamp
    }

    /// `ENC_PRESCALE`.
    pub fn enc_prescale(&self) -> u16 {
        self.rw_field(regs::enc_prescale::ADDR, regs::enc_prescale::PRESCALE) as u16
    }

    /// Channel `c`'s `ENC_CONTROL` settings and this cycle's arm pulses (all 0 for a
    /// channel this build does not have).
    pub fn encoder_config(&self, c: usize) -> ChannelConfig {
        if c >= self.params.n_enc.min(MAX_CHANNELS) {
            return ChannelConfig::default();
        }
        use regs::enc_control as e;
        let word = self.rw[usize::from(e::addr(c))];
        ChannelConfig {
            mode: CountMode::from_bits(e::MODE.get(word)),
            z_active_high: e::Z_ACTIVE_HIGH.get(word) != 0,
            filter: e::FILTER.get(word) as u8,
            arm_index_latch: self.arm_index_latch >> c & 1 != 0,
            arm_index_clear: self.arm_index_clear >> c & 1 != 0,
        }
    }

    /// Every channel's [`Self::encoder_config`].
    pub fn encoder_configs(&self) -> [ChannelConfig; MAX_CHANNELS] {
        std::array::from_fn(|c| self.encoder_config(c))
    }

    /// `PROBE_CONTROL` and this cycle's `ARM` pulse.
    pub fn probe_config(&self) -> ProbeConfig {
        use regs::probe_control as p;
        let word = self.rw[usize::from(p::ADDR)];
        ProbeConfig {
            active_high: p::ACTIVE_HIGH.get(word) != 0,
            filter: p::FILTER.get(word) as u8,
            arm: self.probe_arm,
        }
    }

    /// `MPG_CONTROL`: `(PRESCALE, FILTER)`.
    pub fn mpg_control(&self) -> (u16, u8) {
        use regs::mpg_control as m;
        let word = self.rw[usize::from(m::ADDR)];
        (m::PRESCALE.get(word) as u16, m::FILTER.get(word) as u8)
    }

    /// `JOG_CONTROL.ENABLE`.
    pub fn jog_enable(&self) -> bool {
        self.rw_field(regs::jog_control::ADDR, regs::jog_control::ENABLE) != 0
    }

    /// The jog's settings (`JOG_CONTROL`, `JOG_SCALE`, `JOG_VMAX`, `JOG_ACCEL`,
    /// `JOG_WINDOW`) and `CONTROL.RUN`, `PERIOD_CLOCKS`, `N_AXES`, the pulses; the top
    /// fills in the rest.
    pub fn jog_inputs(&self) -> JogInputs {
        use regs::jog_control as j;
        let control = self.rw[usize::from(j::ADDR)];
        JogInputs {
            enable: j::ENABLE.get(control) != 0,
            axis: j::AXIS.get(control) as u8,
            multiplier: j::MULTIPLIER.get(control) as u8,
            follow: j::FOLLOW.get(control) != 0,
            scale: self.rw_field(regs::jog_scale::ADDR, regs::jog_scale::STEPS) as i32,
            vmax: self.rw_field(regs::jog_vmax::ADDR, regs::jog_vmax::STEPS),
            accel: self.rw_field(regs::jog_accel::ADDR, regs::jog_accel::STEPS),
            window: self.rw_field(regs::jog_window::ADDR, regs::jog_window::STEPS) as u16,
            run: self.run(),
            period_clocks: self.period_clocks(),
            n_axes: self.params.n_axes,
            clear_errors: self.clear_errors,
            clear_counters: self.clear_counters,
            ..JogInputs::default()
        }
    }

    /// `kick` pulse (a register write was served last cycle), high in this cycle.
    pub fn kick(&self) -> bool {
        self.kick
    }

    /// The FIFO's `flush` in this cycle: `flush_cmd`, or the rising edge of `halt`.
    pub fn fifo_flush(&self, halt: bool) -> bool {
        self.flush_cmd || (halt && !self.halt_prev)
    }

    /// The `irq` pin.
    pub fn irq(&self) -> bool {
        self.irq
    }

    /// A push holds the bus in this cycle: the register file reads `RECORD_INC` from its
    /// store for it (the cycle serving the `RECORD_PUSH` write, `served`, and the
    /// `N_AXES - 1` after it); requests that touch the push wait ([`arbitrate`]).
    pub fn bus_hold(&self, served: Option<BusRequest>) -> bool {
        if self.params.inc_direct {
            return false; // no push sequence
        }
        let push_served = matches!(served, Some(r) if r.write
            && r.addr & (ADDRESSES - 1) as u8 == regs::record_push::ADDR);
        push_served || (self.push_seq != 0 && self.push_seq < self.params.n_axes)
    }

    /// A push writes the FIFO's record in this cycle (accepted in its first cycle and not
    /// flushed since): the SPI frame layer sees no room (a FIFO frame's header is refused).
    pub fn push_in_flight(&self, accepted: bool) -> bool {
        if self.push_seq == 1 {
            accepted
        } else {
            self.push_active && self.push_seq != 0
        }
    }

    /// The FIFO's inputs in this cycle, whether a `push` is refused and whether a push is
    /// in flight ([`Self::push_in_flight`]): the SPI frame layer has the write port
    /// whenever it is busy or strobes; a `push` (the cycle after the `RECORD_PUSH` write
    /// was served) is refused when the FIFO is full or the SPI layer has the port, else
    /// accepted: its record `{push_flags, RECORD_INC}` is written (staged) in cycle
    /// `N_AXES` of the sequence and committed in the next (a commit takes the records
    /// staged before its cycle). A flush in between drops it.
    pub fn fifo_port(&self, spi: &SpiFifoPort, fifo_full: bool, halt: bool, pop: bool) -> (FifoInputs, bool, bool) {
        let flush = self.fifo_flush(halt);
        let mut inputs = FifoInputs { flush, clear_errors: self.clear_errors, pop, ..FifoInputs::default() };
        let mut refused = false;
        let mut accepted = false;
        if spi.owns_port() {
            inputs.write = spi.write;
            inputs.commit = spi.commit;
            inputs.abort = spi.abort;
            refused = self.push;
        } else if self.push {
            refused = fifo_full || (self.params.inc_direct && !self.inc_complete());
            accepted = !refused;
        }
        if self.params.inc_direct {
            // RECORD_INC is in the FIFO's record already: the push stages it with the
            // flags, now; it is committed in the next cycle.
            if accepted {
                inputs.write = Some(self.push_record(self.push_flags));
            }
            inputs.commit |= self.push_commit;
            return (inputs, refused, accepted);
        }
        let in_flight = self.push_in_flight(accepted);
        if in_flight && self.push_seq == self.params.n_axes {
            inputs.write = Some(if self.push_seq == 1 { self.push_record(self.push_flags) } else { self.push_flight });
        }
        inputs.commit |= self.push_commit;
        (inputs, refused, in_flight)
    }

    /// `STATUS` from this cycle's state.
    fn status(&self, hw: &HardwareStatus) -> u32 {
        use regs::status as s;
        let bits = [
            (s::RUNNING, hw.core_run),
            (s::STREAMING, hw.gate),
            (s::HALT, hw.halt),
            (s::FAULT_ESTOP, hw.fault_estop),
            (s::FAULT_WATCHDOG, hw.fault_watchdog),
            (s::ESTOP_ACTIVE, hw.estop_active),
            (s::UNDERRUN, hw.underrun),
            (s::OVERFLOW, self.overflow),
            (s::RECORD_ERROR, hw.record_error),
            (s::RATE_ERROR, hw.rate_error != 0),
            (s::STEP_LOST, hw.step_lost != 0),
            (s::BUS_ERROR, self.bus_error),
            (s::IRQ, self.irq),
            (s::FEEDBACK_ERROR, hw.feedback.feedback_error()),
            (s::JOG_ENGAGED, hw.feedback.jog.engaged),
            (s::JOG_REFUSED, hw.feedback.jog.refused),
        ];
        bits.iter().fold(0, |word, &(field, bit)| field.set(word, u32::from(bit)))
    }

    /// Whether a sticky error flag of `STATUS` is set (`IRQ_STATUS.ERROR`).
    fn any_error(&self, hw: &HardwareStatus) -> bool {
        use regs::status as s;
        let status = self.status(hw);
        let errors = [
            s::UNDERRUN,
            s::OVERFLOW,
            s::RECORD_ERROR,
            s::RATE_ERROR,
            s::STEP_LOST,
            s::BUS_ERROR,
            s::FEEDBACK_ERROR,
            s::JOG_REFUSED,
        ];
        errors.iter().any(|field| field.get(status) != 0)
    }

    /// `IRQ_STATUS` from this cycle's state.
    fn irq_status(&self, hw: &HardwareStatus) -> u32 {
        use regs::irq_status as i;
        let watermark = self.rw_field(regs::fifo_watermark::ADDR, regs::fifo_watermark::WATERMARK);
        let bits = [
            (i::FIFO_LOW, (hw.fifo_level as u64) < u64::from(watermark)),
            (i::PERIOD, self.irq_period),
            (i::BLOCK_END, self.irq_block_end),
            (i::FAULT, hw.halt),
            (i::ERROR, self.any_error(hw)),
        ];
        bits.iter().fold(0, |word, &(field, bit)| field.set(word, u32::from(bit)))
    }

    /// The value a read of `addr` (7 bits; higher bits ignored) returns in this cycle.
    pub fn read(&self, addr: u8, hw: &HardwareStatus) -> u32 {
        let addr = addr & (ADDRESSES - 1) as u8;
        let p = &self.params;
        let n = p.n_axes;
        // RECORD_INC is written as any rw register (the push takes it) but, write-only
        // (INC_WRITE_ONLY), reads 0.
        let write_only =
            p.inc_write_only && element_index(addr, regs::record_inc::ADDR, regs::record_inc::STRIDE, n).is_some();
        // So are the per-axis timing and mode registers (AXIS_WRITE_ONLY).
        let axis_block = [
            (regs::axis_timing_a::ADDR, regs::axis_timing_a::STRIDE),
            (regs::axis_timing_b::ADDR, regs::axis_timing_b::STRIDE),
            (regs::axis_mode::ADDR, regs::axis_mode::STRIDE),
        ];
        let write_only = write_only
            || p.axis_write_only
                && axis_block.iter().any(|&(base, stride)| element_index(addr, base, stride, n).is_some());
        let stored = if write_only { 0 } else { self.rw[usize::from(addr)] };
        let axes_mask = |mask: u8| u32::from(mask) & ((1u32 << n) - 1);
        let hardware = match addr {
            regs::id::ADDR => regs::id::MAGIC.set(0, regs::id::MAGIC_VALUE),
            regs::version::ADDR => {
                use regs::version as v;
                let word = v::MAJOR.set(0, regs::MAP_VERSION_MAJOR);
                let word = v::MINOR.set(word, regs::MAP_VERSION_MINOR);
                let word = v::PATCH.set(word, regs::MAP_VERSION_PATCH);
                // The capabilities CAPS has no room for.
                let word = v::ONE_SNAPSHOT.set(word, u32::from(p.one_snapshot));
                let word = v::INC_WRITE_ONLY.set(word, u32::from(p.inc_write_only));
                let word = v::HAS_PBP.set(word, u32::from(p.has_pbp));
                let word = v::INC_DIRECT.set(word, u32::from(p.inc_direct));
                let word = v::ENC_COUNT_16.set(word, u32::from(p.enc_count_w == 16));
                v::AXIS_WRITE_ONLY.set(word, u32::from(p.axis_write_only))
            }
            regs::caps::ADDR => {
                use regs::caps as c;
                [
                    (c::N_AXES, n as u32),
                    (c::N_ENC, p.n_enc as u32),
                    (c::FIFO_DEPTH_LOG2, p.fifo_depth_log2),
                    (c::P_WIDTH, p.p_width),
                    (c::TIMING_W, p.timing_w),
                    (c::HAS_SPI, u32::from(p.has_spi)),
                    (c::HAS_PARALLEL, u32::from(p.has_parallel)),
                    (c::HAS_MPG, u32::from(p.has_mpg)),
                    // log2 R: 0 without a shared step engine (R = 1).
                    (c::STEP_ROUND_LOG2, p.core_params().step_slots().trailing_zeros()),
                    (c::HAS_SPINDLE, u32::from(p.has_spindle)),
                    (c::HAS_OUTPUTS, u32::from(p.has_outputs)),
                    (c::HAS_PANEL, u32::from(p.has_panel)),
                    (c::HAS_GANTRY, u32::from(p.gantry_built())),
                ]
                .iter()
                .fold(0, |word, &(field, value)| field.set(word, value & field.max()))
            }
            regs::clock_hz::ADDR => regs::clock_hz::HZ.set(0, p.clock_hz),
            regs::status::ADDR => self.status(hw),
            regs::fifo_level::ADDR => {
                use regs::fifo_level as f;
                let level = (hw.fifo_level as u32).min(f::LEVEL.max());
                let free = (hw.fifo_free as u32).min(f::FREE.max());
                f::FREE.set(f::LEVEL.set(0, level), free)
            }
            regs::irq_status::ADDR => self.irq_status(hw),
            regs::timestamp::ADDR => regs::timestamp::CLOCKS.set(0, self.timestamp),
            regs::latch_time::ADDR => regs::latch_time::CLOCKS.set(0, self.latch_time),
            regs::period_count::ADDR => regs::period_count::COUNT.set(0, self.period_count),
            regs::underrun_count::ADDR => regs::underrun_count::COUNT.set(0, self.underrun_count.into()),
            regs::crc_error_count::ADDR => regs::crc_error_count::COUNT.set(0, self.crc_error_count.into()),
            regs::frame_error_count::ADDR => regs::frame_error_count::COUNT.set(0, self.frame_error_count.into()),
            regs::parallel_error_count::ADDR => {
                regs::parallel_error_count::COUNT.set(0, self.parallel_error_count.into())
            }
            regs::refused_record_count::ADDR => {
                regs::refused_record_count::COUNT.set(0, self.refused_record_count.into())
            }
            regs::axis_status::ADDR => {
                use regs::axis_status as a;
                a::STEP_LOST.set(a::RATE_ERROR.set(0, axes_mask(hw.rate_error)), axes_mask(hw.step_lost))
            }
            _ => match element_index(addr, regs::position::ADDR, regs::position::STRIDE, n) {
                Some(axis) => regs::position::STEPS.set(0, self.positions[axis]),
                None => self.read_feedback(addr, &hw.feedback) | self.read_io(addr, &hw.io),
            },
        };
        stored | hardware
    }

    /// The read value of the spindle's and the logic outputs' hardware fields.
    fn read_io(&self, addr: u8, io: &IoStatus) -> u32 {
        let p = &self.params;
        match addr {
            regs::spindle_status::ADDR if p.has_spindle => {
                use regs::spindle_status as s;
                let word = s::LEVEL.set(0, io.spindle_level);
                let word = s::AT_SPEED.set(word, u32::from(io.spindle_at_speed));
                s::ENABLED.set(word, u32::from(io.spindle_enabled))
            }
            regs::outputs::ADDR if p.has_outputs => regs::outputs::N_GPIO.set(0, p.n_gpio as u32),
            regs::interlock::ADDR if p.has_outputs => {
                use regs::interlock as i;
                i::BLOCKED.set(i::ACTIVE.set(0, u32::from(io.interlock_active)), u32::from(io.interlock_blocked))
            }
            regs::panel_keys::ADDR if p.has_panel => io.panel_keys,
            regs::panel_menu::ADDR if p.has_panel => io.panel_menu,
            regs::gantry_status::ADDR if p.gantry_built() => io.gantry_status,
            _ => 0,
        }
    }

    /// The read value of a feedback register's hardware fields (0 for other addresses).
    fn read_feedback(&self, addr: u8, fb: &FeedbackStatus) -> u32 {
        let p = &self.params;
        let enc = &fb.encoders;
        let wheel = &fb.hand_wheel;
        let jog = &fb.jog;
        let flags = |bits: &[(Field, u32)]| bits.iter().fold(0, |word, &(field, value)| field.set(word, value));
        if !p.has_mpg && HAND_WHEEL_REGISTERS.contains(&addr) {
            return 0;
        }
        match addr {
            regs::mpg_status::ADDR => {
                use regs::mpg_status as m;
                flags(&[
                    (m::ILLEGAL_COUNT, wheel.illegal_count.into()),
                    (m::ILLEGAL, wheel.illegal.into()),
                    (m::A, wheel.a.into()),
                    (m::B, wheel.b.into()),
                ])
            }
            regs::probe_status::ADDR => {
                use regs::probe_status as s;
                flags(&[
                    (s::ARMED, enc.probe_armed.into()),
                    (s::SEEN, enc.probe_seen.into()),
                    (s::ACTIVE, enc.probe_active.into()),
                ])
            }
            regs::probe_time::ADDR => {
                regs::probe_time::CLOCKS.set(0, if p.one_snapshot { self.latch_time } else { enc.probe_time })
            }
            regs::mpg_count::ADDR => regs::mpg_count::EDGES.set(0, wheel.count),
            regs::mpg_detents::ADDR => regs::mpg_detents::DETENTS.set(0, wheel.detents as u32),
            regs::jog_status::ADDR => {
                use regs::jog_status as j;
                flags(&[
                    (j::ENGAGED, jog.engaged.into()),
                    (j::STOPPING, jog.stopping.into()),
                    (j::REFUSED, jog.refused.into()),
                    (j::DROPPED, jog.dropped.into()),
                ])
            }
            regs::jog_remaining::ADDR => regs::jog_remaining::STEPS.set(0, jog.remaining),
            regs::jog_velocity::ADDR => regs::jog_velocity::STEPS.set(0, jog.velocity),
            _ => {
                let n_enc = p.n_enc.min(MAX_CHANNELS);
                let channel = |base: u8, stride: u8| element_index(addr, base, stride, n_enc).map(|c| &enc.channels[c]);
                if let Some(ch) = channel(regs::enc_count::ADDR, regs::enc_count::STRIDE) {
                    regs::enc_count::VALUE.set(0, ch.count)
                } else if let Some(ch) = channel(regs::enc_index_latch::ADDR, regs::enc_index_latch::STRIDE) {
                    regs::enc_index_latch::VALUE.set(0, ch.index_latch)
                } else if let Some(ch) = channel(regs::enc_probe_latch::ADDR, regs::enc_probe_latch::STRIDE) {
                    regs::enc_probe_latch::VALUE.set(0, ch.probe_latch)
                } else if let Some(ch) = channel(regs::enc_edge_time::ADDR, regs::enc_edge_time::STRIDE) {
                    regs::enc_edge_time::CLOCKS.set(0, ch.edge_time)
                } else if let Some(ch) = channel(regs::enc_status::ADDR, regs::enc_status::STRIDE) {
                    use regs::enc_status as s;
                    flags(&[
                        (s::ILLEGAL_COUNT, ch.illegal_count.into()),
                        (s::ILLEGAL, ch.illegal.into()),
                        (s::INDEX_SEEN, ch.index_seen.into()),
                        (s::LATCH_ARMED, ch.latch_armed.into()),
                        (s::CLEAR_ARMED, ch.clear_armed.into()),
                        (s::A, ch.a.into()),
                        (s::B, ch.b.into()),
                        (s::Z, ch.z.into()),
                    ])
                } else if let Some(axis) =
                    element_index(addr, regs::probe_position::ADDR, regs::probe_position::STRIDE, p.n_axes)
                {
                    let steps = if p.one_snapshot { self.positions[axis] } else { enc.probe_positions[axis] };
                    regs::probe_position::STEPS.set(0, steps)
                } else {
                    0
                }
            }
        }
    }

    /// One rising clock edge.
    pub fn step(&mut self, inp: &RegisterFileInputs) {
        let hw = &inp.hw;
        let irq_next = self.irq_status(hw) & self.rw_field(regs::irq_mask::ADDR, regs::irq_mask::MASK) != 0;
        let boundary = hw.core_run && inp.period_boundary;
        let clear_errors = self.clear_errors;
        let clear_counters = self.clear_counters;

        // The push sequence (see `fifo_port`).
        let n_axes = self.params.n_axes;
        if self.params.inc_direct {
            // No sequence: an accepted push is staged now and committed next cycle. The
            // lanes written: cleared by a push (accepted or not), a flush or the SPI
            // frame layer's use of the port (its records take the slot), else this
            // cycle's RECORD_INC write if the FIFO has room (a write in a push's cycle
            // is lost: it would not be in the record the push stages).
            self.push_commit = self.push && !inp.push_refused;
            let lane = match inp.served {
                Some(BusRequest { write: true, addr, .. }) if !inp.fifo_full && !inp.spi_fifo_in_use && !self.push => {
                    element_index(
                        addr & (ADDRESSES - 1) as u8,
                        regs::record_inc::ADDR,
                        regs::record_inc::STRIDE,
                        n_axes,
                    )
                }
                _ => None,
            };
            self.inc_written = if self.push || inp.fifo_flush || inp.spi_fifo_in_use {
                0
            } else {
                self.inc_written | lane.map_or(0, |axis| 1 << axis)
            };
        }
        let in_flight = !self.params.inc_direct && self.push_in_flight(self.push && !inp.push_refused);
        if !self.params.inc_direct {
            self.push_commit = in_flight && self.push_seq == n_axes;
        }
        if self.push_seq == 1 {
            self.push_flight = self.push_record(self.push_flags);
        }
        self.push_active = in_flight && !inp.fifo_flush && self.push_seq < n_axes;
        self.push_seq = if self.bus_hold(inp.served) && self.push_seq < n_axes { self.push_seq + 1 } else { 0 };

        // Pulses last one cycle.
        self.clear_errors = false;
        self.clear_faults = false;
        self.flush_cmd = false;
        self.clear_counters = false;
        self.push = false;
        self.kick = false;
        self.arm_index_latch = 0;
        self.arm_index_clear = 0;
        self.probe_arm = false;

        let safe_before = self.rw[usize::from(regs::outputs_safe::ADDR)];
        let mut irq_clear = 0;
        match inp.served {
            Some(BusRequest { write: false, addr, .. }) => self.rdata = self.read(addr, hw),
            Some(BusRequest { write: true, addr, wdata }) => {
                let addr = addr & (ADDRESSES - 1) as u8;
                let slot = usize::from(addr);
                self.rw[slot] = (self.rw[slot] & !self.write_mask[slot]) | (wdata & self.write_mask[slot]);
                self.refresh_axis_configs();
                self.kick = true;
                match addr {
                    regs::command::ADDR => {
                        use regs::command as c;
                        self.clear_errors = c::CLEAR_ERRORS.get(wdata) != 0;
                        self.clear_faults = c::CLEAR_FAULTS.get(wdata) != 0;
                        self.flush_cmd = c::FLUSH_FIFO.get(wdata) != 0;
                        self.clear_counters = c::CLEAR_COUNTERS.get(wdata) != 0;
                    }
                    regs::irq_status::ADDR => irq_clear = wdata,
                    regs::record_push::ADDR => {
                        self.push = true;
                        self.push_flags = regs::record_push::FLAGS.get(wdata) as u8;
                    }
                    regs::probe_control::ADDR => self.probe_arm = regs::probe_control::ARM.get(wdata) != 0,
                    _ => {
                        use regs::enc_control as e;
                        let n_enc = self.params.n_enc.min(MAX_CHANNELS);
                        if let Some(c) = element_index(addr, e::ADDR, e::STRIDE, n_enc) {
                            self.arm_index_latch = (e::ARM_INDEX_LATCH.get(wdata) as u8) << c;
                            self.arm_index_clear = (e::ARM_INDEX_CLEAR.get(wdata) as u8) << c;
                        }
                    }
                }
            }
            None => {}
        }
        // The jog and a FIFO run never both drive the core: RUN stays 0 while engaged.
        if hw.halt || hw.feedback.jog.engaged {
            let control = usize::from(regs::control::ADDR);
            self.rw[control] = regs::control::RUN.set(self.rw[control], 0);
        }
        if hw.halt {
            let jog = usize::from(regs::jog_control::ADDR);
            self.rw[jog] = regs::jog_control::ENABLE.set(self.rw[jog], 0);
            // The spindle stops and the logic outputs go safe; the host turns them on
            // again after the fault (the safe levels as they were before this edge).
            let spindle = usize::from(regs::spindle_control::ADDR);
            self.rw[spindle] = regs::spindle_control::ENABLE.set(self.rw[spindle], 0);
            self.rw[usize::from(regs::outputs::ADDR)] = safe_before;
        }

        let latch = position_latch(hw.core_run, inp.period_boundary, inp.latch_hold);
        let snapshot = if self.params.one_snapshot { inp.probe_event || (latch && !inp.probe_seen) } else { latch };
        if snapshot {
            self.positions = inp.positions;
            self.latch_time = self.timestamp;
        }
        self.timestamp = self.timestamp.wrapping_add(1);
        self.period_count = self.period_count.wrapping_add(u32::from(boundary));
        let keep = |flag: bool, field: Field| flag && field.get(irq_clear) == 0;
        self.irq_period = boundary || keep(self.irq_period, regs::irq_status::PERIOD);
        self.irq_block_end = inp.block_end || keep(self.irq_block_end, regs::irq_status::BLOCK_END);
        self.irq = irq_next;

        let refused = u16::from(inp.spi.refused_records) + u16::from(inp.push_refused);
        let bus_error = inp.spi.frame_error || inp.spi.crc_error || inp.parallel_error;
        self.overflow = refused != 0 || (self.overflow && !clear_errors);
        self.bus_error = bus_error || (self.bus_error && !clear_errors);
        let count = |counter: u16, add: u16| if clear_counters { 0 } else { counter.wrapping_add(add) };
        self.underrun_count = count(self.underrun_count, inp.underrun.into());
        self.crc_error_count = count(self.crc_error_count, inp.spi.crc_error.into());
        self.frame_error_count = count(self.frame_error_count, inp.spi.frame_error.into());
        self.parallel_error_count = count(self.parallel_error_count, inp.parallel_error.into());
        self.refused_record_count = count(self.refused_record_count, refused);
        self.halt_prev = hw.halt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(addr: u8, wdata: u32) -> RegisterFileInputs {
        RegisterFileInputs { served: Some(BusRequest { write: true, addr, wdata }), ..Default::default() }
    }

    #[test]
    fn rw_fields_keep_only_the_implemented_bits_and_reset_from_the_map() {
        let params = TopParams { n_axes: 2, timing_w: 4, p_width: 12, has_pbp: false, ..TopParams::default() };
        let mut rf = RegisterFile::new(&params);
        let hw = HardwareStatus::default();
        assert_eq!(rf.read(regs::control::ADDR, &hw), regs::control::reset_word());
        assert_eq!(rf.read(regs::period_clocks::ADDR, &hw), regs::period_clocks::CLOCKS_RESET & 0xFFF);
        rf.step(&write(regs::axis_timing_a::addr(1), 0xFFFF_FFFF));
        assert_eq!(rf.read(regs::axis_timing_a::addr(1), &hw), 0x000F_000F);
        rf.step(&write(regs::axis_timing_a::addr(2), 0xFFFF_FFFF));
        assert_eq!(rf.read(regs::axis_timing_a::addr(2), &hw), 0, "axis 2 of 2 does not exist");
        rf.step(&write(regs::axis_enable::ADDR, 0xFF));
        assert_eq!(rf.read(regs::axis_enable::ADDR, &hw), 0b11);
        assert!(rf.kick(), "every served write kicks the watchdog");
        rf.step(&write(0x7F, 0xFFFF_FFFF));
        assert_eq!(rf.read(0x7F, &hw), 0, "unmapped");
    }

    #[test]
    fn a_push_holds_only_the_requests_that_touch_it() {
        let read = |addr| BusRequest { write: false, addr, wdata: 0 };
        let write = |addr| BusRequest { write: true, addr, wdata: 0 };
        // Held: reads of the axis block and RECORD_INC, writes of RECORD_INC and RECORD_PUSH.
        for axis in 0..8 {
            for addr in [regs::axis_timing_a::addr(axis), regs::axis_timing_b::addr(axis), regs::axis_mode::addr(axis)]
            {
                assert!(touches_push(&read(addr)), "read {addr:#x}");
                assert!(!touches_push(&write(addr)), "write {addr:#x}");
            }
            assert!(touches_push(&read(regs::record_inc::addr(axis))));
            assert!(touches_push(&write(regs::record_inc::addr(axis))));
        }
        assert!(touches_push(&write(regs::record_push::ADDR)));
        for addr in [regs::status::ADDR, regs::fifo_level::ADDR, regs::position::addr(0), regs::command::ADDR] {
            assert!(!touches_push(&read(addr)) && !touches_push(&write(addr)), "{addr:#x}");
        }
        // The arbiter: SPI first, the parallel master's request when the SPI one waits.
        let (inc, status) = (read(regs::record_inc::addr(0)), read(regs::status::ADDR));
        assert_eq!(arbitrate(Some(inc), Some(status), false), Some((Grant::Spi, inc)));
        assert_eq!(arbitrate(Some(inc), Some(status), true), Some((Grant::Parallel, status)));
        assert_eq!(arbitrate(Some(status), Some(inc), true), Some((Grant::Spi, status)));
        assert_eq!(arbitrate(Some(inc), Some(inc), true), None);
        assert_eq!(arbitrate(None, Some(status), true), Some((Grant::Parallel, status)));
    }

    /// One cycle of the push sequence: what the FIFO port and the bus see, then the edge.
    fn push_cycle(
        rf: &mut RegisterFile,
        served: Option<BusRequest>,
        full: bool,
        flush_cmd: bool,
    ) -> (bool, FifoInputs, bool) {
        let spi = SpiFifoPort::default();
        let hold = rf.bus_hold(served);
        let (mut inputs, refused, in_flight) = rf.fifo_port(&spi, full, false, false);
        inputs.flush |= flush_cmd;
        rf.step(&RegisterFileInputs { served, push_refused: refused, fifo_flush: inputs.flush, ..Default::default() });
        (hold, inputs, in_flight)
    }

    #[test]
    fn a_push_holds_the_bus_writes_its_record_after_n_cycles_and_commits_it_in_the_next() {
        let params = TopParams { n_axes: 3, has_pbp: false, ..TopParams::default() };
        let mut rf = RegisterFile::new(&params);
        for (axis, raw) in [7u32, 0xFFFF_FFF0, 0x0001_0000].iter().enumerate() {
            rf.step(&write(regs::record_inc::addr(axis), *raw));
        }
        let push = Some(BusRequest { write: true, addr: regs::record_push::ADDR, wdata: 0x5A });
        let expected = rf.push_record(0x5A);
        // Cycle s serves the write: no grant; s+1, s+2: no grant (the store is read),
        // s+3 = s+N: the record is written; s+4: committed.
        let (hold, inputs, _) = push_cycle(&mut rf, push, false, false);
        assert!(hold && inputs.write.is_none() && !inputs.commit);
        for k in 1..=2 {
            let (hold, inputs, in_flight) = push_cycle(&mut rf, None, false, false);
            assert!(hold && in_flight && inputs.write.is_none() && !inputs.commit, "cycle s+{k}");
        }
        let (hold, inputs, in_flight) = push_cycle(&mut rf, None, false, false);
        assert!(!hold && in_flight && !inputs.commit);
        assert_eq!(inputs.write, Some(expected));
        let (hold, inputs, in_flight) = push_cycle(&mut rf, None, false, false);
        assert!(!hold && !in_flight && inputs.write.is_none() && inputs.commit);
        let (_, inputs, _) = push_cycle(&mut rf, None, false, false);
        assert!(!inputs.commit, "one commit");

        // Refused when full: the bus is still held, nothing written, nothing in flight.
        let (hold, _, _) = push_cycle(&mut rf, push, false, false);
        assert!(hold);
        let (hold, inputs, in_flight) = push_cycle(&mut rf, None, true, false);
        assert!(hold && !in_flight && inputs.write.is_none());
        assert!(rf.read(regs::status::ADDR, &HardwareStatus::default()) & regs::status::OVERFLOW.mask() != 0);
        for _ in 0..3 {
            let (_, inputs, in_flight) = push_cycle(&mut rf, None, false, false);
            assert!(!in_flight && inputs.write.is_none() && !inputs.commit);
        }

        // A flush in s+2 drops the push.
        push_cycle(&mut rf, push, false, false);
        push_cycle(&mut rf, None, false, false);
        let (_, _, in_flight) = push_cycle(&mut rf, None, false, true);
        assert!(in_flight);
        for _ in 0..3 {
            let (_, inputs, in_flight) = push_cycle(&mut rf, None, false, false);
            assert!(!in_flight && inputs.write.is_none() && !inputs.commit);
        }
    }

    #[test]
    fn command_pulses_last_one_cycle_and_run_drops_while_halted() {
        let mut rf = RegisterFile::new(&TopParams::default());
        rf.step(&write(regs::command::ADDR, regs::command::CLEAR_FAULTS.set(0, 1)));
        assert!(rf.clear_faults() && !rf.clear_errors());
        rf.step(&RegisterFileInputs::default());
        assert!(!rf.clear_faults());
        let halted = RegisterFileInputs {
            hw: HardwareStatus { halt: true, ..Default::default() },
            ..write(regs::control::ADDR, 1)
        };
        rf.step(&halted);
        assert!(!rf.run(), "halt wins over the write");
        rf.step(&write(regs::control::ADDR, 1));
        assert!(rf.run());
    }

    #[test]
    fn arm_pulses_last_one_cycle_and_the_jog_holds_run_at_zero() {
        let mut rf = RegisterFile::new(&TopParams::default());
        let arm = regs::enc_control::ARM_INDEX_CLEAR.set(regs::enc_control::reset_word(), 1);
        rf.step(&write(regs::enc_control::addr(3), arm));
        let config = rf.encoder_config(3);
        assert!(config.arm_index_clear && !config.arm_index_latch && config.z_active_high);
        assert!(!rf.encoder_config(2).arm_index_clear, "only the channel written");
        assert_eq!(rf.read(regs::enc_control::addr(3), &HardwareStatus::default()), regs::enc_control::reset_word());
        rf.step(&write(regs::probe_control::ADDR, regs::probe_control::ARM.mask()));
        assert!(rf.probe_config().arm && !rf.encoder_config(3).arm_index_clear);
        rf.step(&RegisterFileInputs::default());
        assert!(!rf.probe_config().arm);

        let engaged = HardwareStatus {
            feedback: FeedbackStatus { jog: JogStatus { engaged: true, ..Default::default() }, ..Default::default() },
            ..Default::default()
        };
        rf.step(&RegisterFileInputs { hw: engaged, ..write(regs::control::ADDR, 1) });
        assert!(!rf.run(), "RUN is forced to 0 while the jog is engaged");
        let status = rf.read(regs::status::ADDR, &engaged);
        assert_eq!(regs::status::JOG_ENGAGED.get(status), 1);
        rf.step(&write(regs::jog_control::ADDR, regs::jog_control::ENABLE.mask()));
        assert!(rf.jog_enable());
        let halted = HardwareStatus { halt: true, ..Default::default() };
        rf.step(&RegisterFileInputs { hw: halted, ..Default::default() });
        assert!(!rf.jog_enable(), "halt clears ENABLE");
    }

    #[test]
    fn absent_channels_and_hand_wheel_read_zero_and_keep_nothing() {
        let params = TopParams { n_enc: 1, has_mpg: false, ..TopParams::default() };
        let mut rf = RegisterFile::new(&params);
        let hw = HardwareStatus::default();
        assert_eq!(rf.read(regs::enc_control::addr(0), &hw), regs::enc_control::reset_word());
        assert_eq!(rf.read(regs::enc_control::addr(1), &hw), 0);
        assert_eq!(rf.read(regs::mpg_control::ADDR, &hw), 0);
        rf.step(&write(regs::jog_control::ADDR, u32::MAX));
        assert!(!rf.jog_enable());
        assert_eq!(rf.read(regs::jog_control::ADDR, &hw), 0);
        let caps = rf.read(regs::caps::ADDR, &hw);
        assert_eq!((regs::caps::N_ENC.get(caps), regs::caps::HAS_MPG.get(caps)), (1, 0));
    }
}
