//! The one error type of the crate: a bad configuration (preset, mission,
//! filter) with the offending field named.

use std::fmt;

/// A configuration value was missing, malformed or out of range.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfigError {
    /// Dotted path of the offending field (e.g. `body.mass_kg`, `step[3].at`).
    pub field: String,
    /// What is wrong with it.
    pub reason: String,
}

impl ConfigError {
    /// An error about `field`.
    pub fn new(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid `{}`: {}", self.field, self.reason)
    }
}

impl std::error::Error for ConfigError {}

/// A configuration error found in the file `path` of `kind`, whose text
/// is `text`, as the file's error: at the line and column of the field
/// when the text writes it the usual way, else named by the file.
pub fn in_file(
    path: &std::path::Path,
    text: &str,
    e: ConfigError,
    kind: &rtpipe_model::input::Kind,
) -> rtpipe_model::SpecError {
    let span = rtpipe_model::input::locate(text, &e.field);
    rtpipe_model::SpecError {
        file: path.display().to_string(),
        source: if span.is_some() {
            text.to_string()
        } else {
            String::new()
        },
        diagnostics: vec![rtpipe_model::Diagnostic::new(e.to_string(), span).help(kind.help)],
    }
}

/// Reads the file `path` of `kind` by the rules of every input file
/// ([`rtpipe_model::input`]), parses it into `T` and checks it with
/// `check`; every error names the file, and its line and column when known.
pub fn load<T: serde::de::DeserializeOwned, U>(
    path: &std::path::Path,
    kind: &rtpipe_model::input::Kind,
    check: impl FnOnce(T) -> Result<U, ConfigError>,
) -> Result<U, rtpipe_model::SpecError> {
    let text = rtpipe_model::input::read_text(path, kind)?;
    let parsed: T = rtpipe_model::input::parse_toml(&path.display().to_string(), &text, kind)?;
    check(parsed).map_err(|e| in_file(path, &text, e, kind))
}

/// Ok if `name` (the field `field`) is a name that prints as itself: not
/// empty, at most 256 characters, no control, bidirectional or invisible
/// characters ([`rtpipe_model::input::name_problem`]).
pub fn check_name(field: &str, name: &str) -> Result<(), ConfigError> {
    match rtpipe_model::input::name_problem(name) {
        None => Ok(()),
        Some(p) => Err(ConfigError::new(
            field,
            format!(
                "\"{}\" {p}; use a short printable name",
                rtpipe_model::input::shown_name(name)
            ),
        )),
    }
}

/// Ok if free text (the field `field`) holds no control character other
/// than line feeds and tabs (a terminal would obey it when it is shown).
pub fn check_text(field: &str, text: &str) -> Result<(), ConfigError> {
    match text
        .chars()
        .find(|&c| c.is_control() && !matches!(c, '\n' | '\t'))
    {
        None => Ok(()),
        Some(c) => Err(ConfigError::new(
            field,
            format!(
                "contains the control character U+{:04X}; remove it",
                c as u32
            ),
        )),
    }
}

/// Ok if `v` is finite and `v > 0`, else an error naming `field`.
pub fn positive(field: &str, v: f64) -> Result<f64, ConfigError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ConfigError::new(field, format!("must be > 0, got {v}")))
    }
}

/// Ok if `v` is finite and `v >= 0`, else an error naming `field`.
pub fn non_negative(field: &str, v: f64) -> Result<f64, ConfigError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ConfigError::new(field, format!("must be >= 0, got {v}")))
    }
}

/// Ok if `lo <= v <= hi`, else an error naming `field`.
pub fn in_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<f64, ConfigError> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(ConfigError::new(
            field,
            format!("must be in [{lo}, {hi}], got {v}"),
        ))
    }
}
