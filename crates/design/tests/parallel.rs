//! The box search examines the two halves of each split in parallel; its
//! result must not depend on the cores: on one thread and on four, the
//! same boxes, the same answer, the same bound ("the same answer
//! on any machine for a given work budget").

use rtpipe_analysis::{bounds_per_chain, Anchor};
use rtpipe_design::{design, Method, Mode, Options, Outcome};
use rtpipe_model::gen::{benchmark_config, design_problem};
use rtpipe_model::Spec;

fn solve_on(threads: usize, spec: &Spec, mode: Mode) -> Outcome {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    let opts = Options {
        mode,
        method: Method::Boxes,
        ..Options::default()
    };
    pool.install(|| design(spec, &opts))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Everything of an outcome that the search decides (not its time).
fn decided(o: &Outcome) -> String {
    let periods: Vec<_> = o
        .spec
        .iter()
        .flat_map(|s| s.tasks.iter().map(|t| t.fixed_period()))
        .collect();
    format!(
        "{:?} {:?} {:?} {:?} boxes {} peak {} {} B {periods:?}",
        o.status,
        o.objective.map(f64::to_bits),
        o.lower_bound.map(f64::to_bits),
        o.gap.map(f64::to_bits),
        o.iterations,
        o.peak_open,
        o.peak_open_bytes,
    )
}

#[test]
fn one_thread_and_four_decide_the_same() {
    let mut searched = 0;
    for (tasks, seed) in [(6, 2018), (20, 2018), (20, 2019), (20, 2024), (50, 2027)] {
        let spec = design_problem(seed, &benchmark_config(tasks), &|s| {
            bounds_per_chain(s, |b| b.sound(Anchor::Read))
        });
        for mode in [Mode::Sound, Mode::Paper] {
            let one = solve_on(1, &spec, mode);
            let four = solve_on(4, &spec, mode);
            assert_eq!(
                decided(&one),
                decided(&four),
                "{tasks} tasks, seed {seed}, {mode:?}"
            );
            searched += usize::from(one.iterations > 10);
        }
    }
    // Not only trivial searches: most of these split many boxes.
    assert!(searched >= 6, "{searched} searches of more than 10 boxes");
}
