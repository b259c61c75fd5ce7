//! The box search's loop: the open boxes, best bound first, and the best
//! verified design (`bnb` examines a box; this decides what becomes of it).
//!
//! Each box on the frontier was examined when it was made: it is narrowed,
//! its corner failed, and how to split it is known. A round takes the
//! [`ROUND`] best boxes and splits them; their halves are examined in
//! parallel (rayon) against the incumbent of that moment, then settled in
//! order. Every examination is a pure function of the box and that
//! incumbent, and the round's size is a constant, so the search is the
//! same on any number of cores: the same boxes, the same answer and bound
//! for a given work budget (tests/parallel.rs).

use crate::api::{Checked, Incumbent};
use crate::axis::Node;
use crate::bnb::{beaten, Branching, Examiner, Fate};
use crate::budget::Budget;
use crate::gate::{Gate, Verdict};
use crate::problem::{Group, Problem};
use crate::trade::Trades;
use rayon::prelude::*;
use rtpipe_analysis::Report;
use rtpipe_model::Spec;
use std::cmp::Ordering as CmpOrdering;
use std::collections::BinaryHeap;
use std::ops::ControlFlow;

/// Most bytes the open boxes may take (`Node::bytes`, counted from their
/// sizes, so the same on every machine): the search stops there with its
/// best design and bound, as at a time limit.
pub const MAX_OPEN_BYTES: usize = 1 << 30;

/// A dive for a better verified design every this many boxes split.
const DIVE_EVERY: u64 = 32;

/// Calls of [`Examiner::trade`] at each dive: the trades and kicks walk
/// towards better designs while the bound, on wide boxes, hardly moves
/// (docs/design.md, "Kicks: the design side of the gap").
const TRADE_CALLS: usize = 8;

/// Boxes taken from the frontier per round: the halves of those split are
/// examined together, in parallel. A constant, not the number of cores, so
/// that the search is the same on every machine; small, since the boxes of
/// a round cannot use each other's designs to prune.
const ROUND: usize = 4;

/// Progress is said every this many boxes split.
const SAY_EVERY: u64 = 128;

/// What the box search ended with.
pub(crate) struct BoxResult {
    /// The best verified design: the spec with its periods, the analysis, U.
    pub(crate) best: Option<(Spec, Report, f64)>,
    /// A proven lower bound on the optimum (over the active groups).
    pub(crate) lower_bound: f64,
    /// Every box was decided: `best` is optimal, or there is none.
    pub(crate) complete: bool,
    /// Boxes examined.
    pub(crate) nodes: u64,
    /// The most boxes held open at once (memory: each holds two indices
    /// per task).
    pub(crate) peak_open: usize,
    /// The most bytes they took at once (`Node::bytes`).
    pub(crate) peak_bytes: usize,
    /// Every design the acceptance check judged (`Options::accept`).
    pub(crate) checked: Vec<Checked>,
    /// Seconds from the design's start to the first verified design held.
    pub(crate) first_at: Option<f64>,
}

/// What taking an open box does.
#[derive(Clone, Copy)]
enum Next {
    /// Its corner failed: split it so.
    Split(Branching),
    /// Its corner verified (U = its bound): check it with the gate, in
    /// best-first order, so that the first design accepted is the best.
    Check,
    /// Put back when the search stopped: it counts for the lower bound.
    Stopped,
}

/// An open box, examined.
struct Open {
    node: Node,
    next: Next,
}

impl Open {
    fn bytes(&self) -> usize {
        self.node.bytes() + std::mem::size_of::<Next>()
    }
}

impl PartialEq for Open {
    fn eq(&self, o: &Self) -> bool {
        self.node == o.node
    }
}
impl Eq for Open {}
impl PartialOrd for Open {
    fn partial_cmp(&self, o: &Self) -> Option<CmpOrdering> {
        Some(self.cmp(o))
    }
}
impl Ord for Open {
    fn cmp(&self, o: &Self) -> CmpOrdering {
        self.node.cmp(&o.node)
    }
}

/// The state of a running box search: the best design so far and the boxes
/// still to split.
struct Frontier {
    /// The best verified design so far: its spec, analysis and U.
    best: Option<(Spec, Report, f64)>,
    /// The open boxes, smallest bound first.
    open: BinaryHeap<Open>,
    /// Boxes examined.
    nodes: u64,
    /// Boxes taken and split.
    splits: u64,
    /// The most boxes open at once.
    peak_open: usize,
    /// The time ran out with boxes still open.
    stopped: bool,
    /// The bytes the open boxes take.
    open_bytes: usize,
    /// When the first verified design was held (`Budget::elapsed`).
    first_at: Option<f64>,
    /// The most bytes they took at once.
    peak_bytes: usize,
}

impl Frontier {
    fn new(best: Option<(Spec, Report, f64)>) -> Self {
        Frontier {
            best,
            open: BinaryHeap::new(),
            nodes: 0,
            splits: 0,
            peak_open: 0,
            stopped: false,
            open_bytes: 0,
            first_at: None,
            peak_bytes: 0,
        }
    }

    fn incumbent(&self) -> Option<f64> {
        self.best.as_ref().map(|b| b.2)
    }

    fn push(&mut self, node: Node, next: Next) {
        let open = Open { node, next };
        self.open_bytes += open.bytes();
        self.open.push(open);
        self.peak_open = self.peak_open.max(self.open.len());
        self.peak_bytes = self.peak_bytes.max(self.open_bytes);
    }

    fn pop(&mut self) -> Option<Open> {
        let open = self.open.pop()?;
        self.open_bytes -= open.bytes();
        Some(open)
    }

    /// The least bound of the open boxes and `floor`.
    fn least_open(&self, floor: f64) -> f64 {
        self.open.iter().map(|o| o.node.bound).fold(floor, f64::min)
    }

    /// What the search proved: the best design, and as the lower bound the
    /// least bound of the boxes still open (or the best design's U, if
    /// smaller; 0 when there is neither).
    fn result(self, checked: Vec<Checked>) -> BoxResult {
        let open_bound = self.least_open(f64::INFINITY);
        let lower_bound = match &self.best {
            Some((_, _, u)) => open_bound.min(*u),
            None => open_bound,
        };
        BoxResult {
            best: self.best,
            lower_bound: if lower_bound.is_finite() {
                lower_bound
            } else {
                0.0
            },
            complete: !self.stopped,
            nodes: self.nodes,
            peak_open: self.peak_open,
            peak_bytes: self.peak_bytes,
            checked,
            first_at: self.first_at,
        }
    }

    /// Notes the time of the first verified design held.
    fn note_first(&mut self, effort: &Budget) {
        if self.first_at.is_none() && self.best.is_some() {
            self.first_at = Some(effort.elapsed());
        }
    }
}

/// A box search: the examiner, the budget each examined box spends, and
/// the acceptance check, if any.
struct BoxSearch<'r, 'a> {
    ex: Examiner<'r, 'a>,
    /// Each box examined is one unit of work.
    effort: &'r mut Budget,
    /// Stop at the first verified design (a feasibility probe).
    first_only: bool,
    /// The check beyond the analysis a design must pass, if any.
    gate: Option<Gate>,
    /// Where trading periods along the chains stands (`Examiner::trade`).
    trades: Trades,
}

impl<'r, 'a> BoxSearch<'r, 'a> {
    fn new(p: &'r Problem<'a>, effort: &'r mut Budget, groups: &'r [Group]) -> Self {
        BoxSearch {
            ex: Examiner::new(p, groups),
            effort,
            first_only: false,
            gate: p.opts.accept.clone().map(Gate::new),
            trades: Trades::default(),
        }
    }

    /// The gate's verdict on the verified point `k` (accepted without one).
    fn judge(&mut self, k: &[u32], spec: &Spec) -> Verdict {
        match &mut self.gate {
            None => Verdict::Accepted,
            Some(g) => g.judge(&self.ex.axes, k, spec),
        }
    }

    /// Runs the search from the whole domain, starting from `seed` (a
    /// verified design, if any).
    fn run(&mut self, seed: Option<(Spec, Report, f64)>) -> BoxResult {
        let n = self.ex.axes.len();
        let mut root = Node {
            lo: vec![0; n],
            hi: self.ex.axes.iter().map(|a| a.len() - 1).collect(),
            above: Vec::new(),
            shares: Default::default(),
            bound: 0.0,
        };
        root.bound = self.ex.bound(&root.hi);
        let mut f = Frontier::new(seed);
        if let Some((spec, _, _)) = &f.best {
            let k = self.ex.indices(spec);
            if !matches!(self.judge(&k, spec), Verdict::Accepted) {
                f.best = None;
            }
        }
        f.note_first(self.effort);
        let floor = root.bound;
        if self.effort.out_of_clock() {
            // Out of time before the root was examined (the first design's
            // local search, an earlier probe of the conflict search): one
            // narrowing of the root of 1,200 tasks costs ~0.1 s, a conflict
            // search probes once per group. The root stays open; its bound
            // is the lower bound. Spent work alone still examines the root,
            // as it always did: answers under a work budget stay the same.
            f.push(root, Next::Stopped);
            f.stopped = true;
            let checked = self.gate.take().map_or(Vec::new(), |g| g.log);
            return f.result(checked);
        }
        let mut flow = self.examine_all(&mut f, floor, vec![root]);
        f.note_first(self.effort);
        while flow.is_continue() && !f.open.is_empty() {
            flow = self.round(&mut f);
            f.note_first(self.effort);
        }
        let checked = self.gate.take().map_or(Vec::new(), |g| g.log);
        f.result(checked)
    }

    /// One round: takes up to [`ROUND`] boxes from the frontier, best
    /// first, and examines the halves of those it splits together. Breaks
    /// when the search must stop; halves not examined then go back to the
    /// frontier with their parents' bounds.
    fn round(&mut self, f: &mut Frontier) -> ControlFlow<()> {
        let mut halves = Vec::with_capacity(2 * ROUND);
        // The first box taken has the least bound of all not yet examined.
        let floor = f.open.peek().map_or(0.0, |o| o.node.bound);
        let mut taken = 0;
        while taken < ROUND {
            // A verified corner is checked only when it has the least bound
            // of all, as in a one-box-at-a-time search (each check may be
            // flights): not after boxes whose halves are not examined yet.
            if taken > 0 && f.open.peek().is_some_and(|o| matches!(o.next, Next::Check)) {
                break;
            }
            let Some(open) = f.pop() else { break };
            taken += 1;
            match self.take(f, open) {
                ControlFlow::Continue(None) => {}
                ControlFlow::Continue(Some((low, high))) => halves.extend([low, high]),
                ControlFlow::Break(()) => {
                    halves.into_iter().for_each(|h| f.push(h, Next::Stopped));
                    return ControlFlow::Break(());
                }
            }
        }
        self.examine_all(f, floor, halves)
    }

    /// Takes the open box `open`: drops it when it can no longer beat the
    /// best design; a verified corner goes to the gate; otherwise, now and
    /// then dives from it for a better design, then splits it into the
    /// halves returned. Breaks when the search must stop (out of time or
    /// memory: the box goes back to the frontier, whose bounds still count
    /// for the lower bound).
    fn take(&mut self, f: &mut Frontier, open: Open) -> ControlFlow<(), Option<(Node, Node)>> {
        let Open { node, next } = open;
        let incumbent = f.incumbent();
        if beaten(node.bound, incumbent) {
            return ControlFlow::Continue(None);
        }
        let full = f.open_bytes > MAX_OPEN_BYTES;
        let exhausted = self.gate.as_ref().is_some_and(|g| g.exhausted());
        if full || exhausted || self.effort.out_of_time() || matches!(next, Next::Stopped) {
            self.effort.memory_full |= full;
            f.push(node, Next::Stopped);
            f.stopped = true;
            return ControlFlow::Break(());
        }
        let Next::Split(how) = next else {
            let (spec, report, ok) = self.ex.verify(&node.hi);
            assert!(ok, "a verified corner no longer verifies");
            let u = node.bound;
            return self
                .accept(f, node, (spec, report, u))
                .map_continue(|()| None);
        };
        f.splits += 1;
        if f.splits % SAY_EVERY == 1 {
            self.progress(f, node.bound, incumbent);
        }
        // With a gate every dive's design would be checked (flown): the
        // best-first order alone reaches the answer with fewer checks.
        if f.splits % DIVE_EVERY == 1 && self.gate.is_none() {
            let dived = self.ex.dive(&node, incumbent, self.effort);
            self.adopt(f, "dive", dived, node.bound);
            // And from the relaxation's least point of the box.
            let guided = self.ex.guided(&node, f.incumbent(), self.effort);
            self.adopt(f, "guided", guided, node.bound);
            // And by trading periods along a chain from the incumbent,
            // or from a kick of it once every trade there has failed.
            for _ in 0..TRADE_CALLS {
                let traded = match (&f.best, self.first_only) {
                    (Some(best), false) => self.ex.trade(best, &mut self.trades, self.effort),
                    _ => None,
                };
                self.adopt(f, "trade", traded, node.bound);
            }
        }
        ControlFlow::Continue(Some(self.ex.children(&node, how)))
    }

    /// Examines `boxes` in parallel against the incumbent of now, then
    /// settles each in order. `floor` is at most the bound of every box
    /// not yet on the frontier (the parent's).
    fn examine_all(&mut self, f: &mut Frontier, floor: f64, boxes: Vec<Node>) -> ControlFlow<()> {
        let incumbent = f.incumbent();
        let ex = &self.ex;
        let fates: Vec<Fate> = boxes
            .into_par_iter()
            .map(|n| ex.examine(n, incumbent))
            .collect();
        f.nodes += fates.len() as u64;
        self.effort.work += fates.len() as u64;
        for fate in fates {
            self.settle(f, floor, fate)?;
        }
        ControlFlow::Continue(())
    }

    /// What becomes of an examined box: a failing one joins the frontier; a
    /// verified corner may be the new best design (with a gate, once it is
    /// taken from the frontier in best-first order). `floor` is at most the
    /// bound of every box not yet on the frontier.
    fn settle(&mut self, f: &mut Frontier, floor: f64, fate: Fate) -> ControlFlow<()> {
        match fate {
            Fate::Pruned => ControlFlow::Continue(()),
            Fate::Open(node, how) => {
                f.push(node, Next::Split(how));
                ControlFlow::Continue(())
            }
            Fate::Verified(mut node, found, u) => {
                let (spec, report) = *found;
                if self.gate.is_some() {
                    // U is the box's least value: it is its bound.
                    node.bound = u;
                    f.push(node, Next::Check);
                    return ControlFlow::Continue(());
                }
                if f.incumbent().is_none_or(|b| u < b) {
                    publish(self.ex.p, &spec, u, f.least_open(floor));
                    f.best = Some((spec, report, u));
                }
                // A feasibility probe stops at its first verified design.
                if self.first_only {
                    return ControlFlow::Break(());
                }
                ControlFlow::Continue(())
            }
        }
    }

    /// The gate's judgement of the verified design `found` of box `node`,
    /// taken from the frontier: the new best design if accepted, else the
    /// parts of the box outside the cut are examined.
    fn accept(
        &mut self,
        f: &mut Frontier,
        node: Node,
        found: (Spec, Report, f64),
    ) -> ControlFlow<()> {
        match self.judge(&node.hi, &found.0) {
            Verdict::Accepted => {
                publish(self.ex.p, &found.0, found.2, f.least_open(node.bound));
                f.best = Some(found);
                ControlFlow::Continue(())
            }
            Verdict::Cut(c) => self.examine_outside(f, &node, c),
            Verdict::Exhausted => {
                f.push(node, Next::Stopped);
                f.stopped = true;
                ControlFlow::Break(())
            }
        }
    }

    /// Examines the parts of `node` outside cut `c`.
    fn examine_outside(&mut self, f: &mut Frontier, node: &Node, c: usize) -> ControlFlow<()> {
        let Some(g) = &self.gate else {
            return ControlFlow::Continue(());
        };
        let parts = g.outside(node, c);
        let parts = parts
            .into_iter()
            .map(|mut part| {
                part.bound = self.ex.bound(&part.hi).max(node.bound);
                part
            })
            .collect();
        self.examine_all(f, node.bound, parts)
    }

    /// A better verified design found by `how` (a dive, a guided design,
    /// a trade), if any, made the incumbent and published with the lower
    /// bound `bound`.
    fn adopt(&self, f: &mut Frontier, how: &str, found: Option<(Spec, Report, f64)>, bound: f64) {
        if let Some(found) = found {
            self.debug(how, found.2);
            publish(self.ex.p, &found.0, found.2, bound);
            f.best = Some(found);
        }
    }

    /// With `RTPIPE_DESIGN_DEBUG` set, which step found a better design
    /// (`how`), its U and when (for measuring how designs are found).
    fn debug(&self, how: &str, u: f64) {
        if crate::problem::debug() {
            eprintln!(
                "incumbent by {how}: U {u:.6} ({:.2} s)",
                self.effort.elapsed()
            );
        }
    }

    fn progress(&self, f: &Frontier, bound: f64, best: Option<f64>) {
        let (nodes, open) = (f.nodes, f.open.len());
        self.ex.p.say(|| {
            let best = best.map_or(String::new(), |u| {
                let gap = if u > 0.0 {
                    (u - bound).max(0.0) / u
                } else {
                    0.0
                };
                format!(", best verified U = {u:.4}, gap {:.2} %", 100.0 * gap)
            });
            format!("branch and bound: {nodes} boxes, {open} open, lower bound {bound:.4}{best}")
        });
    }
}

/// The box search of `p` over `groups` from the whole domain, starting from
/// `seed` (a verified design, if any); each box is a unit of `budget`'s
/// work.
pub(crate) fn search(
    p: &Problem,
    budget: &mut Budget,
    groups: &[Group],
    seed: Option<(Spec, Report, f64)>,
) -> BoxResult {
    // The loop runs on a worker of the pool, so that each split's second
    // half waits where the other workers look for work (a join from
    // outside the pool would hand both halves over and wake one).
    rayon::scope(|_| BoxSearch::new(p, budget, groups).run(seed))
}

/// Whether `groups` can hold together: a box search that stops at the
/// first verified design. `None` when it ran out of time or work.
pub(crate) fn probe(p: &Problem, budget: &mut Budget, groups: &[Group]) -> Option<bool> {
    let mut search = BoxSearch::new(p, budget, groups);
    search.first_only = true;
    search.gate = None;
    let r = search.run(None);
    match (r.best, r.complete) {
        (Some(_), _) => Some(true),
        (None, true) => Some(false),
        (None, false) => None,
    }
}

/// Hands a better verified design (its Σ C/T `u`, the least open bound
/// then) to [`Options::incumbent`](crate::api::Options::incumbent), so that a caller that stops
/// waiting (Ctrl-C) can still report it.
pub(crate) fn publish(p: &Problem, spec: &Spec, u: f64, lower_bound: f64) {
    if let Some(sink) = &p.opts.incumbent {
        if let Ok(mut g) = sink.lock() {
            *g = Some(Incumbent {
                periods: crate::gate::periods_ns(spec),
                utilization: u,
                lower_bound: Some(lower_bound),
            });
        }
    }
}
