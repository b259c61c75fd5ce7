//! Vehicle presets: TOML data files (crates/flight/presets/*.toml, built in
//! with `include_str!`, or a user file) holding the plant, battery,
//! controller and autopilot parameters of one vehicle.

use crate::battery::BatteryParams;
use crate::error::ConfigError;
use crate::pid::PidConfig;
use crate::plant::{BodyParams, PlantParams, RotorParams, SUBSTEP_NS_DEFAULT};
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
    /// Battery.
    pub battery: BatteryParams,
    /// Attitude controller gains.
    pub pid: PidConfig,
    /// Autopilot gains.
    pub autopilot: AutopilotConfig,
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
        p.plant_params().validate()?;
        p.battery.validate()?;
        p.pid.validate()?;
        p.autopilot.validate()?;
        Ok(p)
    }

    /// Read a user preset file.
    pub fn from_file(path: &std::path::Path) -> Result<Self, ConfigError> {
        Self::from_toml_str(&crate::error::read_file(path)?)
    }

    /// A built-in preset by name.
    pub fn builtin(name: &str) -> Result<Self, ConfigError> {
        match name {
            "racer5" => Self::from_toml_str(RACER5_TOML),
            "aero1kg" => Self::from_toml_str(AERO1KG_TOML),
            _ => Err(ConfigError::new(
                "preset",
                format!("unknown built-in preset {name:?} (racer5, aero1kg)"),
            )),
        }
    }

    /// The plant parameters with the default RK4 sub-step.
    pub fn plant_params(&self) -> PlantParams {
        PlantParams {
            body: self.body,
            rotors: self.rotors,
            substep_ns: SUBSTEP_NS_DEFAULT,
        }
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
