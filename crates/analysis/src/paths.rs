//! Worst paths between every source and sink, by dynamic programming.
//!
//! Every bound is a head term plus a sum of link terms (Section III-F), so the
//! worst path from a source is a longest path in a DAG: one pass in
//! topological order per source, O(V + E) each, never enumerating paths. The
//! sound reaction term of a link depends on whether the producer's jobs carry
//! distinct samples, so that DP runs on (task, distinct) states.
//!
//! Feedback loops: edges inside a strongly connected component are left out
//! (paths through the acyclic part are simple by construction) and each
//! skipped cycle is named.

use crate::graph::{kahn, strongly_connected};
use crate::latency::{
    distinct_passes, paper_freshness_link, paper_reaction_link, sound_freshness_last,
    sound_freshness_link, sound_reaction_link, LinkTask,
};
use crate::sched::TaskTiming;
use rtpipe_model::{Nanos, Scheduler, Server, Spec};

/// Stands for an unbounded sound value inside the DP.
const INF: Nanos = Nanos::MAX;

fn add(a: Nanos, b: Option<Nanos>) -> Nanos {
    match b {
        Some(b) if a != INF => a.saturating_add(b),
        _ => INF,
    }
}

/// The worst path for one metric and mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Worst {
    /// Task indices, source first.
    pub path: Vec<usize>,
    /// `None`: unbounded (sound mode, a task without a bounded response time).
    pub value: Option<Nanos>,
}

/// The worst paths between one source and one sink.
#[derive(Debug, Clone, PartialEq)]
pub struct PairBounds {
    /// The source task.
    pub source: usize,
    /// The sink task.
    pub sink: usize,
    /// Worst reaction, paper mode.
    pub reaction_paper: Worst,
    /// Worst reaction, sound mode.
    pub reaction_sound: Worst,
    /// Worst freshness, paper mode.
    pub freshness_paper: Worst,
    /// Worst freshness, sound mode.
    pub freshness_sound: Worst,
}

/// Every source-to-sink pair's worst paths.
#[derive(Debug, Clone, PartialEq)]
pub struct AllPaths {
    /// One entry per pair connected by a path.
    pub pairs: Vec<PairBounds>,
    /// Strongly connected components with more than one task, or a task that
    /// reads itself: their inner edges were skipped.
    pub cycles: Vec<Vec<usize>>,
}

/// The task graph without its feedback: the edges inside strongly
/// connected components dropped, in topological order.
struct Acyclic {
    /// Successors outside the own component.
    dag: Vec<Vec<usize>>,
    /// Live tasks in topological order, and each task's place in it.
    order: Vec<usize>,
    pos: Vec<usize>,
    /// Live tasks without a producer in the acyclic part.
    sources: Vec<usize>,
    /// Components with more than one task, or a task that reads itself.
    cycles: Vec<Vec<usize>>,
}

impl Acyclic {
    /// Background tasks are left out: they have no timing guarantee.
    fn new(spec: &Spec) -> Acyclic {
        let n = spec.tasks.len();
        let live = |i: usize| spec.tasks[i].server != Server::Background;
        let mut succ = vec![Vec::new(); n];
        for (p, c) in spec.edges() {
            if live(p) && live(c) {
                succ[p].push(c);
            }
        }
        let comp = strongly_connected(n, &succ);
        let cycles = cycles_of(&comp, &succ);
        let mut dag = vec![Vec::new(); n];
        let mut indeg = vec![0usize; n];
        for p in 0..n {
            for &c in succ[p].iter().filter(|&&c| comp[p] != comp[c]) {
                dag[p].push(c);
                indeg[c] += 1;
            }
        }
        let sources: Vec<usize> = (0..n).filter(|&i| live(i) && indeg[i] == 0).collect();
        let order = kahn(&dag, indeg, &sources);
        let mut pos = vec![usize::MAX; n];
        for (k, &v) in order.iter().enumerate() {
            pos[v] = k;
        }
        Acyclic {
            dag,
            order,
            pos,
            sources,
            cycles,
        }
    }
}

/// The components that form cycles, each as its members.
fn cycles_of(comp: &[usize], succ: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); comp.len()];
    for (v, &c) in comp.iter().enumerate() {
        members[c].push(v);
    }
    members
        .into_iter()
        .filter(|m| m.len() > 1 || (m.len() == 1 && succ[m[0]].contains(&m[0])))
        .collect()
}

const NONE: usize = usize::MAX;

/// One longest-path value per state and the state it came from.
struct Track {
    val: Vec<Nanos>,
    from: Vec<usize>,
}

impl Track {
    fn new(states: usize) -> Track {
        Track {
            val: vec![0; states],
            from: vec![NONE; states],
        }
    }

    fn set(&mut self, at: usize, val: Nanos, from: usize) {
        self.val[at] = val;
        self.from[at] = from;
    }

    /// Keeps the larger value (the first one on ties).
    fn offer(&mut self, at: usize, val: Nanos, from: usize) {
        if val > self.val[at] {
            self.set(at, val, from);
        }
    }

    /// The states back to the start, first to last.
    fn walk(&self, end: usize) -> Vec<usize> {
        let mut path = vec![end];
        let mut cur = end;
        while self.from[cur] != NONE {
            cur = self.from[cur];
            path.push(cur);
        }
        path.reverse();
        path
    }
}

/// The DP's arrays, reused across sources; `stamp` marks what the current
/// source reached.
struct Scratch {
    stamp: Vec<usize>,
    /// Paper reaction and freshness.
    paper_reaction: Track,
    paper_freshness: Track,
    /// Sound freshness to a task's release, and to its publish through the
    /// last link's own term.
    sound_freshness: Track,
    sound_last: Track,
    /// Sound reaction on (task, distinct) states, index 2·task + distinct,
    /// with `sound_reached` marking the states the current source reached.
    sound_reaction: Track,
    sound_reached: Vec<usize>,
}

impl Scratch {
    fn new(n: usize) -> Scratch {
        Scratch {
            stamp: vec![NONE; n],
            paper_reaction: Track::new(n),
            paper_freshness: Track::new(n),
            sound_freshness: Track::new(n),
            sound_last: Track::new(n),
            sound_reaction: Track::new(2 * n),
            sound_reached: vec![NONE; 2 * n],
        }
    }

    /// Starts the DP at source `s`: sums start at its release.
    fn start(&mut self, s: usize, lt: &[LinkTask]) {
        self.stamp[s] = s;
        self.paper_reaction.set(s, lt[s].l, NONE);
        self.paper_freshness.set(s, lt[s].l, NONE);
        self.sound_freshness.set(s, 0, NONE);
        self.sound_reached[2 * s] = NONE;
        self.sound_reaction.set(2 * s + 1, 0, NONE);
        self.sound_reached[2 * s + 1] = s;
    }

    /// Relaxes edge v → c for source `s`.
    fn relax(&mut self, s: usize, v: usize, c: usize, lt: &[LinkTask], sched: Scheduler) {
        let (p, q) = (&lt[v], &lt[c]);
        let cand_pe = self.paper_reaction.val[v] + paper_reaction_link(p, q);
        let cand_pf = self.paper_freshness.val[v] + paper_freshness_link(p, q);
        let cand_sf = add(
            self.sound_freshness.val[v],
            sound_freshness_link(sched, p, q),
        );
        let cand_sl = add(
            self.sound_freshness.val[v],
            sound_freshness_last(sched, p, q),
        );
        if self.stamp[c] != s {
            self.stamp[c] = s;
            self.paper_reaction.set(c, cand_pe, v);
            self.paper_freshness.set(c, cand_pf, v);
            self.sound_freshness.set(c, cand_sf, v);
            self.sound_last.set(c, cand_sl, v);
            self.sound_reached[2 * c] = NONE;
            self.sound_reached[2 * c + 1] = NONE;
        } else {
            self.paper_reaction.offer(c, cand_pe, v);
            self.paper_freshness.offer(c, cand_pf, v);
            self.sound_freshness.offer(c, cand_sf, v);
            self.sound_last.offer(c, cand_sl, v);
        }
        for d in 0..2 {
            let sv = 2 * v + d;
            if self.sound_reached[sv] != s {
                continue;
            }
            let distinct = d == 1;
            // From the source's read: its link's term starts there.
            let cand = add(
                self.sound_reaction.val[sv],
                sound_reaction_link(sched, p, q, distinct, v == s),
            );
            let sc = 2 * c + usize::from(distinct_passes(p, q, distinct));
            if self.sound_reached[sc] != s || cand > self.sound_reaction.val[sc] {
                self.sound_reaction.set(sc, cand, sv);
                self.sound_reached[sc] = s;
            }
        }
    }

    /// The bounds of source `s` and sink `v`, both reached.
    fn pair(&self, s: usize, v: usize, lt: &[LinkTask]) -> PairBounds {
        let fin = |x: Nanos| if x == INF { None } else { Some(x) };
        // A path of one task is its read-to-publish bound; a longer one ends
        // with its last link's term.
        let (fresh, fresh_path) = if v == s {
            (lt[v].read_to_publish(), vec![v])
        } else {
            let mut path = self.sound_freshness.walk(self.sound_last.from[v]);
            path.push(v);
            (fin(self.sound_last.val[v]), path)
        };
        // The worse sound-reaction state at the sink.
        let best = [2 * v, 2 * v + 1]
            .into_iter()
            .filter(|&sv| self.sound_reached[sv] == s)
            .fold(None, |b: Option<usize>, sv| match b {
                Some(b) if self.sound_reaction.val[sv] <= self.sound_reaction.val[b] => Some(b),
                _ => Some(sv),
            });
        let se_path = best.map_or(vec![v], |b| {
            self.sound_reaction
                .walk(b)
                .into_iter()
                .map(|x| x / 2)
                .collect()
        });
        // The tail's read-to-publish or release-to-publish bound (the
        // period under LET).
        let tail = if v == s {
            lt[v].read_to_publish()
        } else {
            lt[v].publish()
        };
        let react = best.and_then(|b| fin(add(self.sound_reaction.val[b], tail)));
        PairBounds {
            source: s,
            sink: v,
            reaction_paper: Worst {
                path: self.paper_reaction.walk(v),
                value: Some(self.paper_reaction.val[v]),
            },
            reaction_sound: Worst {
                path: se_path,
                // First output ≤ last output: the pair's worst freshness
                // bounds the reaction of every path between them too.
                value: match (react, fresh) {
                    (Some(e), Some(f)) => Some(e.min(f)),
                    (e, _) => e,
                },
            },
            freshness_paper: Worst {
                path: self.paper_freshness.walk(v),
                value: Some(self.paper_freshness.val[v]),
            },
            freshness_sound: Worst {
                path: fresh_path,
                value: fresh,
            },
        }
    }
}

/// Worst paths from every source (no producer in the acyclic part) to every
/// sink (no consumer) it reaches. Background tasks are left out: they have
/// no timing guarantee.
pub fn all_paths(spec: &Spec, timing: &[TaskTiming]) -> AllPaths {
    let g = Acyclic::new(spec);
    let lt: Vec<LinkTask> = (0..spec.tasks.len())
        .map(|i| LinkTask::new(spec, timing, i))
        .collect();
    let mut sc = Scratch::new(spec.tasks.len());
    let mut pairs = Vec::new();
    for &s in &g.sources {
        sc.start(s, &lt);
        let reached = &g.order[g.pos[s]..];
        for &v in reached {
            if sc.stamp[v] == s {
                for &c in &g.dag[v] {
                    sc.relax(s, v, c, &lt, spec.scheduler);
                }
            }
        }
        for &v in reached {
            if sc.stamp[v] == s && g.dag[v].is_empty() {
                pairs.push(sc.pair(s, v, &lt));
            }
        }
    }
    AllPaths {
        pairs,
        cycles: g.cycles,
    }
}
