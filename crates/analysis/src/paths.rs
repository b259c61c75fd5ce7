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

use crate::latency::{
    distinct_passes, paper_freshness_link, paper_reaction_link, sound_freshness_last,
    sound_freshness_link, sound_reaction_link, LinkTask,
};
use crate::sched::TaskTiming;
use rtpipe_model::{Nanos, Server, Spec};

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

/// Tarjan's SCC algorithm, iterative so that 10,000-task graphs cannot
/// overflow the stack.
pub fn strongly_connected(n: usize, succ: &[Vec<usize>]) -> Vec<usize> {
    let mut index = vec![usize::MAX; n];
    let mut low = vec![0; n];
    let mut on_stack = vec![false; n];
    let mut comp = vec![usize::MAX; n];
    let mut stack = Vec::new();
    let mut next = 0;
    let mut ncomp = 0;
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        let mut call: Vec<(usize, usize)> = vec![(root, 0)];
        index[root] = next;
        low[root] = next;
        next += 1;
        stack.push(root);
        on_stack[root] = true;
        while let Some(&mut (v, ref mut k)) = call.last_mut() {
            if *k < succ[v].len() {
                let w = succ[v][*k];
                *k += 1;
                if index[w] == usize::MAX {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    call.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
            } else {
                call.pop();
                if let Some(&(u, _)) = call.last() {
                    low[u] = low[u].min(low[v]);
                }
                if low[v] == index[v] {
                    while let Some(w) = stack.pop() {
                        on_stack[w] = false;
                        comp[w] = ncomp;
                        if w == v {
                            break;
                        }
                    }
                    ncomp += 1;
                }
            }
        }
    }
    comp
}

/// Worst paths from every source (no producer in the acyclic part) to every
/// sink (no consumer) it reaches. Background tasks are left out: they have
/// no timing guarantee.
pub fn all_paths(spec: &Spec, timing: &[TaskTiming]) -> AllPaths {
    let n = spec.tasks.len();
    let live = |i: usize| spec.tasks[i].server != Server::Background;
    let mut succ = vec![Vec::new(); n];
    for (p, c) in spec.edges() {
        if live(p) && live(c) {
            succ[p].push(c);
        }
    }
    let comp = strongly_connected(n, &succ);
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (v, &c) in comp.iter().enumerate() {
        members[c].push(v);
    }
    let mut cycles: Vec<Vec<usize>> = Vec::new();
    for (c, m) in members.iter().enumerate() {
        if m.len() > 1 || (m.len() == 1 && succ[m[0]].contains(&m[0])) {
            let _ = c;
            cycles.push(m.clone());
        }
    }
    // The acyclic part: drop edges inside a component.
    let mut dag = vec![Vec::new(); n];
    let mut indeg = vec![0usize; n];
    for p in 0..n {
        for &c in &succ[p] {
            if comp[p] != comp[c] {
                dag[p].push(c);
                indeg[c] += 1;
            }
        }
    }
    // Kahn topological order.
    let mut order = Vec::with_capacity(n);
    let mut deg = indeg.clone();
    let mut queue: Vec<usize> = (0..n).filter(|&i| live(i) && deg[i] == 0).collect();
    queue.reverse();
    while let Some(v) = queue.pop() {
        order.push(v);
        for &c in &dag[v] {
            deg[c] -= 1;
            if deg[c] == 0 {
                queue.push(c);
            }
        }
    }
    let mut pos = vec![usize::MAX; n];
    for (k, &v) in order.iter().enumerate() {
        pos[v] = k;
    }
    let lt: Vec<LinkTask> = (0..n).map(|i| LinkTask::new(spec, timing, i)).collect();
    let sched = spec.scheduler;
    let sources: Vec<usize> = (0..n).filter(|&i| live(i) && indeg[i] == 0).collect();
    let is_sink = |i: usize| dag[i].is_empty();

    let mut pairs = Vec::new();
    // Scratch arrays reused across sources; `stamp` marks what this source reached.
    const NONE: usize = usize::MAX;
    let mut stamp = vec![NONE; n];
    let mut pe = vec![0 as Nanos; n];
    let mut pe_from = vec![NONE; n];
    let mut pf = vec![0 as Nanos; n];
    let mut pf_from = vec![NONE; n];
    let mut sf = vec![0 as Nanos; n];
    let mut sf_from = vec![NONE; n];
    // Sound freshness ending at a task's publish: the last link's own term.
    let mut sl = vec![0 as Nanos; n];
    let mut sl_from = vec![NONE; n];
    // Sound reaction on (task, distinct) states: index 2·task + distinct.
    let mut se = vec![0 as Nanos; 2 * n];
    let mut se_ok = vec![NONE; 2 * n];
    let mut se_from = vec![NONE; 2 * n];

    for &s in &sources {
        stamp[s] = s;
        pe[s] = lt[s].l;
        pf[s] = lt[s].l;
        sf[s] = 0;
        pe_from[s] = NONE;
        pf_from[s] = NONE;
        sf_from[s] = NONE;
        se_ok[2 * s] = NONE;
        se[2 * s + 1] = 0;
        se_ok[2 * s + 1] = s;
        se_from[2 * s + 1] = NONE;
        let start = pos[s];
        for &v in &order[start..] {
            if stamp[v] != s {
                continue;
            }
            for &c in &dag[v] {
                let (p, q) = (&lt[v], &lt[c]);
                let cand_pe = pe[v] + paper_reaction_link(p, q);
                let cand_pf = pf[v] + paper_freshness_link(p, q);
                let cand_sf = add(sf[v], sound_freshness_link(sched, p, q));
                let cand_sl = add(sf[v], sound_freshness_last(sched, p, q));
                if stamp[c] != s {
                    stamp[c] = s;
                    pe[c] = cand_pe;
                    pe_from[c] = v;
                    pf[c] = cand_pf;
                    pf_from[c] = v;
                    sf[c] = cand_sf;
                    sf_from[c] = v;
                    sl[c] = cand_sl;
                    sl_from[c] = v;
                    se_ok[2 * c] = NONE;
                    se_ok[2 * c + 1] = NONE;
                } else {
                    if cand_pe > pe[c] {
                        pe[c] = cand_pe;
                        pe_from[c] = v;
                    }
                    if cand_pf > pf[c] {
                        pf[c] = cand_pf;
                        pf_from[c] = v;
                    }
                    if cand_sf > sf[c] {
                        sf[c] = cand_sf;
                        sf_from[c] = v;
                    }
                    if cand_sl > sl[c] {
                        sl[c] = cand_sl;
                        sl_from[c] = v;
                    }
                }
                for d in 0..2 {
                    let sv = 2 * v + d;
                    if se_ok[sv] != s {
                        continue;
                    }
                    let distinct = d == 1;
                    let cand = add(se[sv], sound_reaction_link(sched, p, q, distinct));
                    let dc = usize::from(distinct_passes(p, q, distinct));
                    let sc = 2 * c + dc;
                    if se_ok[sc] != s || cand > se[sc] {
                        se[sc] = cand;
                        se_ok[sc] = s;
                        se_from[sc] = sv;
                    }
                }
            }
        }
        for &v in &order[start..] {
            if stamp[v] != s || !is_sink(v) {
                continue;
            }
            let walk = |from: &[usize], end: usize| {
                let mut path = vec![end];
                let mut cur = end;
                while from[cur] != NONE {
                    cur = from[cur];
                    path.push(cur);
                }
                path.reverse();
                path
            };
            let fin = |x: Nanos| if x == INF { None } else { Some(x) };
            // Sums start at the source's release; a path of one task is its
            // response time, a longer one ends with its last link's term.
            let (fresh, fresh_path) = if v == s {
                (lt[v].r, vec![v])
            } else {
                let mut path = walk(&sf_from, sl_from[v]);
                path.push(v);
                (fin(sl[v]), path)
            };
            // Best sound-reaction state at the sink.
            let mut best = NONE;
            for d in 0..2 {
                let sv = 2 * v + d;
                if se_ok[sv] == s && (best == NONE || se[sv] > se[best]) {
                    best = sv;
                }
            }
            let se_path: Vec<usize> = if best == NONE {
                vec![v]
            } else {
                walk(&se_from, best).into_iter().map(|x| x / 2).collect()
            };
            pairs.push(PairBounds {
                source: s,
                sink: v,
                reaction_paper: Worst {
                    path: walk(&pe_from, v),
                    value: Some(pe[v]),
                },
                reaction_sound: Worst {
                    path: se_path,
                    // First output ≤ last output: the pair's worst freshness
                    // bounds the reaction of every path between them too.
                    value: match (
                        if best == NONE {
                            None
                        } else {
                            fin(add(se[best], lt[v].r))
                        },
                        fresh,
                    ) {
                        (Some(e), Some(f)) => Some(e.min(f)),
                        (e, _) => e,
                    },
                },
                freshness_paper: Worst {
                    path: walk(&pf_from, v),
                    value: Some(pf[v]),
                },
                freshness_sound: Worst {
                    path: fresh_path,
                    value: fresh,
                },
            });
        }
    }
    AllPaths { pairs, cycles }
}
