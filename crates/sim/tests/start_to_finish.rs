//! The read-to-publish bound `W` under fixed priority, by hand
//! (docs/analysis.md, "From the read to the publish under fixed
//! priority"): a job's own release jitter, its switch in and the blocking
//! of the immediate ceiling all fall before its start, so a chain bound
//! from the read leaves them out; under priority inheritance a job can be
//! blocked after it started, and the bound keeps the blocking.

use rtpipe_analysis::{analyze, Anchor, Metric, Report};
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::observe::ChainStatsExt;
use rtpipe_sim::{simulate, ExecModel, Jitter, Phasing, SimConfig};

const US: Nanos = 1_000;
const MS: Nanos = 1_000_000;

/// A task of 1 ms every 10 ms, released up to 7 ms late, alone on its
/// CPU: R = J + x = 8 ms, but from its read to its publish every job
/// takes exactly 1 ms.
const JITTER: &str = r#"
[system]
name = "jitter"
time_unit = "ms"
priorities = "explicit"
[channels.mem]
bandwidth = 1
overhead = 0
[tasks.a]
exec = 1
period = 10
jitter = 7
priority = 1
server = "none"
[[chain]]
path = ["a"]
"#;

/// h (1 ms every 5 ms, reading l's output over a channel of 0.25 ms
/// first: x_h = 1.25 ms) shares `bus` with l (2 ms every 10 ms, its first
/// 1.5 ms in the section): B_h = 1.5, R_h = 2.75 ms. Under the immediate
/// ceiling h waits before it starts, W_h = x_h = 1.25 ms; under
/// inheritance h can start while l holds `bus`, read, and wait when it
/// reaches its section (after its input), W_h = R_h.
fn sections(protocol: &str) -> Spec {
    let src = format!(
        r#"
[system]
name = "sections"
time_unit = "ms"
resource_protocol = "{protocol}"
[resources.bus]
[channels.mem]
bandwidth = 1
overhead = 0.25
[tasks.h]
exec = 1
period = 5
server = "none"
reads = ["l"]
critical_sections = [{{ resource = "bus", length = 0.5 }}]
[tasks.l]
exec = 2
period = 10
server = "none"
output = {{ channel = "mem", size = 0 }}
critical_sections = [{{ resource = "bus", length = 1.5 }}]
[[chain]]
path = ["h"]
"#
    );
    Spec::parse("sections.toml", &src).unwrap_or_else(|e| panic!("{e}"))
}

/// The chain's sound bound of `metric` from `anchor`.
fn bound(rep: &Report, metric: Metric, anchor: Anchor) -> Option<Nanos> {
    rep.chains
        .iter()
        .find(|c| c.chain == 0 && c.metric == metric)
        .and_then(|c| c.bound.sound(anchor))
}

/// The largest reaction from the read over runs with task 0 released at
/// every offset on a grid of `step` within `span` (the last task at 0),
/// each with worst-case demands and every jitter model.
fn worst_reaction(spec: &Spec, span: Nanos, step: Nanos) -> Nanos {
    let mut worst = 0;
    for phi in (0..span).step_by(step as usize) {
        for jitter in [
            Jitter::None,
            Jitter::Latest,
            Jitter::Uniform,
            Jitter::Extremes,
        ] {
            let n = spec.tasks.len() as Nanos;
            let offsets = (0..n).map(|k| (n - 1 - k) * phi).collect();
            let cfg = SimConfig {
                phasing: Phasing::Given(offsets),
                exec: ExecModel::Worst,
                jitter,
                ..SimConfig::new(200 * MS)
            };
            let res = simulate(spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
            let seen = res.chains[0].observed(Metric::Reaction, Anchor::Read).max;
            worst = worst.max(seen.unwrap_or(0));
        }
    }
    worst
}

#[test]
fn release_jitter_is_not_in_the_bound_from_the_read() {
    let spec = Spec::parse("jitter.toml", JITTER).unwrap_or_else(|e| panic!("{e}"));
    let rep = analyze(&spec);
    assert_eq!(rep.timing[0].job_response_time, Some(8 * MS));
    assert_eq!(rep.timing[0].read_to_publish, Some(MS));
    for m in [Metric::Reaction, Metric::Freshness] {
        assert_eq!(bound(&rep, m, Anchor::Read), Some(MS), "{}", m.name());
    }
    assert_eq!(worst_reaction(&spec, MS, MS), MS);
}

#[test]
fn ceiling_blocking_is_not_in_the_bound_from_the_read() {
    for protocol in ["pcp", "srp", "pip"] {
        let spec = sections(protocol);
        let rep = analyze(&spec);
        let x_h = spec.tasks[0].demand();
        assert_eq!(x_h, 1_250 * US);
        assert_eq!(rep.timing[0].blocking, 1_500 * US, "{protocol}");
        assert_eq!(
            rep.timing[0].job_response_time,
            Some(2_750 * US),
            "{protocol}"
        );
        let w = if protocol == "pip" { 2_750 * US } else { x_h };
        assert_eq!(rep.timing[0].read_to_publish, Some(w), "{protocol}");
        assert_eq!(
            bound(&rep, Metric::Reaction, Anchor::Read),
            Some(w),
            "{protocol}"
        );
        // l starts at 0 and holds `bus` for 1.5 ms; h released 1 ns
        // later (offset φ) waits for it before it starts under the
        // ceiling, after it starts under inheritance.
        let seen = worst_reaction(&spec, 1_600 * US, 50 * US);
        assert!(seen <= w, "{protocol}: {seen} > {w}");
        assert!(seen * 10 >= w * 9, "{protocol}: {seen} far below {w}");
    }
}

/// h (1 ms every 10 ms) → m (2 ms every 100 ms, released up to 20 ms
/// late) → t (0.5 ms every 5 ms), one CPU, rate-monotonic (t above h above
/// m): R_m = J_m + w_m = 23.5 ms, W_m = 3.5 ms. h preempts m, so the first
/// m job to read h's sample starts before h's next release, within 10 ms
/// of h's read; from that read m publishes within W_m, and t (above m)
/// releases within T_t − x_t of it and responds in 0.5 ms, 18.5 ms in
/// all (10, 3.5, 4.5 and 0.5). Anchored on m's release the same chain
/// paid R_m, 38.5 ms (10, 23.5, 4.5 and 0.5; docs/analysis.md, "From a
/// stage's read").
const STAGES: &str = r#"
[system]
name = "stages"
time_unit = "ms"
[channels.mem]
bandwidth = 1
overhead = 0
[tasks.h]
exec = 1
period = 10
server = "none"
output = { channel = "mem", size = 0 }
[tasks.m]
exec = 2
period = 100
jitter = 20
server = "none"
reads = ["h"]
output = { channel = "mem", size = 0 }
[tasks.t]
exec = 0.5
exec_min = 0.5
period = 5
server = "none"
reads = ["m"]
[[chain]]
path = ["h", "m", "t"]
"#;

/// The worst reaction from the read of chain 0 that a search (6 restarts
/// of 200 steps) finds, checked against the sound bound.
fn searched_reaction(spec: &Spec) -> rtpipe_sim::search::SearchResult {
    let cfg = rtpipe_sim::search::SearchConfig {
        restarts: 6,
        steps: 200,
        anchor: Anchor::Read,
        ..rtpipe_sim::search::SearchConfig::new(0, Metric::Reaction, 1_000 * MS)
    };
    let r = rtpipe_sim::search::search(spec, &cfg).unwrap_or_else(|e| panic!("{e}"));
    assert!(!r.exceeds_sound(), "{r}");
    eprintln!("{r}");
    r
}

#[test]
fn a_stage_reached_at_its_read_pays_w_not_r() {
    let spec = Spec::parse("stages.toml", STAGES).unwrap_or_else(|e| panic!("{e}"));
    let rep = analyze(&spec);
    assert_eq!(rep.timing[1].job_response_time, Some(23_500 * US));
    assert_eq!(rep.timing[1].read_to_publish, Some(3_500 * US));
    let b = bound(&rep, Metric::Reaction, Anchor::Read);
    assert_eq!(b, Some(18_500 * US));
    let r = searched_reaction(&spec);
    let found = r.value.unwrap_or(0);
    assert!(found * 10 >= 18_500 * US * 9, "{r}");
}

/// h (1 ms every 5 ms) above s, a Main VCPU (2 ms every 10 ms, released
/// up to 7 ms late) above l (1 ms every 20 ms), one CPU, rate-monotonic.
/// A job of s released on time just after a late one finds its budget
/// still out (it comes back 7 ms after the late release) and may wait for
/// it after its read, so `R_s` = 7 + 3 = 10 ms was its `W` too. It waits
/// in slack, where it runs whenever nothing else is ready: from its read
/// to its publish the CPU runs s, h or l, and the work that can run
/// there is 2 ms of its own, one h job (none is pending at the read) and
/// one l job: `W_s` = 4 ms (docs/analysis.md, "From the read to the
/// publish of a sporadic server").
const SLACK: &str = r#"
[system]
name = "slack"
time_unit = "ms"
[channels.mem]
bandwidth = 1
overhead = 0
[tasks.h]
exec = 1
period = 5
server = "none"
[tasks.s]
exec = 2
exec_min = 2
period = 10
jitter = 7
server = "main"
[tasks.l]
exec = 1
period = 20
server = "none"
[[chain]]
path = ["s"]
"#;

#[test]
fn a_sporadic_server_waits_for_its_budget_in_slack() {
    let spec = Spec::parse("slack.toml", SLACK).unwrap_or_else(|e| panic!("{e}"));
    let rep = analyze(&spec);
    assert_eq!(rep.timing[1].job_response_time, Some(10 * MS));
    assert_eq!(rep.timing[1].read_to_publish, Some(4 * MS));
    assert_eq!(bound(&rep, Metric::Reaction, Anchor::Read), Some(4 * MS));
    // The design's relaxation at this point bounds W from below by the
    // job's own demand (it has no other task's response time at hand).
    let periods: Vec<Nanos> = spec.tasks.iter().filter_map(|t| t.fixed_period()).collect();
    let relaxed = rtpipe_analysis::relax::relax(&spec, &periods, &periods, &[], true);
    assert_eq!(relaxed.read_to_publish[1], Some(2 * MS));
    searched_reaction(&spec);
}

/// A random fixed-priority system with servers of every kind, budgets
/// below demands and release jitter on about half its tasks.
fn served_system(seed: u64) -> Spec {
    use rtpipe_model::gen::{random_system, GenConfig, Rng};
    let mut r = Rng::new(seed ^ 0x51AC);
    let gen = GenConfig {
        tasks: r.range(2, 8) as usize,
        cpus: r.range(1, 2) as u32,
        utilization: 0.3 + 0.6 * r.unit(),
        mixed_servers: true,
        ..GenConfig::default()
    };
    let mut spec = random_system(seed, &gen);
    spec.schedulability = rtpipe_model::SchedTest::Rta;
    for t in spec.tasks.iter_mut() {
        let Some(p) = t.fixed_period() else { continue };
        if r.chance(0.5) {
            t.jitter = r.range(0, (p / 3) as u64) as Nanos;
        }
    }
    let text = rtpipe_model::to_toml(&spec);
    Spec::parse("served.toml", &text).unwrap_or_else(|e| panic!("seed {seed}: {e}\n{text}"))
}

/// No job of a sporadic server that may wait for its budget after its
/// read (`W` below `R` only by the slack argument) publishes later than
/// `W` after its read, on random systems under every jitter model, random
/// phasings and demands (`RTPIPE_SLACK_SYSTEMS`, default 400).
#[test]
fn sporadic_servers_publish_within_w_of_their_read() {
    let n = rtpipe_testkit::env_u64("RTPIPE_SLACK_SYSTEMS", 400);
    let (mut checked, mut narrowed, mut reached) = (0u64, 0u64, 0u64);
    for seed in 0..n {
        let spec = served_system(seed);
        let rep = analyze(&spec);
        let w: Vec<Option<Nanos>> = rep.timing.iter().map(|t| t.read_to_publish).collect();
        // The Main VCPUs whose W the slack argument narrowed.
        let slack: Vec<bool> = spec
            .tasks
            .iter()
            .zip(&rep.timing)
            .map(|(t, tm)| {
                t.server == rtpipe_model::Server::Main
                    && (t.jitter > 0 || t.demand() > t.budget())
                    && tm.read_to_publish < tm.job_response_time
            })
            .collect();
        narrowed += slack.iter().filter(|&&s| s).count() as u64;
        let mut worst = vec![0; spec.tasks.len()];
        for (k, jitter) in [Jitter::Squeezed, Jitter::Extremes, Jitter::Uniform]
            .into_iter()
            .enumerate()
        {
            let cfg = SimConfig {
                seed: seed * 7 + k as u64,
                phasing: Phasing::Random,
                exec: [ExecModel::Worst, ExecModel::Extremes, ExecModel::Uniform][k],
                jitter,
                log_jobs: true,
                ..SimConfig::new(3_000 * MS)
            };
            let res = simulate(&spec, &cfg).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
            for j in res.jobs {
                worst[j.task] = worst[j.task].max(j.finish - j.read);
            }
        }
        for (i, seen) in worst.into_iter().enumerate() {
            let Some(w) = w[i] else { continue };
            checked += 1;
            reached += u64::from(seen == w && slack[i]);
            assert!(
                seen <= w,
                "seed {seed}: task `{}` published {seen} ns after its read, W = {w}",
                spec.tasks[i].name
            );
        }
    }
    eprintln!("{n} systems: {checked} tasks checked, {narrowed} Main VCPUs with a slack W below R, {reached} of them at W");
    assert!(checked > 0 && narrowed > 0);
}
