//! Battery model (a LiPo pack) and Cleanflight's battery housekeeping.
//!
//! Model: per-cell open-circuit voltage from state of charge (a piecewise
//! linear LiPo curve), a pack internal resistance that sags the terminal
//! voltage with current, a capacity in mAh. The current follows from the
//! electrical power the motors draw: P = V·I with V = E − I·R gives
//! I = (E − √(E² − 4RP)) / 2R.
//!
//! Housekeeping: Cleanflight's four low-rate tasks — system load (a figure
//! passed in), battery voltage (filtered), battery current (with mAh
//! drawn) and the low-battery alert with hysteresis (src/main/sensors/
//! battery.c: warning 3.5 V/cell, critical 3.3 V/cell, hysteresis 0.1 V).

use crate::error::{in_range, positive, ConfigError};
use crate::filter::Pt1;
use serde::Deserialize;

/// LiPo open-circuit voltage per cell vs. state of charge (SoC, V).
const LIPO_OCV: [(f64, f64); 11] = [
    (0.0, 3.27),
    (0.1, 3.61),
    (0.2, 3.69),
    (0.3, 3.71),
    (0.4, 3.73),
    (0.5, 3.77),
    (0.6, 3.79),
    (0.7, 3.85),
    (0.8, 3.93),
    (0.9, 4.03),
    (1.0, 4.20),
];

/// Open-circuit voltage of one LiPo cell at `soc` in [0, 1].
pub fn lipo_cell_ocv(soc: f64) -> f64 {
    let s = soc.clamp(0.0, 1.0);
    for w in LIPO_OCV.windows(2) {
        let ((s0, v0), (s1, v1)) = (w[0], w[1]);
        if s <= s1 {
            return v0 + (v1 - v0) * (s - s0) / (s1 - s0);
        }
    }
    LIPO_OCV[LIPO_OCV.len() - 1].1
}

/// Battery parameters (the `[battery]` table of a preset).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BatteryParams {
    /// Cells in series.
    pub cells: u32,
    /// Capacity, mAh.
    pub capacity_mah: f64,
    /// Pack internal resistance, Ω.
    pub internal_resistance_ohm: f64,
    /// Shaft power / electrical power of motors + ESCs.
    pub efficiency: f64,
    /// Current of the avionics, A.
    #[serde(default)]
    pub base_current_a: f64,
    /// Initial state of charge.
    #[serde(default = "one")]
    pub initial_soc: f64,
}

fn one() -> f64 {
    1.0
}

impl BatteryParams {
    /// Check every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("battery.cells", f64::from(self.cells), 1.0, 14.0)?;
        positive("battery.capacity_mah", self.capacity_mah)?;
        positive(
            "battery.internal_resistance_ohm",
            self.internal_resistance_ohm,
        )?;
        in_range("battery.efficiency", self.efficiency, 0.05, 1.0)?;
        in_range("battery.base_current_a", self.base_current_a, 0.0, 100.0)?;
        in_range("battery.initial_soc", self.initial_soc, 0.0, 1.0)?;
        Ok(())
    }
}

/// The pack's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Battery {
    p: BatteryParams,
    soc: f64,
    voltage: f64,
    current: f64,
}

impl Battery {
    /// A pack at its initial charge.
    pub fn new(p: BatteryParams) -> Result<Self, ConfigError> {
        p.validate()?;
        let v = lipo_cell_ocv(p.initial_soc) * f64::from(p.cells);
        Ok(Self {
            p,
            soc: p.initial_soc,
            voltage: v,
            current: 0.0,
        })
    }
    /// State of charge in [0, 1].
    pub fn soc(&self) -> f64 {
        self.soc
    }
    /// Terminal voltage, V.
    pub fn voltage(&self) -> f64 {
        self.voltage
    }
    /// Current, A.
    pub fn current(&self) -> f64 {
        self.current
    }
    /// Draw `shaft_power_w` of motor shaft power for `dt` seconds.
    pub fn step(&mut self, shaft_power_w: f64, dt: f64) {
        let e = lipo_cell_ocv(self.soc) * f64::from(self.p.cells);
        let r = self.p.internal_resistance_ohm;
        let p = shaft_power_w.max(0.0) / self.p.efficiency;
        let disc = e * e - 4.0 * r * p;
        // Beyond the maximum-power point the pack delivers what it can.
        let i_motor = if disc > 0.0 {
            (e - disc.sqrt()) / (2.0 * r)
        } else {
            e / (2.0 * r)
        };
        self.current = i_motor + self.p.base_current_a;
        self.voltage = (e - self.current * r).max(0.0);
        self.soc = (self.soc - self.current * dt / (self.p.capacity_mah * 3.6)).max(0.0);
    }
}

/// Low-battery alert level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BatteryAlert {
    /// Fine.
    #[default]
    Ok,
    /// Below the warning cell voltage.
    Warning,
    /// Below the critical cell voltage.
    Critical,
}

/// Cleanflight's housekeeping thresholds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HousekeepingConfig {
    /// Cells in series (Cleanflight detects this at boot).
    pub cells: u32,
    /// Warning threshold, V/cell (vbatwarningcellvoltage 3.5).
    pub warning_cell_v: f64,
    /// Critical threshold, V/cell (vbatmincellvoltage 3.3).
    pub critical_cell_v: f64,
    /// Hysteresis to leave a level, V/cell (vbathysteresis 0.1).
    pub hysteresis_v: f64,
    /// Voltage filter cut-off, Hz.
    pub vbat_lpf_hz: f64,
    /// Rate of the voltage task, Hz.
    pub vbat_rate_hz: f64,
}

impl HousekeepingConfig {
    /// Cleanflight's defaults for a pack of `cells`, voltage task at 50 Hz.
    pub fn cleanflight(cells: u32) -> Self {
        Self {
            cells,
            warning_cell_v: 3.5,
            critical_cell_v: 3.3,
            hysteresis_v: 0.1,
            vbat_lpf_hz: 1.0,
            vbat_rate_hz: 50.0,
        }
    }
}

/// The four housekeeping computations' state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Housekeeping {
    cfg: HousekeepingConfig,
    /// Last system load figure, percent.
    pub load_percent: f64,
    vbat_filter: Pt1,
    vbat_init: bool,
    /// Filtered pack voltage, V.
    pub voltage: f64,
    /// Last current reading, A.
    pub current: f64,
    /// Charge drawn, mAh.
    pub mah_drawn: f64,
    /// Current alert level.
    pub alert: BatteryAlert,
}

impl Housekeeping {
    /// Fresh state.
    pub fn new(cfg: HousekeepingConfig) -> Result<Self, ConfigError> {
        let f = Pt1::new(cfg.vbat_lpf_hz, cfg.vbat_rate_hz)
            .map_err(|e| ConfigError::new("housekeeping.vbat_lpf_hz", e.reason))?;
        Ok(Self {
            cfg,
            load_percent: 0.0,
            vbat_filter: f,
            vbat_init: false,
            voltage: 0.0,
            current: 0.0,
            mah_drawn: 0.0,
            alert: BatteryAlert::Ok,
        })
    }
    /// Task "system": record the load figure (computed by the scheduler).
    pub fn system(&mut self, load_percent: f64) {
        self.load_percent = load_percent.clamp(0.0, 100.0);
    }
    /// Task "battery voltage": filter a raw reading.
    pub fn battery_voltage(&mut self, raw_v: f64) -> f64 {
        if !self.vbat_init {
            self.vbat_filter.reset(raw_v);
            self.vbat_init = true;
        }
        self.voltage = self.vbat_filter.apply(raw_v);
        self.voltage
    }
    /// Task "battery current": record a reading, integrate mAh over `dt` s.
    pub fn battery_current(&mut self, raw_a: f64, dt: f64) -> f64 {
        self.current = raw_a;
        self.mah_drawn += raw_a * dt / 3.6;
        self.mah_drawn
    }
    /// Task "battery alerts": update the level with hysteresis.
    pub fn battery_alerts(&mut self) -> BatteryAlert {
        let c = &self.cfg;
        let v = self.voltage / f64::from(c.cells.max(1));
        self.alert = match self.alert {
            _ if v < c.critical_cell_v => BatteryAlert::Critical,
            BatteryAlert::Critical if v < c.critical_cell_v + c.hysteresis_v => {
                BatteryAlert::Critical
            }
            BatteryAlert::Ok if v >= c.warning_cell_v => BatteryAlert::Ok,
            _ if v < c.warning_cell_v + c.hysteresis_v => BatteryAlert::Warning,
            _ => BatteryAlert::Ok,
        };
        self.alert
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pack() -> BatteryParams {
        BatteryParams {
            cells: 4,
            capacity_mah: 100.0,
            internal_resistance_ohm: 0.05,
            efficiency: 0.6,
            base_current_a: 0.0,
            initial_soc: 1.0,
        }
    }

    #[test]
    fn ocv_and_sag_are_hand_computable() {
        assert!((lipo_cell_ocv(1.0) - 4.2).abs() < 1e-12);
        assert!((lipo_cell_ocv(0.55) - 3.78).abs() < 1e-12);
        let mut b = Battery::new(pack()).unwrap();
        // 60 W shaft / 0.6 = 100 W from E = 16.8 V, R = 0.05 Ω:
        // I = (16.8 − √(16.8² − 20)) / 0.1 = 6.0 A (rounded), V = E − I·R.
        b.step(60.0, 0.001);
        let i = (16.8 - (16.8f64 * 16.8 - 20.0).sqrt()) / 0.1;
        assert!((b.current() - i).abs() < 1e-9);
        assert!((b.voltage() * b.current() - 100.0).abs() < 1e-6);
    }

    #[test]
    fn low_battery_alert_fires_with_hysteresis() {
        let mut b = Battery::new(pack()).unwrap();
        let mut hk = Housekeeping::new(HousekeepingConfig::cleanflight(4)).unwrap();
        let mut first_warning = None;
        let mut first_critical = None;
        // 100 mAh pack at ~150 W: drained within a few minutes.
        for k in 0..(50 * 600) {
            b.step(90.0, 0.02);
            hk.battery_voltage(b.voltage());
            hk.battery_current(b.current(), 0.02);
            match hk.battery_alerts() {
                BatteryAlert::Warning if first_warning.is_none() => first_warning = Some(k),
                BatteryAlert::Critical if first_critical.is_none() => first_critical = Some(k),
                _ => {}
            }
        }
        let (w, c) = (first_warning.unwrap(), first_critical.unwrap());
        assert!(w < c, "warning at {w}, critical at {c}");
        assert!(hk.mah_drawn > 90.0);
        // Hysteresis: a reading just above the critical level stays critical.
        hk.voltage = 4.0 * 3.35;
        assert_eq!(hk.battery_alerts(), BatteryAlert::Critical);
        hk.voltage = 4.0 * 3.45;
        assert_eq!(hk.battery_alerts(), BatteryAlert::Warning);
        hk.voltage = 4.0 * 3.55;
        assert_eq!(hk.battery_alerts(), BatteryAlert::Warning);
        hk.voltage = 4.0 * 3.65;
        assert_eq!(hk.battery_alerts(), BatteryAlert::Ok);
        hk.system(37.5);
        assert_eq!(hk.load_percent, 37.5);
    }
}
