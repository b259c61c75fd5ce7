//! Rotor aerodynamics: how the air moving past the vehicle (its own motion
//! and the wind) pushes on each rotor and on the frame, and the moments
//! those pushes make about the centre of mass. This is what turns a gust
//! into a tilt: a rotor's drag acts at its hub, which sits above the centre
//! of mass, so a horizontal gust pushes the top of the vehicle downwind.
//!
//! The model is rotorpy's (github.com/spencerfolk/rotorpy,
//! `rotorpy/vehicles/multirotor.py`, `Multirotor::compute_body_wrench`),
//! restated here with the airspeed v_i at rotor i (body frame) and its
//! speed Ω_i:
//!
//! ```text
//! v_i    = R⊤(v − w) + ω × r_i                 (r_i: hub position, body)
//! H_i    = −Ω_i · (k_d v_i,x, k_d v_i,y, k_z v_i,z)   rotor drag, induced inflow
//! L_i    = k_h (v_i,x² + v_i,y²) ẑ               translational lift
//! M_fl,i = −k_flap Ω_i (v_i × ẑ)                 blade flapping (rotorpy's sign)
//! D      = −|v_b| · diag(c_D) · v_b               parasitic drag of the frame, v_b = R⊤(v − w)
//! F      = Σ (H_i + L_i) + D,   M = Σ (r_i × (H_i + L_i) + M_fl,i)
//! ```
//!
//! The rotors' thrust k_f Ω² and reaction torque stay in the plant's
//! wrench; their moment does not depend on the hub height (the thrust is
//! along z). With every coefficient zero the plant is the linear-drag one,
//! bit for bit (the wrench skips this module).

use crate::error::{in_range, ConfigError};
use crate::math::Vec3;
use serde::Deserialize;

/// The `[aero]` table of a preset: rotorpy's aerodynamic coefficients.
/// Omitted, every term is off.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AeroParams {
    /// Rotor drag (H-force) in the rotor plane, k_d, N per (rad/s · m/s).
    pub rotor_drag: f64,
    /// Induced-inflow drag along the rotor axis, k_z, N per (rad/s · m/s).
    pub induced_inflow: f64,
    /// Translational lift, k_h, N per (m/s)² of in-plane airspeed.
    pub translational_lift: f64,
    /// Blade-flapping moment, k_flap, N·m per (rad/s · m/s).
    pub flapping: f64,
    /// Parasitic (frame) drag per body axis, c_D, N per (m/s)².
    pub parasitic_drag: [f64; 3],
    /// Height of the rotor hubs above the centre of mass, m (the lever of
    /// the rotor drag about roll and pitch).
    pub rotor_height_m: f64,
}

/// The aerodynamic force and moment on the body, both in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeroWrench {
    /// Force, N (body).
    pub force: Vec3,
    /// Moment about the centre of mass, N·m (body).
    pub moment: Vec3,
}

impl AeroParams {
    /// Every term off: the plant is the linear-drag one.
    pub fn is_off(&self) -> bool {
        *self == AeroParams::default()
    }

    /// Each coefficient finite and within a physical range; the error names
    /// the key. Ranges: a 10 g micro quad's coefficients to a 100 kg
    /// lifter's (rotorpy's Crazyflie k_d is 1e-6, its Hummingbird's 1.2e-4).
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("aero.rotor_drag", self.rotor_drag, 0.0, 0.1)?;
        in_range("aero.induced_inflow", self.induced_inflow, 0.0, 0.1)?;
        in_range("aero.translational_lift", self.translational_lift, 0.0, 1.0)?;
        in_range("aero.flapping", self.flapping, 0.0, 0.1)?;
        for (i, c) in self.parasitic_drag.iter().enumerate() {
            in_range(&format!("aero.parasitic_drag[{i}]"), *c, 0.0, 10.0)?;
        }
        in_range("aero.rotor_height_m", self.rotor_height_m, -1.0, 1.0)?;
        Ok(())
    }

    /// The linear damping the rotor terms add at rotor speed `omega_max`
    /// (every rotor at it), as (velocity, N per m/s; rate, N·m per rad/s):
    /// the plant's sub-step and plausibility checks treat them as they
    /// treat `body.drag_linear` and `body.drag_angular`. The rate damping
    /// bounds the ω × r terms: k_z acts on the arm's in-plane lever, k_d on
    /// the hub height, and the flapping moment on its product with it.
    pub fn damping(&self, positions_m: &[[f64; 2]; 4], omega_max: f64) -> (f64, f64) {
        let arm2 = positions_m
            .iter()
            .map(|[x, y]| x * x + y * y)
            .fold(0.0, f64::max);
        let h = self.rotor_height_m;
        let velocity = 4.0 * omega_max * self.rotor_drag.max(self.induced_inflow);
        let rate = 4.0
            * omega_max
            * (self.induced_inflow * arm2 + self.rotor_drag * h * h + self.flapping * h.abs());
        (velocity, rate)
    }

    /// The aerodynamic wrench at body airspeed `airspeed_b` (the body's
    /// velocity minus the wind, in the body frame), body rate `rate` and
    /// rotor speeds `omega`, rotors at `positions_m` (x, y) and this
    /// table's hub height.
    pub fn wrench(
        &self,
        positions_m: &[[f64; 2]; 4],
        omega: &[f64; 4],
        rate: Vec3,
        airspeed_b: Vec3,
    ) -> AeroWrench {
        let c = self.parasitic_drag;
        let drag = Vec3::new(c[0], c[1], c[2]).hadamard(airspeed_b) * -airspeed_b.norm();
        let mut force = drag;
        let mut moment = Vec3::ZERO;
        for ([x, y], w) in positions_m.iter().zip(omega) {
            let r = Vec3::new(*x, *y, self.rotor_height_m);
            let v = airspeed_b + rate.cross(r);
            let lift = self.translational_lift * (v.x * v.x + v.y * v.y);
            let f = Vec3::new(
                -w * self.rotor_drag * v.x,
                -w * self.rotor_drag * v.y,
                -w * self.induced_inflow * v.z + lift,
            );
            let flap = Vec3::new(v.y, -v.x, 0.0) * (-self.flapping * w);
            force += f;
            moment += r.cross(f) + flap;
        }
        AeroWrench { force, moment }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RACER: [[f64; 2]; 4] = [
        [-0.085, -0.0675],
        [0.085, -0.0675],
        [-0.085, 0.0675],
        [0.085, 0.0675],
    ];

    fn rotor_drag_only(h: f64) -> AeroParams {
        AeroParams {
            rotor_drag: 1e-5,
            rotor_height_m: h,
            ..AeroParams::default()
        }
    }

    #[test]
    fn a_gust_on_hubs_above_the_centre_of_mass_tilts_the_top_downwind() {
        // Wind 5 m/s toward +x on a vehicle at rest: airspeed (−5, 0, 0).
        let a = rotor_drag_only(0.03);
        let w = a.wrench(&RACER, &[1000.0; 4], Vec3::ZERO, Vec3::new(-5.0, 0.0, 0.0));
        assert!(
            (w.force.x - 4.0 * 1e-5 * 1000.0 * 5.0).abs() < 1e-12,
            "{w:?}"
        );
        // Pitch about +y lowers the nose (+x): the top goes downwind.
        assert!((w.moment.y - 0.03 * w.force.x).abs() < 1e-12, "{w:?}");
        assert!(
            w.moment.x.abs() < 1e-12 && w.moment.z.abs() < 1e-12,
            "{w:?}"
        );
        // Hubs in the centre of mass's plane: the same push, no tilt.
        let flat = rotor_drag_only(0.0).wrench(
            &RACER,
            &[1000.0; 4],
            Vec3::ZERO,
            Vec3::new(-5.0, 0.0, 0.0),
        );
        assert_eq!(flat.force, w.force);
        assert!(flat.moment.norm() < 1e-15, "{flat:?}");
    }

    #[test]
    fn the_rotor_terms_damp_the_body_rates() {
        let a = AeroParams {
            induced_inflow: 2e-5,
            ..rotor_drag_only(0.03)
        };
        let rate = Vec3::new(1.0, -2.0, 0.5);
        let w = a.wrench(&RACER, &[1500.0; 4], rate, Vec3::ZERO);
        assert!(w.moment.dot(rate) < 0.0, "{w:?}");
    }

    #[test]
    fn off_is_the_default_and_bad_values_name_their_key() {
        assert!(AeroParams::default().is_off());
        assert!(!rotor_drag_only(0.0).is_off());
        let bad = AeroParams {
            rotor_drag: -1.0,
            ..AeroParams::default()
        };
        assert_eq!(
            bad.validate().map_err(|e| e.field),
            Err("aero.rotor_drag".into())
        );
        let bad = AeroParams {
            parasitic_drag: [0.0, f64::NAN, 0.0],
            ..AeroParams::default()
        };
        assert_eq!(
            bad.validate().map_err(|e| e.field),
            Err("aero.parasitic_drag[1]".into())
        );
    }
}
