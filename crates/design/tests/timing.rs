//! `design` with deadline-monotonic and explicit priorities, with EDF
//! under the processor-demand test and with LET communication,
//! on problems small enough to solve by hand. The brute-force agreement on random problems is
//! `timing_agrees_with_brute_force` in tests/brute_force.rs.
//!
//! Two tasks on one CPU: `a` (exec 1 ms, period one of 2–8 ms, no
//! deadline: D = T) and `b` (exec 2 ms, period 10 ms, deadline 3 ms);
//! chain [a] with a maximum reaction time L. From the event a one-task
//! chain reacts within T_a + R_a (docs/analysis.md). Under fixed
//! priorities with exact RTA:
//!
//! - rate-monotonic: a is above b at every choice (T_a < 10), R_a = 1, and
//!   R_b = 2 + ⌈R_b/T_a⌉ = 3 ≤ 3 for T_a ≥ 3: with L = 6, T_a = 5,
//!   U = 1/5 + 2/10 = 0.4;
//! - deadline-monotonic: b (key 3) is above a when T_a > 3, then
//!   R_a = 1 + 2 = 3 and T_a + 3 ≤ 6 needs T_a ≤ 3; at T_a = 3 the keys
//!   tie and a, declared first, is above b: R_a = 1 (4 ≤ 6), R_b = 3 ≤ 3;
//!   T_a = 2 gives R_b = 4 > 3. So T_a = 3, U = 1/3 + 0.2 = 0.5333; with
//!   L = 7, T_a = 4 (4 + 3 = 7; 5 + 3 = 8 > 7), U = 0.45;
//! - explicit, b = 1 and a = 2: R_a = 3 at every T_a, L = 6 gives T_a = 3;
//!   a = 1 and b = 2: as rate-monotonic, T_a = 5.
//!
//! Under EDF with QPA (a's exec 1.5 ms): where the processor-demand test
//! passes, R is Spuri's with the deadlines (`sched::edf_response_times_at`):
//! b's deadline 3 is before a's, so R_a = 1.5 + 2 = 3.5, and b meets a's
//! job only when it is released 2 ms after a's: R_b = 2. The demand at
//! t = 3 is 2 + 1.5 > 3 when T_a ≤ 3, so QPA needs T_a ≥ 4 (at T_a = 4:
//! h(4) = 3.5, h(8) = 5, h(13) = 8.5, all within). With L = 9:
//! T_a + 3.5 ≤ 9 gives T_a = 5, U = 0.3 + 0.2 = 0.5 (when R was taken as
//! D, 2 T_a ≤ 9 gave T_a = 4, U = 0.575); with L = 7 (T_a ≤ 3) no period
//! passes: infeasible, though Σ U ≤ 1 alone would admit T_a = 3 (U = 0.7).

mod common;

use rtpipe_design::{design, Method, Mode, Options, Status};
use rtpipe_model::{Nanos, Spec};

/// The problem of the module's text: `order` the `priorities` (with the
/// explicit ones of a and b), `limit` L (ms).
fn fixed(order: &str, prio: Option<(u32, u32)>, limit: u32) -> Spec {
    let p = |x: Option<u32>| x.map_or(String::new(), |n| format!("priority = {n}\n"));
    let src = format!(
        "[system]\nname = \"hand\"\ntime_unit = \"ms\"\nschedulability = \"rta\"\n\
         priorities = \"{order}\"\n\
         [tasks.a]\nexec = 1\nperiod = {{ choices = [2, 3, 4, 5, 6, 7, 8] }}\nserver = \"none\"\n{}\
         [tasks.b]\nexec = 2\nperiod = 10\ndeadline = 3\nserver = \"none\"\n{}\
         [[chain]]\npath = [\"a\"]\nmax_reaction_time = {limit}\n",
        p(prio.map(|x| x.0)),
        p(prio.map(|x| x.1)),
    );
    Spec::parse("hand.toml", &src).unwrap_or_else(|e| panic!("{e}"))
}

/// The EDF problem of the module's text, with chain limit `limit` (ms).
fn edf(limit: u32) -> Spec {
    let src = format!(
        "[system]\nname = \"hand\"\ntime_unit = \"ms\"\nscheduler = \"edf\"\n\
         schedulability = \"qpa\"\n\
         [tasks.a]\nexec = 1.5\nperiod = {{ choices = [2, 3, 4, 5, 6, 7, 8] }}\nserver = \"none\"\n\
         [tasks.b]\nexec = 2\nperiod = 10\ndeadline = 3\nserver = \"none\"\n\
         [[chain]]\npath = [\"a\"]\nmax_reaction_time = {limit}\n"
    );
    Spec::parse("hand.toml", &src).unwrap_or_else(|e| panic!("{e}"))
}

fn opts(method: Method) -> Options {
    Options {
        mode: Mode::Sound,
        method,
        ..Options::default()
    }
}

/// The hand problems' designs: by `auto`, which must pick the box search.
fn solve(s: &Spec) -> (Vec<Nanos>, Vec<Nanos>, f64) {
    common::solve(s, Method::Auto)
}

fn close(u: f64, v: f64) {
    assert!((u - v).abs() < 1e-12, "{u} vs {v}");
}

#[test]
fn deadline_monotonic_by_hand() {
    let (t, r, u) = solve(&fixed("rate-monotonic", None, 6));
    assert_eq!((t, r), (vec![5_000, 10_000], vec![1_000, 3_000]));
    close(u, 0.4);
    let (t, r, u) = solve(&fixed("deadline-monotonic", None, 6));
    assert_eq!((t, r), (vec![3_000, 10_000], vec![1_000, 3_000]));
    close(u, 1.0 / 3.0 + 0.2);
    let (t, r, u) = solve(&fixed("deadline-monotonic", None, 7));
    assert_eq!((t, r), (vec![4_000, 10_000], vec![3_000, 2_000]));
    close(u, 0.45);
}

#[test]
fn explicit_priorities_by_hand() {
    let (t, r, u) = solve(&fixed("explicit", Some((2, 1)), 6));
    assert_eq!((t, r), (vec![3_000, 10_000], vec![3_000, 2_000]));
    close(u, 1.0 / 3.0 + 0.2);
    let (t, r, u) = solve(&fixed("explicit", Some((1, 2)), 6));
    assert_eq!((t, r), (vec![5_000, 10_000], vec![1_000, 3_000]));
    close(u, 0.4);
}

#[test]
fn qpa_by_hand() {
    let (t, r, u) = solve(&edf(9));
    assert_eq!((t, r), (vec![5_000, 10_000], vec![3_500, 2_000]));
    close(u, 0.5);
    let o = design(&edf(7), &opts(Method::Auto)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(o.status, Status::Infeasible);
}

/// LET (the module's text does not cover it): a (exec 1 ms) → b (exec 2
/// ms), periods 2–10 ms, RM with RTA. LET's sound bounds with arbitrary
/// offsets (`let_bound::any_phasing`): X = T_a + 2 T_b, F = 2 T_a + T_b,
/// reaction from the read min(X, F), from the event T_a + X. Least
/// U = 1/T_a + 2/T_b over the grid (enumerated by hand, every response
/// within its period): reaction ≤ 20 gives (5, 10) by F = 20, U = 0.4;
/// a maximum reaction time of 24 gives 2 T_a + 2 T_b ≤ 24 at (5, 7),
/// U = 1/5 + 2/7 (next: (4, 8) and (6, 6) at 0.5).
fn let_chain(limit: &str) -> Spec {
    let src = format!(
        "[system]\nname = \"hand\"\ntime_unit = \"ms\"\nschedulability = \"rta\"\n\
         communication = \"let\"\n\
         [channels.mem]\nbandwidth = 1\n\
         [tasks.a]\nexec = 1\nperiod = {{ choices = [2, 3, 4, 5, 6, 7, 8, 9, 10] }}\nserver = \"none\"\n\
         output = {{ channel = \"mem\", size = 0 }}\n\
         [tasks.b]\nexec = 2\nperiod = {{ choices = [2, 3, 4, 5, 6, 7, 8, 9, 10] }}\nserver = \"none\"\n\
         reads = [\"a\"]\n\
         [[chain]]\npath = [\"a\", \"b\"]\n{limit}\n"
    );
    Spec::parse("hand.toml", &src).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn let_by_hand() {
    let (t, _, u) = solve(&let_chain("reaction = 20"));
    assert_eq!(t, vec![5_000, 10_000]);
    close(u, 0.4);
    let (t, _, u) = solve(&let_chain("max_reaction_time = 24"));
    assert_eq!(t, vec![5_000, 7_000]);
    close(u, 0.2 + 2.0 / 7.0);
}

/// The MILP compares periods for its priority orders, has no demand test
/// and encodes implicit communication: refused, at the key.
#[test]
fn the_milp_refuses_them() {
    for (s, key) in [
        (fixed("deadline-monotonic", None, 6), "system.priorities"),
        (fixed("explicit", Some((2, 1)), 6), "system.priorities"),
        (edf(9), "tasks.b.deadline"),
        (let_chain("reaction = 20"), "system.communication"),
    ] {
        let e = design(&s, &opts(Method::Milp)).expect_err("refused");
        assert_eq!(e.key.as_deref(), Some(key));
        assert!(e.to_string().contains("box search"), "{e}");
    }
}
