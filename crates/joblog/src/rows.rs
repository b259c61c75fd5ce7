//! One chain's [`SampleRow`]s while a run makes them: a row is complete once
//! a newer sample reached the tail (samples reach it in order, so nothing
//! older can be output again), and a streaming run hands complete rows on
//! and forgets them, so its memory does not grow with its length.

use crate::SampleRow;
use std::collections::VecDeque;

/// Where a streaming run hands each complete row: (chain, row), every
/// chain's rows in sample order.
pub type RowSink = Box<dyn FnMut(usize, &SampleRow) + Send>;

/// The rows of samples `base..`, of which those below `done_below` are
/// complete.
#[derive(Debug, Default)]
pub(crate) struct Rows {
    buf: VecDeque<SampleRow>,
    base: u64,
    done_below: u64,
}

impl Rows {
    /// Every row, from a finished job log (nothing handed on yet).
    pub(crate) fn from_vec(rows: Vec<SampleRow>) -> Rows {
        Rows {
            buf: rows.into(),
            base: 0,
            done_below: 0,
        }
    }

    /// The id the next row gets.
    pub(crate) fn next_id(&self) -> u64 {
        self.base + self.buf.len() as u64
    }

    pub(crate) fn push(&mut self, row: SampleRow) {
        assert_eq!(row.sample, self.next_id(), "rows come in sample order");
        self.buf.push_back(row);
    }

    /// The row of `sample`, which must not have been handed on.
    pub(crate) fn get_mut(&mut self, sample: u64) -> &mut SampleRow {
        assert!(
            sample >= self.base,
            "row {sample} was handed on (kept from {})",
            self.base
        );
        let k = (sample - self.base) as usize;
        &mut self.buf[k]
    }

    /// Rows below `sample` are complete.
    pub(crate) fn complete_below(&mut self, sample: u64) {
        self.done_below = self.done_below.max(sample);
    }

    /// Hands every complete row to `sink` (as chain `chain`) and forgets it;
    /// with `all`, every row (the run is over).
    pub(crate) fn drain(&mut self, chain: usize, sink: &mut RowSink, all: bool) {
        while self.base < self.done_below || (all && !self.buf.is_empty()) {
            let Some(row) = self.buf.pop_front() else {
                break;
            };
            sink(chain, &row);
            self.base += 1;
        }
    }

    /// Forgets the rows of samples from `sample` on (read by a head job the
    /// run ended before it published: a job log has no such job).
    pub(crate) fn truncate(&mut self, sample: u64) {
        let keep = sample.saturating_sub(self.base) as usize;
        self.buf.truncate(keep);
    }

    /// Every row kept (a run that streamed nothing).
    pub(crate) fn into_vec(self) -> Vec<SampleRow> {
        self.buf.into()
    }
}
