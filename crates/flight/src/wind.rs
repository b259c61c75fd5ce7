//! Turbulent wind: the Dryden model of MIL-F-8785C (§3.7.3) in its
//! low-altitude form (MIL-HDBK-1797, h < 1000 ft), as shaping filters driven
//! by seeded white noise.
//!
//! With V the speed at which the frozen turbulence field passes the vehicle
//! and ω in rad/s, the one-sided spectra (∫₀^∞ Φ dω = σ²) are
//!
//! ```text
//! Φ_u(ω) = σ_u² (2 L_u / π V) · 1 / (1 + (L_u ω / V)²)
//! Φ_v(ω) = σ_v² (L_v / π V) · (1 + 3 (L_v ω / V)²) / (1 + (L_v ω / V)²)²
//! Φ_w(ω) = the same as Φ_v with L_w, σ_w
//! ```
//!
//! and, at height h in feet, the low-altitude scales and intensities
//!
//! ```text
//! L_w = h,  L_u = L_v = h / (0.177 + 0.000823 h)^1.2          (feet)
//! σ_w = 0.1 W20,  σ_u = σ_v = σ_w / (0.177 + 0.000823 h)^0.4
//! W20 (wind speed at 20 ft) = 15 / 30 / 45 knots: light / moderate / severe
//! ```
//!
//! MIL-HDBK-1797 writes the v and w spectra with half these scales and a
//! factor 2 inside (2L_v, 2L_w); the spectra are the same.
//!
//! **Discretisation.** Each component is a linear system driven by white
//! noise of one-sided spectral density 1 (intensity π: E η(t)η(s) = π δ(t−s)),
//! u a first-order lag, v and w a double pole with one zero. Between two
//! instants h apart the state moves by the exact transition e^{Ah} and a
//! Gaussian with the exact covariance Q(h) = π ∫₀^h e^{As} B Bᵀ e^{Aᵀs} ds, so
//! the samples have the continuous process's statistics whatever the steps
//! (a forward-Euler or Tustin filter's spectrum depends on dt). The state
//! starts from the stationary distribution: the wind is "on" from t = 0.
//!
//! **Frame.** A hovering vehicle has no airspeed of its own: u is along the
//! world x axis (the direction the field moves), v along y, w along z (up),
//! in m/s, and only the turbulence is modelled (no mean wind: a steady wind
//! needs only a steady tilt). The advection speed V is a parameter.
//!
//! Pure: time is passed in, the noise comes from [`crate::rng::Rng`].

use crate::error::ConfigError;
use crate::math::Vec3;
use crate::rng::Rng;
use serde::Deserialize;

/// Metres per foot (international foot).
pub const M_PER_FT: f64 = 0.3048;
/// Metres per second per knot (1852 m / 3600 s).
pub const MPS_PER_KNOT: f64 = 1852.0 / 3600.0;

/// The standard turbulence intensities of MIL-F-8785C (low altitude).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Intensity {
    /// Calm air.
    #[default]
    None,
    /// W20 = 15 knots.
    Light,
    /// W20 = 30 knots.
    Moderate,
    /// W20 = 45 knots.
    Severe,
}

impl Intensity {
    /// Every intensity, calmest first.
    pub const ALL: [Intensity; 4] = [
        Intensity::None,
        Intensity::Light,
        Intensity::Moderate,
        Intensity::Severe,
    ];

    /// The wind speed at 20 ft, m/s.
    pub fn w20_mps(self) -> f64 {
        let knots = match self {
            Intensity::None => 0.0,
            Intensity::Light => 15.0,
            Intensity::Moderate => 30.0,
            Intensity::Severe => 45.0,
        };
        knots * MPS_PER_KNOT
    }

    /// The lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Intensity::None => "none",
            Intensity::Light => "light",
            Intensity::Moderate => "moderate",
            Intensity::Severe => "severe",
        }
    }

    /// Parse a lower-case name.
    pub fn parse(s: &str) -> Option<Intensity> {
        Intensity::ALL.into_iter().find(|i| i.name() == s)
    }
}

/// The three components' intensities and scales.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dryden {
    /// σ of u, v, w, m/s.
    pub sigma_mps: [f64; 3],
    /// L_u, L_v, L_w in MIL-F-8785C's convention, m.
    pub length_m: [f64; 3],
    /// The speed V at which the field passes the vehicle, m/s.
    pub speed_mps: f64,
}

impl Dryden {
    /// The low-altitude model at height `altitude_m`, advected at
    /// `speed_mps`. The formulas are MIL-HDBK-1797's for 10 ft ≤ h ≤
    /// 1000 ft; a hover at 1 m (3.3 ft) uses them below that range, as
    /// rotorpy does at its default 2 m.
    pub fn low_altitude(
        intensity: Intensity,
        altitude_m: f64,
        speed_mps: f64,
    ) -> Result<Dryden, ConfigError> {
        crate::error::in_range("wind.altitude_m", altitude_m, 0.1, 304.8)?;
        crate::error::in_range("wind.speed_mps", speed_mps, 0.1, 100.0)?;
        let h = altitude_m / M_PER_FT;
        let d = 0.177 + 0.000823 * h;
        let l_uv = h / d.powf(1.2) * M_PER_FT;
        let s_w = 0.1 * intensity.w20_mps();
        let s_uv = s_w / d.powf(0.4);
        Ok(Dryden {
            sigma_mps: [s_uv, s_uv, s_w],
            length_m: [l_uv, l_uv, altitude_m],
            speed_mps,
        })
    }

    /// The one-sided spectrum of component `k` (0 u, 1 v, 2 w) at ω rad/s,
    /// (m/s)² per rad/s.
    pub fn psd(&self, k: usize, omega: f64) -> f64 {
        let (s, l, v) = (self.sigma_mps[k], self.length_m[k], self.speed_mps);
        let x = (l * omega / v).powi(2);
        if k == 0 {
            s * s * 2.0 * l / (std::f64::consts::PI * v) / (1.0 + x)
        } else {
            s * s * l / (std::f64::consts::PI * v) * (1.0 + 3.0 * x) / (1.0 + x).powi(2)
        }
    }

    /// The autocorrelation of component `k` at lag τ s, (m/s)²: σ² e^{−Vτ/L}
    /// for u, σ² (1 − Vτ/2L) e^{−Vτ/L} for v and w (MIL-F-8785C).
    pub fn autocorrelation(&self, k: usize, tau_s: f64) -> f64 {
        let r = self.speed_mps * tau_s.abs() / self.length_m[k];
        let s2 = self.sigma_mps[k].powi(2);
        if k == 0 {
            s2 * (-r).exp()
        } else {
            s2 * (1.0 - r / 2.0) * (-r).exp()
        }
    }
}

/// One shaping filter: states x1 = η/(s+a), x2 = η/(s+a)², a = V/L.
#[derive(Debug, Clone, Copy)]
struct Shaper {
    a: f64,
    /// Output = c · x.
    c: [f64; 2],
    second_order: bool,
    x: [f64; 2],
}

/// The exact covariance of the noise one step of h adds, (x1, x2) entries
/// (q11, q12, q22), for intensity π. With h = ∞ it is the stationary one.
fn step_covariance(a: f64, h: f64) -> [f64; 3] {
    let pi = std::f64::consts::PI;
    let e = if h.is_finite() {
        (-2.0 * a * h).exp()
    } else {
        0.0
    };
    let ah = if h.is_finite() { a * h } else { 0.0 };
    let i0 = (1.0 - e) / (2.0 * a);
    let i1 = (1.0 - e * (1.0 + 2.0 * ah)) / (4.0 * a * a);
    let i2 = (2.0 - e * (2.0 + 4.0 * ah + 4.0 * ah * ah)) / (8.0 * a * a * a);
    [pi * i0, pi * i1, pi * i2]
}

impl Shaper {
    /// H(s) = K a/(s+a) for u; K (a² + √3 a s)/(s+a)² for v and w, with K
    /// chosen so the output variance is σ².
    fn new(sigma: f64, length: f64, speed: f64, second_order: bool) -> Shaper {
        let a = speed / length;
        let pi = std::f64::consts::PI;
        let c = if second_order {
            let k = sigma / (pi * a).sqrt();
            [3f64.sqrt() * a * k, (1.0 - 3f64.sqrt()) * a * a * k]
        } else {
            let k = sigma * (2.0 / (pi * a)).sqrt();
            [k * a, 0.0]
        };
        Shaper {
            a,
            c,
            second_order,
            x: [0.0; 2],
        }
    }

    /// Moves the state by `h` s, adding exact noise from `rng`.
    fn step(&mut self, h: f64, rng: &mut Rng) {
        let [q11, q12, q22] = step_covariance(self.a, h);
        // An infinite step forgets the state (e^{Ah} = 0): a stationary draw.
        let (e, h) = if h.is_finite() {
            ((-self.a * h).exp(), h)
        } else {
            (0.0, 0.0)
        };
        let [x1, x2] = self.x;
        let l11 = q11.sqrt();
        let n1 = rng.gaussian();
        self.x[0] = e * x1 + l11 * n1;
        if self.second_order {
            let l21 = if l11 > 0.0 { q12 / l11 } else { 0.0 };
            let l22 = (q22 - l21 * l21).max(0.0).sqrt();
            self.x[1] = e * (h * x1 + x2) + l21 * n1 + l22 * rng.gaussian();
        }
    }

    fn output(&self) -> f64 {
        self.c[0] * self.x[0] + self.c[1] * self.x[1]
    }
}

/// A turbulent wind: three shaping filters and their noise stream.
#[derive(Debug, Clone)]
pub struct Wind {
    shapers: [Shaper; 3],
    rng: Rng,
    t_ns: u64,
}

impl Wind {
    /// The wind of `model`, seeded by `seed`, in its stationary state at
    /// t = 0.
    pub fn new(model: &Dryden, seed: u64) -> Wind {
        let mut rng = Rng::new(seed);
        let mut shapers = [0, 1, 2].map(|k| {
            Shaper::new(
                model.sigma_mps[k],
                model.length_m[k],
                model.speed_mps,
                k > 0,
            )
        });
        for s in &mut shapers {
            // A step of infinite length draws from the stationary law.
            s.step(f64::INFINITY, &mut rng);
        }
        Wind {
            shapers,
            rng,
            t_ns: 0,
        }
    }

    /// The wind (world x, y, z; m/s) at `t_ns`, moving the filters there
    /// in one exact step. An earlier time returns the current wind.
    pub fn at(&mut self, t_ns: u64) -> Vec3 {
        if t_ns > self.t_ns {
            let h = (t_ns - self.t_ns) as f64 * 1e-9;
            for s in &mut self.shapers {
                s.step(h, &mut self.rng);
            }
            self.t_ns = t_ns;
        }
        self.value()
    }

    /// The wind at the last time asked, m/s.
    pub fn value(&self) -> Vec3 {
        let [u, v, w] = self.shapers.map(|s| s.output());
        Vec3::new(u, v, w)
    }
}

#[cfg(test)]
mod tests;
