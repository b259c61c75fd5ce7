//! `--observed`'s table and JSON: per chain, metric and anchor the count,
//! min, p99 and max measured, every bound as `analyze` shows it, the
//! ratio of the largest to the sound bound, and the verdict.

use super::{Entry, Observed, OPEN_SAMPLES};
use crate::report::{time, Pairs};
use crate::table::Table;
use rtpipe_model::{Nanos, Spec};
use serde::Serialize;

/// `analyze --json`'s `"observed"`.
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "MeasuredFileView")]
pub struct ObservedView<'a> {
    file: &'a str,
    format: &'static str,
    rows: u64,
    /// Whether every p99 below is exact (else within the histogram's
    /// relative error).
    p99_exact: bool,
    measured: Vec<EntryView>,
    not_measured: Vec<String>,
    /// Per chain with any, the publications of samples already closed that
    /// did not count toward reaction (data-age logs only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    late: Vec<(String, u64)>,
    ok: bool,
}

#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "MeasuredEntryView")]
struct EntryView {
    chain: String,
    metric: &'static str,
    from: &'static str,
    count: usize,
    min: Option<f64>,
    p99: Option<f64>,
    max: Option<f64>,
    /// The line of the largest measurement in the file.
    worst_line: u64,
    bounds: Pairs<&'static str, Option<f64>>,
    /// The largest measured over the sound bound (null without one).
    ratio: Option<f64>,
    over_paper: usize,
    over_sound: Option<usize>,
    ok: bool,
}

/// The JSON view of `o`.
pub fn view<'a>(spec: &Spec, r: &rtpipe_analysis::Report, o: &'a Observed) -> ObservedView<'a> {
    let measured = o
        .entries
        .iter()
        .map(|e| {
            let s = e.judged.observed;
            EntryView {
                chain: spec.chain_label(e.chain),
                metric: e.metric.name(),
                from: e.anchor.name(),
                count: s.map_or(0, |s| s.count),
                min: time(spec, s.map(|s| s.min)),
                p99: time(spec, s.map(|s| s.p99)),
                max: time(spec, s.map(|s| s.max)),
                worst_line: e.worst.0,
                bounds: Pairs(bounds(r, e).map(|(b, v)| (b, time(spec, v))).collect()),
                ratio: ratio(e),
                over_paper: e.judged.over_paper,
                over_sound: e.judged.over_sound,
                ok: e.judged.over_sound.unwrap_or(0) == 0,
            }
        })
        .collect();
    ObservedView {
        file: &o.file,
        format: o.format.name(),
        rows: o.rows,
        p99_exact: o.exact(),
        measured,
        not_measured: not_measured(spec, o),
        late: late(spec, o),
        ok: o.ok(),
    }
}

/// The bounds of `e`'s chain and metric from its anchor, as `analyze`
/// lists them.
fn bounds<'r>(
    r: &'r rtpipe_analysis::Report,
    e: &Entry,
) -> impl Iterator<Item = (&'static str, Option<Nanos>)> + 'r {
    let (chain, metric, anchor) = (e.chain, e.metric, e.anchor);
    r.chains
        .iter()
        .filter(move |c| c.chain == chain && c.metric == metric)
        .flat_map(move |c| c.bound.from(anchor).map(|(b, v)| (b.name(), v)))
}

/// The largest measured over the sound bound.
fn ratio(e: &Entry) -> Option<f64> {
    let sound = e.judged.sound.filter(|&s| s > 0)?;
    Some(e.worst.1 as f64 / sound as f64)
}

/// The spec's chains without a row in the file.
fn not_measured(spec: &Spec, o: &Observed) -> Vec<String> {
    (0..spec.chains.len())
        .filter(|&c| o.chain_rows[c] == 0)
        .map(|c| spec.chain_label(c))
        .collect()
}

fn late(spec: &Spec, o: &Observed) -> Vec<(String, u64)> {
    (0..spec.chains.len())
        .filter(|&c| o.late[c] > 0)
        .map(|c| (spec.chain_label(c), o.late[c]))
        .collect()
}

/// The section of the text report.
pub fn text(spec: &Spec, r: &rtpipe_analysis::Report, o: &Observed) -> String {
    let exact = if o.exact() {
        "p99 exact"
    } else {
        "p99 within 0.8 % (histogram)"
    };
    let mut out = format!(
        "\nmeasured ({}, {}: {} rows; {exact}; max/sound: the largest measured over the sound bound):\n",
        o.file,
        o.format.name(),
        o.rows
    );
    out.push_str(&table(spec, r, o));
    for c in not_measured(spec, o) {
        out.push_str(&format!("  {c}: not measured\n"));
    }
    for (c, n) in late(spec, o) {
        out.push_str(&format!(
            "  {c}: {n} publication(s) of samples older than the {OPEN_SAMPLES} newest open ones counted toward freshness only\n"
        ));
    }
    out.push_str(&verdict(spec, o));
    out
}

fn table(spec: &Spec, r: &rtpipe_analysis::Report, o: &Observed) -> String {
    let mut heads = vec!["chain", "metric", "from", "count", "min", "p99", "max"];
    heads.extend(rtpipe_analysis::Bound::ALL.map(|b| b.name()));
    heads.extend(["max/sound", "verdict"]);
    let numeric: Vec<usize> = (3..heads.len() - 1).collect();
    let mut t = Table::new(&heads).numeric(&numeric);
    let fmt = |v: Option<Nanos>| v.map_or_else(|| "unbounded".to_string(), |v| spec.fmt_time(v));
    for e in &o.entries {
        let Some(s) = e.judged.observed else { continue };
        let mut row = vec![
            spec.chain_label(e.chain),
            e.metric.name().to_string(),
            e.anchor.name().to_string(),
            s.count.to_string(),
            spec.fmt_time(s.min),
            spec.fmt_time(s.p99),
            spec.fmt_time(s.max),
        ];
        row.extend(bounds(r, e).map(|(_, v)| fmt(v)));
        row.push(ratio(e).map_or_else(|| "-".into(), |x| format!("{x:.3}")));
        let ok = e.judged.over_sound.unwrap_or(0) == 0;
        row.push(if ok { "ok" } else { "FAIL" }.to_string());
        t.row(row);
    }
    t.render()
}

/// The last line: every measurement within its sound bound, or each that
/// is not with its worst row.
fn verdict(spec: &Spec, o: &Observed) -> String {
    let fails: Vec<String> = o
        .entries
        .iter()
        .filter_map(|e| {
            let sound = e.judged.sound?;
            let over = e.judged.over_sound.filter(|&n| n > 0)?;
            Some(format!(
                "  {} {} from the {}: {over} above the sound bound {}; worst line {} of {}: {} {}\n",
                spec.chain_label(e.chain),
                e.metric.name(),
                e.anchor.name(),
                spec.fmt_time(sound),
                e.worst.0,
                o.file,
                spec.fmt_time(e.worst.1),
                spec.time_unit,
            ))
        })
        .collect();
    if fails.is_empty() {
        return "measured verdict: every measurement within its sound bound\n".to_string();
    }
    format!(
        "measured verdict: FAIL, {} measurement kind(s) above the sound bound:\n{}",
        fails.len(),
        fails.concat()
    )
}
