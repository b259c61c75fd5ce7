//! `rtpipe import e2eeval`: E2EEvaluation's YAML (tests/data, in the format
//! its `utilities/yaml_export.py` writes with PyYAML) to rtpipe specs.

mod common;

use common::{assert_exit, json_of, listing, rtpipe, scratch};
use rtpipe_model::Spec;
use rtpipe_testkit::Scratch;
use std::path::Path;

fn data(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn load(p: &Path) -> Spec {
    Spec::load(p).unwrap_or_else(|e| panic!("{e}"))
}

/// Imports `yaml` (a path) into a fresh directory `out` under a scratch dir.
fn import(tag: &str, yaml: &str) -> (std::process::Output, Scratch) {
    let out = scratch(tag).within("out");
    let o = rtpipe(&["import", "e2eeval", yaml, &out.to_string_lossy()]);
    (o, out)
}

/// Writes `text` as `name` in a scratch dir and imports it.
fn import_text(tag: &str, name: &str, text: &str) -> (std::process::Output, Scratch) {
    let dir = scratch(tag);
    let yaml = dir.join(name);
    if let Err(e) = std::fs::write(&yaml, text) {
        panic!("{e}");
    }
    let out = dir.join("out");
    let o = rtpipe(&[
        "import",
        "e2eeval",
        &yaml.to_string_lossy(),
        &out.to_string_lossy(),
    ]);
    (o, dir.within("out"))
}

/// One `!Task` line as PyYAML writes it (keys sorted, flow style).
fn task(id: i64, ecu: i64, period: &str, bcet: &str, wcet: &str, prio: &str) -> String {
    format!(
        "- !Task {{BCET: {bcet}, CommunicationPolicy: implicit, Deadline: {period}, DeadlineType: implicit, \
         ECU: {ecu}, ExecutionBehaviour: wcet, Jitter: 0, MaxIAT: {period}, MinIAT: {period}, Period: {period}, \
         Phase: 0, Priority: {prio}, ReleasePattern: periodic, TaskID: {id}, WCET: {wcet}}}\n"
    )
}

const GOLDEN: &str = r#"# Imported by `rtpipe import e2eeval` from e2eeval-golden.yaml (E2EEvaluation): task tN is TaskID N,
# exec = WCET, exec_min = BCET, times in ms, declared in the file's priority order.

[system]
name = "e2eeval-golden-ecu0"
time_unit = "ms"
scheduler = "rm"
schedulability = "rta"

[channels.mem]
bandwidth = 1
overhead = "0ms"

[tasks.t5]
exec = "1ms"
exec_min = "0.5ms"
reads = ["t20"]
output = { channel = "mem", size = 0 }
period = "5ms"
budget = "1ms"
offset = "0ms"
server = "none"
cpu = 0

[tasks.t10]
exec = "2ms"
exec_min = "1ms"
reads = ["t5"]
output = { channel = "mem", size = 0 }
period = "10ms"
budget = "2ms"
offset = "0ms"
server = "none"
cpu = 0

[tasks.t20]
exec = "5ms"
exec_min = "2.5ms"
output = { channel = "mem", size = 0 }
period = "20ms"
budget = "5ms"
offset = "0ms"
server = "none"
cpu = 0

[[chain]]
path = ["t20", "t5", "t10"]
"#;

#[test]
fn golden_case_is_written_exactly_and_analyses_to_davare_48() {
    let (o, out) = import("imp-golden", &data("e2eeval-golden.yaml"));
    assert_exit(&o, 0);
    assert_eq!(listing(&out), ["e2eeval-golden-ecu0.toml"]);
    let spec_path = out.join("e2eeval-golden-ecu0.toml");
    assert_eq!(read(&spec_path), GOLDEN);
    // Nothing was rounded, nothing to warn about.
    assert_eq!(stderr(&o), "");
    let table = stdout(&o);
    assert!(table.contains("3 tasks on 1 ECU, 1 chain;"), "{table}");
    assert!(
        table.contains("e2eeval-golden-ecu0.toml  0         3       1"),
        "{table}"
    );

    let a = rtpipe(&["analyze", &spec_path.to_string_lossy(), "--json"]);
    assert_exit(&a, 0);
    let v = json_of(&a);
    let r: Vec<f64> = (0..3)
        .map(|k| v["tasks"][k]["job_response_time"].as_f64().unwrap_or(-1.0))
        .collect();
    assert_eq!(r, [1.0, 3.0, 9.0], "RM response times of t5, t10, t20");
    let reaction = &v["chains"][0];
    assert_eq!(reaction["metric"], "reaction");
    // Davare from the head's read: R(t20) + (T + R)(t5) + (T + R)(t10) = 9 + 6 + 13;
    // from the event the head's period more: Σ (T + R) = 29 + 6 + 13 = 48 ms,
    // E2EEvaluation's davare07 for this chain.
    assert_eq!(reaction["davare"].as_f64(), Some(28.0));
    assert_eq!(reaction["davare"].as_f64().map(|d| d + 20.0), Some(48.0));
    let sound_event = reaction["from_event"]["sound"].as_f64().unwrap_or(f64::MAX);
    assert!(sound_event <= 48.0, "{sound_event}");
}

#[test]
fn ids_of_any_size_import_and_analyse_as_the_small_ones() {
    let (o, out) = import("imp-uuid", &data("e2eeval-uuid.yaml"));
    assert_exit(&o, 0);
    let ecu = "271828182845904523536028747135266249775";
    let name = format!("e2eeval-uuid-ecu{ecu}.toml");
    assert_eq!(listing(&out), std::slice::from_ref(&name));
    let spec = load(&out.join(&name));
    let names: Vec<&str> = spec.tasks.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "t52188295052327366710525154717987669201",
            "t340282366920938463463374607431768211455",
            "t9223372036854775808"
        ]
    );
    // The same system as the golden case: the same bounds.
    let a = json_of(&rtpipe(&[
        "analyze",
        &out.join(&name).to_string_lossy(),
        "--json",
    ]));
    let (golden, g_out) = import("imp-uuid-golden", &data("e2eeval-golden.yaml"));
    assert_exit(&golden, 0);
    let g = json_of(&rtpipe(&[
        "analyze",
        &g_out.join("e2eeval-golden-ecu0.toml").to_string_lossy(),
        "--json",
    ]));
    assert_eq!(a["chains"][0]["davare"], g["chains"][0]["davare"]);
    assert_eq!(a["chains"][0]["from_event"], g["chains"][0]["from_event"]);
    assert_eq!(a["chains"][0]["sound"], g["chains"][0]["sound"]);
}

#[test]
fn local_chains_give_one_spec_per_ecu_with_offsets() {
    let (o, out) = import("imp-local", &data("e2eeval-local.yaml"));
    assert_exit(&o, 0);
    assert_eq!(
        listing(&out),
        ["e2eeval-local-ecu0.toml", "e2eeval-local-ecu1.toml"]
    );
    let (s0, s1) = (
        load(&out.join("e2eeval-local-ecu0.toml")),
        load(&out.join("e2eeval-local-ecu1.toml")),
    );
    assert_eq!((s0.tasks.len(), s0.chains.len()), (8, 2));
    assert_eq!((s1.tasks.len(), s1.chains.len()), (7, 2));
    for s in [&s0, &s1] {
        assert!(s.tasks.iter().all(|t| t.cpu == 0 && t.offset == Some(0)));
        // Declared in the file's (rate-monotonic) priority order.
        let periods: Vec<i64> = s.tasks.iter().filter_map(|t| t.fixed_period()).collect();
        assert!(periods.windows(2).all(|w| w[0] <= w[1]), "{periods:?}");
    }
    assert_eq!(s0.path_label(&s0.chains[0].path), "t105>t101>t102");
    // WCET 0.076751098 ms rounds up, BCET 0.0213016947 ms down.
    let t105 = &s0.tasks[s0.task_index("t105").unwrap_or(0)];
    assert_eq!((t105.exec, t105.exec_min), (76_752, 21_301));
    // One note for all the rounding.
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("note: 30 times finer than 1 ns rounded"),
        "{err}"
    );
    assert!(stdout(&o).contains("15 tasks on 2 ECUs, 4 chains"));
    for f in listing(&out) {
        let a = rtpipe(&["analyze", &out.join(f).to_string_lossy()]);
        assert_exit(&a, 0);
    }
}

#[test]
fn ecus_joined_by_a_chain_share_one_spec_as_cpus_without_offsets() {
    let (o, out) = import("imp-inter", &data("e2eeval-inter.yaml"));
    assert_exit(&o, 0);
    assert_eq!(
        listing(&out),
        ["e2eeval-inter-ecu0+1.toml", "e2eeval-inter-ecu2.toml"]
    );
    let joined = load(&out.join("e2eeval-inter-ecu0+1.toml"));
    assert_eq!((joined.tasks.len(), joined.chains.len()), (15, 2));
    assert!(joined.tasks.iter().all(|t| t.offset.is_none()));
    let cpu = |n: &str| joined.tasks[joined.task_index(n).unwrap_or(0)].cpu;
    assert_eq!((cpu("t105"), cpu("t203")), (0, 1));
    assert_eq!(
        joined.path_label(&joined.chains[0].path),
        "t105>t101>t203>t201"
    );
    let text = read(&out.join("e2eeval-inter-ecu0+1.toml"));
    assert!(text.contains("# ECUs joined by chains, one CPU each: ECU 0 = cpu 0, ECU 1 = cpu 1."));
    let alone = load(&out.join("e2eeval-inter-ecu2.toml"));
    assert_eq!((alone.tasks.len(), alone.chains.len()), (4, 1));
    assert!(alone.tasks.iter().all(|t| t.offset == Some(0)));
    assert!(stdout(&o).contains("e2eeval-inter-ecu0+1.toml  0+1      15       2"));
}

#[test]
fn sub_nanosecond_times_round_safely_with_one_notice() {
    let yaml = format!(
        "Chains:\n- [1, 2]\nTasks:\n{}{}",
        task(1, 0, "1", "1.0e-07", "1.0e-07", "0"),
        task(2, 0, "2.0000000004", "0.0000001", "0.5000000001", "1")
    );
    let (o, out) = import_text("imp-round", "round.yaml", &yaml);
    assert_exit(&o, 0);
    let s = load(&out.join("round-ecu0.toml"));
    // WCET 0.0000001 ms is 0.1 ns: up to 1 ns; the BCET down to 0.
    assert_eq!((s.tasks[0].exec, s.tasks[0].exec_min), (1, 0));
    // Period 2.0000000004 ms to the nearest ns; WCET up, BCET down.
    assert_eq!(s.tasks[1].fixed_period(), Some(2_000_000));
    assert_eq!((s.tasks[1].exec, s.tasks[1].exec_min), (500_001, 0));
    let err = stderr(&o);
    assert_eq!(err.matches("rounded").count(), 1, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("5 times finer than 1 ns rounded (WCET up, BCET down"),
        "{err}"
    );
}

#[test]
fn priorities_set_the_declaration_order_and_non_rm_ones_are_named_once() {
    // The file gives the 20 ms task priority over the 10 ms one.
    let yaml = format!(
        "Chains:\n- [3, 4]\nTasks:\n{}{}{}",
        task(4, 0, "10", "0.1", "1.0", "2"),
        task(3, 0, "20", "0.1", "1.0", "1"),
        task(9, 0, "5", "0.1", "1.0", "0")
    );
    let (o, out) = import_text("imp-prio", "prio.yaml", &yaml);
    assert_exit(&o, 0);
    let s = load(&out.join("prio-ecu0.toml"));
    let names: Vec<&str> = s.tasks.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["t9", "t3", "t4"]);
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("not rate monotonic (t3 (20 ms) above t4 (10 ms) on ECU 0)"),
        "{err}"
    );
}

/// An import that must fail: exit 2, every `needle` in stderr, and OUTDIR
/// not even created.
fn refused(tag: &str, yaml: &str, needles: &[&str]) {
    let (o, out) = import_text(tag, "bad.yaml", yaml);
    assert_exit(&o, 2);
    let err = stderr(&o);
    for n in needles {
        assert!(err.contains(n), "missing {n:?} in:\n{err}");
    }
    assert!(err.contains("bad.yaml"), "names the file: {err}");
    assert!(!out.exists(), "nothing written: {:?}", listing(&out));
    assert_eq!(stdout(&o), "");
}

fn one_task(t: &str) -> String {
    format!("Chains:\n- [1]\nTasks:\n{t}")
}

#[test]
fn bad_input_names_its_place_and_writes_nothing() {
    let ok = task(1, 0, "10", "0.5", "1.0", "0");
    refused(
        "imp-yaml",
        "Chains:\n- [1, 2\nTasks: []\n",
        &["bad.yaml:", "not valid YAML"],
    );
    refused(
        "imp-unknown",
        &format!("Chains:\n- [1]\n- [1, 99]\nTasks:\n{ok}"),
        &["chain Chains[1] = [1, 99]", "no task has TaskID 99"],
    );
    refused(
        "imp-wcet",
        &one_task(&task(1, 0, "10", "0.5", "12.5", "0")),
        &[
            "task 1 (Tasks[0])",
            "WCET 12.5 ms is larger than its Period 10 ms",
        ],
    );
    refused(
        "imp-negative",
        &one_task(&task(1, 0, "10", "-0.5", "1.0", "0")),
        &["task 1 (Tasks[0])", "BCET is negative"],
    );
    refused(
        "imp-bcet",
        &one_task(&task(1, 0, "10", "2.0", "1.0", "0")),
        &["task 1 (Tasks[0])", "BCET 2 ms is larger than WCET 1 ms"],
    );
    refused(
        "imp-dup",
        &format!("Chains: []\nTasks:\n{ok}{ok}"),
        &["TaskID 1 appears twice (Tasks[0] and Tasks[1])"],
    );
    refused(
        "imp-let",
        &one_task(&ok.replace("CommunicationPolicy: implicit", "CommunicationPolicy: LET")),
        &[
            "task 1 (Tasks[0])",
            "CommunicationPolicy LET is not modelled",
        ],
    );
    refused(
        "imp-sporadic",
        &one_task(
            &ok.replace("ReleasePattern: periodic", "ReleasePattern: sporadic")
                .replace("MaxIAT: 10", "MaxIAT: 15"),
        ),
        &[
            "task 1 (Tasks[0])",
            "sporadic task whose inter-arrival time varies",
        ],
    );
    refused(
        "imp-late",
        &one_task(&ok.replace("Phase: 0", "Phase: 10")),
        &["task 1 (Tasks[0])", "Phase is not below Period"],
    );
    refused(
        "imp-jitter",
        &one_task(&ok.replace("Jitter: 0", "Jitter: 0.5")),
        &["task 1 (Tasks[0])", "release jitter"],
    );
    refused(
        "imp-noid",
        &one_task(&ok.replace("TaskID: 1, ", "")),
        &["Tasks[0]: no TaskID"],
    );
    refused(
        "imp-tag",
        &one_task(&ok.replace("!Task", "!Job")),
        &["Tasks[0]: tagged !Job, expected !Task"],
    );
    refused(
        "imp-top",
        "- [1, 2]\n",
        &["expected a mapping with `Tasks`"],
    );
}

#[test]
fn a_missing_file_or_an_outdir_that_is_a_file_is_refused() {
    let dir = scratch("imp-missing");
    let out = dir.join("out");
    let o = rtpipe(&[
        "import",
        "e2eeval",
        &dir.join("nope.yaml").to_string_lossy(),
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 2);
    assert!(stderr(&o).contains("nope.yaml: error: cannot read the file"));
    assert!(!out.exists());

    let file = dir.join("taken");
    if let Err(e) = std::fs::write(&file, "x") {
        panic!("{e}");
    }
    let o = rtpipe(&[
        "import",
        "e2eeval",
        &data("e2eeval-golden.yaml"),
        &file.to_string_lossy(),
    ]);
    assert_exit(&o, 2);
    assert!(stderr(&o).contains("is not a directory"), "{}", stderr(&o));
    assert_eq!(read(&file), "x");
}

#[test]
fn a_failed_import_leaves_an_existing_outdir_as_it_was() {
    let dir = scratch("imp-keep");
    let out = dir.join("out");
    let first = rtpipe(&[
        "import",
        "e2eeval",
        &data("e2eeval-golden.yaml"),
        &out.to_string_lossy(),
    ]);
    assert_exit(&first, 0);
    let before = read(&out.join("e2eeval-golden-ecu0.toml"));
    // Same stem, a broken chain: refused, the old spec untouched, no temporaries.
    let bad = dir.join("e2eeval-golden.yaml");
    let text = read(Path::new(&data("e2eeval-golden.yaml"))).replace("[20, 5, 10]", "[20, 5, 11]");
    if let Err(e) = std::fs::write(&bad, text) {
        panic!("{e}");
    }
    let o = rtpipe(&[
        "import",
        "e2eeval",
        &bad.to_string_lossy(),
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 2);
    assert_eq!(listing(&out), ["e2eeval-golden-ecu0.toml"]);
    assert_eq!(read(&out.join("e2eeval-golden-ecu0.toml")), before);
}

#[test]
fn a_file_name_with_a_newline_is_refused_with_exit_2() {
    // The name reached the specs' header comments and names, and
    // the import exited 3 ("internal error").
    let text = read(Path::new(&data("e2eeval-golden.yaml")));
    let (o, out) = import_text("import-newline", "a\nb.yaml", &text);
    assert_exit(&o, 2);
    assert!(stderr(&o).contains("control character"), "{}", stderr(&o));
    assert!(!out.exists());
}
