//! What a run checks before any thread starts: the spec's tasks on this
//! machine (periods, CPUs, SCHED_DEADLINE's rules and admission), the
//! policy against the spec's scheduler, the size of the job log.

use super::queue;
use crate::class::privileges;
use crate::config::{reservation, Policy, RunConfig, RunError};
use crate::sys;
use rtpipe_model::policy::LinuxClass;
use rtpipe_model::{Nanos, Spec, Task};

/// Largest number of jobs logged in one run (memory: ~48 bytes a job).
const MAX_JOBS: u64 = 20_000_000;

/// Most tasks one run starts: a real-time thread each, whose stack
/// (`TASK_STACK`) mlockall locks under SCHED_FIFO/SCHED_DEADLINE (3,000
/// tasks with default stacks locked 6.2 GB).
pub const MAX_TASKS: usize = 512;

/// Checks that `spec` can run under `cfg` before any thread starts.
pub fn check(spec: &Spec, cfg: &RunConfig) -> Result<(), RunError> {
    if let Some((msg, help)) = crate::comm::refusal(spec, cfg.duration, cfg.policy) {
        return Err(RunError::config(msg, help));
    }
    if let Some(e) = queue::refusal(spec, cfg.policy) {
        return Err(e);
    }
    let cpus = sys::online_cpus();
    let jobs = queue::job_capacity(spec, cfg.duration)
        .into_iter()
        .fold(0, u64::saturating_add);
    let mut bandwidth = 0.0;
    for t in &spec.tasks {
        bandwidth += check_task(t, cfg.policy, cpus)?;
    }
    if spec.tasks.len() > MAX_TASKS {
        return Err(RunError::config(
            format!(
                "the spec has {} tasks, more than the {MAX_TASKS} one run starts (a real-time thread each, its memory locked)",
                spec.tasks.len()
            ),
            "run a smaller spec, or study this one with `rtpipe simulate` (no thread per task)",
        ));
    }
    privileges(spec, cfg.policy)?;
    if jobs > MAX_JOBS {
        return Err(RunError::config(
            format!("the run would log {jobs} jobs, more than the {MAX_JOBS} this executor keeps"),
            "shorten --duration",
        ));
    }
    match (cfg.policy, spec.policy().linux) {
        (Policy::Fifo, LinuxClass::Deadline) => Err(RunError::config(
            "--policy fifo runs the rate-monotonic model, but the spec says scheduler = \"edf\"",
            "use --policy deadline for an edf spec, or set scheduler = \"rm\"",
        )),
        (Policy::Deadline | Policy::EdfFifo, LinuxClass::Fifo) => Err(RunError::config(
            format!(
                "--policy {} runs the edf model, but the spec says scheduler = \"rm\"",
                cfg.policy.name()
            ),
            "use --policy fifo for an rm spec, or set scheduler = \"edf\"",
        )),
        (Policy::Deadline, _) if bandwidth > 0.95 * cpus as f64 => Err(RunError::refused(
            format!(
                "SCHED_DEADLINE admission would fail: total bandwidth Σ C/T = {bandwidth:.3} exceeds 0.95 × {cpus} CPU(s) = {:.2}",
                0.95 * cpus as f64
            ),
            "lower the budgets or lengthen the periods (the kernel admits at most sched_rt_runtime_us/sched_rt_period_us of each CPU)",
        )),
        _ => Ok(()),
    }
}

/// Checks that task `t` can run under `policy` on `cpus` CPUs; returns
/// its SCHED_DEADLINE bandwidth (0 for a data-triggered task, which has no
/// reservation: its policies are refused, `queue::refusal`).
fn check_task(t: &Task, policy: Policy, cpus: usize) -> Result<f64, RunError> {
    let period = match t.fixed_period().filter(|&p| p > 0) {
        Some(p) => p,
        // Released by its triggers: no timer of its own.
        None if t.is_triggered() => return on_a_cpu(t, cpus).map(|()| 0.0),
        None => {
            return Err(RunError::config(
                format!("task {} has no fixed positive period", t.name),
                "give it `period = ...` (run `rtpipe design` to choose free periods)",
            ))
        }
    };
    on_a_cpu(t, cpus)?;
    let deadline = t.deadline_given.unwrap_or(period).min(period);
    let r = reservation(t.budget(), deadline, period);
    if policy == Policy::Deadline {
        deadline_rules(&t.name, t.budget(), (period, r.period))?;
    }
    Ok(r.runtime as f64 / r.period as f64)
}

/// Checks that task `t`'s CPU is one of this machine's `cpus`.
fn on_a_cpu(t: &Task, cpus: usize) -> Result<(), RunError> {
    if t.cpu as usize >= cpus {
        return Err(RunError::config(
            format!(
                "task {} is bound to cpu {} but this machine has {cpus} CPU(s) (0..{})",
                t.name,
                t.cpu,
                cpus - 1
            ),
            format!("set `cpu` of task {} to a CPU below {cpus}", t.name),
        ));
    }
    Ok(())
}

/// The kernel's rules for a SCHED_DEADLINE reservation (kernel/sched/
/// deadline.c: `__checkparam_dl`, and the sched_deadline_period_{min,max}_us
/// sysctls).
/// `reserved` is the reservation's period (`config::reservation`: T less
/// the renewal lead), which the kernel checks against the range.
fn deadline_rules(
    name: &str,
    budget: Nanos,
    (period, reserved): (Nanos, Nanos),
) -> Result<(), RunError> {
    if budget < 1024 {
        return Err(RunError::config(
            format!("task {name}: budget {budget} ns is below SCHED_DEADLINE's minimum runtime of 1024 ns"),
            format!("give task {name} a budget of at least 1.024 us"),
        ));
    }
    if budget > period {
        return Err(RunError::config(
            format!("task {name}: budget {budget} ns exceeds its period {period} ns"),
            format!("give task {name} a budget at most its period"),
        ));
    }
    let sysctl = |f: &str| {
        std::fs::read_to_string(format!("/proc/sys/kernel/{f}"))
            .ok()
            .and_then(|s| s.trim().parse::<i64>().ok())
    };
    let min = sysctl("sched_deadline_period_min_us").unwrap_or(100) * 1000;
    let max = sysctl("sched_deadline_period_max_us").unwrap_or(1 << 22) * 1000;
    if reserved < min || period > max {
        return Err(RunError::config(
            format!(
                "task {name}: period {period} ns (reserved as {reserved} ns, less the renewal lead) is outside SCHED_DEADLINE's allowed range [{min}, {max}] ns (kernel.sched_deadline_period_min_us/max_us)"
            ),
            format!("give task {name} a period in that range, or change the sysctls"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_period_whose_reservation_falls_below_the_kernels_minimum_is_refused() {
        // T = 100 µs is the kernel's default minimum; the reservation's
        // period is T less the lead (12.5 µs here, T/8): below it.
        let text = "[system]\nname = \"fast\"\ntime_unit = \"us\"\nscheduler = \"edf\"\n\
                    schedulability = \"edf\"\n[tasks.a]\nexec = 10\nperiod = 100\n";
        let spec = Spec::parse("fast.toml", text).unwrap_or_else(|e| panic!("{e}"));
        let cfg = RunConfig {
            duration: 10_000_000,
            policy: Policy::Deadline,
            load: 0,
        };
        let min = std::fs::read_to_string("/proc/sys/kernel/sched_deadline_period_min_us")
            .ok()
            .and_then(|s| s.trim().parse::<i64>().ok())
            .unwrap_or(100);
        if min != 100 {
            eprintln!("SKIPPED: sched_deadline_period_min_us is {min} here, not 100");
            return;
        }
        let Err(e) = check(&spec, &cfg) else {
            panic!("a reservation period of 87.5 us was accepted");
        };
        assert!(e.diagnostic.message.contains("reserved as 87500 ns"), "{e}");
    }
}
