//! Missions: a TOML time line of pilot intents.
//!
//! ```toml
//! name = "example"
//! [[step]]
//! at = "0.5s"          # or "500ms", or a number of seconds: at = 0.5
//! arm = true
//! [[step]]
//! at = 1.0
//! altitude_m = 1.0     # altitude hold (autopilot) to 1 m
//! hold_position = true # position hold (autopilot); sticks override it
//! [[step]]
//! at = "6s"
//! roll_deg = 20        # roll stick (angle set-point)
//! [[step]]
//! at = "12s"
//! land = true          # descend at the landing speed, disarm on the ground
//! ```
//!
//! Each step changes only the fields it names; later steps win. Fields:
//! `arm`, `throttle` (manual, ends altitude hold), `altitude_m` (altitude
//! hold, ends manual throttle and landing), `land`, `roll_deg`,
//! `pitch_deg`, `yaw_rate_dps`, `yaw_deg` (heading hold target, relative
//! to the initial heading), `hold_position`.

use crate::error::{in_range, ConfigError};
use crate::wind::{Dryden, Intensity};
use rtpipe_model::input::Kind;
use rtpipe_model::{SpecError, MAX_TIME};
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
enum TimeSpec {
    Seconds(f64),
    Text(String),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct StepFile {
    at: TimeSpec,
    arm: Option<bool>,
    throttle: Option<f64>,
    altitude_m: Option<f64>,
    land: Option<bool>,
    roll_deg: Option<f64>,
    pitch_deg: Option<f64>,
    yaw_rate_dps: Option<f64>,
    yaw_deg: Option<f64>,
    hold_position: Option<bool>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct MissionFile {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    step: Vec<StepFile>,
    /// What the flight must meet; omitted fields keep their defaults.
    #[serde(default)]
    criteria: Criteria,
    /// The world it flies in; calm when omitted.
    #[serde(default)]
    world: World,
}

/// The world a mission flies in (its `[world]` table): turbulence (the
/// Dryden model, [`crate::wind`]) and the vehicle's IMU errors (its
/// preset's `[imu]`). The default is the calm world with the datasheet
/// IMU, which every mission without the table flies.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct World {
    /// MIL-F-8785C intensity: none, light, moderate, severe.
    pub turbulence: Intensity,
    /// The height the turbulence's scales and intensities are taken at, m.
    pub altitude_m: f64,
    /// The speed V at which the turbulence passes the vehicle, m/s.
    pub speed_mps: f64,
    /// Use the preset's IMU bias, scale error and vibration.
    pub sensor_errors: bool,
}

impl Default for World {
    fn default() -> World {
        World {
            turbulence: Intensity::None,
            altitude_m: 1.0,
            speed_mps: 5.0,
            sensor_errors: false,
        }
    }
}

impl World {
    /// The turbulence model, `None` in calm air.
    pub fn dryden(&self) -> Result<Option<Dryden>, ConfigError> {
        let d = Dryden::low_altitude(self.turbulence, self.altitude_m, self.speed_mps)
            .map_err(|e| ConfigError::new(e.field.replace("wind.", "world."), e.reason))?;
        Ok((self.turbulence != Intensity::None).then_some(d))
    }

    /// The world in words (empty for the calm one).
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.turbulence != Intensity::None {
            parts.push(format!(
                "{} turbulence (Dryden, at {} m, passing at {} m/s)",
                self.turbulence.name(),
                self.altitude_m,
                self.speed_mps
            ));
        }
        if self.sensor_errors {
            parts.push("IMU bias, scale error and rotor vibration".to_string());
        }
        parts.join("; ")
    }
}

/// One validated step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MissionStep {
    /// When it applies, ns from the mission start.
    pub t_ns: u64,
    /// Arm switch.
    pub arm: Option<bool>,
    /// Manual throttle.
    pub throttle: Option<f64>,
    /// Altitude-hold target, m.
    pub altitude_m: Option<f64>,
    /// Land.
    pub land: Option<bool>,
    /// Roll stick, deg.
    pub roll_deg: Option<f64>,
    /// Pitch stick, deg.
    pub pitch_deg: Option<f64>,
    /// Yaw stick, deg/s.
    pub yaw_rate_dps: Option<f64>,
    /// Heading target, deg.
    pub yaw_deg: Option<f64>,
    /// Position hold.
    pub hold_position: Option<bool>,
}

/// The pilot's intent at one instant (all steps so far folded together).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PilotIntent {
    /// Arm switch.
    pub arm: bool,
    /// Manual throttle (None: autopilot or zero).
    pub throttle: Option<f64>,
    /// Altitude-hold target, m.
    pub altitude_m: Option<f64>,
    /// Landing.
    pub land: bool,
    /// Roll stick, deg.
    pub roll_deg: f64,
    /// Pitch stick, deg.
    pub pitch_deg: f64,
    /// Yaw stick, deg/s.
    pub yaw_rate_dps: f64,
    /// Heading target, deg.
    pub yaw_deg: Option<f64>,
    /// Position hold on.
    pub hold_position: bool,
}

impl PilotIntent {
    fn apply(&mut self, s: &MissionStep) {
        if let Some(a) = s.arm {
            self.arm = a;
        }
        if let Some(t) = s.throttle {
            self.throttle = Some(t);
            self.altitude_m = None;
            self.land = false;
        }
        if let Some(h) = s.altitude_m {
            self.altitude_m = Some(h);
            self.throttle = None;
            self.land = false;
        }
        if let Some(l) = s.land {
            self.land = l;
        }
        self.roll_deg = s.roll_deg.unwrap_or(self.roll_deg);
        self.pitch_deg = s.pitch_deg.unwrap_or(self.pitch_deg);
        self.yaw_rate_dps = s.yaw_rate_dps.unwrap_or(self.yaw_rate_dps);
        if s.yaw_deg.is_some() {
            self.yaw_deg = s.yaw_deg;
        }
        self.hold_position = s.hold_position.unwrap_or(self.hold_position);
    }
}

/// The most steps a mission may have (each one is a pilot's action; a
/// mission of ten thousand is already a script, not a flight).
pub const MAX_MISSION_STEPS: usize = 10_000;

/// A parsed mission.
#[derive(Debug, Clone, PartialEq)]
pub struct Mission {
    /// Name.
    pub name: String,
    /// Free text.
    pub description: String,
    /// Steps in time order.
    pub steps: Vec<MissionStep>,
    /// The tolerances the flight must meet (`[criteria]`, defaults otherwise).
    pub criteria: Criteria,
    /// The world it flies in (`[world]`, calm otherwise).
    pub world: World,
    /// The intent after each step (steps `0..=k` folded), so that
    /// [`Mission::intent_at`] is a binary search.
    intents: Vec<PilotIntent>,
}

/// Parse "2.5s", "250ms", "1500us" or "2" (seconds) into ns.
pub fn parse_time(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("ms") {
        (n, 1e6)
    } else if let Some(n) = t.strip_suffix("us") {
        (n, 1e3)
    } else if let Some(n) = t.strip_suffix("ns") {
        (n, 1.0)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1e9)
    } else {
        (t, 1e9)
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("not a time: {s:?} (use e.g. \"2.5s\" or \"250ms\")"))?;
    seconds_to_ns(v * scale / 1e9).ok_or_else(|| at_range(format!("{s:?}")))
}

/// The latest `at` of a step, s: the model's longest time
/// ([`rtpipe_model::MAX_TIME`], about 104 days).
pub const MAX_AT_S: f64 = MAX_TIME as f64 * 1e-9;

fn seconds_to_ns(v: f64) -> Option<u64> {
    (v.is_finite() && (0.0..=MAX_AT_S).contains(&v)).then(|| (v * 1e9).round() as u64)
}

/// The message for an `at` outside `0..=MAX_AT_S`.
fn at_range(got: impl std::fmt::Display) -> String {
    format!("must be a time from 0 to {MAX_AT_S:.0} s (about 104 days), got {got}")
}

fn check_step(i: usize, f: &StepFile) -> Result<MissionStep, ConfigError> {
    let field = |n: &str| format!("step[{i}].{n}");
    let t_ns = match &f.at {
        TimeSpec::Seconds(v) => {
            let shown = if v.abs() >= 1e6 {
                format!("{v:e}")
            } else {
                v.to_string()
            };
            seconds_to_ns(*v).ok_or_else(|| ConfigError::new(field("at"), at_range(shown)))?
        }
        TimeSpec::Text(s) => parse_time(s).map_err(|e| ConfigError::new(field("at"), e))?,
    };
    let opt = |n: &str, v: Option<f64>, lo: f64, hi: f64| -> Result<Option<f64>, ConfigError> {
        v.map(|x| in_range(&field(n), x, lo, hi)).transpose()
    };
    Ok(MissionStep {
        t_ns,
        arm: f.arm,
        throttle: opt("throttle", f.throttle, 0.0, 1.0)?,
        altitude_m: opt("altitude_m", f.altitude_m, 0.0, 100.0)?,
        land: f.land,
        roll_deg: opt("roll_deg", f.roll_deg, -60.0, 60.0)?,
        pitch_deg: opt("pitch_deg", f.pitch_deg, -60.0, 60.0)?,
        yaw_rate_dps: opt("yaw_rate_dps", f.yaw_rate_dps, -1000.0, 1000.0)?,
        yaw_deg: opt("yaw_deg", f.yaw_deg, -360.0, 360.0)?,
        hold_position: f.hold_position,
    })
}

/// Built-in `hover` mission source.
pub const HOVER_TOML: &str = include_str!("../../missions/hover.toml");
/// Built-in `steps` mission source.
pub const STEPS_TOML: &str = include_str!("../../missions/steps.toml");
/// Built-in `paper` mission source: the paper's synthetic radio input.
pub const PAPER_TOML: &str = include_str!("../../missions/paper.toml");
/// Built-in `gusty` mission source: a hover in moderate turbulence.
pub const GUSTY_TOML: &str = include_str!("../../missions/gusty.toml");
/// Built-in `breeze` mission source: roll and pitch steps in light
/// turbulence with the IMU's errors on. Its one home is the example file
/// the sweep flies (`examples/missions/sweep-steps-breeze.toml`); built in
/// so that `design --fly`'s default acceptance judges steps in turbulence
/// wherever it runs.
pub const BREEZE_TOML: &str = include_str!("../../../../examples/missions/sweep-steps-breeze.toml");
/// Names of the built-in missions.
pub const BUILTIN_MISSIONS: [&str; 5] = ["hover", "steps", "paper", "gusty", "breeze"];

impl Mission {
    /// Parse a mission; errors name the offending field.
    pub fn from_toml_str(src: &str) -> Result<Self, ConfigError> {
        let f: MissionFile = toml::from_str(src)
            .map_err(|e| ConfigError::new("mission", e.message().to_string()))?;
        Self::from_parsed(f)
    }

    /// Read and parse a mission file by the rules of every input file
    /// ([`rtpipe_model::input`]); errors name the file, and the line and
    /// column of a syntax error or the offending field.
    pub fn from_file(path: &std::path::Path) -> Result<Self, SpecError> {
        crate::error::load(path, &Kind::MISSION, Self::from_parsed)
    }

    fn from_parsed(f: MissionFile) -> Result<Self, ConfigError> {
        crate::error::check_name("name", &f.name)?;
        crate::error::check_text("description", &f.description)?;
        if f.step.len() > MAX_MISSION_STEPS {
            return Err(ConfigError::new(
                "step",
                format!(
                    "the mission has {} steps, more than the {MAX_MISSION_STEPS} rtpipe flies; merge steps or split the mission",
                    f.step.len()
                ),
            ));
        }
        let mut steps = Vec::with_capacity(f.step.len());
        for (i, s) in f.step.iter().enumerate() {
            let st = check_step(i, s)?;
            if steps.last().is_some_and(|p: &MissionStep| p.t_ns > st.t_ns) {
                return Err(ConfigError::new(
                    format!("step[{i}].at"),
                    "steps must be in time order",
                ));
            }
            steps.push(st);
        }
        f.criteria.validate()?;
        f.world.dryden()?;
        let mut now = PilotIntent::default();
        let intents = steps
            .iter()
            .map(|s| {
                now.apply(s);
                now
            })
            .collect();
        Ok(Self {
            name: f.name,
            description: f.description,
            steps,
            criteria: f.criteria,
            world: f.world,
            intents,
        })
    }

    /// A built-in mission by name (`hover`, `steps`, `paper`, `gusty`,
    /// `breeze`).
    pub fn builtin(name: &str) -> Result<Self, ConfigError> {
        match name {
            "hover" => Self::from_toml_str(HOVER_TOML),
            "steps" => Self::from_toml_str(STEPS_TOML),
            "paper" => Self::from_toml_str(PAPER_TOML),
            "gusty" => Self::from_toml_str(GUSTY_TOML),
            "breeze" => Self::from_toml_str(BREEZE_TOML),
            _ => Err(ConfigError::new(
                "mission",
                format!(
                    "unknown built-in mission {name:?} ({})",
                    BUILTIN_MISSIONS.join(", ")
                ),
            )),
        }
    }

    /// The pilot's intent at `t_ns`: every step at or before it folded
    /// (a binary search, O(log steps); no allocation).
    pub fn intent_at(&self, t_ns: u64) -> PilotIntent {
        let k = self.steps.partition_point(|s| s.t_ns <= t_ns);
        match k.checked_sub(1).and_then(|k| self.intents.get(k)) {
            Some(p) => *p,
            None => PilotIntent::default(),
        }
    }

    /// The same mission with every step after the start `by_ns` later
    /// (the arming at 0 stays): where a stick step falls in the output
    /// period is a phase of the flight, not of the controller.
    pub fn shifted(&self, by_ns: u64) -> Mission {
        let mut m = self.clone();
        for s in m.steps.iter_mut().filter(|s| s.t_ns > 0) {
            s.t_ns += by_ns;
        }
        m
    }

    /// Time of the last step, ns.
    pub fn end_ns(&self) -> u64 {
        self.steps.last().map_or(0, |s| s.t_ns)
    }
}

/// Tolerances a flight must meet (a mission's `[criteria]` table; omitted
/// fields keep the defaults).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Criteria {
    /// Hover attitude error RMS, degrees.
    pub attitude_rms_deg: f64,
    /// Hover altitude error RMS, metres.
    pub altitude_rms_m: f64,
    /// Roll and pitch step overshoot of the true attitude, a fraction.
    pub overshoot: f64,
    /// Roll and pitch step settling of the tracked attitude, s.
    pub settling_s: f64,
    /// Hover horizontal position error RMS, metres (judged only when set:
    /// a disturbance-rejection criterion).
    pub position_rms_m: Option<f64>,
    /// Hover oscillation: the RMS of the roll and pitch body rate above
    /// `quality::OSCILLATION_HZ`, °/s.
    pub oscillation_dps: f64,
    /// Hover control effort: the motor commands' total variation per
    /// second, averaged over the motors, 1/s.
    pub motor_variation_per_s: f64,
    /// Tracking during the roll and pitch steps: the true attitude's error
    /// RMS against the set-point over each step's hold (from `settling_s`
    /// after the step until the stick moves again), degrees.
    pub step_tracking_rms_deg: f64,
    /// The envelope, judged over the whole flight: the highest altitude,
    /// m (default: the mission's highest altitude target + 2 m, or 10 m
    /// for a mission without one; `quality::Envelope`).
    pub max_altitude_m: Option<f64>,
    /// The envelope: the farthest horizontal distance from the launch
    /// point, m (default 20 m).
    pub max_distance_m: Option<f64>,
    /// The envelope: the largest tilt from level while off the ground,
    /// degrees (default: the mission's largest roll or pitch stick, at
    /// least 20°, + 40°).
    pub max_tilt_deg: Option<f64>,
}

/// The default hover oscillation limit, °/s, set from flights (no guide
/// gives a number in these units; docs/flight.md, "Oscillation, control
/// effort and tracking"): Table V's timing measures up to 1.5 °/s in
/// moderate turbulence and under 0.1 °/s in calm air; a loop ringing near
/// 5 Hz with its motor output every 44 ms, 2.2–3.9 °/s in moderate
/// turbulence. Calm hovers stay under 0.6 °/s on every design measured, so
/// it flags the ringing turbulence excites.
pub const OSCILLATION_DPS: f64 = 2.0;
/// The default hover control-effort limit, 1/s: gross chatter only (the
/// command jumping by a tenth of its range every 2 ms trace point); the
/// bundled examples measure up to 32/s in moderate turbulence (rotor
/// vibration through the D term at the gyro rate) and under 5/s in calm
/// air.
pub const MOTOR_VARIATION_PER_S: f64 = 50.0;
/// The default step-tracking limit, degrees: the settling criterion's
/// ±5 % band on the bundled missions' 20° steps, as an RMS over the hold.
pub const STEP_TRACKING_RMS_DEG: f64 = 1.0;

impl Default for Criteria {
    /// No crash, hover attitude error RMS < 2°, altitude error RMS < 0.1 m,
    /// roll/pitch steps with overshoot < 20 % settling within 0.5 s.
    fn default() -> Criteria {
        Criteria {
            attitude_rms_deg: 2.0,
            altitude_rms_m: 0.1,
            overshoot: 0.2,
            settling_s: 0.5,
            position_rms_m: None,
            oscillation_dps: OSCILLATION_DPS,
            motor_variation_per_s: MOTOR_VARIATION_PER_S,
            step_tracking_rms_deg: STEP_TRACKING_RMS_DEG,
            max_altitude_m: None,
            max_distance_m: None,
            max_tilt_deg: None,
        }
    }
}

/// A vehicle's own tolerances in turbulence (a preset's `[criteria]`): in a
/// mission whose world has turbulence, each given key replaces the
/// mission's (position only where the mission judges it); calm missions
/// keep theirs. A heavy, draggy vehicle is carried further by the same
/// turbulence than a racer, whatever its timing.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CriteriaOverride {
    /// Hover attitude error RMS, degrees.
    pub attitude_rms_deg: Option<f64>,
    /// Hover altitude error RMS, metres.
    pub altitude_rms_m: Option<f64>,
    /// Hover position error RMS, metres (where the mission judges it).
    pub position_rms_m: Option<f64>,
}

impl CriteriaOverride {
    /// The criteria of a mission in `world` for this vehicle: `c` with its
    /// tolerances when the world has turbulence.
    pub fn in_world(&self, c: Criteria, world: &World) -> Criteria {
        if world.turbulence == Intensity::None {
            return c;
        }
        self.apply(c)
    }

    /// `c` with this vehicle's tolerances (valid when both are: see
    /// [`CriteriaOverride::validate`]).
    pub fn apply(&self, c: Criteria) -> Criteria {
        Criteria {
            attitude_rms_deg: self.attitude_rms_deg.unwrap_or(c.attitude_rms_deg),
            altitude_rms_m: self.altitude_rms_m.unwrap_or(c.altitude_rms_m),
            position_rms_m: c.position_rms_m.map(|p| self.position_rms_m.unwrap_or(p)),
            ..c
        }
    }

    /// Every given tolerance positive and finite; the error names it.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let all = Criteria {
            position_rms_m: Some(1.0),
            ..Criteria::default()
        };
        self.apply(all).validate()
    }
}

impl Criteria {
    /// Read a criterion file (`fly --sweep --criterion`) by the rules of
    /// every input file ([`rtpipe_model::input`]) and validate it.
    pub fn from_file(path: &std::path::Path) -> Result<Self, SpecError> {
        crate::error::load(path, &Kind::CRITERION, |c: Criteria| {
            // The file's keys are the table's, at its top level.
            c.validate().map_err(|e| {
                let field = e.field.trim_start_matches("criteria.");
                ConfigError::new(field, e.reason)
            })?;
            Ok(c)
        })
    }

    /// Every tolerance positive and finite.
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (name, v) in [
            ("criteria.attitude_rms_deg", self.attitude_rms_deg),
            ("criteria.altitude_rms_m", self.altitude_rms_m),
            ("criteria.overshoot", self.overshoot),
            ("criteria.settling_s", self.settling_s),
            ("criteria.oscillation_dps", self.oscillation_dps),
            ("criteria.motor_variation_per_s", self.motor_variation_per_s),
            ("criteria.step_tracking_rms_deg", self.step_tracking_rms_deg),
            (
                "criteria.position_rms_m",
                self.position_rms_m.unwrap_or(1.0),
            ),
            (
                "criteria.max_altitude_m",
                self.max_altitude_m.unwrap_or(1.0),
            ),
            (
                "criteria.max_distance_m",
                self.max_distance_m.unwrap_or(1.0),
            ),
            ("criteria.max_tilt_deg", self.max_tilt_deg.unwrap_or(1.0)),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ConfigError::new(
                    name,
                    format!("must be a positive number, found {v}"),
                ));
            }
        }
        if self.max_tilt_deg.is_some_and(|t| t > 180.0) {
            return Err(ConfigError::new(
                "criteria.max_tilt_deg",
                "must be at most 180 (degrees from level)",
            ));
        }
        Ok(())
    }

    /// The criteria in words.
    pub fn describe(&self) -> String {
        let position = self
            .position_rms_m
            .map_or(String::new(), |p| format!(", position RMS < {p} m"));
        format!(
            "no crash, hover attitude RMS < {}°, altitude RMS < {} m{position}, oscillation < {}°/s, motor variation < {}/s, roll/pitch steps: true overshoot < {} %, tracked settling < {} s, hold tracking RMS < {}°",
            self.attitude_rms_deg,
            self.altitude_rms_m,
            self.oscillation_dps,
            self.motor_variation_per_s,
            100.0 * self.overshoot,
            self.settling_s,
            self.step_tracking_rms_deg
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_parse_in_several_forms() {
        assert_eq!(parse_time("2.5s"), Ok(2_500_000_000));
        assert_eq!(parse_time("250ms"), Ok(250_000_000));
        assert_eq!(parse_time("3"), Ok(3_000_000_000));
        assert!(parse_time("soon").is_err());
        assert!(parse_time("-1s").is_err());
    }

    #[test]
    fn builtins_parse_and_fold() {
        let m = Mission::builtin("hover").unwrap();
        let p = m.intent_at(5_000_000_000);
        assert!(p.arm && p.altitude_m == Some(1.0) && !p.land);
        let s = Mission::builtin("steps").unwrap();
        assert!(s.steps.iter().any(|x| x.roll_deg == Some(20.0)));
        assert!(Mission::builtin("loop").is_err());
        for name in BUILTIN_MISSIONS {
            assert!(Mission::builtin(name).is_ok(), "{name}");
        }
        // The breeze: steps in turbulence, with the IMU's errors.
        let b = Mission::builtin("breeze").unwrap();
        assert!(b.steps.iter().any(|x| x.pitch_deg == Some(20.0)));
        assert!(b.world.dryden().is_ok_and(|d| d.is_some()) && b.world.sensor_errors);
    }

    #[test]
    fn intent_lookup_is_the_fold_of_the_steps_so_far() {
        let m = Mission::builtin("steps").unwrap();
        let ends: Vec<u64> = m.steps.iter().map(|s| s.t_ns).collect();
        for t in ends
            .iter()
            .flat_map(|&t| [t.saturating_sub(1), t, t + 1])
            .chain([0, u64::MAX])
        {
            let mut p = PilotIntent::default();
            for s in m.steps.iter().take_while(|s| s.t_ns <= t) {
                p.apply(s);
            }
            assert_eq!(m.intent_at(t), p, "at {t}");
        }
    }

    #[test]
    fn too_many_steps_and_far_times_are_refused_with_the_limit() {
        let mut text = String::from("name = \"x\"\n");
        for k in 0..=MAX_MISSION_STEPS {
            text.push_str(&format!("[[step]]\nat = {k}\n"));
        }
        let e = Mission::from_toml_str(&text).unwrap_err();
        assert!(e.reason.contains("more than the 10000"), "{e}");
        let e = Mission::from_toml_str("name = \"x\"\n[[step]]\nat = \"1e9s\"\n").unwrap_err();
        assert!(e.reason.contains("from 0 to 9007199 s"), "{e}");
        let e = Mission::from_toml_str("name = \"a\\u202Eb\"\n").unwrap_err();
        assert!(e.reason.contains("bidirectional"), "{e}");
    }

    #[test]
    fn bad_missions_name_the_field() {
        let e = Mission::from_toml_str("name = \"x\"\n[[step]]\nat = \"2 s\"\nroll_deg = 90\n")
            .unwrap_err();
        assert_eq!(e.field, "step[0].roll_deg", "{e}");
        let e = Mission::from_toml_str("name = \"x\"\n[[step]]\nat = \"later\"\n").unwrap_err();
        assert_eq!(e.field, "step[0].at");
        let e = Mission::from_toml_str("name = \"x\"\n[[step]]\nat = 2\n[[step]]\nat = 1\n")
            .unwrap_err();
        assert_eq!(e.field, "step[1].at");
        let e =
            Mission::from_toml_str("name = \"x\"\n[[step]]\nat = 1\nrol_deg = 3\n").unwrap_err();
        assert!(e.reason.contains("rol_deg"), "{e}");
    }
}
