//! The tasks of each CPU: the one index by CPU. Built once per pass in
//! O(n log n), it spares the per-CPU and per-task scans over every task
//! that made the ranks and the analysis quadratic in the task count
//! (docs/analysis.md, "Scale").

use crate::Spec;

/// The tasks of each CPU that has any, in declaration order. A snapshot:
/// a spec whose tasks change CPU needs a new one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TasksByCpu {
    /// The CPUs with tasks, ascending.
    cpus: Vec<u32>,
    /// `tasks[start[k]..start[k + 1]]`: the tasks of `cpus[k]`.
    start: Vec<usize>,
    /// Every task, by CPU, then in declaration order.
    tasks: Vec<usize>,
}

impl TasksByCpu {
    /// The index of `spec`'s tasks.
    pub fn of(spec: &Spec) -> TasksByCpu {
        let mut tasks: Vec<usize> = (0..spec.tasks.len()).collect();
        // Stable: declaration order within a CPU.
        tasks.sort_by_key(|&i| spec.tasks[i].cpu);
        let mut cpus = Vec::new();
        let mut start = Vec::new();
        for (k, &i) in tasks.iter().enumerate() {
            let cpu = spec.tasks[i].cpu;
            if cpus.last() != Some(&cpu) {
                cpus.push(cpu);
                start.push(k);
            }
        }
        start.push(tasks.len());
        TasksByCpu { cpus, start, tasks }
    }

    /// The CPUs that have tasks, ascending.
    pub fn cpus(&self) -> &[u32] {
        &self.cpus
    }

    /// The position of `cpu` in [`TasksByCpu::cpus`], if it has tasks.
    pub fn position(&self, cpu: u32) -> Option<usize> {
        self.cpus.binary_search(&cpu).ok()
    }

    /// The tasks of `cpu` in declaration order (none for a CPU without).
    pub fn on(&self, cpu: u32) -> &[usize] {
        self.position(cpu).map_or(&[], |k| self.at(k))
    }

    /// The tasks of the `k`-th CPU of [`TasksByCpu::cpus`].
    pub fn at(&self, k: usize) -> &[usize] {
        &self.tasks[self.start[k]..self.start[k + 1]]
    }

    /// Each CPU with its tasks, CPUs ascending.
    pub fn iter(&self) -> impl Iterator<Item = (u32, &[usize])> + '_ {
        self.cpus
            .iter()
            .enumerate()
            .map(|(k, &cpu)| (cpu, self.at(k)))
    }
}

impl Spec {
    /// The index of the tasks by CPU ([`TasksByCpu`]).
    pub fn tasks_by_cpu(&self) -> TasksByCpu {
        TasksByCpu::of(self)
    }
}

#[cfg(test)]
mod tests {

    #[test]
    fn groups_by_cpu_in_declaration_order() {
        let spec = crate::gen::waters_system(
            3,
            &crate::gen::WatersConfig {
                tasks: Some(40),
                cpus: 3,
                ..Default::default()
            },
        );
        let index = spec.tasks_by_cpu();
        assert_eq!(index.cpus(), &[0, 1, 2]);
        for (cpu, tasks) in index.iter() {
            let naive: Vec<usize> = (0..spec.tasks.len())
                .filter(|&i| spec.tasks[i].cpu == cpu)
                .collect();
            assert_eq!(tasks, naive.as_slice());
        }
        assert!(index.on(7).is_empty());
        assert_eq!(index.position(2), Some(2));
    }
}
