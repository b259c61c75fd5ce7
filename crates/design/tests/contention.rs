//! `design` with critical sections and scheduling overheads,
//! on a problem small enough to solve by hand. The brute-force agreement
//! on random problems is `contention_agrees_with_brute_force` in
//! tests/brute_force.rs.
//!
//! Two tasks on one CPU under RM with exact RTA: `a` (exec 1 ms, period one
//! of 2, 3, 4, 5, 6 ms) and `b` (exec 2 ms, period 10 ms), both locking `r`
//! (a for 0.5 ms, b for 1 ms); chain [a] with a maximum reaction time of
//! 6 ms. From the event a one-task chain reacts within T_a + R_a
//! (docs/analysis.md), and a is above b at every choice, so:
//!
//! - without sections R_a = 1: T_a + 1 ≤ 6 gives T_a = 5, U = 1/5 + 2/10
//!   = 0.4;
//! - with them (PCP, SRP or PIP alike: one section of b can block a)
//!   B_a = 1, R_a = 2: T_a = 4, U = 1/4 + 2/10 = 0.45;
//! - with overheads too (context switch 0.1 ms, release 0.05 ms):
//!   R_a = 1 + 0.1 (own switch) + 1 (B) + 0.05 + 0.05 (the releases of a
//!   and b at 0) = 2.2, so T_a = 4 reacts within 6.2 > 6 and T_a = 3 within
//!   5.2: U = 1/3 + 2/10. Then R_b = 2 + 0.1 + ⌈w/3⌉ (1 + 0.2) +
//!   ⌈w/3⌉ 0.05 + ⌈w/10⌉ 0.05: w = 3.4 → 4.65 → 4.65 ms.

mod common;

use common::solve;
use rtpipe_design::{design, Method, Mode, Options};
use rtpipe_model::Spec;

fn spec(sections: bool, protocol: &str, overheads: bool) -> Spec {
    let lock = |len: &str| {
        if sections {
            format!("critical_sections = [{{ resource = \"r\", length = {len} }}]\n")
        } else {
            String::new()
        }
    };
    let costs = if overheads {
        "overheads = { context_switch = 0.1, release = 0.05 }\n"
    } else {
        ""
    };
    let src = format!(
        "[system]\nname = \"hand\"\ntime_unit = \"ms\"\nschedulability = \"rta\"\n\
         resource_protocol = \"{protocol}\"\n{costs}\
         [resources.r]\n\
         [tasks.a]\nexec = 1\nperiod = {{ choices = [2, 3, 4, 5, 6] }}\nserver = \"none\"\n{}\
         [tasks.b]\nexec = 2\nperiod = 10\nserver = \"none\"\n{}\
         [[chain]]\npath = [\"a\"]\nmax_reaction_time = 6\n",
        lock("0.5"),
        lock("1")
    );
    Spec::parse("hand.toml", &src).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn blocking_and_overheads_by_hand() {
    let close = |u: f64, v: f64| assert!((u - v).abs() < 1e-12, "{u} vs {v}");
    let (t, r, u) = solve(&spec(false, "pcp", false), Method::Auto);
    assert_eq!((t, r), (vec![5_000, 10_000], vec![1_000, 3_000]));
    close(u, 0.4);
    for p in ["pcp", "srp", "pip"] {
        let (t, r, u) = solve(&spec(true, p, false), Method::Auto);
        assert_eq!(t, vec![4_000, 10_000], "{p}");
        assert_eq!(r[0], 2_000, "{p}");
        close(u, 0.45);
    }
    // PIP is refused with overheads (validation).
    for p in ["pcp", "srp"] {
        let (t, r, u) = solve(&spec(true, p, true), Method::Boxes);
        assert_eq!((t, r), (vec![3_000, 10_000], vec![2_200, 4_650]), "{p}");
        close(u, 1.0 / 3.0 + 0.2);
    }
}

/// The MILP has no blocking or overhead term: refused, at the key.
#[test]
fn the_milp_refuses_sections_and_overheads() {
    let opts = Options {
        mode: Mode::Sound,
        method: Method::Milp,
        ..Options::default()
    };
    for (s, key) in [
        (spec(true, "pcp", false), "tasks.a.critical_sections"),
        (spec(false, "pcp", true), "system.overheads"),
    ] {
        let e = design(&s, &opts).expect_err("refused");
        assert_eq!(e.key.as_deref(), Some(key));
        assert!(e.to_string().contains("box search"), "{e}");
    }
}
