//! Partitioned EDF for SCHED_DEADLINE: one root domain per CPU, made of
//! exclusive cpusets (the kernel's sched-deadline.rst, "SCHED_DEADLINE and
//! cpusets HOWTO"). The kernel only lets a deadline thread be pinned to a
//! CPU set that spans its root domain, so without this every reservation
//! runs global EDF over all CPUs, which the analysis (EDF per CPU, as the
//! spec places the tasks) does not cover. cgroup v1's cpuset hierarchy is
//! used where mounted.
//!
//! The machine's state is restored when the [`Partition`] drops (the end
//! of a run, an error, a panic, a stop signal). A SIGKILL runs no code, so
//! the state also repairs itself: the root's `sched_load_balance` is
//! recorded in [`RECORD`] before it is turned off, the sets carry the pid
//! of the run that made them, and the next start ([`repair`]) removes the
//! sets of a pid that is gone and restores the recorded value. All of it
//! under one lock ([`LOCK`]), so that two runs never see each other's
//! half-made state.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// Where a cgroup v1 cpuset hierarchy may be mounted.
const MOUNTS: [&str; 2] = ["/sys/fs/cgroup/cpuset", "/dev/cpuset"];

/// The root cpuset's `sched_load_balance` as it was before the first run
/// that turned it off; removed when a run puts it back. In /run (a tmpfs,
/// emptied at boot, exactly when the cpusets are), so it never outlives
/// the state it describes.
pub const RECORD: &str = "/run/rtpipe/cpuset.sched_load_balance";

/// The lock every change to the cpusets and the record is made under
/// (flock: released by the kernel when its holder dies, even by SIGKILL).
pub const LOCK: &str = "/run/rtpipe/cpuset.lock";

/// The prefix of a run's sets: `rtpipe-PID-cpuN`.
const PREFIX: &str = "rtpipe-";

/// One exclusive cpuset per CPU for the run; dropped, the machine is as
/// before (threads moved back to the root cpuset, the sets removed, the
/// root's load balancing restored).
pub struct Partition {
    root: PathBuf,
    sets: Vec<PathBuf>,
}

impl Partition {
    /// Splits the CPUs 0..cpus into one root domain each; why not, when it
    /// cannot (no cpuset v1 hierarchy, not root, another run holds the
    /// CPUs, the kernel refused).
    pub fn create(cpus: usize) -> Result<Partition, String> {
        let root = mount()
            .ok_or("no cgroup v1 cpuset hierarchy with cpuset.sched_load_balance is mounted")?;
        let lock = Lock::take()?;
        repair_under(&lock, &root)?;
        if let Some(pid) = live_sets(&root).into_iter().map(|(_, pid)| pid).next() {
            return Err(format!(
                "another rtpipe run (pid {pid}) holds the CPUs' exclusive cpusets"
            ));
        }
        record_balance(&lock, &root)?;
        let mut p = Partition {
            root,
            sets: Vec::new(),
        };
        let made = p.make_sets(cpus);
        // Undone under the lock only after it is released: `drop` takes it.
        drop(lock);
        made.map(|()| p)
    }

    /// The sets, then load balancing off; each set is in `self.sets` as
    /// soon as it exists, so that dropping undoes what was done.
    fn make_sets(&mut self, cpus: usize) -> Result<(), String> {
        let pid = std::process::id();
        let mems = read(&self.root.join("cpuset.mems"))?;
        for cpu in 0..cpus {
            let dir = self.root.join(format!("{PREFIX}{pid}-cpu{cpu}"));
            fs::create_dir(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
            self.sets.push(dir.clone());
            write(&dir.join("cpuset.cpus"), &cpu.to_string())?;
            write(&dir.join("cpuset.mems"), &mems)?;
            write(&dir.join("cpuset.cpu_exclusive"), "1")?;
        }
        write(&self.root.join("cpuset.sched_load_balance"), "0")
    }

    /// Moves the calling thread into `cpu`'s set (its own root domain).
    pub fn enter(&self, cpu: usize) -> io::Result<()> {
        let set = self
            .sets
            .get(cpu)
            .ok_or_else(|| io::Error::from(io::ErrorKind::NotFound))?;
        fs::write(set.join("tasks"), crate::sys::gettid().to_string())
    }
}

impl Drop for Partition {
    fn drop(&mut self) {
        // Best effort: a step that fails leaves the rest to do, and what
        // is left the next start repairs. Without the lock (its file
        // cannot be opened) the sets still go.
        let lock = Lock::take().ok();
        for set in &self.sets {
            remove_set(&self.root, set);
        }
        if let Some(lock) = &lock {
            let _ = restore_balance(lock, &self.root);
        }
    }
}

/// Removes the cpusets of rtpipe runs that are gone (killed by SIGKILL)
/// and, when no run holds any, restores the root's load balancing from
/// [`RECORD`]: what was repaired, one line each (empty when the machine
/// was as it should be, or has no cpuset v1 hierarchy). Every run calls
/// it at its start, whatever its policy.
pub fn repair() -> Result<Vec<String>, String> {
    let Some(root) = mount() else {
        return Ok(Vec::new());
    };
    if !crate::sys::is_root() {
        return Ok(Vec::new());
    }
    let lock = Lock::take()?;
    repair_under(&lock, &root)
}

/// [`repair`] with the lock held.
fn repair_under(lock: &Lock, root: &Path) -> Result<Vec<String>, String> {
    let mut done: Vec<String> = Vec::new();
    for (set, pid) in sets(root) {
        if alive(pid) {
            continue;
        }
        remove_set(root, &set);
        if set.exists() {
            return Err(format!(
                "cannot remove {}, left by a killed rtpipe run (pid {pid}); remove it by hand (rmdir)",
                set.display()
            ));
        }
        done.push(format!(
            "note: removed cpuset {}, left by a killed rtpipe run (pid {pid})",
            set.display()
        ));
    }
    if !done.is_empty() && !Path::new(RECORD).exists() {
        // A killed run of an rtpipe that kept no record: the kernel's
        // default is what it found.
        write_record("1")?;
    }
    if let Some(restored) = restore_balance(lock, root)? {
        done.push(format!(
            "note: restored {}/cpuset.sched_load_balance to {restored}, left off by a killed rtpipe run",
            root.display()
        ));
    }
    Ok(done)
}

/// When no run holds a set: puts the root's load balancing back to the
/// recorded value and removes the record; the value restored, if it was
/// changed.
fn restore_balance(_lock: &Lock, root: &Path) -> Result<Option<String>, String> {
    if !sets(root).is_empty() {
        return Ok(None);
    }
    let flag = root.join("cpuset.sched_load_balance");
    let recorded = match fs::read_to_string(RECORD) {
        Ok(v) => v.trim().to_string(),
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read {RECORD}: {e}")),
    };
    if !matches!(recorded.as_str(), "0" | "1") {
        return Err(format!(
            "{RECORD} holds `{recorded}`, not a sched_load_balance value; write 1 (the kernel's default) to {} and remove it",
            flag.display()
        ));
    }
    let now = read(&flag)?;
    if now != recorded {
        write(&flag, &recorded)?;
    }
    fs::remove_file(RECORD).map_err(|e| format!("cannot remove {RECORD}: {e}"))?;
    Ok((now != recorded).then_some(recorded))
}

/// Records the root's load balancing before a run turns it off, unless a
/// record is already there (a killed run's: it holds the machine's own
/// value, the flag now is that run's 0).
fn record_balance(_lock: &Lock, root: &Path) -> Result<(), String> {
    if Path::new(RECORD).exists() {
        return Ok(());
    }
    write_record(&read(&root.join("cpuset.sched_load_balance"))?)
}

/// Writes [`RECORD`] whole or not at all (a temporary renamed over it).
fn write_record(value: &str) -> Result<(), String> {
    let temp = format!("{RECORD}.{}", std::process::id());
    fs::write(&temp, value)
        .and_then(|()| fs::rename(&temp, RECORD))
        .map_err(|e| {
            let _ = fs::remove_file(&temp);
            format!("cannot record the load-balancing flag in {RECORD}: {e}")
        })
}

/// The pid of another live rtpipe run whose exclusive cpusets split the
/// CPUs into one root domain each, if any. A run that is not partitioned
/// beside it is no global EDF either: the kernel admits each of its
/// SCHED_DEADLINE threads against the bandwidth of the root domain of the
/// CPU it sits on (`sched_dl_overflow`: one CPU's share, beside that run's
/// reservations there), and schedules it within that domain.
pub fn split_by_another_run() -> Option<u32> {
    let own = std::process::id();
    let root = mount()?;
    live_sets(&root)
        .into_iter()
        .map(|(_, pid)| pid)
        .find(|&pid| pid != own)
}

/// The cpuset hierarchy's root.
fn mount() -> Option<PathBuf> {
    MOUNTS
        .iter()
        .map(PathBuf::from)
        .find(|p| p.join("cpuset.sched_load_balance").exists())
}

/// Every `rtpipe-PID-cpuN` set under `root`, with its PID.
fn sets(root: &Path) -> Vec<(PathBuf, u32)> {
    let Ok(dir) = fs::read_dir(root) else {
        return Vec::new();
    };
    let mut found: Vec<(PathBuf, u32)> = dir
        .filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let (pid, cpu) = name.strip_prefix(PREFIX)?.split_once("-cpu")?;
            cpu.parse::<usize>().ok()?;
            Some((e.path(), pid.parse().ok()?))
        })
        .collect();
    found.sort();
    found
}

/// The sets of runs still alive.
fn live_sets(root: &Path) -> Vec<(PathBuf, u32)> {
    sets(root)
        .into_iter()
        .filter(|&(_, pid)| alive(pid))
        .collect()
}

/// Whether process `pid` exists.
fn alive(pid: u32) -> bool {
    Path::new("/proc").join(pid.to_string()).exists()
}

/// Moves whatever is left in `set` to the root, then removes it.
fn remove_set(root: &Path, set: &Path) {
    if let Ok(tasks) = fs::read_to_string(set.join("tasks")) {
        for tid in tasks.split_whitespace() {
            let _ = fs::write(root.join("tasks"), tid);
        }
    }
    let _ = fs::remove_dir(set);
}

/// The held [`LOCK`]; released when dropped (the file closed).
struct Lock {
    _file: fs::File,
}

impl Lock {
    fn take() -> Result<Lock, String> {
        let dir = Path::new(LOCK).parent().unwrap_or(Path::new("/run"));
        fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let file = fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(LOCK)
            .map_err(|e| format!("cannot open {LOCK}: {e}"))?;
        use std::os::fd::AsRawFd;
        loop {
            // SAFETY: flock on a descriptor this function owns.
            if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } == 0 {
                return Ok(Lock { _file: file });
            }
            let e = io::Error::last_os_error();
            if e.kind() != io::ErrorKind::Interrupted {
                return Err(format!("cannot lock {LOCK}: {e}"));
            }
        }
    }
}

fn read(p: &Path) -> Result<String, String> {
    fs::read_to_string(p)
        .map(|s| s.trim().to_string())
        .map_err(|e| format!("cannot read {}: {e}", p.display()))
}

fn write(p: &Path, v: &str) -> Result<(), String> {
    fs::write(p, v).map_err(|e| format!("cannot write {v} to {}: {e}", p.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sys;

    /// A thread in its CPU's set may be pinned there and given a
    /// reservation; dropped, the sets are gone and balancing is back.
    #[test]
    fn a_pinned_deadline_thread_in_its_own_root_domain() {
        if !sys::is_root() {
            eprintln!("SKIPPED: cpusets need root");
            return;
        }
        let before = mount().map(|r| read(&r.join("cpuset.sched_load_balance")));
        let p = match Partition::create(sys::online_cpus()) {
            Ok(p) => p,
            Err(why) => {
                eprintln!("SKIPPED: {why}");
                return;
            }
        };
        let sets = p.sets.clone();
        let r = std::thread::spawn(move || {
            let cpu = sets.len() - 1;
            p.enter(cpu)?;
            sys::pin_to(cpu)?;
            sys::set_deadline(1_000_000, 10_000_000, 10_000_000, 0)?;
            let _ = sys::set_other(sys::gettid());
            drop(p);
            Ok::<(), io::Error>(())
        })
        .join();
        assert!(matches!(r, Ok(Ok(()))), "{r:?}");
        let after = mount().map(|r| read(&r.join("cpuset.sched_load_balance")));
        assert_eq!(after, before);
    }
}
