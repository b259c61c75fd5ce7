//! Who reads whom in the event analysis ([`super::analyze`]): the units
//! whose responses read a task's activations, found from the ranked
//! lists of the tasks above, and the order of the triggers.

use super::Ranked;
use crate::graph::Lists;
use rtpipe_model::{Server, Spec};

/// The unit of task `i`: its thread (numbered after the tasks), or itself.
pub(super) fn unit_of(spec: &Spec, i: usize) -> usize {
    spec.tasks[i].thread.map_or(i, |th| spec.tasks.len() + th)
}

/// Who reads whom: the units whose responses read a task's activations
/// are its own and those of the tasks it runs above, whose prefixes
/// ([`Ranked`]) hold it. On a CPU's list ranked by priority those are the
/// tasks whose prefix passes its entry: no unit's list of reads is kept,
/// nor scanned (docs/analysis.md "Cost at 1,000 tasks", tenth round).
pub(super) struct Readers {
    /// The ranked lists, one after the other.
    pub(super) flat: Vec<usize>,
    /// Per entry of `flat`, where its list starts.
    pub(super) list_start: Vec<usize>,
    /// Per entry of `flat`, its task's unit (what [`Deps::above`] leaves
    /// out of a task's prefix: the task and its thread's own).
    pub(super) unit_at: Vec<usize>,
    /// Per task the entries of `flat` above it (and maybe itself and its
    /// thread's tasks, which its unit reads anyway; none for a background
    /// task, which has no response).
    pub(super) prefix: Vec<std::ops::Range<usize>>,
    /// Per task the entries of `flat` that are it.
    pub(super) occurs: Lists,
    /// Per list (by where it starts) the units whose tasks' prefixes lie
    /// in it, as (the farthest end of their prefixes, unit), each unit
    /// once, by that end descending, then ([`Readers::group`]) by
    /// component and by that end descending in each.
    pub(super) reach: Vec<Vec<(usize, usize)>>,
}

impl Readers {
    pub(super) fn of(spec: &Spec, ranked: Ranked) -> Readers {
        let n = spec.tasks.len();
        assert_eq!(ranked.prefix.len(), n, "a prefix per task");
        let mut starts = Vec::with_capacity(ranked.lists.len());
        let mut flat = Vec::new();
        let mut list_start = Vec::new();
        for list in &ranked.lists {
            starts.push(flat.len());
            list_start.resize(flat.len() + list.len(), flat.len());
            flat.extend_from_slice(list);
        }
        let prefix: Vec<std::ops::Range<usize>> = (0..n)
            .map(|i| {
                let (l, len) = ranked.prefix[i];
                assert!(
                    len <= ranked.lists[l].len(),
                    "task {i}'s prefix passes its list"
                );
                let len = if spec.tasks[i].server == Server::Background {
                    0
                } else {
                    len
                };
                starts[l]..starts[l] + len
            })
            .collect();
        let unit_at = flat.iter().map(|&j| unit_of(spec, j)).collect();
        let occurs = Lists::build(n, |entry| {
            for (g, &j) in flat.iter().enumerate() {
                entry.add(j, g);
            }
        });
        // Per list the (end, unit) of every task with a prefix there, the
        // farthest first, a unit kept at its farthest only.
        let mut reach: Vec<Vec<(usize, usize)>> = vec![Vec::new(); flat.len() + 1];
        let mut by_end: Vec<(usize, usize, usize)> = (0..n)
            .filter(|&i| !prefix[i].is_empty())
            .map(|i| (prefix[i].start, prefix[i].end, unit_of(spec, i)))
            .collect();
        by_end.sort_unstable_by(|a, b| (a.0, b.1).cmp(&(b.0, a.1)));
        let mut last = vec![usize::MAX; n + spec.threads.len()];
        // A prefix starts where its list does.
        for (list, end, u) in by_end {
            if last[u] != list {
                last[u] = list;
                reach[list].push((end, u));
            }
        }
        Readers {
            flat,
            list_start,
            unit_at,
            prefix,
            occurs,
            reach,
        }
    }

    /// Sorts each list's readers by their component (`of_unit`, per
    /// unit), keeping them by their prefixes' end descending in each, so
    /// that [`Readers::reading`] walks one component's alone.
    pub(super) fn group(&mut self, of_unit: &[usize]) {
        for list in &mut self.reach {
            list.sort_unstable_by_key(|&(end, u)| (of_unit[u], std::cmp::Reverse(end)));
        }
    }

    /// Hands `visit` the units of component `inside.1` (`inside.0` gives
    /// each unit's) whose responses read task `j`'s activations: its own,
    /// then those whose tasks' prefixes hold it (a unit may come twice
    /// where j stands in more than one list). Each list's readers of that
    /// component are a run of it, sorted by their prefixes' end
    /// ([`Readers::group`]), so those whose prefix passes j's entry are a
    /// stretch of it found by two binary searches, walked as a plain slice
    /// (a refresh walks it for each changed task: docs/analysis.md "Cost at
    /// 1,000 tasks", the eleventh round).
    pub(super) fn reading(
        &self,
        spec: &Spec,
        j: usize,
        inside: (&[usize], usize),
        mut visit: impl FnMut(usize),
    ) {
        let (of_unit, c) = inside;
        let own = unit_of(spec, j);
        if of_unit[own] == c {
            visit(own);
        }
        for &g in self.occurs.of(j) {
            let list = &self.reach[self.list_start[g]];
            let run = &list[list.partition_point(|&(_, u)| of_unit[u] < c)..];
            let passing = run.partition_point(|&(end, u)| of_unit[u] == c && end > g);
            for &(_, u) in &run[..passing] {
                if u != own {
                    visit(u);
                }
            }
        }
    }
}

/// Every task, each after its triggers (Kahn's order; validation makes
/// the trigger graph acyclic).
pub(super) fn trigger_order(spec: &Spec, consumers: &[Vec<usize>]) -> Vec<usize> {
    let degree: Vec<usize> = spec
        .tasks
        .iter()
        .map(|t| t.triggers().map_or(0, |(t, _)| t.len()))
        .collect();
    let sources: Vec<usize> = (0..spec.tasks.len()).filter(|&i| degree[i] == 0).collect();
    let order = crate::graph::kahn(consumers, degree, &sources);
    assert_eq!(
        order.len(),
        spec.tasks.len(),
        "the trigger graph has a cycle"
    );
    order
}
