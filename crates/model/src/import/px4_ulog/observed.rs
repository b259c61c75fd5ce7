//! The measured data ages: one row per logged message that carries
//! `timestamp_sample`, on a topic where a chain of the spec ends.

use super::{Ulog, UlogError};
use std::fmt::Write as _;

/// `observed.csv`'s header; `analyze --observed` reads files with it.
pub const OBSERVED_HEADER: &str = "chain,topic,timestamp_ns,timestamp_sample_ns,data_age_ns";

/// One logged message: its chain, topic and times (ns).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObservedRow {
    /// The spec's chain that ends at the topic.
    pub chain: String,
    /// The uORB topic.
    pub topic: String,
    /// Publication instant, ns since boot.
    pub timestamp_ns: u64,
    /// The gyro sample's instant, ns since boot.
    pub timestamp_sample_ns: u64,
}

impl ObservedRow {
    /// `timestamp − timestamp_sample`.
    pub fn data_age_ns(&self) -> u64 {
        self.timestamp_ns - self.timestamp_sample_ns
    }
}

/// The rows of `topic` (instance 0) for `chain`; `Ok(None)` when the log
/// has no such topic with both stamps. A sample stamped after its message
/// is refused: it would be a negative age.
pub(super) fn rows(
    log: &Ulog,
    topic: &str,
    chain: &str,
) -> Result<Option<Vec<ObservedRow>>, UlogError> {
    let Some(sub) = log.topic(topic, 0) else {
        return Ok(None);
    };
    let (Some(ts), Some(samples)) = (
        log.u64_values(sub, "timestamp"),
        log.u64_values(sub, "timestamp_sample"),
    ) else {
        return Ok(None);
    };
    let mut out = Vec::with_capacity(ts.len());
    for (k, (&t, &s)) in ts.iter().zip(&samples).enumerate() {
        if s > t || t > u64::MAX / 1000 {
            return Err(UlogError {
                offset: 0,
                message_type: Some(b'D'),
                problem: format!(
                    "{topic} message {k}: timestamp {t} µs is before its timestamp_sample {s} µs (or too large); a sample cannot be younger than its message"
                ),
            });
        }
        out.push(ObservedRow {
            chain: chain.to_string(),
            topic: topic.to_string(),
            timestamp_ns: t * 1000,
            timestamp_sample_ns: s * 1000,
        });
    }
    Ok((!out.is_empty()).then_some(out))
}

/// The rows as CSV text with [`OBSERVED_HEADER`].
pub(super) fn to_csv(rows: &[ObservedRow]) -> String {
    let mut s = String::with_capacity(64 * (rows.len() + 1));
    s.push_str(OBSERVED_HEADER);
    s.push('\n');
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{}",
            crate::output::csv_field(&r.chain),
            crate::output::csv_field(&r.topic),
            r.timestamp_ns,
            r.timestamp_sample_ns,
            r.data_age_ns()
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::csv_field;

    #[test]
    fn chain_names_are_quoted_when_they_need_it() {
        assert_eq!(csv_field("gyro to x"), "gyro to x");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        let r = ObservedRow {
            chain: "c,1".into(),
            topic: "t".into(),
            timestamp_ns: 5000,
            timestamp_sample_ns: 1000,
        };
        assert_eq!(
            to_csv(&[r]),
            format!("{OBSERVED_HEADER}\n\"c,1\",t,5000,1000,4000\n")
        );
    }
}
