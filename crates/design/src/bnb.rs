//! Sound-mode design by branch and bound over boxes of periods.
//!
//! A node is a box: an interval of each task's period values. Its bound is
//! the utilisation at the longest periods, Σ C/hi, which no point of the box
//! goes below. The box's corner at the longest periods is checked by the
//! analysis itself: if it verifies, it is the best point of the box and the
//! box is done. A box is dropped when `rtpipe_analysis::relax` (the sound
//! analysis at the box's most favourable values) shows that some constraint
//! fails everywhere in it, or when its bound cannot beat the best verified
//! design. Before that, each task's interval is narrowed: periods so long
//! that the relaxation fails are cut from the top (by bisection, since
//! relaxations only grow on sub-boxes), periods so short that the bound
//! cannot beat the incumbent from the bottom. Otherwise the box is split in
//! two at the utilisation midpoint of one task, chosen among the tasks of a
//! constraint the corner fails. Boxes are taken best bound first, so the
//! smallest open bound is a proven lower bound at every moment.
//!
//! Nothing is approximated: the answer is verified by the analysis, and
//! every pruned box provably holds nothing better. docs/design.md argues it.

use crate::api::utilization;
use crate::axis::{Axis, Node};
use crate::budget::Budget;
use crate::harmonic;
use crate::joint::{joint_bound, least_under, split_bound, Row, Shares, SplitLimit};
use crate::problem::{Group, Problem};
use rtpipe_analysis::relax::{
    paper_pieces, relax, sound_pieces, Affine, MinSum, Relaxed, SoundSums,
};
use rtpipe_analysis::{Anchor, Metric, Mode, Report};
use rtpipe_model::policy::RankKey;
use rtpipe_model::{Nanos, Server, Spec};

/// Relative tolerance under which a box's bound counts as no better than
/// the incumbent (the same as the MILP search's "closed" gap).
const GAP_TOLERANCE: f64 = 1e-9;

/// Rounds of narrowing per box at most (each may enable the next).
const NARROW_ROUNDS: usize = 2;

/// Branch on an open order rather than a period once the order's narrower
/// span is at least this share of the widest period split's.
const ORDER_FIRST: f64 = 0.5;

/// How a box whose corner fails is split in two.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Branching {
    /// On the rank order of two tasks: (a above b) and (b above a).
    Order((usize, usize)),
    /// On task i's period, at its utilisation midpoint.
    Split(usize),
}

/// What examining a box found.
pub(crate) enum Fate {
    /// Nothing in it is feasible and better than the incumbent.
    Pruned,
    /// Its corner of longest periods verifies (the box narrowed, the
    /// verified design, its analysis and U): nothing in the box is better.
    Verified(Node, Box<(Spec, Report)>, f64),
    /// Its corner fails: the box narrowed, and how to split it.
    Open(Node, Branching),
}

/// A box's bound `bound` cannot beat the incumbent's U.
pub(crate) fn beaten(bound: f64, incumbent: Option<f64>) -> bool {
    incumbent.is_some_and(|u| bound >= u * (1.0 - GAP_TOLERANCE))
}

/// The examination of boxes of one problem: which constraint groups count,
/// the axes. Pure (`&self` only), so boxes are examined in parallel.
pub(crate) struct Examiner<'r, 'a> {
    pub(crate) p: &'r Problem<'a>,
    groups: &'r [Group],
    pub(crate) axes: Vec<Axis>,
    /// Budgets C_i of guaranteed tasks (0 for background ones).
    budget: Vec<f64>,
    /// The spec has threads or data-triggered tasks: `relax` does not
    /// bound its analysis (`events`).
    events: bool,
    /// Per task, the longest period the from-event limits allow
    /// (`events::source_caps`; empty unless `events` in sound mode).
    caps: Vec<Option<Nanos>>,
}

impl<'r, 'a> Examiner<'r, 'a> {
    pub(crate) fn new(p: &'r Problem<'a>, groups: &'r [Group]) -> Self {
        let axes = p.dom.iter().map(|d| Axis::new(d, p.g)).collect();
        let budget = p
            .spec
            .tasks
            .iter()
            .map(|t| match t.server {
                Server::Background => 0.0,
                _ => t.budget() as f64,
            })
            .collect();
        Examiner {
            p,
            groups,
            axes,
            budget,
            events: p.spec.event_triggered(),
            caps: crate::events::source_caps(p.spec, p.opts.mode, groups),
        }
    }

    pub(crate) fn periods(&self, k: &[u32]) -> Vec<Nanos> {
        k.iter().zip(&self.axes).map(|(&k, a)| a.value(k)).collect()
    }

    pub(crate) fn bound(&self, hi: &[u32]) -> f64 {
        self.utilization_at(&self.periods(hi))
    }

    /// Σ C/T at periods `t` (ns): the least utilisation of a box whose
    /// longest periods they are (a data-triggered task at the rate it
    /// inherits, which never falls as a period grows).
    fn utilization_at(&self, t: &[Nanos]) -> f64 {
        if !self.events {
            return t.iter().zip(&self.budget).map(|(&t, c)| c / t as f64).sum();
        }
        let spec = self.p.spec;
        let own = |j: usize| Some(t[j]);
        (0..t.len())
            .map(|i| match spec.activation_period_with(i, &own) {
                Some(p) => self.budget[i] / p as f64,
                None => unreachable!("every period is given"),
            })
            .sum()
    }

    /// Task i's rank key at its period index k (`policy::rank_key`: the
    /// period under RM, the deadline or else the period under DM, the
    /// explicit priority), and whether it is the period itself.
    fn key(&self, i: usize, k: u32) -> (Nanos, bool) {
        let spec = self.p.spec;
        let key = rtpipe_model::policy::rank_key(spec.priorities, &spec.tasks[i]);
        (key.at(self.axes[i].value(k)), key == RankKey::Period)
    }

    /// Shrinks the box to the points that have the imposed orders
    /// (a above b ⟺ (K_a, a) < (K_b, b), K the rank key: only a key that
    /// is the period moves); false when none is left.
    fn enforce_orders(&self, node: &mut Node) -> bool {
        for _ in 0..node.above.len() + 1 {
            let mut changed = false;
            for &(a, b) in &node.above {
                let tie = Nanos::from(a > b);
                // K_a ≤ K_b − tie: a's top and b's bottom move.
                let (top, _) = self.key(b, node.hi[b]);
                let (bottom, _) = self.key(a, node.lo[a]);
                if bottom + tie > top {
                    return false;
                }
                if self.key(a, node.hi[a]).1 {
                    match self.axes[a].last_at_most(top - tie) {
                        Some(k) if k >= node.lo[a] => {
                            changed |= k < node.hi[a];
                            node.hi[a] = node.hi[a].min(k);
                        }
                        _ => return false,
                    }
                }
                if self.key(b, node.lo[b]).1 {
                    let k = self.axes[b].first_at_least((bottom + tie) as f64);
                    if k > node.hi[b] {
                        return false;
                    }
                    changed |= k > node.lo[b];
                    node.lo[b] = node.lo[b].max(k);
                }
            }
            if !changed {
                return true;
            }
        }
        true
    }

    fn may_hold(&self, r: &Relaxed, lo: &[Nanos]) -> bool {
        let spec = self.p.spec;
        let sound = self.mode() == Mode::Sound;
        // The sound analysis needs every chain bounded, limit or not.
        if sound && r.chains.iter().any(|c| c.0.is_none() || c.1.is_none()) {
            return false;
        }
        let least = |k: usize, m: Metric| match (sound, m) {
            (true, Metric::Reaction) => r.chains[k].0,
            (true, Metric::Freshness) => r.chains[k].1,
            (false, Metric::Reaction) => Some(r.paper[k].0),
            (false, Metric::Freshness) => Some(r.paper[k].1),
        };
        self.groups.iter().all(|g| match *g {
            Group::Limit(k, m) => {
                // From the event every bound is at least the one from the
                // read plus the head's period (`limit_forms`); the sound
                // reaction from the event has a bound of its own.
                let head = lo[spec.chains[k].path[0]];
                Anchor::ALL.into_iter().all(|a| {
                    let least = match (a, sound, m) {
                        (Anchor::Event, true, Metric::Reaction) => r.event_reaction[k],
                        (Anchor::Event, _, _) => least(k, m).map(|b| b + head),
                        (Anchor::Read, _, _) => least(k, m),
                    };
                    m.limit(&spec.chains[k], a)
                        .is_none_or(|l| least.is_some_and(|b| b <= l))
                })
            }
            Group::Sched(cpu) => r.cpus.iter().any(|&(c, ok)| c == cpu && ok),
        })
    }

    fn mode(&self) -> Mode {
        self.p.opts.mode
    }

    /// The split bound's share rounds at the root: more in sound mode
    /// (docs/design.md, "The lower bound, round seven"); paper mode's, whose
    /// bound already meets its designs within 0.4 %, as they were.
    fn root_share_rounds(&self) -> usize {
        match self.mode() {
            Mode::Sound => crate::joint::ROOT_SHARE_ROUNDS,
            Mode::Paper => crate::joint::SHARE_ROUNDS,
        }
    }

    /// The affine forms whose least is the limited figure of chain k in the
    /// mode (`None`: the chain is unbounded everywhere in the box).
    fn forms_of<'x>(&self, r: &'x Relaxed, k: usize, m: Metric) -> Option<Vec<&'x Affine>> {
        Some(match (self.mode(), m) {
            (Mode::Sound, Metric::Reaction) => {
                let (e, f) = r.forms[k].as_ref()?;
                vec![e, f]
            }
            (Mode::Sound, Metric::Freshness) => vec![&r.forms[k].as_ref()?.1],
            (Mode::Paper, Metric::Reaction) => vec![&r.paper_forms[k].0],
            (Mode::Paper, Metric::Freshness) => vec![&r.paper_forms[k].1],
        })
    }

    /// Each limit of chain k's metric m with the affine forms whose least
    /// bounds the limited figure over the box. From the event, every bound
    /// is at least the one from the read plus the head's period (sound
    /// reaction from the event drops the reachability options, which only
    /// lower a link term), so its forms are the read forms plus T_head.
    /// `None`: the chain is unbounded everywhere in the box.
    fn limit_forms(
        &self,
        r: &Relaxed,
        lo: &[Nanos],
        k: usize,
        m: Metric,
    ) -> Option<Vec<(f64, Vec<Affine>)>> {
        let forms = self.forms_of(r, k, m)?;
        let ch = &self.p.spec.chains[k];
        let head = ch.path[0];
        let mut out = Vec::new();
        for a in Anchor::ALL {
            let Some(limit) = m.limit(ch, a) else {
                continue;
            };
            if (a, m, self.mode()) == (Anchor::Event, Metric::Reaction, Mode::Sound) {
                // Its own form: no reachability options, T_1 included.
                out.push((limit as f64, vec![r.event_forms[k].clone()?]));
                continue;
            }
            let shifted = forms.iter().map(|f| match a {
                Anchor::Read => (*f).clone(),
                Anchor::Event => {
                    let mut f = (*f).clone();
                    f.base += lo[head] as f64;
                    f.slopes.push((head, 1.0));
                    f
                }
            });
            out.push((limit as f64, shifted.collect()));
        }
        Some(out)
    }

    /// Each limit of the active groups with the least-of-pieces sums one
    /// of which must meet it (`relax::sound_pieces`, `paper_pieces`), for
    /// [`split_bound`]; a chain without pieces is left out (fewer limits,
    /// a lower bound still).
    fn limit_sums(
        &self,
        r: &Relaxed,
        (lo, hi): (&[Nanos], &[Nanos]),
        above: &[(usize, usize)],
    ) -> Vec<SplitLimit> {
        let spec = self.p.spec;
        let mut out = Vec::new();
        for (index, g) in self.groups.iter().enumerate() {
            let Group::Limit(k, m) = *g else { continue };
            let sums = match self.mode() {
                Mode::Sound => sound_pieces(spec, (lo, hi), above, r, k),
                Mode::Paper => {
                    paper_pieces(spec, (lo, hi), above, k).map(|(e, f)| vec![(e.clone(), f, e)])
                }
            };
            let Some(parts) = sums else {
                continue;
            };
            // Every part of the box (`sound_pieces`' partition) offers its
            // own sums, each holding in its part only.
            let each = |pick: &dyn Fn(&SoundSums) -> Vec<MinSum>| -> Vec<MinSum> {
                parts.iter().flat_map(pick).collect()
            };
            let head = spec.chains[k].path[0];
            for (anchor, a) in Anchor::ALL.into_iter().enumerate() {
                let Some(limit) = m.limit(&spec.chains[k], a) else {
                    continue;
                };
                let read = match (m, self.mode()) {
                    (Metric::Reaction, Mode::Sound) => each(&|p| vec![p.0.clone(), p.1.clone()]),
                    (Metric::Reaction, Mode::Paper) => each(&|p| vec![p.0.clone()]),
                    (Metric::Freshness, _) => each(&|p| vec![p.1.clone()]),
                };
                let sums = match (a, m, self.mode()) {
                    (Anchor::Read, _, _) => read,
                    // The sound reaction from the event: its own sum.
                    (Anchor::Event, Metric::Reaction, Mode::Sound) => each(&|p| vec![p.2.clone()]),
                    (Anchor::Event, _, _) => {
                        read.into_iter().map(|s| s.plus_period(head)).collect()
                    }
                };
                out.push(SplitLimit {
                    key: (index * Anchor::ALL.len() + anchor) as u32,
                    limit: limit as f64,
                    sums,
                });
            }
        }
        out
    }

    /// The analysis of one point, and whether it meets the active groups
    /// (and, in sound mode, bounds every chain).
    pub(crate) fn verify(&self, k: &[u32]) -> (Spec, Report, bool) {
        let periods = self.periods(k);
        let spec = self.p.with_periods(&periods);
        let report = rtpipe_analysis::analyze(&spec);
        let mode = self.mode();
        let harmonic = !self.p.spec.harmonic || harmonic::all_pairs(&periods);
        let bounded = mode == Mode::Paper
            || report
                .chains
                .iter()
                .all(|c| c.bound.sound(rtpipe_analysis::Anchor::Read).is_some());
        let ok = harmonic
            && bounded
            && self.groups.iter().all(|g| match *g {
                Group::Limit(k, m) => report
                    .chains
                    .iter()
                    .filter(|c| c.chain == k && c.metric == m)
                    .all(|c| c.ok_in(mode)),
                Group::Sched(cpu) => report
                    .schedulability
                    .cpus
                    .iter()
                    .filter(|v| v.cpu == cpu)
                    .all(|v| v.schedulable),
            });
        (spec, report, ok)
    }

    /// Narrows the box in place and sets its bound; false when it holds
    /// nothing feasible that can beat `best`.
    fn narrow(&self, node: &mut Node, best: Option<f64>) -> bool {
        if self.events {
            return self.narrow_events(node, best);
        }
        for _ in 0..NARROW_ROUNDS {
            if !self.enforce_orders(node) {
                return false;
            }
            if self.p.spec.harmonic && !harmonic::propagate(&self.axes, node) {
                return false;
            }
            if let Some(u) = best {
                if self.raise_lows(node, u).is_none() {
                    return false;
                }
            }
            let (lo, hi) = (self.periods(&node.lo), self.periods(&node.hi));
            let r = relax(self.p.spec, &lo, &hi, &node.above, true);
            if !self.may_hold(&r, &lo) {
                return false;
            }
            let Some((bound, shares)) = self.form_bound(&r, (&lo, &hi), node) else {
                return false;
            };
            // A sub-box of the box whose bound it carries: both hold.
            node.bound = node.bound.max(bound);
            node.shares = shares;
            if beaten(bound, best) {
                return false;
            }
            let raised = match self.raise_to_responses(node, &r) {
                None => return false,
                Some(x) => x,
            };
            match self.cut_by_forms(node, &r, &lo) {
                None => return false,
                Some(false) if !raised => return true,
                _ => {}
            }
        }
        // The last cut's box: its bound is at least the one set above.
        node.bound = node.bound.max(self.bound(&node.hi));
        true
    }

    /// `narrow` for a spec with threads or data-triggered tasks, with only
    /// what stays a lower bound of its analysis (`events`): the from-event
    /// caps on source periods, and the utilisation against `best`.
    fn narrow_events(&self, node: &mut Node, best: Option<f64>) -> bool {
        if self.p.spec.harmonic && !harmonic::propagate(&self.axes, node) {
            return false;
        }
        for (i, cap) in self.caps.iter().enumerate() {
            let Some(cap) = *cap else { continue };
            if self.axes[i].value(node.hi[i]) <= cap {
                continue;
            }
            match self.axes[i].last_at_most(cap) {
                Some(k) if k >= node.lo[i] => node.hi[i] = k,
                _ => return false,
            }
        }
        if let Some(u) = best {
            if self.raise_lows(node, u).is_none() {
                return false;
            }
        }
        node.bound = node.bound.max(self.bound(&node.hi));
        !beaten(node.bound, best)
    }

    /// Periods shorter than a response time's lower bound fail where that
    /// response time must fit its period: at job level for chain tasks in
    /// sound mode (a chain needs them bounded), at budget level under RTA.
    /// Raises each interval's bottom past them; `None` when one empties.
    fn raise_to_responses(&self, node: &mut Node, r: &Relaxed) -> Option<bool> {
        let spec = self.p.spec;
        let rta = spec.schedulability == rtpipe_model::SchedTest::Rta;
        let sound = self.mode() == Mode::Sound;
        let mut changed = false;
        for i in 0..node.lo.len() {
            let need = [
                (sound && self.p.on_chain[i], r.job_response[i]),
                (
                    rta && spec.tasks[i].server != Server::Background,
                    r.budget_response[i],
                ),
            ];
            for (applies, least) in need {
                let Some(least) = least.filter(|_| applies) else {
                    continue;
                };
                let k = self.axes[i].first_at_least(least as f64);
                if k > node.hi[i] {
                    return None;
                }
                if k > node.lo[i] {
                    node.lo[i] = k;
                    changed = true;
                }
            }
        }
        Some(changed)
    }

    /// Cuts from the top of every task's interval the periods at which some
    /// limit's affine forms exceed it even with every other period at its
    /// shortest; `None` when an interval empties, else whether any moved.
    fn cut_by_forms(&self, node: &mut Node, r: &Relaxed, lo: &[Nanos]) -> Option<bool> {
        let mut changed = false;
        for g in self.groups {
            let Group::Limit(k, metric) = *g else {
                continue;
            };
            let Some(limits) = self.limit_forms(r, lo, k, metric) else {
                continue;
            };
            for (limit, forms) in &limits {
                if !self.cut_one(node, forms, *limit, lo, &mut changed) {
                    return None;
                }
            }
        }
        Some(changed)
    }

    /// `cut_by_forms` for one limit and its forms; false when an interval
    /// empties.
    fn cut_one(
        &self,
        node: &mut Node,
        forms: &[Affine],
        limit: f64,
        lo: &[Nanos],
        changed: &mut bool,
    ) -> bool {
        let n = node.lo.len();
        // The longest period each task may have: the most any form allows.
        let mut allow = vec![f64::NEG_INFINITY; n];
        for a in forms {
            if a.base > limit {
                continue;
            }
            let mut slope = vec![0.0; n];
            a.slopes.iter().for_each(|&(i, s)| slope[i] += s);
            for (i, (cap, &s)) in allow.iter_mut().zip(&slope).enumerate() {
                let room = if s > 0.0 {
                    lo[i] as f64 + (limit - a.base) / s
                } else {
                    f64::INFINITY
                };
                *cap = cap.max(room);
            }
        }
        for (i, &cap) in allow.iter().enumerate() {
            if cap >= self.axes[i].value(node.hi[i]) as f64 {
                continue;
            }
            match self.axes[i].last_at_most(cap.floor().max(-1.0) as Nanos) {
                Some(k) if k >= node.lo[i] => {
                    node.hi[i] = k;
                    *changed = true;
                }
                _ => return false,
            }
        }
        true
    }

    /// The box's bound: Σ C/hi, raised by each chain limit whose affine
    /// forms (`Relaxed::forms`) keep the periods of its tasks from all
    /// being longest. `None` when some limit cannot hold in the box.
    fn form_bound(
        &self,
        r: &Relaxed,
        (lo, hi): (&[Nanos], &[Nanos]),
        node: &Node,
    ) -> Option<(f64, Shares)> {
        let plain = self.utilization_at(hi);
        let mut bound = plain;
        let mut joint = Vec::new();
        for g in self.groups {
            let Group::Limit(k, metric) = *g else {
                continue;
            };
            for (limit, forms) in self.limit_forms(r, lo, k, metric)? {
                let b = forms
                    .iter()
                    .filter_map(|a| least_under(&self.budget, a, limit, lo, hi))
                    .min_by(f64::total_cmp)?;
                bound = bound.max(b);
                let refs: Vec<&Affine> = forms.iter().collect();
                joint.push(Row::new(&refs, limit, lo, lo.len()));
            }
        }
        let jb = joint_bound(&self.budget, &joint, lo, hi);
        let sums = self.limit_sums(r, (lo, hi), &node.above);
        let start = (&node.shares, self.root_share_rounds());
        let split = split_bound(&self.budget, &sums, lo, hi, start)?;
        Some((bound.max(jb).max(split.bound), split.shares))
    }

    /// Periods so short that the bound cannot beat `u`: C_i/T_i must stay
    /// below u minus everyone else's least utilisation.
    fn raise_lows(&self, node: &mut Node, u: f64) -> Option<bool> {
        let total = self.bound(&node.hi);
        if total >= u * (1.0 - GAP_TOLERANCE) {
            return None;
        }
        let mut changed = false;
        for i in 0..node.lo.len() {
            if node.lo[i] == node.hi[i] || self.budget[i] == 0.0 {
                continue;
            }
            let own = self.budget[i] / self.axes[i].value(node.hi[i]) as f64;
            let room = u - (total - own);
            debug_assert!(room > 0.0);
            let k = self.axes[i].first_at_least(self.budget[i] / room);
            if k > node.lo[i] {
                if k > node.hi[i] {
                    return None;
                }
                node.lo[i] = k;
                changed = true;
            }
        }
        Some(changed)
    }

    /// How to split a box whose corner fails: on the rank order of two
    /// tasks of a failing constraint that the box leaves open (a response
    /// time there jumps with the order, which no box split separates), else
    /// on the period of one task.
    fn branch(&self, node: &Node, report: &Report) -> Option<Branching> {
        let blamed = self.blamed(node, report);
        let split = self.split_task(node, &blamed);
        let widest = split.map_or(0.0, |i| self.span(node, i));
        // An order is worth a branch once the pair's narrower interval is
        // about as wide as the widest split (else splitting that period
        // first often separates the pair anyway).
        let order = self
            .open_order(node, &blamed)
            .filter(|&(a, b)| self.span(node, a).min(self.span(node, b)) >= ORDER_FIRST * widest);
        if let Some(pair) = order {
            return Some(Branching::Order(pair));
        }
        match split {
            Some(i) => Some(Branching::Split(i)),
            None => Some(Branching::Order(self.open_order(node, &blamed)?)),
        }
    }

    /// The two halves of `node` by branching `b`.
    pub(crate) fn children(&self, node: &Node, b: Branching) -> (Node, Node) {
        match b {
            Branching::Order(pair) => Self::ordered(node, pair),
            Branching::Split(i) => self.split(node, i),
        }
    }

    /// Examines `node`: drops it when it cannot beat `incumbent`, narrows
    /// it, then checks the corner of its longest periods: if that verifies,
    /// nothing in the box is better; otherwise says how to split it. Pure,
    /// so the halves of a split are examined in parallel.
    pub(crate) fn examine(&self, mut node: Node, incumbent: Option<f64>) -> Fate {
        if beaten(node.bound, incumbent) || !self.narrow(&mut node, incumbent) {
            return Fate::Pruned;
        }
        let (spec, report, ok) = self.verify(&node.hi);
        if ok {
            let u = utilization(&spec);
            return Fate::Verified(node, Box::new((spec, report)), u);
        }
        match self.branch(&node, &report) {
            Some(b) => Fate::Open(node, b),
            None => Fate::Pruned, // a single point that fails
        }
    }

    /// The two children of an order branch: a above b, and b above a.
    fn ordered(node: &Node, (a, b): (usize, usize)) -> (Node, Node) {
        // Exactly one more order each (a push would double the capacity,
        // and the orders are most of an open box's memory).
        let mut ab = node.clone();
        ab.above.reserve_exact(1);
        ab.above.push((a, b));
        let mut ba = node.clone();
        ba.above.reserve_exact(1);
        ba.above.push((b, a));
        (ab, ba)
    }

    /// A pair on one CPU under fixed priorities, one of them blamed, whose
    /// order the box and the imposed orders leave open (their rank keys'
    /// intervals overlap): the widest narrower span first.
    fn open_order(&self, node: &Node, blamed: &[bool]) -> Option<(usize, usize)> {
        let spec = self.p.spec;
        if !spec.policy().fixed_priority() {
            return None;
        }
        let ranked = |i: usize| spec.tasks[i].server != Server::Background;
        let v = |i: usize, k: u32| (self.key(i, k).0, i);
        let mut best: Option<((usize, usize), f64)> = None;
        for a in 0..node.lo.len() {
            for b in a + 1..node.lo.len() {
                let open = ranked(a)
                    && ranked(b)
                    && (blamed[a] || blamed[b])
                    && spec.tasks[a].cpu == spec.tasks[b].cpu
                    && v(a, node.lo[a]) < v(b, node.hi[b])
                    && v(b, node.lo[b]) < v(a, node.hi[a])
                    && !node.above.contains(&(a, b))
                    && !node.above.contains(&(b, a));
                if open {
                    let w = self.span(node, a).min(self.span(node, b));
                    if best.is_none_or(|(_, x)| w > x) {
                        best = Some(((a, b), w));
                    }
                }
            }
        }
        best.map(|(p, _)| p)
    }

    fn span(&self, node: &Node, i: usize) -> f64 {
        let a = &self.axes[i];
        self.budget[i] / a.value(node.lo[i]) as f64 - self.budget[i] / a.value(node.hi[i]) as f64
    }

    /// Tasks of a constraint the corner fails.
    fn blamed(&self, node: &Node, report: &Report) -> Vec<bool> {
        let spec = self.p.spec;
        let mut blamed = vec![false; node.lo.len()];
        for c in &report.chains {
            if !c.ok {
                spec.chains[c.chain]
                    .path
                    .iter()
                    .for_each(|&i| blamed[i] = true);
            }
        }
        for v in report.schedulability.cpus.iter().filter(|v| !v.schedulable) {
            for (i, t) in spec.tasks.iter().enumerate() {
                blamed[i] |= t.cpu == v.cpu;
            }
        }
        if self.events {
            crate::events::blame_triggers(spec, &mut blamed);
        }
        // A corner the analysis accepts but that breaks a harmonic pair:
        // the split goes to the tasks of the broken pairs.
        if spec.harmonic && !blamed.contains(&true) {
            return harmonic::broken(&self.periods(&node.hi));
        }
        blamed
    }

    /// The task to split: the widest utilisation span among the blamed
    /// tasks (any task with room otherwise).
    fn split_task(&self, node: &Node, blamed: &[bool]) -> Option<usize> {
        let span = |i: usize| self.span(node, i);
        let open = |i: &usize| node.lo[*i] < node.hi[*i];
        let pick = |only_blamed: bool| {
            (0..node.lo.len())
                .filter(open)
                .filter(|&i| !only_blamed || blamed[i])
                .max_by(|&a, &b| span(a).total_cmp(&span(b)).then(b.cmp(&a)))
        };
        pick(true).or_else(|| pick(false))
    }

    /// Splits task i's interval at its utilisation midpoint (the harmonic
    /// mean of its ends).
    fn split(&self, node: &Node, i: usize) -> (Node, Node) {
        let a = &self.axes[i];
        let (l, h) = (a.value(node.lo[i]) as f64, a.value(node.hi[i]) as f64);
        let mid = 2.0 * l * h / (l + h);
        let k = a
            .first_at_least(mid)
            .saturating_sub(1)
            .clamp(node.lo[i], node.hi[i] - 1);
        let mut low = node.clone();
        low.hi[i] = k;
        // A sub-box: the parent's bound holds for it too.
        low.bound = self.bound(&low.hi).max(node.bound);
        let mut high = node.clone();
        high.lo[i] = k + 1;
        (low, high)
    }

    /// A verified point near the frontier below `node`: follow the low child
    /// of the split (shorter periods) until the corner verifies, then
    /// lengthen each period as far as the design still verifies. Asks
    /// `budget` at every step: on 600 tasks a dive is thousands of
    /// analyses (`design --time-limit 1` once ran 16 s in one).
    pub(crate) fn dive(
        &self,
        node: &Node,
        best: Option<f64>,
        budget: &Budget,
    ) -> Option<(Spec, Report, f64)> {
        let mut node = node.clone();
        for _ in 0..256 {
            if budget.out_of_time() || !self.narrow(&mut node, best) {
                return None;
            }
            let (spec, report, ok) = self.verify(&node.hi);
            if ok {
                let k = self.polish(node.hi.clone(), budget);
                let (spec, report, ok) = if k == node.hi {
                    (spec, report, ok)
                } else {
                    self.verify(&k)
                };
                debug_assert!(ok);
                let u = utilization(&spec);
                return best.is_none_or(|b| u < b).then_some((spec, report, u));
            }
            let b = self.branch(&node, &report)?;
            node = self.children(&node, b).0;
        }
        None
    }

    /// A verified design from the relaxation's least point of `node`
    /// (repair and round): each period of a limited task at the shortest
    /// its limits' least asks (`split_bound`'s guide, from the shares the
    /// box carries), the others at their longest; those periods scaled
    /// down (by 0.85, up to 30 times) until the design verifies, then
    /// lengthened by `polish`. `None` without a guide, a verified design
    /// or one better than `best`.
    pub(crate) fn guided(
        &self,
        node: &Node,
        best: Option<f64>,
        budget: &Budget,
    ) -> Option<(Spec, Report, f64)> {
        if self.events || self.p.spec.harmonic {
            return None;
        }
        let (lo, hi) = (self.periods(&node.lo), self.periods(&node.hi));
        let r = relax(self.p.spec, &lo, &hi, &node.above, true);
        let sums = self.limit_sums(&r, (&lo, &hi), &node.above);
        let start = (&node.shares, self.root_share_rounds());
        let guide = split_bound(&self.budget, &sums, &lo, &hi, start)?.guide;
        if guide.iter().all(Option::is_none) {
            return None;
        }
        let mut scale = 1.0;
        for _ in 0..30 {
            if budget.out_of_time() {
                return None;
            }
            let k: Vec<u32> = (0..lo.len())
                .map(|i| match guide[i] {
                    None => node.hi[i],
                    Some(t) => self.axes[i]
                        .last_at_most((t * scale) as Nanos)
                        .unwrap_or(0)
                        .clamp(node.lo[i], node.hi[i]),
                })
                .collect();
            if self.verify(&k).2 {
                let (spec, report, ok) = self.verify(&self.polish(k, budget));
                let u = utilization(&spec);
                return (ok && best.is_none_or(|b| u < b)).then_some((spec, report, u));
            }
            scale *= 0.85;
        }
        None
    }

    /// Lengthens each period (largest utilisation first) by bisection over
    /// the values that keep the design verified; `k` must verify, and so
    /// does the answer, also when `budget` runs out on the way.
    fn polish(&self, mut k: Vec<u32>, budget: &Budget) -> Vec<u32> {
        for _ in 0..3 {
            let mut moved = false;
            let mut order: Vec<usize> = (0..k.len()).collect();
            let u = |i: usize| self.budget[i] / self.axes[i].value(k[i]) as f64;
            order.sort_by(|&a, &b| u(b).total_cmp(&u(a)));
            for i in order {
                if budget.out_of_time() {
                    return k;
                }
                let from = k[i];
                moved |= self.lengthen(&mut k, i) != from;
            }
            if !moved {
                break;
            }
        }
        k
    }

    /// The longest period index for task i found by bisection over the
    /// values it may move to (under `harmonic`, those harmonic with every
    /// other period of `k`) with the design still verified, left in
    /// `k[i]`; `k` verifies, and so does it after.
    pub(crate) fn lengthen(&self, k: &mut [u32], i: usize) -> u32 {
        let from = k[i];
        let ups = self
            .p
            .spec
            .harmonic
            .then(|| harmonic::moves_up(&self.axes, k, i));
        let at = |x: u32| match &ups {
            None => from + x,
            Some(_) if x == 0 => from,
            Some(u) => u[x as usize - 1],
        };
        let count = ups
            .as_ref()
            .map_or(self.axes[i].len() - from, |u| u.len() as u32 + 1);
        // Invariant: position a verifies; the search is for a longer one.
        let (mut a, mut b) = (0, count);
        while b - a > 1 {
            let m = a + (b - a) / 2;
            k[i] = at(m);
            if self.verify(k).2 {
                a = m;
            } else {
                b = m;
            }
        }
        k[i] = at(a);
        k[i]
    }

    /// The axis index of every period of `spec` (on the grid).
    pub(crate) fn indices(&self, spec: &Spec) -> Vec<u32> {
        spec.tasks
            .iter()
            .zip(&self.axes)
            .map(|(t, a)| a.first_at_least(t.fixed_period().unwrap_or(0) as f64))
            .collect()
    }
}
