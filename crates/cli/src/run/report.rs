//! `rtpipe run`'s report: what ran, the chains against the bounds, the
//! tasks, the verdict and the flight, as text, JSON or tables.

use super::verdict::Verdict;
use crate::report::analysis::{ReportView, TaskView};
use crate::report::flight::{EnvelopeView, RmsMax};
use crate::report::{self, time};
use crate::simulate::{chain_table, observations_view, Extended, ObsChain};
use crate::table::Table;
use rtpipe_analysis::{Anchor, Metric, Report};
use rtpipe_fly::{Flight, Setup};
use rtpipe_model::{Nanos, Spec};
use rtpipe_runtime::{Policy, RunResult, Spin};
use rtpipe_sim::observe::{ChainObs, Summary};
use serde::Serialize;

use super::tables::{sections_table, task_table};

/// `rtpipe run`'s report.
pub(super) struct RunReport<'a> {
    pub spec: &'a Spec,
    pub report: &'a Report,
    pub res: &'a RunResult,
    pub obs: &'a [ChainObs],
    pub spin: Spin,
    pub verdict: &'a Verdict,
    pub flight: Option<(&'a Flight, &'a Setup)>,
}

impl Serialize for RunReport<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut v = to_json(
            self.spec,
            self.report,
            self.res,
            self.obs,
            self.spin,
            self.verdict,
        );
        v.flight = self.flight.map(|(f, s)| flight_json(f, s));
        v.serialize(s)
    }
}

impl rtpipe_printer::Report for RunReport<'_> {
    /// The text with the verdict and the flight.
    fn text(&self) -> String {
        let spec = self.spec;
        let flown = self.flight.is_some();
        let mut out = to_text(spec, self.report, self.res, self.obs, self.spin, flown);
        out.push('\n');
        out.push_str(&self.verdict.text(spec, 10));
        if let Some((f, s)) = self.flight {
            let failures = f.quality.failures(&s.criteria());
            out.push_str(&format!(
                "\nflight ({}, mission {}, bodies on real threads):\n",
                s.preset.name, s.mission.name
            ));
            out.push_str(&report::flight::quality_text(
                &f.quality,
                &s.criteria(),
                &failures,
            ));
        }
        out
    }

    /// The analysis' tasks and chains, then what the run observed of each
    /// chain from each anchor (as `simulate`'s).
    fn tables(&self) -> Vec<rtpipe_printer::Table> {
        let mut ts = crate::report::analysis::tables(self.spec, self.report);
        ts.push(crate::simulate::observed_table(self.spec, self.obs));
        ts
    }
}

/// The `flight` entry of the JSON: the vehicle, the mission and how the
/// flight went, its figures named as `fly --json` names them.
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "RunFlightView")]
struct FlightView<'a> {
    vehicle: &'a str,
    mission: &'a str,
    crashed: bool,
    airborne_s: f64,
    landed_s: Option<f64>,
    attitude_error_deg: RmsMax,
    altitude_error_m: RmsMax,
    envelope: EnvelopeView,
    failures: Vec<String>,
}

fn flight_json<'a>(f: &Flight, s: &'a Setup) -> FlightView<'a> {
    let q = &f.quality;
    FlightView {
        vehicle: &s.preset.name,
        mission: &s.mission.name,
        crashed: q.crashed,
        airborne_s: q.airborne_s,
        landed_s: q.landed_s,
        attitude_error_deg: (&q.attitude_error_deg).into(),
        altitude_error_m: (&q.altitude_error_m).into(),
        envelope: q.into(),
        failures: q.failures(&s.criteria()),
    }
}

/// The text report: what ran, the chains against the bounds (from the
/// head's read, from the event, and the paper's Fig. 10 columns), the
/// tasks, and the steal time.
fn to_text(
    spec: &Spec,
    report: &Report,
    res: &RunResult,
    obs: &[ChainObs],
    spin: Spin,
    flight: bool,
) -> String {
    let mut out = crate::report::analysis::system_line(spec);
    out.push_str(&ran_line(spec, res, spin, flight));
    if res.policy == Policy::Deadline {
        out.push_str(if res.partitioned {
            "SCHED_DEADLINE, partitioned EDF: one root domain per CPU (exclusive cpusets), each thread pinned to its task's CPU\n"
        } else {
            "SCHED_DEADLINE threads are not pinned (the kernel requires their affinity to span the root domain): global EDF on all CPUs\n"
        });
    }
    out.extend(res.dispatch.map(|d| d.describe()));
    if !obs.is_empty() {
        out.push_str(
            "\nchains (observed from the head's read, against the analysis' worst-case bounds):\n",
        );
        out.push_str(&chain_table(spec, obs, Anchor::Read));
        out.push_str("\nfrom the event just after each head read, against the +event bounds:\n");
        out.push_str(&chain_table(spec, obs, Anchor::Event));
        out.push_str(
            "\nthe paper's Fig. 10 columns (from the head's read; AVG mean, WC max, MaxV max - min; R reaction, F freshness):\n",
        );
        out.push_str(&fig10_table(spec, obs));
    }
    let overheads = if spec.overheads.is_zero() {
        "which has no wake-up latency or switching overhead"
    } else {
        "with the spec's [system] overheads (`--measure-overheads` measures this machine's)"
    };
    out.push_str(&format!(
        "\ntasks (R = publish - release; R(job): the analysed worst case, {overheads}; \
         start = read - release; demand = CPU time of one job):\n",
    ));
    out.push_str(&task_table(spec, report, res));
    if !spec.resources.is_empty() {
        out.push_str(&format!(
            "\ncritical sections (resource_protocol = \"{}\"; held: lock taken to given back, wall time; overlaps: holds of one resource that overlapped, 0 when mutual exclusion held):\n",
            spec.resource_protocol.name()
        ));
        out.push_str(&sections_table(spec, res));
    }
    out.push_str(&format!(
        "\nsteal time during the run: {}\n",
        res.steal
            .map_or_else(|| "unknown".into(), |s| format!("{:.1} ms", s as f64 / 1e6))
    ));
    for t in &res.foreign_rt {
        out.push_str(&format!(
            "foreign real-time thread on the run's CPUs: {}\n",
            t.describe()
        ));
    }
    out
}

/// What ran, for how long, under which class and load, with which bodies;
/// best effort says loudly that no figure is a real-time measurement.
fn ran_line(spec: &Spec, res: &RunResult, spin: Spin, flight: bool) -> String {
    let u = spec.time_unit;
    let rt = if res.policy == Policy::Other {
        " -- NOT REAL-TIME (best effort): no figure below is a real-time measurement"
    } else {
        ""
    };
    format!(
        "ran {} {u} under {}{}{}{rt}; {}\n",
        spec.fmt_time(res.sim.horizon),
        res.policy.class(),
        match res.load {
            0 => String::new(),
            n => format!(" with {n} background hog(s)"),
        },
        if res.interrupted {
            format!(", interrupted by {}", rtpipe_runtime::sys::stop_name())
        } else {
            String::new()
        },
        if flight {
            "the flight bodies, the world co-simulated at the true instants".to_string()
        } else {
            format!(
                "synthetic bodies burning each task's demand (spin loop: {:.0} iterations/us)",
                spin.iters_per_us
            )
        }
    )
}

/// `run --json`: the observations report with each task's measurements,
/// the Fig. 10 figures, the run, and the flight when bodies flew.
#[derive(Serialize, schemars::JsonSchema)]
pub(super) struct RunView<'a> {
    #[serde(flatten)]
    report: ReportView<'a, Extended<TaskView<'a>, TaskMeasured>, ObsChain<'a>>,
    /// The paper's Fig. 10 figures per chain.
    fig10: Vec<Fig10View>,
    /// The run's settings and figures.
    run: RunInfo<'a>,
    /// When the tasks flew bodies: how the flight went.
    #[serde(skip_serializing_if = "Option::is_none")]
    flight: Option<FlightView<'a>>,
}

/// What the run measured of a task's thread (counts of jobs; times in
/// the spec's unit).
#[derive(Serialize, schemars::JsonSchema)]
#[schemars(rename = "Measured")]
struct TaskMeasured {
    /// Jobs released.
    released: u64,
    /// Jobs completed.
    completed: u64,
    /// The largest response time measured, in the spec's time unit.
    max_response: Option<f64>,
    /// The mean response time, in the spec's time unit.
    mean_response: Option<f64>,
    /// The 99th percentile response time, in the spec's time unit.
    p99_response: Option<f64>,
    /// Completed jobs that finished after their deadline, counted from the
    /// nominal release.
    late: u64,
    /// Jobs that published after their deadline (release + D).
    missed_periods: u64,
    /// Jobs whose CPU time (read to publish) exceeded the task's budget.
    overruns: u64,
    /// Releases merged into a job still queued (a task in a work-queue
    /// thread or data-triggered); 0 for any other.
    merged: u64,
    /// The largest demand a job measured, in the spec's time unit.
    max_demand: f64,
    /// The largest delay from release to read, in the spec's time unit (for
    /// a CPU's highest-priority task, the kernel's wake-up latency).
    max_start: f64,
    /// The thread's SCHED_FIFO priority (`fifo` only; else null).
    priority: Option<i32>,
    /// The share of its CPU the thread used.
    utilization: f64,
}

#[derive(Serialize, schemars::JsonSchema)]
struct RunInfo<'a> {
    /// The run's length, in the spec's time unit.
    duration: f64,
    /// The scheduling policy (`fifo`, `deadline`, `edf-fifo`, `other`).
    policy: &'static str,
    /// Background CPU hogs (SCHED_OTHER) that ran for the whole run.
    load: usize,
    /// CLOCK_MONOTONIC at the run's time 0, ns.
    epoch_monotonic_ns: Nanos,
    /// Whether the tasks ran under a real-time class (false: best effort, no
    /// guarantee).
    real_time: bool,
    /// Whether a signal stopped the run early.
    interrupted: bool,
    /// Steal time of all CPUs during the run (a hypervisor ran someone
    /// else), in the spec's time unit; null when /proc/stat lacks it.
    steal: Option<f64>,
    /// Other processes' real-time threads that may run on the run's CPUs
    /// and used CPU time during it, in words (most CPU time first).
    foreign_rt_threads: Vec<String>,
    /// The calibrated busy loop's iterations per µs.
    spin_iterations_per_us: f64,
    /// EDF only: `partitioned` (SCHED_DEADLINE with a root domain per CPU,
    /// or the EDF dispatcher's pinned threads) or `global` EDF.
    edf: Option<&'static str>,
    /// Observations above a sound bound, and their causes.
    sound_bound_violations: &'a Verdict,
    /// Notes of the run, in words.
    notes: &'a [String],
    /// Per resource: its sections as the threads held them.
    critical_sections: Vec<HeldView<'a>>,
    /// Under `edf-fifo`: what the EDF dispatcher did.
    dispatcher: Option<DispatchView>,
}

/// The EDF dispatcher's counts (`rtpipe_runtime::edf::Stats`).
#[derive(Serialize, schemars::JsonSchema)]
struct DispatchView {
    dispatches: u64,
    priority_changes: u64,
    held_back_by_ceiling: u64,
    quiet_section_exits: u64,
    contended: u64,
    refused: u64,
}

impl From<rtpipe_runtime::edf::Stats> for DispatchView {
    fn from(s: rtpipe_runtime::edf::Stats) -> DispatchView {
        DispatchView {
            dispatches: s.dispatches,
            priority_changes: s.changes,
            held_back_by_ceiling: s.held_back,
            quiet_section_exits: s.quiet_exits,
            contended: s.contended,
            refused: s.failed,
        }
    }
}

/// One resource's sections in a run.
#[derive(Serialize, schemars::JsonSchema)]
struct HeldView<'a> {
    resource: &'a str,
    holds: usize,
    max_held: f64,
    overlaps: usize,
}

fn held_json<'a>(spec: &'a Spec, res: &RunResult) -> Vec<HeldView<'a>> {
    let holds: Vec<_> = res
        .tasks
        .iter()
        .flat_map(|t| t.sections.iter().copied())
        .collect();
    let rows = rtpipe_runtime::locks::summary(spec.resources.len(), &holds);
    spec.resources
        .iter()
        .zip(rows)
        .map(|(r, (holds, longest, overlaps))| HeldView {
            resource: &r.name,
            holds,
            max_held: spec.in_unit(longest),
            overlaps,
        })
        .collect()
}

fn to_json<'a>(
    spec: &'a Spec,
    report: &Report,
    res: &'a RunResult,
    obs: &[ChainObs],
    spin: Spin,
    verdict: &'a Verdict,
) -> RunView<'a> {
    let measured = |(ts, tr): (&rtpipe_joblog::TaskStats, &rtpipe_runtime::TaskRun)| {
        let s = Summary::of(&tr.responses);
        TaskMeasured {
            released: ts.released,
            completed: ts.completed,
            max_response: time(spec, ts.max_response),
            mean_response: s.map(|s| s.mean / spec.time_unit.nanos() as f64),
            p99_response: time(spec, s.map(|s| s.p99)),
            late: ts.late,
            missed_periods: tr.missed,
            overruns: tr.overruns,
            merged: ts.merged,
            max_demand: spec.in_unit(tr.max_demand),
            max_start: spec.in_unit(tr.max_start),
            priority: tr.priority,
            utilization: ts.busy as f64 / res.sim.horizon as f64,
        }
    };
    let runs = res.sim.tasks.iter().zip(&res.tasks);
    let report = observations_view(spec, report, obs).with(
        |tasks| {
            (tasks.into_iter().zip(runs))
                .map(|(base, r)| Extended {
                    base,
                    observed: measured(r),
                })
                .collect()
        },
        |chains| chains,
    );
    let run = RunInfo {
        duration: spec.in_unit(res.sim.horizon),
        policy: res.policy.name(),
        load: res.load,
        epoch_monotonic_ns: res.epoch,
        real_time: res.policy != Policy::Other,
        edf: res
            .policy
            .edf()
            .then_some(if res.partitioned || res.policy == Policy::EdfFifo {
                "partitioned"
            } else {
                "global"
            }),
        interrupted: res.interrupted,
        steal: res.steal.map(|s| spec.in_unit(s)),
        foreign_rt_threads: res.foreign_rt.iter().map(|t| t.describe()).collect(),
        spin_iterations_per_us: spin.iters_per_us,
        sound_bound_violations: verdict,
        notes: &res.notes,
        critical_sections: held_json(spec, res),
        dispatcher: res.dispatch.map(DispatchView::from),
    };
    RunView {
        report,
        fig10: fig10_json(spec, obs),
        run,
        flight: None,
    }
}

/// One chain's Fig. 10 figures from the head's read: (mean, max, max − min)
/// of reaction and of freshness, and the sound bounds.
struct Fig10 {
    chain: usize,
    reaction: Option<Summary>,
    freshness: Option<Summary>,
    sound_r: Option<Nanos>,
    sound_f: Option<Nanos>,
}

/// The chains in order, each with its two metrics.
fn fig10_rows(obs: &[ChainObs]) -> Vec<Fig10> {
    let mut rows: Vec<Fig10> = Vec::new();
    for o in obs {
        if rows.last().is_none_or(|r| r.chain != o.chain) {
            rows.push(Fig10 {
                chain: o.chain,
                reaction: None,
                freshness: None,
                sound_r: None,
                sound_f: None,
            });
        }
        let Some(row) = rows.last_mut() else { continue };
        match o.metric {
            Metric::Reaction => (row.reaction, row.sound_r) = (o.read.observed, o.read.sound),
            Metric::Freshness => (row.freshness, row.sound_f) = (o.read.observed, o.read.sound),
        }
    }
    rows
}

fn fig10_table(spec: &Spec, obs: &[ChainObs]) -> String {
    let mut t = Table::new(&[
        "chain", "AVGR", "WCR", "MaxRV", "sound R", "AVGF", "WCF", "MaxFV", "sound F",
    ])
    .numeric(&[1, 2, 3, 4, 5, 6, 7, 8]);
    let f = |x: Option<Nanos>| x.map_or_else(|| "-".into(), |v| spec.fmt_time(v));
    let summary_cells = |s: Option<Summary>| {
        [
            f(s.map(|s| s.mean.round() as Nanos)),
            f(s.map(|s| s.max)),
            f(s.map(|s| s.max - s.min)),
        ]
    };
    for r in fig10_rows(obs) {
        let mut row = vec![spec.chain_label(r.chain)];
        row.extend(summary_cells(r.reaction));
        row.push(f(r.sound_r));
        row.extend(summary_cells(r.freshness));
        row.push(f(r.sound_f));
        t.row(row);
    }
    t.render()
}

/// `fig10`: one entry per chain, in the spec's unit.
#[derive(Serialize, schemars::JsonSchema)]
#[allow(non_snake_case)] // the paper's names for the figures
struct Fig10View {
    /// The chain's label.
    chain: String,
    /// The mean reaction time, in the spec's time unit.
    AVGR: Option<f64>,
    /// The largest reaction time, in the spec's time unit.
    WCR: Option<f64>,
    /// Reaction-time variation (max − min), in the spec's time unit.
    MaxRV: Option<f64>,
    /// The sound reaction bound, in the spec's time unit.
    sound_reaction: Option<f64>,
    /// The mean freshness (data age), in the spec's time unit.
    AVGF: Option<f64>,
    /// The largest freshness, in the spec's time unit.
    WCF: Option<f64>,
    /// Freshness variation (max − min), in the spec's time unit.
    MaxFV: Option<f64>,
    /// The sound freshness bound, in the spec's time unit.
    sound_freshness: Option<f64>,
}

fn fig10_json(spec: &Spec, obs: &[ChainObs]) -> Vec<Fig10View> {
    let unit = spec.time_unit.nanos() as f64;
    let n = |x: Option<Nanos>| time(spec, x);
    let summary_cells = |s: Option<Summary>| {
        (
            s.map(|s| s.mean / unit),
            n(s.map(|s| s.max)),
            n(s.map(|s| s.max - s.min)),
        )
    };
    fig10_rows(obs)
        .into_iter()
        .map(|r| {
            let (avgr, wcr, maxrv) = summary_cells(r.reaction);
            let (avgf, wcf, maxfv) = summary_cells(r.freshness);
            Fig10View {
                chain: spec.chain_label(r.chain),
                AVGR: avgr,
                WCR: wcr,
                MaxRV: maxrv,
                sound_reaction: n(r.sound_r),
                AVGF: avgf,
                WCF: wcf,
                MaxFV: maxfv,
                sound_freshness: n(r.sound_f),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_names_the_flight_s_figures_as_fly_does() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/cleanflight.toml");
        let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let r = rtpipe_fly::Request {
            spec_path: &path,
            vehicle: "racer5",
            mission: "hover",
            horizon: Some(6_000_000_000),
            seed: 0,
        };
        let s = rtpipe_fly::setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
        let f = rtpipe_fly::fly(&spec, &s, rtpipe_sim::ExecModel::Uniform)
            .unwrap_or_else(|e| panic!("{e}"));
        let v = serde_json::to_value(flight_json(&f, &s)).unwrap_or_default();
        // `fly --json` has flight.attitude_error_deg.rms and .max.
        for key in ["attitude_error_deg", "altitude_error_m"] {
            assert!(
                v[key]["rms"].is_number() && v[key]["max"].is_number(),
                "{v}"
            );
        }
        assert!(v.get("attitude_error_deg_rms").is_none(), "{v}");
    }
}
