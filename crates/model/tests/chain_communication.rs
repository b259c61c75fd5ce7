//! `communication` per chain. A chain's key sets how every task
//! on it reads and publishes; the system's value is the default, and covers
//! the tasks on no chain with its own key. A task on two chains of
//! different semantics, and a LET task LET cannot run (an I/O VCPU, release
//! jitter), are located diagnostics with a fix.

mod common;

use rtpipe_model::{Communication, Spec, SpecError};

/// a → b → c, then the chains; `SYS`, `A`, `B` and `C` are replaced.
const BASE: &str = "[system]\nname = \"k\"\nSYS\n[channels.m]\nbandwidth = 1\noverhead = 0\n\
[tasks.a]\nexec = 1\nperiod = 10\noutput = { channel = \"m\", size = 0 }\nA\n\
[tasks.b]\nexec = 1\nperiod = 20\nreads = [\"a\"]\noutput = { channel = \"m\", size = 0 }\nB\n\
[tasks.c]\nexec = 1\nperiod = 5\nreads = [\"b\"]\nC\n";

fn parse(sys: &str, tasks: [&str; 3], chains: &str) -> Result<Spec, SpecError> {
    let text = BASE
        .replace("SYS", sys)
        .replace("A\n", &format!("{}\n", tasks[0]))
        .replace("B\n", &format!("{}\n", tasks[1]))
        .replace("C\n", &format!("{}\n", tasks[2]))
        + chains;
    Spec::parse("k.toml", &text)
}

/// The single diagnostic: (location, message, help).
fn error(sys: &str, tasks: [&str; 3], chains: &str) -> (String, String, String) {
    common::single_error(
        parse(sys, tasks, chains),
        &format!("{sys} / {tasks:?} / {chains}"),
    )
}

const NONE: [&str; 3] = ["", "", ""];

#[test]
fn a_chain_sets_its_tasks_and_the_system_the_rest() {
    use Communication::{Implicit, Let};
    let chains = "[[chain]]\nname = \"ab\"\npath = [\"a\", \"b\"]\ncommunication = \"let\"\n";
    let s = parse("", NONE, chains).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.communication, Implicit);
    assert_eq!(s.chains[0].communication, Some(Let));
    assert_eq!(s.communications(), vec![Let, Let, Implicit]);
    assert_eq!(s.task_communication(2), Implicit);
    assert!(s.any_let());
    // Written back with the key, read back the same.
    let text = rtpipe_model::to_toml(&s);
    assert!(text.contains("communication = \"let\""), "{text}");
    let again = Spec::parse("w.toml", &text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again, s);
    // The other way round: LET system, an implicit chain.
    let chains = "[[chain]]\npath = [\"b\", \"c\"]\ncommunication = \"implicit\"\n";
    let s = parse("communication = \"let\"", NONE, chains).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.communications(), vec![Let, Implicit, Implicit]);
    // Chains of one semantics may share tasks.
    let chains = "[[chain]]\npath = [\"a\", \"b\"]\ncommunication = \"let\"\n\
        [[chain]]\npath = [\"b\", \"c\"]\ncommunication = \"let\"\n";
    let s = parse("", NONE, chains).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.communications(), vec![Let; 3]);
    assert!(!parse("", NONE, "")
        .unwrap_or_else(|e| panic!("{e}"))
        .any_let());
}

#[test]
fn a_task_on_chains_of_two_semantics_is_refused() {
    // The second chain has no key: the system's implicit.
    let chains = "[[chain]]\nname = \"ab\"\npath = [\"a\", \"b\"]\ncommunication = \"let\"\n\
        [[chain]]\nname = \"bc\"\npath = [\"b\", \"c\"]\n";
    let (at, msg, help) = error("", NONE, chains);
    assert_eq!(at, "k.toml:29:8", "at the second chain's path");
    assert!(
        msg.contains("task `b` is on chain `ab` (let) and on chain `bc` (implicit)"),
        "{msg}"
    );
    assert!(
        help.contains("communication = \"let\" in chain `bc`"),
        "{help}"
    );
    // With the key, at the key; unnamed chains by their path.
    let chains = "[[chain]]\npath = [\"a\", \"b\"]\n\
        [[chain]]\npath = [\"b\", \"c\"]\ncommunication = \"let\"\n";
    let (at, msg, help) = error("", NONE, chains);
    assert_eq!(at, "k.toml:27:17");
    assert!(
        msg.contains("chain `a>b` (implicit) and on chain `b>c` (let)"),
        "{msg}"
    );
    assert!(help.contains("or take `b` off one of them"), "{help}");
}

#[test]
fn a_let_chain_refuses_what_system_let_refuses() {
    let chains = "[[chain]]\nname = \"ab\"\npath = [\"a\", \"b\"]\ncommunication = \"let\"\n";
    let (at, msg, help) = error("", ["jitter = 1", "", ""], chains);
    assert_eq!(at, "k.toml:11:10");
    assert!(
        msg.contains(
            "task `a` has release jitter, but it is on chain `ab`, whose communication is LET"
        ),
        "{msg}"
    );
    assert!(
        help.contains("communication = \"implicit\" in chain `ab`"),
        "{help}"
    );
    let (at, msg, help) = error("", ["", "server = \"io\"\nserves = \"c\"", ""], chains);
    assert_eq!(at, "k.toml:17:10");
    assert!(
        msg.contains("task `b` is an I/O VCPU, but it is on chain `ab`"),
        "{msg}"
    );
    assert!(help.contains("server = \"main\""), "{help}");
    // Off the LET chain the same task is fine.
    assert!(parse("", ["", "", "jitter = 1"], chains).is_ok());
    // Under a LET system, an implicit chain takes its tasks out of LET.
    let chains = "[[chain]]\npath = [\"c\"]\ncommunication = \"implicit\"\n";
    assert!(parse("communication = \"let\"", ["", "", "jitter = 1"], chains).is_ok());
    let (_, msg, _) = error("communication = \"let\"", ["", "", "jitter = 1"], "");
    assert!(
        msg.contains("release jitter under LET communication"),
        "{msg}"
    );
    // An unknown value is located at the chain's key.
    let (at, msg, _) = error(
        "",
        NONE,
        "[[chain]]\npath = [\"a\"]\ncommunication = \"lte\"\n",
    );
    assert_eq!(at, "k.toml:25:17");
    assert!(msg.contains("unknown communication \"lte\""), "{msg}");
}
