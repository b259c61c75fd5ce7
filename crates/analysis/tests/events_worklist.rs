//! The event analysis' holistic iteration (`events::analyze`: the tasks
//! above each task and each thread's tasks found once, each round only
//! the responses whose inputs changed re-analysed, a thread's members that
//! see the same inputs analysed once) against the straightforward
//! iteration it replaced, kept here as the reference: every task's
//! activations and response recomputed every round, a thread's members
//! found by a scan of every task. On a few hundred random event-triggered
//! systems both give the same figures, to the last field, and so does
//! the whole `analyze` (its fixed-priority analysis built per CPU).
//! The reference runs every task's response in every round (Jacobi);
//! `events::analyze` runs the units' strongly connected components in
//! dependency order, so the two orders are held together also on
//! systems whose threads trigger each other in cycles and on ones whose
//! figures become unbounded. The rounds climb no faster than the sweeps,
//! so where the rounds run out first they go on (`LONGER_ROUNDS`) before
//! the figures are compared.

use proptest::prelude::*;
use rtpipe_analysis::arrivals::Arrivals;
use rtpipe_analysis::events::{self, EventResult, EventTiming, FixedPriority, MAX_ROUNDS};
use rtpipe_analysis::graph::strongly_connected;
use rtpipe_analysis::sched::{interference, interferers, level_response, top_priorities, OwnJobs};
use rtpipe_analysis::thread_rta::{fifo_response, Member};
use rtpipe_model::gen::{event_triggered_system, EventGenConfig, Rng};
use rtpipe_model::{Join, Nanos, Server, Spec};

const SYSTEMS: u64 = 200;

/// The fixed-priority analysis by scans of every task (the generated
/// systems have no servers, sections or overheads).
struct Naive<'a> {
    spec: &'a Spec,
    prio: Vec<Option<usize>>,
    top: Vec<Option<usize>>,
}

impl<'a> Naive<'a> {
    fn new(spec: &'a Spec) -> Naive<'a> {
        let prio = spec.policy().priorities(spec);
        let top = top_priorities(spec, &prio);
        Naive { spec, prio, top }
    }
}

impl FixedPriority for Naive<'_> {
    fn above(&self, i: usize) -> Vec<usize> {
        interferers(self.spec, &self.prio, &self.top, i)
    }

    fn interference(&self, j: usize) -> Nanos {
        interference(&self.spec.tasks[j])
    }

    fn blocking(&self, i: usize) -> Nanos {
        rtpipe_analysis::blocking::blocking(self.spec, &self.prio, i)
    }

    fn periodic_response(
        &self,
        i: usize,
        hp: &[(Nanos, Nanos, Nanos)],
    ) -> (Option<Nanos>, Option<Nanos>) {
        let t = &self.spec.tasks[i];
        let own = |work| OwnJobs {
            work,
            switch: rtpipe_analysis::overheads::own(self.spec, i),
            blocking: self.blocking(i),
            jitter: t.jitter,
            period: t.fixed_period().expect("a periodic task"),
        };
        (
            level_response(own(t.budget()), hp),
            level_response(own(t.demand()), hp),
        )
    }
}

/// One round's (budget, job, actual) response of a task.
type Response = (Option<Nanos>, Option<Nanos>, Option<Nanos>);

/// The straightforward holistic iteration, at most [`MAX_ROUNDS`] rounds.
fn reference(spec: &Spec, fp: &impl FixedPriority) -> Vec<(Option<Nanos>, Option<Nanos>)> {
    let mut rounds = Rounds::new(spec);
    rounds.run_to(spec, fp, MAX_ROUNDS);
    rounds.figures()
}

/// The straightforward holistic iteration's state: every task's delay
/// (output jitter) and last (budget, job) figures, after `round` rounds,
/// with the round it reached the fixed point in.
struct Rounds {
    delay: Vec<Option<Nanos>>,
    /// The delays [`SETTLED_ROUNDS`] before the last cap the rounds ran to.
    settled_from: Vec<Option<Nanos>>,
    last: Vec<(Option<Nanos>, Option<Nanos>)>,
    round: usize,
    converged: Option<usize>,
}

impl Rounds {
    fn new(spec: &Spec) -> Rounds {
        let n = spec.tasks.len();
        Rounds {
            delay: vec![Some(0); n],
            settled_from: vec![Some(0); n],
            last: vec![(None, None); n],
            round: 0,
            converged: None,
        }
    }

    /// Goes on to the fixed point or to round `cap`, whichever comes first.
    fn run_to(&mut self, spec: &Spec, fp: &impl FixedPriority, cap: usize) {
        assert!(
            cap >= self.round + SETTLED_ROUNDS,
            "a cap past the settling rounds"
        );
        while self.converged.is_none() && self.round < cap {
            if self.round == cap - SETTLED_ROUNDS {
                self.settled_from.clone_from(&self.delay);
            }
            self.step(spec, fp);
        }
    }

    /// One round: every task's activations and response recomputed.
    fn step(&mut self, spec: &Spec, fp: &impl FixedPriority) {
        let n = spec.tasks.len();
        let delay = &self.delay;
        let mut memo = vec![None; n];
        let arrivals: Vec<Option<Arrivals>> = (0..n)
            .map(|i| activation(spec, delay, &mut memo, i))
            .collect();
        let responses: Vec<Response> = (0..n).map(|i| respond(spec, fp, &arrivals, i)).collect();
        self.last = responses.iter().map(|r| (r.0, r.1)).collect();
        let next: Vec<Option<Nanos>> = (0..n)
            .map(|i| Some((responses[i].2? - spec.tasks[i].demand_min()).max(delay[i]?)))
            .collect();
        if next == self.delay {
            self.converged = Some(self.round);
        }
        self.delay = next;
        self.round += 1;
    }

    /// The figures: at the fixed point, the last round's; out of rounds,
    /// unbounded for the tasks whose delay still moved in the last
    /// [`SETTLED_ROUNDS`] (the ones the rounds gave up on), while a task
    /// whose delay had settled keeps its figures (the component order
    /// analyses a component that no diverging one feeds to its fixed
    /// point, where the rounds' cap is spent elsewhere).
    fn figures(&self) -> Vec<(Option<Nanos>, Option<Nanos>)> {
        if self.converged.is_some() {
            return self.last.clone();
        }
        (0..self.delay.len())
            .map(|i| {
                if self.settled_from[i] == self.delay[i] {
                    self.last[i]
                } else {
                    (None, None)
                }
            })
            .collect()
    }
}

/// The rounds at the end of a run over which a task's delay must not move
/// to count as settled.
const SETTLED_ROUNDS: usize = 100;

/// Task `i`'s activations from its triggers' (each found once a round:
/// `memo`).
fn activation(
    spec: &Spec,
    delay: &[Option<Nanos>],
    memo: &mut [Option<Option<Arrivals>>],
    i: usize,
) -> Option<Arrivals> {
    if let Some(known) = &memo[i] {
        return known.clone();
    }
    let t = &spec.tasks[i];
    let found = match t.triggers() {
        None => t
            .fixed_period()
            .map(|period| Arrivals::periodic(period, t.jitter)),
        Some((triggers, join)) => triggers
            .iter()
            .map(|&p| activation(spec, delay, memo, p)?.delayed(delay[p]?))
            .collect::<Option<Vec<Arrivals>>>()
            .map(|outputs| {
                let refs: Vec<&Arrivals> = outputs.iter().collect();
                match join {
                    Join::Any => Arrivals::any(&refs),
                    Join::All => Arrivals::all(&refs),
                }
            }),
    };
    memo[i] = Some(found.clone());
    found
}

fn respond(
    spec: &Spec,
    fp: &impl FixedPriority,
    arrivals: &[Option<Arrivals>],
    i: usize,
) -> Response {
    let t = &spec.tasks[i];
    if t.server == Server::Background {
        return (None, None, None);
    }
    let above: Vec<usize> = fp
        .above(i)
        .into_iter()
        .filter(|&j| t.thread.is_none() || spec.tasks[j].thread != t.thread)
        .collect();
    let Some(models) = above
        .iter()
        .map(|&j| arrivals[j].as_ref().map(|a| (fp.interference(j), a)))
        .collect::<Option<Vec<_>>>()
    else {
        return (None, None, None);
    };
    if !events::merging(spec, i) {
        let hp: Vec<(Nanos, Nanos, Nanos)> = models
            .iter()
            .flat_map(|&(c, a)| a.streams.iter().map(move |s| (c, s.period, s.jitter)))
            .collect();
        let (budget, job) = fp.periodic_response(i, &hp);
        return (budget, job, job);
    }
    let members: Vec<usize> = match t.thread {
        Some(th) => (0..spec.tasks.len())
            .filter(|&j| spec.tasks[j].thread == Some(th))
            .collect(),
        None => vec![i],
    };
    let members: Option<Vec<Member>> = members
        .iter()
        .map(|&j| {
            let work = if j == i {
                t.demand()
            } else {
                fp.interference(j)
            };
            Some(Member {
                work,
                arrivals: arrivals[j].as_ref()?,
            })
        })
        .collect();
    let Some(actual) = members.and_then(|m| fifo_response(&m, &models, fp.blocking(i))) else {
        return (None, None, None);
    };
    let job = actual.checked_add(t.jitter);
    (job, job, Some(actual))
}

/// System `seed`: small ones as the campaign draws them, and larger ones
/// (every tenth: up to 16 chains, threads of many tasks) where the worklist and the
/// shared thread figures matter.
fn system(seed: u64) -> Spec {
    let mut rng = Rng::new(seed ^ 0xe7e7);
    let cfg = if seed.is_multiple_of(10) {
        EventGenConfig {
            min_chains: 8,
            max_chains: 16,
            max_threads: 8,
            max_cpus: 4,
            utilization: 0.2 + 0.6 * rng.unit(),
            thread_fraction: rng.unit(),
            ..EventGenConfig::default()
        }
    } else {
        EventGenConfig {
            utilization: 0.2 + 0.7 * rng.unit(),
            ..EventGenConfig::default()
        }
    };
    event_triggered_system(seed, &cfg)
}

#[test]
fn the_worklist_iteration_gives_the_straightforward_figures() {
    let mut bounded = 0;
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        let naive = Naive::new(&spec);
        let want = reference(&spec, &naive);
        let fast: Vec<EventResult> = events::analyze(&spec, &naive);
        let got: Vec<(Option<Nanos>, Option<Nanos>)> =
            fast.iter().map(|r| (r.budget, r.job)).collect();
        assert_eq!(got, want, "seed {seed}: events::analyze");
        // The whole analysis: its per-CPU fixed-priority analysis gives the
        // same event facts as the naive one.
        let report = rtpipe_analysis::analyze(&spec);
        let timings: Vec<&EventTiming> = fast.iter().map(|r| &r.timing).collect();
        for (i, t) in report.timing.iter().enumerate() {
            assert_eq!(
                format!("{:?}", t.events.as_ref()),
                format!("{:?}", Some(timings[i])),
                "seed {seed}: task {i}'s event facts"
            );
            assert_eq!(
                (t.response_time, t.job_response_time),
                want[i],
                "seed {seed}: task {i}"
            );
        }
        bounded += usize::from(want.iter().all(|r| r.1.is_some()));
    }
    // Most systems are bounded throughout: the figures compared are numbers.
    assert!(
        bounded * 2 > SYSTEMS as usize,
        "{bounded} of {SYSTEMS} bounded"
    );
}

/// Whether some threads trigger each other in a cycle (a member of one
/// triggers a member of the next, and so back to the first; a member that
/// triggers one of its own thread included): their figures wait for each
/// other and are iterated together.
fn threads_cycle(spec: &Spec) -> bool {
    let mut succ = vec![Vec::new(); spec.threads.len()];
    for t in &spec.tasks {
        if let (Some(to), Some((triggers, _))) = (t.thread, t.triggers()) {
            for from in triggers.iter().filter_map(|&p| spec.tasks[p].thread) {
                succ[from].push(to);
            }
        }
    }
    let comp = strongly_connected(succ.len(), &succ);
    (0..succ.len()).any(|a| succ[a].iter().any(|&b| comp[b] == comp[a]))
}

/// A system with many data-triggered tasks in few threads, up to
/// overloaded CPUs: thread cycles and unbounded figures are common.
fn cyclic_config(
    chains: usize,
    threads: usize,
    cpus: u32,
    utilization: f64,
    thread_fraction: f64,
) -> EventGenConfig {
    EventGenConfig {
        min_chains: chains,
        max_chains: chains,
        max_threads: threads,
        max_cpus: cpus,
        utilization,
        data_fraction: 0.9,
        thread_fraction,
        ..EventGenConfig::default()
    }
}

/// `events::analyze`'s (budget, job) figures, against the reference's.
/// Where the rounds reach the fixed point, the figures are the same to the
/// last field. The rounds (Jacobi) climb no faster than the component
/// order's sweeps (Gauss–Seidel, a component analysed once what it reads is
/// final), so where they run out they may not yet have reached a fixed
/// point the sweeps found: there they go on, up to [`LONGER_ROUNDS`], and
/// each figure must be the one they end at, or unbounded (a component out
/// of its own sweeps).
/// The rounds, where they ended, are returned.
fn assert_same_figures(spec: &Spec) -> Rounds {
    let naive = Naive::new(spec);
    let got: Vec<(Option<Nanos>, Option<Nanos>)> = events::analyze(spec, &naive)
        .iter()
        .map(|r| (r.budget, r.job))
        .collect();
    let mut rounds = Rounds::new(spec);
    rounds.run_to(spec, &naive, MAX_ROUNDS);
    let figures = rounds.figures();
    if rounds.converged.is_some() || got == figures {
        assert_eq!(got, figures);
        return rounds;
    }
    rounds.run_to(spec, &naive, LONGER_ROUNDS);
    let figures = rounds.figures();
    if rounds.converged.is_none() {
        assert_eq!(got, figures, "out of {LONGER_ROUNDS} rounds");
        return rounds;
    }
    for (i, (fast, fixed_point)) in got.iter().zip(&figures).enumerate() {
        assert!(
            fast == fixed_point || *fast == (None, None),
            "task {i}: {fast:?}, where the rounds reach {fixed_point:?}"
        );
    }
    rounds
}

/// The rounds the reference goes on to where it ran out of [`MAX_ROUNDS`]
/// and the component order did not.
const LONGER_ROUNDS: usize = 10 * MAX_ROUNDS;

#[test]
fn the_component_order_gives_the_round_figures_on_cycles_and_overloads() {
    let (mut cyclic, mut unbounded, mut bounded) = (0, 0, 0);
    for seed in 0..120u64 {
        let mut rng = Rng::new(seed ^ 0x5cc);
        let cfg = cyclic_config(
            2 + (seed % 8) as usize,
            1 + (seed % 3) as usize,
            1 + (seed % 2) as u32,
            0.3 + 0.9 * rng.unit(),
            0.6 + 0.4 * rng.unit(),
        );
        let spec = event_triggered_system(seed, &cfg);
        let figures = assert_same_figures(&spec).figures();
        cyclic += usize::from(threads_cycle(&spec));
        let all = figures.iter().all(|r| r.1.is_some());
        bounded += usize::from(all);
        unbounded += usize::from(!all);
    }
    // The cases the two orders could part on are all drawn.
    assert!(cyclic >= 10, "{cyclic} systems with a cycle of threads");
    assert!(
        unbounded >= 10,
        "{unbounded} systems with an unbounded figure"
    );
    assert!(bounded >= 10, "{bounded} bounded systems");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    #[test]
    fn random_systems_give_the_same_figures_in_either_order(
        seed in any::<u64>(),
        chains in 1usize..=10,
        threads in 1usize..=5,
        cpus in 1u32..=3,
        utilization in 0.2f64..1.3,
        thread_fraction in 0.0f64..=1.0,
    ) {
        let cfg = cyclic_config(chains, threads, cpus, utilization, thread_fraction);
        assert_same_figures(&event_triggered_system(seed, &cfg));
    }
}

/// A system proptest drew where one component diverges slowly and the
/// rounds run out: a task no diverging component feeds (its delay settled
/// at 1 µs from the first round) keeps its figures, 52 µs, as in the
/// component order; the rounds used to call every task unbounded.
#[test]
fn a_component_no_diverging_one_feeds_keeps_its_figures_when_the_rounds_run_out() {
    let cfg = cyclic_config(8, 4, 3, 0.9321958104652496, 0.42904570351881055);
    assert_same_figures(&event_triggered_system(6237359605873261581, &cfg));
}

/// A system proptest drew (one CPU, two threads, utilisation 0.77) whose
/// rounds reach their fixed point only in round 1,454, past
/// [`MAX_ROUNDS`], where the component order's sweeps reach it within
/// theirs: the same figures, once the rounds go on.
#[test]
fn the_rounds_reach_the_sweeps_figures_past_their_cap() {
    let cfg = cyclic_config(10, 2, 1, 0.7745162726491704, 0.5837276469482792);
    let spec = event_triggered_system(7360017079293678417, &cfg);
    let rounds = assert_same_figures(&spec);
    assert!(
        rounds.converged > Some(MAX_ROUNDS),
        "the rounds' fixed point in round {:?}",
        rounds.converged
    );
    let figures = rounds.figures();
    assert!(figures.iter().all(|f| f.1.is_some()), "{figures:?}");
}
