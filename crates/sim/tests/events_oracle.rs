//! The simulator as an oracle for threads and data-triggered tasks: on
//! random event-triggered systems (`gen::event_triggered_system`: chains
//! of 2–8 links mixing periodic and data-triggered ones, join any and
//! all, 1–6 threads, 1–2 CPUs), no simulated job responds later than its
//! task's R and no chain's reaction or freshness, from the read or from
//! the event, exceeds its sound bound (docs/analysis.md, "Threads and
//! data-triggered tasks").
//!
//! `RTPIPE_EVENT_SYSTEMS` (default 100) sets the number of systems; run
//! with `--nocapture` for the tightness summary.

use rtpipe_analysis::{analyze, Anchor, Report};
use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::observe::ChainStatsExt;
use rtpipe_sim::{simulate, ExecModel, Jitter, Phasing, SimConfig};
use rtpipe_testkit::env_u64;
use std::collections::BTreeMap;

const US: Nanos = 1_000;

/// Phasings, demands and jitters simulated for every system.
fn runs() -> [(Phasing, ExecModel, Jitter); 4] {
    [
        (Phasing::Sync, ExecModel::Worst, Jitter::Latest),
        (Phasing::Random, ExecModel::Uniform, Jitter::Uniform),
        (
            Phasing::Grid(250 * US),
            ExecModel::Extremes,
            Jitter::Extremes,
        ),
        (Phasing::Random, ExecModel::Worst, Jitter::Extremes),
    ]
}

/// About thirty of the longest periods.
fn horizon(spec: &Spec) -> Nanos {
    let longest = spec.tasks.iter().filter_map(|t| t.fixed_period()).max();
    30 * longest.unwrap_or(1000 * US)
}

/// Observed / bound per figure.
#[derive(Default)]
struct Tally {
    ratios: BTreeMap<String, Vec<f64>>,
    failures: Vec<String>,
}

impl Tally {
    fn check(&mut self, what: String, seen: Nanos, bound: Nanos, seed: u64) {
        if seen > bound {
            self.failures.push(format!(
                "seed {seed}: {what}: observed {seen} ns > bound {bound} ns"
            ));
        }
        if bound > 0 {
            let key = what.split(':').next().unwrap_or("").to_string();
            let r = seen as f64 / bound as f64;
            self.ratios.entry(key).or_default().push(r);
        }
    }

    fn summary(&self) -> String {
        let mut out = String::new();
        for (k, v) in &self.ratios {
            let mut v = v.clone();
            v.sort_by(f64::total_cmp);
            out.push_str(&format!(
                "{k}: {} figures, observed/bound max {:.3}, median {:.3}, min {:.3}\n",
                v.len(),
                v[v.len() - 1],
                v[v.len() / 2],
                v[0]
            ));
        }
        out
    }
}

/// One system, every run, every figure.
fn check_system(seed: u64, spec: &Spec, report: &Report, tally: &mut Tally) {
    for (run, (phasing, exec, jitter)) in runs().into_iter().enumerate() {
        let cfg = SimConfig {
            seed: seed.wrapping_mul(31).wrapping_add(run as u64),
            phasing,
            exec,
            jitter,
            ..SimConfig::new(horizon(spec))
        };
        let res = match simulate(spec, &cfg) {
            Ok(r) => r,
            Err(e) => panic!("seed {seed}: the simulator refused the system: {e}"),
        };
        for (i, ts) in res.tasks.iter().enumerate() {
            if let (Some(r), Some(seen)) = (report.timing[i].job_response_time, ts.max_response) {
                tally.check(format!("task R: {}", spec.tasks[i].name), seen, r, seed);
            }
        }
        for c in &report.chains {
            for anchor in Anchor::ALL {
                let seen = res.chains[c.chain].observed(c.metric, anchor).max;
                if let (Some(seen), Some(b)) = (seen, c.bound.sound(anchor)) {
                    let what = format!(
                        "{} from the {}: chain {}, run {run}",
                        c.metric.name(),
                        anchor.name(),
                        c.chain
                    );
                    tally.check(what, seen, b, seed);
                }
            }
        }
    }
}

#[test]
fn no_simulated_job_or_chain_exceeds_the_event_analysis() {
    let systems = env_u64("RTPIPE_EVENT_SYSTEMS", 100);
    let cfg = EventGenConfig::default();
    let mut tally = Tally::default();
    for seed in 0..systems {
        let spec = event_triggered_system(seed, &cfg);
        let report = analyze(&spec);
        check_system(seed, &spec, &report, &mut tally);
    }
    println!("{systems} systems\n{}", tally.summary());
    assert!(
        tally.failures.is_empty(),
        "{} observations above their bounds; first ones:\n{}",
        tally.failures.len(),
        tally.failures[..tally.failures.len().min(10)].join("\n")
    );
}
