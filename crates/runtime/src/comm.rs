//! What no run can do, whatever the machine: a non-positive duration, or
//! LET communication (`[system] communication = "let"`). The executor's
//! threads read when a job starts and publish when it completes (implicit
//! communication); LET's timer-driven copies at releases and period ends
//! are simulated exactly (`rtpipe simulate`) but not implemented here.

use rtpipe_model::{Communication, Nanos, Spec};

/// (what is wrong, how to fix it) when `spec` cannot run for `duration`.
pub(crate) fn refusal(spec: &Spec, duration: Nanos) -> Option<(&'static str, &'static str)> {
    if duration <= 0 {
        return Some(("the duration must be positive", "e.g. --duration 2s"));
    }
    (spec.communication == Communication::Let).then_some((
        "communication = \"let\": the runtime executes implicit communication only",
        "use communication = \"implicit\" to run it (`rtpipe simulate` runs LET exactly)",
    ))
}
