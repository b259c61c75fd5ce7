//! Scheduling overheads on the simulated CPUs (`[system] overheads`;
//! docs/analysis.md, "Scheduling overheads"; the analysis' accounting is
//! `analysis/src/overheads.rs`).
//!
//! Each CPU has **kernel work** pending (release handlers: `rel` per
//! release of any of its tasks, plus `rep` when the task is a budget
//! server, whose budget the release replenishes), which runs first, at top
//! priority, and a **switch** in progress: when the CPU's choice becomes a
//! job other than the one whose context it holds, that job first runs `cs`
//! of switching (at its own priority: a new choice abandons it), then its
//! own work. Neither consumes a server's budget. A job reads when its own
//! work starts (after both), takes a resource only then, and completes
//! only when nothing of either is left.

use rtpipe_model::{Nanos, Spec};

/// One CPU's overhead state.
#[derive(Debug, Clone, Default)]
pub(crate) struct CpuOverhead {
    /// `cs` on this CPU.
    switch_cost: Nanos,
    /// Kernel work not yet run.
    kernel: Nanos,
    /// The job (task, index) whose context the CPU holds.
    context: Option<(usize, u64)>,
    /// The job being switched to, and the switching left.
    target: Option<(usize, u64)>,
    switch_left: Nanos,
}

/// Every CPU's state and every task's kernel work per release.
#[derive(Debug, Clone, Default)]
pub(crate) struct Overheads {
    cpus: Vec<CpuOverhead>,
    per_release: Vec<Nanos>,
}

impl Overheads {
    /// The spec's costs on the dense CPUs `cpu_ids` (sorted spec CPU
    /// numbers).
    pub(crate) fn new(spec: &Spec, cpu_ids: &[u32]) -> Overheads {
        Overheads {
            cpus: cpu_ids
                .iter()
                .map(|&c| CpuOverhead {
                    switch_cost: spec.overheads.on(c).context_switch,
                    ..CpuOverhead::default()
                })
                .collect(),
            per_release: spec
                .tasks
                .iter()
                .map(|t| spec.overheads.on(t.cpu).per_release(spec, t.server))
                .collect(),
        }
    }

    /// The kernel work `released` jobs of task `i` bring.
    pub(crate) fn release_work(&self, i: usize, released: u64) -> Nanos {
        self.per_release[i].saturating_mul(released as Nanos)
    }

    /// Kernel work joins `cpu`'s (charged up to now first: the caller's
    /// part).
    pub(crate) fn add_kernel(&mut self, cpu: usize, work: Nanos) {
        if let Some(c) = self.cpus.get_mut(cpu) {
            c.kernel += work;
        }
    }

    /// What `cpu` must run before its chosen job's own work.
    pub(crate) fn lead(&self, cpu: usize) -> Nanos {
        self.cpus.get(cpu).map_or(0, |c| c.kernel + c.switch_left)
    }

    /// Runs `dt` of `cpu`'s overheads (kernel work first, then the
    /// switch); returns what is left of `dt` for the job.
    pub(crate) fn run(&mut self, cpu: usize, dt: Nanos) -> Nanos {
        let Some(c) = self.cpus.get_mut(cpu) else {
            return dt;
        };
        let k = c.kernel.min(dt);
        c.kernel -= k;
        let s = c.switch_left.min(dt - k);
        c.switch_left -= s;
        if c.switch_left == 0 && c.target.is_some() {
            c.context = c.target.take();
        }
        dt - k - s
    }

    /// The CPU now chooses `job` (none: idle): a switch to it starts
    /// unless the CPU holds its context or already switches to it.
    pub(crate) fn choose(&mut self, cpu: usize, job: Option<(usize, u64)>) {
        let Some(c) = self.cpus.get_mut(cpu) else {
            return;
        };
        if job == c.target && job.is_some() {
            return;
        }
        if job.is_none() || job == c.context || c.switch_cost == 0 {
            // Back to the loaded context (or nothing): a switch in
            // progress is abandoned.
            c.target = None;
            c.switch_left = 0;
            if c.switch_cost == 0 && job.is_some() {
                c.context = job;
            }
            return;
        }
        c.target = job;
        c.switch_left = c.switch_cost;
    }
}
