//! `dda_axis`: the digital differential analyser of one axis.
//!
//! Specification: docs/spec/dda_axis.md
//!
//! The accumulator `acc` stays in `[0, M)` with `M = p_act * 65536`; each cycle it adds
//! the axis's increment and wraps, and a wrap is a step request `req` of +1 or -1 in the
//! next cycle. While stopped it is preset to `M / 2`, so the number of requests since
//! `run` rose is `floor(T / M + 1/2)` for the sum `T` of the increments applied.

/// State of one DDA.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DdaAxis {
    pub(crate) acc: i64,
    pub(crate) req: i8,
}

impl Default for DdaAxis {
    /// The reset state: `acc = 32768` (half of `M` for `P = 1`), no request.
    fn default() -> Self {
        DdaAxis { acc: HALF_STEP, req: 0 }
    }
}

/// Half a step in I16F16: the preset of the accumulator per clock of period.
pub(crate) const HALF_STEP: i64 = 1 << 15;
/// One step in I16F16.
pub(crate) const ONE_STEP: i64 = 1 << 16;

impl DdaAxis {
    /// The accumulator, in `[0, M)`.
    pub fn acc(&self) -> i64 {
        self.acc
    }

    /// The step request in this cycle: -1, 0 or +1.
    pub fn req(&self) -> i8 {
        self.req
    }

    /// One rising edge: `period` is `max(period_clocks, 1)` (used while stopped), `d`
    /// the axis's current raw increment and `m` the modulus `p_act * 65536`.
    #[inline]
    pub(crate) fn step(&mut self, run: bool, period: u32, d: i32, m: i64) {
        if !run {
            self.acc = i64::from(period) * HALF_STEP;
            self.req = 0;
            return;
        }
        let s = self.acc + i64::from(d);
        if s >= m {
            self.acc = s - m;
            self.req = 1;
        } else if s < 0 {
            self.acc = s + m;
            self.req = -1;
        } else {
            self.acc = s;
            self.req = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_half_up_and_wraps_both_ways() {
        let mut dda = DdaAxis::default();
        dda.step(false, 4, 0, 65536);
        let m = 4 * ONE_STEP;
        assert_eq!(dda.acc(), m / 2);
        // +1/2 step: exactly the rounding point gives a request.
        dda.step(true, 4, (m / 2) as i32, m);
        assert_eq!((dda.req(), dda.acc()), (1, 0));
        dda.step(true, 4, -1, m);
        assert_eq!((dda.req(), dda.acc()), (-1, m - 1));
        dda.step(true, 4, 0, m);
        assert_eq!((dda.req(), dda.acc()), (0, m - 1));
    }
}
