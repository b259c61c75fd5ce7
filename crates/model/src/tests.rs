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

/// One task `a` with these extra lines; the error text.
fn err_text(task_lines: &str) -> String {
    err(&format!(
        "[system]\nname = \"x\"\n[tasks.a]\nexec = 1\n{task_lines}\n"
    ))
    .to_string()
}

#[test]
fn bad_names_are_rejected_with_a_place() {
    let e = err("[system]\nname = \"x\"\n[tasks.\"\"]\nexec = 1\nperiod = 10\n").to_string();
    assert!(e.contains("x.toml:3:8: error: task name is empty"), "{e}");
    assert!(e.contains("help: use a short printable name"), "{e}");
    let e = err("[system]\nname = \"x\"\n[tasks.\"a>b\"]\nexec = 1\nperiod = 10\n").to_string();
    assert!(
        e.contains("x.toml:3:8: error: task name \"a>b\" contains `>`"),
        "{e}"
    );
    let e = err("[system]\nname = \"x\"\n[tasks.\"a\\u001b[31m\"]\nexec = 1\nperiod = 10\n");
    let text = e.to_string();
    assert!(text.contains("x.toml:3:8: error: task name"), "{text}");
    assert!(text.contains("control character U+001B"), "{text}");
    assert!(!text.contains('\u{1b}'), "no raw escape in {text:?}");
    let e = err("[system]\nname = \"\\u0007\"\n[tasks.a]\nexec = 1\nperiod = 10\n").to_string();
    assert!(e.contains("system name"), "{e}");
    let e = err("[system]\nname = \"x\"\n[channels.\"m\\n\"]\nbandwidth = 1\n[tasks.a]\nexec = 1\nperiod = 10\n").to_string();
    assert!(e.contains("x.toml:3:11: error: channel name"), "{e}");
    // Reading an unknown task with an escape in its name never prints it raw.
    let e =
        err("[system]\nname = \"x\"\n[tasks.a]\nexec = 1\nperiod = 10\nreads = [\"\\u001b[2J\"]\n")
            .to_string();
    assert!(e.contains("unknown task"), "{e}");
    assert!(!e.contains('\u{1b}'), "{e:?}");
}

#[test]
fn non_finite_and_tiny_times_say_so() {
    for v in ["nan", "inf", "-inf", "+nan"] {
        let e = err_text(&format!("period = {v}"));
        assert!(
            e.contains("x.toml:5:10: error: period: not a finite number"),
            "{v}: {e}"
        );
    }
    let e = err_text("period = 1e-12");
    assert!(
        e.contains("period: time is below the model's 1 ns resolution"),
        "{e}"
    );
    assert!(!e.contains("found 0"), "{e}");
}

#[test]
fn exponents_in_time_strings_are_times() {
    let e = err_text("period = \"1e30ms\"");
    assert!(
        e.contains("x.toml:5:10: error: period: time is too large"),
        "{e}"
    );
    assert!(!e.contains("unknown time unit"), "{e}");
    let s = match Spec::parse(
        "x.toml",
        "[system]\nname = \"x\"\n[tasks.a]\nexec = \"5e2us\"\nperiod = \"1e1ms\"\n",
    ) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(s.tasks[0].exec, 500_000);
    assert_eq!(s.tasks[0].fixed_period(), Some(10_000_000));
}

#[test]
fn integer_overflow_has_a_place_and_help() {
    let e = err_text("period = 99999999999999999999");
    assert!(e.contains("x.toml:5:10: error:"), "{e}");
    assert!(e.contains("help: whole numbers must fit in 64 bits"), "{e}");
}

#[test]
fn harmonic_fixed_periods_are_checked_with_a_place() {
    let src = "[system]\nname = \"x\"\nharmonic = true\n[tasks.a]\nexec = 1\nperiod = 10\n[tasks.b]\nexec = 1\nperiod = 15\n[tasks.c]\nexec = 1\nperiod = { max = 40 }\n";
    let e = err(src).to_string();
    assert!(
        e.contains("x.toml:9:10: error: harmonic = true, but the fixed periods of `a` (10) and `b` (15) do not divide one another"),
        "{e}"
    );
    assert!(
        e.contains("help: make one period a multiple of the other (e.g. period = 20 here)"),
        "{e}"
    );
    // Harmonic fixed periods pass.
    assert!(Spec::parse("x.toml", &src.replace("period = 15", "period = 20")).is_ok());
}

#[test]
fn load_caps_the_size() {
    let dir = rtpipe_testkit::Scratch::new("model-cap");
    let big = dir.join("big.toml");
    let f = std::fs::File::create(&big).and_then(|f| {
        f.set_len(MAX_SPEC_BYTES + 1)?;
        Ok(f)
    });
    assert!(f.is_ok(), "{f:?}");
    let e = match Spec::load(&big) {
        Ok(_) => panic!("a 16 MiB + 1 file loaded"),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("big.toml: error: the spec is larger than 16 MiB"),
        "{e}"
    );
    drop(dir);
    #[cfg(unix)]
    {
        let t = std::time::Instant::now();
        let e = match Spec::load(std::path::Path::new("/dev/zero")) {
            Ok(_) => panic!("/dev/zero loaded"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains(
                "/dev/zero: error: cannot read the spec: it is a device, not a regular file"
            ),
            "{e}"
        );
        assert!(t.elapsed().as_secs() < 5);
    }
}

#[test]
fn offsets_known_or_synchronous() {
    // Unknown by default: the analysis holds for every phasing.
    let s = Spec::parse("x.toml", MINI).expect("valid");
    assert_eq!(s.tasks[0].offset, None);
    // One task's own offset; the other stays unknown.
    let src = MINI.replace("period = 10", "period = 10\noffset = \"2.5ms\"");
    let s = Spec::parse("x.toml", &src).expect("valid");
    assert_eq!(s.tasks[0].offset, Some(2_500_000));
    assert_eq!(s.tasks[1].offset, None);
    // release = "synchronous" fills the others with 0 and keeps given ones.
    let sync = src.replace(
        "time_unit = \"ms\"",
        "time_unit = \"ms\"\nrelease = \"synchronous\"",
    );
    let s = Spec::parse("x.toml", &sync).expect("valid");
    assert_eq!(s.tasks[0].offset, Some(2_500_000));
    assert_eq!(s.tasks[1].offset, Some(0));
    // Written specs keep them.
    let back = Spec::parse("y.toml", &crate::write::to_toml(&s)).expect("round trip");
    assert_eq!(back.tasks[0].offset, Some(2_500_000));
    assert_eq!(back.tasks[1].offset, Some(0));
    // Negative offsets and unknown release modes are located errors.
    let e = err(&MINI.replace("period = 10", "period = 10\noffset = -1"));
    assert!(e.diagnostics[0].message.contains("offset"), "{e}");
    let e = err(&MINI.replace(
        "time_unit = \"ms\"",
        "time_unit = \"ms\"\nrelease = \"sync\"",
    ));
    assert!(e.to_string().contains("synchronous"), "{e}");
}

#[test]
fn offsets_must_be_below_the_period() {
    // A task released a period or more late has no job in its first
    // periods: refused, with the offset modulo the period suggested.
    let e = err(&MINI.replace("period = 10", "period = 10\noffset = 12"));
    assert!(
        e.diagnostics[0].message.contains("not below its period"),
        "{e}"
    );
    assert!(e.to_string().contains("offset = 2"), "{e}");
    let e = err(&MINI.replace("period = 10", "period = { min = 5, max = 20 }\noffset = 5"));
    assert!(
        e.diagnostics[0]
            .message
            .contains("least period of its range"),
        "{e}"
    );
    // Just below is fine.
    let s = Spec::parse(
        "x.toml",
        &MINI.replace("period = 10", "period = 10\noffset = 9.999"),
    )
    .expect("valid");
    assert_eq!(s.tasks[0].offset, Some(9_999_000));
}

#[test]
fn from_event_limits_and_max_period_parse_and_round_trip() {
    let src = MINI.replace(
        "reaction = 10\n",
        "reaction = 10\nmax_reaction_time = 25\nfreshness_from_event = \"30ms\"\n",
    ) + "";
    let src = src.replace("period = 5\n", "period = 5\nmax_period = 8\n");
    let s = Spec::parse("x.toml", &src).expect("valid");
    assert_eq!(s.chains[0].max_reaction_time, Some(25_000_000));
    assert_eq!(s.chains[0].freshness_from_event, Some(30_000_000));
    assert_eq!(s.tasks[1].max_period, Some(8_000_000));
    assert_eq!(s.tasks[0].max_period, None);
    let back = Spec::parse("y.toml", &crate::write::to_toml(&s)).expect("written spec parses");
    assert_eq!(back.chains, s.chains);
    assert_eq!(back.tasks[1].max_period, s.tasks[1].max_period);
}

/// The former key of freshness from the event is refused where it stands,
/// with the new name and the key that limits the literature's maximum data
/// age.
#[test]
fn the_former_max_data_age_key_is_refused_with_its_new_name() {
    let e = err(&MINI.replace("reaction = 10\n", "reaction = 10\nmax_data_age = 30\n")).to_string();
    assert!(
        e.contains("x.toml:25:16: error: `max_data_age` is now `freshness_from_event`"),
        "{e}"
    );
    assert!(e.contains("not the literature's maximum data age"), "{e}");
    assert!(
        e.contains("rename the key to `freshness_from_event`; to limit the literature's maximum data age, use `max_reaction_time`"),
        "{e}"
    );
}

#[test]
fn bad_from_event_limits_and_max_period_are_located() {
    let e =
        err(&MINI.replace("reaction = 10\n", "reaction = 10\nmax_reaction_time = 0\n")).to_string();
    assert!(
        e.contains("x.toml:25:21: error: max_reaction_time must be positive"),
        "{e}"
    );
    assert!(
        e.contains("help: give max_reaction_time a value greater than zero"),
        "{e}"
    );
    let e = err(&MINI.replace(
        "reaction = 10\n",
        "reaction = 10\nfreshness_from_event = \"-2ms\"\n",
    ))
    .to_string();
    assert!(
        e.contains("x.toml:25:24: error: freshness_from_event must be positive"),
        "{e}"
    );
    let e = err(&MINI.replace("period = 5\n", "period = 5\nmax_period = \"fast\"\n")).to_string();
    assert!(e.contains("x.toml:21:14: error: "), "{e}");
    assert!(e.contains("max_period"), "{e}");
}
