//! The text printer: plain aligned tables for people (two spaces before
//! and between columns, numbers right-aligned, no trailing blanks).

use crate::{Kind, Table};

/// An aligned table of text cells, built row by row (the reports' own
/// text uses it for tables among their prose).
pub struct TextTable {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
    /// Columns aligned to the right (numbers).
    right: Vec<bool>,
}

impl TextTable {
    /// A table with this header.
    pub fn new(header: &[&str]) -> TextTable {
        TextTable {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
            right: vec![false; header.len()],
        }
    }

    /// Right-align the given columns.
    pub fn numeric(mut self, cols: &[usize]) -> TextTable {
        for &c in cols {
            if c < self.right.len() {
                self.right[c] = true;
            }
        }
        self
    }

    /// Adds a row.
    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// The table, a line per row after the header.
    pub fn render(&self) -> String {
        let n = self.header.len();
        let mut w = vec![0; n];
        for r in std::iter::once(&self.header).chain(&self.rows) {
            for (i, c) in r.iter().enumerate().take(n) {
                w[i] = w[i].max(c.chars().count());
            }
        }
        let mut out = String::new();
        for r in std::iter::once(&self.header).chain(&self.rows) {
            let mut line = String::from("  ");
            for (i, c) in r.iter().enumerate().take(n) {
                let pad = w[i] - c.chars().count();
                if self.right[i] {
                    line.push_str(&" ".repeat(pad));
                    line.push_str(c);
                } else {
                    line.push_str(c);
                    line.push_str(&" ".repeat(pad));
                }
                if i + 1 < n {
                    line.push_str("  ");
                }
            }
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out
    }
}

/// A typed [`Table`] aligned for people: numbers to the right.
pub fn table(t: &Table) -> String {
    let header: Vec<&str> = t.columns().iter().map(|c| c.name.as_str()).collect();
    let numeric: Vec<usize> = (t.columns().iter().enumerate())
        .filter(|(_, c)| c.kind != Kind::Text)
        .map(|(i, _)| i)
        .collect();
    let mut out = TextTable::new(&header).numeric(&numeric);
    for row in t.rows() {
        out.row(row.iter().map(|c| c.plain()).collect());
    }
    out.render()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Cell, Column};

    #[test]
    fn numbers_align_right_and_text_left() {
        let mut t = Table::new(
            "t",
            vec![Column::new("task", Kind::Text), Column::new("n", Kind::Int)],
        )
        .expect("distinct names");
        t.push(vec![Cell::from("gyro"), Cell::Int(5)]);
        t.push(vec![Cell::from("pid"), Cell::Int(10)]);
        assert_eq!(table(&t), "  task   n\n  gyro   5\n  pid   10\n");
    }
}
