//! Flight speed along its axes: flight length (26 s, 600 s and
//! 3,600 s of an airborne hold (`benches/hold.toml`) and of the built-in
//! hover, which lands at 16 s, and the 26 s steps mission) and the timing
//! sweep (`rtpipe fly --sweep`: the issue's 37 flights, period scales and
//! chain delays, and today's default 53, rate sweep included) on 1 and 2
//! threads. Criterion reports simulated
//! milliseconds per CPU second as elements/s for the flights (1,000× real
//! time = 1 M elements/s; group `flight-cpu`, measured in the process's
//! CPU time, which the other processes of a shared machine do not
//! inflate) and flights per CPU second for the sweeps (all threads': on
//! an idle machine the 2-thread sweep's wall time is about half its CPU
//! time).
//!
//! `cargo bench -p rtpipe-fly --bench speed` (about eight minutes on a
//! shared 2-core machine, the 3,600 s flights a minute each).
//!
//! Before and after, side by side in one run: build the commit before in
//! its own tree and name its binary in `RTPIPE_BEFORE`; the bench then
//! also runs `rtpipe fly` of that binary and of this tree's
//! (`target/release/rtpipe`, build it first) on the same flights,
//! alternating, and prints the median wall time and the mean CPU time of
//! each:
//!
//! ```text
//! git worktree add /tmp/before <commit> && (cd /tmp/before && cargo build --release -p rtpipe)
//! cargo build --release -p rtpipe
//! RTPIPE_BEFORE=/tmp/before/target/release/rtpipe cargo bench -p rtpipe-fly --bench speed
//! ```

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rtpipe_fly::sweep::{default_variations, sweep, How, Variation};
use rtpipe_fly::{fly, setup, Request, Setup};
use rtpipe_model::Spec;
use rtpipe_sim::ExecModel;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicU64;
use std::time::{Duration, Instant};

fn cleanflight() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml")
}

fn setup_of(spec: &Spec, mission: &str, seconds: Option<i64>) -> Setup {
    let path = cleanflight();
    let r = Request {
        spec_path: &path,
        vehicle: "racer5",
        mission,
        horizon: seconds.map(|s| s * 1_000_000_000),
        seed: 1,
    };
    let mut s = setup(spec, &r).unwrap_or_else(|e| panic!("{e}"));
    // As `rtpipe fly` without --plot or --log: the quality streams.
    s.keep_trace = false;
    s
}

/// The airborne mission (take off, hold 1 m until the end): hold.toml.
const HOLD: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/hold.toml");

/// The flights of the length axis: (label, mission, seconds). The built-in
/// hover lands at 16 s: its long flights are mostly on the ground.
const FLIGHTS: [(&str, &str, Option<i64>); 7] = [
    ("steps-26s", "steps", None),
    ("hold-26s", HOLD, Some(26)),
    ("hold-600s", HOLD, Some(600)),
    ("hold-3600s", HOLD, Some(3600)),
    ("hover-26s", "hover", Some(26)),
    ("hover-600s", "hover", Some(600)),
    ("hover-3600s", "hover", Some(3600)),
];

/// CPU time of this process (`CLOCK_PROCESS_CPUTIME_ID`): on a shared
/// machine a single-threaded flight's wall time counts the other
/// processes' turns too, its CPU time only its own work.
struct CpuTime;

fn cpu_now() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec for the call to fill in.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_PROCESS_CPUTIME_ID)");
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

impl Measurement for CpuTime {
    type Intermediate = Duration;
    type Value = Duration;
    fn start(&self) -> Duration {
        cpu_now()
    }
    fn end(&self, i: Duration) -> Duration {
        cpu_now().saturating_sub(i)
    }
    fn add(&self, a: &Duration, b: &Duration) -> Duration {
        *a + *b
    }
    fn zero(&self) -> Duration {
        Duration::ZERO
    }
    fn to_f64(&self, v: &Duration) -> f64 {
        v.as_nanos() as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        static WALL: WallTime = WallTime;
        WALL.formatter()
    }
}

fn flights(c: &mut Criterion<CpuTime>) {
    let spec = Spec::load(&cleanflight()).unwrap_or_else(|e| panic!("{e}"));
    let mut group = c.benchmark_group("flight-cpu");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    for (label, mission, seconds) in FLIGHTS {
        let s = setup_of(&spec, mission, seconds);
        let t0 = Instant::now();
        let f = fly(&spec, &s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"));
        let wall = t0.elapsed().as_secs_f64();
        let flown = s.horizon as f64 * 1e-9;
        eprintln!(
            "{label}: {flown:.0} s flown, {} events, one run {wall:.3} s ({:.0}× real time)",
            f.sim.events,
            flown / wall
        );
        group.throughput(Throughput::Elements((s.horizon / 1_000_000) as u64));
        group.bench_function(BenchmarkId::from_parameter(label), |b| {
            b.iter(|| black_box(fly(black_box(&spec), black_box(&s), ExecModel::Uniform)))
        });
    }
    group.finish();
}

fn sweeps(c: &mut Criterion<CpuTime>) {
    let spec = Spec::load(&cleanflight()).unwrap_or_else(|e| panic!("{e}"));
    let s = setup_of(&spec, "steps", None);
    let all = default_variations(&spec, &s, 0.5, 8.0);
    // The issue's sweep: before the rate sweep existed.
    let issue: Vec<Variation> = all
        .iter()
        .copied()
        .filter(|v| !matches!(v, Variation::Rate(_)))
        .collect();
    assert_eq!((issue.len(), all.len()), (37, 53));
    let crit = s.criteria();
    let mut group = c.benchmark_group("sweep");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(6));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap_or_else(|e| panic!("{e}"));
        for vars in [&issue, &all] {
            let run = || {
                let done = AtomicU64::new(0);
                pool.install(|| {
                    sweep(
                        &spec,
                        &s,
                        &How::once(ExecModel::Uniform, &crit),
                        vars,
                        &done,
                        &|| false,
                    )
                    .unwrap_or_default()
                })
            };
            group.throughput(Throughput::Elements(vars.len() as u64));
            let id = format!("{}-flights-{threads}-threads", vars.len());
            group.bench_function(BenchmarkId::from_parameter(id), |b| {
                b.iter(|| black_box(run()))
            });
        }
    }
    group.finish();
}

/// CPU time of this process's waited-for children so far, s (utime +
/// stime, /proc/self/stat fields 16 and 17, in clock ticks of 10 ms).
fn children_cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name, which is in parentheses.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    // rest starts at field 3 (state): cutime is field 16, cstime 17.
    (f.get(13).copied().unwrap_or(0.0) + f.get(14).copied().unwrap_or(0.0)) / 100.0
}

/// One run of `bin fly SPEC args`: its wall time and CPU time, s.
fn run_cli(bin: &Path, args: &[&str]) -> (f64, f64) {
    let cpu0 = children_cpu();
    let t0 = Instant::now();
    let out = Command::new(bin)
        .arg("fly")
        .arg(cleanflight())
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", bin.display()));
    let wall = t0.elapsed().as_secs_f64();
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "{} fly {args:?}: {}",
        bin.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    (wall, children_cpu() - cpu0)
}

/// `RTPIPE_BEFORE` against this tree's binary, alternating, five runs each.
fn before_after(_: &mut Criterion) {
    let Some(before) = std::env::var_os("RTPIPE_BEFORE").map(PathBuf::from) else {
        eprintln!("RTPIPE_BEFORE not set: no before/after table (see the bench's docs)");
        return;
    };
    let after = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/release/rtpipe");
    let cases: [(&str, &[&str]); 8] = [
        ("steps, 26 s", &[]),
        ("hold, 26 s", &["--mission", HOLD, "--duration", "26s"]),
        ("hold, 600 s", &["--mission", HOLD, "--duration", "600s"]),
        ("hold, 3600 s", &["--mission", HOLD, "--duration", "3600s"]),
        ("hover, 26 s", &["--mission", "hover", "--duration", "26s"]),
        (
            "hover, 600 s",
            &["--mission", "hover", "--duration", "600s"],
        ),
        (
            "hover, 3600 s",
            &["--mission", "hover", "--duration", "3600s"],
        ),
        ("--sweep (53 flights)", &["--sweep"]),
    ];
    const RUNS: usize = 5;
    println!("\nrtpipe fly examples/cleanflight.toml ..., {RUNS} runs each, alternating");
    println!(
        "  (median wall s / mean CPU s; before: {})",
        before.display()
    );
    println!("{:<22} {:>18} {:>18}", "run", "before", "after");
    for (label, args) in cases {
        let mut t = [Vec::new(), Vec::new()];
        for _ in 0..RUNS {
            for (k, bin) in [&before, &after].into_iter().enumerate() {
                t[k].push(run_cli(bin, args));
            }
        }
        let cell = |v: &mut Vec<(f64, f64)>| {
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let cpu = v.iter().map(|x| x.1).sum::<f64>() / v.len() as f64;
            format!("{:.3} / {cpu:.3}", v[v.len() / 2].0)
        };
        let [b, a] = &mut t;
        println!("{label:<22} {:>18} {:>18}", cell(b), cell(a));
    }
}

criterion_group!(
    name = cpu;
    config = Criterion::default().with_measurement(CpuTime);
    targets = flights, sweeps
);
criterion_group!(wall, before_after);
criterion_main!(cpu, wall);
