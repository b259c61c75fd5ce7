//! Property tests of the analysis with release jitter, constrained
//! deadlines and deadline-monotonic or explicit priorities, on
//! generated systems: sound ≤ min(Davare, Dürr) still holds, reaction ≤
//! freshness, from the event ≥ from the read, and jitter never lowers a
//! response time or a bound (removing it from a system can only tighten
//! them). 3,000 cases each; `--nocapture` prints the tally.

use proptest::prelude::*;
use rtpipe_analysis::{analyze, Anchor, Bound, Report};
use rtpipe_model::gen::{random_system, GenConfig, Rng};
use rtpipe_model::{Nanos, Priorities, SchedTest, Scheduler, Server, Spec};
use rtpipe_testkit::check;

const CASES: u32 = 3_000;

fn inf(x: Option<Nanos>) -> Nanos {
    x.unwrap_or(Nanos::MAX)
}

/// A generated fixed-priority system with jitter on some tasks (up to
/// `jf`·T), deadlines in [(1 − df)·T, T] on some, and the priority order
/// `order` (0 rate, 1 deadline monotonic, 2 explicit, a random permutation).
fn system(seed: u64, tasks: usize, jf: f64, df: f64, order: u8) -> Spec {
    let gen = GenConfig {
        tasks,
        cpus: 1 + (seed % 2) as u32,
        utilization: 0.3 + 0.5 * ((seed >> 8) % 100) as f64 / 100.0,
        scheduler: Scheduler::Rm,
        mixed_servers: seed.is_multiple_of(3),
        chains: 4,
        ..GenConfig::default()
    };
    let mut s = random_system(seed, &gen);
    let mut r = Rng::new(seed ^ 0x1D);
    s.schedulability = SchedTest::Rta;
    s.priorities = [
        Priorities::RateMonotonic,
        Priorities::DeadlineMonotonic,
        Priorities::Explicit,
    ][usize::from(order)];
    let n = s.tasks.len() as u32;
    let mut prios: Vec<u32> = (1..=n).collect();
    for i in (1..prios.len()).rev() {
        prios.swap(i, r.range(0, i as u64) as usize);
    }
    for (i, t) in s.tasks.iter_mut().enumerate() {
        let Some(p) = t.fixed_period() else { continue };
        if r.chance(0.5) {
            t.jitter = ((p as f64 * jf * r.unit()) as Nanos).min(p - 1);
        }
        if t.server != Server::Background {
            if r.chance(0.5) {
                t.deadline_given = Some(p - (p as f64 * df * r.unit()) as Nanos);
            }
            if s.priorities == Priorities::Explicit {
                t.priority = Some(prios[i]);
            }
        }
    }
    s
}

fn strategy() -> impl Strategy<Value = (u64, usize, f64, f64, u8)> {
    (any::<u64>(), 2usize..=10, 0.0f64..0.9, 0.0f64..0.5, 0u8..3)
}

/// Every chain's bounds, in report order.
fn each_bound(r: &Report, mut f: impl FnMut(usize, &rtpipe_analysis::ChainResult)) {
    for (k, c) in r.chains.iter().enumerate() {
        f(k, c);
    }
}

#[test]
fn sound_within_davare_and_duerr_with_jitter() {
    check(
        "sound_within_davare_and_duerr_with_jitter",
        CASES,
        strategy(),
        |(seed, n, jf, df, o)| {
            let s = system(seed, n, jf, df, o);
            let r = analyze(&s);
            let mut outcome = "no bounded chain";
            let mut bad = None;
            each_bound(&r, |k, c| {
                for a in Anchor::ALL {
                    let sound = c.bound.sound(a);
                    for m in [Bound::Davare, Bound::Duerr] {
                        if sound.is_some() {
                            outcome = "checked";
                        }
                        if inf(sound) > inf(c.bound.get(m, a)) {
                            bad = Some(format!(
                                "entry {k} {} from {}: sound {sound:?} > {m:?}",
                                c.metric.name(),
                                a.name()
                            ));
                        }
                    }
                    if inf(c.bound.sound(Anchor::Event)) < inf(c.bound.sound(Anchor::Read)) {
                        bad = Some(format!("entry {k}: from the event below from the read"));
                    }
                }
            });
            for k in 0..r.chains.len() / 2 {
                let (re, fr) = (&r.chains[2 * k].bound, &r.chains[2 * k + 1].bound);
                if inf(re.sound(Anchor::Read)) > inf(fr.sound(Anchor::Read)) {
                    bad = Some(format!("chain {k}: reaction above freshness"));
                }
            }
            prop_assert!(bad.is_none(), "seed {seed}: {bad:?}");
            Ok(outcome)
        },
    );
}

#[test]
fn jitter_never_lowers_a_response_time_or_a_bound() {
    check(
        "jitter_never_lowers_a_response_time_or_a_bound",
        CASES,
        strategy(),
        |(seed, n, jf, df, o)| {
            let s = system(seed, n, jf, df, o);
            if s.tasks.iter().all(|t| t.jitter == 0) {
                return Ok("no jitter drawn");
            }
            let mut calm = s.clone();
            calm.tasks.iter_mut().for_each(|t| t.jitter = 0);
            let (r, c) = (analyze(&s), analyze(&calm));
            for (i, (a, b)) in r.timing.iter().zip(&c.timing).enumerate() {
                prop_assert!(
                    inf(a.job_response_time) >= inf(b.job_response_time),
                    "seed {seed}: task {i}: {:?} < {:?} without jitter",
                    a.job_response_time,
                    b.job_response_time
                );
            }
            for (x, y) in r.chains.iter().zip(&c.chains) {
                for a in Anchor::ALL {
                    prop_assert!(
                        inf(x.bound.sound(a)) >= inf(y.bound.sound(a)),
                        "seed {seed}: chain {} {}: {:?} < {:?} without jitter",
                        x.chain,
                        x.metric.name(),
                        x.bound.sound(a),
                        y.bound.sound(a)
                    );
                }
            }
            Ok("checked")
        },
    );
}
