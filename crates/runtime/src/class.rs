//! The scheduling class of a run's threads: what the process may use
//! (checked up front), memory locking, and putting each task's thread into
//! its class (SCHED_FIFO pinned to its CPU, or a SCHED_DEADLINE
//! reservation, partitioned into the CPU's root domain where possible).

use crate::config::{fifo_priorities, reservation, Policy, RunError};
use crate::partition::Partition;
use crate::sys;
use rtpipe_model::{Nanos, Spec};

/// Where and how one task's thread runs.
pub(crate) struct Placement<'a> {
    /// The task's name (for errors).
    pub(crate) name: &'a str,
    /// Its CPU.
    pub(crate) cpu: usize,
    /// Its SCHED_FIFO priority (fifo only).
    pub(crate) priority: Option<i32>,
    /// C, D and T.
    pub(crate) budget: Nanos,
    pub(crate) deadline: Nanos,
    pub(crate) period: Nanos,
    /// How long to retry a reservation the kernel refuses as busy (EBUSY):
    /// the run's longest period plus [`crate::config::ADMISSION_MARGIN`].
    pub(crate) admission_wait: Nanos,
}

/// Puts the calling thread into its scheduling class.
pub(crate) fn configure(
    th: &Placement<'_>,
    policy: Policy,
    partition: Option<&Partition>,
) -> Result<(), RunError> {
    let name = th.name;
    let refused = |what: &str, e: std::io::Error, help: String| {
        RunError::refused(format!("task {name}: the kernel refused {what}: {e}"), help)
    };
    let no_privilege = |what: &str| {
        format!(
            "{what} needs root or CAP_SYS_NICE (and an RLIMIT_RTPRIO for SCHED_FIFO); \
             run as root, or run without real-time guarantees: --policy other --best-effort"
        )
    };
    match policy {
        Policy::Fifo | Policy::Other | Policy::EdfFifo => {
            if let Err(e) = sys::pin_to(th.cpu) {
                return Err(refused(
                    &format!("pinning to cpu {}", th.cpu),
                    e,
                    format!(
                        "set `cpu` of task {name} to a CPU this process may use (see taskset -p)"
                    ),
                ));
            }
            // Under the EDF dispatcher a thread waits for its release at
            // DISPATCH (`crate::edf`).
            let fifo = match policy {
                Policy::Fifo => th.priority,
                Policy::EdfFifo => Some(crate::edf::DISPATCH),
                _ => None,
            };
            if let Some(p) = fifo {
                if let Err(e) = sys::set_fifo(p) {
                    let help = if e.raw_os_error() == Some(libc::EPERM) {
                        no_privilege("SCHED_FIFO")
                    } else {
                        "check the RT limits (ulimit -r)".into()
                    };
                    return Err(refused(&format!("SCHED_FIFO priority {p}"), e, help));
                }
            }
        }
        Policy::Deadline => deadline(th, partition, refused, no_privilege)?,
    }
    Ok(())
}

/// SCHED_DEADLINE for the calling thread: into its CPU's root domain and
/// pinned when EDF is partitioned, then the reservation.
fn deadline(
    th: &Placement<'_>,
    partition: Option<&Partition>,
    refused: impl Fn(&str, std::io::Error, String) -> RunError,
    no_privilege: impl Fn(&str) -> String,
) -> Result<(), RunError> {
    let name = th.name;
    if let Some(p) = partition {
        // Partitioned EDF: into the CPU's own root domain, pinned.
        if let Err(e) = p.enter(th.cpu).and_then(|()| sys::pin_to(th.cpu)) {
            let help =
                "check the cpuset hierarchy (rtpipe makes one exclusive set per CPU for the run)"
                    .to_string();
            return Err(refused(&format!("cpu {}'s cpuset", th.cpu), e, help));
        }
    }
    // The runtime carries the job frame on top of the budget; deadline and
    // period lead the task's (`config::reservation`).
    let r = reservation(th.budget, th.deadline, th.period);
    let (c, t) = (r.runtime as u64, r.period as u64);
    // The kernel signals an overrun of the reservation (SIGXCPU), which the
    // verdict names; the handler goes first. A kernel without the flag
    // (before 4.16) refuses it: reserve without it then.
    sys::count_dl_overruns();
    let reserve = |flags: u64| sys::set_deadline(c, r.deadline as u64, t, flags);
    let reserved = retry_busy(th.admission_wait, || {
        reserve(sys::SCHED_FLAG_DL_OVERRUN).or_else(|e| match e.raw_os_error() {
            Some(libc::EINVAL) => reserve(0),
            _ => Err(e),
        })
    });
    if let Err(e) = reserved {
        let help = match e.raw_os_error() {
            Some(libc::EPERM) => no_privilege("SCHED_DEADLINE"),
            Some(libc::EBUSY) => busy_help(c as f64 / t as f64, th, partition.is_some()),
            Some(libc::EINVAL) => format!(
                "task {name}: runtime {c} ns, deadline {} ns, period {t} ns break the kernel's rules \
                 (runtime ≥ 1024 ns, runtime ≤ deadline ≤ period, period within the sched_deadline_period sysctls)",
                r.deadline
            ),
            _ => String::new(),
        };
        return Err(refused(
            &format!("SCHED_DEADLINE (runtime {c} ns, period {t} ns)"),
            e,
            help,
        ));
    }
    Ok(())
}

/// What to do about a reservation of bandwidth `share` refused as busy
/// (EBUSY) for `th`; `partitioned`: the run has its own root domain per
/// CPU.
fn busy_help(share: f64, th: &Placement<'_>, partitioned: bool) -> String {
    let split = (!partitioned)
        .then(crate::partition::split_by_another_run)
        .flatten();
    match split {
        // Measured: paper-table2-edf beside a partitioned run of itself
        // (0.72 of CPU 0): refused pinned to CPU 0, admitted on CPU 1.
        Some(pid) => format!(
            "admission control: another rtpipe run (pid {pid}) holds the CPUs' exclusive cpusets, which \
             make each CPU a root domain of its own; the kernel admits this thread (C/T = {share:.3}) \
             against the one CPU it is on, beside that run's reservations there, not against all CPUs; \
             wait until that run ends, or pin this one (taskset -c) to CPUs that run leaves free"
        ),
        None => format!(
            "admission control: the reservations already admitted plus this one \
             (C/T = {share:.3}) exceed the deadline bandwidth (sched_rt_runtime_us/sched_rt_period_us per CPU), \
             still after {} ms of retrying (a run that just ended frees its bandwidth within its longest period); \
             lower the budgets or lengthen the periods, or stop the other SCHED_DEADLINE threads",
            th.admission_wait / 1_000_000
        ),
    }
}

/// `reserve()` until it is not refused as busy (EBUSY) or `wait` ns have
/// passed (or a stop signal came), sleeping 10 ms, then doubling up to
/// 200 ms, between tries: the bandwidth of a run that ended just before is
/// freed by the kernel only at its reservations' 0-lag time.
pub(crate) fn retry_busy(
    wait: Nanos,
    mut reserve: impl FnMut() -> std::io::Result<()>,
) -> std::io::Result<()> {
    let give_up = sys::now() + wait;
    let mut pause: Nanos = 10_000_000;
    loop {
        match reserve() {
            Err(e) if e.raw_os_error() == Some(libc::EBUSY) => {
                let now = sys::now();
                if now >= give_up || sys::stop_requested() {
                    return Err(e);
                }
                sys::sleep_until(now + pause.min(give_up - now));
                pause = (pause * 2).min(200_000_000);
            }
            done => return done,
        }
    }
}

/// Refuses up front a real-time policy this process may not use (rather
/// than failing thread by thread once the load has started).
pub(crate) fn privileges(spec: &Spec, policy: Policy) -> Result<(), RunError> {
    if policy == Policy::Other || sys::is_root() || sys::has_capability(sys::CAP_SYS_NICE) {
        return Ok(());
    }
    let top = match policy {
        Policy::EdfFifo => crate::edf::DISPATCH,
        _ => fifo_priorities(spec).into_iter().max().unwrap_or(1),
    };
    let rtprio = sys::soft_limit(libc::RLIMIT_RTPRIO);
    if matches!(policy, Policy::Fifo | Policy::EdfFifo) && rtprio >= top as u64 {
        return Ok(());
    }
    let (class, need) = match policy {
        Policy::Deadline => ("SCHED_DEADLINE", "root or CAP_SYS_NICE".to_string()),
        _ => (
            "SCHED_FIFO",
            format!("root, CAP_SYS_NICE, or an RLIMIT_RTPRIO of at least {top} (it is {rtprio})"),
        ),
    };
    Err(RunError::refused(
        format!("{class} needs {need}; this process has none of them"),
        "run as root, or grant the capability (e.g. `setcap cap_sys_nice,cap_ipc_lock+ep $(which rtpipe)`), or run without real-time guarantees: --policy other --best-effort",
    ))
}

/// Stack of a task thread: the bodies need little, and under mlockall every
/// byte of it is locked (the default 2 MiB made a thread cost 2 MiB; the
/// flight bodies run in well under 256 KiB).
pub(crate) const TASK_STACK: usize = 512 * 1024;

/// Locks memory for a real-time run where that cannot starve thread
/// stacks; the warning when it does not.
pub(crate) fn lock_memory(policy: Policy, threads: usize) -> Option<String> {
    if policy == Policy::Other {
        return None;
    }
    // What mlockall will hold at least: every task thread's whole stack.
    let stacks = threads as u64 * TASK_STACK as u64;
    if let Some(avail) = mem_available().filter(|&a| 2 * stacks > a) {
        return Some(format!(
            "warning: memory not locked: the {threads} task threads' stacks alone would lock {} MiB, more than half of the {} MiB available; page faults may delay jobs (run fewer tasks)",
            stacks >> 20,
            avail >> 20
        ));
    }
    if !may_lock_memory() {
        return Some(format!(
            "warning: memory not locked (RLIMIT_MEMLOCK is {} KiB, and mlockall under it starves thread stacks): page faults may delay jobs; `ulimit -l unlimited` or CAP_IPC_LOCK locks it",
            sys::soft_limit(libc::RLIMIT_MEMLOCK) / 1024
        ));
    }
    sys::lock_memory()
        .err()
        .map(|e| format!("warning: mlockall failed ({e}): page faults may delay jobs"))
}

/// MemAvailable of /proc/meminfo, bytes (`None` where it cannot be read).
fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kb: u64 = text
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// Whether locking all current and future memory can work: unlimited
/// RLIMIT_MEMLOCK, root or CAP_IPC_LOCK. Under a finite limit mlockall
/// itself succeeds, and then every later thread stack that does not fit
/// fails to map (EAGAIN at thread spawn), so it is not tried.
fn may_lock_memory() -> bool {
    sys::is_root()
        || sys::has_capability(sys::CAP_IPC_LOCK)
        || sys::soft_limit(libc::RLIMIT_MEMLOCK) == u64::MAX
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lock_beyond_the_available_memory_is_not_tried() {
        // Before, 3,000 tasks locked 6.2 GB. Stacks of 10^7 threads
        // exceed any machine's memory: refused with a warning, nothing
        // locked (the check comes before mlockall).
        let avail = mem_available();
        assert!(avail.is_some_and(|a| a > 0), "{avail:?}");
        let w = lock_memory(Policy::Fifo, 10_000_000).unwrap_or_default();
        assert!(w.contains("memory not locked"), "{w}");
        assert_eq!(lock_memory(Policy::Other, 10_000_000), None);
    }

    fn busy() -> std::io::Error {
        std::io::Error::from_raw_os_error(libc::EBUSY)
    }

    #[test]
    fn a_busy_reservation_is_retried_until_the_kernel_admits_it() {
        let mut tries = 0;
        let r = retry_busy(1_000_000_000, || {
            tries += 1;
            if tries < 3 {
                Err(busy())
            } else {
                Ok(())
            }
        });
        assert!(r.is_ok());
        assert_eq!(tries, 3);
    }

    #[test]
    fn a_busy_reservation_is_refused_once_the_wait_is_over() {
        let mut tries = 0;
        let r = retry_busy(25_000_000, || {
            tries += 1;
            Err(busy())
        });
        assert_eq!(r.map_err(|e| e.raw_os_error()), Err(Some(libc::EBUSY)));
        // 10 ms, 15 ms (the rest of the wait), then given up: bounded.
        assert!((2..=4).contains(&tries), "{tries} tries");
    }

    #[test]
    fn other_refusals_are_not_retried() {
        let mut tries = 0;
        let r = retry_busy(1_000_000_000, || {
            tries += 1;
            Err(std::io::Error::from_raw_os_error(libc::EPERM))
        });
        assert!(r.is_err());
        assert_eq!(tries, 1);
    }
}
