//! The JSON Schema of every command's `--json` report, derived from the
//! view structs that serialize it (`schemars::JsonSchema` beside
//! `serde::Serialize`, the fields' doc comments its descriptions). It is
//! the one source of the Python package's typed results:
//! `crates/cli/tests/python_reports.rs` renders
//! `crates/python/python/rtpipe/reports.py` from it.

/// One report: the Python class that holds it, the command that answers
/// it, and its schema.
pub struct ReportSchema {
    /// The class name in `rtpipe.reports`.
    pub class: &'static str,
    /// The command (and flag) whose `--json` it is.
    pub command: &'static str,
    /// The schema, its nested objects under `$defs`.
    pub schema: schemars::Schema,
}

/// Every report, in the order the Python module lists them.
pub fn all() -> Vec<ReportSchema> {
    let one = |class, command, schema| ReportSchema {
        class,
        command,
        schema,
    };
    vec![
        one("AnalysisReport", "analyze", crate::analyze::json_schema()),
        one(
            "SimulationReport",
            "simulate",
            crate::simulate::json_schema(),
        ),
        one("FlightReport", "fly", crate::fly::json_schema()),
        one(
            "SweepReport",
            "fly --sweep",
            crate::fly::sweep_json_schema(),
        ),
        one("DesignReport", "design", crate::design::json_schema()),
        one("RunReport", "run", crate::run::json_schema()),
        one(
            "CampaignSummary",
            "campaign",
            crate::campaign::json_schema(),
        ),
        one(
            "CampaignPlan",
            "campaign --plan",
            crate::campaign::plan_json_schema(),
        ),
    ]
}
