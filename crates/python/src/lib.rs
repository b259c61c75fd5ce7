//! `rtpipe._rtpipe`: the native module under the `rtpipe` Python package
//! (python/rtpipe/__init__.py is the API people use). A thin layer over
//! `rtpipe::api`: a spec is loaded once and held; a command runs with the
//! flags of the command line on a worker thread while the interpreter is
//! free (the GIL released) and Ctrl-C is honoured; the answer comes back as
//! the `--json` value turned into Python objects.

mod errors;
mod tables;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use rtpipe::api::{self, Columns, Failure, Reply};
use rtpipe_model::{Diagnostic, SpecError as ModelError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

create_exception!(
    _rtpipe,
    RtpipeError,
    PyException,
    "Every error rtpipe raises."
);
create_exception!(
    _rtpipe,
    SpecError,
    RtpipeError,
    "The spec is wrong: `diagnostics` holds each problem with its place (file, line, column) and a fix."
);
create_exception!(
    _rtpipe,
    InputError,
    RtpipeError,
    "An argument or a file it names is wrong: `help` says how to fix it."
);
create_exception!(
    _rtpipe,
    RunError,
    InputError,
    "A run on this machine could not start (the kernel refused a real-time class or a reservation, a CPU or cpuset is missing): `help` says how to fix it."
);
create_exception!(
    _rtpipe,
    InternalError,
    RtpipeError,
    "A bug in rtpipe (or a solver's failure): please report it with the spec and the call."
);

/// A loaded spec: what `rtpipe.load` returns inside `rtpipe.System`.
#[pyclass(frozen, module = "rtpipe._rtpipe")]
struct Spec {
    spec: rtpipe_model::Spec,
    /// The path it was read from, or a name for messages.
    label: String,
}

#[pymethods]
impl Spec {
    #[getter]
    fn name(&self) -> &str {
        &self.spec.name
    }

    #[getter]
    fn label(&self) -> &str {
        &self.label
    }

    #[getter]
    fn tasks(&self) -> Vec<String> {
        self.spec.tasks.iter().map(|t| t.name.clone()).collect()
    }

    #[getter]
    fn chains(&self) -> Vec<String> {
        (0..self.spec.chains.len())
            .map(|c| self.spec.chain_label(c))
            .collect()
    }

    /// Tasks without a fixed period (what `design` chooses).
    fn free_tasks(&self) -> Vec<String> {
        rtpipe_analysis::missing_periods(&self.spec)
            .into_iter()
            .map(String::from)
            .collect()
    }

    /// The spec as TOML, as `design --write` writes it.
    fn to_toml(&self) -> String {
        rtpipe_model::to_toml(&self.spec)
    }

    /// The value at `keys` (a key path into the spec's tables, as
    /// [`Spec::to_toml`] writes them: `["tasks", "gyro", "period"]`,
    /// `["chain", 0, "reaction"]`), or None where the spec has none.
    fn get(&self, py: Python<'_>, keys: Vec<Key>) -> PyResult<Py<PyAny>> {
        let table = self.table()?;
        let mut at = &toml::Value::Table(table);
        for k in &keys {
            let next = match (at, k) {
                (toml::Value::Table(t), Key::Name(n)) => t.get(n),
                (toml::Value::Array(a), Key::Index(i)) => a.get(*i),
                _ => None,
            };
            match next {
                Some(v) => at = v,
                None => return Ok(py.None()),
            }
        }
        let json = serde_json::to_value(at).map_err(|e| InternalError::new_err(e.to_string()))?;
        json_to_py(py, &json)
    }

    /// A copy of the spec with the value at `keys` set to `value` (None
    /// removes the key), checked by the spec's one validation; `at` names
    /// the edit in errors (the Python attribute, `system.tasks["gyro"].period`),
    /// since the TOML the check reads is not a file the caller has.
    fn edit(
        &self,
        py: Python<'_>,
        keys: Vec<Key>,
        value: &Bound<'_, PyAny>,
        at: &str,
    ) -> PyResult<Spec> {
        let new = if value.is_none() {
            None
        } else {
            let json = to_json(value, at, &mut Vec::new())?;
            let v = toml::Value::try_from(&json)
                .map_err(|e| InputError::new_err(format!("{at}: {e}")))?;
            Some(v)
        };
        let mut table = toml::Value::Table(self.table()?);
        set(&mut table, &keys, new, at)?;
        let text =
            toml::to_string(&table).map_err(|e| InputError::new_err(format!("{at}: {e}")))?;
        match rtpipe_model::Spec::parse(&self.label, &text) {
            Ok(spec) => Ok(Spec {
                spec,
                label: self.label.clone(),
            }),
            Err(e) => Err(edit_error(py, &e, at, value)),
        }
    }

    /// Pickling: the spec as its TOML and its label, loaded again by
    /// `load_text` (so a `multiprocessing.Pool` or Ray can ship it).
    fn __reduce__(&self, py: Python<'_>) -> PyResult<(Py<PyAny>, (String, String))> {
        let load = py.import("rtpipe._rtpipe")?.getattr("load_text")?.unbind();
        Ok((load, (self.to_toml(), self.label.clone())))
    }

    fn __repr__(&self) -> String {
        format!(
            "<rtpipe spec {:?} from {:?}: {} tasks, {} chains>",
            self.spec.name,
            self.label,
            self.spec.tasks.len(),
            self.spec.chains.len()
        )
    }
}

impl Spec {
    /// The spec's tables, as `to_toml` writes them.
    fn table(&self) -> PyResult<toml::Table> {
        toml::from_str(&rtpipe_model::to_toml(&self.spec)).map_err(|e| {
            InternalError::new_err(format!(
                "internal error (a bug in rtpipe): the spec's own TOML does not read back: {e}"
            ))
        })
    }
}

/// One step of a key path: a table's key or an array's index.
#[derive(FromPyObject)]
enum Key {
    Name(String),
    Index(usize),
}

impl std::fmt::Display for Key {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Key::Name(n) => write!(f, "{n}"),
            Key::Index(i) => write!(f, "{i}"),
        }
    }
}

/// Sets (or, with None, removes) the value at `keys` under `root`; every
/// table or array on the way must exist (an edit changes a task or a
/// chain, it does not make one).
fn set(root: &mut toml::Value, keys: &[Key], value: Option<toml::Value>, at: &str) -> PyResult<()> {
    let Some((last, path)) = keys.split_last() else {
        return Err(InputError::new_err(format!("{at}: an empty key path")));
    };
    let mut here = root;
    for (n, k) in path.iter().enumerate() {
        let next = match (here, k) {
            (toml::Value::Table(t), Key::Name(name)) => t.get_mut(name),
            (toml::Value::Array(a), Key::Index(i)) => a.get_mut(*i),
            _ => None,
        };
        let Some(next) = next else {
            let gone: Vec<String> = keys[..=n].iter().map(Key::to_string).collect();
            return Err(InputError::new_err(format!(
                "{at}: the spec has no {}; an edit changes what the spec has",
                gone.join(".")
            )));
        };
        here = next;
    }
    let (toml::Value::Table(t), Key::Name(name)) = (here, last) else {
        return Err(InputError::new_err(format!("{at}: not a key of a table")));
    };
    match value {
        Some(v) => {
            t.insert(name.clone(), v);
        }
        None => {
            t.remove(name);
        }
    }
    Ok(())
}

/// A rejected edit as [`InputError`]: the edit (`at = value`) and each of
/// the validation's problems with its fix; no line of the TOML the check
/// read, which the caller never saw.
fn edit_error(py: Python<'_>, e: &ModelError, at: &str, value: &Bound<'_, PyAny>) -> PyErr {
    let shown = value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "the value".into());
    let first = e.diagnostics.first();
    let message = match first {
        Some(d) => format!("{at} = {shown}: {}", d.message),
        None => format!("{at} = {shown}: the spec does not validate"),
    };
    let mut text = format!("error: {message}");
    for d in e.diagnostics.iter().skip(1) {
        text.push_str(&format!("\nerror: {}", d.message));
    }
    let help = first.and_then(|d| d.help.clone());
    if let Some(h) = &help {
        text.push_str(&format!("\n  = help: {h}"));
    }
    text.push_str("\n  (the edit was not made: the system is as it was)");
    let err = InputError::new_err(text);
    let _ = err.value(py).setattr("help", help);
    let _ = err.value(py).setattr("message", message);
    err
}

/// `(flag, help)` of every flag of `command`, as its `--help` says.
#[pyfunction]
fn flag_help(command: &str) -> Vec<(String, String)> {
    api::flag_help(command)
}

/// Reads a spec file.
#[pyfunction]
fn load_path(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Spec> {
    let label = path.display().to_string();
    match py.detach(|| rtpipe_model::Spec::load(&path)) {
        Ok(spec) => Ok(Spec { spec, label }),
        Err(e) => Err(spec_error(py, &e)),
    }
}

/// Parses a spec from TOML text; `label` names it in messages.
#[pyfunction]
fn load_text(py: Python<'_>, text: &str, label: &str) -> PyResult<Spec> {
    match rtpipe_model::Spec::parse(label, text) {
        Ok(spec) => Ok(Spec {
            spec,
            label: label.to_string(),
        }),
        Err(e) => Err(spec_error(py, &e)),
    }
}

/// The WATERS task set of `rtpipe generate waters FLAGS` (no file).
#[pyfunction]
fn waters(py: Python<'_>, flags: Vec<String>) -> PyResult<Spec> {
    match api::waters(&flags) {
        Ok(spec) => Ok(Spec {
            label: format!("<{}>", spec.name),
            spec,
        }),
        Err(f) => Err(raise(py, f)),
    }
}

/// TOML text from a dict of TOML tables (`None` has no TOML form).
#[pyfunction]
fn dict_to_toml(value: &Bound<'_, PyAny>) -> PyResult<String> {
    let v = to_json(value, "spec", &mut Vec::new())?;
    let t = toml::Value::try_from(&v).map_err(|e| InputError::new_err(format!("{e}")))?;
    toml::to_string(&t).map_err(|e| InputError::new_err(format!("{e}")))
}

/// What a dict spec may hold, for the messages that refuse anything else.
const PLAIN_DATA: &str = "a str, int, float, bool, list, tuple or dict";

/// A Python value as JSON (what TOML can hold), `at` its key path for
/// messages. Only plain data is read: an iterator or an arbitrary object
/// could be endless or run code, and `open` (the containers from the root
/// to here) refuses a value that contains itself and nesting deeper than a
/// spec file may have, either of which would recurse without end.
fn to_json(v: &Bound<'_, PyAny>, at: &str, open: &mut Vec<usize>) -> PyResult<serde_json::Value> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyString, PyTuple};
    use serde_json::Value as J;
    if v.is_none() {
        return Err(InputError::new_err(format!(
            "{at} is None, which a spec cannot hold: leave the key out"
        )));
    }
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(J::Bool(b.is_true()));
    }
    if v.cast::<PyInt>().is_ok() {
        return integer(v, at).map(J::from);
    }
    if let Ok(f) = v.cast::<PyFloat>() {
        return finite(f.value(), at);
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(J::String(s.to_cow()?.into_owned()));
    }
    let is_container =
        v.cast::<PyDict>().is_ok() || v.cast::<PyList>().is_ok() || v.cast::<PyTuple>().is_ok();
    if !is_container {
        return Err(InputError::new_err(format!(
            "{at} is a {}, which a spec cannot hold: use {PLAIN_DATA} (make an iterator or a \
             generator a list, a numpy number an int or a float, first)",
            v.get_type().name()?
        )));
    }
    enter(v, at, open)?;
    let value = container(v, at, open);
    open.pop();
    value
}

/// Refuses a container that is already open on the way from the root (a
/// cycle) or one nested deeper than a spec file may be; else opens it.
fn enter(v: &Bound<'_, PyAny>, at: &str, open: &mut Vec<usize>) -> PyResult<()> {
    let id = v.as_ptr() as usize;
    if open.contains(&id) {
        return Err(InputError::new_err(format!(
            "{at} contains itself (a dict or list that holds itself, directly or \
             deeper): a spec is a tree; give {at} a copy instead"
        )));
    }
    let deepest = rtpipe_model::input::MAX_NESTING;
    if open.len() >= deepest {
        return Err(InputError::new_err(format!(
            "{at} nests deeper than {deepest} levels of dicts and lists, the most a spec \
             may have: flatten it"
        )));
    }
    open.push(id);
    Ok(())
}

/// The items of a dict, list or tuple (opened by [`enter`]) as JSON.
fn container(v: &Bound<'_, PyAny>, at: &str, open: &mut Vec<usize>) -> PyResult<serde_json::Value> {
    use serde_json::Value as J;
    if let Ok(d) = v.cast::<PyDict>() {
        let mut m = serde_json::Map::new();
        for (k, x) in d.iter() {
            let Ok(k) = k.extract::<String>() else {
                return Err(InputError::new_err(format!(
                    "{at} has a key that is a {}, not a str: TOML keys are strings",
                    k.get_type().name()?
                )));
            };
            let place = format!("{at}.{k}");
            m.insert(k, to_json(&x, &place, open)?);
        }
        return Ok(J::Object(m));
    }
    // A list or a tuple: its length is known, nothing is iterated lazily.
    let items = v.cast::<pyo3::types::PySequence>()?;
    let mut out = Vec::with_capacity(items.len()?);
    for i in 0..items.len()? {
        out.push(to_json(&items.get_item(i)?, &format!("{at}[{i}]"), open)?);
    }
    Ok(J::Array(out))
}

/// An int as TOML's 64-bit integer, or an error naming `at`.
fn integer(v: &Bound<'_, PyAny>, at: &str) -> PyResult<i64> {
    v.extract::<i64>().map_err(|_| {
        InputError::new_err(format!(
            "{at} is an integer outside -2**63 .. 2**63-1, which TOML cannot hold: \
             write a smaller number"
        ))
    })
}

/// A float, refused with its key path when NaN or infinite (no spec
/// value is either).
fn finite(f: f64, at: &str) -> PyResult<serde_json::Value> {
    if !f.is_finite() {
        return Err(InputError::new_err(format!(
            "{at} is {f}, which a spec cannot hold: write a finite number"
        )));
    }
    Ok(serde_json::Value::from(f))
}

/// Runs `command` on `spec` with command-line `flags` (the interpreter
/// free meanwhile; Ctrl-C raises KeyboardInterrupt and stops the run).
/// `samples` returns the sample rows as columns, at most `max_samples`
/// of them (`MAX_SAMPLE_ROWS` by default, the most it takes; a run with
/// more raises MemoryError). Returns (report, exit status, notes, sample
/// columns or None, designed spec or None, tables).
#[pyfunction]
#[pyo3(signature = (command, spec, flags, samples=false, max_samples=None))]
fn run(
    py: Python<'_>,
    command: &str,
    spec: Py<Spec>,
    flags: Vec<String>,
    samples: bool,
    max_samples: Option<usize>,
) -> PyResult<Py<PyAny>> {
    let (command, held) = (command.to_string(), spec.clone_ref(py));
    let most = samples.then(|| max_samples.unwrap_or(api::MAX_SAMPLE_ROWS));
    let reply = in_worker(py, move |stop| {
        let s = held.get();
        api::run(&command, &s.spec, &s.label, &flags, most, stop)
    })?;
    answer(py, reply)
}

/// Runs `command` (one without a spec: `campaign`) with command-line
/// `flags`, as [`run`] does.
#[pyfunction]
fn run_plain(py: Python<'_>, command: &str, flags: Vec<String>) -> PyResult<Py<PyAny>> {
    let command = command.to_string();
    let reply = in_worker(py, move |stop| api::run_plain(&command, &flags, None, stop))?;
    answer(py, reply)
}

/// Runs a command that makes specs (`import e2eeval`, `import
/// px4-ulog`, `generate waters`) with command-line `flags` (`text`: the
/// content of the file they name, read in its place); returns (report,
/// notes, [(name, Spec)], {file name: text}). Nothing is written.
#[pyfunction]
#[pyo3(signature = (command, flags, text=None))]
fn make(
    py: Python<'_>,
    command: &str,
    flags: Vec<String>,
    text: Option<String>,
) -> PyResult<Py<PyAny>> {
    let command = command.to_string();
    let reply = in_worker(py, move |stop| {
        api::run_plain(&command, &flags, text.as_deref(), stop)
    })?;
    let r = reply.map_err(|f| raise(py, f))?;
    let report = match &r.json {
        Some(v) => json_to_py(py, v)?,
        None => py.None(),
    };
    let specs = PyList::empty(py);
    for (name, spec) in r.specs {
        let label = format!("<{}>", spec.name);
        specs.append((name, Py::new(py, Spec { spec, label })?))?;
    }
    let files = PyDict::new(py);
    for (name, text) in r.files {
        files.set_item(name, text)?;
    }
    let notes = PyList::new(py, &r.notes)?;
    let t = (report, notes, specs, files).into_pyobject(py)?;
    Ok(t.into_any().unbind())
}

/// How Python reaches each command of the binary: (command path, the
/// function or method that calls it or None, why not or None).
fn reach() -> Vec<(String, Option<String>, Option<String>)> {
    rtpipe::registry::REACH
        .iter()
        .map(|(path, r)| match r {
            rtpipe::command::Reach::Python(n) => (path.to_string(), Some(n.to_string()), None),
            rtpipe::command::Reach::Not(why) => (path.to_string(), None, Some(why.to_string())),
        })
        .collect()
}

/// `work` on a worker thread while this thread waits with the GIL
/// released, checking for Ctrl-C every 50 ms: on one, the stop flag is set,
/// the worker is waited for (it ends at its next stop point, so nothing of
/// the call runs on, or writes, after it returns) and KeyboardInterrupt
/// raised.
fn in_worker(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> Result<Reply, Failure> + Send + 'static,
) -> PyResult<Result<Reply, Failure>> {
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel();
    let worker_stop = Arc::clone(&stop);
    std::thread::spawn(move || {
        // The receiver is gone only when Ctrl-C already answered.
        let _ = tx.send(work(worker_stop));
    });
    let mut rx = rx;
    loop {
        // The receiver goes into the GIL-free wait and comes back out.
        let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
        rx = back;
        match got {
            Ok(r) => return Ok(r),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    stop.store(true, Ordering::Relaxed);
                    // Its answer, if it finished meanwhile, is not the
                    // whole call's: the interrupt is.
                    let _ = py.detach(move || rx.recv());
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(InternalError::new_err(
                    "the worker thread ended without an answer",
                ))
            }
        }
    }
}

/// A command's reply as Python objects, or its failure as an exception.
fn answer(py: Python<'_>, reply: Result<Reply, Failure>) -> PyResult<Py<PyAny>> {
    reply.map_or_else(|f| Err(raise(py, f)), |r| reply_to_py(py, r))
}

/// A failure as the Python exception that says it.
fn raise(py: Python<'_>, f: Failure) -> PyErr {
    match f {
        Failure::Input(d) => input_error(py, &d),
        Failure::Run(d) => {
            let e = input_error(py, &d);
            let run = RunError::new_err(e.value(py).to_string());
            let _ = run.value(py).setattr("help", d.help.clone());
            let _ = run.value(py).setattr("message", d.message.clone());
            run
        }
        Failure::Stopped => pyo3::exceptions::PyKeyboardInterrupt::new_err("stopped"),
        // MemoryError, as Python says it; raised before memory runs out.
        Failure::TooManySamples(d) => {
            let text = format!("{}: {}", d.message, d.help.unwrap_or_default());
            pyo3::exceptions::PyMemoryError::new_err(text)
        }
        Failure::Internal(m) => InternalError::new_err(format!(
            "internal error (a bug in rtpipe): {m}; please report it with the spec and the call"
        )),
    }
}

/// (report, status, notes, columns, designed spec, tables) as a Python
/// tuple.
fn reply_to_py(py: Python<'_>, r: Reply) -> PyResult<Py<PyAny>> {
    let report = match &r.json {
        Some(v) => json_to_py(py, v)?,
        None => py.None(),
    };
    let cols = match &r.samples {
        Some(c) => columns_to_py(py, c)?.into_any().unbind(),
        None => py.None(),
    };
    let designed = match r.designed {
        Some(spec) => Py::new(
            py,
            Spec {
                spec,
                label: "<designed>".into(),
            },
        )?
        .into_any(),
        None => py.None(),
    };
    let notes = PyList::new(py, &r.notes)?.into_any().unbind();
    let status = r.status.into_pyobject(py)?.into_any().unbind();
    let tables = tables::tables_to_py(py, &r.tables)?.into_any().unbind();
    let t = pyo3::types::PyTuple::new(py, [report, status, notes, cols, designed, tables])?;
    Ok(t.into_any().unbind())
}

/// The JSON value as Python objects (dicts keep the report's key order).
fn json_to_py(py: Python<'_>, v: &serde_json::Value) -> PyResult<Py<PyAny>> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => py.None(),
        J::Bool(b) => b.into_pyobject(py)?.to_owned().into_any().unbind(),
        J::Number(n) => match (n.as_i64(), n.as_u64(), n.as_f64()) {
            (Some(i), _, _) => i.into_pyobject(py)?.into_any().unbind(),
            (None, Some(u), _) => u.into_pyobject(py)?.into_any().unbind(),
            (None, None, f) => f.unwrap_or(f64::NAN).into_pyobject(py)?.into_any().unbind(),
        },
        J::String(s) => s.into_pyobject(py)?.into_any().unbind(),
        J::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any().unbind()
        }
        J::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any().unbind()
        }
    })
}

/// The sample columns as raw little-endian buffers (the Python side views
/// them as numpy arrays without copying): `name -> bytes` for int64
/// columns, `name -> (bytes, mask bytes)` for columns with empty cells.
fn columns_to_py<'py>(py: Python<'py>, c: &Columns) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let ints = |v: &[i64]| {
        PyBytes::new(
            py,
            &v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>(),
        )
    };
    let chain: Vec<i64> = c.chain.iter().map(|&x| i64::from(x)).collect();
    let sample: Vec<i64> = c
        .sample
        .iter()
        .map(|&x| i64::try_from(x).unwrap_or(i64::MAX))
        .collect();
    d.set_item("chain", ints(&chain))?;
    d.set_item("sample", ints(&sample))?;
    d.set_item("read_ns", ints(&c.read_ns))?;
    let optional = [
        ("event_ns", &c.event_ns),
        ("first_output_ns", &c.first_output_ns),
        ("last_output_ns", &c.last_output_ns),
        ("reaction_ns", &c.reaction_ns),
        ("freshness_ns", &c.freshness_ns),
        ("event_reaction_ns", &c.event_reaction_ns),
        ("event_freshness_ns", &c.event_freshness_ns),
    ];
    for (name, col) in optional {
        let values: Vec<i64> = col.iter().map(|x| x.unwrap_or(0)).collect();
        let missing: Vec<u8> = col.iter().map(|x| u8::from(x.is_none())).collect();
        d.set_item(name, (ints(&values), PyBytes::new(py, &missing)))?;
    }
    Ok(d)
}

/// A bad argument as [`InputError`]: its message, with `help` set.
fn input_error(py: Python<'_>, d: &Diagnostic) -> PyErr {
    let text = d.to_string();
    let e = InputError::new_err(text.trim_end().to_string());
    let _ = e.value(py).setattr("help", d.help.clone());
    let _ = e.value(py).setattr("message", d.message.clone());
    e
}

/// A spec's errors as [`SpecError`]: the whole report as its message, the
/// first problem's place and fix, and every problem under `diagnostics`.
fn spec_error(py: Python<'_>, e: &ModelError) -> PyErr {
    let err = SpecError::new_err(e.to_string().trim_end().to_string());
    // Setting plain attributes on a fresh exception cannot fail short of
    // memory, when the exception itself is the best answer left.
    let _ = errors::describe_spec_error(py, &err, e);
    err
}

#[pymodule]
fn _rtpipe(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Spec>()?;
    m.add_function(wrap_pyfunction!(load_path, m)?)?;
    m.add_function(wrap_pyfunction!(load_text, m)?)?;
    m.add_function(wrap_pyfunction!(dict_to_toml, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(run_plain, m)?)?;
    m.add_function(wrap_pyfunction!(waters, m)?)?;
    m.add_function(wrap_pyfunction!(make, m)?)?;
    m.add("REACH", reach())?;
    m.add_function(wrap_pyfunction!(flag_help, m)?)?;
    m.add("RtpipeError", py.get_type::<RtpipeError>())?;
    m.add("SpecError", py.get_type::<SpecError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    m.add("COMMANDS", api::commands())?;
    m.add("MAX_SAMPLE_ROWS", api::MAX_SAMPLE_ROWS)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
