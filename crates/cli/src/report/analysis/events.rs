//! What `analyze` adds for a spec with threads and data-triggered tasks:
//! each task's activations, its gaps, and what the columns mean there.

use crate::table::Table;
use rtpipe_analysis::Report;
use rtpipe_model::{Nanos, Spec};
use serde::Serialize;

/// A task's activations in the JSON report (left out in a periodic spec).
#[derive(Serialize, schemars::JsonSchema)]
pub struct ActivationView<'a> {
    /// Its thread, when it runs in one.
    #[serde(skip_serializing_if = "Option::is_none")]
    thread: Option<&'a str>,
    /// The tasks whose publications release it (data-triggered only).
    #[serde(skip_serializing_if = "Option::is_none")]
    triggers: Option<Vec<&'a str>>,
    /// "any" or "all" (data-triggered only).
    #[serde(skip_serializing_if = "Option::is_none")]
    join: Option<&'static str>,
    /// Its jobs merge (in a thread, or data-triggered).
    merging: bool,
    /// A: the longest from any instant to its next activation.
    gap: Option<f64>,
    /// P = A + R: the longest from any instant to its next publication.
    publish_gap: Option<f64>,
}

/// Task `i`'s activations, in a spec with threads or data-triggered tasks.
pub fn activation_view<'a>(spec: &'a Spec, r: &Report, i: usize) -> Option<ActivationView<'a>> {
    let e = r.timing[i].events.as_ref()?;
    let t = &spec.tasks[i];
    let time = |v: Option<Nanos>| v.map(|v| spec.in_unit(v));
    Some(ActivationView {
        thread: t.thread.map(|th| spec.threads[th].name.as_str()),
        triggers: t
            .triggers()
            .map(|(tr, _)| tr.iter().map(|&p| spec.tasks[p].name.as_str()).collect()),
        join: t.triggers().map(|(_, j)| j.name()),
        merging: e.merging,
        gap: time(e.gap),
        publish_gap: time(e.publish_gap),
    })
}

/// The table of activations and the notes on the other columns, in a
/// spec with threads or data-triggered tasks (nothing otherwise).
pub fn activations_text(spec: &Spec, r: &Report) -> String {
    if !spec.event_triggered() {
        return String::new();
    }
    let heads = ["task", "thread", "activation", "A", "P"];
    let mut t = Table::new(&heads).numeric(&[3, 4]);
    for (i, task) in spec.tasks.iter().enumerate() {
        let Some(e) = r.timing[i].events.as_ref() else {
            continue;
        };
        let opt =
            |v: Option<Nanos>| v.map_or_else(|| "unbounded".to_string(), |v| spec.fmt_time(v));
        t.row(vec![
            task.name.clone(),
            task.thread
                .map_or_else(|| "-".to_string(), |th| spec.threads[th].name.clone()),
            activation(spec, i),
            opt(e.gap),
            opt(e.publish_gap),
        ]);
    }
    format!(
        "\nactivations (A: the longest from any instant to the next activation; P = A + R: \
         to the next publication; R counts from a job's first release, a release while a \
         job of the task waits unstarted joins it; docs/analysis.md, \"Threads and \
         data-triggered tasks\"):\n{}\
         notes: a data-triggered task's period T is its triggers' nominal rate, used by C/T and \
         by the paper's equations (the paper has none for data-triggered links); davare and \
         duerr assume periodic tasks each on a thread of its own, so chains through a thread \
         or a data-triggered task show them unbounded.\n",
        t.render()
    )
}

/// "period T" with its jitter, or "data: a, b (join)".
fn activation(spec: &Spec, i: usize) -> String {
    let t = &spec.tasks[i];
    match t.triggers() {
        Some((tr, join)) => {
            let names: Vec<&str> = tr.iter().map(|&p| spec.tasks[p].name.as_str()).collect();
            format!("data: {} ({})", names.join(", "), join.name())
        }
        None => match (t.fixed_period(), t.jitter) {
            (Some(p), 0) => format!("period {}", spec.fmt_time(p)),
            (Some(p), j) => format!("period {} J {}", spec.fmt_time(p), spec.fmt_time(j)),
            (None, _) => "-".to_string(),
        },
    }
}
