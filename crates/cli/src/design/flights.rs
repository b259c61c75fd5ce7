//! `design --fly`: every design the search would return is flown (each
//! mission on each vehicle with each seed) before it may be the answer.

use rtpipe_design::{Acceptance, Checked};
use rtpipe_fly::{fly, setup, Request, Setup};
use rtpipe_model::{Diagnostic, Spec};
use rtpipe_sim::ExecModel;
use serde::Serialize;
use std::path::Path;

/// The flights a design must pass: one setup per (vehicle, mission, seed).
pub struct Flights {
    /// "vehicle/mission/seed" and its setup.
    setups: Vec<(String, Setup)>,
    exec: ExecModel,
}

impl std::fmt::Debug for Flights {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let labels: Vec<&str> = self.setups.iter().map(|(l, _)| l.as_str()).collect();
        f.debug_struct("Flights").field("setups", &labels).finish()
    }
}

/// What `--fly`, `--vehicle` and `--seed` ask.
pub struct FlyRequest<'a> {
    pub missions: &'a [String],
    pub vehicles: &'a [String],
    pub seeds: &'a [u64],
}

impl FlyRequest<'_> {
    /// "racer5, aero1kg × steps, gusty, seed 0": for the report.
    pub fn describe(&self) -> String {
        let seeds: Vec<String> = self.seeds.iter().map(u64::to_string).collect();
        format!(
            "{} × {}, seed {}",
            self.vehicles.join(", "),
            self.missions.join(", "),
            seeds.join(", ")
        )
    }
}

/// The flights of `r` for designs of `spec` (read from `path`); an error
/// names the bad vehicle, mission or body before the search starts.
pub fn flights(path: &Path, spec: &Spec, r: &FlyRequest) -> Result<Flights, Diagnostic> {
    let mut setups = Vec::new();
    for v in r.vehicles {
        for m in r.missions {
            for &seed in r.seeds {
                let req = Request {
                    spec_path: path,
                    vehicle: v,
                    mission: m,
                    horizon: None,
                    seed,
                };
                let mut s = setup(spec, &req)?;
                // Only the flight's quality is judged: chains only observe.
                s.track_chains = false;
                let label = if r.seeds.len() > 1 {
                    format!("{}/{}/seed {seed}", s.preset.name, s.mission.name)
                } else {
                    format!("{}/{}", s.preset.name, s.mission.name)
                };
                setups.push((label, s));
            }
        }
    }
    Ok(Flights {
        setups,
        exec: ExecModel::Uniform,
    })
}

impl Flights {
    /// Why the flight of `spec` in setup `s` misses its mission's criteria.
    fn failures(&self, spec: &Spec, s: &Setup) -> Vec<String> {
        match fly(spec, s, self.exec) {
            Ok(f) => f.quality.failures(&s.criteria()),
            Err(d) => vec![d.message],
        }
    }
}

impl Acceptance for Flights {
    /// Flies every setup (one thread each); the failures of each that
    /// misses its criteria, "vehicle/mission: why".
    fn accept(&self, spec: &Spec) -> Result<(), String> {
        let failed: Vec<String> = std::thread::scope(|scope| {
            let runs: Vec<_> = self
                .setups
                .iter()
                .map(|(label, s)| scope.spawn(move || (label, self.failures(spec, s))))
                .collect();
            runs.into_iter()
                .map(|h| match h.join() {
                    Ok(r) => r,
                    Err(e) => std::panic::resume_unwind(e),
                })
                .filter(|(_, f)| !f.is_empty())
                .map(|(label, f)| format!("{label}: {}", f.join("; ")))
                .collect()
        });
        if failed.is_empty() {
            Ok(())
        } else {
            Err(failed.join(" | "))
        }
    }
}

/// One flown design, for `--json`.
#[derive(Serialize)]
pub struct FlownView {
    utilization: f64,
    /// Periods of the free tasks, in the spec's unit.
    periods: crate::report::Pairs<String, f64>,
    flies: bool,
    failure: Option<String>,
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
        })
        .collect()
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
        out.push_str(&format!(
            "  U = {:.4} {}: {}\n",
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
