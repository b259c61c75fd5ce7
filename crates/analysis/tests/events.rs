//! The analysis of threads and data-triggered tasks on hand-computed
//! examples (docs/analysis.md, "Threads and data-triggered tasks", works
//! each figure out).

use rtpipe_analysis::{all_paths, analyze, Anchor, Bound, Metric, Report};
use rtpipe_model::Nanos;
use rtpipe_testkit::{example, spec};

const US: Nanos = 1_000;

/// (reaction, freshness) × (read, event) of chain `k` under `bound`.
fn bounds(r: &Report, k: usize, bound: Bound) -> [Option<Nanos>; 4] {
    let get = |m: Metric, a: Anchor| {
        r.chains
            .iter()
            .find(|c| c.chain == k && c.metric == m)
            .and_then(|c| c.bound.get(bound, a))
    };
    [
        get(Metric::Reaction, Anchor::Read),
        get(Metric::Freshness, Anchor::Read),
        get(Metric::Reaction, Anchor::Event),
        get(Metric::Freshness, Anchor::Event),
    ]
}

fn us(v: [Nanos; 4]) -> [Option<Nanos>; 4] {
    v.map(|x| Some(x * US))
}

#[test]
fn work_queues_response_times_by_hand() {
    let s = example("work-queues.toml");
    let r = analyze(&s);
    let job: Vec<Option<Nanos>> = r.timing.iter().map(|t| t.job_response_time).collect();
    // The rate thread on top: its four items once each, 107; imu on spi1
    // under them: 25 + 107 + J 20 = 152; the nav thread's two (550) under
    // imu and the rate items, control_allocator twice (its activation
    // jitter 337 puts a second release in a window of 682): 697.
    let want = [152, 107, 107, 107, 107, 697, 697].map(|x| Some(x * US));
    assert_eq!(job, want);
    let gaps: Vec<(Option<Nanos>, Option<Nanos>)> = r
        .timing
        .iter()
        .map(|t| {
            t.events
                .as_ref()
                .map_or((None, None), |e| (e.gap, e.publish_gap))
        })
        .collect();
    let want = [
        (1000, 1152),
        (1152, 1259),
        (1259, 1366),
        (1366, 1473),
        (10_000, 10_107),
        (4000, 4697),
        (20_000, 20_697),
    ]
    .map(|(a, p)| (Some(a * US), Some(p * US)));
    assert_eq!(gaps, want);
    // A data-triggered task's period is its triggers' nominal one.
    assert_eq!(r.timing[3].period, 1000 * US);
    assert!(r.schedulability.schedulable);
}

#[test]
fn work_queues_chain_bounds_by_hand() {
    let s = example("work-queues.toml");
    let r = analyze(&s);
    // rate loop: reaction 152 + 0 + 107 + 107 (+ R_ca 107) = 473, from
    // the event 1000 more; freshness, each link's producer its consumer's
    // only trigger, 152 + 107 + (107 + 107) = 473, from the event 1473.
    assert_eq!(bounds(&r, 0, Bound::Sound), us([473, 473, 1473, 1473]));
    // attitude to actuators: reaction 697 + A_rc 1259 + 107 + 107 =
    // 2170; freshness (697 − 150 + 4000) + 697 + (107 + 107) = 5458; from
    // the event 4000 more each.
    assert_eq!(bounds(&r, 1, Bound::Sound), us([2170, 5458, 6170, 9458]));
    // The paper's equations at the nominal periods; Davare's and Dürr's
    // do not apply.
    assert_eq!(bounds(&r, 0, Bound::Paper), us([3015, 3015, 4015, 4015]));
    assert_eq!(bounds(&r, 0, Bound::Davare), [None; 4]);
    assert_eq!(bounds(&r, 1, Bound::Duerr), [None; 4]);
    // freshness_from_event 1.5 ms holds (1473); the paper's 4015 does not.
    assert!(r.ok_in(rtpipe_analysis::Mode::Sound));
    assert!(!r.ok_in(rtpipe_analysis::Mode::Paper));
}

#[test]
fn work_queues_all_paths_agree_with_the_declared_chain() {
    let s = example("work-queues.toml");
    let r = analyze(&s);
    let paths = all_paths(&s, &r.timing);
    let imu = paths
        .pairs
        .iter()
        .find(|p| p.source == 0 && p.sink == 3)
        .map(|p| (p.reaction_sound.value, p.freshness_sound.value));
    // The worst path leaves the declared chain through attitude_control:
    // 152 + (107 + 4000) + (697 + 1259) + 107 + 107 = 6429; freshness
    // 152 + (107 − 12 + 1152 + 107) + (697 − 150 + 4000 + 697) + (107 +
    // 107) = 6964.
    assert_eq!(imu, Some((Some(6429 * US), Some(6964 * US))));
}

/// Two periodic triggers of one fusion task.
fn fusion(join: &str) -> String {
    format!(
        "[system]\nname = \"fusion\"\ntime_unit = \"us\"\npriorities = \"explicit\"\n\
         [channels.mem]\nbandwidth = 1000\noverhead = 0\n\
         [tasks.a]\nperiod = 1000\nexec = 10\nexec_min = 10\npriority = 1\nserver = \"none\"\n\
         output = {{ channel = \"mem\", size = 0 }}\n\
         [tasks.b]\nperiod = 2000\nexec = 20\nexec_min = 20\npriority = 2\nserver = \"none\"\n\
         output = {{ channel = \"mem\", size = 0 }}\n\
         [tasks.f]\nactivation = \"data\"\nreads = [\"a\", \"b\"]\njoin = \"{join}\"\n\
         exec = 30\nexec_min = 30\npriority = 3\n\
         [[chain]]\npath = [\"a\", \"f\"]\n[[chain]]\npath = [\"b\", \"f\"]\n"
    )
}

#[test]
fn join_all_waits_for_the_other_trigger() {
    let r = analyze(&spec("fusion.toml", &fusion("all")));
    // f: at most 1 + η⁺_b(Δ) activations (b the slower input): 2·30 under
    // a (10) and b (20) = 90.
    assert_eq!(r.timing[2].job_response_time, Some(90 * US));
    let e = r.timing[2]
        .events
        .as_ref()
        .map(|e| (e.gap, e.waits.clone()));
    // P_a = 1000 + 10, P_b = 2000 + 30: A_f = 2030; after a publishes, f
    // waits up to P_b, after b up to P_a.
    let want = (
        Some(2030 * US),
        vec![(0, Some(2030 * US)), (1, Some(1010 * US))],
    );
    assert_eq!(e, Some(want));
    // a → f: reaction min(10 + 2030 + 90, freshness 1000 + 10 + 90) =
    // 1100; from the event 1000 + 10 + 2030 + 90 = 3130, 2100.
    assert_eq!(bounds(&r, 0, Bound::Sound), us([1100, 1100, 3130, 2100]));
    // b → f: 30 + 1010 + 90 = 1130; freshness 2000 + 30 + 90 = 2120.
    assert_eq!(bounds(&r, 1, Bound::Sound), us([1130, 2120, 3130, 4120]));
    // (Two triggers: neither is f's only one, so freshness pays p's next
    // release, T_p.)
}

#[test]
fn join_any_is_released_at_every_publication() {
    let r = analyze(&spec("fusion.toml", &fusion("any")));
    // f: η⁺_a + η⁺_b activations: in a window of 90, one of each (with
    // b's output jitter 10): 2·30 + 10 + 20 = 90, the same.
    assert_eq!(r.timing[2].job_response_time, Some(90 * US));
    let e = r.timing[2]
        .events
        .as_ref()
        .map(|e| (e.gap, e.waits.clone()));
    // A_f = min(P_a, P_b) = 1010; no wait after either trigger.
    let want = (Some(1010 * US), vec![(0, Some(0)), (1, Some(0))]);
    assert_eq!(e, Some(want));
    // a → f: 10 + 0 + 90 = 100.
    assert_eq!(bounds(&r, 0, Bound::Sound)[0], Some(100 * US));
}

#[test]
fn an_unbounded_trigger_leaves_its_consumers_unbounded() {
    // b overloaded under a (10/1000 + 995/2000 ... with a at 600):
    // a (600 of 1000) above b (900 of 2000): 0.6 + 0.45 > 1.
    let text = fusion("any")
        .replace("exec = 10\nexec_min = 10", "exec = 600\nexec_min = 600")
        .replace("exec = 20\nexec_min = 20", "exec = 900\nexec_min = 900");
    let r = analyze(&spec("fusion.toml", &text));
    assert_eq!(r.timing[1].job_response_time, None);
    assert_eq!(r.timing[2].job_response_time, None);
    assert_eq!(bounds(&r, 1, Bound::Sound), [None; 4]);
    assert!(!r.ok_in(rtpipe_analysis::Mode::Sound));
}
