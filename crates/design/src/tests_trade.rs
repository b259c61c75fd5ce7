//! Trading periods along a chain (`Examiner::trade`, with its kicks) from
//! a verified design: every answer verifies, is better than the design it starts
//! from and never below the brute-force optimum; and it lowers U on
//! small generated problems from their worst verified design and on
//! E2EEvaluation's 50-task problem from the local search's design, where
//! kicks lower it further.

use crate::api::{utilization, Options};
use crate::bnb::Examiner;
use crate::budget::Budget;
use crate::domain::domains;
use crate::heuristic::descent;
use crate::problem::Problem;
use crate::tests_split::{brute_force, small_problems};
use crate::trade::Trades;
use crate::{Method, Mode};
use rtpipe_model::Spec;
use std::path::Path;

/// The verified point of the whole domain with the largest U, by
/// enumeration (the worst start for a trade).
fn worst_verified(ex: &Examiner, n: usize) -> Option<Vec<u32>> {
    let mut k = vec![0u32; n];
    let mut worst: Option<(f64, Vec<u32>)> = None;
    loop {
        let (spec, _, ok) = ex.verify(&k);
        let u = utilization(&spec);
        if ok && worst.as_ref().is_none_or(|w| u > w.0) {
            worst = Some((u, k.clone()));
        }
        // The next assignment, odometer-wise.
        let mut i = 0;
        loop {
            if i == n {
                return worst.map(|w| w.1);
            }
            k[i] += 1;
            if k[i] < ex.axes[i].len() {
                break;
            }
            k[i] = 0;
            i += 1;
        }
    }
}

/// Trades (and kicks) from `start` until every trade from the incumbent
/// and its kicks has failed; the U of each answer, in order, and whether
/// a kick came before it.
fn trade_until_stuck(ex: &Examiner, start: &[u32], opts: &Options) -> Vec<(f64, bool)> {
    let budget = Budget::new(opts, std::time::Instant::now());
    let (spec, report, ok) = ex.verify(start);
    assert!(ok, "the start verifies");
    let u = utilization(&spec);
    let mut best = (spec, report, u);
    let (mut state, mut found) = (Trades::default(), Vec::new());
    while !state.is_spent() {
        let Some(next) = ex.trade(&best, &mut state, &budget) else {
            continue;
        };
        let (_, _, ok) = ex.verify(&ex.indices(&next.0));
        assert!(ok, "a traded design that does not verify");
        assert!(next.2 < best.2, "a trade that does not lower U");
        found.push((next.2, state.kicks() > 0));
        best = next;
    }
    found
}

#[test]
fn trades_verify_and_never_go_below_the_optimum() {
    let mut improved = 0;
    small_problems(300, |seed, ex, n, opts| {
        let mode = opts.mode;
        let Some(start) = worst_verified(ex, n) else {
            return;
        };
        let best = brute_force(ex, n).expect("a verified point");
        let found = trade_until_stuck(ex, &start, opts);
        if let Some(&(u, _)) = found.last() {
            assert!(
                u >= best * (1.0 - 1e-9),
                "seed {seed} {mode:?}: traded {u} below the optimum {best}"
            );
            improved += 1;
        }
    });
    assert!(improved >= 30, "trades improved only {improved} designs");
}

#[test]
fn trades_improve_the_local_search_design_of_a_waters_task_set() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/e2eeval-50-1.toml");
    let spec = Spec::load(&path).expect("the fixture loads");
    let opts = Options {
        mode: Mode::Sound,
        ..Options::default()
    };
    let d = domains(&spec).expect("the fixture's domains");
    let p = Problem::new(&spec, &opts, d, Method::Boxes);
    let groups = p.all_groups();
    let ex = Examiner::new(&p, &groups);
    let budget = Budget::new(&opts, std::time::Instant::now());
    let (spec, _, u) = descent(&p, &budget).expect("the local search's design");
    let found = trade_until_stuck(&ex, &ex.indices(&spec), &opts);
    let last = |kicked: bool| {
        let mut before = found.iter().filter(|f| kicked || !f.1).map(|f| f.0);
        before.next_back().unwrap_or(u)
    };
    let (traded, kicked) = (last(false), last(true));
    assert!(
        traded < u * 0.99,
        "trades lowered U only from {u} to {traded}"
    );
    // The trades stop at a local minimum; kicks from it find lower ones.
    assert!(
        kicked < traded * 0.98,
        "kicks lowered U only from {traded} to {kicked}"
    );
}
