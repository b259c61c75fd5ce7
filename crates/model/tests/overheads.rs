//! `[system] overheads`: the keys, their defaults, per-CPU
//! tables overriding key by key, the writer, and every refusal as a
//! located diagnostic (file:line:column) with a fix. A spec whose
//! overheads make it unschedulable still analyses (the analysis crate's
//! tests; here: it validates).

mod common;

use rtpipe_model::overheads::Costs;
use rtpipe_model::{Spec, SpecError};

const BASE: &str = "[system]\nname = \"o\"\nSYSTEM\n[tasks.a]\nexec = 1\nperiod = 10\nA\n[tasks.b]\nexec = 1\nperiod = 20\ncpu = 1\nB\n";

fn parse(system: &str, a: &str, b: &str) -> Result<Spec, SpecError> {
    let text = BASE
        .replace("SYSTEM", system)
        .replace("A\n", &format!("{a}\n"))
        .replace("B\n", &format!("{b}\n"));
    Spec::parse("o.toml", &text)
}

/// The single diagnostic: (location, message, help).
fn error(system: &str, a: &str, b: &str) -> (String, String, String) {
    common::single_error(parse(system, a, b), &format!("{system} / {a} / {b}"))
}

#[test]
fn keys_default_and_cpu_tables_override_key_by_key() {
    let s = parse("", "", "").unwrap_or_else(|e| panic!("{e}"));
    assert!(s.overheads.is_zero());
    // An inline table cannot be extended by a [system.overheads.cpu.N]
    // header (TOML): the table form takes both.
    let sys = "[system.overheads]\ncontext_switch = \"5us\"\nrelease = 0.002\n\
               [system.overheads.cpu.1]\nrelease = \"3us\"\nreplenish = \"1us\"";
    let s = parse(sys, "", "").unwrap_or_else(|e| panic!("{e}"));
    let costs = |cs, release, replenish| Costs {
        context_switch: cs,
        release,
        replenish,
    };
    assert_eq!(s.overheads.on(0), costs(5_000, 2_000, 0));
    assert_eq!(s.overheads.on(1), costs(5_000, 3_000, 1_000));
    // The writer keeps every key, the CPU table's too.
    let again = Spec::parse("w.toml", &rtpipe_model::to_toml(&s)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, s);
}

#[test]
fn negative_and_absurd_values() {
    let (at, msg, help) = error("overheads = { context_switch = \"-5us\" }", "", "");
    assert_eq!(at, "o.toml:3:32");
    assert!(msg.contains("context_switch must not be negative"), "{msg}");
    assert!(help.contains("zero or more"), "{help}");
    // A bare number is in the time unit (ms): 5 ms is a context switch of
    // no kernel; 0.2 s is refused as a slip.
    let (at, msg, help) = error("overheads = { release = 200 }", "", "");
    assert_eq!(at, "o.toml:3:25");
    assert!(
        msg.contains("release overhead of 200 is above 100"),
        "{msg}"
    );
    assert!(help.contains("\"5us\""), "{help}");
    let (_, msg, _) = error("overheads = { replenish = \"1 fortnight\" }", "", "");
    assert!(msg.starts_with("replenish:"), "{msg}");
    let (_, msg, _) = error("overheads = { switch = \"1us\" }", "", "");
    assert!(msg.contains("unknown field `switch`"), "{msg}");
}

#[test]
fn a_table_for_a_cpu_without_tasks() {
    let (at, msg, help) = error("[system.overheads.cpu.2]\nrelease = \"1us\"", "", "");
    assert_eq!(at, "o.toml:3:23");
    assert_eq!(msg, "overheads for CPU 2, but no task runs on CPU 2");
    assert!(help.contains("cpu = N"), "{help}");
    let (_, msg, _) = error("[system.overheads.cpu.x]\nrelease = \"1us\"", "", "");
    assert!(msg.contains("not a CPU index"), "{msg}");
}

#[test]
fn combinations_the_accounting_does_not_bound() {
    let ov = "overheads = { context_switch = \"5us\" }";
    let (at, msg, help) = error(ov, "jitter = 1", "");
    assert_eq!(at, "o.toml:7:10");
    assert!(
        msg.contains("release jitter on task `a`, a budget server"),
        "{msg}"
    );
    assert!(help.contains("server = \"none\""), "{help}");
    // A plain task keeps its jitter.
    assert!(parse(ov, "jitter = 1\nserver = \"none\"", "").is_ok());
    let (at, msg, help) = error(&format!("{ov}\nschedulability = \"liu-layland\""), "", "");
    assert_eq!(at, "o.toml:3:32", "the first overhead given");
    assert!(msg.contains("liu-layland"), "{msg}");
    assert!(help.contains("\"rta\""), "{help}");
    let (_, msg, help) = error(&format!("{ov}\nscheduler = \"edf\""), "deadline = 8", "");
    assert!(msg.contains("deadlines below periods"), "{msg}");
    assert!(help.contains("Spuri"), "{help}");
    let pip = format!("{ov}\nresource_protocol = \"pip\"\n[resources.bus]");
    let section = "server = \"none\"\ncritical_sections = [{ resource = \"bus\", length = 0.5 }]";
    let (_, msg, help) = error(&pip, section, "");
    assert!(msg.contains("pip"), "{msg}");
    assert!(help.contains("\"pcp\""), "{help}");
    assert!(parse(&pip.replace("pip", "pcp"), section, "").is_ok());
    // Zero overheads are no overheads: nothing is refused.
    assert!(parse("overheads = { release = 0 }", "jitter = 1", "").is_ok());
}

#[test]
fn overheads_that_overload_a_cpu_still_validate() {
    let s =
        parse("overheads = { context_switch = \"5ms\" }", "", "").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.overheads.on(0).context_switch, 5_000_000);
}
