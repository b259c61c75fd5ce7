//! `rtpipe import px4-ulog`: pyulog's Cube Orange log (model's
//! tests/data/px4) in, a spec that loads and analyses and its measured data
//! ages out; logs that lack what the spec needs refused with nothing written.

mod common;

use common::{assert_exit, json_of, listing, rtpipe, scratch};
use rtpipe_model::Spec;
use rtpipe_testkit::Scratch;
use std::path::{Path, PathBuf};

fn log(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../model/tests/data/px4")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn import(tag: &str, log: &str, extra: &[&str]) -> (std::process::Output, Scratch) {
    let out = scratch(tag).within("out");
    let mut args = vec!["import", "px4-ulog", log];
    let shown = out.to_string_lossy().into_owned();
    args.push(&shown);
    args.extend_from_slice(extra);
    (rtpipe(&args), out)
}

/// The observed rows of one topic: (count, least and largest data age ns).
fn ages(csv: &str, topic: &str) -> (usize, u64, u64) {
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("chain,topic,timestamp_ns,timestamp_sample_ns,data_age_ns")
    );
    let (mut n, mut lo, mut hi) = (0, u64::MAX, 0);
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 5, "{line}");
        if f[1] != topic {
            continue;
        }
        assert_eq!(f[0], format!("gyro to {topic}"));
        let (t, s, age): (u64, u64, u64) = (
            f[2].parse().unwrap(),
            f[3].parse().unwrap(),
            f[4].parse().unwrap(),
        );
        assert_eq!(t - s, age);
        assert_eq!(t % 1000, 0, "µs × 1000");
        n += 1;
        lo = lo.min(age);
        hi = hi.max(age);
    }
    (n, lo, hi)
}

#[test]
fn the_cube_orange_log_imports_loads_and_analyses() {
    let (o, out) = import(
        "px4-cube",
        &log("sample_log_small.ulg"),
        &["--exec", "mean"],
    );
    assert_exit(&o, 0);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("CUBEPILOT_CUBEORANGE (PX4 v1.11.2)"),
        "{stdout}"
    );
    assert!(
        stdout.contains("interrupt load"),
        "the summary states the assumptions: {stdout}"
    );
    assert_eq!(listing(&out), ["observed.csv", "spec.toml"]);
    let csv = std::fs::read_to_string(out.join("observed.csv")).unwrap();
    assert_eq!(
        ages(&csv, "vehicle_angular_velocity"),
        (1812, 395_000, 445_000)
    );
    assert_eq!(ages(&csv, "actuator_controls_0"), (1812, 414_000, 465_000));
    let spec_path = out.join("spec.toml");
    let spec = Spec::load(&spec_path).unwrap_or_else(|e| panic!("{e}"));
    assert!(spec.event_triggered());
    let a = rtpipe(&["analyze", &spec_path.to_string_lossy(), "--json"]);
    assert_exit(&a, 0);
    let report = json_of(&a);
    assert_eq!(report["ok"], true, "{report}");
    // Every measured data age lies within the sound bound from the event
    // (the gyro samples before its driver reads the FIFO).
    for chain in report["chains"].as_array().unwrap() {
        let name = chain["name"].as_str().unwrap();
        let Some(topic) = name.strip_prefix("gyro to ").filter(|t| *t != "outputs") else {
            continue;
        };
        let bound = chain["from_event"]["sound"].as_f64();
        let (_, _, hi) = ages(&csv, topic);
        assert!(
            bound.is_some_and(|b| hi as f64 / 1000.0 <= b),
            "{name}: {hi} ns against {bound:?}"
        );
    }
    // `analyze --observed` agrees: every row within its bound, exit 0.
    let observed = out.join("observed.csv");
    let spec_arg = spec_path.to_string_lossy();
    let obs_arg = observed.to_string_lossy();
    let a = rtpipe(&["analyze", &spec_arg, "--observed", &obs_arg, "--json"]);
    assert_exit(&a, 0);
    let v = json_of(&a);
    assert_eq!(v["observed"]["ok"], true, "{}", v["observed"]);
    let measured = v["observed"]["measured"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert_eq!(measured.len(), 4, "two chains × reaction and freshness");
    for m in &measured {
        assert_eq!(m["count"], 1812, "{m}");
        assert!(m["ratio"].as_f64().is_some_and(|r| r < 0.2), "{m}");
    }
}

#[test]
fn a_log_before_work_queues_without_times_is_refused_and_nothing_is_written() {
    let v16 = log("sample_appended_multiple.ulg");
    let (o, out) = import("px4-noperf", &v16, &[]);
    assert_exit(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("lacks perf_counter_*")
            && stderr.contains("--exec-from")
            && stderr.contains("--exec-us"),
        "{stderr}"
    );
    assert!(!out.exists());
    // A version the log contradicts is refused by name.
    let cube = log("sample_log_small.ulg");
    let extra = ["--exec-from", cube.as_str(), "--px4-version", "1.11"];
    let (o, out) = import("px4-v16-wrong", &v16, &extra);
    assert_exit(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("PX4 v1.6.0"), "{stderr}");
    assert!(!out.exists());
    // A version that is not X.Y is refused with the form expected.
    let extra = ["--exec-from", cube.as_str(), "--px4-version", "six"];
    let (o, out) = import("px4-v16-bad", &v16, &extra);
    assert_exit(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("expected X.Y"), "{stderr}");
    assert!(!out.exists());
}

/// PX4 v1.6.0 (Pixhawk 4 Pro, ekf2), before work queues: each module a
/// task polling the topic before it, timed by the Cube Orange's counters.
#[test]
fn a_v1_6_log_imports_as_tasks_and_analyze_exits_0() {
    let cube = log("sample_log_small.ulg");
    let extra = ["--exec-from", cube.as_str()];
    let (o, out) = import("px4-v16", &log("sample_appended_multiple.ulg"), &extra);
    assert_exit(&o, 0);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("PX4FMU_V4PRO (PX4 v1.6.0)"), "{stdout}");
    assert!(stdout.contains("SCHED_PRIORITY_MAX - 5"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("observed.csv")).unwrap();
    assert_eq!(
        ages(&csv, "actuator_controls_0"),
        (95, 3_520_000, 4_660_000)
    );
    let measured = analyze_observed(&out);
    assert_eq!(measured.len(), 1, "{measured:?}");
    let (chain, count, ratio) = &measured[0];
    assert_eq!(
        (chain.as_str(), *count),
        ("gyro to actuator_controls_0", 95)
    );
    assert!(*ratio > 0.5 && *ratio < 0.6, "{ratio}");
}

/// pyulog's `sample.ulg` (AUAV-X2.1, 2016, no `ver_sw_release`, 4 MB, not
/// copied here): from `RTPIPE_PYULOG_DIR`, skipped when unset. Its version
/// is inferred (v1.5–v1.6), its estimator `attitude_estimator_q`, which no
/// counter of the Cube Orange times: given with `--exec-us`.
#[test]
fn pyulog_sample_before_work_queues_imports_and_analyze_exits_0() {
    let Some(dir) = std::env::var_os("RTPIPE_PYULOG_DIR") else {
        eprintln!("note: RTPIPE_PYULOG_DIR is unset: pyulog's sample.ulg not imported");
        return;
    };
    let sample = Path::new(&dir).join("sample.ulg");
    let cube = log("sample_log_small.ulg");
    let sample = sample.to_string_lossy();
    let (o, out) = import("px4-sample", &sample, &["--exec-from", cube.as_str()]);
    assert_exit(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("--exec-us attitude_estimator_q=US"),
        "{stderr}"
    );
    assert!(!out.exists());
    let extra = ["--exec-from", cube.as_str(), "--exec-us", ESTIMATOR_Q];
    let (o, out) = import("px4-sample", &sample, &extra);
    assert_exit(&o, 0);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("AUAV_X21 (PX4 v1.5–v1.6, inferred)"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(out.join("observed.csv")).unwrap();
    assert_eq!(
        ages(&csv, "actuator_controls_0"),
        (3269, 355_000, 2_115_000)
    );
    let measured = analyze_observed(&out);
    assert_eq!(measured.len(), 1, "{measured:?}");
    assert!(measured[0].2 > 0.2 && measured[0].2 < 0.3, "{measured:?}");
}

/// `attitude_estimator_q`'s time for pyulog's `sample.ulg`: the Cube
/// Orange's longest `ekf2: update` run, 342 µs (docs/px4.md says why).
const ESTIMATOR_Q: &str = "attitude_estimator_q=342";

/// `analyze SPEC --observed observed.csv --json` of an import: exit 0, and
/// each measured chain's (name, count, largest/sound ratio).
fn analyze_observed(out: &Path) -> Vec<(String, u64, f64)> {
    let spec = out.join("spec.toml");
    let observed = out.join("observed.csv");
    let a = rtpipe(&[
        "analyze",
        &spec.to_string_lossy(),
        "--observed",
        &observed.to_string_lossy(),
        "--json",
    ]);
    assert_exit(&a, 0);
    let v = json_of(&a);
    assert_eq!(v["observed"]["ok"], true, "{}", v["observed"]);
    let measured = v["observed"]["measured"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    measured
        .iter()
        .filter(|m| m["metric"] == "freshness")
        .map(|m| {
            (
                m["chain"].as_str().unwrap_or("?").to_string(),
                m["count"].as_u64().unwrap_or(0),
                m["ratio"].as_f64().unwrap_or(f64::NAN),
            )
        })
        .collect()
}

#[test]
fn sitl_logs_import_with_the_cube_orange_counters_and_analyze_exits_0() {
    let cube = log("sample_log_small.ulg");
    for (name, tag, counts) in [
        (
            "sample_logging_tagged_and_default_params.ulg",
            "px4-sitl13",
            &[1078u64, 217][..],
        ),
        (
            "sample_px4_events.ulg",
            "px4-sitl15",
            &[1558, 1558, 313][..],
        ),
    ] {
        let extra = ["--exec-from", cube.as_str(), "--exec", "mean"];
        let (o, out) = import(tag, &log(name), &extra);
        assert_exit(&o, 0);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(stdout.contains("lockstep ages"), "{stdout}");
        assert!(stdout.contains("PX4_SITL"), "{stdout}");
        let measured = analyze_observed(&out);
        let got: Vec<u64> = measured.iter().map(|m| m.1).collect();
        assert_eq!(got, counts, "{name}: {measured:?}");
        // Lockstep: every age 0 µs, so every ratio is 0.
        assert!(measured.iter().all(|m| m.2 == 0.0), "{measured:?}");
    }
}

#[test]
fn a_sitl_log_without_exec_from_is_refused_naming_the_flag() {
    let (o, out) = import("px4-sitl-alone", &log("sample_px4_events.ulg"), &[]);
    assert_exit(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("0 µs") && stderr.contains("--exec-from"),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// Every log of pyulog's `test/` folder (`RTPIPE_PYULOG_DIR`; skipped when
/// unset): each imports with the Cube Orange's counters and `analyze
/// --observed` exits 0 on it, or it is refused (exit 2, one `error:` line
/// naming what it lacks, nothing written).
#[test]
fn pyulog_logs_from_a_folder() {
    let Some(dir) = std::env::var_os("RTPIPE_PYULOG_DIR") else {
        eprintln!("note: RTPIPE_PYULOG_DIR is unset: pyulog's test logs not imported");
        return;
    };
    let cube = log("sample_log_small.ulg");
    let mut logs: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ulg"))
        .collect();
    logs.sort();
    for (k, path) in logs.iter().enumerate() {
        let (o, out) = import_pyulog(&format!("px4-pyulog-{k}"), path, &cube);
        let stderr = String::from_utf8_lossy(&o.stderr);
        match o.status.code() {
            Some(0) => {
                let measured = analyze_observed(&out);
                eprintln!("{}: imported, {measured:?}", path.display());
            }
            Some(2) => {
                assert!(stderr.starts_with("error: "), "{stderr}");
                assert!(!out.exists());
                eprintln!("{}: refused: {stderr}", path.display());
            }
            code => panic!("{}: exit {code:?}: {stderr}", path.display()),
        }
    }
}

/// Imports one of pyulog's logs with the Cube Orange's counters, `--exec
/// mean`; a log before work queues with `--exec max` (the Cube's average
/// runs are too short for those boards: docs/px4.md), and with
/// attitude_estimator_q's time when it is refused for want of it.
fn import_pyulog(tag: &str, path: &Path, cube: &str) -> (std::process::Output, Scratch) {
    let shown = path.to_string_lossy();
    let mut extra = vec!["--exec-from", cube, "--exec", "mean"];
    let (o, out) = import(tag, &shown, &extra);
    let estimator = String::from_utf8_lossy(&o.stderr).contains("attitude_estimator_q=US");
    if estimator {
        extra.extend(["--exec-us", ESTIMATOR_Q]);
    }
    let tasks = |o: &std::process::Output| {
        String::from_utf8_lossy(&o.stdout).contains("before work queues")
    };
    if estimator || tasks(&o) {
        extra[3] = "max";
        let (o, out) = import(&format!("{tag}-tasks"), &shown, &extra);
        assert_exit(&o, 0);
        assert!(tasks(&o));
        return (o, out);
    }
    (o, out)
}

#[test]
fn a_file_that_is_not_ulog_is_refused_with_its_place() {
    let dir = scratch("px4-notulog");
    let f = dir.join("x.ulg");
    std::fs::write(&f, "[system]\nname = \"x\"\n").unwrap();
    let (o, out) = import("px4-notulog2", &f.to_string_lossy(), &[]);
    assert_exit(&o, 2);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("byte 0") && stderr.contains("ULog header"),
        "{stderr}"
    );
    assert!(!out.exists());
}
