//! The entry points of the Python package (`crates/python`): a command on a
//! loaded spec, its flags given as on the command line (so they are
//! checked by the same parser, with the same messages), answering the JSON
//! of `--json`. Nothing here prints, reads a clock or catches a signal: the
//! caller owns the process (Python's SIGINT handler stays Python's).

use crate::analyze::AnalyzeArgs;
use crate::command::{self, Answer, Hooks, Rendered};
use crate::design::DesignArgs;
use crate::fly::FlyArgs;
use crate::simulate::SimulateArgs;
use clap::{Args, FromArgMatches};
use rtpipe_joblog::SampleRow;
use rtpipe_model::{Diagnostic, Spec};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The commands the API runs.
pub const COMMANDS: [&str; 6] = ["analyze", "simulate", "fly", "design", "run", "campaign"];

/// What a command answered.
pub struct Reply {
    /// The `--json` report (absent when the command failed: see `notes`).
    pub json: Option<serde_json::Value>,
    /// The report's tables (what `--format csv` prints), with the JSON.
    pub tables: Vec<rtpipe_printer::Table>,
    /// The command line's exit status (0 ok, 1 a verdict failed, 2 bad
    /// input, 3 internal error, 130 stopped).
    pub status: u8,
    /// What the command line prints on stderr.
    pub notes: Vec<String>,
    /// One column per field of `--samples`, when asked for.
    pub samples: Option<Columns>,
    /// `design`'s designed spec, when there is one.
    pub designed: Option<Spec>,
}

/// Why a command gave no reply.
#[derive(Debug)]
pub enum Failure {
    /// A flag or a value is wrong: what and how to fix it.
    Input(Diagnostic),
    /// A run on this machine could not start (`run`: the kernel refused a
    /// class or a reservation, a CPU is missing): what and how to fix it.
    Run(Diagnostic),
    /// The stop flag was set.
    Stopped,
    /// The sample rows asked for would not fit [`MAX_SAMPLE_ROWS`]: what
    /// and how to get them all (a file).
    TooManySamples(Diagnostic),
    /// A bug: a panic's message.
    Internal(String),
}

/// The most sample rows a run hands back as [`Columns`]: they are held in
/// memory (about 130 bytes a row while collected, twice that while sorted),
/// so a longer run stops at this many with [`Failure::TooManySamples`]
/// rather than exhaust the memory; `--samples FILE` streams any number.
pub const MAX_SAMPLE_ROWS: usize = 2_000_000;

/// `--samples` as columns (integer nanoseconds; `None` where the CSV
/// leaves a cell empty), rows grouped by chain, each chain's in sample
/// order.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Columns {
    pub chain: Vec<u32>,
    pub sample: Vec<u64>,
    pub read_ns: Vec<i64>,
    pub event_ns: Vec<Option<i64>>,
    pub first_output_ns: Vec<Option<i64>>,
    pub last_output_ns: Vec<Option<i64>>,
    pub reaction_ns: Vec<Option<i64>>,
    pub freshness_ns: Vec<Option<i64>>,
    pub event_reaction_ns: Vec<Option<i64>>,
    pub event_freshness_ns: Vec<Option<i64>>,
}

impl Columns {
    fn push(&mut self, chain: usize, r: &SampleRow) {
        self.chain.push(u32::try_from(chain).unwrap_or(u32::MAX));
        self.sample.push(r.sample);
        self.read_ns.push(r.read);
        self.event_ns.push(r.event);
        self.first_output_ns.push(r.first);
        self.last_output_ns.push(r.last);
        self.reaction_ns.push(r.reaction());
        self.freshness_ns.push(r.freshness());
        self.event_reaction_ns.push(r.event_reaction());
        self.event_freshness_ns.push(r.event_freshness());
    }

    /// The rows sorted by chain (a run hands them on chain by chain as
    /// they complete, interleaved), each chain's in sample order.
    fn sorted(self) -> Columns {
        let mut idx: Vec<usize> = (0..self.chain.len()).collect();
        idx.sort_by_key(|&i| (self.chain[i], self.sample[i]));
        let pick = |v: &[Option<i64>]| idx.iter().map(|&i| v[i]).collect();
        Columns {
            chain: idx.iter().map(|&i| self.chain[i]).collect(),
            sample: idx.iter().map(|&i| self.sample[i]).collect(),
            read_ns: idx.iter().map(|&i| self.read_ns[i]).collect(),
            event_ns: pick(&self.event_ns),
            first_output_ns: pick(&self.first_output_ns),
            last_output_ns: pick(&self.last_output_ns),
            reaction_ns: pick(&self.reaction_ns),
            freshness_ns: pick(&self.freshness_ns),
            event_reaction_ns: pick(&self.event_reaction_ns),
            event_freshness_ns: pick(&self.event_freshness_ns),
        }
    }
}

/// Runs `command` (one of [`COMMANDS`]) on `spec`, read from `label` (a
/// path or a name for messages), with `flags` as the command line takes
/// them after the spec (`--json` is implied); `samples` collects up to
/// that many of `--samples`' rows as columns (simulate and fly; at most
/// [`MAX_SAMPLE_ROWS`], one more is [`Failure::TooManySamples`]). `stop` stops a
/// simulation or a design search early ([`Failure::Stopped`]).
pub fn run(
    command: &str,
    spec: &Spec,
    label: &str,
    flags: &[String],
    samples: Option<usize>,
    stop: Arc<AtomicBool>,
) -> Result<Reply, Failure> {
    let cols = Arc::new(Mutex::new(Columns::default()));
    let full = Arc::new(AtomicBool::new(false));
    let rows = samples.map(|most| column_sink(&cols, most, &stop, &full));
    let hooks = Hooks {
        rows,
        stop: Some(Arc::clone(&stop)),
    };
    let argv = std::iter::once(label.to_string())
        .chain(flags.iter().cloned())
        .collect();
    let done = guarded(&stop, || dispatch(command, spec, argv, hooks, &stop));
    if let (true, Some(most)) = (full.load(Ordering::Relaxed), samples) {
        return Err(Failure::TooManySamples(too_many_samples(most)));
    }
    let (answer, designed) = done?;
    let samples = samples.map(|_| {
        let taken = cols.lock().map(|mut g| std::mem::take(&mut *g));
        taken.unwrap_or_default().sorted()
    });
    Ok(reply(answer, samples, designed))
}

/// A row sink that collects into `cols` up to `most` rows (no more than
/// [`MAX_SAMPLE_ROWS`]); one more sets `full` and `stop`, which ends the
/// run (nothing more is held).
fn column_sink(
    cols: &Arc<Mutex<Columns>>,
    most: usize,
    stop: &Arc<AtomicBool>,
    full: &Arc<AtomicBool>,
) -> rtpipe_joblog::RowSink {
    let most = most.min(MAX_SAMPLE_ROWS);
    let (cols, stop, full) = (Arc::clone(cols), Arc::clone(stop), Arc::clone(full));
    Box::new(move |c: usize, r: &SampleRow| {
        let Ok(mut g) = cols.lock() else { return };
        if g.chain.len() < most {
            g.push(c, r);
        } else {
            full.store(true, Ordering::Relaxed);
            stop.store(true, Ordering::Relaxed);
        }
    })
}

fn too_many_samples(most: usize) -> Diagnostic {
    let most = most.min(MAX_SAMPLE_ROWS);
    Diagnostic::error(
        format!(
            "the run has more than {most} sample rows, the most `samples=True` holds in \
             memory; it was stopped there"
        ),
        "stream them to a file instead: pass samples=\"FILE.csv\" (any number of rows, \
         read it back with pandas or polars), or run a shorter duration",
    )
}

/// Runs `command` without a spec (`campaign`), with `flags` as the command
/// line takes them (`--json` implied); `stop` ends it after the shard in
/// progress ([`Failure::Stopped`]).
pub fn run_plain(command: &str, flags: &[String], stop: Arc<AtomicBool>) -> Result<Reply, Failure> {
    let mut argv = flags.to_vec();
    argv.push("--json".into());
    let answer = guarded(&stop, || match command {
        "campaign" => {
            let a: crate::campaign::CampaignArgs = parse(command, &argv)?;
            let stopped = || stop.load(Ordering::Relaxed);
            crate::campaign::execute(&a, &stopped).map_err(Failure::Input)
        }
        _ => Err(Failure::Input(Diagnostic::error(
            format!("no command `{command}` without a spec"),
            "use campaign",
        ))),
    })?;
    Ok(reply(answer, None, None))
}

/// `work`'s answer; a panic in it is [`Failure::Internal`], and an answer
/// that came after `stop` was set (a long loop's [`Answer::stopped`], or
/// one that finished meanwhile) is [`Failure::Stopped`]: it is not the
/// whole run.
fn guarded<T>(stop: &AtomicBool, work: impl FnOnce() -> Result<T, Failure>) -> Result<T, Failure> {
    let answer = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)) {
        Ok(r) => r?,
        Err(p) => return Err(Failure::Internal(panic_message(p.as_ref()))),
    };
    if stop.load(Ordering::Relaxed) {
        return Err(Failure::Stopped);
    }
    Ok(answer)
}

/// The WATERS task set `rtpipe generate waters FLAGS` writes, as a spec
/// (no file: the flags' OUTFILE is not given).
pub fn waters(flags: &[String]) -> Result<Spec, Failure> {
    let mut argv = flags.to_vec();
    argv.push("<python>".into());
    let a: crate::generate::WatersArgs = parse("waters", &argv)?;
    Ok(crate::generate::waters_spec(&a))
}

fn reply(answer: Answer, samples: Option<Columns>, designed: Option<Spec>) -> Reply {
    let (json, tables) = match answer.report {
        Rendered::Json(v, tables) => (Some(v), tables),
        Rendered::Text(_) | Rendered::Nothing => (None, Vec::new()),
    };
    Reply {
        json,
        tables,
        status: answer.status,
        notes: answer.notes,
        samples,
        designed,
    }
}

/// The command's flags parsed, then the command run.
fn dispatch(
    command: &str,
    spec: &Spec,
    mut argv: Vec<String>,
    hooks: Hooks,
    stop: &AtomicBool,
) -> Result<(Answer, Option<Spec>), Failure> {
    argv.push("--json".into());
    let input = Failure::Input;
    let problem = match command {
        "design" => None,
        "simulate" => command::unsimulable(spec),
        _ => command::missing_periods(spec),
    };
    if let Some(d) = problem {
        return Err(input(d));
    }
    match command {
        "analyze" => {
            let a: AnalyzeArgs = parse(command, &argv)?;
            let stop = || stop.load(Ordering::Relaxed);
            Ok((
                crate::analyze::execute(spec, &a, &stop).map_err(input)?,
                None,
            ))
        }
        "simulate" => {
            let a: SimulateArgs = parse(command, &argv)?;
            Ok((
                crate::simulate::execute(spec, &a, hooks).map_err(input)?,
                None,
            ))
        }
        "fly" => {
            let a: FlyArgs = parse(command, &argv)?;
            Ok((crate::fly::execute(spec, &a, hooks).map_err(input)?, None))
        }
        "run" => {
            let a: crate::run::RunArgs = parse(command, &argv)?;
            let answer = crate::run::answer(spec, &a, false).map_err(Failure::Run)?;
            Ok((answer, None))
        }
        "design" => {
            let a: DesignArgs = parse(command, &argv)?;
            let stop = || stop.load(Ordering::Relaxed);
            crate::design::execute(spec, &a, &stop).map_err(input)
        }
        _ => Err(Failure::Input(Diagnostic::error(
            format!("no command `{command}`"),
            format!("use one of {}", COMMANDS.join(", ")),
        ))),
    }
}

/// Every flag of `command` (one of [`COMMANDS`], or `waters`) and its
/// help as `rtpipe COMMAND --help` prints it (the long form): what the
/// Python methods' docstrings say of each keyword. Empty for another
/// name.
pub fn flag_help(command: &str) -> Vec<(String, String)> {
    let cmd = clap::Command::new("rtpipe");
    let cmd = match command {
        "analyze" => AnalyzeArgs::augment_args(cmd),
        "simulate" => SimulateArgs::augment_args(cmd),
        "fly" => FlyArgs::augment_args(cmd),
        "design" => DesignArgs::augment_args(cmd),
        "run" => crate::run::RunArgs::augment_args(cmd),
        "campaign" => crate::campaign::CampaignArgs::augment_args(cmd),
        "waters" => crate::generate::WatersArgs::augment_args(cmd),
        _ => return Vec::new(),
    };
    cmd.get_arguments()
        .filter_map(|a| {
            let help = a.get_long_help().or_else(|| a.get_help())?.to_string();
            Some((a.get_long()?.to_string(), help))
        })
        .collect()
}

/// `argv` (the spec's label, then the flags) parsed as the command line
/// would parse `rtpipe COMMAND ...`.
fn parse<A: Args + FromArgMatches>(command: &str, argv: &[String]) -> Result<A, Failure> {
    let name = COMMANDS
        .iter()
        .find(|c| **c == command)
        .copied()
        .unwrap_or("rtpipe");
    let cmd = A::augment_args(clap::Command::new(name))
        .no_binary_name(true)
        .disable_help_flag(true);
    let parsed = cmd
        .try_get_matches_from(argv)
        .and_then(|m| A::from_arg_matches(&m));
    parsed.map_err(|e| Failure::Input(flag_error(&e, command)))
}

/// A parser error as a diagnostic for a Python caller: its first line
/// (the values the flag takes, when the parser lists them, after it),
/// without clap's usage and help lines; the help is clap's tip, or where
/// to read the keywords and their values.
fn flag_error(e: &clap::Error, command: &str) -> Diagnostic {
    let text = e.render().to_string();
    let first = text.lines().next().unwrap_or("invalid arguments");
    let mut message = first.trim_start_matches("error: ").to_string();
    if let Some(values) = text.lines().find_map(|l| {
        l.trim()
            .strip_prefix("[possible values: ")
            .and_then(|v| v.strip_suffix(']'))
    }) {
        message.push_str(&format!(" (possible values: {values})"));
    }
    let help = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("tip: ").map(str::to_string))
        .unwrap_or_else(|| {
            let at = if command == "waters" {
                "rtpipe.waters".to_string()
            } else if command == "campaign" {
                "rtpipe.campaign".to_string()
            } else {
                format!("rtpipe.System.{command}")
            };
            format!("see help({at}) for the arguments and the values they take")
        });
    Diagnostic::error(message, help)
}

fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<String>()
        .cloned()
        .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "a panic without a message".into())
}
