//! Vehicle presets: TOML data files (crates/flight/presets/*.toml, built in
//! with `include_str!`, or a user file) holding the plant, battery,
//! controller and autopilot parameters of one vehicle.

use crate::battery::BatteryParams;
use crate::error::ConfigError;
use crate::imu::{ImuConfig, Vibration};
use crate::math::Vec3;
use crate::pid::PidConfig;
use crate::plant::{AeroParams, BodyParams, PlantParams, RotorParams};
use crate::radio::AutopilotConfig;
use serde::Deserialize;

/// Source of the built-in `racer5` preset.
pub const RACER5_TOML: &str = include_str!("../presets/racer5.toml");
/// Source of the built-in `aero1kg` preset.
pub const AERO1KG_TOML: &str = include_str!("../presets/aero1kg.toml");
/// Names of the built-in presets.
pub const BUILTIN: [&str; 2] = ["racer5", "aero1kg"];

/// A complete vehicle description.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    /// Name.
    pub name: String,
    /// Rigid body.
    pub body: BodyParams,
    /// Rotors.
    pub rotors: RotorParams,
    /// Rotor aerodynamics (`[aero]`; all off when omitted: the linear-drag
    /// plant of `body.drag_linear`).
    #[serde(default)]
    pub aero: AeroParams,
    /// Battery.
    pub battery: BatteryParams,
    /// Attitude controller gains.
    pub pid: PidConfig,
    /// The gyro filters of a loop at the gyro's data-ready rate (the
    /// `gyro_filter` body's; `[gyro_filter]`, optional for a vehicle that
    /// flies only Cleanflight's structure).
    #[serde(default)]
    pub gyro_filter: Option<crate::filter::GyroFilterConfig>,
    /// Autopilot gains.
    pub autopilot: AutopilotConfig,
    /// The IMU's errors in a disturbed world (`[imu]`; none when omitted).
    #[serde(default)]
    pub imu: ImuErrors,
    /// This vehicle's own tolerances, replacing the mission's
    /// (`[criteria]`; none when omitted).
    #[serde(default)]
    pub criteria: crate::radio::CriteriaOverride,
    /// Where it came from, for errors that blame one of its keys: "preset
    /// file PATH" or "built-in preset NAME" (not a key of the file).
    #[serde(skip)]
    pub source: String,
}

/// What a real IMU on this vehicle adds to the datasheet noise: residual
/// bias, scale error and the rotors' vibration. Flights use them only in a
/// disturbed world (a mission's `[world] sensor_errors = true`), so the
/// calm missions fly the datasheet IMU.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImuErrors {
    /// Gyro bias left after the boot calibration, °/s per axis.
    pub gyro_bias_dps: [f64; 3],
    /// Accelerometer bias left after trimming, m/s² per axis.
    pub accel_bias_mps2: [f64; 3],
    /// Gyro scale error per axis, a fraction.
    pub gyro_scale_error: [f64; 3],
    /// Accelerometer scale error per axis, a fraction.
    pub accel_scale_error: [f64; 3],
    /// Gyro vibration per rotor and axis at the hover speed, °/s, at the
    /// rotation frequency and its 2nd and 3rd harmonics.
    pub gyro_vibration_dps: [f64; 3],
    /// Accelerometer vibration per rotor and axis at the hover speed, m/s²,
    /// harmonics 1, 2, 3.
    pub accel_vibration_mps2: [f64; 3],
    /// The firmware's accelerometer low-pass cut-off, Hz, applied to the
    /// vibration only (0: none); see [`Vibration::accel_lpf_hz`].
    pub accel_lpf_hz: f64,
}

impl ImuErrors {
    /// Every field finite; amplitudes ≥ 0; scale errors within ±10 %.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let groups = [
            ("imu.gyro_bias_dps", self.gyro_bias_dps, -10.0, 10.0),
            ("imu.accel_bias_mps2", self.accel_bias_mps2, -5.0, 5.0),
            ("imu.gyro_scale_error", self.gyro_scale_error, -0.1, 0.1),
            ("imu.accel_scale_error", self.accel_scale_error, -0.1, 0.1),
            (
                "imu.gyro_vibration_dps",
                self.gyro_vibration_dps,
                0.0,
                500.0,
            ),
            (
                "imu.accel_vibration_mps2",
                self.accel_vibration_mps2,
                0.0,
                200.0,
            ),
            ("imu.accel_lpf_hz", [self.accel_lpf_hz; 3], 0.0, 1000.0),
        ];
        for (name, v, lo, hi) in groups {
            for (i, x) in v.iter().enumerate() {
                crate::error::in_range(&format!("{name}[{i}]"), *x, lo, hi)?;
            }
        }
        Ok(())
    }

    /// `cfg` with these errors, the vibration's amplitudes given at the
    /// rotor speed `hover_omega_rad_s`, rotors at `positions_m`.
    pub fn apply(
        &self,
        cfg: ImuConfig,
        hover_omega_rad_s: f64,
        positions_m: [[f64; 2]; 4],
    ) -> ImuConfig {
        let rad = |d: [f64; 3]| d.map(f64::to_radians);
        ImuConfig {
            gyro_bias: cfg.gyro_bias + Vec3::from_array(rad(self.gyro_bias_dps)),
            accel_bias: cfg.accel_bias + Vec3::from_array(self.accel_bias_mps2),
            gyro_scale_error: Vec3::from_array(self.gyro_scale_error),
            accel_scale_error: Vec3::from_array(self.accel_scale_error),
            vibration: Vibration {
                gyro_rad_s: rad(self.gyro_vibration_dps),
                accel_mps2: self.accel_vibration_mps2,
                ref_omega_rad_s: hover_omega_rad_s,
                arm_dir: positions_m.map(|[x, y]| {
                    let r = x.hypot(y).max(1e-9);
                    [y / r, -x / r]
                }),
                accel_lpf_hz: self.accel_lpf_hz,
            },
            ..cfg
        }
    }
}

impl Preset {
    /// Parse and validate; errors name the offending field.
    pub fn from_toml_str(src: &str) -> Result<Self, ConfigError> {
        let p: Preset = toml::from_str(src).map_err(|e| {
            let at = e
                .span()
                .map(|s| format!(" (at byte {})", s.start))
                .unwrap_or_default();
            ConfigError::new("preset", format!("{}{at}", e.message()))
        })?;
        p.validate_all()?;
        Ok(p)
    }

    /// Every part checked, and the name printable.
    fn validate_all(&self) -> Result<(), ConfigError> {
        crate::error::check_name("name", &self.name)?;
        self.plant_params().validate()?;
        self.battery.validate()?;
        self.pid.validate()?;
        self.autopilot.validate()?;
        self.imu.validate()?;
        self.criteria.validate()
    }

    /// Read a user preset file by the rules of every input file
    /// ([`rtpipe_model::input`]); errors name the file, and the line and
    /// column of a syntax error or the offending field.
    pub fn from_file(path: &std::path::Path) -> Result<Self, rtpipe_model::SpecError> {
        crate::error::load(path, &rtpipe_model::input::Kind::PRESET, |p: Preset| {
            p.validate_all()?;
            Ok(Preset {
                source: format!("preset file {}", path.display()),
                ..p
            })
        })
    }

    /// A built-in preset by name.
    pub fn builtin(name: &str) -> Result<Self, ConfigError> {
        let p = match name {
            "racer5" => Self::from_toml_str(RACER5_TOML),
            "aero1kg" => Self::from_toml_str(AERO1KG_TOML),
            _ => Err(ConfigError::new(
                "preset",
                format!("unknown built-in preset {name:?} (racer5, aero1kg)"),
            )),
        }?;
        Ok(Preset {
            source: format!("built-in preset {name} (crates/flight/presets/{name}.toml)"),
            ..p
        })
    }

    /// The rotor speed at which the four rotors carry the weight, rad/s.
    pub fn hover_omega_rad_s(&self) -> f64 {
        let pp = self.plant_params();
        pp.omega_for_cmd(pp.hover_cmd())
    }

    /// The plant parameters, with the RK4 sub-step its dynamics call for
    /// ([`PlantParams::with_substep`]).
    pub fn plant_params(&self) -> PlantParams {
        PlantParams::with_substep(self.body, self.rotors, self.aero)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_load_with_plausible_physics() {
        for n in BUILTIN {
            let p = Preset::builtin(n).unwrap();
            let pp = p.plant_params();
            let tw = pp.thrust_to_weight();
            let h = pp.hover_cmd();
            assert!(tw > 1.5 && tw < 6.0, "{n}: T/W {tw}");
            assert!(h > 0.2 && h < 0.8, "{n}: hover {h}");
        }
        // racer5: gym-pybullet-drones' thrust2weight = 4.17 (with g = 9.8).
        let r = Preset::builtin("racer5").unwrap().plant_params();
        assert!((r.thrust_to_weight() - 4.17).abs() < 0.02);
        // aero1kg: SIH's T_MAX = 5 N per rotor, Q_MAX = 0.1 N·m.
        let a = Preset::builtin("aero1kg").unwrap().rotors;
        assert!((a.k_f * a.omega_max_rad_s.powi(2) - 5.0).abs() < 1e-9);
        assert!((a.k_m * a.omega_max_rad_s.powi(2) - 0.1).abs() < 1e-9);
    }

    #[test]
    fn bad_presets_name_the_field() {
        let bad = RACER5_TOML.replace("mass_kg = 0.830", "mass_kg = -1.0");
        let e = Preset::from_toml_str(&bad).unwrap_err();
        assert_eq!(e.field, "body.mass_kg", "{e}");
        let bad = RACER5_TOML.replace("mass_kg = 0.830", "");
        let e = Preset::from_toml_str(&bad).unwrap_err();
        assert!(e.reason.contains("mass_kg"), "{e}");
        let bad = RACER5_TOML.replace("dterm_lpf_hz = 75.0", "dterm_lpf_hz = \"fast\"");
        assert!(Preset::from_toml_str(&bad).is_err());
        assert!(Preset::builtin("x500").is_err());
    }
}
