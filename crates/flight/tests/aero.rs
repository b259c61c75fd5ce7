//! rtpipe's rotor aerodynamics against rotorpy's own numbers
//! (tests/data/aero/, written by rotorpy_compare.py there from rotorpy
//! 3.0.0, the built-in racer5 preset's body and rotors and the [aero]
//! table of vehicle.toml there): the aerodynamic force and moment
//! at random states, and the open-loop attitude response to a step gust and
//! a sinusoidal gust over 1 s, every rotor commanded at hover.

use rtpipe_flight::math::{Quat, Vec3};
use rtpipe_flight::plant::{Plant, State};
use rtpipe_flight::preset::Preset;

/// rotorpy's gravity (its hover speed is sqrt(m·9.81 / 4k_f)).
const ROTORPY_G: f64 = 9.81;

fn table(name: &str) -> Vec<Vec<f64>> {
    let path = format!("{}/tests/data/aero/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let rows = text.lines().skip(1).map(|l| {
        l.split(',')
            .map(|v| v.parse().unwrap_or_else(|e| panic!("{path}: {v}: {e}")))
            .collect()
    });
    rows.collect()
}

/// racer5 with the comparison's aerodynamics.
fn racer5() -> Preset {
    #[derive(serde::Deserialize)]
    struct Vehicle {
        aero: rtpipe_flight::plant::AeroParams,
    }
    let path = format!(
        "{}/tests/data/aero/vehicle.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let v: Vehicle = toml::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let preset = Preset::builtin("racer5").unwrap_or_else(|e| panic!("{e}"));
    Preset {
        aero: v.aero,
        ..preset
    }
}

#[test]
fn the_aerodynamic_wrench_is_rotorpys() {
    let p = racer5();
    let (mut max_f, mut max_m, mut peak) = (0.0f64, 0.0f64, 0.0f64);
    for r in table("wrench.csv") {
        let v = |i: usize| Vec3::new(r[i], r[i + 1], r[i + 2]);
        let omega = [r[3], r[4], r[5], r[6]];
        let w = p.aero.wrench(&p.rotors.positions_m, &omega, v(0), v(7));
        max_f = max_f.max((w.force - v(10)).norm());
        max_m = max_m.max((w.moment - v(13)).norm());
        peak = peak.max(v(10).norm());
    }
    eprintln!("wrench: max |ΔF| {max_f:.3e} N (largest F {peak:.3} N), max |ΔM| {max_m:.3e} N·m");
    assert!(peak > 0.5, "the states exercise the model: {peak} N");
    assert!(max_f < 1e-12 && max_m < 1e-12, "{max_f} N, {max_m} N·m");
}

/// The open-loop flight of `name`'s gust in rtpipe's plant, against
/// rotorpy's rows: (max, RMS) of the roll/pitch difference, rad, and the
/// largest roll/pitch rotorpy reached.
fn open_loop(name: &str, wind: fn(f64) -> Vec3) -> (f64, f64, f64) {
    let preset = racer5();
    let mut params = preset.plant_params();
    // rotorpy has no lumped drag; racer5's linear drag is 0 already.
    params.body.drag_linear = 0.0;
    params.body.drag_angular = 0.0;
    let hover = (params.body.mass_kg * ROTORPY_G / (4.0 * params.rotors.k_f)).sqrt();
    let r = &params.rotors;
    let cmd = (hover / r.omega_max_rad_s - r.idle_fraction) / (1.0 - r.idle_fraction);
    let mut plant = Plant::new(params).unwrap_or_else(|e| panic!("{e}"));
    plant.set_state(State {
        pos: Vec3::new(0.0, 0.0, 10.0),
        vel: Vec3::ZERO,
        q: Quat::IDENTITY,
        rate: Vec3::ZERO,
        omega: [hover; 4],
    });
    plant.set_motor_commands([cmd; 4], true);
    let reference = table(name);
    let (mut max, mut sum2, mut peak) = (0.0f64, 0.0, 0.0f64);
    for k in 0..=1000u64 {
        if k % 10 == 0 {
            let row = &reference[(k / 10) as usize];
            let e = plant.truth().euler;
            for (ours, theirs) in [(e.roll, row[1]), (e.pitch, row[2])] {
                max = max.max((ours - theirs).abs());
                sum2 += (ours - theirs).powi(2);
                peak = peak.max(theirs.abs());
            }
        }
        plant.set_wind(wind(k as f64 * 1e-3));
        plant.advance_to((k + 1) * 1_000_000);
    }
    let rms = (sum2 / (2.0 * reference.len() as f64)).sqrt();
    eprintln!(
        "{name}: roll/pitch max |Δ| {:.3e}°, RMS {:.3e}° (rotorpy's largest {:.2}°)",
        max.to_degrees(),
        rms.to_degrees(),
        peak.to_degrees()
    );
    (max, rms, peak)
}

fn step_gust(t: f64) -> Vec3 {
    if t >= 0.1 {
        Vec3::new(3.0, 2.0, 0.5)
    } else {
        Vec3::ZERO
    }
}

fn sine_gust(t: f64) -> Vec3 {
    use std::f64::consts::TAU;
    Vec3::new(
        2.0 * (TAU * 2.0 * t).sin(),
        1.5 * (TAU * 3.0 * t + 0.5).sin(),
        0.5 * (TAU * t).sin(),
    )
}

#[test]
fn a_step_gust_tilts_the_open_loop_vehicle_as_in_rotorpy() {
    let (max, _, peak) = open_loop("step.csv", step_gust);
    // The gust tilts the vehicle by tens of degrees in the second; the two
    // integrations agree to a small fraction of that.
    assert!(peak > 10f64.to_radians(), "{}°", peak.to_degrees());
    assert!(max < 1e-3 * peak, "{max} rad against {peak} rad");
}

#[test]
fn a_sinusoidal_gust_tilts_the_open_loop_vehicle_as_in_rotorpy() {
    let (max, _, peak) = open_loop("sine.csv", sine_gust);
    assert!(peak > 1f64.to_radians(), "{}°", peak.to_degrees());
    assert!(max < 1e-3 * peak, "{max} rad against {peak} rad");
}
