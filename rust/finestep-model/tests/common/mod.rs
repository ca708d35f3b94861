//! Shared test helpers: a stream driver and an independent ideal model.
//!
//! The ideal knows only the spec's schedule (record `k` applied in cycles
//! `b0 + kP + 1 ..= b0 + (k+1)P`) and the increments; it computes the exact commanded
//! position `X(n) = T(n) / M` with integer (i128) or `BigRational` arithmetic.

#![allow(dead_code)]

use finestep_interface::pin_timing::StepDirMonitor;
use finestep_model::{AxisConfig, Core, CoreInputs, CoreOutputs, CoreParams, DriveTiming, PeriodRecord, MAX_AXES};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};

/// The first boundary: `run` is 0 in cycle 0 (samples `P`) and 1 from cycle 1 on, so
/// `active` rises in cycle 2, which is a boundary.
pub const FIRST_BOUNDARY: u64 = 2;

/// Exact commanded position of one axis from its increments alone.
#[derive(Clone, Debug)]
pub struct Ideal {
    pub p: u64,
    /// Raw increments per period.
    pub d: Vec<i64>,
    /// `prefix[k]`: `T` after `k` whole periods (raw steps * P).
    prefix: Vec<i128>,
}

impl Ideal {
    pub fn new(p: u32, d: Vec<i64>) -> Self {
        let p = u64::from(p.max(1));
        let mut prefix = vec![0i128];
        for &x in &d {
            prefix.push(prefix.last().unwrap() + i128::from(x) * i128::from(p));
        }
        Ideal { p, d, prefix }
    }

    /// `M = P * 65536`.
    pub fn m(&self) -> i128 {
        i128::from(self.p) << 16
    }

    /// `T(n)`: the sum of the increments the DDA adds in cycles `0..=n`.
    pub fn t(&self, n: u64) -> i128 {
        if n <= FIRST_BOUNDARY {
            return 0;
        }
        let since = n - FIRST_BOUNDARY - 1;
        let k = (since / self.p) as usize;
        if k >= self.d.len() {
            return *self.prefix.last().unwrap();
        }
        let within = since % self.p + 1;
        self.prefix[k] + i128::from(self.d[k]) * i128::from(within)
    }

    /// `R(n) = floor(T(n) / M + 1/2)`: the whole steps requested after cycle `n`.
    pub fn requested(&self, n: u64) -> i64 {
        let m = self.m();
        (self.t(n) + m / 2).div_euclid(m) as i64
    }

    /// `floor(sum D + 1/2)` by exact rational arithmetic.
    pub fn final_steps(&self) -> i64 {
        let mut sum = BigRational::zero();
        let step = BigInt::from(65536);
        for &x in &self.d {
            sum += BigRational::new(BigInt::from(x), step.clone());
        }
        let half = BigRational::new(BigInt::one(), BigInt::from(2));
        let rounded = (sum + half).floor().to_integer();
        i64::try_from(rounded).expect("fits")
    }
}

/// Everything seen while driving one stream of records through a core.
pub struct Run {
    pub params: CoreParams,
    pub axes: [AxisConfig; MAX_AXES],
    pub p: u32,
    pub records: Vec<PeriodRecord>,
    /// Outputs in cycles `0..outputs.len()`.
    pub outputs: Vec<CoreOutputs>,
}

impl Run {
    /// Drives `records` back to back (each offered until consumed) from reset with the
    /// per-clock [`Core::step`], then `drain` more cycles with no record, and checks
    /// the records were consumed at `FIRST_BOUNDARY + k * P`.
    pub fn drive(
        params: CoreParams,
        axes: [AxisConfig; MAX_AXES],
        p: u32,
        records: Vec<PeriodRecord>,
        drain: u64,
    ) -> Run {
        let mut core = Core::new(params);
        let mut inputs = CoreInputs { run: false, period_clocks: p, axes, ..CoreInputs::default() };
        let p_eff = u64::from(params.effective_period(p));
        let end = FIRST_BOUNDARY + records.len() as u64 * p_eff + drain;
        let mut outputs = Vec::with_capacity(end as usize + 1);
        outputs.push(core.outputs());
        let mut next = 0;
        while core.cycle() < end {
            if core.cycle() >= 1 {
                inputs.run = true;
            }
            inputs.rec_valid = next < records.len();
            if inputs.rec_valid {
                inputs.record = records[next];
            }
            if core.outputs().rec_ready() && inputs.rec_valid {
                assert_eq!(core.cycle(), FIRST_BOUNDARY + next as u64 * p_eff, "record {next} consumed off schedule");
                next += 1;
            }
            core.step(&inputs);
            outputs.push(core.outputs());
        }
        assert_eq!(next, records.len(), "every record consumed");
        Run { params, axes, p, records, outputs }
    }

    pub fn ideal(&self, axis: usize) -> Ideal {
        let d = self.records.iter().map(|r| i64::from(r.inc[axis].to_bits())).collect();
        Ideal::new(self.params.effective_period(self.p), d)
    }

    pub fn position(&self, n: usize, axis: usize) -> i64 {
        i64::from(self.outputs[n].position(axis))
    }

    pub fn final_position(&self, axis: usize) -> i64 {
        self.position(self.outputs.len() - 1, axis)
    }

    /// Property (b): `|position(n+2) - X(n)| <= 1` in every cycle; the first failure.
    pub fn first_lag_violation(&self, axis: usize) -> Option<String> {
        let ideal = self.ideal(axis);
        let m = ideal.m();
        for n in 0..self.outputs.len().saturating_sub(2) {
            let pos = i128::from(self.position(n + 2, axis));
            let t = ideal.t(n as u64);
            if (pos * m - t).abs() > m {
                return Some(format!(
                    "axis {axis}: cycle {n}: X = {:.4} but position(n+2) = {pos}",
                    t as f64 / m as f64
                ));
            }
        }
        None
    }

    /// Steps are only ever made towards the requested count: a rise shown at `n+2`
    /// never passes `R(n)`. The first failure.
    pub fn first_overshoot(&self, axis: usize) -> Option<String> {
        let ideal = self.ideal(axis);
        for n in 0..self.outputs.len().saturating_sub(2) {
            let before = self.position(n + 1, axis);
            let after = self.position(n + 2, axis);
            let r = ideal.requested(n as u64);
            let ok = match after - before {
                0 => true,
                1 => after <= r,
                -1 => after >= r,
                _ => false,
            };
            if !ok {
                return Some(format!("axis {axis}: cycle {}: position {before} -> {after} with R = {r}", n + 2));
            }
        }
        None
    }

    /// Pins of `axis` with the inversions undone: (A, B) per cycle. Cycle 0 (pins reset
    /// to 0 whatever the inversion) shows cycle 1's values.
    pub fn pins(&self, axis: usize) -> Vec<(bool, bool)> {
        let inv = self.axes[axis].invert;
        let mut pins: Vec<(bool, bool)> =
            self.outputs.iter().map(|o| (o.pin_a(axis) ^ (inv & 1 != 0), o.pin_b(axis) ^ (inv & 2 != 0))).collect();
        if pins.len() > 1 {
            pins[0] = pins[1];
        }
        pins
    }

    /// Position counted from the pins in the axis's mode, per cycle (one cycle behind
    /// `position`: the pins are registered from the state).
    pub fn decoded_positions(&self, axis: usize) -> Vec<i64> {
        let mode = self.axes[axis].mode & 3;
        let pins = self.pins(axis);
        let mut pos = 0i64;
        let mut out = vec![0];
        for w in pins.windows(2) {
            pos += pin_step(mode, w[0], w[1]).unwrap_or_else(|| panic!("axis {axis}: quadrature skipped a phase"));
            out.push(pos);
        }
        out
    }
}

/// One cycle of the steps the pins A, B show in output mode `mode` (0/3 step/dir, 1
/// up/down, 2 quadrature), from `(a0, b0)` to `(a1, b1)`: -1, 0 or +1; `None` when a
/// quadrature output skips a phase.
pub fn pin_step(mode: u8, (a0, b0): (bool, bool), (a1, b1): (bool, bool)) -> Option<i64> {
    match mode {
        1 => Some(i64::from(a1 && !a0) - i64::from(b1 && !b0)),
        2 => {
            let phase = |a: bool, b: bool| match (a, b) {
                (false, false) => 0i32,
                (true, false) => 1,
                (true, true) => 2,
                (false, true) => 3,
            };
            match (phase(a1, b1) - phase(a0, b0)).rem_euclid(4) {
                0 => Some(0),
                1 => Some(1),
                3 => Some(-1),
                _ => None,
            }
        }
        _ => Some(if a1 && !a0 {
            if b1 {
                1
            } else {
                -1
            }
        } else {
            0
        }),
    }
}

impl Run {
    /// The position decoded from the pins is `position` one cycle later; the first
    /// cycle where it is not.
    pub fn first_pin_mismatch(&self, axis: usize) -> Option<String> {
        let decoded = self.decoded_positions(axis);
        (1..decoded.len()).find_map(|n| {
            let want = self.position(n - 1, axis);
            (decoded[n] != want)
                .then(|| format!("axis {axis}: cycle {n}: pins say {} but position(n-1) = {want}", decoded[n]))
        })
    }
}

/// The shaper's timing guarantees read from step/dir pins (A step, B dir), for timing
/// `t`, by the one pin-timing check ([`StepDirMonitor`]), and each pulse high for exactly
/// `L`. Returns the first violation.
pub fn first_timing_violation(pins: &[(bool, bool)], t: &DriveTiming) -> Option<String> {
    let f = StepDirMonitor::measure(pins, 0, *t);
    if let Some(v) = f.first {
        return Some(v.to_string());
    }
    let l = u64::from(t.step_len.max(1));
    f.high_max.filter(|&high| high != l).map(|high| format!("a pulse high for {high} cycles, L = {l} exactly"))
}
