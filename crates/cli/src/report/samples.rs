//! One row per sample (`--samples FILE.csv` of `simulate`, `fly` and
//! `run`): every chain's head samples with the instants that end their
//! latencies, for pandas, polars or a spreadsheet.

use rtpipe_joblog::SampleRow;
use rtpipe_model::Spec;
use std::fmt::Write;

/// The header: instants and latencies in integer nanoseconds; an empty
/// cell where the run ended before the instant (a sample that never
/// reached the tail has no reaction).
pub const HEADER: &str = "chain,sample,read_ns,event_ns,first_output_ns,last_output_ns,\
reaction_ns,freshness_ns,event_reaction_ns,event_freshness_ns";

/// The CSV text of every chain's rows (indexed like `Spec::chains`).
pub fn samples_csv(spec: &Spec, rows: &[Vec<SampleRow>]) -> String {
    let mut out = String::from(HEADER);
    out.push('\n');
    for (c, rows) in rows.iter().enumerate() {
        let label = quoted(&spec.chain_label(c));
        for r in rows {
            let cells = [
                Some(r.read),
                r.event,
                r.first,
                r.last,
                r.reaction(),
                r.freshness(),
                r.event_reaction(),
                r.event_freshness(),
            ];
            let _ = write!(out, "{label},{}", r.sample);
            for v in cells {
                out.push(',');
                if let Some(v) = v {
                    let _ = write!(out, "{v}");
                }
            }
            out.push('\n');
        }
    }
    out
}

/// A CSV field (RFC 4180): quoted when it holds a comma, quote or newline.
fn quoted(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_with_commas_or_quotes_are_quoted() {
        assert_eq!(quoted("gyro→pwm"), "gyro→pwm");
        assert_eq!(quoted("a,b"), "\"a,b\"");
        assert_eq!(quoted("say \"hi\""), "\"say \"\"hi\"\"\"");
    }
}
