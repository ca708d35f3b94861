//! `spi_frame`: the SPI frame layer on top of [`spi_slave_phy`](crate::spi_slave_phy).
//!
//! Specification: docs/spec/spi_frame.md
//!
//! Every frame starts with a header `cmd, addr, count`. READ answers `count` register
//! words and their CRC; WRITE applies one register write only when its CRC checks; FIFO
//! stages `count` period records into the position FIFO as they arrive and commits them
//! only when the frame's CRC checks, so a corrupted or truncated frame never reaches the
//! period timer. The byte the phy sends next ([`SpiFrame::tx_byte`]) is a function of the
//! state: the status byte first, then zeros, read data or the result code.
//!
//! Latency: a byte's `rx_valid` is acted on at the edge ending its cycle; the FIFO
//! strobes (`wr_en`, `wr_commit`, `wr_abort`) and a register-bus request are high in the
//! next cycle; a requested read's data reaches `next_word` at the edge ending the cycle
//! after its grant. Error events (`frame_error`, `crc_error`, refused records) are
//! reported in the cycle of the byte or `frame_end` that causes them.

use crate::crc16_byte::{crc16_byte, INITIAL};
use crate::record::PeriodRecord;
use crate::register_bus::BusRequest;
use crate::{Increment, MAX_AXES};

/// Command bytes (the first byte of a frame): the interface's.
pub use finestep_interface::spi::command;

/// Result codes of WRITE and FIFO frames, and of every rejected frame: the interface's.
pub use finestep_interface::spi::result;

/// Where the frame layer is in the current frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Phase {
    /// Waiting for the command byte (sending the status byte).
    #[default]
    Idle,
    /// Waiting for the address byte.
    Addr,
    /// Waiting for the count byte.
    Count,
    /// Receiving a WRITE word or FIFO records.
    Data,
    /// Receiving the CRC's high byte.
    CrcHi,
    /// Receiving the CRC's low byte.
    CrcLo,
    /// The frame has its result; every further byte sent is the result code.
    Result,
    /// Sending read words.
    ReadData,
    /// Sending the read CRC's high byte.
    ReadCrcHi,
    /// Sending the read CRC's low byte.
    ReadCrcLo,
    /// The read frame is complete; zeros follow.
    ReadTail,
}

/// What the frame layer sees in one cycle (the phy's registered outputs and the state
/// of the other blocks in that cycle).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpiFrameInputs {
    /// The phy's `frame_start`.
    pub frame_start: bool,
    /// The phy's `frame_end`.
    pub frame_end: bool,
    /// The phy's `frame_whole`: the frame ended on a byte boundary.
    pub frame_whole: bool,
    /// The phy's `rx_valid`.
    pub rx_valid: bool,
    /// The phy's `rx_byte`.
    pub rx_byte: u8,
    /// Records the FIFO can still take (`FREE`).
    pub fifo_free: usize,
    /// The FIFO is flushed at this edge (any cause).
    pub fifo_flush: bool,
    /// This layer's register-bus request is granted in this cycle.
    pub granted: bool,
    /// The register bus's `rdata`.
    pub rdata: u32,
}

/// Error events of one cycle, for the register file's counters and flags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpiFrameEvents {
    /// A frame error (bad command or count, truncated frame, flushed FIFO frame).
    pub frame_error: bool,
    /// A CRC mismatch.
    pub crc_error: bool,
    /// Records refused at a FIFO header (`count > FREE`); sets `OVERFLOW`.
    pub refused_records: u8,
}

/// The frame layer's FIFO write-port strobes in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpiFifoPort {
    /// A FIFO frame is between its header and its result: the port is this layer's.
    pub busy: bool,
    /// `wr_en` with `wr_data`: a record to stage.
    pub write: Option<PeriodRecord>,
    /// `wr_commit`.
    pub commit: bool,
    /// `wr_abort`.
    pub abort: bool,
}

impl SpiFifoPort {
    /// The layer drives the FIFO's write port in this cycle.
    pub fn owns_port(&self) -> bool {
        self.busy || self.write.is_some() || self.commit || self.abort
    }
}

/// Bytes of a record on the wire for up to [`MAX_AXES`] axes.
const MAX_RECORD_BYTES: usize = 4 * MAX_AXES + 1;

/// State of the SPI frame layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiFrame {
    n_axes: usize,
    phase: Phase,
    cmd: u8,
    addr: u8,
    count: u8,
    items_left: u8,
    byte_in_item: u8,
    crc: u16,
    result: u8,
    write_word: u32,
    record_bytes: [u8; MAX_RECORD_BYTES],
    tx_word: u32,
    next_word: u32,
    read_addr: u8,
    any_bits: bool,
    request: Option<BusRequest>,
    /// The read granted last cycle: the register file serves it in this cycle.
    read_served: bool,
    /// The read served last cycle: `rdata` goes to `next_word` at this edge.
    read_returning: bool,
    port: SpiFifoPort,
}

/// Register addresses are 7 bits.
const ADDR_MASK: u8 = 0x7F;

impl SpiFrame {
    /// The reset state for a core of `n_axes` axes (records of `4 * n_axes + 1` bytes).
    pub fn new(n_axes: usize) -> Self {
        SpiFrame {
            n_axes: n_axes.clamp(1, MAX_AXES),
            phase: Phase::Idle,
            cmd: 0,
            addr: 0,
            count: 0,
            items_left: 0,
            byte_in_item: 0,
            crc: INITIAL,
            result: 0,
            write_word: 0,
            record_bytes: [0; MAX_RECORD_BYTES],
            tx_word: 0,
            next_word: 0,
            read_addr: 0,
            any_bits: false,
            request: None,
            read_served: false,
            read_returning: false,
            port: SpiFifoPort::default(),
        }
    }

    /// Bytes of one record on the wire: `R = 4 * N_AXES + 1`.
    pub fn record_bytes(&self) -> usize {
        4 * self.n_axes + 1
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The pending register-bus request (`req` with `we`, `addr`, `wdata`).
    pub fn request(&self) -> Option<BusRequest> {
        self.request
    }

    /// The FIFO write-port strobes of this cycle.
    pub fn fifo_port(&self) -> SpiFifoPort {
        self.port
    }

    /// `latch_hold`: an SPI read frame is in progress (from the cycle after its command
    /// byte to its end), so the position latch holds for a coherent read.
    pub fn latch_hold(&self) -> bool {
        self.cmd == command::READ && self.phase != Phase::Idle
    }

    /// The byte the phy sends next, given `STATUS[7:0]` of this cycle.
    pub fn tx_byte(&self, status: u8) -> u8 {
        match self.phase {
            Phase::Idle => status,
            Phase::Addr | Phase::Count | Phase::Data | Phase::CrcHi | Phase::CrcLo => 0,
            Phase::Result => self.result,
            Phase::ReadData => self.tx_word.to_be_bytes()[usize::from(self.byte_in_item & 3)],
            Phase::ReadCrcHi => self.crc.to_be_bytes()[0],
            Phase::ReadCrcLo => self.crc.to_be_bytes()[1],
            Phase::ReadTail => 0,
        }
    }

    /// Requests a register read of `addr` whose data goes to `next_word`.
    fn request_read(&mut self, addr: u8) {
        self.request = Some(BusRequest { write: false, addr: addr & ADDR_MASK, wdata: 0 });
    }

    /// Ends the frame's use of the FIFO: `wr_abort` (or `wr_commit`) next cycle.
    fn release_fifo(&mut self, commit: bool) {
        self.port.busy = false;
        self.port.commit = commit;
        self.port.abort = !commit;
    }

    /// The staged record from the received bytes: axis `i` from bytes `4i..4i+4`, most
    /// significant first, then the flags byte; axes at and above `N_AXES` are 0.
    fn record(&self) -> PeriodRecord {
        let mut record = PeriodRecord::default();
        for (axis, inc) in record.inc[..self.n_axes].iter_mut().enumerate() {
            let mut word = [0u8; 4];
            word.copy_from_slice(&self.record_bytes[4 * axis..4 * axis + 4]);
            *inc = Increment::from_bits(i32::from_be_bytes(word));
        }
        record.flags = self.record_bytes[4 * self.n_axes];
        record
    }

    /// One rising clock edge. Returns this cycle's error events.
    ///
    /// The phy never gives two of `frame_start`, `frame_end`, `rx_valid` in one cycle
    /// under the host timing; if it does, `frame_end` wins, then a FIFO flush, then
    /// `frame_start`, then the byte (which is dropped).
    pub fn step(&mut self, inp: &SpiFrameInputs) -> SpiFrameEvents {
        let mut events = SpiFrameEvents::default();
        let next_word_before = self.next_word;
        self.port.write = None;
        self.port.commit = false;
        self.port.abort = false;
        if self.read_returning {
            self.next_word = inp.rdata;
        }
        self.read_returning = self.read_served;
        self.read_served = false;
        if inp.granted {
            self.read_served = self.request.is_some_and(|r| !r.write);
            self.request = None;
        }

        if inp.frame_end {
            let incomplete = match self.phase {
                Phase::Addr | Phase::Count => true,
                Phase::Idle => !inp.frame_whole,
                Phase::Data | Phase::CrcHi | Phase::CrcLo => true,
                _ => false,
            };
            if self.any_bits && incomplete {
                events.frame_error = true;
            }
            if self.port.busy {
                self.release_fifo(false);
            }
            self.phase = Phase::Idle;
            self.any_bits = false;
        } else if inp.fifo_flush && self.port.busy {
            self.result = result::FIFO_FLUSHED;
            self.phase = Phase::Result;
            self.release_fifo(false);
            events.frame_error = true;
        } else if inp.frame_start {
            self.phase = Phase::Idle;
            self.crc = INITIAL;
            self.any_bits = true;
        } else if inp.rx_valid {
            self.receive(inp.rx_byte, inp.fifo_free, next_word_before, &mut events);
        }
        events
    }

    /// Acts on one received byte `b`.
    fn receive(&mut self, b: u8, fifo_free: usize, next_word: u32, events: &mut SpiFrameEvents) {
        let crc_after = crc16_byte(self.crc, b);
        match self.phase {
            Phase::Idle => {
                self.cmd = b;
                self.crc = crc_after;
                self.phase = Phase::Addr;
            }
            Phase::Addr => {
                self.addr = b & ADDR_MASK;
                self.crc = crc_after;
                self.phase = Phase::Count;
                if self.cmd == command::READ {
                    self.request_read(self.addr);
                    self.read_addr = self.addr.wrapping_add(1) & ADDR_MASK;
                }
            }
            Phase::Count => {
                self.count = b;
                self.crc = crc_after;
                match self.cmd {
                    command::READ if b >= 1 => {
                        self.phase = Phase::ReadData;
                        self.tx_word = next_word;
                        self.byte_in_item = 0;
                        self.items_left = b;
                        self.request_read(self.read_addr);
                        self.read_addr = self.read_addr.wrapping_add(1) & ADDR_MASK;
                    }
                    command::WRITE if b == 1 => {
                        self.phase = Phase::Data;
                        self.byte_in_item = 0;
                        self.items_left = 1;
                    }
                    command::FIFO if b >= 1 && usize::from(b) <= fifo_free => {
                        self.phase = Phase::Data;
                        self.byte_in_item = 0;
                        self.items_left = b;
                        self.port.busy = true;
                    }
                    command::FIFO if b >= 1 => {
                        self.phase = Phase::Result;
                        self.result = result::FIFO_REFUSED;
                        events.refused_records = b;
                    }
                    _ => {
                        self.phase = Phase::Result;
                        self.result = result::BAD_COMMAND;
                        events.frame_error = true;
                    }
                }
            }
            Phase::Data => {
                self.crc = crc_after;
                let index = usize::from(self.byte_in_item);
                let item_bytes = if self.cmd == command::WRITE { 4 } else { self.record_bytes() };
                if self.cmd == command::WRITE {
                    self.write_word = (self.write_word << 8) | u32::from(b);
                } else if index < MAX_RECORD_BYTES {
                    self.record_bytes[index] = b;
                }
                self.byte_in_item += 1;
                if usize::from(self.byte_in_item) >= item_bytes {
                    self.byte_in_item = 0;
                    self.items_left = self.items_left.wrapping_sub(1);
                    if self.cmd == command::FIFO {
                        self.port.write = Some(self.record());
                    }
                    if self.items_left == 0 {
                        self.phase = Phase::CrcHi;
                    }
                }
            }
            Phase::CrcHi => {
                self.crc = crc_after;
                self.phase = Phase::CrcLo;
            }
            Phase::CrcLo => {
                self.crc = crc_after;
                let good = crc_after == 0;
                self.result = if good { result::ACK } else { result::CRC_MISMATCH };
                events.crc_error = !good;
                if self.cmd == command::WRITE && good {
                    self.request = Some(BusRequest { write: true, addr: self.addr, wdata: self.write_word });
                }
                if self.port.busy {
                    self.release_fifo(good);
                }
                self.phase = Phase::Result;
            }
            Phase::ReadData => {
                self.crc = crc16_byte(self.crc, self.tx_byte(0));
                self.byte_in_item += 1;
                if self.byte_in_item >= 4 {
                    self.byte_in_item = 0;
                    self.items_left = self.items_left.wrapping_sub(1);
                    if self.items_left == 0 {
                        self.phase = Phase::ReadCrcHi;
                    } else {
                        self.tx_word = next_word;
                        self.request_read(self.read_addr);
                        self.read_addr = self.read_addr.wrapping_add(1) & ADDR_MASK;
                    }
                }
            }
            Phase::ReadCrcHi => self.phase = Phase::ReadCrcLo,
            Phase::ReadCrcLo => self.phase = Phase::ReadTail,
            Phase::Result | Phase::ReadTail => {}
        }
    }
}
