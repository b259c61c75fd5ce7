//! `rtpipe simulate` end to end: JSON shape, soundness on the examples, the
//! trace and SVG outputs, bad flags, determinism.

mod common;

use common::{assert_exit, example, json_of, rtpipe, scratch};
use serde_json::Value;
use std::path::Path;

fn files_in(dir: &Path) -> Vec<String> {
    match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect(),
        Err(e) => panic!("{e}"),
    }
}

fn read(p: &Path) -> String {
    match std::fs::read_to_string(p) {
        Ok(s) => s,
        Err(e) => panic!("cannot read {}: {e}", p.display()),
    }
}

#[test]
fn json_has_the_documented_shape() {
    let o = rtpipe(&[
        "simulate",
        &example("paper-table3.toml"),
        "--outputs",
        "50",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    // The analyze report is all there.
    assert_eq!(v["system"], "paper-table3");
    assert_eq!(v["time_unit"], "ms");
    assert!(v["schedulability"]["schedulable"].is_boolean());
    let chains = v["chains"].as_array().cloned().unwrap_or_default();
    assert_eq!(chains.len(), 4, "one entry per chain and metric");
    for c in &chains {
        for key in [
            "name",
            "path",
            "metric",
            "paper",
            "sound",
            "observed",
            "violations",
        ] {
            assert!(c.get(key).is_some(), "chain key {key}: {c}");
        }
        let ob = &c["observed"];
        let count = ob["count"].as_u64().unwrap_or(0);
        assert!(count > 0, "{ob}");
        let (min, mean, p99, max) = (
            ob["min"].as_f64().unwrap_or(f64::NAN),
            ob["mean"].as_f64().unwrap_or(f64::NAN),
            ob["p99"].as_f64().unwrap_or(f64::NAN),
            ob["max"].as_f64().unwrap_or(f64::NAN),
        );
        assert!(
            min <= mean && mean <= max && min <= p99 && p99 <= max,
            "{ob}"
        );
        assert!(c["violations"]["paper"].is_u64());
        assert_eq!(c["violations"]["sound"], 0);
    }
    let s = &v["simulation"];
    // 50 × the slowest tail (150 ms) + the largest period (150 ms).
    assert_eq!(s["horizon"], 7650.0);
    assert_eq!(s["seed"], 0);
    assert_eq!(s["exec"], "worst");
    assert_eq!(s["phasing"], "sync");
    assert_eq!(s["offsets"]["p1"], 0.0);
    assert!(s["events"].as_u64().unwrap_or(0) > 0);
    assert!(s["seconds"].as_f64().is_some());
    let tasks = v["tasks"].as_array().cloned().unwrap_or_default();
    assert_eq!(tasks.len(), 7);
    for t in &tasks {
        let ob = &t["observed"];
        for key in [
            "released",
            "completed",
            "max_response",
            "late",
            "exhaustions",
            "utilization",
        ] {
            assert!(ob.get(key).is_some(), "task key {key}: {ob}");
        }
        let u = ob["utilization"].as_f64().unwrap_or(-1.0);
        assert!((0.0..=1.0).contains(&u), "{ob}");
    }
    // Every tail completed at least 50 jobs.
    for tail in [4, 6] {
        assert!(tasks[tail]["observed"]["completed"].as_u64().unwrap_or(0) >= 50);
    }
}

#[test]
fn no_sound_violations_on_the_examples() {
    for name in ["paper-table2.toml", "paper-table3.toml", "cleanflight.toml"] {
        for extra in [
            &["--exec", "worst"][..],
            &["--exec", "uniform", "--phasing", "random", "--seed", "5"][..],
        ] {
            let mut args = vec!["simulate", "--outputs", "300", "--json"];
            let spec = example(name);
            args.push(&spec);
            args.extend_from_slice(extra);
            let o = rtpipe(&args);
            assert_eq!(
                o.status.code(),
                Some(0),
                "{name} {extra:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let v = json_of(&o);
            for c in v["chains"].as_array().cloned().unwrap_or_default() {
                assert_eq!(c["violations"]["sound"], 0, "{name}: {c}");
                if let (Some(max), Some(sound)) =
                    (c["observed"]["max"].as_f64(), c["sound"].as_f64())
                {
                    assert!(max <= sound, "{name}: {c}");
                }
            }
        }
    }
}

#[test]
fn table_output_for_people() {
    let o = rtpipe(&["simulate", &example("paper-table3.toml"), "--outputs", "20"]);
    assert_eq!(o.status.code(), Some(0));
    let text = String::from_utf8_lossy(&o.stdout);
    for want in [
        "system paper-table3",
        "max/sound",
        ">sound",
        "P1 ",
        "freshness",
        "busy/horizon",
        "events simulated in",
        "verdict: no sample above a sound bound",
    ] {
        assert!(text.contains(want), "missing {want:?} in\n{text}");
    }
}

#[test]
fn trace_parses_with_slices_on_every_task_track() {
    let dir = scratch("sim-trace");
    let f = dir.join("run.json");
    let o = rtpipe(&[
        "simulate",
        &example("paper-table3.toml"),
        "--duration",
        "1s",
        "--trace",
        &f.to_string_lossy(),
    ]);
    assert_exit(&o, 0);
    let v: Value = match serde_json::from_str(&read(&f)) {
        Ok(v) => v,
        Err(e) => panic!("trace is not JSON: {e}"),
    };
    let ev = v["traceEvents"].as_array().cloned().unwrap_or_default();
    assert!(!ev.is_empty());
    for e in &ev {
        let ph = e["ph"].as_str().unwrap_or("");
        assert!(["M", "X", "i", "s", "f"].contains(&ph), "{e}");
        assert!(
            e["pid"].is_u64() && e["tid"].is_u64() && e["name"].is_string(),
            "{e}"
        );
        if ph != "M" {
            assert!(e["ts"].as_f64().is_some_and(|t| t >= 0.0), "{e}");
        }
        if ph == "X" {
            assert!(e["dur"].as_f64().is_some_and(|d| d > 0.0), "{e}");
        }
        if ph == "s" || ph == "f" {
            assert!(e["id"].is_u64(), "{e}");
        }
    }
    // Task tracks named by metadata, each with slices named by the task.
    let tasks = ["p1", "p2", "p3", "p4", "p5", "p6", "p7"];
    for t in tasks {
        let track = ev
            .iter()
            .find(|e| e["ph"] == "M" && e["name"] == "thread_name" && e["args"]["name"] == t);
        let Some(track) = track else {
            panic!("no track for {t}")
        };
        let tid = &track["tid"];
        let slices = ev
            .iter()
            .filter(|e| e["ph"] == "X" && &e["tid"] == tid && e["name"] == t)
            .count();
        assert!(slices > 0, "no slices on {t}");
        let stages = ev
            .iter()
            .filter(|e| e["ph"] == "X" && &e["tid"] == tid && e["cat"] == "stage")
            .count();
        assert!(stages >= 3 * slices.min(1), "no read/process/write on {t}");
    }
    // Flow starts and ends pair up by id.
    let ids = |ph: &str| {
        let mut v: Vec<u64> = ev
            .iter()
            .filter(|e| e["ph"] == ph)
            .filter_map(|e| e["id"].as_u64())
            .collect();
        v.sort_unstable();
        v
    };
    assert!(!ids("s").is_empty());
    assert_eq!(ids("s"), ids("f"));
    assert_eq!(
        files_in(&dir),
        vec!["run.json".to_string()],
        "no temp files left"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plot_and_gantt_are_svg_naming_the_chains() {
    let dir = scratch("sim-svg");
    let (plot, gantt) = (dir.join("fig9.svg"), dir.join("gantt.svg"));
    let o = rtpipe(&[
        "simulate",
        &example("paper-table3.toml"),
        "--outputs",
        "100",
        "--plot",
        &plot.to_string_lossy(),
        "--gantt",
        &gantt.to_string_lossy(),
        "--window",
        "0,300ms",
    ]);
    assert_exit(&o, 0);
    let p = read(&plot);
    assert!(
        p.starts_with("<svg") || p.starts_with("<?xml"),
        "{}",
        &p[..p.len().min(80)]
    );
    assert!(p.trim_end().ends_with("</svg>"));
    for want in [
        "P1",
        "P2",
        "p1&gt;p2&gt;p3&gt;p4&gt;p5",
        "reaction",
        "freshness",
        "sound",
    ] {
        assert!(p.contains(want), "plot lacks {want}");
    }
    let g = read(&gantt);
    assert!(g.starts_with("<svg") || g.starts_with("<?xml"));
    for want in ["p1", "p7", "cpu 0", "time (ms)"] {
        assert!(g.contains(want), "gantt lacks {want}");
    }
    let mut names = files_in(&dir);
    names.sort();
    assert_eq!(names, vec!["fig9.svg".to_string(), "gantt.svg".to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_flags_exit_2_and_write_nothing() {
    let dir = scratch("sim-bad");
    let out = dir.join("out.svg").to_string_lossy().into_owned();
    let trace = dir.join("t.json").to_string_lossy().into_owned();
    let spec = example("paper-table3.toml");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--outputs", "0"], "--outputs"),
        (vec!["--outputs", "-5"], "--outputs"),
        (vec!["--duration", "0"], "--duration"),
        (vec!["--duration", "-2s"], "--duration"),
        (vec!["--duration", "2 parsecs"], "--duration"),
        (vec!["--duration", "1s", "--outputs", "10"], "--outputs"),
        (vec!["--exec", "fastest"], "--exec"),
        (vec!["--phasing", "sideways"], "--phasing"),
        (vec!["--window", "0,10"], "--gantt"),
        (vec!["--gantt", &out, "--window", "10,5"], "--window"),
        (vec!["--gantt", &out, "--window", "nope"], "--window"),
        (
            vec!["--gantt", &out, "--duration", "1s", "--window", "0,2s"],
            "--window",
        ),
        (
            vec!["--plot", "/nonexistent-dir/x.svg", "--trace", &trace],
            "--plot",
        ),
        (vec!["--plot", &out, "--gantt", &out], "--gantt"),
    ];
    for (flags, named) in cases {
        let mut args = vec!["simulate", spec.as_str()];
        args.extend_from_slice(&flags);
        let o = rtpipe(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {err}");
        assert!(err.contains(named), "{flags:?} should name {named}: {err}");
        assert!(o.stdout.is_empty(), "{flags:?}: nothing on stdout");
        assert!(
            files_in(&dir).is_empty(),
            "{flags:?} left {:?}",
            files_in(&dir)
        );
    }
    // A missing spec, with outputs asked for.
    let o = rtpipe(&["simulate", "/nonexistent/spec.toml", "--plot", &out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot read the spec"));
    assert!(files_in(&dir).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The JSON without its wall-clock field.
fn stable(mut v: Value) -> Value {
    if let Some(s) = v.get_mut("simulation").and_then(Value::as_object_mut) {
        s.remove("seconds");
    }
    v
}

#[test]
fn same_seed_same_json() {
    let spec = example("paper-table2.toml");
    let run = |seed: &str| {
        let o = rtpipe(&[
            "simulate",
            &spec,
            "--outputs",
            "200",
            "--json",
            "--phasing",
            "random",
            "--exec",
            "uniform",
            "--seed",
            seed,
        ]);
        stable(json_of(&o))
    };
    let a = run("42");
    assert_eq!(a, run("42"));
    let b = run("43");
    assert_ne!(a["simulation"]["offsets"], b["simulation"]["offsets"]);
}

/// Runs `rtpipe ARGS` and samples its peak resident memory (VmHWM, kB)
/// from /proc while it runs: its stdout and the last peak seen.
fn peak_kb(args: &[&str]) -> (String, u64) {
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn();
    let Ok(mut child) = child else {
        panic!("cannot start rtpipe");
    };
    let status = format!("/proc/{}/status", child.id());
    let mut stdout = child.stdout.take();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(o) = stdout.as_mut() {
            let _ = std::io::Read::read_to_string(o, &mut s);
        }
        s
    });
    let mut peak = 0;
    while matches!(child.try_wait(), Ok(None)) {
        let text = std::fs::read_to_string(&status).unwrap_or_default();
        let hwm = text
            .lines()
            .find_map(|l| l.strip_prefix("VmHWM:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok());
        peak = peak.max(hwm.unwrap_or(0));
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    (reader.join().unwrap_or_default(), peak)
}

#[test]
fn memory_does_not_grow_with_the_simulated_span() {
    // 20000 s of cleanflight peaked at 1.46 GB (73 KB per
    // simulated second); 5020 s (100x the default horizon) at 371 MB.
    let spec = example("cleanflight.toml");
    let (out, kb) = peak_kb(&["simulate", &spec, "--duration", "5020s"]);
    assert!(out.contains("simulated 5020000000 us"), "{out}");
    assert!(kb < 64 * 1024, "peak {kb} kB");
    // Many distinct latencies: the histograms turn coarse, said with a ~.
    let (out, kb) = peak_kb(&[
        "simulate",
        &spec,
        "--exec",
        "uniform",
        "--duration",
        "1000s",
    ]);
    assert!(out.contains("~ p99 within 0.78 %"), "{out}");
    assert!(kb < 64 * 1024, "peak {kb} kB");
    // The per-sample record too, when asked for: written as it goes
    // (5020 s: 10.5 M rows, 780 MB of CSV), not held.
    let dir = scratch("samples-stream");
    let csv = dir.join("s.csv");
    let (out, kb) = peak_kb(&[
        "simulate",
        &spec,
        "--duration",
        "5020s",
        "--samples",
        &csv.to_string_lossy(),
    ]);
    assert!(out.contains("simulated 5020000000 us"), "{out}");
    assert!(kb < 64 * 1024, "peak {kb} kB with --samples");
    let rows = std::fs::read(&csv).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count());
    assert!(rows > 10_000_000, "{rows} rows");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_event_triggered_spec_is_observed_against_its_bounds() {
    let o = rtpipe(&[
        "simulate",
        &example("work-queues.toml"),
        "--outputs",
        "50",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let tasks = v["tasks"].as_array().cloned().unwrap_or_default();
    let task = |name: &str| {
        tasks
            .iter()
            .find(|t| t["name"] == name)
            .cloned()
            .unwrap_or_else(|| panic!("no task {name}"))
    };
    // Every task of the example is in a thread: each reports its merges,
    // and its analysed response time bounds the largest seen.
    let av = task("angular_velocity");
    assert_eq!(av["activation"]["thread"], "rate_ctrl");
    assert_eq!(av["observed"]["merged"], 0);
    assert!(task("imu")["observed"]["released"]
        .as_u64()
        .is_some_and(|n| n >= 50));
    for t in &tasks {
        let (seen, bound) = (
            t["observed"]["max_response"].as_f64(),
            t["job_response_time"].as_f64(),
        );
        assert!(matches!((seen, bound), (Some(s), Some(b)) if s <= b), "{t}");
    }
    let chains = v["chains"].as_array().cloned().unwrap_or_default();
    assert_eq!(chains.len(), 4, "two chains, reaction and freshness");
    for c in &chains {
        let (max, sound) = (c["observed"]["max"].as_f64(), c["sound"].as_f64());
        assert!(
            matches!((max, sound), (Some(m), Some(b)) if 0.0 < m && m <= b),
            "{c}"
        );
        assert_eq!(c["violations"]["sound"], 0, "{c}");
    }
}

#[test]
fn an_event_triggered_gantt_has_a_row_per_thread_and_samples_are_written() {
    let dir = scratch("sim-wq-gantt");
    let (gantt, samples) = (dir.join("gantt.svg"), dir.join("samples.csv"));
    let o = rtpipe(&[
        "simulate",
        &example("work-queues.toml"),
        "--duration",
        "3ms",
        "--gantt",
        &gantt.to_string_lossy(),
        "--window",
        "0,150",
        "--samples",
        &samples.to_string_lossy(),
    ]);
    assert_exit(&o, 0);
    // The samples' provenance through the triggered items: the rate loop's
    // first sample, read by imu at 60 µs, reaches the allocator at 132.
    let csv = read(&samples);
    assert!(
        csv.lines()
            .any(|l| l.starts_with("rate loop,0,60000,,132000,")),
        "{csv}"
    );
    let g = read(&gantt);
    // The rate thread's row, and its jobs labelled with their tasks.
    for want in [
        "thread spi1",
        "thread rate_ctrl",
        "land_detector",
        "rate_control",
    ] {
        assert!(g.contains(want), "gantt lacks {want}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_event_triggered_spec_plots_its_observations_against_the_bounds() {
    let dir = scratch("sim-wq-plot");
    let plot = dir.join("fig9.svg");
    let o = rtpipe(&[
        "simulate",
        &example("work-queues.toml"),
        "--duration",
        "100ms",
        "--plot",
        &plot.to_string_lossy(),
    ]);
    assert_exit(&o, 0);
    let svg = std::fs::read_to_string(&plot).unwrap_or_default();
    assert!(
        svg.starts_with("<svg") && svg.contains("rate loop"),
        "{svg:.200}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
