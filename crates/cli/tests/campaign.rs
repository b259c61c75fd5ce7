//! `rtpipe campaign` end to end: the bundled example (shrunk), its report
//! and files, resumption, Ctrl-C, bad input.

mod common;

use common::{assert_exit, example, json_of, rtpipe, rtpipe_interrupted, scratch};
use std::path::Path;
use std::time::Duration;

/// The bundled campaign with fewer, shorter systems.
fn small(dir: &Path, systems: u64, duration: &str) -> String {
    let text = std::fs::read_to_string(example("campaigns/waters.toml")).expect("the example");
    let text = text
        .replace("systems = 2000", &format!("systems = {systems}"))
        .replace("shard_size = 500", "shard_size = 25")
        .replace("duration = \"2s\"", &format!("duration = \"{duration}\""));
    let path = dir.join("c.toml");
    std::fs::write(&path, text).expect("a config");
    path.display().to_string()
}

/// The shard files (the folder's `_campaign.parquet` is not one).
fn parquet_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("the shards")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .filter(|n| n.starts_with("shard-") && n.ends_with(".parquet"))
        .collect();
    v.sort();
    v
}

#[test]
fn a_campaign_writes_its_shards_and_resumes() {
    let dir = scratch("campaign");
    let config = small(&dir, 100, "200ms");
    let out = dir.join("out");
    let o = rtpipe(&["campaign", &config, out.to_str().expect("utf-8"), "--json"]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(v["systems"], 100);
    assert_eq!(
        (v["shards"].as_u64(), v["written"].as_u64()),
        (Some(4), Some(4))
    );
    assert!(v["rows"].as_u64().is_some_and(|r| r > 400), "{v}");
    assert!(v["systems_per_second_per_job"]
        .as_f64()
        .is_some_and(|r| r > 0.0));
    assert_eq!(parquet_files(&out).len(), 4);
    let magic = std::fs::read(out.join("shard-000000.parquet")).expect("a shard");
    assert!(magic.starts_with(b"PAR1") && magic.ends_with(b"PAR1"));
    // Again: everything is there already.
    let o = rtpipe(&["campaign", &config, out.to_str().expect("utf-8")]);
    assert_exit(&o, 0);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("wrote 0 shard(s)") && text.contains("(4 already there)"),
        "{text}"
    );
}

#[test]
fn ctrl_c_keeps_whole_shards_only() {
    let dir = scratch("campaign-int");
    let config = small(&dir, 4000, "2s");
    let out = dir.join("out");
    let args = ["campaign", &config, out.to_str().expect("utf-8")];
    let (o, after) = rtpipe_interrupted(
        &dir,
        &args,
        Duration::from_millis(700),
        Duration::from_secs(120),
    );
    assert_exit(&o, 130);
    assert!(after < Duration::from_secs(10), "{after:?}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("run the same command again"));
    let names: Vec<String> = std::fs::read_dir(&out)
        .expect("the directory")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert!(names.iter().all(|n| n.ends_with(".parquet")), "{names:?}");
    assert!(parquet_files(&out).len() < 160);
}

#[test]
fn bad_input_exits_2_with_the_place() {
    let dir = scratch("campaign-bad");
    let config = small(&dir, 10, "1s");
    let out = dir.join("out");
    let out = out.to_str().expect("utf-8");
    let o = rtpipe(&["campaign", &config, out, "--shard", "4/4"]);
    assert_exit(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("i must be below n"));
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[campaign]\nname = \"x\"\nsystems = 5\n\n[generate]\nkind = \"waters\"\nutilization = 2\n",
    )
    .expect("a file");
    let o = rtpipe(&["campaign", bad.to_str().expect("utf-8"), out]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml:7") && err.contains("utilization"),
        "{err}"
    );
    let o = rtpipe(&["campaign", &example("paper-table2.toml"), out]);
    assert_exit(&o, 2);
    // A file where the directory should be.
    let o = rtpipe(&["campaign", &config, &config]);
    assert_exit(&o, 2);
}

#[test]
fn another_campaigns_directory_is_refused_by_plan_and_run() {
    let dir = scratch("campaign-foreign");
    let config = small(&dir, 30, "100ms");
    let out = dir.join("out");
    let out_s = out.to_str().expect("utf-8");
    assert_exit(&rtpipe(&["campaign", &config, out_s]), 0);
    let kept = std::fs::read(out.join("_campaign.parquet")).expect("the configuration");
    let other = dir.join("other.toml");
    let text = std::fs::read_to_string(&config).expect("the config");
    std::fs::write(&other, text.replace("seed = 0", "seed = 1")).expect("a config");
    let other = other.to_str().expect("utf-8");
    for extra in [&["--plan"][..], &[][..], &["--plan", "--json"][..]] {
        let o = rtpipe(&[&["campaign", other, out_s][..], extra].concat());
        assert_exit(&o, 2);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("another campaign"), "{extra:?}: {err}");
    }
    assert_eq!(
        std::fs::read(out.join("_campaign.parquet")).ok(),
        Some(kept)
    );
    // A damaged shard is reported by --plan and written again by a run.
    std::fs::write(out.join("shard-000001.parquet"), "PAR1").expect("a file");
    let o = rtpipe(&["campaign", &config, out_s, "--plan", "--json"]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(v["written"], serde_json::json!([0]), "{v}");
    assert_eq!(v["rerun"], serde_json::json!([1]), "{v}");
    let o = rtpipe(&["campaign", &config, out_s, "--json"]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(
        (v["written"].as_u64(), v["rewritten"].as_u64()),
        (Some(1), Some(1))
    );
}

/// Ten to the nine shards are planned in bounded memory: under a 1 GiB
/// address-space limit (a list of them would take 8 GB).
#[cfg(unix)]
#[test]
fn a_billion_shards_plan_in_bounded_memory() {
    let dir = scratch("campaign-billion");
    let config = small(&dir, 1_000_000_000, "1s");
    let text = std::fs::read_to_string(&config).expect("the config");
    std::fs::write(&config, text.replace("shard_size = 25", "shard_size = 1")).expect("a config");
    let out = dir.join("out");
    let o = std::process::Command::new("sh")
        .args(["-c", "ulimit -v 1048576 && exec \"$0\" \"$@\""])
        .arg(env!("CARGO_BIN_EXE_rtpipe"))
        .args([
            "campaign",
            &config,
            out.to_str().expect("utf-8"),
            "--plan",
            "--json",
        ])
        .output()
        .expect("sh runs");
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(v["part_shards"].as_u64(), Some(1_000_000_000), "{v}");
    assert_eq!(v["written"], serde_json::json!([]), "{v}");
}

#[test]
fn systems_with_fewer_chains_than_asked_are_counted() {
    let dir = scratch("campaign-short");
    let config = dir.join("short.toml");
    std::fs::write(
        &config,
        "[campaign]\nname = \"short\"\nsystems = 40\nseed = 3\n\n[generate]\nkind = \"waters\"\n\
         tasks = [3, 8]\nutilization = 0.5\nchains = 8\n",
    )
    .expect("a config");
    let config = config.to_str().expect("utf-8");
    let out = dir.join("out");
    let o = rtpipe(&["campaign", config, out.to_str().expect("utf-8"), "--json"]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let short = v["systems_short"].as_u64().unwrap_or(0);
    let none = v["systems_without_chains"].as_u64().unwrap_or(0);
    assert!(short > 0 && none > 0 && none <= short && short <= 40, "{v}");
    let o = rtpipe(&[
        "campaign",
        config,
        dir.join("text").to_str().expect("utf-8"),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!(
            "short: {short} of 40 systems have fewer than the 8 chains asked ({none} have none"
        )),
        "{text}"
    );
}

/// Ctrl-C during one long system (an hour simulated) stops it: the
/// simulation asks the stop flag as it goes, so the command does not wait
/// for the system to end (it would take many minutes).
#[test]
fn ctrl_c_stops_a_long_system() {
    let dir = scratch("campaign-long");
    let config = small(&dir, 1, "3600s");
    let text = std::fs::read_to_string(&config).expect("the config");
    std::fs::write(&config, text.replace("tasks = [10, 40]", "tasks = 40")).expect("a config");
    let out = dir.join("out");
    let args = ["campaign", &config, out.to_str().expect("utf-8")];
    let (o, after) = rtpipe_interrupted(
        &dir,
        &args,
        Duration::from_millis(700),
        Duration::from_secs(240),
    );
    assert_exit(&o, 130);
    assert!(after < Duration::from_secs(60), "{after:?}");
    assert!(parquet_files(&out).is_empty());
}
