//! Task and ECU ids of any size. E2EEvaluation's ids are Python ints (its
//! WATERS task sets draw them from `uuid4().int`, up to 2^128 − 1), which
//! no machine integer type of the YAML parser holds; they are kept as the
//! decimal text they are written in, ordered as the numbers they are.

use serde_yaml::Value;
use std::borrow::Cow;
use std::cmp::Ordering;
use std::fmt;

/// An integer id of any size, canonical decimal (no leading zeros, no
/// "-0").
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct Id {
    negative: bool,
    digits: String,
}

/// The most digits an id may have: tasks are named `t<TaskID>` and specs
/// `<stem>-ecu<ECU>`, which must stay printable names and file names
/// (E2EEvaluation's largest ids, `uuid4().int`, have 39).
pub(crate) const MAX_ID_DIGITS: usize = 100;

impl Id {
    /// How many digits the id has.
    pub(crate) fn digits(&self) -> usize {
        self.digits.len()
    }

    /// The id of a YAML value: an integer, or the decimal text of one that
    /// [`quote_big_integers`] quoted. `None` for anything else.
    pub(crate) fn of(v: &Value) -> Option<Id> {
        match v {
            Value::Number(n) if n.is_i64() || n.is_u64() => Id::parse(&n.to_string()),
            Value::String(s) => Id::parse(s),
            _ => None,
        }
    }

    fn parse(s: &str) -> Option<Id> {
        let (negative, digits) = match s.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, s),
        };
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let digits = digits.trim_start_matches('0');
        let digits = if digits.is_empty() { "0" } else { digits };
        Some(Id {
            negative: negative && digits != "0",
            digits: digits.to_string(),
        })
    }
}

impl Ord for Id {
    fn cmp(&self, other: &Id) -> Ordering {
        let magnitude = (self.digits.len(), &self.digits).cmp(&(other.digits.len(), &other.digits));
        match (self.negative, other.negative) {
            (false, false) => magnitude,
            (true, true) => magnitude.reverse(),
            (true, false) => Ordering::Less,
            (false, true) => Ordering::Greater,
        }
    }
}

impl PartialOrd for Id {
    fn partial_cmp(&self, other: &Id) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl fmt::Display for Id {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.negative {
            f.write_str("-")?;
        }
        f.write_str(&self.digits)
    }
}

/// Integers too long for an i64 (19 digits or more) as plain YAML scalars
/// get double quotes, so that the parser keeps their text; quoted strings
/// and comments are left alone. Linear in the text.
pub(crate) fn quote_big_integers(text: &str) -> Cow<'_, str> {
    let b = text.as_bytes();
    let mut out: Option<String> = None;
    let mut copied = 0;
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'"' | b'\'' => i = skip_quoted(b, i),
            b'#' if i == 0 || b[i - 1].is_ascii_whitespace() => {
                i = b[i..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |p| i + p)
            }
            c if c.is_ascii_digit() || c == b'-' => {
                let end = scalar_end(b, i);
                if is_big_integer(b, i, end) {
                    let s = out.get_or_insert_with(String::new);
                    s.push_str(&text[copied..i]);
                    s.push('"');
                    s.push_str(&text[i..end]);
                    s.push('"');
                    copied = end;
                }
                i = end.max(i + 1);
            }
            _ => i += 1,
        }
    }
    match out {
        None => Cow::Borrowed(text),
        Some(mut s) => {
            s.push_str(&text[copied..]);
            Cow::Owned(s)
        }
    }
}

/// The index after the quoted scalar that starts at `i` (YAML's '' and \"
/// escapes); the end of the text when it never closes.
fn skip_quoted(b: &[u8], i: usize) -> usize {
    let q = b[i];
    let mut k = i + 1;
    while k < b.len() {
        match b[k] {
            b'\\' if q == b'"' => k += 2,
            c if c == q && q == b'\'' && b.get(k + 1) == Some(&b'\'') => k += 2,
            c if c == q => return k + 1,
            _ => k += 1,
        }
    }
    b.len()
}

/// Where a plain scalar starting at `i` ends: at a flow indicator, a
/// space, a line end or the text's end.
fn scalar_end(b: &[u8], i: usize) -> usize {
    b[i..]
        .iter()
        .position(|c| matches!(c, b',' | b']' | b'}' | b' ' | b'\t' | b'\r' | b'\n'))
        .map_or(b.len(), |p| i + p)
}

/// `b[i..end]` is an optionally signed run of 19 or more digits that
/// stands as a scalar of its own (after a flow indicator, a space or a
/// line start).
fn is_big_integer(b: &[u8], i: usize, end: usize) -> bool {
    let own = i == 0 || matches!(b[i - 1], b' ' | b'\t' | b'\n' | b'[' | b',' | b'{');
    let s = &b[i..end];
    let digits = s.strip_prefix(b"-").unwrap_or(s);
    own && digits.len() >= 19 && digits.iter().all(u8::is_ascii_digit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn big_integers_are_quoted_and_nothing_else_is() {
        let big = "52188295052327366710525154717987669201";
        let text = format!(
            "Chains:\n- [{big}, 7]\n# {big} in a comment\nTasks:\n- !Task {{ECU: {big}, Name: '{big}', Period: 1.5, TaskID: {big}}}\n"
        );
        let q = quote_big_integers(&text);
        assert_eq!(
            q,
            format!(
                "Chains:\n- [\"{big}\", 7]\n# {big} in a comment\nTasks:\n- !Task {{ECU: \"{big}\", Name: '{big}', Period: 1.5, TaskID: \"{big}\"}}\n"
            )
        );
        // Small integers and floats stay as they are.
        let small = "x: [9223372036854775, 1.0e30, -12]\n";
        assert!(matches!(quote_big_integers(small), Cow::Borrowed(_)));
    }

    #[test]
    fn ids_order_as_numbers_whatever_their_size() {
        let v = |s: &str| Id::parse(s).unwrap_or_else(|| panic!("{s}"));
        let mut ids = [
            v("52188295052327366710525154717987669201"),
            v("-3"),
            v("10"),
            v("9"),
            v("-40"),
            v("0"),
            v("340282366920938463463374607431768211455"),
        ];
        ids.sort();
        let shown: Vec<String> = ids.iter().map(Id::to_string).collect();
        assert_eq!(
            shown,
            [
                "-40",
                "-3",
                "0",
                "9",
                "10",
                "52188295052327366710525154717987669201",
                "340282366920938463463374607431768211455"
            ]
        );
        assert_eq!(v("007"), v("7"));
        assert_eq!(v("-0"), v("0"));
        assert!(Id::parse("1.5").is_none() && Id::parse("").is_none() && Id::parse("-").is_none());
    }
}
