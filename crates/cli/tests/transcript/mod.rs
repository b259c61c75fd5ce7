//! The transcript harness' pure half: finding ```console blocks in a
//! Markdown file, matching a command's output against the block's text
//! with its elisions, and the text a bless writes back (elisions kept).
//! Running the commands is `transcripts.rs`'s half.
//!
//! The syntax (docs/reference/transcripts.md says it to writers):
//! - a block fenced ```console holds one or more steps; a step is a line
//!   `$ COMMAND` followed by the output expected from it (stdout and stderr
//!   merged, trailing blanks ignored);
//! - `...` alone on a line matches any number of lines (none too);
//! - `[..]` inside a line matches any text within that line;
//! - ```console,ignore-reason=WHY marks a block that is not run (root,
//!   real-time measurements, minutes of search): the harness lists it with
//!   its reason.

/// One `$ COMMAND` line and the output the document expects from it.
#[derive(Debug, Clone)]
pub struct Step {
    pub command: String,
    pub expected: Vec<String>,
}

/// One ```console block of a document.
#[derive(Debug, Clone)]
pub struct Block {
    /// Index (0-based) of the opening fence's line.
    pub open: usize,
    /// Index of the closing fence's line.
    pub close: usize,
    /// The opening fence as written (kept verbatim by a bless).
    pub fence: String,
    /// Why the block is not run, when it is marked so.
    pub ignore: Option<String>,
    pub steps: Vec<Step>,
}

/// What a document holds: its console blocks, and problems that make a
/// transcript unchecked (a `$ ` block under another fence, a console block
/// without a command, a fence never closed), each as `line: message`.
#[derive(Debug, Default)]
pub struct Parsed {
    pub blocks: Vec<Block>,
    pub problems: Vec<String>,
}

/// The line that matches any number of lines.
pub const ANY_LINES: &str = "...";
/// The text that matches anything within one line.
pub const ANY_TEXT: &str = "[..]";
const FENCE: &str = "```";
const CONSOLE: &str = "console";
const IGNORE_KEY: &str = "ignore-reason=";

/// Finds every fenced block of `text` and parses the console ones.
pub fn parse(text: &str) -> Parsed {
    let lines: Vec<&str> = text.lines().collect();
    let mut parsed = Parsed::default();
    let mut i = 0;
    while i < lines.len() {
        if !lines[i].starts_with(FENCE) {
            i += 1;
            continue;
        }
        let open = i;
        let Some(close) = (open + 1..lines.len()).find(|&j| lines[j].trim_end() == FENCE) else {
            parsed
                .problems
                .push(format!("{}: a code fence is never closed", open + 1));
            break;
        };
        let info = lines[open][FENCE.len()..].trim();
        let body = &lines[open + 1..close];
        if let Some(attributes) = console_attributes(info) {
            match block(open, close, lines[open], attributes, body) {
                Ok(b) => parsed.blocks.push(b),
                Err(e) => parsed.problems.push(format!("{}: {e}", open + 1)),
            }
        } else if body.first().is_some_and(|l| l.starts_with("$ ")) {
            parsed.problems.push(format!(
                "{}: a transcript fenced ```{info} is not checked: fence it ```console",
                open + 1
            ));
        }
        i = close + 1;
    }
    parsed
}

/// `Some(attributes)` when the info string opens a console block.
fn console_attributes(info: &str) -> Option<&str> {
    let rest = info.strip_prefix(CONSOLE)?;
    if rest.is_empty() {
        Some("")
    } else {
        rest.strip_prefix(',')
    }
}

fn block(
    open: usize,
    close: usize,
    fence: &str,
    attributes: &str,
    body: &[&str],
) -> Result<Block, String> {
    let ignore = if attributes.is_empty() {
        None
    } else if let Some(reason) = attributes.strip_prefix(IGNORE_KEY) {
        if reason.trim().is_empty() {
            return Err("ignore-reason= needs a reason".into());
        }
        Some(reason.trim().to_string())
    } else {
        return Err(format!(
            "unknown console attribute `{attributes}`: the one known is {IGNORE_KEY}WHY"
        ));
    };
    let mut steps: Vec<Step> = Vec::new();
    for line in body {
        if let Some(command) = line.strip_prefix("$ ") {
            steps.push(Step {
                command: command.to_string(),
                expected: Vec::new(),
            });
        } else if let Some(step) = steps.last_mut() {
            // "…" and an indented "..." are the same elision as "...".
            let line = match line.trim() {
                "..." | "…" => ANY_LINES,
                _ => line.trim_end(),
            };
            step.expected.push(line.to_string());
        } else {
            return Err("a console block must start with a `$ COMMAND` line".into());
        }
    }
    if steps.is_empty() {
        return Err("a console block without a `$ COMMAND` line".into());
    }
    for step in &mut steps {
        trim_trailing_blanks(&mut step.expected);
    }
    Ok(Block {
        open,
        close,
        fence: fence.to_string(),
        ignore,
        steps,
    })
}

/// Drops the empty lines at the end (a blank before the next `$` line or the
/// fence is layout, not output).
pub fn trim_trailing_blanks(lines: &mut Vec<String>) {
    while lines.last().is_some_and(|l| l.is_empty()) {
        lines.pop();
    }
}

/// Whether `actual` matches the pattern line `pattern` (`[..]`: any text).
pub fn line_matches(pattern: &str, actual: &str) -> bool {
    let parts: Vec<&str> = pattern.split(ANY_TEXT).collect();
    let (first, rest) = match parts.split_first() {
        Some(split) => split,
        None => return actual.is_empty(),
    };
    let Some(mut remaining) = actual.strip_prefix(first) else {
        return false;
    };
    let Some((last, middle)) = rest.split_last() else {
        return remaining.is_empty();
    };
    for part in middle {
        match remaining.find(part) {
            Some(at) => remaining = &remaining[at + part.len()..],
            None => return false,
        }
    }
    remaining.ends_with(last)
}

/// One move of the alignment of the expected lines with the actual ones.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Move {
    /// The expected line matches the actual one.
    Keep,
    /// The expected line stands for a different actual line.
    Replace,
    /// An expected line the output lacks.
    Drop,
    /// An actual line the expected text lacks.
    Add,
    /// `...` takes one more actual line.
    Swallow,
    /// `...` is done.
    Close,
}

/// The result of holding an output against a step's expected text.
pub struct Comparison {
    pub matches: bool,
    /// The expected text rewritten to the output, its elisions kept where
    /// they still match (what a bless writes).
    pub blessed: Vec<String>,
}

/// Aligns the expected lines with the actual ones (an edit distance where
/// `...` swallows lines for free) and writes the blessed text from the
/// cheapest alignment.
pub fn compare(expected: &[String], actual: &[String]) -> Comparison {
    let moves = align(expected, actual);
    let matches = moves
        .iter()
        .all(|m| matches!(m, Move::Keep | Move::Swallow | Move::Close));
    let mut blessed = Vec::new();
    let (mut i, mut j) = (0, 0);
    for (at, &m) in moves.iter().enumerate() {
        match m {
            Move::Keep => blessed.push(expected[i].clone()),
            Move::Replace => blessed.push(reelide(&expected[i], &actual[j])),
            Move::Add if !expected.is_empty() && in_long_addition(&moves, at) => {
                if at == 0 || moves[at - 1] != Move::Add {
                    blessed.push(ANY_LINES.to_string());
                }
            }
            Move::Add => blessed.push(actual[j].clone()),
            Move::Close => blessed.push(ANY_LINES.to_string()),
            Move::Drop | Move::Swallow => {}
        }
        let (di, dj) = steps_of(m);
        i += di;
        j += dj;
    }
    Comparison { matches, blessed }
}

/// Added lines a bless writes as `...` when they run this long: a
/// transcript that showed some of the output (the page's choice of rows)
/// keeps showing those, and a new block (nothing expected yet) shows all.
const ELIDED_ADDITION: usize = 4;

/// Whether the Add at `at` is in a run of at least [`ELIDED_ADDITION`].
fn in_long_addition(moves: &[Move], at: usize) -> bool {
    let is_add = |m: &&Move| **m == Move::Add;
    let before = moves[..at].iter().rev().take_while(is_add).count();
    let after = moves[at..].iter().take_while(is_add).count();
    before + after >= ELIDED_ADDITION
}

/// How far a move advances in (expected, actual).
fn steps_of(m: Move) -> (usize, usize) {
    match m {
        Move::Keep | Move::Replace => (1, 1),
        Move::Drop | Move::Close => (1, 0),
        Move::Add | Move::Swallow => (0, 1),
    }
}

/// The cheapest sequence of moves (dynamic programming over prefixes).
fn align(expected: &[String], actual: &[String]) -> Vec<Move> {
    let (n, m) = (expected.len(), actual.len());
    let width = m + 1;
    let mut cost = vec![usize::MAX; (n + 1) * width];
    let mut how = vec![Move::Keep; (n + 1) * width];
    cost[0] = 0;
    for i in 0..=n {
        for j in 0..=m {
            if i == 0 && j == 0 {
                continue;
            }
            let best = candidates(expected, actual, i, j)
                .into_iter()
                .flatten()
                .map(|(mv, extra)| {
                    let (di, dj) = steps_of(mv);
                    (cost[(i - di) * width + j - dj].saturating_add(extra), mv)
                })
                .min_by_key(|&(c, _)| c);
            if let Some((c, mv)) = best {
                cost[i * width + j] = c;
                how[i * width + j] = mv;
            }
        }
    }
    let mut moves = Vec::new();
    let (mut i, mut j) = (n, m);
    while i > 0 || j > 0 {
        let mv = how[i * width + j];
        moves.push(mv);
        let (di, dj) = steps_of(mv);
        i -= di;
        j -= dj;
    }
    moves.reverse();
    moves
}

/// The cost of an expected line the alignment does not keep, against 1 for
/// an added line: the cheapest alignment keeps as many of the page's lines
/// as it can (a page that shows a few rows of a long output keeps showing
/// them), and adds lines only after that.
const UNSHOWN: usize = 1000;

/// The moves that can end at (i, j), with their costs; the order breaks
/// ties (a replacement, as cheap as a drop, comes first, so `[..]` carries
/// over).
fn candidates(
    expected: &[String],
    actual: &[String],
    i: usize,
    j: usize,
) -> [Option<(Move, usize)>; 4] {
    let previous = (i > 0).then(|| expected[i - 1].as_str());
    let any_lines = previous == Some(ANY_LINES);
    let diagonal = match previous {
        Some(p) if j > 0 && !any_lines => Some(if line_matches(p, &actual[j - 1]) {
            (Move::Keep, 0)
        } else {
            (Move::Replace, UNSHOWN)
        }),
        _ => None,
    };
    let down = previous.map(|_| {
        if any_lines {
            (Move::Close, 0)
        } else {
            (Move::Drop, UNSHOWN)
        }
    });
    let right = (j > 0).then_some(if any_lines {
        (Move::Swallow, 0)
    } else {
        (Move::Add, 1)
    });
    // Under `...` the Swallow must be taken from the same row, so it comes
    // from (i, j-1) like Add; Close leaves the row.
    [diagonal, right, down, None]
}

/// The actual line with the expected line's `[..]` words kept where the
/// two lines have the same words otherwise (a table row whose timing moved
/// keeps its elided column); otherwise the actual line.
fn reelide(expected: &str, actual: &str) -> String {
    if !expected.contains(ANY_TEXT) {
        return actual.to_string();
    }
    let expected_words: Vec<&str> = expected.split_whitespace().collect();
    let actual_words: Vec<(usize, &str)> = words_at(actual);
    if expected_words.len() != actual_words.len() {
        return actual.to_string();
    }
    let mut out = String::new();
    let mut copied = 0;
    for (e, (at, a)) in expected_words.iter().zip(&actual_words) {
        if e.contains(ANY_TEXT) {
            out.push_str(&actual[copied..*at]);
            out.push_str(e);
            copied = at + a.len();
        }
    }
    out.push_str(&actual[copied..]);
    out
}

/// The whitespace-separated words of a line with their byte offsets.
fn words_at(line: &str) -> Vec<(usize, &str)> {
    let mut words = Vec::new();
    let mut start = None;
    for (at, c) in line.char_indices() {
        match (c.is_whitespace(), start) {
            (true, Some(s)) => {
                words.push((s, &line[s..at]));
                start = None;
            }
            (false, None) => start = Some(at),
            _ => {}
        }
    }
    if let Some(s) = start {
        words.push((s, &line[s..]));
    }
    words
}
