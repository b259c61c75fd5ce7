use super::*;

const MINI: &str = r#"
[system]
name = "mini"
time_unit = "ms"

[channels.mem]
bandwidth = 20
overhead = 0.1

[tasks.a]
exec = 0.5
input = { channel = "mem", size = 3 }
output = { channel = "mem", size = 3 }
period = 10

[tasks.b]
exec = "500us"
reads = ["a"]
output = { channel = "mem", size = 3 }
period = 5

[[chain]]
path = ["a", "b"]
reaction = 10
"#;

fn err(src: &str) -> SpecError {
    match Spec::parse("x.toml", src) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

#[test]
fn parses_mini() {
    let s = Spec::parse("mini.toml", MINI).expect("valid");
    assert_eq!(s.tasks.len(), 2);
    assert_eq!(s.scheduler, Scheduler::Rm);
    assert_eq!(s.schedulability, SchedTest::Rta);
    // Δ = 3/20 ms + 0.1 ms = 0.25 ms each way.
    assert_eq!(s.tasks[0].delta_in, 250_000);
    assert_eq!(s.tasks[0].delta_out, 250_000);
    // C = Δin + p + Δout = 0.25 + 0.5 + 0.25 = 1 ms.
    assert_eq!(s.tasks[0].budget(), 1_000_000);
    assert_eq!(s.tasks[1].exec, 500_000);
    assert_eq!(s.chains[0].path, vec![0, 1]);
    assert_eq!(s.chains[0].reaction, Some(10_000_000));
    assert_eq!(s.chains[0].freshness, None);
}

#[test]
fn fan_in_aggregates_per_channel_with_one_overhead() {
    let src = MINI.replace("reads = [\"a\"]", "reads = [\"a\", \"c\"]")
        + "\n[tasks.c]\nexec = 1\noutput = { channel = \"mem\", size = 3 }\nperiod = 20\n";
    let s = Spec::parse("x.toml", &src).expect("valid");
    // b reads 3 + 3 units over mem: 6/20 + 0.1 = 0.4 ms.
    assert_eq!(s.tasks[1].delta_in, 400_000);
}

#[test]
fn unknown_key_is_located() {
    let e = err(&MINI.replace("exec = 0.5", "exc = 0.5"));
    assert_eq!(e.locations(), vec!["x.toml:11:1".to_string()]);
    assert!(e.diagnostics[0].message.contains("unknown field `exc`"));
}

#[test]
fn unknown_task_in_reads_suggests() {
    let e = err(&MINI.replace("reads = [\"a\"]", "reads = [\"aa\"]"));
    assert_eq!(e.locations(), vec!["x.toml:18:10".to_string()]);
    assert_eq!(e.diagnostics[0].help.as_deref(), Some("did you mean `a`?"));
}

#[test]
fn path_must_follow_edges() {
    let e = err(&MINI.replace("path = [\"a\", \"b\"]", "path = [\"b\", \"a\"]"));
    assert!(
        e.diagnostics[0].message.contains("does not follow an edge"),
        "{e}"
    );
    assert_eq!(e.locations(), vec!["x.toml:23:14".to_string()]);
}

#[test]
fn unit_typos() {
    let e = err(&MINI.replace("time_unit = \"ms\"", "time_unit = \"msec\""));
    assert!(e.diagnostics[0]
        .help
        .as_deref()
        .unwrap_or("")
        .contains("\"ms\""));
    let e = err(&MINI.replace("exec = \"500us\"", "exec = \"500 usec\""));
    assert!(
        e.diagnostics[0].message.contains("unknown time unit"),
        "{e}"
    );
}

#[test]
fn non_positive_times() {
    let e = err(&MINI.replace("period = 5", "period = 0"));
    assert!(
        e.diagnostics[0].message.contains("period must be positive"),
        "{e}"
    );
    let e = err(&MINI.replace("exec = 0.5", "exec = -1"));
    assert!(
        e.diagnostics[0].message.contains("exec must be positive"),
        "{e}"
    );
}

#[test]
fn budget_below_demand() {
    let e = err(&MINI.replace("period = 10", "period = 10\nbudget = 0.9"));
    assert!(
        e.diagnostics[0].message.contains("smaller than its demand"),
        "{e}"
    );
    assert!(e.diagnostics[0]
        .help
        .as_deref()
        .unwrap_or("")
        .contains("at least 1"));
}

#[test]
fn reads_needs_output() {
    let e = err(&MINI.replace(
        "output = { channel = \"mem\", size = 3 }\nperiod = 10",
        "period = 10",
    ));
    assert!(e.diagnostics[0].message.contains("has no output"), "{e}");
}

#[test]
fn several_errors_reported_together() {
    let src = MINI.replace("period = 5", "period = 0").replace(
        "channel = \"mem\", size = 3 }\nperiod = 10",
        "channel = \"mme\", size = 3 }\nperiod = 10",
    );
    let e = err(&src);
    assert!(e.diagnostics.len() >= 2, "{e}");
    let text = e.to_string();
    assert!(text.contains("did you mean \"mem\"?"), "{text}");
}

#[test]
fn display_shows_caret() {
    let e = err(&MINI.replace("reads = [\"a\"]", "reads = [\"zz\"]"));
    let text = e.to_string();
    assert!(
        text.starts_with("x.toml:18:10: error: unknown task `zz`"),
        "{text}"
    );
    assert!(text.contains("   18 | reads = [\"zz\"]"), "{text}");
    assert!(text.contains("^^^^"), "{text}");
}

#[test]
fn scheduler_and_test_must_fit() {
    let e = err(&MINI.replace(
        "time_unit = \"ms\"",
        "time_unit = \"ms\"\nscheduler = \"edf\"\nschedulability = \"rta\"",
    ));
    assert!(e.diagnostics[0].message.contains("does not apply"), "{e}");
}

#[test]
fn period_forms() {
    let s = Spec::parse(
        "x.toml",
        &MINI.replace("period = 5", "period = { min = \"250us\", max = \"20ms\" }"),
    )
    .expect("valid");
    assert_eq!(
        s.tasks[1].period,
        PeriodSpec::Range {
            min: Some(250_000),
            max: Some(20_000_000)
        }
    );
    let s = Spec::parse(
        "x.toml",
        &MINI.replace("period = 5", "period = { choices = [\"2ms\", 1, \"5ms\"] }"),
    )
    .expect("valid");
    assert_eq!(
        s.tasks[1].period,
        PeriodSpec::Choices(vec![1_000_000, 2_000_000, 5_000_000])
    );
}

#[test]
fn examples_parse() {
    for f in ["paper-table2.toml", "cleanflight.toml", "paper-table3.toml"] {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples")
            .join(f);
        let s = Spec::load(&p);
        assert!(
            s.is_ok(),
            "{f}: {}",
            s.err().map(|e| e.to_string()).unwrap_or_default()
        );
    }
}

#[test]
fn garbage_never_panics() {
    for src in [
        "",
        "[",
        "system = 3",
        "[system]\nname=1",
        "[tasks.a]\nexec=1",
        "\u{0}\u{ffff}",
    ] {
        assert!(Spec::parse("x.toml", src).is_err());
    }
}

#[test]
fn serves_is_checked() {
    let base = "[system]\nname = \"s\"\n[tasks.m]\nexec = 1\nperiod = 10\n[tasks.io]\nexec = 1\nperiod = 20\nserver = \"io\"\nserves = \"m\"\n";
    let s = Spec::parse("s.toml", base).expect("valid");
    assert_eq!(s.tasks[1].serves, Some(0));
    let e = err(&base.replace("server = \"io\"\n", ""));
    assert!(
        e.diagnostics[0]
            .message
            .contains("`serves` is for I/O VCPUs"),
        "{e}"
    );
    let e = err(&base.replace("[tasks.m]\nexec = 1\n", "[tasks.m]\nexec = 1\ncpu = 1\n"));
    assert!(e.diagnostics[0].message.contains("on another cpu"), "{e}");
    let e = err(&base.replace("serves = \"m\"", "serves = \"mm\""));
    assert!(
        e.diagnostics[0].message.contains("unknown task `mm`"),
        "{e}"
    );
}
