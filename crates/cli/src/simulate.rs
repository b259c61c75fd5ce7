//! `rtpipe simulate`: run the discrete-event simulator on a spec and hold the
//! observed reaction and freshness times against the analysis' bounds.

use crate::analyze;
use crate::output;
use crate::plot;
use crate::table::Table;
use crate::EXIT_BAD_INPUT;
use clap::{Args, ValueEnum};
use rtpipe_analysis::{Anchor, Metric, Report};
use rtpipe_model::time::number_to_nanos;
use rtpipe_model::{parse_time_str, Nanos, Spec, TimeUnit, MAX_TIME};
use rtpipe_sim::observe::{horizon_for_outputs, observe, response_violations, ChainObs, Judged};
use rtpipe_sim::search::{search, SearchConfig, SearchResult};
use rtpipe_sim::trace::{chrome_trace_with, TraceOptions};
use rtpipe_sim::{simulate_with_progress, ExecModel, Phasing, SimConfig, SimError, SimResult};
use serde_json::{json, Value};
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Tail outputs simulated when neither `--outputs` nor `--duration` is given.
pub const DEFAULT_OUTPUTS: u64 = 10_000;

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// The system spec (TOML), e.g. examples/paper-table3.toml.
    pub spec: PathBuf,
    /// Simulate until every chain's tail has published at least N outputs
    /// [default: 10000].
    #[arg(
        long,
        value_name = "N",
        value_parser = parse_outputs,
        conflicts_with = "duration",
        allow_hyphen_values = true
    )]
    pub outputs: Option<u64>,
    /// Simulated time instead of --outputs: "2s", "500ms", or a number in the
    /// spec's time unit.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub duration: Option<String>,
    /// Seeds the random offsets and demands (the same seed gives the same run).
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// How each job's demand Δin + p + Δout is drawn: p = exec (worst),
    /// exec_min (best), uniform in between, or one of the two at random
    /// (extremes).
    #[arg(long, value_enum, default_value_t = ExecArg::Worst)]
    pub exec: ExecArg,
    /// Release offsets: all at 0 (sync), uniform in [0, T) per task (random),
    /// or random plus an adversarial search for each chain's worst case
    /// (search), reported beside the bounds as a tightness ratio.
    #[arg(long, value_enum, default_value_t = PhasingArg::Sync)]
    pub phasing: PhasingArg,
    /// With --phasing search: candidates tried per local search (4 restarts).
    #[arg(long, value_name = "N", default_value_t = 50)]
    pub search_steps: u32,
    /// Print one JSON object (the `analyze --json` report plus observations)
    /// instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Write a Chrome trace-event file for the Perfetto UI
    /// (https://ui.perfetto.dev): one track per task, grouped by CPU.
    #[arg(long, value_name = "FILE.json")]
    pub trace: Option<PathBuf>,
    /// Write the observed-vs-predicted chart (the paper's Fig. 9) as SVG.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Write a Gantt chart of the schedule as SVG (see --window).
    #[arg(long, value_name = "FILE.svg")]
    pub gantt: Option<PathBuf>,
    /// The span of --gantt, START,END in the spec's time unit or with units
    /// ("0,30ms") [default: the first 3 × the largest period].
    #[arg(long, value_name = "START,END", allow_hyphen_values = true)]
    pub window: Option<String>,
    /// --seed was given on the command line (set by main).
    #[arg(skip)]
    pub seed_given: bool,
    /// --search-steps was given on the command line (set by main).
    #[arg(skip)]
    pub search_steps_given: bool,
}

/// `--exec`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExecArg {
    Worst,
    Uniform,
    Best,
    Extremes,
}

impl ExecArg {
    pub(crate) fn model(self) -> ExecModel {
        match self {
            ExecArg::Worst => ExecModel::Worst,
            ExecArg::Uniform => ExecModel::Uniform,
            ExecArg::Best => ExecModel::Best,
            ExecArg::Extremes => ExecModel::Extremes,
        }
    }
}

/// `--phasing`. Each variant maps to one way of running the simulator in
/// [`run_simulation`]; add a variant there to add a phasing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PhasingArg {
    Sync,
    Random,
    /// Random phasing for the observations, plus an adversarial search
    /// (restarts and local search over offsets and execution times) for the
    /// worst latency of every chain and metric.
    Search,
}

/// The command-line name of a value of a [`ValueEnum`].
fn flag_name<E: ValueEnum>(e: &E) -> String {
    e.to_possible_value()
        .map(|v| v.get_name().to_string())
        .unwrap_or_default()
}

fn parse_outputs(s: &str) -> Result<u64, String> {
    match s.trim().parse::<u64>() {
        Ok(0) => Err("must be at least 1 (outputs of every chain's tail)".into()),
        Ok(n) => Ok(n),
        Err(_) => {
            Err("must be a positive whole number of tail outputs, e.g. --outputs 1000".into())
        }
    }
}

/// A bad flag or value: what is wrong and how to fix it (exit status 2).
#[derive(Debug)]
pub struct Bad {
    msg: String,
    help: String,
}

impl Bad {
    pub(crate) fn new(msg: impl Into<String>, help: impl Into<String>) -> Bad {
        Bad {
            msg: msg.into(),
            help: help.into(),
        }
    }
}

impl From<output::OutputError> for Bad {
    fn from(e: output::OutputError) -> Bad {
        Bad::new(e.msg, e.help)
    }
}

impl fmt::Display for Bad {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "error: {}", self.msg)?;
        if !self.help.is_empty() {
            writeln!(f, "  = help: {}", self.help)?;
        }
        Ok(())
    }
}

pub(crate) fn fail(b: Bad) -> ExitCode {
    eprint!("{b}");
    ExitCode::from(EXIT_BAD_INPUT)
}

/// A time from the command line: a bare number in the spec's unit or a
/// string with a unit.
pub(crate) fn parse_time(spec: &Spec, s: &str) -> Result<Nanos, String> {
    let t = s.trim();
    let r = match t.parse::<f64>() {
        Ok(x) => number_to_nanos(x, spec.time_unit),
        Err(_) => parse_time_str(t),
    };
    r.map_err(|e| e.to_string())
}

/// What to simulate, checked before anything runs.
#[derive(Debug)]
struct Plan {
    horizon: Nanos,
    /// Tail outputs asked for (`--outputs` or the default).
    outputs: Option<u64>,
    window: (Nanos, Nanos),
    log_jobs: bool,
}

fn plan(spec: &Spec, a: &SimulateArgs) -> Result<Plan, Bad> {
    let t_max = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .max()
        .unwrap_or(0);
    if t_max <= 0 {
        return Err(Bad::new(
            "no task has a fixed period, so nothing is ever released",
            "give the tasks a `period = ...`",
        ));
    }
    let (horizon, outputs) = match (&a.duration, a.outputs) {
        (Some(d), None) => {
            let h = parse_time(spec, d).map_err(|e| {
                Bad::new(
                    format!("invalid value `{d}` for --duration: {e}"),
                    format!(
                        "write a positive time like --duration 2s or --duration 500ms, or a bare number in {}",
                        spec.time_unit
                    ),
                )
            })?;
            if h <= 0 {
                return Err(Bad::new(
                    format!("--duration must be positive, found `{d}`"),
                    "write a positive time like --duration 2s",
                ));
            }
            (h, None)
        }
        (None, o) => {
            let n = o.unwrap_or(DEFAULT_OUTPUTS);
            match horizon_for_outputs(spec, n) {
                Some(h) => (h, Some(n)),
                None => {
                    return Err(Bad::new(
                        format!(
                            "--outputs {n} needs more than {} of simulated time (the longest the model allows)",
                            spec.fmt_time(MAX_TIME)
                        ),
                        "ask for fewer outputs, e.g. --outputs 10000",
                    ))
                }
            }
        }
        (Some(_), Some(_)) => {
            return Err(Bad::new(
                "--outputs and --duration both set the simulated span",
                "give only one of them",
            ))
        }
    };
    if a.search_steps_given && a.phasing != PhasingArg::Search {
        return Err(Bad::new(
            "--search-steps sets the adversarial search, but --phasing is not search",
            "add --phasing search, or drop --search-steps",
        ));
    }
    if a.seed_given
        && a.phasing == PhasingArg::Sync
        && matches!(a.exec, ExecArg::Worst | ExecArg::Best)
    {
        return Err(Bad::new(
            format!(
                "--seed has no effect: nothing is random with --phasing sync and --exec {}",
                flag_name(&a.exec)
            ),
            "add --phasing random (or --exec uniform), or drop --seed",
        ));
    }
    let window = match &a.window {
        None => (0, (3 * t_max).min(horizon)),
        Some(w) => {
            if a.gantt.is_none() {
                return Err(Bad::new(
                    "--window sets the span of the Gantt chart, but no --gantt was given",
                    "add --gantt FILE.svg, or drop --window",
                ));
            }
            let help = format!(
                "write --window START,END with times in {} or with units, e.g. --window 0,{}",
                spec.time_unit,
                spec.fmt_time((3 * t_max).min(horizon))
            );
            let Some((s, e)) = w.split_once(',') else {
                return Err(Bad::new(
                    format!("invalid value `{w}` for --window: expected START,END"),
                    help,
                ));
            };
            let (s, e) = match (parse_time(spec, s), parse_time(spec, e)) {
                (Ok(s), Ok(e)) => (s, e),
                (Err(m), _) | (_, Err(m)) => {
                    return Err(Bad::new(
                        format!("invalid value `{w}` for --window: {m}"),
                        help,
                    ))
                }
            };
            if s < 0 || e <= s {
                return Err(Bad::new(
                    format!("invalid value `{w}` for --window: need 0 <= START < END"),
                    help,
                ));
            }
            if e > horizon {
                return Err(Bad::new(
                    format!(
                        "--window ends at {} {u}, after the simulated span of {} {u}",
                        spec.fmt_time(e),
                        spec.fmt_time(horizon),
                        u = spec.time_unit
                    ),
                    "lengthen --duration (or --outputs), or pick an earlier END",
                ));
            }
            (s, e)
        }
    };
    let mut outs = Vec::new();
    for (flag, p) in [
        ("--trace", &a.trace),
        ("--plot", &a.plot),
        ("--gantt", &a.gantt),
    ] {
        let Some(p) = p else { continue };
        outs.push(output::prepare(flag, p, &a.spec, None).map_err(Bad::from)?);
    }
    output::distinct(&outs).map_err(Bad::from)?;
    Ok(Plan {
        horizon,
        outputs,
        window,
        log_jobs: a.trace.is_some() || a.gantt.is_some(),
    })
}

/// Runs the simulator as `--phasing` asks, reporting the simulated time
/// reached to `progress`. One simulation per run today; a phasing that
/// searches offsets would run several here and return the worst.
fn run_simulation(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    progress: &mut dyn FnMut(Nanos),
) -> Result<SimResult, SimError> {
    let phasing = match a.phasing {
        PhasingArg::Sync => Phasing::Sync,
        PhasingArg::Random | PhasingArg::Search => Phasing::Random,
    };
    let cfg = SimConfig {
        horizon: p.horizon,
        seed: a.seed,
        phasing,
        exec: a.exec.model(),
        log_jobs: p.log_jobs,
    };
    simulate_with_progress(spec, &cfg, progress)
}

/// Runs `f` with a progress bar over the simulated horizon (fraction done,
/// elapsed time and ETA) on stderr, hidden when stderr is not a terminal.
/// `f` reports the simulated time it has reached.
fn with_horizon_bar<T>(
    msg: String,
    horizon: Nanos,
    f: impl FnOnce(&mut dyn FnMut(Nanos)) -> T,
) -> T {
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(horizon.max(1) as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg} [{bar:30}] {percent:>3}% [{elapsed_precise}, ETA {eta_precise}]",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(msg);
    pb.enable_steady_tick(std::time::Duration::from_millis(100));
    let out = f(&mut |t| pb.set_position(t.max(0) as u64));
    pb.finish_and_clear();
    out
}

/// Runs `f` with a spinner and the elapsed time on stderr (hidden when stderr
/// is not a terminal).
pub(crate) fn with_spinner<T>(msg: String, f: impl FnOnce() -> T) -> T {
    let pb = crate::spinner(msg);
    let out = f();
    pb.finish_and_clear();
    out
}

/// The files to write, rendered in memory first.
struct Outputs {
    files: Vec<(&'static str, PathBuf, String)>,
    notes: Vec<String>,
}

fn render_outputs(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    res: &SimResult,
    obs: &[ChainObs],
) -> Result<Outputs, Bad> {
    let mut out = Outputs {
        files: Vec::new(),
        notes: Vec::new(),
    };
    if let Some(path) = &a.trace {
        let t = chrome_trace_with(spec, res, TraceOptions::default());
        out.notes.push(format!(
            "wrote {}: {} CPU slices, {} data-flow arrows; open it in https://ui.perfetto.dev",
            path.display(),
            t.slices,
            t.flows
        ));
        if let Some(cut) = t.truncated_at {
            out.notes.push(format!(
                "note: the trace stops at {} {u} of {} {u} to stay small; a shorter --duration traces a whole run",
                spec.fmt_time(cut),
                spec.fmt_time(res.horizon),
                u = spec.time_unit
            ));
        }
        if t.flows_dropped > 0 {
            out.notes.push(format!(
                "note: {} later data-flow arrows were left out of the trace",
                t.flows_dropped
            ));
        }
        out.files.push(("--trace", path.clone(), t.json));
    }
    if let Some(path) = &a.plot {
        let subtitle = format!(
            "{} {} simulated, seed {}, exec {}, phasing {}",
            spec.fmt_time(res.horizon),
            spec.time_unit,
            a.seed,
            flag_name(&a.exec),
            flag_name(&a.phasing)
        );
        let svg = plot::fig9(spec, obs, &subtitle)
            .map_err(|e| Bad::new(format!("cannot draw --plot {}: {e}", path.display()), ""))?;
        out.notes.push(format!("wrote {}", path.display()));
        out.files.push(("--plot", path.clone(), svg));
    }
    if let Some(path) = &a.gantt {
        let svg = plot::gantt(spec, res, p.window)
            .map_err(|e| Bad::new(format!("cannot draw --gantt {}: {e}", path.display()), ""))?;
        out.notes.push(format!(
            "wrote {}: {}..{} {}",
            path.display(),
            spec.fmt_time(p.window.0),
            spec.fmt_time(p.window.1),
            spec.time_unit
        ));
        out.files.push(("--gantt", path.clone(), svg));
    }
    Ok(out)
}

/// Checks the output paths again (they may have changed during the run) and
/// writes them all or none (see [`output::write_all`]).
pub(crate) fn write_all(spec: &Path, files: &[(&'static str, PathBuf, String)]) -> Result<(), Bad> {
    let mut outs = Vec::new();
    for (flag, path, _) in files {
        outs.push(output::prepare(flag, path, spec, None).map_err(Bad::from)?);
    }
    let pairs: Vec<(&output::Output, &str)> = outs
        .iter()
        .zip(files)
        .map(|(o, (_, _, text))| (o, text.as_str()))
        .collect();
    output::write_all(&pairs).map_err(Bad::from)
}

pub fn run(a: &SimulateArgs) -> ExitCode {
    let spec = match analyze::load(&a.spec) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let p = match plan(&spec, a) {
        Ok(p) => p,
        Err(b) => return fail(b),
    };
    let report = rtpipe_analysis::analyze(&spec);
    let started = Instant::now();
    let msg = format!(
        "simulating {} for {} {}{}",
        spec.name,
        spec.fmt_time(p.horizon),
        spec.time_unit,
        human(&spec, p.horizon)
    );
    let res = match with_horizon_bar(msg, p.horizon, |progress| {
        run_simulation(&spec, a, &p, progress)
    }) {
        Ok(r) => r,
        Err(e) => {
            return fail(Bad::new(
                format!("{}: cannot simulate: {e}", a.spec.display()),
                "give every task a fixed positive period",
            ))
        }
    };
    let searches = if a.phasing == PhasingArg::Search {
        match with_spinner(format!("searching worst cases of {}", spec.name), || {
            run_searches(&spec, a, &p)
        }) {
            Ok(v) => v,
            Err(e) => {
                return fail(Bad::new(
                    format!("{}: cannot search: {e}", a.spec.display()),
                    "give every task a fixed positive period",
                ))
            }
        }
    } else {
        Vec::new()
    };
    let seconds = started.elapsed().as_secs_f64();
    let obs = observe(&report, &res);
    let outputs = match render_outputs(&spec, a, &p, &res, &obs) {
        Ok(o) => o,
        Err(b) => return fail(b),
    };
    if let Err(b) = write_all(&a.spec, &outputs.files) {
        return fail(b);
    }
    let late_rt = response_violations(&report, &res);
    let over_sound: usize = obs.iter().map(ChainObs::over_sound).sum();
    let over_search = searches.iter().filter(|r| r.exceeds_sound()).count();
    if a.json {
        let mut v = to_json(&spec, &report, a, &res, &obs, seconds);
        if !searches.is_empty() {
            v["search"] = search_json(&spec, &searches);
        }
        if let Err(code) = crate::analyze::print_json(&v) {
            return code;
        }
    } else {
        print!("{}", to_text(&spec, &report, a, &p, &res, &obs, seconds));
        if !searches.is_empty() {
            print!("{}", search_text(&spec, &searches));
        }
    }
    for n in &outputs.notes {
        eprintln!("{n}");
    }
    if let Some(n) = p.outputs {
        let short: Vec<String> = spec
            .chains
            .iter()
            .filter_map(|c| c.path.last())
            .filter(|&&t| res.tasks.get(t).is_some_and(|ts| ts.completed < n))
            .map(|&t| spec.tasks[t].name.clone())
            .collect();
        if !short.is_empty() {
            eprintln!(
                "note: tail task(s) {} completed fewer than {n} jobs (late or starved jobs); the run stopped at {} {}",
                short.join(", "),
                spec.fmt_time(res.horizon),
                spec.time_unit
            );
        }
    }
    if over_search > 0 {
        eprintln!("error: SOUND BOUND EXCEEDED by an adversarial search ({over_search} chain metric(s)); the replayable offsets are in --json");
        return ExitCode::from(1);
    }
    if over_sound > 0 || !late_rt.is_empty() {
        eprintln!(
            "error: SOUND BOUND EXCEEDED: {over_sound} sample(s) above a sound chain bound, {} task(s) above their analysed response time",
            late_rt.len()
        );
        eprintln!(
            "  = this is a bug in the analysis or the simulator: please report it with the spec and this command line:"
        );
        eprintln!(
            "    rtpipe simulate {} --duration {}{} --seed {} --exec {} --phasing {}",
            a.spec.display(),
            spec.fmt_time(res.horizon),
            spec.time_unit,
            a.seed,
            flag_name(&a.exec),
            flag_name(&a.phasing)
        );
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}

/// One adversarial search per chain, metric and anchor (`--phasing search`).
fn run_searches(spec: &Spec, a: &SimulateArgs, p: &Plan) -> Result<Vec<SearchResult>, SimError> {
    let longest = spec
        .tasks
        .iter()
        .filter_map(|t| t.fixed_period())
        .max()
        .unwrap_or(1);
    // Each candidate needs a few hyperperiod-ish spans, not the whole run.
    let horizon = p.horizon.min(40 * longest);
    let mut out = Vec::new();
    for chain in 0..spec.chains.len() {
        for anchor in Anchor::ALL {
            for metric in [Metric::Reaction, Metric::Freshness] {
                let mut cfg = SearchConfig::new(chain, metric, horizon);
                cfg.anchor = anchor;
                cfg.steps = a.search_steps;
                cfg.seed = a.seed;
                out.push(search(spec, &cfg)?);
            }
        }
    }
    Ok(out)
}

fn search_json(spec: &Spec, rs: &[SearchResult]) -> Value {
    Value::Array(
        rs.iter()
            .map(|r| {
                json!({
                    "chain": spec.chain_label(r.chain),
                    "metric": r.metric.name(),
                    "from": r.anchor.name(),
                    "found": num(spec, r.value),
                    "paper": num(spec, r.paper),
                    "sound": num(spec, r.sound),
                    "tightness": r.tightness(),
                    "simulations": r.simulations,
                    "offsets": r.best.offsets.iter().map(|&o| spec.in_unit(o)).collect::<Vec<_>>(),
                    "exec": format!("{:?}", r.best.exec).to_lowercase(),
                    "seed": r.best.seed,
                })
            })
            .collect(),
    )
}

fn search_text(spec: &Spec, rs: &[SearchResult]) -> String {
    let mut t = Table::new(&[
        "chain",
        "metric",
        "from",
        "found",
        "paper",
        "sound",
        "found/sound",
        "above paper",
        "simulations",
    ])
    .numeric(&[3, 4, 5, 6, 8]);
    for r in rs {
        let f = |v: Option<Nanos>| v.map_or("-".to_string(), |n| spec.fmt_time(n));
        t.row(vec![
            spec.chain_label(r.chain),
            r.metric.name().to_string(),
            r.anchor.name().to_string(),
            f(r.value),
            f(r.paper),
            f(r.sound),
            r.tightness().map_or("-".into(), |x| format!("{x:.4}")),
            match (r.value, r.paper) {
                (Some(v), Some(p)) if v > p => "yes".into(),
                _ => "no".into(),
            },
            r.simulations.to_string(),
        ]);
    }
    format!(
        "\nadversarial search (a lower bound on the true worst case; found/sound brackets it):\n{}",
        t.render()
    )
}

pub(crate) fn num(spec: &Spec, ns: Option<Nanos>) -> Value {
    ns.map_or(Value::Null, |n| json!(spec.in_unit(n)))
}

fn to_json(
    spec: &Spec,
    report: &Report,
    a: &SimulateArgs,
    res: &SimResult,
    obs: &[ChainObs],
    seconds: f64,
) -> Value {
    let mut v = observations_json(spec, report, obs);
    if let Some(tasks) = v.get_mut("tasks").and_then(Value::as_array_mut) {
        for (entry, ts) in tasks.iter_mut().zip(&res.tasks) {
            entry["observed"] = json!({
                "released": ts.released,
                "completed": ts.completed,
                "max_response": num(spec, ts.max_response),
                "late": ts.late,
                "exhaustions": ts.exhaustions,
                "utilization": ts.busy as f64 / res.horizon as f64,
            });
        }
    }
    let offsets: serde_json::Map<String, Value> = spec
        .tasks
        .iter()
        .zip(&res.offsets)
        .map(|(t, &o)| (t.name.clone(), json!(spec.in_unit(o))))
        .collect();
    v["simulation"] = json!({
        "horizon": spec.in_unit(res.horizon),
        "seed": a.seed,
        "exec": flag_name(&a.exec),
        "phasing": flag_name(&a.phasing),
        "offsets": offsets,
        "events": res.events,
        "seconds": seconds,
    });
    v
}

/// The `analyze --json` report with each chain entry's observations from the
/// read and from the event.
pub(crate) fn observations_json(spec: &Spec, report: &Report, obs: &[ChainObs]) -> Value {
    let mut v = analyze::report_json(spec, report);
    if let Some(chains) = v.get_mut("chains").and_then(Value::as_array_mut) {
        for (entry, o) in chains.iter_mut().zip(obs) {
            entry["observed"] = observed_json(spec, &o.read);
            entry["violations"] = json!({"paper": o.read.over_paper, "sound": o.read.over_sound});
            entry["observed_from_event"] = observed_json(spec, &o.event);
            entry["violations_from_event"] =
                json!({"paper": o.event.over_paper, "sound": o.event.over_sound});
        }
    }
    v
}

/// {count, min, mean, p99, max, variation} in the spec's unit; variation =
/// max − min, the spread the paper's Fig. 10 reports (MaxRV, MaxFV).
pub(crate) fn observed_json(spec: &Spec, j: &Judged) -> Value {
    let unit = spec.time_unit.nanos() as f64;
    match j.observed {
        Some(s) => json!({
            "count": s.count,
            "min": spec.in_unit(s.min),
            "mean": s.mean / unit,
            "p99": spec.in_unit(s.p99),
            "max": spec.in_unit(s.max),
            "variation": spec.in_unit(s.max - s.min),
        }),
        None => {
            json!({"count": 0, "min": null, "mean": null, "p99": null, "max": null, "variation": null})
        }
    }
}

/// A mean in the spec's unit, to a thousandth of the unit.
fn fmt_mean(spec: &Spec, mean_ns: f64) -> String {
    let step = (spec.time_unit.nanos() / 1000).max(1) as f64;
    spec.fmt_time(((mean_ns / step).round() * step) as Nanos)
}

/// A duration for people in the largest unit that keeps it at least 1
/// ("300.01 s"), when that differs from the spec's unit.
fn human(spec: &Spec, ns: Nanos) -> String {
    let unit = TimeUnit::ALL
        .iter()
        .rev()
        .copied()
        .find(|u| ns >= u.nanos())
        .unwrap_or(TimeUnit::Ns);
    if unit == spec.time_unit {
        return String::new();
    }
    let x = unit.from_nanos(ns);
    let v = format!("{x:.2}");
    let v = v.trim_end_matches('0').trim_end_matches('.');
    format!(" ({v} {unit})")
}

/// 1234567 → "1.23M".
fn si(x: f64) -> String {
    match x {
        x if x >= 1e9 => format!("{:.2}G", x / 1e9),
        x if x >= 1e6 => format!("{:.2}M", x / 1e6),
        x if x >= 1e3 => format!("{:.1}k", x / 1e3),
        x => format!("{x:.0}"),
    }
}

/// One row per chain and metric: the observations from `a` against the
/// bounds from `a`.
pub(crate) fn chain_table(spec: &Spec, obs: &[ChainObs], a: Anchor) -> String {
    let mut t = Table::new(&[
        "chain",
        "metric",
        "count",
        "min",
        "mean",
        "p99",
        "max",
        "paper",
        "sound",
        ">paper",
        ">sound",
        "max/sound",
    ])
    .numeric(&[2, 3, 4, 5, 6, 7, 8, 9, 10, 11]);
    for o in obs {
        let j = o.from(a);
        let dash = || "-".to_string();
        let (count, min, mean, p99, max) = match j.observed {
            Some(s) => (
                s.count.to_string(),
                spec.fmt_time(s.min),
                fmt_mean(spec, s.mean),
                spec.fmt_time(s.p99),
                spec.fmt_time(s.max),
            ),
            None => ("0".into(), dash(), dash(), dash(), dash()),
        };
        let ratio = match (j.observed, j.sound) {
            (Some(s), Some(b)) if b > 0 => format!("{:.3}", s.max as f64 / b as f64),
            _ => dash(),
        };
        let over_sound = match j.over_sound {
            Some(0) => "0".to_string(),
            Some(n) => format!("{n} !!"),
            None => dash(),
        };
        t.row(vec![
            spec.chain_label(o.chain),
            o.metric.name().to_string(),
            count,
            min,
            mean,
            p99,
            max,
            spec.fmt_time(j.paper),
            j.sound
                .map_or_else(|| "unbounded".into(), |s| spec.fmt_time(s)),
            j.over_paper.to_string(),
            over_sound,
            ratio,
        ]);
    }
    t.render()
}

fn to_text(
    spec: &Spec,
    report: &Report,
    a: &SimulateArgs,
    p: &Plan,
    res: &SimResult,
    obs: &[ChainObs],
    seconds: f64,
) -> String {
    let u = spec.time_unit;
    let mut out = crate::analyze::system_line(spec);
    let span = match p.outputs {
        Some(n) => format!(", >= {n} outputs of every chain's tail"),
        None => String::new(),
    };
    out.push_str(&format!(
        "simulated {} {u}{}{span}; seed {}, exec {}, phasing {}\n",
        spec.fmt_time(res.horizon),
        human(spec, res.horizon),
        a.seed,
        flag_name(&a.exec),
        flag_name(&a.phasing)
    ));
    if res.offsets.iter().any(|&o| o != 0) {
        let offs: Vec<String> = spec
            .tasks
            .iter()
            .zip(&res.offsets)
            .map(|(t, &o)| format!("{}={}", t.name, spec.fmt_time(o)))
            .collect();
        out.push_str(&format!("offsets: {}\n", offs.join(" ")));
    }
    if !obs.is_empty() {
        out.push_str(
            "\nchains (observed from the head's read, against the analysis' worst-case bounds):\n",
        );
        out.push_str(&chain_table(spec, obs, Anchor::Read));
        out.push_str(
            "\nfrom the event just after each head read (reaction: to the first output that \
             reflects it; freshness: to the last output of the next sample), against the +event bounds:\n",
        );
        out.push_str(&chain_table(spec, obs, Anchor::Event));
    }
    out.push_str("\ntasks (R(job): the analysed worst-case job response time):\n");
    let mut t = Table::new(&[
        "task",
        "cpu",
        "released",
        "completed",
        "max R",
        "R(job)",
        "late",
        "exhaustions",
        "busy/horizon",
    ])
    .numeric(&[1, 2, 3, 4, 5, 6, 7, 8]);
    for ((task, ts), tm) in spec.tasks.iter().zip(&res.tasks).zip(&report.timing) {
        let over = matches!((ts.max_response, tm.bounded_response()), (Some(s), Some(r)) if s > r);
        t.row(vec![
            task.name.clone(),
            task.cpu.to_string(),
            ts.released.to_string(),
            ts.completed.to_string(),
            ts.max_response
                .map_or_else(|| "-".into(), |r| spec.fmt_time(r))
                + if over { " !!" } else { "" },
            tm.job_response_time
                .map_or_else(|| "unbounded".into(), |r| spec.fmt_time(r)),
            ts.late.to_string(),
            ts.exhaustions.to_string(),
            format!("{:.4}", ts.busy as f64 / res.horizon as f64),
        ]);
    }
    out.push_str(&t.render());
    let eps = if seconds > 0.0 {
        res.events as f64 / seconds
    } else {
        0.0
    };
    out.push_str(&format!(
        "\n{} events simulated in {seconds:.3} s ({} events/s)\n",
        res.events,
        si(eps)
    ));
    let over_sound: usize = obs.iter().map(ChainObs::over_sound).sum();
    let over_paper: usize = obs
        .iter()
        .map(|o| o.read.over_paper + o.event.over_paper)
        .sum();
    let late_rt = response_violations(report, res).len();
    // Background tasks have no deadline: their backlog is not a miss.
    let late: u64 = res
        .tasks
        .iter()
        .zip(&spec.tasks)
        .filter(|(_, t)| t.server != rtpipe_model::Server::Background)
        .map(|(r, _)| r.late)
        .sum();
    let verdict = if over_sound > 0 || late_rt > 0 {
        format!(
            "verdict: SOUND BOUND EXCEEDED ({over_sound} sample(s), {late_rt} task response time(s)): a bug in the analysis or the simulator"
        )
    } else {
        let paper = match over_paper {
            0 => "none above the paper bounds either".to_string(),
            n => format!(
                "{n} above the paper bounds (the published equations are not upper bounds here)"
            ),
        };
        format!("verdict: no sample above a sound bound; {paper}")
    };
    out.push_str(&verdict);
    out.push('\n');
    if late > 0 {
        out.push_str(&format!(
            "note: {late} job(s) finished after their period: the system breaks the model's assumptions\n"
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: SimulateArgs,
    }

    fn spec() -> Spec {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/paper-table3.toml"
        );
        match Spec::load(Path::new(path)) {
            Ok(s) => s,
            Err(e) => panic!("{e}"),
        }
    }

    fn args(flags: &[&str]) -> SimulateArgs {
        let mut v = vec!["rtpipe", "spec.toml"];
        v.extend_from_slice(flags);
        match Cli::try_parse_from(v) {
            Ok(c) => c.args,
            Err(e) => panic!("{e}"),
        }
    }

    const MS: Nanos = 1_000_000;

    #[test]
    fn outputs_set_the_horizon() {
        let s = spec();
        // Tails p5 (150 ms) and p7 (50 ms); the largest period is 150 ms.
        let p = plan(&s, &args(&["--outputs", "4"]));
        assert_eq!(p.map(|p| p.horizon).ok(), Some(4 * 150 * MS + 150 * MS));
        let p = plan(&s, &args(&[]));
        assert_eq!(p.map(|p| p.outputs).ok(), Some(Some(DEFAULT_OUTPUTS)));
        let p = plan(&s, &args(&["--duration", "2s"]));
        assert_eq!(
            p.map(|p| (p.horizon, p.window)).ok(),
            Some((2000 * MS, (0, 450 * MS)))
        );
        let p = plan(&s, &args(&["--duration", "250"]));
        assert_eq!(
            p.map(|p| (p.horizon, p.window)).ok(),
            Some((250 * MS, (0, 250 * MS)))
        );
        let p = plan(&s, &args(&["--outputs", "18446744073709551615"]));
        assert!(p.is_err());
    }

    #[test]
    fn windows_take_units() {
        let s = spec();
        let p = plan(&s, &args(&["--gantt", "g.svg", "--window", "1.5, 20ms"]));
        assert_eq!(p.map(|p| p.window).ok(), Some((1_500_000, 20 * MS)));
        for bad in ["20,10", "-1,5", "5", "a,b", "0,0"] {
            assert!(
                plan(&s, &args(&["--gantt", "g.svg", "--window", bad])).is_err(),
                "{bad}"
            );
        }
    }

    #[test]
    fn samples_above_a_sound_bound_are_counted() {
        let s = spec();
        let report = rtpipe_analysis::analyze(&s);
        let sound = report.chains[0].bound.sound.unwrap_or(0);
        let paper = report.chains[0].bound.paper;
        let mut res = SimResult {
            offsets: vec![0; s.tasks.len()],
            tasks: vec![Default::default(); s.tasks.len()],
            chains: vec![Default::default(); s.chains.len()],
            jobs: Vec::new(),
            segments: Vec::new(),
            events: 0,
            horizon: 1,
        };
        res.chains[0].reaction.values = vec![1, paper + 1, sound + 1, sound];
        let event = report.chains[0].bound.from_event_sound.unwrap_or(0);
        res.chains[0].event_reaction.values = vec![event, event + 1, event + 2];
        let obs = observe(&report, &res);
        assert_eq!(obs[0].metric, Metric::Reaction);
        assert_eq!(obs[0].read.over_sound, Some(1));
        assert_eq!(obs[0].read.over_paper, 2 + usize::from(sound > paper));
        assert_eq!(obs[0].event.over_sound, Some(2));
        assert_eq!(obs[0].over_sound(), 3);
        assert_eq!(obs[1].read.observed, None);
        assert_eq!(obs[1].read.over_sound, Some(0));
        assert_eq!(obs[1].event.over_sound, Some(0));
    }
}
