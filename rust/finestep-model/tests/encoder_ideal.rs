//! The encoder channels against the ideal position of the waveform driving them.
//!
//! A quadrature encoder at absolute position `p` (quarter cycles; phase `p mod 4` is
//! (A,B) = 00, 10, 11, 01, A leading B forward) has crossed, since position `p0`:
//! x4: `p - p0` edges; x2: the edges of A, at the half-integers `k + 1/2` with `k` even,
//! `floor((p + 1) / 2) - floor((p0 + 1) / 2)`; x1: the edges of A while B is low, at
//! `k + 1/2` with `k = 0 mod 4`, `floor((p + 3) / 4) - floor((p0 + 3) / 4)`. A step/dir
//! source has made the signed number of its step pulses. The rate claim of
//! docs/spec/input_filter.md: a channel of the shared decoder is sampled every
//! `T = S * (ENC_PRESCALE + 1)` clocks (`S = max(N_ENC, 2)` slots, no stalls here), and a
//! state that lasts at least `max(FILTER, 1) * T` clocks is seen in that many samples in
//! a row (the extra clock it quotes is for the asynchronous pins; the pins here change on
//! clock edges, and the waveforms vary the state lengths from that minimum). So:
//! - (a) such waveforms are counted exactly, edge for edge and in order, in every mode;
//! - (b) glitches of at most `max(FILTER, 1) - 1` samples, on A, B or both, change nothing;
//! - (c) A and B changing in the same clock is flagged and counted, and never moves the
//!   count; the legal moves around it still count exactly.
//!
//! Every cycle the count moves by at most one, only at a sampling visit of its channel,
//! and `edge_time` is the `TIMESTAMP` of the cycle whose decoding moved it.
//!
//! The bound is tight: one clock shorter, a step pulse is lost at some phase of the
//! schedule (exactly when it covers fewer than `max(FILTER, 1)` samples), and with
//! FILTER 0 or 1 quadrature states skip a sample and are flagged instead of counted.

use finestep_model::encoder_bank::{slots, ChannelConfig, EncoderBank, EncoderBankInputs, ProbeConfig, MAX_CHANNELS};
use finestep_model::quadrature_channel::CountMode;
use proptest::prelude::*;

/// Pin levels `(a, b)` at absolute quadrature position `p`.
fn levels(p: i64) -> (bool, bool) {
    [(false, false), (true, false), (true, true), (false, true)][p.rem_euclid(4) as usize]
}

/// The ideal count of a quadrature decoder at absolute position `p` (0 at `p = 0`).
fn ideal(mode: CountMode, p: i64) -> i64 {
    match mode {
        CountMode::X4 => p,
        CountMode::X2 => (p + 1).div_euclid(2),
        CountMode::X1 => (p + 3).div_euclid(4),
        CountMode::StepDir => unreachable!("step/dir has no quadrature position"),
    }
}

/// A stretch of constant pin levels.
#[derive(Clone, Copy, Debug)]
struct Segment {
    clocks: u64,
    a: bool,
    b: bool,
}

/// What a run of a waveform through one channel gave.
#[derive(Debug)]
struct Observed {
    /// The count after every cycle, consecutive repeats removed, as signed numbers.
    counts: Vec<i64>,
    illegal: bool,
    illegal_count: u16,
}

fn dedup(mut values: Vec<i64>) -> Vec<i64> {
    values.dedup();
    values
}

/// One case's settings: mode, `FILTER`, `ENC_PRESCALE`, `N_ENC` and the channel driven.
#[derive(Clone, Copy, Debug)]
struct Settings {
    mode: CountMode,
    filter: u8,
    prescale: u16,
    n_enc: usize,
    channel: usize,
}

impl Settings {
    /// `T = S * (PRESCALE + 1)`: clocks between two samples of a channel.
    fn period(&self) -> u64 {
        slots(self.n_enc) as u64 * (u64::from(self.prescale) + 1)
    }

    /// The shortest state that passes the filter: `max(FILTER, 1) * T` clocks.
    fn min_state(&self) -> u64 {
        u64::from(self.filter.max(1)) * self.period()
    }

    /// The channel's first sample is in cycle `S + channel` and sees the pins of cycle
    /// `S + channel - 2`: the pins before the first change.
    fn adopted_clocks(&self) -> u64 {
        (slots(self.n_enc) + self.channel - 1) as u64
    }
}

/// Runs `segments` on one channel of a fresh bank and checks the per-cycle rules.
fn run(segments: &[Segment], settings: Settings) -> Result<Observed, TestCaseError> {
    let Settings { mode, filter, prescale, n_enc, channel } = settings;
    let mut bank = EncoderBank::new(n_enc);
    let config = ChannelConfig { mode, z_active_high: true, filter, ..ChannelConfig::default() };
    let mut inputs = EncoderBankInputs {
        prescale,
        channels: [config; MAX_CHANNELS],
        probe: ProbeConfig { active_high: true, filter: 1, arm: false },
        ..EncoderBankInputs::default()
    };
    let mut counts = vec![0];
    let mut timestamp = 0u32;
    for segment in segments {
        inputs.enc_a = u8::from(segment.a) << channel;
        inputs.enc_b = u8::from(segment.b) << channel;
        for _ in 0..segment.clocks {
            let before = *bank.channel(channel);
            let sampling_visit = bank.visit(None) == Some(channel) && bank.sampling();
            inputs.timestamp = timestamp;
            bank.step(&inputs);
            let after = bank.channel(channel);
            let moved = after.count().wrapping_sub(before.count()) as i32;
            prop_assert!(moved.abs() <= 1, "the count moved by {} in cycle {}", moved, timestamp);
            prop_assert!(moved == 0 || sampling_visit, "counted outside a sampling visit in cycle {}", timestamp);
            if moved != 0 {
                prop_assert_eq!(after.edge_time(), timestamp, "edge_time of the cycle that counted");
            } else {
                prop_assert_eq!(after.edge_time(), before.edge_time(), "edge_time moved without a count");
            }
            counts.push(i64::from(after.count() as i32));
            timestamp += 1;
        }
    }
    for other in (0..n_enc).filter(|&c| c != channel) {
        prop_assert_eq!(bank.channel(other).count(), 0, "idle channel {} counted", other);
    }
    let ch = bank.channel(channel);
    Ok(Observed { counts: dedup(counts), illegal: ch.illegal(), illegal_count: ch.illegal_count() })
}

/// Settings of one case: every `N_ENC` (so `S` = 2 and 4, and the idle slot of
/// `N_ENC = 1`), every channel of it.
fn settings(modes: &'static [CountMode], filters: std::ops::RangeInclusive<u8>) -> impl Strategy<Value = Settings> {
    let prescales = prop_oneof![Just(0u16), 0..=5u16];
    (prop::sample::select(modes), filters, prescales, 1..=MAX_CHANNELS, any::<prop::sample::Index>()).prop_map(
        |(mode, filter, prescale, n_enc, channel)| Settings {
            mode,
            filter,
            prescale,
            n_enc,
            channel: channel.index(n_enc),
        },
    )
}

const QUADRATURE: &[CountMode] = &[CountMode::X4, CountMode::X2, CountMode::X1];

/// The first change of a pin must come after the pins the first sample adopts; long
/// enough at the end for the last state to be counted.
fn start_and_end(p0: i64, rest: u64, settings: &Settings) -> (Segment, Segment) {
    let (a, b) = levels(p0);
    let start = Segment { clocks: settings.adopted_clocks() + rest, a, b };
    (start, Segment { clocks: 2 * settings.min_state() + 8, a, b })
}

#[test]
fn clean_quadrature_counts_exactly_in_every_mode() {
    let mut runner = finestep_testkit::runner("clean_quadrature_counts_exactly_in_every_mode", 256);
    let moves = prop::collection::vec((any::<bool>(), 0..=3u64), 1..150);
    let case = (settings(QUADRATURE, 0..=15), 0..4i64, 0..20u64, moves);
    runner
        .run(&case, |(settings, p0, rest, moves)| {
            let (mode, min) = (settings.mode, settings.min_state());
            let (start, _) = start_and_end(p0, rest, &settings);
            let mut segments = vec![start];
            let mut p = p0;
            let mut expected = vec![0];
            for &(forward, extra) in &moves {
                p += if forward { 1 } else { -1 };
                let (a, b) = levels(p);
                segments.push(Segment { clocks: min + extra, a, b });
                expected.push(ideal(mode, p) - ideal(mode, p0));
            }
            segments.push(start_and_end(p, 0, &settings).1);
            let observed = run(&segments, settings)?;
            prop_assert_eq!(observed.counts, dedup(expected));
            prop_assert!(!observed.illegal && observed.illegal_count == 0);
            Ok(())
        })
        .unwrap();
}

#[test]
fn step_dir_counts_every_step_pulse() {
    let mut runner = finestep_testkit::runner("step_dir_counts_every_step_pulse", 128);
    let steps = prop::collection::vec((any::<bool>(), 0..=3u64, 0..=3u64, 0..=3u64), 1..100);
    let case = (settings(&[CountMode::StepDir], 0..=15), any::<bool>(), 0..20u64, steps);
    runner
        .run(&case, |(settings, dir0, rest, steps)| {
            let min = settings.min_state();
            let mut segments = vec![Segment { clocks: settings.adopted_clocks() + rest, a: false, b: dir0 }];
            let mut dir = dir0;
            let mut position = 0;
            let mut expected = vec![0];
            for &(up, setup, high, low) in &steps {
                if up != dir {
                    dir = up;
                    segments.push(Segment { clocks: min + setup, a: false, b: dir });
                }
                segments.push(Segment { clocks: min + high, a: true, b: dir });
                segments.push(Segment { clocks: min + low, a: false, b: dir });
                position += if up { 1 } else { -1 };
                expected.push(position);
            }
            segments.push(Segment { clocks: 2 * min + 8, a: false, b: dir });
            let observed = run(&segments, settings)?;
            prop_assert_eq!(observed.counts, expected);
            prop_assert!(!observed.illegal, "no illegal transitions in step/dir");
            Ok(())
        })
        .unwrap();
}

#[test]
fn glitches_shorter_than_the_filter_never_count() {
    let mut runner = finestep_testkit::runner("glitches_shorter_than_the_filter_never_count", 192);
    // Per move: direction, extra clocks, and glitches (which pins: 1 A, 2 B, 3 both;
    // length and gap as fractions of their ranges).
    let glitch = (1..=3u8, any::<prop::sample::Index>(), any::<prop::sample::Index>());
    let moves = prop::collection::vec(
        (prop_oneof![Just(0i64), Just(1), Just(-1)], 0..=3u64, prop::collection::vec(glitch, 0..4)),
        1..80,
    );
    let case = (settings(QUADRATURE, 2..=15), 0..4i64, 0..20u64, moves);
    runner
        .run(&case, |(settings, p0, rest, moves)| {
            let (mode, min) = (settings.mode, settings.min_state());
            let period = settings.period();
            // At most FILTER - 1 samples: any (FILTER - 1) * T clocks.
            let longest = u64::from(settings.filter - 1) * period;
            let (start, _) = start_and_end(p0, rest, &settings);
            let mut segments = vec![start];
            let mut p = p0;
            let mut expected = vec![0];
            for (step, extra, glitches) in &moves {
                p += step;
                let (a, b) = levels(p);
                segments.push(Segment { clocks: min + extra, a, b });
                for &(pins, length, gap) in glitches {
                    let clocks = 1 + length.index(longest as usize) as u64;
                    segments.push(Segment { clocks, a: a ^ (pins & 1 != 0), b: b ^ (pins & 2 != 0) });
                    // At least one clean sample before anything else happens.
                    segments.push(Segment { clocks: period + gap.index(period as usize) as u64, a, b });
                }
                expected.push(ideal(mode, p) - ideal(mode, p0));
            }
            segments.push(start_and_end(p, 0, &settings).1);
            let observed = run(&segments, settings)?;
            prop_assert_eq!(observed.counts, dedup(expected));
            prop_assert!(!observed.illegal, "a glitch of both pins reached the decoder");
            Ok(())
        })
        .unwrap();
}

#[test]
fn both_pins_changing_in_one_clock_is_illegal_and_never_counts() {
    let mut runner = finestep_testkit::runner("both_pins_changing_in_one_clock_is_illegal_and_never_counts", 192);
    // Moves of -1, +1 or 2 (both pins at once), with extra clocks.
    let moves = prop::collection::vec((prop_oneof![3 => Just(1i64), 3 => Just(-1), 1 => Just(2)], 0..=3u64), 1..120);
    let case = (settings(QUADRATURE, 0..=15), 0..4i64, 0..20u64, moves);
    runner
        .run(&case, |(settings, p0, rest, moves)| {
            let (mode, min) = (settings.mode, settings.min_state());
            let (start, _) = start_and_end(p0, rest, &settings);
            let mut segments = vec![start];
            let mut p = p0;
            let mut count = 0;
            let mut expected = vec![0];
            let mut jumps = 0u16;
            for &(step, extra) in &moves {
                let old = p;
                p += step;
                if step.abs() == 2 {
                    jumps += 1;
                } else {
                    count += ideal(mode, p) - ideal(mode, old);
                }
                let (a, b) = levels(p);
                segments.push(Segment { clocks: min + extra, a, b });
                expected.push(count);
            }
            segments.push(start_and_end(p, 0, &settings).1);
            let observed = run(&segments, settings)?;
            prop_assert_eq!(observed.counts, dedup(expected));
            prop_assert_eq!(observed.illegal_count, jumps);
            prop_assert_eq!(observed.illegal, jumps > 0);
            Ok(())
        })
        .unwrap();
}

/// The cycles in `[from, to)` whose pins a sampling visit of the settings' channel sees:
/// the visits are in cycles `S * (1 + k * (PRESCALE + 1)) + channel` and see the pins of
/// two cycles before (the synchroniser).
fn samples_of_pins(settings: &Settings, from: u64, to: u64) -> usize {
    let s = slots(settings.n_enc) as u64;
    (0..)
        .map(|k| s * (1 + k * (u64::from(settings.prescale) + 1)) + settings.channel as u64 - 2)
        .take_while(|&seen| seen < to)
        .filter(|&seen| seen >= from)
        .count()
}

#[test]
fn a_step_pulse_counts_exactly_when_it_covers_filter_steps() {
    let mut cases = 0;
    for n_enc in 1..=MAX_CHANNELS {
        for channel in 0..n_enc {
            for prescale in 0..=2u16 {
                for filter in 0..=4u8 {
                    let settings = Settings { mode: CountMode::StepDir, filter, prescale, n_enc, channel };
                    let (min, period) = (settings.min_state(), settings.period());
                    let mut lost_one_short = 0;
                    for clocks in [min - 1, min] {
                        for offset in 0..period {
                            // Settled at A = 0, B = 1 (up); then A high for `clocks`.
                            let start = settings.adopted_clocks() + 2 * min + offset;
                            let segments = [
                                Segment { clocks: start, a: false, b: true },
                                Segment { clocks, a: true, b: true },
                                Segment { clocks: 2 * min + 8, a: false, b: true },
                            ];
                            let observed = run(&segments, settings).unwrap();
                            let covered = samples_of_pins(&settings, start, start + clocks);
                            let counted = covered >= usize::from(filter.max(1));
                            let expected = if counted { vec![0, 1] } else { vec![0] };
                            assert_eq!(observed.counts, expected, "{settings:?}, {clocks} clocks at {start}");
                            lost_one_short += usize::from(!counted && clocks < min);
                            assert!(counted || clocks < min, "{settings:?}: a pulse of the rated length lost");
                            cases += 1;
                        }
                    }
                    assert!(lost_one_short > 0, "{settings:?}: one clock short of the bound never lost");
                }
            }
        }
    }
    // Every channel of every N_ENC (10), 3 prescales, 5 filters, 2 lengths, T offsets.
    assert!(cases > 10 * 3 * 5 * 2 * 2, "{cases} cases");
}

#[test]
fn quadrature_one_clock_short_of_the_bound_is_not_counted_exactly() {
    // FILTER 0 and 1 (one sample a state): a state of `T - 1` clocks is missed by some
    // sample, A and B then change at one sample: flagged, not counted.
    for n_enc in 1..=MAX_CHANNELS {
        for channel in 0..n_enc {
            for prescale in 0..=2u16 {
                for filter in [0u8, 1] {
                    for mode in QUADRATURE.iter().copied() {
                        let settings = Settings { mode, filter, prescale, n_enc, channel };
                        let short = settings.min_state() - 1;
                        let (start, _) = start_and_end(0, 0, &settings);
                        let mut segments = vec![start];
                        let states = 4 * settings.period() as i64 + 4;
                        for p in 1..=states {
                            let (a, b) = levels(p);
                            segments.push(Segment { clocks: short, a, b });
                        }
                        segments.push(start_and_end(states, 0, &settings).1);
                        let observed = run(&segments, settings).unwrap();
                        let exact = dedup((0..=states).map(|p| ideal(mode, p)).collect());
                        assert!(observed.illegal, "{settings:?}: no state skipped");
                        assert_ne!(observed.counts, exact, "{settings:?}");
                    }
                }
            }
        }
    }
}
