//! Issue 22's `[system] communication`: implicit by default, LET on
//! request; the tasks LET cannot run are located diagnostics with a fix.

use rtpipe_model::{Communication, Spec, SpecError};

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
    let e = match parse(system, a, b) {
        Ok(_) => panic!("accepted: {system} / {a} / {b}"),
        Err(e) => e,
    };
    assert_eq!(e.diagnostics.len(), 1, "{e}");
    let d = &e.diagnostics[0];
    (
        e.locations()[0].clone(),
        d.message.clone(),
        d.help.clone().unwrap_or_default(),
    )
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
