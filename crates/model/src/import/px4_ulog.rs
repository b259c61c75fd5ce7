//! PX4 flight logs (ULog) as rtpipe specs and measured data ages
//! (`rtpipe import px4-ulog LOG.ulg OUTDIR`).
//!
//! [`load`] reads a log ([`read`]: the format, every message checked);
//! [`import`] builds from it the spec (`spec.rs`: threads and priorities
//! from `perf_top_*` or PX4's source, what the log says of its system in
//! `facts.rs`, modules and their execution times from `perf_counter_*` or
//! another log's, the module → work-queue table of the PX4 versions
//! covered in `px4.rs`) and the observed data ages (`observed.rs`). Nothing
//! here writes a file: the caller writes both, all or none.

mod facts;
mod observed;
mod perf;
mod px4;
mod read;
mod spec;
#[cfg(test)]
mod tests;

use crate::input::{self, Kind, Syntax};
use crate::Diagnostic;
use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::Path;

pub use observed::{ObservedRow, OBSERVED_HEADER};
pub use spec::{import, ExecFrom, Import, Options, TopicAges};

/// The largest log read: 512 MiB (a long flight at a high logging rate).
pub const MAX_BYTES: u64 = 512 << 20;

/// A problem with a log: where (byte offset, and the type of the message
/// there, when one was being read) and what was expected.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UlogError {
    /// Byte offset in the file of the message (or header) at fault.
    pub offset: usize,
    /// The message type byte (`b'D'`, `b'F'`, ...), when a message was read.
    pub message_type: Option<u8>,
    /// What was expected and found.
    pub problem: String,
}

impl fmt::Display for UlogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "byte {}", self.offset)?;
        match self.message_type {
            Some(t) if t.is_ascii_graphic() => write!(f, ", message '{}'", t as char)?,
            Some(t) => write!(f, ", message type 0x{t:02x}")?,
            None => {}
        }
        write!(f, ": {}", self.problem)
    }
}

impl UlogError {
    /// The error as a diagnostic, with how to fix it.
    pub fn diagnostic(&self) -> Diagnostic {
        Diagnostic::error(
            format!("not a readable ULog file: {self}"),
            "give a PX4 log (.ulg) as the logger wrote it; a log cut short can be read again after `ulog_info` (pyulog) shows it whole",
        )
    }
}

/// The basic types of ULog fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum FieldType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Char,
}

impl FieldType {
    /// The type named `name` in a format, if basic.
    pub fn of(name: &str) -> Option<FieldType> {
        use FieldType::*;
        Some(match name {
            "int8_t" => I8,
            "uint8_t" => U8,
            "int16_t" => I16,
            "uint16_t" => U16,
            "int32_t" => I32,
            "uint32_t" => U32,
            "int64_t" => I64,
            "uint64_t" => U64,
            "float" => F32,
            "double" => F64,
            "bool" => Bool,
            "char" => Char,
            _ => return None,
        })
    }

    /// Its size in bytes.
    pub fn size(self) -> usize {
        use FieldType::*;
        match self {
            I8 | U8 | Bool | Char => 1,
            I16 | U16 => 2,
            I32 | U32 | F32 => 4,
            I64 | U64 | F64 => 8,
        }
    }

    /// The value of `b` (exactly [`FieldType::size`] bytes) as a number.
    fn number(self, b: &[u8]) -> f64 {
        use FieldType::*;
        let mut a = [0u8; 8];
        a[..b.len()].copy_from_slice(b);
        match self {
            I8 => f64::from(b[0] as i8),
            U8 | Bool | Char => f64::from(b[0]),
            I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            I64 => i64::from_le_bytes(a) as f64,
            U64 => u64::from_le_bytes(a) as f64,
            F64 => f64::from_le_bytes(a),
        }
    }
}

/// One basic field of a subscription, nested formats flattened
/// (`parent.child`, `array[2]`); a `char` array is one field of `len` bytes.
#[derive(Debug, Clone)]
pub struct Field {
    /// The flattened name.
    pub name: String,
    /// Its type.
    pub ty: FieldType,
    /// Byte offset in a data message (after the message id).
    pub offset: usize,
    /// Elements (1 except for a `char` array).
    pub len: usize,
}

/// An info message's or parameter's value.
#[derive(Debug, Clone, PartialEq)]
pub struct Value {
    /// Its type.
    pub ty: FieldType,
    /// Its bytes.
    pub bytes: Vec<u8>,
}

impl Value {
    /// A number (the first element of an array); NaN for an empty array
    /// (a key may be `int32_t[0] name`).
    pub fn number(&self) -> f64 {
        match self.bytes.get(..self.ty.size()) {
            Some(b) => self.ty.number(b),
            None => f64::NAN,
        }
    }

    /// A `char` array as text.
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.bytes)
            .trim_end_matches('\0')
            .to_string()
    }
}

/// One subscription (`A` message): a topic instance and its data messages.
#[derive(Debug, Clone)]
pub struct Subscription {
    /// The format (topic) name.
    pub name: String,
    /// The instance.
    pub multi_id: u8,
    /// Its fields, padding left out.
    pub fields: Vec<Field>,
    /// The smallest data message (trailing padding may be left out).
    pub min_size: usize,
    /// The format's size.
    pub size: usize,
    /// Each data message's fields, as a range of the file's bytes.
    payloads: Vec<Range<usize>>,
}

impl Subscription {
    /// Data messages logged.
    pub fn len(&self) -> usize {
        self.payloads.len()
    }

    /// No data message was logged.
    pub fn is_empty(&self) -> bool {
        self.payloads.is_empty()
    }

    /// The field named `name`.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }
}

/// A read log: its info, parameters and subscriptions; the data stay in
/// the file's bytes.
#[derive(Debug, Clone, Default)]
pub struct Ulog {
    /// The header's timestamp (µs).
    pub start_timestamp_us: u64,
    /// Info messages (`I`), the first of each key.
    pub info: BTreeMap<String, Value>,
    /// Info-multiple messages (`M`): per key, each message with its
    /// continuations, as text.
    pub info_multiple: BTreeMap<String, Vec<Vec<String>>>,
    /// Parameters (`P`): the initial value of each.
    pub parameters: BTreeMap<String, Value>,
    /// Subscriptions in the order of their `A` messages.
    pub subscriptions: Vec<Subscription>,
    /// Dropout messages (`O`).
    pub dropouts: usize,
    bytes: Vec<u8>,
}

impl Ulog {
    /// Reads a log held in memory.
    pub fn parse(bytes: Vec<u8>) -> Result<Ulog, UlogError> {
        read::parse(bytes)
    }

    /// The subscription of `topic` instance `multi_id`.
    pub fn topic(&self, topic: &str, multi_id: u8) -> Option<&Subscription> {
        self.subscriptions
            .iter()
            .find(|s| s.name == topic && s.multi_id == multi_id)
    }

    /// An info message as text (`ver_sw`, `ver_hw`, ...).
    pub fn info_text(&self, key: &str) -> Option<String> {
        self.info.get(key).map(|v| match v.ty {
            FieldType::Char => v.text(),
            _ => format!("{}", v.number()),
        })
    }

    /// Every value of an unsigned 64-bit field of `sub`, in log order.
    pub fn u64_values(&self, sub: &Subscription, field: &str) -> Option<Vec<u64>> {
        let f = sub.field(field).filter(|f| f.ty == FieldType::U64)?;
        Some(
            sub.payloads
                .iter()
                .map(|p| {
                    let at = p.start + f.offset;
                    let mut a = [0u8; 8];
                    a.copy_from_slice(&self.bytes[at..at + 8]);
                    u64::from_le_bytes(a)
                })
                .collect(),
        )
    }

    /// Every value of a numeric field of `sub`, in log order.
    pub fn values(&self, sub: &Subscription, field: &str) -> Option<Vec<f64>> {
        let f = sub.field(field).filter(|f| f.len == 1)?;
        let n = f.ty.size();
        Some(
            sub.payloads
                .iter()
                .map(|p| {
                    f.ty.number(&self.bytes[p.start + f.offset..p.start + f.offset + n])
                })
                .collect(),
        )
    }
}

/// Reads the log at `path` (a regular file of at most [`MAX_BYTES`]).
pub fn load(path: &Path) -> Result<Ulog, Diagnostic> {
    let kind = Kind {
        name: "log",
        max_bytes: MAX_BYTES,
        syntax: Syntax::Toml,
        help: "give a PX4 flight log (.ulg)",
    };
    let bytes = input::read_bytes(path, &kind).map_err(|e| {
        e.diagnostics
            .into_iter()
            .next()
            .unwrap_or_else(|| Diagnostic::error("cannot read the log", kind.help))
    })?;
    Ulog::parse(bytes).map_err(|e| e.diagnostic())
}
