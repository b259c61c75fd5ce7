//! `rtpipe fly --sweep`: timing limits from control quality. Flies the same
//! mission over period scales and pure chain delays (rtpipe_fly::sweep) and
//! reports where the flight stops meeting its criteria, the chain limits
//! that follow, and optionally writes them into a spec.

mod report;

use super::args::FlyArgs;
use crate::command::{self, Answer};
use crate::output;
use crate::table::Table;
use rtpipe_flight::quality::{Axis, Criteria, FlightQuality};
use rtpipe_fly::confidence::Requirement;
use rtpipe_fly::sweep::{
    check_below, deciding, derived_limits, edge, refine, scale_edge, sweep, tails, variations,
    ChainPair, Derived, How, Point, Rule, Stage, Trials, Variation, DELAY_LINES,
};
use rtpipe_fly::Setup;
use rtpipe_model::{Diagnostic, Nanos, Spec};
use serde::Serialize;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

fn criteria(a: &FlyArgs, s: &Setup) -> Result<Criteria, Diagnostic> {
    let Some(path) = &a.criterion else {
        return Ok(s.criteria());
    };
    Criteria::from_file(path).map_err(|e| rtpipe_fly::from_file("--criterion", &e, ""))
}

fn ms(ns: Option<Nanos>) -> String {
    ns.map_or("-".into(), |v| format!("{:.3}", v as f64 * 1e-6))
}

/// A point's timing, and "(check)" after a check point's.
fn timing(p: &Point) -> String {
    match p.stage {
        Stage::Check => format!("{} (check)", what(&p.variation)),
        Stage::Grid | Stage::Refinement => what(&p.variation),
    }
}

fn what(v: &Variation) -> String {
    match v {
        Variation::Scale(k) => format!("periods ×{k:.3}"),
        Variation::Rate(k) => format!("tail period ×{k:.3}"),
        Variation::Delay { line, ns } => {
            // Exact decimals of the integer delay: a float product printed
            // grid points as 90.50966799999999.
            let delay = Nanos::try_from(*ns).map_or_else(
                |_| format!("{ns}e-6"),
                |d| rtpipe_model::time::format_in(d, rtpipe_model::time::TimeUnit::Ms),
            );
            format!("{} +{delay} ms", DELAY_LINES[*line].name())
        }
    }
}

/// Whether a point flies, with its flights passed / flown and, under the
/// pass-rate rule, the counts of the setup that decides it (the lowest
/// bound; named among several `setups`).
fn verdict(p: &Point, setups: &[String]) -> String {
    let per_setup = p.against_reference.as_deref().and_then(deciding);
    let count = match (p.flights(), per_setup) {
        (_, Some((k, a))) => format!(
            " ({}/{} flights; {}{}/{} of the reference's passes, lower bound {:.3})",
            p.passed(),
            p.flights(),
            match setups {
                [_, _, ..] => format!("lowest of the setups, {}: ", setups[k]),
                _ => String::new(),
            },
            a.passed,
            a.counted,
            a.lower_bound
        ),
        (2.., None) => format!(" ({}/{} flights)", p.passed(), p.flights()),
        _ => String::new(),
    };
    match (p.schedulable, p.pass()) {
        (false, _) => "unschedulable".into(),
        (true, true) => format!("flies{count}"),
        // Under the pass-rate rule a timing may fail on its count alone.
        (true, false) if p.failures.is_empty() => format!("FAILS{count}"),
        (true, false) => format!("FAILS{count}: {}", p.failures.join("; ")),
    }
}

fn points_table(spec: &Spec, points: &[&Point], setups: &[String]) -> String {
    let mut head = vec!["timing".to_string()];
    for k in 0..spec.chains.len() {
        head.push(format!("{} R/F ms", spec.chain_label(k)));
    }
    head.push("flight".into());
    let refs: Vec<&str> = head.iter().map(String::as_str).collect();
    let mut t = Table::new(&refs);
    for p in points {
        let mut row = vec![timing(p)];
        for b in &p.bounds {
            row.push(format!("{} / {}", ms(b.0), ms(b.1)));
        }
        row.push(verdict(p, setups));
        t.row(row);
    }
    t.render()
}

fn limits_text(spec: &Spec, d: &Derived) -> String {
    let mut t = Table::new(&[
        "chain",
        "reaction",
        "freshness",
        "max reaction time",
        "freshness from event",
        "spec's reaction",
        "spec's freshness",
    ])
    .numeric(&[1, 2, 3, 4, 5, 6]);
    for (k, (l, e)) in d.read.iter().zip(&d.event).enumerate() {
        let ch = &spec.chains[k];
        t.row(vec![
            spec.chain_label(k),
            ms(l.0),
            ms(l.1),
            ms(e.0),
            ms(e.1),
            ms(ch.reaction),
            ms(ch.freshness),
        ]);
    }
    t.render()
}

/// The spec with every derived limit (see `--write-limits`); the periods
/// of the tasks in `free` ([`freed`]) become ranges up to the largest
/// from-event limit of their chains (so that no fixed period elsewhere, a
/// housekeeping task's say, sets their ceiling), and no further than the
/// longest period of the task the scale sweep flew and passed
/// ([`Derived::scaled_period`]): a longer one was never flown.
fn with_limits(spec: &Spec, s: &Setup, d: &Derived, free: &[bool]) -> Spec {
    let mut out = spec.clone();
    for ((ch, l), e) in out.chains.iter_mut().zip(&d.read).zip(&d.event) {
        ch.reaction = l.0.or(ch.reaction);
        ch.freshness = l.1.or(ch.freshness);
        ch.max_reaction_time = e.0.or(ch.max_reaction_time);
        ch.freshness_from_event = e.1.or(ch.freshness_from_event);
    }
    let tails = tails(spec, s);
    for (i, t) in out.tasks.iter_mut().enumerate() {
        if tails.contains(&i) {
            t.max_period = d.max_period[i].or(t.max_period);
        }
        let cap = spec
            .chains
            .iter()
            .zip(&d.event)
            .filter(|(c, _)| c.path.contains(&i))
            .filter_map(|(_, e)| e.0.max(e.1))
            .max()
            .map(|m| d.scaled_period[i].map_or(m, |flown| m.min(flown)));
        if let (true, Some(max)) = (free[i], cap) {
            let max = max - max % spec.resolution.max(1);
            t.period = rtpipe_model::PeriodSpec::Range {
                min: None,
                max: Some(max),
            };
        }
    }
    out
}

/// Whether task `i` may have its period freed: it is guaranteed (not a
/// background server's), periodic (a data-triggered task's rate is its
/// triggers': the design frees its sources instead) and on a chain.
fn freeable(spec: &Spec, i: usize) -> bool {
    let t = &spec.tasks[i];
    t.server != rtpipe_model::Server::Background
        && !matches!(t.period, rtpipe_model::PeriodSpec::Triggered { .. })
        && spec.chains.iter().any(|c| c.path.contains(&i))
}

/// Which tasks' periods `--free-periods` frees: none without it, every
/// freeable task with it alone, the named ones with a list (each must be
/// freeable; checked before any flight).
fn freed(spec: &Spec, names: Option<&[String]>) -> Result<Vec<bool>, Diagnostic> {
    let n = spec.tasks.len();
    let Some(names) = names else {
        return Ok(vec![false; n]);
    };
    if names.is_empty() {
        return Ok((0..n).map(|i| freeable(spec, i)).collect());
    }
    let mut free = vec![false; n];
    for name in names {
        let found = spec.tasks.iter().position(|t| &t.name == name);
        match found {
            Some(i) if freeable(spec, i) => free[i] = true,
            Some(_) => {
                return Err(Diagnostic::error(
                    format!("--free-periods: task `{name}` has no period the design may choose: it is data-triggered, a background server's, or on no chain"),
                    "name periodic tasks on a chain (the sources of the triggered ones), or give --free-periods alone to free them all",
                ))
            }
            None => {
                return Err(Diagnostic::error(
                    format!("--free-periods: the spec has no task `{name}`"),
                    "name tasks of the spec, separated by commas: --free-periods=gyro,attitude",
                ))
            }
        }
    }
    Ok(free)
}

#[derive(Serialize, schemars::JsonSchema)]
struct PointView<'a> {
    /// What the sweep varied at this point (e.g. `scale`).
    varied: &'static str,
    /// Its value.
    value: f64,
    /// Which pass of the sweep flew it: `grid`, `refinement` (bisecting
    /// an edge) or `check` (below a written limit, --check-step).
    stage: &'static str,
    /// Each chain's sound bounds from the read at this timing, ms.
    bounds_ms: Vec<PairMs>,
    /// From the event: `reaction` is the maximum reaction time,
    /// `freshness` freshness from the event.
    event_bounds_ms: Vec<PairMs>,
    /// Whether the timing passes the schedulability test.
    schedulable: bool,
    /// The timing is schedulable and its flight met the criterion: a
    /// point the limits may rest on.
    flies: bool,
    /// The simulated flight met the criterion, whatever the schedulability
    /// test says (an unschedulable timing may still fly in simulation when
    /// its worst case does not happen).
    flight_met_criterion: bool,
    /// Flights flown at this timing (seeds × phases × setups): it flies
    /// when all met the criterion, or by the pass-rate rule (`rule`).
    flights: u32,
    /// Flights that met the criterion.
    passed: u32,
    /// With --pass-rate, per vehicle/mission setup (in the sweep's
    /// order): of its flights the reference timing passed, how many passed
    /// here too, and the Wilson lower bound of that share (the timing
    /// flies when every setup's reaches the rate).
    #[serde(skip_serializing_if = "Option::is_none")]
    against_reference: Option<Vec<AgainstReferenceView>>,
    /// Each flight met its criterion (true) or not, in the sweep's flight
    /// order: the setups as listed (the first, then `also`'s), within each
    /// the seeds, within each seed the phase draws; empty when the timing
    /// could not be flown.
    outcomes: &'a [bool],
    /// The criteria the flights missed, in words.
    failures: &'a [String],
    /// Attitude error RMS over the flights, degrees.
    attitude_error_rms_deg: Option<f64>,
    /// Altitude error RMS over the flights, m.
    altitude_error_rms_m: Option<f64>,
    /// Position error RMS over the flights, m (missions that judge it).
    position_error_rms_m: Option<f64>,
    /// Whether a flight crashed.
    crashed: Option<bool>,
}

/// A setup's flights at a timing counted against the reference timing's.
#[derive(Serialize, schemars::JsonSchema)]
struct AgainstReferenceView {
    /// The setup, "vehicle/mission".
    setup: String,
    /// Flights the reference timing passed that passed here too.
    passed: u32,
    /// Flights the reference timing passed.
    counted: u32,
    /// The lower end of the Wilson interval of passed / counted.
    lower_bound: f64,
}

/// A chain's reaction and freshness, in ms (null: none).
#[derive(Serialize, schemars::JsonSchema)]
struct PairMs {
    /// The maximum reaction time, ms; null when unbounded.
    reaction: Option<f64>,
    /// The maximum data age, ms; null when unbounded.
    freshness: Option<f64>,
}

impl From<&ChainPair> for PairMs {
    fn from(p: &ChainPair) -> Self {
        let ms = |ns: Option<Nanos>| ns.map(|x| x as f64 * 1e-6);
        PairMs {
            reaction: ms(p.0),
            freshness: ms(p.1),
        }
    }
}

fn point_json<'a>(p: &'a Point, setups: &[String]) -> PointView<'a> {
    let (varied, value) = match p.variation {
        Variation::Scale(k) => ("scale", k),
        Variation::Rate(k) => ("tail rate", k),
        Variation::Delay { line, ns } => (DELAY_LINES[line].name(), ns as f64 * 1e-6),
    };
    let q = p.quality.as_ref();
    // A crashed flight, or one that never hovered, has no hover figures.
    let hover = q.filter(|q| !q.crashed && q.attitude_error_deg.count > 0);
    PointView {
        varied,
        value,
        stage: p.stage.name(),
        bounds_ms: p.bounds.iter().map(PairMs::from).collect(),
        event_bounds_ms: p.event.iter().map(PairMs::from).collect(),
        schedulable: p.schedulable,
        flies: p.schedulable && p.pass(),
        flight_met_criterion: p.pass(),
        flights: p.flights(),
        passed: p.passed(),
        against_reference: p.against_reference.as_ref().map(|per_setup| {
            per_setup
                .iter()
                .zip(setups)
                .map(|(a, setup)| AgainstReferenceView {
                    setup: setup.clone(),
                    passed: a.passed,
                    counted: a.counted,
                    lower_bound: a.lower_bound,
                })
                .collect()
        }),
        outcomes: &p.outcomes,
        failures: &p.failures,
        attitude_error_rms_deg: hover.map(|q| q.attitude_error_deg.rms),
        altitude_error_rms_m: hover.map(|q| q.altitude_error_m.rms),
        position_error_rms_m: hover.map(|q| q.position_error_m.rms),
        crashed: q.map(|q| q.crashed),
    }
}

/// The sweep plot: per chain, every scale point and the chain's own delay
/// points.
fn chart(spec: &Spec, s: &Setup, c: &Criteria, points: &[Point]) -> Result<String, String> {
    use crate::plot::DotOutcome;
    let measure = sweep_measure(s, c);
    let figure = |q: &FlightQuality| match measure.as_ref().map(|m| m.1) {
        Some(Figure::Settling) => q
            .steps
            .iter()
            .filter(|st| st.axis != Axis::Yaw)
            .map(|st| st.tracked.settling_s)
            .fold(0.0, f64::max),
        // Never hovered: nothing held, drawn at the top.
        _ if q.attitude_error_deg.count == 0 => f64::INFINITY,
        Some(Figure::Position) => q.position_error_m.rms,
        _ => q.attitude_error_deg.rms,
    };
    let outcome = |p: &Point| match &p.quality {
        None => DotOutcome::NotFlown,
        Some(q) if q.crashed => DotOutcome::Crashed,
        Some(q) => DotOutcome::Measured(figure(q)),
    };
    let panels = (0..spec.chains.len())
        .map(|k| {
            let line = rtpipe_fly::sweep::head_line(spec, s, k);
            let dots = points
                .iter()
                .filter(|p| p.schedulable)
                .filter(|p| match p.variation {
                    Variation::Scale(_) => true,
                    Variation::Rate(_) => false,
                    Variation::Delay { line: l, .. } => Some(l) == line,
                })
                .filter_map(|p| {
                    let (r, f) = *p.bounds.get(k)?;
                    Some(crate::plot::SweepDot {
                        reaction_ms: r? as f64 * 1e-6,
                        freshness_ms: f? as f64 * 1e-6,
                        outcome: outcome(p),
                        flies: p.pass(),
                        delay: matches!(p.variation, Variation::Delay { .. }),
                        passed: p.passed(),
                        flown: p.flights(),
                        check: p.stage == Stage::Check,
                    })
                })
                .collect();
            let ch = &spec.chains[k];
            let ms = |l: Option<Nanos>| l.map(|l| l as f64 * 1e-6);
            (
                spec.chain_label(k),
                (ms(ch.reaction), ms(ch.freshness)),
                dots,
            )
        })
        .collect::<Vec<_>>();
    crate::plot::sweep_chart(&panels, measure.as_ref().map(|m| &m.0))
}

/// Which figure of a flight the sweep plot shows.
#[derive(Clone, Copy)]
enum Figure {
    Settling,
    Position,
    Attitude,
}

/// What the sweep plot measures for the mission `s` flies, judged by `c`:
/// the worst roll/pitch step's settling when it has such steps, else the
/// hover's position error (where the criterion judges it) or attitude
/// error; `None` for a mission with neither (nothing to plot).
fn sweep_measure(s: &Setup, c: &Criteria) -> Option<(crate::plot::SweepMeasure, Figure)> {
    let has_steps =
        s.mission.steps.iter().any(|st| {
            st.roll_deg.is_some_and(|r| r != 0.0) || st.pitch_deg.is_some_and(|p| p != 0.0)
        });
    let hovers = s.mission.steps.iter().any(|st| st.altitude_m.is_some());
    let (axis, criterion, limit, figure) = if has_steps {
        let l = c.settling_s;
        (
            "worst step settling (s)",
            format!("criterion: settling < {l} s"),
            l,
            Figure::Settling,
        )
    } else if let (true, Some(l)) = (hovers, c.position_rms_m) {
        (
            "hover position error RMS (m)",
            format!("criterion: position RMS < {l} m"),
            l,
            Figure::Position,
        )
    } else if hovers {
        let l = c.attitude_rms_deg;
        (
            "hover attitude error RMS (°)",
            format!("criterion: attitude RMS < {l}°"),
            l,
            Figure::Attitude,
        )
    } else {
        return None;
    };
    let m = crate::plot::SweepMeasure {
        axis: axis.to_string(),
        criterion,
        limit,
    };
    Some((m, figure))
}

/// Runs the sweep `a` asks for on `spec` as set up in `s`.
/// `also`: further (vehicle, mission) setups every timing is flown on too,
/// each judged by `--criterion` or its own criteria.
pub fn execute(
    spec: &Spec,
    (s, also): (&Setup, &[Setup]),
    a: &FlyArgs,
    stop: Option<&AtomicBool>,
) -> Result<Answer, Diagnostic> {
    let c = criteria(a, s)?;
    let also = also
        .iter()
        .map(|o| Ok((o.clone(), criteria(a, o)?)))
        .collect::<Result<Vec<_>, Diagnostic>>()?;
    enough_flights(a, 1 + also.len() as u32)?;
    let (lo, hi) = a.scale.unwrap_or((0.5, 8.0));
    let vars = variations(spec, s, lo, hi, a.per_octave);
    if let Some(out) = &a.write_limits {
        crate::output::prepare("--write-limits", out, &a.spec, None)?;
    }
    let free = freed(spec, a.free_periods.as_deref())?;
    let Some(points) = fly_all(spec, (s, &also), a, &c, &vars, stop) else {
        return Ok(Answer::stopped());
    };
    let limits = derived_limits(spec, s, &points, a.safety);
    // Nothing flew: a spec "with these limits" would carry none of them.
    let nothing = limits
        .read
        .iter()
        .chain(&limits.event)
        .all(|l| l.0.is_none() && l.1.is_none())
        && limits.max_period.iter().all(Option::is_none);
    let write_limits = a.write_limits.as_deref().filter(|_| !nothing);
    let written = write_files(spec, s, a, (&c, &free), &points, &limits, write_limits);
    let view = report::SweepReport {
        spec,
        setup: s,
        also: &also,
        criteria: &c,
        args: a,
        points: &points,
        limits: &limits,
        written: write_limits.filter(|_| written.is_ok()),
    };
    let report = command::render(&view, a.output.chosen())?;
    let mut notes = too_few_counted(a, &setups(s, &also), &points);
    if let (Some(out), true) = (&a.write_limits, nothing) {
        let d = Diagnostic::error(
            format!(
                "no flight of the sweep met the criterion, so no chain limit could be derived: {} was not written",
                out.display()
            ),
            "check that the vehicle flies the mission at the spec's own periods (rtpipe fly), relax the criterion, or widen --scale",
        );
        // A diagnostic ends its own last line; a note gets one when printed.
        notes.push(d.to_string().trim_end().to_string());
    }
    let status = u8::from(!notes.is_empty());
    let answer = Answer {
        report,
        notes,
        status,
    };
    Ok(answer.after_write(written))
}

/// The sweep's progress bar on stderr, `timings` long, named by the spec.
fn progress_bar(name: &str, timings: usize) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(timings as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "sweeping {msg} [{bar:30}] {pos}/{len} timings, {elapsed_precise} elapsed, ETA {eta}",
    ) {
        pb.set_style(style);
    }
    pb.set_message(name.to_string());
    pb
}

/// Flies every variation (on a worker thread) while a progress bar on
/// stderr counts the flights done; a panic in the sweep goes on unwinding
/// here. `None` when `stop` (asked before each flight) ended the sweep.
fn fly_all(
    spec: &Spec,
    (s, also): (&Setup, &[(Setup, Criteria)]),
    a: &FlyArgs,
    c: &Criteria,
    vars: &[Variation],
    stop: Option<&AtomicBool>,
) -> Option<Vec<Point>> {
    let done = AtomicU64::new(0);
    let pb = progress_bar(&spec.name, vars.len());
    let stopped = || crate::command::Hooks::stopped(stop);
    let how = How {
        exec: a.exec.model(),
        criteria: c,
        trials: Trials {
            seeds: a.seeds,
            phases: a.phases,
        },
        also,
        rule: Rule::AllPass,
    };
    let points = std::thread::scope(|scope| {
        let worker = scope.spawn(|| {
            // The pass-rate rule judges every timing against the flights of
            // the spec's own.
            let reference = match requirement(a) {
                Some(_) if stopped() => return None,
                Some(_) => rtpipe_fly::sweep::reference(spec, s, &how),
                None => Vec::new(),
            };
            let how = match requirement(a) {
                Some(need) => How {
                    rule: Rule::PassRate {
                        need,
                        reference: &reference,
                        setups: 1 + also.len(),
                    },
                    ..how
                },
                None => how,
            };
            let mut points = sweep(spec, s, &how, vars, &done, &stopped)?;
            if a.resolution > 0.0 {
                pb.set_message(format!("{} (refining the edges)", spec.name));
                points = refine(spec, s, &how, points, a.resolution, &done, &stopped)?;
            }
            if a.check_step > 0.0 {
                pb.set_message(format!("{} (checking below the limits)", spec.name));
                points = check_below(spec, s, &how, points, a.check_step, &done, &stopped)?;
            }
            Some(points)
        });
        while !worker.is_finished() {
            pb.set_position(done.load(Ordering::Relaxed));
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        worker.join()
    });
    pb.finish_and_clear();
    match points {
        Ok(p) => p,
        Err(e) => std::panic::resume_unwind(e),
    }
}

/// `--write-limits` (the spec with the derived limits; `write_limits`,
/// `None` when no limit was derived) and `--plot` (DIR/sweep.svg), all
/// written or none.
fn write_files(
    spec: &Spec,
    s: &Setup,
    a: &FlyArgs,
    (c, free): (&Criteria, &[bool]),
    points: &[Point],
    limits: &Derived,
    write_limits: Option<&Path>,
) -> Result<(), Diagnostic> {
    let mut files = Vec::new();
    if let Some(out) = write_limits {
        let text = rtpipe_model::to_toml(&with_limits(spec, s, limits, free));
        files.push(("--write-limits", out.to_path_buf(), text));
    }
    if let Some(dir) = &a.plot {
        match chart(spec, s, c, points) {
            Ok(svg) => files.push(("--plot", dir.join("sweep.svg"), svg)),
            Err(e) => return Err(Diagnostic::error(format!("cannot draw the sweep: {e}"), "")),
        }
        output::ensure_dir(dir)?;
    }
    output::write_files(&a.spec, &files)
}

/// The sweep as one JSON object: the setup, every point, the derived
/// limits (ms).
#[derive(Serialize, schemars::JsonSchema)]
pub(super) struct SweepView<'a> {
    /// The system's name.
    system: &'a str,
    /// The vehicle flown.
    vehicle: &'a str,
    /// The mission flown.
    mission: &'a str,
    /// The criterion a flight must meet for its timing to fly.
    criterion: String,
    /// Flights per timing: seeds × phase draws.
    seeds: u32,
    /// Phase draws per seed.
    phases: u32,
    /// Every derived limit is the bound at the last timing that flew × this.
    safety: f64,
    /// When a timing flies, in words: every flight passes, or the pass-rate
    /// rule with its rate and confidence.
    rule: String,
    /// With --pass-rate: the rate the lower bound must reach.
    #[serde(skip_serializing_if = "Option::is_none")]
    pass_rate: Option<f64>,
    /// With --pass-rate: the confidence of the bound.
    #[serde(skip_serializing_if = "Option::is_none")]
    confidence: Option<f64>,
    /// Every timing flown, in sweep order.
    points: Vec<PointView<'a>>,
    /// The limits derived per chain, ms.
    limits_ms: Vec<LimitMs>,
    /// The tail's `max_period` (ms): the longest period that flew in the
    /// rate sweep.
    max_period_ms: crate::report::Pairs<&'a str, f64>,
    /// Further "vehicle/mission" setups every timing was flown on (each
    /// point's flights count theirs too).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    also: Vec<String>,
}

#[derive(Serialize, schemars::JsonSchema)]
struct LimitMs {
    /// The chain's label.
    chain: String,
    #[serde(flatten)]
    limit: PairMs,
    /// The derived `max_reaction_time` to write into the spec, ms; null when
    /// none flew.
    max_reaction_time: Option<f64>,
    /// The derived `freshness_from_event` limit to write into the spec, ms;
    /// null when none flew.
    freshness_from_event: Option<f64>,
}

fn sweep_json<'a>(
    spec: &'a Spec,
    (s, also): (&'a Setup, &[(Setup, Criteria)]),
    c: &Criteria,
    a: &FlyArgs,
    points: &'a [Point],
    limits: &Derived,
) -> SweepView<'a> {
    let chains = limits.read.iter().zip(&limits.event).enumerate();
    let chain_limits = chains.map(|(k, (l, e))| {
        let PairMs {
            reaction,
            freshness,
        } = e.into();
        LimitMs {
            chain: spec.chain_label(k),
            limit: l.into(),
            max_reaction_time: reaction,
            freshness_from_event: freshness,
        }
    });
    let max_period = spec.tasks.iter().zip(&limits.max_period);
    SweepView {
        system: &spec.name,
        vehicle: &s.preset.name,
        mission: &s.mission.name,
        criterion: c.describe(),
        seeds: a.seeds,
        phases: a.phases,
        safety: a.safety,
        rule: rule_text(a, "its criterion"),
        pass_rate: requirement(a).map(|r| r.rate),
        confidence: requirement(a).map(|r| r.confidence),
        points: points
            .iter()
            .map(|p| point_json(p, &setups(s, also)))
            .collect(),
        limits_ms: chain_limits.collect(),
        max_period_ms: crate::report::Pairs(
            max_period
                .filter_map(|(t, m)| Some((t.name.as_str(), (*m)? as f64 * 1e-6)))
                .collect(),
        ),
        also: also.iter().map(|(o, _)| label(o)).collect(),
    }
}

/// The rate sweep's table and the tail's derived `max_period`.
fn rate_text(
    spec: &Spec,
    (s, also): (&Setup, &[(Setup, Criteria)]),
    points: &[Point],
    limits: &Derived,
    safety: f64,
) -> String {
    let pts: Vec<&Point> = points
        .iter()
        .filter(|p| matches!(p.variation, Variation::Rate(_)))
        .collect();
    let tails = tails(spec, s);
    if pts.is_empty() || tails.is_empty() {
        return String::new();
    }
    let names: Vec<&str> = tails.iter().map(|&i| spec.tasks[i].name.as_str()).collect();
    let mut out = format!(
        "\nactuation rate ({} period alone; sound bounds from the read):\n",
        names.join(", ")
    );
    out.push_str(&points_table(spec, &pts, &setups(s, also)));
    for &i in &tails {
        out.push_str(&match limits.max_period[i] {
            Some(p) => format!(
                "{}: max_period {} ms (the longest period that flew{})\n",
                spec.tasks[i].name,
                ms(Some(p)),
                if safety < 1.0 {
                    format!(" × {safety}, on the design grid")
                } else {
                    String::new()
                }
            ),
            None => format!("{}: no period flew\n", spec.tasks[i].name),
        });
    }
    out
}

/// "racer5/gusty": a setup among several.
fn label(s: &Setup) -> String {
    format!("{}/{}", s.preset.name, s.mission.name)
}

/// Every setup's label, in the sweep's order (the first, then `also`'s).
fn setups(s: &Setup, also: &[(Setup, Criteria)]) -> Vec<String> {
    std::iter::once(s)
        .chain(also.iter().map(|(o, _)| o))
        .map(label)
        .collect()
}

/// The further setups every timing was flown on, each with its criterion.
fn also_text(also: &[(Setup, Criteria)], by_rate: bool) -> String {
    let mut out = String::from(if by_rate {
        "every timing is also flown (same seeds and phases) on each of these, judged by its criterion; each must reach the pass rate below on its own flights:\n"
    } else {
        "every timing is also flown (same seeds and phases) on each of these, judged by its criterion; it flies only if every flight of every one meets it:\n"
    });
    for (o, c) in also {
        out.push_str(&format!("  {}: criterion: {}\n", label(o), c.describe()));
    }
    out
}

/// What was swept, on what, judged how, and how many flights per timing.
fn header_text(
    spec: &Spec,
    (s, also): (&Setup, &[(Setup, Criteria)]),
    c: &Criteria,
    a: &FlyArgs,
) -> String {
    let mut out = format!(
        "sweep of {} ({} tasks): vehicle {}, mission {}, criterion: {}\n",
        spec.name,
        spec.tasks.len(),
        s.preset.name,
        s.mission.name,
        c.describe()
    );
    if !also.is_empty() {
        out.push_str(&also_text(also, a.pass_rate.is_some()));
    }
    let setups = 1 + also.len() as u32;
    if setups > 1 {
        out.push_str(&format!(
            "each timing flown {} times ({} seeds × {} phases × {setups} vehicle/mission setups): it flies {}\n",
            a.seeds * a.phases * setups,
            a.seeds,
            a.phases,
            rule_text(a, "its criterion")
        ));
    } else if a.seeds * a.phases > 1 || a.pass_rate.is_some() {
        out.push_str(&format!(
            "each timing flown {} times ({} seeds × {} phases): it flies {}\n",
            a.seeds * a.phases,
            a.seeds,
            a.phases,
            rule_text(a, "the criterion")
        ));
    }
    out
}

/// The pass rate and confidence `--pass-rate` asks of a timing's flights
/// (`None`: every flight must pass).
fn requirement(a: &FlyArgs) -> Option<Requirement> {
    let rate = a.pass_rate?;
    Some(Requirement {
        rate,
        confidence: a.confidence.unwrap_or(Requirement::DEFAULT.confidence),
    })
}

/// When a timing flies, in words (`criterion`: "the criterion", or "its
/// criterion" when each setup has its own).
fn rule_text(a: &FlyArgs, criterion: &str) -> String {
    match requirement(a) {
        None => format!("only if every flight meets {criterion}"),
        Some(r) => format!(
            "when, in each vehicle/mission setup, of the flights the spec's own timing (periods ×1.000) meets {criterion} on, the share it meets it on too has a lower bound (Wilson) ≥ {} at {} % confidence",
            r.rate,
            r.confidence * 100.0
        ),
    }
}

/// `--pass-rate`'s flights: enough in each vehicle/mission setup (the rule
/// judges each setup on its own flights) that all of them passing can
/// reach the rate, else an error naming the fewest that can.
fn enough_flights(a: &FlyArgs, setups: u32) -> Result<(), Diagnostic> {
    let Some(need) = requirement(a) else {
        return Ok(());
    };
    let (flights, least) = (a.seeds * a.phases, need.least_flights());
    if flights >= least {
        return Ok(());
    }
    let each = if setups > 1 {
        format!(" in each of the {setups} vehicle/mission setups")
    } else {
        String::new()
    };
    Err(Diagnostic::error(
        format!(
            "--pass-rate {} at {} % confidence needs at least {least} flights a timing{each} (all passing), but --seeds {} × --phases {} fly {flights}",
            need.rate,
            need.confidence * 100.0,
            a.seeds,
            a.phases
        ),
        "raise --seeds or --phases, or lower --pass-rate or --confidence",
    ))
}

/// Under --pass-rate, a note for each setup whose reference (the spec's own
/// timing) passed too few flights for any timing to reach the rate there:
/// no timing flies, and the note says why.
fn too_few_counted(a: &FlyArgs, labels: &[String], points: &[Point]) -> Vec<String> {
    let (Some(need), Some(reference)) = (
        requirement(a),
        points.iter().find(|p| p.variation == Variation::Scale(1.0)),
    ) else {
        return Vec::new();
    };
    let least = need.least_flights();
    let per_setup = reference.against_reference.as_deref().unwrap_or_default();
    per_setup
        .iter()
        .zip(labels)
        .filter(|(r, _)| r.counted < least)
        .map(|(r, label)| {
            format!(
                "{label}: the spec's own timing met its criterion on {} of its {} flights, fewer than the {least} a setup needs for --pass-rate {} at {} % confidence, so no timing flies there: fly more --seeds or --phases, or fix what fails at the spec's own timing",
                r.counted,
                a.seeds * a.phases,
                need.rate,
                need.confidence * 100.0
            )
        })
        .collect()
}

fn text(
    spec: &Spec,
    setups_all: (&Setup, &[(Setup, Criteria)]),
    (c, a): (&Criteria, &FlyArgs),
    points: &[Point],
    limits: &Derived,
    written: Option<&Path>,
) -> String {
    let s = setups_all.0;
    let mut out = header_text(spec, setups_all, c, a);
    out.push_str("\nperiod scale (budgets fixed; sound bounds from the read):\n");
    let scales: Vec<&Point> = points
        .iter()
        .filter(|p| matches!(p.variation, Variation::Scale(_)))
        .collect();
    let labels = setups(s, setups_all.1);
    out.push_str(&points_table(spec, &scales, &labels));
    let e = scale_edge(points);
    out.push_str(&match (e.last_pass, e.first_fail) {
        (Some(p), Some(f)) => format!(
            "the flight stops meeting the criterion between {} (flies) and {} (fails)\n",
            what(&p.variation),
            what(&f.variation)
        ),
        (Some(p), None) => format!(
            "it flies up to {} (no failure in range)\n",
            what(&p.variation)
        ),
        (None, _) => "no schedulable scale flies\n".into(),
    });
    for (line, role) in DELAY_LINES.iter().enumerate() {
        let pts: Vec<&Point> = points
            .iter()
            .filter(|p| matches!(p.variation, Variation::Delay { line: l, .. } if l == line))
            .collect();
        if pts.is_empty() {
            continue;
        }
        out.push_str(&format!("\npure delay on the {} samples:\n", role.name()));
        out.push_str(&points_table(spec, &pts, &labels));
        let d = edge(
            points,
            |v| matches!(v, Variation::Delay { line: l, .. } if *l == line),
        );
        if let (Some(p), None) = (d.last_pass, d.first_fail) {
            out.push_str(&format!("no failure up to {}\n", what(&p.variation)));
        }
    }
    out.push_str(&rate_text(spec, setups_all, points, limits, a.safety));
    out.push_str("\nderived chain limits (ms; the smaller of the period-scale and the delay sweep; reaction and freshness from the head's read, max reaction time and freshness from the event)");
    if a.safety < 1.0 {
        out.push_str(&format!(
            ", each × {} (the safety factor; the tail's max_period too)",
            a.safety
        ));
    }
    out.push_str(":\n");
    out.push_str(&limits_text(spec, limits));
    if let Some(w) = written {
        out.push_str(&format!("wrote {} with these limits\n", w.display()));
    }
    out
}

/// The JSON Schema of `fly --sweep --json`'s report.
pub(super) fn json_schema() -> schemars::Schema {
    schemars::schema_for!(SweepView<'static>)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Under --pass-rate, a setup whose reference passed fewer flights
    /// than the rate needs (34 of 40 < 35 at 0.9) is named in a note; one
    /// that passed enough is not; without --pass-rate nothing is said.
    #[test]
    fn a_setup_with_too_few_counted_flights_is_named() {
        use clap::Parser;
        use rtpipe_fly::sweep::AgainstReference;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            fly: FlyArgs,
        }
        let args = |extra: &[&str]| {
            let base = ["rtpipe", "spec.toml", "--sweep", "--seeds", "40"];
            Cli::try_parse_from(base.iter().chain(extra))
                .map(|c| c.fly)
                .unwrap_or_else(|e| panic!("{e}"))
        };
        let counted = |counted| AgainstReference {
            passed: counted,
            counted,
            lower_bound: 0.0,
        };
        let reference = Point {
            variation: Variation::Scale(1.0),
            bounds: Vec::new(),
            event: Vec::new(),
            schedulable: true,
            quality: None,
            failures: Vec::new(),
            outcomes: vec![true; 80],
            against_reference: Some(vec![counted(40), counted(34)]),
            flies: false,
            stage: Stage::Grid,
        };
        let labels = ["racer5/steps".to_string(), "racer5/gusty".to_string()];
        let notes = too_few_counted(
            &args(&["--pass-rate", "0.9"]),
            &labels,
            std::slice::from_ref(&reference),
        );
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with("racer5/gusty: ")
                && notes[0].contains("34 of its 40 flights, fewer than the 35"),
            "{notes:?}"
        );
        assert!(too_few_counted(&args(&[]), &labels, &[reference]).is_empty());
    }

    /// A delay point is labelled by its integer delay in exact decimals,
    /// a whole one without any.
    #[test]
    fn delay_labels_are_exact() {
        let at = |ns| what(&Variation::Delay { line: 0, ns });
        assert_eq!(at(90_509_668), "gyro +90.509668 ms");
        assert_eq!(at(2_000_000), "gyro +2 ms");
        assert_eq!(at(25_500_000), "gyro +25.5 ms");
    }
}
