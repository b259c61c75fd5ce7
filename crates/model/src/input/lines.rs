//! A file of any length read one line at a time, by the module's rules:
//! a regular file only, UTF-8 (a leading byte-order mark dropped), no
//! control character but tab. Memory holds one line, at most
//! [`MAX_LINE_BYTES`], whatever the file's size.

use super::{first_control, refuse_non_regular, Kind};
use crate::Diagnostic;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// The longest line read: 64 KiB (a row of measurements is well under
/// 1 KiB; a longer line is a binary or a wrong file).
pub const MAX_LINE_BYTES: usize = 64 << 10;

/// The lines of a file, each checked as it is read; errors name the file,
/// the line and the column.
pub struct Lines {
    file: String,
    kind: Kind,
    reader: BufReader<std::fs::File>,
    buf: Vec<u8>,
    text: String,
    number: u64,
}

impl Lines {
    /// Opens `path` (a regular file, refused before it is opened
    /// otherwise).
    pub fn open(path: &Path, kind: &Kind) -> Result<Lines, Diagnostic> {
        let file = path.display().to_string();
        refuse_non_regular(path, kind).map_err(|e| e.located())?;
        let f = std::fs::File::open(path).map_err(|e| {
            Diagnostic::error(
                format!("{file}: cannot read the {}: {e}", kind.name),
                kind.help,
            )
        })?;
        Ok(Lines {
            file,
            kind: *kind,
            reader: BufReader::with_capacity(1 << 16, f),
            buf: Vec::new(),
            text: String::new(),
            number: 0,
        })
    }

    /// The next line without its line end, with its number (1 for the
    /// first); `None` at the end of the file.
    pub fn next_line(&mut self) -> Result<Option<(u64, &str)>, Diagnostic> {
        self.buf.clear();
        let limit = MAX_LINE_BYTES as u64 + 1;
        let read = (&mut self.reader)
            .take(limit)
            .read_until(b'\n', &mut self.buf)
            .map_err(|e| {
                let msg = format!("cannot read the {}: {e}", self.kind.name);
                self.at_line(self.number + 1, 1, msg, self.kind.help)
            })?;
        if read == 0 {
            return Ok(None);
        }
        self.number += 1;
        if self.buf.last() == Some(&b'\n') {
            self.buf.pop();
            if self.buf.last() == Some(&b'\r') {
                self.buf.pop();
            }
        } else if self.buf.len() > MAX_LINE_BYTES {
            let msg = format!(
                "the line is longer than {} KiB, the most rtpipe reads in a {}",
                MAX_LINE_BYTES >> 10,
                self.kind.name
            );
            return Err(self.at(1, msg, self.kind.help));
        }
        self.check()?;
        Ok(Some((self.number, &self.text)))
    }

    /// Checks the line in `buf` (UTF-8, no control character) into `text`.
    fn check(&mut self) -> Result<(), Diagnostic> {
        let text = match std::str::from_utf8(&self.buf) {
            Ok(t) => t,
            Err(e) => {
                let at = e.valid_up_to();
                let byte = self.buf.get(at).copied().unwrap_or(0);
                let msg = format!(
                    "cannot read the {}: not UTF-8 text (byte 0x{byte:02X})",
                    self.kind.name
                );
                let col = String::from_utf8_lossy(&self.buf[..at]).chars().count() + 1;
                return Err(self.at(col, msg, self.kind.help));
            }
        };
        let text = match (self.number, text.strip_prefix('\u{feff}')) {
            (1, Some(rest)) => rest,
            _ => text,
        };
        if let Some((at, c)) = first_control(text) {
            let col = text[..at].chars().count() + 1;
            let msg = format!(
                "the {} holds the control character U+{:04X}; it holds printable text",
                self.kind.name, c as u32
            );
            return Err(self.at(col, msg, "remove it"));
        }
        self.text.clear();
        self.text.push_str(text);
        Ok(())
    }

    /// The number of the line last read (1 for the first).
    pub fn number(&self) -> u64 {
        self.number
    }

    /// The file's name as given.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// A problem at column `col` (1-based, in characters) of the line last
    /// read: `FILE:LINE:COL: message`, with `help`.
    pub fn at(&self, col: usize, message: impl AsRef<str>, help: &str) -> Diagnostic {
        self.at_line(self.number, col, message, help)
    }

    fn at_line(&self, line: u64, col: usize, message: impl AsRef<str>, help: &str) -> Diagnostic {
        Diagnostic::error(
            format!(
                "{}:{line}:{col}: {}",
                self.file,
                crate::printable(message.as_ref())
            ),
            help,
        )
    }
}
