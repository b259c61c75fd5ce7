//! `fly --sweep`'s report: every timing flown and the limits derived, as
//! text, JSON or tables. The tables are read off the JSON's view, so the
//! two formats cannot disagree.

use super::{sweep_json, text, FlyArgs, LimitMs, PairMs, SweepView};
use crate::report::record_table;
use rtpipe_flight::quality::Criteria;
use rtpipe_fly::sweep::{Derived, Point};
use rtpipe_fly::Setup;
use rtpipe_model::Spec;
use rtpipe_printer::{Cell, Column, Kind, Table};
use serde::Serialize;
use std::path::Path;

/// `rtpipe fly --sweep`'s report.
pub(in crate::fly) struct SweepReport<'a> {
    pub spec: &'a Spec,
    pub setup: &'a Setup,
    /// Further (vehicle, mission) setups every timing was flown on, each
    /// with its criterion.
    pub also: &'a [(Setup, Criteria)],
    pub criteria: &'a Criteria,
    pub args: &'a FlyArgs,
    pub points: &'a [Point],
    pub limits: &'a Derived,
    /// The spec written with the derived limits (`--write-limits`), when
    /// it was.
    pub written: Option<&'a Path>,
}

impl SweepReport<'_> {
    fn view(&self) -> SweepView<'_> {
        sweep_json(
            self.spec,
            (self.setup, self.also),
            self.criteria,
            self.args,
            self.points,
            self.limits,
        )
    }
}

impl Serialize for SweepReport<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.view().serialize(s)
    }
}

impl rtpipe_printer::Report for SweepReport<'_> {
    fn text(&self) -> String {
        let how = (self.criteria, self.args);
        text(
            self.spec,
            (self.setup, self.also),
            how,
            self.points,
            self.limits,
            self.written,
        )
    }

    /// The sweep's setup (one row), its points, each point's bounds per
    /// chain, the derived limits per chain and the tails' `max_period`.
    fn tables(&self) -> Vec<Table> {
        let v = self.view();
        let labels: Vec<String> = (0..self.spec.chains.len())
            .map(|k| self.spec.chain_label(k))
            .collect();
        vec![
            setup_table(&v),
            points_table(&v),
            bounds_table(&v, &labels),
            limits_table(&v.limits_ms),
            max_period_table(&v),
        ]
    }
}

fn setup_table(v: &SweepView) -> Table {
    record_table(
        "sweep",
        vec![
            ("system", Kind::Text, Cell::from(v.system)),
            ("vehicle", Kind::Text, Cell::from(v.vehicle)),
            ("mission", Kind::Text, Cell::from(v.mission)),
            ("criterion", Kind::Text, Cell::from(v.criterion.as_str())),
            ("seeds", Kind::UInt, Cell::UInt(u64::from(v.seeds))),
            ("phases", Kind::UInt, Cell::UInt(u64::from(v.phases))),
            ("safety", Kind::Float, Cell::Float(v.safety)),
        ],
    )
}

/// A row per timing flown, numbered from 0 in the order of the JSON's
/// `points` (the `bounds` table's `point`).
fn points_table(v: &SweepView) -> Table {
    let mut columns = vec![
        Column::new("point", Kind::UInt),
        Column::new("varied", Kind::Text),
        Column::new("value", Kind::Float),
        Column::new("stage", Kind::Text),
    ];
    columns.extend(
        ["schedulable", "flies", "flight_met_criterion"].map(|n| Column::new(n, Kind::Bool)),
    );
    columns.extend(["flights", "passed"].map(|n| Column::new(n, Kind::UInt)));
    columns.push(Column::new("failures", Kind::Text));
    columns.extend(
        [
            "attitude_error_rms_deg",
            "altitude_error_rms_m",
            "position_error_rms_m",
        ]
        .map(|n| Column::new(n, Kind::Float)),
    );
    // Empty when the timing could not be flown.
    columns.push(Column::new("crashed", Kind::Text));
    let Ok(mut t) = Table::new("points", columns) else {
        unreachable!("the points table's columns are distinct names");
    };
    for (k, p) in v.points.iter().enumerate() {
        t.push(vec![
            Cell::UInt(k as u64),
            Cell::from(p.varied),
            Cell::Float(p.value),
            Cell::from(p.stage),
            Cell::Bool(p.schedulable),
            Cell::Bool(p.flies),
            Cell::Bool(p.flight_met_criterion),
            Cell::UInt(u64::from(p.flights)),
            Cell::UInt(u64::from(p.passed)),
            Cell::from(p.failures.join("; ")),
            Cell::opt_float(p.attitude_error_rms_deg),
            Cell::opt_float(p.altitude_error_rms_m),
            Cell::opt_float(p.position_error_rms_m),
            p.crashed.map_or(Cell::Empty, |c| Cell::from(c.to_string())),
        ]);
    }
    t
}

/// A row per point, chain and anchor: the sound bounds of the timing
/// flown, ms (from the read: reaction and freshness; from the event:
/// maximum reaction time and freshness from the event).
fn bounds_table(v: &SweepView, labels: &[String]) -> Table {
    let mut columns = vec![Column::new("point", Kind::UInt)];
    columns.extend(["chain", "from"].map(|n| Column::new(n, Kind::Text)));
    columns.extend(["reaction_ms", "freshness_ms"].map(|n| Column::new(n, Kind::Float)));
    let Ok(mut t) = Table::new("bounds", columns) else {
        unreachable!("the bounds table's columns are distinct names");
    };
    for (k, p) in v.points.iter().enumerate() {
        for (from, pairs) in [("read", &p.bounds_ms), ("event", &p.event_bounds_ms)] {
            for (label, pair) in labels.iter().zip(pairs.iter()) {
                t.push(vec![
                    Cell::UInt(k as u64),
                    Cell::from(label.as_str()),
                    Cell::from(from),
                    Cell::opt_float(pair.reaction),
                    Cell::opt_float(pair.freshness),
                ]);
            }
        }
    }
    t
}

/// A row per chain: the derived limits, ms (empty: none derived).
fn limits_table(limits: &[LimitMs]) -> Table {
    let mut columns = vec![Column::new("chain", Kind::Text)];
    columns.extend(
        [
            "reaction_ms",
            "freshness_ms",
            "max_reaction_time_ms",
            "freshness_from_event_ms",
        ]
        .map(|n| Column::new(n, Kind::Float)),
    );
    let Ok(mut t) = Table::new("limits", columns) else {
        unreachable!("the limits table's columns are distinct names");
    };
    for l in limits {
        let PairMs {
            reaction,
            freshness,
        } = &l.limit;
        t.push(vec![
            Cell::from(l.chain.as_str()),
            Cell::opt_float(*reaction),
            Cell::opt_float(*freshness),
            Cell::opt_float(l.max_reaction_time),
            Cell::opt_float(l.freshness_from_event),
        ]);
    }
    t
}

/// A row per tail whose rate sweep flew: its derived `max_period`, ms.
fn max_period_table(v: &SweepView) -> Table {
    let columns = vec![
        Column::new("task", Kind::Text),
        Column::new("max_period_ms", Kind::Float),
    ];
    let Ok(mut t) = Table::new("max_period", columns) else {
        unreachable!("the max_period table's columns are distinct names");
    };
    for (task, ms) in &v.max_period_ms.0 {
        t.push(vec![Cell::from(*task), Cell::Float(*ms)]);
    }
    t
}
