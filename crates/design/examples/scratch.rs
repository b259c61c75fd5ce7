use rtpipe_analysis::bounds_per_chain;
use rtpipe_design::{design, Mode, Options};
use rtpipe_model::gen::{design_problem, DesignGenConfig, GenConfig};
fn cpu() -> f64 { let s = std::fs::read_to_string("/proc/self/stat").unwrap(); let f: Vec<&str> = s.split_whitespace().collect(); (f[13].parse::<f64>().unwrap() + f[14].parse::<f64>().unwrap()) / 100.0 }
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let tasks: usize = a[1].parse().unwrap();
    let seeds: Vec<u64> = a[2].split(',').map(|s| s.parse().unwrap()).collect();
    let patience: u64 = a[3].parse().unwrap();
    let mode = if a.get(4).map_or(false, |m| m == "paper") { Mode::Paper } else { Mode::Sound };
    let (cpus, chains) = match tasks { 0..=10 => (1, 2), 11..=30 => (2, 4), 31..=60 => (4, 6), _ => (8, 10) };
    let cfg = DesignGenConfig { system: GenConfig { tasks, cpus, utilization: 0.5, chains, ..DesignGenConfig::default().system }, choices_fraction: 0.0, ..DesignGenConfig::default() };
    for seed in seeds {
        let spec = design_problem(seed, &cfg, &|s| bounds_per_chain(s, |b| b.sound));
        let opts = Options { mode, patience: Some(patience), ..Options::default() };
        let c0 = cpu();
        let o = design(&spec, &opts).unwrap();
        println!("{tasks} seed {seed}: {} obj {:.5} lb {:.5} gap {:.3}% boxes {} peak {} cpu {:.2}s", o.status.name(), o.objective.unwrap_or(f64::NAN), o.lower_bound.unwrap_or(f64::NAN), 100.0*o.gap.unwrap_or(f64::NAN), o.iterations, o.peak_open, cpu() - c0);
    }
}
