//! `rtpipe::api` (what the Python package calls) answers what the binary's
//! `--json` prints, hands `--samples`' rows over as the CSV's columns,
//! refuses bad flags with the parser's message, and stops when asked.

use rtpipe::api::{self, Columns, Failure, Reply};
use rtpipe_model::Spec;
use rtpipe_testkit::Scratch;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

fn load(path: &Path) -> Spec {
    match Spec::load(path) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

fn call(cmd: &str, path: &Path, flags: &[&str], samples: bool) -> Result<Reply, Failure> {
    let spec = load(path);
    let flags: Vec<String> = flags.iter().map(|s| s.to_string()).collect();
    let label = path.display().to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let most = samples.then_some(api::MAX_SAMPLE_ROWS);
    api::run(cmd, &spec, &label, &flags, most, stop)
}

/// The binary's `--json` for the same command line.
fn binary_json(cmd: &str, path: &Path, flags: &[&str]) -> (Value, i32) {
    let out = Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .arg(cmd)
        .arg(path)
        .args(flags)
        .arg("--json")
        .output()
        .expect("the binary runs");
    let v = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    (v, out.status.code().unwrap_or(-1))
}

/// Wall-clock figures differ between two runs of the same command.
fn without_clock(v: &mut Value) {
    match v {
        Value::Object(m) => {
            m.retain(|k, _| !k.contains("seconds") && !k.contains("real_time"));
            m.values_mut().for_each(without_clock);
        }
        Value::Array(a) => a.iter_mut().for_each(without_clock),
        _ => {}
    }
}

fn same_as_binary(cmd: &str, file: &str, flags: &[&str]) {
    let path = example(file);
    let reply = match call(cmd, &path, flags, false) {
        Ok(r) => r,
        Err(e) => panic!("{cmd} {file}: {e:?}"),
    };
    let (mut expected, status) = binary_json(cmd, &path, flags);
    let mut got = reply.json.expect("a JSON report");
    without_clock(&mut expected);
    without_clock(&mut got);
    assert_eq!(got, expected, "{cmd} {file} {flags:?}");
    assert_eq!(i32::from(reply.status), status, "{cmd} {file} {flags:?}");
}

#[test]
fn every_command_answers_what_the_binary_prints() {
    same_as_binary("analyze", "paper-table3.toml", &["--all-paths"]);
    same_as_binary("analyze", "paper-table2.toml", &["--mode", "paper"]);
    same_as_binary("analyze", "cleanflight.toml", &["--margins"]);
    same_as_binary("simulate", "paper-table3.toml", &["--outputs", "50"]);
    same_as_binary(
        "simulate",
        "resources.toml",
        &[
            "--duration",
            "2s",
            "--phasing",
            "search",
            "--search-steps",
            "3",
        ],
    );
    same_as_binary("simulate", "work-queues.toml", &["--outputs", "50"]);
    same_as_binary("fly", "cleanflight.toml", &["--mission", "hover"]);
    same_as_binary("design", "table2-design.toml", &[]);
    same_as_binary("design", "cleanflight-design.toml", &[]);
}

#[test]
fn design_hands_over_the_designed_spec() {
    let reply = call("design", &example("cleanflight-design.toml"), &[], false);
    let reply = reply.unwrap_or_else(|e| panic!("{e:?}"));
    let designed = reply.designed.expect("a design");
    assert!(designed.tasks.iter().all(|t| t.fixed_period().is_some()));
    let json = reply.json.expect("a report");
    assert_eq!(json["design"]["status"], "optimal");
}

/// The columns of `--samples`' CSV, as the binary writes it.
fn csv_columns(path: &Path, labels: &[String]) -> Columns {
    let text = std::fs::read_to_string(path).expect("the CSV");
    let mut c = Columns::default();
    let cell = |s: &str| (!s.is_empty()).then(|| s.parse::<i64>().expect("an integer"));
    for line in text.lines().skip(1) {
        // A label with a comma or a quote is quoted: split after it.
        let end = match line.strip_prefix('"') {
            Some(rest) => rest.rfind('"').map_or(0, |i| i + 2),
            None => line.find(',').unwrap_or(0),
        };
        let (label, rest) = line.split_at(end);
        let f: Vec<&str> = rest.trim_start_matches(',').split(',').collect();
        let label = label.trim_matches('"').replace("\"\"", "\"");
        let chain = labels.iter().position(|l| *l == label).expect("a chain");
        c.chain.push(chain as u32);
        c.sample.push(f[0].parse().expect("a sample id"));
        c.read_ns.push(f[1].parse().expect("a read"));
        c.event_ns.push(cell(f[2]));
        c.first_output_ns.push(cell(f[3]));
        c.last_output_ns.push(cell(f[4]));
        c.reaction_ns.push(cell(f[5]));
        c.freshness_ns.push(cell(f[6]));
        c.event_reaction_ns.push(cell(f[7]));
        c.event_freshness_ns.push(cell(f[8]));
    }
    c
}

#[test]
fn samples_are_the_csv_columns() {
    let dir = Scratch::new("api-samples");
    for (cmd, file, flags) in [
        ("simulate", "paper-table3.toml", vec!["--outputs", "40"]),
        ("fly", "cleanflight.toml", vec!["--duration", "3s"]),
    ] {
        let path = example(file);
        let csv = dir.join(format!("{cmd}.csv"));
        let mut with_file = flags.clone();
        with_file.extend(["--samples", csv.to_str().expect("utf-8")]);
        binary_json(cmd, &path, &with_file);
        let spec = load(&path);
        let labels: Vec<String> = (0..spec.chains.len())
            .map(|c| spec.chain_label(c))
            .collect();
        let reply = call(cmd, &path, &flags, true).unwrap_or_else(|e| panic!("{e:?}"));
        let got = reply.samples.expect("columns");
        assert!(got.read_ns.len() > 10, "{cmd}: {} rows", got.read_ns.len());
        assert_eq!(got, csv_columns(&csv, &labels), "{cmd} {file}");
    }
}

#[test]
fn bad_flags_are_input_failures_with_the_parsers_message() {
    let path = example("paper-table3.toml");
    let Err(Failure::Input(d)) = call("simulate", &path, &["--exec", "often"], false) else {
        panic!("an input failure");
    };
    assert!(d.message.contains("--exec"), "{}", d.message);
    assert!(d.message.contains("often"), "{}", d.message);
    let flight = example("cleanflight.toml");
    let Err(Failure::Input(d)) = call("fly", &flight, &["--vehicle", "zeppelin"], false) else {
        panic!("an input failure");
    };
    assert!(d.message.contains("zeppelin"), "{}", d.message);
    assert!(matches!(
        call("launch", &path, &[], false),
        Err(Failure::Input(_))
    ));
    // Free periods are design's to choose, as on the command line.
    let free = example("cleanflight-design.toml");
    for cmd in ["analyze", "simulate", "fly"] {
        let Err(Failure::Input(d)) = call(cmd, &free, &[], false) else {
            panic!("{cmd}: an input failure");
        };
        assert!(
            d.message.contains("no fixed period for tasks"),
            "{cmd}: {}",
            d.message
        );
    }
}

/// Every long loop asks the stop flag and returns (no unwinding): a
/// simulation, its adversarial searches, a design search, a flight, a
/// sweep and its refinement.
#[test]
fn a_set_stop_flag_stops_every_long_loop() {
    for (cmd, file, flags) in [
        ("simulate", "paper-table3.toml", &[][..]),
        (
            "simulate",
            "paper-table3.toml",
            &["--phasing", "search", "--outputs", "10"][..],
        ),
        ("design", "table2-design.toml", &[][..]),
        ("fly", "cleanflight.toml", &[][..]),
        (
            "fly",
            "cleanflight.toml",
            &["--sweep", "--scale", "1..2"][..],
        ),
    ] {
        let path = example(file);
        let spec = load(&path);
        let stop = Arc::new(AtomicBool::new(true));
        let flags: Vec<String> = flags.iter().map(|f| f.to_string()).collect();
        let r = api::run(cmd, &spec, "spec.toml", &flags, None, stop);
        assert!(matches!(r, Err(Failure::Stopped)), "{cmd} {flags:?}");
    }
}

#[test]
fn more_sample_rows_than_held_stop_the_run_with_a_failure_naming_the_file_option() {
    let path = example("cleanflight.toml");
    let spec = load(&path);
    let stop = Arc::new(AtomicBool::new(false));
    let flags = ["--duration".to_string(), "60s".to_string()];
    let r = api::run("fly", &spec, "spec.toml", &flags, Some(1000), stop);
    let Err(Failure::TooManySamples(d)) = r else {
        panic!("a too-many-samples failure");
    };
    assert!(
        d.message.contains("more than 1000 sample rows"),
        "{}",
        d.message
    );
    let help = d.help.unwrap_or_default();
    assert!(help.contains("samples=\"FILE.csv\""), "{help}");
    // Asked for more than it holds, it holds no more.
    let small = load(&example("paper-table3.toml"));
    let flags = ["--outputs".to_string(), "40".to_string()];
    let stop = Arc::new(AtomicBool::new(false));
    let r = api::run("simulate", &small, "s", &flags, Some(usize::MAX), stop);
    assert!(r.is_ok_and(|r| r.samples.is_some_and(|c| c.read_ns.len() > 10)));
}

#[test]
fn a_samples_file_streams_through_the_api_and_a_stopped_run_leaves_none() {
    let dir = Scratch::new("api-file");
    let path = example("cleanflight.toml");
    let csv = dir.join("rows.csv");
    let flags = [
        "--duration",
        "3s",
        "--samples",
        csv.to_str().expect("utf-8"),
    ];
    call("fly", &path, &flags, false).unwrap_or_else(|e| panic!("{e:?}"));
    let labels: Vec<String> = (0..load(&path).chains.len())
        .map(|c| load(&path).chain_label(c))
        .collect();
    let streamed = csv_columns(&csv, &labels);
    assert!(streamed.read_ns.len() > 1000);
    std::fs::remove_file(&csv).expect("the file was written");
    // Stopped in the middle (a flight long enough to reach a stop point):
    // no file, and no temporary beside it.
    let spec = load(&path);
    let mut flags: Vec<String> = flags.iter().map(|s| s.to_string()).collect();
    flags[1] = "60s".into();
    let stop = Arc::new(AtomicBool::new(true));
    let r = api::run("fly", &spec, "spec.toml", &flags, None, stop);
    assert!(matches!(r, Err(Failure::Stopped)));
    let left: Vec<_> = std::fs::read_dir(&dir).expect("dir").collect();
    assert!(left.is_empty(), "{left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_refuses_its_flags_alone_before_anything_runs() {
    let path = example("paper-table3.toml");
    for (flags, said) in [
        (
            &["--policy", "other"][..],
            "--policy other runs without real-time guarantees",
        ),
        (
            &["--best-effort"][..],
            "--best-effort only applies to --policy other",
        ),
        (&["--load", "65"][..], "--load 65 is more than 64 hogs"),
        (&["--duration", "0s"][..], "--duration 0s is not positive"),
        (
            &["--synthetic", "--mission", "hover"][..],
            "--vehicle and --mission choose",
        ),
    ] {
        match call("run", &path, flags, false) {
            Err(Failure::Input(d)) => assert!(d.message.starts_with(said), "{flags:?}: {d}"),
            Err(f) => panic!("{flags:?}: {f:?}"),
            Ok(r) => panic!("{flags:?} ran: {:?}", r.notes),
        }
    }
}

#[test]
fn import_and_generate_hand_over_their_specs_without_writing() {
    let stop = || Arc::new(AtomicBool::new(false));
    let yaml = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/e2eeval-inter.yaml");
    let outdir = Scratch::new("import-unwritten").within("out");
    let flags = [yaml.display().to_string(), outdir.display().to_string()];
    let r = api::run_plain("import e2eeval", &flags, None, stop()).expect("imported");
    let names: Vec<&str> = r.specs.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["e2eeval-inter-ecu0+1", "e2eeval-inter-ecu2"]);
    assert!(!outdir.exists(), "nothing is written");
    let text = std::fs::read_to_string(&yaml).expect("the fixture");
    let again = api::run_plain("import e2eeval", &flags, Some(&text), stop()).expect("from text");
    let tomls = |r: &Reply| -> Vec<String> {
        r.specs
            .iter()
            .map(|(_, s)| rtpipe_model::to_toml(s))
            .collect()
    };
    assert_eq!(tomls(&again), tomls(&r));
    let waters = api::waters(&["--seed=2".to_string()]).expect("generated");
    assert_eq!(waters.name, "waters-2");
    match api::run_plain("import e2eeval", &["--bogus".into()], None, stop()) {
        Err(Failure::Input(d)) => assert!(d.message.contains("--bogus"), "{d}"),
        other => panic!("{:?}", other.map(|r| r.status)),
    }
}
