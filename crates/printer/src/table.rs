//! A table: a name, named and typed columns, and rows of cells.

/// What a column holds (CSV writes every kind as text; Parquet and other
/// typed writers map each to their type).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Text.
    Text,
    /// A signed integer.
    Int,
    /// An unsigned integer.
    UInt,
    /// An unsigned count below 2^31 (a typed writer may store it in 32
    /// bits).
    Count,
    /// A floating-point number.
    Float,
    /// True or false.
    Bool,
    /// A signed integer that may be absent (an empty CSV field).
    OptInt,
}

/// A named, typed column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// The header, written as it is (CSV quotes it where it must, never
    /// changes it).
    pub name: String,
    /// What its cells hold.
    pub kind: Kind,
}

impl Column {
    /// A column named `name` holding `kind`.
    pub fn new(name: impl Into<String>, kind: Kind) -> Column {
        Column {
            name: name.into(),
            kind,
        }
    }
}

/// One value of a row.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// Text.
    Text(String),
    /// A signed integer.
    Int(i64),
    /// An unsigned integer.
    UInt(u64),
    /// A floating-point number, written in the shortest form that reads
    /// back the same.
    Float(f64),
    /// A number written with a fixed number of decimals.
    Fixed(f64, usize),
    /// True or false.
    Bool(bool),
    /// No value (an [`Kind::OptInt`]'s or a float's absence).
    Empty,
}

impl From<&str> for Cell {
    fn from(s: &str) -> Cell {
        Cell::Text(s.to_string())
    }
}

impl From<String> for Cell {
    fn from(s: String) -> Cell {
        Cell::Text(s)
    }
}

impl Cell {
    /// An optional signed integer: [`Cell::Empty`] for none.
    pub fn opt_int(v: Option<i64>) -> Cell {
        v.map_or(Cell::Empty, Cell::Int)
    }

    /// An optional float: [`Cell::Empty`] for none.
    pub fn opt_float(v: Option<f64>) -> Cell {
        v.map_or(Cell::Empty, Cell::Float)
    }

    /// Whether this cell may stand in a column of `kind`.
    fn fits(&self, kind: Kind) -> bool {
        matches!(
            (self, kind),
            (Cell::Text(_), Kind::Text)
                | (Cell::Int(_), Kind::Int | Kind::OptInt)
                | (Cell::UInt(_), Kind::UInt)
                | (Cell::UInt(0..=0x7fff_ffff), Kind::Count)
                | (Cell::Float(_) | Cell::Fixed(..), Kind::Float)
                | (Cell::Bool(_), Kind::Bool)
                | (Cell::Empty, Kind::OptInt | Kind::Float | Kind::Text)
        )
    }

    /// The cell as text, unquoted (the printers quote).
    pub fn plain(&self) -> String {
        match self {
            Cell::Text(s) => s.clone(),
            Cell::Int(v) => v.to_string(),
            Cell::UInt(v) => v.to_string(),
            Cell::Float(v) => v.to_string(),
            Cell::Fixed(v, places) => format!("{v:.places$}"),
            Cell::Bool(b) => b.to_string(),
            Cell::Empty => String::new(),
        }
    }
}

/// Two columns of one table share a name (a reader could not tell them
/// apart, so no table holds such a pair).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DuplicateColumn {
    /// The table's name.
    pub table: String,
    /// The name two columns share.
    pub column: String,
}

impl std::fmt::Display for DuplicateColumn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "table `{}` has two columns named `{}`",
            self.table, self.column
        )
    }
}

impl std::error::Error for DuplicateColumn {}

/// Named, typed columns and rows of cells; no two columns share a name.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    name: String,
    columns: Vec<Column>,
    rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table; refused when two columns share a name.
    pub fn new(name: impl Into<String>, columns: Vec<Column>) -> Result<Table, DuplicateColumn> {
        let name = name.into();
        let mut seen = std::collections::HashSet::new();
        if let Some(c) = columns.iter().find(|c| !seen.insert(c.name.as_str())) {
            return Err(DuplicateColumn {
                table: name,
                column: c.name.clone(),
            });
        }
        Ok(Table {
            name,
            columns,
            rows: Vec::new(),
        })
    }

    /// Adds a row: one cell per column, each of its column's kind (a
    /// wrong row is a bug in the report that builds it).
    pub fn push(&mut self, row: Vec<Cell>) {
        assert_eq!(
            row.len(),
            self.columns.len(),
            "table `{}`: a row has one cell per column",
            self.name
        );
        for (cell, col) in row.iter().zip(&self.columns) {
            assert!(
                cell.fits(col.kind),
                "table `{}`: column `{}` holds {:?}, not {cell:?}",
                self.name,
                col.name,
                col.kind
            );
        }
        self.rows.push(row);
    }

    /// The table's name (what a reader of several tables tells them by).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The columns, in order.
    pub fn columns(&self) -> &[Column] {
        &self.columns
    }

    /// The rows, in order.
    pub fn rows(&self) -> &[Vec<Cell>] {
        &self.rows
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_columns_of_one_name_are_refused() {
        let cols = vec![
            Column::new("gyro path_reaction_ms", Kind::Float),
            Column::new("gyro-path_reaction_ms", Kind::Float),
        ];
        assert!(Table::new("log", cols.clone()).is_ok());
        let twice = vec![cols[0].clone(), cols[0].clone()];
        let e = Table::new("log", twice).err();
        assert_eq!(
            e.map(|e| e.to_string()),
            Some("table `log` has two columns named `gyro path_reaction_ms`".into())
        );
    }

    #[test]
    #[should_panic(expected = "column `n` holds Int")]
    fn a_cell_of_another_kind_is_a_bug() {
        let mut t = Table::new("t", vec![Column::new("n", Kind::Int)]).expect("one column");
        t.push(vec![Cell::from("x")]);
    }
}
