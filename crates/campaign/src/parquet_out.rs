//! A shard's rows as one Parquet file (Snappy), written a row group at a
//! time into a temporary beside its target and renamed into place
//! (`rtpipe_model::output`), with the campaign's fingerprint, the shard's
//! index and its systems in the footer; and the footer read back, to tell
//! a complete shard of this campaign from anything else.

use crate::system::Row;
use parquet::basic::Compression;
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int32Type, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::{SerializedColumnWriter, SerializedFileWriter};
use parquet::schema::parser::parse_message_type;
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

/// The columns, in file order (the Parquet schema and [`columns`] follow
/// it): bounds are `{paper,sound,davare,duerr}_ns` from the read and
/// `event_*` from the event; `offsets_*` under the known offsets;
/// `observed_*` from the simulation.
pub const COLUMNS: [&str; 26] = [
    "system",
    "seed",
    "tasks",
    "cpus",
    "chains",
    "utilization_target",
    "utilization",
    "schedulable",
    "chain",
    "chain_tasks",
    "metric",
    "paper_ns",
    "sound_ns",
    "davare_ns",
    "duerr_ns",
    "event_paper_ns",
    "event_sound_ns",
    "event_davare_ns",
    "event_duerr_ns",
    "offsets_ns",
    "event_offsets_ns",
    "observed_max_ns",
    "event_observed_max_ns",
    "observed_count",
    "observed_over_bound",
    "simulated",
];

fn columns(rows: &[Row]) -> Vec<Values> {
    let u64s = |f: fn(&Row) -> u64| Values::U64(rows.iter().map(|r| f(r) as i64).collect());
    let i32s = |f: fn(&Row) -> u32| Values::I32(rows.iter().map(|r| f(r) as i32).collect());
    let ns = |f: &dyn Fn(&Row) -> Option<i64>| Values::Ns(rows.iter().map(f).collect());
    let mut out = vec![
        u64s(|r| r.system),
        u64s(|r| r.seed),
        i32s(|r| r.tasks),
        i32s(|r| r.cpus),
        i32s(|r| r.chains),
        Values::F64(rows.iter().map(|r| r.utilization_target).collect()),
        Values::F64(rows.iter().map(|r| r.utilization).collect()),
        Values::Bool(rows.iter().map(|r| r.schedulable).collect()),
        i32s(|r| r.chain),
        i32s(|r| r.chain_tasks),
        Values::Str(
            rows.iter()
                .map(|r| ByteArray::from(r.metric.name()))
                .collect(),
        ),
    ];
    for a in 0..2 {
        for b in 0..4 {
            out.push(ns(&move |r: &Row| r.bounds[b][a]));
        }
    }
    out.push(ns(&|r: &Row| r.offsets[0]));
    out.push(ns(&|r: &Row| r.offsets[1]));
    out.push(ns(&|r: &Row| r.observed.and_then(|o| o.max[0])));
    out.push(ns(&|r: &Row| r.observed.and_then(|o| o.max[1])));
    out.push(ns(&|r: &Row| r.observed.map(|o| o.count as i64)));
    out.push(ns(&|r: &Row| r.observed.map(|o| o.over_bound as i64)));
    out.push(Values::Bool(
        rows.iter().map(|r| r.observed.is_some()).collect(),
    ));
    assert_eq!(out.len(), COLUMNS.len(), "one value list per column");
    out
}

fn schema(cols: &[Values]) -> String {
    let fields: Vec<String> = cols
        .iter()
        .zip(COLUMNS)
        .map(|(v, name)| format!("  {};", v.schema_type().replace("{}", name)))
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

/// What a shard's footer says it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ShardMeta {
    pub campaign: String,
    pub shard: u64,
    pub systems: std::ops::Range<u64>,
}

impl ShardMeta {
    fn key_values(&self) -> Vec<KeyValue> {
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
    pub fn new(file: &'f mut std::fs::File, meta: &ShardMeta) -> std::io::Result<Self> {
        let schema = Arc::new(parse_message_type(&schema(&columns(&[]))).map_err(io)?);
        let props = Arc::new(
            WriterProperties::builder()
                .set_compression(Compression::SNAPPY)
                .set_created_by("rtpipe campaign".into())
                .set_key_value_metadata(Some(meta.key_values()))
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
