//! The root box's bound (with the split bound of `joint::split_bound`)
//! against brute force on small generated problems: the least utilisation
//! of a verified design is never below it, and the chains lift it above
//! Σ C/hi on some of them (the check is not vacuous); the design repaired
//! and rounded from the relaxation's least point is verified.

use crate::api::{utilization, Options};
use crate::axis::Node;
use crate::bnb::{Branching, Examiner, Fate};
use crate::budget::Budget;
use crate::domain::domains;
use crate::problem::Problem;
use crate::{Method, Mode};
use rtpipe_analysis::{bounds_per_chain, Anchor};
use rtpipe_model::gen::{design_problem, ChainBounds, DesignGenConfig, GenConfig, Rng};
use rtpipe_model::{Scheduler, Spec};

fn sound_bounds(spec: &Spec) -> Vec<ChainBounds> {
    bounds_per_chain(spec, |b| b.sound(Anchor::Read))
}

fn paper_bounds(spec: &Spec) -> Vec<ChainBounds> {
    bounds_per_chain(spec, |b| Some(b.paper(Anchor::Read)))
}

/// Problem `seed`: 3–5 tasks, one or two CPUs, 1–3 chains, at most 256
/// choices of periods in all; limits from the generating design's bounds.
pub(crate) fn problem(seed: u64, mode: Mode) -> Spec {
    let mut r = Rng::new(seed ^ 0x5b11_7b0d);
    let tasks = r.range(3, 5) as usize;
    let cfg = DesignGenConfig {
        system: GenConfig {
            tasks,
            cpus: if r.chance(0.3) { 2 } else { 1 },
            utilization: 0.3 + 0.4 * r.unit(),
            scheduler: if r.chance(0.15) {
                Scheduler::Edf
            } else {
                Scheduler::Rm
            },
            chains: r.range(1, 3) as usize,
            ..GenConfig::default()
        },
        choices_only: true,
        max_choices: if tasks <= 4 { 4 } else { 3 },
        ..DesignGenConfig::default()
    };
    match mode {
        Mode::Paper => design_problem(seed, &cfg, &paper_bounds),
        Mode::Sound => design_problem(seed, &cfg, &sound_bounds),
    }
}

/// The least U of a verified point of the whole domain, by enumeration.
pub(crate) fn brute_force(ex: &Examiner, n: usize) -> Option<f64> {
    let hi: Vec<u32> = ex.axes.iter().map(|a| a.len() - 1).collect();
    brute_force_in(ex, &vec![0; n], &hi)
}

/// The least U of a verified point of the box `lo ≤ k ≤ hi` (axis
/// indices), by enumeration.
fn brute_force_in(ex: &Examiner, lo: &[u32], hi: &[u32]) -> Option<f64> {
    let mut k = lo.to_vec();
    let mut best: Option<f64> = None;
    loop {
        let (spec, _, ok) = ex.verify(&k);
        if ok {
            let u = utilization(&spec);
            best = Some(best.map_or(u, |b: f64| b.min(u)));
        }
        // The next assignment, odometer-wise.
        let mut i = 0;
        loop {
            if i == k.len() {
                return best;
            }
            k[i] += 1;
            if k[i] <= hi[i] {
                break;
            }
            k[i] = lo[i];
            i += 1;
        }
    }
}

/// Runs `each` on the small generated problems of seeds `0..count`,
/// sound and paper mode in turn, with their examiner and its axes' count
/// (a problem whose periods have no domain is skipped).
pub(crate) fn small_problems(count: u64, mut each: impl FnMut(u64, &Examiner, usize, &Options)) {
    for seed in 0..count {
        let mode = if seed % 2 == 0 {
            Mode::Sound
        } else {
            Mode::Paper
        };
        let spec = problem(seed, mode);
        let opts = Options {
            mode,
            ..Options::default()
        };
        let Ok(d) = domains(&spec) else { continue };
        let p = Problem::new(&spec, &opts, d, Method::Boxes);
        let groups = p.all_groups();
        let ex = Examiner::new(&p, &groups);
        each(seed, &ex, ex.axes.len(), &opts);
    }
}

/// Over the box `lo..=hi` (axis indices), whether some chain's sound
/// pieces come in parts (`relax::sound_pieces`' partition by the orders
/// the periods decide), and whether some task's period is cut twice or
/// more there (a staircase).
fn in_parts(ex: &Examiner, lo: &[u32], hi: &[u32]) -> (bool, bool) {
    let spec = ex.p.spec;
    let (lo, hi) = (ex.periods(lo), ex.periods(hi));
    let r = rtpipe_analysis::relax::relax(spec, &lo, &hi, &[], false);
    let ranges = (0..spec.chains.len())
        .filter_map(|k| rtpipe_analysis::relax::sound_pieces(spec, (&lo, &hi), &[], &r, k))
        .map(|parts| rtpipe_analysis::relax::most_ranges(&parts))
        .max()
        .unwrap_or(1);
    (ranges > 1, ranges > 2)
}

#[test]
fn the_root_bound_is_below_the_brute_force_optimum() {
    let (mut lifted, mut parts, mut stairs) = (0, 0, 0);
    small_problems(600, |seed, ex, n, opts| {
        let mode = opts.mode;
        let hi: Vec<u32> = ex.axes.iter().map(|a| a.len() - 1).collect();
        let plain = ex.bound(&hi);
        if mode == Mode::Sound {
            let (split, staircase) = in_parts(ex, &vec![0; n], &hi);
            parts += usize::from(split);
            stairs += usize::from(staircase);
        }
        let root = Node {
            lo: vec![0; n],
            hi,
            above: Vec::new(),
            shares: Default::default(),
            bound: plain,
        };
        let best = brute_force(ex, n);
        // A design from the relaxation's least point verifies, and none
        // is below the optimum (a problem whose chains have no pieces
        // has no guide).
        let budget = Budget::new(opts, std::time::Instant::now());
        if let Some((_, _, u)) = ex.guided(&root, None, &budget) {
            let b = best.expect("a guided design where brute force finds none");
            assert!(u >= b * (1.0 - 1e-9), "seed {seed}: guided {u} below {b}");
        }
        let bound = match ex.examine(root, None) {
            Fate::Pruned => {
                assert_eq!(best, None, "seed {seed} {mode:?}: pruned a feasible root");
                return;
            }
            Fate::Verified(node, _, _) | Fate::Open(node, _) => node.bound,
        };
        let best = best.unwrap_or(f64::INFINITY);
        assert!(
            bound <= best * (1.0 + 1e-9),
            "seed {seed} {mode:?}: root bound {bound} above the optimum {best}"
        );
        lifted += usize::from(bound > plain * (1.0 + 1e-6));
    });
    println!("{lifted} root bounds lifted, {parts} roots in parts, {stairs} in a staircase");
    assert!(lifted >= 30, "the chains lifted only {lifted} root bounds");
    assert!(parts >= 30, "only {parts} roots in parts");
    assert!(stairs >= 20, "only {stairs} roots in a staircase");
}

/// Below the root, where the pieces' shared slopes and the relaxation's
/// distinctness meet narrower boxes: every box the period splits make, to
/// depth 6, is pruned only when it holds no verified point, and its bound
/// is at most the least U of a verified point inside it (by enumeration
/// of the box).
#[test]
fn split_boxes_bound_their_own_optimum() {
    let (mut boxes, mut parts, mut stairs) = (0, 0, 0);
    small_problems(600, |seed, ex, n, opts| {
        let hi: Vec<u32> = ex.axes.iter().map(|a| a.len() - 1).collect();
        let root = Node {
            lo: vec![0; n],
            bound: ex.bound(&hi),
            hi,
            above: Vec::new(),
            shares: Default::default(),
        };
        let mut open = vec![(root, 0)];
        while let Some((node, depth)) = open.pop() {
            let what = format!(
                "seed {seed} {:?} box {:?}..{:?}",
                opts.mode, node.lo, node.hi
            );
            let best = brute_force_in(ex, &node.lo, &node.hi);
            boxes += usize::from(depth > 0);
            if opts.mode == Mode::Sound {
                let (split, staircase) = in_parts(ex, &node.lo, &node.hi);
                parts += usize::from(split);
                stairs += usize::from(staircase);
            }
            let (node, branching) = match ex.examine(node, None) {
                Fate::Pruned => {
                    assert_eq!(best, None, "{what}: pruned a box with a verified point");
                    continue;
                }
                Fate::Verified(node, _, _) => (node, None),
                Fate::Open(node, b) => (node, Some(b)),
            };
            let best = best.unwrap_or(f64::INFINITY);
            assert!(
                node.bound <= best * (1.0 + 1e-9),
                "{what}: bound {} above the box's optimum {best}",
                node.bound
            );
            // Order branches impose ranks the enumeration would have to
            // filter by; only the period splits are followed.
            if let (Some(Branching::Split(i)), true) = (branching, depth < 6) {
                let (a, b) = ex.children(&node, Branching::Split(i));
                open.push((a, depth + 1));
                open.push((b, depth + 1));
            }
        }
    });
    println!("{boxes} boxes below the root, {parts} boxes in parts, {stairs} in a staircase");
    assert!(boxes >= 700, "only {boxes} boxes below the root");
    assert!(parts >= 100, "only {parts} boxes in parts");
    assert!(stairs >= 30, "only {stairs} boxes in a staircase");
}
