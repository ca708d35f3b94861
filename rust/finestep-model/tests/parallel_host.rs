//! The 8080/FSMC link of `finestep_top`, driven by a pin-level master: 32-bit writes
//! and coherent 32-bit reads, the read timing of the spec, and aborted or mismatched
//! cycles that must write nothing.

mod host;

use finestep_interface::regs;
use finestep_model::top::TopParams;
use finestep_model::MAX_AXES;
use host::*;
use proptest::prelude::*;

fn master() -> impl Strategy<Value = ParallelMaster> {
    (3..7u64, 3..7u64, 9..14u64, 4..9u64).prop_map(|(adv_low, wr_low, rd_low, recovery)| ParallelMaster {
        adv_low,
        wr_low,
        rd_low,
        recovery,
    })
}

#[test]
fn register_writes_read_back_as_stored() {
    let mut runner = finestep_testkit::runner("parallel_register_writes_read_back", 64);
    let case =
        (1..=MAX_AXES, 1..=16u32, master(), prop::collection::vec((any::<prop::sample::Index>(), any::<u32>()), 1..24));
    runner
        .run(&case, |(n_axes, timing_w, bus, writes)| {
            let p = TopParams { n_axes, timing_w, has_pbp: n_axes >= 4, ..TopParams::default() };
            let mut bench = Bench::new(p);
            let addrs = rw_addresses(&p);
            let mut expected: Vec<u32> = (0..128).map(|a| rw_reset(a as u8, &p)).collect();
            for (index, value) in writes {
                let addr = addrs[index.index(addrs.len())];
                bus.write32(&mut bench, addr, value);
                // Halted all along (E-stop fault from reset): RUN and the jog's ENABLE are forced to 0.
                let stored = halted_write(addr, value & rw_mask(addr, &p).unwrap());
                expected[usize::from(addr)] = stored;
                prop_assert_eq!(bus.read32(&mut bench, addr), stored, "register {:#04x}", addr);
            }
            for &addr in &addrs {
                prop_assert_eq!(bus.read32(&mut bench, addr), expected[usize::from(addr)], "register {:#04x}", addr);
            }
            prop_assert_eq!(bench.reg(regs::parallel_error_count::ADDR), 0);
            Ok(())
        })
        .unwrap();
}

/// `TIMESTAMP` counts clocks from reset, so its true value in every cycle is known: a
/// 32-bit read must give the value of one cycle within its low-half strobe, also when
/// the low half wraps between the halves and SPI traffic or a pause comes in between.
#[test]
fn thirty_two_bit_reads_are_coherent_across_the_low_half_wrap() {
    let mut runner = finestep_testkit::runner("parallel_reads_are_coherent", 96);
    let case = (master(), 0..200u64, prop::bool::ANY, prop_oneof![Just(0u64), 0..300u64]);
    runner
        .run(&case, |(bus, offset, spi_between, pause)| {
            let mut bench = Bench::new(TopParams::default());
            // Start the read so the low half wraps (0xFFFF -> 0x0000) between halves.
            bench.clock((0x1_0000u64 - 100).saturating_sub(bench.since_reset) + offset / 2);
            let start = bench.since_reset;
            let low = bus.read16(&mut bench, regs::timestamp::ADDR, false).expect("low half driven");
            let low_end = bench.since_reset;
            if spi_between {
                SpiMaster::default().read(&mut bench, regs::timestamp::ADDR, 2);
            }
            bench.clock(pause);
            let high = bus.read16(&mut bench, regs::timestamp::ADDR, true).expect("high half driven");
            let value = u64::from(high) << 16 | u64::from(low);
            prop_assert!(
                value >= start && value <= low_end,
                "value {:#x} outside [{:#x}, {:#x}]",
                value,
                start,
                low_end
            );
            Ok(())
        })
        .unwrap();
}

#[test]
fn read_data_timing_is_as_documented() {
    let mut bench = Bench::new(TopParams::default());
    let bus = ParallelMaster::default();
    // Address phase, then hold bus_rd_n low and watch bus_ad_oe.
    bench.pins.bus_cs_n = false;
    bench.pins.bus_ad_in = u16::from(regs::id::ADDR) << 1;
    bench.pins.bus_adv_n = false;
    bench.clock(bus.adv_low);
    bench.pins.bus_adv_n = true;
    bench.pins.bus_rd_n = false;
    let fall = bench.since_reset;
    let mut first_driven = None;
    for _ in 0..12 {
        bench.clock(1);
        let out = bench.top.outputs();
        if out.bus_ad_oe && first_driven.is_none() {
            first_driven = Some(bench.since_reset - fall);
            assert_eq!(out.bus_ad_out, regs::id::MAGIC_VALUE as u16);
        }
    }
    assert_eq!(first_driven, Some(6), "driven {first_driven:?} clocks after bus_rd_n fell, spec: from cycle 6");
    bench.pins.bus_rd_n = true;
    let rise = bench.since_reset;
    let mut released = None;
    for _ in 0..8 {
        bench.clock(1);
        if !bench.top.outputs().bus_ad_oe && released.is_none() {
            released = Some(bench.since_reset - rise);
        }
    }
    assert_eq!(released, Some(3), "spec: released 3 clocks after bus_rd_n rises");
    // The high half was latched by the low-half read.
    bench.pins.bus_cs_n = true;
    bench.clock(4);
    assert_eq!(bus.read16(&mut bench, regs::id::ADDR, true), Some((regs::id::MAGIC_VALUE >> 16) as u16));
}

#[test]
fn mismatched_and_aborted_cycles_write_nothing_and_count() {
    let bus = ParallelMaster::default();
    let p = TopParams::default();
    let mut bench = Bench::new(p);
    let target = regs::fifo_watermark::ADDR;
    let other = regs::start_level::ADDR;
    let before = (bench.reg(target), bench.reg(other));
    // A high half alone.
    bus.write16(&mut bench, target, true, 0x1234);
    // A low half of one register completed by the high half of another.
    bus.write16(&mut bench, other, false, 0x0005);
    bus.write16(&mut bench, target, true, 0x0000);
    // A low half, then a read (which drops the held low half), then the high half.
    bus.write16(&mut bench, target, false, 0x0007);
    bus.read16(&mut bench, regs::id::ADDR, false);
    bus.write16(&mut bench, target, true, 0x0000);
    bench.clock(4);
    assert_eq!((bench.reg(target), bench.reg(other)), before, "nothing written");
    assert_eq!(bench.reg(regs::parallel_error_count::ADDR), 3);
    assert_eq!(regs::status::BUS_ERROR.get(bench.reg(regs::status::ADDR)), 1);
    // A read strobe too short to be answered in time, then a normal read: still right.
    let short = ParallelMaster { rd_low: 3, ..bus };
    short.read16(&mut bench, regs::id::ADDR, false);
    assert_eq!(bus.read32(&mut bench, regs::id::ADDR), regs::id::MAGIC_VALUE);
    // A complete 32-bit write after all that.
    bus.write32(&mut bench, target, 0x0000_0042);
    assert_eq!(bench.reg(target), 0x42);
    assert_eq!(bench.reg(regs::parallel_error_count::ADDR), 3);
}

/// Both host links at once: the SPI frame layer has priority on the register bus and
/// the 8080 slave waits for it, within the 8080 read timing; every access of both is
/// right.
#[test]
fn spi_and_parallel_at_once_both_get_their_accesses() {
    let mut runner = finestep_testkit::runner("spi_and_parallel_at_once", 96);
    let case =
        (0..400usize, prop::collection::vec(any::<u32>(), 1..4), prop::collection::vec(any::<u32>(), 1..4), 4..7u64);
    runner
        .run(&case, |(delay, spi_values, bus_values, half_period)| {
            let p = TopParams::default();
            let mut bench = Bench::new(p);
            let spi = SpiMaster { half_period, ..SpiMaster::default() };
            let bus = ParallelMaster::default();
            // SPI writes RECORD_INC[k] and reads them all back in one frame; the 8080
            // master writes and reads AXIS_TIMING_A[k] meanwhile.
            let mut spi_bytes = vec![];
            for (k, value) in spi_values.iter().enumerate() {
                spi_bytes.push(write_frame(regs::record_inc::addr(k), *value));
            }
            let count = spi_values.len() as u8;
            let mut read = vec![CMD_READ, regs::record_inc::ADDR, count];
            read.resize(3 + 4 * usize::from(count) + 2, 0);
            let mut spi_wave = Waveform { pins: vec![(true, false, false); delay], samples: vec![] };
            let mut frame_samples = vec![];
            for bytes in spi_bytes.iter().chain([&read]) {
                let wave = spi.waveform(bytes, None);
                let offset = spi_wave.pins.len();
                frame_samples.push((spi_wave.samples.len(), wave.samples.len()));
                spi_wave.samples.extend(wave.samples.iter().map(|s| s + offset));
                spi_wave.pins.extend(wave.pins);
            }
            let mut accesses = vec![];
            for (k, value) in bus_values.iter().enumerate() {
                accesses.extend(ParallelMaster::write32_accesses(regs::axis_timing_a::addr(k), *value));
            }
            for k in 0..bus_values.len() {
                accesses.extend(ParallelMaster::read32_accesses(regs::axis_timing_a::addr(k)));
            }
            // Repeat the reads for the whole SPI traffic, so requests collide.
            let mut bus_wave = bus.waveform(&accesses);
            let reads: Vec<BusAccess> = (0..bus_values.len())
                .flat_map(|k| ParallelMaster::read32_accesses(regs::axis_timing_a::addr(k)))
                .collect();
            while bus_wave.pins.len() < spi_wave.pins.len() {
                let more = bus.waveform(&reads);
                let offset = bus_wave.pins.len();
                bus_wave.samples.extend(more.samples.iter().map(|s| s + offset));
                bus_wave.pins.extend(more.pins);
            }
            let (miso, ad) = run_waveforms(&mut bench, &spi_wave, &bus_wave);

            let timing_mask = 0x0FFF_0FFF;
            let expected: Vec<u32> = bus_values.iter().map(|v| v & timing_mask).collect();
            for (i, pair) in ad.chunks(2).enumerate() {
                let low = pair[0].expect("low half not driven");
                let high = pair[1].expect("high half not driven");
                let k = i % bus_values.len();
                prop_assert_eq!(
                    u32::from(high) << 16 | u32::from(low),
                    expected[k],
                    "8080 read {} of AXIS_TIMING_A[{}]",
                    i,
                    k
                );
            }
            for (frame, &(first, len)) in frame_samples.iter().enumerate() {
                let rx = bits_to_bytes(&miso[first..first + len]);
                if frame < spi_values.len() {
                    prop_assert_eq!(rx[rx.len() - 1], ACK, "SPI write {}", frame);
                } else {
                    let words: Vec<u32> = rx[3..3 + 4 * usize::from(count)]
                        .chunks(4)
                        .map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]))
                        .collect();
                    prop_assert_eq!(&words, &spi_values, "SPI read-back");
                }
            }
            prop_assert_eq!(bench.reg(regs::parallel_error_count::ADDR), 0);
            prop_assert_eq!(bench.reg(regs::frame_error_count::ADDR), 0);
            Ok(())
        })
        .unwrap();
}

/// `INC_WRITE_ONLY` (docs/spec/register_file.md#write-only-record_inc): `RECORD_INC` reads
/// 0 over the bus, and `RECORD_PUSH` still queues what was written; without it the words
/// read back as written.
#[test]
fn write_only_record_inc_reads_zero_and_still_pushes() {
    let bus = ParallelMaster::default();
    let incs: [i32; 4] = [0x0001_8000, -0x0001_0000, 0x0000_4000, -3];
    for write_only in [false, true] {
        let mut bench = Bench::new(TopParams { inc_write_only: write_only, ..TopParams::default() });
        bench.bring_up(&bus);
        for (axis, &inc) in incs.iter().enumerate() {
            bus.write32(&mut bench, regs::record_inc::addr(axis), inc as u32);
        }
        for (axis, &inc) in incs.iter().enumerate() {
            let read = bus.read32(&mut bench, regs::record_inc::addr(axis));
            assert_eq!(read, if write_only { 0 } else { inc as u32 }, "RECORD_INC[{axis}], write-only {write_only}");
        }
        bus.write32(&mut bench, regs::record_push::ADDR, regs::record_push::FLAGS.set(0, 1));
        bench.clock(10);
        let queued: Vec<_> = bench.top.fifo().records().copied().collect();
        assert_eq!(queued, vec![finestep_model::PeriodRecord::from_raw(&incs, 1)], "write-only {write_only}");
    }
}

/// `INC_DIRECT` (docs/spec/register_file.md#record_inc-straight-into-the-fifo): a push
/// queues the increments written since the last push, and only when every axis's was
/// written; a push without them, or with one missing, is refused (`OVERFLOW`, one refused
/// record) and queues nothing, where the default build queues `RECORD_INC` as it holds it.
/// A write of `RECORD_INC` while the FIFO is full is lost: the push after it is refused
/// even after a flush made room.
#[test]
fn direct_record_inc_pushes_only_whole_records() {
    let bus = ParallelMaster::default();
    let incs: [i32; 4] = [0x0001_8000, -0x0001_0000, 0x0000_4000, -3];
    let record = |flags| finestep_model::PeriodRecord::from_raw(&incs, flags);
    for direct in [false, true] {
        let params = TopParams {
            has_spi: false,
            inc_write_only: true,
            inc_direct: direct,
            fifo_depth_log2: 2,
            ..TopParams::default()
        };
        let mut bench = Bench::new(params);
        bench.bring_up(&bus);
        let write_incs = |bench: &mut Bench, lanes: usize| {
            for (axis, &inc) in incs.iter().enumerate().take(lanes) {
                bus.write32(bench, regs::record_inc::addr(axis), inc as u32);
            }
        };
        let push = |bench: &mut Bench, flags: u32| {
            bus.write32(bench, regs::record_push::ADDR, regs::record_push::FLAGS.set(0, flags));
            bench.clock(10);
        };
        write_incs(&mut bench, 4);
        push(&mut bench, 1);
        // Again without writing, then with 3 of the 4 lanes written.
        push(&mut bench, 0);
        write_incs(&mut bench, 3);
        push(&mut bench, 0);
        let queued: Vec<_> = bench.top.fifo().records().copied().collect();
        let refused = bench.reg(regs::refused_record_count::ADDR);
        let overflow = regs::status::OVERFLOW.get(bench.reg(regs::status::ADDR));
        if direct {
            assert_eq!(queued, vec![record(1)]);
            assert_eq!((refused, overflow), (2, 1));
        } else {
            assert_eq!(queued, vec![record(1), record(0), record(0)]);
            assert_eq!((refused, overflow), (0, 0));
        }
        // Fill the FIFO, then write the lanes while it is full and flush: the lanes
        // written while full are lost (INC_DIRECT), the push is refused.
        bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_COUNTERS.set(0, 1));
        while bench.top.fifo_level() < 4 {
            write_incs(&mut bench, 4);
            push(&mut bench, 0);
        }
        write_incs(&mut bench, 4);
        bus.write32(&mut bench, regs::command::ADDR, regs::command::FLUSH_FIFO.set(0, 1));
        bench.clock(10);
        push(&mut bench, 1);
        let queued: Vec<_> = bench.top.fifo().records().copied().collect();
        let refused = bench.reg(regs::refused_record_count::ADDR);
        if direct {
            assert!(queued.is_empty(), "{queued:?}");
            assert_eq!(refused, 1);
        } else {
            assert_eq!(queued, vec![record(1)]);
            assert_eq!(refused, 0);
        }
        // The whole record written again is queued.
        write_incs(&mut bench, 4);
        push(&mut bench, 0);
        assert_eq!(bench.top.fifo().records().last().copied(), Some(record(0)), "direct {direct}");
    }
}

/// `AXIS_WRITE_ONLY` (docs/spec/register_file.md#write-only-axis-registers):
/// `AXIS_TIMING_A/B` and `AXIS_MODE` read 0 over the bus, and the core still takes what
/// was written; without it they read back as written.
#[test]
fn write_only_axis_registers_read_zero_and_still_configure() {
    let bus = ParallelMaster::default();
    let timing_a = regs::axis_timing_a::STEP_SPACE.set(regs::axis_timing_a::STEP_LEN.set(0, 7), 9);
    let timing_b = regs::axis_timing_b::DIR_HOLD.set(regs::axis_timing_b::DIR_SETUP.set(0, 5), 6);
    let mode = regs::axis_mode::INVERT_B.set(regs::axis_mode::OUT_MODE.set(0, 1), 1);
    for write_only in [false, true] {
        let mut bench = Bench::new(TopParams { axis_write_only: write_only, ..TopParams::default() });
        bench.bring_up(&bus);
        let words = [
            (regs::axis_timing_a::addr(2), timing_a),
            (regs::axis_timing_b::addr(2), timing_b),
            (regs::axis_mode::addr(2), mode),
        ];
        for &(addr, word) in &words {
            bus.write32(&mut bench, addr, word);
        }
        for &(addr, word) in &words {
            let read = bus.read32(&mut bench, addr);
            assert_eq!(read, if write_only { 0 } else { word }, "{addr:#x}, write-only {write_only}");
        }
        let config = bench.top.registers().axis_config(2);
        let written = finestep_model::DriveTiming::new(7, 9, 5, 6);
        assert_eq!(config.timing, written, "the core takes the timing written, write-only {write_only}");
        assert_eq!((config.mode, config.invert), (1, finestep_interface::invert::PIN_B), "write-only {write_only}");
    }
}
