//! The incremental demand (`demand::Demand`: each stream divided only where
//! its count grows) against the straightforward sums it replaced, and the
//! two analyses that use it, `sched::level_response` and
//! `thread_rta::fifo_response`, against their straightforward iterations
//! (every stream's ⌈(w + J)/T⌉ recomputed at every step, with checked
//! arithmetic), kept here as the reference: on random streams, windows,
//! own jobs and thread members, the same figures, unbounded ones and
//! overflows included; and both analyses started warm from their last
//! stops against the same analyses from the bottom, after the activations
//! grew; and the demand of tasks above, as `thread_rta` hands it, against
//! the direct sum of their streams. 3,000 cases each; `--nocapture` prints
//! the tally.

use proptest::prelude::*;
use rtpipe_analysis::arrivals::{Arrivals, Stream};
use rtpipe_analysis::demand::Demand;
use rtpipe_analysis::load::full;
use rtpipe_analysis::sched::{level_response, level_response_from, OwnJobs, MAX_BUSY_JOBS};
use rtpipe_analysis::thread_rta::{
    self, fifo_by_busy_period, fifo_response, fifo_response_from, Above, Member, MAX_CANDIDATES,
    MAX_STEPS,
};
use rtpipe_model::{Nanos, MAX_TIME};
use rtpipe_testkit::check;
use std::cell::Cell;

const CASES: u32 = 3_000;

/// Σ ⌈(w + J)/T⌉·C of (C, T, J), `None` on overflow (the old `sched` sum).
fn direct(loads: &[(Nanos, Nanos, Nanos)], w: Nanos) -> Option<Nanos> {
    loads.iter().try_fold(0 as Nanos, |sum, &(c, t, j)| {
        ((w + j + t - 1) / t).checked_mul(c)?.checked_add(sum)
    })
}

/// The level-i busy period, every step summing every stream afresh.
fn straight_level_response(own: OwnJobs, hp: &[(Nanos, Nanos, Nanos)]) -> Option<Nanos> {
    // The guard itself is `load::full`'s, the one home of the rule.
    let own_load = (
        own.work.checked_add(own.switch.checked_mul(2)?)?,
        own.period,
    );
    let loads = hp.iter().map(|&(c, t, _)| (c, t));
    if full(loads.chain(std::iter::once(own_load))) {
        return None;
    }
    let (mut worst, mut w): (Nanos, Nanos) = (0, 0);
    for q in 0..MAX_BUSY_JOBS {
        let demand = (q + 1)
            .checked_mul(own.work)?
            .checked_add((2 * q + 1).checked_mul(own.switch)?)?
            .checked_add(own.blocking)?;
        let first = demand.checked_add(hp.iter().map(|&(c, _, _)| c).sum::<Nanos>())?;
        let mut r = first.max(w.checked_add(own.work)?);
        w = loop {
            let next = direct(hp, r)?.checked_add(demand)?;
            if next > MAX_TIME {
                return None;
            }
            if next == r {
                break r;
            }
            r = next;
        };
        worst = worst.max(w - q.saturating_mul(own.period));
        if w <= (q + 1).saturating_mul(own.period) - own.jitter {
            return worst.checked_add(own.jitter);
        }
    }
    None
}

/// The FIFO response of a thread, every step summing every stream above
/// afresh.
fn straight_fifo_response(members: &[Member], above: &Above, blocking: Nanos) -> Option<Nanos> {
    if full(thread_rta::loads(members, above)) {
        return None;
    }
    let thread = |delta: Nanos| -> Option<Nanos> {
        members.iter().try_fold(blocking, |sum, m| {
            sum.checked_add(m.arrivals.eta(delta).checked_mul(m.work)?)
        })
    };
    let interference = |w: Nanos| -> Option<Nanos> {
        above.iter().try_fold(0 as Nanos, |sum, &(c, a)| {
            sum.checked_add(a.eta(w).checked_mul(c)?)
        })
    };
    let steps = Cell::new(MAX_STEPS);
    let fixed_point = |start: Nanos, f: &dyn Fn(Nanos) -> Option<Nanos>| -> Option<Nanos> {
        let mut w = start;
        loop {
            steps.set(steps.get().checked_sub(1)?);
            let next = f(w)?;
            if next > MAX_TIME {
                return None;
            }
            if next <= w {
                return Some(w);
            }
            w = next;
        }
    };
    let length = fixed_point(1, &|w| thread(w)?.checked_add(interference(w)?))?;
    let mut candidates = vec![0];
    for m in members {
        candidates.extend(m.arrivals.steps_below(length, MAX_CANDIDATES)?);
        if candidates.len() > MAX_CANDIDATES {
            return None;
        }
    }
    candidates.sort_unstable();
    candidates.dedup();
    let (mut worst, mut finish) = (0, 0);
    for a in candidates {
        let released = thread(a.checked_add(1)?)?;
        finish = fixed_point(finish.max(released), &|w| {
            released.checked_add(interference(w)?)
        })?;
        worst = worst.max(finish - a);
    }
    Some(worst)
}

/// (C, T, J) streams: works from tiny to past overflow, jitters up to a
/// few periods.
fn loads(max: usize) -> impl Strategy<Value = Vec<(Nanos, Nanos, Nanos)>> {
    prop::collection::vec(
        (
            1..20_000 as Nanos,
            0..40u32,
            prop_oneof![8 => 0..400 as Nanos, 1 => 1 as Nanos..Nanos::MAX / 64],
        )
            .prop_map(|(t, jf, c)| (c, t, t * Nanos::from(jf) / 10)),
        0..max,
    )
}

#[test]
fn the_incremental_demand_is_the_direct_sum() {
    let strategy = (loads(16), prop::collection::vec(0..50_000 as Nanos, 1..40));
    check(
        "incremental demand",
        CASES,
        strategy,
        |(hp, mut windows)| {
            windows.sort_unstable();
            let mut demand = Demand::of_loads(&hp);
            for &w in &windows {
                // Saturated where the checked sum overflows; 0 in an empty window.
                let want = if w == 0 { Some(0) } else { direct(&hp, w) };
                prop_assert_eq!(demand.at(w), want.unwrap_or(Nanos::MAX), "w = {}", w);
            }
            Ok(if hp.is_empty() {
                "no stream"
            } else {
                "checked"
            })
        },
    );
}

/// A task's own jobs for a level-i busy period, its release jitter up to
/// four tenths of its period.
fn own_jobs() -> impl Strategy<Value = OwnJobs> {
    (
        1..3_000 as Nanos,
        0..40 as Nanos,
        0..600 as Nanos,
        0..5u32,
        200..40_000 as Nanos,
    )
        .prop_map(|(work, switch, blocking, jf, period)| OwnJobs {
            work,
            switch,
            blocking,
            jitter: period * Nanos::from(jf) / 10,
            period,
        })
}

#[test]
fn level_response_is_the_straightforward_iteration() {
    let own = own_jobs();
    check("level response", CASES, (own, loads(12)), |(own, hp)| {
        let want = straight_level_response(own, &hp);
        prop_assert_eq!(level_response(own, &hp), want);
        Ok(if want.is_some() {
            "bounded"
        } else {
            "unbounded"
        })
    });
}

/// Streams of an event model: 1–3, jitters up to a few periods.
fn arrivals() -> impl Strategy<Value = Arrivals> {
    prop::collection::vec((50..20_000 as Nanos, 0..40u32), 1..4).prop_map(|s| Arrivals {
        streams: s
            .into_iter()
            .map(|(period, jf)| Stream {
                period,
                jitter: period * Nanos::from(jf) / 10,
            })
            .collect(),
    })
}

#[test]
fn fifo_response_is_the_straightforward_iteration() {
    let members = prop::collection::vec((1..2_000 as Nanos, arrivals()), 1..4);
    let above = prop::collection::vec((1..1_500 as Nanos, arrivals()), 0..6);
    check(
        "fifo response",
        CASES,
        (members, above, 0..500 as Nanos),
        |(members, above, blocking)| {
            let members: Vec<Member> = members
                .iter()
                .map(|(work, a)| Member {
                    work: *work,
                    arrivals: a,
                })
                .collect();
            let above: Vec<(Nanos, &Arrivals)> = above.iter().map(|(c, a)| (*c, a)).collect();
            let want = straight_fifo_response(&members, &above, blocking);
            prop_assert_eq!(fifo_response(&members, &above, blocking), want);
            Ok(if want.is_some() {
                "bounded"
            } else {
                "unbounded"
            })
        },
    );
}

/// The demand of tasks above as `thread_rta` hands them (a stretch of
/// terms per task, made at the first window that counts an event) is the
/// direct sum of their streams, at any first window and after it.
#[test]
fn the_demand_of_arrivals_is_the_direct_sum() {
    let works = prop_oneof![8 => 0..400 as Nanos, 1 => 1 as Nanos..Nanos::MAX / 64];
    let above = prop::collection::vec((works, arrivals()), 0..8);
    // Some first windows empty (0), counting no event: the terms are made
    // at the next one.
    let window = prop_oneof![1 => Just(0 as Nanos), 9 => 0..60_000 as Nanos];
    let windows = prop::collection::vec(window, 1..30);
    check(
        "demand of arrivals",
        CASES,
        (above, windows),
        |(above, mut windows)| {
            windows.sort_unstable();
            let loads: Vec<(Nanos, Nanos, Nanos)> = above
                .iter()
                .flat_map(|(c, a)| a.streams.iter().map(|s| (*c, s.period, s.jitter)))
                .collect();
            let pairs = pairs(&above);
            let mut demand = Demand::of_arrivals(&pairs);
            for &w in &windows {
                let want = if w == 0 { Some(0) } else { direct(&loads, w) };
                prop_assert_eq!(demand.at(w), want.unwrap_or(Nanos::MAX), "w = {}", w);
            }
            Ok(match (above.is_empty(), windows[0]) {
                (true, _) => "no task above",
                (false, 0) => "first window empty",
                _ => "first window counts",
            })
        },
    );
}

/// A thread's members as `thread_rta` takes them.
fn view(members: &[(Nanos, Arrivals)]) -> Vec<Member<'_>> {
    members
        .iter()
        .map(|(work, a)| Member {
            work: *work,
            arrivals: a,
        })
        .collect()
}

/// Tasks above as `thread_rta` takes them.
fn pairs(above: &[(Nanos, Arrivals)]) -> Vec<(Nanos, &Arrivals)> {
    above.iter().map(|(c, a)| (*c, a)).collect()
}

/// `a` with each stream's jitter grown by the next of `extra` (cycled).
fn grown(a: &Arrivals, extra: &[Nanos], k: &mut usize) -> Arrivals {
    Arrivals {
        streams: a
            .streams
            .iter()
            .map(|s| {
                *k += 1;
                Stream {
                    period: s.period,
                    jitter: s.jitter + extra[*k % extra.len()],
                }
            })
            .collect(),
    }
}

/// How much each stream's jitter grows between two analyses (none for
/// some), drawn per stream in turn.
/// Tasks as (work, activations).
type Works = Vec<(Nanos, Arrivals)>;

/// `members` and `above` with their jitters grown by `extra`'s draws in
/// turn (one count across both, so the two lists draw different growths).
fn grown_both(
    members: &[(Nanos, Arrivals)],
    above: &[(Nanos, Arrivals)],
    extra: &[Nanos],
) -> (Works, Works) {
    let mut k = 0;
    let mut grow = |m: &[(Nanos, Arrivals)]| -> Works {
        m.iter()
            .map(|(c, a)| (*c, grown(a, extra, &mut k)))
            .collect()
    };
    let grown_members = grow(members);
    (grown_members, grow(above))
}

fn jitter_growth() -> impl Strategy<Value = Vec<Nanos>> {
    prop::collection::vec(
        prop_oneof![2 => Just(0 as Nanos), 3 => 0..3_000 as Nanos],
        1..8,
    )
}

#[test]
fn a_warm_fifo_response_is_the_one_from_the_bottom() {
    // The event analysis re-analyses a thread from its last stops after
    // its inputs' jitters grew: the figure and the stops must be those of
    // an analysis from the bottom.
    let members = prop::collection::vec((1..2_000 as Nanos, arrivals()), 1..4);
    let above = prop::collection::vec((1..1_500 as Nanos, arrivals()), 0..6);
    let extra = jitter_growth();
    check(
        "warm fifo response",
        CASES,
        (members, above, 0..500 as Nanos, extra),
        |(members, above, blocking, extra)| {
            let (grown_members, grown_above) = grown_both(&members, &above, &extra);
            let old = fifo_response_from(&view(&members), &pairs(&above), blocking, None);
            let (new_members, new_above) = (view(&grown_members), pairs(&grown_above));
            let cold = fifo_response_from(&new_members, &new_above, blocking, None);
            let warm = fifo_response_from(&new_members, &new_above, blocking, old.as_ref());
            prop_assert_eq!(&warm, &cold);
            Ok(match (old, cold) {
                (Some(o), Some(c)) if o != c => "warm, moved",
                (Some(_), Some(_)) => "warm, the same",
                (Some(_), None) => "warm, unbounded now",
                (None, _) => "cold",
            })
        },
    );
}

#[test]
fn the_candidates_in_order_stop_where_the_busy_period_first_does() {
    // `fifo_response_from` takes the candidates in order, with no busy
    // period iterated first, and stops at the first job that ends by the
    // next step of a member's η⁺: its stops (the busy period and every
    // candidate's finish), cold and warm after the jitters grew, must be
    // those of the busy period first, by the definition. One member (a
    // thread-less data-triggered task) in half the cases, loads up to
    // overloaded.
    let member = || (1..400 as Nanos, arrivals());
    let members = prop_oneof![
        1 => prop::collection::vec(member(), 1..2),
        1 => prop::collection::vec(member(), 2..4),
    ];
    let above = prop::collection::vec((1..300 as Nanos, arrivals()), 0..6);
    check(
        "candidates in order",
        CASES,
        (members, above, 0..500 as Nanos, jitter_growth()),
        |(members, above, blocking, extra)| {
            let (m, a) = (view(&members), pairs(&above));
            let cold = fifo_response_from(&m, &a, blocking, None);
            prop_assert_eq!(&cold, &fifo_by_busy_period(&m, &a, blocking, None));
            let (grown_members, grown_above) = grown_both(&members, &above, &extra);
            let (gm, ga) = (view(&grown_members), pairs(&grown_above));
            let warm = fifo_response_from(&gm, &ga, blocking, cold.as_ref());
            prop_assert_eq!(&warm, &fifo_by_busy_period(&gm, &ga, blocking, None));
            Ok(match cold.map(|s| s.windows().len()) {
                None => "unbounded",
                Some(1) => "one candidate",
                Some(_) => "several candidates",
            })
        },
    );
}

#[test]
fn a_warm_level_response_is_the_one_from_the_bottom() {
    let own = own_jobs();
    let extra = jitter_growth();
    check(
        "warm level response",
        CASES,
        (own, loads(12), extra),
        |(own, hp, extra)| {
            let grown: Vec<(Nanos, Nanos, Nanos)> = hp
                .iter()
                .enumerate()
                .map(|(k, &(c, t, j))| (c, t, j + extra[k % extra.len()]))
                .collect();
            let (old, stops) = level_response_from(own, &hp, Nanos::MAX, &[]);
            let cold = level_response_from(own, &grown, Nanos::MAX, &[]);
            let warm = level_response_from(own, &grown, Nanos::MAX, &stops);
            prop_assert_eq!(cold.0, level_response(own, &grown));
            prop_assert_eq!(&warm, &cold);
            Ok(match (old, cold.0) {
                (Some(o), Some(c)) if o != c => "warm, moved",
                (Some(_), Some(_)) => "warm, the same",
                (Some(_), None) => "warm, unbounded now",
                (None, _) => "cold",
            })
        },
    );
}
