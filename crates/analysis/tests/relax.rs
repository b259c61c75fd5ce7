//! `relax` against the analysis: at a box of one point it is the analysis;
//! over any box it bounds the analysis at every point inside from below
//! (the property the design's branch and bound prunes with).

use rtpipe_analysis::relax::{paper_monotone, relax, Relaxed};
use rtpipe_analysis::Anchor;
use rtpipe_analysis::{analyze, Metric, Report};
use rtpipe_model::gen::{add_contention, add_timing, random_system, Contention, GenConfig, Rng};
use rtpipe_model::{
    Communication, Nanos, PeriodSpec, Priorities, SchedTest, Scheduler, Server, Spec,
};

const SYSTEMS: u64 = 1500;

fn config(seed: u64) -> GenConfig {
    let mut rng = Rng::new(seed ^ 0x5eed);
    GenConfig {
        tasks: rng.range(2, 9) as usize,
        cpus: rng.range(1, 2) as u32,
        utilization: 0.3 + 0.6 * rng.unit(),
        scheduler: if rng.chance(0.2) {
            Scheduler::Edf
        } else {
            Scheduler::Rm
        },
        chains: 3,
        mixed_servers: rng.chance(0.5),
        inheritance: if rng.chance(0.3) { 0.5 } else { 0.0 },
        ..GenConfig::default()
    }
}

fn with_test(mut spec: Spec, seed: u64) -> Spec {
    spec.schedulability = match seed % 4 {
        0 => SchedTest::Rta,
        1 => SchedTest::LiuLayland,
        2 => SchedTest::Hyperbolic,
        _ => SchedTest::Edf,
    };
    spec
}

/// System `seed` of the tests: for odd seeds with critical sections
/// and scheduling overheads where `add_contention` draws them (written and
/// parsed back; a spec validation refuses stays without them).
fn system(seed: u64) -> Spec {
    let spec = timed(contended(seed), seed);
    // A box never goes below a deadline (the design's domains keep T ≥ D).
    assert!(spec
        .tasks
        .iter()
        .all(|t| t.deadline_given.is_none_or(|d| t.fixed_period() >= Some(d))));
    spec
}

/// For a third of the seeds: constrained deadlines with deadline-monotonic
/// or explicit priorities (RM, with RTA) or QPA (EDF), `gen::add_timing`,
/// written and parsed back (unchanged when validation refuses it).
fn timed(spec: Spec, seed: u64) -> Spec {
    if (seed / 2) % 3 == 2 {
        // LET communication, where validation takes it.
        let mut s = spec.clone();
        s.communication = Communication::Let;
        return Spec::parse("l.toml", &rtpipe_model::to_toml(&s)).unwrap_or(spec);
    }
    if (seed / 2) % 3 != 1 {
        return spec;
    }
    let mut s = spec.clone();
    if s.policy().fixed_priority() {
        s.schedulability = SchedTest::Rta;
    }
    add_timing(&mut s, &mut Rng::new(seed ^ 0x7e57));
    Spec::parse("t.toml", &rtpipe_model::to_toml(&s)).unwrap_or(spec)
}

/// The generated system of `seed`, with contention for odd seeds.
fn contended(seed: u64) -> Spec {
    let spec = with_test(random_system(seed, &config(seed)), seed);
    if seed.is_multiple_of(2) {
        return spec;
    }
    let mut s = spec.clone();
    let c = Contention {
        sections: 0.6,
        overheads: 0.6,
        max_cost: 40_000,
    };
    add_contention(&mut s, &mut Rng::new(seed ^ 0xc0de), &c);
    Spec::parse("c.toml", &rtpipe_model::to_toml(&s)).unwrap_or(spec)
}

fn periods(spec: &Spec) -> Vec<Nanos> {
    spec.tasks
        .iter()
        .map(|t| t.fixed_period().expect("generated periods are fixed"))
        .collect()
}

fn at(spec: &Spec, t: &[Nanos]) -> Spec {
    let mut s = spec.clone();
    for (task, &p) in s.tasks.iter_mut().zip(t) {
        task.period = PeriodSpec::Fixed(p);
    }
    s
}

fn paper(report: &Report, chain: usize, metric: Metric) -> Nanos {
    report
        .chains
        .iter()
        .find(|c| c.chain == chain && c.metric == metric)
        .map_or(Nanos::MAX, |c| c.bound.paper(Anchor::Read))
}

/// The paper figures and forms of `r` against the analysis at `t` (equal at
/// a point box), when the paper's terms are monotone.
fn paper_below(
    r: &Relaxed,
    spec: &Spec,
    lo: &[Nanos],
    t: &[Nanos],
    report: &Report,
    what: &str,
    exact: bool,
) {
    if !paper_monotone(spec) {
        return;
    }
    for (k, &(e, f)) in r.paper.iter().enumerate() {
        let (pe, pf) = (
            paper(report, k, Metric::Reaction),
            paper(report, k, Metric::Freshness),
        );
        if exact {
            assert_eq!((e, f), (pe, pf), "{what}: chain {k} paper");
        } else {
            assert!(
                e <= pe && f <= pf,
                "{what}: chain {k} paper ({e}, {f}) vs ({pe}, {pf})"
            );
        }
        let (fe, ff) = &r.paper_forms[k];
        assert!(
            fe.at(lo, t) <= pe as f64 + 1e-6,
            "{what}: chain {k} paper reaction form"
        );
        assert!(
            ff.at(lo, t) <= pf as f64 + 1e-6,
            "{what}: chain {k} paper freshness form"
        );
    }
}

fn sound(report: &Report, chain: usize, metric: Metric) -> Option<Nanos> {
    report
        .chains
        .iter()
        .find(|c| c.chain == chain && c.metric == metric)
        .and_then(|c| c.bound.sound(Anchor::Read))
}

/// The affine forms of every chain bound its sound figures at `t` from
/// below (reaction is the smaller sum, freshness the second).
fn forms_below(r: &Relaxed, lo: &[Nanos], t: &[Nanos], report: &Report, what: &str) {
    for (k, form) in r.forms.iter().enumerate() {
        let (se, sf) = (
            sound(report, k, Metric::Reaction),
            sound(report, k, Metric::Freshness),
        );
        let Some((e, f)) = form else {
            assert!(
                se.is_none() && sf.is_none(),
                "{what}: chain {k} has no forms but is bounded"
            );
            continue;
        };
        let (e, f) = (e.at(lo, t), f.at(lo, t));
        if let Some(x) = se {
            assert!(
                e.min(f) <= x as f64 + 1e-6,
                "{what}: chain {k} reaction form {} above {x}",
                e.min(f)
            );
        }
        if let Some(x) = sf {
            assert!(
                f <= x as f64 + 1e-6,
                "{what}: chain {k} freshness form {f} above {x}"
            );
        }
    }
}

fn sound_event_reaction(report: &Report, chain: usize) -> Option<Nanos> {
    report
        .chains
        .iter()
        .find(|c| c.chain == chain && c.metric == Metric::Reaction)
        .and_then(|c| c.bound.sound(Anchor::Event))
}

/// The sound reaction from the event: its lower bound (exact at a point
/// box) and its affine form below the analysis at `t`.
fn event_below(r: &Relaxed, lo: &[Nanos], t: &[Nanos], report: &Report, what: &str, exact: bool) {
    for k in 0..r.event_reaction.len() {
        let x = sound_event_reaction(report, k);
        let l = r.event_reaction[k];
        if exact {
            assert_eq!(l, x, "{what}: chain {k} reaction from the event");
        } else {
            assert!(below(l, x), "{what}: chain {k} event {l:?} vs {x:?}");
        }
        match (&r.event_forms[k], x) {
            (Some(f), Some(x)) => assert!(
                f.at(lo, t) <= x as f64 + 1e-6,
                "{what}: chain {k} event reaction form {} above {x}",
                f.at(lo, t)
            ),
            (None, Some(_)) => panic!("{what}: chain {k} has no event form but is bounded"),
            _ => {}
        }
    }
}

/// `lower` is at most `exact`, reading `None` as +∞.
fn below(lower: Option<Nanos>, exact: Option<Nanos>) -> bool {
    match (lower, exact) {
        (_, None) => true,
        (None, Some(_)) => false,
        (Some(l), Some(e)) => l <= e,
    }
}

fn bounds_point(r: &Relaxed, spec: &Spec, report: &Report, what: &str, exact: bool) {
    let same = |l: Option<Nanos>, e: Option<Nanos>| if exact { l == e } else { below(l, e) };
    for (i, tm) in report.timing.iter().enumerate() {
        if spec.tasks[i].server == Server::Background {
            continue;
        }
        // The RTA test asks R ≤ D (D = T unless given).
        let budget = tm
            .response_time
            .filter(|&x| x <= tm.deadline.min(tm.period));
        assert!(
            same(r.job_response[i], tm.bounded_response()),
            "{what}: job R of task {i}: {:?} vs {:?}",
            r.job_response[i],
            tm.bounded_response()
        );
        assert!(
            same(r.budget_response[i], budget),
            "{what}: budget R of task {i}"
        );
        assert!(
            same(r.read_to_publish[i], tm.bounded_read_to_publish()),
            "{what}: W of task {i}: {:?} vs {:?}",
            r.read_to_publish[i],
            tm.bounded_read_to_publish()
        );
    }
    for (v, &(cpu, may)) in report.schedulability.cpus.iter().zip(&r.cpus) {
        assert_eq!(v.cpu, cpu);
        if exact {
            assert_eq!(may, v.schedulable, "{what}: cpu {cpu} verdict");
        } else {
            assert!(
                may || !v.schedulable,
                "{what}: cpu {cpu} passes but the box says never"
            );
        }
    }
    for (k, &(e, f)) in r.chains.iter().enumerate() {
        let (se, sf) = (
            sound(report, k, Metric::Reaction),
            sound(report, k, Metric::Freshness),
        );
        assert!(same(e, se), "{what}: chain {k} reaction {e:?} vs {se:?}");
        assert!(same(f, sf), "{what}: chain {k} freshness {f:?} vs {sf:?}");
    }
}

#[test]
fn a_point_box_is_the_analysis() {
    let mut bounded = 0;
    let (mut blocked, mut charged) = (0, 0);
    let (mut dm, mut explicit, mut qpa, mut lets) = (0, 0, 0, 0);
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        blocked += usize::from(spec.tasks.iter().any(|t| !t.sections.is_empty()));
        charged += usize::from(!spec.overheads.is_zero());
        dm += usize::from(spec.priorities == Priorities::DeadlineMonotonic);
        explicit += usize::from(spec.priorities == Priorities::Explicit);
        qpa += usize::from(spec.schedulability == SchedTest::Qpa);
        lets += usize::from(spec.communication == Communication::Let);
        let t = periods(&spec);
        let r = relax(&spec, &t, &t, &[], true);
        bounded += r.chains.iter().filter(|c| c.0.is_some()).count();
        let report = analyze(&spec);
        bounds_point(&r, &spec, &report, &format!("seed {seed}"), true);
        event_below(&r, &t, &t, &report, &format!("seed {seed}"), true);
        paper_below(&r, &spec, &t, &t, &report, &format!("seed {seed}"), true);
    }
    let monotone = (0..SYSTEMS)
        .filter(|&seed| paper_monotone(&random_system(seed, &config(seed))))
        .count();
    assert!(
        monotone > SYSTEMS as usize / 2,
        "only {monotone} systems check the paper figures"
    );
    // Most generated chains are bounded: the comparison is not vacuous.
    assert!(bounded > SYSTEMS as usize, "only {bounded} bounded chains");
    // A fair share of the systems have sections and overheads.
    assert!(
        blocked > SYSTEMS as usize / 8 && charged > SYSTEMS as usize / 8,
        "{blocked} systems with sections, {charged} with overheads"
    );
    // And with deadline-monotonic or explicit priorities, or QPA.
    eprintln!("{dm} deadline-monotonic, {explicit} explicit, {qpa} QPA, {lets} LET systems");
    assert!(
        dm > SYSTEMS as usize / 16 && explicit > SYSTEMS as usize / 16 && qpa > 20,
        "{dm} deadline-monotonic, {explicit} explicit, {qpa} QPA systems"
    );
    assert!(lets > SYSTEMS as usize / 16, "{lets} LET systems");
}

#[test]
fn a_box_bounds_every_point_inside_from_below() {
    let mut checked = 0;
    let mut bounded = 0;
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        let t = periods(&spec);
        let mut rng = Rng::new(seed);
        // A box around the generated periods, up to halving and doubling.
        let lo: Vec<Nanos> = t
            .iter()
            .map(|&p| (p - (rng.unit() * p as f64 / 2.0) as Nanos).max(1))
            .zip(&spec.tasks)
            .map(|(p, task)| p.max(task.deadline_given.unwrap_or(1)))
            .collect();
        let hi: Vec<Nanos> = t
            .iter()
            .map(|&p| p + (rng.unit() * p as f64) as Nanos)
            .collect();
        let r = relax(&spec, &lo, &hi, &[], true);
        bounded += r.chains.iter().filter(|c| c.0.is_some()).count();
        for probe in 0..8 {
            let point: Vec<Nanos> = (0..t.len())
                .map(|i| match probe {
                    0 => lo[i],
                    1 => hi[i],
                    _ => lo[i] + (rng.unit() * (hi[i] - lo[i]) as f64) as Nanos,
                })
                .collect();
            let s = at(&spec, &point);
            let report = analyze(&s);
            bounds_point(
                &r,
                &s,
                &report,
                &format!("seed {seed} probe {probe}"),
                false,
            );
            forms_below(
                &r,
                &lo,
                &point,
                &report,
                &format!("seed {seed} probe {probe}"),
            );
            event_below(
                &r,
                &lo,
                &point,
                &report,
                &format!("seed {seed} probe {probe}"),
                false,
            );
            paper_below(
                &r,
                &spec,
                &lo,
                &point,
                &report,
                &format!("seed {seed} probe {probe}"),
                false,
            );
            checked += 1;
        }
        // A sub-box never has lower figures.
        let mid: Vec<Nanos> = (0..t.len()).map(|i| lo[i] + (hi[i] - lo[i]) / 2).collect();
        for sub in [
            relax(&spec, &lo, &mid, &[], true),
            relax(&spec, &mid, &hi, &[], true),
        ] {
            for (a, b) in r.chains.iter().zip(&sub.chains) {
                assert!(
                    below(a.0, b.0) && below(a.1, b.1),
                    "seed {seed}: a sub-box lowered a chain"
                );
            }
        }
    }
    assert_eq!(checked, 8 * SYSTEMS);
    assert!(
        bounded > SYSTEMS as usize / 2,
        "only {bounded} bounded chains over boxes"
    );
}

/// With rank orders imposed, the box bounds every point inside that has
/// those orders (here: the orders of one random point).
#[test]
fn imposed_orders_bound_the_points_that_have_them() {
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        if spec.scheduler != Scheduler::Rm {
            continue;
        }
        let t = periods(&spec);
        let mut rng = Rng::new(seed ^ 0xabc);
        let lo: Vec<Nanos> = t
            .iter()
            .zip(&spec.tasks)
            .map(|(&p, task)| (p / 2).max(task.deadline_given.unwrap_or(1)))
            .collect();
        let hi: Vec<Nanos> = t.iter().map(|&p| 2 * p).collect();
        let point: Vec<Nanos> = (0..t.len())
            .map(|i| lo[i] + (rng.unit() * (hi[i] - lo[i]) as f64) as Nanos)
            .collect();
        let s = at(&spec, &point);
        let report = analyze(&s);
        let mut imposed = Vec::new();
        for a in 0..t.len() {
            for b in 0..t.len() {
                let (pa, pb) = (report.timing[a].priority, report.timing[b].priority);
                let same = spec.tasks[a].cpu == spec.tasks[b].cpu;
                if let (Some(x), Some(y), true) = (pa, pb, same) {
                    if x < y && rng.chance(0.5) {
                        imposed.push((a, b));
                    }
                }
            }
        }
        let r = relax(&spec, &lo, &hi, &imposed, true);
        bounds_point(
            &r,
            &s,
            &report,
            &format!("seed {seed} imposed {imposed:?}"),
            false,
        );
        forms_below(&r, &lo, &point, &report, &format!("seed {seed} imposed"));
        event_below(
            &r,
            &lo,
            &point,
            &report,
            &format!("seed {seed} imposed"),
            false,
        );
        paper_below(
            &r,
            &spec,
            &lo,
            &point,
            &report,
            &format!("seed {seed} imposed"),
            false,
        );
        // At the point itself, imposing its own orders changes nothing.
        let exact = relax(&spec, &point, &point, &imposed, true);
        bounds_point(&exact, &s, &report, &format!("seed {seed} point"), true);
    }
}
