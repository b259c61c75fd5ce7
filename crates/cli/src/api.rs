//! The entry points of the Python package (`crates/python`): a command on a
//! loaded spec, its flags given as on the command line (so they are
//! checked by the same parser, with the same messages), answering the JSON
//! of `--json`. Nothing here prints, reads a clock or catches a signal: the
//! caller owns the process (Python's SIGINT handler stays Python's).

use crate::command::{Call, Done, Hooks, Reach, Refusal, Rendered};
use crate::registry::{self, Commands};
use clap::{FromArgMatches, Subcommand};
use rtpipe_joblog::SampleRow;
use rtpipe_model::{Diagnostic, Spec};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The commands Python reaches (paths such as `import e2eeval`).
pub fn commands() -> Vec<&'static str> {
    registry::REACH
        .iter()
        .filter(|(_, r)| matches!(r, Reach::Python(_)))
        .map(|(path, _)| *path)
        .collect()
}

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
    /// The specs a command made (an import's, by name; a generated one).
    pub specs: Vec<(String, Spec)>,
    /// The text of the other files a command made, by file name (`import
    /// px4-ulog`'s `observed.csv`).
    pub files: Vec<(String, String)>,
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

/// Runs `command` (one of [`commands`]) on `spec`, read from `label` (a
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
    let argv: Vec<String> = std::iter::once(label.to_string())
        .chain(flags.iter().cloned())
        .collect();
    let call = Call {
        spec: Some(spec),
        text: None,
        hooks,
    };
    let done = guarded(&stop, || dispatch(command, &argv, call));
    if let (true, Some(most)) = (full.load(Ordering::Relaxed), samples) {
        return Err(Failure::TooManySamples(too_many_samples(most)));
    }
    let samples = samples.map(|_| {
        let taken = cols.lock().map(|mut g| std::mem::take(&mut *g));
        taken.unwrap_or_default().sorted()
    });
    Ok(reply(done?, samples))
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

/// Runs `command` without a spec (`campaign`, `import e2eeval`,
/// `generate waters`), with `flags` as the command line takes them
/// (`--json` implied where the command has it); `text` is the content of
/// the file the flags name, given in its place (an import's). `stop` ends
/// a long one early ([`Failure::Stopped`]).
pub fn run_plain(
    command: &str,
    flags: &[String],
    text: Option<&str>,
    stop: Arc<AtomicBool>,
) -> Result<Reply, Failure> {
    let call = Call {
        spec: None,
        text,
        hooks: Hooks {
            rows: None,
            stop: Some(Arc::clone(&stop)),
        },
    };
    let done = guarded(&stop, || dispatch(command, flags, call))?;
    Ok(reply(done, None))
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
    let stop = Arc::new(AtomicBool::new(false));
    let r = run_plain("generate waters", &argv, None, stop)?;
    r.specs
        .into_iter()
        .next()
        .map(|(_, s)| s)
        .ok_or_else(|| Failure::Internal("generate waters made no spec".into()))
}

fn reply(done: Done, samples: Option<Columns>) -> Reply {
    let Done {
        answer,
        mut specs,
        files,
    } = done;
    let designed = specs
        .iter()
        .position(|(name, _)| name == "designed")
        .map(|i| specs.remove(i).1);
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
        specs,
        files,
    }
}

/// The command at `path` (`analyze`, `import e2eeval`) with its arguments
/// `argv` parsed as the command line parses `rtpipe PATH ARGV...`
/// (`--json` added where the command has it), then called.
fn dispatch(path: &str, argv: &[String], call: Call) -> Result<Done, Failure> {
    if registry::reach(path).is_none() {
        let known: Vec<&str> = registry::REACH.iter().map(|(p, _)| *p).collect();
        return Err(Failure::Input(Diagnostic::error(
            format!("no command `{path}`"),
            format!("use one of {}", known.join(", ")),
        )));
    }
    let parsed = parse(path, argv)?;
    let command = parsed.registered();
    command.check(&call).map_err(Failure::Input)?;
    command.call(call).map_err(|d| match command.refusal() {
        Refusal::Input => Failure::Input(d),
        Refusal::Run => Failure::Run(d),
    })
}

/// Every flag of `command` (a path of [`commands`], such as `analyze` or
/// `generate waters`; `waters` is `generate waters`) and its help as
/// `rtpipe COMMAND --help` prints it (the long form), from the one
/// registration: what the Python functions' docstrings say of each
/// keyword. Empty for another name.
pub fn flag_help(command: &str) -> Vec<(String, String)> {
    let path = if command == "waters" {
        "generate waters"
    } else {
        command
    };
    let root = Commands::augment_subcommands(clap::Command::new("rtpipe"));
    let mut leaf = &root;
    for word in path.split(' ') {
        match leaf.find_subcommand(word) {
            Some(c) => leaf = c,
            None => return Vec::new(),
        }
    }
    leaf.get_arguments()
        .filter_map(|a| {
            let help = a.get_long_help().or_else(|| a.get_help())?.to_string();
            Some((a.get_long()?.to_string(), help))
        })
        .collect()
}

/// `argv` (the spec's label, then the flags) parsed as the command line
/// would parse `rtpipe PATH ...`, into the one registration's enum.
fn parse(path: &str, argv: &[String]) -> Result<Commands, Failure> {
    let cmd = Commands::augment_subcommands(clap::Command::new("rtpipe"))
        .no_binary_name(true)
        .disable_help_subcommand(true);
    let words: Vec<&str> = path.split(' ').collect();
    let mut leaf = &cmd;
    for w in &words {
        leaf = leaf
            .find_subcommand(w)
            .ok_or_else(|| Failure::Internal(format!("no subcommand {w} of {path}")))?;
    }
    let json = leaf.get_arguments().any(|a| a.get_id() == "json");
    let mut full: Vec<String> = words.iter().map(|w| w.to_string()).collect();
    full.extend(argv.iter().cloned());
    if json {
        full.push("--json".into());
    }
    let parsed = cmd
        .try_get_matches_from(full)
        .and_then(|m| Commands::from_arg_matches(&m));
    parsed.map_err(|e| Failure::Input(flag_error(&e, path)))
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
            let at = match registry::reach(command) {
                Some(Reach::Python(n)) if n.starts_with("System.") => format!("rtpipe.{n}"),
                Some(Reach::Python(n)) => n.to_string(),
                _ => "rtpipe".to_string(),
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
