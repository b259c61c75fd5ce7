//! The hover's oscillation, the motors' control effort and the steps'
//! tracking (docs/flight.md, "Oscillation, control effort and tracking"):
//! Table V's schedule (examples/cleanflight.toml) meets every criterion on
//! `steps` and `gusty` on both vehicles; the same pipeline with the motor
//! output every 44 ms (the answer `design --fly` once gave) rings near 5 Hz
//! in turbulence and fails the oscillation criterion on `gusty` on both
//! vehicles, where every criterion before it let the design pass.

use rtpipe_flight::preset::BUILTIN;
use rtpipe_fly::{fly, setup, Request};
use rtpipe_model::Spec;
use rtpipe_sim::ExecModel;
use std::path::Path;

/// Every failure of `spec` on `mission` with `vehicle`, seed 0.
fn failures(spec: &Spec, path: &Path, vehicle: &str, mission: &str) -> Vec<String> {
    let r = Request {
        spec_path: path,
        vehicle,
        mission,
        horizon: None,
        seed: 0,
    };
    let s = setup(spec, &r).unwrap_or_else(|e| panic!("{e}"));
    let f = fly(spec, &s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"));
    let q = &f.quality;
    println!(
        "{vehicle} {mission}: oscillation {:.3} °/s, motor variation {:.3} /s, step tracking {:.3}°",
        q.oscillation_dps, q.motor_variation_per_s, q.step_tracking_deg.rms
    );
    q.failures(&s.criteria())
}

#[test]
fn table_v_meets_every_criterion_and_a_44_ms_motor_output_oscillates() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
    let table_v = Spec::parse(&path.display().to_string(), &text).unwrap_or_else(|e| panic!("{e}"));
    // The pwm task's period, Table V's 5 ms, is its block's first "period".
    let at = text
        .find("[tasks.pwm]")
        .unwrap_or_else(|| panic!("no pwm task"));
    let slow = text[..at].to_string() + &text[at..].replacen("period = 5000", "period = 44000", 1);
    assert_ne!(slow, text);
    let pwm_44 = Spec::parse(&path.display().to_string(), &slow).unwrap_or_else(|e| panic!("{e}"));
    for vehicle in BUILTIN {
        for mission in ["steps", "gusty"] {
            let f = failures(&table_v, &path, vehicle, mission);
            assert!(f.is_empty(), "Table V, {vehicle} {mission}: {f:?}");
            let f = failures(&pwm_44, &path, vehicle, mission);
            let rings = f.iter().any(|x| x.starts_with("hover oscillation"));
            assert_eq!(
                rings,
                mission == "gusty",
                "PWM at 44 ms, {vehicle} {mission}: {f:?}"
            );
        }
    }
}
