//! Both host links at once around a `RECORD_PUSH`, RTL and model in lockstep at the pins:
//! an SPI master writes `RECORD_PUSH` while the 8080 master reads, the read's strobe
//! swept across the cycles the push holds the register bus (docs/spec/register_file.md,
//! "Push sequence"; docs/spec/parallel_bus_slave.md, host timing).
//!
//! What the spec says and this checks, besides every pin on every clock:
//! - a read that does not touch the push (here `STATUS`, `FIFO_LEVEL`) is not held: its
//!   data is on the bus from cycle 6 after `bus_rd_n` falls, 7 when the SPI master has
//!   the grant in that cycle, whatever the push does;
//! - a read of `RECORD_INC` (the store the push reads) waits for the hold: its data from
//!   cycle `7 + N_AXES` at the latest (one clock for the SPI grant of the push, `N_AXES`
//!   for the hold), the value written; with `bus_rd_n` low `9 + N_AXES` clocks it is
//!   never a parallel error;
//! - every push lands in the FIFO.

use finestep_cosim::TopLockstep;
use finestep_host::pins::layout::{IN_BUS_AD0, IN_BUS_ADV_N, IN_BUS_CS_N, IN_BUS_RD_N, OUT_BUS_AD0, OUT_BUS_AD_OE};
use finestep_host::regs::{command, fifo_level, parallel_error_count, record_inc, record_push, status};
use finestep_host::{Bus, BusError, PinHost, PinTarget, PinTiming, SpiBus};

const N_AXES: usize = 4;
/// Address phase (`bus_adv_n` low) of the scheduled read, as the host driver's.
const ADV: u64 = 4;

/// An 8080 read the overlay drives on its own schedule: the address phase from `start`,
/// one clock with `bus_adv_n` high, then `bus_rd_n` low for `strobe` clocks.
#[derive(Clone, Copy)]
struct Read {
    start: u64,
    halfword: u8,
    strobe: u64,
}

/// What the read saw: the first clock of the strobe (0 = the cycle `bus_rd_n` falls) with
/// `bus_ad_oe` high, and the bus in the strobe's last clock (if driven).
#[derive(Clone, Copy, Debug, Default)]
struct Seen {
    first_oe: Option<u64>,
    data: Option<u16>,
}

/// A pin target that overlays a scheduled 8080 read on the inputs the SPI host drives,
/// one clock at a time.
struct Overlay {
    inner: TopLockstep,
    cycle: u64,
    read: Option<Read>,
    seen: Seen,
}

impl Overlay {
    fn pins(&self, inputs: u64) -> u64 {
        let Some(read) = self.read else { return inputs };
        let rd_from = read.start + ADV + 1;
        if self.cycle < read.start || self.cycle >= rd_from + read.strobe {
            return inputs;
        }
        let mut word = inputs & !(0xFFFF << IN_BUS_AD0) & !(1 << IN_BUS_CS_N);
        if self.cycle < read.start + ADV {
            word &= !(1 << IN_BUS_ADV_N);
            word |= u64::from(read.halfword) << IN_BUS_AD0;
        } else {
            word |= 1 << IN_BUS_ADV_N;
        }
        if self.cycle >= rd_from {
            word &= !(1 << IN_BUS_RD_N);
        }
        word
    }

    fn observe(&mut self) {
        let Some(read) = self.read else { return };
        let rd_from = read.start + ADV + 1;
        if self.cycle < rd_from || self.cycle >= rd_from + read.strobe {
            return;
        }
        let outputs = self.inner.outputs();
        let oe = outputs >> OUT_BUS_AD_OE & 1 != 0;
        if oe && self.seen.first_oe.is_none() {
            self.seen.first_oe = Some(self.cycle - rd_from);
        }
        if self.cycle + 1 == rd_from + read.strobe {
            self.seen.data = oe.then_some((outputs >> OUT_BUS_AD0) as u16);
        }
    }
}

impl PinTarget for Overlay {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        for _ in 0..cycles {
            let pins = self.pins(inputs);
            self.inner.drive(pins, 1)?;
            self.cycle += 1;
            self.observe();
        }
        Ok(())
    }

    fn outputs(&self) -> u64 {
        self.inner.outputs()
    }
}

type Spi = SpiBus<PinHost<Overlay>>;

fn ok<T>(result: Result<T, BusError>) -> T {
    result.unwrap_or_else(|e| panic!("{e}"))
}

fn overlay(spi: &mut Spi) -> &mut Overlay {
    spi.link_mut().target_mut()
}

/// Pushes one record over SPI while the 8080 master reads `halfword` with a strobe of
/// `strobe` clocks starting `offset` clocks after the SPI frame begins; returns what the
/// read saw.
fn push_with_read(spi: &mut Spi, offset: u64, halfword: u8, strobe: u64) -> Seen {
    let start = overlay(spi).cycle + offset;
    overlay(spi).read = Some(Read { start, halfword, strobe });
    overlay(spi).seen = Seen::default();
    ok(spi.write(record_push::ADDR, 0));
    // Let the read finish and the bus recover.
    ok(spi.link_mut().idle(ADV + 1 + strobe + 8));
    let seen = overlay(spi).seen;
    overlay(spi).read = None;
    seen
}

#[test]
fn a_push_holds_only_the_requests_that_touch_it() {
    let target =
        Overlay { inner: TopLockstep::motion_no_mpg("push_hold"), cycle: 0, read: None, seen: Seen::default() };
    let mut host = PinHost::new(target, PinTiming::default());
    ok(host.reset(8));
    ok(host.idle(4));
    let mut spi = SpiBus::new(host, N_AXES);
    let incs = [0x0001_2345u32, 0x0002_A5A5, 0xFFFF_0F0F, 0x0000_00FF];
    for (axis, &inc) in incs.iter().enumerate() {
        ok(spi.write(record_inc::addr(axis), inc));
    }
    // The SPI frame's length in clocks: the push is served in its last bytes (the CRC;
    // the answer byte and the gap follow).
    let before = overlay(&mut spi).cycle;
    ok(spi.write(record_push::ADDR, 0));
    let frame = overlay(&mut spi).cycle - before;
    let sweep = frame.saturating_sub(200)..frame;

    // A read that does not touch the push, at the minimum strobe (9 clocks), its strobe
    // swept across the frame's last 200 clocks.
    for (halfword, what) in [(status::ADDR << 1, "STATUS"), (fifo_level::ADDR << 1, "FIFO_LEVEL")] {
        flush(&mut spi);
        for offset in sweep.clone() {
            let seen = push_with_read(&mut spi, offset, halfword, 9);
            let first = seen.first_oe.unwrap_or_else(|| panic!("{what} at offset {offset}: never driven"));
            assert!(first <= 7, "{what} at offset {offset}: data from cycle {first} of the strobe, not 6 or 7");
            assert!(seen.data.is_some(), "{what} at offset {offset}: not driven at the strobe's end");
        }
        check_pushes(&mut spi, sweep.end - sweep.start);
    }

    // A read of RECORD_INC[1] (the push's store) waits for the hold but, with the strobe
    // 9 + N_AXES clocks long, returns the value written.
    flush(&mut spi);
    let mut latest = 0;
    for offset in sweep.clone() {
        let seen = push_with_read(&mut spi, offset, record_inc::addr(1) << 1, 9 + N_AXES as u64);
        assert_eq!(seen.data, Some(incs[1] as u16), "RECORD_INC[1] at offset {offset}");
        latest = latest.max(seen.first_oe.unwrap_or(u64::MAX));
    }
    assert!(latest > 7, "a read of the push's store was never held (latest data from cycle {latest})");
    // Cycle 6, one more for the SPI grant of RECORD_PUSH itself, N_AXES for the hold.
    assert!(latest <= 7 + N_AXES as u64, "RECORD_INC[1] held longer than N_AXES clocks: cycle {latest}");
    check_pushes(&mut spi, sweep.end - sweep.start);
}

fn flush(spi: &mut Spi) {
    ok(spi.write(command::ADDR, command::FLUSH_FIFO.set(0, 1)));
}

/// Every push since the last flush is in the FIFO, and no 8080 access was refused.
fn check_pushes(spi: &mut Spi, pushes: u64) {
    assert_eq!(ok(spi.read_one(parallel_error_count::ADDR)), 0, "no 8080 access was refused");
    let level = fifo_level::LEVEL.get(ok(spi.read_one(fifo_level::ADDR)));
    assert_eq!(u64::from(level), pushes, "every push is in the FIFO");
}
