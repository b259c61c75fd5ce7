//! Period domains: the grid every period lives on, each task's domain
//! (fixed, a range of grid steps, or a list of choices), harmonic domains.

use crate::api::{DesignError, Method};
use rtpipe_model::{format_in, gcd, Nanos, PeriodSpec, Spec, Task, MAX_TIME};

/// The period domain of one task, in grid units (g ns).
#[derive(Debug, Clone)]
pub(crate) enum Dom {
    Fixed(i64),
    /// T = step · k, k ∈ [lo, hi].
    Grid {
        step: i64,
        lo: i64,
        hi: i64,
    },
    Choice(Vec<i64>),
}

impl Dom {
    pub(crate) fn min(&self) -> i64 {
        match self {
            Dom::Fixed(t) => *t,
            Dom::Grid { step, lo, .. } => step * lo,
            Dom::Choice(v) => v.iter().copied().min().unwrap_or(0),
        }
    }
    pub(crate) fn max(&self) -> i64 {
        match self {
            Dom::Fixed(t) => *t,
            Dom::Grid { step, hi, .. } => step * hi,
            Dom::Choice(v) => v.iter().copied().max().unwrap_or(0),
        }
    }
}

/// Converts ns to grid units.
pub(crate) fn grid_units(ns: Nanos, g: i64) -> f64 {
    ns as f64 / g as f64
}

/// Most candidate periods a free task keeps under `harmonic = true` before
/// its domain is thinned to 5-smooth multiples of the grid, per search: the
/// MILP constrains every pair of choices (its master grows with their
/// product); the box search only walks them (Cleanflight at 100 µs keeps its
/// 440 values per task and is solved in 0.4 s).
pub(crate) fn harmonic_candidates(method: Method) -> usize {
    match method {
        Method::Milp => 256,
        _ => 4096,
    }
}

/// Harmonic periods (every pair divides one way): each free domain becomes
/// a choice among the values that divide or are divided by every fixed
/// period; `build` then forbids every non-harmonic pair of choices. Large
/// ranges keep only the values g·2^a·3^b·5^c (said in a note).
pub(crate) fn harmonic_domains(
    spec: &Spec,
    dom: &mut [Dom],
    notes: &mut Vec<String>,
    method: Method,
) -> Result<(), DesignError> {
    let most = harmonic_candidates(method);
    let fixed: Vec<i64> = dom
        .iter()
        .filter_map(|d| match d {
            Dom::Fixed(t) => Some(*t),
            _ => None,
        })
        .collect();
    for (a, &p) in fixed.iter().enumerate() {
        for &q in &fixed[a + 1..] {
            if !harmonic_pair(p, q) {
                return Err(DesignError::input(
                    "harmonic = true, but the fixed periods are not harmonic (one of each pair must divide the other)",
                ));
            }
        }
    }
    let smooth = |mut v: i64, primes: &[i64]| {
        for f in primes {
            while v % f == 0 {
                v /= f;
            }
        }
        v == 1
    };
    for (i, d) in dom.iter_mut().enumerate() {
        let values: Vec<i64> = match d {
            Dom::Fixed(_) => continue,
            Dom::Choice(v) => v.clone(),
            Dom::Grid { step, lo, hi } => (*lo..=*hi).map(|k| k * *step).collect(),
        };
        let mut ok: Vec<i64> = values
            .into_iter()
            .filter(|&v| fixed.iter().all(|&f| harmonic_pair(v, f)))
            .collect();
        if ok.len() > most {
            // Still too many 5-smooth values (every pair of choices is
            // constrained, so the master grows with their product): keep
            // the 3-smooth ones.
            let mut kept = "2^a·3^b·5^c";
            ok.retain(|&v| smooth(v, &[2, 3, 5]));
            if ok.len() > most {
                ok.retain(|&v| smooth(v, &[2, 3]));
                kept = "2^a·3^b";
            }
            notes.push(format!(
                "harmonic: task `{}` chooses among the {} periods of its range that are {kept} grid steps (optimal among those)",
                spec.tasks[i].name,
                ok.len()
            ));
        }
        if ok.is_empty() {
            return Err(DesignError::input(format!(
                "harmonic = true: no period in the range of task `{}` divides or is a multiple of every fixed period",
                spec.tasks[i].name
            )));
        }
        *d = Dom::Choice(ok);
    }
    Ok(())
}

pub(crate) use rtpipe_model::harmonic_pair;

#[allow(clippy::too_many_arguments)]
pub(crate) fn range_dom(
    spec: &Spec,
    t: &Task,
    min: Option<Nanos>,
    max: Option<Nanos>,
    c: Nanos,
    horizon: Nanos,
    res: Nanos,
    g: i64,
) -> Result<Dom, DesignError> {
    let lo_ns = min.unwrap_or(0).max(c);
    let hi_ns = match max {
        Some(m) => m,
        None if horizon > 0 => horizon,
        None => {
            return Err(DesignError::input(format!(
                "task `{}` has a free period without an upper end and no chain limit bounds it; give period = {{ max = ... }}",
                t.name
            )))
        }
    };
    let lo = (lo_ns + res - 1) / res;
    let hi = hi_ns / res;
    if lo > hi {
        return Err(DesignError::input(format!(
            "task `{}`: no multiple of the resolution {}{} lies in [{}, {}] {} (the period must also be at least the budget and the deadline)",
            t.name,
            format_in(res, spec.time_unit),
            spec.time_unit,
            format_in(lo_ns, spec.time_unit),
            format_in(hi_ns, spec.time_unit),
            spec.time_unit
        )));
    }
    Ok(Dom::Grid {
        step: res / g,
        lo,
        hi,
    })
}

/// The grid and every task's domain on it.
pub(crate) struct Domains {
    /// The grid step (ns): the gcd of the resolution, every fixed period
    /// and every period choice.
    pub(crate) g: i64,
    pub(crate) dom: Vec<Dom>,
    /// Upper end for periods without a max: the largest limit or fixed
    /// period (ns).
    pub(crate) horizon: Nanos,
}

/// The grid and the period domain of every task (before harmonic domains).
pub(crate) fn domains(spec: &Spec) -> Result<Domains, DesignError> {
    let horizon = horizon(spec);
    let g = grid(spec);
    let mut dom = Vec::with_capacity(spec.tasks.len());
    for t in &spec.tasks {
        dom.push(task_dom(spec, t, horizon, g)?);
    }
    check_steps(spec, &dom)?;
    Ok(Domains { g, dom, horizon })
}

/// The largest chain limit or fixed period.
fn horizon(spec: &Spec) -> Nanos {
    let mut horizon: i64 = 0;
    for c in &spec.chains {
        horizon = horizon
            .max(c.reaction.unwrap_or(0))
            .max(c.freshness.unwrap_or(0))
            .max(c.max_reaction_time.unwrap_or(0))
            .max(c.freshness_from_event.unwrap_or(0));
    }
    for t in &spec.tasks {
        if let Some(p) = t.fixed_period() {
            horizon = horizon.max(p);
        }
    }
    horizon
}

/// The grid: periods are multiples of g (resolution, fixed periods, choices).
fn grid(spec: &Spec) -> i64 {
    let mut g = spec.resolution;
    for t in &spec.tasks {
        match &t.period {
            PeriodSpec::Fixed(p) => g = gcd(g, *p),
            PeriodSpec::Choices(v) => v.iter().for_each(|&p| g = gcd(g, p)),
            _ => {}
        }
    }
    g.max(1)
}

/// The domain of task `t` on the grid `g`.
fn task_dom(spec: &Spec, t: &Task, horizon: Nanos, g: i64) -> Result<Dom, DesignError> {
    let res = spec.resolution;
    // T ≥ C, and T ≥ D when a deadline is given (constrained deadlines).
    let c = t.budget().max(t.deadline_given.unwrap_or(0));
    // `max_period` caps every period the design may give the task: control
    // needs at least that rate, whatever the chains allow.
    let cap = t.max_period.unwrap_or(Nanos::MAX);
    Ok(match &t.period {
        PeriodSpec::Fixed(p) => Dom::Fixed(p / g),
        PeriodSpec::Choices(v) => {
            let ok: Vec<i64> = v
                .iter()
                .filter(|&&p| p >= c && p <= cap)
                .map(|&p| p / g)
                .collect();
            if ok.is_empty() {
                return Err(DesignError::input(format!(
                    "task `{}`: no period choice is at least its budget (and deadline) {}{} and at most its max_period",
                    t.name,
                    format_in(c, spec.time_unit),
                    spec.time_unit
                )));
            }
            Dom::Choice(ok)
        }
        PeriodSpec::Range { min, max } => {
            let max = max.map_or(t.max_period, |m| Some(m.min(cap)));
            range_dom(spec, t, *min, max, c, horizon, res, g)?
        }
        PeriodSpec::Free => range_dom(spec, t, None, t.max_period, c, horizon, res, g)?,
        // A data-triggered task has no period of its own: its rate is its
        // triggers' (`Spec::activation_period_with`). It keeps one value,
        // a single grid step (harmonic with every period on the grid),
        // which `Problem::with_periods` never writes into the spec.
        PeriodSpec::Triggered { .. } => Dom::Fixed(1),
    })
}

/// microlp keeps integers in the i32 range: say which period range and
/// resolution make the steps too many.
fn check_steps(spec: &Spec, dom: &[Dom]) -> Result<(), DesignError> {
    let res = spec.resolution;
    for (t, d) in spec.tasks.iter().zip(dom) {
        if let Dom::Grid { hi, .. } = d {
            if *hi > i64::from(i32::MAX) {
                let mut coarser = res;
                while coarser < MAX_TIME && (hi.saturating_mul(res)) / coarser > i64::from(i32::MAX)
                {
                    coarser = coarser.saturating_mul(10);
                }
                return Err(DesignError::input(format!(
                    "task `{}`: its period range up to {}{u} is {hi} steps of the resolution {}{u}, more than the solver's integers hold ({})",
                    t.name,
                    format_in(hi.saturating_mul(res), spec.time_unit),
                    format_in(res, spec.time_unit),
                    i32::MAX,
                    u = spec.time_unit
                ))
                .help(format!(
                    "set a coarser resolution in [system], e.g. resolution = \"{}{}\", or a smaller period max for [tasks.{}]",
                    format_in(coarser, spec.time_unit),
                    spec.time_unit,
                    t.name
                )));
            }
        }
    }
    Ok(())
}
