//! The feedback blocks in `finestep_top`, through the pins and the register bus, against
//! the feedback blocks' specs (docs/spec/): the hand wheel jogs an axis whose quadrature output
//! an encoder channel reads back (the count must equal the step position, and both the
//! rounded commanded position), the probe snapshots them on one clock, the index arms,
//! illegal transitions, the jog's interplay with `CONTROL.RUN` and the FIFO, the
//! builds without channels or hand wheel, and host reads of the encoder bank's store
//! (a read granted in the visited channel's slot stalls the shared decoder).

mod host;

use finestep_interface::regs;
use finestep_interface::Field;
use finestep_model::top::TopParams;
use host::*;

/// Quadrature pin levels `(a, b)` at position `p` (A leads B forward).
fn levels(p: i64) -> (bool, bool) {
    [(false, false), (true, false), (true, true), (false, true)][p.rem_euclid(4) as usize]
}

fn get(bench: &Bench, addr: u8, field: Field) -> u32 {
    field.get(bench.reg(addr))
}

/// Moves the hand wheel `edges` quadrature edges (signed), `hold` clocks per state.
fn turn_wheel(bench: &mut Bench, phase: &mut i64, edges: i64, hold: u64) {
    for _ in 0..edges.abs() {
        *phase += edges.signum();
        (bench.pins.mpg_a, bench.pins.mpg_b) = levels(*phase);
        bench.clock(hold);
    }
}

/// Moves encoder channel `c` by `edges` quadrature edges, `hold` clocks per state.
fn turn_encoder(bench: &mut Bench, c: usize, phase: &mut i64, edges: i64, hold: u64) {
    for _ in 0..edges.abs() {
        *phase += edges.signum();
        let (a, b) = levels(*phase);
        bench.pins.enc_a = bench.pins.enc_a & !(1 << c) | u8::from(a) << c;
        bench.pins.enc_b = bench.pins.enc_b & !(1 << c) | u8::from(b) << c;
        bench.clock(hold);
    }
}

#[test]
fn a_jogged_axis_read_back_by_an_encoder_lands_on_the_wheel_target() {
    use regs::{jog_control as jc, jog_status as js, status as st};
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(TopParams::default());
    bench.bring_up(&bus);
    bench.loopback = true;
    bus.write32(&mut bench, regs::axis_mode::addr(0), regs::axis_mode::OUT_MODE.set(0, 2));
    bus.write32(&mut bench, regs::axis_enable::ADDR, 1);
    bus.write32(&mut bench, regs::period_clocks::ADDR, 200);
    let mpg = regs::mpg_control::FILTER.set(regs::mpg_control::PRESCALE.set(0, 0), 1);
    bus.write32(&mut bench, regs::mpg_control::ADDR, mpg);
    // The wheel's prescaler counts down from the reset PRESCALE (499) before it reloads.
    bench.clock(500);
    // 1.5 steps per detent.
    bus.write32(&mut bench, regs::jog_scale::ADDR, 3 << 15);
    bus.write32(&mut bench, jc::ADDR, jc::FOLLOW.set(jc::ENABLE.set(0, 1), 1));
    bench.clock(4);
    assert_eq!(get(&bench, js::ADDR, js::ENGAGED), 1);
    let status = bench.reg(st::ADDR);
    assert_eq!((st::JOG_ENGAGED.get(status), st::RUNNING.get(status), st::STREAMING.get(status)), (1, 1, 0));

    // Three detents forward, one back: 2 detents = 3 steps.
    let mut phase = 0;
    turn_wheel(&mut bench, &mut phase, 12, 10);
    bench.clock(2000);
    turn_wheel(&mut bench, &mut phase, -4, 10);
    assert_eq!(get(&bench, regs::mpg_count::ADDR, regs::mpg_count::EDGES), 8);
    assert_eq!(get(&bench, regs::mpg_detents::ADDR, regs::mpg_detents::DETENTS), 2);
    assert_eq!(bench.top.jog().target(), 2 * (3 << 15));

    // The FIFO waits while the jog drives the core.
    bus.write32(&mut bench, regs::record_inc::addr(0), 1 << 16);
    bus.write32(&mut bench, regs::record_push::ADDR, 0);
    let mut periods = 0;
    while !(bench.top.jog().cmd() == bench.top.jog().target() && bench.top.jog().vel() == 0) {
        bench.clock(200);
        periods += 1;
        assert!(periods < 500, "the jog does not settle");
    }
    // Until the pins, the encoder's filter and the next boundary's latch have caught up.
    bench.clock(1000);
    let target_steps = rounded_steps(bench.top.jog().target());
    assert_eq!(target_steps, 3);
    assert_eq!(get(&bench, regs::position::addr(0), regs::position::STEPS) as i32, 3);
    assert_eq!(get(&bench, regs::enc_count::addr(0), regs::enc_count::VALUE) as i32, 3, "encoder reads the axis back");
    assert_eq!(get(&bench, regs::jog_remaining::ADDR, regs::jog_remaining::STEPS), 0);
    assert_eq!(get(&bench, regs::jog_velocity::ADDR, regs::jog_velocity::STEPS), 0);
    assert_eq!(bench.top.fifo_level(), 1, "the FIFO is not popped while engaged");

    // RUN is refused while engaged.
    bus.write32(&mut bench, regs::control::ADDR, regs::control::RUN.set(regs::control::reset_word(), 1));
    bench.clock(2);
    assert_eq!(get(&bench, regs::control::ADDR, regs::control::RUN), 0);
    let status = bench.reg(st::ADDR);
    assert_eq!((st::JOG_REFUSED.get(status), st::JOG_ENGAGED.get(status)), (1, 1));
    assert_eq!(get(&bench, regs::irq_status::ADDR, regs::irq_status::ERROR), 1);
    bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_ERRORS.set(0, 1));
    bench.clock(2);
    assert_eq!(get(&bench, js::ADDR, js::REFUSED), 0);
    assert_eq!(get(&bench, regs::irq_status::ADDR, regs::irq_status::ERROR), 0);

    // The probe snapshots the moved axis and the encoder on one clock.
    use regs::{probe_control as pc, probe_status as ps};
    bus.write32(&mut bench, pc::ADDR, pc::ARM.set(pc::reset_word(), 1));
    bench.clock(2);
    assert_eq!(bench.reg(ps::ADDR), ps::ARMED.mask());
    let t = bench.since_reset;
    // The probe is sampled at slot 0 of the bank's sampling rounds: with ENC_PRESCALE 0
    // every round, every S = 4 clocks (no reads stall it here).
    assert_eq!(get(&bench, regs::enc_prescale::ADDR, regs::enc_prescale::PRESCALE), 0);
    let slots = bench.top.encoders().slots() as u64;
    let slot_at_raw = (bench.top.encoders().slot() as u64 + 2) % slots;
    bench.pins.probe_pin = true;
    bench.clock(10);
    // 2 synchroniser clocks, the next sample, and the event in the cycle after it.
    let event = t + 2 + (slots - slot_at_raw) % slots + 1;
    assert!((t + 3..=t + 2 + slots).contains(&event));
    assert_eq!(get(&bench, regs::probe_time::ADDR, regs::probe_time::CLOCKS), event as u32);
    assert_eq!(bench.reg(ps::ADDR), ps::SEEN.mask() | ps::ACTIVE.mask());
    assert_eq!(get(&bench, regs::probe_position::addr(0), regs::probe_position::STEPS), 3);
    assert_eq!(get(&bench, regs::enc_probe_latch::addr(0), regs::enc_probe_latch::VALUE), 3);

    // ENABLE = 0: the jog stops and lets the core go.
    bus.write32(&mut bench, jc::ADDR, jc::FOLLOW.set(0, 1));
    bench.clock(1000);
    let status = bench.reg(st::ADDR);
    assert_eq!((st::JOG_ENGAGED.get(status), st::RUNNING.get(status)), (0, 0));
    assert_eq!(bench.top.fifo_level(), 1);
}

#[test]
fn the_jog_refuses_a_short_period_and_a_running_fifo() {
    use regs::{jog_control as jc, jog_status as js};
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(TopParams::default());
    bench.bring_up(&bus);
    bus.write32(&mut bench, regs::period_clocks::ADDR, 127);
    bus.write32(&mut bench, jc::ADDR, jc::ENABLE.set(0, 1));
    bench.clock(4);
    assert_eq!(bench.reg(js::ADDR), js::REFUSED.mask(), "PERIOD_CLOCKS < 128: refused, not engaged");
    bus.write32(&mut bench, jc::ADDR, 0);
    bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_ERRORS.set(0, 1));
    bus.write32(&mut bench, regs::period_clocks::ADDR, 1000);
    bus.write32(&mut bench, regs::control::ADDR, regs::control::RUN.set(regs::control::reset_word(), 1));
    bus.write32(&mut bench, jc::ADDR, jc::ENABLE.set(0, 1));
    bench.clock(4);
    assert_eq!(bench.reg(js::ADDR), js::REFUSED.mask(), "RUN = 1: refused, not engaged");
    assert_eq!(get(&bench, regs::control::ADDR, regs::control::RUN), 1, "the FIFO run goes on");
    // A halt clears both RUN and ENABLE.
    bench.pins.estop_pin = true;
    bench.clock(100);
    assert_eq!(get(&bench, regs::control::ADDR, regs::control::RUN), 0);
    assert_eq!(get(&bench, jc::ADDR, jc::ENABLE), 0);
}

#[test]
fn index_arms_latch_and_clear_on_the_next_index() {
    use regs::enc_status as es;
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(TopParams::default());
    let c = 1;
    let mut phase = 0;
    bench.clock(10);
    turn_encoder(&mut bench, c, &mut phase, 5, 4);
    bench.clock(4);
    assert_eq!(get(&bench, regs::enc_count::addr(c), regs::enc_count::VALUE), 5);
    let control = regs::enc_control::reset_word();
    let arm = regs::enc_control::ARM_INDEX_CLEAR.set(regs::enc_control::ARM_INDEX_LATCH.set(control, 1), 1);
    bus.write32(&mut bench, regs::enc_control::addr(c), arm);
    bench.clock(2);
    let status = bench.reg(es::addr(c));
    assert_eq!((es::LATCH_ARMED.get(status), es::CLEAR_ARMED.get(status), es::INDEX_SEEN.get(status)), (1, 1, 0));
    bench.pins.enc_z = 1 << c;
    bench.clock(5);
    assert_eq!(get(&bench, es::addr(c), es::Z), 1);
    bench.pins.enc_z = 0;
    bench.clock(5);
    let status = bench.reg(es::addr(c));
    assert_eq!((es::LATCH_ARMED.get(status), es::CLEAR_ARMED.get(status), es::INDEX_SEEN.get(status)), (0, 0, 1));
    assert_eq!(get(&bench, regs::enc_index_latch::addr(c), regs::enc_index_latch::VALUE), 5);
    assert_eq!(get(&bench, regs::enc_count::addr(c), regs::enc_count::VALUE), 0, "cleared by the index");
    // A second index without arming changes nothing.
    turn_encoder(&mut bench, c, &mut phase, -2, 4);
    bench.pins.enc_z = 1 << c;
    bench.clock(5);
    bench.pins.enc_z = 0;
    bench.clock(5);
    assert_eq!(get(&bench, regs::enc_count::addr(c), regs::enc_count::VALUE) as i32, -2);
    assert_eq!(get(&bench, regs::enc_index_latch::addr(c), regs::enc_index_latch::VALUE), 5);
    // The edge time: a pin change in cycle t is counted in cycle t + 3 (2 synchroniser
    // clocks, 1 sample at ENC_PRESCALE = 0, then the decoder compares with the cycle before).
    let t = bench.since_reset;
    turn_encoder(&mut bench, c, &mut phase, 1, 8);
    assert_eq!(get(&bench, regs::enc_edge_time::addr(c), regs::enc_edge_time::CLOCKS), t as u32 + 3);
}

#[test]
fn illegal_transitions_raise_feedback_error_until_cleared() {
    use regs::{enc_status as es, mpg_status as ms, status as st};
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(TopParams::default());
    bus.write32(&mut bench, regs::mpg_control::ADDR, regs::mpg_control::FILTER.set(0, 1));
    // The wheel's prescaler counts down from the reset PRESCALE (499) before it reloads.
    bench.clock(500);
    // Channel 2: A and B change in the same clock, twice.
    for pins in [0b100, 0] {
        bench.pins.enc_a = pins;
        bench.pins.enc_b = pins;
        bench.clock(6);
    }
    let status = bench.reg(es::addr(2));
    assert_eq!((es::ILLEGAL.get(status), es::ILLEGAL_COUNT.get(status)), (1, 2));
    assert_eq!(get(&bench, regs::enc_count::addr(2), regs::enc_count::VALUE), 0);
    assert_eq!(get(&bench, st::ADDR, st::FEEDBACK_ERROR), 1);
    assert_eq!(get(&bench, regs::irq_status::ADDR, regs::irq_status::ERROR), 1);
    bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_ERRORS.set(0, 1));
    bench.clock(2);
    let status = bench.reg(es::addr(2));
    assert_eq!((es::ILLEGAL.get(status), es::ILLEGAL_COUNT.get(status)), (0, 2), "CLEAR_ERRORS keeps the count");
    assert_eq!(get(&bench, st::ADDR, st::FEEDBACK_ERROR), 0);
    bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_COUNTERS.set(0, 1));
    bench.clock(2);
    assert_eq!(bench.reg(es::addr(2)) & es::ILLEGAL_COUNT.mask(), 0);
    // The hand wheel's illegal transitions count in FEEDBACK_ERROR too.
    bench.pins.mpg_a = true;
    bench.pins.mpg_b = true;
    bench.clock(6);
    let status = bench.reg(ms::ADDR);
    assert_eq!(
        (ms::ILLEGAL.get(status), ms::ILLEGAL_COUNT.get(status), ms::A.get(status), ms::B.get(status)),
        (1, 1, 1, 1)
    );
    assert_eq!(get(&bench, st::ADDR, st::FEEDBACK_ERROR), 1);
    assert_eq!(get(&bench, regs::mpg_count::ADDR, regs::mpg_count::EDGES), 0);
}

#[test]
fn builds_without_channels_or_hand_wheel_read_zero_there() {
    let params = TopParams { n_enc: 2, has_mpg: false, ..TopParams::default() };
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(params);
    bench.bring_up(&bus);
    let caps = bench.reg(regs::caps::ADDR);
    assert_eq!((regs::caps::N_ENC.get(caps), regs::caps::HAS_MPG.get(caps)), (2, 0));
    bus.write32(&mut bench, regs::period_clocks::ADDR, 1000);
    bus.write32(&mut bench, regs::jog_control::ADDR, regs::jog_control::ENABLE.set(0, 1));
    bus.write32(&mut bench, regs::enc_control::addr(3), 0xFFFF_FFFF);
    assert_eq!(bench.reg(regs::mpg_control::ADDR), 0);
    for addr in [regs::jog_control::ADDR, regs::jog_scale::ADDR, regs::enc_control::addr(2), regs::enc_control::addr(3)]
    {
        assert_eq!(bench.reg(addr), 0, "register {addr:#04x}");
    }
    // Every channel and the wheel turn: only channels 0 and 1 count.
    let mut phase = 0;
    for _ in 0..3 {
        phase += 1;
        let (a, b) = levels(phase);
        bench.pins.enc_a = if a { 0xF } else { 0 };
        bench.pins.enc_b = if b { 0xF } else { 0 };
        (bench.pins.mpg_a, bench.pins.mpg_b) = (a, b);
        bench.clock(3000);
    }
    let counts: Vec<u32> = (0..4).map(|c| bench.reg(regs::enc_count::addr(c))).collect();
    assert_eq!(counts, [3, 3, 0, 0]);
    assert_eq!(bench.reg(regs::mpg_count::ADDR), 0);
    assert_eq!(get(&bench, regs::status::ADDR, regs::status::JOG_ENGAGED), 0);
    assert_eq!(get(&bench, regs::status::ADDR, regs::status::RUNNING), 0);
}

#[test]
fn reads_of_the_visited_channel_stall_it_and_read_the_copies() {
    use finestep_model::encoder_bank::store_channel;
    use finestep_model::register_file::arbitrate;
    let mut bench = Bench::new(TopParams::default());
    bench.clock(10);
    let moves = [3i64, -2, 7, 1];
    for (c, &edges) in moves.iter().enumerate() {
        let mut phase = 0;
        turn_encoder(&mut bench, c, &mut phase, edges, 4);
    }
    bench.clock(8);
    let spi = SpiMaster::default();
    let mut tx = vec![CMD_READ, regs::enc_count::ADDR, 16];
    tx.resize(3 + 4 * 16 + 2, 0);
    let wave = spi.waveform(&tx, None);
    let mut stalls = 0;
    // Every alignment of the frame's reads with the bank's slots.
    for offset in 0..8 {
        bench.clock(offset);
        let mut miso = Vec::new();
        let mut served: Option<u8> = None;
        for (cycle, &(cs_n, sck, mosi)) in wave.pins.iter().enumerate() {
            (bench.pins.spi_cs_n, bench.pins.spi_sck, bench.pins.spi_mosi) = (cs_n, sck, mosi);
            if wave.samples.contains(&cycle) {
                miso.push(bench.top.outputs().spi_miso);
            }
            let top = &bench.top;
            let grant = arbitrate(top.spi_frame().request(), top.parallel().request(), false);
            let bank = top.encoders();
            let (slot, slots) = (bank.slot(), bank.slots());
            // The bank stalls on the read the bus stage serves: the one granted in the
            // cycle before (docs/spec/encoder_bank.md).
            let stall = served.and_then(|addr| store_channel(addr, bank.n_enc())) == Some(slot);
            assert_eq!(bank.stall(served), stall);
            served = grant.filter(|(_, r)| !r.write).map(|(_, r)| r.addr);
            bench.clock(1);
            let next = if stall { slot } else { (slot + 1) % slots };
            assert_eq!(bench.top.encoders().slot(), next, "offset {offset} cycle {cycle}");
            stalls += usize::from(stall);
        }
        let rx = bits_to_bytes(&miso);
        let words: Vec<u32> = rx[3..3 + 64].chunks(4).map(|w| u32::from_be_bytes([w[0], w[1], w[2], w[3]])).collect();
        for (c, &edges) in moves.iter().enumerate() {
            let channel = bench.top.encoders().channel(c);
            assert_eq!(words[c] as i32, edges as i32, "ENC_COUNT[{c}]");
            assert_eq!((words[4 + c], words[8 + c]), (0, 0), "ENC_INDEX_LATCH, ENC_PROBE_LATCH [{c}]");
            assert_eq!(words[12 + c], channel.edge_time(), "ENC_EDGE_TIME[{c}]");
            assert!(channel.edge_time() > 10);
        }
    }
    assert!(stalls > 0, "no read met its channel's slot");
}

/// `ONE_SNAPSHOT` (docs/spec/register_file.md#one-snapshot): one position snapshot for
/// the period latch and the probe. Stopped, the period latch takes it every clock and the
/// probe's registers read it; the probe's event takes it, and it holds the event's time
/// and positions while `SEEN` (the period latch leaves it alone) until the next arm.
#[test]
fn one_snapshot_holds_the_probe_event_until_the_next_arm() {
    use regs::{latch_time as lt, probe_control as pc, probe_status as ps, probe_time as pt, timestamp as ts};
    let bus = ParallelMaster::default();
    let mut bench = Bench::new(TopParams { one_snapshot: true, ..TopParams::default() });
    bench.bring_up(&bus);
    let n_axes = bench.top.params().n_axes;
    let follows_the_period_latch = |bench: &Bench| {
        // Stopped: latched at every edge, from the TIMESTAMP before it.
        let latched = bench.reg(ts::ADDR).wrapping_sub(1);
        assert_eq!(get(bench, lt::ADDR, lt::CLOCKS), latched);
        assert_eq!(get(bench, pt::ADDR, pt::CLOCKS), latched, "PROBE_TIME reads LATCH_TIME");
    };
    let positions_shared = |bench: &Bench| {
        for axis in 0..n_axes {
            let position = bench.reg(regs::position::addr(axis));
            assert_eq!(bench.reg(regs::probe_position::addr(axis)), position, "PROBE_POSITION[{axis}]");
        }
    };
    follows_the_period_latch(&bench);
    positions_shared(&bench);

    bus.write32(&mut bench, pc::ADDR, pc::ARM.set(pc::reset_word(), 1));
    bench.clock(2);
    assert_eq!(bench.reg(ps::ADDR), ps::ARMED.mask());
    follows_the_period_latch(&bench);
    let t = bench.since_reset;
    let slots = bench.top.encoders().slots() as u64;
    let slot_at_raw = (bench.top.encoders().slot() as u64 + 2) % slots;
    bench.pins.probe_pin = true;
    bench.clock(10);
    // The event's clock as in the probe test above (the encoder bank's spec).
    let event = (t + 2 + (slots - slot_at_raw) % slots + 1) as u32;
    assert_eq!(bench.reg(ps::ADDR), ps::SEEN.mask() | ps::ACTIVE.mask());
    // Held while SEEN, however many period latches (every clock while stopped) pass.
    for _ in 0..3 {
        assert_eq!(get(&bench, lt::ADDR, lt::CLOCKS), event);
        assert_eq!(get(&bench, pt::ADDR, pt::CLOCKS), event);
        positions_shared(&bench);
        bench.clock(100);
    }
    assert!(bench.reg(ts::ADDR) > event + 300);

    // The next arm clears SEEN and the period latch takes the snapshot again.
    bus.write32(&mut bench, pc::ADDR, pc::ARM.set(pc::reset_word(), 1));
    bench.clock(2);
    assert_eq!(bench.reg(ps::ADDR), ps::ARMED.mask() | ps::ACTIVE.mask());
    follows_the_period_latch(&bench);
    positions_shared(&bench);
}
