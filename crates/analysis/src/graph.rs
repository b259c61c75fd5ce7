//! Directed graphs as successor lists: strongly connected components
//! (Tarjan's) and a topological order (Kahn's), for the path enumeration
//! (`paths`) and the event analysis' order of
//! what waits for what (`events`).

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
