//! `rtpipe fly` end to end: one flight, its outputs, the sweep, bad input.

mod common;
use common::{assert_exit, example, json_of, rtpipe, scratch};

#[test]
fn a_flight_reports_quality_and_chains_as_json() {
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--mission",
        "hover",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let f = &v["flight"];
    assert_eq!(f["crashed"], false);
    assert_eq!(f["criteria_met"], true);
    assert!(f["attitude_error_deg"]["rms"]
        .as_f64()
        .is_some_and(|x| x < 2.0));
    assert!(f["altitude_error_m"]["rms"]
        .as_f64()
        .is_some_and(|x| x < 0.1));
    let chains = v["chains"].as_array().map_or(0, |c| c.len());
    assert_eq!(chains, 6, "three chains, two metrics");
    for c in v["chains"].as_array().into_iter().flatten() {
        assert_eq!(c["violations"]["sound"], 0);
        assert_eq!(c["violations_from_event"]["sound"], 0);
        assert!(c["observed"]["count"].as_u64().is_some_and(|n| n > 1000));
    }
}

/// A flight honours LET. examples/cleanflight.toml with its three
/// chains under LET (its I/O VCPUs made Main VCPUs, which LET needs; the
/// background tasks stay implicit): the bodies read at their releases and
/// publish at their periods' ends, so the flight's latencies are LET's,
/// the same as `simulate`'s (LET's data flow does not depend on the
/// execution times). By hand, gyro path (gyro 1 ms → ahrs 5 → pid 2 → pwm
/// 5, synchronous): the gyro sample read at 4 ms is out at 5, read by ahrs
/// at 5 (out 10), pid at 10 (out 12), pwm at 15 (out 20): 16 ms; every
/// sample that gets through takes the same.
#[test]
fn a_flight_honours_let_chains() {
    let dir = scratch("fly-let");
    let text = std::fs::read_to_string(example("cleanflight.toml")).unwrap_or_default();
    let text = text
        .replace("server = \"io\"", "server = \"main\"")
        .replace(
            "\nfreshness = \"23ms\"\n",
            "\nfreshness = \"23ms\"\ncommunication = \"let\"\n",
        )
        .replace(
            "\nfreshness = \"44ms\"",
            "\nfreshness = \"44ms\"\ncommunication = \"let\"",
        );
    assert_eq!(text.matches("communication = \"let\"").count(), 3);
    let spec = dir.join("let.toml");
    if let Err(e) = std::fs::write(&spec, text) {
        panic!("{e}");
    }
    let spec = spec.to_string_lossy().into_owned();
    let o = rtpipe(&["fly", &spec, "--mission", "hover", "--json"]);
    assert_exit(&o, 0);
    let fly = json_of(&o);
    assert_eq!(fly["flight"]["criteria_met"], true);
    let o = rtpipe(&["simulate", &spec, "--json"]);
    let sim = json_of(&o);
    let (fc, sc) = (&fly["chains"], &sim["chains"]);
    for k in 0..6 {
        assert_eq!(fc[k]["communication"], "let");
        assert_eq!(fc[k]["violations"]["sound"], 0);
        assert_eq!(fc[k]["violations_from_event"]["sound"], 0);
        for q in ["min", "max"] {
            assert_eq!(fc[k]["observed"][q], sc[k]["observed"][q], "chain {k} {q}");
        }
    }
    assert_eq!(fc[0]["observed"]["min"].as_f64(), Some(16_000.0));
    assert_eq!(fc[0]["observed"]["max"].as_f64(), Some(16_000.0));
}

#[test]
fn plots_and_log_are_written_whole() {
    let dir = scratch("fly-out");
    let plots = dir.join("plots");
    let log = dir.join("flight.csv");
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--duration",
        "6s",
        "--mission",
        "hover",
        "--plot",
        &plots.to_string_lossy(),
        "--log",
        &log.to_string_lossy(),
    ]);
    // 6 s of the hover mission: up and hovering within the criteria.
    assert_exit(&o, 0);
    for f in ["attitude.svg", "altitude.svg", "motors.svg", "latency.svg"] {
        let svg = std::fs::read_to_string(plots.join(f)).unwrap_or_default();
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{f}"
        );
    }
    let csv = std::fs::read_to_string(&log).unwrap_or_default();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    assert_eq!(header[0], "time_s");
    assert!(header.contains(&"gyro path_reaction_ms"), "{header:?}");
    // One row every 2 ms over 6 s, every row as wide as the header.
    assert_eq!(lines.clone().count(), 3001);
    assert!(lines.all(|l| l.split(',').count() == header.len()));
}

#[test]
fn the_sweep_finds_the_edge_and_writes_the_limits() {
    let dir = scratch("fly-sweep");
    let out = dir.join("limits.toml");
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--sweep",
        "--scale",
        "1..2.6",
        // The grid and the refinement alone: the check below the limit
        // (on by default) flies a ladder whose points need not be
        // monotone (×1.811 fails, ×1.897 flies); its own test is
        // `a_check_flies_every_step_below_the_period_limits`.
        "--check-step",
        "0",
        "--json",
        "--write-limits",
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let points = v["points"].as_array().cloned().unwrap_or_default();
    let scales: Vec<(f64, bool)> = points
        .iter()
        .filter(|p| p["varied"] == "scale")
        .map(|p| (p["value"].as_f64().unwrap_or(0.0), p["flies"] == true))
        .collect();
    // ×1, ×1.26, ×1.59 fly; ×2 and ×2.52 do not (docs/flight.md); the
    // points bisecting ×1.59..×2 (the default --resolution 0.02) lie
    // between them in order, and the edge is bracketed within 2 %.
    let flies: Vec<bool> = scales.iter().map(|s| s.1).collect();
    let last = flies.iter().rposition(|&f| f).unwrap_or(0);
    assert!(flies[..=last].iter().all(|&f| f) && !flies[last + 1..].iter().any(|&f| f));
    assert!(scales.windows(2).all(|w| w[0].0 < w[1].0), "{scales:?}");
    let (a, b) = (scales[last].0, scales[last + 1].0);
    assert!(
        (1.587..2.0).contains(&a) && b <= 2.0 && b - a <= 0.02 * b,
        "{a} {b}"
    );
    assert!(scales.len() > 5, "refined: {scales:?}");
    for p in points.iter().filter(|p| p["varied"] == "scale") {
        assert_eq!(
            (p["flights"].as_u64(), p["passed"].as_u64()),
            (Some(1), Some(u64::from(p["flies"] == true)))
        );
    }
    let gyro = &v["limits_ms"][0];
    assert_eq!(gyro["chain"], "gyro path");
    let lim = gyro["reaction"].as_f64().unwrap_or(0.0);
    let reaction = |p: &serde_json::Value| p["bounds_ms"][0]["reaction"].as_f64().unwrap_or(0.0);
    let at_scale = |x: f64| {
        points
            .iter()
            .find(|p| p["varied"] == "scale" && p["value"].as_f64() == Some(x))
            .map_or(0.0, reaction)
    };
    assert!(lim <= at_scale(a) && lim < at_scale(b), "{lim}");
    // The written spec carries the limits and analyses.
    let a = rtpipe(&["analyze", &out.to_string_lossy(), "--json"]);
    let spec = json_of(&a);
    let written = spec["chains"][0]["limit"].as_f64().unwrap_or(0.0);
    assert!(
        (written - lim * 1000.0).abs() < 1e-3,
        "{written} µs vs {lim} ms"
    );
}

#[test]
fn bad_flight_input_exits_2() {
    let spec = example("cleanflight.toml");
    for args in [
        vec!["fly", &spec, "--vehicle", "zeppelin"],
        vec!["fly", &spec, "--mission", "loop-the-loop"],
        vec!["fly", &spec, "--scale", "1..2"],
        vec!["fly", &spec, "--sweep", "--scale", "2..1"],
        vec!["fly", &spec, "--sweep", "--log", "flight.csv"],
        vec!["fly", &spec, "--duration", "-3s"],
    ] {
        let o = rtpipe(&args);
        assert_exit(&o, 2);
    }
    // A spec whose tasks name no bodies cannot fly.
    let o = rtpipe(&["fly", &example("paper-table2.toml")]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("body = \"gyro\""), "{err}");
}

#[test]
fn a_sweep_where_nothing_flies_writes_no_limits_and_exits_1() {
    // It wrote "wrote l.toml with these limits" (every limit "-")
    // and exited 0.
    let dir = scratch("fly-sweep-none");
    let crit = dir.join("c.toml");
    if let Err(e) = std::fs::write(&crit, "attitude_rms_deg = 0.000001\n") {
        panic!("{e}");
    }
    let out = dir.join("l.toml");
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--sweep",
        "--scale",
        "1..1",
        "--criterion",
        &crit.to_string_lossy(),
        "--write-limits",
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no chain limit could be derived"), "{err}");
    assert!(!String::from_utf8_lossy(&o.stdout).contains("wrote"));
    assert!(!out.exists());
}

/// racer5 with two propellers' spin swapped (rotors 1 and 3): yaw control
/// is lost after the heading step and the vehicle climbs to 423 m, still
/// armed, where every window the criteria judge had long closed; `fly`
/// said "criteria met" and exited 0.
#[test]
fn a_flight_that_leaves_the_envelope_fails_naming_what_and_when() {
    let dir = scratch("fly-envelope");
    let preset = dir.join("swapped.toml");
    let text = rtpipe_flight::preset::RACER5_TOML.replace(
        "spin = [\"cw\", \"ccw\", \"ccw\", \"cw\"]",
        "spin = [\"ccw\", \"ccw\", \"cw\", \"cw\"]",
    );
    assert!(text.contains("[\"ccw\", \"ccw\", \"cw\", \"cw\"]"));
    if let Err(e) = std::fs::write(&preset, text) {
        panic!("{e}");
    }
    let spec = example("cleanflight.toml");
    let o = rtpipe(&[
        "fly",
        &spec,
        "--vehicle",
        &preset.to_string_lossy(),
        "--seed",
        "1",
    ]);
    assert_exit(&o, 1);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("left the envelope at 16.68 s: altitude above 3 m (highest 139.2 m at 26.00 s; criteria key max_altitude_m)"),
        "{out}"
    );
    assert!(
        out.contains("did not land: the mission lands from 21.0 s"),
        "{out}"
    );
    // The same flight with the propellers as built stays inside.
    let o = rtpipe(&["fly", &spec, "--seed", "1", "--json"]);
    assert_exit(&o, 0);
    let e = &json_of(&o)["flight"]["envelope"];
    assert_eq!(e["max_altitude_m"], 3.0);
    assert!(e["highest_m"].as_f64().is_some_and(|h| h < 1.2), "{e}");
}

/// A D-term cut-off above the Nyquist frequency of the PID task's rate was
/// blamed on the task ("give it a fixed period the body can run at") and
/// the preset file was not named.
#[test]
fn a_filter_above_nyquist_names_the_preset_file_and_key() {
    let dir = scratch("fly-dterm");
    let preset = dir.join("dterm.toml");
    let text =
        rtpipe_flight::preset::RACER5_TOML.replace("dterm_lpf_hz = 75.0", "dterm_lpf_hz = 300.0");
    if let Err(e) = std::fs::write(&preset, text) {
        panic!("{e}");
    }
    let shown = preset.to_string_lossy();
    let o = rtpipe(&["fly", &example("cleanflight.toml"), "--vehicle", &shown]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!(
            "error: preset file {shown}: `pid.dterm_lpf_hz` does not suit task `pid` (body pid), which runs every 2 ms (500 Hz): cut-off 300 Hz must be in (0, 250 Hz) (Nyquist)"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!("change `pid.dterm_lpf_hz` in preset file {shown}")),
        "{err}"
    );
    assert!(!err.contains("give it a fixed period"), "{err}");
}

/// The sweep's JSON said `"flies": true` of unschedulable points: `flies`
/// is now "schedulable and met the criterion", the flight alone is
/// `flight_met_criterion`.
#[test]
fn an_unschedulable_sweep_point_does_not_fly() {
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--sweep",
        "--scale",
        "0.5..1",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    let points = v["points"].as_array().cloned().unwrap_or_default();
    let unschedulable: Vec<_> = points
        .iter()
        .filter(|p| p["schedulable"] == false)
        .collect();
    assert!(!unschedulable.is_empty());
    assert!(
        unschedulable.iter().all(|p| p["flies"] == false),
        "{unschedulable:?}"
    );
    // ×0.5 and ×0.63 fail the spec's schedulability test, yet their
    // flights met the criterion in simulation: the two are told apart.
    assert!(
        unschedulable
            .iter()
            .any(|p| p["flight_met_criterion"] == true),
        "{unschedulable:?}"
    );
    assert!(points.iter().any(|p| p["flies"] == true));
}

/// The `gusty` mission has no steps: its sweep plot put every point at
/// "settling 0". It now plots what the mission judges (the hover's
/// position error against its criterion).
#[test]
fn a_sweep_of_a_mission_without_steps_plots_what_it_measures() {
    let dir = scratch("fly-sweep-gusty");
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--sweep",
        "--mission",
        "gusty",
        "--scale",
        "1..1",
        "--plot",
        &dir.to_string_lossy(),
    ]);
    assert!(o.status.code().is_some_and(|c| c <= 1), "{o:?}");
    let svg = std::fs::read_to_string(dir.join("sweep.svg")).unwrap_or_default();
    assert!(svg.contains("hover position error RMS (m)"), "{svg}");
    assert!(
        svg.contains("criterion: position RMS &lt; 0.5 m")
            || svg.contains("criterion: position RMS < 0.5 m")
    );
    assert!(!svg.contains("settling"), "{svg}");
}

/// The JSON of a small sweep of Table V (period scales × 1 and × 2, one
/// point an octave) with `extra` flags; it must exit 0.
fn small_sweep(extra: &[&str]) -> serde_json::Value {
    let spec = example("cleanflight.toml");
    let mut args = vec![
        "fly",
        spec.as_str(),
        "--sweep",
        "--scale",
        "1..2",
        "--per-octave",
        "1",
        "--json",
    ];
    args.extend_from_slice(extra);
    let o = rtpipe(&args);
    assert_exit(&o, 0);
    json_of(&o)
}

/// `--seeds` and `--phases`: every timing flown seeds × phases times, a
/// timing flies only when all did, and `--safety` scales every limit down.
#[test]
fn a_sweep_over_seeds_and_phases_counts_every_flight_and_keeps_a_margin() {
    let plain = small_sweep(&[]);
    let v = small_sweep(&["--seeds", "2", "--phases", "2", "--safety", "0.9"]);
    assert_eq!(
        (v["seeds"].as_u64(), v["phases"].as_u64()),
        (Some(2), Some(2))
    );
    assert_eq!(v["safety"], 0.9);
    let points = v["points"].as_array().cloned().unwrap_or_default();
    assert!(!points.is_empty());
    for p in &points {
        let (flights, passed) = (p["flights"].as_u64(), p["passed"].as_u64());
        if p["failures"][0]
            .as_str()
            .is_some_and(|f| f.contains("below its budget"))
        {
            continue;
        }
        assert_eq!(flights, Some(4), "{p}");
        let all = passed == Some(4);
        assert_eq!(p["flight_met_criterion"], all, "{p}");
        if !all {
            let f = p["failures"][0].as_str().unwrap_or("");
            assert!(f.starts_with("seed "), "the failing flight is named: {f}");
        }
    }
    // Every limit is at most 0.9 × the one-flight sweep's (more flights can
    // only move the edge down).
    let plain_limits = plain["limits_ms"].as_array().cloned().unwrap_or_default();
    let limits = v["limits_ms"].as_array().cloned().unwrap_or_default();
    for (a, b) in plain_limits.iter().zip(&limits) {
        for key in [
            "reaction",
            "freshness",
            "max_reaction_time",
            "freshness_from_event",
        ] {
            if let (Some(x), Some(y)) = (a[key].as_f64(), b[key].as_f64()) {
                assert!(y <= 0.9 * x + 1e-6, "{key}: {y} > 0.9 × {x}");
            }
        }
    }
    let spec = example("cleanflight.toml");
    for bad in [
        ["--safety", "0"],
        ["--safety", "1.5"],
        ["--seeds", "0"],
        ["--phases", "x"],
    ] {
        let mut args = vec!["fly", spec.as_str(), "--sweep"];
        args.extend_from_slice(&bad);
        assert_exit(&rtpipe(&args), 2);
    }
    // Without --sweep they are refused, not ignored.
    assert_exit(&rtpipe(&["fly", spec.as_str(), "--seeds", "2"]), 2);
}

/// `--check-step S`: below each period edge (scale and motor period) every
/// value 1 × (1 + S)^i is flown as a check point (`stage: "check"`), and
/// the written limits rest on points every one of which below them flew;
/// a bad step is refused.
#[test]
fn a_check_flies_every_step_below_the_period_limits() {
    let v = small_sweep(&["--check-step", "0.1"]);
    let points = v["points"].as_array().cloned().unwrap_or_default();
    for varied in ["scale", "tail rate"] {
        let mine: Vec<&serde_json::Value> =
            points.iter().filter(|p| p["varied"] == varied).collect();
        let values: Vec<f64> = mine.iter().filter_map(|p| p["value"].as_f64()).collect();
        assert!(values.windows(2).all(|w| w[0] < w[1]), "{values:?}");
        let checks: Vec<f64> = mine
            .iter()
            .filter(|p| p["stage"] == "check")
            .filter_map(|p| p["value"].as_f64())
            .collect();
        assert!(!checks.is_empty(), "{varied}: no check point");
        for x in &checks {
            let i = x.ln() / 1.1f64.ln();
            assert!((i - i.round()).abs() < 1e-6, "{varied}: {x} is not 1.1^i");
        }
        // The edge: the last point that flies before the first that does
        // not; every check below it flew.
        let first_fail = mine
            .iter()
            .position(|p| p["schedulable"] == true && p["flies"] == false);
        let below = &mine[..first_fail.unwrap_or(mine.len())];
        assert!(below
            .iter()
            .all(|p| p["schedulable"] == false || p["flies"] == true));
    }
    let spec = example("cleanflight.toml");
    for bad in ["0.6", "-0.1", "x"] {
        let o = rtpipe(&["fly", &spec, "--sweep", "--check-step", bad]);
        assert_exit(&o, 2);
    }
}

/// The check is on by default (S = 0.02: it is what backs a written
/// limit), and `--check-step 0` turns it off.
#[test]
fn the_check_is_on_by_default_and_0_turns_it_off() {
    let checks = |extra: &[&str]| {
        let v = small_sweep(extra);
        let points = v["points"].as_array().cloned().unwrap_or_default();
        points
            .iter()
            .filter(|p| p["stage"] == "check")
            .filter_map(|p| p["value"].as_f64())
            .collect::<Vec<f64>>()
    };
    let default = checks(&[]);
    assert!(!default.is_empty(), "no check point by default");
    for x in &default {
        let i = x.ln() / 1.02f64.ln();
        assert!((i - i.round()).abs() < 1e-6, "{x} is not 1.02^i");
    }
    assert_eq!(checks(&["--check-step", "0"]), Vec::<f64>::new());
}

/// `--pass-rate`: a count of flights that cannot reach the rate even all
/// passing is refused before any flight, naming the fewest that can; a
/// rate or confidence outside (0, 1), or `--confidence` alone, is refused.
#[test]
fn a_pass_rate_the_flights_cannot_show_is_refused() {
    let spec = example("cleanflight.toml");
    let sweep = ["fly", spec.as_str(), "--sweep"];
    let o = rtpipe(&[&sweep[..], &["--seeds", "10", "--pass-rate", "0.95"]].concat());
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("needs at least 73 flights a timing") && err.contains("fly 10"),
        "{err}"
    );
    for bad in [
        &["--pass-rate", "1"][..],
        &["--pass-rate", "-0.5"],
        &[
            "--seeds",
            "80",
            "--pass-rate",
            "0.95",
            "--confidence",
            "1.5",
        ],
        &["--confidence", "0.9"],
    ] {
        assert_exit(&rtpipe(&[&sweep[..], bad].concat()), 2);
    }
    assert_exit(&rtpipe(&["fly", spec.as_str(), "--pass-rate", "0.9"]), 2);
}

/// The held-out missions of docs/flight.md load, and Table V flies each
/// on racer5 at seed 10 (scripts/held-out-flights.sh flies them all).
#[test]
fn the_held_out_missions_load_and_table_v_flies_them_on_racer5() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/missions");
    for m in ["steps-turbulent", "aggressive-steps", "gusty-120s"] {
        let mission = format!("{dir}/{m}.toml");
        let o = rtpipe(&[
            "fly",
            &example("cleanflight.toml"),
            "--mission",
            &mission,
            "--seed",
            "10",
        ]);
        // Seed 10's turbulent roll step missed the plain ±1° band late in
        // its hold (0.85 s) by the turbulence's own wander, which its
        // hover shows too: judged on the band widened by it, it settles in
        // 0.21 s (docs/flight.md, "Settling in a disturbed world").
        assert_exit(&o, 0);
    }
}

/// `--mission A,B --vehicle V,W` with `--sweep`: every timing is flown on
/// each of the four setups (the JSON names the three besides the first and
/// counts their flights in every point), so the edge is the worst's; one
/// flight takes one vehicle and one mission.
#[test]
fn a_sweep_over_missions_and_vehicles_flies_every_timing_on_each() {
    let spec = example("cleanflight.toml");
    let o = rtpipe(&[
        "fly",
        &spec,
        "--sweep",
        "--vehicle",
        "racer5,aero1kg",
        "--mission",
        "hover,gusty",
        "--scale",
        "1..2",
        "--per-octave",
        "1",
        "--resolution",
        "0",
        "--duration",
        "6s",
        "--json",
    ]);
    assert_exit(&o, 0);
    let v = json_of(&o);
    assert_eq!(
        v["also"],
        serde_json::json!(["racer5/gusty", "aero1kg/hover", "aero1kg/gusty"])
    );
    let points = v["points"].as_array().cloned().unwrap_or_default();
    assert!(!points.is_empty());
    for p in points.iter().filter(|p| p["flights"] != 0) {
        assert_eq!(p["flights"], 4, "{p}");
    }
    let o = rtpipe(&["fly", &spec, "--mission", "hover,gusty"]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--sweep"), "{err}");
}

/// The sweep's own turbulent mission (examples/missions/sweep-steps-breeze.toml,
/// not a held-out one) loads, and Table V flies it on both vehicles at
/// the sweep's first seed: the nominal timing of docs/flight.md's sweep
/// over it.
#[test]
fn the_sweep_breeze_mission_loads_and_table_v_flies_it() {
    let mission = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/missions/sweep-steps-breeze.toml"
    );
    for v in ["racer5", "aero1kg"] {
        let o = rtpipe(&[
            "fly",
            &example("cleanflight.toml"),
            "--vehicle",
            v,
            "--mission",
            mission,
        ]);
        assert_exit(&o, 0);
    }
}

/// `--phase K` flies the sweep's phase draw K: draw 0 is the nominal
/// flight, any other shifts the steps within the 5 ms motor period (and
/// lengthens the flight by as much); a sweep draws its own phases.
#[test]
fn a_flight_at_a_phase_draw_shifts_its_steps_within_the_motor_period() {
    let duration = |phase: &str| {
        let o = rtpipe(&[
            "fly",
            &example("cleanflight.toml"),
            "--phase",
            phase,
            "--json",
        ]);
        json_of(&o)["flight"]["duration_s"].as_f64()
    };
    let nominal = duration("0").unwrap_or(f64::NAN);
    assert_eq!(
        Some(nominal),
        duration("0"),
        "the same draw, the same flight"
    );
    let shifted = duration("2").unwrap_or(f64::NAN);
    assert!(
        shifted > nominal && shifted < nominal + 0.005,
        "{nominal} s, then {shifted} s"
    );
    let o = rtpipe(&[
        "fly",
        &example("cleanflight.toml"),
        "--phase",
        "2",
        "--sweep",
    ]);
    assert_exit(&o, 2);
}
