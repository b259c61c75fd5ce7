//! The keys: `[system] priorities` and `communication`, and per task
//! `priority`, `deadline` and `jitter`. Every bad combination is a located
//! diagnostic (file:line:column) with a fix; LET (`communication = "let"`)
//! is implicit communication's alternative, refused for the tasks it cannot
//! run.

mod common;

use rtpipe_model::{Communication, Priorities, SchedTest, Spec, SpecError};

const BASE: &str = "[system]\nname = \"k\"\nSYSTEM\n[tasks.a]\nexec = 1\nperiod = 10\nA\n[tasks.b]\nexec = 1\nperiod = 20\nB\n";

fn parse(system: &str, a: &str, b: &str) -> Result<Spec, SpecError> {
    let text = BASE
        .replace("SYSTEM", system)
        .replace("A\n", &format!("{a}\n"))
        .replace("B\n", &format!("{b}\n"));
    Spec::parse("k.toml", &text)
}

/// The single diagnostic: (location, message, help).
fn error(system: &str, a: &str, b: &str) -> (String, String, String) {
    common::single_error(parse(system, a, b), &format!("{system} / {a} / {b}"))
}

#[test]
fn good_keys_parse_and_default() {
    let s = parse("", "deadline = 8\njitter = \"500us\"", "").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.priorities, Priorities::RateMonotonic);
    assert_eq!(s.tasks[0].deadline(), Some(8_000_000));
    assert_eq!(s.tasks[1].deadline(), Some(20_000_000));
    assert_eq!(s.tasks[0].jitter, 500_000);
    assert_eq!(s.schedulability, SchedTest::Rta);
    let s = parse("priorities = \"explicit\"", "priority = 2", "priority = 1")
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (s.tasks[0].priority, s.tasks[1].priority),
        (Some(2), Some(1))
    );
    // The writer keeps every key.
    let again = Spec::parse("w.toml", &rtpipe_model::to_toml(&s)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, s);
}

#[test]
fn deadline_above_the_period() {
    let (at, msg, help) = error("", "deadline = 12", "");
    assert_eq!(at, "k.toml:7:12");
    assert!(
        msg.contains("deadline 12 of task `a` is above its period (10)"),
        "{msg}"
    );
    assert!(help.contains("make it at most 10,"), "{help}");
}

#[test]
fn jitter_at_the_period() {
    let (at, msg, help) = error("", "jitter = 10", "");
    assert_eq!(at, "k.toml:7:10");
    assert!(
        msg.contains("jitter 10 of task `a` is not below its period (10)"),
        "{msg}"
    );
    assert!(help.contains("less than 10"), "{help}");
}

#[test]
fn priority_without_explicit_order() {
    let (at, msg, help) = error("", "priority = 1", "");
    assert_eq!(at, "k.toml:7:12");
    assert!(msg.contains("priorities are rate-monotonic"), "{msg}");
    assert!(help.contains("priorities = \"explicit\""), "{help}");
}

#[test]
fn explicit_order_without_priority() {
    let (at, msg, _) = error("priorities = \"explicit\"", "priority = 1", "");
    assert_eq!(at, "k.toml:8:8");
    assert!(msg.contains("task `b` has no priority"), "{msg}");
}

#[test]
fn duplicate_explicit_priorities_on_one_cpu() {
    let (at, msg, help) = error("priorities = \"explicit\"", "priority = 1", "priority = 1");
    assert_eq!(at, "k.toml:11:12");
    assert!(msg.contains("both have priority 1"), "{msg}");
    assert!(help.contains("priority = 2"), "{help}");
    // On different CPUs they may repeat.
    assert!(parse(
        "priorities = \"explicit\"",
        "priority = 1",
        "priority = 1\ncpu = 1"
    )
    .is_ok());
}

#[test]
fn utilisation_tests_refuse_what_they_do_not_cover() {
    let (at, msg, help) = error("schedulability = \"liu-layland\"", "deadline = 5", "");
    assert_eq!(at, "k.toml:3:18");
    assert!(msg.contains("assumes rate-monotonic priorities"), "{msg}");
    assert!(help.contains("\"rta\""), "{help}");
    let (_, msg, help) = error(
        "scheduler = \"edf\"\nschedulability = \"edf\"",
        "deadline = 5",
        "",
    );
    assert!(msg.contains("a deadline below its period"), "{msg}");
    assert!(help.contains("\"qpa\""), "{help}");
    let (_, msg, _) = error("scheduler = \"edf\"", "jitter = 1", "");
    assert!(
        msg.contains("release jitter under an EDF scheduler"),
        "{msg}"
    );
    let (_, msg, _) = error("scheduler = \"edf\"\npriorities = \"explicit\"", "", "");
    assert!(msg.contains("has no fixed priorities"), "{msg}");
}

#[test]
fn implicit_by_default_let_on_request_and_written_back() {
    let s = parse("", "", "").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.communication, Communication::Implicit);
    assert!(!rtpipe_model::to_toml(&s).contains("communication"));
    let s = parse(
        "communication = \"let\"",
        "deadline = 8",
        "server = \"none\"",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.communication, Communication::Let);
    let again = Spec::parse("w.toml", &rtpipe_model::to_toml(&s)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, s);
}

#[test]
fn unknown_semantics() {
    let (at, msg, _) = error("communication = \"explicit\"", "", "");
    assert_eq!(at, "k.toml:3:17");
    assert!(msg.contains("explicit"), "{msg}");
}

#[test]
fn let_refuses_io_vcpus_background_tasks_and_jitter() {
    let sys = "communication = \"let\"";
    let (at, msg, help) = error(sys, "", "server = \"io\"\nserves = \"a\"");
    assert_eq!(at, "k.toml:11:10");
    assert!(msg.contains("task `b` is an I/O VCPU"), "{msg}");
    assert!(help.contains("server = \"main\""), "{help}");
    let (at, msg, help) = error(sys, "server = \"background\"", "");
    assert_eq!(at, "k.toml:7:10");
    assert!(msg.contains("background task `a`"), "{msg}");
    assert!(help.contains("communication = \"implicit\""), "{help}");
    let (at, msg, help) = error(sys, "jitter = 1", "");
    assert_eq!(at, "k.toml:7:10");
    assert!(msg.contains("release jitter under LET"), "{msg}");
    assert!(help.contains("remove the jitter"), "{help}");
    // The same tasks are fine under implicit communication.
    assert!(parse("", "server = \"background\"", "").is_ok());
}
