//! The ULog format (docs.px4.io, "ULog File Format"; the reference reader
//! is PX4/pyulog's `core.py`): a 16-byte header, then messages, each a
//! `u16` payload size, a `u8` type and the payload, little-endian.
//!
//! Every message is checked as it is read; a message that does not fit the
//! file, a format that does not parse, a data message of an unknown
//! subscription or of the wrong size is a [`UlogError`] naming the byte
//! offset, the message type and what was expected. Nothing is allocated
//! beyond a bounded multiple of the file's size: payloads stay in the file's
//! buffer, addressed by offset. Unknown message types are skipped, as the
//! format asks (their size is known); unknown incompatible flag bits refuse
//! the file, as the format asks too.

use super::{Field, FieldType, Subscription, Ulog, UlogError};
use std::collections::BTreeMap;
use std::ops::Range;

/// The magic bytes every ULog file begins with.
const MAGIC: &[u8; 7] = b"ULog\x01\x12\x35";

/// The header's size: magic, version, start timestamp.
const HEADER_BYTES: usize = 16;

/// Nested formats deeper than this are refused (a format that contains
/// itself would recurse forever).
const MAX_NESTING: usize = 16;

/// The most fields of all subscriptions together (a log's formats could
/// otherwise make a small file expand without bound).
const MAX_FIELDS: usize = 1 << 20;

/// The incompatible flag bit that says data was appended.
const INCOMPAT_DATA_APPENDED: u8 = 1;

/// A message's place and type while it is read, for errors.
#[derive(Clone, Copy)]
struct At {
    offset: usize,
    kind: u8,
}

impl At {
    fn err(self, expected: impl Into<String>) -> UlogError {
        UlogError {
            offset: self.offset,
            message_type: Some(self.kind),
            problem: expected.into(),
        }
    }
}

/// The state of a read: what the definitions said so far.
struct Reader<'a> {
    bytes: &'a [u8],
    /// Format name → its fields as written (`type name`, array size).
    formats: BTreeMap<String, Vec<RawField>>,
    /// Subscription id → index in `log.subscriptions`.
    ids: BTreeMap<u16, usize>,
    /// Fields of all subscriptions so far.
    fields_total: usize,
    log: Ulog,
}

/// One field of a format as written: its type name (a basic type or a
/// nested format), array length (`None`: not an array; info keys may be
/// `char[0]`, an empty string), name.
#[derive(Clone)]
struct RawField {
    type_name: String,
    array: Option<usize>,
    name: String,
}

/// Reads a whole ULog file held in `bytes`.
pub(super) fn parse(bytes: Vec<u8>) -> Result<Ulog, UlogError> {
    let start = read_header(&bytes)?;
    let mut r = Reader {
        bytes: &bytes,
        formats: BTreeMap::new(),
        ids: BTreeMap::new(),
        fields_total: 0,
        log: Ulog {
            start_timestamp_us: start,
            ..Ulog::default()
        },
    };
    let (appended, mut pos) = r.read_flags()?;
    // The data up to each appended offset, then from there: a write cut by
    // the append may leave a partial message before the offset.
    for &until in &appended {
        r.read_messages(pos, Some(until))?;
        pos = until;
    }
    r.read_messages(pos, None)?;
    let mut log = r.log;
    log.bytes = bytes;
    Ok(log)
}

/// The flag bits message's payload size.
const FLAG_PAYLOAD: usize = 40;

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

/// Checks the magic bytes; the log's start timestamp (µs).
fn read_header(bytes: &[u8]) -> Result<u64, UlogError> {
    let at = |problem: String| UlogError {
        offset: 0,
        message_type: None,
        problem,
    };
    if bytes.len() < HEADER_BYTES || &bytes[..7] != MAGIC {
        return Err(at(format!(
            "expected the ULog header (the bytes \"ULog\" 01 12 35 and 9 more), found {} byte{} that are not",
            bytes.len().min(HEADER_BYTES),
            if bytes.len() == 1 { "" } else { "s" }
        )));
    }
    Ok(u64_at(bytes, 8))
}

impl Reader<'_> {
    /// The flag bits message, when the log has one (format version 1 and
    /// later begin with it): the appended data's offsets, ascending, and
    /// where the next message begins.
    fn read_flags(&mut self) -> Result<(Vec<usize>, usize), UlogError> {
        let b = self.bytes;
        if b.len() < HEADER_BYTES + 3 || b[HEADER_BYTES + 2] != b'B' {
            return Ok((Vec::new(), HEADER_BYTES));
        }
        let at = At {
            offset: HEADER_BYTES,
            kind: b'B',
        };
        let size = usize::from(u16_at(b, HEADER_BYTES));
        let body = HEADER_BYTES + 3;
        if size < FLAG_PAYLOAD || b.len() < body + size {
            return Err(at.err(format!(
                "expected a flag bits message of at least {FLAG_PAYLOAD} bytes within the file, its size says {size}"
            )));
        }
        let incompat = &b[body + 8..body + 16];
        let unknown =
            incompat[0] & !INCOMPAT_DATA_APPENDED != 0 || incompat[1..].iter().any(|&x| x != 0);
        if unknown {
            return Err(at.err(format!(
                "the log sets incompatible flag bits {incompat:02x?} that this reader does not know (only bit 0, data appended); the log needs a newer reader"
            )));
        }
        if incompat[0] & INCOMPAT_DATA_APPENDED == 0 {
            return Ok((Vec::new(), body + size));
        }
        let mut offsets = Vec::new();
        for k in 0..3 {
            let o = u64_at(b, body + 16 + 8 * k);
            if o == 0 {
                break;
            }
            let o = usize::try_from(o).unwrap_or(usize::MAX);
            let floor = offsets.last().copied().unwrap_or(body + size);
            if o < floor || o > b.len() {
                return Err(at.err(format!(
                    "appended data offset {k} is {o}: expected ascending offsets after the flag bits and within the file's {} bytes",
                    b.len()
                )));
            }
            offsets.push(o);
        }
        Ok((offsets, body + size))
    }

    /// Reads messages from `pos` until the end of the file or, with
    /// `until`, until the next message would pass it; where it stopped.
    fn read_messages(&mut self, mut pos: usize, until: Option<usize>) -> Result<usize, UlogError> {
        let end = self.bytes.len();
        while pos < end {
            if end - pos < 3 {
                return Err(UlogError {
                    offset: pos,
                    message_type: None,
                    problem: format!(
                        "expected a message header (3 bytes), the file ends after {} byte{} (a cut log)",
                        end - pos,
                        if end - pos == 1 { "" } else { "s" }
                    ),
                });
            }
            let size = usize::from(u16_at(self.bytes, pos));
            let at = At {
                offset: pos,
                kind: self.bytes[pos + 2],
            };
            let body = pos + 3;
            if until.is_some_and(|u| body + size > u) {
                return Ok(pos);
            }
            if body + size > end {
                return Err(at.err(format!(
                    "expected a payload of {size} bytes, the file ends after {} (a cut log)",
                    end - body
                )));
            }
            self.message(at, body..body + size)?;
            pos = body + size;
        }
        Ok(pos)
    }

    /// One message's payload.
    fn message(&mut self, at: At, payload: Range<usize>) -> Result<(), UlogError> {
        let p = &self.bytes[payload.clone()];
        match at.kind {
            b'F' => self.format(at, p),
            b'A' => self.add_logged(at, p),
            b'D' => self.data(at, payload),
            b'I' => {
                let (key, value) = key_value(at, p)?;
                self.log.info.entry(key).or_insert(value);
                Ok(())
            }
            b'M' => self.info_multiple(at, p),
            b'P' => {
                let (key, value) = key_value(at, p)?;
                // The first value is the initial one; later ones are changes.
                self.log.parameters.entry(key).or_insert(value);
                Ok(())
            }
            b'Q' => {
                // Default parameters: one byte of default types, then a key.
                let rest = p
                    .get(1..)
                    .ok_or_else(|| at.err("expected a default types byte"))?;
                key_value(at, rest).map(|_| ())
            }
            b'L' => need(at, p, 9, "a log level and a timestamp"),
            b'C' => need(at, p, 11, "a log level, a tag and a timestamp"),
            b'O' => {
                need(at, p, 2, "a dropout duration")?;
                self.log.dropouts += 1;
                Ok(())
            }
            b'R' => need(at, p, 2, "a subscription id"),
            b'B' => Err(at.err("a flag bits message only directly after the header")),
            // Sync markers and any message type this reader does not know
            // are skipped by their size, as the format asks.
            _ => Ok(()),
        }
    }

    /// A format message: `name:type field;type field;...`.
    fn format(&mut self, at: At, p: &[u8]) -> Result<(), UlogError> {
        let text = std::str::from_utf8(p).map_err(|_| at.err("expected a format as ASCII text"))?;
        let (name, fields) = text
            .split_once(':')
            .ok_or_else(|| at.err(format!("expected `name:type field;...`, found {text:?}")))?;
        let mut out = Vec::new();
        for f in fields.split(';').filter(|f| !f.is_empty()) {
            out.push(raw_field(f).ok_or_else(|| {
                at.err(format!(
                    "format {name:?}: expected a field `type name` or `type[N] name`, found {f:?}"
                ))
            })?);
        }
        self.formats.insert(name.to_string(), out);
        Ok(())
    }

    /// A subscription: `u8 multi_id, u16 msg_id, name`.
    fn add_logged(&mut self, at: At, p: &[u8]) -> Result<(), UlogError> {
        need(at, p, 4, "a multi id, a message id and a format name")?;
        let id = u16_at(p, 1);
        let name = std::str::from_utf8(&p[3..])
            .map_err(|_| at.err("expected the format name as ASCII text"))?
            .to_string();
        let mut fields = Vec::new();
        let size = self.flatten(at, &name, "", 0, &mut fields)?;
        // Padding at the end may be left out of a data message.
        let min_size = fields
            .iter()
            .rev()
            .find(|f| !f.name.starts_with("_padding"))
            .map_or(0, |f| f.offset + f.ty.size());
        fields.retain(|f| !f.name.contains("_padding"));
        self.fields_total += fields.len();
        let sub = Subscription {
            name,
            multi_id: p[0],
            fields,
            min_size,
            size,
            payloads: Vec::new(),
        };
        self.ids.insert(id, self.log.subscriptions.len());
        self.log.subscriptions.push(sub);
        Ok(())
    }

    /// Appends the basic fields of format `name` (nested formats flattened
    /// with `prefix.`), from byte `base`; the format's size.
    fn flatten(
        &self,
        at: At,
        name: &str,
        prefix: &str,
        base: usize,
        out: &mut Vec<Field>,
    ) -> Result<usize, UlogError> {
        if prefix.matches('.').count() >= MAX_NESTING {
            return Err(at.err(format!(
                "format {name:?} nests deeper than {MAX_NESTING} levels"
            )));
        }
        let fields = self.formats.get(name).ok_or_else(|| {
            at.err(format!(
                "expected a format message defining {name:?} before it is used"
            ))
        })?;
        let mut offset = base;
        for f in fields {
            for i in 0..f.array.unwrap_or(1) {
                let fname = match f.array {
                    None => format!("{prefix}{}", f.name),
                    Some(_) => format!("{prefix}{}[{i}]", f.name),
                };
                offset = match FieldType::of(&f.type_name) {
                    Some(FieldType::Char) if f.array.is_some() => {
                        if i == 0 {
                            let (name, len) = (format!("{prefix}{}", f.name), f.array.unwrap_or(1));
                            out.push(Field {
                                name,
                                ty: FieldType::Char,
                                offset,
                                len,
                            });
                        }
                        offset + 1
                    }
                    Some(ty) => {
                        out.push(Field {
                            name: fname,
                            ty,
                            offset,
                            len: 1,
                        });
                        offset + ty.size()
                    }
                    None => {
                        let size =
                            self.flatten(at, &f.type_name, &format!("{fname}."), offset, out)?;
                        if size == 0 {
                            break; // an empty format: its other elements add nothing
                        }
                        offset + size
                    }
                };
                if out.len() + self.fields_total > MAX_FIELDS {
                    return Err(at.err(format!("the subscriptions have more than {MAX_FIELDS} fields in all; PX4's logs have a few thousand")));
                }
                if offset - base > usize::from(u16::MAX) {
                    return Err(at.err(format!(
                        "format {name:?} is larger than a message can be (65535 bytes)"
                    )));
                }
            }
        }
        Ok(offset - base)
    }

    /// A data message: `u16 msg_id`, then the subscription's fields.
    fn data(&mut self, at: At, payload: Range<usize>) -> Result<(), UlogError> {
        let p = &self.bytes[payload.clone()];
        need(at, p, 2, "a message id")?;
        let id = u16_at(p, 0);
        let &index = self.ids.get(&id).ok_or_else(|| {
            at.err(format!(
                "expected the message id of an add-logged message, found {id}, never subscribed"
            ))
        })?;
        let sub = &mut self.log.subscriptions[index];
        let size = p.len() - 2;
        if size < sub.min_size || size > sub.size {
            return Err(at.err(format!(
                "a {} message of {size} bytes; its format has {} ({} without trailing padding)",
                sub.name, sub.size, sub.min_size
            )));
        }
        sub.payloads.push(payload.start + 2..payload.end);
        Ok(())
    }

    /// An info-multiple message: `u8 is_continued`, then a key and value.
    fn info_multiple(&mut self, at: At, p: &[u8]) -> Result<(), UlogError> {
        need(at, p, 1, "a continuation byte")?;
        let continued = p[0] != 0;
        let (key, value) = key_value(at, &p[1..])?;
        let text = String::from_utf8_lossy(&value.bytes).into_owned();
        let list = self.log.info_multiple.entry(key).or_default();
        match list.last_mut() {
            Some(last) if continued => last.push(text),
            _ => list.push(vec![text]),
        }
        Ok(())
    }
}

/// Refuses a payload shorter than `n` bytes.
fn need(at: At, p: &[u8], n: usize, what: &str) -> Result<(), UlogError> {
    if p.len() < n {
        return Err(at.err(format!(
            "expected {what} ({n} bytes), the payload has {}",
            p.len()
        )));
    }
    Ok(())
}

/// `type name` or `type[N] name`.
fn raw_field(f: &str) -> Option<RawField> {
    let (ty, name) = f.trim().split_once(' ')?;
    let (type_name, array) = match ty.split_once('[') {
        None => (ty.to_string(), None),
        Some((t, n)) => (t.to_string(), Some(n.strip_suffix(']')?.parse().ok()?)),
    };
    if type_name.is_empty() || name.is_empty() {
        return None;
    }
    Some(RawField {
        type_name,
        array,
        name: name.to_string(),
    })
}

/// An info or parameter payload: `u8 key_len`, the key `type name`, the
/// value's bytes.
fn key_value(at: At, p: &[u8]) -> Result<(String, super::Value), UlogError> {
    need(at, p, 1, "a key length")?;
    let len = usize::from(p[0]);
    let key = p.get(1..1 + len).ok_or_else(|| {
        at.err(format!(
            "expected a key of {len} bytes, the payload has {}",
            p.len() - 1
        ))
    })?;
    let key = std::str::from_utf8(key).map_err(|_| at.err("expected the key as ASCII text"))?;
    let field = raw_field(key)
        .ok_or_else(|| at.err(format!("expected a key `type name`, found {key:?}")))?;
    let value = &p[1 + len..];
    let ty = FieldType::of(&field.type_name)
        .ok_or_else(|| at.err(format!("key {key:?}: expected a basic type")))?;
    let want = ty.size() * field.array.unwrap_or(1);
    if value.len() != want {
        return Err(at.err(format!(
            "key {key:?}: expected a value of {want} bytes, found {}",
            value.len()
        )));
    }
    Ok((
        field.name,
        super::Value {
            ty,
            bytes: value.to_vec(),
        },
    ))
}
