//! The flags of `rtpipe fly` (one flight, or `--sweep`).

use crate::command::ExecArg;
use clap::Args;
use rtpipe_flight::wind::Intensity;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct FlyArgs {
    /// The system spec (TOML) whose tasks name their `body`, e.g.
    /// examples/cleanflight.toml.
    pub spec: PathBuf,
    /// The vehicle: a built-in preset (racer5, aero1kg) or a preset file.
    /// With --sweep, a comma-separated list: every timing is flown on each.
    #[arg(long, value_name = "PRESET|FILE", default_value = "racer5")]
    pub vehicle: String,
    /// The mission: a built-in one (steps, hover, paper, gusty, breeze) or
    /// a mission file (crates/flight/missions/*.toml show the format,
    /// `[criteria]` and `[world]` included). With --sweep, a comma-separated list: every
    /// timing is flown on each mission (and vehicle), each judged by its
    /// own criterion, and flies only if every flight meets it.
    #[arg(
        long,
        value_name = "FILE|steps|hover|paper|gusty|breeze",
        default_value = "steps"
    )]
    pub mission: String,
    /// The turbulence (Dryden, MIL-F-8785C intensities) instead of the
    /// mission's own: none, light (W20 = 15 kn), moderate (30 kn), severe
    /// (45 kn). The mission's other world settings stay.
    #[arg(long, value_name = "INTENSITY", value_parser = parse_turbulence)]
    pub turbulence: Option<Intensity>,
    /// Flight time: "30s", "2500ms", or a number in the spec's time unit
    /// [default: 5 s after the mission's last step].
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub duration: Option<String>,
    /// Seeds the sensor noise and the execution times (the same seed gives
    /// the same flight, bit for bit).
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// One flight at phase draw K, as `--sweep --phases` and `design --fly`
    /// fly it: 0 is the nominal phase (every task released at 0, the
    /// mission's steps where it puts them); each other K places every
    /// periodic task's first release within its period and shifts the stick
    /// steps within the motor-output period, the same draw for every seed.
    #[arg(long, value_name = "K", default_value_t = 0, conflicts_with = "sweep")]
    pub phase: u64,
    /// How each job's demand is drawn (see `simulate --exec`).
    #[arg(long, value_enum, default_value_t = ExecArg::Uniform)]
    pub exec: ExecArg,
    #[command(flatten)]
    pub output: crate::command::FormatArgs,
    /// Write SVG plots into this directory (created if missing):
    /// attitude.svg, altitude.svg, motors.svg, latency.svg; with --sweep,
    /// sweep.svg.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Sweep instead of one flight: fly the mission over period scales
    /// (budgets fixed) and over pure delays on each chain's head, and derive
    /// the chain limits under which the vehicle still meets its criterion.
    #[arg(long)]
    pub sweep: bool,
    /// With --sweep: the period scales, LO..HI (steps of 2^(1/3)).
    #[arg(long, value_name = "LO..HI", value_parser = parse_scale, requires = "sweep")]
    pub scale: Option<(f64, f64)>,
    /// With --sweep: points per doubling of every swept quantity (period
    /// scale, tail period, head delay from 2 ms); finer finds the edges more
    /// closely at proportionally more flights.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=48), requires = "sweep")]
    pub per_octave: u32,
    /// With --sweep: seeds of the noise and execution times flown at every
    /// timing (--seed, --seed + 1, …); a timing flies only if every flight
    /// meets the criterion (or by --pass-rate).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100), requires = "sweep")]
    pub seeds: u32,
    /// With --sweep: phase draws flown per seed: the first is the nominal
    /// phase (every task released at 0, the mission's steps where it puts
    /// them); each other places every periodic task's first release at
    /// random within its period and shifts the stick steps within the
    /// motor-output period.
    #[arg(long, value_name = "M", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100), requires = "sweep")]
    pub phases: u32,
    /// With --sweep: judge a timing by pass rate instead of all-pass: in
    /// each vehicle/mission setup, of its flights the spec's own timing
    /// (every period × 1) meets its criterion on, the share this timing
    /// meets it on too must have a lower confidence bound (Wilson) ≥ R, in
    /// (0, 1). Flights the spec's own timing fails (the weather's, not the
    /// timing's) count neither way; a setup where it passes too few for
    /// the bound to reach R lets no timing fly [default: every flight must
    /// pass].
    #[arg(long, value_name = "R", value_parser = crate::command::parse_fraction, allow_hyphen_values = true, requires = "sweep")]
    pub pass_rate: Option<f64>,
    /// With --pass-rate: the confidence of that bound, in (0, 1) [default:
    /// 0.95].
    #[arg(long, value_name = "C", value_parser = crate::command::parse_fraction, allow_hyphen_values = true, requires = "pass_rate")]
    pub confidence: Option<f64>,
    /// With --sweep: after the grid, bisect each sweep's edge (between its
    /// last passing and first failing point, flown with the same seeds ×
    /// phases) until the two are within this fraction of each other, so a
    /// limit is written only where every finer point below it passed; 0
    /// flies the grid alone.
    #[arg(long, value_name = "R", default_value_t = 0.02, value_parser = parse_resolution, requires = "sweep")]
    pub resolution: f64,
    /// With --sweep: after the edges, fly every period scale and motor
    /// period from the spec's own (× 1) up to each edge's last passing
    /// point at steps of × (1 + S), with the same seeds × phases and rule,
    /// so a written limit is one below which every such step flew (a
    /// failing step brings it below that step); about ln(edge)/ln(1 + S)
    /// timings a sweep (49 up to × 2.64 at 0.02); on by default, as it is
    /// what backs a written limit; 0 turns it off (the grid and the
    /// refinement alone).
    #[arg(long, value_name = "S", default_value_t = 0.02, value_parser = parse_check_step, requires = "sweep")]
    pub check_step: f64,
    /// With --sweep: every derived limit × this factor in (0, 1] (the
    /// margin a written limit keeps from the last timing that flew).
    #[arg(long, value_name = "F", default_value_t = 1.0, value_parser = parse_safety, requires = "sweep")]
    pub safety: f64,
    /// With --sweep: the criterion, a TOML file with attitude_rms_deg,
    /// altitude_rms_m, overshoot, settling_s, position_rms_m [default: the
    /// mission's].
    #[arg(long, value_name = "FILE", requires = "sweep")]
    pub criterion: Option<PathBuf>,
    /// With --sweep: write the spec with every derived limit here: each
    /// chain's reaction and freshness (from the read), max_reaction_time and
    /// freshness_from_event (from the event), and the motor-output task's max_period
    /// (from the rate sweep).
    #[arg(long, value_name = "OUT.toml", requires = "sweep")]
    pub write_limits: Option<PathBuf>,
    /// With --write-limits: free the period of every guaranteed periodic
    /// task on a chain (a range up to the largest from-event limit of its
    /// chains, and no further than its period × the last period scale
    /// that flew), so that `rtpipe design` can choose them; other tasks keep
    /// their fixed periods, data-triggered ones their triggers. With
    /// `--free-periods=A,B` only tasks A and B (each such a task).
    #[arg(
        long,
        requires = "write_limits",
        num_args = 0..=1,
        require_equals = true,
        value_delimiter = ',',
        value_name = "TASKS"
    )]
    pub free_periods: Option<Vec<String>>,
    /// Write the flight as CSV (one row every 2 ms; the header names every
    /// column and its unit, ending with each chain's latest observed
    /// reaction and freshness in ms; readable by PlotJuggler).
    #[arg(long, value_name = "FILE.csv")]
    pub log: Option<PathBuf>,
    /// Write one CSV row per head sample of every chain (as `simulate
    /// --samples`): read, event, first and last tail output, reaction and
    /// freshness from the read and from the event, integer ns.
    #[arg(long, value_name = "FILE.csv")]
    pub samples: Option<PathBuf>,
}

/// `--scale LO..HI`: two positive factors.
pub fn parse_scale(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("expected LO..HI like 0.5..8, found `{s}`"))?;
    let num = |x: &str| {
        x.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
    };
    match (num(a), num(b)) {
        (Some(lo), Some(hi)) if lo <= hi && hi <= 64.0 => Ok((lo, hi)),
        _ => Err(format!(
            "expected two positive factors LO <= HI <= 64, like 0.5..8, found `{s}`"
        )),
    }
}

/// `--resolution`: 0 (no refinement) or a fraction in (0, 0.5].
pub fn parse_resolution(s: &str) -> Result<f64, String> {
    zero_or_fraction(s, "no refinement")
}

/// `--check-step`: 0 (no check) or a fraction in (0, 0.5].
pub fn parse_check_step(s: &str) -> Result<f64, String> {
    zero_or_fraction(s, "no check")
}

/// 0 (`off`: the step is skipped) or a fraction in (0, 0.5].
fn zero_or_fraction(s: &str, off: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(r) if r == 0.0 || (r > 0.0 && r <= 0.5) => Ok(r),
        _ => Err(format!(
            "must be 0 ({off}) or a fraction in (0, 0.5], e.g. 0.02"
        )),
    }
}

/// `--safety F`: a factor in (0, 1].
pub fn parse_safety(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(f) if f > 0.0 && f <= 1.0 => Ok(f),
        _ => Err(format!(
            "expected a factor in (0, 1] (e.g. 0.9: limits 10 % inside the last timing that flew), found `{s}`"
        )),
    }
}

/// `--turbulence none|light|moderate|severe`.
pub fn parse_turbulence(s: &str) -> Result<Intensity, String> {
    Intensity::parse(s).ok_or_else(|| {
        format!("expected none, light, moderate or severe (MIL-F-8785C), found `{s}`")
    })
}

impl FlyArgs {
    /// The names of `--vehicle`'s comma-separated list.
    pub fn vehicles(&self) -> Vec<&str> {
        listed(&self.vehicle)
    }

    /// The names of `--mission`'s comma-separated list.
    pub fn missions(&self) -> Vec<&str> {
        listed(&self.mission)
    }

    /// The checks of the flags alone, whichever way they came (the command
    /// line, Python's keywords): a flag that would do nothing is an error
    /// that names the fix.
    pub fn validate(&self) -> Result<(), rtpipe_model::Diagnostic> {
        let one_flight = [("--log", &self.log), ("--samples", &self.samples)];
        let given = one_flight
            .into_iter()
            .find_map(|(flag, p)| p.as_ref().map(|_| flag));
        let listed = self.vehicles().len() * self.missions().len() > 1;
        match given {
            Some(flag) if self.sweep => Err(rtpipe_model::Diagnostic::error(
                format!("{flag} describes one flight; --sweep flies many"),
                format!("drop {flag}, or drop --sweep (--plot DIR writes sweep.svg)"),
            )),
            _ if listed && !self.sweep => Err(rtpipe_model::Diagnostic::error(
                format!(
                    "one flight flies one vehicle on one mission, found --vehicle {} --mission {}",
                    self.vehicle, self.mission
                ),
                "give one of each, or add --sweep to judge every timing on each vehicle and mission",
            )),
            _ => Ok(()),
        }
    }
}

/// The names of a comma-separated `--vehicle` or `--mission` list.
fn listed(list: &str) -> Vec<&str> {
    list.split(',').map(str::trim).collect()
}
