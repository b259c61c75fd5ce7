//! Fly a built-in mission with a built-in preset under ideal timing and
//! print the closed-loop figures:
//! `cargo run --release -p rtpipe-flight --example fly -- racer5 steps [seed] [delay_ms]`.

use rtpipe_flight::loop_sim::{fly, LoopConfig, Timing};
use rtpipe_flight::preset::Preset;
use rtpipe_flight::radio::Mission;
use rtpipe_flight::trace::{metrics, TracePoint};

fn print_trace(tr: &[TracePoint]) {
    let every = tr.len() / 120 + 1;
    for p in tr.iter().step_by(every) {
        println!(
            "t={:6.2} z={:6.3} x={:6.2} y={:6.2} roll={:6.2} pitch={:6.2} yaw={:7.2} est_roll={:6.2} sp_r={:6.2} thr={:.3} armed={} gnd={} crash={} V={:.2}",
            p.t_ns as f64 * 1e-9, p.pos.z, p.pos.x, p.pos.y,
            p.euler.roll.to_degrees(), p.euler.pitch.to_degrees(), p.euler.yaw.to_degrees(),
            p.est.roll.to_degrees(), p.sp.roll.to_degrees(), p.sp.throttle, p.armed, p.on_ground, p.crashed, p.voltage
        );
    }
}

fn print_steps(tr: &[TracePoint]) {
    let step = |name: &str, f: &dyn Fn(&TracePoint) -> f64, t0: f64, t1: f64, to: f64| {
        let r = metrics::step_response(tr, f, t0, t1, 0.0, to, 0.05);
        println!("{name}: {r:?}");
    };
    step(
        "roll step (true)",
        &|p| p.euler.roll.to_degrees(),
        6.0,
        7.0,
        20.0,
    );
    step(
        "roll step (est)",
        &|p| p.est.roll.to_degrees(),
        6.0,
        7.0,
        20.0,
    );
    step(
        "pitch step (true)",
        &|p| p.euler.pitch.to_degrees(),
        11.0,
        12.0,
        20.0,
    );
    step(
        "pitch step (est)",
        &|p| p.est.pitch.to_degrees(),
        11.0,
        12.0,
        20.0,
    );
    step(
        "yaw step (true)",
        &|p| p.euler.yaw.to_degrees(),
        16.0,
        21.0,
        90.0,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let preset = Preset::builtin(args.get(1).map_or("racer5", String::as_str))?;
    let mission = Mission::builtin(args.get(2).map_or("hover", String::as_str))?;
    let seed = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let delay_ms = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(2);
    let secs = mission.end_ns() as f64 * 1e-9 + 6.0;
    let mut cfg = LoopConfig::new(secs, seed);
    cfg.timing = Timing::table_v(delay_ms);
    cfg.world.trace_every_ns = 1_000_000;
    let tr = fly(&preset, mission, cfg)?;
    print_trace(&tr);
    println!(
        "alt rms [4,14) = {:.4} m",
        metrics::altitude_rms(&tr, 4.0, 14.0)
    );
    println!(
        "att rms [4,14) = {:.3} deg",
        metrics::attitude_rms_deg(&tr, 4.0, 14.0)
    );
    print_steps(&tr);
    let last = tr.last().ok_or("empty trace")?;
    println!(
        "end: armed={} on_ground={} crashed={} z={:.3}",
        last.armed, last.on_ground, last.crashed, last.pos.z
    );
    Ok(())
}
