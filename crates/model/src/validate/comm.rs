//! Validation of `[system] communication` (issue 22): implicit by default,
//! or LET. Under LET every job reads at its release and publishes at the
//! end of its period, so each task must own a period of its own in which
//! it is guaranteed to finish: what cannot be, the spec refuses here.
//!
//! Refused under LET, each with its place and a fix:
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
use crate::raw::{RawSystem, RawTask, S};
use crate::*;

impl Builder {
    /// `[system] communication`, and the tasks LET cannot run.
    pub(super) fn communication(
        &mut self,
        sys: &RawSystem,
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &[Task],
    ) -> Communication {
        let Some(c) = &sys.communication else {
            return Communication::Implicit;
        };
        let options = Communication::ALL.map(|c| (c.name(), c));
        let comm = self
            .choice(c, "communication", &options)
            .unwrap_or(Communication::Implicit);
        if comm == Communication::Let {
            for ((k, v), t) in raw_tasks.iter().zip(tasks) {
                self.let_task(k, v.get_ref(), t);
            }
        }
        comm
    }

    /// One task under LET: a guaranteed period of its own, no jitter.
    fn let_task(&mut self, k: &S<String>, rt: &RawTask, t: &Task) {
        let at = rt.server.as_ref().map_or_else(|| span(k), span);
        match t.server {
            Server::Io => self.err(
                format!("task `{}` is an I/O VCPU, but communication is LET", t.name),
                at,
                "an I/O VCPU runs on the budget of the task it serves and has no LET period to finish in: use server = \"main\" (or \"none\"), or communication = \"implicit\"",
            ),
            Server::Background => self.err(
                format!("background task `{}` under LET communication", t.name),
                at,
                "a background task has no guarantee to finish by its period's end, where LET publishes: give it a server (server = \"main\"), or use communication = \"implicit\"",
            ),
            Server::Main | Server::None => {}
        }
        if let (true, Some(js)) = (t.jitter > 0, &rt.jitter) {
            self.err(
                format!("task `{}` has release jitter under LET communication", t.name),
                span(js),
                "LET reads and publishes at the nominal release instants: remove the jitter, or use communication = \"implicit\"",
            );
        }
    }
}
