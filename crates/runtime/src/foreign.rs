//! Other processes' real-time threads on the run's CPUs (not the kernel's
//! own threads, such as migration/N): what a run's
//! foreign time may be made of, named. The run scans
//! `/proc/*/task/*/stat` (policy, priority, last CPU) and
//! `/proc/PID/task/TID/schedstat` (CPU time so far) before it starts and
//! after it ends; a SCHED_FIFO, SCHED_RR or SCHED_DEADLINE thread of
//! another process that may run on one of the run's CPUs and used CPU time
//! in between is named by [`crate::blame`] beside the foreign time of those
//! CPUs. The scans are not in the run's time: two passes over /proc.

use rtpipe_model::Nanos;
use std::collections::BTreeMap;

/// One real-time thread of another process that ran during the run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ForeignThread {
    /// Its process's id and name (`/proc/PID/comm`).
    pub pid: i32,
    /// The process's name.
    pub process: String,
    /// The thread's id and name (`/proc/PID/task/TID/comm`).
    pub tid: i32,
    /// The thread's name.
    pub thread: String,
    /// `SCHED_FIFO`, `SCHED_RR` or `SCHED_DEADLINE`.
    pub policy: &'static str,
    /// Its real-time priority (0 under SCHED_DEADLINE).
    pub priority: u32,
    /// The CPUs it may run on (its affinity), in order.
    pub cpus: Vec<usize>,
    /// The CPU it last ran on.
    pub last_cpu: usize,
    /// CPU time it used between the scans, ns (all of it for a thread
    /// that started during the run).
    pub cpu_time: Nanos,
}

impl ForeignThread {
    /// In words, for a verdict's cause or the report.
    pub fn describe(&self) -> String {
        let prio = if self.policy == "SCHED_DEADLINE" {
            String::new()
        } else {
            format!(" priority {}", self.priority)
        };
        format!(
            "{} (process {}, pid {}, tid {}), {}{prio}, last on CPU {}, {:.1} ms of CPU time during the run",
            self.thread,
            self.process,
            self.pid,
            self.tid,
            self.policy,
            self.last_cpu,
            self.cpu_time as f64 / 1e6
        )
    }
}

/// What one scan found of a thread.
#[derive(Debug, Clone)]
struct Seen {
    process: String,
    thread: String,
    policy: &'static str,
    priority: u32,
    cpus: Vec<usize>,
    last_cpu: usize,
    cpu_time: Nanos,
}

/// A scan of every other process's real-time threads, keyed by (pid, tid).
#[derive(Debug, Clone, Default)]
pub struct Scan(BTreeMap<(i32, i32), Seen>);

impl Scan {
    /// Every real-time thread of a process other than this one now.
    pub fn now() -> Scan {
        let own = std::process::id() as i32;
        let mut out = BTreeMap::new();
        for pid in numbered("/proc").filter(|&p| p != own) {
            let process = read_trimmed(&format!("/proc/{pid}/comm")).unwrap_or_default();
            for tid in numbered(&format!("/proc/{pid}/task")) {
                if let Some(seen) = thread(pid, tid, &process) {
                    out.insert((pid, tid), seen);
                }
            }
        }
        Scan(out)
    }

    /// The threads real-time at either scan that used CPU time between
    /// `self` (before) and `after` and may run on one of `cpus`, most CPU
    /// time first. A thread gone by the second scan is not seen.
    pub fn ran_until(&self, after: &Scan, cpus: &[usize]) -> Vec<ForeignThread> {
        let mut out: Vec<ForeignThread> = after
            .0
            .iter()
            .filter_map(|(&(pid, tid), a)| {
                let before = self.0.get(&(pid, tid)).map_or(0, |b| b.cpu_time);
                let used = a.cpu_time - before;
                let here = a.cpus.iter().any(|c| cpus.contains(c));
                (used > 0 && here).then(|| ForeignThread {
                    pid,
                    process: a.process.clone(),
                    tid,
                    thread: a.thread.clone(),
                    policy: a.policy,
                    priority: a.priority,
                    cpus: a.cpus.clone(),
                    last_cpu: a.last_cpu,
                    cpu_time: used,
                })
            })
            .collect();
        out.sort_by(|x, y| y.cpu_time.cmp(&x.cpu_time).then(x.tid.cmp(&y.tid)));
        out
    }
}

/// The CPUs of a spec's tasks, in order.
pub fn cpus_of(spec: &rtpipe_model::Spec) -> Vec<usize> {
    let mut cpus: Vec<usize> = spec.tasks.iter().map(|t| t.cpu as usize).collect();
    cpus.sort_unstable();
    cpus.dedup();
    cpus
}

/// The numeric entries of a /proc directory (none when unreadable).
fn numbered(dir: &str) -> impl Iterator<Item = i32> {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok()?.file_name().to_str()?.parse().ok())
}

fn read_trimmed(path: &str) -> Option<String> {
    Some(std::fs::read_to_string(path).ok()?.trim().to_string())
}

/// A kernel thread (include/linux/sched.h).
const PF_KTHREAD: u64 = 0x0020_0000;

/// Thread `tid` of `pid` when it is real-time now (a thread gone or
/// unreadable meanwhile is skipped).
fn thread(pid: i32, tid: i32, process: &str) -> Option<Seen> {
    let base = format!("/proc/{pid}/task/{tid}");
    let stat = std::fs::read_to_string(format!("{base}/stat")).ok()?;
    let (name, fields) = split_stat(&stat)?;
    // After the name, field 3 (state) is index 0: processor is field 39,
    // rt_priority 40, policy 41 (proc(5)).
    let field = |n: usize| fields.get(n - 3)?.parse::<u64>().ok();
    // The kernel's own threads (flags, field 9: PF_KTHREAD), migration/N
    // and the like, are the kernel's latency, not another process.
    if field(9)? & PF_KTHREAD != 0 {
        return None;
    }
    let policy = match field(41)? {
        1 => "SCHED_FIFO",
        2 => "SCHED_RR",
        6 => "SCHED_DEADLINE",
        _ => return None,
    };
    let schedstat = std::fs::read_to_string(format!("{base}/schedstat")).ok()?;
    let status = std::fs::read_to_string(format!("{base}/status")).ok()?;
    let cpus = status
        .lines()
        .find_map(|l| l.strip_prefix("Cpus_allowed_list:"))
        .map(|l| cpu_list(l.trim()))
        .unwrap_or_default();
    Some(Seen {
        process: process.to_string(),
        thread: name.to_string(),
        policy,
        priority: field(40)? as u32,
        cpus,
        last_cpu: field(39)? as usize,
        cpu_time: schedstat.split_whitespace().next()?.parse().ok()?,
    })
}

/// A stat line's name (between the first '(' and the last ')': a name may
/// hold both) and the fields after it.
fn split_stat(stat: &str) -> Option<(&str, Vec<&str>)> {
    let open = stat.find('(')?;
    let close = stat.rfind(')')?;
    let name = stat.get(open + 1..close)?;
    Some((name, stat.get(close + 1..)?.split_whitespace().collect()))
}

/// A kernel CPU list ("0-3,6") as CPU numbers.
fn cpu_list(text: &str) -> Vec<usize> {
    let mut out = Vec::new();
    for part in text.split(',').filter(|p| !p.is_empty()) {
        let mut ends = part.splitn(2, '-').map(|x| x.trim().parse::<usize>());
        match (ends.next(), ends.next()) {
            (Some(Ok(a)), None) => out.push(a),
            (Some(Ok(a)), Some(Ok(b))) if a <= b => out.extend(a..=b),
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stat_line_s_name_may_hold_parentheses_and_spaces() {
        let (name, f) = split_stat("42 (a (b) c) S 1 2").unwrap_or(("", Vec::new()));
        assert_eq!(name, "a (b) c");
        assert_eq!(f, ["S", "1", "2"]);
    }

    #[test]
    fn cpu_lists_read_as_the_kernel_writes_them() {
        assert_eq!(cpu_list("0-2,5"), [0, 1, 2, 5]);
        assert_eq!(cpu_list("1"), [1]);
        assert!(cpu_list("").is_empty());
    }

    #[test]
    fn only_threads_that_ran_on_the_run_s_cpus_are_named() {
        let seen = |cpu_time: Nanos, cpus: Vec<usize>| Seen {
            process: "p".into(),
            thread: "t".into(),
            policy: "SCHED_FIFO",
            priority: 99,
            cpus,
            last_cpu: 0,
            cpu_time,
        };
        let before = Scan(BTreeMap::from([
            ((1, 1), seen(5, vec![0])),
            ((2, 2), seen(5, vec![1])),
        ]));
        let after = Scan(BTreeMap::from([
            ((1, 1), seen(5, vec![0])),
            ((2, 2), seen(9, vec![1])),
            ((3, 3), seen(7, vec![0, 1])),
        ]));
        let ran = before.ran_until(&after, &[1]);
        let ids: Vec<(i32, Nanos)> = ran.iter().map(|t| (t.tid, t.cpu_time)).collect();
        // (1, 1) used nothing; (3, 3) started during the run.
        assert_eq!(ids, [(3, 7), (2, 4)]);
        assert!(
            ran[0].describe().contains("SCHED_FIFO priority 99"),
            "{}",
            ran[0].describe()
        );
    }

    #[test]
    fn neither_this_process_nor_the_kernel_s_threads_are_foreign() {
        let own = std::process::id() as i32;
        let scan = Scan::now();
        assert!(scan.0.keys().all(|&(pid, _)| pid != own));
        // kthreadd (pid 2) and its children are the kernel's.
        assert!(
            scan.0
                .values()
                .all(|s| !s.process.starts_with("migration/")),
            "{scan:?}"
        );
    }
}
