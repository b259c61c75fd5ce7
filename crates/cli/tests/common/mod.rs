//! Helpers shared by the end-to-end tests of the `rtpipe` binary.
#![allow(dead_code)] // each test file uses its own subset

use serde_json::Value;
use std::process::{Command, Output};

/// The path of a bundled example.
pub fn example(name: &str) -> String {
    rtpipe_testkit::example_path(name)
        .to_string_lossy()
        .into_owned()
}

/// Runs the binary with these arguments.
pub fn rtpipe(args: &[&str]) -> Output {
    match Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(args)
        .output()
    {
        Ok(o) => o,
        Err(e) => panic!("cannot run rtpipe: {e}"),
    }
}

/// Stdout as JSON (the test fails with both streams shown otherwise).
pub fn json_of(o: &Output) -> Value {
    match serde_json::from_slice(&o.stdout) {
        Ok(v) => v,
        Err(e) => panic!(
            "stdout is not JSON ({e}): {}\nstderr: {}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    }
}

/// A fresh, empty scratch directory per test (`tag` unique in the test
/// binary), removed when the guard is dropped unless the test fails.
pub fn scratch(tag: &str) -> rtpipe_testkit::Scratch {
    rtpipe_testkit::Scratch::new(tag)
}

/// The exit status is `code`; the test shows stderr otherwise.
pub fn assert_exit(o: &Output, code: i32) {
    assert_eq!(
        o.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs the binary in `dir` with extra environment variables; kills it and
/// fails the test when it runs longer than `timeout`.
pub fn rtpipe_in(
    dir: &std::path::Path,
    args: &[&str],
    env: &[(&str, &str)],
    timeout: std::time::Duration,
) -> Output {
    supervise(dir, args, env, timeout, None).0
}

/// Runs the binary in `dir`, sends it SIGINT (Ctrl-C) after `after`, and
/// returns what it printed and how long it took to exit after the signal;
/// kills it and fails the test when it runs longer than `timeout` in all.
pub fn rtpipe_interrupted(
    dir: &std::path::Path,
    args: &[&str],
    after: std::time::Duration,
    timeout: std::time::Duration,
) -> (Output, std::time::Duration) {
    let (o, sent) = supervise(dir, args, &[], timeout, Some(after));
    match sent {
        Some(t) => (o, t.elapsed()),
        None => panic!(
            "rtpipe {} exited before SIGINT was sent: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr)
        ),
    }
}

/// Sends SIGINT to a process (through kill(1): no libc in the tests).
fn sigint(pid: u32) {
    match Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status()
    {
        Ok(s) if s.success() => {}
        other => panic!("kill -INT {pid} failed: {other:?}"),
    }
}

/// Runs the binary, optionally sending SIGINT after a delay (the instant it
/// was sent is returned), and kills it past `timeout`.
fn supervise(
    dir: &std::path::Path,
    args: &[&str],
    env: &[(&str, &str)],
    timeout: std::time::Duration,
    sigint_after: Option<std::time::Duration>,
) -> (Output, Option<std::time::Instant>) {
    use std::io::Read;
    use std::process::Stdio;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rtpipe"));
    cmd.args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (k, v) in env {
        cmd.env(k, v);
    }
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => panic!("cannot run rtpipe: {e}"),
    };
    let mut out = child.stdout.take();
    let mut err = child.stderr.take();
    let t_out = std::thread::spawn(move || {
        let mut b = Vec::new();
        if let Some(o) = out.as_mut() {
            let _ = o.read_to_end(&mut b);
        }
        b
    });
    let t_err = std::thread::spawn(move || {
        let mut b = Vec::new();
        if let Some(e) = err.as_mut() {
            let _ = e.read_to_end(&mut b);
        }
        b
    });
    let start = std::time::Instant::now();
    let mut sent = None;
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if sent.is_none() && sigint_after.is_some_and(|a| start.elapsed() >= a) => {
                sigint(child.id());
                sent = Some(std::time::Instant::now());
            }
            Ok(None) if start.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                panic!(
                    "rtpipe {} ran longer than {timeout:?}: killed",
                    args.join(" ")
                );
            }
            Ok(None) => std::thread::sleep(std::time::Duration::from_millis(20)),
            Err(e) => panic!("cannot wait for rtpipe: {e}"),
        }
    };
    let o = Output {
        status,
        stdout: t_out.join().unwrap_or_default(),
        stderr: t_err.join().unwrap_or_default(),
    };
    (o, sent)
}

/// The names in a directory, sorted (hidden files included).
pub fn listing(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect(),
        Err(e) => panic!("cannot list {}: {e}", dir.display()),
    };
    v.sort();
    v
}

/// A small pipeline: sensor (2 ms) → filter (5 ms) → actuator (10 ms), on
/// `cpu`, times in ms.
pub fn small_pipeline(scheduler: &str, cpu: u32, extra: &str) -> String {
    format!(
        r#"[system]
name = "small"
time_unit = "ms"
scheduler = "{scheduler}"

[channels.shm]
bandwidth = 1000
overhead = 0

[tasks.sensor]
exec = 0.2
period = 2
cpu = {cpu}
output = {{ channel = "shm", size = 0 }}
{extra}

[tasks.filter]
exec = 0.5
reads = ["sensor"]
period = 5
cpu = {cpu}
output = {{ channel = "shm", size = 0 }}

[tasks.actuator]
exec = 0.5
reads = ["filter"]
period = 10
cpu = {cpu}
output = {{ channel = "shm", size = 0 }}

[[chain]]
name = "loop"
path = ["sensor", "filter", "actuator"]
"#
    )
}
