//! `design` on many generated problems per size: status counts, median
//! time and peak memory, default build, paper and sound mode.
//!
//! `cargo bench -p rtpipe-design --bench sizes` (add `--features highs` to
//! let the MILP use HiGHS). Problems are those of the `solve` bench (WATERS
//! periods; 6, 20, 50 and 100 tasks on 1, 2, 4 and 8 CPUs; RM with exact
//! RTA; ranges around the generating design; limits at its sound bounds
//! times [0.8, 1.5]), seeds 2018.. (`RTPIPE_BENCH_SEEDS`, default 10 per
//! size), each solved once with `--method auto` and a 10 s time limit
//! (`RTPIPE_BENCH_LIMIT`); `RTPIPE_BENCH_SIZES=200` picks other sizes
//! (200 tasks: 8 CPUs, 10 chains); `-- --spec TASKS SEED` prints one
//! problem as a spec for `rtpipe design`. A second table solves Cleanflight
//! with `harmonic = true` on a 100 µs grid by the MILP (what harmonic
//! periods always used before) and by the box search. A third table runs
//! the box search on one thread beside every core (`RTPIPE_BENCH_THREADS`,
//! `RTPIPE_BENCH_THREAD_SEEDS`). Each solve runs in a child process so that its
//! peak resident memory (VmHWM) is its own. Prints a Markdown table.

use rtpipe_analysis::bounds_per_chain;
use rtpipe_analysis::Anchor;
use rtpipe_design::{design, Method, Mode, Options, Status};
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

/// The generated problem of `tasks` tasks and `seed`.
fn problem(tasks: usize, seed: u64) -> rtpipe_model::Spec {
    design_problem(seed, &config(tasks), &|s| {
        bounds_per_chain(s, |b| b.sound(Anchor::Read))
    })
}

/// Cleanflight with Table V's budgets, `harmonic = true` and a 100 µs grid
/// (the MILP did not finish it in 120 s).
fn cleanflight_harmonic() -> rtpipe_model::Spec {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/cleanflight-design.toml"
    );
    let text = std::fs::read_to_string(path).unwrap_or_default().replace(
        "schedulability = \"rta\"",
        "schedulability = \"rta\"\nharmonic = true\nresolution = \"100us\"",
    );
    match rtpipe_model::Spec::parse(path, &text) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

/// A problem by name: a number of tasks (generated with `seed`) or
/// `cleanflight-harmonic`.
fn problem_of(kind: &str, seed: u64) -> rtpipe_model::Spec {
    match kind {
        "cleanflight-harmonic" => cleanflight_harmonic(),
        n => problem(n.parse().unwrap_or(6), seed),
    }
}

fn method_named(name: &str) -> Method {
    match name {
        "boxes" => Method::Boxes,
        "milp" => Method::Milp,
        _ => Method::Auto,
    }
}

/// The child: one solve, one line "status seconds gap peak_kib method work
/// objective".
fn child(kind: &str, seed: u64, mode: Mode, limit: f64, method: Method) {
    let spec = problem_of(kind, seed);
    let opts = Options {
        mode,
        method,
        time_limit: Some(limit),
        ..Options::default()
    };
    let t0 = std::time::Instant::now();
    let (status, gap, method, work, u) = match design(&spec, &opts) {
        Ok(o) => (
            o.status.name(),
            o.gap.unwrap_or(f64::NAN),
            o.method.name(),
            o.iterations,
            o.objective.unwrap_or(f64::NAN),
        ),
        Err(_) => ("error", f64::NAN, "-", 0, f64::NAN),
    };
    let secs = t0.elapsed().as_secs_f64();
    // The work (boxes or master solves): the same on every machine.
    println!("{status} {secs} {gap} {} {method} {work} {u}", peak_kib());
}

struct Row {
    status: String,
    secs: f64,
    gap: f64,
    kib: u64,
    method: String,
    work: u64,
    objective: f64,
}

fn run_child(kind: &str, seed: u64, mode: Mode, limit: f64, method: Method) -> Option<Row> {
    run_child_on(None, kind, seed, mode, limit, method)
}

/// One solve in a child process, on `threads` threads (rayon's default,
/// every core, when `None`).
fn run_child_on(
    threads: Option<usize>,
    kind: &str,
    seed: u64,
    mode: Mode,
    limit: f64,
    method: Method,
) -> Option<Row> {
    let exe = std::env::current_exe().ok()?;
    let mut cmd = Command::new(exe);
    if let Some(n) = threads {
        cmd.env("RAYON_NUM_THREADS", n.to_string());
    }
    let out = cmd
        .args([
            "--one",
            kind,
            &seed.to_string(),
            mode.name(),
            &limit.to_string(),
            method.name(),
        ])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let f: Vec<&str> = text.split_whitespace().collect();
    (f.len() == 7).then(|| Row {
        status: f[0].to_string(),
        secs: f[1].parse().unwrap_or(f64::NAN),
        gap: f[2].parse().unwrap_or(f64::NAN),
        kib: f[3].parse().unwrap_or(0),
        method: f[4].to_string(),
        work: f[5].parse().unwrap_or(0),
        objective: f[6].parse().unwrap_or(f64::NAN),
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
            &args[i + 1],
            args[i + 2].parse().unwrap_or(FIRST_SEED),
            mode,
            args[i + 4].parse().unwrap_or(10.0),
            method_named(&args[i + 5]),
        );
        return;
    }
    if let Some(i) = args.iter().position(|a| a == "--spec") {
        // The problem of one size and seed as a spec, for `rtpipe design`.
        let tasks = args.get(i + 1).and_then(|v| v.parse().ok()).unwrap_or(6);
        let seed = args
            .get(i + 2)
            .and_then(|v| v.parse().ok())
            .unwrap_or(FIRST_SEED);
        print!("{}", rtpipe_model::to_toml(&problem(tasks, seed)));
        return;
    }
    if args.iter().any(|a| a == "--list") {
        return; // cargo bench -- --list
    }
    let seeds: u64 = env("RTPIPE_BENCH_SEEDS", 10);
    // `RTPIPE_BENCH_SIZES=200` (comma-separated) for other sizes.
    let sizes: Vec<usize> = std::env::var("RTPIPE_BENCH_SIZES")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| SIZES.to_vec());
    let limit: f64 = env("RTPIPE_BENCH_LIMIT", 10.0);
    if !sizes.is_empty() {
        println!("| tasks | mode | method | statuses | median s | max s | median gap of feasible | median peak MiB | max peak MiB |");
        println!("|---|---|---|---|---|---|---|---|---|");
    }
    for tasks in sizes {
        for mode in [Mode::Paper, Mode::Sound] {
            let rows: Vec<Row> = (FIRST_SEED..FIRST_SEED + seeds)
                .filter_map(|seed| {
                    let r = run_child(&tasks.to_string(), seed, mode, limit, Method::Auto);
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
    harmonic_table(limit);
    threads_table(limit);
}

/// The box search on one thread beside all cores, on the same problems:
/// wall time, and whether the two decided the same (status, boxes, U; a
/// search stopped by the time limit does more work on more cores, so
/// there the gap is what to compare). `RTPIPE_BENCH_THREADS=50,100` picks
/// the sizes (0 skips), `RTPIPE_BENCH_THREAD_SEEDS` the seeds per size.
fn threads_table(limit: f64) {
    let sizes: Vec<usize> = std::env::var("RTPIPE_BENCH_THREADS")
        .unwrap_or_else(|_| "20,50".to_string())
        .split(',')
        .filter_map(|x| x.trim().parse().ok())
        .filter(|&n| n > 0)
        .collect();
    if sizes.is_empty() {
        return;
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let seeds: u64 = env("RTPIPE_BENCH_THREAD_SEEDS", 10);
    println!();
    println!("| box search | mode | finished on both | same answer and boxes | 1 thread: median s | {cores} threads: median s | median speed-up | stopped at the limit | median boxes, {cores} threads / 1 | median gap, 1 / {cores} threads |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for tasks in sizes {
        for mode in [Mode::Paper, Mode::Sound] {
            let pairs: Vec<(Row, Row)> = (FIRST_SEED..FIRST_SEED + seeds)
                .filter_map(|seed| {
                    let kind = tasks.to_string();
                    let one = run_child_on(Some(1), &kind, seed, mode, limit, Method::Boxes)?;
                    let all = run_child_on(Some(cores), &kind, seed, mode, limit, Method::Boxes)?;
                    eprintln!(
                        "{tasks} tasks, {} mode, seed {seed}: {:.2} s / {:.2} s, boxes {} / {}",
                        mode.name(),
                        one.secs,
                        all.secs,
                        one.work,
                        all.work
                    );
                    Some((one, all))
                })
                .collect();
            println!("{}", threads_row(tasks, mode, &pairs));
        }
    }
}

/// One row of the threads table from (one thread, every core) pairs.
fn threads_row(tasks: usize, mode: Mode, pairs: &[(Row, Row)]) -> String {
    let done =
        |r: &Row| [Status::Optimal.name(), Status::Infeasible.name()].contains(&r.status.as_str());
    type Pairs<'p> = Vec<&'p (Row, Row)>;
    let (finished, stopped): (Pairs, Pairs) = pairs.iter().partition(|(a, b)| done(a) && done(b));
    let same = finished
        .iter()
        .filter(|(a, b)| {
            a.status == b.status
                && a.work == b.work
                && a.objective.to_bits() == b.objective.to_bits()
        })
        .count();
    let med = |v: Vec<f64>| {
        if v.is_empty() {
            "-".to_string()
        } else {
            format!("{:.2}", median(v))
        }
    };
    format!(
        "| {tasks} tasks | {} | {} | {same} | {} | {} | {}x | {} | {}x | {} % / {} % |",
        mode.name(),
        finished.len(),
        med(finished.iter().map(|p| p.0.secs).collect()),
        med(finished.iter().map(|p| p.1.secs).collect()),
        med(finished.iter().map(|p| p.0.secs / p.1.secs).collect()),
        stopped.len(),
        med(stopped
            .iter()
            .map(|p| p.1.work as f64 / p.0.work as f64)
            .collect()),
        med(stopped.iter().map(|p| 100.0 * p.0.gap).collect()),
        med(stopped.iter().map(|p| 100.0 * p.1.gap).collect()),
    )
}

/// Harmonic Cleanflight, the MILP (before: `harmonic = true` always used
/// it) beside the box search, each mode, one solve each
/// (`RTPIPE_BENCH_HARMONIC=0` skips it).
fn harmonic_table(limit: f64) {
    if env("RTPIPE_BENCH_HARMONIC", 1) == 0 {
        return;
    }
    println!();
    println!(
        "| cleanflight, harmonic, 100 us grid | mode | method | status | U | gap | s | peak MiB |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for mode in [Mode::Sound, Mode::Paper] {
        for method in [Method::Milp, Method::Boxes] {
            let Some(r) = run_child("cleanflight-harmonic", 0, mode, limit, method) else {
                println!(
                    "| | {} | {} | (no answer) | | | | |",
                    mode.name(),
                    method.name()
                );
                continue;
            };
            println!(
                "| | {} | {} | {} | {:.4} | {:.2} % | {:.2} | {:.1} |",
                mode.name(),
                r.method,
                r.status,
                r.objective,
                100.0 * r.gap,
                r.secs,
                r.kib as f64 / 1024.0
            );
        }
    }
}
