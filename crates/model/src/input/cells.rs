//! One CSV row of a measurements file (`rtpipe analyze --observed`): its
//! cells (quoted as RFC 4180 and as `simulate --samples` writes them), each
//! with its column for messages, and the cells read as counts, instants and
//! latencies. Here, below the analysis, so that the per-row work is built
//! optimised while the cli (glue) is built cheaply (docs/architecture.md,
//! "Building").

use crate::Nanos;
use std::borrow::Cow;

/// What is wrong with a row, where (a 1-based column in characters) and
/// how to fix it; the reader adds the file and line.
#[derive(Debug)]
pub struct Bad {
    /// The 1-based column, in characters, where the fault starts.
    pub col: usize,
    /// What is wrong.
    pub message: String,
    /// How to fix it.
    pub help: String,
}

impl Bad {
    /// The fault at `col`.
    pub fn at(col: usize, message: impl Into<String>, help: impl Into<String>) -> Bad {
        Bad {
            col,
            message: message.into(),
            help: help.into(),
        }
    }
}

/// A row's cells with the column each starts at.
pub struct Cells<'a> {
    cells: Vec<(usize, Cow<'a, str>)>,
    /// The column after the row's last character.
    end: usize,
    /// The header's column names, once the width is checked.
    header: &'static str,
}

impl<'a> Cells<'a> {
    /// The cells of `line`: separated by commas; a cell that starts with a
    /// double quote runs to the closing one, `""` inside it being one.
    pub fn split(line: &'a str) -> Result<Cells<'a>, Bad> {
        let mut cells = Vec::with_capacity(10);
        let mut rest = line;
        let mut col = 1;
        loop {
            let (cell, width, after) = match rest.strip_prefix('"') {
                Some(quoted) => unquote(quoted, col)?,
                None => {
                    let end = rest.find(',').unwrap_or(rest.len());
                    let cell = &rest[..end];
                    (Cow::Borrowed(cell), cell.chars().count(), &rest[end..])
                }
            };
            cells.push((col, cell));
            col += width;
            match after.strip_prefix(',') {
                Some(next) => {
                    rest = next;
                    col += 1;
                }
                None if after.is_empty() => break,
                None => {
                    return Err(Bad::at(
                        col,
                        "a quoted cell goes on after its closing quote",
                        "end a quoted cell with `\"` followed by `,` or the line's end",
                    ))
                }
            }
        }
        Ok(Cells {
            cells,
            end: col,
            header: "",
        })
    }

    /// Refuses a row of another width than `header`'s, whose column names
    /// the messages then use.
    pub fn expect_header(&mut self, header: &'static str) -> Result<(), Bad> {
        let n = self.cells.len();
        let width = header.split(',').count();
        if n == width {
            self.header = header;
            return Ok(());
        }
        let col = if n > width { self.col(width) } else { self.end };
        Err(Bad::at(
            col,
            format!("the row has {n} cells, the header {width}"),
            "give every row one cell per header column (an empty cell where a value is undefined)",
        ))
    }

    /// The text of cell `k`.
    pub fn text(&self, k: usize) -> &str {
        &self.cells[k].1
    }

    /// The header's name of column `k`.
    fn name(&self, k: usize) -> &'static str {
        self.header.split(',').nth(k).unwrap_or("?")
    }

    /// The column cell `k` starts at.
    pub fn col(&self, k: usize) -> usize {
        self.cells[k].0
    }

    /// Cell `k` as an integer, `None` when empty.
    fn integer(&self, k: usize) -> Result<Option<i64>, Bad> {
        let t = self.text(k).trim();
        if t.is_empty() {
            return Ok(None);
        }
        t.parse::<i64>().map(Some).map_err(|_| {
            Bad::at(
                self.col(k),
                format!("`{t}` in column {} is not an integer", self.name(k)),
                "write integer nanoseconds (e.g. 1500000 for 1.5 ms), or leave the cell empty where the value is undefined",
            )
        })
    }

    /// Cell `k`, which must not be empty.
    fn required(&self, k: usize) -> Result<i64, Bad> {
        self.integer(k)?.ok_or_else(|| {
            Bad::at(
                self.col(k),
                format!("the cell of column {} is empty", self.name(k)),
                "this column has a value in every row",
            )
        })
    }

    /// Cell `k` as a count (a sample's number): an integer ≥ 0.
    pub fn count(&self, k: usize) -> Result<i64, Bad> {
        self.required(k)
            .and_then(|v| self.non_negative(k, v, "a sample number"))
    }

    /// Cell `k` as an instant in nanoseconds.
    pub fn instant(&self, k: usize) -> Result<Nanos, Bad> {
        self.required(k)
    }

    /// Cell `k` as an instant, or empty.
    pub fn optional_instant(&self, k: usize) -> Result<Option<Nanos>, Bad> {
        self.integer(k)
    }

    /// Cell `k` as a latency (≥ 0 ns), or empty.
    pub fn latency(&self, k: usize) -> Result<Option<Nanos>, Bad> {
        match self.integer(k)? {
            Some(v) => self.non_negative(k, v, "a latency").map(Some),
            None => Ok(None),
        }
    }

    fn non_negative(&self, k: usize, v: i64, what: &str) -> Result<i64, Bad> {
        if v >= 0 {
            return Ok(v);
        }
        Err(Bad::at(
            self.col(k),
            format!(
                "{} is {what} and cannot be negative, found {v}",
                self.name(k)
            ),
            "a latency ends after it starts: check the instants it was computed from",
        ))
    }
}

/// A quoted cell after its opening quote (at column `col`): its text, its
/// width in characters with the quotes, and what follows it.
fn unquote(s: &str, col: usize) -> Result<(Cow<'_, str>, usize, &str), Bad> {
    let mut text = String::new();
    let mut chars = s.char_indices();
    let mut width = 1;
    while let Some((i, c)) = chars.next() {
        width += 1;
        if c != '"' {
            text.push(c);
            continue;
        }
        if s[i + 1..].starts_with('"') {
            chars.next();
            width += 1;
            text.push('"');
            continue;
        }
        return Ok((Cow::Owned(text), width, &s[i + 1..]));
    }
    Err(Bad::at(
        col,
        "a quoted cell has no closing quote",
        "close the cell with `\"` (a quote inside it is written `\"\"`)",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_split_and_unquoted_with_their_columns() {
        let c = Cells::split(r#"a,"b,""c""",,7"#).map_err(|b| b.message);
        let c = c.as_ref().ok();
        let texts: Option<Vec<&str>> = c.map(|c| (0..4).map(|k| c.text(k)).collect());
        assert_eq!(texts, Some(vec!["a", "b,\"c\"", "", "7"]));
        let cols: Option<Vec<usize>> = c.map(|c| (0..4).map(|k| c.col(k)).collect());
        assert_eq!(cols, Some(vec![1, 3, 13, 14]));
    }

    #[test]
    fn broken_quotes_and_numbers_are_refused_at_their_column() {
        assert_eq!(Cells::split(r#"a,"b"#).err().map(|b| b.col), Some(3));
        assert_eq!(Cells::split(r#""a"b,c"#).err().map(|b| b.col), Some(4));
        let c = Cells::split("x,1e3,-5").ok();
        let bad = c.as_ref().and_then(|c| c.latency(1).err());
        let bad = bad.map(|b| (b.col, b.message));
        assert_eq!(bad, Some((3, "`1e3` in column ? is not an integer".into())));
        let neg = c.as_ref().and_then(|c| c.latency(2).err());
        assert_eq!(neg.map(|b| b.col), Some(7));
    }
}
