//! What no run can do, whatever the machine: a non-positive duration,
//! critical sections (`[resources]`: the threads do not take a ceiling
//! lock yet, so a run would not follow the protocol the analysis bounds),
//! or LET communication (`[system] communication = "let"`). The executor's
//! threads read when a job starts and publish when it completes (implicit
//! communication); LET's timer-driven copies at releases and period ends
//! are simulated exactly (`rtpipe simulate`) but not implemented here.

use rtpipe_model::{Communication, Nanos, Spec};

/// (what is wrong, how to fix it) when `spec` cannot run for `duration`.
pub(crate) fn refusal(spec: &Spec, duration: Nanos) -> Option<(&'static str, &'static str)> {
    if duration <= 0 {
        return Some(("the duration must be positive", "e.g. --duration 2s"));
    }
    if spec.tasks.iter().any(|t| !t.sections.is_empty()) {
        return Some((
            "critical sections (critical_sections, [resources]): the runtime does not run the resource protocol yet",
            "remove the tasks' critical_sections to run it (`rtpipe simulate` runs the protocol exactly, `rtpipe analyze` bounds it)",
        ));
    }
    (spec.communication == Communication::Let).then_some((
        "communication = \"let\": the runtime executes implicit communication only",
        "use communication = \"implicit\" to run it (`rtpipe simulate` runs LET exactly)",
    ))
}
