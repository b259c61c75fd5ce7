//! `analyze --observed FILE.csv`: measured chain latencies held against the
//! report's bounds. Two formats, told apart by the header line: the
//! `--samples` CSV of `simulate`, `fly` and `run` (each row a sample's
//! reaction and freshness from the read and from the event) and a flight
//! log's data ages (`import px4-ulog`: one row per published message).
//! The file is streamed a line at a time through `rtpipe_model::input`'s
//! rules; each chain, metric and anchor keeps a `joblog` histogram, so
//! memory does not grow with the file. The judging is `sim::observe`'s;
//! the report's view of the result is the cli's. The reading runs once per
//! row of a file of any length, so it lives here, built optimised, and not
//! in the cli, which is glue built cheaply (docs/architecture.md,
//! "Building").

use super::Judged;
use rtpipe_analysis::{Anchor, Metric, Report};
use rtpipe_joblog::samples::HEADER as SAMPLES_HEADER;
use rtpipe_joblog::Histogram;
use rtpipe_model::input::cells::{Bad, Cells};
use rtpipe_model::input::{Kind, Lines, Syntax};
use rtpipe_model::{Diagnostic, Nanos, Spec};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// The header of a flight log's measured data ages (`import px4-ulog`).
pub const LOG_HEADER: &str = "chain,topic,timestamp_ns,timestamp_sample_ns,data_age_ns";

/// The most samples of one chain a data-age log keeps open (their earliest
/// publication not yet final): a sample closes when this many newer ones
/// of its chain are open. A publication of a closed sample still counts
/// toward freshness; toward reaction it is counted as late and reported.
pub const OPEN_SAMPLES: usize = 1 << 16;

/// The file kind in messages (`Lines` caps a line, not the file).
const KIND: Kind = Kind {
    name: "measurements file",
    max_bytes: u64::MAX,
    syntax: Syntax::Toml,
    help: "give the --samples CSV of simulate, fly or run, or the data ages of import px4-ulog",
};

/// Which of the two formats a file is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// The `--samples` CSV.
    Samples,
    /// A flight log's data ages.
    Log,
}

impl Format {
    /// The name in output and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Format::Samples => "samples",
            Format::Log => "data ages",
        }
    }
}

/// What a file measured, judged: one entry per chain, metric and anchor
/// with measurements, in the report's order.
pub struct Observed {
    /// The file as given.
    pub file: String,
    /// Its format.
    pub format: Format,
    /// Its data rows.
    pub rows: u64,
    /// Data rows per chain (indexed like `Spec::chains`).
    pub chain_rows: Vec<u64>,
    /// Per chain, the publications of samples already closed
    /// ([`OPEN_SAMPLES`]) that could not count toward reaction.
    pub late: Vec<u64>,
    /// The judged measurements.
    pub entries: Vec<Entry>,
}

impl Observed {
    /// Every measurement within its sound bound.
    pub fn ok(&self) -> bool {
        self.entries
            .iter()
            .all(|e| e.judged.over_sound.unwrap_or(0) == 0)
    }

    /// Whether every p99 is exact (the histograms stayed exact).
    pub fn exact(&self) -> bool {
        self.entries
            .iter()
            .all(|e| e.judged.observed.is_none_or(|s| s.exact))
    }
}

/// One chain, metric and anchor: the measurements against the bounds.
pub struct Entry {
    /// Index in `Spec::chains`.
    pub chain: usize,
    /// The metric.
    pub metric: Metric,
    /// Measured from.
    pub anchor: Anchor,
    /// The measurements against the paper and sound bounds (the counts
    /// above them exact; the p99 as `Summary` says).
    pub judged: Judged,
    /// The largest measurement: its line in the file and its value.
    pub worst: (u64, Nanos),
}

/// One chain, metric and anchor while the file is read: the histogram
/// (for the distribution), the worst row, and exact counts above the
/// paper and sound bounds (the histogram's are approximate once coarse).
#[derive(Default)]
struct Tally {
    hist: Histogram,
    worst: Option<(u64, Nanos)>,
    paper: Nanos,
    sound: Option<Nanos>,
    over_paper: usize,
    over_sound: usize,
}

impl Tally {
    fn push(&mut self, line: u64, v: Nanos) {
        self.hist.push(v);
        if self.worst.is_none_or(|(_, w)| v > w) {
            self.worst = Some((line, v));
        }
        self.over_paper += usize::from(v > self.paper);
        self.over_sound += usize::from(self.sound.is_some_and(|s| v > s));
    }
}

/// Every chain's tallies, indexed by chain, metric and anchor.
struct Tallies(Vec<[[Tally; 2]; 2]>);

impl Tallies {
    fn get(&mut self, chain: usize, metric: Metric, anchor: Anchor) -> &mut Tally {
        let m = usize::from(metric == Metric::Freshness);
        let a = usize::from(anchor == Anchor::Event);
        &mut self.0[chain][m][a]
    }
}

/// Reads `path` and judges it against `report`, the analysis of `spec`.
/// A wrong file is an error naming its line and column and the fix.
pub fn read(path: &Path, spec: &Spec, report: &Report) -> Result<Observed, Diagnostic> {
    let mut lines = Lines::open(path, &KIND)?;
    let format = match lines.next_line()? {
        None => {
            return Err(Diagnostic::error(
                format!("{}:1:1: the measurements file is empty", lines.file()),
                header_help(),
            ))
        }
        Some((_, h)) => match h.trim_end() {
            SAMPLES_HEADER => Some(Format::Samples),
            LOG_HEADER => Some(Format::Log),
            _ => None,
        },
    };
    let Some(format) = format else {
        return Err(lines.at(1, "unknown header line", &header_help()));
    };
    let mut reader = Reader::new(spec, report, format);
    while let Some((number, line)) = lines.next_line()? {
        if line.trim().is_empty() {
            continue;
        }
        let done = reader.row(line, number);
        done.map_err(|b| lines.at(b.col, b.message, &b.help))?;
    }
    Ok(reader.finish(lines.file(), report))
}

/// How to fix a wrong header.
fn header_help() -> String {
    format!(
        "a measurements file starts with the header `{SAMPLES_HEADER}` (the --samples CSV of \
         simulate, fly and run) or `{LOG_HEADER}` (import px4-ulog's data ages)"
    )
}

/// The state of one file's reading.
struct Reader<'s> {
    spec: &'s Spec,
    format: Format,
    chains: HashMap<String, usize>,
    tallies: Tallies,
    rows: u64,
    chain_rows: Vec<u64>,
    /// Per chain, the open samples of a data-age log: the sample instant →
    /// its earliest publication and that row's line.
    open: Vec<BTreeMap<Nanos, (Nanos, u64)>>,
    /// Per chain, the latest sample instant closed.
    closed: Vec<Option<Nanos>>,
    late: Vec<u64>,
}

impl<'s> Reader<'s> {
    fn new(spec: &'s Spec, report: &Report, format: Format) -> Reader<'s> {
        let n = spec.chains.len();
        let mut tallies = Tallies((0..n).map(|_| Default::default()).collect());
        for c in &report.chains {
            for anchor in Anchor::ALL {
                let t = tallies.get(c.chain, c.metric, anchor);
                (t.paper, t.sound) = (c.bound.paper(anchor), c.bound.sound(anchor));
            }
        }
        Reader {
            spec,
            format,
            chains: (0..n).map(|c| (spec.chain_label(c), c)).collect(),
            tallies,
            rows: 0,
            chain_rows: vec![0; n],
            open: vec![BTreeMap::new(); n],
            closed: vec![None; n],
            late: vec![0; n],
        }
    }

    /// One data row, at `line`.
    fn row(&mut self, text: &str, line: u64) -> Result<(), Bad> {
        let mut cells = Cells::split(text)?;
        cells.expect_header(match self.format {
            Format::Samples => SAMPLES_HEADER,
            Format::Log => LOG_HEADER,
        })?;
        let chain = self.chain(&cells)?;
        self.rows += 1;
        self.chain_rows[chain] += 1;
        match self.format {
            Format::Samples => self.samples_row(&cells, chain, line),
            Format::Log => self.log_row(&cells, chain, line),
        }
    }

    /// The chain named in the first cell.
    fn chain(&self, cells: &Cells) -> Result<usize, Bad> {
        let name = cells.text(0);
        if let Some(&c) = self.chains.get(name) {
            return Ok(c);
        }
        // The --samples writer guards a label that starts like a
        // spreadsheet formula with an apostrophe.
        let unguarded = name
            .strip_prefix('\'')
            .filter(|n| n.starts_with(['=', '+', '-', '@', '\t', '\r']));
        if let Some(&c) = unguarded.and_then(|n| self.chains.get(n)) {
            return Ok(c);
        }
        let names: Vec<String> = (0..self.spec.chains.len())
            .map(|c| format!("`{}`", self.spec.chain_label(c)))
            .collect();
        Err(Bad::at(
            cells.col(0),
            format!(
                "chain `{name}` is not in the spec {}",
                rtpipe_model::input::shown_name(&self.spec.name)
            ),
            format!(
                "name one of the spec's chains: {} (or analyse the spec the measurements are of)",
                names.join(", ")
            ),
        ))
    }

    /// A `--samples` row: its latencies, each from its anchor.
    fn samples_row(&mut self, cells: &Cells, chain: usize, line: u64) -> Result<(), Bad> {
        cells.count(1)?;
        cells.instant(2)?;
        for k in 3..6 {
            cells.optional_instant(k)?;
        }
        let latencies = [
            (6, Metric::Reaction, Anchor::Read),
            (7, Metric::Freshness, Anchor::Read),
            (8, Metric::Reaction, Anchor::Event),
            (9, Metric::Freshness, Anchor::Event),
        ];
        for (k, metric, anchor) in latencies {
            if let Some(v) = cells.latency(k)? {
                self.tallies.get(chain, metric, anchor).push(line, v);
            }
        }
        Ok(())
    }

    /// A data-age row: its age is a freshness from the event (a sensor
    /// samples the world at or before the head's read of it, after the
    /// head's previous read: the event anchor's instant); the earliest
    /// publication of its sample is the sample's reaction from the event.
    fn log_row(&mut self, cells: &Cells, chain: usize, line: u64) -> Result<(), Bad> {
        let published = cells.instant(2)?;
        let sampled = cells.instant(3)?;
        let Some(age) = cells.latency(4)? else {
            return Err(Bad::at(
                cells.col(4),
                "data_age_ns is empty",
                "every published message has a data age: timestamp_ns - timestamp_sample_ns",
            ));
        };
        if published.checked_sub(sampled) != Some(age) {
            return Err(Bad::at(
                cells.col(4),
                format!(
                    "data_age_ns {age} is not timestamp_ns - timestamp_sample_ns = {published} - {sampled}"
                ),
                "the data age is the publication instant minus the head sample's instant",
            ));
        }
        self.tallies
            .get(chain, Metric::Freshness, Anchor::Event)
            .push(line, age);
        self.first_publication(chain, sampled, published, line);
        Ok(())
    }

    /// Keeps the earliest publication of each open sample of `chain`.
    fn first_publication(&mut self, chain: usize, sampled: Nanos, published: Nanos, line: u64) {
        if self.closed[chain].is_some_and(|c| sampled <= c)
            && !self.open[chain].contains_key(&sampled)
        {
            self.late[chain] += 1;
            return;
        }
        let entry = self.open[chain].entry(sampled).or_insert((published, line));
        if published < entry.0 {
            *entry = (published, line);
        }
        if self.open[chain].len() > OPEN_SAMPLES {
            self.close_oldest(chain);
        }
    }

    /// Closes `chain`'s oldest open sample: its reaction is final.
    fn close_oldest(&mut self, chain: usize) {
        if let Some((sampled, (published, line))) = self.open[chain].pop_first() {
            self.closed[chain] = Some(sampled);
            self.tallies
                .get(chain, Metric::Reaction, Anchor::Event)
                .push(line, published - sampled);
        }
    }

    /// Closes every open sample and judges the tallies against `report`.
    fn finish(mut self, file: &str, report: &Report) -> Observed {
        for c in 0..self.open.len() {
            while !self.open[c].is_empty() {
                self.close_oldest(c);
            }
        }
        let mut entries = Vec::new();
        for c in &report.chains {
            for anchor in Anchor::ALL {
                let t = self.tallies.get(c.chain, c.metric, anchor);
                let Some(worst) = t.worst else { continue };
                let mut judged = Judged::of_hist(&t.hist, t.paper, t.sound);
                // The histogram's counts near a bound are approximate once
                // it is coarse; the tally's are exact.
                judged.over_paper = t.over_paper;
                judged.over_sound = t.sound.map(|_| t.over_sound);
                entries.push(Entry {
                    chain: c.chain,
                    metric: c.metric,
                    anchor,
                    judged,
                    worst,
                });
            }
        }
        Observed {
            file: file.to_string(),
            format: self.format,
            rows: self.rows,
            chain_rows: self.chain_rows,
            late: self.late,
            entries,
        }
    }
}
