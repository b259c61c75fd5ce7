//! What the box search may cut for a spec with work-queue threads or
//! data-triggered tasks (docs/design.md, "Event-triggered specs").
//!
//! `rtpipe_analysis::relax` evaluates the periodic analysis over a box and
//! knows nothing of threads, merged releases or triggers, so it is not a
//! lower bound of the event analysis and the search does not use it for
//! these specs. What remains valid, and all it prunes with:
//!
//! - **Utilisation.** A data-triggered task's rate is its triggers'
//!   (`Spec::activation_period_with`: the least of theirs under
//!   `join = "any"`, the largest under `"all"`), which never falls as a
//!   period grows; so Σ C/T is least at a box's longest periods, and its
//!   corner there is the best point of the box.
//! - **Limits from the event (sound mode).** The analysis' bound from the
//!   event is the bound from the head's release (a sum of response times,
//!   periods and gaps, never negative) plus the head's sampling delay: T
//!   for a periodic head, its activation gap `A` for a merging one
//!   (`latency::from_event`). `A` is T for a periodic task and, for a
//!   data-triggered one, the least (`any`) or largest (`all`) of its
//!   triggers' `A + R`, so it is at least the head's activation period.
//!   A from-event limit L therefore caps that activation period, and with
//!   it the period of each source it cannot be shorter than: the head
//!   itself when periodic, every trigger under `all`, the one trigger of
//!   a single-trigger task. (With several triggers under `any` the least
//!   of them caps none alone.) `crates/design/tests/events.rs` checks the
//!   inequality on generated systems.
//!
//! The search's other assumptions hold without monotonicity of the
//! analysis in the periods: a box's corner is verified by
//! `rtpipe_analysis::analyze` itself, and lengthening periods after a
//! verified corner (the dive) only proposes candidates, each verified.

use crate::problem::Group;
use rtpipe_analysis::{Anchor, Mode};
use rtpipe_model::{Join, Nanos, Spec};

/// The longest period each task may have by the from-event limits alone
/// (`None`: no cap); empty for a spec without threads or data-triggered
/// tasks, or outside sound mode, where the relaxation serves.
pub(crate) fn source_caps(spec: &Spec, mode: Mode, groups: &[Group]) -> Vec<Option<Nanos>> {
    if !spec.event_triggered() || mode != Mode::Sound {
        return Vec::new();
    }
    let mut caps = vec![None; spec.tasks.len()];
    for g in groups {
        let Group::Limit(k, metric) = *g else {
            continue;
        };
        let ch = &spec.chains[k];
        let Some(limit) = metric.limit(ch, Anchor::Event) else {
            continue;
        };
        for i in capped_by_head(spec, ch.path[0]) {
            let cap: &mut Option<Nanos> = &mut caps[i];
            *cap = Some(cap.map_or(limit, |c| c.min(limit)));
        }
    }
    caps
}

/// The periodic tasks whose period is at most the activation period of
/// task `head` at every choice of periods.
pub(crate) fn capped_by_head(spec: &Spec, head: usize) -> Vec<usize> {
    match spec.tasks[head].triggers() {
        None => vec![head],
        Some((triggers, Join::All)) => triggers
            .iter()
            .flat_map(|&q| capped_by_head(spec, q))
            .collect(),
        Some(([only], Join::Any)) => capped_by_head(spec, *only),
        Some((_, Join::Any)) => Vec::new(),
    }
}

/// Adds to `blamed` the triggers, transitively, of every blamed
/// data-triggered task: its rate, and so the fate of a constraint it is
/// on, moves only with theirs.
pub(crate) fn blame_triggers(spec: &Spec, blamed: &mut [bool]) {
    fn mark(spec: &Spec, i: usize, blamed: &mut [bool]) {
        for &q in spec.tasks[i].triggers().map_or(&[][..], |(t, _)| t) {
            blamed[q] = true;
            mark(spec, q, blamed);
        }
    }
    for i in 0..blamed.len() {
        if blamed[i] {
            mark(spec, i, blamed);
        }
    }
}
