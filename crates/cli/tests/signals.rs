//! A command ended by a signal leaves the machine as it was: SIGTERM and
//! SIGHUP are handled as Ctrl-C is (the command cleans up and exits 128 +
//! the signal), and what a SIGKILL leaves behind (it runs no code) is
//! repaired by the next start: a `run`'s cpusets and the root cpuset's
//! load balancing, a `--samples` file's temporaries. The cpuset tests need
//! root and a cgroup v1 cpuset hierarchy; without them they print why and
//! pass.

mod common;

use common::{example, listing, rtpipe_in, scratch, small_pipeline};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const CPUSETS: &str = "/sys/fs/cgroup/cpuset";
/// Long enough for a start on a loaded machine, short of hanging CI.
const LIMIT: Duration = Duration::from_secs(60);

fn spawn(dir: &Path, args: &[&str]) -> Child {
    let child = Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn();
    match child {
        Ok(c) => c,
        Err(e) => panic!("cannot run rtpipe: {e}"),
    }
}

/// Sends `signal` (kill(1)'s name for it) to `pid`.
fn kill(signal: &str, pid: u32) {
    match Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .status()
    {
        Ok(s) if s.success() => {}
        other => panic!("kill -{signal} {pid} failed: {other:?}"),
    }
}

/// Waits until `ready` holds (true) or the child exits or [`LIMIT`] passes
/// (false).
fn wait_for(child: &mut Child, ready: impl Fn() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < LIMIT {
        if ready() {
            return true;
        }
        if matches!(child.try_wait(), Ok(Some(_))) {
            return false;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

/// The child's exit code and stderr, killing it past [`LIMIT`].
fn finish(mut child: Child) -> (Option<i32>, String) {
    use std::io::Read;
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if start.elapsed() > LIMIT => {
                let _ = child.kill();
                let _ = child.wait();
                panic!("rtpipe did not end within {LIMIT:?} of the signal");
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => panic!("cannot wait for rtpipe: {e}"),
        }
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = e.read_to_string(&mut err);
    }
    (status.code(), err)
}

/// The `rtpipe-*` sets under the cpuset root, and the root's load balancing.
fn cpuset_state() -> (Vec<String>, String) {
    let sets = listing(Path::new(CPUSETS))
        .into_iter()
        .filter(|n| n.starts_with("rtpipe-"))
        .collect();
    let flag = std::fs::read_to_string(Path::new(CPUSETS).join("cpuset.sched_load_balance"))
        .unwrap_or_default();
    (sets, flag.trim().to_string())
}

/// The cpuset tests one at a time: each compares the whole tree with what
/// it was before, which another's run would change.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Why the cpuset tests cannot run here, if they cannot: not root, no
/// cgroup v1 cpuset hierarchy, or another run holding the CPUs (whose
/// state would not be ours to compare).
fn cpusets_unavailable() -> Option<String> {
    let uid = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Uid:"))
                .and_then(|v| v.split_whitespace().nth(1).map(str::to_string))
        });
    if uid.as_deref() != Some("0") {
        return Some("cpusets need root".into());
    }
    if !Path::new(CPUSETS)
        .join("cpuset.sched_load_balance")
        .exists()
    {
        return Some(format!("no cgroup v1 cpuset hierarchy at {CPUSETS}"));
    }
    let (sets, _) = cpuset_state();
    (!sets.is_empty()).then(|| format!("another run holds cpusets: {sets:?}"))
}

/// A deadline run of the small pipeline in `dir`, once its partition is
/// made (its sets exist and load balancing is off); `None` (the child
/// stopped) when it never is.
fn partitioned_run(dir: &Path, seconds: &str) -> Option<Child> {
    partitioned(dir, &["--duration", seconds])
}

/// `run --policy deadline` of the small pipeline in `dir` with `extra`
/// flags, once its partition is made (as [`partitioned_run`]).
fn partitioned(dir: &Path, extra: &[&str]) -> Option<Child> {
    let spec = dir.join("spec.toml");
    if let Err(e) = std::fs::write(&spec, small_pipeline("edf", 0, "")) {
        panic!("cannot write {}: {e}", spec.display());
    }
    let spec = spec.to_string_lossy().into_owned();
    let mut args = vec!["run", &spec, "--policy", "deadline"];
    args.extend_from_slice(extra);
    let mut child = spawn(dir, &args);
    let own = PathBuf::from(CPUSETS).join(format!("rtpipe-{}-cpu0", child.id()));
    // The flag goes off once every set is made: the partition is whole.
    if wait_for(&mut child, || own.exists() && cpuset_state().1 == "0") {
        return Some(child);
    }
    let _ = child.kill();
    let (_, err) = finish(child);
    eprintln!("SKIPPED: the run made no cpusets:\n{err}");
    None
}

/// SIGTERM (what `timeout` sends) and SIGHUP end a partitioned deadline
/// run as Ctrl-C does: its cpusets removed, load balancing restored, the
/// report of the span run printed, exit 128 + the signal.
#[test]
fn sigterm_and_sighup_leave_no_cpuset_and_balancing_on() {
    let _one = serial();
    if let Some(why) = cpusets_unavailable() {
        eprintln!("SKIPPED: {why}");
        return;
    }
    let before = cpuset_state();
    for (signal, code) in [("TERM", 143), ("HUP", 129)] {
        let dir = scratch(&format!("signal-run-{signal}"));
        let Some(child) = partitioned_run(&dir, "60s") else {
            return;
        };
        kill(signal, child.id());
        let (status, err) = finish(child);
        assert_eq!(status, Some(code), "SIG{signal}: {err}");
        assert!(
            err.contains(&format!("interrupted by SIG{signal} after")),
            "{err}"
        );
        assert_eq!(cpuset_state(), before, "after SIG{signal}: {err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// SIGKILL runs no clean-up: the cpusets and the flag stay as the run
/// left them, and the next run (any policy) removes the dead run's sets,
/// restores the flag from its record and runs partitioned itself.
#[test]
fn what_sigkill_leaves_the_next_start_repairs() {
    let _one = serial();
    if let Some(why) = cpusets_unavailable() {
        eprintln!("SKIPPED: {why}");
        return;
    }
    let before = cpuset_state();
    let dir = scratch("signal-run-kill");
    let Some(child) = partitioned_run(&dir, "60s") else {
        return;
    };
    let pid = child.id();
    kill("KILL", pid);
    let (status, _) = finish(child);
    assert_eq!(status, None, "killed by a signal");
    let (left, flag) = cpuset_state();
    assert!(left.contains(&format!("rtpipe-{pid}-cpu0")), "{left:?}");
    assert_eq!(flag, "0", "the killed run's flag");
    let spec = dir.join("spec.toml").to_string_lossy().into_owned();
    let args = ["run", &spec, "--policy", "deadline", "--duration", "0.3s"];
    let next = rtpipe_in(&dir, &args, &[], LIMIT);
    let err = String::from_utf8_lossy(&next.stderr).into_owned();
    assert!(matches!(next.status.code(), Some(0 | 1)), "{err}");
    assert!(
        err.contains(&format!(
            "removed cpuset {CPUSETS}/rtpipe-{pid}-cpu0, left by a killed rtpipe run (pid {pid})"
        )),
        "{err}"
    );
    assert!(!err.contains("global EDF"), "{err}");
    assert_eq!(cpuset_state(), before, "{err}");
    assert!(!Path::new("/run/rtpipe/cpuset.sched_load_balance").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `run --measure-overheads` under deadline partitions the CPUs as a run
/// does: SIGTERM ends it with its sets removed and balancing restored, and
/// what a SIGKILL leaves the next start repairs.
#[test]
fn measure_overheads_ended_by_a_signal_leaves_the_machine_as_it_was() {
    let _one = serial();
    if let Some(why) = cpusets_unavailable() {
        eprintln!("SKIPPED: {why}");
        return;
    }
    let before = cpuset_state();
    let dir = scratch("signal-overheads");
    let Some(child) = partitioned(&dir, &["--measure-overheads"]) else {
        return;
    };
    kill("TERM", child.id());
    let (status, err) = finish(child);
    assert_eq!(status, Some(143), "SIGTERM: {err}");
    assert_eq!(cpuset_state(), before, "after SIGTERM: {err}");
    let Some(child) = partitioned(&dir, &["--measure-overheads"]) else {
        return;
    };
    let pid = child.id();
    kill("KILL", pid);
    let (status, _) = finish(child);
    assert_eq!(status, None, "killed by a signal");
    assert_ne!(cpuset_state(), before, "a SIGKILL runs no clean-up");
    let spec = dir.join("spec.toml").to_string_lossy().into_owned();
    let args = ["run", &spec, "--policy", "deadline", "--duration", "0.3s"];
    let next = rtpipe_in(&dir, &args, &[], LIMIT);
    let err = String::from_utf8_lossy(&next.stderr).into_owned();
    assert!(matches!(next.status.code(), Some(0 | 1)), "{err}");
    assert!(err.contains(&format!("(pid {pid})")), "{err}");
    assert_eq!(cpuset_state(), before, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The hidden temporaries `--samples` streams into.
fn temporaries(dir: &Path) -> Vec<String> {
    listing(dir)
        .into_iter()
        .filter(|n| n.starts_with(".s.csv.") && n.ends_with(".tmp"))
        .collect()
}

fn samples_run(dir: &Path, cmd: &str) -> Child {
    let spec = example("cleanflight.toml");
    let args = [cmd, &spec, "--duration", "20000s", "--samples", "s.csv"];
    let mut child = spawn(dir, &args);
    let started = wait_for(&mut child, || !temporaries(dir).is_empty());
    assert!(started, "rtpipe {cmd} wrote no temporary");
    child
}

/// SIGTERM and SIGHUP during `simulate`/`fly --samples` remove the
/// streamed temporaries, as Ctrl-C does, and exit 128 + the signal.
#[test]
fn sigterm_and_sighup_leave_no_samples_temporary() {
    for cmd in ["simulate", "fly"] {
        for (signal, code) in [("TERM", 143), ("HUP", 129)] {
            let dir = scratch(&format!("signal-samples-{cmd}-{signal}"));
            let child = samples_run(&dir, cmd);
            kill(signal, child.id());
            let (status, err) = finish(child);
            assert_eq!(status, Some(code), "{cmd} SIG{signal}: {err}");
            assert!(
                err.contains(&format!("interrupted (SIG{signal}): nothing written")),
                "{err}"
            );
            assert_eq!(listing(&dir), Vec::<String>::new(), "{cmd} SIG{signal}");
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
}

/// A SIGKILL leaves the temporaries; the next write into that folder
/// removes them (their pid is gone) and leaves only its own file.
#[test]
fn the_next_write_removes_what_sigkill_left() {
    let dir = scratch("signal-samples-kill");
    let child = samples_run(&dir, "simulate");
    kill("KILL", child.id());
    let (status, _) = finish(child);
    assert_eq!(status, None, "killed by a signal");
    assert!(!temporaries(&dir).is_empty(), "{:?}", listing(&dir));
    let spec = example("cleanflight.toml");
    let args = ["simulate", &spec, "--duration", "1s", "--samples", "s.csv"];
    let o = rtpipe_in(&dir, &args, &[], LIMIT);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(listing(&dir), vec!["s.csv".to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A deadline run beside a partitioned one is not global EDF: the other
/// run's exclusive cpusets make each CPU a root domain of its own, and the
/// kernel admits each thread against the one CPU it is on. Pinned to CPU 0,
/// where the other run already holds 0.72 of the bandwidth, a second
/// paper-table2-edf is refused (EBUSY) with that cause named, not "lower
/// the budgets".
#[test]
fn a_refusal_beside_another_run_s_cpusets_names_its_root_domains() {
    let _one = serial();
    if let Some(why) = cpusets_unavailable() {
        eprintln!("SKIPPED: {why}");
        return;
    }
    if Command::new("taskset").arg("--version").output().is_err() {
        eprintln!("SKIPPED: no taskset (util-linux) to pin the second run");
        return;
    }
    let before = cpuset_state();
    let dir = scratch("signal-run-beside");
    let spec = example("paper-table2-edf.toml");
    let args = ["run", &spec, "--policy", "deadline", "--duration", "60s"];
    let mut first = spawn(&dir, &args);
    let own = PathBuf::from(CPUSETS).join(format!("rtpipe-{}-cpu0", first.id()));
    // Its six reservations made, not only its cpusets.
    let pid = first.id();
    if !wait_for(&mut first, || deadline_threads(pid) == 6) {
        let _ = first.kill();
        let (_, err) = finish(first);
        eprintln!("SKIPPED: the first run made no cpusets:\n{err}");
        return;
    }
    let second = Command::new("taskset")
        .args(["-c", "0", env!("CARGO_BIN_EXE_rtpipe")])
        .args(["run", &spec, "--policy", "deadline", "--duration", "1s"])
        .current_dir(&dir)
        .stdin(Stdio::null())
        .output();
    kill("TERM", first.id());
    let (status, err) = finish(first);
    assert_eq!(status, Some(143), "the first run: {err}");
    let Ok(second) = second else {
        panic!("cannot run taskset");
    };
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(2), "{err}");
    let named = format!(
        "another rtpipe run (pid {}) holds the CPUs' exclusive cpusets, which make each CPU a root domain of its own",
        own.to_string_lossy()
            .rsplit("rtpipe-")
            .next()
            .and_then(|s| s.split('-').next())
            .unwrap_or("?")
    );
    assert!(err.contains(&named), "{err}");
    assert_eq!(cpuset_state(), before, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// How many threads of process `pid` are in SCHED_DEADLINE (policy 6, the
/// 41st field of /proc/PID/task/TID/stat).
fn deadline_threads(pid: u32) -> usize {
    let Ok(dir) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return 0;
    };
    dir.filter_map(Result::ok)
        .filter_map(|t| std::fs::read_to_string(t.path().join("stat")).ok())
        .filter(|stat| {
            // The fields after the command's closing parenthesis start at
            // the 3rd: the policy is the 39th of them.
            stat.rsplit_once(')')
                .and_then(|(_, rest)| rest.split_whitespace().nth(38).map(str::to_string))
                .as_deref()
                == Some("6")
        })
        .count()
}
