//! `design --fly`: every design the search would return is flown before it
//! may be the answer, each mission on each vehicle over randomised seeds
//! and phases, and accepted only when the lower confidence bound of its
//! pass rate (Wilson, `rtpipe_fly::confidence`) reaches the rate asked.

use rtpipe_design::{Acceptance, Checked, Judgement, Trials};
use rtpipe_fly::confidence::Requirement;
use rtpipe_fly::phases::phased;
use rtpipe_fly::{fly, setup, Request, Setup};
use rtpipe_model::{Diagnostic, Spec};
use rtpipe_sim::ExecModel;
use serde::Serialize;
use std::path::Path;

/// The missions `--fly` alone flies: the calm steps, the turbulent hover
/// and steps in light turbulence (`breeze`). Without the last, an answer
/// was judged on no step in turbulence and missed held-out turbulent steps
/// Table V's periods passed (docs/flight.md, "Held-out missions").
pub const DEFAULT_MISSIONS: [&str; 3] = ["steps", "gusty", "breeze"];

/// The flights a design must pass: per (vehicle, mission) setup, flights
/// 0, 1, … each with the next seed of the noise and execution times and
/// the next phase draw (`rtpipe_fly::phases`; draw 0 the nominal phase),
/// two streams of their own.
pub struct Flights {
    /// "vehicle/mission" and its setup (its seed the stream's first).
    setups: Vec<(String, Setup)>,
    /// Flights per setup.
    per_setup: u32,
    need: Requirement,
    exec: ExecModel,
}

impl std::fmt::Debug for Flights {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let labels: Vec<&str> = self.setups.iter().map(|(l, _)| l.as_str()).collect();
        f.debug_struct("Flights")
            .field("setups", &labels)
            .field("per_setup", &self.per_setup)
            .finish()
    }
}

/// What `--fly`, `--vehicle`, `--seed`, `--flights`, `--pass-rate` and
/// `--confidence` ask.
pub struct FlyRequest<'a> {
    pub missions: &'a [String],
    pub vehicles: &'a [String],
    /// The first seed of every setup's stream.
    pub seed: u64,
    /// Flights per design at least (`None`: the fewest that can meet
    /// `need`).
    pub flights: Option<u32>,
    pub need: Requirement,
}

/// The flights per setup: the flights asked (or the fewest that can meet
/// the requirement) spread evenly over the setups, rounded up.
fn per_setup(r: &FlyRequest, setups: u32) -> u32 {
    let total = r.flights.unwrap_or_else(|| r.need.least_flights());
    // `DesignArgs::validate` refused fewer than can show the pass rate.
    debug_assert!(enough(r.flights, r.need).is_ok());
    total.div_ceil(setups.max(1))
}

/// `--flights` (the fewest that can show `need` when not given) can show
/// the pass rate `need` asks for: even all passing, fewer cannot.
pub fn enough(flights: Option<u32>, need: Requirement) -> Result<(), Diagnostic> {
    let least = need.least_flights();
    let total = flights.unwrap_or(least);
    if total < least {
        return Err(Diagnostic::error(
            format!(
                "--flights {total} cannot show a pass rate of {} at {} % confidence: even all {total} passing gives a lower bound below it; the fewest that can is {least}",
                need.rate,
                need.confidence * 100.0
            ),
            format!("give --flights {least} or more, or lower --pass-rate or --confidence"),
        ));
    }
    Ok(())
}

/// The flights of `r` for designs of `spec` (read from `path`); an error
/// names the bad vehicle, mission or body, or a flight count too small,
/// before the search starts.
pub fn flights(path: &Path, spec: &Spec, r: &FlyRequest) -> Result<Flights, Diagnostic> {
    let mut setups = Vec::new();
    for v in r.vehicles {
        for m in r.missions {
            let req = Request {
                spec_path: path,
                vehicle: v,
                mission: m,
                horizon: None,
                seed: r.seed,
            };
            let mut s = setup(spec, &req)?;
            // Only the flight's quality is judged: chains only observe.
            s.track_chains = false;
            setups.push((format!("{}/{}", s.preset.name, s.mission.name), s));
        }
    }
    let per_setup = per_setup(r, setups.len() as u32);
    Ok(Flights {
        setups,
        per_setup,
        need: r.need,
        exec: ExecModel::Uniform,
    })
}

impl FlyRequest<'_> {
    /// "racer5, aero1kg × steps, gusty; 74 flights a design (seeds from 0,
    /// phase draws 0–36); pass rate ≥ 0.95 at 95 % confidence".
    pub fn describe(&self, f: &Flights) -> String {
        let n = f.per_setup;
        format!(
            "{} × {}; {} flights a design ({n} per vehicle and mission: seeds {}–{}, phase draws 0–{}); accepted when the pass rate's lower bound (Wilson) ≥ {} at {} % confidence",
            self.vehicles.join(", "),
            self.missions.join(", "),
            n as usize * f.setups.len(),
            self.seed,
            self.seed + u64::from(n) - 1,
            n - 1,
            self.need.rate,
            self.need.confidence * 100.0,
        )
    }
}

impl Flights {
    /// Why flight `j` of setup `s` misses its criteria (empty: it passed).
    fn failures(&self, spec: &Spec, s: &Setup, j: u32) -> Vec<String> {
        let mut one = phased(spec, s, u64::from(j));
        one.world.seed = s.world.seed.wrapping_add(u64::from(j));
        match fly(spec, &one, self.exec) {
            Ok(f) => f.quality.failures(&s.criteria()),
            Err(d) => vec![d.message],
        }
    }

    /// Every flight, round-robin over the setups (so that the flights
    /// flown before an early rejection cover every vehicle and mission).
    fn plan(&self) -> Vec<(usize, u32)> {
        (0..self.per_setup)
            .flat_map(|j| (0..self.setups.len()).map(move |k| (k, j)))
            .collect()
    }
}

impl Acceptance for Flights {
    /// Flies the design's flights a few at a time (one thread each) and
    /// stops as soon as more have failed than the requirement allows.
    fn accept(&self, spec: &Spec) -> Judgement {
        let plan = self.plan();
        let total = plan.len() as u32;
        let allowed = self.need.failures_allowed(total).unwrap_or(0);
        let width = std::thread::available_parallelism().map_or(1, |n| n.get());
        let (mut passed, mut run, mut first) = (0u32, 0u32, None);
        for round in plan.chunks(width) {
            let results = fly_round(self, spec, round);
            for ((k, j), missed) in round.iter().zip(results) {
                run += 1;
                if missed.is_empty() {
                    passed += 1;
                } else if first.is_none() {
                    let (label, s) = &self.setups[*k];
                    let seed = s.world.seed.wrapping_add(u64::from(*j));
                    first = Some(format!(
                        "{label}/seed {seed}/phase {j}: {}",
                        missed.join("; ")
                    ));
                }
            }
            if run - passed > allowed {
                break;
            }
        }
        let lower_bound = rtpipe_fly::confidence::wilson_lower(passed, run, self.need.z());
        let met = run == total && self.need.met(passed, run);
        let failure = (!met).then(|| {
            format!(
                "{passed}/{run} flights passed, more failures than {allowed} of {total} allow; first: {}",
                first.as_deref().unwrap_or("none")
            )
        });
        Judgement {
            failure,
            trials: Some(Trials {
                passed,
                run,
                lower_bound,
                required: self.need.rate,
            }),
        }
    }
}

/// The failures of each flight of `round`, in its order (one thread each).
fn fly_round(f: &Flights, spec: &Spec, round: &[(usize, u32)]) -> Vec<Vec<String>> {
    std::thread::scope(|scope| {
        let runs: Vec<_> = round
            .iter()
            .map(|&(k, j)| scope.spawn(move || f.failures(spec, &f.setups[k].1, j)))
            .collect();
        runs.into_iter()
            .map(|h| match h.join() {
                Ok(r) => r,
                Err(e) => std::panic::resume_unwind(e),
            })
            .collect()
    })
}

/// One flown design, for `--json`.
#[derive(Serialize, schemars::JsonSchema)]
pub struct FlownView {
    utilization: f64,
    /// Periods of the free tasks, in the spec's unit.
    periods: crate::report::Pairs<String, f64>,
    flies: bool,
    failure: Option<String>,
    /// Flights that met their criteria, and flights flown.
    passed: Option<u32>,
    flown: Option<u32>,
    /// passed / flown.
    pass_rate: Option<f64>,
    /// The Wilson lower bound of the pass rate.
    lower_bound: Option<f64>,
    /// lower_bound − the required rate (≥ 0 when accepted).
    margin: Option<f64>,
}

/// The flown designs for `--json`.
pub fn flown_json(spec: &Spec, checked: &[Checked]) -> Vec<FlownView> {
    checked
        .iter()
        .map(|c| FlownView {
            utilization: c.utilization,
            periods: crate::report::Pairs(
                free_periods(spec, c)
                    .map(|(n, p)| (n.to_string(), spec.in_unit(p)))
                    .collect(),
            ),
            flies: c.failure.is_none(),
            failure: c.failure.clone(),
            passed: c.trials.map(|t| t.passed),
            flown: c.trials.map(|t| t.run),
            pass_rate: c.trials.map(pass_rate),
            lower_bound: c.trials.map(|t| t.lower_bound),
            margin: c.trials.map(|t| t.lower_bound - t.required),
        })
        .collect()
}

fn pass_rate(t: Trials) -> f64 {
    f64::from(t.passed) / f64::from(t.run.max(1))
}

/// The free tasks' names and periods (ns) of a flown design.
fn free_periods<'a>(spec: &'a Spec, c: &'a Checked) -> impl Iterator<Item = (&'a str, i64)> {
    spec.tasks
        .iter()
        .zip(&c.periods)
        .filter(|(t, _)| t.fixed_period().is_none())
        .map(|(t, &p)| (t.name.as_str(), p))
}

/// The flown designs for people: one line each, in the order flown.
pub fn flown_text(spec: &Spec, what: &str, checked: &[Checked]) -> String {
    let mut out = format!(
        "\nflights ({what}): {} design(s) flown, in the order flown\n",
        checked.len()
    );
    for c in checked {
        let periods: Vec<String> = free_periods(spec, c)
            .map(|(n, p)| format!("{n}={}", spec.fmt_time(p)))
            .collect();
        let counted = c.trials.map_or(String::new(), |t| {
            format!(
                " {}/{} flights, pass rate {:.3}, lower bound {:.3}, margin {:+.3}",
                t.passed,
                t.run,
                pass_rate(t),
                t.lower_bound,
                t.lower_bound - t.required
            )
        });
        out.push_str(&format!(
            "  U = {:.4} {}:{counted}: {}\n",
            c.utilization,
            periods.join(" "),
            match &c.failure {
                None => "flies".to_string(),
                Some(why) => format!("FAILS ({why}); cut"),
            }
        ));
    }
    out
}
