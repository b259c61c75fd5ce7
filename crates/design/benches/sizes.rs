//! `design` on many generated problems per size: status counts, median
//! time and peak memory, default build, paper and sound mode.
//!
//! `cargo bench -p rtpipe-design --bench sizes` (add `--features highs` to
//! let the MILP use HiGHS). Problems are those of the `solve` bench (WATERS
//! periods; 6, 20, 50 and 100 tasks on 1, 2, 4 and 8 CPUs; RM with exact
//! RTA; ranges around the generating design; limits at its sound bounds
//! times [0.8, 1.5]), seeds 2018.. (`RTPIPE_BENCH_SEEDS`, default 10 per
//! size), each solved once with `--method auto` and a 10 s time limit
//! (`RTPIPE_BENCH_LIMIT`). Each solve runs in a child process so that its
//! peak resident memory (VmHWM) is its own. Prints a Markdown table.

use rtpipe_analysis::bounds_per_chain;
use rtpipe_analysis::Anchor;
use rtpipe_design::{design, Mode, Options, Status};
use rtpipe_model::gen::{benchmark_config, design_problem, DesignGenConfig};
use std::collections::BTreeMap;
use std::process::Command;

const SIZES: [usize; 4] = [6, 20, 50, 100];
const FIRST_SEED: u64 = 2018;

fn config(tasks: usize) -> DesignGenConfig {
    benchmark_config(tasks)
}

fn env<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Peak resident memory of this process, in KiB (Linux).
fn peak_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// The child: one solve, one line "status seconds gap peak_kib method".
fn child(tasks: usize, seed: u64, mode: Mode, limit: f64) {
    let cfg = config(tasks);
    let spec = design_problem(seed, &cfg, &|s| {
        bounds_per_chain(s, |b| b.sound(Anchor::Read))
    });
    let opts = Options {
        mode,
        time_limit: Some(limit),
        ..Options::default()
    };
    let t0 = std::time::Instant::now();
    let (status, gap, method, work) = match design(&spec, &opts) {
        Ok(o) => (
            o.status.name(),
            o.gap.unwrap_or(f64::NAN),
            o.method.name(),
            o.iterations,
        ),
        Err(_) => ("error", f64::NAN, "-", 0),
    };
    let secs = t0.elapsed().as_secs_f64();
    // The work (boxes or master solves) last: the same on every machine.
    println!("{status} {secs} {gap} {} {method} {work}", peak_kib());
}

struct Row {
    status: String,
    secs: f64,
    gap: f64,
    kib: u64,
    method: String,
}

fn run_child(tasks: usize, seed: u64, mode: Mode, limit: f64) -> Option<Row> {
    let exe = std::env::current_exe().ok()?;
    let out = Command::new(exe)
        .args([
            "--one",
            &tasks.to_string(),
            &seed.to_string(),
            mode.name(),
            &limit.to_string(),
        ])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let f: Vec<&str> = text.split_whitespace().collect();
    (f.len() == 6).then(|| Row {
        status: f[0].to_string(),
        secs: f[1].parse().unwrap_or(f64::NAN),
        gap: f[2].parse().unwrap_or(f64::NAN),
        kib: f[3].parse().unwrap_or(0),
        method: f[4].to_string(),
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--one") {
        let mode = if args[i + 3] == "paper" {
            Mode::Paper
        } else {
            Mode::Sound
        };
        child(
            args[i + 1].parse().unwrap_or(6),
            args[i + 2].parse().unwrap_or(FIRST_SEED),
            mode,
            args[i + 4].parse().unwrap_or(10.0),
        );
        return;
    }
    if args.iter().any(|a| a == "--list") {
        return; // cargo bench -- --list
    }
    let seeds: u64 = env("RTPIPE_BENCH_SEEDS", 10);
    let limit: f64 = env("RTPIPE_BENCH_LIMIT", 10.0);
    println!("| tasks | mode | method | statuses | median s | max s | median gap of feasible | median peak MiB | max peak MiB |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for tasks in SIZES {
        for mode in [Mode::Paper, Mode::Sound] {
            let rows: Vec<Row> = (FIRST_SEED..FIRST_SEED + seeds)
                .filter_map(|seed| {
                    let r = run_child(tasks, seed, mode, limit);
                    if let Some(r) = &r {
                        eprintln!("{tasks} tasks, {} mode, seed {seed}: {} in {:.2} s, gap {:.4}, peak {} KiB", mode.name(), r.status, r.secs, r.gap, r.kib);
                    }
                    r
                })
                .collect();
            let mut statuses: BTreeMap<&str, usize> = BTreeMap::new();
            rows.iter()
                .for_each(|r| *statuses.entry(&r.status).or_default() += 1);
            let statuses: Vec<String> = statuses.iter().map(|(s, n)| format!("{n} {s}")).collect();
            let feasible_gaps: Vec<f64> = rows
                .iter()
                .filter(|r| r.status == Status::Feasible.name())
                .map(|r| 100.0 * r.gap)
                .collect();
            let mib = |k: u64| k as f64 / 1024.0;
            let methods: std::collections::BTreeSet<&str> =
                rows.iter().map(|r| r.method.as_str()).collect();
            println!(
                "| {tasks} | {} | {} | {} | {:.2} | {:.2} | {} | {:.1} | {:.1} |",
                mode.name(),
                methods.into_iter().collect::<Vec<_>>().join(", "),
                statuses.join(", "),
                median(rows.iter().map(|r| r.secs).collect()),
                rows.iter().map(|r| r.secs).fold(0.0, f64::max),
                if feasible_gaps.is_empty() {
                    "-".to_string()
                } else {
                    format!("{:.2} %", median(feasible_gaps))
                },
                median(rows.iter().map(|r| mib(r.kib)).collect()),
                rows.iter().map(|r| mib(r.kib)).fold(0.0, f64::max),
            );
        }
    }
}
