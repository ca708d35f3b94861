//! `motion_control`: the gate between the position FIFO and the period timer.
//!
//! Specification: docs/spec/motion_control.md
//!
//! Motion starts only once `START_LEVEL` records are queued (a rotary-buffer
//! threshold); an empty FIFO after a record with `BLOCK_END` is a normal stop, after
//! which the gate waits for the threshold again; an empty FIFO in the middle of a block
//! is an underrun: every axis holds from that boundary on, the sticky `UNDERRUN` sets,
//! one underrun is counted, and the gate stays shut until `clear_errors`.

use crate::record::flags::BLOCK_END;
use crate::record::PeriodRecord;

/// What motion control sees in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MotionInputs<'a> {
    /// `core_run = CONTROL.RUN && !halt`.
    pub core_run: bool,
    /// The core's `rec_ready`.
    pub rec_ready: bool,
    /// The FIFO head (`rd_data` while `rd_valid`), `None` when empty.
    pub head: Option<&'a PeriodRecord>,
    /// The FIFO's committed records (`level`).
    pub level: usize,
    /// `START_LEVEL` (0 acts as 1).
    pub start_level: u32,
    /// `clear_errors`: clears `UNDERRUN` (an underrun in the same cycle wins).
    pub clear_errors: bool,
    /// The interlock holds a shut gate shut (`logic_outputs`'s `inhibit`).
    pub inhibit: bool,
}

/// State of motion control.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MotionControl {
    gate: bool,
    at_rest: bool,
    underrun: bool,
}

impl Default for MotionControl {
    /// The reset state: gate shut, at rest, no underrun.
    fn default() -> Self {
        MotionControl { gate: false, at_rest: true, underrun: false }
    }
}

impl MotionControl {
    /// The gate is open: records flow to the core (`STATUS.STREAMING`).
    pub fn gate(&self) -> bool {
        self.gate
    }

    /// The last record consumed ended a block (or none was consumed since the run
    /// started): an empty FIFO now is a normal stop.
    pub fn at_rest(&self) -> bool {
        self.at_rest
    }

    /// Sticky: the FIFO ran dry in the middle of a block.
    pub fn underrun(&self) -> bool {
        self.underrun
    }

    /// The core's `rec_valid`: the gate is open and the FIFO has a record.
    pub fn rec_valid(&self, inp: &MotionInputs<'_>) -> bool {
        self.gate && inp.head.is_some()
    }

    /// The FIFO's `rd_pop`: the core takes the head at this edge.
    pub fn pop(&self, inp: &MotionInputs<'_>) -> bool {
        inp.rec_ready && self.rec_valid(inp)
    }

    /// `start_blocked`: in this cycle the gate would open (running, shut, no underrun,
    /// the threshold reached) but the inhibit holds it.
    pub fn start_blocked(&self, inp: &MotionInputs<'_>) -> bool {
        inp.inhibit
            && inp.core_run
            && !self.gate
            && !self.underrun
            && inp.level as u64 >= u64::from(inp.start_level.max(1))
    }

    /// One rising clock edge. Returns whether an underrun is counted in this cycle.
    pub fn step(&mut self, inp: &MotionInputs<'_>) -> bool {
        let boundary = inp.core_run && inp.rec_ready;
        let start = inp.start_level.max(1);
        let mut underrun_now = false;
        if !inp.core_run {
            self.gate = false;
            self.at_rest = true;
        } else if boundary && self.gate && inp.head.is_none() {
            self.gate = false;
            underrun_now = !self.at_rest;
        } else if let (true, true, Some(record)) = (boundary, self.gate, inp.head) {
            self.at_rest = record.flags & BLOCK_END != 0;
        } else if !self.gate && !self.underrun && !inp.inhibit && inp.level as u64 >= u64::from(start) {
            self.gate = true;
        }
        self.underrun = underrun_now || (self.underrun && !inp.clear_errors);
        underrun_now
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opens_at_the_threshold_and_underruns_only_mid_block() {
        let mid = PeriodRecord::from_raw(&[1], 0);
        let last = PeriodRecord::from_raw(&[1], BLOCK_END);
        let mut mc = MotionControl::default();
        let mut inp = MotionInputs { core_run: true, level: 1, start_level: 2, head: Some(&mid), ..Default::default() };
        mc.step(&inp);
        assert!(!mc.gate(), "one record queued, threshold 2");
        inp.level = 2;
        mc.step(&inp);
        assert!(mc.gate());
        inp.rec_ready = true;
        assert!(mc.pop(&inp));
        mc.step(&inp);
        assert!(!mc.at_rest());
        inp.head = None;
        inp.level = 0;
        assert!(mc.step(&inp), "dry mid-block: an underrun");
        assert!(mc.underrun() && !mc.gate());
        inp.level = 5;
        inp.head = Some(&last);
        inp.rec_ready = false;
        mc.step(&inp);
        assert!(!mc.gate(), "shut until the underrun is cleared");
        inp.clear_errors = true;
        mc.step(&inp);
        inp.clear_errors = false;
        mc.step(&inp);
        assert!(mc.gate());
        inp.rec_ready = true;
        mc.step(&inp);
        assert!(mc.at_rest());
        inp.head = None;
        assert!(!mc.step(&inp), "dry after BLOCK_END: a normal stop");
        assert!(!mc.underrun() && !mc.gate());
    }
}
