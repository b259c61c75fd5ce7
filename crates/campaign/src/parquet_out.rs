//! A shard's rows as one Parquet file (Snappy), written a row group at a
//! time into a temporary beside its target and renamed into place
//! (`rtpipe_model::output`), with the campaign's fingerprint, the shard's
//! index and its systems in the footer; and the footer read back, to tell
//! a complete shard of this campaign from anything else. The directory's
//! configuration file is Parquet too (`_campaign.parquet`, no rows, the
//! shards' columns, the configuration in its footer): a folder of Parquet
//! files only is what every reader takes as it is (polars refuses a
//! directory that mixes file types).

use crate::system::Row;
use parquet::basic::Compression;
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int32Type, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::{SerializedColumnWriter, SerializedFileWriter};
use parquet::schema::parser::parse_message_type;
use rtpipe_printer::{Cell, Kind};
use std::path::Path;
use std::sync::Arc;

/// A column's values.
enum Values {
    U64(Vec<i64>),
    I32(Vec<i32>),
    F64(Vec<f64>),
    Bool(Vec<bool>),
    Str(Vec<ByteArray>),
    /// Nanoseconds, `None` where there is no value.
    Ns(Vec<Option<i64>>),
}

impl Values {
    fn schema_type(&self) -> &'static str {
        match self {
            Values::U64(_) => "REQUIRED INT64 {} (INTEGER(64,false))",
            Values::I32(_) => "REQUIRED INT32 {}",
            Values::F64(_) => "REQUIRED DOUBLE {}",
            Values::Bool(_) => "REQUIRED BOOLEAN {}",
            Values::Str(_) => "REQUIRED BYTE_ARRAY {} (STRING)",
            Values::Ns(_) => "OPTIONAL INT64 {}",
        }
    }
}

impl Values {
    /// An empty list for a column of `kind`.
    fn of_kind(kind: Kind, rows: usize) -> Values {
        match kind {
            Kind::UInt => Values::U64(Vec::with_capacity(rows)),
            Kind::Count => Values::I32(Vec::with_capacity(rows)),
            Kind::Float => Values::F64(Vec::with_capacity(rows)),
            Kind::Bool => Values::Bool(Vec::with_capacity(rows)),
            Kind::Text => Values::Str(Vec::with_capacity(rows)),
            Kind::Int | Kind::OptInt => Values::Ns(Vec::with_capacity(rows)),
        }
    }

    /// Adds a cell (its kind was checked by `Table::push`).
    fn push(&mut self, cell: &Cell) {
        match (self, cell) {
            // Stored as INT64 with the unsigned annotation: the bits as
            // they are.
            (Values::U64(v), Cell::UInt(x)) => v.push(*x as i64),
            (Values::I32(v), Cell::UInt(x)) => v.push(i32::try_from(*x).unwrap_or(i32::MAX)),
            (Values::F64(v), Cell::Float(x)) => v.push(*x),
            (Values::Bool(v), Cell::Bool(x)) => v.push(*x),
            (Values::Str(v), Cell::Text(x)) => v.push(ByteArray::from(x.as_str())),
            (Values::Ns(v), Cell::Int(x)) => v.push(Some(*x)),
            (Values::Ns(v), Cell::Empty) => v.push(None),
            (_, c) => unreachable!("a {c:?} cell in a column of another kind"),
        }
    }
}

/// The rows' values, a list per column of the row description
/// ([`crate::columns`]).
fn columns(rows: &[Row]) -> Vec<Values> {
    let mut table = crate::columns::table();
    for r in rows {
        table.push(r.cells());
    }
    let mut out: Vec<Values> = (table.columns().iter())
        .map(|c| Values::of_kind(c.kind, rows.len()))
        .collect();
    for row in table.rows() {
        for (values, cell) in out.iter_mut().zip(row) {
            values.push(cell);
        }
    }
    out
}

fn schema(cols: &[Values]) -> String {
    let fields: Vec<String> = cols
        .iter()
        .zip(crate::columns::names())
        .map(|(v, name)| format!("  {};", v.schema_type().replace("{}", &name)))
        .collect();
    format!("message rtpipe_campaign {{\n{}\n}}", fields.join("\n"))
}

/// Rows per row group: a shard is written a row group at a time, so a
/// run holds at most about this many rows (plus the systems in flight),
/// whatever the shard's size.
pub const ROW_GROUP_ROWS: usize = 16_384;

/// Key-value metadata keys of a shard's footer: the campaign's
/// [`Config::fingerprint`](crate::Config::fingerprint), the shard's index
/// and its systems (`first..last`).
pub(crate) const KEY_CAMPAIGN: &str = "rtpipe.campaign";
pub(crate) const KEY_SHARD: &str = "rtpipe.shard";
pub(crate) const KEY_SYSTEMS: &str = "rtpipe.systems";
/// The key of `_campaign.parquet`'s footer that holds the configuration's
/// text as it was given (comments included).
pub(crate) const KEY_CONFIG: &str = "rtpipe.config";

/// What a shard's footer says it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ShardMeta {
    pub campaign: String,
    pub shard: u64,
    pub systems: std::ops::Range<u64>,
}

impl ShardMeta {
    pub fn key_values(&self) -> Vec<KeyValue> {
        let (a, b) = (self.systems.start, self.systems.end);
        vec![
            KeyValue::new(KEY_CAMPAIGN.into(), self.campaign.clone()),
            KeyValue::new(KEY_SHARD.into(), self.shard.to_string()),
            KeyValue::new(KEY_SYSTEMS.into(), format!("{a}..{b}")),
        ]
    }

    /// The metadata of a footer's key-value pairs; `None` when one is
    /// missing or malformed (not a shard rtpipe wrote).
    fn from_key_values(kv: &[KeyValue]) -> Option<ShardMeta> {
        let get = |key: &str| {
            kv.iter()
                .find(|p| p.key == key)
                .and_then(|p| p.value.clone())
        };
        let systems = get(KEY_SYSTEMS)?;
        let (a, b) = systems.split_once("..")?;
        Some(ShardMeta {
            campaign: get(KEY_CAMPAIGN)?,
            shard: get(KEY_SHARD)?.parse().ok()?,
            systems: a.parse().ok()?..b.parse().ok()?,
        })
    }
}

/// A shard file being written, a row group at a time, into `file` (the
/// temporary [`rtpipe_model::output::write_atomically`] hands over).
pub(crate) struct ShardWriter<'f> {
    writer: SerializedFileWriter<std::io::BufWriter<&'f mut std::fs::File>>,
}

impl<'f> ShardWriter<'f> {
    /// A file whose footer holds `key_values` (a shard's [`ShardMeta`],
    /// or the configuration of [`write_kept`]).
    pub fn new(file: &'f mut std::fs::File, key_values: Vec<KeyValue>) -> std::io::Result<Self> {
        let schema = Arc::new(parse_message_type(&schema(&columns(&[]))).map_err(io)?);
        let props = Arc::new(
            WriterProperties::builder()
                .set_compression(Compression::SNAPPY)
                .set_created_by("rtpipe campaign".into())
                .set_key_value_metadata(Some(key_values))
                .build(),
        );
        let buffered = std::io::BufWriter::new(file);
        let writer = SerializedFileWriter::new(buffered, schema, props).map_err(io)?;
        Ok(ShardWriter { writer })
    }

    /// Writes `rows` as one row group (none when empty).
    pub fn row_group(&mut self, rows: &[Row]) -> std::io::Result<()> {
        if rows.is_empty() {
            return Ok(());
        }
        let mut group = self.writer.next_row_group().map_err(io)?;
        for values in &columns(rows) {
            let Some(col) = group.next_column().map_err(io)? else {
                unreachable!("the schema has a column per value list");
            };
            write_column(col, values).map_err(io)?;
        }
        group.close().map_err(io)?;
        Ok(())
    }

    /// Writes the footer and flushes the file (the caller syncs it).
    pub fn finish(self) -> std::io::Result<()> {
        let buffered = self.writer.into_inner().map_err(io)?;
        buffered.into_inner().map_err(|e| e.into_error())?;
        Ok(())
    }
}

fn io(e: parquet::errors::ParquetError) -> std::io::Error {
    std::io::Error::other(e)
}

/// The footer of the regular file `path`: its metadata and row count, or
/// why it is not a complete shard rtpipe wrote (unreadable, truncated, not
/// Parquet, no rtpipe metadata).
pub(crate) fn read_footer(path: &Path) -> Result<(ShardMeta, u64), String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be opened: {e}"))?;
    let reader =
        SerializedFileReader::new(file).map_err(|e| format!("has no Parquet footer ({e})"))?;
    let meta = reader.metadata().file_metadata();
    let kv = meta.key_value_metadata().map_or(&[][..], Vec::as_slice);
    let shard = ShardMeta::from_key_values(kv)
        .ok_or_else(|| "is Parquet without a campaign's metadata".to_string())?;
    let rows =
        u64::try_from(meta.num_rows()).map_err(|_| "has a negative row count".to_string())?;
    Ok((shard, rows))
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
    let key_values = vec![
        KeyValue::new(KEY_CAMPAIGN.into(), fingerprint.to_string()),
        KeyValue::new(KEY_CONFIG.into(), config_text.to_string()),
    ];
    ShardWriter::new(file, key_values)?.finish()
}

/// The configuration text in the footer of the regular file `path` (a
/// `_campaign.parquet`), or why it is not one rtpipe wrote.
pub(crate) fn read_kept(path: &Path) -> Result<String, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be opened: {e}"))?;
    let reader =
        SerializedFileReader::new(file).map_err(|e| format!("has no Parquet footer ({e})"))?;
    let meta = reader.metadata().file_metadata();
    (meta.key_value_metadata().into_iter().flatten())
        .find(|p| p.key == KEY_CONFIG)
        .and_then(|p| p.value.clone())
        .ok_or_else(|| format!("is Parquet without a campaign configuration (`{KEY_CONFIG}`)"))
}

fn write_column(
    mut col: SerializedColumnWriter<'_>,
    values: &Values,
) -> parquet::errors::Result<()> {
    match values {
        Values::U64(v) => col.typed::<Int64Type>().write_batch(v, None, None)?,
        Values::I32(v) => col.typed::<Int32Type>().write_batch(v, None, None)?,
        Values::F64(v) => col.typed::<DoubleType>().write_batch(v, None, None)?,
        Values::Bool(v) => col.typed::<BoolType>().write_batch(v, None, None)?,
        Values::Str(v) => col.typed::<ByteArrayType>().write_batch(v, None, None)?,
        Values::Ns(v) => {
            let present: Vec<i64> = v.iter().flatten().copied().collect();
            let levels: Vec<i16> = v.iter().map(|x| i16::from(x.is_some())).collect();
            col.typed::<Int64Type>()
                .write_batch(&present, Some(&levels), None)?
        }
    };
    col.close()
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

    /// The Parquet schema's field names, in order.
    fn schema_names() -> Vec<String> {
        let text = schema(&columns(&[]));
        let Ok(t) = parse_message_type(&text) else {
            panic!("the schema parses: {text}");
        };
        t.get_fields()
            .iter()
            .map(|f| f.name().to_string())
            .collect()
    }

    #[test]
    fn every_bound_and_anchor_reaches_parquet() {
        let names = schema_names();
        assert_eq!(names, crate::columns::names());
        for a in ["", "event_"] {
            for b in Bound::ALL {
                let n = format!("{a}{}_ns", b.name());
                assert!(names.contains(&n), "{n} missing from {names:?}");
            }
        }
        // A value list per column, each as long as the rows.
        let values = columns(&[row(), row()]);
        assert_eq!(values.len(), names.len());
        let Values::Ns(event_duerr) = &values[names
            .iter()
            .position(|n| n == "event_duerr_ns")
            .unwrap_or(0)]
        else {
            panic!("bounds are optional nanoseconds");
        };
        assert_eq!(event_duerr, &[Some(31), Some(31)]);
    }

    #[test]
    fn the_csv_of_the_rows_has_the_parquet_columns() {
        let mut t = crate::columns::table();
        t.push(row().cells());
        let csv = rtpipe_printer::csv::table(&t);
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some(schema_names().join(",").as_str()));
        let first = lines.next().unwrap_or_default();
        assert!(first.starts_with("7,18446744073709551615,5,1,2,0.5,0.49,true,1,3,freshness,0,10,20,30,1,11,21,31,1,,4,5,9,0,true"), "{first}");
    }
}
