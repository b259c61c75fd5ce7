//! The `--samples` CSV of a run: one row per sample of a chain, its
//! instants and latencies in integer nanoseconds, through the printer's
//! one CSV rule. It runs once per sample of a long run, so it lives here,
//! built optimised, and not in the cli, which is glue built cheaply
//! (docs/architecture.md, "Building").

use crate::SampleRow;
use rtpipe_model::Spec;
use rtpipe_printer::{csv, Cell, Column, Kind, Table};
use std::fs::File;
use std::io::{BufWriter, Write as _};

/// The header: instants and latencies in integer nanoseconds; an empty
/// cell where the run ended before the instant (a sample that never
/// reached the tail has no reaction).
pub const HEADER: &str = "chain,sample,read_ns,event_ns,first_output_ns,last_output_ns,\
reaction_ns,freshness_ns,event_reaction_ns,event_freshness_ns";

/// The columns of [`HEADER`]: the chain's label, the sample's number, and
/// instants and latencies that may be absent.
pub fn columns() -> Vec<Column> {
    HEADER
        .split(',')
        .enumerate()
        .map(|(i, name)| {
            let kind = match i {
                0 => Kind::Text,
                1 => Kind::UInt,
                _ => Kind::OptInt,
            };
            Column::new(name, kind)
        })
        .collect()
}

/// The CSV text of every chain's rows (indexed like `Spec::chains`), by
/// the CSV printer.
pub fn samples_csv(spec: &Spec, rows: &[Vec<SampleRow>]) -> String {
    let Ok(mut t) = Table::new("samples", columns()) else {
        unreachable!("the samples' columns are distinct names");
    };
    for (c, rows) in rows.iter().enumerate() {
        let label = spec.chain_label(c);
        for r in rows {
            t.push(row_cells(&label, r));
        }
    }
    csv::table(&t)
}

/// One row's cells, in [`HEADER`]'s order.
pub fn row_cells(label: &str, r: &SampleRow) -> Vec<Cell> {
    let mut row = vec![Cell::from(label), Cell::UInt(r.sample)];
    row.extend(
        [
            Some(r.read),
            r.event,
            r.first,
            r.last,
            r.reaction(),
            r.freshness(),
            r.event_reaction(),
            r.event_freshness(),
        ]
        .map(Cell::opt_int),
    );
    row
}

/// One row as a CSV line (with its newline), as [`samples_csv`] writes it.
pub fn csv_line(label: &str, r: &SampleRow) -> String {
    csv::row_line(&row_cells(label, r))
}

/// Appends one row's CSV line to `out`: the streamed `--samples` file's
/// per-sample write, concrete so that it is built here (optimised) and
/// not in the caller.
pub fn write_row(out: &mut BufWriter<File>, label: &str, r: &SampleRow) -> std::io::Result<()> {
    out.write_all(csv_line(label, r).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_streamed_rows_are_the_printers() {
        let Ok(t) = Table::new("samples", columns()) else {
            panic!("distinct names");
        };
        assert_eq!(csv::header(&t).trim_end(), HEADER);
    }
}
