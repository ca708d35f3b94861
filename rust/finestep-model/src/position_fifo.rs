//! `position_fifo`: the buffer of period records between the host and the period timer.
//!
//! Specification: docs/spec/position_fifo.md
//!
//! First-word-fall-through: while `rd_valid`, the head record (the oldest committed one)
//! is readable. Writes are staged and become readable only at a commit; an abort drops
//! them (a bus frame whose CRC fails never reaches the period timer). A write when
//! committed + staged records fill the FIFO is refused and sets the sticky `overflow`; a
//! pop while `rd_valid` is low does nothing; `flush` empties it and wins over everything
//! else.
//!
//! `rd_valid` lags the commits (the RTL's output register): with `L` the committed
//! records and `v = rd_valid` before an edge, and `pop = rd_pop && v && !flush`, after
//! the edge `rd_valid = !flush && (pop ? L >= 2 : (v || L >= 1))`. Records committed at
//! an edge do not count at that edge, so a record committed into an empty FIFO is
//! readable in the second cycle after its commit; a pop with another committed record
//! behind the head keeps `rd_valid` high. `level` counts every committed record, readable
//! or not. The block is proven in `make formal` (never overwrites, never reads empty,
//! level right, order kept, the `rd_valid` rule); the co-simulation of it comes with the
//! host-interface top that instantiates it.
//!
//! The RTL's write lanes (`wr_lane`: a record written a word at a time) are not modelled:
//! every writer writes every lane of a record before staging it (the SPI frame layer's
//! formal proof), so a write here is the whole record.

use std::collections::VecDeque;

use crate::record::PeriodRecord;

/// The inputs of one clock edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FifoInputs {
    /// Empty the FIFO.
    pub flush: bool,
    /// Clear the sticky `overflow` (a new overflow in the same cycle wins).
    pub clear_errors: bool,
    /// A record staged this cycle.
    pub write: Option<PeriodRecord>,
    /// Make the records staged before this cycle readable (this cycle's write stays staged).
    pub commit: bool,
    /// Drop the staged records, this cycle's included (wins over `commit`).
    pub abort: bool,
    /// Pop the head this cycle.
    pub pop: bool,
}

/// State of the position FIFO.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PositionFifo {
    entries: VecDeque<PeriodRecord>,
    staged: Vec<PeriodRecord>,
    depth: usize,
    overflow: bool,
    /// `rd_valid`: the head is readable.
    valid: bool,
}

impl PositionFifo {
    /// An empty FIFO of `2^depth_log2` records (the RTL's `DEPTH_LOG2`).
    pub fn new(depth_log2: u32) -> Self {
        let depth = 1usize << depth_log2;
        PositionFifo {
            entries: VecDeque::with_capacity(depth),
            staged: Vec::new(),
            depth,
            overflow: false,
            valid: false,
        }
    }

    /// Committed records (`level`), readable or not yet.
    pub fn level(&self) -> usize {
        self.entries.len()
    }

    /// Records written but not yet committed (`staged`).
    pub fn staged(&self) -> usize {
        self.staged.len()
    }

    /// The capacity in records.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Whether a write would be refused: committed + staged records fill the FIFO.
    pub fn full(&self) -> bool {
        self.entries.len() + self.staged.len() == self.depth
    }

    /// Sticky: a write was refused because the FIFO was full.
    pub fn overflow(&self) -> bool {
        self.overflow
    }

    /// The committed records, oldest first.
    pub fn records(&self) -> impl Iterator<Item = &PeriodRecord> + '_ {
        self.entries.iter()
    }

    /// `rd_valid`: the head record is readable (and a pop takes it).
    pub fn rd_valid(&self) -> bool {
        self.valid
    }

    /// The head record (`rd_data`) while `rd_valid`, else `None`.
    pub fn head(&self) -> Option<&PeriodRecord> {
        if self.valid {
            self.entries.front()
        } else {
            None
        }
    }

    /// One rising clock edge. Fullness and emptiness are those before the edge: a write
    /// to a full FIFO is refused even when the head is popped in the same cycle.
    pub fn step(&mut self, inputs: &FifoInputs) {
        let refused = inputs.write.is_some() && self.full() && !inputs.flush;
        let committed = self.entries.len();
        let pop = inputs.pop && self.valid && !inputs.flush;
        // Counted before this edge's commit: a record becomes readable one edge after
        // the one that commits it at the earliest.
        self.valid = !inputs.flush && if pop { committed >= 2 } else { self.valid || committed >= 1 };
        if inputs.flush {
            self.entries.clear();
            self.staged.clear();
        } else {
            let was_full = self.full();
            if pop {
                self.entries.pop_front();
            }
            if inputs.abort {
                self.staged.clear();
            } else {
                if inputs.commit {
                    self.entries.extend(self.staged.drain(..));
                }
                if let (Some(record), false) = (inputs.write, was_full) {
                    self.staged.push(record);
                }
            }
        }
        self.overflow = refused || (self.overflow && !inputs.clear_errors);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Increment;

    fn record(n: i32) -> PeriodRecord {
        let mut r = PeriodRecord::default();
        r.inc[0] = Increment::from_bits(n);
        r
    }

    /// Stages `n` and commits what was staged before (as a run of RECORD_PUSH writes does).
    fn write(n: i32) -> FifoInputs {
        FifoInputs { write: Some(record(n)), commit: true, ..Default::default() }
    }

    fn commit() -> FifoInputs {
        FifoInputs { commit: true, ..Default::default() }
    }

    #[test]
    fn keeps_order_and_level() {
        let mut fifo = PositionFifo::new(2);
        for n in 0..3 {
            fifo.step(&write(n));
        }
        assert_eq!((fifo.level(), fifo.staged()), (2, 1), "a commit does not take its own cycle's write");
        fifo.step(&commit());
        assert_eq!((fifo.level(), fifo.staged()), (3, 0));
        assert_eq!(fifo.head(), Some(&record(0)));
        fifo.step(&FifoInputs { pop: true, write: Some(record(3)), ..Default::default() });
        fifo.step(&commit());
        assert_eq!((fifo.level(), fifo.head()), (3, Some(&record(1))));
        for n in 1..4 {
            assert_eq!(fifo.head(), Some(&record(n)));
            fifo.step(&FifoInputs { pop: true, ..Default::default() });
        }
        assert_eq!((fifo.level(), fifo.head()), (0, None));
        fifo.step(&FifoInputs { pop: true, ..Default::default() });
        assert_eq!(fifo.level(), 0, "a pop of an empty FIFO does nothing");
        assert!(!fifo.overflow());
    }

    #[test]
    fn full_refuses_writes_overwrites_nothing_and_flags() {
        let mut fifo = PositionFifo::new(2);
        for n in 0..4 {
            fifo.step(&write(n));
        }
        assert!(fifo.full() && !fifo.overflow(), "staged records count towards full");
        fifo.step(&commit());
        assert!(fifo.full() && !fifo.overflow());
        // Refused even with a pop in the same cycle: fullness is that before the edge.
        fifo.step(&FifoInputs { pop: true, write: Some(record(99)), commit: true, ..Default::default() });
        assert!(fifo.overflow());
        assert_eq!((fifo.level(), fifo.staged()), (3, 0));
        let drained: Vec<_> = std::iter::from_fn(|| {
            let head = fifo.head().copied();
            fifo.step(&FifoInputs { pop: true, ..Default::default() });
            head
        })
        .collect();
        assert_eq!(drained, vec![record(1), record(2), record(3)]);
        // Sticky until cleared; a new overflow in the clearing cycle wins.
        assert!(fifo.overflow());
        fifo.step(&FifoInputs { clear_errors: true, ..Default::default() });
        assert!(!fifo.overflow());
    }

    #[test]
    fn staged_records_are_invisible_until_commit_and_gone_after_abort() {
        let mut fifo = PositionFifo::new(2);
        fifo.step(&write(0));
        let stage = |n| FifoInputs { write: Some(record(n)), ..Default::default() };
        fifo.step(&FifoInputs { commit: true, ..stage(1) });
        fifo.step(&stage(2));
        assert_eq!((fifo.level(), fifo.staged(), fifo.full()), (1, 2, false));
        fifo.step(&FifoInputs { abort: true, commit: true, ..stage(3) });
        assert_eq!((fifo.level(), fifo.staged()), (1, 0), "an abort wins and drops its own cycle's write");
        fifo.step(&stage(4));
        fifo.step(&FifoInputs { commit: true, ..stage(5) });
        assert_eq!((fifo.level(), fifo.staged()), (2, 1));
        fifo.step(&commit());
        assert_eq!((fifo.level(), fifo.staged()), (3, 0));
        let drained: Vec<_> = std::iter::from_fn(|| {
            let head = fifo.head().copied();
            fifo.step(&FifoInputs { pop: true, ..Default::default() });
            head
        })
        .collect();
        assert_eq!(drained, vec![record(0), record(4), record(5)]);
    }

    #[test]
    fn readable_in_the_second_cycle_after_the_commit_and_no_bubble_on_a_pop() {
        let pop = FifoInputs { pop: true, ..Default::default() };
        let idle = FifoInputs::default();
        let mut fifo = PositionFifo::new(2);
        fifo.step(&write(0));
        assert_eq!((fifo.level(), fifo.staged(), fifo.rd_valid()), (0, 1, false), "staged by its write");
        fifo.step(&write(1));
        // Committed and counted, not readable yet; a pop now does nothing.
        assert_eq!((fifo.level(), fifo.rd_valid(), fifo.head()), (1, false, None));
        fifo.step(&FifoInputs { commit: true, pop: true, ..Default::default() });
        assert_eq!((fifo.level(), fifo.head()), (2, Some(&record(0))), "the second cycle after the commit");
        // A pop with a record behind the head (committed a cycle ago): no bubble.
        fifo.step(&pop);
        assert_eq!((fifo.level(), fifo.head()), (1, Some(&record(1))));
        // The last record popped while another is committed: that one waits a cycle.
        fifo.step(&FifoInputs { pop: true, ..write(2) });
        fifo.step(&FifoInputs { pop: true, ..commit() });
        assert_eq!((fifo.level(), fifo.head()), (1, None));
        fifo.step(&idle);
        assert_eq!((fifo.level(), fifo.head()), (1, Some(&record(2))));
        fifo.step(&pop);
        assert_eq!((fifo.level(), fifo.rd_valid()), (0, false));
        // A flush in the cycle after a commit: nothing becomes readable.
        fifo.step(&write(3));
        fifo.step(&commit());
        fifo.step(&FifoInputs { flush: true, ..Default::default() });
        fifo.step(&idle);
        assert_eq!((fifo.level(), fifo.rd_valid()), (0, false));
    }

    #[test]
    fn flush_wins() {
        let mut fifo = PositionFifo::new(3);
        fifo.step(&write(1));
        fifo.step(&write(2));
        fifo.step(&commit());
        assert!(fifo.rd_valid());
        fifo.step(&FifoInputs { flush: true, write: Some(record(3)), commit: true, pop: true, ..Default::default() });
        assert_eq!((fifo.level(), fifo.staged(), fifo.rd_valid(), fifo.overflow()), (0, 0, false, false));
    }
}
