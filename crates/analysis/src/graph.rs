//! Directed graphs as successor lists: strongly connected components
//! (Tarjan's) and a topological order (Kahn's), for the path enumeration
//! (`paths`) and the event analysis' order of
//! what waits for what (`events`), which keeps its lists flat ([`Lists`]).

/// Per node a list of nodes, in two flat arrays (compressed sparse rows):
/// node `v`'s list is `to[start[v]..start[v + 1]]`, with no vector per
/// node (the event analysis' unit graph and readers of 1,000 tasks spent
/// about 7 M instructions growing a vector per node one entry at a time).
#[derive(Debug, Clone)]
pub struct Lists {
    start: Vec<usize>,
    to: Vec<usize>,
}

impl Lists {
    /// The lists of `n` nodes whose entries `entries` hands, as `(node,
    /// entry)`, to [`Entries::add`], each node's in the order handed.
    /// `entries` runs twice, to count and then to place them (no list of
    /// pairs: the pairs took more memory than the lists), and must hand
    /// the same entries both times.
    pub fn build(n: usize, entries: impl Fn(&mut Entries)) -> Lists {
        let mut count = Entries {
            start: vec![0; n + 1],
            to: Vec::new(),
            placing: false,
        };
        entries(&mut count);
        let mut start = count.start;
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut place = Entries {
            to: vec![0; start[n]],
            // Per node where its next entry goes.
            start: start.clone(),
            placing: true,
        };
        entries(&mut place);
        assert!(
            (0..n).all(|v| place.start[v] == start[v + 1]),
            "the entries of a list changed between the two passes"
        );
        Lists {
            start,
            to: place.to,
        }
    }

    /// Node `v`'s list.
    pub fn of(&self, v: usize) -> &[usize] {
        &self.to[self.start[v]..self.start[v + 1]]
    }
}

/// The entries of [`Lists::build`] as they are handed: counted in its
/// first pass, placed in its second.
pub struct Entries {
    /// Counting: per node one past the index, its count. Placing: per
    /// node where its next entry goes.
    start: Vec<usize>,
    to: Vec<usize>,
    placing: bool,
}

impl Entries {
    /// Entry `w` of node `v`'s list, after the ones handed before.
    #[inline]
    pub fn add(&mut self, v: usize, w: usize) {
        if self.placing {
            self.to[self.start[v]] = w;
            self.start[v] += 1;
        } else {
            self.start[v + 1] += 1;
        }
    }
}

/// Successor lists as [`strongly_connected`] reads them.
pub trait Successors {
    /// The successors of node `v`.
    fn of(&self, v: usize) -> &[usize];
}

impl Successors for [Vec<usize>] {
    fn of(&self, v: usize) -> &[usize] {
        &self[v]
    }
}

impl Successors for Vec<Vec<usize>> {
    fn of(&self, v: usize) -> &[usize] {
        &self[v]
    }
}

impl Successors for Lists {
    fn of(&self, v: usize) -> &[usize] {
        Lists::of(self, v)
    }
}

/// Tarjan's SCC algorithm, iterative so that 10,000-task graphs cannot
/// overflow the stack.
pub fn strongly_connected(n: usize, succ: &(impl Successors + ?Sized)) -> Vec<usize> {
    let mut index = vec![usize::MAX; n];
    let mut low = vec![0; n];
    let mut on_stack = vec![false; n];
    let mut comp = vec![usize::MAX; n];
    let mut stack = Vec::new();
    let mut next = 0;
    let mut ncomp = 0;
    // The depth-first search's own stack, one for every root.
    let mut call: Vec<(usize, usize)> = Vec::new();
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        call.push((root, 0));
        index[root] = next;
        low[root] = next;
        next += 1;
        stack.push(root);
        on_stack[root] = true;
        while let Some(&mut (v, ref mut k)) = call.last_mut() {
            if let Some(&w) = succ.of(v).get(*k) {
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

/// Kahn's topological order from the nodes `sources` without
/// predecessors (`deg`: each node's number of predecessors).
pub(crate) fn kahn(dag: &[Vec<usize>], mut deg: Vec<usize>, sources: &[usize]) -> Vec<usize> {
    let mut order = Vec::with_capacity(dag.len());
    let mut queue: Vec<usize> = sources.to_vec();
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
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries in a scrambled order, some nodes with none, one repeated.
    fn entries(n: usize) -> Vec<(usize, usize)> {
        (0..5 * n)
            .map(|k| ((k * 7 + 3) % n, (k * 13 + 5) % n))
            .filter(|&(v, _)| v % 4 != 1)
            .chain([(0, 0), (0, 0)])
            .collect()
    }

    #[test]
    fn flat_lists_hold_each_nodes_entries_in_the_order_handed() {
        for n in [1, 2, 9, 40] {
            let pairs = entries(n);
            let mut nested = vec![Vec::new(); n];
            for &(v, w) in &pairs {
                nested[v].push(w);
            }
            let flat = Lists::build(n, |e| {
                for &(v, w) in &pairs {
                    e.add(v, w);
                }
            });
            for (v, list) in nested.iter().enumerate() {
                assert_eq!(flat.of(v), &list[..], "n = {n}, node {v}");
            }
            // The same graph, the same components.
            assert_eq!(
                strongly_connected(n, &flat),
                strongly_connected(n, &nested),
                "n = {n}"
            );
        }
        assert!(Lists::build(3, |_| {}).of(2).is_empty());
    }

    #[test]
    #[should_panic(expected = "changed between the two passes")]
    fn entries_that_change_between_the_passes_are_a_bug() {
        let pass = std::cell::Cell::new(0);
        Lists::build(2, |e| {
            pass.set(pass.get() + 1);
            e.add(0, 1);
            if pass.get() == 1 {
                e.add(1, 0);
            }
        });
    }
}
