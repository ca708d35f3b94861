//! `step_serial`: the digit-serial step engine (the CPLD's), one DDA and one step shaper
//! visiting the axes, each visit a word's length of clocks.
//!
//! Specification: docs/spec/step_serial.md
//!
//! `S = 2^SL` slots (`SL` 1 for up to 2 axes, 2 for up to 4, 3 for up to 8) of
//! `Q = 32 / DIGIT` clocks each make a round of `R = S * Q` clocks; `phase` (reset 0)
//! counts every clock modulo `R`, `slot = phase / Q`, `j = phase mod Q`. Slot `a` is the
//! DDA visit of axis `a`, slot `a + 1 (mod S)` its shaper visit. A visit acts once:
//! - the DDA visit at its first clock (`run`, `live`, `inc` and `p_active` of that
//!   clock; the environment keeps `inc` and `p_active` constant over a visit) with
//!   `V = p_active / R` and `M = V * 65536`: `s = (live ? acc : M/2) + d`, wrapped into
//!   `[0, M)`, a request of +1 / -1 on a wrap; the request is the shaper's from the next
//!   slot on, unless the run falls before the visit's last clock (then none). `live[a]` clears in every clock with `run = 0`; a visit whose first clock
//!   runs sets it at its end when `run` has stayed 1 throughout.
//! - the shaper visit at its first clock: `step_shaper`'s rule with the counters
//!   counting visits and every compare `cnt >= X` read as `cnt * R >= X`, made with the
//!   timings of the visit that left the counter (the environment keeps an axis's
//!   timings constant over its shaper visit; a change counts from the visit after the
//!   one it falls in); the pins of
//!   the axis take the state it leaves at the end of that clock; the new position
//!   leaves on `pos_digit`, digit `j` one clock after the visit's clock `j`.
//!
//! This model holds each axis's words as numbers (no rings, no digits but the output
//! stream): it states what a visit computes, not how the digits flow.

/// Build parameters of the engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SerialParams {
    /// Axes, 1..=8.
    pub n_axes: usize,
    /// Width of `p_active`.
    pub p_width: u32,
    /// Width of the drive timings (and the counters).
    pub timing_w: u32,
    /// Bits a clock: 1, 2, 4 or 8.
    pub digit: u32,
}

impl Default for SerialParams {
    fn default() -> Self {
        SerialParams { n_axes: 4, p_width: 20, timing_w: 12, digit: 4 }
    }
}

impl SerialParams {
    /// `SL`.
    pub fn slots_log2(&self) -> u32 {
        match self.n_axes {
            0..=2 => 1,
            3..=4 => 2,
            _ => 3,
        }
    }
    /// `S`.
    pub fn slots(&self) -> u32 {
        1 << self.slots_log2()
    }
    /// `Q = 32 / DIGIT`: the clocks of a visit.
    pub fn visit_clocks(&self) -> u32 {
        32 / self.digit
    }
    /// `log2 R`.
    pub fn round_log2(&self) -> u32 {
        self.slots_log2() + self.visit_clocks().trailing_zeros()
    }
    /// `R = S * Q`: the clocks between two visits of an axis, the step-edge quantum.
    pub fn round(&self) -> u32 {
        1 << self.round_log2()
    }
    /// The largest visit count of a period the engine takes (`V < 2^15`, and what
    /// `p_active` can hold).
    pub fn max_visits(&self) -> u32 {
        let by_width = ((1u64 << self.p_width) - 1) >> self.round_log2();
        by_width.min((1 << 15) - 1) as u32
    }
    /// The fastest step train the shaper makes with these drive timings, in clocks per
    /// step: a high of `R * ceil(max(L, 1) / R)` and a low of `R * ceil(max(Sp, 1) / R)`.
    pub fn min_step_clocks(&self, step_len: u32, step_space: u32) -> u64 {
        let r = u64::from(self.round());
        let up = |x: u32| u64::from(x.max(1)).div_ceil(r) * r;
        up(step_len) + up(step_space)
    }
}

/// One clock's inputs (per-axis arrays: entries at and beyond `n_axes` are ignored).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SerialInputs {
    /// The DDAs' run (`run && active` of the period timer).
    pub run: bool,
    /// The running period in clocks, a multiple of `R`.
    pub p_active: u32,
    /// Q16.16 steps per period.
    pub inc: [i32; 8],
    /// Bit `a`: axis `a`'s drive enable.
    pub axis_enable: u8,
    /// Drive timings in clocks.
    pub step_len: [u16; 8],
    /// Low time between pulses.
    pub step_space: [u16; 8],
    /// Direction setup before a rise.
    pub dir_setup: [u16; 8],
    /// Direction hold after a fall.
    pub dir_hold: [u16; 8],
    /// Output modes (0/3 step/dir, 1 up/down, 2 quadrature).
    pub out_mode: [u8; 8],
    /// Pin inversions (bit 0 A, 1 B, 2 enable).
    pub invert: [u8; 8],
    /// Clears the sticky flags.
    pub clear_errors: bool,
    /// The safety monitor's halt.
    pub halt: bool,
}

/// The outputs in a cycle (bit `a` of each mask is axis `a`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SerialOutputs {
    /// `phase == R - 2`: a run may start.
    pub start_ok: bool,
    /// Step pins A.
    pub pin_a: u8,
    /// Step pins B.
    pub pin_b: u8,
    /// Enable pins.
    pub pin_en: u8,
    /// Sticky: pulses fell behind the DDA.
    pub rate_error: u8,
    /// Sticky: a pending count overflowed.
    pub step_lost: u8,
    /// A digit of a position.
    pub pos_digit: u8,
    /// Which digit.
    pub pos_index: u8,
    /// Whose.
    pub pos_axis: u8,
}

/// One axis's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Axis {
    acc: u64,
    live: bool,
    /// The request of the axis's last DDA visit: -1, 0, +1.
    req: i32,
    pending: i32,
    level: bool,
    dir: bool,
    cnt: u32,
    dcnt: u32,
    quad: u32,
    position: u32,
    /// The compares the axis's last shaper visit made of the counters it left, against
    /// the timings of that visit: `cnt * R >= L`, `>= Sp`, `>= H`, `dcnt * R >= U`.
    len_ok: bool,
    space_ok: bool,
    hold_ok: bool,
    setup_ok: bool,
}

/// The engine.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StepSerial {
    params: SerialParams,
    phase: u32,
    axes: Vec<Axis>,
    /// `run` stayed 1 since the first clock of the current DDA visit.
    dda_running: bool,
    out: SerialOutputs,
    /// The position the current shaper visit left, streamed a digit a clock.
    streamed: u32,
}

impl StepSerial {
    /// An engine out of reset.
    pub fn new(params: SerialParams) -> Self {
        assert!((1..=8).contains(&params.n_axes), "1 to 8 axes");
        assert!(matches!(params.digit, 1 | 2 | 4 | 8), "DIGIT 1, 2, 4 or 8");
        let mut engine = StepSerial {
            params,
            phase: 0,
            axes: Vec::new(),
            dda_running: false,
            out: SerialOutputs::default(),
            streamed: 0,
        };
        engine.reset();
        engine
    }

    /// The synchronous reset.
    pub fn reset(&mut self) {
        let max = self.counter_max();
        let axis = Axis {
            acc: 0,
            live: false,
            req: 0,
            pending: 0,
            level: false,
            dir: true,
            cnt: max,
            dcnt: max,
            quad: 0,
            position: 0,
            len_ok: true,
            space_ok: true,
            hold_ok: true,
            setup_ok: true,
        };
        self.axes = vec![axis; self.params.n_axes];
        self.phase = 0;
        self.dda_running = false;
        self.streamed = 0;
        self.out = SerialOutputs::default();
        self.out.start_ok = self.start_ok();
    }

    /// The parameters.
    pub fn params(&self) -> SerialParams {
        self.params
    }

    fn counter_max(&self) -> u32 {
        (1 << self.params.timing_w) - 1
    }

    fn start_ok(&self) -> bool {
        self.phase == self.params.round() - 2
    }

    /// The outputs in the current cycle.
    pub fn outputs(&self) -> SerialOutputs {
        self.out
    }

    /// Axis `a`'s position (its step count, as the stream carries it).
    pub fn position(&self, a: usize) -> u32 {
        self.axes[a].position
    }

    /// The clock in the round, `0..R`.
    pub fn phase(&self) -> u32 {
        self.phase
    }

    /// One clock.
    pub fn step(&mut self, inp: &SerialInputs) {
        let p = self.params;
        let q = p.visit_clocks();
        let s = p.slots();
        let r = p.round();
        let slot = self.phase / q;
        let j = self.phase % q;
        let first = j == 0;
        let last = j == q - 1;
        let sh_axis = (slot + s - 1) % s;
        let n = p.n_axes as u32;
        let mut next = self.out;
        let mut set_rate = 0u8;
        let mut set_lost = 0u8;

        // ---- DDA visit of axis `slot` ----
        if slot < n {
            let ax = &mut self.axes[slot as usize];
            if first {
                self.dda_running = inp.run;
                if inp.run {
                    let v = u64::from(inp.p_active >> p.round_log2());
                    let m = (v << 16) as i64;
                    let b = if ax.live { ax.acc as i64 } else { m / 2 };
                    let sum = b + i64::from(inp.inc[slot as usize]);
                    let (acc, req) = if sum >= m {
                        (sum - m, 1)
                    } else if sum < 0 {
                        (sum + m, -1)
                    } else {
                        (sum, 0)
                    };
                    assert!((0..m).contains(&acc), "|d| < M (the record check)");
                    ax.acc = acc as u64;
                    ax.req = req;
                } else {
                    ax.req = 0;
                }
            }
            self.dda_running &= inp.run;
            if last {
                ax.live = self.dda_running;
                // A visit during which the run falls makes no request.
                if !self.dda_running {
                    ax.req = 0;
                }
            }
        }
        if !inp.run {
            for ax in &mut self.axes {
                ax.live = false;
            }
        }

        // ---- Shaper visit of axis `slot - 1` ----
        if sh_axis < n {
            let a = sh_axis as usize;
            if first {
                let max = self.counter_max();
                let rr = u64::from(r);
                let reached = |cnt: u32, x: u16| u64::from(cnt) * rr >= u64::from(x);
                let (len, space, setup, hold) = (inp.step_len[a], inp.step_space[a], inp.dir_setup[a], inp.dir_hold[a]);
                let ax = &mut self.axes[a];
                let e = ax.pending + ax.req;
                let mut rise = false;
                let mut fall = false;
                let mut turn = false;
                if ax.level {
                    fall = ax.len_ok;
                } else if e != 0 && !inp.halt {
                    if (e > 0) == ax.dir {
                        rise = ax.space_ok && ax.setup_ok;
                    } else {
                        turn = ax.hold_ok;
                    }
                }
                let issued = if rise {
                    if ax.dir {
                        1
                    } else {
                        -1
                    }
                } else {
                    0
                };
                if inp.halt {
                    ax.pending = 0;
                } else {
                    if e.abs() >= 2 {
                        set_rate |= 1 << a;
                    }
                    let left = e - issued;
                    if left.abs() > 127 {
                        set_lost |= 1 << a;
                    }
                    ax.pending = left.clamp(-127, 127);
                }
                if rise {
                    ax.position = ax.position.wrapping_add(issued as u32);
                    ax.quad = (ax.quad as i32 + issued).rem_euclid(4) as u32;
                    ax.level = true;
                }
                if fall {
                    ax.level = false;
                }
                ax.cnt = if rise || fall { 1 } else { (ax.cnt + 1).min(max) };
                if turn {
                    ax.dir = !ax.dir;
                }
                ax.dcnt = if turn { 1 } else { (ax.dcnt + 1).min(max) };
                ax.len_ok = reached(ax.cnt, len);
                ax.space_ok = reached(ax.cnt, space);
                ax.hold_ok = reached(ax.cnt, hold);
                ax.setup_ok = reached(ax.dcnt, setup);
                let (pa, pb) = match inp.out_mode[a] & 3 {
                    1 => (ax.level && ax.dir, ax.level && !ax.dir),
                    2 => (matches!(ax.quad, 1 | 2), ax.quad >= 2),
                    _ => (ax.level, ax.dir),
                };
                let inv = inp.invert[a];
                let set = |mask: u8, bit: bool| (mask & !(1 << a)) | (u8::from(bit) << a);
                next.pin_a = set(next.pin_a, pa ^ (inv & 1 != 0));
                next.pin_b = set(next.pin_b, pb ^ (inv & 2 != 0));
                self.streamed = ax.position;
            }
            next.pos_digit = ((u64::from(self.streamed) >> (j * p.digit)) & ((1 << p.digit) - 1)) as u8;
        } else {
            next.pos_digit = 0;
        }
        next.pos_index = j as u8;
        next.pos_axis = sh_axis as u8;

        // ---- Every clock: enables; sticky flags cleared (a set at a visit wins) ----
        if inp.clear_errors {
            next.rate_error = set_rate;
            next.step_lost = set_lost;
        } else {
            next.rate_error |= set_rate;
            next.step_lost |= set_lost;
        }
        let mut en = 0u8;
        for a in 0..p.n_axes {
            let on = inp.axis_enable & (1 << a) != 0 && !inp.halt;
            en |= u8::from(on ^ (inp.invert[a] & 4 != 0)) << a;
        }
        next.pin_en = en;

        self.phase = (self.phase + 1) % r;
        next.start_ok = self.start_ok();
        self.out = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of whole periods with these per-period increments (Q16.16, every axis the
    /// same list shifted), stopped after; returns the engine and pin A's levels.
    fn run(p: SerialParams, visits: u32, len: u16, space: u16, incs: &[i32]) -> (StepSerial, Vec<u8>) {
        let mut e = StepSerial::new(p);
        let r = p.round();
        let mut inp = SerialInputs { p_active: visits * r, axis_enable: 0xff, ..SerialInputs::default() };
        for a in 0..8 {
            inp.step_len[a] = len;
            inp.step_space[a] = space;
            inp.dir_setup[a] = 1;
            inp.dir_hold[a] = 1;
        }
        let mut pins = Vec::new();
        // Idle to the round start (phase 0), then periods back to back.
        while e.phase() != 0 {
            e.step(&inp);
            pins.push(e.outputs().pin_a);
        }
        for (k, _) in incs.iter().enumerate() {
            inp.run = true;
            for a in 0..p.n_axes {
                inp.inc[a] = incs[(k + a) % incs.len()];
            }
            for _ in 0..visits * r {
                e.step(&inp);
                pins.push(e.outputs().pin_a);
            }
        }
        inp.run = false;
        for _ in 0..(300 * r) {
            e.step(&inp);
            pins.push(e.outputs().pin_a);
        }
        (e, pins)
    }

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        *seed >> 33
    }

    #[test]
    fn exact_position_after_every_run_rounding_half_up() {
        let mut seed = 7u64;
        for digit in [1, 2, 4, 8] {
            for n_axes in [1, 2, 3, 4, 5] {
                let p_width = if digit == 8 && n_axes > 4 { 18 } else { 20 };
                let p = SerialParams { n_axes, p_width, timing_w: 12, digit };
                for _ in 0..4 {
                    let visits = 2 + (lcg(&mut seed) % 30) as u32;
                    // At most half a step per visit (a pulse takes two): late steps still all go out.
                    let max = i64::from(visits) * 65536 / 2;
                    let incs: Vec<i32> = (0..5).map(|_| ((lcg(&mut seed) as i64 % (2 * max)) - max) as i32).collect();
                    let (e, _) = run(p, visits, 1, 1, &incs);
                    assert_eq!(e.outputs().step_lost, 0);
                    for a in 0..n_axes {
                        let total: i64 = (0..incs.len()).map(|k| i64::from(incs[(k + a) % incs.len()])).sum();
                        // floor(total / 65536 + 1/2)
                        let ideal = (total + 32768).div_euclid(65536);
                        assert_eq!(e.position(a) as i32 as i64, ideal, "{p:?} axis {a} incs {incs:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn pulses_meet_the_drive_timing_rounded_up_to_rounds() {
        let p = SerialParams::default();
        let r = p.round() as usize;
        for (len, space) in [(0u16, 0u16), (1, 1), (31, 33), (32, 32), (33, 70), (100, 5)] {
            // Fast enough that the shaper runs at its limit.
            let visits = 40;
            let incs = [visits as i32 * 65536 - 1];
            let (e, pins) = run(p, visits, len, space, &incs);
            let high = r * usize::from(len.max(1)).div_ceil(r);
            let low = r * usize::from(space.max(1)).div_ceil(r);
            let edges: Vec<usize> = (1..pins.len()).filter(|&t| (pins[t] ^ pins[t - 1]) & 1 != 0).collect();
            assert!(edges.len() > 10);
            // Every edge one round apart from the first's placement.
            for w in edges.windows(2) {
                assert_eq!((w[1] - w[0]) % r, 0, "placement quantum");
            }
            for (i, w) in edges.windows(2).enumerate() {
                let rising = pins[w[0]] & 1 == 1;
                if rising {
                    assert_eq!(w[1] - w[0], high, "high time, len {len}");
                } else {
                    assert!(w[1] - w[0] >= low, "low time {} < {low}, edge {i}", w[1] - w[0]);
                }
            }
            // No step lost: the position counted every rise, and they are the DDA's.
            let rises = edges.iter().filter(|&&t| pins[t] & 1 == 1).count();
            assert_eq!(e.position(0) as usize, rises);
            assert_eq!(e.outputs().step_lost, 0);
        }
    }
}
