//! `relax::sound_pieces` and `paper_pieces` against the analysis: over any
//! box, at every point inside (with the imposed orders), each chain's
//! least-of-pieces sums are below the analysis' figures (the property the
//! design's split bound rests on), also over boxes as wide as a design's
//! domains (an eighth to four times the generated periods). The sound
//! reaction sums' reachability pieces in a chain's middle share their
//! slope with every stage before them; that they do is counted, so the
//! check covers them. The sound sums come one set per part of the box
//! (`sound_pieces`' partition by the orders the periods decide); each
//! point is checked against the part that holds it, and the chains in
//! parts are counted too.

use rtpipe_analysis::relax::{
    most_ranges, paper_monotone, paper_pieces, relax, sound_pieces, MinSum,
};
use rtpipe_analysis::{analyze, Anchor, Metric, Report};
use rtpipe_model::gen::{random_system, GenConfig, Rng};
use rtpipe_model::{Nanos, PeriodSpec, SchedTest, Scheduler, Spec};

const SYSTEMS: u64 = 1200;

fn system(seed: u64) -> Spec {
    let mut rng = Rng::new(seed ^ 0x9135);
    let cfg = GenConfig {
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
        ..GenConfig::default()
    };
    let mut spec = random_system(seed, &cfg);
    if spec.scheduler == Scheduler::Rm && rng.chance(0.5) {
        spec.schedulability = SchedTest::Rta;
    }
    spec
}

/// For an even seed [`system`], for an odd one two tasks on one CPU and
/// one chain, with its periods; `None` unless ranked rate-monotonic (the
/// order the tied pieces and the parts follow).
fn rm_system_or_pair(seed: u64) -> Option<(Spec, Vec<Nanos>)> {
    let pair = GenConfig {
        tasks: 2,
        cpus: 1,
        chains: 1,
        ..GenConfig::default()
    };
    let spec = match seed % 2 {
        0 => system(seed),
        _ => random_system(seed, &pair),
    };
    if spec.scheduler != Scheduler::Rm {
        return None;
    }
    let t = spec
        .tasks
        .iter()
        .map(|x| x.fixed_period().expect("fixed"))
        .collect();
    Some((spec, t))
}

fn at(spec: &Spec, t: &[Nanos]) -> Spec {
    let mut s = spec.clone();
    for (task, &p) in s.tasks.iter_mut().zip(t) {
        task.period = PeriodSpec::Fixed(p);
    }
    s
}

/// The analysis' figure of chain k (`None`: unbounded).
fn figure(report: &Report, k: usize, m: Metric, sound: bool, a: Anchor) -> Option<Nanos> {
    let c = report
        .chains
        .iter()
        .find(|c| c.chain == k && c.metric == m)?;
    if sound {
        c.bound.sound(a)
    } else {
        Some(c.bound.paper(a))
    }
}

fn below(what: &str, lower: f64, exact: Option<Nanos>) {
    if let Some(x) = exact {
        assert!(lower <= x as f64 + 1e-6, "{what}: {lower} above {x}");
    }
}

/// A sound reaction term's pieces in at least `periods` periods (a
/// reachability piece that shares its slope with the stages before it),
/// in `e`.
fn shared_pieces(e: &MinSum, periods: usize) -> usize {
    e.terms
        .iter()
        .flatten()
        .filter(|p| p.slopes.len() >= periods)
        .count()
}

/// What [`pieces_below`] checked: chains with pieces, sound reaction
/// pieces that share a slope, those that share it with two stages or
/// more, chains whose box was split into parts
/// (`relax::sound_pieces`' partition by the orders the periods decide),
/// and those where one task's period was cut twice or more (a staircase).
#[derive(Default)]
struct Checked {
    with: usize,
    shared: usize,
    long: usize,
    split: usize,
    stairs: usize,
}

impl std::ops::AddAssign for Checked {
    fn add_assign(&mut self, o: Checked) {
        self.with += o.with;
        self.shared += o.shared;
        self.long += o.long;
        self.split += o.split;
        self.stairs += o.stairs;
    }
}

/// Every chain's pieces at `t` against the analysis there (the paper
/// mode's too with `paper`): in sound mode those of the part of the box
/// that holds `t`.
fn pieces_below(
    spec: &Spec,
    (lo, hi): (&[Nanos], &[Nanos]),
    imposed: &[(usize, usize)],
    t: &[Nanos],
    (what, paper): (&str, bool),
) -> Checked {
    // Pieces bound the analysis only inside their box: outside it a link's
    // case may be one the box rules out (a probe below a task's lower end
    // once put paper mode's pieces above the analysis, docs/design.md,
    // "The relaxation on wide boxes, term by term").
    let inside = t
        .iter()
        .zip(lo.iter().zip(hi))
        .all(|(x, (l, h))| l <= x && x <= h);
    assert!(inside, "{what}: probe {t:?} outside the box {lo:?}..{hi:?}");
    let r = relax(spec, lo, hi, imposed, false);
    let report = analyze(&at(spec, t));
    let (mut with, mut shared, mut long, mut split, mut stairs) = (0, 0, 0, 0, 0);
    for k in 0..spec.chains.len() {
        let fig = |m, sound, a| figure(&report, k, m, sound, a);
        let w = |s: &str| format!("{what}: chain {k} {s}");
        if let Some(parts) = sound_pieces(spec, (lo, hi), imposed, &r, k) {
            // The parts partition the box: exactly one holds at each point.
            let mut holding = parts.iter().filter(|(e, _, _)| e.holds_at(t));
            let (e, f, ev) = holding.next().expect("a part at every point");
            assert!(holding.next().is_none(), "{what}: parts overlap at {t:?}");
            assert!(parts
                .iter()
                .all(|(e, f, ev)| e.within == f.within && f.within == ev.within));
            with += 1;
            split += usize::from(parts.len() > 1);
            stairs += usize::from(most_ranges(&parts) > 2);
            shared += shared_pieces(e, 2);
            long += shared_pieces(e, 3);
            let least = |s: &MinSum| s.at(t);
            below(
                &w("sound reaction"),
                least(e).min(least(f)),
                fig(Metric::Reaction, true, Anchor::Read),
            );
            below(
                &w("sound freshness"),
                least(f),
                fig(Metric::Freshness, true, Anchor::Read),
            );
            below(
                &w("sound event reaction"),
                least(ev),
                fig(Metric::Reaction, true, Anchor::Event),
            );
        }
        let paper = paper.then(|| paper_pieces(spec, (lo, hi), imposed, k));
        if let Some((e, f)) = paper.flatten() {
            with += 1;
            assert!(paper_monotone(spec));
            below(
                &w("paper reaction"),
                e.at(t),
                fig(Metric::Reaction, false, Anchor::Read),
            );
            below(
                &w("paper freshness"),
                f.at(t),
                fig(Metric::Freshness, false, Anchor::Read),
            );
        }
    }
    Checked {
        with,
        shared,
        long,
        split,
        stairs,
    }
}

/// The rank orders of the tasks at `t` (a above b), each kept by chance.
fn orders_at(spec: &Spec, t: &[Nanos], rng: &mut Rng) -> Vec<(usize, usize)> {
    let report = analyze(&at(spec, t));
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
    imposed
}

#[test]
fn pieces_bound_every_point_of_a_box_from_below() {
    let mut checked = Checked::default();
    let mut count = |c: Checked| checked += c;
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        let t: Vec<Nanos> = spec
            .tasks
            .iter()
            .map(|x| x.fixed_period().expect("fixed"))
            .collect();
        let mut rng = Rng::new(seed);
        // Narrow boxes (half to twice), and as wide as a design's domains.
        let (down, up) = if seed % 2 == 0 { (2, 2) } else { (8, 4) };
        // A design's domains keep T ≥ C (and T ≥ D).
        let lo: Vec<Nanos> = t
            .iter()
            .zip(&spec.tasks)
            .map(|(&p, x)| {
                (p / down)
                    .max(x.budget())
                    .max(x.deadline_given.unwrap_or(1))
                    .max(1)
            })
            .collect();
        let hi: Vec<Nanos> = t.iter().map(|&p| p * up).collect();
        let probe = |rng: &mut Rng| -> Vec<Nanos> {
            (0..t.len())
                .map(|i| lo[i] + (rng.unit() * (hi[i] - lo[i]) as f64) as Nanos)
                .collect()
        };
        for k in 0..6 {
            let point = match k {
                0 => lo.clone(),
                1 => hi.clone(),
                _ => probe(&mut rng),
            };
            let what = format!("seed {seed} probe {k}");
            count(pieces_below(&spec, (&lo, &hi), &[], &point, (&what, true)));
        }
        if spec.scheduler == Scheduler::Rm {
            let point = probe(&mut rng);
            let imposed = orders_at(&spec, &point, &mut rng);
            let what = format!("seed {seed} imposed {imposed:?}");
            count(pieces_below(
                &spec,
                (&lo, &hi),
                &imposed,
                &point,
                (&what, true),
            ));
        }
    }
    // Not vacuous: most chains get pieces, and many middle links a
    // shared reachability piece, some of them with two stages or more.
    let Checked {
        with,
        shared,
        long,
        split,
        ..
    } = checked;
    println!(
        "{with} chains with pieces, {shared} shared pieces, {long} with two stages or more, \
         {split} in parts"
    );
    assert!(shared > SYSTEMS as usize, "only {shared} shared pieces");
    assert!(
        long > SYSTEMS as usize / 4,
        "only {long} pieces shared with two stages"
    );
    assert!(
        with > SYSTEMS as usize * 6,
        "only {with} chains with pieces"
    );
    assert!(split > SYSTEMS as usize, "only {split} chains in parts");
}

/// Boxes where one link's two tasks share a CPU and every other period is
/// fixed, the two periods open across each other (so that their order is
/// open and the other response times are nearly exact): the pieces tied
/// to the order the periods imply (Case One only where `T_c ≤ T_p`, with
/// c's interference in `R_p`) are below the analysis on both sides.
#[test]
fn tied_pieces_bound_both_sides_of_an_open_order() {
    let mut probes = 0;
    for seed in 0..2 * SYSTEMS {
        // Half of them two tasks on one CPU and one chain, where the tied
        // pieces are exact on Case One's side (the tail's R and the
        // producer's R and W are then C plus the other's interference).
        let Some((spec, t)) = rm_system_or_pair(seed) else {
            continue;
        };
        let mut rng = Rng::new(seed ^ 0x71ed);
        let links: Vec<(usize, usize)> = spec
            .chains
            .iter()
            .flat_map(|c| c.path.windows(2).map(|w| (w[0], w[1])))
            .filter(|&(p, c)| p != c && spec.tasks[p].cpu == spec.tasks[c].cpu)
            .collect();
        for (p, c) in links {
            let floor = |i: usize| {
                let x = &spec.tasks[i];
                x.budget().max(x.deadline_given.unwrap_or(1)).max(1)
            };
            let (a, b) = (t[p].min(t[c]), t[p].max(t[c]));
            let (mut lo, mut hi) = (t.clone(), t.clone());
            for i in [p, c] {
                lo[i] = (a / 2).max(floor(i));
                hi[i] = b * 2;
            }
            // Both periods drawn from the part of the box open to each, so
            // that either may take the other's value and the probe stays
            // inside the box (a floor, C or D, differs between the two).
            let (low, high) = (lo[p].max(lo[c]), hi[p].min(hi[c]));
            let span = |rng: &mut Rng| low + (rng.unit() * (high - low) as f64) as Nanos;
            for k in 0..6 {
                let mut point = t.clone();
                let (x, y) = (span(&mut rng), span(&mut rng));
                // Both sides: c's period below p's, then above, then the
                // two equal (the order then falls to the tie-break).
                (point[p], point[c]) = match k % 3 {
                    0 => (x.max(y), x.min(y)),
                    1 => (x.min(y), x.max(y)),
                    _ => (x, x),
                };
                let what = format!("seed {seed} link {p}->{c} probe {k}");
                probes += pieces_below(&spec, (&lo, &hi), &[], &point, (&what, true)).with;
            }
        }
    }
    assert!(probes > SYSTEMS as usize, "only {probes} probes");
}

/// Boxes where a chain task `a`'s period is open above the longest period
/// of another task `b` on its CPU, every other period fixed: the box is
/// split where `b` starts to be above `a` at every point
/// (`relax::sound_pieces`' parts), and each part's pieces, which count
/// `b`'s interference in `a`'s response times above the split, are below
/// the analysis on both sides of it (on two tasks on one CPU they are
/// exact there).
#[test]
fn parts_bound_both_sides_of_a_decided_order() {
    let (mut probes, mut split) = (0, 0);
    for seed in 0..2 * SYSTEMS {
        let Some((spec, t)) = rm_system_or_pair(seed) else {
            continue;
        };
        let mut rng = Rng::new(seed ^ 0x5b17);
        let floor = |i: usize| {
            let x = &spec.tasks[i];
            x.budget().max(x.deadline_given.unwrap_or(1)).max(1)
        };
        let chain_tasks: Vec<usize> = spec.chains.iter().flat_map(|c| c.path.clone()).collect();
        for &a in &chain_tasks {
            let mates = (0..t.len()).filter(|&b| b != a && spec.tasks[b].cpu == spec.tasks[a].cpu);
            for b in mates.collect::<Vec<_>>() {
                // b's range inside the lower part of a's, so that a's
                // period is open across it and above it.
                let top = t[a].max(t[b]);
                let (mut lo, mut hi) = (t.clone(), t.clone());
                lo[a] = (t[a].min(t[b]) / 2).max(floor(a));
                hi[a] = top * 2;
                lo[b] = (t[b] / 2).max(floor(b));
                hi[b] = top.max(lo[b]);
                for k in 0..4 {
                    let mut point = t.clone();
                    let span = |rng: &mut Rng, l: Nanos, h: Nanos| {
                        l + (rng.unit() * (h - l) as f64) as Nanos
                    };
                    point[b] = span(&mut rng, lo[b], hi[b]);
                    // Above b's longest period (b above a), then anywhere.
                    point[a] = match k % 2 {
                        0 => span(&mut rng, (hi[b] + 1).min(hi[a]), hi[a]),
                        _ => span(&mut rng, lo[a], hi[a]),
                    };
                    let what = format!("seed {seed} task {a} over {b} probe {k}");
                    let c = pieces_below(&spec, (&lo, &hi), &[], &point, (&what, false));
                    probes += c.with;
                    split += c.split;
                }
            }
        }
    }
    println!("{probes} chain checks, {split} of them in parts");
    assert!(split > SYSTEMS as usize, "only {split} chains in parts");
}

/// Boxes where a chain task `a`'s period is open across the longest
/// periods of every other task on its CPU (each open below its own
/// period), every other period fixed: `a`'s range is cut at several of
/// them (`R_a` is a staircase in `T_a`, `relax::sound_pieces`' parts), and
/// each part's pieces are below the analysis, probed just above each
/// step, just below it and anywhere.
#[test]
fn parts_bound_every_step_of_a_staircase() {
    let (mut probes, mut stairs) = (0, 0);
    for seed in 0..SYSTEMS {
        let spec = system(seed);
        if spec.scheduler != Scheduler::Rm {
            continue;
        }
        let t: Vec<Nanos> = spec
            .tasks
            .iter()
            .map(|x| x.fixed_period().expect("fixed"))
            .collect();
        let mut rng = Rng::new(seed ^ 0x57a1);
        let floor = |i: usize| {
            let x = &spec.tasks[i];
            x.budget().max(x.deadline_given.unwrap_or(1)).max(1)
        };
        let chain_tasks: Vec<usize> = spec.chains.iter().flat_map(|c| c.path.clone()).collect();
        for &a in &chain_tasks {
            let mates: Vec<usize> = (0..t.len())
                .filter(|&b| b != a && spec.tasks[b].cpu == spec.tasks[a].cpu)
                .collect();
            if mates.len() < 2 {
                continue;
            }
            let (mut lo, mut hi) = (t.clone(), t.clone());
            let least = mates.iter().map(|&b| t[b]).min().unwrap_or(t[a]);
            let top = mates.iter().map(|&b| t[b]).max().unwrap_or(t[a]).max(t[a]);
            lo[a] = (t[a].min(least) / 2).max(floor(a));
            hi[a] = top * 2;
            for &b in &mates {
                lo[b] = (t[b] / 2).max(floor(b)).min(t[b]);
            }
            let span =
                |rng: &mut Rng, l: Nanos, h: Nanos| l + (rng.unit() * (h - l) as f64) as Nanos;
            let steps: Vec<Nanos> = mates.iter().map(|&b| hi[b] + 1).collect();
            for k in 0..3 * steps.len() + 2 {
                let mut point = t.clone();
                for &b in &mates {
                    point[b] = span(&mut rng, lo[b], hi[b]);
                }
                let step = steps[k % steps.len()];
                point[a] = match k / steps.len() {
                    0 => step,
                    1 => step - 1,
                    _ => span(&mut rng, lo[a], hi[a]),
                }
                .clamp(lo[a], hi[a]);
                let what = format!("seed {seed} task {a} probe {k}");
                let c = pieces_below(&spec, (&lo, &hi), &[], &point, (&what, false));
                probes += c.with;
                stairs += c.stairs;
            }
        }
    }
    println!("{probes} chain checks, {stairs} of them in a staircase");
    assert!(
        stairs > SYSTEMS as usize,
        "only {stairs} chains in a staircase"
    );
}
