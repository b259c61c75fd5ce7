//! `design --objective margin --max-utilization U` and `design --margins`:
//! the flags, and the margin search and the answer's margins in the report
//! (the margins themselves are rendered as `analyze --margins` renders
//! them).

use super::{DesignArgs, ObjectiveArg};
use crate::report::margins;
use rtpipe_analysis::margins::Margins;
use rtpipe_design::{MarginSearch, Objective, Outcome};
use rtpipe_model::Diagnostic;
use serde::Serialize;

/// `--max-utilization`: a positive finite number.
pub fn parse_cap(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(u) if u.is_finite() && u > 0.0 => Ok(u),
        _ => Err(
            "must be a positive number (a total utilisation, e.g. --max-utilization 0.8)".into(),
        ),
    }
}

/// The objective the flags ask for; `--max-utilization` belongs to
/// `--objective margin` and is required there.
pub fn objective(a: &DesignArgs) -> Result<Objective, Diagnostic> {
    match (a.objective, a.max_utilization) {
        (ObjectiveArg::Utilization, None) => Ok(Objective::Utilization),
        (ObjectiveArg::Utilization, Some(_)) => Err(Diagnostic::error(
            "--max-utilization caps the utilisation of --objective margin, which is not given (the least-utilisation design needs no cap)",
            "add --objective margin, or drop --max-utilization",
        )),
        (ObjectiveArg::Margin, None) => Err(Diagnostic::error(
            "--objective margin needs a utilisation cap: without one, longer periods always buy more margin",
            "add --max-utilization U (e.g. 0.8)",
        )),
        (ObjectiveArg::Margin, Some(max_utilization)) => {
            if !a.missions.is_empty() {
                return Err(Diagnostic::error(
                    "--fly with --objective margin would fly every factor's design: not supported",
                    "design with --objective margin, then check the answer with `rtpipe fly`",
                ));
            }
            Ok(Objective::Margin { max_utilization })
        }
    }
}

/// The margin search and the answer's margins, added to the report.
pub fn append_text(t: &mut String, out: &Outcome, found: Option<&Margins>) {
    if let Some(m) = &out.margin {
        t.push_str(&search_text(m));
    }
    if let (Some(s), Some(m)) = (out.spec.as_ref(), found) {
        t.push_str(&margins::text(s, m));
    }
}

/// [`append_text`]'s JSON: `design --json`'s `margin_search`, when the
/// objective was the margin.
pub fn search_json(out: &Outcome) -> Option<SearchView> {
    out.margin.as_ref().map(search_view)
}

/// The margin search in words: the factor found and every factor tried.
fn search_text(m: &MarginSearch) -> String {
    let mut out = match m.factor {
        Some(f) => format!(
            "\nmargin objective: every exec ×{f:.3} keeps every limit and the schedulability test within utilisation {} ({}); the answer's own critical scaling factor is {}\n",
            m.cap,
            if m.exact {
                "the largest such factor, to 0.1 %"
            } else {
                "verified, not proven the largest: see docs/design.md"
            },
            m.critical.map_or("-".into(), margins::factor_text),
        ),
        None => format!("\nmargin objective: no design within utilisation {}\n", m.cap),
    };
    out.push_str("  factors tried (every exec ×): ");
    let tried: Vec<String> = m
        .steps
        .iter()
        .map(|s| {
            let u = s
                .utilization
                .map_or("no design".into(), |u| format!("U {u:.4}"));
            let mark = if s.accepted { "ok" } else { "no" };
            format!("{:.3} ({u}, {mark})", s.factor)
        })
        .collect();
    out.push_str(&tried.join(", "));
    out.push('\n');
    out
}

/// `design --json`'s `margin_search`.
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "MarginSearch")]
pub struct SearchView {
    max_utilization: f64,
    factor: Option<f64>,
    critical_scaling_factor: Option<f64>,
    largest: bool,
    steps: Vec<StepView>,
}

#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "MarginStep")]
struct StepView {
    factor: f64,
    status: &'static str,
    utilization: Option<f64>,
    accepted: bool,
}

fn search_view(m: &MarginSearch) -> SearchView {
    SearchView {
        max_utilization: m.cap,
        factor: m.factor,
        critical_scaling_factor: m.critical.and_then(margins::factor_value),
        largest: m.exact,
        steps: m
            .steps
            .iter()
            .map(|s| StepView {
                factor: s.factor,
                status: s.status.name(),
                utilization: s.utilization,
                accepted: s.accepted,
            })
            .collect(),
    }
}
