//! The keys: `[threads.NAME]` and per task `thread`, `activation`,
//! `triggers` and `join`. A good spec parses into threads and triggered
//! tasks and survives the writer; every bad combination is one located
//! diagnostic (file:line:column) with a fix.

mod common;

use rtpipe_model::{Join, PeriodSpec, Server, Spec, SpecError};

/// A rate thread with a gyro source on a driver thread and a triggered
/// controller; `SYSTEM`, `THREAD`, `GYRO` and `CTRL` are replaced by extra
/// lines of each table.
const BASE: &str = r#"[system]
name = "e"
time_unit = "us"
SYSTEM
[channels.m]
bandwidth = 1
overhead = 0

[threads.spi]
priority = 1
THREAD
[threads.rate]
priority = 2

[tasks.gyro]
exec = 10
period = 250
output = { channel = "m", size = 0 }
GYRO
[tasks.ctrl]
exec = 20
reads = ["gyro"]
output = { channel = "m", size = 0 }
CTRL
"#;

fn text(system: &str, thread: &str, gyro: &str, ctrl: &str) -> String {
    let system = if system.is_empty() {
        "priorities = \"explicit\""
    } else {
        system
    };
    BASE.replace("SYSTEM", system)
        .replace("THREAD", thread)
        .replace("GYRO", gyro)
        .replace("CTRL", ctrl)
}

fn parse(system: &str, thread: &str, gyro: &str, ctrl: &str) -> Result<Spec, SpecError> {
    Spec::parse("e.toml", &text(system, thread, gyro, ctrl))
}

/// The single diagnostic: (location, message, help).
fn error(system: &str, thread: &str, gyro: &str, ctrl: &str) -> (String, String, String) {
    common::single_error(
        parse(system, thread, gyro, ctrl),
        &text(system, thread, gyro, ctrl),
    )
}

const GOOD_GYRO: &str = "thread = \"spi\"";
const GOOD_CTRL: &str = "thread = \"rate\"\nactivation = \"data\"";

#[test]
fn a_triggered_task_on_a_thread_parses_and_round_trips() {
    let s = parse("", "cpu = 1", GOOD_GYRO, GOOD_CTRL).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.threads.len(), 2);
    assert_eq!((s.threads[0].priority, s.threads[0].cpu), (1, 1));
    let (gyro, ctrl) = (&s.tasks[0], &s.tasks[1]);
    // A task takes its thread's cpu and priority, and has no server.
    assert_eq!(
        (gyro.cpu, gyro.priority, gyro.server),
        (1, Some(1), Server::None)
    );
    assert_eq!(
        (ctrl.cpu, ctrl.priority, ctrl.thread),
        (0, Some(2), Some(1))
    );
    assert_eq!(
        ctrl.period,
        PeriodSpec::Triggered {
            triggers: vec![0],
            join: Join::Any
        }
    );
    assert!(s.event_triggered());
    assert_eq!(s.activation_period(1), Some(250_000));
    assert_eq!(s.triggered_by(), vec![vec![1], vec![]]);
    let again = Spec::parse("w.toml", &rtpipe_model::to_toml(&s)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, s);
}

#[test]
fn the_tasks_of_a_thread_share_its_rank() {
    let extra = "\n[tasks.timer]\nexec = 5\nperiod = 1000\nthread = \"rate\"\n[tasks.solo]\nexec = 5\nperiod = 500\npriority = 3\n";
    let s =
        parse("", "", GOOD_GYRO, &format!("{GOOD_CTRL}{extra}")).unwrap_or_else(|e| panic!("{e}"));
    let ranks = rtpipe_model::policy::ranks(&s);
    assert_eq!(ranks, vec![Some(1), Some(2), Some(2), Some(3)]);
}

#[test]
fn join_all_and_named_triggers() {
    let extra = "\n[tasks.acc]\nexec = 5\nperiod = 1000\noutput = { channel = \"m\", size = 0 }\nthread = \"spi\"\n";
    let ctrl = format!("{GOOD_CTRL}\njoin = \"all\"\ntriggers = [\"gyro\", \"acc\"]\n{extra}");
    let t =
        text("", "", GOOD_GYRO, &ctrl).replace("reads = [\"gyro\"]", "reads = [\"gyro\", \"acc\"]");
    let s = Spec::parse("e.toml", &t).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.tasks[1].triggers(), Some((&[0, 2][..], Join::All)));
    // Join all waits for the slowest trigger.
    assert_eq!(s.activation_period(1), Some(1_000_000));
}

#[test]
fn a_trigger_that_is_not_read() {
    let extra = "\n[tasks.acc]\nexec = 5\nperiod = 1000\noutput = { channel = \"m\", size = 0 }\nthread = \"spi\"\n";
    let ctrl = format!("{GOOD_CTRL}\ntriggers = [\"acc\"]\n{extra}");
    let (at, msg, help) = error("", "", GOOD_GYRO, &ctrl);
    assert_eq!(at, "e.toml:26:13");
    assert!(
        msg.contains("trigger `acc` is not in the task's reads"),
        "{msg}"
    );
    assert!(help.contains("add \"acc\" to `reads`"), "{help}");
}

#[test]
fn a_cycle_of_triggers() {
    let gyro = "thread = \"spi\"\nactivation = \"data\"\nreads = [\"ctrl\"]";
    let t = text("", "", gyro, GOOD_CTRL).replace("period = 250\n", "");
    let (at, msg, help) = common::single_error(Spec::parse("e.toml", &t), &t);
    assert!(at.starts_with("e.toml:"), "{at}");
    assert!(msg.contains("cycle of triggers"), "{msg}");
    assert!(help.contains("make one task on it periodic"), "{help}");
}

#[test]
fn join_on_a_periodic_task() {
    let (at, msg, help) = error(
        "",
        "",
        GOOD_GYRO,
        "thread = \"rate\"\nperiod = 500\njoin = \"all\"",
    );
    assert_eq!(at, "e.toml:26:8");
    assert!(
        msg.contains("`join` is set, but the task is periodic"),
        "{msg}"
    );
    assert!(help.contains("activation = \"data\""), "{help}");
}

#[test]
fn a_thread_on_two_cpus() {
    let (at, msg, help) = error("", "", GOOD_GYRO, &format!("{GOOD_CTRL}\ncpu = 1"));
    assert_eq!(at, "e.toml:26:7");
    assert!(
        msg.contains("task `ctrl` is on cpu 1, but its thread `rate` runs on cpu 0"),
        "{msg}"
    );
    assert!(help.contains("a thread runs on one cpu"), "{help}");
}

#[test]
fn a_data_triggered_task_with_a_period() {
    let (at, msg, help) = error("", "", GOOD_GYRO, &format!("{GOOD_CTRL}\nperiod = 250"));
    assert_eq!(at, "e.toml:26:10");
    assert!(
        msg.contains("a data-triggered task has no `period`"),
        "{msg}"
    );
    assert!(help.contains("remove `period`"), "{help}");
}

#[test]
fn threads_without_explicit_priorities() {
    let (at, msg, help) = error("release = \"arbitrary\"", "", GOOD_GYRO, GOOD_CTRL);
    assert_eq!(at, "e.toml:9:10");
    assert!(
        msg.contains("threads need explicit priorities, but priorities are rate-monotonic"),
        "{msg}"
    );
    assert!(help.contains("priorities = \"explicit\""), "{help}");
}

#[test]
fn threads_under_edf() {
    let (_, msg, help) = error("scheduler = \"edf\"", "", GOOD_GYRO, GOOD_CTRL);
    assert!(
        msg.contains("scheduled by fixed priority, but the scheduler is \"edf\""),
        "{msg}"
    );
    assert!(help.contains("scheduler = \"rm\""), "{help}");
}

#[test]
fn let_on_a_data_triggered_task() {
    let (at, msg, help) = error(
        "priorities = \"explicit\"\ncommunication = \"let\"",
        "",
        GOOD_GYRO,
        GOOD_CTRL,
    );
    assert_eq!(at, "e.toml:26:14");
    assert!(
        msg.contains("data-triggered task `ctrl` would communicate under LET"),
        "{msg}"
    );
    assert!(help.contains("make the task periodic"), "{help}");
}

#[test]
fn a_priority_on_a_task_in_a_thread() {
    let (at, msg, help) = error("", "", GOOD_GYRO, &format!("{GOOD_CTRL}\npriority = 5"));
    assert_eq!(at, "e.toml:26:12");
    assert!(
        msg.contains("gives a priority, but it runs in thread `rate`"),
        "{msg}"
    );
    assert!(help.contains("the thread's (2) applies"), "{help}");
}

#[test]
fn an_unknown_thread_is_suggested() {
    let (at, msg, help) = error("", "", GOOD_GYRO, "thread = \"rat\"\nactivation = \"data\"");
    assert_eq!(at, "e.toml:24:10");
    assert!(msg.contains("unknown thread `rat`"), "{msg}");
    assert!(help.contains("did you mean `rate`?"), "{help}");
}

#[test]
fn two_threads_with_one_priority() {
    let t = text("", "", GOOD_GYRO, GOOD_CTRL).replace(
        "[threads.rate]\npriority = 2",
        "[threads.rate]\npriority = 1",
    );
    let (at, msg, help) = common::single_error(Spec::parse("e.toml", &t), &t);
    assert_eq!(at, "e.toml:13:12");
    assert!(
        msg.contains("thread `rate` and thread `spi` on cpu 0 both have priority 1"),
        "{msg}"
    );
    assert!(help.contains("its own priority"), "{help}");
}

#[test]
fn a_thread_without_tasks() {
    let (at, msg, help) = error("", "", "priority = 3", GOOD_CTRL);
    assert_eq!(at, "e.toml:9:10");
    assert!(msg.contains("thread `spi` runs no task"), "{msg}");
    assert!(help.contains("remove the thread"), "{help}");
}

#[test]
fn a_data_triggered_task_that_reads_nothing() {
    let t = text("", "", GOOD_GYRO, GOOD_CTRL).replace("reads = [\"gyro\"]\n", "");
    let (at, msg, help) = common::single_error(Spec::parse("e.toml", &t), &t);
    assert_eq!(at, "e.toml:24:14");
    assert!(msg.contains("reads nothing"), "{msg}");
    assert!(help.contains("add the producer to `reads`"), "{help}");
}

#[test]
fn the_bundled_example_parses() {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/work-queues.toml");
    let s = Spec::load(&p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.threads.len(), 3);
    assert_eq!(s.tasks.iter().filter(|t| t.is_triggered()).count(), 3);
    let again = Spec::parse("w.toml", &rtpipe_model::to_toml(&s)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, s);
}

/// The generator's systems are valid event-triggered specs: each one
/// survives the writer and the parser unchanged, for 500 seeds, and a seed
/// always means the same system.
#[test]
fn generated_event_triggered_systems_round_trip() {
    use rtpipe_model::gen::{event_triggered_system, EventGenConfig};
    let cfg = EventGenConfig::default();
    let (mut triggered, mut all, mut threaded) = (0, 0, 0);
    for seed in 0..500 {
        let s = event_triggered_system(seed, &cfg);
        let text = rtpipe_model::to_toml(&s);
        let again = Spec::parse("g.toml", &text).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(again, s, "seed {seed}:\n{text}");
        assert_eq!(s, event_triggered_system(seed, &cfg), "seed {seed}");
        assert!(s.event_triggered());
        let chain_lengths = s.chains.iter().map(|c| c.path.len());
        assert!(chain_lengths.clone().all(|n| (2..=8).contains(&n)));
        triggered += s.tasks.iter().filter(|t| t.is_triggered()).count();
        all += s
            .tasks
            .iter()
            .filter(|t| t.triggers().is_some_and(|(_, j)| j == Join::All))
            .count();
        threaded += s.tasks.iter().filter(|t| t.thread.is_some()).count();
    }
    // Every kind of activation and placement shows up.
    assert!(triggered > 500 && all > 50 && threaded > 500);
}

#[test]
fn the_gyro_triggered_cleanflight_parses() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/cleanflight-triggered.toml");
    let s = Spec::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let triggered: Vec<&str> = s
        .tasks
        .iter()
        .filter(|t| t.is_triggered())
        .map(|t| t.name.as_str())
        .collect();
    assert_eq!(triggered, ["ahrs", "pid", "pwm"]);
    // Each runs at the gyro's rate.
    for name in triggered {
        let i = s.task_index(name).expect("a task");
        assert_eq!(s.activation_period(i), Some(1_000_000), "{name}");
    }
}

#[test]
fn pibs_inheritance_beside_threads() {
    let extra = "\n[tasks.io]\nexec = 5\nperiod = 1000\nserver = \"io\"\npriority = 4\nserves = \"main\"\n[tasks.main]\nexec = 5\nperiod = 1000\npriority = 5\n";
    let (_, msg, help) = error("", "", GOOD_GYRO, &format!("{GOOD_CTRL}{extra}"));
    assert!(
        msg.contains("task `io` serves another (PIBS inheritance)"),
        "{msg}"
    );
    assert!(help.contains("remove `serves`"), "{help}");
}
