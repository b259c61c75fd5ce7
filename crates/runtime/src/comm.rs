//! What no run can do, whatever the machine (a non-positive duration,
//! sections under SCHED_DEADLINE: `crate::locks::unrunnable`), and
//! what a run with the caller's own bodies cannot: critical sections, which
//! the runtime holds itself around synthetic bodies only (`crate::locks`,
//! [`crate::run_synthetic`]: it cannot place them inside foreign code), and
//! LET with a world, whose reads happen at releases a thread need not be
//! running at (`crate::let_comm` keeps LET's data flow by index; a world
//! sensed at the release would have to be sensed in the past).

use crate::config::Policy;
use rtpipe_model::{Communication, Nanos, Spec};

/// (what is wrong, how to fix it) when `spec` cannot run for `duration`
/// under `policy`.
pub(crate) fn refusal(
    spec: &Spec,
    duration: Nanos,
    policy: Policy,
) -> Option<(&'static str, &'static str)> {
    if let Some(r) = crate::locks::unrunnable(spec, policy) {
        return Some(r);
    }
    (duration <= 0).then_some(("the duration must be positive", "e.g. --duration 2s"))
}

/// (what is wrong, how to fix it) when `spec` cannot run with the caller's
/// bodies (`world`: with an environment).
pub(crate) fn bodies_refusal(spec: &Spec, world: bool) -> Option<(&'static str, &'static str)> {
    if spec.tasks.iter().any(|t| !t.sections.is_empty()) {
        return Some((
            "critical sections (critical_sections, [resources]) run with synthetic bodies only: the runtime holds them around the body, which it cannot do inside task code",
            "run it with synthetic bodies (`rtpipe run --synthetic`), or remove the tasks' critical_sections (`rtpipe simulate` runs the protocol with any body)",
        ));
    }
    if world && spec.communication == Communication::Let {
        return Some((
            "communication = \"let\" with a world (flight bodies): LET reads at the release, when the thread need not be running, and a world cannot be sensed in the past",
            "use communication = \"implicit\" to fly it on real threads, `rtpipe fly` to fly it under LET, or `rtpipe run --synthetic`",
        ));
    }
    (world && spec.any_let()).then_some((
        "a chain with communication = \"let\" with a world (flight bodies): LET reads at the release, when the thread need not be running, and a world cannot be sensed in the past",
        "remove the chain's communication key to fly it on real threads, `rtpipe fly` to fly it under LET, or `rtpipe run --synthetic`",
    ))
}
