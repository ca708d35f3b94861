//! Bus fuzzing of the bus-level top, RTL and model in lockstep: random sequences of
//! valid SPI frames, frames with a flipped bit, truncated frames (chip select released
//! after a random number of bits), garbage frames, and 8080 accesses cut short (short
//! strobes, chip select released before the strobe ends, a high half without its low
//! half, aborted reads), interleaved with valid accesses over both links.
//!
//! The expected state is tracked here from docs/spec/ and `docs/registers.md` alone:
//! every `rw` register holds exactly its last valid write, everything else reads what
//! the spec says (no register changes otherwise), the error counters count exactly the
//! corrupted, truncated and torn accesses, and the FIFO holds exactly the records of the
//! accepted frames (checked by level, then by running them out and comparing every
//! axis's position with the rounded sum). The machine stays stopped until that run-out.
//! TopLockstep compares every output pin on every clock throughout.
//!
//! `FINESTEP_CASES` sets the number of cases, `FINESTEP_SEED` reruns one seed.

use std::collections::VecDeque;

use finestep_cosim::TopLockstep;
use finestep_host::frame::{self, FRAME_CRC};
use finestep_host::pins::layout::{IN_BUS_AD0, IN_BUS_ADV_N, IN_BUS_CS_N, IN_BUS_RD_N, IN_BUS_WR_N};
use finestep_host::regs::{
    axis_enable, axis_mode, axis_timing_a, axis_timing_b, command, control, enc_control, enc_status, fifo_level, id,
    period_clocks, position, start_level, status,
};
use finestep_host::stream::wait_idle;
use finestep_host::{Bus, BusError, PinHost, PinTarget, PinTiming, SpiBus, SpiTransfer};
use finestep_model::PeriodRecord;
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

const N_AXES: usize = 4;
const FIFO_DEPTH: u32 = 256;
const RECORD_BYTES: usize = 4 * N_AXES + 1;
/// Largest |increment| of a generated record, in steps: within the rated rate of the
/// run-out (L = S = U = H = 1: I_rev = 4 clocks, 16 with the step engine's 4 slots;
/// 4 * 16 <= RUN_PERIOD).
const MAX_STEPS: i32 = 4;
const RUN_PERIOD: u32 = 64;

type Host = PinHost<TopLockstep>;
type Spi = SpiBus<Host>;

fn fail(e: BusError) -> TestCaseError {
    TestCaseError::fail(format!("{e}"))
}

/// The bits of each `rw` register that store (docs/registers.md, with the widths of
/// this build: N_AXES = 4, TIMING_W = 12, P_WIDTH = 20, WD_W = 24), and its reset value.
/// CONTROL is rw too but never written by the fuzzer (it would run or halt the machine),
/// nor are PROBE_CONTROL (its ARM), JOG_CONTROL (its ENABLE, cleared by the halt) and
/// INTERLOCK (a polarity write makes ACTIVE follow the pin after its filter). The machine
/// stays halted (the power-on E-stop fault), so SPINDLE_CONTROL.ENABLE never holds a 1
/// and OUTPUTS reads OUTPUTS_SAFE (docs/spec/spindle.md, docs/spec/logic_outputs.md).
fn rw_register(addr: u8) -> Option<(u32, u32)> {
    let timing = 0x0FFF_0FFF;
    match addr {
        0x1A => Some((0xF6, 0x10)),               // SPINDLE_CONTROL: DIR, DAC, DAC_DIV (reset 1)
        0x1B => Some((0xFFFF, 4096)),             // SPINDLE_PERIOD
        0x1C | 0x1D => Some((0xFFFF, 0)),         // SPINDLE_LEVEL, SPINDLE_RAMP
        0x23 => Some((0xF07, 0)),                 // OUTPUTS_SAFE: MIST, FLOOD, LIGHT, GPIO[0..4]
        0x08 => Some((0xFFFF, 0)),                // FIFO_WATERMARK
        0x09 => Some((0xFFFF, 1)),                // START_LEVEL
        0x0A => Some(((1 << 20) - 1, 50_000)),    // PERIOD_CLOCKS
        0x0B => Some(((1 << 24) - 1, 5_000_000)), // WATCHDOG_TIMEOUT
        0x0C => Some((0xFF, 50)),                 // ESTOP_FILTER
        0x0E => Some((0x1F, 0)),                  // IRQ_MASK
        0x18 => Some((0xF, 0)),                   // AXIS_ENABLE: one bit per axis
        0x20..=0x2F => match (addr - 0x20) % 4 {
            0 | 1 => Some((timing, 0x0001_0001)), // AXIS_TIMING_A/B
            2 => Some((0x1F, 0)),                 // AXIS_MODE
            _ => None,
        },
        0x48..=0x4B => Some((u32::MAX, 0)),      // RECORD_INC[0..4]
        0x51 => Some((0xFFFF, 0)),               // ENC_PRESCALE
        0x57 => Some((0xF_FFFF, 4 << 16 | 499)), // MPG_CONTROL
        0x59 => Some((u32::MAX, 1 << 16)),       // JOG_SCALE
        0x5A => Some((0x7FFF_FFFF, 1 << 16)),    // JOG_VMAX
        0x5B => Some((0x7FFF_FFFF, 4096)),       // JOG_ACCEL
        0x5C => Some((0xFFFF, 1000)),            // JOG_WINDOW
        0x70..=0x73 => Some((0xF7, 0x14)),       // ENC_CONTROL: mode, index polarity, filter
        _ => None,
    }
}

/// Addresses the fuzzer writes: everything but CONTROL, COMMAND and RECORD_PUSH (which
/// have their own operations). Writes to read-only and unmapped addresses, and to the
/// arrays' elements of absent axes, must change nothing.
fn safe_addr() -> impl Strategy<Value = u8> {
    let rw: Vec<u8> = (0u8..0x80).filter(|&a| rw_register(a).is_some()).collect();
    let all: Vec<u8> = (0u8..0x80).filter(|&a| !matches!(a, 0x04 | 0x05 | 0x27 | 0x50 | 0x52 | 0x58)).collect();
    prop_oneof![3 => prop::sample::select(rw), 1 => prop::sample::select(all)]
}

fn value() -> impl Strategy<Value = u32> {
    prop_oneof![any::<u32>(), 0u32..300, Just(u32::MAX)]
}

/// A record of increments with any flags but PBP: the default top builds the pbp block,
/// which runs a record with that flag as a line or an arc (random lanes: a random move or
/// `record_error`), and the run-out check below states the sum of increments. The pbp
/// records' bus path is `top_pbp`'s.
fn record() -> impl Strategy<Value = PeriodRecord> {
    let inc = -(MAX_STEPS << 16)..=(MAX_STEPS << 16);
    (prop::array::uniform4(inc), any::<u8>())
        .prop_map(|(raw, flags)| PeriodRecord::from_raw(&raw, flags & !finestep_interface::flags::PBP))
}

fn records() -> impl Strategy<Value = Vec<PeriodRecord>> {
    prop::collection::vec(record(), 1..=3)
}

#[derive(Clone, Debug)]
enum Op {
    /// An SPI frame: the first `bits` bits of `bytes` (all of them: a whole frame).
    /// `garbage`: random bytes, never allowed to apply anything.
    Spi { bytes: Vec<u8>, bits: usize, garbage: bool },
    /// COMMAND over SPI (CLEAR_ERRORS, FLUSH_FIFO, CLEAR_COUNTERS; never CLEAR_FAULTS).
    Command(u32),
    /// A valid 32-bit 8080 write (low half, then high half).
    ParWrite { addr: u8, value: u32 },
    /// A valid 32-bit 8080 read (low half, then high half), checked.
    ParRead { addr: u8 },
    /// One 8080 halfword write with a write strobe of `wr` clocks (may be shorter than
    /// the host timing asks), the address phase `adv` clocks; chip select released
    /// `early` clocks before the strobe ends (0: not early).
    ParHalf { addr: u8, half: u8, data: u16, adv: u64, wr: u64, early: u64 },
    /// One 8080 halfword read cut short: a read strobe of `rd` clocks, chip select
    /// released `early` clocks before it ends.
    ParReadAbort { addr: u8, half: u8, adv: u64, rd: u64, early: u64 },
    /// An 8080 low half of `addr`, then `between` (0 nothing, 1 an aborted read of
    /// `other`, 2 a valid SPI write of `spi_value` to `addr`, 3 a low half of `other`),
    /// then the high half of `addr`, with short strobes.
    ParTorn { addr: u8, other: u8, low: u16, high: u16, between: u8, spi_value: u32 },
    /// RECORD_INC[0..4] and RECORD_PUSH over the 8080 bus.
    ParPush(PeriodRecord),
    /// A full register dump over SPI, compared with the expectation.
    Dump,
}

fn flip(mut bytes: Vec<u8>, bit: usize) -> Vec<u8> {
    bytes[bit / 8] ^= 0x80 >> (bit % 8);
    bytes
}

fn spi_op() -> impl Strategy<Value = Op> {
    let whole = |bytes: Vec<u8>| {
        let bits = bytes.len() * 8;
        Op::Spi { bytes, bits, garbage: false }
    };
    prop_oneof![
        // Valid frames.
        4 => (safe_addr(), value()).prop_map(move |(a, v)| whole(frame::write_request(a, v))),
        2 => records().prop_map(move |r| whole(frame::fifo_request(&r, N_AXES))),
        // One bit flipped in the data or the CRC (never the header nor the trailing byte).
        2 => (safe_addr(), value(), 24usize..72).prop_map(move |(a, v, bit)| whole(flip(frame::write_request(a, v), bit))),
        2 => (records(), any::<prop::sample::Index>()).prop_map(move |(r, i)| {
            let bytes = frame::fifo_request(&r, N_AXES);
            let bit = 24 + i.index(bytes.len() * 8 - 8 - 24);
            whole(flip(bytes, bit))
        }),
        // Truncated: chip select released after a random number of bits (0 ..= all).
        3 => (safe_addr(), value(), 0usize..=80).prop_map(|(a, v, bits)| Op::Spi {
            bytes: frame::write_request(a, v),
            bits,
            garbage: false
        }),
        2 => (records(), any::<prop::sample::Index>()).prop_map(|(r, i)| {
            let bytes = frame::fifo_request(&r, N_AXES);
            let bits = i.index(bytes.len() * 8 + 1);
            Op::Spi { bytes, bits, garbage: false }
        }),
        // Garbage: random bytes, a random number of their bits; first bytes biased to
        // the real commands so that they get past the header.
        3 => (prop::collection::vec(any::<u8>(), 1..=14), 0u8..6, any::<prop::sample::Index>()).prop_map(
            |(mut bytes, cmd, i)| {
                if cmd < 4 {
                    bytes[0] = cmd;
                }
                if bytes.len() > 2 && bytes[0] == 3 {
                    bytes[2] %= 4; // FIFO counts that fit, mostly
                }
                let bits = i.index(bytes.len() * 8 + 1);
                Op::Spi { bytes, bits, garbage: true }
            }
        ),
        // A FIFO frame whose header asks for more than the room (refused at the header,
        // then cut anywhere: a refused frame is no frame error).
        1 => (200u8..=255, 24usize..64).prop_map(|(count, bits)| {
            let mut bytes = vec![frame::Command::Fifo as u8, 0, count];
            bytes.resize(8, 0x5A);
            Op::Spi { bytes, bits, garbage: false }
        }),
    ]
}

fn par_op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => (safe_addr(), value()).prop_map(|(addr, value)| Op::ParWrite { addr, value }),
        2 => (0u8..0x80).prop_map(|addr| Op::ParRead { addr }),
        4 => (safe_addr(), 0u8..2, any::<u16>(), 1u64..=4, 1u64..=5, 0u64..=3).prop_map(
            |(addr, half, data, adv, wr, early)| Op::ParHalf { addr, half, data, adv, wr, early: early.min(wr) }
        ),
        2 => (0u8..0x80, 0u8..2, 1u64..=4, 1u64..=10, 0u64..=3).prop_map(|(addr, half, adv, rd, early)| {
            Op::ParReadAbort { addr, half, adv, rd, early: early.min(rd - 1) }
        }),
        1 => record().prop_map(Op::ParPush),
        2 => (safe_addr(), safe_addr(), any::<u16>(), any::<u16>(), 0u8..4, value()).prop_map(
            |(addr, other, low, high, between, spi_value)| Op::ParTorn { addr, other, low, high, between, spi_value }
        ),
    ]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        12 => spi_op(),
        10 => par_op(),
        1 => prop::sample::select(vec![
            command::CLEAR_ERRORS.mask(),
            command::FLUSH_FIFO.mask(),
            command::CLEAR_COUNTERS.mask(),
            command::CLEAR_ERRORS.mask() | command::CLEAR_COUNTERS.mask(),
        ])
        .prop_map(Op::Command),
        1 => Just(Op::Dump),
    ]
}

/// What an SPI frame does, from the frame layer's spec: `bits` bits of `bytes` sent,
/// `free` records of room in the FIFO at its header.
#[derive(Clone, Debug, PartialEq)]
enum Outcome {
    Nothing,
    Read,
    FrameError,
    CrcError,
    Refused(u32),
    Write(u8, u32),
    Fifo(Vec<PeriodRecord>),
}

fn spi_outcome(bytes: &[u8], bits: usize, free: u32) -> Outcome {
    let whole = bits / 8;
    if bits == 0 {
        return Outcome::Nothing; // CS fell and rose without a bit: not counted
    }
    if whole < 3 {
        return Outcome::FrameError; // IDLE mid-byte, ADDR or COUNT
    }
    let (cmd, addr, count) = (bytes[0], bytes[1] & 0x7F, bytes[2]);
    match cmd {
        0x01 if count >= 1 => Outcome::Read,
        0x02 if count == 1 => {
            if whole < 9 {
                Outcome::FrameError
            } else if FRAME_CRC.checksum(&bytes[..9]) == 0 {
                Outcome::Write(addr, u32::from_be_bytes([bytes[3], bytes[4], bytes[5], bytes[6]]))
            } else {
                Outcome::CrcError
            }
        }
        0x03 if count >= 1 && u32::from(count) <= free => {
            let len = 3 + RECORD_BYTES * usize::from(count) + 2;
            if whole < len {
                Outcome::FrameError
            } else if FRAME_CRC.checksum(&bytes[..len]) == 0 {
                let records = bytes[3..len - 2]
                    .chunks_exact(RECORD_BYTES)
                    .map(|r| {
                        let raw: Vec<i32> = r[..4 * N_AXES]
                            .chunks_exact(4)
                            .map(|w| i32::from_be_bytes([w[0], w[1], w[2], w[3]]))
                            .collect();
                        PeriodRecord::from_raw(&raw, r[4 * N_AXES])
                    })
                    .collect();
                Outcome::Fifo(records)
            } else {
                Outcome::CrcError
            }
        }
        0x03 if count >= 1 => Outcome::Refused(u32::from(count)),
        _ => Outcome::FrameError, // bad command or count
    }
}

/// The expected state of the core, tracked from the spec.
struct Expect {
    /// Values of the rw registers (indexed by address).
    rw: [u32; 128],
    /// ID, VERSION, CAPS, CLOCK_HZ as read after reset.
    constants: [u32; 4],
    fifo: VecDeque<PeriodRecord>,
    overflow: bool,
    bus_error: bool,
    crc_errors: u32,
    frame_errors: u32,
    parallel_errors: u32,
    refused: u32,
    /// The 8080 slave's low half waiting for its high half: (register, data).
    low_half: Option<(u8, u16)>,
    /// ENC_STATUS of each channel but its Z bit: INDEX_SEEN and the arms. The index pin
    /// stays low, so there is no index event: a visit compares the index before and after
    /// its sample under the polarity of that cycle, so a polarity write is none either.
    enc_arms: [u32; 4],
}

impl Expect {
    fn new(constants: [u32; 4]) -> Expect {
        let mut rw = [0; 128];
        for addr in 0..128u8 {
            if let Some((_, reset)) = rw_register(addr) {
                rw[usize::from(addr)] = reset;
            }
        }
        Expect {
            rw,
            constants,
            fifo: VecDeque::new(),
            overflow: false,
            bus_error: false,
            crc_errors: 0,
            frame_errors: 0,
            parallel_errors: 0,
            refused: 0,
            low_half: None,
            enc_arms: [0; 4],
        }
    }

    fn level(&self) -> u32 {
        self.fifo.len() as u32
    }

    fn push(&mut self, record: PeriodRecord) {
        if self.level() == FIFO_DEPTH {
            self.refused += 1;
            self.overflow = true;
        } else {
            self.fifo.push_back(record);
        }
    }

    /// A register write that reached the register bus (either master).
    fn write(&mut self, addr: u8, value: u32) {
        if let Some((mask, _)) = rw_register(addr) {
            self.rw[usize::from(addr)] = value & mask;
        }
        match addr {
            0x04 => panic!("the fuzzer never writes CONTROL"),
            0x05 => {
                if value & command::CLEAR_ERRORS.mask() != 0 {
                    self.overflow = false;
                    self.bus_error = false;
                }
                if value & command::FLUSH_FIFO.mask() != 0 {
                    self.fifo.clear();
                }
                if value & command::CLEAR_COUNTERS.mask() != 0 {
                    self.crc_errors = 0;
                    self.frame_errors = 0;
                    self.parallel_errors = 0;
                    self.refused = 0;
                }
                assert_eq!(value & command::CLEAR_FAULTS.mask(), 0, "the fuzzer keeps the machine halted");
            }
            0x70..=0x73 => {
                // The rw part is stored above; the arms are pulses.
                let status = &mut self.enc_arms[usize::from(addr - 0x70)];
                let (seen, latch, clear) = (enc_status::INDEX_SEEN, enc_status::LATCH_ARMED, enc_status::CLEAR_ARMED);
                if enc_control::ARM_INDEX_LATCH.get(value) != 0 {
                    *status = seen.set(latch.set(*status, 1), 0);
                }
                if enc_control::ARM_INDEX_CLEAR.get(value) != 0 {
                    *status = clear.set(*status, 1);
                }
            }
            0x50 => {
                let raw: Vec<i32> = (0..N_AXES).map(|i| self.rw[0x48 + i] as i32).collect();
                self.push(PeriodRecord::from_raw(&raw, value as u8));
            }
            _ => {}
        }
    }

    fn spi(&mut self, outcome: Outcome) {
        match outcome {
            Outcome::Nothing | Outcome::Read => {}
            Outcome::FrameError => {
                self.frame_errors += 1;
                self.bus_error = true;
            }
            Outcome::CrcError => {
                self.crc_errors += 1;
                self.bus_error = true;
            }
            Outcome::Refused(count) => {
                self.refused += count;
                self.overflow = true;
            }
            Outcome::Write(addr, value) => self.write(addr, value),
            Outcome::Fifo(records) => self.fifo.extend(records),
        }
    }

    /// An 8080 write strobe that ended with chip select low.
    fn parallel_write_half(&mut self, reg: u8, half: u8, data: u16) {
        if half == 0 {
            self.low_half = Some((reg, data));
        } else {
            match self.low_half {
                Some((low_reg, low)) if low_reg == reg => self.write(reg, u32::from(data) << 16 | u32::from(low)),
                _ => {
                    self.parallel_errors += 1;
                    self.bus_error = true;
                }
            }
            self.low_half = None;
        }
    }

    fn irq_status(&self) -> u32 {
        let fifo_low = self.level() < self.rw[0x08];
        let error = self.overflow || self.bus_error;
        // FAULT: the machine is halted (the power-on E-stop fault is never cleared).
        u32::from(error) << 4 | 1 << 3 | u32::from(fifo_low)
    }

    fn status(&self) -> u32 {
        let irq = self.irq_status() & self.rw[0x0E] != 0;
        status::HALT.mask()
            | status::FAULT_ESTOP.mask()
            | u32::from(self.overflow) << status::OVERFLOW.lsb
            | u32::from(self.bus_error) << status::BUS_ERROR.lsb
            | u32::from(irq) << status::IRQ.lsb
    }

    /// What a read of `addr` returns, or None for the free-running clocks.
    fn read(&self, addr: u8) -> Option<u32> {
        Some(match addr {
            0x00..=0x03 => self.constants[usize::from(addr)],
            0x04 => control::ESTOP_ACTIVE_HIGH.mask(),
            0x06 => self.status(),
            0x07 => (FIFO_DEPTH - self.level()) << 16 | self.level(),
            0x0D => self.irq_status(),
            0x0F | 0x10 => return None, // TIMESTAMP, LATCH_TIME
            0x13 => self.crc_errors & 0xFFFF,
            0x14 => self.frame_errors & 0xFFFF,
            0x15 => self.parallel_errors & 0xFFFF,
            0x16 => self.refused & 0xFFFF,
            // SPINDLE_STATUS while halted: level 0, at its target (0), not enabled.
            0x1E => 1 << 16,
            // OUTPUTS while halted: the safe levels, and N_GPIO = 4.
            0x1F => self.rw[0x23] | 4 << 24,
            // INTERLOCK at reset: active high, filter 50, prescale 4999; the pin low: not
            // active.
            0x27 => 4999 << 18 | 0x3202,
            // PROBE_CONTROL at reset: active high, filter 1; ENC_STATUS: the arms.
            0x52 => 0x11,
            0x74..=0x77 => {
                let z = enc_control::Z_ACTIVE_HIGH.get(self.rw[usize::from(addr - 4)]) ^ 1;
                enc_status::Z.set(self.enc_arms[usize::from(addr - 0x74)], z)
            }
            a if rw_register(a).is_some() => self.rw[usize::from(a)],
            // COMMAND, PERIOD_COUNT, UNDERRUN_COUNT, AXIS_STATUS, POSITION,
            // RECORD_PUSH, absent axes, unmapped: 0 (nothing ran).
            _ => 0,
        })
    }
}

/// The packed inputs of an 8080 bus cycle on top of `base` (the idle pins).
fn bus_pins(base: u64, cs: bool, adv: bool, rd: bool, wr: bool, ad: u16) -> u64 {
    let mut word = base & !(0xFFFF << IN_BUS_AD0);
    for (bit, active) in [(IN_BUS_CS_N, cs), (IN_BUS_ADV_N, adv), (IN_BUS_RD_N, rd), (IN_BUS_WR_N, wr)] {
        if active {
            word &= !(1 << bit);
        } else {
            word |= 1 << bit;
        }
    }
    word | u64::from(ad) << IN_BUS_AD0
}

/// Clocks all strobes stay high after a raw 8080 access (>= 4 after a read).
const RECOVERY: u64 = 5;

/// A raw 8080 access: address phase of `adv` clocks, then a strobe (`write`: WR_n with
/// `data`, else RD_n) of `strobe` clocks whose last `early` clocks have CS_n high.
fn raw_parallel(
    host: &mut Host,
    halfword: u8,
    adv: u64,
    write: Option<u16>,
    strobe: u64,
    early: u64,
) -> Result<(), BusError> {
    let base = host.inputs();
    let target = host.target_mut();
    target.drive(bus_pins(base, true, true, false, false, u16::from(halfword)), adv)?;
    target.drive(bus_pins(base, true, false, false, false, 0), 1)?;
    let data = write.unwrap_or(0);
    let (rd, wr) = (write.is_none(), write.is_some());
    target.drive(bus_pins(base, true, false, rd, wr, data), strobe - early)?;
    if early > 0 {
        target.drive(bus_pins(base, false, false, rd, wr, data), early)?;
    }
    target.drive(base, RECOVERY)
}

fn spi_read(spi: &mut Spi, addr: u8, count: usize) -> Result<Vec<u32>, TestCaseError> {
    let mut words = vec![0; count];
    spi.read(addr, &mut words).map_err(fail)?;
    Ok(words)
}

fn check_dump(spi: &mut Spi, expect: &Expect, when: &str) -> Result<(), TestCaseError> {
    let words = spi_read(spi, 0, 128)?;
    for (addr, &got) in words.iter().enumerate() {
        if let Some(want) = expect.read(addr as u8) {
            prop_assert_eq!(got, want, "{}: register {:#04x} reads {:#x}, expected {:#x}", when, addr, got, want);
        }
    }
    Ok(())
}

fn run_op(spi: &mut Spi, expect: &mut Expect, op: &Op, index: usize) -> Result<(), TestCaseError> {
    match op {
        Op::Spi { bytes, bits, garbage } => {
            let mut bytes = bytes.clone();
            let free = FIFO_DEPTH - expect.level();
            let mut outcome = spi_outcome(&bytes, *bits, free);
            if *garbage {
                // Garbage that happens to carry a good CRC must not write anywhere: break
                // its CRC (a single flipped bit always fails it).
                let crc_end = match &outcome {
                    Outcome::Write(..) => Some(9),
                    Outcome::Fifo(records) => Some(3 + RECORD_BYTES * records.len() + 2),
                    _ => None,
                };
                if let Some(end) = crc_end {
                    bytes[end - 1] ^= 1;
                    outcome = spi_outcome(&bytes, *bits, free);
                }
            }
            let host = spi.link_mut();
            if *bits == bytes.len() * 8 {
                let rx = host.transfer(&bytes).map_err(fail)?;
                // A whole WRITE or FIFO frame answers its result in the last byte.
                let result = match outcome {
                    Outcome::Write(..) | Outcome::Fifo(_) => Some(0xA0),
                    Outcome::CrcError => Some(0xE1),
                    Outcome::Refused(_) => Some(0xE3),
                    _ => None,
                };
                if let (Some(code), false) = (result, *garbage) {
                    prop_assert_eq!(rx[rx.len() - 1], code, "op {}: {:?} answered {:02x?}", index, outcome, rx);
                }
            } else {
                host.spi_begin().map_err(fail)?;
                host.spi_send_bits(&bytes, *bits).map_err(fail)?;
                host.spi_end().map_err(fail)?;
            }
            expect.spi(outcome);
        }
        Op::Command(word) => {
            spi.write(command::ADDR, *word).map_err(fail)?;
            expect.write(command::ADDR, *word);
        }
        Op::ParWrite { addr, value } => {
            let host = spi.link_mut();
            host.parallel_write16(addr << 1, *value as u16).map_err(fail)?;
            expect.parallel_write_half(*addr, 0, *value as u16);
            host.parallel_write16(addr << 1 | 1, (value >> 16) as u16).map_err(fail)?;
            expect.parallel_write_half(*addr, 1, (value >> 16) as u16);
        }
        Op::ParRead { addr } => {
            let host = spi.link_mut();
            let low = host.parallel_read16(addr << 1).map_err(fail)?;
            let high = host.parallel_read16(addr << 1 | 1).map_err(fail)?;
            expect.low_half = None;
            let got = u32::from(high) << 16 | u32::from(low);
            if let Some(want) = expect.read(*addr) {
                prop_assert_eq!(got, want, "op {}: 8080 read of {:#04x}", index, addr);
            }
        }
        Op::ParHalf { addr, half, data, adv, wr, early } => {
            raw_parallel(spi.link_mut(), addr << 1 | half, *adv, Some(*data), *wr, *early).map_err(fail)?;
            if *early == 0 {
                // Synchronised, the data and the strobe keep their alignment: any
                // strobe length writes; with CS_n released first it is no write at all.
                expect.parallel_write_half(*addr, *half, *data);
            }
        }
        Op::ParReadAbort { addr, half, adv, rd, early } => {
            raw_parallel(spi.link_mut(), addr << 1 | half, *adv, None, *rd, *early).map_err(fail)?;
            // The strobe started with CS_n low: a read, which drops a waiting low half.
            expect.low_half = None;
        }
        Op::ParTorn { addr, other, low, high, between, spi_value } => {
            raw_parallel(spi.link_mut(), addr << 1, 1, Some(*low), 2, 0).map_err(fail)?;
            expect.parallel_write_half(*addr, 0, *low);
            match between {
                1 => {
                    raw_parallel(spi.link_mut(), other << 1, 1, None, 2, 0).map_err(fail)?;
                    expect.low_half = None;
                }
                2 => {
                    spi.write(*addr, *spi_value).map_err(fail)?;
                    expect.write(*addr, *spi_value);
                }
                3 => {
                    raw_parallel(spi.link_mut(), other << 1, 1, Some(*high), 1, 0).map_err(fail)?;
                    expect.parallel_write_half(*other, 0, *high);
                }
                _ => {}
            }
            raw_parallel(spi.link_mut(), addr << 1 | 1, 1, Some(*high), 1, 0).map_err(fail)?;
            expect.parallel_write_half(*addr, 1, *high);
        }
        Op::ParPush(record) => {
            let host = spi.link_mut();
            for axis in 0..N_AXES {
                let value = record.inc[axis].to_bits() as u32;
                let reg = 0x48 + axis as u8;
                host.parallel_write16(reg << 1, value as u16).map_err(fail)?;
                host.parallel_write16(reg << 1 | 1, (value >> 16) as u16).map_err(fail)?;
                expect.parallel_write_half(reg, 0, value as u16);
                expect.parallel_write_half(reg, 1, (value >> 16) as u16);
            }
            host.parallel_write16(0x50 << 1, u16::from(record.flags)).map_err(fail)?;
            host.parallel_write16(0x50 << 1 | 1, 0).map_err(fail)?;
            expect.parallel_write_half(0x50, 0, u16::from(record.flags));
            expect.parallel_write_half(0x50, 1, 0);
        }
        Op::Dump => check_dump(spi, expect, &format!("dump at op {index}"))?,
    }
    Ok(())
}

/// Runs the FIFO out and checks every axis ends on the rounded sum of the records the
/// expectation says it holds.
fn run_out(spi: &mut Spi, expect: &mut Expect) -> Result<(), TestCaseError> {
    if expect.level() < FIFO_DEPTH {
        let last = PeriodRecord::from_raw(&[0; N_AXES], 1);
        spi.push_records(&[last]).map_err(fail)?;
        expect.fifo.push_back(last);
    }
    for axis in 0..N_AXES {
        spi.write(axis_timing_a::addr(axis), 0x0001_0001).map_err(fail)?;
        spi.write(axis_timing_b::addr(axis), 0x0001_0001).map_err(fail)?;
        spi.write(axis_mode::addr(axis), 0).map_err(fail)?;
    }
    spi.write(axis_enable::ADDR, 0xF).map_err(fail)?;
    spi.write(period_clocks::ADDR, RUN_PERIOD).map_err(fail)?;
    spi.write(start_level::ADDR, 1).map_err(fail)?;
    spi.write(command::ADDR, command::CLEAR_FAULTS.mask() | command::CLEAR_ERRORS.mask()).map_err(fail)?;
    let level = fifo_level::LEVEL.get(spi.read_one(fifo_level::ADDR).map_err(fail)?);
    prop_assert_eq!(level, expect.level());
    spi.write(control::ADDR, control::RUN.mask() | control::ESTOP_ACTIVE_HIGH.mask()).map_err(fail)?;
    wait_idle(spi, 2000, u64::from(RUN_PERIOD) * (u64::from(FIFO_DEPTH) + 8)).map_err(fail)?;
    spi.wait(4 * u64::from(RUN_PERIOD)).map_err(fail)?;
    let steps = spi_read(spi, position::ADDR, N_AXES)?;
    for (axis, &got) in steps.iter().enumerate().take(N_AXES) {
        let total: i64 = expect.fifo.iter().map(|r| i64::from(r.inc[axis].to_bits())).sum();
        let want = ((total + (1 << 15)) >> 16) as i32;
        prop_assert_eq!(got as i32, want, "axis {} after running out {} records", axis, expect.level());
    }
    let word = spi.read_one(status::ADDR).map_err(fail)?;
    prop_assert_eq!(word & 0xFC0, 0, "no error while running out: STATUS {:#x}", word);
    Ok(())
}

fn fuzz_case(ops: &[Op]) -> Result<(), TestCaseError> {
    let mut host = PinHost::new(TopLockstep::new("top_bus_fuzz"), PinTiming::default());
    host.reset(4).map_err(fail)?;
    host.idle(60).map_err(fail)?; // the E-stop filter (50) sees the pin released
    let mut spi = SpiBus::new(host, N_AXES);
    let head = spi_read(&mut spi, 0, 4)?;
    prop_assert_eq!(head[0], id::MAGIC_VALUE);
    let mut expect = Expect::new([head[0], head[1], head[2], head[3]]);
    check_dump(&mut spi, &expect, "after reset")?;
    for (index, op) in ops.iter().enumerate() {
        run_op(&mut spi, &mut expect, op, index)?;
    }
    check_dump(&mut spi, &expect, "at the end")?;
    run_out(&mut spi, &mut expect)
}

#[test]
fn bus_fuzz_corrupts_nothing() {
    let mut runner = finestep_testkit::runner("bus_fuzz_corrupts_nothing", 400);
    let started = std::time::Instant::now();
    runner.run(&prop::collection::vec(op(), 4..40), |ops| fuzz_case(&ops)).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("bus_fuzz_corrupts_nothing: {:.1} s", started.elapsed().as_secs_f64());
}
