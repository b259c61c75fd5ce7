//! A shard's rows as one Parquet file (`rtpipe_parquet`, which holds the
//! Parquet writer so that an edit to the analysis does not compile it
//! again), written a row group at a time into a temporary beside its
//! target and renamed into place (`rtpipe_model::output`), with the
//! campaign's fingerprint, the shard's index and its systems in the
//! footer; and the footer read back, to tell a complete shard of this
//! campaign from anything else. The directory's configuration file is
//! Parquet too (`_campaign.parquet`, no rows, the shards' columns, the
//! configuration in its footer): a folder of Parquet files only is what
//! every reader takes as it is (polars refuses a directory that mixes file
//! types).

use crate::system::Row;
use rtpipe_parquet::{Footer, TableWriter};
use rtpipe_printer::Table;
use std::path::Path;

/// Rows per row group: a shard is written a row group at a time, so a
/// run holds at most about this many rows (plus the systems in flight),
/// whatever the shard's size.
pub const ROW_GROUP_ROWS: usize = 16_384;

/// The Parquet schema's message name.
const MESSAGE: &str = "rtpipe_campaign";

/// Key-value metadata keys of a shard's footer: the campaign's
/// [`Config::fingerprint`](crate::Config::fingerprint), the shard's index
/// and its systems (`first..last`).
pub(crate) const KEY_CAMPAIGN: &str = "rtpipe.campaign";
pub(crate) const KEY_SHARD: &str = "rtpipe.shard";
pub(crate) const KEY_SYSTEMS: &str = "rtpipe.systems";
/// The key of the configuration's text in `_campaign.parquet`'s footer.
pub(crate) const KEY_CONFIG: &str = "rtpipe.config";

/// What a shard's footer says it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ShardMeta {
    pub campaign: String,
    pub shard: u64,
    pub systems: std::ops::Range<u64>,
}

impl ShardMeta {
    pub fn key_values(&self) -> [(&'static str, String); 3] {
        let (a, b) = (self.systems.start, self.systems.end);
        [
            (KEY_CAMPAIGN, self.campaign.clone()),
            (KEY_SHARD, self.shard.to_string()),
            (KEY_SYSTEMS, format!("{a}..{b}")),
        ]
    }

    /// The metadata of a footer; `None` when a key is missing or malformed
    /// (not a shard rtpipe wrote).
    fn from_footer(footer: &Footer) -> Option<ShardMeta> {
        let (a, b) = footer.get(KEY_SYSTEMS)?.split_once("..")?;
        Some(ShardMeta {
            campaign: footer.get(KEY_CAMPAIGN)?.to_string(),
            shard: footer.get(KEY_SHARD)?.parse().ok()?,
            systems: a.parse().ok()?..b.parse().ok()?,
        })
    }
}

/// The rows as a table of the row description ([`crate::columns`]).
fn table(rows: &[Row]) -> Table {
    let mut table = crate::columns::table();
    for r in rows {
        table.push(r.cells());
    }
    table
}

/// A shard file being written, a row group at a time, into `file` (the
/// temporary [`rtpipe_model::output::write_atomically`] hands over).
pub(crate) struct ShardWriter<'f> {
    writer: TableWriter<'f>,
}

impl<'f> ShardWriter<'f> {
    /// A file whose footer holds `key_values` (a shard's
    /// [`ShardMeta::key_values`], or the configuration of [`write_kept`]).
    pub fn new(
        file: &'f mut std::fs::File,
        key_values: &[(&'static str, String)],
    ) -> std::io::Result<Self> {
        let columns = crate::columns::columns();
        let writer = TableWriter::new(file, MESSAGE, &columns, "rtpipe campaign", key_values)?;
        Ok(ShardWriter { writer })
    }

    /// Writes `rows` as one row group (none when empty).
    pub fn row_group(&mut self, rows: &[Row]) -> std::io::Result<()> {
        self.writer.row_group(&table(rows))
    }

    /// Writes the footer and flushes the file (the caller syncs it).
    pub fn finish(self) -> std::io::Result<()> {
        self.writer.finish()
    }
}

/// The footer of the regular file `path`: its metadata and row count, or
/// why it is not a complete shard rtpipe wrote (unreadable, truncated, not
/// Parquet, no rtpipe metadata).
pub(crate) fn read_footer(path: &Path) -> Result<(ShardMeta, u64), String> {
    let footer = rtpipe_parquet::read_footer(path)?;
    let shard = ShardMeta::from_footer(&footer)
        .ok_or_else(|| "is Parquet without a campaign's metadata".to_string())?;
    Ok((shard, footer.rows))
}

/// Writes a directory's `_campaign.parquet` into `file`: the shards'
/// columns and no rows, so readers that take every Parquet file of a
/// folder (polars) read it as nothing and those that skip `_` names
/// (pyarrow, pandas) never open it; the footer holds the fingerprint and
/// the configuration's text.
pub(crate) fn write_kept(
    file: &mut std::fs::File,
    fingerprint: &str,
    config_text: &str,
) -> std::io::Result<()> {
    let key_values = [
        (KEY_CAMPAIGN, fingerprint.to_string()),
        (KEY_CONFIG, config_text.to_string()),
    ];
    ShardWriter::new(file, &key_values)?.finish()
}

/// The configuration text in the footer of the regular file `path` (a
/// `_campaign.parquet`), or why it is not one rtpipe wrote.
pub(crate) fn read_kept(path: &Path) -> Result<String, String> {
    let footer = rtpipe_parquet::read_footer(path)?;
    footer
        .get(KEY_CONFIG)
        .map(str::to_string)
        .ok_or_else(|| format!("is Parquet without a campaign configuration (`{KEY_CONFIG}`)"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::Observed;
    use rtpipe_analysis::{Anchor, Bound, Metric};

    fn row() -> Row {
        Row {
            system: 7,
            seed: u64::MAX,
            tasks: 5,
            cpus: 1,
            chains: 2,
            utilization_target: 0.5,
            utilization: 0.49,
            schedulable: true,
            chain: 1,
            chain_tasks: 3,
            metric: Metric::Freshness,
            bounds: Bound::ALL.map(|b| Anchor::ALL.map(|a| Some(10 * b as i64 + a as i64))),
            offsets: [Some(1), None],
            observed: Some(Observed {
                max: [Some(4), Some(5)],
                count: 9,
                over_bound: 0,
            }),
        }
    }

    /// A shard of `rows` written and its footer read back.
    fn written(rows: &[Row]) -> (rtpipe_parquet::Footer, ShardMeta) {
        let file = rtpipe_testkit::Scratch::new("campaign-parquet-out").within("s.parquet");
        let mut f = std::fs::File::create(&file).expect("a file");
        let meta = ShardMeta {
            campaign: "abc".into(),
            shard: 3,
            systems: 6..8,
        };
        let mut w = ShardWriter::new(&mut f, &meta.key_values()).expect("a writer");
        w.row_group(rows).expect("a row group");
        w.finish().expect("the footer");
        drop(f);
        let footer = rtpipe_parquet::read_footer(&file).expect("a footer");
        let (read, rows) = read_footer(&file).expect("a shard's footer");
        assert_eq!(rows, footer.rows);
        (footer, read)
    }

    #[test]
    fn every_bound_and_anchor_reaches_parquet() {
        let (footer, meta) = written(&[row(), row()]);
        assert_eq!(footer.rows, 2);
        assert_eq!(
            (meta.campaign.as_str(), meta.shard, meta.systems),
            ("abc", 3, 6..8)
        );
        let names = footer.columns;
        assert_eq!(names, crate::columns::names());
        for a in ["", "event_"] {
            for b in Bound::ALL {
                let n = format!("{a}{}_ns", b.name());
                assert!(names.contains(&n), "{n} missing from {names:?}");
            }
        }
        // A cell per column, its value where the name says.
        let t = table(&[row()]);
        let at = names.iter().position(|n| n == "event_duerr_ns");
        assert_eq!(
            at.map(|i| &t.rows()[0][i]),
            Some(&rtpipe_printer::Cell::Int(31))
        );
    }

    #[test]
    fn the_csv_of_the_rows_has_the_parquet_columns() {
        let mut t = crate::columns::table();
        t.push(row().cells());
        let csv = rtpipe_printer::csv::table(&t);
        let mut lines = csv.lines();
        assert_eq!(
            lines.next(),
            Some(crate::columns::names().join(",").as_str())
        );
        let first = lines.next().unwrap_or_default();
        assert!(first.starts_with("7,18446744073709551615,5,1,2,0.5,0.49,true,1,3,freshness,0,10,20,30,1,11,21,31,1,,4,5,9,0,true"), "{first}");
    }
}
