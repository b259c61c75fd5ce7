//! # rtpipe-parquet
//!
//! A typed table ([`rtpipe_printer::Table`]) as one Parquet file (Snappy),
//! written a row group at a time into a file the caller opened (the
//! campaign's shards: a temporary that `rtpipe_model::output` renames into
//! place), with the caller's key-value metadata in the footer; and the
//! footer read back.
//!
//! A crate of its own so that the `parquet` crate's generic writers are
//! compiled once, here, and not again by every edit to the analysis the
//! campaign depends on (docs/architecture.md, "Building").
#![deny(missing_docs)]

use parquet::basic::Compression;
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int32Type, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::{SerializedColumnWriter, SerializedFileWriter};
use parquet::schema::parser::parse_message_type;
use rtpipe_printer::{Cell, Column, Kind, Table};
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
    /// The Parquet type of a column of `kind` (`{}` stands for its name).
    fn schema_type(kind: Kind) -> &'static str {
        match kind {
            Kind::UInt => "REQUIRED INT64 {} (INTEGER(64,false))",
            Kind::Count => "REQUIRED INT32 {}",
            Kind::Float => "REQUIRED DOUBLE {}",
            Kind::Bool => "REQUIRED BOOLEAN {}",
            Kind::Text => "REQUIRED BYTE_ARRAY {} (STRING)",
            Kind::Int | Kind::OptInt => "OPTIONAL INT64 {}",
        }
    }

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

/// The table's values, a list per column.
fn values(table: &Table) -> Vec<Values> {
    let mut out: Vec<Values> = (table.columns().iter())
        .map(|c| Values::of_kind(c.kind, table.rows().len()))
        .collect();
    for row in table.rows() {
        for (values, cell) in out.iter_mut().zip(row) {
            values.push(cell);
        }
    }
    out
}

/// The Parquet schema (message type) of a table named `name` with these
/// columns.
pub fn schema(name: &str, columns: &[Column]) -> String {
    let fields: Vec<String> = (columns.iter())
        .map(|c| format!("  {};", Values::schema_type(c.kind).replace("{}", &c.name)))
        .collect();
    format!("message {name} {{\n{}\n}}", fields.join("\n"))
}

/// A Parquet file being written, a row group at a time, into `file`.
pub struct TableWriter<'f> {
    writer: SerializedFileWriter<std::io::BufWriter<&'f mut std::fs::File>>,
}

impl<'f> TableWriter<'f> {
    /// Starts the file with the schema of `columns` (the message is named
    /// `name`); `created_by` and `key_values` go into the footer.
    pub fn new(
        file: &'f mut std::fs::File,
        name: &str,
        columns: &[Column],
        created_by: &str,
        key_values: &[(&str, String)],
    ) -> std::io::Result<Self> {
        let schema = Arc::new(parse_message_type(&schema(name, columns)).map_err(io)?);
        let kv = (key_values.iter())
            .map(|(k, v)| KeyValue::new((*k).to_string(), v.clone()))
            .collect();
        let props = Arc::new(
            WriterProperties::builder()
                .set_compression(Compression::SNAPPY)
                .set_created_by(created_by.into())
                .set_key_value_metadata(Some(kv))
                .build(),
        );
        let buffered = std::io::BufWriter::new(file);
        let writer = SerializedFileWriter::new(buffered, schema, props).map_err(io)?;
        Ok(TableWriter { writer })
    }

    /// Writes the table's rows as one row group (none when it has none).
    /// Its columns are those the writer was made with.
    pub fn row_group(&mut self, table: &Table) -> std::io::Result<()> {
        if table.rows().is_empty() {
            return Ok(());
        }
        let mut group = self.writer.next_row_group().map_err(io)?;
        for values in &values(table) {
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

/// What a Parquet file's footer holds that its writer chose.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Footer {
    /// The key-value metadata, in file order (a key without a value has
    /// `None`).
    pub key_values: Vec<(String, Option<String>)>,
    /// The rows of all row groups.
    pub rows: u64,
    /// The rows of each row group, in file order.
    pub row_groups: Vec<u64>,
    /// The schema's column names, in file order.
    pub columns: Vec<String>,
}

impl Footer {
    /// The value of `key`, if the footer has it with a value.
    pub fn get(&self, key: &str) -> Option<&str> {
        (self.key_values.iter())
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v.as_deref())
    }
}

/// The footer of the regular file `path`, or why it has none (unreadable,
/// truncated, not Parquet), as words that follow the file's name.
pub fn read_footer(path: &Path) -> Result<Footer, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be opened: {e}"))?;
    let reader =
        SerializedFileReader::new(file).map_err(|e| format!("has no Parquet footer ({e})"))?;
    let meta = reader.metadata().file_metadata();
    let kv = meta.key_value_metadata().map_or(&[][..], Vec::as_slice);
    let rows =
        u64::try_from(meta.num_rows()).map_err(|_| "has a negative row count".to_string())?;
    let row_groups = (reader.metadata().row_groups().iter())
        .map(|g| u64::try_from(g.num_rows()).unwrap_or(0))
        .collect();
    let columns = (meta.schema_descr().columns().iter())
        .map(|c| c.name().to_string())
        .collect();
    Ok(Footer {
        key_values: kv
            .iter()
            .map(|p| (p.key.clone(), p.value.clone()))
            .collect(),
        rows,
        row_groups,
        columns,
    })
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
mod tests;
