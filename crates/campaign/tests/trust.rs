//! A campaign trusts only its own complete shards and never clobbers a
//! file it did not write: bad shards are run again, another campaign's
//! directory or shard is refused, a planted link is never followed, the
//! stop flag reaches into a long system, and the plan of 10⁹ shards is
//! never listed.

use rtpipe_campaign::{config, run, shard_path, survey, Part, Summary, KEPT};
use rtpipe_testkit::Scratch;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};

const CONFIG: &str = r#"
[campaign]
name = "trust"
systems = 12
seed = 5
shard_size = 4

[generate]
kind = "waters"
tasks = [5, 12]
utilization = [0.4, 0.8]
chains = 2
release = "synchronous"
"#;

/// A campaign's output directory, not yet made, in a scratch directory
/// that goes with the guard.
fn dir(name: &str) -> Scratch {
    Scratch::new(&format!("trust-{name}")).within("out")
}

fn go_with(text: &str, d: &Path) -> Result<Summary, rtpipe_campaign::Error> {
    let cfg = config::parse("t.toml", text).expect("a valid config");
    run(&cfg, text, d, Part::ALL, 2, &|| {}, &|| false)
}

fn go(d: &Path) -> Summary {
    go_with(CONFIG, d).unwrap_or_else(|e| panic!("{}: {}", e.message, e.help))
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_default()
}

#[test]
fn every_bad_shard_kind_is_run_again_not_trusted() {
    let whole = dir("whole");
    go(&whole);
    let good = bytes(&shard_path(&whole, 1));
    let d = dir("bad");
    go(&d);
    // Truncated, text, empty, and another shard's file under this name.
    std::fs::write(shard_path(&d, 0), &good[..good.len() / 2]).expect("write");
    std::fs::write(shard_path(&d, 1), "not parquet").expect("write");
    std::fs::write(shard_path(&d, 2), "").expect("write");
    std::fs::copy(shard_path(&whole, 1), shard_path(&d, 2)).expect("copy");
    let cfg = config::parse("t.toml", CONFIG).expect("a valid config");
    let found = survey(&d, &cfg, Part::ALL).expect("a survey");
    assert_eq!(found.rerun.keys().copied().collect::<Vec<_>>(), [0, 1, 2]);
    assert!(found.rerun[&1].contains("no Parquet footer"), "{found:?}");
    assert!(found.rerun[&2].contains("not shard 2"), "{found:?}");
    let s = go(&d);
    assert_eq!((s.written, s.rewritten, s.skipped), (3, 3, 0));
    for k in 0..3 {
        assert_eq!(bytes(&shard_path(&d, k)), bytes(&shard_path(&whole, k)));
    }
}

#[cfg(unix)]
#[test]
fn names_that_are_not_regular_files_are_refused_untouched() {
    let d = dir("special");
    go(&d);
    let victim = d.join("victim");
    std::fs::write(&victim, "precious").expect("write");
    let shard = shard_path(&d, 1);
    for plant in ["dir", "link", "fifo"] {
        let _ = std::fs::remove_file(&shard);
        let _ = std::fs::remove_dir(&shard);
        match plant {
            "dir" => std::fs::create_dir(&shard).expect("a directory"),
            "link" => std::os::unix::fs::symlink(&victim, &shard).expect("a link"),
            _ => {
                let ok = std::process::Command::new("mkfifo")
                    .arg(&shard)
                    .status()
                    .is_ok_and(|s| s.success());
                if !ok {
                    continue;
                }
            }
        }
        let e = go_with(CONFIG, &d).expect_err(plant);
        assert!(
            e.message.contains("shard-000001.parquet") && e.help.contains("remove"),
            "{plant}: {}",
            e.message
        );
        assert_eq!(
            std::fs::read_to_string(&victim).ok().as_deref(),
            Some("precious")
        );
    }
}

#[test]
fn another_campaigns_directory_or_shard_is_refused() {
    let d = dir("foreign");
    go(&d);
    let before = bytes(&d.join(KEPT));
    let other = CONFIG.replace("seed = 5", "seed = 6");
    let e = go_with(&other, &d).expect_err("another campaign");
    assert!(e.message.contains("another campaign"), "{}", e.message);
    assert_eq!(bytes(&d.join(KEPT)), before, "its configuration is kept");
    // A comment changes nothing: the same campaign.
    let commented = format!("# the same campaign\n{CONFIG}");
    assert_eq!(go_with(&commented, &d).map(|s| s.skipped).ok(), Some(3));
    // Without its _campaign.parquet, the shards' footers still say whose they are.
    std::fs::remove_file(d.join(KEPT)).expect("remove");
    let shard = bytes(&shard_path(&d, 0));
    let e = go_with(&other, &d).expect_err("another campaign's shards");
    assert!(
        e.message.contains("shard of another campaign"),
        "{}",
        e.message
    );
    assert_eq!(bytes(&shard_path(&d, 0)), shard, "not replaced");
    assert!(!d.join(KEPT).exists(), "nothing written");
    // A _campaign.parquet that is no campaign's.
    std::fs::write(d.join(KEPT), "hello").expect("write");
    let e = go_with(CONFIG, &d).expect_err("not a campaign file");
    assert!(
        e.message.contains("not a campaign configuration"),
        "{}",
        e.message
    );
}

#[cfg(unix)]
#[test]
fn planted_links_at_the_writers_temporaries_are_never_followed() {
    let d = dir("planted");
    std::fs::create_dir_all(&d).expect("a directory");
    let victim = d.join("victim");
    std::fs::write(&victim, "precious").expect("write");
    let mut planted = Vec::new();
    for k in 0..3 {
        planted.extend(rtpipe_model::output::temp_names(
            &shard_path(&d, k),
            "shard",
        ));
    }
    planted.extend(rtpipe_model::output::temp_names(&d.join(KEPT), "config"));
    // Only the first names: the writer takes the next free one.
    for p in planted.iter().step_by(2) {
        std::os::unix::fs::symlink(&victim, p).expect("a link");
    }
    let s = go(&d);
    assert_eq!(s.written, 3);
    assert_eq!(
        std::fs::read_to_string(&victim).ok().as_deref(),
        Some("precious")
    );
}

#[test]
fn the_stop_flag_reaches_into_a_long_simulation() {
    let text = CONFIG
        .replace("systems = 12", "systems = 1")
        .replace("tasks = [5, 12]", "tasks = 30")
        + "\n[simulate]\nduration = \"120s\"\n";
    let cfg = config::parse("t.toml", &text).expect("a valid config");
    let d = dir("long");
    // Asked before the shard, before the system, then inside its simulation.
    let asked = AtomicU32::new(0);
    let stop = || asked.fetch_add(1, Ordering::Relaxed) >= 2;
    let s = run(&cfg, &text, &d, Part::ALL, 1, &|| {}, &stop).expect("a run");
    assert!(s.stopped && s.written == 0, "{s:?}");
    assert_eq!(asked.load(Ordering::Relaxed), 3, "the simulation asked");
    let names: Vec<_> = std::fs::read_dir(&d).expect("the directory").collect();
    assert_eq!(names.len(), 1, "only {KEPT}: no shard, no temporary");
}

#[test]
fn a_billion_shards_are_counted_never_listed() {
    let text = CONFIG
        .replace("systems = 12", "systems = 1000000000")
        .replace("shard_size = 4", "shard_size = 1");
    let cfg = config::parse("t.toml", &text).expect("a valid config");
    let total = rtpipe_campaign::shard_count(&cfg);
    assert_eq!(total, 1_000_000_000);
    let part = Part { index: 3, count: 7 };
    assert_eq!(part.shard_count(total), 142_857_143);
    let last = part.shards(total).skip(142_857_140).collect::<Vec<_>>();
    assert_eq!(last, [999_999_983, 999_999_990, 999_999_997]);
    let d = dir("billion");
    let found = survey(&d, &cfg, part).expect("a survey of nothing");
    assert!(found.done.is_empty() && !found.kept);
}

/// A shard is written a row group at a time: its rows are never all held
/// at once (the groups end at the first system past `ROW_GROUP_ROWS`).
#[test]
fn a_large_shard_is_written_in_bounded_row_groups() {
    let text = CONFIG
        .replace("systems = 12", "systems = 4000")
        .replace("shard_size = 4", "shard_size = 4000")
        .replace("chains = 2", "chains = 5")
        .replace("tasks = [5, 12]", "tasks = [20, 40]");
    let d = dir("groups");
    let s = go_with(&text, &d).unwrap_or_else(|e| panic!("{}", e.message));
    assert!(s.rows > 2 * rtpipe_campaign::ROW_GROUP_ROWS as u64, "{s:?}");
    let footer = rtpipe_parquet::read_footer(&shard_path(&d, 0)).expect("a footer");
    let groups = footer.row_groups;
    assert!(groups.len() >= 3, "{groups:?}");
    // One system adds at most 2 × 5 rows past the limit.
    let most = rtpipe_campaign::ROW_GROUP_ROWS as u64 + 10;
    assert!(groups.iter().all(|&n| n <= most), "{groups:?}");
    assert_eq!(groups.iter().sum::<u64>(), s.rows);
}
