//! `rtpipe analyze` on a spec with threads and data-triggered tasks
//! (`examples/work-queues.toml`; the figures are worked out in
//! docs/analysis.md, "Threads and data-triggered tasks").

mod common;

use common::{assert_exit, example, json_of, rtpipe};
use serde_json::json;

#[test]
fn work_queues_text_lists_activations_and_every_bound() {
    let spec = example("work-queues.toml");
    let o = rtpipe(&["analyze", &spec]);
    // Its freshness_from_event holds in sound mode.
    assert_exit(&o, 0);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(
            "  angular_velocity   rate_ctrl            data: imu (any)                1152   1259"
        ),
        "{text}"
    );
    assert!(
        text.contains("notes: a data-triggered task's period T is its triggers' nominal rate"),
        "{text}"
    );
    assert!(text.contains("  rate loop              freshness      -         1500   3015    473  unbounded  unbounded         4015         1473"), "{text}");
}

#[test]
fn work_queues_json_paper_mode_and_all_paths() {
    let spec = example("work-queues.toml");
    let o = rtpipe(&["analyze", &spec, "--json"]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(v["tasks"][1]["job_response_time"], json!(107.0));
    let want = json!({"thread": "rate_ctrl", "triggers": ["imu"], "join": "any", "merging": true, "gap": 1152.0, "publish_gap": 1259.0});
    assert_eq!(v["tasks"][1]["activation"], want);
    assert_eq!(v["chains"][1]["sound"], json!(473.0));
    assert_eq!(v["chains"][1]["davare"], json!(null));
    // Paper mode judges by the paper's equations at the nominal periods.
    let o = rtpipe(&["analyze", &spec, "--mode", "paper"]);
    assert_exit(&o, 1);
    assert!(String::from_utf8_lossy(&o.stdout).contains("fail under the paper analysis"));
    let o = rtpipe(&["analyze", &spec, "--all-paths"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("imu               control_allocator      6429  imu>angular_velocity>attitude_control>rate_control>control_allocator       6964"), "{text}");
}
