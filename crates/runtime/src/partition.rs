//! Partitioned EDF for SCHED_DEADLINE: one root domain per CPU, made of
//! exclusive cpusets (the kernel's sched-deadline.rst, "SCHED_DEADLINE and
//! cpusets HOWTO"). The kernel only lets a deadline thread be pinned to a
//! CPU set that spans its root domain, so without this every reservation
//! runs global EDF over all CPUs, which the analysis (EDF per CPU, as the
//! spec places the tasks) does not cover. cgroup v1's cpuset hierarchy is
//! used where mounted; the machine's state is restored when the
//! [`Partition`] drops.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// Where a cgroup v1 cpuset hierarchy may be mounted.
const MOUNTS: [&str; 2] = ["/sys/fs/cgroup/cpuset", "/dev/cpuset"];

/// One exclusive cpuset per CPU for the run; dropped, the machine is as
/// before (threads moved back to the root cpuset, the sets removed, the
/// root's load balancing restored).
pub struct Partition {
    root: PathBuf,
    sets: Vec<PathBuf>,
    balance_was: String,
}

impl Partition {
    /// Splits the CPUs 0..cpus into one root domain each; why not, when it
    /// cannot (no cpuset v1 hierarchy, not root, the kernel refused).
    pub fn create(cpus: usize) -> Result<Partition, String> {
        let root = MOUNTS
            .iter()
            .map(PathBuf::from)
            .find(|p| p.join("cpuset.sched_load_balance").exists())
            .ok_or("no cgroup v1 cpuset hierarchy with cpuset.sched_load_balance is mounted")?;
        let balance_was = read(&root.join("cpuset.sched_load_balance"))?;
        let mut p = Partition {
            root,
            sets: Vec::new(),
            balance_was,
        };
        let pid = std::process::id();
        for cpu in 0..cpus {
            let dir = p.root.join(format!("rtpipe-{pid}-cpu{cpu}"));
            fs::create_dir(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
            p.sets.push(dir.clone());
            write(&dir.join("cpuset.cpus"), &cpu.to_string())?;
            write(
                &dir.join("cpuset.mems"),
                &read(&p.root.join("cpuset.mems"))?,
            )?;
            write(&dir.join("cpuset.cpu_exclusive"), "1")?;
        }
        write(&p.root.join("cpuset.sched_load_balance"), "0")?;
        Ok(p)
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
        // Best effort: a step that fails leaves the rest to do.
        let _ = fs::write(
            self.root.join("cpuset.sched_load_balance"),
            &self.balance_was,
        );
        for set in &self.sets {
            if let Ok(tasks) = fs::read_to_string(set.join("tasks")) {
                for tid in tasks.split_whitespace() {
                    let _ = fs::write(self.root.join("tasks"), tid);
                }
            }
            let _ = fs::remove_dir(set);
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
            sys::set_deadline(1_000_000, 10_000_000, 10_000_000)?;
            let _ = sys::set_other(sys::gettid());
            drop(p);
            Ok::<(), io::Error>(())
        })
        .join();
        assert!(matches!(r, Ok(Ok(()))), "{r:?}");
        let root = MOUNTS.iter().map(PathBuf::from).find(|p| p.exists());
        assert!(root
            .is_some_and(|r| read(&r.join("cpuset.sched_load_balance")).is_ok_and(|b| b == "1")));
    }
}
