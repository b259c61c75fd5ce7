//! W, the read-to-publish bound, of a sporadic server that may wait for its
//! budget after its start (docs/analysis.md, "From the read to the publish
//! of a sporadic server").
//!
//! Such a job (a Main VCPU whose job exceeds its budget, or is released
//! with jitter, so that a job may find its budget still out when it
//! starts) can exhaust its budget after its read and wait for a
//! replenishment up to its own jitter later, so `fp_start_to_finish` takes
//! `W = R`. But it waits in slack: a sporadic server out of budget drops to
//! background priority and runs whenever nothing else is ready (Sprunt,
//! Sha and Lehoczky 1989; the corrected POSIX rules of Stanovich, Baker,
//! Wang and González Harbour 2010 keep that), so from its start to its
//! publish its CPU never idles. Every instant of that window runs the job
//! itself or another job of its CPU, which bounds the window by the work
//! that can run in it: a busy window over every other task of the CPU,
//! as Lehoczky's level-i busy period is one over the tasks above.

use super::{inherited_carry_in, interference, outranks, period_or_max, Levels, Responses};
use rtpipe_model::policy::Budget;
use rtpipe_model::{Nanos, Server, Spec};

/// Task `i` is a sporadic server that may run in slack (out of budget)
/// with a job pending: a Main VCPU under a sporadic-server policy whose
/// budget need not be whole at a release ([`super::fp_start_after`]).
pub(crate) fn may_run_in_slack(spec: &Spec, i: usize) -> bool {
    spec.policy().budget(spec.tasks[i].server) == Some(Budget::Sporadic)
        && super::fp_start_after(spec, i).is_none()
}

/// W of a sporadic server `i` that may run in slack, given every task's
/// figures: the least fixed point of `w = x_i + Σ_j ⌈(w + Q_j)/T_j⌉ · c_j`
/// over the other guaranteed tasks of i's CPU. When the job starts,
/// nothing is ready above it in its own class or any class above
/// (otherwise that would run instead), and from then on the CPU runs it
/// or another job: own work, work of the others, nothing idle. A task `j`
/// that can run above `i` and never runs in slack is pending at the start
/// only out of budget, and its budget brings at most what `hp_load` says
/// (`c_j = I_j`, `Q_j = J_j`, or a PIBS server's inherited carry-in);
/// any other task (below i, or a sporadic server that may itself run in
/// slack beyond its budget) may have jobs pending at the start, each of
/// which completes within `R_j` of its nominal release, so the jobs that
/// run in the window are released in `(s − R_j, s + w)`: `c_j = max(x_j,
/// I_j)`, `Q_j = R_j` (the carry-in of Bertogna and Cirinei 2007, with
/// whole demands, and never below `hp_load`'s term). The
/// job's own blocking is work of a lower task in that window, already
/// counted. `None` when the argument does not apply: kernel overheads
/// (switches at budget exhaustions no job's count holds), a background
/// task on the CPU (ready above slack with no bound on its backlog) or a
/// task of the CPU without a response time.
pub(super) fn slack_start_to_finish(
    levels: &Levels,
    i: usize,
    responses: &[Responses],
) -> Option<Nanos> {
    let spec = levels.spec;
    if !spec.overheads.is_zero() {
        return None;
    }
    let mut load = Vec::new();
    for &j in levels.cpu_of(i) {
        let o = &spec.tasks[j];
        if j == i {
            continue;
        }
        if o.server == Server::Background {
            return None;
        }
        let above = outranks(j, levels.top[j], i, levels.prio[i]);
        load.push(if above && !may_run_in_slack(spec, j) {
            if levels.prio[j] > levels.prio[i] {
                let (work, jitter) = inherited_carry_in(levels, j)?;
                (work, period_or_max(o), jitter)
            } else {
                (interference(o), period_or_max(o), o.jitter)
            }
        } else {
            // At least the term the task above brings without slack, so
            // that the window never falls below the one of a job that
            // cannot wait for its budget (release jitter only adds).
            let (budget_r, job_r, _) = responses[j];
            let work = o.demand().max(interference(o));
            (work, period_or_max(o), budget_r?.max(job_r?))
        });
    }
    super::busy_window(spec.tasks[i].demand(), &load)
}
