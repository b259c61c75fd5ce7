//! Threads and data-triggered tasks in the simulator, on systems small
//! enough to schedule by hand: FIFO order in a thread, merging, join all
//! waiting for both triggers, preemption between threads, a timer item in
//! a thread; and invariants of random event-triggered systems.

use rtpipe_analysis::Metric;
use rtpipe_joblog::{JobRecord, SimResult, Trigger};
use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::search::{search, SearchConfig};
use rtpipe_sim::{simulate, ExecModel, Jitter, Phasing, SimConfig};

const US: Nanos = 1000;

/// A spec in µs with explicit priorities, from its channel, thread and task
/// tables.
fn spec(tables: &str) -> Spec {
    let text = format!(
        "[system]\nname = \"e\"\ntime_unit = \"us\"\npriorities = \"explicit\"\n\n\
         [channels.m]\nbandwidth = 1000\noverhead = 0\n\n{tables}"
    );
    rtpipe_testkit::spec("e.toml", &text)
}

/// A synchronous worst-case run of `horizon` µs with its job log.
fn run(s: &Spec, horizon: Nanos) -> SimResult {
    let cfg = SimConfig {
        log_jobs: true,
        ..SimConfig::new(horizon * US)
    };
    simulate(s, &cfg).unwrap_or_else(|e| panic!("{e}"))
}

/// The logged jobs of task `name`: (read, finish) in µs, in completion
/// order.
fn spans(s: &Spec, r: &SimResult, name: &str) -> Vec<(Nanos, Nanos)> {
    jobs(s, r, name)
        .map(|j| (j.read / US, j.finish / US))
        .collect()
}

fn jobs<'a>(s: &Spec, r: &'a SimResult, name: &str) -> impl Iterator<Item = &'a JobRecord> {
    let i = s
        .task_index(name)
        .unwrap_or_else(|| panic!("no task {name}"));
    r.jobs.iter().filter(move |j| j.task == i)
}

#[test]
fn a_thread_runs_its_jobs_in_release_order_one_at_a_time() {
    // x and z are released at 0 (declaration order: x first), y at 1, the
    // lowest priority thread-less task q at 0: the thread runs x, z, y back
    // to back, never preempting its own running job; q waits for it all.
    let s = spec(
        "[threads.w]\npriority = 1\n\n\
         [tasks.x]\nexec = 4\nperiod = 100\nthread = \"w\"\n\
         [tasks.y]\nexec = 3\nperiod = 100\noffset = 1\nthread = \"w\"\n\
         [tasks.z]\nexec = 2\nperiod = 100\nthread = \"w\"\n\
         [tasks.q]\nexec = 1\nperiod = 100\npriority = 2\n",
    );
    let r = run(&s, 50);
    assert_eq!(spans(&s, &r, "x"), vec![(0, 4)]);
    assert_eq!(spans(&s, &r, "z"), vec![(4, 6)]);
    assert_eq!(spans(&s, &r, "y"), vec![(6, 9)]);
    assert_eq!(spans(&s, &r, "q"), vec![(9, 10)]);
}

#[test]
fn a_timer_and_a_publication_at_one_instant_queue_in_declaration_order() {
    // a publishes at 1, releasing c; the timer item p (declared before c)
    // is released at 1 too: the thread runs p first, then c, although the
    // publication came first in the instant.
    let s = spec(
        "[threads.w]\npriority = 2\n\n\
         [tasks.a]\nexec = 1\nperiod = 10\npriority = 1\noutput = { channel = \"m\", size = 0 }\n\
         [tasks.p]\nexec = 2\nperiod = 10\noffset = 1\nthread = \"w\"\n\
         [tasks.c]\nactivation = \"data\"\nreads = [\"a\"]\nexec = 1\nthread = \"w\"\n",
    );
    let r = run(&s, 10);
    assert_eq!(spans(&s, &r, "p"), vec![(1, 3)]);
    assert_eq!(spans(&s, &r, "c"), vec![(3, 4)]);
}

#[test]
fn a_release_while_a_job_is_queued_merges_into_it() {
    // The timer item t (every 10 µs from 5) waits behind l's 50 µs job in
    // their thread: its releases at 15, 25, 35 and 45 join the job queued
    // at 5, which runs at 50; from 55 on it runs at once.
    let s = spec(
        "[threads.w]\npriority = 1\ncpu = 0\n\n\
         [tasks.l]\nexec = 50\nperiod = 1000\nthread = \"w\"\n\
         [tasks.t]\nexec = 1\nperiod = 10\noffset = 5\nthread = \"w\"\n",
    );
    let r = run(&s, 100);
    let t = s.task_index("t").unwrap_or(0);
    assert_eq!(r.tasks[t].merged, 4);
    assert_eq!(r.tasks[t].released, 6, "5, 55, 65, 75, 85, 95");
    assert_eq!(
        spans(&s, &r, "t"),
        vec![(50, 51), (55, 56), (65, 66), (75, 76), (85, 86), (95, 96)]
    );
    // Its response counts from the release it merged into.
    assert_eq!(r.tasks[t].max_response, Some(46 * US));
}

#[test]
fn a_thread_less_periodic_task_queues_every_job() {
    // The same load without threads: nothing merges, every job queues.
    let s = spec(
        "[tasks.l]\nexec = 50\nperiod = 1000\npriority = 1\n\
         [tasks.t]\nexec = 1\nperiod = 10\noffset = 5\npriority = 2\n",
    );
    let r = run(&s, 100);
    let t = s.task_index("t").unwrap_or(0);
    assert_eq!((r.tasks[t].merged, r.tasks[t].released), (0, 10));
}

/// Producers a (publishes at 1, 11, …) and b (at 4, 14, …) and a consumer
/// c triggered by both, joined `join`.
fn fusion(join: &str) -> Spec {
    spec(&format!(
        "[tasks.a]\nexec = 1\nperiod = 10\npriority = 1\noutput = {{ channel = \"m\", size = 0 }}\n\
         [tasks.b]\nexec = 1\nperiod = 10\noffset = 3\npriority = 2\noutput = {{ channel = \"m\", size = 0 }}\n\
         [tasks.c]\nactivation = \"data\"\nreads = [\"a\", \"b\"]\njoin = \"{join}\"\nexec = 2\npriority = 3\n"
    ))
}

#[test]
fn join_all_waits_for_every_trigger() {
    let s = fusion("all");
    let r = run(&s, 30);
    // Released when b completes the set, at 4 and 14 and 24.
    assert_eq!(spans(&s, &r, "c"), vec![(4, 6), (14, 16), (24, 26)]);
    let b = s.task_index("b").unwrap_or(0);
    let triggers: Vec<Option<Trigger>> = jobs(&s, &r, "c").map(|j| j.trigger).collect();
    assert_eq!(
        triggers,
        (0..3)
            .map(|k| Some(Trigger { task: b, job: k }))
            .collect::<Vec<_>>()
    );
    assert_eq!(jobs(&s, &r, "c").next().map(|j| j.release), Some(4 * US));
}

#[test]
fn join_any_releases_at_every_publication() {
    let s = fusion("any");
    let r = run(&s, 20);
    assert_eq!(spans(&s, &r, "c"), vec![(1, 3), (4, 6), (11, 13), (14, 16)]);
    let a = s.task_index("a").unwrap_or(0);
    assert_eq!(
        jobs(&s, &r, "c").next().and_then(|j| j.trigger),
        Some(Trigger { task: a, job: 0 })
    );
}

#[test]
fn a_triggered_release_merges_while_its_job_waits() {
    // c (priority 3) cannot start before h (priority 2, released at 0)
    // is done: h runs 1–10 and 11–20 (a preempts it at 10 and 20). a's
    // publications at 1 release c; those at 11 and 21 merge into that
    // job, which runs 21–23.
    let s = spec(
        "[tasks.a]\nexec = 1\nperiod = 10\npriority = 1\noutput = { channel = \"m\", size = 0 }\n\
         [tasks.h]\nexec = 18\nperiod = 100\npriority = 2\n\
         [tasks.c]\nactivation = \"data\"\nreads = [\"a\"]\nexec = 2\npriority = 3\n",
    );
    let r = run(&s, 30);
    let c = s.task_index("c").unwrap_or(0);
    assert_eq!((r.tasks[c].released, r.tasks[c].merged), (1, 2));
    assert_eq!(spans(&s, &r, "c"), vec![(21, 23)]);
    assert_eq!(r.tasks[c].max_response, Some(22 * US));
}

#[test]
fn threads_preempt_each_other_by_priority() {
    // l's job (thread lo) is preempted by h's (thread hi) at 3, resumes at
    // 5; a job of lo's timer item t released at 4 waits for l's to finish.
    let s = spec(
        "[threads.hi]\npriority = 1\n\n[threads.lo]\npriority = 2\n\n\
         [tasks.h]\nexec = 2\nperiod = 10\noffset = 3\nthread = \"hi\"\n\
         [tasks.l]\nexec = 5\nperiod = 100\nthread = \"lo\"\n\
         [tasks.t]\nexec = 1\nperiod = 100\noffset = 4\nthread = \"lo\"\n",
    );
    let r = run(&s, 20);
    assert_eq!(spans(&s, &r, "h"), vec![(3, 5), (13, 15)]);
    assert_eq!(spans(&s, &r, "l"), vec![(0, 7)]);
    assert_eq!(spans(&s, &r, "t"), vec![(7, 8)]);
    let segments: Vec<(usize, Nanos, Nanos)> = r
        .segments
        .iter()
        .map(|g| (g.task, g.start / US, g.end / US))
        .collect();
    assert_eq!(
        &segments[..4],
        &[(1, 0, 3), (0, 3, 5), (1, 5, 7), (2, 7, 8)]
    );
}

#[test]
fn the_bundled_example_s_first_millisecond_by_hand() {
    // The rate thread (priority 1) runs its timer item, the land detector
    // (released at 0, 60 µs), first; the IMU driver on the SPI thread
    // (released at 20, its latest jitter) waits for it, reads at 60 and
    // publishes at 85, which releases the rate loop's items on the rate
    // thread one after the other; the lowest thread's items come last, in
    // declaration order (both released at 0).
    let s = rtpipe_testkit::example("work-queues.toml");
    let cfg = SimConfig {
        jitter: Jitter::Latest,
        log_jobs: true,
        ..SimConfig::new(1_000 * US)
    };
    let r = simulate(&s, &cfg).unwrap_or_else(|e| panic!("{e}"));
    for (task, span) in [
        ("land_detector", (0, 60)),
        ("imu", (60, 85)),
        ("angular_velocity", (85, 97)),
        ("rate_control", (97, 117)),
        ("control_allocator", (117, 132)),
        ("attitude_control", (132, 282)),
        ("position_control", (282, 682)),
    ] {
        assert_eq!(spans(&s, &r, task), vec![span], "{task}");
    }
    let imu = s.task_index("imu").unwrap_or(0);
    assert_eq!(r.tasks[imu].max_response, Some(85 * US));
}

/// Per thread, the logged jobs of its tasks: none overlaps another
/// (read to finish), and they start in the order they were queued.
fn check_threads(s: &Spec, r: &SimResult, seed: u64) {
    for th in 0..s.threads.len() {
        let mut js: Vec<&JobRecord> = r
            .jobs
            .iter()
            .filter(|j| s.tasks[j.task].thread == Some(th))
            .collect();
        js.sort_by_key(|j| j.read);
        for w in js.windows(2) {
            assert!(
                w[0].finish <= w[1].read,
                "seed {seed}: thread {th} runs two jobs at once: {:?} {:?}",
                w[0],
                w[1]
            );
        }
    }
}

/// Every triggered job was released at the publication of its trigger.
fn check_triggers(s: &Spec, r: &SimResult, seed: u64) {
    for j in &r.jobs {
        let Some(tr) = j.trigger else {
            assert!(!s.tasks[j.task].is_triggered(), "seed {seed}: {j:?}");
            continue;
        };
        let publication = r
            .jobs
            .iter()
            .find(|p| p.task == tr.task && p.index == tr.job)
            .map(|p| p.finish);
        assert_eq!(publication, Some(j.release), "seed {seed}: {j:?}");
    }
}

#[test]
fn random_event_triggered_systems_keep_the_thread_and_trigger_rules() {
    let cfg = EventGenConfig::default();
    for seed in 0..100 {
        let s = event_triggered_system(seed, &cfg);
        for (exec, phasing) in [
            (ExecModel::Worst, Phasing::Sync),
            (ExecModel::Uniform, Phasing::Random),
        ] {
            let run = SimConfig {
                seed,
                exec,
                phasing,
                log_jobs: true,
                ..SimConfig::new(50_000 * US)
            };
            let r = simulate(&s, &run).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            check_threads(&s, &r, seed);
            check_triggers(&s, &r, seed);
            for (t, ts) in s.tasks.iter().zip(&r.tasks) {
                assert!(t.merges_releases() || ts.merged == 0, "seed {seed}");
                assert!(ts.completed <= ts.released, "seed {seed}");
            }
        }
    }
}

#[test]
fn the_search_moves_periodic_sources_to_a_triggered_chain_s_worst_case() {
    // c is triggered by a and shares thread w (above a) with the timer
    // item l. In sync l runs first, a reads at 5 and c ends at 7: 2 µs.
    // The worst case has l released just after a's read: l preempts a,
    // which publishes at read + 6, and c ends at read + 7. Only the
    // periodic sources' offsets move; c's stays 0.
    let s = spec(
        "[threads.w]\npriority = 1\n\n\
         [tasks.a]\nexec = 1\nperiod = 10\npriority = 2\noutput = { channel = \"m\", size = 0 }\n\
         [tasks.l]\nexec = 5\nperiod = 10\nthread = \"w\"\n\
         [tasks.c]\nactivation = \"data\"\nreads = [\"a\"]\nexec = 1\nthread = \"w\"\n\n\
         [[chain]]\npath = [\"a\", \"c\"]\n",
    );
    let sync = run(&s, 200);
    assert_eq!(sync.chains[0].reaction.max, Some(2 * US));
    let cfg = SearchConfig::new(0, Metric::Reaction, 200 * US);
    let found = search(&s, &cfg).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(found.value, Some(7 * US), "{found}");
    assert_eq!(
        found.best.offsets[2], 0,
        "a data-triggered task has no offset"
    );
    // The analysis bounds what the search found, and the result replays.
    assert!(
        found.sound.is_some_and(|b| b >= 7 * US),
        "sound bound {:?} below the 7 µs found",
        found.sound
    );
    assert!(found.paper.is_some());
    let replay = simulate(&s, &found.config).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(replay.chains[0].reaction.max, Some(7 * US));
}
