//! rtpipe's report layer: every format a command's report is printed in
//! lives here, one module per format.
//!
//! A report is a value that derives `Serialize` (its JSON) and implements
//! [`Report`]: its text for people and its [`Table`]s (named, typed
//! columns; rows) for CSV. [`print`] picks the printer the user's
//! [`Format`] names, so a command never formats its own output: adding a
//! format is one printer module and one arm in [`print`].

#![deny(missing_docs)]

pub mod csv;
mod table;
pub mod text;

pub use table::{Cell, Column, DuplicateColumn, Kind, Table};

use serde::Serialize;

/// The format a report is printed in (`--format`; `--json` is `json`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// Aligned tables and prose for people.
    #[default]
    Text,
    /// One JSON object (the report's `Serialize`).
    Json,
    /// The report's tables as RFC 4180 CSV.
    Csv,
}

impl Format {
    /// Every format, in the order the help lists them.
    pub const ALL: [Format; 3] = [Format::Text, Format::Json, Format::Csv];

    /// The name `--format` takes.
    pub fn name(self) -> &'static str {
        match self {
            Format::Text => "text",
            Format::Json => "json",
            Format::Csv => "csv",
        }
    }
}

impl std::str::FromStr for Format {
    type Err = String;

    fn from_str(s: &str) -> Result<Format, String> {
        Format::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| format!("unknown format `{s}`: use text, json or csv"))
    }
}

/// A command's report: its JSON is its `Serialize`, its text and its
/// tables are given here.
pub trait Report: Serialize {
    /// The report for people (what `--format text` prints).
    fn text(&self) -> String;

    /// The report's tables, in order (what `--format csv` prints).
    fn tables(&self) -> Vec<Table>;
}

/// A report printed: text (`text` or `csv`) to print as it is, or a JSON
/// value (printed pretty by the binary, handed to Python as objects).
#[derive(Debug, Clone, PartialEq)]
pub enum Printed {
    /// Text to print as it is.
    Text(String),
    /// The JSON value of the report.
    Json(serde_json::Value),
}

/// `report` in `format`; an error only when the report cannot be encoded
/// as JSON (a bug: a map with non-string keys).
pub fn print<R: Report>(report: &R, format: Format) -> Result<Printed, serde_json::Error> {
    Ok(match format {
        Format::Text => Printed::Text(report.text()),
        Format::Json => Printed::Json(serde_json::to_value(report)?),
        Format::Csv => Printed::Text(csv::tables(&report.tables())),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Tiny {
        name: &'static str,
        value: f64,
    }

    impl Report for Tiny {
        fn text(&self) -> String {
            format!("{} = {}\n", self.name, self.value)
        }

        fn tables(&self) -> Vec<Table> {
            let mut t = Table::new(
                "tiny",
                vec![
                    Column::new("name", Kind::Text),
                    Column::new("value", Kind::Float),
                ],
            )
            .expect("distinct names");
            t.push(vec![Cell::from(self.name), Cell::Float(self.value)]);
            vec![t]
        }
    }

    #[test]
    fn one_report_prints_in_every_format() {
        let r = Tiny {
            name: "a, b",
            value: 1.5,
        };
        assert_eq!(
            print(&r, Format::Text).ok(),
            Some(Printed::Text("a, b = 1.5\n".into()))
        );
        assert_eq!(
            print(&r, Format::Json).ok(),
            Some(Printed::Json(
                serde_json::json!({"name": "a, b", "value": 1.5})
            ))
        );
        assert_eq!(
            print(&r, Format::Csv).ok(),
            Some(Printed::Text("name,value\n\"a, b\",1.5\n".into()))
        );
    }

    #[test]
    fn formats_are_named_and_parsed_alike() {
        for f in Format::ALL {
            assert_eq!(f.name().parse::<Format>(), Ok(f));
        }
        let e = "xml".parse::<Format>().err().unwrap_or_default();
        assert!(
            e.contains("`xml`") && e.contains("text, json or csv"),
            "{e}"
        );
    }
}
