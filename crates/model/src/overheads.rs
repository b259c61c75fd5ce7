//! Scheduling overheads (`[system] overheads`): what the kernel
//! costs the CPU per context switch, per release and per budget
//! replenishment. The analysis charges them in every response time
//! (`analysis/src/overheads.rs`), the simulator runs them
//! (`sim/src/overheads.rs`), `rtpipe run --measure-overheads` measures
//! them. docs/analysis.md, "Scheduling overheads", has the accounting.

use crate::{Nanos, Server, Spec};
use std::collections::BTreeMap;

/// The costs on one CPU (0 each by default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Costs {
    /// One switch from a job (or idle) to another job.
    pub context_switch: Nanos,
    /// The release handler run at top priority at every release of every
    /// task of the CPU.
    pub release: Nanos,
    /// The budget replenishment run at top priority with every release of
    /// a job of a budget server (`main`, `io`).
    pub replenish: Nanos,
}

impl Costs {
    /// Every cost is zero.
    pub fn is_zero(&self) -> bool {
        *self == Costs::default()
    }

    /// The top-priority kernel work one release of `server`'s job brings:
    /// the release handler, and the replenishment when a budget server
    /// gets its budget back for the job.
    pub fn per_release(&self, spec: &Spec, server: Server) -> Nanos {
        let rep = if spec.policy().budget(server).is_some() {
            self.replenish
        } else {
            0
        };
        self.release.saturating_add(rep)
    }
}

/// The overheads of every CPU: the system's costs, each key of which a
/// CPU's own table may override.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Overheads {
    /// The costs of a CPU without its own table.
    pub system: Costs,
    /// Per CPU, the keys its table gives (the others are the system's).
    pub cpus: BTreeMap<u32, CpuCosts>,
}

/// A CPU's own overheads: the keys it overrides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CpuCosts {
    /// `context_switch`, when given.
    pub context_switch: Option<Nanos>,
    /// `release`, when given.
    pub release: Option<Nanos>,
    /// `replenish`, when given.
    pub replenish: Option<Nanos>,
}

impl Overheads {
    /// The costs on `cpu`.
    pub fn on(&self, cpu: u32) -> Costs {
        let s = self.system;
        match self.cpus.get(&cpu) {
            Some(c) => Costs {
                context_switch: c.context_switch.unwrap_or(s.context_switch),
                release: c.release.unwrap_or(s.release),
                replenish: c.replenish.unwrap_or(s.replenish),
            },
            None => s,
        }
    }

    /// No CPU has any overhead (the model of every spec before them).
    pub fn is_zero(&self) -> bool {
        self.system.is_zero()
            && self.cpus.values().all(|c| {
                [c.context_switch, c.release, c.replenish]
                    .iter()
                    .all(|v| v.is_none_or(|v| v == 0))
            })
    }
}
