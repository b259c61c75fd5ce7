//! The plant's unit tests (private parts).

use super::*;
use crate::preset::Preset;

#[test]
fn wrap_tau_is_rem_euclid_bit_for_bit() {
    use std::f64::consts::TAU;
    let mut rng = crate::rng::Rng::new(5);
    let mut cases = vec![0.0, -0.0, TAU, 2.0 * TAU, TAU.next_down(), -1e-300, 1e300];
    cases.extend((0..100_000).map(|_| 5.0 * TAU * rng.uniform() - TAU));
    for a in cases {
        assert_eq!(wrap_tau(a).to_bits(), a.rem_euclid(TAU).to_bits(), "{a}");
    }
}

/// The step on the ground is the full RK4 with the body's derivatives
/// zero, bit for bit (the plant's code before the two were split).
#[test]
fn the_held_step_is_the_full_step_with_a_still_body() {
    let p = Preset::builtin("racer5").map(|p| p.plant_params());
    let mut plant = p.and_then(Plant::new).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = crate::rng::Rng::new(9);
    for k in 0..2_000 {
        let mut u = || rng.gaussian();
        let mut s = *plant.state();
        s.pos = Vec3::new(u(), -0.0, 0.0);
        s.vel = Vec3::new(-0.0, u(), u());
        s.q = Quat::new(u(), u(), -0.0, u()).normalized();
        s.rate = Vec3::new(u(), u(), -0.0);
        s.omega = [u().abs() * 900.0, 0.0, u() * 3.0, 1e-5];
        plant.s = s;
        plant.on_ground = true;
        plant.set_motor_commands([0.2, 0.0, 1.0, 0.5], k % 2 == 0);
        let h = (1 + k * 131 % 250_000) as f64 * 1e-9;
        let still = |x: &State| State {
            pos: Vec3::ZERO,
            vel: Vec3::ZERO,
            q: Quat::new(0.0, 0.0, 0.0, 0.0),
            rate: Vec3::ZERO,
            omega: plant.omega_rate(&x.omega),
        };
        let k1 = still(&s);
        let k2 = still(&s.add_scaled(&k1, 0.5 * h));
        let k3 = still(&s.add_scaled(&k2, 0.5 * h));
        let k4 = still(&s.add_scaled(&k3, h));
        let want = s
            .add_scaled(&k1, h / 6.0)
            .add_scaled(&k2, h / 3.0)
            .add_scaled(&k3, h / 3.0)
            .add_scaled(&k4, h / 6.0);
        assert_eq!(format!("{:?}", plant.rk4_held(h)), format!("{want:?}"));
    }
}

#[test]
fn stopped_rotors_come_to_rest_at_zero_not_in_subnormals() {
    let p = Preset::builtin("racer5").map(|p| p.plant_params());
    let mut plant = p.and_then(Plant::new).unwrap_or_else(|e| panic!("{e}"));
    plant.set_motor_commands([0.3; 4], true);
    plant.advance_to(1_000_000_000);
    assert!(plant.state().omega.iter().all(|&w| w > 100.0));
    plant.set_motor_commands([0.0; 4], false);
    // ln(1000 rad/s / 1e-3 rad/s) · 20 ms = 0.28 s to rest; the
    // subnormal range begins only after ln(1000/2.2e-308) · 20 ms = 14 s.
    plant.advance_to(1_400_000_000);
    assert_eq!(plant.state().omega, [0.0; 4]);
    plant.advance_to(60_000_000_000);
    assert!(plant
        .state()
        .omega
        .iter()
        .all(|w| *w == 0.0 && !w.is_subnormal()));
}

#[test]
fn implausible_presets_are_refused_naming_the_field() {
    // Before: mass_kg = 1e-30 flew NaNs and "landed"; five rotor
    // positions were cut to four while three were refused.
    use crate::preset::RACER5_TOML;
    let err = |text: String| match Preset::from_toml_str(&text) {
        Ok(_) => panic!("accepted: {text}"),
        Err(e) => e.to_string(),
    };
    let e = err(RACER5_TOML.replace("mass_kg = 0.830", "mass_kg = 1e-30"));
    assert!(
        e.contains("body.mass_kg") && e.contains("[0.01, 100]"),
        "{e}"
    );
    let e = err(RACER5_TOML.replace("k_f = 7.7237e-7", "k_f = 1e-12"));
    assert!(e.contains("thrust over weight"), "{e}");
    let five = "positions_m = [[0.1, 0.1], [-0.085, -0.0675],";
    let e = err(RACER5_TOML.replace("positions_m = [[-0.085, -0.0675],", five));
    assert!(e.contains("rotors.positions_m needs exactly 4"), "{e}");
    let e = err(RACER5_TOML.replace("[-0.085, -0.0675], [0.085, -0.0675],", ""));
    assert!(e.contains("found 2") || e.contains("exactly 4"), "{e}");
    let e = err(RACER5_TOML.replace(r#"spin = ["cw", "ccw", "ccw", "cw"]"#, r#"spin = ["cw"]"#));
    assert!(e.contains("rotors.spin needs exactly 4"), "{e}");
}

#[test]
fn a_diverging_integration_is_a_crash_not_nans() {
    let p = Preset::builtin("racer5").map(|p| p.plant_params());
    let mut plant = p.and_then(Plant::new).unwrap_or_else(|e| panic!("{e}"));
    let mut s = *plant.state();
    s.pos.z = 10.0;
    s.rate = Vec3::new(1e200, 1e200, 1e200);
    plant.set_state(s);
    plant.advance_to(10_000_000);
    let t = plant.truth();
    assert!(t.crashed);
    assert!(t.pos.x.is_finite() && t.pos.z.is_finite(), "{:?}", t.pos);
}

#[test]
fn drag_acts_on_the_airspeed() {
    // The linear-drag plant (aero off): at rest in a 3 m/s wind, pushed
    // downwind at drag·3/m.
    let mut p = Preset::builtin("racer5")
        .map(|p| p.plant_params())
        .unwrap_or_else(|e| panic!("{e}"));
    p.body.drag_linear = 0.06;
    p.aero = AeroParams::default();
    let mut plant = Plant::new(p).unwrap_or_else(|e| panic!("{e}"));
    let mut s = *plant.state();
    s.pos.z = 10.0;
    plant.set_state(s);
    plant.set_wind(Vec3::new(3.0, 0.0, 0.0));
    let sf = plant.truth().specific_force;
    let ax = 0.06 * 3.0 / p.body.mass_kg;
    assert!((sf.x - ax).abs() < 1e-12, "{sf:?} vs {ax}");
}

/// With the rotors spinning, a gust on the hubs above the centre of mass
/// turns the vehicle: an angular acceleration about the axis the
/// aerodynamic moment gives, which the linear-drag plant never has.
#[test]
fn a_gust_turns_the_vehicle_through_the_rotors() {
    let mut p = Preset::builtin("racer5")
        .map(|p| p.plant_params())
        .unwrap_or_else(|e| panic!("{e}"));
    p.aero = AeroParams {
        rotor_drag: 2.6e-5,
        rotor_height_m: 0.015,
        ..AeroParams::default()
    };
    let mut plant = Plant::new(p).unwrap_or_else(|e| panic!("{e}"));
    let mut s = *plant.state();
    s.pos.z = 10.0;
    s.omega = [1600.0; 4];
    plant.set_state(s);
    plant.set_wind(Vec3::new(3.0, 0.0, 0.0));
    let t = plant.truth();
    // Wind toward +x: the top goes downwind, a positive pitch.
    assert!(t.ang_accel.y > 1.0, "{:?}", t.ang_accel);
    let mut off = p;
    off.aero = AeroParams::default();
    let mut plant = Plant::new(off).unwrap_or_else(|e| panic!("{e}"));
    plant.set_state(s);
    plant.set_wind(Vec3::new(3.0, 0.0, 0.0));
    assert_eq!(plant.truth().ang_accel, Vec3::ZERO);
}
