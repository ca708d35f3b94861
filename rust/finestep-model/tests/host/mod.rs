//! Pin-level host masters for the `finestep_top` model: an SPI mode-0 master and an
//! STM32-FSMC-style 8080 master, each written from the spec's host timing, and the
//! frame encoding of the SPI protocol. Shared by the host-interface tests.

#![allow(dead_code)]

use finestep_interface::regs;
use finestep_model::top::{Top, TopInputs, TopOutputs, TopParams};
use finestep_model::{PeriodRecord, MAX_AXES};

/// CRC-16/IBM-3740 from the `crc` crate: the ideal the frames are checked against.
pub const CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);

/// Frame commands and result codes, as the frame table of docs/spec/spi_frame.md gives them.
pub const CMD_READ: u8 = 0x01;
pub const CMD_WRITE: u8 = 0x02;
pub const CMD_FIFO: u8 = 0x03;
pub const ACK: u8 = 0xA0;
pub const CRC_MISMATCH: u8 = 0xE1;
pub const BAD_COMMAND: u8 = 0xE2;
pub const FIFO_REFUSED: u8 = 0xE3;
pub const FIFO_FLUSHED: u8 = 0xE4;

/// What a test watches in one cycle (the state of that cycle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// Clock edges since the end of the last reset.
    pub cycle: u64,
    pub outputs: TopOutputs,
    pub fifo_level: usize,
    pub fifo_staged: usize,
    /// The core's `rec_ready`.
    pub rec_ready: bool,
    pub core_run: bool,
    pub gate: bool,
    pub halt: bool,
    /// The register file's watchdog kick pulse.
    pub kick: bool,
    pub underrun_count: u32,
    /// `CONTROL.RUN` as a read shows it.
    pub run_bit: bool,
    pub positions: [i32; MAX_AXES],
}

impl Sample {
    /// A period boundary while running.
    pub fn boundary(&self) -> bool {
        self.core_run && self.rec_ready
    }
}

/// A top and the pins presented to it.
pub struct Bench {
    pub top: Top,
    pub pins: TopInputs,
    /// Clock edges since the end of the last reset (what `TIMESTAMP` should read).
    pub since_reset: u64,
    /// When set, every cycle's [`Sample`] is appended.
    pub trace: Option<Vec<Sample>>,
    /// When set, every cycle the drive pins A and B of axis `c` are wired to encoder
    /// channel `c`'s A and B (an encoder reading back a quadrature axis).
    pub loopback: bool,
}

impl Bench {
    /// A top held in reset for 2 cycles with idle pins.
    pub fn new(params: TopParams) -> Bench {
        let mut bench =
            Bench { top: Top::new(params), pins: TopInputs::default(), since_reset: 0, trace: None, loopback: false };
        bench.reset();
        bench
    }

    /// `rst` for 2 cycles.
    pub fn reset(&mut self) {
        self.pins.rst = true;
        self.clock(2);
        self.pins.rst = false;
        self.since_reset = 0;
    }

    /// `n` clock edges with the current pins.
    pub fn clock(&mut self, n: u64) {
        for _ in 0..n {
            if self.trace.is_some() {
                let sample = self.sample();
                if let Some(trace) = self.trace.as_mut() {
                    trace.push(sample);
                }
            }
            if self.loopback {
                let out = self.top.outputs();
                self.pins.enc_a = out.pin_a;
                self.pins.enc_b = out.pin_b;
            }
            self.top.step(&self.pins);
            self.since_reset += 1;
        }
    }

    /// The state of the current cycle.
    pub fn sample(&self) -> Sample {
        let top = &self.top;
        let core = top.core().outputs();
        let mut positions = [0; MAX_AXES];
        for (axis, position) in positions.iter_mut().enumerate() {
            *position = core.position(axis);
        }
        Sample {
            cycle: self.since_reset,
            outputs: top.outputs(),
            fifo_level: top.fifo().level(),
            fifo_staged: top.fifo().staged(),
            rec_ready: core.rec_ready(),
            core_run: top.core_run(),
            gate: top.motion().gate(),
            halt: top.halt(),
            kick: top.registers().kick(),
            underrun_count: self.reg(regs::underrun_count::ADDR),
            run_bit: regs::control::RUN.get(self.reg(regs::control::ADDR)) != 0,
            positions,
        }
    }

    /// A register's value as a read would latch it now.
    pub fn reg(&self, addr: u8) -> u32 {
        self.top.register(addr)
    }

    /// Out of reset into a runnable machine: E-stop released (pin 0, active high) for
    /// longer than the filter, then `COMMAND.CLEAR_FAULTS` over the 8080 bus.
    pub fn bring_up(&mut self, bus: &ParallelMaster) {
        self.pins.estop_pin = false;
        self.clock(60);
        bus.write32(self, regs::command::ADDR, regs::command::CLEAR_FAULTS.set(0, 1));
        self.clock(4);
        assert_eq!(regs::status::HALT.get(self.reg(regs::status::ADDR)), 0, "bring-up left the machine halted");
    }
}

/// SPI mode-0 master at the pin level. Timing in core clocks, from
/// docs/spec/spi_frame.md: SCK at
/// most clk/8 (`half_period >= 4`), at least 4 clocks from CS_n falling to the first
/// SCK edge, CS_n rising half an SCK period after the last falling edge.
#[derive(Clone, Copy, Debug)]
pub struct SpiMaster {
    /// Clocks SCK stays high, and low, per bit (at least 4).
    pub half_period: u64,
    /// Clocks from CS_n falling to the first rising SCK edge (at least 4).
    pub cs_setup: u64,
    /// Clocks CS_n stays high after a frame.
    pub cs_idle: u64,
    /// Extra low clocks between bytes.
    pub byte_gap: u64,
}

impl Default for SpiMaster {
    /// The fastest legal timing.
    fn default() -> Self {
        SpiMaster { half_period: 4, cs_setup: 4, cs_idle: 4, byte_gap: 0 }
    }
}

/// One master's pins cycle by cycle, and the cycles at which it samples the outputs.
#[derive(Clone, Debug, Default)]
pub struct Waveform<P> {
    /// The master's pins in each cycle from the start.
    pub pins: Vec<P>,
    /// Cycles (from the start) at which the master samples what the slave drives.
    pub samples: Vec<usize>,
}

/// SPI pins of one cycle: (cs_n, sck, mosi).
pub type SpiLevels = (bool, bool, bool);

/// 8080 pins of one cycle: (cs_n, adv_n, rd_n, wr_n, ad).
pub type BusLevels = (bool, bool, bool, bool, u16);

/// Runs an SPI and an 8080 waveform at the same time (either may be empty), idle pins
/// after each ends. Returns the MISO bits and the `bus_ad` values (`None` when not
/// driven) at their sample cycles.
pub fn run_waveforms(
    bench: &mut Bench,
    spi: &Waveform<SpiLevels>,
    bus: &Waveform<BusLevels>,
) -> (Vec<bool>, Vec<Option<u16>>) {
    let cycles = spi.pins.len().max(bus.pins.len());
    let (mut miso, mut ad) = (vec![], vec![]);
    let (mut next_spi, mut next_bus) = (0, 0);
    for cycle in 0..cycles {
        let (cs_n, sck, mosi) = spi.pins.get(cycle).copied().unwrap_or((true, false, false));
        bench.pins.spi_cs_n = cs_n;
        bench.pins.spi_sck = sck;
        bench.pins.spi_mosi = mosi;
        let (cs_n, adv_n, rd_n, wr_n, data) = bus.pins.get(cycle).copied().unwrap_or((true, true, true, true, 0));
        bench.pins.bus_cs_n = cs_n;
        bench.pins.bus_adv_n = adv_n;
        bench.pins.bus_rd_n = rd_n;
        bench.pins.bus_wr_n = wr_n;
        bench.pins.bus_ad_in = data;
        let out = bench.top.outputs();
        if spi.samples.get(next_spi) == Some(&cycle) {
            assert!(out.spi_miso_oe, "MISO not driven during the frame");
            miso.push(out.spi_miso);
            next_spi += 1;
        }
        if bus.samples.get(next_bus) == Some(&cycle) {
            ad.push(out.bus_ad_oe.then_some(out.bus_ad_out));
            next_bus += 1;
        }
        bench.clock(1);
    }
    (miso, ad)
}

/// MSB-first bits into bytes (a partial last byte is dropped).
pub fn bits_to_bytes(bits: &[bool]) -> Vec<u8> {
    bits.chunks_exact(8).map(|c| c.iter().fold(0u8, |byte, &bit| byte << 1 | u8::from(bit))).collect()
}

impl SpiMaster {
    /// The pins of one frame sending the first `bits` bits of `tx` (all when `None`),
    /// MSB first, sampling MISO at every rising SCK edge, then CS_n released.
    pub fn waveform(&self, tx: &[u8], bits: Option<usize>) -> Waveform<SpiLevels> {
        let total = bits.unwrap_or(tx.len() * 8).min(tx.len() * 8);
        let mut wave = Waveform::default();
        let hold = |wave: &mut Waveform<SpiLevels>, levels: SpiLevels, clocks: u64| {
            wave.pins.extend(std::iter::repeat(levels).take(clocks as usize));
        };
        let bit = |k: usize| tx[k / 8] >> (7 - k % 8) & 1 != 0;
        hold(&mut wave, (false, false, total > 0 && bit(0)), self.cs_setup);
        for k in 0..total {
            if k > 0 && k % 8 == 0 {
                hold(&mut wave, (false, false, bit(k)), self.byte_gap);
            }
            // The master samples MISO at its rising edge.
            wave.samples.push(wave.pins.len());
            hold(&mut wave, (false, true, bit(k)), self.half_period);
            hold(&mut wave, (false, false, bit(k)), self.half_period);
        }
        hold(&mut wave, (true, false, false), self.cs_idle);
        wave
    }

    /// One frame (see [`Self::waveform`]); returns the bytes read on MISO (a partial
    /// last byte is dropped).
    pub fn transfer(&self, bench: &mut Bench, tx: &[u8], bits: Option<usize>) -> Vec<u8> {
        let (miso, _) = run_waveforms(bench, &self.waveform(tx, bits), &Waveform::default());
        bits_to_bytes(&miso)
    }

    /// READ frame of `count` words from `addr`: returns (status byte, words), checking
    /// the zeros and the response CRC against the `crc` crate.
    pub fn read(&self, bench: &mut Bench, addr: u8, count: u8) -> (u8, Vec<u32>) {
        let mut tx = vec![CMD_READ, addr, count];
        tx.resize(3 + 4 * usize::from(count) + 2, 0);
        let rx = self.transfer(bench, &tx, None);
        assert_eq!(rx[1..3], [0, 0], "zeros during the header");
        let data = &rx[3..3 + 4 * usize::from(count)];
        let mut covered = tx[..3].to_vec();
        covered.extend_from_slice(data);
        let crc = u16::from_be_bytes([rx[rx.len() - 2], rx[rx.len() - 1]]);
        assert_eq!(crc, CRC.checksum(&covered), "READ response CRC");
        let words = data.chunks(4).map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]])).collect();
        (rx[0], words)
    }

    /// WRITE frame; returns (status byte, result code).
    pub fn write(&self, bench: &mut Bench, addr: u8, value: u32) -> (u8, u8) {
        let rx = self.transfer(bench, &write_frame(addr, value), None);
        (rx[0], rx[rx.len() - 1])
    }

    /// FIFO frame of `records` for `n_axes` axes; returns (status byte, result code).
    pub fn fifo(&self, bench: &mut Bench, records: &[PeriodRecord], n_axes: usize) -> (u8, u8) {
        let rx = self.transfer(bench, &fifo_frame(records, n_axes), None);
        (rx[0], rx[rx.len() - 1])
    }
}

/// Appends the CRC of `body` (high byte first) and one byte to read the result on.
fn with_crc_and_result_byte(mut body: Vec<u8>) -> Vec<u8> {
    body.extend_from_slice(&CRC.checksum(&body).to_be_bytes());
    body.push(0);
    body
}

/// The bytes of a WRITE frame.
pub fn write_frame(addr: u8, value: u32) -> Vec<u8> {
    let mut body = vec![CMD_WRITE, addr, 1];
    body.extend_from_slice(&value.to_be_bytes());
    with_crc_and_result_byte(body)
}

/// The bytes of a record on the wire: each axis's increment most significant byte
/// first, then the flags.
pub fn record_bytes(record: &PeriodRecord, n_axes: usize) -> Vec<u8> {
    let mut bytes: Vec<u8> = record.inc[..n_axes].iter().flat_map(|inc| inc.to_bits().to_be_bytes()).collect();
    bytes.push(record.flags);
    bytes
}

/// The bytes of a FIFO frame (`records.len()` at most 255).
pub fn fifo_frame(records: &[PeriodRecord], n_axes: usize) -> Vec<u8> {
    let mut body = vec![CMD_FIFO, 0, records.len() as u8];
    for record in records {
        body.extend(record_bytes(record, n_axes));
    }
    with_crc_and_result_byte(body)
}

/// A record with the increments of `n_axes` axes and zeros above (as the FIFO holds it).
pub fn record(raw: &[i32], flags: u8, n_axes: usize) -> PeriodRecord {
    PeriodRecord::from_raw(&raw[..raw.len().min(n_axes)], flags)
}

/// 8080 master in the STM32 FSMC's multiplexed mode, at the pin level. Timing in core
/// clocks, from docs/spec/parallel_bus_slave.md: address valid >= 3 clocks before
/// `bus_adv_n` rises and
/// `bus_adv_n` low >= 3; write data valid >= 3 clocks before `bus_wr_n` rises;
/// `bus_rd_n` low >= 9 clocks (data driven from 6 clocks after it falls); >= 4 clocks
/// of turnaround after a read; >= 3 clocks high between strobes.
#[derive(Clone, Copy, Debug)]
pub struct ParallelMaster {
    /// Clocks `bus_adv_n` is low (address valid throughout), at least 3.
    pub adv_low: u64,
    /// Clocks `bus_wr_n` is low with the data valid, at least 3.
    pub wr_low: u64,
    /// Clocks `bus_rd_n` is low, at least 9; the data is sampled in its last cycle.
    pub rd_low: u64,
    /// Clocks after a strobe rises before the next access, at least 4.
    pub recovery: u64,
}

impl Default for ParallelMaster {
    /// The fastest legal timing.
    fn default() -> Self {
        ParallelMaster { adv_low: 3, wr_low: 3, rd_low: 9, recovery: 4 }
    }
}

/// One access of the 8080 master.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusAccess {
    /// Write `data` to register `reg`, half `high`.
    Write { reg: u8, high: bool, data: u16 },
    /// Read register `reg`, half `high`.
    Read { reg: u8, high: bool },
}

impl ParallelMaster {
    /// The pins of a sequence of accesses; a read samples `bus_ad` in its strobe's last
    /// low cycle.
    pub fn waveform(&self, accesses: &[BusAccess]) -> Waveform<BusLevels> {
        let mut wave = Waveform::default();
        let hold = |wave: &mut Waveform<BusLevels>, levels: BusLevels, clocks: u64| {
            wave.pins.extend(std::iter::repeat(levels).take(clocks as usize));
        };
        for access in accesses {
            let (reg, high) = match *access {
                BusAccess::Write { reg, high, .. } | BusAccess::Read { reg, high } => (reg, high),
            };
            let a = u16::from(reg << 1 | u8::from(high));
            hold(&mut wave, (false, false, true, true, a), self.adv_low);
            match *access {
                BusAccess::Write { data, .. } => {
                    hold(&mut wave, (false, true, true, false, data), self.wr_low);
                    hold(&mut wave, (false, true, true, true, data), 1);
                }
                BusAccess::Read { .. } => {
                    hold(&mut wave, (false, true, false, true, 0), self.rd_low - 1);
                    wave.samples.push(wave.pins.len());
                    hold(&mut wave, (false, true, false, true, 0), 1);
                    hold(&mut wave, (false, true, true, true, 0), 1);
                }
            }
            hold(&mut wave, (true, true, true, true, 0), self.recovery);
        }
        wave
    }

    /// The accesses of a 32-bit write: low half, then high half.
    pub fn write32_accesses(reg: u8, value: u32) -> [BusAccess; 2] {
        [
            BusAccess::Write { reg, high: false, data: value as u16 },
            BusAccess::Write { reg, high: true, data: (value >> 16) as u16 },
        ]
    }

    /// The accesses of a 32-bit read: low half, then high half.
    pub fn read32_accesses(reg: u8) -> [BusAccess; 2] {
        [BusAccess::Read { reg, high: false }, BusAccess::Read { reg, high: true }]
    }

    /// Writes one halfword: register `reg`, half `high`.
    pub fn write16(&self, bench: &mut Bench, reg: u8, high: bool, data: u16) {
        run_waveforms(bench, &Waveform::default(), &self.waveform(&[BusAccess::Write { reg, high, data }]));
    }

    /// Reads one halfword: register `reg`, half `high`. Returns `None` when the slave
    /// did not drive the bus in the sampling cycle.
    pub fn read16(&self, bench: &mut Bench, reg: u8, high: bool) -> Option<u16> {
        let (_, ad) = run_waveforms(bench, &Waveform::default(), &self.waveform(&[BusAccess::Read { reg, high }]));
        ad[0]
    }

    /// A 32-bit register write: low half, then high half.
    pub fn write32(&self, bench: &mut Bench, reg: u8, value: u32) {
        self.write16(bench, reg, false, value as u16);
        self.write16(bench, reg, true, (value >> 16) as u16);
    }

    /// A 32-bit register read: low half, then high half.
    pub fn read32(&self, bench: &mut Bench, reg: u8) -> u32 {
        let low = self.read16(bench, reg, false).expect("low half not driven");
        let high = self.read16(bench, reg, true).expect("high half not driven");
        u32::from(high) << 16 | u32::from(low)
    }
}

/// `p` as drawn if its parameters allow the step engine it asks for, else `p` with the
/// step engine instead of the digit-serial one if they allow that, else `p` with a DDA and
/// a shaper per axis (the engines need `P_WIDTH` above log2 of their round, the
/// digit-serial one `TIMING_W` and `P_WIDTH` within its word).
pub fn engine_if_valid(p: TopParams) -> TopParams {
    if p.validate().is_ok() {
        p
    } else if (TopParams { step_digit: 0, ..p }).validate().is_ok() {
        TopParams { step_digit: 0, ..p }
    } else {
        TopParams { step_shared: false, ..p }
    }
}

/// The bits a write to `addr` stores, from docs/spec/register_file.md ("timing fields keep only
/// `TIMING_W` bits, `PERIOD_CLOCKS` only `P_WIDTH`, `WATCHDOG_TIMEOUT` only `WD_W`";
/// fields of axes at and above `N_AXES` read 0), or `None` for an address that is not a
/// plain read/write register.
pub fn rw_mask(addr: u8, p: &TopParams) -> Option<u32> {
    let low = |bits: u32| if bits >= 32 { u32::MAX } else { (1u32 << bits) - 1 };
    let per_axis = |base: u8, stride: u8| -> Option<usize> {
        let offset = addr.checked_sub(base)?;
        (offset % stride == 0 && usize::from(offset / stride) < MAX_AXES).then_some(usize::from(offset / stride))
    };
    let axis_mask = |axis: usize, mask: u32| if axis < p.n_axes { mask } else { 0 };
    // The hand wheel's and the jog's registers read 0 without HAS_MPG.
    let mpg = |mask: u32| if p.has_mpg { mask } else { 0 };
    let timing = low(p.timing_w) | low(p.timing_w) << 16;
    match addr {
        regs::control::ADDR => Some(
            regs::control::RUN.mask() | regs::control::WATCHDOG_ENABLE.mask() | regs::control::ESTOP_ACTIVE_HIGH.mask(),
        ),
        regs::fifo_watermark::ADDR => Some(regs::fifo_watermark::WATERMARK.mask()),
        regs::start_level::ADDR => Some(regs::start_level::LEVEL.mask()),
        regs::period_clocks::ADDR => Some(low(p.p_width)),
        regs::watchdog_timeout::ADDR => Some(low(p.wd_w)),
        regs::estop_filter::ADDR => Some(regs::estop_filter::SAMPLES.mask()),
        regs::irq_mask::ADDR => Some(regs::irq_mask::MASK.mask()),
        regs::axis_enable::ADDR => Some(low(p.n_axes as u32)),
        regs::enc_prescale::ADDR => Some(regs::enc_prescale::PRESCALE.mask()),
        regs::probe_control::ADDR => Some(regs::probe_control::ACTIVE_HIGH.mask() | regs::probe_control::FILTER.mask()),
        regs::mpg_control::ADDR => Some(mpg(regs::mpg_control::PRESCALE.mask() | regs::mpg_control::FILTER.mask())),
        regs::jog_control::ADDR => {
            use regs::jog_control as j;
            Some(mpg(j::ENABLE.mask() | j::AXIS.mask() | j::MULTIPLIER.mask() | j::FOLLOW.mask()))
        }
        regs::jog_scale::ADDR => Some(mpg(regs::jog_scale::STEPS.mask())),
        regs::jog_vmax::ADDR => Some(mpg(regs::jog_vmax::STEPS.mask())),
        regs::jog_accel::ADDR => Some(mpg(regs::jog_accel::STEPS.mask())),
        regs::jog_window::ADDR => Some(mpg(regs::jog_window::STEPS.mask())),
        _ => {
            let channel = addr.checked_sub(regs::enc_control::ADDR).map(usize::from);
            if let Some(c) = channel.filter(|&c| c < regs::enc_control::COUNT) {
                use regs::enc_control as e;
                let mask = e::MODE.mask() | e::Z_ACTIVE_HIGH.mask() | e::FILTER.mask();
                return Some(if c < p.n_enc { mask } else { 0 });
            }
            if let Some(axis) = per_axis(regs::axis_timing_a::ADDR, regs::axis_timing_a::STRIDE) {
                return Some(axis_mask(axis, timing));
            }
            if let Some(axis) = per_axis(regs::axis_timing_b::ADDR, regs::axis_timing_b::STRIDE) {
                return Some(axis_mask(axis, timing));
            }
            if let Some(axis) = per_axis(regs::axis_mode::ADDR, regs::axis_mode::STRIDE) {
                use regs::axis_mode as m;
                let mask = m::OUT_MODE.mask() | m::INVERT_A.mask() | m::INVERT_B.mask() | m::INVERT_EN.mask();
                return Some(axis_mask(axis, mask));
            }
            if let Some(axis) = per_axis(regs::record_inc::ADDR, regs::record_inc::STRIDE) {
                return Some(axis_mask(axis, u32::MAX));
            }
            None
        }
    }
}

/// What a write of `stored` to `addr` leaves while the machine is halted: `halt` forces
/// `CONTROL.RUN` and `JOG_CONTROL.ENABLE` to 0 over a write.
pub fn halted_write(addr: u8, stored: u32) -> u32 {
    match addr {
        regs::control::ADDR => regs::control::RUN.set(stored, 0),
        regs::jog_control::ADDR => regs::jog_control::ENABLE.set(stored, 0),
        _ => stored,
    }
}

/// Every plain read/write register address.
pub fn rw_addresses(p: &TopParams) -> Vec<u8> {
    (0..128u8).filter(|&a| rw_mask(a, p).is_some()).collect()
}

/// A register's value after reset according to the map (every `rw` field's reset
/// value, cut to the bits the build keeps).
pub fn rw_reset(addr: u8, p: &TopParams) -> u32 {
    let mask = rw_mask(addr, p).unwrap_or(0);
    let register = regs::REGISTERS.iter().find(|r| (0..r.count()).any(|i| r.addr_of(i) == Some(addr)));
    let word = register.map_or(0, |r| {
        r.fields.iter().fold(0, |word, f| word | f.reset.map_or(0, |v| f.field.set(0, v & f.field.max())))
    });
    word & mask
}

/// `AXIS_TIMING_A` word: step length `l` and space `s`.
pub fn timing_a(l: u32, s: u32) -> u32 {
    regs::axis_timing_a::STEP_SPACE.set(regs::axis_timing_a::STEP_LEN.set(0, l), s)
}

/// `AXIS_TIMING_B` word: direction setup `u` and hold `h`.
pub fn timing_b(u: u32, h: u32) -> u32 {
    regs::axis_timing_b::DIR_HOLD.set(regs::axis_timing_b::DIR_SETUP.set(0, u), h)
}

/// The steps the DDA requests for a sum of raw I16F16 increments: `floor(T/M + 1/2)`
/// with `T/M` the sum in steps (docs/spec/dda_axis.md's rounding half up).
pub fn rounded_steps(raw_sum: i64) -> i64 {
    (raw_sum + (1 << 15)).div_euclid(1 << 16)
}
