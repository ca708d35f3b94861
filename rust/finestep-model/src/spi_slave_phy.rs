//! `spi_slave_phy`: the SPI link's pins (mode 0: SCK idles low, MOSI sampled on the
//! rising edge, MISO changed after the falling edge, MSB first) brought into the core
//! clock domain, byte by byte.
//!
//! Specification: docs/spec/spi_slave_phy.md
//!
//! CS_n, SCK and MOSI pass two-flop synchronisers (`*_s` is the second flop); SCK has one
//! more flop (`sck_prev`) to find its edges; `selected` is `!cs_s` one clock later and
//! finds the CS_n edges. Latency, counting the first cycle a pin shows its new level as
//! cycle `n`: an edge is seen in cycle `n+2` and acted on at the edge ending it, so
//! `frame_start`, `frame_end` and `rx_valid` are high in cycle `n+3` (`rx_valid` after a
//! byte's 8th rising SCK edge) and a new MISO bit shows in `n+3` after a falling edge.
//! `tx_byte` is loaded at the edge that sets `frame_start` (the first byte out) and at
//! the falling SCK edge after each 8th rising one (the next byte); the frame layer
//! presents the next byte from the clock after `rx_valid`.

/// The pins of the link in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiPins {
    /// Chip select, active low.
    pub cs_n: bool,
    /// Serial clock.
    pub sck: bool,
    /// Master out, slave in.
    pub mosi: bool,
}

impl Default for SpiPins {
    /// Idle: deselected, SCK low.
    fn default() -> Self {
        SpiPins { cs_n: true, sck: false, mosi: false }
    }
}

/// State of the byte-level SPI slave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpiSlavePhy {
    /// The synchronisers' two flops: `[first, second]`.
    cs_n_sync: [bool; 2],
    sck_sync: [bool; 2],
    mosi_sync: [bool; 2],
    /// `sck_s` one clock later.
    sck_prev: bool,
    /// `!cs_s` one clock later: the link is selected.
    selected: bool,
    /// Bits of the current byte received so far (mod 8).
    bit_count: u8,
    rx_shift: u8,
    rx_byte: u8,
    rx_valid: bool,
    tx_shift: u8,
    frame_start: bool,
    frame_end: bool,
    frame_whole: bool,
}

impl Default for SpiSlavePhy {
    /// The reset state: synchronisers at the idle pin levels, deselected, all else 0.
    fn default() -> Self {
        let idle = SpiPins::default();
        SpiSlavePhy {
            cs_n_sync: [idle.cs_n; 2],
            sck_sync: [idle.sck; 2],
            mosi_sync: [idle.mosi; 2],
            sck_prev: idle.sck,
            selected: false,
            bit_count: 0,
            rx_shift: 0,
            rx_byte: 0,
            rx_valid: false,
            tx_shift: 0,
            frame_start: false,
            frame_end: false,
            frame_whole: false,
        }
    }
}

impl SpiSlavePhy {
    /// One-clock pulse: CS_n fell (the cycle `selected` rises).
    pub fn frame_start(&self) -> bool {
        self.frame_start
    }

    /// One-clock pulse: CS_n rose (the cycle `selected` falls).
    pub fn frame_end(&self) -> bool {
        self.frame_end
    }

    /// With [`Self::frame_end`]: the frame ended on a byte boundary (0 for other cycles).
    pub fn frame_whole(&self) -> bool {
        self.frame_whole
    }

    /// One-clock pulse: [`Self::rx_byte`] is a newly received byte.
    pub fn rx_valid(&self) -> bool {
        self.rx_valid
    }

    /// The last byte received.
    pub fn rx_byte(&self) -> u8 {
        self.rx_byte
    }

    /// The MISO pin: the most significant bit of the transmit shift register.
    pub fn miso(&self) -> bool {
        self.tx_shift & 0x80 != 0
    }

    /// MISO's output enable: the link is selected.
    pub fn miso_oe(&self) -> bool {
        self.selected
    }

    /// Whether the coming edge loads `tx_byte` (frame start, or the falling SCK edge
    /// after a whole byte): the caller need only compute `tx_byte` then.
    pub fn takes_tx_byte(&self) -> bool {
        let cs_s = self.cs_n_sync[1];
        let start = !cs_s && !self.selected;
        start || (self.falling() && self.bit_count == 0)
    }

    fn falling(&self) -> bool {
        self.selected && !self.sck_sync[1] && self.sck_prev
    }

    fn rising(&self) -> bool {
        self.selected && self.sck_sync[1] && !self.sck_prev
    }

    /// One rising clock edge with the pins of this cycle and the frame layer's `tx_byte`
    /// (used only when [`Self::takes_tx_byte`]).
    pub fn step(&mut self, pins: &SpiPins, tx_byte: u8) {
        let cs_s = self.cs_n_sync[1];
        let sck_s = self.sck_sync[1];
        let mosi_s = self.mosi_sync[1];
        let start = !cs_s && !self.selected;
        let end = cs_s && self.selected;
        let rising = self.rising();
        let falling = self.falling();
        let load = self.takes_tx_byte();

        self.frame_start = start;
        self.frame_end = end;
        self.frame_whole = end && self.bit_count == 0;
        self.rx_valid = false;
        if rising {
            let byte = (self.rx_shift << 1) | u8::from(mosi_s);
            self.rx_shift = byte;
            if self.bit_count == 7 {
                self.rx_byte = byte;
                self.rx_valid = true;
            }
            self.bit_count = (self.bit_count + 1) & 7;
        }
        if load {
            self.tx_shift = tx_byte;
        } else if falling {
            self.tx_shift <<= 1;
        }
        if !self.selected {
            // Every frame starts at bit 0.
            self.bit_count = 0;
        }
        self.selected = !cs_s;
        self.sck_prev = sck_s;
        self.cs_n_sync = [pins.cs_n, self.cs_n_sync[0]];
        self.sck_sync = [pins.sck, self.sck_sync[0]];
        self.mosi_sync = [pins.mosi, self.mosi_sync[0]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps `phy` with `pins` for `clocks` cycles, answering `tx` for every load, and
    /// collects the received bytes and the MISO bits sampled at each rising SCK edge.
    struct Bench {
        phy: SpiSlavePhy,
        cycle: u64,
        received: Vec<(u64, u8)>,
        starts: Vec<u64>,
        ends: Vec<(u64, bool)>,
    }

    impl Bench {
        fn new() -> Self {
            Bench { phy: SpiSlavePhy::default(), cycle: 0, received: vec![], starts: vec![], ends: vec![] }
        }
        fn clock(&mut self, pins: SpiPins, tx: u8) {
            self.phy.step(&pins, tx);
            self.cycle += 1;
            if self.phy.rx_valid() {
                self.received.push((self.cycle, self.phy.rx_byte()));
            }
            if self.phy.frame_start() {
                self.starts.push(self.cycle);
            }
            if self.phy.frame_end() {
                self.ends.push((self.cycle, self.phy.frame_whole()));
            }
        }
    }

    #[test]
    fn a_byte_each_way_with_the_documented_latencies() {
        let mut bench = Bench::new();
        let mut pins = SpiPins::default();
        bench.clock(pins, 0);
        pins.cs_n = false;
        let cs_fall = bench.cycle; // the first cycle the pin is low
        let out = 0xA5u8;
        let mut miso = 0u8;
        // Four clocks to the first rising edge, then 4 low / 4 high.
        for _ in 0..4 {
            bench.clock(pins, out);
        }
        let mut last_rise = 0;
        for bit in (0..8).rev() {
            pins.mosi = (0x3Cu8 >> bit) & 1 != 0;
            pins.sck = true;
            miso = (miso << 1) | u8::from(bench.phy.miso());
            last_rise = bench.cycle;
            for _ in 0..4 {
                bench.clock(pins, out);
            }
            pins.sck = false;
            for _ in 0..4 {
                bench.clock(pins, 0x91);
            }
        }
        pins.cs_n = true;
        let cs_rise = bench.cycle;
        for _ in 0..5 {
            bench.clock(pins, 0);
        }
        assert_eq!(miso, out);
        assert_eq!(bench.received, vec![(last_rise + 3, 0x3C)]);
        assert_eq!(bench.starts, vec![cs_fall + 3]);
        assert_eq!(bench.ends, vec![(cs_rise + 3, true)]);
        assert!(bench.phy.miso(), "the byte after the frame (0x91) was loaded at the last fall");
    }
}
