//! The task sets and cause-effect chains of TU Dortmund's E2EEvaluation
//! framework as rtpipe specs (`rtpipe import e2eeval FILE.yaml OUTDIR`).
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
//! Every problem in the file is a [`Diagnostic`] that names the task or
//! chain; nothing here writes a file, so a caller can build every spec
//! before it writes the first.

mod id;
mod read;

use crate::{
    to_toml, Chain, Channel, Diagnostic, SchedTest, Scheduler, Server, Spec, Task, TimeUnit,
};
use id::Id;
use read::{fmt_ms, E2eFile, E2eTask};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::path::Path;

/// The largest file read: E2EEvaluation's files of a thousand task sets
/// are about 15 MiB.
pub const MAX_BYTES: u64 = 64 << 20;

/// A problem with the file: what is wrong and how to fix it, and for a
/// YAML syntax error where (1-based line and column, as the YAML parser
/// counts them; they are not byte offsets, so not a [`Diagnostic`] span).
#[derive(Debug, Clone, PartialEq)]
pub struct ImportError {
    /// Line and column of a syntax error.
    pub at: Option<(usize, usize)>,
    /// What is wrong and how to fix it.
    pub diagnostic: Diagnostic,
}

impl From<Diagnostic> for ImportError {
    fn from(diagnostic: Diagnostic) -> Self {
        ImportError {
            at: None,
            diagnostic,
        }
    }
}

/// A file's specs, built and written to text, and what the file held.
#[derive(Debug, Clone)]
pub struct Import {
    /// One spec per group of ECUs joined by chains.
    pub specs: Vec<ImportedSpec>,
    /// Tasks in the file.
    pub tasks: usize,
    /// Distinct ECUs in the file.
    pub ecus: usize,
    /// Chains in the file.
    pub chains: usize,
    /// What the user should know: rounding, priorities, deadlines.
    pub notes: Vec<Note>,
}

/// One spec of an [`Import`].
#[derive(Debug, Clone)]
pub struct ImportedSpec {
    /// The ECU ids it holds (decimal, of any size), ascending (ECU
    /// `ecus[k]` is `cpu = k`).
    pub ecus: Vec<String>,
    /// Its name, also the file name without `.toml`.
    pub name: String,
    /// The spec as TOML, with comment lines saying where it came from.
    pub text: String,
    /// Its tasks.
    pub tasks: usize,
    /// Its chains.
    pub chains: usize,
}

/// A remark about an import that does not stop it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Note {
    /// `"note"` (rtpipe changed something harmlessly) or `"warning"` (it
    /// analyses something other than what the file says).
    pub level: &'static str,
    /// The remark, one line.
    pub message: String,
}

/// Reads `file` (at most [`MAX_BYTES`]) and builds its specs.
pub fn load(file: &Path) -> Result<Import, ImportError> {
    let text = read::read_text(file)?;
    import(file, &text)
}

/// Builds the specs of `text`, the content of `file` (whose name goes into
/// the specs' names and comments).
pub fn import(file: &Path, text: &str) -> Result<Import, ImportError> {
    let value = read::parse_yaml(text)?;
    let parsed = read::read_file(&value)?;
    let specs = plan_specs(&parsed, file)?;
    Ok(Import {
        specs,
        tasks: parsed.tasks.len(),
        ecus: parsed
            .tasks
            .iter()
            .map(|t| &t.ecu)
            .collect::<BTreeSet<_>>()
            .len(),
        chains: parsed.chains.len(),
        notes: notes(&parsed),
    })
}

/// The groups of ECUs joined by chains (a union–find over ECUs), each in
/// ascending order, the groups ordered by their first ECU.
fn ecu_groups(f: &E2eFile) -> Vec<Vec<Id>> {
    let ecu_of: HashMap<&Id, &Id> = f.tasks.iter().map(|t| (&t.id, &t.ecu)).collect();
    let mut parent: BTreeMap<&Id, &Id> = f.tasks.iter().map(|t| (&t.ecu, &t.ecu)).collect();
    fn root<'a>(p: &BTreeMap<&'a Id, &'a Id>, mut x: &'a Id) -> &'a Id {
        while let Some(&up) = p.get(x).filter(|&&up| up != x) {
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
    let mut groups: BTreeMap<&Id, Vec<Id>> = BTreeMap::new();
    let ecus: Vec<&Id> = parent.keys().copied().collect();
    for e in ecus {
        let r = root(&parent, e);
        groups.entry(r).or_default().push(e.clone());
    }
    groups.into_values().collect()
}

/// Every spec built and written to text; nothing is written to disk.
fn plan_specs(f: &E2eFile, file: &Path) -> Result<Vec<ImportedSpec>, Diagnostic> {
    if f.tasks.is_empty() {
        return Err(Diagnostic::error(
            "`Tasks` is empty",
            "the file needs at least one task",
        ));
    }
    let stem = file_stem(file);
    let source = file
        .file_name()
        .map_or_else(|| stem.clone(), |n| n.to_string_lossy().into_owned());
    let mut plans = Vec::new();
    for ecus in ecu_groups(f) {
        if ecus.len() > 1024 {
            return Err(Diagnostic::error(
                format!(
                    "{} ECUs are joined by chains; rtpipe's specs have at most 1024 CPUs",
                    ecus.len()
                ),
                "split the interconnected chains over several files",
            ));
        }
        let name = spec_name(&stem, &ecus);
        let spec = build_spec(f, &ecus, &name);
        let text = format!("{}{}", header(&source, &ecus), to_toml(&spec));
        plans.push(ImportedSpec {
            name,
            tasks: spec.tasks.len(),
            chains: spec.chains.len(),
            ecus: ecus.iter().map(Id::to_string).collect(),
            text,
        });
    }
    Ok(plans)
}

/// `<stem>-ecu<N>`, or `<stem>-ecu<N>+<M>...` for ECUs joined by chains
/// (`<stem>-ecu<N>-and-<k>-more` when that gets long).
fn spec_name(stem: &str, ecus: &[Id]) -> String {
    let joined: Vec<String> = ecus.iter().map(Id::to_string).collect();
    let name = format!("{stem}-ecu{}", joined.join("+"));
    if name.len() <= 120 {
        name
    } else {
        format!("{stem}-ecu{}-and-{}-more", ecus[0], ecus.len() - 1)
    }
}

/// Comment lines that say where the spec came from and how ECUs map to CPUs.
fn header(source: &str, ecus: &[Id]) -> String {
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
fn ordered<'a>(f: &'a E2eFile, ecus: &[Id]) -> Vec<&'a E2eTask> {
    let mut ts: Vec<&E2eTask> = f.tasks.iter().filter(|t| ecus.contains(&t.ecu)).collect();
    ts.sort_by(|a, b| {
        let key = |t: &E2eTask| (t.priority.unwrap_or(i64::MAX), t.index);
        a.ecu.cmp(&b.ecu).then(key(a).cmp(&key(b)))
    });
    ts
}

/// The spec of one group of ECUs (see the module documentation).
fn build_spec(f: &E2eFile, ecus: &[Id], name: &str) -> Spec {
    let ts = ordered(f, ecus);
    let at: HashMap<&Id, usize> = ts.iter().enumerate().map(|(k, t)| (&t.id, k)).collect();
    let one_ecu = ecus.len() == 1;
    let mut tasks: Vec<Task> = ts
        .iter()
        .map(|t| Task {
            name: format!("t{}", t.id),
            exec_min: t.bcet,
            budget_given: Some(t.wcet),
            server: Server::None,
            cpu: ecus.iter().position(|e| *e == t.ecu).unwrap_or(0) as u32,
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
        priorities: crate::Priorities::RateMonotonic,
        communication: crate::Communication::Implicit,
        resource_protocol: crate::ResourceProtocol::Pcp,
        resources: Vec::new(),
        overheads: crate::Overheads::default(),
        channels: vec![Channel {
            name: "mem".into(),
            bandwidth: 1.0,
            overhead: 0,
        }],
        threads: Vec::new(),
        tasks,
        chains,
    }
}

/// The most bytes of the file's stem a spec's name takes: with `-ecu<N>`
/// and `.toml` the written file's name stays far within the 255 bytes a
/// file name may have, whatever the YAML file is called.
const MAX_STEM_BYTES: usize = 100;

/// The file name without its extension (`cause_effect_chains`), cut to
/// [`MAX_STEM_BYTES`] on a character boundary.
fn file_stem(file: &Path) -> String {
    let stem = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "e2eeval".into());
    let mut cut = stem.len().min(MAX_STEM_BYTES);
    while !stem.is_char_boundary(cut) {
        cut -= 1;
    }
    stem[..cut].to_string()
}

/// Pairs of one ECU, in the file's priority order, where the higher-priority
/// task has the longer period.
fn inversions(f: &E2eFile) -> Vec<String> {
    let mut by_ecu: BTreeMap<&Id, Vec<&E2eTask>> = BTreeMap::new();
    for t in f.tasks.iter().filter(|t| t.priority.is_some()) {
        by_ecu.entry(&t.ecu).or_default().push(t);
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
fn notes(f: &E2eFile) -> Vec<Note> {
    let mut out = Vec::new();
    if f.rounded > 0 {
        out.push(Note {
            level: "note",
            message: format!(
                "{} time{} finer than 1 ns rounded (WCET up, BCET down, periods and phases to the nearest ns)",
                f.rounded,
                plural(f.rounded)
            ),
        });
    }
    let inv = inversions(f);
    if !inv.is_empty() {
        out.push(Note {
            level: "warning",
            message: format!(
                "the file's priorities are not rate monotonic ({}); rtpipe analyses the rate-monotonic schedule (shorter period first, equal periods in the file's order)",
                some_of(&inv)
            ),
        });
    }
    let dl: Vec<String> = f
        .tasks
        .iter()
        .filter(|t| t.deadline_differs)
        .map(|t| format!("t{}", t.id))
        .collect();
    if !dl.is_empty() {
        out.push(Note {
            level: "warning",
            message: format!(
                "Deadline differs from Period for {}; ignored: rtpipe's schedulability test checks R ≤ T",
                some_of(&dl)
            ),
        });
    }
    out
}
