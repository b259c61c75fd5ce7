//! The CSV printer (RFC 4180): one field rule, `rtpipe_model::output::
//! csv_field` (quotes where a comma, quote or line break needs them, and a
//! spreadsheet formula neutralised), for headers and text cells alike; a
//! header is never otherwise changed. Numbers are written as they are (a
//! minus sign is not a formula). Lines end in `\n`.

use crate::{Cell, Table};
use rtpipe_model::output::csv_field;

/// One table: its header line, then a line per row.
pub fn table(t: &Table) -> String {
    let mut out = header(t);
    for row in t.rows() {
        out.push_str(&row_line(row));
    }
    out
}

/// One row's line: text cells by the field rule, numbers as they are.
pub fn row_line(row: &[Cell]) -> String {
    let mut out = String::new();
    for (i, c) in row.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        match c {
            Cell::Text(s) => out.push_str(&csv_field(s)),
            other => out.push_str(&other.plain()),
        }
    }
    out.push('\n');
    out
}

/// The header line of `t` (for a writer that streams the rows).
pub fn header(t: &Table) -> String {
    line(t.columns().iter().map(|c| c.name.clone()))
}

/// One line of text fields, each quoted by the one rule.
pub fn line(fields: impl IntoIterator<Item = String>) -> String {
    let mut out = String::new();
    for (i, f) in fields.into_iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(&csv_field(&f));
    }
    out.push('\n');
    out
}

/// Several tables: one alone is plain CSV; several are each a complete
/// CSV (header, rows) after a `# NAME` line, separated by an empty line,
/// so a reader splits them at the empty lines.
pub fn tables(ts: &[Table]) -> String {
    if let [one] = ts {
        return table(one);
    }
    let parts: Vec<String> = ts
        .iter()
        .map(|t| format!("# {}\n{}", t.name(), table(t)))
        .collect();
    parts.join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Column, Kind};

    fn chains() -> Table {
        let mut t = Table::new(
            "chains",
            vec![
                Column::new("chain", Kind::Text),
                Column::new("bound, ms", Kind::Float),
                Column::new("jobs", Kind::OptInt),
            ],
        )
        .expect("distinct names");
        t.push(vec![Cell::from("a \"b\""), Cell::Float(0.25), Cell::Int(3)]);
        t.push(vec![Cell::from("=cmd"), Cell::Fixed(1.0, 3), Cell::Empty]);
        t.push(vec![Cell::from("-x"), Cell::Float(-0.5), Cell::Int(-2)]);
        t
    }

    #[test]
    fn headers_and_cells_follow_one_quoting_rule() {
        assert_eq!(
            table(&chains()),
            "chain,\"bound, ms\",jobs\n\"a \"\"b\"\"\",0.25,3\n\"'=cmd\",1.000,\n\"'-x\",-0.5,-2\n"
        );
    }

    #[test]
    fn several_tables_are_named_and_split_by_an_empty_line() {
        let one = Table::new("one", vec![Column::new("x", Kind::Bool)]).expect("one column");
        let out = tables(&[one, chains()]);
        assert!(out.starts_with("# one\nx\n\n# chains\nchain,"), "{out}");
    }
}
