//! # rtpipe-design
//!
//! Section IV of Cheng, West, Einstein (EMSOFT 2018), solved exactly: choose
//! the free periods so that every chain limit holds under the chosen analysis,
//! every CPU passes the system's schedulability test, T ≥ C, and the total
//! utilisation Σ C/T is minimal. docs/design.md explains the formulation.
//!
//! Every answer is re-checked by `rtpipe_analysis::analyze` before it is
//! returned; the [`Outcome`] carries that report.
//!
//! Two searches share the problem (`problem`: spec, domains, options;
//! `domain` the period grids), what the search learns (`learnt`: cuts,
//! response-time levels, tangent points) and the budget (`budget`: work,
//! time, iterations). The box search: `boxes` (the whole design) runs
//! `frontier` (the search's loop, open boxes best bound first, halves
//! examined in parallel) over `bnb` (the examination of one box) and
//! `trade` (better incumbents by trading periods along a chain), which
//! use `axis` (boxes of period values) and `joint` (bounds from the chain
//! limits). The MILP: `runner` (the loop of master
//! solves and cuts) runs `solve` (one master solve) on `master` (the master
//! problem assembled from `model`, its variables and switches, and the
//! encodings `paper` / `sound` / `rta`, written with `linear` expressions
//! for the solver layer `lp`), with `heuristic` (quick verified designs).
//! `explain` (conflicts of an infeasible problem) probes with either.
//! `api` holds the public types. No module uses one of a layer above its
//! own (listed below), so the modules import each other without cycles;
//! docs/architecture.md places the crate in the workspace.
#![deny(missing_docs)]

// Layers, bottom up; a module uses only modules of lower layers:
// lp < api, linear < domain < problem < budget, events, model < paper, rta,
// sound < learnt < master < solve < heuristic, axis, joint < bnb < trade
// < frontier < explain < boxes, runner < robust < lib.rs (`design`).
mod api;
mod axis;
mod bnb;
mod boxes;
mod budget;
mod domain;
mod events;
mod explain;
mod frontier;
mod gate;
mod harmonic;
mod heuristic;
mod joint;
mod kick;
mod learnt;
mod linear;
/// The solver layer: a small MILP handed to good_lp (microlp, HiGHS).
pub mod lp;
mod master;
mod model;
mod paper;
mod problem;
mod robust;
mod rta;
mod runner;
mod solve;
mod sound;
mod trade;

pub use api::{
    utilization, Acceptance, Checked, Conflict, DesignError, ErrorKind, Incumbent, Judgement,
    MarginSearch, MarginStep, Method, Objective, Options, Outcome, Status, Trials, EXACT_PATIENCE,
    EXPLAIN_EFFORT,
};
use budget::Budget;
use domain::domains;
pub use frontier::MAX_OPEN_BYTES;
pub use gate::{CUT_MARGIN, MAX_CHECKS};
use learnt::Learnt;
use lp::LpError;
use problem::Problem;
use rtpipe_model::{Nanos, Spec};
use std::time::Instant;

/// Which analysis the chain limits are judged by (one enum for the whole
/// workspace).
pub use rtpipe_analysis::Mode;

/// Designs the periods of `spec` for `opts.objective`.
pub fn design(spec: &Spec, opts: &Options) -> Result<Outcome, DesignError> {
    match opts.objective {
        Objective::Utilization => least_utilization(spec, opts),
        Objective::Margin { max_utilization } => {
            if !(max_utilization.is_finite() && max_utilization > 0.0) {
                return Err(DesignError::input(format!(
                    "a utilisation cap of {max_utilization} admits no design"
                ))
                .help("give a positive cap, e.g. --max-utilization 0.8"));
            }
            robust::most_robust(spec, opts, max_utilization, least_utilization)
        }
    }
}

/// The periods of `spec` of least utilisation.
fn least_utilization(spec: &Spec, opts: &Options) -> Result<Outcome, DesignError> {
    let start = Instant::now();
    if !opts.solver.available() {
        return Err(DesignError::input(
            LpError::Unavailable(opts.solver.name()).to_string(),
        ));
    }
    if let Some(t) = spec.tasks.iter().find(|t| t.serves.is_some()) {
        return Err(DesignError::input(format!(
            "task `{}` uses `serves` (PIBS priority inheritance), which `design` does not model yet; remove it to design, then add it back and check with `analyze`",
            t.name
        )));
    }
    // Known offsets do not enter the design: its bounds hold for any
    // phasing, and a job-level analysis of every candidate would cost a
    // hyperperiod each. The answer keeps them.
    let offsets: Vec<Option<Nanos>> = spec.tasks.iter().map(|t| t.offset).collect();
    let plain;
    let spec = if offsets.iter().any(Option::is_some) {
        let mut s = spec.clone();
        s.tasks.iter_mut().for_each(|t| t.offset = None);
        plain = s;
        &plain
    } else {
        spec
    };
    let mut domains = domains(spec)?;
    let mut notes = Vec::new();
    if offsets.iter().any(Option::is_some) {
        notes.push(
            "known release offsets are kept but not used by the design: its bounds hold for any phasing (`rtpipe analyze` shows the known-offset bounds of the result)"
                .to_string(),
        );
    }
    let boxes = choose_method(spec, opts)?;
    let method = if boxes { Method::Boxes } else { Method::Milp };
    if spec.harmonic {
        domain::harmonic_domains(spec, &mut domains.dom, &mut notes, method)?;
    }
    let tops = implicit_tops(spec, &domains);
    if opts.accept.is_some() && !boxes {
        return Err(DesignError::input(
            "an acceptance check (`--fly`) needs the box search: sound mode, or paper mode where it applies",
        )
        .help("leave out --fly, or design in sound mode"));
    }
    let p = Problem::new(spec, opts, domains, method);
    let mut learnt = Learnt::new(spec.tasks.len());
    let mut budget = Budget::new(opts, start);
    let mut o = if boxes {
        boxes::solve_boxes(&p, &mut learnt, &mut budget)?
    } else {
        runner::solve_all(&p, &mut learnt, &mut budget)?
    };
    o.notes.splice(0..0, notes);
    o.notes.extend(at_implicit_tops(spec, &o, &tops));
    if let Some(s) = o.spec.as_mut() {
        for (t, &x) in s.tasks.iter_mut().zip(&offsets) {
            t.offset = x;
        }
    }
    Ok(o)
}

/// Per task whose free period has no upper end of its own (no `max`, no
/// `max_period`): the top of its domain, which the spec's largest chain
/// limit or fixed period set (ns).
fn implicit_tops(spec: &Spec, d: &domain::Domains) -> Vec<Option<Nanos>> {
    spec.tasks
        .iter()
        .zip(&d.dom)
        .map(|(t, dom)| {
            let own_max = match &t.period {
                rtpipe_model::PeriodSpec::Free => false,
                rtpipe_model::PeriodSpec::Range { max, .. } => max.is_some(),
                _ => true,
            };
            (!own_max && t.max_period.is_none()).then(|| dom.max() * d.g)
        })
        .collect()
}

/// A note for each designed period at the top it did not choose: control
/// may need that task faster than any chain limit says (a motor output).
fn at_implicit_tops(spec: &Spec, o: &Outcome, tops: &[Option<Nanos>]) -> Vec<String> {
    let Some(designed) = &o.spec else {
        return Vec::new();
    };
    designed
        .tasks
        .iter()
        .zip(tops)
        .filter_map(|(t, top)| {
            let (p, top) = (t.fixed_period()?, (*top)?);
            (p == top).then(|| {
                format!(
                    "task `{}` got the longest period its free range allows ({}{u}), an upper end it does not set itself: the spec's largest chain limit or fixed period; if control needs it faster (a motor output), give it `max_period` or period = {{ max = ... }}",
                    t.name,
                    spec.fmt_time(p),
                    u = spec.time_unit
                )
            })
        })
        .collect()
}

/// The search `design` runs for `spec` with `opts` ([`Method::Boxes`] or
/// [`Method::Milp`]; an invalid `--method boxes` is reported by `design`).
pub fn method_for(spec: &Spec, opts: &Options) -> Method {
    match choose_method(spec, opts) {
        Ok(true) | Err(_) if opts.method != Method::Milp => Method::Boxes,
        _ => Method::Milp,
    }
}

/// Whether the box search runs (true) or the MILP.
fn choose_method(spec: &Spec, opts: &Options) -> Result<bool, DesignError> {
    // With threads or data-triggered tasks the box search does not use
    // the relaxation (`events`), so paper mode needs no monotone Eq. 12.
    let fits = match opts.mode {
        Mode::Sound => true,
        Mode::Paper => spec.event_triggered() || rtpipe_analysis::relax::paper_monotone(spec),
    };
    let paper_refusal = || {
        DesignError::input(
            "in paper mode the box search needs no chain task whose demand exceeds three budgets (Eq. 12 then falls as its period grows)",
        )
    };
    match (opts.method, contention(spec)) {
        (Method::Auto | Method::Boxes, Some((what, key))) if !fits => Err(paper_refusal()
            .at(key)
            .help(format!("the MILP does not model {what}: design in sound mode (leave --mode out)"))),
        (Method::Milp, Some((what, key))) => Err(DesignError::input(format!(
            "{what}: the MILP (--method milp) has no blocking, overhead or jitter term, and only rate-monotonic ranks, implicit deadlines under EDF and implicit communication; the box search models them"
        ))
        .at(key)
        .help("leave --method out (or use --method boxes)")),
        (Method::Auto, _) => Ok(fits),
        (Method::Milp, None) => Ok(false),
        (Method::Boxes, _) if fits => Ok(true),
        (Method::Boxes, _) => {
            Err(paper_refusal().help("use --method milp (or leave --method out)"))
        }
    }
}

/// What only the box search models, and the spec key that gives it:
/// critical sections (their blocking, `analysis::blocking`, enters its
/// relaxation as the least over the orders a box leaves open), release
/// jitter (the relaxation's response times are R = J + w, Audsley et al.),
/// scheduling overheads (`analysis::overheads`, charged per job and per
/// release), deadline-monotonic or explicit priorities (the relaxation
/// ranks by `policy::rank_key`; the MILP's order binaries compare
/// periods), the processor-demand test (its demand bounds no MILP row
/// writes) and LET communication (the relaxation takes LET's chain
/// bounds, linear in the periods; the MILP encodes implicit
/// communication's). Deadlines are honoured by both (every answer passes
/// R ≤ D, or the demand test, re-checked by `analyze`). docs/design.md,
/// "Critical sections and overheads" and "Priorities and deadlines".
fn contention(spec: &Spec) -> Option<(String, String)> {
    if let Some(x) = event_triggered(spec) {
        return Some(x);
    }
    if let Some(x) = ranks_or_demand(spec) {
        return Some(x);
    }
    contention_costs(spec).map(|(what, key)| (what.to_string(), key))
}

/// Work-queue threads or data-triggered tasks (the MILP's rows are the
/// periodic analysis'; the box search verifies every candidate with the
/// event analysis, docs/design.md "Event-triggered specs"), and the key of
/// the first task that gives one: its `thread`, else its `activation`.
fn event_triggered(spec: &Spec) -> Option<(String, String)> {
    let what = "threads and data-triggered tasks (their event analysis)".to_string();
    let t = spec
        .tasks
        .iter()
        .find(|t| t.thread.is_some() || t.is_triggered())?;
    let key = if t.thread.is_some() {
        "thread"
    } else {
        "activation"
    };
    Some((what, format!("tasks.{}.{key}", t.name)))
}

/// A priority order other than rate monotonic, the processor-demand test
/// or LET communication, and its key.
fn ranks_or_demand(spec: &Spec) -> Option<(String, String)> {
    if spec.communication == rtpipe_model::Communication::Let {
        let what = "communication = \"let\" (LET chain bounds)".to_string();
        return Some((what, "system.communication".to_string()));
    }
    let let_chain = (0..spec.chains.len())
        .find(|&k| spec.chains[k].communication == Some(rtpipe_model::Communication::Let));
    if let Some(k) = let_chain {
        let what = format!("chain `{}` under LET", spec.chain_label(k));
        return Some((what, format!("chain[{k}].communication")));
    }
    let fixed = spec.policy().fixed_priority();
    if fixed && spec.priorities != rtpipe_model::Priorities::RateMonotonic {
        let what = format!("priorities = \"{}\"", spec.priorities.name());
        return Some((what, "system.priorities".to_string()));
    }
    if spec.schedulability != rtpipe_model::SchedTest::Qpa {
        return None;
    }
    let what = "schedulability = \"qpa\" (EDF with deadlines, the processor-demand test)";
    // QPA is the default under EDF with deadlines: the first deadline is
    // then where the spec asks for it.
    let key = match spec.tasks.iter().find(|t| t.deadline_given.is_some()) {
        Some(t) => format!("tasks.{}.deadline", t.name),
        None => "system.schedulability".to_string(),
    };
    Some((what.to_string(), key))
}

/// Critical sections, release jitter or overheads, and the key.
fn contention_costs(spec: &Spec) -> Option<(&'static str, String)> {
    if let Some(t) = spec.tasks.iter().find(|t| !t.sections.is_empty()) {
        let key = format!("tasks.{}.critical_sections", t.name);
        return Some(("critical sections (blocking)", key));
    }
    if let Some(t) = spec.tasks.iter().find(|t| t.jitter > 0) {
        let key = format!("tasks.{}.jitter", t.name);
        return Some(("release jitter", key));
    }
    (!spec.overheads.is_zero()).then(|| {
        (
            "[system] overheads (scheduling overheads)",
            "system.overheads".to_string(),
        )
    })
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_encoding;
#[cfg(test)]
mod tests_split;
#[cfg(test)]
mod tests_trade;
