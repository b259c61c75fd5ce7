//! `rtpipe import e2eeval FILE.yaml OUTDIR`: the task sets and cause-effect
//! chains of TU Dortmund's E2EEvaluation framework as rtpipe specs.
//!
//! The framework writes its chains with PyYAML (`utilities/yaml_export.py`):
//! a mapping with `Chains`, a list of chains each a list of `TaskID`s, and
//! `Tasks`, a list of `!Task` mappings (`TaskID`, `ECU`, `Period`, `Phase`,
//! `BCET`, `WCET`, `Priority`, `Deadline`, `MinIAT`, `MaxIAT`, `Jitter`,
//! `ReleasePattern`, `CommunicationPolicy`, ...) with times in ms as floats.
//! A chain is local to one ECU (one task set), or an interconnected chain:
//! local chains of several ECUs one after another.
//!
//! The mapping, and why:
//!
//! - One spec per ECU, `OUTDIR/<stem>-ecu<N>.toml`, with its local chains.
//!   ECUs joined by a chain go into ONE spec, each ECU a CPU (`cpu = k`, in
//!   ascending ECU order), named `<stem>-ecu<N>+<M>...toml`: rtpipe analyses a
//!   chain in one spec, and its bounds for a link between CPUs use only
//!   periods and response times (Davare's argument), which hold whatever
//!   the clocks of the two ECUs, as the framework's inter-ECU analyses
//!   assume. Such a spec gives no task an offset: the ECUs' clocks are not
//!   synchronised, so phases on different ECUs are not comparable, and an
//!   unknown offset keeps every bound valid for every phasing.
//! - Each task: `exec` = WCET, `exec_min` = BCET, `period` = Period,
//!   `offset` = Phase (single-ECU specs), a plain task (`server = "none"`,
//!   `budget` = WCET) whose output costs nothing (channel `mem`, size 0); each
//!   chain step is an edge (the consumer `reads` the producer), as the
//!   framework's implicit communication has no transfer cost.
//! - `scheduler = "rm"`, `schedulability = "rta"`. Tasks are declared in the
//!   file's `Priority` order (0 first, per ECU), so equal periods keep the
//!   file's order; rtpipe's priorities are rate monotonic, and when the
//!   file's are not, one warning names the inverted pairs.
//! - Times finer than 1 ns are rounded safely: WCET up, BCET down, periods
//!   and phases to the nearest nanosecond; one note on stderr counts them.
//! - What rtpipe cannot model is refused, naming the task: sporadic tasks
//!   whose inter-arrival time varies, LET or explicit communication,
//!   release jitter. A `Deadline` other than the period is ignored (rtpipe
//!   checks R ≤ T) with a warning.
//!
//! Every problem in the file is an error that names the file and the task
//! or chain, with exit status 2, and nothing is written: the whole file is
//! read and every spec built and parsed back before the first file is
//! written, and then all of them are written atomically.

use crate::output;
use crate::table::Table;
use crate::{EXIT_BAD_INPUT, EXIT_INTERNAL};
use rtpipe_model::{Chain, Channel, Nanos, SchedTest, Scheduler, Server, Spec, Task, TimeUnit};
use serde_yaml::{Mapping, Value};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The formats `rtpipe import` reads.
#[derive(clap::Subcommand)]
pub enum ImportCommand {
    /// Task sets and cause-effect chains written by TU Dortmund's
    /// E2EEvaluation framework (its cause_effect_chains.yaml): one spec per
    /// ECU, ECUs joined by a chain in one spec as CPUs.
    ///
    /// Exit status: 0 when every spec was written, 2 on bad input (the file,
    /// a task or chain rtpipe cannot model, the output directory; nothing is
    /// written then), 3 on an internal error.
    #[command(name = "e2eeval")]
    E2eeval {
        /// The YAML file (`Chains:` and `Tasks:` with `!Task` entries).
        file: PathBuf,
        /// The directory the specs are written to (created if missing);
        /// existing specs of the same names are replaced.
        outdir: PathBuf,
    },
}

/// Runs `rtpipe import`.
pub fn run(cmd: &ImportCommand) -> ExitCode {
    match cmd {
        ImportCommand::E2eeval { file, outdir } => match import_e2eeval(file, outdir) {
            Ok(()) => ExitCode::SUCCESS,
            Err(code) => code,
        },
    }
}

/// The largest file read: E2EEvaluation's files of a thousand task sets
/// are about 15 MiB.
const MAX_BYTES: u64 = 64 << 20;

/// A problem with the input, printed as `FILE: error: MSG` and a help line.
struct Bad {
    msg: String,
    help: String,
}

fn bad(msg: impl Into<String>, help: impl Into<String>) -> Bad {
    Bad {
        msg: msg.into(),
        help: help.into(),
    }
}

/// One `!Task`, its times in ns.
#[derive(Debug, Clone)]
struct E2eTask {
    id: i64,
    ecu: i64,
    /// Position in the file's `Tasks` list.
    index: usize,
    period: Nanos,
    wcet: Nanos,
    bcet: Nanos,
    /// `None` for a sporadic task (its phase is not fixed).
    phase: Option<Nanos>,
    priority: Option<i64>,
    /// The `Deadline` differs from the period (ignored, with a warning).
    deadline_differs: bool,
}

/// What reading the file found, and what it had to round.
struct E2eFile {
    tasks: Vec<E2eTask>,
    chains: Vec<Vec<i64>>,
    rounded: usize,
}

/// One spec to write: the ECUs it holds and its text.
struct Planned {
    ecus: Vec<i64>,
    path: PathBuf,
    text: String,
    tasks: usize,
    chains: usize,
}

fn import_e2eeval(file: &Path, outdir: &Path) -> Result<(), ExitCode> {
    let shown = file.display().to_string();
    let fail = |b: Bad| {
        eprintln!("{shown}: error: {}", b.msg);
        if !b.help.is_empty() {
            eprintln!("  = help: {}", b.help);
        }
        ExitCode::from(EXIT_BAD_INPUT)
    };
    let text = read_text(file).map_err(fail)?;
    let value = parse_yaml(&shown, &text)?;
    let parsed = read_file(&value).map_err(fail)?;
    let plans = plan_specs(&parsed, file, outdir).map_err(fail)?;
    verify(&plans)?;
    warn_about(&shown, &parsed);
    write_specs(&plans, outdir)?;
    print_summary(&shown, &parsed, &plans);
    Ok(())
}

/// The file as text, at most [`MAX_BYTES`].
fn read_text(file: &Path) -> Result<String, Bad> {
    use std::io::Read;
    let help = "give the cause_effect_chains.yaml that E2EEvaluation wrote";
    let f =
        std::fs::File::open(file).map_err(|e| bad(format!("cannot read the file: {e}"), help))?;
    if f.metadata().is_ok_and(|m| m.is_dir()) {
        return Err(bad("cannot read the file: it is a directory", help));
    }
    let mut bytes = Vec::new();
    f.take(MAX_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| bad(format!("cannot read the file: {e}"), help))?;
    if bytes.len() as u64 > MAX_BYTES {
        return Err(bad(
            format!(
                "the file is larger than {} MiB, the most rtpipe reads",
                MAX_BYTES >> 20
            ),
            "split the chains over several files",
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        bad(
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
            help,
        )
    })
}

/// The YAML document; a syntax error names its line and column.
fn parse_yaml(shown: &str, text: &str) -> Result<Value, ExitCode> {
    serde_yaml::from_str::<Value>(text).map_err(|e| {
        let at = e
            .location()
            .map(|l| format!(":{}:{}", l.line(), l.column()))
            .unwrap_or_default();
        eprintln!("{shown}{at}: error: not valid YAML: {e}");
        eprintln!(
            "  = help: E2EEvaluation writes `Chains:` and `Tasks:` (a list of `!Task {{...}}`)"
        );
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

/// `Tasks` and `Chains`, every task checked and every chain resolved.
fn read_file(v: &Value) -> Result<E2eFile, Bad> {
    let top = v.as_mapping().ok_or_else(|| {
        bad(
            "expected a mapping with `Tasks` and `Chains` at the top",
            "E2EEvaluation's export is `Chains: [[1, 2], ...]` and `Tasks: [!Task {...}, ...]`",
        )
    })?;
    let list = field(top, "Tasks")
        .and_then(Value::as_sequence)
        .ok_or_else(|| {
            bad(
                "no `Tasks` list",
                "the file needs `Tasks:` with one `!Task` per task",
            )
        })?;
    let mut rounded = 0;
    let mut tasks = Vec::with_capacity(list.len());
    for (k, t) in list.iter().enumerate() {
        tasks.push(read_task(t, k, &mut rounded)?);
    }
    check_unique(&tasks)?;
    let chains = read_chains(top, &tasks)?;
    Ok(E2eFile {
        tasks,
        chains,
        rounded,
    })
}

/// A key of a mapping, `null` counting as absent.
fn field<'a>(m: &'a Mapping, key: &str) -> Option<&'a Value> {
    m.get(key).filter(|v| !v.is_null())
}

/// `Tasks[k]`, or its task id once known, for messages.
fn task_place(k: usize, id: Option<i64>) -> String {
    match id {
        Some(id) => format!("task {id} (Tasks[{k}])"),
        None => format!("Tasks[{k}]"),
    }
}

/// The mapping of a `!Task` (an untagged mapping is accepted too).
fn task_mapping(v: &Value, k: usize) -> Result<&Mapping, Bad> {
    let inner = match v {
        Value::Tagged(t) if t.tag == "Task" => &t.value,
        Value::Tagged(t) => {
            return Err(bad(
                format!("{}: tagged {}, expected !Task", task_place(k, None), t.tag),
                "every entry of Tasks is a `!Task {...}`",
            ))
        }
        other => other,
    };
    inner.as_mapping().ok_or_else(|| {
        bad(
            format!(
                "{}: expected a `!Task {{...}}` mapping",
                task_place(k, None)
            ),
            "every entry of Tasks is a `!Task {TaskID: ..., ECU: ..., Period: ..., WCET: ...}`",
        )
    })
}

/// An integer field (`TaskID`, `ECU`, `Priority`); `None` when absent.
fn integer(m: &Mapping, key: &str, place: &str) -> Result<Option<i64>, Bad> {
    match field(m, key) {
        None => Ok(None),
        Some(v) => v.as_i64().map(Some).ok_or_else(|| {
            bad(
                format!("{place}: {key} must be an integer, found {}", show(v)),
                format!("write e.g. {key}: 3"),
            )
        }),
    }
}

/// A time field in ms; `None` when absent. Must be finite and not negative.
fn number(m: &Mapping, key: &str, place: &str) -> Result<Option<f64>, Bad> {
    let Some(v) = field(m, key) else {
        return Ok(None);
    };
    match v.as_f64() {
        Some(x) if x.is_finite() && x >= 0.0 => Ok(Some(x)),
        Some(x) if x < 0.0 => Err(bad(
            format!("{place}: {key} is negative ({})", show(v)),
            format!("times are in ms and at least 0; fix {key}"),
        )),
        _ => Err(bad(
            format!("{place}: {key} must be a number of ms, found {}", show(v)),
            format!("write e.g. {key}: 10.0"),
        )),
    }
}

/// A value in YAML's flow style, as the file writes it, for messages.
fn show(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("{s:?}"),
        Value::Sequence(items) => {
            let items: Vec<String> = items.iter().map(show).collect();
            format!("[{}]", items.join(", "))
        }
        Value::Mapping(_) => "a mapping".into(),
        Value::Tagged(t) => format!("{} {}", t.tag, show(&t.value)),
    }
}

/// A string field (`ReleasePattern`, `CommunicationPolicy`).
fn text<'a>(m: &'a Mapping, key: &str) -> Option<&'a str> {
    field(m, key).and_then(Value::as_str)
}

/// One `!Task`, checked: what rtpipe cannot model is an error.
fn read_task(v: &Value, k: usize, rounded: &mut usize) -> Result<E2eTask, Bad> {
    let m = task_mapping(v, k)?;
    let id = integer(m, "TaskID", &task_place(k, None))?.ok_or_else(|| {
        bad(
            format!("{}: no TaskID", task_place(k, None)),
            "give every task a TaskID",
        )
    })?;
    let place = task_place(k, Some(id));
    check_model(m, &place)?;
    let ecu = integer(m, "ECU", &place)?.ok_or_else(|| {
        bad(
            format!("{place}: no ECU"),
            "give every task the ECU it runs on, e.g. ECU: 0",
        )
    })?;
    let (period, phase) = release(m, &place, rounded)?;
    let (wcet, bcet) = exec_times(m, &place, period, rounded)?;
    Ok(E2eTask {
        id,
        ecu,
        index: k,
        period,
        wcet,
        bcet,
        phase,
        priority: integer(m, "Priority", &place)?,
        deadline_differs: number(m, "Deadline", &place)?
            .is_some_and(|d| to_ns(d, Round::Nearest).is_ok_and(|(d, _)| d != period)),
    })
}

/// Refuses what rtpipe's model lacks: LET or explicit communication and
/// release jitter.
fn check_model(m: &Mapping, place: &str) -> Result<(), Bad> {
    if let Some(c) = text(m, "CommunicationPolicy").filter(|&c| c != "implicit") {
        return Err(bad(
            format!("{place}: CommunicationPolicy {c} is not modelled"),
            "rtpipe's jobs read their inputs when they start and publish when they end (implicit communication)",
        ));
    }
    if number(m, "Jitter", place)?.is_some_and(|j| j > 0.0) {
        return Err(bad(
            format!("{place}: release jitter is not modelled"),
            "rtpipe releases every job exactly a period after the last; give Jitter: 0",
        ));
    }
    Ok(())
}

/// The period and phase (ns). A sporadic task is accepted only when its
/// inter-arrival time is fixed (MinIAT = MaxIAT), as a periodic task of
/// unknown phase.
fn release(m: &Mapping, place: &str, rounded: &mut usize) -> Result<(Nanos, Option<Nanos>), Bad> {
    let sporadic = text(m, "ReleasePattern") == Some("sporadic");
    let period = if sporadic {
        fixed_iat(m, place)?
    } else {
        number(m, "Period", place)?.ok_or_else(|| {
            bad(
                format!("{place}: no Period"),
                "give the period in ms, e.g. Period: 10",
            )
        })?
    };
    let period = time(period, Round::Nearest, "Period", place, rounded)?;
    if period == 0 {
        return Err(bad(
            format!("{place}: Period is 0"),
            "periods are positive (ms)",
        ));
    }
    if sporadic {
        return Ok((period, None));
    }
    let phase = number(m, "Phase", place)?.unwrap_or(0.0);
    let phase = time(phase, Round::Nearest, "Phase", place, rounded)?;
    if phase >= period {
        return Err(bad(
            format!("{place}: Phase is not below Period"),
            "a task released a period or more late has no job in its first periods, which rtpipe does not model; give a Phase below the Period",
        ));
    }
    Ok((period, Some(phase)))
}

/// A sporadic task's inter-arrival time, which must not vary.
fn fixed_iat(m: &Mapping, place: &str) -> Result<f64, Bad> {
    match (number(m, "MinIAT", place)?, number(m, "MaxIAT", place)?) {
        (Some(a), Some(b)) if a == b => Ok(a),
        _ => Err(bad(
            format!("{place}: a sporadic task whose inter-arrival time varies is not modelled"),
            "rtpipe's tasks are periodic; a sporadic task is read only with MinIAT = MaxIAT",
        )),
    }
}

/// WCET (rounded up) and BCET (rounded down), checked against each other
/// and the period.
fn exec_times(
    m: &Mapping,
    place: &str,
    period: Nanos,
    rounded: &mut usize,
) -> Result<(Nanos, Nanos), Bad> {
    let w = number(m, "WCET", place)?.ok_or_else(|| {
        bad(
            format!("{place}: no WCET"),
            "give the worst-case execution time in ms",
        )
    })?;
    let b = number(m, "BCET", place)?.unwrap_or(0.0);
    let wcet = time(w, Round::Up, "WCET", place, rounded)?;
    let bcet = time(b, Round::Down, "BCET", place, rounded)?;
    if wcet == 0 {
        return Err(bad(
            format!("{place}: WCET is 0"),
            "execution times are positive",
        ));
    }
    if b > w {
        return Err(bad(
            format!("{place}: BCET {b} ms is larger than WCET {w} ms"),
            "the best case is at most the worst case",
        ));
    }
    if wcet > period {
        return Err(bad(
            format!(
                "{place}: WCET {w} ms is larger than its Period {} ms",
                fmt_ms(period)
            ),
            "a task needs WCET ≤ Period to be schedulable at all",
        ));
    }
    Ok((wcet, bcet))
}

/// How a time finer than 1 ns is rounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Round {
    Up,
    Down,
    Nearest,
}

/// A time in ms (as the file's float) in whole ns, counting it when it had
/// to be rounded.
fn time(ms: f64, r: Round, key: &str, place: &str, rounded: &mut usize) -> Result<Nanos, Bad> {
    let (ns, inexact) =
        to_ns(ms, r).map_err(|e| bad(format!("{place}: {key} {e}"), "times are in ms"))?;
    *rounded += usize::from(inexact);
    Ok(ns)
}

/// ms → ns exactly: the float's shortest decimal form (the digits PyYAML
/// wrote) is shifted by six places, so 0.3 ms is 300000 ns, not the
/// 300000.00000000006 of a binary multiplication. Returns whether digits
/// below 1 ns were rounded away.
fn to_ns(ms: f64, r: Round) -> Result<(Nanos, bool), String> {
    let s = format!("{ms}");
    let (int, frac) = s.split_once('.').unwrap_or((&s, ""));
    let too_large = || format!("{ms} ms is larger than rtpipe's largest time (about 106 days)");
    if int.len() > 12 {
        return Err(too_large());
    }
    let (ns_digits, rest) = frac.split_at(frac.len().min(6));
    let whole: i128 = format!("{int}{ns_digits:0<6}")
        .parse()
        .map_err(|_| format!("{s} is not a time"))?;
    let inexact = rest.bytes().any(|b| b != b'0');
    let up = match r {
        Round::Up => inexact,
        Round::Down => false,
        Round::Nearest => rest.as_bytes().first().is_some_and(|&b| b >= b'5'),
    };
    let ns = whole + i128::from(up);
    if ns > rtpipe_model::MAX_TIME as i128 {
        return Err(too_large());
    }
    Ok((ns as Nanos, inexact))
}

/// A time in ms as rtpipe writes it.
fn fmt_ms(ns: Nanos) -> String {
    rtpipe_model::format_in(ns, TimeUnit::Ms)
}

/// Every TaskID once.
fn check_unique(tasks: &[E2eTask]) -> Result<(), Bad> {
    let mut seen: HashMap<i64, usize> = HashMap::new();
    for t in tasks {
        if let Some(first) = seen.insert(t.id, t.index) {
            return Err(bad(
                format!(
                    "TaskID {} appears twice (Tasks[{first}] and Tasks[{}])",
                    t.id, t.index
                ),
                "chains name tasks by TaskID, so each must be unique",
            ));
        }
    }
    Ok(())
}

/// `Chains`: lists of known TaskIDs, no task twice in a row.
fn read_chains(top: &Mapping, tasks: &[E2eTask]) -> Result<Vec<Vec<i64>>, Bad> {
    let Some(list) = field(top, "Chains") else {
        return Ok(Vec::new());
    };
    let list = list
        .as_sequence()
        .ok_or_else(|| bad("`Chains` is not a list", "write Chains: [[1, 2, 3], ...]"))?;
    let known: HashMap<i64, usize> = tasks.iter().map(|t| (t.id, t.index)).collect();
    list.iter()
        .enumerate()
        .map(|(k, c)| read_chain(c, k, &known))
        .collect()
}

/// One chain, `Chains[k]`.
fn read_chain(c: &Value, k: usize, known: &HashMap<i64, usize>) -> Result<Vec<i64>, Bad> {
    let place = format!("chain Chains[{k}]");
    let ids: Option<Vec<i64>> = c
        .as_sequence()
        .map(|s| s.iter().map(Value::as_i64).collect::<Option<Vec<_>>>())
        .unwrap_or(None);
    let ids = ids.ok_or_else(|| {
        bad(
            format!("{place} = {}: expected a list of TaskIDs", show(c)),
            "a chain lists the TaskIDs of its tasks, e.g. [12, 7, 30]",
        )
    })?;
    if ids.is_empty() {
        return Err(bad(
            format!("{place} is empty"),
            "a chain lists at least one task",
        ));
    }
    if let Some(id) = ids.iter().find(|id| !known.contains_key(id)) {
        return Err(bad(
            format!("{place} = {}: no task has TaskID {id}", show(c)),
            "every TaskID of a chain must be in Tasks",
        ));
    }
    if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
        return Err(bad(
            format!("{place} = {}: task {} follows itself", show(c), w[0]),
            "a chain step joins two different tasks",
        ));
    }
    Ok(ids)
}

/// The groups of ECUs joined by chains (a union–find over ECUs), each in
/// ascending order, the groups ordered by their first ECU.
fn ecu_groups(f: &E2eFile) -> Vec<Vec<i64>> {
    let ecu_of: HashMap<i64, i64> = f.tasks.iter().map(|t| (t.id, t.ecu)).collect();
    let mut parent: BTreeMap<i64, i64> = f.tasks.iter().map(|t| (t.ecu, t.ecu)).collect();
    fn root(p: &BTreeMap<i64, i64>, mut x: i64) -> i64 {
        while let Some(&up) = p.get(&x).filter(|&&up| up != x) {
            x = up;
        }
        x
    }
    for c in &f.chains {
        for w in c.windows(2) {
            let (Some(&x), Some(&y)) = (ecu_of.get(&w[0]), ecu_of.get(&w[1])) else {
                continue;
            };
            let (a, b) = (root(&parent, x), root(&parent, y));
            parent.insert(a.max(b), a.min(b));
        }
    }
    let mut groups: BTreeMap<i64, Vec<i64>> = BTreeMap::new();
    let ecus: Vec<i64> = parent.keys().copied().collect();
    for e in ecus {
        let r = root(&parent, e);
        groups.entry(r).or_default().push(e);
    }
    groups.into_values().collect()
}

/// Every spec built and written to text; nothing is written to disk.
fn plan_specs(f: &E2eFile, file: &Path, outdir: &Path) -> Result<Vec<Planned>, Bad> {
    if f.tasks.is_empty() {
        return Err(bad("`Tasks` is empty", "the file needs at least one task"));
    }
    let stem = file_stem(file);
    let source = file
        .file_name()
        .map_or_else(|| stem.clone(), |n| n.to_string_lossy().into_owned());
    let mut plans = Vec::new();
    for ecus in ecu_groups(f) {
        if ecus.len() > 1024 {
            return Err(bad(
                format!(
                    "{} ECUs are joined by chains; rtpipe's specs have at most 1024 CPUs",
                    ecus.len()
                ),
                "split the interconnected chains over several files",
            ));
        }
        let name = spec_name(&stem, &ecus);
        let spec = build_spec(f, &ecus, &name);
        let text = format!("{}{}", header(&source, &ecus), rtpipe_model::to_toml(&spec));
        plans.push(Planned {
            path: outdir.join(format!("{name}.toml")),
            tasks: spec.tasks.len(),
            chains: spec.chains.len(),
            ecus,
            text,
        });
    }
    Ok(plans)
}

/// Every spec text parses as it will be read (a failure is a bug: exit 3).
fn verify(plans: &[Planned]) -> Result<(), ExitCode> {
    for p in plans {
        if let Err(e) = Spec::parse(&p.path.display().to_string(), &p.text) {
            eprint!("{e}");
            eprintln!("error: internal error: the spec written for ECU {} does not parse; please report it with the file", p.ecus[0]);
            return Err(ExitCode::from(EXIT_INTERNAL));
        }
    }
    Ok(())
}

/// `<stem>-ecu<N>`, or `<stem>-ecu<N>+<M>...` for ECUs joined by chains
/// (`<stem>-ecu<N>-and-<k>-more` when that gets long).
fn spec_name(stem: &str, ecus: &[i64]) -> String {
    let joined: Vec<String> = ecus.iter().map(i64::to_string).collect();
    let name = format!("{stem}-ecu{}", joined.join("+"));
    if name.len() <= 120 {
        name
    } else {
        format!("{stem}-ecu{}-and-{}-more", ecus[0], ecus.len() - 1)
    }
}

/// Comment lines that say where the spec came from and how ECUs map to CPUs.
fn header(source: &str, ecus: &[i64]) -> String {
    let mut h = format!(
        "# Imported by `rtpipe import e2eeval` from {source} (E2EEvaluation): task tN is TaskID N,\n\
         # exec = WCET, exec_min = BCET, times in ms, declared in the file's priority order.\n"
    );
    if ecus.len() > 1 {
        let map: Vec<String> = ecus
            .iter()
            .enumerate()
            .map(|(k, e)| format!("ECU {e} = cpu {k}"))
            .collect();
        let _ = writeln!(
            h,
            "# ECUs joined by chains, one CPU each: {}.",
            map.join(", ")
        );
        h.push_str("# No offsets: the ECUs' clocks are not synchronised, so the bounds hold for every phasing.\n");
    }
    h.push('\n');
    h
}

/// The tasks of these ECUs in declaration order: by ECU, then the file's
/// priority (0 first; none given: last), then the file's order.
fn ordered<'a>(f: &'a E2eFile, ecus: &[i64]) -> Vec<&'a E2eTask> {
    let mut ts: Vec<&E2eTask> = f.tasks.iter().filter(|t| ecus.contains(&t.ecu)).collect();
    ts.sort_by_key(|t| (t.ecu, t.priority.unwrap_or(i64::MAX), t.index));
    ts
}

/// The spec of one group of ECUs (see the module documentation).
fn build_spec(f: &E2eFile, ecus: &[i64], name: &str) -> Spec {
    let ts = ordered(f, ecus);
    let at: HashMap<i64, usize> = ts.iter().enumerate().map(|(k, t)| (t.id, k)).collect();
    let one_ecu = ecus.len() == 1;
    let mut tasks: Vec<Task> = ts
        .iter()
        .map(|t| Task {
            name: format!("t{}", t.id),
            exec_min: t.bcet,
            budget_given: Some(t.wcet),
            server: Server::None,
            cpu: ecus.iter().position(|&e| e == t.ecu).unwrap_or(0) as u32,
            offset: if one_ecu { t.phase } else { None },
            ..Task::periodic(t.wcet, t.period)
        })
        .collect();
    let mut chains = Vec::new();
    for c in &f.chains {
        // Every TaskID is known (read_chains) and a chain's ECUs are in one
        // group, so a chain is either wholly in this spec or not at all.
        let Some(path) = c
            .iter()
            .map(|id| at.get(id).copied())
            .collect::<Option<Vec<usize>>>()
        else {
            continue;
        };
        chains.push(Chain::linked(&mut tasks, path));
    }
    Spec {
        name: name.to_string(),
        time_unit: TimeUnit::Ms,
        scheduler: Scheduler::Rm,
        schedulability: SchedTest::Rta,
        resolution: 1_000_000,
        harmonic: false,
        channels: vec![Channel {
            name: "mem".into(),
            bandwidth: 1.0,
            overhead: 0,
        }],
        tasks,
        chains,
    }
}

/// The file name without its extension (`cause_effect_chains`).
fn file_stem(file: &Path) -> String {
    file.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "e2eeval".into())
}

/// Pairs of one ECU, in the file's priority order, where the higher-priority
/// task has the longer period.
fn inversions(f: &E2eFile) -> Vec<String> {
    let mut by_ecu: BTreeMap<i64, Vec<&E2eTask>> = BTreeMap::new();
    for t in f.tasks.iter().filter(|t| t.priority.is_some()) {
        by_ecu.entry(t.ecu).or_default().push(t);
    }
    let mut out = Vec::new();
    for (ecu, mut ts) in by_ecu {
        ts.sort_by_key(|t| (t.priority, t.index));
        for w in ts.windows(2).filter(|w| w[0].period > w[1].period) {
            out.push(format!(
                "t{} ({} ms) above t{} ({} ms) on ECU {ecu}",
                w[0].id,
                fmt_ms(w[0].period),
                w[1].id,
                fmt_ms(w[1].period)
            ));
        }
    }
    out
}

/// "s" unless one.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// Up to five items, then how many more.
fn some_of(items: &[String]) -> String {
    let mut s = items.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
    if items.len() > 5 {
        let _ = write!(s, " and {} more", items.len() - 5);
    }
    s
}

/// The one-line notes: rounding, priorities, deadlines.
fn warn_about(shown: &str, f: &E2eFile) {
    if f.rounded > 0 {
        eprintln!(
            "{shown}: note: {} time{} finer than 1 ns rounded (WCET up, BCET down, periods and phases to the nearest ns)",
            f.rounded,
            plural(f.rounded)
        );
    }
    let inv = inversions(f);
    if !inv.is_empty() {
        eprintln!(
            "{shown}: warning: the file's priorities are not rate monotonic ({}); rtpipe analyses the rate-monotonic schedule (shorter period first, equal periods in the file's order)",
            some_of(&inv)
        );
    }
    let dl: Vec<String> = f
        .tasks
        .iter()
        .filter(|t| t.deadline_differs)
        .map(|t| format!("t{}", t.id))
        .collect();
    if !dl.is_empty() {
        eprintln!(
            "{shown}: warning: Deadline differs from Period for {}; ignored: rtpipe's schedulability test checks R ≤ T",
            some_of(&dl)
        );
    }
}

/// Creates OUTDIR and writes every spec atomically (all or none).
fn write_specs(plans: &[Planned], outdir: &Path) -> Result<(), ExitCode> {
    let fail = |msg: String, help: &str| {
        eprintln!("error: {msg}");
        eprintln!("  = help: {help}");
        ExitCode::from(EXIT_BAD_INPUT)
    };
    if outdir.exists() && !outdir.is_dir() {
        return Err(fail(
            format!("OUTDIR {} is not a directory", outdir.display()),
            "give a directory for the specs",
        ));
    }
    std::fs::create_dir_all(outdir).map_err(|e| {
        fail(
            format!("OUTDIR {}: cannot create it: {e}", outdir.display()),
            "check the path and its permissions",
        )
    })?;
    let mut outs = Vec::new();
    for p in plans {
        let o = output::prepare("OUTDIR", &p.path, Path::new(""), None).map_err(|e| {
            eprint!("{e}");
            ExitCode::from(EXIT_BAD_INPUT)
        })?;
        outs.push(o);
    }
    let files: Vec<(&output::Output, &str)> = outs
        .iter()
        .zip(plans)
        .map(|(o, p)| (o, p.text.as_str()))
        .collect();
    output::write_all(&files).map_err(|e| {
        eprint!("{e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

/// What was written: one row per spec.
fn print_summary(shown: &str, f: &E2eFile, plans: &[Planned]) {
    let ecus: std::collections::BTreeSet<i64> = f.tasks.iter().map(|t| t.ecu).collect();
    println!(
        "imported {shown} (E2EEvaluation): {} task{} on {} ECU{}, {} chain{}; times in ms",
        f.tasks.len(),
        plural(f.tasks.len()),
        ecus.len(),
        plural(ecus.len()),
        f.chains.len(),
        plural(f.chains.len()),
    );
    println!();
    let mut t = Table::new(&["file", "ECUs", "tasks", "chains"]).numeric(&[2, 3]);
    for p in plans {
        let e: Vec<String> = p.ecus.iter().map(i64::to_string).collect();
        t.row(vec![
            p.path.display().to_string(),
            e.join("+"),
            p.tasks.to_string(),
            p.chains.to_string(),
        ]);
    }
    print!("{}", t.render());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ms_to_ns_is_exact_on_decimals_and_rounds_safely() {
        assert_eq!(to_ns(0.3, Round::Up), Ok((300_000, false)));
        assert_eq!(to_ns(5.0, Round::Up), Ok((5_000_000, false)));
        assert_eq!(to_ns(1e-7, Round::Up), Ok((1, true)));
        assert_eq!(to_ns(1e-7, Round::Down), Ok((0, true)));
        assert_eq!(to_ns(1e-7, Round::Nearest), Ok((0, true)));
        assert_eq!(to_ns(0.0000005, Round::Nearest), Ok((1, true)));
        assert_eq!(to_ns(0.00123456789, Round::Up), Ok((1235, true)));
        assert_eq!(to_ns(0.00123456789, Round::Down), Ok((1234, true)));
        assert_eq!(to_ns(12.000001, Round::Down), Ok((12_000_001, false)));
        assert!(to_ns(1e300, Round::Up).is_err());
    }
}
