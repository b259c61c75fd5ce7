//! A row's description: its named, typed columns, in file order (its
//! cells: `Row::cells`, in `system.rs`). The Parquet schema and writer
//! (`parquet_out.rs`) and any CSV of the rows (`rtpipe_printer::csv`) are
//! derived from it, so a column added here reaches every format.

use rtpipe_analysis::{Anchor, Bound};
use rtpipe_printer::{Column, Kind, Table};

/// A column's prefix per anchor: none from the read, `event_` from the
/// event.
fn prefix(a: Anchor) -> &'static str {
    match a {
        Anchor::Read => "",
        Anchor::Event => "event_",
    }
}

/// The columns, in file order: bounds are `{paper,sound,davare,duerr}_ns`
/// from the read and `event_*` from the event ([`Bound::ALL`] ×
/// [`Anchor::ALL`]); `offsets_*` under the known offsets; `observed_*`
/// from the simulation.
pub fn columns() -> Vec<Column> {
    let mut c = vec![
        Column::new("system", Kind::UInt),
        Column::new("seed", Kind::UInt),
    ];
    c.extend(["tasks", "cpus", "chains"].map(|n| Column::new(n, Kind::Count)));
    c.extend(["utilization_target", "utilization"].map(|n| Column::new(n, Kind::Float)));
    c.push(Column::new("schedulable", Kind::Bool));
    c.extend(["chain", "chain_tasks"].map(|n| Column::new(n, Kind::Count)));
    c.push(Column::new("metric", Kind::Text));
    for a in Anchor::ALL {
        c.extend(
            Bound::ALL.map(|b| Column::new(format!("{}{}_ns", prefix(a), b.name()), Kind::OptInt)),
        );
    }
    c.extend(Anchor::ALL.map(|a| Column::new(format!("{}offsets_ns", prefix(a)), Kind::OptInt)));
    c.extend(
        Anchor::ALL.map(|a| Column::new(format!("{}observed_max_ns", prefix(a)), Kind::OptInt)),
    );
    c.extend(["observed_count", "observed_over_bound"].map(|n| Column::new(n, Kind::OptInt)));
    c.push(Column::new("simulated", Kind::Bool));
    c
}

/// The columns' names, in file order.
pub fn names() -> Vec<String> {
    columns().into_iter().map(|c| c.name).collect()
}

/// An empty table of the rows' columns.
pub fn table() -> Table {
    let Ok(t) = Table::new("campaign", columns()) else {
        unreachable!("the campaign's columns are distinct names");
    };
    t
}
