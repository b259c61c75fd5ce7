//! Validation of `[system] overheads`: `context_switch`,
//! `release` and `replenish`, each a time of zero or more and at most
//! [`MAX_OVERHEAD`], for the system and per CPU
//! (`[system.overheads.cpu.N]`, overriding key by key).
//!
//! Refused, each with its place and a fix, where the accounting of
//! docs/analysis.md ("Scheduling overheads") would not bound what runs:
//! a CPU table for a CPU no task runs on; overheads with the QPA test
//! (its demand walk has no term for release handlers of later deadlines);
//! with priority inheritance over critical sections (a job waiting for a
//! lock causes switches no release or completion pays for); with release
//! jitter on a budget server under fixed priorities (it may wait for its
//! budget and run in slack, switching without a release or completion).
//! The utilisation bounds `liu-layland` and `hyperbolic` are refused with
//! overheads (they assume rate-monotonic order, which top-priority
//! handlers break); `edf` becomes the utilisation with the overheads and
//! Spuri's response times within the deadlines (`analysis/src/sched.rs`).
//! A spec whose overheads only make it unschedulable is not refused: the
//! analysis reports it.

use super::{span, Builder};
use crate::overheads::{Costs, CpuCosts, Overheads};
use crate::raw::{RawCosts, RawOverheads, RawSystem, RawTask, S};
use crate::*;

/// Where a refusal points: the first key given (the table itself has no
/// span of its own: a table made implicit by `[system.overheads.cpu.N]`
/// does not deserialise with one).
fn overheads_span(raw: &RawOverheads) -> Option<std::ops::Range<usize>> {
    [&raw.context_switch, &raw.release, &raw.replenish]
        .into_iter()
        .flatten()
        .map(span)
        .chain(raw.cpu.0.iter().map(|(k, _)| span(k)))
        .flatten()
        .min_by_key(|r| r.start)
}

/// The largest overhead a spec may give: far beyond any kernel path, so a
/// larger value is a unit slip (`context_switch = 5` in a spec whose
/// time unit is ms).
pub const MAX_OVERHEAD: Nanos = 100_000_000;

impl Builder {
    /// `[system] overheads`, checked against the tasks and the policy.
    pub(super) fn overheads(
        &mut self,
        sys: &RawSystem,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
        scheduler: Option<Scheduler>,
        protocol: ResourceProtocol,
        test: Option<SchedTest>,
    ) -> Overheads {
        let Some(raw) = &sys.overheads else {
            return Overheads::default();
        };
        let out = self.overhead_values(raw, tasks);
        let at = overheads_span(raw);
        if out.is_zero() {
            return out;
        }
        if let Some(t) = test.filter(|t| matches!(t, SchedTest::LiuLayland | SchedTest::Hyperbolic))
        {
            self.err(
                format!("overheads with schedulability = \"{}\"", t.name()),
                at.clone(),
                "utilisation bounds for rate-monotonic order do not cover release handlers at top priority: use schedulability = \"rta\" (the response-time test charges every overhead)",
            );
        }
        if let Some((msg, help, place)) =
            self.overhead_refusal(raw_tasks, tasks, scheduler, protocol)
        {
            self.err(msg, place.or(at), help);
        }
        out
    }

    /// The values, each checked on its own.
    fn overhead_values(&mut self, raw: &RawOverheads, tasks: &[Task]) -> Overheads {
        let sys = self.cpu_costs(&raw.context_switch, &raw.release, &raw.replenish);
        let mut out = Overheads {
            system: Costs {
                context_switch: sys.context_switch.unwrap_or(0),
                release: sys.release.unwrap_or(0),
                replenish: sys.replenish.unwrap_or(0),
            },
            ..Overheads::default()
        };
        for (k, v) in &raw.cpu.0 {
            let RawCosts {
                context_switch,
                release,
                replenish,
            } = v.get_ref();
            let costs = self.cpu_costs(context_switch, release, replenish);
            let Ok(cpu) = k.get_ref().parse::<u32>() else {
                self.err(
                    format!("\"{}\" is not a CPU index", k.get_ref()),
                    span(k),
                    "name the CPU by its index, as tasks do with `cpu`: [system.overheads.cpu.1]",
                );
                continue;
            };
            if !tasks.iter().any(|t| t.cpu == cpu) {
                self.err(
                    format!("overheads for CPU {cpu}, but no task runs on CPU {cpu}"),
                    span(k),
                    "correct the CPU index or remove the table (tasks choose their CPU with `cpu = N`)",
                );
            }
            out.cpus.insert(cpu, costs);
        }
        out
    }

    /// One table's three keys.
    fn cpu_costs(
        &mut self,
        cs: &Option<S<toml::Value>>,
        rel: &Option<S<toml::Value>>,
        rep: &Option<S<toml::Value>>,
    ) -> CpuCosts {
        let mut one = |v: &Option<S<toml::Value>>, what: &str| {
            let v = v.as_ref()?;
            let t = self.nonneg_time(v, what)?;
            if t > MAX_OVERHEAD {
                self.err(
                    format!(
                        "{what} overhead of {} is above {}: no kernel path takes that long",
                        format_in(t, self.unit()),
                        format_in(MAX_OVERHEAD, self.unit())
                    ),
                    span(v),
                    format!("overheads are microseconds on a typical machine: write a time with its unit, e.g. {what} = \"5us\" (a bare number is in {})", self.unit()),
                );
                return None;
            }
            Some(t)
        };
        CpuCosts {
            context_switch: one(cs, "context_switch"),
            release: one(rel, "release"),
            replenish: one(rep, "replenish"),
        }
    }

    /// (what is wrong, how to fix it, where when not at the overheads) when
    /// the analysis cannot bound the overheads of this spec.
    fn overhead_refusal(
        &self,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
        scheduler: Option<Scheduler>,
        protocol: ResourceProtocol,
    ) -> Option<(String, String, Option<std::ops::Range<usize>>)> {
        let policy = scheduler?.policy();
        let jittered = tasks
            .iter()
            .zip(raw_tasks)
            .find(|(t, _)| t.jitter > 0 && policy.budget(t.server).is_some());
        if policy.fixed_priority() {
            if let Some((t, (_, rt))) = jittered {
                return Some((
                    format!("overheads with release jitter on task `{}`, a budget server", t.name),
                    "a jittered server may wait for its budget and run in slack, switching at instants the overhead analysis does not count: give the task server = \"none\" or remove its jitter".into(),
                    rt.get_ref().jitter.as_ref().and_then(span),
                ));
            }
        }
        let sections = tasks.iter().any(|t| !t.sections.is_empty());
        if sections && protocol == ResourceProtocol::Pip {
            return Some((
                "overheads with resource_protocol = \"pip\"".into(),
                "a job waiting for a lock under priority inheritance causes context switches the overhead analysis does not count: use resource_protocol = \"pcp\" or \"srp\"".into(),
                None,
            ));
        }
        let constrained = tasks
            .iter()
            .any(|t| t.deadline_given.is_some_and(|d| Some(d) < t.fixed_period()));
        if !policy.fixed_priority() && constrained {
            return Some((
                "overheads under EDF with deadlines below periods (the processor-demand test)".into(),
                "the demand test has no term for the release handlers of later deadlines: remove the deadlines (Spuri's response-time analysis then charges the overheads), or use scheduler = \"rm\"".into(),
                None,
            ));
        }
        None
    }
}
