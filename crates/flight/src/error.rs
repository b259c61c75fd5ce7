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

/// The text of a user's configuration file (a preset or a mission); an
/// error names the file.
pub fn read_file(path: &std::path::Path) -> Result<String, ConfigError> {
    std::fs::read_to_string(path)
        .map_err(|e| ConfigError::new(path.display().to_string(), e.to_string()))
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
