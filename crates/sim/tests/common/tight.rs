//! Tightness per feature (docs/analysis.md, "How tight, per feature"):
//! for every chain and quantity of a feature oracle's random systems, a
//! search of its own for the worst latency, divided by the sound bound,
//! reported per feature the system has (release jitter, deadline-monotonic
//! or explicit priorities and deadlines, PCP, PIP, SRP, overheads, LET,
//! EDF with QPA), as the median and the least. Every run of every search
//! is also checked against the bound (0 violations, or the test fails).
//!
//! `RTPIPE_TIGHT_SYSTEMS` (default 60) systems from seed 0,
//! `RTPIPE_TIGHT_RESTARTS` × `RTPIPE_TIGHT_STEPS` (default 10 × 200) runs
//! per search (3 × 40 left much of the gap to the search, docs/analysis.md),
//! and the `RTPIPE_TIGHT_SHOW` loosest chains and quantities printed
//! (default none); known offsets are dropped, since the ratios measure the
//! bound for any phasing. The tests that call it are ignored (minutes of
//! work):
//! `cargo test --release -p rtpipe-sim --test jitter_oracle tightness --
//! --ignored --nocapture`.

use rtpipe_analysis::{analyze, Anchor, Metric};
use rtpipe_model::{
    Communication, Nanos, Priorities, ResourceProtocol, SchedTest, Scheduler, Spec,
};
use rtpipe_sim::search::{search_with, SearchConfig};
use rtpipe_testkit::env_u64;
use std::collections::BTreeMap;

/// The four quantities, in the order of the tables.
const QUANTITIES: [(Metric, Anchor); 4] = [
    (Metric::Reaction, Anchor::Read),
    (Metric::Freshness, Anchor::Read),
    (Metric::Reaction, Anchor::Event),
    (Metric::Freshness, Anchor::Event),
];

/// The features a system has, by name.
pub fn features(spec: &Spec) -> Vec<&'static str> {
    let mut out = Vec::new();
    let fixed = spec.scheduler == Scheduler::Rm;
    if spec.tasks.iter().any(|t| t.jitter > 0) {
        out.push("jitter");
    }
    if fixed
        && (spec.priorities != Priorities::RateMonotonic
            || spec.tasks.iter().any(|t| t.deadline_given.is_some()))
    {
        out.push("dm/explicit, deadlines");
    }
    if spec.tasks.iter().any(|t| !t.sections.is_empty()) {
        out.push(match spec.resource_protocol {
            ResourceProtocol::Pcp => "pcp",
            ResourceProtocol::Pip => "pip",
            ResourceProtocol::Srp if fixed => "srp (fixed priority)",
            ResourceProtocol::Srp => "srp (edf)",
        });
    }
    if !spec.overheads.is_zero() {
        out.push("overheads");
    }
    if (0..spec.tasks.len()).any(|i| spec.task_communication(i) == Communication::Let) {
        out.push("let");
    }
    if !fixed && spec.schedulability == SchedTest::Qpa {
        out.push("edf, qpa");
    }
    out
}

/// Per feature and quantity, the found/sound ratios; and the samples the
/// searches simulated.
#[derive(Default)]
pub struct Spread {
    pub ratios: BTreeMap<&'static str, [Vec<f64>; 4]>,
    pub samples: u64,
    pub systems: u64,
    /// Every ratio with where it comes from, for `RTPIPE_TIGHT_SHOW`.
    pub cases: Vec<Case>,
}

/// One searched chain and quantity.
pub struct Case {
    pub ratio: f64,
    pub seed: u64,
    pub chain: usize,
    /// Index into [`QUANTITIES`].
    pub quantity: usize,
    pub found: Nanos,
    pub bound: Nanos,
}

impl Spread {
    fn merge(&mut self, o: Spread) {
        for (k, v) in o.ratios {
            let mine = self.ratios.entry(k).or_default();
            for (a, b) in mine.iter_mut().zip(v) {
                a.extend(b);
            }
        }
        self.samples += o.samples;
        self.systems += o.systems;
        self.cases.extend(o.cases);
    }
}

/// The worst latency the search `cfg` finds on `spec`, the system of
/// `seed` (`None` without a sample), asserted not above its sound bound,
/// and the samples it simulated.
pub fn worst_found(spec: &Spec, seed: u64, cfg: &SearchConfig) -> (Option<Nanos>, u64) {
    let mut samples = 0;
    let r = search_with(spec, cfg, |_, res| {
        samples += res.chains.iter().map(|s| s.samples).sum::<u64>();
    })
    .unwrap_or_else(|e| panic!("seed {seed}: search refused the system: {e}"));
    assert!(!r.exceeds_sound(), "seed {seed}: {r}");
    (r.value, samples)
}

/// `spec` with every known offset dropped. The ratios measure the bound
/// for any phasing, so the search must range over every phasing: a system
/// released synchronously (the oracles draw some, to check their
/// known-offset bounds) may have a smaller worst case than any phasing
/// reaches, which no search of its demands alone can find.
fn any_phasing(spec: &Spec) -> Spec {
    let mut free = spec.clone();
    for t in free.tasks.iter_mut() {
        t.offset = None;
    }
    free
}

/// One system's searched ratios, added under each of its features.
fn system_tightness(spec: &Spec, seed: u64, restarts: u32, steps: u32, out: &mut Spread) {
    let feats = features(spec);
    out.systems += 1;
    if feats.is_empty() {
        return;
    }
    let spec = &any_phasing(spec);
    let report = analyze(spec);
    let horizon = super::horizon(spec);
    for c in &report.chains {
        for (q, &(metric, anchor)) in QUANTITIES.iter().enumerate() {
            if metric != c.metric {
                continue;
            }
            let Some(bound) = c.bound.sound(anchor) else {
                continue;
            };
            let search = SearchConfig {
                restarts,
                steps,
                seed: seed ^ 0x7167,
                anchor,
                ..SearchConfig::new(c.chain, metric, horizon)
            };
            let (found, samples) = worst_found(spec, seed, &search);
            out.samples += samples;
            if let Some(v) = found {
                let ratio = v as f64 / bound as f64;
                out.cases.push(Case {
                    ratio,
                    seed,
                    chain: c.chain,
                    quantity: q,
                    found: v,
                    bound,
                });
                for f in &feats {
                    out.ratios.entry(f).or_default()[q].push(ratio);
                }
            }
        }
    }
}

/// The tightness of `system`'s random systems per feature, printed as a
/// table (see the module's doc); `what` names the oracle.
pub fn per_feature(what: &str, system: impl Fn(u64) -> Spec + Sync) {
    let n = env_u64("RTPIPE_TIGHT_SYSTEMS", 60);
    let restarts = env_u64("RTPIPE_TIGHT_RESTARTS", 10) as u32;
    let steps = env_u64("RTPIPE_TIGHT_STEPS", 200) as u32;
    let workers = std::thread::available_parallelism().map_or(1, |p| p.get()) as u64;
    let mut all = Spread::default();
    std::thread::scope(|s| {
        let system = &system;
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                s.spawn(move || {
                    let mut mine = Spread::default();
                    let mut seed = w;
                    while seed < n {
                        system_tightness(&system(seed), seed, restarts, steps, &mut mine);
                        seed += workers;
                    }
                    mine
                })
            })
            .collect();
        for h in handles {
            all.merge(h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        }
    });
    println!(
        "tightness per feature, {what}: {} systems, {restarts} x {steps} runs per search, {} samples simulated",
        all.systems, all.samples
    );
    print_table(&all);
    print_loosest(&mut all.cases, env_u64("RTPIPE_TIGHT_SHOW", 0) as usize);
}

/// The loosest `k` chains and quantities: where to look for a loose term.
fn print_loosest(cases: &mut [Case], k: usize) {
    cases.sort_by(|a, b| a.ratio.total_cmp(&b.ratio));
    for c in cases.iter().take(k) {
        let (metric, anchor) = QUANTITIES[c.quantity];
        println!(
            "loose: seed {} chain {} {} from the {}: found {} of {} ({:.3})",
            c.seed,
            c.chain,
            metric.name(),
            anchor.name(),
            c.found,
            c.bound,
            c.ratio
        );
    }
}

/// The median and the least ratio per feature and quantity.
fn print_table(all: &Spread) {
    println!("| feature | quantity | chains | median | min |");
    for (feature, quantities) in &all.ratios {
        for (q, (metric, anchor)) in QUANTITIES.iter().enumerate() {
            let mut w = quantities[q].clone();
            w.sort_by(f64::total_cmp);
            let mid = ((w.len() as f64 - 1.0) * 0.5).round() as usize;
            let median = w.get(mid).copied().unwrap_or(f64::NAN);
            let min = w.first().copied().unwrap_or(f64::NAN);
            println!(
                "| {feature} | {} from the {} | {} | {median:.3} | {min:.3} |",
                metric.name(),
                anchor.name(),
                w.len()
            );
        }
    }
}
