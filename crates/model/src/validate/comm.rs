//! Validation of the communication semantics: `[system]
//! communication`, implicit by default, or LET; and `communication` in a
//! `[[chain]]`, which sets it for every task on that chain. Under LET every
//! job reads at its release and publishes at the end of its period, so
//! each such task must own a period of its own in which it is guaranteed to
//! finish: what cannot be, the spec refuses here.
//!
//! LET is how a task reads and publishes, not a property of one chain's
//! view of it: a task on two chains of different semantics (a chain
//! without the key has the system's) is refused, naming both chains. Tasks
//! on no chain with its own key follow the system's value
//! (`Spec::communications`).
//!
//! Refused for a task under LET, each with its place and a fix:
//! - `server = "io"` (PIBS I/O VCPUs): they run on the budget of the Main
//!   VCPU they serve, so their jobs have no period of their own to finish in;
//! - `server = "background"`: no guarantee at all, so no LET deadline;
//! - `jitter`: LET's read and publish are timer instants at the nominal
//!   releases; a late release would leave its job less than a period.
//!
//! Whether a budget is large enough for every job to finish within its
//! period is not decided here: `analyze` checks R ≤ T (no R, no LET bound).

use super::{span, Builder};
use crate::policy::Communication;
use crate::raw::{RawChain, RawSystem, RawTask, S};
use crate::*;

/// Where a task's LET comes from, for the diagnostics.
enum Whence<'a> {
    /// `[system] communication = "let"`.
    System,
    /// A chain's `communication = "let"` (its label).
    Chain(&'a str),
}

impl Builder {
    /// `[system] communication` (the tasks it covers are checked by
    /// [`Builder::task_semantics`]).
    pub(super) fn communication(&mut self, sys: &RawSystem) -> Communication {
        let Some(c) = &sys.communication else {
            return Communication::Implicit;
        };
        let options = Communication::ALL.map(|c| (c.name(), c));
        self.choice(c, "communication", &options)
            .unwrap_or(Communication::Implicit)
    }

    /// A chain's own `communication`, if it gives one.
    pub(super) fn chain_communication(&mut self, c: &RawChain) -> Option<Communication> {
        let options = Communication::ALL.map(|c| (c.name(), c));
        let v = c.communication.as_ref()?;
        self.choice(v, "communication", &options)
    }

    /// Every task's semantics: no task on chains of different semantics,
    /// and each LET task able to run under LET. `raw` and `chains` are the
    /// same chains (every one valid).
    pub(super) fn task_semantics(
        &mut self,
        raw: &[S<RawChain>],
        chains: &[Chain],
        system: Communication,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
    ) {
        assert_eq!(raw.len(), chains.len(), "only valid chains get here");
        // Per task: the first chain it is on (index) and that chain's
        // semantics.
        let mut first: Vec<Option<usize>> = vec![None; tasks.len()];
        let label = |k: usize| chain_label(raw[k].get_ref(), k);
        let comm = |k: usize| chains[k].communication.unwrap_or(system);
        for (k, ch) in chains.iter().enumerate() {
            for &i in &ch.path {
                match first[i] {
                    None => first[i] = Some(k),
                    Some(j) if comm(j) != comm(k) => {
                        let rc = raw[k].get_ref();
                        let at = rc
                            .communication
                            .as_ref()
                            .map_or_else(|| span(&rc.path), span);
                        self.err(
                            format!(
                                "task `{}` is on chain `{}` ({}) and on chain `{}` ({}): a task reads and publishes one way",
                                tasks[i].name,
                                label(j),
                                comm(j).name(),
                                label(k),
                                comm(k).name()
                            ),
                            at,
                            format!(
                                "give both chains the same communication (communication = \"{}\" in chain `{}`), or take `{}` off one of them",
                                comm(j).name(),
                                label(k),
                                tasks[i].name
                            ),
                        );
                    }
                    Some(_) => {}
                }
            }
        }
        for (i, ((k, v), t)) in raw_tasks.iter().zip(tasks).enumerate() {
            let own = first[i].filter(|&j| chains[j].communication.is_some());
            let name = own.map(label);
            let whence = name.as_deref().map_or(Whence::System, Whence::Chain);
            if own.map_or(system, comm) == Communication::Let {
                self.let_task(k, v.get_ref(), t, whence);
            }
        }
    }

    /// One task under LET: a guaranteed period of its own, no jitter.
    fn let_task(&mut self, k: &S<String>, rt: &RawTask, t: &Task, whence: Whence) {
        let at = rt.server.as_ref().map_or_else(|| span(k), span);
        let (why, off) = match whence {
            Whence::System => (
                "communication is LET".to_string(),
                "communication = \"implicit\"".to_string(),
            ),
            Whence::Chain(c) => (
                format!("it is on chain `{c}`, whose communication is LET"),
                format!("communication = \"implicit\" in chain `{c}`"),
            ),
        };
        match t.server {
            Server::Io => self.err(
                format!("task `{}` is an I/O VCPU, but {why}", t.name),
                at,
                format!("an I/O VCPU runs on the budget of the task it serves and has no LET period to finish in: use server = \"main\" (or \"none\"), or {off}"),
            ),
            Server::Background => self.err(
                format!("background task `{}` under LET communication", t.name),
                at,
                format!("a background task has no guarantee to finish by its period's end, where LET publishes: give it a server (server = \"main\"), or use {off}"),
            ),
            Server::Main | Server::None => {}
        }
        if let (true, Some(js)) = (t.jitter > 0, &rt.jitter) {
            let msg = match whence {
                Whence::System => format!(
                    "task `{}` has release jitter under LET communication",
                    t.name
                ),
                Whence::Chain(_) => format!("task `{}` has release jitter, but {why}", t.name),
            };
            self.err(
                msg,
                span(js),
                format!("LET reads and publishes at the nominal release instants: remove the jitter, or use {off}"),
            );
        }
    }
}

/// A chain as the diagnostics name it: its name, or its path (`a>b`), or
/// its position.
fn chain_label(c: &RawChain, k: usize) -> String {
    if let Some(n) = &c.name {
        return n.get_ref().clone();
    }
    let names: Vec<&str> = c
        .path
        .get_ref()
        .iter()
        .map(|n| n.get_ref().as_str())
        .collect();
    if names.is_empty() {
        format!("chain {}", k + 1)
    } else {
        names.join(">")
    }
}
