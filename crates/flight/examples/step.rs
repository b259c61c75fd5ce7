//! Print the roll step of the `steps` mission every 20 ms (tuning aid):
//! `cargo run --release -p rtpipe-flight --example step -- aero1kg [preset.toml]`.

use rtpipe_flight::loop_sim::{fly, LoopConfig};
use rtpipe_flight::preset::Preset;
use rtpipe_flight::radio::Mission;
use rtpipe_flight::trace::metrics;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let preset = match args.get(2) {
        Some(f) => Preset::from_file(std::path::Path::new(f))?,
        None => Preset::builtin(args.get(1).map_or("racer5", String::as_str))?,
    };
    let mut cfg = LoopConfig::new(8.0, 1);
    cfg.world.trace_every_ns = 20_000_000;
    let tr = fly(&preset, Mission::builtin("steps")?, cfg)?;
    for p in tr
        .iter()
        .filter(|p| (5.9..7.0).contains(&(p.t_ns as f64 * 1e-9)))
    {
        println!(
            "t={:.2} est={:6.2} true={:6.2}",
            p.t_ns as f64 * 1e-9,
            p.est.roll.to_degrees(),
            p.euler.roll.to_degrees()
        );
    }
    let mut cfg = LoopConfig::new(8.0, 1);
    cfg.world.trace_every_ns = 1_000_000;
    let tr = fly(&preset, Mission::builtin("steps")?, cfg)?;
    let r = metrics::step_response(&tr, |p| p.est.roll.to_degrees(), 6.0, 7.0, 0.0, 20.0, 0.05);
    println!("est: {r:?}");
    Ok(())
}
