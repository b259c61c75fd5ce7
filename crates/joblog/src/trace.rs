//! Chrome trace-event JSON of a run, for the Perfetto UI
//! (<https://ui.perfetto.dev>) or `chrome://tracing`.
//!
//! Needs a run with a job log (the simulator's `SimConfig::log_jobs`): the
//! trace is built from [`SimResult::segments`] and [`SimResult::jobs`]. The
//! real runtime (`rtpipe run`) produces a `SimResult` too, whose segments
//! are job spans rather than CPU slices ([`TraceOptions::spans`]), so
//! prediction and reality open side by side in one format.
//!
//! Layout:
//! - one process per CPU (`pid` = dense CPU index, named `cpu <id>`), one
//!   thread (track) per task (`tid` = task index + 1, named by the task),
//!   except that the tasks of a work-queue thread share one track, the
//!   thread's ([`Tracks`]: `tid` = tasks + thread index + 1, named
//!   `thread <name>`), on which each slice is named by its task;
//! - a data-triggered job's slices and release carry its trigger in
//!   `args.trigger` (`task#job`: the publication that released it), and an
//!   arrow (category `trigger`) runs from that publication to the release;
//! - every CPU slice is a complete event (`"ph": "X"`) named by the task, with
//!   `args: {job, background}`; inside it, nested complete events `read`,
//!   `process` and `write` mark which part of the job's demand ran there (the
//!   first Δin of its execution, the middle, the last Δout);
//! - releases are instant events (`"ph": "i"`) named `release`;
//! - data flow along chain edges: a flow start (`"ph": "s"`) at the producer
//!   job's publish and a flow end (`"ph": "f"`, `"bp": "e"`) at the read of the
//!   consumer job that copied that value. The producer job is the latest one
//!   that published at or before the consumer's read (register semantics),
//!   checked against the samples both jobs carried.
//!
//! Times are microseconds (fractional, so nanoseconds survive). Long runs are
//! cut at [`TraceOptions::max_slices`] CPU slices and
//! [`TraceOptions::max_flows`] flow arrows so files stay openable.

use crate::{Carried, JobRecord, Segment, SimResult, Trigger};
use rtpipe_model::{Nanos, Spec, Task};
use serde_json::{json, Value};
use std::collections::{HashMap, HashSet};

/// Limits that keep traces of long runs reasonable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TraceOptions {
    /// CPU slices kept; the trace ends at the start of the first slice left out.
    pub max_slices: usize,
    /// Flow arrows (producer publish → consumer read) kept, earliest first.
    pub max_flows: usize,
    /// The segments are job spans (read to publish, preemptions included:
    /// what a real run knows), not CPU slices: they are drawn in category
    /// `span` and without read/process/write stages, which need slices.
    pub spans: bool,
}

impl Default for TraceOptions {
    fn default() -> TraceOptions {
        TraceOptions {
            max_slices: 50_000,
            max_flows: 20_000,
            spans: false,
        }
    }
}

/// A rendered trace and what was left out.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// The Chrome trace-event JSON.
    pub json: String,
    /// Trace events written (metadata included).
    pub events: usize,
    /// CPU slices written.
    pub slices: usize,
    /// Flow arrows written.
    pub flows: usize,
    /// When the slice limit cut the trace: no slice, release or flow starting
    /// at or after this instant is in it (slices begun before it are whole).
    pub truncated_at: Option<Nanos>,
    /// Flow arrows left out by the flow limit.
    pub flows_dropped: usize,
}

/// Trace events serialised into one buffer, comma-separated.
#[derive(Default)]
struct Events {
    buf: String,
    count: usize,
}

impl Events {
    fn push(&mut self, v: Value) {
        if self.count > 0 {
            self.buf.push_str(",\n");
        }
        self.buf.push_str(&v.to_string());
        self.count += 1;
    }
}

/// The trace of `result` with the default [`TraceOptions`].
pub fn chrome_trace(spec: &Spec, result: &SimResult) -> String {
    chrome_trace_with(spec, result, TraceOptions::default()).json
}

fn us(ns: Nanos) -> f64 {
    ns as f64 / 1000.0
}

/// A time for an event: whole microseconds as an integer (exact in every
/// reader; Perfetto truncates fractional µs when it converts to ns), else
/// fractional.
fn ts(ns: Nanos) -> Value {
    if ns % 1000 == 0 {
        json!(ns / 1000)
    } else {
        json!(us(ns))
    }
}

/// The trace of `result`, with explicit limits and a summary of the cut.
pub fn chrome_trace_with(spec: &Spec, result: &SimResult, opts: TraceOptions) -> Trace {
    let lay = Layout::new(spec);
    // The cut: the start of the first slice beyond the limit.
    let cut: Option<Nanos> = result.segments.get(opts.max_slices).map(|s| s.start);
    let end = cut.unwrap_or(result.horizon.saturating_add(1));
    let mut ev = Events::default();
    lay.metadata(&mut ev);
    let slices = lay.slices(spec, result, &opts, &mut ev);
    lay.releases(spec, result, end, &mut ev);
    let (flows, flows_dropped) = lay.flows(spec, result, end, opts.max_flows, &mut ev);
    let events = ev.count;
    let other = json!({
            "system": spec.name,
            "source": if opts.spans { "run" } else { "simulation" },
            "time_unit": spec.time_unit.name(),
            "horizon_us": us(result.horizon),
            "offsets_us": result.offsets.iter().map(|&o| us(o)).collect::<Vec<_>>(),
            "truncated_at_us": cut.map(us),
            "flows_dropped": flows_dropped,
    });
    // Events are serialised one by one as they come: a tree of values for
    // the whole trace would take tens of times the file's size.
    let mut json = String::with_capacity(ev.buf.len() + 512);
    json.push_str("{\"traceEvents\":[");
    json.push_str(&ev.buf);
    json.push_str("],\"displayTimeUnit\":\"ms\",\"otherData\":");
    json.push_str(&other.to_string());
    json.push('}');
    Trace {
        json,
        events,
        slices,
        flows,
        truncated_at: cut,
        flows_dropped,
    }
}

/// The rows a schedule is drawn in (this trace's tracks, the Gantt
/// chart's rows): one per task, except that the tasks of a work-queue
/// thread share the thread's, since they run on it one job at a time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tracks {
    /// The track of each task.
    pub of: Vec<usize>,
    /// Each track, in order of its first task's declaration.
    pub tracks: Vec<Track>,
}

/// One row of a schedule.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Track {
    /// Its label: the task's name, or `thread <name>`.
    pub name: String,
    /// The CPU it runs on.
    pub cpu: u32,
    /// Its first task (index into `Spec::tasks`).
    pub first: usize,
    /// The work-queue thread it is (index into `Spec::threads`), if any.
    pub thread: Option<usize>,
}

impl Tracks {
    /// The tracks of `spec`'s tasks.
    pub fn of(spec: &Spec) -> Tracks {
        let mut of = Vec::with_capacity(spec.tasks.len());
        let mut tracks: Vec<Track> = Vec::new();
        let mut thread_track = vec![None; spec.threads.len()];
        for (i, t) in spec.tasks.iter().enumerate() {
            let known = t
                .thread
                .and_then(|th| thread_track.get(th).copied().flatten());
            if let Some(k) = known {
                of.push(k);
                continue;
            }
            let name = match t.thread.and_then(|th| spec.threads.get(th)) {
                Some(th) => format!("thread {}", th.name),
                None => t.name.clone(),
            };
            if let Some(slot) = t.thread.and_then(|th| thread_track.get_mut(th)) {
                *slot = Some(tracks.len());
            }
            of.push(tracks.len());
            tracks.push(Track {
                name,
                cpu: t.cpu,
                first: i,
                thread: t.thread,
            });
        }
        Tracks { of, tracks }
    }
}

/// Where each task's track is: a process per CPU, a thread per task or
/// work-queue thread.
struct Layout {
    cpu_ids: Vec<u32>,
    pid_of: Vec<usize>,
    tracks: Tracks,
    /// The `tid` of each task's track.
    tid_of: Vec<usize>,
}

impl Layout {
    fn new(spec: &Spec) -> Layout {
        let mut cpu_ids: Vec<u32> = spec.tasks.iter().map(|t| t.cpu).collect();
        cpu_ids.sort_unstable();
        cpu_ids.dedup();
        let pid_of: Vec<usize> = spec
            .tasks
            .iter()
            .map(|t| cpu_ids.binary_search(&t.cpu).unwrap_or(0))
            .collect();
        let tracks = Tracks::of(spec);
        let tid_of = (0..spec.tasks.len())
            .map(|i| Self::track_tid(spec, &tracks.tracks[tracks.of[i]]))
            .collect();
        Layout {
            cpu_ids,
            pid_of,
            tracks,
            tid_of,
        }
    }

    /// A task's own track is its index + 1 (as before threads), a
    /// thread's comes after every task's.
    fn track_tid(spec: &Spec, track: &Track) -> usize {
        match track.thread {
            Some(th) => spec.tasks.len() + th + 1,
            None => track.first + 1,
        }
    }

    fn tid(&self, task: usize) -> usize {
        self.tid_of[task]
    }

    /// Names and order of the CPU processes and task threads.
    fn metadata(&self, ev: &mut Events) {
        for (pid, id) in self.cpu_ids.iter().enumerate() {
            ev.push(
                json!({"ph": "M", "name": "process_name", "pid": pid, "tid": 0,
                           "args": {"name": format!("cpu {id}")}}),
            );
            ev.push(
                json!({"ph": "M", "name": "process_sort_index", "pid": pid, "tid": 0,
                           "args": {"sort_index": pid}}),
            );
        }
        for track in &self.tracks.tracks {
            let i = track.first;
            let (pid, tid) = (self.pid_of[i], self.tid(i));
            ev.push(
                json!({"ph": "M", "name": "thread_name", "pid": pid, "tid": tid,
                           "args": {"name": track.name}}),
            );
            ev.push(
                json!({"ph": "M", "name": "thread_sort_index", "pid": pid, "tid": tid,
                           "args": {"sort_index": i}}),
            );
        }
    }

    /// One slice per stretch of execution (with its job's stages, unless
    /// `opts.spans`); returns how many slices.
    fn slices(
        &self,
        spec: &Spec,
        result: &SimResult,
        opts: &TraceOptions,
        ev: &mut Events,
    ) -> usize {
        let jobs: HashMap<(usize, u64), &JobRecord> =
            result.jobs.iter().map(|j| ((j.task, j.index), j)).collect();
        // CPU time each job has received before the slice at hand.
        let mut done: HashMap<(usize, u64), Nanos> = HashMap::new();
        let mut slices = 0;
        for seg in result.segments.iter().take(opts.max_slices) {
            if seg.task >= spec.tasks.len() {
                continue;
            }
            let (pid, tid) = (self.pid_of[seg.task], self.tid(seg.task));
            let task = &spec.tasks[seg.task];
            let mut args = json!({"job": seg.job, "background": seg.background});
            let job = jobs.get(&(seg.task, seg.job));
            if let Some(tr) = job.and_then(|j| j.trigger) {
                args["trigger"] = json!(trigger_label(spec, tr));
            }
            ev.push(json!({
                "ph": "X", "cat": if opts.spans { "span" } else { "job" }, "name": task.name, "pid": pid, "tid": tid,
                "ts": ts(seg.start), "dur": ts(seg.end - seg.start),
                "args": args,
            }));
            slices += 1;
            if opts.spans {
                continue;
            }
            let key = (seg.task, seg.job);
            let before = *done.get(&key).unwrap_or(&0);
            done.insert(key, before + (seg.end - seg.start));
            // Stages need the job's demand: only completed jobs have it.
            if let Some(job) = jobs.get(&key) {
                stages(task, job, seg, before, (pid, tid), ev);
            }
        }
        slices
    }

    /// An instant event at every release before `end`, named by its task
    /// on a thread's track; a data-triggered one with its trigger and an
    /// arrow from the trigger's publication.
    fn releases(&self, spec: &Spec, result: &SimResult, end: Nanos, ev: &mut Events) {
        let mut arrows = 0usize;
        for j in &result.jobs {
            if j.release >= end || j.task >= spec.tasks.len() {
                continue;
            }
            let (pid, tid) = (self.pid_of[j.task], self.tid(j.task));
            let name = match spec.tasks[j.task].thread {
                Some(_) => format!("release {}", spec.tasks[j.task].name),
                None => "release".to_string(),
            };
            let mut args = json!({"job": j.index});
            let trigger = j.trigger.filter(|tr| tr.task < spec.tasks.len());
            if let Some(tr) = trigger {
                args["trigger"] = json!(trigger_label(spec, tr));
            }
            ev.push(json!({"ph": "i", "s": "t", "cat": "release", "name": name,
                           "pid": pid, "tid": tid, "ts": ts(j.release), "args": args}));
            if let Some(tr) = trigger {
                arrows += 1;
                let id = format!("trigger-{arrows}");
                ev.push(json!({"ph": "s", "cat": "trigger", "name": "trigger", "id": id,
                               "pid": self.pid_of[tr.task], "tid": self.tid(tr.task), "ts": ts(j.release),
                               "args": {"job": tr.job}}));
                ev.push(
                    json!({"ph": "f", "bp": "e", "cat": "trigger", "name": "trigger", "id": id,
                               "pid": pid, "tid": tid, "ts": ts(j.release),
                               "args": {"job": j.index}}),
                );
            }
        }
    }

    /// Data flow: an arrow from the publish of each chain sample to each
    /// read that took it, at most `max_flows`; returns (drawn, dropped).
    fn flows(
        &self,
        spec: &Spec,
        result: &SimResult,
        end: Nanos,
        max_flows: usize,
        ev: &mut Events,
    ) -> (usize, usize) {
        // Jobs per task in completion (= publish) order.
        let mut by_task: Vec<Vec<&JobRecord>> = vec![Vec::new(); spec.tasks.len()];
        for j in result.jobs.iter().filter(|j| j.task < spec.tasks.len()) {
            by_task[j.task].push(j);
        }
        let mut linked: HashSet<(usize, u64, usize, u64)> = HashSet::new();
        let (mut flows, mut flows_dropped) = (0usize, 0usize);
        let mut consumers: Vec<&JobRecord> = result.jobs.iter().filter(|j| j.read < end).collect();
        consumers.sort_by_key(|j| (j.read, j.task));
        for cj in consumers {
            for c in &cj.carried {
                let Some((pj, sample)) = producer_of(spec, &by_task, cj, c) else {
                    continue;
                };
                if !linked.insert((pj.task, pj.index, cj.task, cj.index)) {
                    continue;
                }
                if flows >= max_flows {
                    flows_dropped += 1;
                    continue;
                }
                flows += 1;
                self.arrow(pj, cj, c.chain, sample, flows, ev);
            }
        }
        (flows, flows_dropped)
    }

    /// The flow events of one arrow from `pj`'s publish to `cj`'s read.
    fn arrow(
        &self,
        pj: &JobRecord,
        cj: &JobRecord,
        chain: usize,
        sample: u64,
        id: usize,
        ev: &mut Events,
    ) {
        // Bind the start inside the producer's last slice (it ends at the
        // publish instant, and a slice does not enclose its end).
        let start = if pj.finish > pj.read {
            pj.finish - 1
        } else {
            pj.finish
        };
        ev.push(json!({"ph": "s", "cat": "data", "name": "data", "id": id,
                       "pid": self.pid_of[pj.task], "tid": self.tid(pj.task), "ts": ts(start),
                       "args": {"job": pj.index, "chain": chain, "sample": sample}}));
        ev.push(
            json!({"ph": "f", "bp": "e", "cat": "data", "name": "data", "id": id,
                       "pid": self.pid_of[cj.task], "tid": self.tid(cj.task), "ts": ts(cj.read),
                       "args": {"job": cj.index, "chain": chain, "sample": sample}}),
        );
    }
}

/// A publication as the trace names it: `task#job`.
fn trigger_label(spec: &Spec, tr: Trigger) -> String {
    let name = spec.tasks.get(tr.task).map_or("?", |t| t.name.as_str());
    format!("{name}#{}", tr.job)
}

/// The read, process and write stages of `job` that fall in slice `seg`,
/// which starts after `before` of the job's CPU time.
fn stages(
    task: &Task,
    job: &JobRecord,
    seg: &Segment,
    before: Nanos,
    (pid, tid): (usize, usize),
    ev: &mut Events,
) {
    let ran = seg.end - seg.start;
    let d_in = task.delta_in.clamp(0, job.demand);
    let d_out = task.delta_out.clamp(0, job.demand - d_in);
    let stages = [
        ("read", 0, d_in),
        ("process", d_in, job.demand - d_out),
        ("write", job.demand - d_out, job.demand),
    ];
    for (name, lo, hi) in stages {
        // Overlap of [lo, hi) with the execution [before, before + ran).
        let a = lo.max(before);
        let b = hi.min(before + ran);
        if b > a {
            ev.push(json!({
                "ph": "X", "cat": "stage", "name": name, "pid": pid, "tid": tid,
                "ts": ts(seg.start + (a - before)), "dur": ts(b - a),
                "args": {"job": seg.job},
            }));
        }
    }
}

/// The producer job whose output `cj` read for the chain sample `c`, when it
/// carried that very sample one position earlier on the chain.
fn producer_of<'r>(
    spec: &Spec,
    by_task: &[Vec<&'r JobRecord>],
    cj: &JobRecord,
    c: &Carried,
) -> Option<(&'r JobRecord, u64)> {
    let sample = c.sample.filter(|_| c.pos > 0)?;
    let producer = *spec.chains.get(c.chain)?.path.get(c.pos - 1)?;
    let list = by_task.get(producer)?;
    // Completions publish before reads at one instant: finish ≤ read.
    let k = list.partition_point(|p| p.finish <= cj.read);
    // The simulator's reads take the latest value published; a real run's
    // may take an older one (its publish instant is taken before the
    // register write). Samples only grow along a task's jobs, so look back
    // from the latest until the sample is older than the one carried.
    let carried = |pj: &JobRecord| {
        pj.carried
            .iter()
            .find(|pc| pc.chain == c.chain && pc.pos + 1 == c.pos)
            .and_then(|pc| pc.sample)
    };
    list[..k]
        .iter()
        .rev()
        .take_while(|pj| carried(pj).is_some_and(|s| s >= sample))
        .find(|pj| carried(pj) == Some(sample))
        .map(|pj| (*pj, sample))
}
