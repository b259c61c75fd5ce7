//! Sound mode: response-time variables and their cuts, and each link term
//! as the smallest valid option of docs/analysis.md.

use crate::domain::grid_units;
use crate::linear::{Bin, Lin};
use crate::lp::{Cmp, Lp};
use crate::model::Master;
use crate::problem::{Group, Problem};
use rtpipe_analysis::sched::interference;
use rtpipe_analysis::{Metric, Report};
use rtpipe_model::policy::ResponseAnalysis;
use rtpipe_model::{Nanos, Server, Spec};

/// What the sound model knows of response times: unconditional lower
/// bounds, and conditional ones learnt from verified candidates.
#[derive(Debug, Clone)]
pub(crate) struct SoundModel {
    /// R_i ≥ this whatever the periods (grid units).
    pub(crate) rlow: Vec<f64>,
    /// W_i (the read-to-publish bound, modelled under EDF) ≥ this whatever
    /// the periods (grid units).
    pub(crate) wlow: Vec<f64>,
    pub(crate) cuts: Vec<RCut>,
    /// Heuristic phase: response times pinned to these estimates (not a
    /// relaxation; its candidates still go through the analysis). One per
    /// task (R; W is pinned to R), or two (R of every task, then W).
    pub(crate) fixed: Option<Vec<f64>>,
}

/// R_i ≥ r unless some higher-priority task's period grew past its value
/// then, or left the higher-priority set (RTA is monotone in both). Under
/// EDF `hp` is empty, `periods` holds every other task of i's CPU (Spuri's
/// bound never grows with another task's period: fewer jobs, later
/// deadlines, a shorter busy period) and `own` i's period, which moves the
/// bound either way: the cut holds only while it is unchanged.
#[derive(Debug, Clone)]
pub(crate) struct RCut {
    pub(crate) i: usize,
    pub(crate) r: f64,
    pub(crate) hp: Vec<usize>,
    pub(crate) periods: Vec<(usize, i64)>,
    pub(crate) own: Option<i64>,
    /// A cut on W_i rather than R_i (EDF): the read-to-publish bound is
    /// monotone in the same way (`edf::start_to_finish`: fewer and later
    /// jobs of others can only lower it).
    pub(crate) read: bool,
}

/// Lower bounds on job response times that hold for every choice of
/// periods: own demand plus one job of each task that has higher priority
/// whatever the periods (under EDF: whose period is never above i's, so
/// whose first deadline never comes after i's; `analysis::relax` uses the
/// same bound).
pub(crate) fn rhat_lower(p: &Problem) -> Vec<f64> {
    let spec = p.spec;
    let n = spec.tasks.len();
    (0..n)
        .map(|i| {
            let fp = spec.policy().fixed_priority();
            let mut r = spec.tasks[i].demand();
            if !fp {
                r = r.max(1);
            }
            for j in 0..n {
                if j == i
                    || spec.tasks[j].cpu != spec.tasks[i].cpu
                    || spec.tasks[j].server == Server::Background
                {
                    continue;
                }
                let (di, dj) = (&p.dom[i], &p.dom[j]);
                let always_above = dj.max() < di.min() || (j < i && dj.max() <= di.min());
                let counts = match fp {
                    true => always_above,
                    false => dj.max() <= di.min(),
                };
                if counts {
                    r += interference(&spec.tasks[j]);
                }
            }
            grid_units(r, p.g)
        })
        .collect()
}

/// Lower bounds on the read-to-publish bounds W_i for every choice of
/// periods: own demand plus one job of each task whose deadline is before
/// i's whatever the periods (`edf::start_to_finish` counts no task of a
/// deadline at or after i's; `analysis::relax` uses the same bound). Only
/// modelled under EDF, where W can be below R.
pub(crate) fn w_lower(p: &Problem) -> Vec<f64> {
    let spec = p.spec;
    let n = spec.tasks.len();
    let d = |j: usize, t: i64| {
        let t = t * p.g;
        spec.tasks[j].deadline_given.map_or(t, |d| d.min(t))
    };
    (0..n)
        .map(|i| {
            let mut w = spec.tasks[i].demand().max(1);
            for j in 0..n {
                let mate = j != i
                    && spec.tasks[j].cpu == spec.tasks[i].cpu
                    && spec.tasks[j].server != Server::Background;
                if mate && d(j, p.dom[j].max()) < d(i, p.dom[i].min()) {
                    w += interference(&spec.tasks[j]);
                }
            }
            grid_units(w, p.g)
        })
        .collect()
}

/// An upper end for R_i: T_i (it finishes within its period) and every
/// active freshness limit of a chain through i (T_p and the tail's R both
/// appear in the freshness sum).
pub(crate) fn rmax_of(m: &Master, groups: &[Group], i: usize) -> f64 {
    let mut r = m.dom[i].max() as f64;
    for (k, ch) in m.spec.chains.iter().enumerate() {
        if let (true, Some(l)) = (
            ch.path.contains(&i) && groups.contains(&Group::Limit(k, Metric::Freshness)),
            ch.freshness,
        ) {
            r = r.min(grid_units(l, m.g));
        }
    }
    r
}

/// Adds a cut for every chain task whose response time (or, under EDF,
/// read-to-publish bound) the model under-estimated at this candidate;
/// false when there was none. `rmodel` holds the model's R of every task,
/// then its W of every task (`solve.rs`).
pub(crate) fn learn_r_cuts(
    g: i64,
    cand: &Spec,
    report: &Report,
    periods: &[Nanos],
    rmodel: &[Option<f64>],
    sm: &mut SoundModel,
) -> bool {
    let prio = rtpipe_model::policy::rate_monotonic(cand);
    let top = rtpipe_analysis::sched::top_priorities(cand, &prio);
    let mut learnt = false;
    let n = cand.tasks.len();
    for (k, mv) in rmodel.iter().enumerate() {
        let (i, read) = (k % n, k >= n);
        let tm = &report.timing[i];
        let analysed = if read {
            tm.read_to_publish
        } else {
            tm.job_response_time
        };
        let (Some(mv), Some(tr)) = (mv, analysed) else {
            continue;
        };
        let tr = grid_units(tr, g);
        if tr > mv + 1e-6 {
            let cut = r_cut(g, cand, &prio, &top, periods, i, tr);
            sm.cuts.push(RCut { read, ..cut });
            learnt = true;
        }
    }
    learnt
}

/// The cut of task i's analysed response time `r` at the candidate's
/// periods (see [`RCut`]).
fn r_cut(
    g: i64,
    cand: &Spec,
    prio: &[Option<usize>],
    top: &[Option<usize>],
    periods: &[Nanos],
    i: usize,
    r: f64,
) -> RCut {
    if cand.policy().fixed_priority() {
        let hp = rtpipe_analysis::sched::interferers(cand, prio, top, i);
        let periods = hp.iter().map(|&j| (j, periods[j] / g)).collect();
        return RCut {
            i,
            r,
            hp,
            periods,
            own: None,
            read: false,
        };
    }
    let t = &cand.tasks[i];
    let own = Some(periods[i] / g);
    let periods = (0..cand.tasks.len())
        .filter(|&j| j != i && cand.tasks[j].cpu == t.cpu)
        .filter(|&j| cand.tasks[j].server != Server::Background)
        .map(|j| (j, periods[j] / g))
        .collect();
    RCut {
        i,
        r,
        hp: Vec::new(),
        periods,
        own,
        read: false,
    }
}

/// R_i ≥ r − M·(Σ [hp period grew] + Σ [left the hp set] + [T_i moved]).
pub(crate) fn add_r_cut(m: &mut Master, cut: &RCut) {
    let var = if cut.read {
        m.wvar[cut.i]
    } else {
        m.rvar[cut.i]
    };
    let Some(rv) = var else { return };
    let big = m.big_m;
    let mut terms: Vec<(usize, f64)> = vec![(rv, 1.0)];
    let mut rhs = cut.r;
    for &(j, tj) in &cut.periods {
        if let Some(b) = m.grew(j, tj) {
            terms.push((b, big));
        }
    }
    if let Some(ti) = cut.own {
        let moved = [m.grew(cut.i, ti), m.shrank(cut.i, ti)];
        terms.extend(moved.into_iter().flatten().map(|b| (b, big)));
    }
    for &j in &cut.hp {
        match m.above(j, cut.i) {
            Bin::Const(true) => {}
            Bin::Const(false) => return,
            Bin::Var(z) => {
                // (1 − z)·M on the right: R + … − M z ≥ r − M
                terms.push((z, -big));
                rhs -= big;
            }
        }
    }
    m.lp.row(terms, Cmp::Ge, rhs);
}

/// Sound mode (docs/analysis.md): both sums from the head's read (from the
/// event, with `shift` the head period: from its release), each link term
/// the smallest valid option, the priority cases and the "distinct"
/// property of each stage as binaries. Returns the sums [E, F]: E the
/// reaction sum (links + the tail's R; W for a task alone from its read),
/// F the freshness sum (links, the last one to the tail's publish); the
/// reaction limit holds when either fits, as the reported reaction is
/// min(E, F).
pub(crate) fn sound_chain(
    m: &mut Master,
    path: &[usize],
    metric: Metric,
    limit: f64,
    shift: &Lin,
) -> Vec<Lin> {
    let tail = *path.last().unwrap_or(&0);
    let from_read = shift.terms.is_empty() && shift.c == 0.0;
    let mut e = response(m, tail);
    let mut f = Lin::default();
    if path.len() == 1 {
        // From the read a task alone is its read-to-publish bound; from the
        // event its release anchors the freshness (R).
        e = if from_read { read_response(m, tail) } else { e };
        f = e.clone();
    }
    // d = 1: the stage's jobs carry distinct samples (true at the head).
    let mut d = Bin::Const(true);
    for (k, w) in path.windows(2).enumerate() {
        let (p, c) = (w[0], w[1]);
        let (l, gq) = sound_link(m, p, c, d, k + 2 == path.len(), from_read && k == 0);
        e = e.plus(&Lin {
            terms: vec![(l, 1.0)],
            c: 0.0,
        });
        f = f.plus(&Lin {
            terms: vec![(gq, 1.0)],
            c: 0.0,
        });
        d = pass_distinct(m, p, c, d);
    }
    let big = m.big_m;
    // From the event, `shift` is the head period (freshness only: reaction
    // from the event has its own encoding, `sound_event_reaction`).
    let (es, fs) = (e.plus(shift), f.plus(shift));
    match metric {
        Metric::Freshness => m.lp.row(fs.terms, Cmp::Le, limit - fs.c),
        Metric::Reaction => {
            // The reported reaction is min(E, F): one of them must fit.
            let w = m.lp.binary();
            let mut t = es.terms;
            t.push((w, -big));
            m.lp.row(t, Cmp::Le, limit - es.c);
            let mut t = fs.terms;
            t.push((w, big));
            m.lp.row(t, Cmp::Le, limit - fs.c + big);
        }
    }
    vec![e, f]
}

/// Sound reaction from the event ≤ `limit`: T_1 + Σ link terms + R_n, the
/// links without the reachability options (the producer's stage never
/// counts as distinct), as `rtpipe_analysis::latency::sound_event_reaction`.
/// Returns the sum.
pub(crate) fn sound_event_reaction(m: &mut Master, path: &[usize], limit: f64) -> Lin {
    let tail = *path.last().unwrap_or(&0);
    let mut e = response(m, tail).plus(&m.period[path[0]]);
    for (k, w) in path.windows(2).enumerate() {
        let (l, _) = sound_link(m, w[0], w[1], Bin::Const(false), k + 2 == path.len(), false);
        e = e.plus(&Lin {
            terms: vec![(l, 1.0)],
            c: 0.0,
        });
    }
    m.lp.row(e.terms.clone(), Cmp::Le, limit - e.c);
    e
}

/// The job response time of task i: its variable, or its period where a
/// response time is the server period (and where it has none).
fn response(m: &Master, i: usize) -> Lin {
    match m.rvar[i] {
        Some(v) if m.spec.policy().response != ResponseAnalysis::ServerPeriod => Lin {
            terms: vec![(v, 1.0)],
            c: 0.0,
        },
        _ => m.period[i].clone(),
    }
}

/// The read-to-publish bound W of task i: its variable under EDF, else its
/// response time (the same figure under fixed priority).
fn read_response(m: &Master, i: usize) -> Lin {
    match m.wvar[i] {
        Some(v) => Lin {
            terms: vec![(v, 1.0)],
            c: 0.0,
        },
        None => response(m, i),
    }
}

/// The demands x_min(i) and x(i) in grid units.
fn xmin(m: &Master, i: usize) -> f64 {
    grid_units(m.spec.tasks[i].demand_min(), m.g)
}

fn demand(m: &Master, i: usize) -> f64 {
    grid_units(m.spec.tasks[i].demand(), m.g)
}

/// The smallest and largest values of some options over the variables'
/// bounds, within ±big.
fn span(opts: &[&Lin], lp: &Lp, big: f64) -> (f64, f64) {
    let lo = opts
        .iter()
        .map(|o| o.min_in(lp))
        .fold(f64::INFINITY, f64::min);
    let hi = opts
        .iter()
        .map(|o| o.max_in(lp))
        .fold(f64::NEG_INFINITY, f64::max);
    (lo.max(-big), hi.min(big))
}

/// Link p → c with the producer's stage distinct when `d`: the reaction
/// term variable (≥ the option its binaries pick) and the freshness term
/// variable (≥ the option of the priority order; to the consumer's publish
/// when `last`). The options are `rtpipe_analysis::latency`'s
/// `sound_reaction_link_in`, `sound_freshness_link_in` and
/// `sound_freshness_last_in`, release-anchored but for the head's reaction
/// term from its read (`p_read`: W_p in place of R_p to its publish); the
/// last freshness link ends W_c after the tail's read.
fn sound_link(
    m: &mut Master,
    p: usize,
    c: usize,
    d: Bin,
    last: bool,
    p_read: bool,
) -> (usize, usize) {
    let rp = response(m, p);
    let wc = read_response(m, c);
    // p's publish from where the term starts.
    let fp = if p_read {
        read_response(m, p)
    } else {
        rp.clone()
    };
    let same = m.spec.policy().fixed_priority() && m.spec.tasks[p].cpu == m.spec.tasks[c].cpu;
    let (tp, tc) = (m.period[p].clone(), m.period[c].clone());
    let o1 = fp.plus(&tc);
    let o2 = fp.plus(&tc).add_c(-xmin(m, c));
    let o3 = tp.plus(&rp);
    let o4 = tp.clone();
    let o5 = tc.clone();
    let (q1, q2, q3) = if last {
        (tp.plus(&rp).plus(&wc), tp.plus(&rp), tp.plus(&wc))
    } else {
        (tp.plus(&rp), tp.plus(&rp).add_c(-xmin(m, c)), tp.clone())
    };
    // EDF on one CPU, implicit deadlines (the design's): the options
    // T_c + (T_p − T_c)⁺ = max(T_c, T_p) and T_p + (T_p − T_c)⁺.
    let cpu = |i: usize| m.spec.tasks[i].cpu;
    let implicit = |i: usize| m.spec.tasks[i].deadline_given.is_none();
    let edf = !m.spec.policy().fixed_priority() && cpu(p) == cpu(c) && implicit(p) && implicit(c);
    let o6 = tp.scale(2.0).plus(&tc.scale(-1.0));
    let mut opts = vec![&o1, &o2, &o3, &o4, &o5];
    if edf {
        opts.push(&o6);
    }
    let l = option_var(m, &opts);
    let gq = option_var(m, &[&q1, &q2, &q3]);
    let b = reach_binary(m, d);
    if same {
        let o = m.above(c, p); // 1: c ≻ p (P1), 0: p ≻ c (P2)
        m.ge_option(l, &o2, &[(o, true), (b, false)]);
        m.ge_option(l, &o3, &[(o, true), (b, true)]);
        m.ge_option(l, &o5, &[(o, false), (b, false)]);
        m.ge_option(l, &o4, &[(o, false), (b, true)]);
        m.ge_option(gq, &q2, &[(o, true)]);
        m.ge_option(gq, &q3, &[(o, false)]);
    } else if edf {
        // Freshness: T_p + R_p on a middle link, T_p + max(R_p, W_c) on the
        // last.
        let mut fresh = vec![tp.plus(&rp)];
        if last {
            fresh.push(tp.plus(&wc));
        }
        sound_link_edf(m, (l, gq), b, [&o1, &o3, &o4, &o5, &o6], &fresh);
    } else {
        m.ge_option(l, &o1, &[(b, false)]);
        m.ge_option(l, &o3, &[(b, true)]);
        m.ge_option(gq, &q1, &[]);
    }
    (l, gq)
}

/// A variable for the least of some options, bounded by them so that the
/// switches get tight big-Ms. HiGHS gets the bounds declared; microlp's
/// basis can go singular when both the bounds and the big-Ms are tight,
/// so there they are only known (used for the big-Ms).
fn option_var(m: &mut Master, opts: &[&Lin]) -> usize {
    let big = m.big_m;
    let (lo, hi) = span(opts, &m.lp, big);
    let v = if m.tight_bounds {
        m.lp.var(lo, hi, false)
    } else {
        m.lp.var(-big, big, false)
    };
    m.floor.insert(v, lo);
    v
}

/// b = 1 picks a reachability option; allowed only when d = 1.
fn reach_binary(m: &mut Master, d: Bin) -> Bin {
    match d {
        Bin::Const(false) => Bin::Const(false),
        _ => {
            let v = m.lp.binary();
            if let Bin::Var(dv) = d {
                m.lp.row(vec![(v, 1.0), (dv, -1.0)], Cmp::Le, 0.0);
            }
            Bin::Var(v)
        }
    }
}

/// The options of an EDF link on one CPU (`latency`'s `edf_together`):
/// a binary e picks the deadline-order options, `b` reachability as
/// elsewhere; `o` = [R_p + T_c (or W_p + T_c), T_p + R_p, T_p, T_c,
/// 2 T_p − T_c]; the freshness variable is at least every `fresh` option.
fn sound_link_edf(m: &mut Master, (l, gq): (usize, usize), b: Bin, o: [&Lin; 5], fresh: &[Lin]) {
    let e = Bin::Var(m.lp.binary());
    m.ge_option(l, o[0], &[(b, false), (e, false)]);
    m.ge_option(l, o[1], &[(b, true), (e, false)]);
    // T_c + (T_p − T_c)⁺ = max(T_c, T_p).
    m.ge_option(l, o[3], &[(b, false), (e, true)]);
    m.ge_option(l, o[2], &[(b, false), (e, true)]);
    // T_p + (T_p − T_c)⁺ = max(T_p, 2 T_p − T_c).
    m.ge_option(l, o[2], &[(b, true), (e, true)]);
    m.ge_option(l, o[4], &[(b, true), (e, true)]);
    for f in fresh {
        m.ge_option(gq, f, &[]);
    }
}

/// Distinct passes to c when c's reads are further apart than p's
/// publishes can be: T_c − R_c + x_c > T_p + R_p − x_min(p).
fn pass_distinct(m: &mut Master, p: usize, c: usize, d: Bin) -> Bin {
    if let Bin::Const(false) = d {
        return d;
    }
    let big = m.big_m;
    let (rp, rc) = (response(m, p), response(m, c));
    let (tp, tc) = (m.period[p].clone(), m.period[c].clone());
    let dc = m.lp.binary();
    if let Bin::Var(dv) = d {
        m.lp.row(vec![(dc, 1.0), (dv, -1.0)], Cmp::Le, 0.0);
    }
    let lhs = tc
        .plus(&rc.scale(-1.0))
        .plus(&tp.scale(-1.0))
        .plus(&rp.scale(-1.0));
    // lhs + x_c + x_min(p) ≥ ε − M(1 − dc), ε = one grid unit's share of a ns
    let eps = 1.0 / m.g as f64;
    let mut t = lhs.terms.clone();
    t.push((dc, -big));
    m.lp.row(t, Cmp::Ge, eps - demand(m, c) - xmin(m, p) - lhs.c - big);
    Bin::Var(dc)
}
