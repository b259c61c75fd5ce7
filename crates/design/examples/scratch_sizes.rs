use rtpipe_analysis::bounds_per_chain;
use rtpipe_design::{design, Method, Mode, Options};
use rtpipe_model::gen::{design_problem, DesignGenConfig, GenConfig};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let tasks: usize = args[1].parse().unwrap();
    let seeds: u64 = args[2].parse().unwrap();
    let (cpus, chains) = match tasks { 0..=10 => (1, 2), 11..=30 => (2, 4), 31..=60 => (4, 6), _ => (8, 10) };
    let cfg = DesignGenConfig { system: GenConfig { tasks, cpus, utilization: 0.5, chains, ..DesignGenConfig::default().system }, choices_fraction: 0.0, ..DesignGenConfig::default() };
    let first: u64 = args.get(3).map_or(0, |s| s.parse().unwrap());
    for seed in first..first + seeds {
        let spec = design_problem(2018 + seed, &cfg, &|s| bounds_per_chain(s, |b| b.sound));
        for method in [Method::Boxes] {
            let opts = Options { mode: Mode::Sound, method, time_limit: Some(std::env::var("TL").map_or(10.0, |v| v.parse().unwrap())), ..Options::default() };
            let t0 = std::time::Instant::now();
            let o = design(&spec, &opts).unwrap();
            println!("{tasks} seed {seed} {:?}: {} obj {:?} lb {:?} gap {:?} nodes {} peak {} in {:.2}s", method, o.status.name(), o.objective, o.lower_bound, o.gap, o.iterations, o.peak_open, t0.elapsed().as_secs_f64());
        }
    }
}
