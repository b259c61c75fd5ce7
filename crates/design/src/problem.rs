//! The immutable problem of one design search: the spec, its period
//! domains and the options, and the constraint groups it is made of.

use crate::api::{Incumbent, Method, Options};
use crate::domain::{grid_units, Dom, Domains};
use rtpipe_analysis::{Anchor, ChainResult, Metric, Report};
use rtpipe_model::{Nanos, PeriodSpec, Spec};

/// Whether `RTPIPE_DESIGN_DEBUG` asks for the searches' story on stderr
/// (the master solves, the MILP's iterations, how incumbents were found).
pub(crate) fn debug() -> bool {
    std::env::var_os("RTPIPE_DESIGN_DEBUG").is_some()
}

/// What one design search is asked: read by every part of it, changed by
/// none (the conflict search's limit moves get a problem of their own).
pub(crate) struct Problem<'a> {
    pub(crate) spec: &'a Spec,
    pub(crate) opts: &'a Options,
    /// The period grid (ns): every period is a multiple of it.
    pub(crate) g: i64,
    pub(crate) dom: Vec<Dom>,
    pub(crate) big_m: f64,
    /// Task i lies on some declared chain.
    pub(crate) on_chain: Vec<bool>,
    /// The search that decides: [`Method::Boxes`] or [`Method::Milp`].
    pub(crate) method: Method,
}

/// Which constraint groups are active (for the conflict search).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Group {
    Limit(usize, Metric),
    Sched(u32),
}

impl<'a> Problem<'a> {
    /// The problem of designing `spec` over these domains with `method`.
    pub(crate) fn new(spec: &'a Spec, opts: &'a Options, domains: Domains, method: Method) -> Self {
        let Domains { g, dom, horizon } = domains;
        let n = spec.tasks.len();
        let max_t = dom.iter().map(|d| d.max()).max().unwrap_or(1) as f64;
        let max_limit = grid_units(horizon, g);
        let big_m = 4.0 * (max_t + max_limit) + 10.0;
        Problem {
            spec,
            opts,
            g,
            dom,
            big_m,
            on_chain: (0..n)
                .map(|i| spec.chains.iter().any(|c| c.path.contains(&i)))
                .collect(),
            method,
        }
    }

    /// This problem for `spec` (this one's with a chain limit moved to
    /// `l`): the same domains, a big-M that covers the new limit.
    pub(crate) fn with_limit<'s>(&self, spec: &'s Spec, l: Nanos) -> Problem<'s>
    where
        'a: 's,
    {
        Problem {
            spec,
            opts: self.opts,
            g: self.g,
            dom: self.dom.clone(),
            big_m: self.big_m.max(4.0 * grid_units(l, self.g)),
            on_chain: self.on_chain.clone(),
            method: self.method,
        }
    }

    /// Tells [`Options::progress`] what the search is doing.
    pub(crate) fn say(&self, what: impl FnOnce() -> String) {
        if let Some(p) = &self.opts.progress {
            if let Ok(mut g) = p.lock() {
                *g = what();
            }
        }
    }

    /// Hands a better verified design to [`Options::incumbent`], so that a
    /// caller that stops waiting (Ctrl-C) can still report it.
    pub(crate) fn publish(&self, best: &Option<(Spec, Report, f64)>, lower_bound: Option<f64>) {
        if let (Some(sink), Some((s, _, u))) = (&self.opts.incumbent, best) {
            if let Ok(mut g) = sink.lock() {
                *g = Some(Incumbent {
                    periods: s
                        .tasks
                        .iter()
                        .map(|t| t.fixed_period().unwrap_or(0))
                        .collect(),
                    utilization: *u,
                    lower_bound: lower_bound.map(|b| b.min(*u)),
                });
            }
        }
    }

    /// Every constraint group: each chain limit, each CPU's test.
    pub(crate) fn all_groups(&self) -> Vec<Group> {
        let mut v = Vec::new();
        for (k, ch) in self.spec.chains.iter().enumerate() {
            // One group per metric holds its limits from both anchors.
            for m in [Metric::Reaction, Metric::Freshness] {
                if Anchor::ALL.iter().any(|&a| m.limit(ch, a).is_some()) {
                    v.push(Group::Limit(k, m));
                }
            }
        }
        let mut cpus: Vec<u32> = self.spec.tasks.iter().map(|t| t.cpu).collect();
        cpus.sort_unstable();
        cpus.dedup();
        v.extend(cpus.into_iter().map(Group::Sched));
        v
    }

    /// The spec with these periods fixed; a data-triggered task keeps
    /// its triggers (its entry in `periods` is a placeholder, `domain`).
    pub(crate) fn with_periods(&self, periods: &[Nanos]) -> Spec {
        let mut s = self.spec.clone();
        for (t, &p) in s.tasks.iter_mut().zip(periods) {
            if !t.is_triggered() {
                t.period = PeriodSpec::Fixed(p);
            }
        }
        s
    }

    /// One chain limit holds under the mode's analysis.
    pub(crate) fn chain_ok(&self, c: &ChainResult) -> bool {
        c.ok_in(self.opts.mode)
    }

    /// Every chain limit holds under the mode's analysis.
    pub(crate) fn limits_ok(&self, report: &Report) -> bool {
        report.chains.iter().all(|c| self.chain_ok(c))
    }
}
