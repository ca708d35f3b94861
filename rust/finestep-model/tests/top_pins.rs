//! `finestep_top` under arbitrary pin activity: it never panics, the FIFO bookkeeping
//! holds, the outputs of an absent host link stay 0, and the pin packing round-trips.

mod host;

use finestep_model::encoder_bank::MAX_CHANNELS;
use finestep_model::top::{Top, TopInputs, TopOutputs, TopParams};
use finestep_model::MAX_AXES;
use proptest::prelude::*;

fn params() -> impl Strategy<Value = TopParams> {
    let links = (any::<bool>(), any::<bool>(), 1..=MAX_CHANNELS, any::<bool>(), any::<bool>());
    let io = (
        any::<bool>(),
        any::<bool>(),
        0..=8usize,
        prop::sample::select(vec![0u32, 1, 2, 4, 8]),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    );
    (1..=MAX_AXES, 1..=24u32, 1..=16u32, 1..=6u32, 1..=24u32, links, io).prop_map(
        |(
            n_axes,
            p_width,
            timing_w,
            fifo_depth_log2,
            wd_w,
            (has_spi, has_parallel, n_enc, has_mpg, step_shared),
            (has_spindle, has_outputs, n_gpio, step_digit, one_snapshot, inc_write_only, axis_write_only),
        )| {
            let p = TopParams {
                n_axes,
                p_width,
                timing_w,
                fifo_depth_log2,
                wd_w,
                clock_hz: 1,
                has_spi,
                has_parallel,
                n_enc,
                has_mpg,
                step_shared,
                step_digit,
                one_snapshot,
                inc_write_only,
                axis_write_only,
                // INC_DIRECT needs INC_WRITE_ONLY; drawn with ONE_SNAPSHOT's bit
                inc_direct: inc_write_only && one_snapshot,
                // ENC_COUNT_W 16 or 32, drawn with AXIS_WRITE_ONLY's bit
                enc_count_w: if axis_write_only { 16 } else { 32 },
                has_spindle,
                has_outputs,
                n_gpio,
                has_panel: false,
                // (the pbp block needs 4 axes and no digit-serial engine: apart, in core_pbp)
                has_pbp: false,
                has_gantry: false,
            };
            host::engine_if_valid(p)
        },
    )
}

#[test]
fn random_pins_never_break_the_top() {
    let mut runner = finestep_testkit::runner("random_pins_never_break_the_top", 128);
    // Runs of random pin words, each held a random number of clocks.
    let case = (params(), prop::collection::vec((any::<u64>(), 1..40u64), 1..300));
    runner
        .run(&case, |(p, runs)| {
            let mut top = Top::new(p);
            let depth = 1usize << p.fifo_depth_log2;
            for (word, clocks) in runs {
                // Reset rarely, so the links get to do things.
                let word = if word % 64 == 0 { word | 1 } else { word & !1 };
                let inputs = TopInputs::unpack(word);
                prop_assert_eq!(TopInputs::unpack(inputs.pack()), inputs);
                for _ in 0..clocks {
                    top.step(&inputs);
                    let out = top.outputs();
                    prop_assert_eq!(TopOutputs::unpack(out.pack()), out);
                    prop_assert!(top.fifo().level() + top.fifo().staged() <= depth);
                    let unused = !0u8 << p.n_axes.min(7) & if p.n_axes == 8 { 0 } else { 0xFF };
                    prop_assert_eq!((out.pin_a | out.pin_b | out.pin_en) & unused, 0, "pins of absent axes");
                    if !p.has_spi {
                        prop_assert!(!out.spi_miso && !out.spi_miso_oe);
                    }
                    if !p.has_parallel {
                        prop_assert!(!out.bus_ad_oe && out.bus_ad_out == 0);
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}

/// The axis registers reach the pins: with the machine halted and stopped, pin A is
/// the step level (0) and pin B the direction (1, positive), each XOR its inversion, and
/// the enable pin `(AXIS_ENABLE & !halt) ^ INVERT_EN`, from the pin table of
/// docs/spec/step_shaper.md.
#[test]
fn axis_registers_reach_the_idle_pins() {
    use finestep_interface::regs::{axis_enable, axis_mode};
    let p = TopParams { n_axes: 3, has_pbp: false, ..TopParams::default() };
    let bus = host::ParallelMaster::default();
    let mut bench = host::Bench::new(p);
    let inverts = [(false, false, true), (true, true, false), (true, false, true)];
    for (axis, &(a, b, en)) in inverts.iter().enumerate() {
        let word = axis_mode::INVERT_A.set(0, u32::from(a));
        let word = axis_mode::INVERT_B.set(word, u32::from(b));
        let word = axis_mode::INVERT_EN.set(word, u32::from(en));
        bus.write32(&mut bench, axis_mode::addr(axis), word);
    }
    bus.write32(&mut bench, axis_enable::ADDR, 0b011);
    bench.clock(2);
    let check = |bench: &host::Bench, halted: bool| {
        let out = bench.top.outputs();
        for (axis, &(a, b, en)) in inverts.iter().enumerate() {
            let enabled = axis < 2 && !halted;
            assert_eq!(out.pin_a(axis), a, "axis {axis} pin A");
            assert_eq!(out.pin_b(axis), !b, "axis {axis} pin B");
            assert_eq!(out.pin_en(axis), enabled != en, "axis {axis} enable, halted {halted}");
        }
    };
    check(&bench, true);
    bench.bring_up(&bus);
    check(&bench, false);
}

/// `IRQ_STATUS.PERIOD` sets in the clock after a boundary and the `irq` flip-flop
/// follows one clock later when the source is enabled; writing 1 clears the source.
#[test]
fn irq_follows_the_masked_period_source() {
    use finestep_interface::regs::{control, irq_mask, irq_status, period_clocks};
    let bus = host::ParallelMaster::default();
    let mut bench = host::Bench::new(TopParams::default());
    bench.bring_up(&bus);
    bus.write32(&mut bench, period_clocks::ADDR, 1000);
    bus.write32(&mut bench, irq_mask::ADDR, irq_status::PERIOD.mask());
    bench.trace = Some(vec![]);
    bus.write32(&mut bench, control::ADDR, control::RUN.set(control::reset_word(), 1));
    bench.clock(100);
    let trace = bench.trace.take().unwrap();
    let b = trace.iter().position(|s| s.boundary()).expect("no boundary");
    assert!(trace[..b + 2].iter().all(|s| !s.outputs.irq), "irq before its source");
    assert!(trace[b + 2..].iter().all(|s| s.outputs.irq), "irq two clocks after the boundary, then held");
    assert_eq!(irq_status::PERIOD.get(bench.reg(irq_status::ADDR)), 1);
    bus.write32(&mut bench, irq_status::ADDR, irq_status::PERIOD.mask());
    bench.clock(2);
    assert_eq!(irq_status::PERIOD.get(bench.reg(irq_status::ADDR)), 0, "written 1 clears");
    assert!(!bench.top.outputs().irq);
    bench.clock(1000);
    assert!(bench.top.outputs().irq, "the next boundary sets it again");
}
