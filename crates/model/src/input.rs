//! The one way rtpipe reads a file a user hands it: a spec, a mission, a
//! vehicle preset, a criterion or a YAML file to import. Every kind gets
//! the same rules:
//!
//! - only regular files are read (symlinks followed): directories, named
//!   pipes, devices and sockets are refused before the file is opened (a
//!   pipe would block the open until a writer came, a device can stream
//!   forever);
//! - at most [`Kind::max_bytes`] bytes are read (a larger file is refused
//!   from its size before reading, one that grows while read after that
//!   many bytes);
//! - the text must be UTF-8; a leading byte-order mark is dropped; a
//!   control character other than tab, line feed and carriage return is
//!   refused with its line and column (TOML and YAML allow none, and a
//!   terminal would obey it when the text is shown);
//! - nesting (arrays and tables, or YAML's collections) deeper than
//!   [`MAX_NESTING`] is refused by a linear scan before the parser runs,
//!   so no input makes parsing slow;
//! - a TOML syntax error names file, line and column ([`parse_toml`]).
//!
//! A file of any length read a line at a time (a CSV of measurements) is
//! [`Lines`]: the same rules line by line, with a cap on a line's length in
//! place of the file's size.
//!
//! Errors are [`SpecError`]s: the file, and a diagnostic with its place
//! when it has one and how to fix it. Names that are shown on a terminal
//! are checked by [`name_problem`].

use crate::{Diagnostic, SpecError};
use std::io::Read;
use std::path::Path;

pub mod cells;
mod lines;
pub use lines::{Lines, MAX_LINE_BYTES};

/// The largest TOML file rtpipe reads (spec, mission, preset, criterion):
/// 16 MiB.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// The deepest nesting of arrays, tables or YAML collections read.
pub const MAX_NESTING: usize = 64;

/// The longest name (task, channel, chain, system, mission, preset), in
/// characters.
pub const MAX_NAME_CHARS: usize = 256;

/// The syntax of a file, for the nesting scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Syntax {
    /// TOML: nesting is brackets and braces.
    Toml,
    /// YAML: brackets and braces, and block collections by indentation and
    /// `- ` entries.
    Yaml,
}

/// A kind of input file: what it is called in messages, its size cap, its
/// syntax and what a right file looks like.
#[derive(Debug, Clone, Copy)]
pub struct Kind {
    /// The file's role, e.g. `"spec"`, `"mission"`.
    pub name: &'static str,
    /// The most bytes read.
    pub max_bytes: u64,
    /// TOML or YAML.
    pub syntax: Syntax,
    /// How to fix a wrong file (shown as help).
    pub help: &'static str,
}

impl Kind {
    /// A spec.
    pub const SPEC: Kind = Kind {
        name: "spec",
        max_bytes: MAX_INPUT_BYTES,
        syntax: Syntax::Toml,
        help: "specs are small TOML files such as examples/paper-table2.toml; check the path (a device, log or binary file is not a spec)",
    };
    /// A mission (`fly --mission`, `run --mission`).
    pub const MISSION: Kind = Kind {
        name: "mission",
        max_bytes: MAX_INPUT_BYTES,
        syntax: Syntax::Toml,
        help: "missions are small TOML files such as crates/flight/missions/hover.toml",
    };
    /// A vehicle preset (`--vehicle`).
    pub const PRESET: Kind = Kind {
        name: "vehicle preset",
        max_bytes: MAX_INPUT_BYTES,
        syntax: Syntax::Toml,
        help: "presets are small TOML files such as crates/flight/presets/racer5.toml",
    };
    /// A flight criterion (`fly --sweep --criterion`).
    pub const CRITERION: Kind = Kind {
        name: "criterion",
        max_bytes: MAX_INPUT_BYTES,
        syntax: Syntax::Toml,
        help: "a criterion is a small TOML file with attitude_rms_deg, altitude_rms_m, overshoot, settling_s, position_rms_m, oscillation_dps, motor_variation_per_s, step_tracking_rms_deg",
    };
}

fn fail(file: &str, msg: String, help: &str) -> SpecError {
    SpecError {
        file: file.to_string(),
        source: String::new(),
        diagnostics: vec![Diagnostic::error(msg, help)],
    }
}

/// The bytes of `path`, at most `kind.max_bytes`, by the rules of the
/// module documentation that apply to any file (regular files only, the
/// size cap): the one way to read a binary input such as a flight log
/// (`kind.syntax` is not used).
pub fn read_bytes(path: &Path, kind: &Kind) -> Result<Vec<u8>, SpecError> {
    let file = path.display().to_string();
    let what = kind.name;
    let too_big = || {
        fail(
            &file,
            format!(
                "the {what} is larger than {} MiB, the most rtpipe reads",
                kind.max_bytes >> 20
            ),
            kind.help,
        )
    };
    refuse_non_regular(path, kind)?;
    let f = std::fs::File::open(path)
        .map_err(|e| fail(&file, format!("cannot read the {what}: {e}"), kind.help))?;
    if f.metadata().is_ok_and(|m| m.len() > kind.max_bytes) {
        return Err(too_big());
    }
    let mut bytes = Vec::new();
    f.take(kind.max_bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| fail(&file, format!("cannot read the {what}: {e}"), kind.help))?;
    if bytes.len() as u64 > kind.max_bytes {
        return Err(too_big());
    }
    Ok(bytes)
}

/// Refuses, before opening it, a path that is not a regular file (symlinks
/// followed): opening a named pipe for reading blocks until a writer
/// comes, and a device or socket can stream forever or block.
fn refuse_non_regular(path: &Path, kind: &Kind) -> Result<(), SpecError> {
    let file = path.display().to_string();
    let what = kind.name;
    let m = std::fs::metadata(path)
        .map_err(|e| fail(&file, format!("cannot read the {what}: {e}"), kind.help))?;
    let t = m.file_type();
    let is = if t.is_file() {
        return Ok(());
    } else if t.is_dir() {
        "a directory"
    } else {
        special_kind(&t)
    };
    Err(fail(
        &file,
        format!("cannot read the {what}: it is {is}, not a regular file"),
        &format!(
            "save the {what} as a regular file and give its path ({})",
            kind.help
        ),
    ))
}

/// What a special file is, in words.
fn special_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
    }
    let _ = t;
    "a special file"
}

/// The text of `path` by the rules of the module documentation.
pub fn read_text(path: &Path, kind: &Kind) -> Result<String, SpecError> {
    let file = path.display().to_string();
    let bytes = read_bytes(path, kind)?;
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let byte = e.as_bytes().get(at).copied().unwrap_or(0);
            let mut bytes = e.into_bytes();
            bytes.truncate(at);
            let source = String::from_utf8(bytes).unwrap_or_default();
            return Err(SpecError {
                file,
                diagnostics: vec![Diagnostic::new(
                    format!(
                        "cannot read the {}: not UTF-8 text (byte 0x{byte:02X} at offset {at})",
                        kind.name
                    ),
                    Some(source.len()..source.len()),
                )
                .help(kind.help)],
                source,
            });
        }
    };
    let text = match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    };
    check_text(&file, text, kind)
}

/// Refuses control characters and deep nesting (see the module docs).
pub fn check_text(file: &str, text: String, kind: &Kind) -> Result<String, SpecError> {
    let located = |text: String, at: usize, msg: String, help: &str| SpecError {
        file: file.to_string(),
        diagnostics: vec![Diagnostic::new(msg, Some(at..at + 1)).help(help)],
        source: text,
    };
    if let Some((at, c)) = first_control(&text) {
        let msg = format!(
            "the {} holds the control character U+{:04X}; {} files hold printable text",
            kind.name,
            c as u32,
            if kind.syntax == Syntax::Toml {
                "TOML"
            } else {
                "YAML"
            }
        );
        return Err(located(
            text,
            at,
            msg,
            "remove it (in a string, write it as an escape such as \\u001B)",
        ));
    }
    if let Some(at) = too_deep(&text, kind.syntax) {
        let msg = format!(
            "the {} nests deeper than {MAX_NESTING} levels, the most rtpipe reads",
            kind.name
        );
        return Err(located(text, at, msg, kind.help));
    }
    Ok(text)
}

/// The first control character other than tab, line feed and carriage
/// return, with its byte offset: what no file rtpipe reads may hold.
pub fn first_control(text: &str) -> Option<(usize, char)> {
    text.char_indices()
        .find(|&(_, c)| c.is_control() && !matches!(c, '\t' | '\n' | '\r'))
}

/// The byte offset where nesting first exceeds [`MAX_NESTING`], if it
/// does. One pass; strings and comments are skipped (a quote opens a
/// string only where a value or key can start, so an apostrophe in a
/// plain YAML word does not).
pub fn too_deep(text: &str, syntax: Syntax) -> Option<usize> {
    let b = text.as_bytes();
    let mut flow = 0usize;
    let mut indents: Vec<usize> = Vec::new();
    let mut i = 0;
    let mut line_start = true;
    while i < b.len() {
        if line_start && flow == 0 && syntax == Syntax::Yaml {
            let (block, next) = yaml_block_depth(b, i, &mut indents);
            if block > MAX_NESTING {
                return Some(next.min(b.len().saturating_sub(1)));
            }
            i = next;
            line_start = false;
            continue;
        }
        line_start = false;
        let c = b[i];
        let prev = if i == 0 { b'\n' } else { b[i - 1] };
        match c {
            b'\n' => line_start = true,
            b'#' if prev.is_ascii_whitespace() || syntax == Syntax::Toml => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'"' | b'\'' if value_start(b, i) => {
                i = skip_string(b, i);
                continue;
            }
            b'[' | b'{' => {
                flow += 1;
                let block = if syntax == Syntax::Yaml {
                    indents.len()
                } else {
                    0
                };
                if flow + block > MAX_NESTING {
                    return Some(i);
                }
            }
            b']' | b'}' => flow = flow.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
    None
}

/// Whether a quote at `i` opens a string: the previous non-blank byte on
/// the line is a key, value or entry separator, or there is none.
fn value_start(b: &[u8], i: usize) -> bool {
    let mut k = i;
    while k > 0 {
        k -= 1;
        match b[k] {
            b' ' | b'\t' => continue,
            b'\n' => return true,
            c => return matches!(c, b':' | b'-' | b'[' | b'{' | b',' | b'=' | b'.' | b'?'),
        }
    }
    true
}

/// The index after the string opened by the quote at `i` (a backslash
/// escapes in double quotes; `''` in single quotes closes and reopens).
fn skip_string(b: &[u8], i: usize) -> usize {
    let q = b[i];
    let mut k = i + 1;
    while k < b.len() {
        if q == b'"' && b[k] == b'\\' {
            k += 2;
            continue;
        }
        if b[k] == q {
            return k + 1;
        }
        k += 1;
    }
    b.len()
}

/// A YAML line's block depth (enclosing indentation levels plus its
/// leading `- ` and `? ` entries) and where its content starts. Blank and
/// comment lines keep the levels.
fn yaml_block_depth(b: &[u8], start: usize, indents: &mut Vec<usize>) -> (usize, usize) {
    let mut i = start;
    while i < b.len() && b[i] == b' ' {
        i += 1;
    }
    let indent = i - start;
    if i >= b.len() || matches!(b[i], b'\n' | b'\r' | b'#') {
        return (indents.len(), i);
    }
    while indents.last().is_some_and(|&top| top > indent) {
        indents.pop();
    }
    if indents.last().is_none_or(|&top| top < indent) {
        indents.push(indent);
    }
    let mut entries = 0;
    while i + 1 < b.len() && matches!(b[i], b'-' | b'?') && matches!(b[i + 1], b' ' | b'\t') {
        entries += 1;
        i += 2;
        while i < b.len() && matches!(b[i], b' ' | b'\t') {
            i += 1;
        }
        if entries > MAX_NESTING {
            break;
        }
    }
    (indents.len() + entries, i)
}

/// Parses TOML text into `T`; a syntax or type error names its line and
/// column in `file`.
pub fn parse_toml<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
    kind: &Kind,
) -> Result<T, SpecError> {
    toml::from_str(text).map_err(|e| {
        let message = e.message().trim().to_string();
        let message = if message.is_empty() {
            format!("the {} is not valid TOML", kind.name)
        } else {
            message
        };
        SpecError {
            file: file.to_string(),
            source: text.to_string(),
            diagnostics: vec![Diagnostic::new(message, e.span()).help(kind.help)],
        }
    })
}

/// Reads `path` by the module's rules and parses it as TOML into `T`.
pub fn load_toml<T: serde::de::DeserializeOwned>(path: &Path, kind: &Kind) -> Result<T, SpecError> {
    let text = read_text(path, kind)?;
    parse_toml(&path.display().to_string(), &text, kind)
}

/// Where the field a dotted path names (`name`, `body.mass_kg`,
/// `step[3].at`, `rotors.positions_m[2]`) is written in TOML `text`: the
/// byte range of its key, or of its table's header when the key is not
/// written (a default that fails with the others). `None` when the text
/// writes it another way (inline tables, dotted keys).
pub fn locate(text: &str, field: &str) -> Option<std::ops::Range<usize>> {
    let strip = |s: &str| s.split('[').next().unwrap_or(s).to_string();
    let (table, key) = match field.rsplit_once('.') {
        Some((t, k)) => (t, strip(k)),
        None => ("", strip(field)),
    };
    let index: usize = table
        .rsplit_once('[')
        .and_then(|(_, i)| i.trim_end_matches(']').parse().ok())
        .unwrap_or(0);
    let header = strip(table);
    let mut current = String::new();
    let mut seen = 0usize;
    let mut header_at = None;
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let start = offset;
        offset += line.len();
        let t = line.trim();
        if let Some(h) = t.strip_prefix('[') {
            let name = h.trim_start_matches('[');
            current = name.split(']').next().unwrap_or("").trim().to_string();
            if current == header {
                seen += 1;
                if seen == index + 1 {
                    header_at = Some(start..start + line.trim_end().len());
                }
            }
            continue;
        }
        let here = if header.is_empty() {
            current.is_empty()
        } else {
            current == header && seen == index + 1
        };
        let Some(rest) = t.strip_prefix(key.as_str()) else {
            continue;
        };
        if here && rest.trim_start().starts_with('=') {
            let col = line.len() - line.trim_start().len();
            return Some(start + col..start + col + key.len());
        }
    }
    header_at
}

/// What is wrong with a name shown on terminals and in files, if anything:
/// empty, longer than [`MAX_NAME_CHARS`], or holding a control character,
/// a bidirectional control or an invisible (zero-width) character, any of
/// which would make the name print as something it is not.
pub fn name_problem(name: &str) -> Option<String> {
    let n = name.chars().count();
    if name.trim().is_empty() {
        return Some("is empty".into());
    }
    if n > MAX_NAME_CHARS {
        return Some(format!(
            "has {n} characters, more than the {MAX_NAME_CHARS} allowed"
        ));
    }
    let c = name.chars().find(|&c| c.is_control() || invisible(c))?;
    let kind = if c.is_control() {
        "the control character"
    } else if bidi(c) {
        "the bidirectional control"
    } else {
        "the invisible character"
    };
    Some(format!("contains {kind} U+{:04X}", c as u32))
}

/// A name as shown in a message about it: escaped (`\u{202e}`), and cut
/// to 40 characters with `…`.
pub fn shown_name(name: &str) -> String {
    let mut s: String = name
        .chars()
        .take(40)
        .collect::<String>()
        .escape_debug()
        .to_string();
    if name.chars().nth(40).is_some() {
        s.push('…');
    }
    s
}

/// Unicode's bidirectional formatting characters.
fn bidi(c: char) -> bool {
    matches!(c, '\u{061C}' | '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
}

/// Characters that print as nothing: bidirectional controls, zero-width
/// spaces and joiners, the word joiner and invisible operators, the BOM.
fn invisible(c: char) -> bool {
    bidi(c)
        || matches!(
            c,
            '\u{00AD}' | '\u{180E}' | '\u{200B}'..='\u{200D}' | '\u{2060}'..='\u{2064}' | '\u{FEFF}'
        )
}

impl SpecError {
    /// The first problem as one line, `FILE:LINE:COL: message` (without
    /// the place when it has none), with its help: for callers that report
    /// a file's problem as one of their own (`--mission m.toml:3:5: ...`).
    pub fn located(&self) -> Diagnostic {
        let Some(d) = self.diagnostics.first() else {
            return Diagnostic::error(format!("{}: unreadable", self.file), "");
        };
        let place = match &d.span {
            Some(s) => {
                let (l, c) = self.line_col(s.start);
                format!("{}:{l}:{c}", self.file)
            }
            None => self.file.clone(),
        };
        Diagnostic {
            message: format!("{place}: {}", crate::printable(&d.message)),
            help: d.help.clone(),
            span: None,
        }
    }
}

#[cfg(test)]
mod tests;
