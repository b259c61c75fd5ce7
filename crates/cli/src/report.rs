//! Rendering that several commands' reports share, one module per kind of
//! report (the commands print their own reports from these parts).

pub mod analysis;
pub mod flight;
pub mod margins;
pub mod samples;

use rtpipe_model::{Nanos, Spec};

/// Keys and values serialized as a JSON object in their order (the keys
/// come from the spec or the analysis, so they are not struct fields).
pub struct Pairs<K, V>(pub Vec<(K, V)>);

impl<K: serde::Serialize, V: serde::Serialize> serde::Serialize for Pairs<K, V> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

/// An object whose keys are data (task names, bound names), each value a `V`.
impl<K, V: schemars::JsonSchema> schemars::JsonSchema for Pairs<K, V> {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        format!("Pairs_{}", V::schema_name()).into()
    }

    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "type": "object",
            "additionalProperties": generator.subschema_for::<V>(),
        })
    }
}

/// A time in the spec's unit; `None` (JSON null) for none.
pub fn time(spec: &Spec, ns: Option<Nanos>) -> Option<f64> {
    ns.map(|n| spec.in_unit(n))
}

/// A table of one row, built from its fields (name, kind, value) in
/// order: a report's figures that are one record, not a list.
pub fn record_table(
    name: &str,
    fields: Vec<(&str, rtpipe_printer::Kind, rtpipe_printer::Cell)>,
) -> rtpipe_printer::Table {
    let columns = fields
        .iter()
        .map(|(n, k, _)| rtpipe_printer::Column::new(*n, *k))
        .collect();
    let Ok(mut t) = rtpipe_printer::Table::new(name, columns) else {
        unreachable!("table `{name}`: a record's fields are distinct names");
    };
    t.push(fields.into_iter().map(|(_, _, c)| c).collect());
    t
}
