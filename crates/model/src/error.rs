//! Diagnostics that name file, line and column and say how to fix the input.

use std::fmt;
use std::ops::Range;

/// One problem in a spec, located in its source text.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// What is wrong.
    pub message: String,
    /// What to change, when we can tell.
    pub help: Option<String>,
    /// Byte range in the source, when known.
    pub span: Option<Range<usize>>,
}

impl Diagnostic {
    /// A diagnostic at `span` (byte range in the source), without help.
    pub fn new(message: impl Into<String>, span: Option<Range<usize>>) -> Self {
        Diagnostic {
            message: message.into(),
            help: None,
            span,
        }
    }

    /// A problem that has no place in a source text (a flag, a file, a
    /// run): what is wrong and how to fix it (an empty `help` is none).
    pub fn error(message: impl Into<String>, help: impl Into<String>) -> Self {
        let help: String = help.into();
        Diagnostic {
            message: message.into(),
            help: (!help.is_empty()).then_some(help),
            span: None,
        }
    }

    /// The same problem, its message prefixed by the place it is in
    /// (`PLACE: message`), e.g. the file a library's caller read.
    pub fn within(mut self, place: impl fmt::Display) -> Self {
        self.message = format!("{place}: {}", self.message);
        self
    }

    /// Adds what to change.
    pub fn help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
}

/// `error: MESSAGE` and `  = help: HELP` lines, without place: how the
/// commands print a problem that is not in a spec's text (a [`SpecError`]
/// shows its diagnostics with file, line and source instead). The text is
/// printed as given.
impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "error: {}", self.message)?;
        if let Some(h) = &self.help {
            writeln!(f, "  = help: {h}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostic {}

/// All problems found in one spec file, with the text needed to show them.
#[derive(Debug, Clone)]
pub struct SpecError {
    /// The file's name as shown in diagnostics.
    pub file: String,
    /// The file's text.
    pub source: String,
    /// Every problem found, in source order where known.
    pub diagnostics: Vec<Diagnostic>,
}

impl SpecError {
    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        line_col(&self.source, offset)
    }

    /// The diagnostics as `file:line:col` locations, for tests and JSON.
    pub fn locations(&self) -> Vec<String> {
        self.diagnostics
            .iter()
            .map(|d| match &d.span {
                Some(s) => {
                    let (l, c) = self.line_col(s.start);
                    format!("{}:{}:{}", self.file, l, c)
                }
                None => self.file.clone(),
            })
            .collect()
    }
}

/// 1-based line and column (in characters) of a byte offset in `source`.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let mut line = 1;
    let mut line_start = 0;
    for (i, b) in source.bytes().enumerate().take(offset) {
        if b == b'\n' {
            line += 1;
            line_start = i + 1;
        }
    }
    let col = source
        .get(line_start..offset)
        .map(|s| s.chars().count())
        .unwrap_or(0)
        + 1;
    (line, col)
}

/// Text with control characters (terminal escapes; tabs stay) shown escaped, so a
/// diagnostic never prints them raw.
pub fn printable(s: &str) -> std::borrow::Cow<'_, str> {
    let bad = |c: char| c.is_control() && c != '\t';
    if s.chars().any(bad) {
        std::borrow::Cow::Owned(
            s.chars()
                .map(|c| {
                    if bad(c) {
                        c.escape_default().to_string()
                    } else {
                        c.to_string()
                    }
                })
                .collect(),
        )
    } else {
        std::borrow::Cow::Borrowed(s)
    }
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, d) in self.diagnostics.iter().enumerate() {
            let message = printable(&d.message);
            if i > 0 {
                writeln!(f)?;
            }
            match &d.span {
                Some(span) => {
                    let (line, col) = self.line_col(span.start);
                    writeln!(f, "{}:{}:{}: error: {message}", self.file, line, col)?;
                    if let Some(text) = self.source.lines().nth(line - 1) {
                        let width = {
                            let end = span.end.min(
                                self.source[..span.start.min(self.source.len())]
                                    .rfind('\n')
                                    .map(|p| p + 1)
                                    .unwrap_or(0)
                                    + text.len(),
                            );
                            self.source
                                .get(span.start..end.max(span.start))
                                .map(|s| s.chars().count())
                                .unwrap_or(1)
                                .max(1)
                        };
                        let (shown, col, width) = window(text, col, width);
                        writeln!(f, "{line:>5} | {}", printable(&shown))?;
                        writeln!(f, "      | {}{}", " ".repeat(col - 1), "^".repeat(width))?;
                    }
                }
                None => writeln!(f, "{}: error: {message}", self.file)?,
            }
            if let Some(h) = &d.help {
                writeln!(f, "      = help: {}", printable(h))?;
            }
        }
        Ok(())
    }
}

impl std::error::Error for SpecError {}

/// Longest source line shown whole in a diagnostic, in characters.
pub const MAX_SHOWN_LINE: usize = 120;

/// The part of a source line shown under a diagnostic: the whole line when
/// short, else a window of [`MAX_SHOWN_LINE`] characters around the error
/// column with `…` where it was cut. Returns the text and the (1-based)
/// column and width of the carets in it.
fn window(text: &str, col: usize, width: usize) -> (String, usize, usize) {
    let n = text.chars().count();
    if n <= MAX_SHOWN_LINE {
        return (text.to_string(), col, width);
    }
    let before = 40;
    let start = col.saturating_sub(1).saturating_sub(before).min(n);
    let end = (start + MAX_SHOWN_LINE).min(n);
    let start = end.saturating_sub(MAX_SHOWN_LINE).min(start);
    let mut shown: String = text.chars().skip(start).take(end - start).collect();
    let mut col = col - start;
    if start > 0 {
        shown.insert(0, '…');
        col += 1;
    }
    if end < n {
        shown.push('…');
    }
    // Carets stay within the shown text.
    let room = (end - start + 1 + usize::from(start > 0)).saturating_sub(col);
    (shown, col, width.min(room.max(1)))
}

/// The closest candidate by edit distance, if it is close enough to be a typo.
pub fn suggest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let mut best: Option<(usize, &str)> = None;
    for c in candidates {
        let d = edit_distance(word, c);
        // A typo: a few edits, or one name a prefix of the other ("msec" → "ms").
        let close = d <= (word.len().max(c.len()) / 3).max(1)
            || (c.len() >= 2 && (word.starts_with(c) || c.starts_with(word)));
        if close && best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c)
}

fn edit_distance(a: &str, b: &str) -> usize {
    // Optimal string alignment: insertions, deletions, substitutions and
    // adjacent transpositions ("exce" is one step from "exec").
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = v;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column() {
        let s = "a\nbc\n\tdé f";
        assert_eq!(line_col(s, 0), (1, 1));
        assert_eq!(line_col(s, 2), (2, 1));
        assert_eq!(line_col(s, 3), (2, 2));
        // Columns count characters, not bytes: 'é' is two bytes.
        assert_eq!(line_col(s, s.find('f').unwrap_or(0)), (3, 5));
    }

    #[test]
    fn long_lines_are_cut_around_the_error() {
        let long = format!("name = \"{}\" bad", "x".repeat(200_000));
        let at = long.find("bad").unwrap_or(0);
        let e = SpecError {
            file: "f.toml".into(),
            source: long.clone(),
            diagnostics: vec![Diagnostic::new("oops", Some(at..at + 3))],
        };
        let text = e.to_string();
        assert!(text.len() < 1000, "{} bytes", text.len());
        assert!(text.contains("f.toml:1:200011: error: oops"), "{text}");
        assert!(text.contains("…"), "{text}");
        // The carets sit under `bad` in the shown window.
        let lines: Vec<&str> = text.lines().collect();
        let src = lines[1];
        let carets = lines[2];
        let c = carets.chars().position(|c| c == '^').unwrap_or(0);
        let under: String = src.chars().skip(c).take(3).collect();
        assert_eq!(under, "bad", "{text}");
        assert_eq!(carets.matches('^').count(), 3);
        // Short lines are shown whole.
        let e = SpecError {
            file: "f.toml".into(),
            source: "a = 1".into(),
            diagnostics: vec![Diagnostic::new("oops", Some(4..5))],
        };
        assert!(e.to_string().contains("    1 | a = 1\n      |     ^\n"));
    }

    #[test]
    fn suggestions() {
        assert_eq!(suggest("exce", ["exec", "period"]), Some("exec"));
        assert_eq!(suggest("gyr", ["gyro", "accl"]), Some("gyro"));
        assert_eq!(suggest("zzzz", ["gyro", "accl"]), None);
    }
}
