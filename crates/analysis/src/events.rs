//! Response times of a spec with work-queue threads and data-triggered
//! tasks: event models per task ([`crate::arrivals`]), the FIFO analysis
//! inside a thread ([`crate::thread_rta`]) and the fixed-priority one of
//! the thread-less tasks (`sched`'s, handed in as [`FixedPriority`]),
//! iterated holistically (Tindell and Clark 1994): a data-triggered task's
//! activations are its triggers' publications, whose jitter grows with
//! their response times, which grow with the jitter of what runs above
//! them. From zero jitter the iteration only grows, and stops when no
//! figure changes or one becomes unbounded. docs/analysis.md, "Threads and
//! data-triggered tasks".

use crate::arrivals::{Arrivals, Stream};
use crate::graph::Lists;
use crate::thread_rta::{fifo_response_from, FifoStops, Member};
use rtpipe_model::{Join, Nanos, Server, Spec};

mod change;
mod readers;
use change::Change;
use readers::{trigger_order, unit_of, Readers};

/// Most rounds of the holistic iteration (sweeps of one strongly connected
/// component of units) before every figure that depends on the jitter is
/// called unbounded.
pub const MAX_ROUNDS: usize = 1_000;

/// One stream of what runs above a task: (I, T, J), the work of each of
/// its jobs, its period and its release jitter.
pub type Load = (Nanos, Nanos, Nanos);

/// A task's (budget, job) response times (`None`: unbounded).
pub type Figures = (Option<Nanos>, Option<Nanos>);

/// What the fixed-priority analysis provides (`sched` implements it, so
/// that thread-less tasks keep their own analysis, servers included).
pub trait FixedPriority {
    /// The tasks that can run above task `i` on its CPU (its thread's
    /// own tasks among them, which the caller leaves out), in any order:
    /// nothing the analysis computes from them depends on it.
    fn above(&self, i: usize) -> Vec<usize>;
    /// The tasks above each of the `n` tasks as prefixes of lists the
    /// tasks share ([`Ranked`]), so that the set-up reads who reads whom
    /// from the lists, not from every task's tasks above. The default:
    /// each task's [`above`](Self::above) a list of its own, whole.
    fn ranked(&self, n: usize) -> Ranked {
        let lists: Vec<Vec<usize>> = (0..n).map(|i| self.above(i)).collect();
        Ranked {
            prefix: (0..n).map(|i| (i, lists[i].len())).collect(),
            lists,
        }
    }
    /// What one job of task `j` takes from the tasks below it.
    fn interference(&self, j: usize) -> Nanos;
    /// B of task `i`: once per busy period.
    fn blocking(&self, i: usize) -> Nanos;
    /// (budget, job) response times of a thread-less periodic task `i`,
    /// from its nominal release, under `hp` as (I, T, J).
    fn periodic_response(&self, i: usize, hp: &[Load]) -> (Option<Nanos>, Option<Nanos>);
    /// [`periodic_response`](Self::periodic_response) with the fixed
    /// points its iterations stopped at, so that the figures hold as long
    /// as the streams keep their periods and works and every task's η⁺,
    /// which only grows, is the same at them (the last, the largest window
    /// the iterations read `hp` at), each iteration started from `warm`'s
    /// (the task's last stops; the figures must be those from the bottom).
    /// `None` (the default) when unknown: the task is then re-analysed
    /// whenever an input changes, from the bottom.
    fn periodic_response_windows(
        &self,
        i: usize,
        hp: &[Load],
        warm: Option<&FpStops>,
    ) -> (Figures, Option<FpStops>) {
        let _ = warm;
        (self.periodic_response(i, hp), None)
    }
}

/// The tasks above each task as a prefix of a list tasks share: under
/// fixed priority a CPU's guaranteed tasks by their highest rank, the
/// tasks above a task those ranked at or above its own (`sched`'s
/// `Levels`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ranked {
    /// The lists.
    pub lists: Vec<Vec<usize>>,
    /// Per task its list and the length of its prefix: the tasks that can
    /// run above it are the prefix's, itself left out where it is one.
    pub prefix: Vec<(usize, usize)>,
}

/// Where a fixed-priority analysis' iterations stopped: each job's fixed
/// point `w_q` of the job figure's level-i busy period, and of the budget
/// figure's (empty when the budget figure is the job figure),
/// `sched::level_response_from`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FpStops {
    /// The job figure's `w_q`, in order.
    pub job: Vec<Nanos>,
    /// The budget figure's `w_q`, in order.
    pub budget: Vec<Nanos>,
}

impl FpStops {
    /// Every stop, ascending and distinct.
    fn windows(&self) -> Vec<Nanos> {
        let mut windows = self.job.clone();
        windows.extend(&self.budget);
        windows.sort_unstable();
        windows.dedup();
        windows
    }
}

/// What the event analysis knows of a task, beside its response times.
#[derive(Debug, Clone, PartialEq)]
pub struct EventTiming {
    /// Its jobs merge: it is in a thread or data-triggered, so a release
    /// while one of its jobs is queued and not started joins that job.
    pub merging: bool,
    /// Its activations (`None`: unbounded, a trigger has no response).
    pub arrivals: Option<Arrivals>,
    /// R: from a job's first release (the nominal one of a periodic task)
    /// to its completion, for every job, with no need for R ≤ T.
    pub response: Option<Nanos>,
    /// A: the longest from any instant to the task's next activation (or
    /// nominal release): T, or from its triggers' publications.
    pub gap: Option<Nanos>,
    /// P = A + R: the longest from any instant to its next publication.
    pub publish_gap: Option<Nanos>,
    /// Per trigger (a data-triggered task's), the longest from its
    /// publication to the release it brings: 0 under `join = "any"`, the
    /// other triggers' largest `P` under `join = "all"`.
    pub waits: Vec<(usize, Option<Nanos>)>,
}

/// One task's figures: (budget, job) response times and its event facts.
#[derive(Debug, Clone, PartialEq)]
pub struct EventResult {
    /// The budget response time (C delivered), from the nominal release.
    pub budget: Option<Nanos>,
    /// The job response time (demand x), from the nominal release.
    pub job: Option<Nanos>,
    /// The rest.
    pub timing: EventTiming,
}

/// Every task's figures, by the holistic iteration, in the order of what
/// waits for what: a *unit* (a thread, a thread-less task) reads the
/// activations of the tasks above its tasks and of its thread's tasks
/// ([`Deps`]), and those depend on the output jitter of their triggers'
/// units. The units' strongly connected components are analysed in
/// topological order, each until its own figures stop changing, its
/// inputs then final: a unit that reads nothing of its own component is
/// analysed once. Inside a component, sweeps in the order of the units' periods
/// re-analyse a unit when an input changed since its last analysis where
/// that analysis depends on it (a task above at a fixed point its
/// iterations stopped at, its own tasks up to its reach: an input whose
/// η⁺ only grew but is the same there leaves a response as it was), from
/// the figures as they are then. From
/// zero jitter the figures only grow, so this reaches the least fixed
/// point that re-analysing every task round after round reaches (chaotic
/// iteration, docs/analysis.md "Cost at 1,000 tasks";
/// `analysis/tests/events_worklist.rs` holds the two together).
pub fn analyze(spec: &Spec, fp: &impl FixedPriority) -> Vec<EventResult> {
    let n = spec.tasks.len();
    let mut deps = Deps::of(spec, fp);
    let order = deps.components(spec);
    deps.readers.group(&order.of_unit);
    // Each task's output jitter R − R_min, from zero.
    let delay: Vec<Option<Nanos>> = vec![Some(0); n];
    let mut state = State {
        arrivals: deps.activations(spec, &delay),
        delay,
        responses: vec![Response::NONE; n],
        dirty: vec![false; n + spec.threads.len()],
        marked: vec![false; n],
        lists: SweepLists::default(),
        reach: vec![None; n + spec.threads.len()],
    };
    for c in 0..order.units.len() {
        if !deps.settle(spec, fp, &order, c, &mut state) {
            // No fixed point found: nothing that depends on the jitter is
            // bounded.
            let arrivals = deps.activations(spec, &vec![None; n]);
            let mut responses = state.responses;
            for u in deps.units(spec) {
                deps.respond_unit(spec, fp, &arrivals, &mut responses, u);
            }
            return finish(spec, arrivals, responses);
        }
    }
    finish(spec, state.arrivals, state.responses)
}

/// The iteration's figures so far.
struct State {
    /// Per task its output jitter (`None`: unbounded).
    delay: Vec<Option<Nanos>>,
    /// Per task its activations under `delay`.
    arrivals: Vec<Option<Arrivals>>,
    /// Per task its response under `arrivals`, once its unit is analysed.
    responses: Vec<Response>,
    /// Per unit whether its inputs changed since its last analysis.
    dirty: Vec<bool>,
    /// Per task a scratch mark, all clear between uses.
    marked: Vec<bool>,
    /// The sweeps' lists, kept between uses rather than allocated at each.
    lists: SweepLists,
    /// Per unit the reach of its responses as last analysed
    /// ([`Deps::reach`], kept rather than gathered at every
    /// [`Deps::sees`]).
    reach: Vec<Option<Nanos>>,
}

/// The lists a unit's analysis hands on to its readers, each empty between
/// uses: kept from one analysis to the next, so that a sweep allocates
/// only where one outgrows what it had.
#[derive(Default)]
struct SweepLists {
    /// The unit's tasks whose output jitter grew ([`Deps::grow`]).
    grown: Vec<usize>,
    /// The tasks downstream of those ([`Deps::downstream`]).
    downstream: Vec<usize>,
    /// [`Deps::downstream`]'s tasks still to visit.
    next: Vec<usize>,
    /// The downstream tasks whose activations changed ([`Deps::refresh`]).
    changed: Vec<usize>,
    /// The streams of one change ([`Change::moved`]).
    moved: Vec<(Stream, Stream)>,
}

/// The units' strongly connected components in the order to analyse them:
/// every unit a component's units read from is in it or before it.
struct Components {
    units: Vec<Vec<usize>>,
    /// Per unit its component's place in `units`.
    of_unit: Vec<usize>,
}

/// What each task's response reads, built once per analysis. A *unit* is
/// a thread (its tasks' responses are analysed together: they share the
/// tasks above them and read each other's activations), numbered after
/// the tasks, or a thread-less task, numbered as the task.
struct Deps {
    /// Per task what one of its jobs takes from the tasks below it
    /// ([`FixedPriority::interference`], asked once per task rather than
    /// once per task above, per analysis).
    interference: Vec<Nanos>,
    /// Per thread its tasks, in declaration order.
    members: Vec<Vec<usize>>,
    /// Who reads whom, from the ranked lists ([`Readers`]).
    readers: Readers,
    /// Per task the data-triggered tasks it triggers.
    consumers: Vec<Vec<usize>>,
    /// Every task, each after its triggers.
    trigger_order: Vec<usize>,
    /// Per task its place in `trigger_order`.
    trigger_rank: Vec<usize>,
}

impl Deps {
    fn of(spec: &Spec, fp: &impl FixedPriority) -> Deps {
        let n = spec.tasks.len();
        let mut members = vec![Vec::new(); spec.threads.len()];
        for (i, t) in spec.tasks.iter().enumerate() {
            if let Some(th) = t.thread {
                members[th].push(i);
            }
        }
        let readers = Readers::of(spec, fp.ranked(n));
        let interference = (0..n).map(|j| fp.interference(j)).collect();
        let consumers = spec.triggered_by();
        let trigger_order = trigger_order(spec, &consumers);
        let mut trigger_rank = vec![0; n];
        for (k, &i) in trigger_order.iter().enumerate() {
            trigger_rank[i] = k;
        }
        Deps {
            interference,
            members,
            readers,
            consumers,
            trigger_order,
            trigger_rank,
        }
    }

    /// The units: every thread-less task and every thread.
    fn units<'a>(&'a self, spec: &'a Spec) -> impl Iterator<Item = usize> + 'a {
        let n = spec.tasks.len();
        let tasks = (0..n).filter(|&i| spec.tasks[i].thread.is_none());
        tasks.chain(n..n + self.members.len())
    }

    /// The tasks that can run above task `i`, its thread's own left out
    /// (none for a background task, which has no response): its prefix of
    /// its CPU's ranked list, read in place rather than copied per task
    /// (docs/analysis.md "Cost at 1,000 tasks", tenth round).
    fn above<'a>(&'a self, spec: &Spec, i: usize) -> impl Iterator<Item = usize> + 'a {
        let own = unit_of(spec, i);
        let prefix = self.readers.prefix[i].clone();
        let units = &self.readers.unit_at[prefix.clone()];
        self.readers.flat[prefix]
            .iter()
            .zip(units)
            .filter(move |&(_, &u)| u != own)
            .map(|(&j, _)| j)
    }

    /// Whether tasks `k` and `i` of one unit have the same tasks above
    /// ([`Deps::above`]): two prefixes of one list differ only in the
    /// entries past the shorter, which are the unit's own or not.
    fn same_above(&self, spec: &Spec, k: usize, i: usize) -> bool {
        let (a, b) = (&self.readers.prefix[k], &self.readers.prefix[i]);
        let own = unit_of(spec, i);
        if a.start != b.start || unit_of(spec, k) != own {
            return self.above(spec, k).eq(self.above(spec, i));
        }
        let between = a.end.min(b.end)..a.end.max(b.end);
        self.readers.unit_at[between].iter().all(|&u| u == own)
    }

    /// The tasks of unit `u`.
    fn unit_tasks(&self, u: usize) -> impl Iterator<Item = usize> + '_ {
        let n = self.interference.len();
        let own = (u < n).then_some(u);
        let thread = u.checked_sub(n).map(|th| &self.members[th]);
        own.into_iter().chain(thread.into_iter().flatten().copied())
    }

    /// The units' strongly connected components, in topological order
    /// (Tarjan's, [`crate::graph::strongly_connected`]), of the graph
    /// where a unit reaches each task whose activations it reads, and a
    /// data-triggered task points to each trigger and the trigger's unit
    /// (whose response gives the trigger's output jitter): a task's
    /// activations depend on the units of its triggers, theirs, and so on
    /// ([`Deps::reads`]).
    fn components(&self, spec: &Spec) -> Components {
        let n = spec.tasks.len();
        let units = n + self.members.len();
        let nodes = units + n + self.readers.flat.len();
        let succ = Lists::build(nodes, |edge| self.reads(spec, edge));
        // Tarjan's numbers a component after every component it reaches.
        let comp = crate::graph::strongly_connected(nodes, &succ);
        let mut by_comp: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        for u in self.units(spec) {
            by_comp[comp[u]].push(u);
        }
        by_comp.retain(|c| !c.is_empty());
        // Inside a component, what a unit reads first where the cycles
        // allow, so that a sweep carries most changes to their readers: a
        // task reads the tasks above it on its CPU, of shorter or equal
        // periods under rate-monotonic priorities, and the triggers
        // upstream of those, so the units in ascending order of their
        // activations' period, then of their place in the trigger order.
        // (A depth-first post-order of the graph analysed each unit of the
        // 1,000-task bench's one big component 3 times on average, this
        // order 2.0, docs/analysis.md "Cost at 1,000 tasks".)
        let key = |u: usize| {
            let period = self
                .unit_tasks(u)
                .filter_map(|i| spec.activation_period(i))
                .min();
            let rank = self.unit_tasks(u).map(|i| self.trigger_rank[i]).min();
            (period, rank, u)
        };
        for on in &mut by_comp {
            if on.len() > 1 {
                on.sort_by_cached_key(|&u| key(u));
            }
        }
        let mut of_unit = vec![usize::MAX; units];
        for (c, on) in by_comp.iter().enumerate() {
            for &u in on {
                of_unit[u] = c;
            }
        }
        Components {
            units: by_comp,
            of_unit,
        }
    }

    /// The edges of [`Deps::components`]' graph. Its nodes: the units,
    /// then the tasks (`units + j`: j's activations), then the entries of
    /// the ranked lists (`units + n + g`: the entry `g` of
    /// [`Readers::flat`] and every entry before it in its list). A unit
    /// points to its own tasks and to the last entry of each of its tasks'
    /// prefixes, an entry to its task and to the entry before it, and a
    /// data-triggered task to each trigger and the trigger's unit (whose
    /// response gives the trigger's output jitter). So a unit reaches
    /// through the entries exactly the tasks of its tasks' prefixes: the
    /// tasks above them, and they themselves and their thread's tasks,
    /// which it reads anyway; a periodic task points nowhere (its
    /// activations depend on no unit). One entry per task above per task,
    /// as the graph had before (docs/analysis.md "Cost at 1,000 tasks",
    /// tenth round), became one per entry of the lists.
    fn reads(&self, spec: &Spec, edge: &mut crate::graph::Entries) {
        let n = spec.tasks.len();
        let units = n + self.members.len();
        let entry = |g: usize| units + n + g;
        for u in self.units(spec) {
            for i in self.unit_tasks(u) {
                edge.add(u, units + i);
                let prefix = self.readers.prefix[i].clone();
                if !prefix.is_empty() {
                    edge.add(u, entry(prefix.end - 1));
                }
            }
        }
        for (g, &j) in self.readers.flat.iter().enumerate() {
            edge.add(entry(g), units + j);
            if g > self.readers.list_start[g] {
                edge.add(entry(g), entry(g - 1));
            }
        }
        for j in 0..n {
            let Some((triggers, _)) = spec.tasks[j].triggers() else {
                continue;
            };
            for &p in triggers {
                edge.add(units + j, units + p);
                edge.add(units + j, unit_of(spec, p));
            }
        }
    }

    /// Analyses component `c` of `order` until
    /// its tasks' output jitters stop changing, at most [`MAX_ROUNDS`]
    /// sweeps (`false`: no fixed point). The units it reads from outside it
    /// are final. A sweep takes the units in order and re-analyses those
    /// whose inputs changed since their last analysis, each growth carried
    /// to its readers at once: a reader later in the order sees it in the
    /// same sweep.
    fn settle(
        &self,
        spec: &Spec,
        fp: &impl FixedPriority,
        order: &Components,
        c: usize,
        state: &mut State,
    ) -> bool {
        let units = &order.units[c][..];
        for &u in units {
            state.dirty[u] = true;
        }
        for _ in 0..MAX_ROUNDS {
            let mut analysed = 0;
            for &u in units.iter() {
                if !std::mem::take(&mut state.dirty[u]) {
                    continue;
                }
                analysed += 1;
                self.respond_unit(spec, fp, &state.arrivals, &mut state.responses, u);
                state.reach[u] = self.reach(u, &state.responses);
                let mut lists = std::mem::take(&mut state.lists);
                self.grow(spec, u, state, &mut lists.grown);
                self.refresh(spec, (&order.of_unit, c), state, &mut lists);
                lists.grown.clear();
                state.lists = lists;
            }
            if analysed == 0 {
                return true;
            }
        }
        for &u in units {
            state.dirty[u] = false;
        }
        false
    }

    /// The output jitters of unit `u`'s tasks from their responses, into
    /// `state.delay`; the tasks whose jitter changed, into `grown` (empty).
    fn grow(&self, spec: &Spec, u: usize, state: &mut State, grown: &mut Vec<usize>) {
        for i in self.unit_tasks(u) {
            let next = (|| {
                let grown = state.responses[i].actual? - spec.tasks[i].demand_min();
                // Monotone: a figure never shrinks from one round to the next.
                Some(grown.max(state.delay[i]?))
            })();
            if next != state.delay[i] {
                state.delay[i] = next;
                grown.push(i);
            }
        }
    }

    /// Recomputes the activations of every task downstream of the tasks
    /// whose jitter grew (`lists.grown`); the units of component `inside.1`
    /// (`inside.0` gives each unit's)
    /// that read one that changed where they read it ([`Deps::sees`]:
    /// their responses, computed from the old activations, are those the
    /// new ones give when both agree there). `lists` but `grown` are left
    /// empty.
    fn refresh(
        &self,
        spec: &Spec,
        inside: (&[usize], usize),
        state: &mut State,
        lists: &mut SweepLists,
    ) {
        let SweepLists {
            grown,
            downstream,
            next,
            changed,
            moved,
        } = lists;
        self.downstream(grown, &mut state.marked, next, downstream);
        // `marked`: the tasks whose output (jitter or activations) changed
        // so far. A task none of whose triggers is marked keeps its
        // activations, which are a function of its triggers' alone, and is
        // not recomputed (each task comes after its triggers).
        for &p in grown.iter() {
            state.marked[p] = true;
        }
        for &j in downstream.iter() {
            let Some((triggers, _)) = spec.tasks[j].triggers() else {
                continue;
            };
            if !triggers.iter().any(|&p| state.marked[p]) {
                continue;
            }
            let fresh = activation(spec, &state.delay, &state.arrivals, j);
            if fresh == state.arrivals[j] {
                continue;
            }
            state.marked[j] = true;
            changed.push(j);
            let old = std::mem::replace(&mut state.arrivals[j], fresh);
            let change = Change::of(spec, j, &old, &state.arrivals[j], moved);
            self.readers.reading(spec, j, inside, |u| {
                if !state.dirty[u] && self.sees(u, &change, state) {
                    state.dirty[u] = true;
                }
            });
        }
        for &j in grown.iter().chain(changed.iter()) {
            state.marked[j] = false;
        }
        downstream.clear();
        changed.clear();
    }

    /// Whether unit `u`'s responses, as last analysed, could read `change`:
    /// a response without windows, one whose reach passes the first window
    /// where the change shows, when it is of one of `u`'s own tasks (whose
    /// η⁺ a FIFO analysis reads up to the busy period) or changes a
    /// stream's period or number, else one with a fixed point at which the
    /// task's η⁺ differs (the tasks above are read through the demand
    /// alone, and their η⁺ only grows: equal at every fixed point the
    /// iterations stopped at, each iteration stops at the same one, in at
    /// most as many steps, `thread_rta::fifo_response_windows` and
    /// `sched::busy::level_response_from`).
    fn sees(&self, u: usize, change: &Change, state: &State) -> bool {
        let responses = &state.responses;
        let Some(reach) = state.reach[u] else {
            return true;
        };
        if reach <= change.same {
            return false;
        }
        let (Some(moved), true) = (&change.moved, change.unit != u) else {
            return true;
        };
        self.unit_tasks(u).any(|i| {
            let windows = responses[i].windows.as_deref().unwrap_or(&[]);
            let first = windows.partition_point(|&w| w <= change.same);
            windows[first..]
                .iter()
                .any(|&w| moved.iter().any(|(s, t)| s.eta(w) != t.eta(w)))
        })
    }

    /// The tasks triggered, directly or not, by the tasks `from`, each
    /// after its triggers, into `out` (empty; `marked`, clear, and `next`,
    /// empty, are left so).
    fn downstream(
        &self,
        from: &[usize],
        marked: &mut [bool],
        next: &mut Vec<usize>,
        out: &mut Vec<usize>,
    ) {
        next.extend(from.iter().flat_map(|&p| &self.consumers[p]));
        while let Some(j) = next.pop() {
            if !marked[j] {
                marked[j] = true;
                out.push(j);
                next.extend(&self.consumers[j]);
            }
        }
        for &j in out.iter() {
            marked[j] = false;
        }
        out.sort_unstable_by_key(|&j| self.trigger_rank[j]);
    }

    /// The largest reach of unit `u`'s responses (`None`: a response
    /// without windows, re-analysed on any change).
    fn reach(&self, u: usize, responses: &[Response]) -> Option<Nanos> {
        self.unit_tasks(u)
            .try_fold(0, |m: Nanos, i| Some(m.max(responses[i].reach()?)))
    }

    /// The responses of unit `u`'s tasks, into `responses`.
    fn respond_unit(
        &self,
        spec: &Spec,
        fp: &impl FixedPriority,
        arrivals: &[Option<Arrivals>],
        responses: &mut [Response],
        u: usize,
    ) {
        // The members' FIFO figures, shared between members that see the
        // same thread (ThreadCache).
        let mut cache = Vec::new();
        for i in self.unit_tasks(u) {
            responses[i] = respond(spec, fp, self, arrivals, i, &responses[i], &mut cache);
        }
    }

    /// Each task's activations given each task's output jitter (`None`:
    /// unbounded): periodic tasks their period and release jitter, a
    /// data-triggered one its triggers' publications joined.
    fn activations(&self, spec: &Spec, delay: &[Option<Nanos>]) -> Vec<Option<Arrivals>> {
        let mut out = vec![None; spec.tasks.len()];
        for &i in &self.trigger_order {
            out[i] = activation(spec, delay, &out, i);
        }
        out
    }
}

/// FIFO responses of one thread this round, by (a member whose tasks
/// above are the same, blocking), for members whose own work is the work
/// the others see of them (then every input of
/// [`crate::thread_rta::fifo_response`] is the same for them, and so is
/// its figure).
type ThreadCache = Vec<(usize, Nanos, Option<FifoStops>)>;

/// One round's response of a task.
#[derive(Debug, Clone)]
struct Response {
    budget: Option<Nanos>,
    job: Option<Nanos>,
    /// From the actual release (the first one of a merged job), for the
    /// output jitter; at most `job`.
    actual: Option<Nanos>,
    /// The fixed points at which the figures' iterations stopped, ascending
    /// and distinct; the last, the reach, bounds every window at which they
    /// read any η⁺ (`None`: unbounded, or not known).
    windows: Option<Vec<Nanos>>,
    /// A FIFO analysis' stops, the next one's warm start
    /// ([`fifo_response_from`]; `None`: none, or not a FIFO analysis).
    fifo: Option<FifoStops>,
    /// A fixed-priority analysis' stops, the next one's warm start
    /// ([`FixedPriority::periodic_response_windows`]).
    fp: Option<FpStops>,
}

impl Response {
    /// No figure: unbounded.
    const NONE: Response = Response {
        budget: None,
        job: None,
        actual: None,
        windows: None,
        fifo: None,
        fp: None,
    };

    /// The largest window at which the figures read an η⁺ (`None`: not
    /// known).
    fn reach(&self) -> Option<Nanos> {
        Some(self.windows.as_ref()?.last().copied().unwrap_or(0))
    }
}

/// Task `i`'s activations, its triggers' already in `arrivals`: its
/// period and release jitter, or its triggers' publications joined.
fn activation(
    spec: &Spec,
    delay: &[Option<Nanos>],
    arrivals: &[Option<Arrivals>],
    i: usize,
) -> Option<Arrivals> {
    let t = &spec.tasks[i];
    match t.triggers() {
        None => t
            .fixed_period()
            .map(|period| Arrivals::periodic(period, t.jitter)),
        Some((triggers, join)) => {
            // Every trigger's publications: its activations delayed by its
            // output jitter (`None` while one is unbounded).
            let inputs = triggers
                .iter()
                .map(|&p| Some((arrivals[p].as_ref()?, delay[p]?)));
            match join {
                Join::Any => Arrivals::any_delayed(inputs),
                Join::All => Arrivals::all_delayed(inputs),
            }
        }
    }
}

/// Task `i`'s jobs merge: it runs in a thread or is data-triggered.
pub fn merging(spec: &Spec, i: usize) -> bool {
    let t = &spec.tasks[i];
    t.thread.is_some() || t.is_triggered()
}

/// Task `i`'s response times this round, `old` its last (its analysis'
/// warm start: every activation has only grown since).
fn respond(
    spec: &Spec,
    fp: &impl FixedPriority,
    deps: &Deps,
    arrivals: &[Option<Arrivals>],
    i: usize,
    old: &Response,
    cache: &mut ThreadCache,
) -> Response {
    let t = &spec.tasks[i];
    if t.server == Server::Background {
        return Response::NONE;
    }
    if !merging(spec, i) {
        let Some(hp) = streams_above(spec, deps, arrivals, i) else {
            return Response::NONE;
        };
        return fixed_priority_respond(fp, i, &hp, old);
    }
    let mut models = Vec::with_capacity(deps.readers.prefix[i].len());
    if for_each_above(spec, deps, arrivals, i, |c, a| models.push((c, a))).is_none() {
        return Response::NONE;
    }
    let blocking = fp.blocking(i);
    let shared = t.demand() == deps.interference[i];
    let known = cache
        .iter()
        .find(|&&(k, b, _)| shared && b == blocking && deps.same_above(spec, k, i))
        .map(|(_, _, r)| r.clone());
    let stops = known.unwrap_or_else(|| {
        let warm = old.fifo.as_ref();
        let r = thread_response(spec, deps, arrivals, i, &models, blocking, warm);
        if shared {
            cache.push((i, blocking, r.clone()));
        }
        r
    });
    let Some(stops) = stops else {
        return Response::NONE;
    };
    let actual = stops.response();
    // A periodic task's figure counts from its nominal release.
    let job = actual.checked_add(t.jitter);
    Response {
        budget: job,
        job,
        actual: Some(actual),
        windows: Some(stops.windows()),
        fifo: Some(stops),
        fp: None,
    }
}

/// Hands `visit` each task above task `i` as its interference and its
/// activations; `None` (having stopped) at the first without activations,
/// where nothing bounds what it brings.
fn for_each_above<'a>(
    spec: &Spec,
    deps: &Deps,
    arrivals: &'a [Option<Arrivals>],
    i: usize,
    mut visit: impl FnMut(Nanos, &'a Arrivals),
) -> Option<()> {
    for j in deps.above(spec, i) {
        visit(deps.interference[j], arrivals[j].as_ref()?);
    }
    Some(())
}

/// Each stream above task `i` as (C, T, J), in one pass over the tasks
/// above; `None` when one has no activations.
fn streams_above(
    spec: &Spec,
    deps: &Deps,
    arrivals: &[Option<Arrivals>],
    i: usize,
) -> Option<Vec<Load>> {
    // Room for two streams a task; more grows the list.
    let mut hp: Vec<Load> = Vec::with_capacity(2 * deps.readers.prefix[i].len());
    let each =
        |c: Nanos, a: &Arrivals| hp.extend(a.streams.iter().map(|s| (c, s.period, s.jitter)));
    for_each_above(spec, deps, arrivals, i, each)?;
    Some(hp)
}

/// The response times of task `i`, which no job merges into (periodic and
/// thread-less), under fixed priority from its streams above `hp`.
fn fixed_priority_respond(
    fp: &impl FixedPriority,
    i: usize,
    hp: &[Load],
    old: &Response,
) -> Response {
    let ((budget, job), stops) = fp.periodic_response_windows(i, hp, old.fp.as_ref());
    let stops = stops.filter(|_| budget.is_some() && job.is_some());
    Response {
        budget,
        job,
        actual: job,
        windows: stops.as_ref().map(FpStops::windows),
        fifo: None,
        fp: stops,
    }
}

/// The FIFO response of task `i`'s jobs in its thread (a thread of its
/// own for a thread-less data-triggered task), from their first release,
/// started from `warm` ([`fifo_response_from`]).
fn thread_response(
    spec: &Spec,
    deps: &Deps,
    arrivals: &[Option<Arrivals>],
    i: usize,
    above: &[(Nanos, &Arrivals)],
    blocking: Nanos,
    warm: Option<&FifoStops>,
) -> Option<FifoStops> {
    let t = &spec.tasks[i];
    let alone = [i];
    let members = t.thread.map_or(&alone[..], |th| &deps.members[th][..]);
    let members: Option<Vec<Member>> = members
        .iter()
        .map(|&j| {
            let work = if j == i {
                t.demand()
            } else {
                deps.interference[j]
            };
            Some(Member {
                work,
                arrivals: arrivals[j].as_ref()?,
            })
        })
        .collect::<Option<_>>();
    fifo_response_from(&members?, above, blocking, warm)
}

/// The iteration's last round as each task's figures, with the gaps.
fn finish(
    spec: &Spec,
    arrivals: Vec<Option<Arrivals>>,
    responses: Vec<Response>,
) -> Vec<EventResult> {
    let n = spec.tasks.len();
    let mut gap: Vec<Option<Option<Nanos>>> = vec![None; n];
    for i in 0..n {
        activation_gap(spec, &responses, &mut gap, i);
    }
    let gap: Vec<Option<Nanos>> = gap.into_iter().map(Option::flatten).collect();
    let publish_gap = |i: usize| gap[i]?.checked_add(responses[i].job?);
    (0..n)
        .zip(arrivals)
        .map(|(i, arrivals)| EventResult {
            budget: responses[i].budget,
            job: responses[i].job,
            timing: EventTiming {
                merging: merging(spec, i),
                arrivals,
                response: responses[i].job,
                gap: gap[i],
                publish_gap: publish_gap(i),
                waits: waits(spec, i, &publish_gap),
            },
        })
        .collect()
}

/// A of task `i` into `memo`: T for a periodic task; for a
/// data-triggered one, after any instant each trigger publishes within
/// its `P = A + R`, so `join = "any"` is released within the least of
/// them, `join = "all"` within the largest.
fn activation_gap(
    spec: &Spec,
    responses: &[Response],
    memo: &mut [Option<Option<Nanos>>],
    i: usize,
) -> Option<Nanos> {
    if let Some(known) = memo[i] {
        return known;
    }
    let t = &spec.tasks[i];
    let a = match t.triggers() {
        None => t.fixed_period(),
        Some((triggers, join)) => {
            let p: Vec<Option<Nanos>> = triggers
                .iter()
                .map(|&q| activation_gap(spec, responses, memo, q)?.checked_add(responses[q].job?))
                .collect();
            match join {
                Join::Any => p.into_iter().flatten().min(),
                Join::All => p.into_iter().collect::<Option<Vec<_>>>()?.into_iter().max(),
            }
        }
    };
    memo[i] = Some(a);
    a
}

/// Per trigger of task `i`, the longest from its publication to the
/// release of `i` it brings (see [`EventTiming::waits`]).
fn waits(
    spec: &Spec,
    i: usize,
    publish_gap: &impl Fn(usize) -> Option<Nanos>,
) -> Vec<(usize, Option<Nanos>)> {
    let Some((triggers, join)) = spec.tasks[i].triggers() else {
        return Vec::new();
    };
    triggers
        .iter()
        .map(|&p| {
            let wait = match join {
                Join::Any => Some(0),
                Join::All => triggers
                    .iter()
                    .filter(|&&q| q != p)
                    .map(|&q| publish_gap(q))
                    .try_fold(0, |m: Nanos, g| Some(m.max(g?))),
            };
            (p, wait)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_lists_its_own_moved_streams_in_the_kept_list() {
        let (fast, slow) = (Arrivals::periodic(10, 0), Arrivals::periodic(30, 2));
        let a = Arrivals::any(&[&fast, &slow]);
        let b = Arrivals::any(&[&Arrivals::periodic(10, 4), &slow]);
        let c = Arrivals::any(&[&fast, &Arrivals::periodic(30, 9)]);
        let mut moved = Vec::new();
        let first = Change::moved(0, &a, &b, &mut moved);
        assert_eq!(first.moved, Some(&[(a.streams[0], b.streams[0])][..]));
        // The list kept from the first change holds the second's alone.
        let second = Change::moved(0, &a, &c, &mut moved);
        assert_eq!(second.moved, Some(&[(a.streams[1], c.streams[1])][..]));
        assert_eq!(second.same, a.same_up_to(&c));
    }
}
