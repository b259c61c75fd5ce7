//! Campaigns are deterministic whatever the threads and shards, resume
//! where they stopped, never leave half a file, and refuse bad configs at
//! their key.

use rtpipe_campaign::{config, run, run_system, shard_path, Part};
use rtpipe_testkit::Scratch;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

const CONFIG: &str = r#"
[campaign]
name = "test"
systems = 60
seed = 11
shard_size = 16

[generate]
kind = "waters"
tasks = [5, 20]
utilization = [0.4, 0.9]
chains = 3
release = "synchronous"

[simulate]
duration = "300ms"
"#;

/// A campaign's output directory, not yet made, in a scratch directory
/// that goes with the guard.
fn dir(name: &str) -> Scratch {
    Scratch::new(&format!("campaign-{name}")).within("out")
}

fn files(d: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(d)
        .expect("the directory")
        .map(|e| {
            let p = e.expect("an entry").path();
            let name = p.file_name().expect("a name").to_string_lossy().to_string();
            (name, std::fs::read(&p).expect("the file"))
        })
        .collect();
    v.sort();
    v
}

fn go(d: &Path, part: Part, jobs: usize) -> rtpipe_campaign::Summary {
    let cfg = config::parse("test.toml", CONFIG).expect("a valid config");
    match run(&cfg, CONFIG, d, part, jobs, &|| {}, &|| false) {
        Ok(s) => s,
        Err(e) => panic!("{}: {}", e.message, e.help),
    }
}

#[test]
fn the_same_files_whatever_the_threads_and_the_shards() {
    let one = dir("one");
    let s = go(&one, Part::ALL, 1);
    assert_eq!((s.shards, s.written, s.systems), (4, 4, 60));
    // Up to three chains of two metrics each (a small set may offer fewer).
    assert!(
        s.rows.is_multiple_of(2) && (300..=360).contains(&s.rows),
        "{s:?}"
    );
    let two = dir("two");
    go(&two, Part::ALL, 2);
    assert_eq!(files(&one), files(&two), "threads change nothing");
    let split = dir("split");
    let mut owned = 0;
    for i in 0..3 {
        owned += go(&split, Part { index: i, count: 3 }, 2).written;
    }
    assert_eq!(owned, 4);
    assert_eq!(
        files(&one),
        files(&split),
        "three parts write what one run writes"
    );
}

#[test]
fn a_system_is_a_function_of_its_seed_alone() {
    let cfg = config::parse("test.toml", CONFIG).expect("a valid config");
    let a = run_system(&cfg, 37);
    assert_eq!(a, run_system(&cfg, 37));
    assert_ne!(a, run_system(&cfg, 38));
    assert!(a.iter().all(|r| r.system == 37 && r.observed.is_some()));
    // Simulated against its bounds: nothing above the bound that holds.
    assert!(a
        .iter()
        .all(|r| r.observed.is_some_and(|o| o.over_bound == 0)));
    for r in &a {
        let (observed, sound) = (r.observed.and_then(|o| o.max[0]), r.bounds[1][0]);
        if let (Some(o), Some(b)) = (observed, sound) {
            assert!(o <= b, "{r:?}");
        }
    }
}

#[test]
fn a_stopped_run_resumes_and_leaves_no_partial_file() {
    let d = dir("resume");
    let cfg = config::parse("test.toml", CONFIG).expect("a valid config");
    let stop = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    // Stop once the first shard's systems are under way.
    let tick = || {
        if done.fetch_add(1, Ordering::Relaxed) == 20 {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let stopped = || stop.load(Ordering::Relaxed);
    let s = run(&cfg, CONFIG, &d, Part::ALL, 1, &tick, &stopped).expect("a run");
    assert!(s.stopped && s.written >= 1 && s.written < 4, "{s:?}");
    let names: Vec<String> = files(&d).into_iter().map(|(n, _)| n).collect();
    assert!(names.iter().all(|n| n.ends_with(".parquet")), "{names:?}");
    assert_eq!(names.len() as u64, 1 + s.written);
    let again = go(&d, Part::ALL, 2);
    assert_eq!((again.skipped, again.written), (s.written, 4 - s.written));
    let whole = dir("whole");
    go(&whole, Part::ALL, 2);
    assert_eq!(files(&d), files(&whole), "resumed = uninterrupted");
    assert!(shard_path(&d, 3).exists());
}

#[test]
fn another_config_is_refused_in_the_same_directory() {
    let d = dir("other");
    go(&d, Part { index: 0, count: 4 }, 1);
    let other = CONFIG.replace("seed = 11", "seed = 12");
    let cfg = config::parse("o.toml", &other).expect("a valid config");
    let r = run(&cfg, &other, &d, Part::ALL, 1, &|| {}, &|| false);
    let e = r.expect_err("refused");
    assert!(e.message.contains("another campaign"), "{}", e.message);
}

#[test]
fn bad_configs_name_their_key() {
    let cases = [
        ("systems = 60", "systems = 0", "0 systems", 4),
        ("kind = \"waters\"", "kind = \"autosar\"", "autosar", 9),
        (
            "utilization = [0.4, 0.9]",
            "utilization = [0.9, 0.4]",
            "utilization",
            11,
        ),
        (
            "release = \"synchronous\"",
            "release = \"sometimes\"",
            "sometimes",
            13,
        ),
        ("duration = \"300ms\"", "duration = \"soon\"", "soon", 16),
        ("chains = 3", "chains = 3\ncolour = 1", "colour", 13),
    ];
    for (from, to, says, line) in cases {
        let text = CONFIG.replace(from, to);
        let e = config::parse("c.toml", &text).expect_err(to);
        let d = &e.diagnostics[0];
        let shown = e.to_string();
        assert!(
            shown.contains(says) || d.message.contains(says),
            "{to}: {shown}"
        );
        let span = d.span.clone().expect("a place");
        assert_eq!(e.line_col(span.start).0, line, "{to}: {shown}");
        assert!(d.help.is_some(), "{to}");
    }
    assert!(Part::parse("2/2").is_err() && Part::parse("x").is_err());
    assert_eq!(Part::parse("1/4"), Ok(Part { index: 1, count: 4 }));
}

/// An event-triggered campaign's keys: parsed, fingerprinted apart from
/// WATERS', and refused where they do not belong.
#[test]
fn event_triggered_configs_parse_and_refuse_foreign_keys() {
    let events = CONFIG
        .replace(
            "kind = \"waters\"\ntasks = [5, 20]",
            "kind = \"event-triggered\"\nthreads = 4\nlinks = [2, 6]",
        )
        .replace("release = \"synchronous\"", "cpus = 2");
    let cfg = config::parse("e.toml", &events).unwrap_or_else(|e| panic!("{e}"));
    let keys = cfg.generate.events.as_ref().expect("event keys");
    assert_eq!(
        (keys.threads, keys.links, keys.data_fraction),
        (4, (2, 6), 0.6)
    );
    assert!(!cfg.generate.exact_chains());
    let waters = config::parse("w.toml", CONFIG).expect("a valid config");
    assert!(waters.generate.exact_chains());
    assert_ne!(cfg.fingerprint(), waters.fingerprint());
    let cases = [
        (
            CONFIG.replace("chains = 3", "chains = 3\nthreads = 2"),
            "generate.threads",
            "threads",
        ),
        (
            events.replace("cpus = 2", "cpus = 2\ntasks = 9"),
            "generate.tasks",
            "follow from its chains",
        ),
        (
            events.replace("cpus = 2", "cpus = 2\nrelease = \"synchronous\""),
            "generate.release",
            "synchronous",
        ),
        (
            events.replace("links = [2, 6]", "links = [1, 6]"),
            "generate.links",
            "links [1, 6]",
        ),
        (
            events.replace("threads = 4", "threads = 4\ndata_fraction = 2.0"),
            "generate.data_fraction",
            "not a probability",
        ),
    ];
    for (text, key, says) in cases {
        let e = config::parse("c.toml", &text).expect_err(key);
        let d = &e.diagnostics[0];
        assert!(d.message.contains(says), "{key}: {e}");
        assert!(d.span.is_some() && d.help.is_some(), "{key}: {e}");
    }
}
