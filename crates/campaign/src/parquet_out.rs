//! A shard's rows as one Parquet file (one row group, Snappy), written
//! beside its target and renamed into place.

use crate::system::Row;
use crate::Error;
use parquet::basic::Compression;
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int32Type, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::writer::{SerializedColumnWriter, SerializedFileWriter};
use parquet::schema::parser::parse_message_type;
use std::io::Write;
use std::path::{Path, PathBuf};
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
pub const COLUMNS: [&str; 25] = [
    "system",
    "seed",
    "tasks",
    "cpus",
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

/// Writes `rows` as the Parquet file `path`, whole or not at all.
pub(crate) fn write_atomically(path: &Path, rows: &[Row]) -> Result<(), Error> {
    let tmp = temp_beside(path);
    let written = write(&tmp, rows)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io("rename into", path, &e)));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// Writes `bytes` as `path`, whole or not at all.
pub(crate) fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let tmp = temp_beside(path);
    let written = std::fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()))
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| Error::io("write", path, &e));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

fn temp_beside(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

fn write(path: &Path, rows: &[Row]) -> Result<(), Error> {
    let fail = |e: &dyn std::fmt::Display| Error::io("write", path, e);
    let cols = columns(rows);
    let schema = Arc::new(parse_message_type(&schema(&cols)).map_err(|e| fail(&e))?);
    let props = Arc::new(
        WriterProperties::builder()
            .set_compression(Compression::SNAPPY)
            .set_created_by("rtpipe campaign".into())
            .build(),
    );
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut w = SerializedFileWriter::new(file, schema, props).map_err(|e| fail(&e))?;
    if !rows.is_empty() {
        let mut group = w.next_row_group().map_err(|e| fail(&e))?;
        for values in &cols {
            let Some(col) = group.next_column().map_err(|e| fail(&e))? else {
                unreachable!("the schema has a column per value list");
            };
            write_column(col, values).map_err(|e| fail(&e))?;
        }
        group.close().map_err(|e| fail(&e))?;
    }
    let file = w.into_inner().map_err(|e| fail(&e))?;
    file.sync_all().map_err(|e| fail(&e))
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
