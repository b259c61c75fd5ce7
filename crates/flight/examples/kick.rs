//! Print the response to a roll impulse in the hover (tuning aid):
//! `cargo run --release -p rtpipe-flight --example kick -- racer5 10`.

use rtpipe_flight::loop_sim::{fly, LoopConfig};
use rtpipe_flight::math::Vec3;
use rtpipe_flight::preset::Preset;
use rtpipe_flight::radio::Mission;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let p = Preset::builtin(args.get(1).map_or("racer5", String::as_str))?;
    let kick: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let mut cfg = LoopConfig::new(11.0, 2018);
    cfg.world.trace_every_ns = 20_000_000;
    cfg.world.impulse = Some((
        8_000_000_000,
        Vec3::new(p.body.inertia_kg_m2[0] * kick, 0.0, 0.0),
    ));
    let tr = fly(&p, Mission::builtin("hover")?, cfg)?;
    for q in tr
        .iter()
        .filter(|q| q.t_ns >= 7_960_000_000 && q.t_ns < 9_600_000_000)
    {
        println!(
            "t={:.2} true={:7.2} est={:7.2} sp={:7.2} y={:6.3} vy={:6.3}",
            q.t_ns as f64 * 1e-9,
            q.euler.roll.to_degrees(),
            q.est.roll.to_degrees(),
            q.sp.roll.to_degrees(),
            q.pos.y,
            q.vel.y
        );
    }
    Ok(())
}
