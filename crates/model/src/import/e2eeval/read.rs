//! Reading the YAML: the file's text, its `Tasks` (each checked against
//! what rtpipe can model, times in whole ns) and its `Chains`.

use super::id::{quote_big_integers, Id, MAX_ID_DIGITS};
use super::{ImportError, MAX_BYTES};
use crate::input::{self, Kind, Syntax};
use crate::{format_in, Diagnostic, Nanos, TimeUnit, MAX_TIME};
use serde_yaml::{Mapping, Value};
use std::collections::HashMap;
use std::path::Path;

/// A problem with the input: what is wrong and how to fix it.
fn bad(msg: impl Into<String>, help: impl Into<String>) -> Diagnostic {
    Diagnostic::error(msg, help)
}

/// One `!Task`, its times in ns.
#[derive(Debug, Clone)]
pub(super) struct E2eTask {
    pub(super) id: Id,
    pub(super) ecu: Id,
    /// Position in the file's `Tasks` list.
    pub(super) index: usize,
    pub(super) period: Nanos,
    pub(super) wcet: Nanos,
    pub(super) bcet: Nanos,
    /// `None` for a sporadic task (its phase is not fixed).
    pub(super) phase: Option<Nanos>,
    pub(super) priority: Option<i64>,
    /// The `Deadline` differs from the period (ignored, with a warning).
    pub(super) deadline_differs: bool,
}

/// What reading the file found, and what it had to round.
pub(super) struct E2eFile {
    pub(super) tasks: Vec<E2eTask>,
    pub(super) chains: Vec<Vec<Id>>,
    pub(super) rounded: usize,
}

/// The file as text, at most [`MAX_BYTES`], by the rules of every input
/// file ([`crate::input`]: UTF-8, no control characters, nesting bounded
/// before the YAML parser sees it).
pub(super) fn read_text(file: &Path) -> Result<String, ImportError> {
    let kind = Kind {
        name: "file",
        max_bytes: MAX_BYTES,
        syntax: Syntax::Yaml,
        help: "give the cause_effect_chains.yaml that E2EEvaluation wrote",
    };
    input::read_text(file, &kind).map_err(|e| {
        let d = e.diagnostics.into_iter().next();
        let at = d
            .as_ref()
            .and_then(|d| d.span.clone())
            .map(|s| crate::line_col(&e.source, s.start));
        let mut diagnostic = d.unwrap_or_else(|| bad("cannot read the file", kind.help));
        diagnostic.span = None;
        if diagnostic.message.contains("larger than") {
            diagnostic.help = Some("split the chains over several files".into());
        }
        ImportError { at, diagnostic }
    })
}

/// The YAML document; a syntax error names its line and column (as the
/// YAML parser counts them, on a line with an id of 19 digits or more a
/// column later per such id: they are quoted first, see [`Id`]).
pub(super) fn parse_yaml(text: &str) -> Result<Value, ImportError> {
    serde_yaml::from_str::<Value>(&quote_big_integers(text)).map_err(|e| ImportError {
        at: e.location().map(|l| (l.line(), l.column())),
        diagnostic: bad(
            format!("not valid YAML: {e}"),
            "E2EEvaluation writes `Chains:` and `Tasks:` (a list of `!Task {...}`)",
        ),
    })
}

/// `Tasks` and `Chains`, every task checked and every chain resolved.
pub(super) fn read_file(v: &Value) -> Result<E2eFile, Diagnostic> {
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
fn task_place(k: usize, id: Option<&Id>) -> String {
    match id {
        Some(id) => format!("task {id} (Tasks[{k}])"),
        None => format!("Tasks[{k}]"),
    }
}

/// The mapping of a `!Task` (an untagged mapping is accepted too).
fn task_mapping(v: &Value, k: usize) -> Result<&Mapping, Diagnostic> {
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

/// An id field (`TaskID`, `ECU`): an integer of any size; `None` when
/// absent.
fn id_field(m: &Mapping, key: &str, place: &str) -> Result<Option<Id>, Diagnostic> {
    match field(m, key) {
        None => Ok(None),
        Some(v) => match Id::of(v) {
            None => Err(bad(
                format!("{place}: {key} must be an integer, found {}", show(v)),
                format!("write e.g. {key}: 3"),
            )),
            Some(id) if id.digits() > MAX_ID_DIGITS => Err(bad(
                format!(
                    "{place}: {key} {} has {} digits, more than the {MAX_ID_DIGITS} rtpipe takes (its tasks and specs are named after it)",
                    show(v),
                    id.digits()
                ),
                format!("renumber it with at most {MAX_ID_DIGITS} digits"),
            )),
            Some(id) => Ok(Some(id)),
        },
    }
}

/// An integer field (`Priority`); `None` when absent.
fn integer(m: &Mapping, key: &str, place: &str) -> Result<Option<i64>, Diagnostic> {
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
fn number(m: &Mapping, key: &str, place: &str) -> Result<Option<f64>, Diagnostic> {
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

/// The longest value shown in a message, in characters.
const MAX_SHOWN_CHARS: usize = 80;

/// A value in YAML's flow style, as the file writes it, for messages; a
/// long one is cut in the middle (a 5-million-digit id would fill the
/// terminal), saying how long it is.
fn show(v: &Value) -> String {
    cut(show_whole(v))
}

/// Text for a message, cut in the middle when longer than
/// [`MAX_SHOWN_CHARS`], saying how long it is.
fn cut(s: String) -> String {
    let n = s.chars().count();
    if n <= MAX_SHOWN_CHARS {
        return s;
    }
    let head: String = s.chars().take(MAX_SHOWN_CHARS - 20).collect();
    let tail: String = s.chars().skip(n - 10).collect();
    format!("{head}…{tail} ({n} characters)")
}

/// A value in YAML's flow style, whole.
fn show_whole(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("{s:?}"),
        Value::Sequence(items) => {
            let items: Vec<String> = items.iter().map(show_whole).collect();
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
fn read_task(v: &Value, k: usize, rounded: &mut usize) -> Result<E2eTask, Diagnostic> {
    let m = task_mapping(v, k)?;
    let id = id_field(m, "TaskID", &task_place(k, None))?.ok_or_else(|| {
        bad(
            format!("{}: no TaskID", task_place(k, None)),
            "give every task a TaskID",
        )
    })?;
    let place = task_place(k, Some(&id));
    check_model(m, &place)?;
    let ecu = id_field(m, "ECU", &place)?.ok_or_else(|| {
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
fn check_model(m: &Mapping, place: &str) -> Result<(), Diagnostic> {
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
fn release(
    m: &Mapping,
    place: &str,
    rounded: &mut usize,
) -> Result<(Nanos, Option<Nanos>), Diagnostic> {
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
fn fixed_iat(m: &Mapping, place: &str) -> Result<f64, Diagnostic> {
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
) -> Result<(Nanos, Nanos), Diagnostic> {
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
fn time(
    ms: f64,
    r: Round,
    key: &str,
    place: &str,
    rounded: &mut usize,
) -> Result<Nanos, Diagnostic> {
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
    let too_large = || format!("{ms} ms is larger than rtpipe's largest time (about 104 days)");
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
    if ns > MAX_TIME as i128 {
        return Err(too_large());
    }
    Ok((ns as Nanos, inexact))
}

/// A time in ms as rtpipe writes it.
pub(super) fn fmt_ms(ns: Nanos) -> String {
    format_in(ns, TimeUnit::Ms)
}

/// Every TaskID once.
fn check_unique(tasks: &[E2eTask]) -> Result<(), Diagnostic> {
    let mut seen: HashMap<&Id, usize> = HashMap::new();
    for t in tasks {
        if let Some(first) = seen.insert(&t.id, t.index) {
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
fn read_chains(top: &Mapping, tasks: &[E2eTask]) -> Result<Vec<Vec<Id>>, Diagnostic> {
    let Some(list) = field(top, "Chains") else {
        return Ok(Vec::new());
    };
    let list = list
        .as_sequence()
        .ok_or_else(|| bad("`Chains` is not a list", "write Chains: [[1, 2, 3], ...]"))?;
    let known: HashMap<&Id, usize> = tasks.iter().map(|t| (&t.id, t.index)).collect();
    list.iter()
        .enumerate()
        .map(|(k, c)| read_chain(c, k, &known))
        .collect()
}

/// One chain, `Chains[k]`.
fn read_chain(c: &Value, k: usize, known: &HashMap<&Id, usize>) -> Result<Vec<Id>, Diagnostic> {
    let place = format!("chain Chains[{k}]");
    let ids: Option<Vec<Id>> = c
        .as_sequence()
        .map(|s| s.iter().map(Id::of).collect::<Option<Vec<_>>>())
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
            format!(
                "{place} = {}: no task has TaskID {}",
                show(c),
                cut(id.to_string())
            ),
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
