//! `parallel_bus_slave`: the STM32 FSMC's asynchronous multiplexed (8080-style) mode on
//! the register bus. `bus_ad` carries the halfword address `a[7:0]` while `bus_adv_n` is
//! low, then data; register `a[7:1]`, half `a[0]` (0 = bits 15:0).
//!
//! Specification: docs/spec/parallel_bus_slave.md
//!
//! The strobes pass two-flop synchronisers and one more flop (`x_s` synchronised, `x_p`
//! the cycle before); `bus_ad_in` a two-flop synchroniser. A write of the low half is
//! held until the high half of the same register completes it (one 32-bit register
//! write); a read of the low half latches the high half, so a 32-bit read (low, then
//! high) is coherent. Latency, counting the first cycle a strobe pin is low as `n`: a
//! read strobe is seen in `n+2`, its register read requested in `n+3` and, granted at
//! once (served by the register file in `n+4`), driven on `bus_ad` from `n+6` (from
//! `n+3` for a latched high half); `bus_ad` is released 3 clocks after `bus_rd_n` rises.

use crate::register_bus::BusRequest;

/// The bus pins in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParallelPins {
    /// Chip select, active low.
    pub cs_n: bool,
    /// Address valid, active low.
    pub adv_n: bool,
    /// Read strobe, active low.
    pub rd_n: bool,
    /// Write strobe, active low.
    pub wr_n: bool,
    /// Address/data from the host.
    pub ad: u16,
}

impl Default for ParallelPins {
    /// Idle: every strobe high, `bus_ad` 0.
    fn default() -> Self {
        ParallelPins { cs_n: true, adv_n: true, rd_n: true, wr_n: true, ad: 0 }
    }
}

/// One active-low strobe's synchroniser: two flops, then `prev` one clock later.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Strobe {
    sync: [bool; 2],
    prev: bool,
}

impl Strobe {
    /// Reset: high (inactive) in every flop.
    const IDLE: Strobe = Strobe { sync: [true; 2], prev: true };

    /// `x_s`.
    fn now(&self) -> bool {
        self.sync[1]
    }

    fn step(&mut self, pin: bool) {
        self.prev = self.sync[1];
        self.sync = [pin, self.sync[0]];
    }
}

/// State of the parallel bus slave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParallelBusSlave {
    cs: Strobe,
    adv: Strobe,
    rd: Strobe,
    wr: Strobe,
    ad_sync: [u16; 2],
    /// Halfword address `a[7:0]`.
    addr: u8,
    wdata: u16,
    lo_data: u16,
    lo_reg: u8,
    lo_valid: bool,
    hi_data: u16,
    hi_reg: u8,
    hi_valid: bool,
    ad_out: u16,
    ad_oe: bool,
    request: Option<BusRequest>,
    /// The half (`a[0]`) and register (`a[7:1]`) of the read in flight, taken when its
    /// strobe started.
    read_half: bool,
    read_reg: u8,
    /// The read granted last cycle: the register file serves it in this cycle.
    read_served: bool,
    /// The read served last cycle: its `rdata` is taken at this edge.
    read_returning: bool,
}

impl Default for ParallelBusSlave {
    /// The reset state: synchronisers at the idle pin levels, nothing latched or driven.
    fn default() -> Self {
        ParallelBusSlave {
            cs: Strobe::IDLE,
            adv: Strobe::IDLE,
            rd: Strobe::IDLE,
            wr: Strobe::IDLE,
            ad_sync: [0; 2],
            addr: 0,
            wdata: 0,
            lo_data: 0,
            lo_reg: 0,
            lo_valid: false,
            hi_data: 0,
            hi_reg: 0,
            hi_valid: false,
            ad_out: 0,
            ad_oe: false,
            request: None,
            read_half: false,
            read_reg: 0,
            read_served: false,
            read_returning: false,
        }
    }
}

impl ParallelBusSlave {
    /// `bus_ad_out`.
    pub fn ad_out(&self) -> u16 {
        self.ad_out
    }

    /// `bus_ad_oe`: the slave drives `bus_ad`.
    pub fn ad_oe(&self) -> bool {
        self.ad_oe
    }

    /// The pending register-bus request.
    pub fn request(&self) -> Option<BusRequest> {
        self.request
    }

    /// One rising clock edge with this cycle's pins, grant and `rdata`. Returns whether
    /// this cycle had a parallel error (a high-half write without its low half, or a
    /// strobe while the previous request waits for the bus).
    pub fn step(&mut self, pins: &ParallelPins, granted: bool, rdata: u32) -> bool {
        let cs_s = self.cs.now();
        let adv_s = self.adv.now();
        let rd_s = self.rd.now();
        let wr_s = self.wr.now();
        let ad_s = self.ad_sync[1];
        let reg = (self.addr >> 1) & 0x7F;
        let half_high = self.addr & 1 != 0;
        // Requested, or granted with its read data not yet taken.
        let busy = self.request.is_some() || self.read_served || self.read_returning;
        let write_end = wr_s && !self.wr.prev && !self.cs.prev;
        let read_start = !rd_s && self.rd.prev && !cs_s;
        let mut error = false;

        if !cs_s && !adv_s {
            self.addr = ad_s as u8;
        }
        if !wr_s {
            self.wdata = ad_s;
        }
        // The read granted last cycle answers now.
        if self.read_returning {
            let [lo, hi] = [rdata as u16, (rdata >> 16) as u16];
            if self.read_half {
                self.ad_out = hi;
                self.hi_valid = false;
            } else {
                self.ad_out = lo;
                self.hi_data = hi;
                self.hi_reg = self.read_reg;
                self.hi_valid = true;
            }
            self.ad_oe = !rd_s;
        }
        self.read_returning = self.read_served;
        self.read_served = false;
        if granted {
            self.read_served = self.request.is_some_and(|r| !r.write);
            self.request = None;
        }
        if rd_s {
            self.ad_oe = false;
        }
        if (write_end || read_start) && busy {
            error = true;
        } else if write_end {
            if half_high {
                if self.lo_valid && self.lo_reg == reg {
                    let word = (u32::from(self.wdata) << 16) | u32::from(self.lo_data);
                    self.request = Some(BusRequest { write: true, addr: reg, wdata: word });
                } else {
                    error = true;
                }
                self.lo_valid = false;
            } else {
                self.lo_data = self.wdata;
                self.lo_reg = reg;
                self.lo_valid = true;
            }
            self.hi_valid = false;
        } else if read_start {
            self.lo_valid = false;
            if half_high && self.hi_valid && self.hi_reg == reg {
                self.ad_out = self.hi_data;
                self.ad_oe = true;
                self.hi_valid = false;
            } else {
                self.request = Some(BusRequest { write: false, addr: reg, wdata: 0 });
                self.read_half = half_high;
                self.read_reg = reg;
            }
        }

        self.cs.step(pins.cs_n);
        self.adv.step(pins.adv_n);
        self.rd.step(pins.rd_n);
        self.wr.step(pins.wr_n);
        self.ad_sync = [pins.ad, self.ad_sync[0]];
        error
    }
}
