//! The event analysis' holistic iteration (`events::analyze`: the tasks
//! above each task and each thread's tasks found once, each round only
//! the responses whose inputs changed re-analysed, a thread's members that
//! see the same inputs analysed once) against the straightforward
//! iteration it replaced, kept here as the reference: every task's
//! activations and response recomputed every round, a thread's members
//! found by a scan of every task. On a few hundred random event-triggered
//! systems both give the same figures, to the last field, and so does
//! the whole `analyze` (its fixed-priority analysis built per CPU).

use rtpipe_analysis::arrivals::Arrivals;
use rtpipe_analysis::events::{self, EventResult, EventTiming, FixedPriority, MAX_ROUNDS};
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

/// The straightforward holistic iteration.
fn reference(spec: &Spec, fp: &impl FixedPriority) -> Vec<(Option<Nanos>, Option<Nanos>)> {
    let n = spec.tasks.len();
    let mut delay: Vec<Option<Nanos>> = vec![Some(0); n];
    for _ in 0..MAX_ROUNDS {
        let arrivals: Vec<Option<Arrivals>> = (0..n).map(|i| activation(spec, &delay, i)).collect();
        let responses: Vec<Response> = (0..n).map(|i| respond(spec, fp, &arrivals, i)).collect();
        let next: Vec<Option<Nanos>> = (0..n)
            .map(|i| Some((responses[i].2? - spec.tasks[i].demand_min()).max(delay[i]?)))
            .collect();
        if next == delay {
            return responses.iter().map(|r| (r.0, r.1)).collect();
        }
        delay = next;
    }
    vec![(None, None); n]
}

/// Task `i`'s activations, its triggers' recomputed (no memo).
fn activation(spec: &Spec, delay: &[Option<Nanos>], i: usize) -> Option<Arrivals> {
    let t = &spec.tasks[i];
    match t.triggers() {
        None => Some(Arrivals::periodic(t.fixed_period()?, t.jitter)),
        Some((triggers, join)) => {
            let outputs: Vec<Arrivals> = triggers
                .iter()
                .map(|&p| activation(spec, delay, p)?.delayed(delay[p]?))
                .collect::<Option<_>>()?;
            let refs: Vec<&Arrivals> = outputs.iter().collect();
            Some(match join {
                Join::Any => Arrivals::any(&refs),
                Join::All => Arrivals::all(&refs),
            })
        }
    }
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
