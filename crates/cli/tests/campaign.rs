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

fn parquet_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("the shards")
        .map(|e| {
            e.expect("an entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .filter(|n| n.ends_with(".parquet"))
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
    assert!(
        names
            .iter()
            .all(|n| n == "_campaign.toml" || n.ends_with(".parquet")),
        "{names:?}"
    );
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
