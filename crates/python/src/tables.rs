//! A report's tables (the `rtpipe_printer::Table`s `--format csv` prints)
//! as columns for Python: each numeric column one little-endian buffer
//! that numpy views without copying, with a mask buffer where a cell is
//! empty; text columns a list of str. `rtpipe._record.Table` reads them.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use rtpipe_printer::{Cell, Kind, Table};

/// `name -> (column names, {column: (dtype, data, mask or None)})`, in
/// the report's order (a dict keeps it).
pub fn tables_to_py<'py>(py: Python<'py>, tables: &[Table]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for t in tables {
        let names: Vec<&str> = t.columns().iter().map(|c| c.name.as_str()).collect();
        let cols = PyDict::new(py);
        for (i, c) in t.columns().iter().enumerate() {
            let cells = t.rows().iter().map(|r| &r[i]);
            cols.set_item(&c.name, column(py, c.kind, cells)?)?;
        }
        out.set_item(t.name(), (names, cols))?;
    }
    Ok(out)
}

/// One column as `(dtype, data, mask)`: dtype a numpy type string ("<i8",
/// "<u8", "<f8", "|b1") or "str" (data a list); mask one byte per row, 1
/// where the cell is empty, or None when none is.
fn column<'py, 'a>(
    py: Python<'py>,
    kind: Kind,
    cells: impl Iterator<Item = &'a Cell>,
) -> PyResult<Bound<'py, PyAny>> {
    let cells: Vec<&Cell> = cells.collect();
    let mask: Vec<u8> = cells.iter().map(|c| u8::from(**c == Cell::Empty)).collect();
    let mask = if mask.contains(&1) {
        PyBytes::new(py, &mask).into_any()
    } else {
        py.None().into_bound(py)
    };
    let (dtype, data): (&str, Bound<'py, PyAny>) = match kind {
        Kind::Text => {
            let text: Vec<String> = cells.iter().map(|c| c.plain()).collect();
            ("str", PyList::new(py, text)?.into_any())
        }
        Kind::Float => (
            "<f8",
            bytes(py, cells.iter().map(|c| float(c).to_le_bytes())),
        ),
        Kind::UInt => (
            "<u8",
            bytes(py, cells.iter().map(|c| unsigned(c).to_le_bytes())),
        ),
        Kind::Bool => (
            "|b1",
            bytes(
                py,
                cells.iter().map(|c| [u8::from(**c == Cell::Bool(true))]),
            ),
        ),
        Kind::Int | Kind::Count | Kind::OptInt => (
            "<i8",
            bytes(py, cells.iter().map(|c| signed(c).to_le_bytes())),
        ),
    };
    (dtype, data, mask).into_pyobject(py).map(Bound::into_any)
}

fn bytes<'py, const N: usize>(
    py: Python<'py>,
    items: impl Iterator<Item = [u8; N]>,
) -> Bound<'py, PyAny> {
    let raw: Vec<u8> = items.flatten().collect();
    PyBytes::new(py, &raw).into_any()
}

/// A float cell's value; NaN for an empty one (the mask says so too).
fn float(c: &Cell) -> f64 {
    match c {
        Cell::Float(v) | Cell::Fixed(v, _) => *v,
        Cell::Int(v) => *v as f64,
        Cell::UInt(v) => *v as f64,
        _ => f64::NAN,
    }
}

/// An integer cell's value; 0 for an empty one (masked).
fn signed(c: &Cell) -> i64 {
    match c {
        Cell::Int(v) => *v,
        Cell::UInt(v) => i64::try_from(*v).unwrap_or(i64::MAX),
        _ => 0,
    }
}

fn unsigned(c: &Cell) -> u64 {
    match c {
        Cell::UInt(v) => *v,
        Cell::Int(v) => u64::try_from(*v).unwrap_or(0),
        _ => 0,
    }
}
