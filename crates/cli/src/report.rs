//! Rendering that several commands' reports share, one module per kind of
//! report (the commands print their own reports from these parts).

pub mod flight;

use rtpipe_model::{Nanos, Spec};
use serde_json::{json, Value};

/// A time in the spec's unit; `None` (JSON null) for none.
pub fn time(spec: &Spec, ns: Option<Nanos>) -> Option<f64> {
    ns.map(|n| spec.in_unit(n))
}

/// A time in the spec's unit as a JSON number; `null` for none.
pub fn num(spec: &Spec, ns: Option<Nanos>) -> Value {
    ns.map_or(Value::Null, |n| json!(spec.in_unit(n)))
}
