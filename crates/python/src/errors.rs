//! What the exceptions carry besides their message: the place and the
//! fix of a spec's problems (`SpecError`), read from the spec's text.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rtpipe_model::SpecError as ModelError;

/// The TOML key at byte `offset` of `source`: the table header above it
/// and the key its line assigns (`tasks.gyro.period`), or the header
/// itself on a header line; None before any key (or in a text that is
/// not a spec's TOML lines).
pub fn key_at(source: &str, offset: usize) -> Option<String> {
    let before = source.get(..offset.min(source.len()))?;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line = source[line_start..].lines().next().unwrap_or("");
    let header = |l: &str| {
        let l = l.trim();
        let inner = l.strip_prefix('[')?.trim_start_matches('[');
        let end = inner.find(']')?;
        Some(inner[..end].trim().replace(['"', '\''], ""))
    };
    if let Some(h) = header(line) {
        return Some(h);
    }
    let table = source[..line_start].lines().rev().find_map(header);
    let key = line
        .split_once('=')
        .map(|(k, _)| k.trim().replace(['"', '\''], ""));
    match (table, key) {
        (Some(t), Some(k)) if !k.is_empty() => Some(format!("{t}.{k}")),
        (None, Some(k)) if !k.is_empty() => Some(k),
        (t, _) => t,
    }
}

/// The diagnostics of a spec error as dicts (message, help, line,
/// column, key), in order.
pub fn diagnostics<'py>(py: Python<'py>, e: &ModelError) -> PyResult<Vec<Bound<'py, PyDict>>> {
    e.diagnostics
        .iter()
        .map(|d| {
            let at = d
                .span
                .as_ref()
                .map(|s| (e.line_col(s.start), key_at(&e.source, s.start)));
            let item = PyDict::new(py);
            item.set_item("message", &d.message)?;
            item.set_item("help", &d.help)?;
            item.set_item("line", at.as_ref().map(|((l, _), _)| *l))?;
            item.set_item("column", at.as_ref().map(|((_, c), _)| *c))?;
            item.set_item("key", at.and_then(|(_, k)| k))?;
            Ok(item)
        })
        .collect()
}

/// Sets `file` and `diagnostics` on a SpecError, and the first problem's
/// `line`, `column`, `key`, `message` and `fix` (its help) as attributes
/// of their own.
pub fn describe_spec_error(py: Python<'_>, err: &PyErr, e: &ModelError) -> PyResult<()> {
    let value = err.value(py);
    let items = diagnostics(py, e)?;
    value.setattr("file", &e.file)?;
    for attr in ["line", "column", "key", "message"] {
        let first = match items.first() {
            Some(d) => d.get_item(attr)?,
            None => None,
        };
        value.setattr(attr, first)?;
    }
    let fix = match items.first() {
        Some(d) => d.get_item("help")?,
        None => None,
    };
    value.setattr("fix", fix)?;
    value.setattr("diagnostics", items)?;
    Ok(())
}
