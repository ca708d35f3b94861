//! The SPI link of `finestep_top`, driven by a pin-level SPI master: register reads
//! after writes against the storage rules of docs/spec/register_file.md, FIFO records
//! exact and in order,
//! CRC errors rejected and counted, truncated frames never applied, the status byte.

mod host;

use finestep_interface::regs;
use finestep_model::encoder_bank::MAX_CHANNELS;
use finestep_model::top::TopParams;
use finestep_model::{PeriodRecord, MAX_AXES};
use host::*;
use proptest::prelude::*;

fn params() -> impl Strategy<Value = TopParams> {
    use finestep_interface::params::finestep_top::{N_AXES, P_WIDTH, TIMING_W, WD_W};
    let feedback = (
        prop_oneof![Just(MAX_CHANNELS), 1..=MAX_CHANNELS],
        prop_oneof![Just(true), any::<bool>()],
        prop_oneof![Just(true), any::<bool>()],
        prop::sample::select(vec![0u32, 1, 2, 4, 8]),
    );
    (
        N_AXES.min as usize..=N_AXES.max as usize,
        prop_oneof![Just(P_WIDTH.default), P_WIDTH.min..=P_WIDTH.max],
        prop_oneof![Just(TIMING_W.default), TIMING_W.min..=TIMING_W.max],
        2..=8u32,
        WD_W.min..=WD_W.max,
        feedback,
    )
        .prop_map(
            |(n_axes, p_width, timing_w, fifo_depth_log2, wd_w, (n_enc, has_mpg, step_shared, step_digit))| {
                let p = TopParams {
                    // (the pbp block needs 4 axes and no digit-serial engine)
                    has_pbp: false,
                    n_axes,
                    p_width,
                    timing_w,
                    fifo_depth_log2,
                    wd_w,
                    n_enc,
                    has_mpg,
                    step_shared,
                    step_digit,
                    ..TopParams::default()
                };
                engine_if_valid(p)
            },
        )
}

fn master() -> impl Strategy<Value = SpiMaster> {
    (4..9u64, 4..12u64, prop_oneof![Just(2u64), 2..40u64], prop_oneof![Just(0u64), 0..30u64])
        .prop_map(|(half_period, cs_setup, cs_idle, byte_gap)| SpiMaster { half_period, cs_setup, cs_idle, byte_gap })
}

fn any_record(n_axes: usize) -> impl Strategy<Value = PeriodRecord> {
    (prop::array::uniform8(any::<i32>()), any::<u8>()).prop_map(move |(raw, flags)| record(&raw, flags, n_axes))
}

/// Clocks for a frame's end to pass the synchroniser and the frame layer.
const SETTLE: u64 = 6;

/// The status byte from the `STATUS` bits of docs/registers.md while halted out of reset.
fn halted_status(estop_active: bool) -> u8 {
    use regs::status as s;
    let word = s::HALT.set(0, 1);
    let word = s::FAULT_ESTOP.set(word, 1);
    s::ESTOP_ACTIVE.set(word, u32::from(estop_active)) as u8
}

#[test]
fn register_writes_read_back_as_stored() {
    let mut runner = finestep_testkit::runner("spi_register_writes_read_back_as_stored", 48);
    let case = (params(), master(), prop::collection::vec((any::<prop::sample::Index>(), any::<u32>(), 1..6u8), 1..12));
    runner
        .run(&case, |(p, spi, writes)| {
            let mut bench = Bench::new(p);
            let addrs = rw_addresses(&p);
            let mut expected: Vec<u32> = (0..128).map(|a| rw_reset(a as u8, &p)).collect();
            // After reset every rw register reads its map reset value.
            for &addr in &addrs {
                let (_, words) = spi.read(&mut bench, addr, 1);
                prop_assert_eq!(words[0], expected[usize::from(addr)], "reset value of {:#04x}", addr);
            }
            for (index, value, count) in writes {
                let addr = addrs[index.index(addrs.len())];
                let (_, result) = spi.write(&mut bench, addr, value);
                prop_assert_eq!(result, ACK);
                // Halted all along (E-stop fault from reset): RUN and the jog's ENABLE are forced to 0.
                let stored = halted_write(addr, value & rw_mask(addr, &p).unwrap());
                expected[usize::from(addr)] = stored;
                let (_, words) = spi.read(&mut bench, addr, count);
                for (k, word) in words.iter().enumerate() {
                    let a = (usize::from(addr) + k) % 128;
                    if rw_mask(a as u8, &p).is_some() {
                        prop_assert_eq!(*word, expected[a], "register {:#04x}", a);
                    }
                }
            }
            // The constant registers.
            let (_, words) = spi.read(&mut bench, regs::id::ADDR, 3);
            prop_assert_eq!(words[0], regs::id::MAGIC_VALUE);
            prop_assert_eq!(regs::version::MINOR.get(words[1]), regs::MAP_VERSION_MINOR);
            prop_assert_eq!(regs::caps::N_AXES.get(words[2]) as usize, p.n_axes);
            prop_assert_eq!(regs::caps::FIFO_DEPTH_LOG2.get(words[2]), p.fifo_depth_log2);
            prop_assert_eq!(regs::caps::TIMING_W.get(words[2]), p.timing_w);
            prop_assert_eq!(regs::caps::N_ENC.get(words[2]) as usize, p.n_enc);
            prop_assert_eq!(regs::caps::HAS_MPG.get(words[2]), u32::from(p.has_mpg));
            // The step engine's slots: 2 for up to 2 axes, 4 for up to 4, 8 beyond.
            let slots_log2 = match (p.step_shared, p.n_axes) {
                (false, _) => 0,
                (true, 1..=2) => 1,
                (true, 3..=4) => 2,
                (true, _) => 3,
            };
            // The digit-serial engine's round: the slots times 32 / STEP_DIGIT.
            let visit_log2 = if p.step_shared && p.step_digit != 0 { 5 - p.step_digit.trailing_zeros() } else { 0 };
            prop_assert_eq!(regs::caps::STEP_ROUND_LOG2.get(words[2]), slots_log2 + visit_log2);
            Ok(())
        })
        .unwrap();
}

#[test]
fn status_byte_follows_the_machine_state() {
    let spi = SpiMaster::default();
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(TopParams::default());
    // Right out of reset the filter still takes the E-stop as active.
    let (status, _) = spi.read(&mut bench, regs::id::ADDR, 1);
    assert_eq!(status, halted_status(true));
    bench.clock(100);
    let (status, _) = spi.read(&mut bench, regs::id::ADDR, 1);
    assert_eq!(status, halted_status(false), "released for longer than ESTOP_FILTER");
    bench.bring_up(&bus);
    let (status, result) = spi.write(&mut bench, regs::control::ADDR, regs::control::reset_word() | 1);
    assert_eq!((status, result), (0, ACK));
    let (status, _) = spi.read(&mut bench, regs::id::ADDR, 1);
    assert_eq!(status, regs::status::RUNNING.set(0, 1) as u8);
    // A bad command: every byte after the header reads the result; BUS_ERROR then shows.
    let rx = spi.transfer(&mut bench, &[0x7E, 0, 0, 0, 0], None);
    assert_eq!(rx[3..], [BAD_COMMAND, BAD_COMMAND]);
    let (status, _) = spi.read(&mut bench, regs::id::ADDR, 1);
    let running_with_error = regs::status::BUS_ERROR.set(regs::status::RUNNING.set(0, 1), 1);
    assert_eq!(status, running_with_error as u8, "bit 11 (BUS_ERROR) is not in the status byte");
    let (_, words) = spi.read(&mut bench, regs::status::ADDR, 1);
    assert_eq!(regs::status::BUS_ERROR.get(words[0]), 1);
    assert_eq!(bench.reg(regs::frame_error_count::ADDR), 1);
}

#[test]
fn fifo_frames_queue_exact_records_in_order_and_refuse_what_does_not_fit() {
    let mut runner = finestep_testkit::runner("spi_fifo_frames_exact", 32);
    let case = (params(), master()).prop_flat_map(|(p, spi)| {
        let frames = prop::collection::vec(prop::collection::vec(any_record(p.n_axes), 1..12), 1..8);
        (Just(p), Just(spi), frames)
    });
    runner
        .run(&case, |(p, spi, frames)| {
            let mut bench = Bench::new(p);
            let depth = 1usize << p.fifo_depth_log2;
            let mut queued: Vec<PeriodRecord> = vec![];
            let mut refused = 0u32;
            for frame in &frames {
                let (_, result) = spi.fifo(&mut bench, frame, p.n_axes);
                if queued.len() + frame.len() <= depth {
                    prop_assert_eq!(result, ACK);
                    queued.extend_from_slice(frame);
                } else {
                    prop_assert_eq!(result, FIFO_REFUSED);
                    refused += frame.len() as u32;
                }
                let held: Vec<PeriodRecord> = bench.top.fifo().records().copied().collect();
                prop_assert_eq!(&held, &queued);
                let level = bench.reg(regs::fifo_level::ADDR);
                prop_assert_eq!(regs::fifo_level::LEVEL.get(level) as usize, queued.len());
                prop_assert_eq!(regs::fifo_level::FREE.get(level) as usize, depth - queued.len());
            }
            prop_assert_eq!(bench.reg(regs::refused_record_count::ADDR), refused);
            prop_assert_eq!(regs::status::OVERFLOW.get(bench.reg(regs::status::ADDR)), u32::from(refused > 0));
            prop_assert_eq!(bench.reg(regs::crc_error_count::ADDR), 0);
            prop_assert_eq!(bench.reg(regs::frame_error_count::ADDR), 0);
            Ok(())
        })
        .unwrap();
}

/// A random WRITE or FIFO frame, its payload, and what applying it changes.
#[derive(Clone, Debug)]
enum Frame {
    Write { index: prop::sample::Index, value: u32 },
    Fifo { records: Vec<[i32; MAX_AXES]> },
}

fn frame() -> impl Strategy<Value = Frame> {
    prop_oneof![
        (any::<prop::sample::Index>(), any::<u32>()).prop_map(|(index, value)| Frame::Write { index, value }),
        prop::collection::vec(prop::array::uniform8(any::<i32>()), 1..5).prop_map(|records| Frame::Fifo { records }),
    ]
}

/// Everything a frame could change: every rw register and the FIFO contents.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Observable {
    registers: Vec<(u8, u32)>,
    fifo: Vec<PeriodRecord>,
    staged: usize,
}

fn observable(bench: &Bench, p: &TopParams) -> Observable {
    Observable {
        registers: rw_addresses(p).iter().map(|&a| (a, bench.reg(a))).collect(),
        fifo: bench.top.fifo().records().copied().collect(),
        staged: bench.top.fifo().staged(),
    }
}

impl Frame {
    fn is_fifo(&self) -> bool {
        matches!(self, Frame::Fifo { .. })
    }

    fn records(&self, p: &TopParams) -> Vec<PeriodRecord> {
        match self {
            Frame::Write { .. } => vec![],
            Frame::Fifo { records } => records.iter().map(|raw| record(raw, 0, p.n_axes)).collect(),
        }
    }

    fn write_target(&self, p: &TopParams) -> Option<(u8, u32)> {
        match self {
            Frame::Write { index, value } => {
                let addrs = rw_addresses(p);
                Some((addrs[index.index(addrs.len())], *value))
            }
            Frame::Fifo { .. } => None,
        }
    }

    fn bytes(&self, p: &TopParams) -> Vec<u8> {
        match self.write_target(p) {
            Some((addr, value)) => write_frame(addr, value),
            None => fifo_frame(&self.records(p), p.n_axes),
        }
    }

    /// What applying the frame to a machine halted since reset changes, by the spec.
    fn applied_to(&self, before: &Observable, p: &TopParams) -> Observable {
        let mut after = before.clone();
        if let Some((addr, value)) = self.write_target(p) {
            // Halted all along (E-stop fault from reset): RUN and the jog's ENABLE are forced to 0.
            let stored = halted_write(addr, value & rw_mask(addr, p).unwrap());
            for slot in after.registers.iter_mut().filter(|(a, _)| *a == addr) {
                slot.1 = stored;
            }
        }
        after.fifo.extend(self.records(p));
        after
    }
}

#[test]
fn corrupted_frames_are_rejected_and_counted() {
    let mut runner = finestep_testkit::runner("spi_corrupted_frames_rejected", 128);
    let case = (params(), master(), frame(), any::<prop::sample::Index>(), 1..=255u8);
    runner
        .run(&case, |(p, spi, frame, at, flip)| {
            let mut bench = Bench::new(p);
            let mut bytes = frame.bytes(&p);
            // Any byte after the command up to the CRC's low byte. A FIFO frame's count
            // is left alone (a changed count re-frames the records, a different test);
            // a WRITE frame's count changed makes it a bad command.
            let mut position = 1 + at.index(bytes.len() - 2 - usize::from(frame.is_fifo()));
            if frame.is_fifo() && position >= 2 {
                position += 1;
            }
            let count_changed = position == 2;
            bytes[position] ^= flip;
            let before = observable(&bench, &p);
            let rx = spi.transfer(&mut bench, &bytes, None);
            bench.clock(SETTLE);
            prop_assert_eq!(observable(&bench, &p), before, "a corrupted frame changed something");
            let crc_errors = bench.reg(regs::crc_error_count::ADDR);
            let frame_errors = bench.reg(regs::frame_error_count::ADDR);
            if count_changed {
                prop_assert_eq!(rx[rx.len() - 1], BAD_COMMAND);
                prop_assert_eq!((crc_errors, frame_errors), (0, 1));
            } else {
                prop_assert_eq!(rx[rx.len() - 1], CRC_MISMATCH);
                prop_assert_eq!((crc_errors, frame_errors), (1, 0));
            }
            prop_assert_eq!(regs::status::BUS_ERROR.get(bench.reg(regs::status::ADDR)), 1);
            // The link still works afterwards.
            let (_, words) = spi.read(&mut bench, regs::id::ADDR, 1);
            prop_assert_eq!(words[0], regs::id::MAGIC_VALUE);
            Ok(())
        })
        .unwrap();
}

#[test]
fn truncated_frames_apply_nothing_and_count_a_frame_error() {
    let mut runner = finestep_testkit::runner("spi_truncated_frames_apply_nothing", 256);
    let case = (params(), master(), frame(), any::<prop::sample::Index>());
    runner
        .run(&case, |(p, spi, frame, cut)| {
            let mut bench = Bench::new(p);
            let bytes = frame.bytes(&p);
            // The frame is complete once the CRC's low byte is in (the byte before the
            // result byte).
            let complete_bits = 8 * (bytes.len() - 1);
            let bits = cut.index(complete_bits + 8 + 1);
            let before = observable(&bench, &p);
            spi.transfer(&mut bench, &bytes, Some(bits));
            // CS_n's rise reaches the frame layer through the synchroniser.
            bench.clock(SETTLE);
            let applied = bits >= complete_bits;
            let frame_errors = bench.reg(regs::frame_error_count::ADDR);
            if applied {
                prop_assert_eq!(observable(&bench, &p), frame.applied_to(&before, &p), "complete frame");
                prop_assert_eq!(frame_errors, 0);
            } else {
                prop_assert_eq!(observable(&bench, &p), before, "cut after {} bits changed something", bits);
                prop_assert_eq!(frame_errors, u32::from(bits > 0), "cut after {} bits", bits);
            }
            prop_assert_eq!(bench.top.fifo().staged(), 0, "staged records left behind");
            prop_assert_eq!(bench.reg(regs::crc_error_count::ADDR), 0);
            // A complete frame after the cut one works.
            let (_, words) = spi.read(&mut bench, regs::id::ADDR, 2);
            prop_assert_eq!(words[0], regs::id::MAGIC_VALUE);
            Ok(())
        })
        .unwrap();
}

#[test]
fn bad_commands_and_counts_answer_bad_command() {
    let spi = SpiMaster::default();
    let p = TopParams::default();
    let mut bench = Bench::new(p);
    for header in [[CMD_READ, 0, 0], [CMD_WRITE, 4, 2], [CMD_WRITE, 4, 0], [CMD_FIFO, 0, 0], [0x00, 0, 1], [0xFF, 0, 1]]
    {
        let mut tx = header.to_vec();
        tx.extend_from_slice(&[0; 4]);
        let rx = spi.transfer(&mut bench, &tx, None);
        assert_eq!(rx[3..], [BAD_COMMAND; 4], "header {header:?}");
    }
    assert_eq!(bench.reg(regs::frame_error_count::ADDR), 6);
}

/// A FIFO flush (COMMAND.FLUSH_FIFO over the 8080 bus) in the middle of a FIFO frame:
/// the frame answers FIFO_FLUSHED, nothing of it is queued, one frame error is counted.
#[test]
fn a_flush_during_a_fifo_frame_drops_it() {
    let mut runner = finestep_testkit::runner("spi_flush_during_fifo_frame", 32);
    let case = (prop::collection::vec(any_record(4), 2..6), 0.05..0.9f64);
    runner
        .run(&case, |(records, when)| {
            let p = TopParams::default();
            let mut bench = Bench::new(p);
            let spi = SpiMaster::default();
            let bus = ParallelMaster::default();
            let spi_wave = spi.waveform(&fifo_frame(&records, p.n_axes), None);
            // The flush lands while the records are being received (between the
            // header's end and the CRC's start).
            let header_end = spi_wave.samples[24];
            let crc_start = spi_wave.samples[spi_wave.samples.len() - 24];
            let start = header_end + ((crc_start - header_end - 40) as f64 * when) as usize;
            let mut bus_wave = Waveform { pins: vec![(true, true, true, true, 0); start], samples: vec![] };
            let flush = bus
                .waveform(&ParallelMaster::write32_accesses(regs::command::ADDR, regs::command::FLUSH_FIFO.set(0, 1)));
            bus_wave.pins.extend(flush.pins);
            let (miso, _) = run_waveforms(&mut bench, &spi_wave, &bus_wave);
            bench.clock(SETTLE);
            let rx = bits_to_bytes(&miso);
            prop_assert_eq!(rx[rx.len() - 1], FIFO_FLUSHED);
            prop_assert_eq!((bench.top.fifo().level(), bench.top.fifo().staged()), (0, 0));
            prop_assert_eq!(bench.reg(regs::frame_error_count::ADDR), 1);
            prop_assert_eq!(bench.reg(regs::crc_error_count::ADDR), 0);
            Ok(())
        })
        .unwrap();
}
