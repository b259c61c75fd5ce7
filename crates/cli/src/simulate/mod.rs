//! `rtpipe simulate`: run the discrete-event simulator on a spec and hold the
//! observed reaction and freshness times against the analysis' bounds.

mod files;
mod plan;
mod report;

use crate::command::{self, fail, parse_time, Answer, ExecArg, Hooks};
use crate::output;
use crate::plot;
use crate::report::samples::{self, SamplesFile};
use crate::table::Table;
use clap::{Args, ValueEnum};
pub(crate) use files::with_spinner;
use files::{render_outputs, with_horizon_bar};
use plan::*;
pub(crate) use report::*;
use rtpipe_analysis::{Anchor, Metric, Report};
use rtpipe_joblog::trace::{chrome_trace_with, TraceOptions};
use rtpipe_joblog::RowSink;
use rtpipe_joblog::SimResult;
use rtpipe_model::{Diagnostic, Nanos, Spec, TimeUnit, MAX_TIME};
use rtpipe_sim::observe::{horizon_for_outputs, observe, response_violations, ChainObs, Judged};
use rtpipe_sim::search::{search, SearchConfig, SearchResult};
use rtpipe_sim::{simulate_watched, Jitter, Phasing, SimConfig, SimError};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
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
    /// Seeds the random offsets and demands (the same seed gives the same
    /// run) [default: 0].
    // Absent rather than defaulted, so that a seed given where nothing is
    // random is refused (`SimulateArgs::validate`), however it came.
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// How each job's demand Δin + p + Δout is drawn: p = exec (worst),
    /// exec_min (best), uniform in between, or one of the two at random
    /// (extremes).
    #[arg(long, value_enum, default_value_t = ExecArg::Worst)]
    pub exec: ExecArg,
    /// Release offsets: all at 0 (sync), uniform in [0, T) per task (random),
    /// or random plus an adversarial search for each chain's worst case
    /// (search), reported beside the bounds as a tightness ratio. A task
    /// with a known `offset` in the spec keeps it in every mode.
    #[arg(long, value_enum, default_value_t = PhasingArg::Sync)]
    pub phasing: PhasingArg,
    /// With --phasing search: candidates tried per local search (4
    /// restarts) [default: 50].
    #[arg(long, value_name = "N")]
    pub search_steps: Option<u32>,
    #[command(flatten)]
    pub output: command::FormatArgs,
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
    /// Write one CSV row per head sample of every chain: its read, the
    /// event before it, its first and last tail outputs, and its reaction
    /// and freshness from the read and from the event (integer ns).
    #[arg(long, value_name = "FILE.csv")]
    pub samples: Option<PathBuf>,
    /// The span of --gantt, START,END in the spec's time unit or with units
    /// ("0,30ms") [default: the first 3 × the largest period].
    #[arg(long, value_name = "START,END", allow_hyphen_values = true)]
    pub window: Option<String>,
}

impl SimulateArgs {
    /// `--seed`, or its default.
    pub fn seed(&self) -> u64 {
        self.seed.unwrap_or(0)
    }

    /// `--search-steps`, or its default.
    pub fn search_steps(&self) -> u32 {
        self.search_steps.unwrap_or(50)
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

/// Runs the simulator as `--phasing` asks, reporting the simulated time
/// reached to `progress`. One simulation per run today; a phasing that
/// searches offsets would run several here and return the worst.
fn run_simulation(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    progress: &mut dyn FnMut(Nanos) -> bool,
    rows: Option<RowSink>,
) -> Result<Option<SimResult>, SimError> {
    let phasing = match a.phasing {
        PhasingArg::Sync => Phasing::Sync,
        PhasingArg::Random | PhasingArg::Search => Phasing::Random,
    };
    let cfg = SimConfig {
        horizon: p.horizon,
        seed: a.seed(),
        phasing,
        exec: a.exec.model(),
        // Jittered tasks: every job at its latest under the deterministic
        // synchronous phasing, uniform in its window otherwise (the search
        // explores the other models).
        jitter: match a.phasing {
            PhasingArg::Sync => Jitter::Latest,
            PhasingArg::Random | PhasingArg::Search => Jitter::Uniform,
        },
        log_jobs: p.log_jobs,
    };
    // With rows on disk as it goes, the binary's Ctrl-C must take them away.
    let streamed = rows.is_some();
    let mut checked = |t: Nanos| {
        if streamed {
            samples::stop_if_interrupted(|| {});
        }
        progress(t)
    };
    simulate_watched(spec, &cfg, &mut checked, rows)
}

pub fn run(a: &SimulateArgs) -> ExitCode {
    let spec = match command::load_simulated(&a.spec) {
        Ok(s) => s,
        Err(code) => return code,
    };
    match execute(&spec, a, Hooks::default()) {
        Ok(answer) => answer.emit(),
        Err(b) => fail(b),
    }
}

/// `simulate` on a loaded spec (every period fixed), with `hooks`' extra
/// row sink and stop flag.
pub fn execute(spec: &Spec, a: &SimulateArgs, hooks: Hooks) -> Result<Answer, Diagnostic> {
    let p = plan(spec, a)?;
    let report = rtpipe_analysis::analyze(spec);
    let samples = SamplesFile::open(a.samples.as_ref(), &a.spec, spec, &hooks)?;
    let sink = command::tee(samples.as_ref().map(SamplesFile::sink), hooks.rows);
    let stop = hooks.stop.as_deref();
    let Some((res, searches, seconds)) = simulate_and_search(spec, a, &p, sink, stop)? else {
        return Ok(Answer::stopped());
    };
    let obs = observe(&report, &res);
    let mut outputs = render_outputs(spec, a, &p, &res, &obs)?;
    let written = write_all_outputs(a, &mut outputs, samples);
    let printed = report::SimulateReport {
        spec,
        args: a,
        plan: &p,
        report: &report,
        res: &res,
        obs: &obs,
        searches: &searches,
        seconds,
    };
    let out = command::render(&printed, a.output.chosen())?;
    let mut notes = outputs.notes;
    if let Some(n) = p.outputs {
        notes.extend(short_tails(spec, &res, n));
    }
    let status = exit_status(spec, a, &report, &res, &obs, &searches, &mut notes);
    let answer = Answer {
        report: out,
        notes,
        status,
    };
    Ok(answer.after_write(written))
}

/// The files `render_outputs` made, then `--samples` (written as the run
/// went) renamed into place; nothing of it stays when a write fails.
fn write_all_outputs(
    a: &SimulateArgs,
    outputs: &mut files::Outputs,
    samples: Option<SamplesFile>,
) -> Result<(), Diagnostic> {
    let rows = samples::write_with(&a.spec, &outputs.files, samples)?;
    if let (Some(n), Some(path)) = (rows, &a.samples) {
        outputs
            .notes
            .push(format!("wrote {}: {n} samples", path.display()));
    }
    Ok(())
}

/// The simulation, and the adversarial searches under `--phasing search`,
/// with their progress shown; and the seconds they took. `None` when `stop`
/// ended them.
fn simulate_and_search(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    rows: Option<RowSink>,
    stop: Option<&AtomicBool>,
) -> Result<Option<(SimResult, Vec<SearchResult>, f64)>, Diagnostic> {
    let started = Instant::now();
    let msg = format!(
        "simulating {} for {} {}{}",
        spec.name,
        spec.fmt_time(p.horizon),
        spec.time_unit,
        human(spec, p.horizon)
    );
    let res = with_horizon_bar(msg, p.horizon, |progress| {
        let mut checked = |t: Nanos| {
            progress(t);
            !Hooks::stopped(stop)
        };
        run_simulation(spec, a, p, &mut checked, rows)
    })
    .map_err(|e| {
        Diagnostic::error(
            format!("{}: cannot simulate: {e}", a.spec.display()),
            "give every task a fixed positive period",
        )
    })?;
    let Some(res) = res else {
        return Ok(None);
    };
    let searches = if a.phasing == PhasingArg::Search {
        with_spinner(format!("searching worst cases of {}", spec.name), || {
            run_searches(spec, a, p, stop)
        })
        .map_err(|e| {
            Diagnostic::error(
                format!("{}: cannot search: {e}", a.spec.display()),
                "give every task a fixed positive period",
            )
        })?
    } else {
        Some(Vec::new())
    };
    Ok(searches.map(|searches| (res, searches, started.elapsed().as_secs_f64())))
}

/// Which chain tails published fewer than the `n` outputs asked for.
fn short_tails(spec: &Spec, res: &SimResult, n: u64) -> Option<String> {
    let short: Vec<String> = spec
        .chains
        .iter()
        .filter_map(|c| c.path.last())
        .filter(|&&t| res.tasks.get(t).is_some_and(|ts| ts.completed < n))
        .map(|&t| spec.tasks[t].name.clone())
        .collect();
    (!short.is_empty()).then(|| {
        format!(
            "note: tail task(s) {} completed fewer than {n} jobs (late or starved jobs); the run stopped at {} {}",
            short.join(", "),
            spec.fmt_time(res.horizon),
            spec.time_unit
        )
    })
}

/// 1 (with the replay command) when a sample, a response time or a search
/// exceeded a sound bound, else 0.
fn exit_status(
    spec: &Spec,
    a: &SimulateArgs,
    report: &Report,
    res: &SimResult,
    obs: &[ChainObs],
    searches: &[SearchResult],
    notes: &mut Vec<String>,
) -> u8 {
    let late_rt = response_violations(report, res);
    // The bound that holds for these runs: under known offsets when the
    // chain has them (ChainObs::violations).
    let over_sound: usize = obs.iter().map(ChainObs::violations).sum();
    let over_search = searches.iter().filter(|r| r.exceeds_sound()).count();
    if over_search > 0 {
        notes.push(format!("error: SOUND BOUND EXCEEDED by an adversarial search ({over_search} chain metric(s)); the replayable offsets are in --json"));
        return 1;
    }
    if over_sound > 0 || !late_rt.is_empty() {
        notes.push(format!(
            "error: SOUND BOUND EXCEEDED: {over_sound} sample(s) above a sound chain bound, {} task(s) above their analysed response time",
            late_rt.len()
        ));
        notes.push(
            "  = this is a bug in the analysis or the simulator: please report it with the spec and this command line:".into()
        );
        notes.push(format!(
            "    rtpipe simulate {} --duration {}{} --seed {} --exec {} --phasing {}",
            a.spec.display(),
            spec.fmt_time(res.horizon),
            spec.time_unit,
            a.seed(),
            flag_name(&a.exec),
            flag_name(&a.phasing)
        ));
        return 1;
    }
    0
}

/// One adversarial search per chain, metric and anchor (`--phasing search`).
fn run_searches(
    spec: &Spec,
    a: &SimulateArgs,
    p: &Plan,
    stop: Option<&AtomicBool>,
) -> Result<Option<Vec<SearchResult>>, SimError> {
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
                cfg.steps = a.search_steps();
                cfg.seed = a.seed();
                if Hooks::stopped(stop) {
                    return Ok(None);
                }
                out.push(search(spec, &cfg)?);
            }
        }
    }
    Ok(Some(out))
}

impl command::Registered for SimulateArgs {
    fn run(&self) -> ExitCode {
        run(self)
    }

    fn call(&self, call: command::Call<'_>) -> Result<command::Done, Diagnostic> {
        let spec = call.spec()?;
        if let Some(d) = command::unsimulable(spec) {
            return Err(d);
        }
        execute(spec, self, call.hooks).map(command::Done::from)
    }
}

/// The JSON Schema of `--json`'s report (its fields and their doc
/// comments: the source of the Python package's typed results).
pub fn json_schema() -> schemars::Schema {
    schemars::schema_for!(report::SimulateView<'static>)
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
        match Spec::load(std::path::Path::new(path)) {
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
        use rtpipe_joblog::Histogram;
        let s = spec();
        let report = rtpipe_analysis::analyze(&s);
        let sound = report.chains[0].bound.sound(Anchor::Read).unwrap_or(0);
        let paper = report.chains[0].bound.paper(Anchor::Read);
        let mut res = SimResult {
            offsets: vec![0; s.tasks.len()],
            tasks: vec![Default::default(); s.tasks.len()],
            chains: vec![Default::default(); s.chains.len()],
            jobs: Vec::new(),
            segments: Vec::new(),
            events: 0,
            horizon: 1,
        };
        res.chains[0].reaction.hist = Histogram::of(&[1, paper + 1, sound + 1, sound]);
        let event = report.chains[0].bound.sound(Anchor::Event).unwrap_or(0);
        res.chains[0].event_reaction.hist = Histogram::of(&[event, event + 1, event + 2]);
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
