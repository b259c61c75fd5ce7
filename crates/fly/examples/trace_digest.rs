//! Digests of whole flights at full precision (every trace point's every
//! f64 by its Debug form, which tells -0.0 from 0.0 and round-trips, the
//! quality, the alerts, the simulator's events and per-task figures), to check that a speed
//! change keeps flights bit for bit: run it on the commits before and after
//! and compare the lines.
//!
//! `cargo run --release -p rtpipe-fly --example trace_digest`

use rtpipe_flight::math::Vec3;
use rtpipe_fly::{fly, setup, Request};
use rtpipe_model::Spec;
use rtpipe_sim::ExecModel;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::Path;

fn digest(text: &str) -> u64 {
    let mut h = DefaultHasher::new();
    text.hash(&mut h);
    h.finish()
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let cases: [(&str, &str, &str, Option<i64>, u64); 9] = [
        ("cleanflight", "racer5", "steps", None, 1),
        ("cleanflight", "aero1kg", "steps", None, 2),
        ("cleanflight", "racer5", "hover", Some(40), 0),
        ("cleanflight", "racer5", "gusty", None, 3),
        ("cleanflight", "aero1kg", "paper", None, 4),
        ("cleanflight-derived-design", "racer5", "steps", None, 5),
        ("cleanflight", "racer5", "impulse", Some(12), 6),
        ("cleanflight", "racer5", "delay", Some(14), 7),
        ("cleanflight", "racer5", "crash", Some(8), 8),
    ];
    for (system, vehicle, mission, secs, seed) in cases {
        let path = root.join(format!("examples/{system}.toml"));
        let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let m = match mission {
            "impulse" | "delay" => "hover",
            "crash" => "steps",
            m => m,
        };
        let r = Request {
            spec_path: &path,
            vehicle,
            mission: m,
            horizon: secs.map(|s| s * 1_000_000_000),
            seed,
        };
        let mut s = setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
        if mission == "impulse" {
            s.world.impulse = Some((8_000_000_000, Vec3::new(0.03, 0.01, 0.0)));
        }
        if mission == "delay" {
            s.world.sense_delay_ns = [4_000_000, 2_000_000, 8_000_000];
        }
        if mission == "crash" {
            // The gyro path 64 ms late: the racer crashes (docs/flight.md).
            s.world.sense_delay_ns = [64_000_000, 0, 0];
        }
        let f = fly(&spec, &s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"));
        println!(
            "{system} {vehicle} {mission} seed {seed}: {} points, trace {:016x}, quality {:016x}, alerts {:016x}, sim {:016x}",
            f.trace.len(),
            digest(&format!("{:?}", f.trace)),
            digest(&format!("{:?}", f.quality)),
            digest(&format!("{:?}", f.alerts)),
            // Not the chains' figures: their histograms are hash maps,
            // whose Debug order changes from run to run.
            digest(&format!("{} {:?} {:?}", f.sim.events, f.sim.tasks, f.sim.offsets)),
        );
    }
}
