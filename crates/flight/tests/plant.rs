//! Plant tests: RK4 against closed forms, and the mixer's signs checked in
//! the plant (the angular acceleration the mixed motor commands produce).

use rtpipe_flight::math::{Euler, Quat, Vec3, GRAVITY};
use rtpipe_flight::mixer::mix;
use rtpipe_flight::pid::AxisCommand;
use rtpipe_flight::plant::{Plant, State};
use rtpipe_flight::preset::{Preset, BUILTIN};

fn plant(name: &str, drag: bool) -> Plant {
    let mut p = Preset::builtin(name).unwrap().plant_params();
    if !drag {
        p.body.drag_linear = 0.0;
        p.body.drag_angular = 0.0;
        p.aero = rtpipe_flight::plant::AeroParams::default();
    }
    Plant::new(p).unwrap()
}

fn airborne(p: &mut Plant, z: f64) {
    let s = *p.state();
    p.set_state(State {
        pos: Vec3::new(0.0, 0.0, z),
        vel: Vec3::ZERO,
        q: Quat::IDENTITY,
        rate: Vec3::ZERO,
        ..s
    });
}

#[test]
fn free_fall_matches_closed_form() {
    // Rotors stopped, no drag: z(t) = z0 − g t²/2. RK4 is exact for a
    // quadratic, so the tolerance is rounding only (1e-9 m over 1 s), and
    // the partial last step (1 s = 4000 sub-steps + 0) plus an odd
    // timestamp exercise advance_to.
    let mut p = plant("racer5", false);
    airborne(&mut p, 10.0);
    for t_ns in [123_457u64, 500_000_001, 1_000_000_000] {
        p.advance_to(t_ns);
        let t = t_ns as f64 * 1e-9;
        let z = 10.0 - 0.5 * GRAVITY * t * t;
        assert!(
            (p.state().pos.z - z).abs() < 1e-9,
            "t={t}: {} vs {z}",
            p.state().pos.z
        );
        assert!((p.state().vel.z + GRAVITY * t).abs() < 1e-9);
    }
    // Hitting the ground at ~10 m/s is a crash; the body rests at z = 0.
    p.advance_to(2_000_000_000);
    let tr = p.truth();
    assert_eq!(tr.pos.z, 0.0);
    assert!(tr.crashed && tr.on_ground);
}

#[test]
fn motor_spin_up_matches_first_order_lag() {
    // ω(t) = ω_target (1 − e^(−t/τ)). RK4's step multiplies the gap to
    // the target by 1 + z + z²/2 + z³/6 + z⁴/24 (z = −h/τ) instead of e^z:
    // (h/τ)⁵/120 too little per step, so after n steps the error is about
    // n·e^(−(n−1)h/τ)·(h/τ)⁵/120 of the target, at most
    // (h/τ)⁴·e^(h/τ − 1)/120 (n = τ/h): 2.0e-8 for h = 1 ms, τ = 20 ms.
    let mut p = plant("racer5", true);
    let pp = *p.params();
    let x = pp.substep_ns as f64 * 1e-9 / pp.rotors.time_constant_s;
    let bound = 1.1 * x.powi(4) * (x - 1.0).exp() / 120.0;
    p.set_motor_commands([0.3; 4], true);
    let target = pp.omega_for_cmd(0.3);
    for t_ns in [5_000_000u64, 20_000_000, 60_000_000] {
        p.advance_to(t_ns);
        let t = t_ns as f64 * 1e-9;
        let w = target * (1.0 - (-t / pp.rotors.time_constant_s).exp());
        let got = p.state().omega[0];
        assert!((got - w).abs() < bound * target, "t={t}: {got} vs {w}");
    }
    // Below hover thrust the vehicle stays on the ground.
    assert!(p.truth().on_ground && p.state().pos.z == 0.0);
}

#[test]
fn mixer_signs_give_the_right_body_torque_in_the_plant() {
    for name in BUILTIN {
        for (axis, cmd) in [
            (0, [0.1, 0.0, 0.0]),
            (1, [0.0, 0.1, 0.0]),
            (2, [0.0, 0.0, 0.1]),
        ] {
            let mut p = plant(name, false);
            airborne(&mut p, 5.0);
            let hover = p.params().hover_cmd();
            let c = AxisCommand {
                roll: cmd[0],
                pitch: cmd[1],
                yaw: cmd[2],
                throttle: hover,
            };
            let m = mix(&c);
            // Start the rotors at their targets so the torque is immediate.
            let mut s = *p.state();
            for (o, u) in s.omega.iter_mut().zip(m.motors.iter()) {
                *o = p.params().omega_for_cmd(*u);
            }
            p.set_state(s);
            p.set_motor_commands(m.motors, true);
            let a = p.truth().ang_accel;
            let (on, off) = (a.axis(axis), [a.x, a.y, a.z]);
            assert!(on > 1.0, "{name} axis {axis}: angular acceleration {on}");
            for (k, v) in off.iter().enumerate() {
                if k != axis {
                    assert!(
                        v.abs() < 1e-9 * on.abs().max(1.0),
                        "{name} axis {axis}: cross-coupling {v} on {k}"
                    );
                }
            }
            // And the rotation goes the right way: roll lowers the right
            // side, pitch lowers the nose, yaw turns left.
            p.advance_to(50_000_000);
            let e = p.truth().euler;
            let got = [e.roll, e.pitch, e.yaw][axis];
            assert!(got > 0.0, "{name} axis {axis}: angle {got}");
        }
    }
}

#[test]
fn hover_command_holds_altitude_open_loop() {
    for name in BUILTIN {
        let mut p = plant(name, true);
        airborne(&mut p, 2.0);
        let h = p.params().hover_cmd();
        let mut s = *p.state();
        s.omega = [p.params().omega_for_cmd(h); 4];
        p.set_state(s);
        p.set_motor_commands([h; 4], true);
        p.advance_to(1_000_000_000);
        let tr = p.truth();
        assert!((tr.pos.z - 2.0).abs() < 1e-9, "{name}: z {}", tr.pos.z);
        assert!((tr.specific_force.z - GRAVITY).abs() < 1e-9);
        assert_eq!(tr.euler, Euler::default());
    }
}

/// The sub-step's accuracy where flights use it: each built-in vehicle
/// airborne, a new random motor command every 5 ms (a PWM task's period)
/// around hover, sampled at odd instants between the grid points (dense
/// output) as the IMU is, against the same plant integrated with a
/// sub-step 64 times shorter. The bound is the measured error's order:
/// far below the gyro's noise (0.28 °/s = 5e-3 rad/s) and the accelerometer's
/// (about 0.05 m/s²).
#[test]
fn the_default_sub_step_tracks_a_64_times_finer_one() {
    for name in BUILTIN {
        let coarse = Preset::builtin(name).unwrap().plant_params();
        let fine = rtpipe_flight::plant::PlantParams {
            substep_ns: coarse.substep_ns / 64,
            ..coarse
        };
        let (mut a, mut b) = (Plant::new(coarse).unwrap(), Plant::new(fine).unwrap());
        for p in [&mut a, &mut b] {
            airborne(p, 50.0);
        }
        let hover = coarse.hover_cmd();
        let mut rng = rtpipe_model::gen::Rng::new(1);
        let mut rnd = || rng.unit();
        let (mut rate_err, mut sf_err, mut pos_err) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..400u64 {
            let cmd = std::array::from_fn(|_| (hover + 0.3 * (rnd() - 0.5)).clamp(0.0, 1.0));
            for p in [&mut a, &mut b] {
                p.set_motor_commands(cmd, true);
            }
            for j in 1..5u64 {
                let t = k * 5_000_000 + j * 1_000_000 + 123_457 * j;
                a.advance_to(t);
                b.advance_to(t);
                let (ta, tb) = (a.truth(), b.truth());
                rate_err = rate_err.max((ta.rate - tb.rate).norm());
                sf_err = sf_err.max((ta.specific_force - tb.specific_force).norm());
                pos_err = pos_err.max((ta.pos - tb.pos).norm());
            }
            a.advance_to((k + 1) * 5_000_000);
            b.advance_to((k + 1) * 5_000_000);
        }
        assert!(!a.truth().on_ground && !a.truth().crashed, "{name}");
        eprintln!("{name}: h {} ns: rate {rate_err:.2e} rad/s, specific force {sf_err:.2e} m/s², position {pos_err:.2e} m", coarse.substep_ns);
        assert!(rate_err < 1e-5 && sf_err < 1e-4 && pos_err < 1e-5, "{name}");
    }
}
