//! E2EEvaluation's own export, as its generator writes it, imported and
//! analysed; the bounds set against the figures E2EEvaluation's own
//! analyses printed for the same chains (tests/data/README.md says how both
//! files were made, and at which commit).

mod common;

use common::{assert_exit, json_of, rtpipe, scratch};
use rtpipe_testkit::Scratch;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The file's times are in ms with up to 17 digits; rtpipe rounds WCETs up
/// to whole ns (by < 1 ns each). A bound is monotone in the WCETs and
/// counts each WCET once per job it charges, so rounding raises it by less
/// than 1 ns per job charged; 1 µs allows a thousand of them (the chains
/// here charge at most a few hundred). The same holds for a completion
/// time in a schedule, which moves by less than 1 ns per job run before it
/// in its busy period.
const ROUNDING_MS: f64 = 0.001;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// E2EEvaluation's `results.csv`: one column per analysis (its short name),
/// one row per chain in the file's order.
fn results(name: &str) -> Vec<std::collections::HashMap<String, f64>> {
    let text = std::fs::read_to_string(data(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_owned)
        .collect();
    lines
        .map(|l| {
            let cells = l.split(',').map(|c| c.parse::<f64>().unwrap_or(f64::NAN));
            head.iter().cloned().zip(cells).collect()
        })
        .collect()
}

/// Imports `yaml` and returns the one spec written and the import's stdout.
fn import_one(tag: &str, yaml: &str) -> (Scratch, String) {
    let out = scratch(tag).within("out");
    let o = rtpipe(&[
        "import",
        "e2eeval",
        &data(yaml).to_string_lossy(),
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 0);
    let specs = common::listing(&out);
    assert_eq!(specs.len(), 1, "{specs:?}");
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    (out.within(&format!("out/{}", specs[0])), stdout)
}

/// The chains of `metric`, in the file's order.
fn chains<'a>(v: &'a Value, metric: &str) -> Vec<&'a Value> {
    let all = v["chains"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    all.iter().filter(|c| c["metric"] == metric).collect()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// rtpipe's figure is E2EEvaluation's, raised only by the rounding.
fn same_bound(what: &str, k: usize, ours: f64, theirs: f64) {
    assert!(
        theirs <= ours && ours - theirs < ROUNDING_MS,
        "chain {k}, {what}: rtpipe {ours} ms, E2EEvaluation {theirs} ms"
    );
}

/// WATERS task sets at E2EEvaluation's default settings: one ECU, 95
/// tasks, 55 local chains, synchronous release, BCET = WCET.
#[test]
fn the_real_waters_export_imports_and_its_bounds_are_the_literature_s() {
    let (spec, table) = import_one("e2e-real", "e2eeval-waters.yaml");
    assert!(table.contains("95 tasks on 1 ECU, 55 chains"), "{table}");
    let a = rtpipe(&["analyze", &spec.to_string_lossy(), "--json"]);
    assert_exit(&a, 0);
    let v = json_of(&a);
    let (reaction, freshness) = (chains(&v, "reaction"), chains(&v, "freshness"));
    let theirs = results("e2eeval-waters-results.csv");
    assert_eq!(
        (reaction.len(), freshness.len(), theirs.len()),
        (55, 55, 55)
    );
    for (k, t) in theirs.iter().enumerate() {
        let (r, f) = (reaction[k], freshness[k]);
        // Davare et al. 2007 and Dürr et al. 2019 from the event.
        same_bound("D07", k, num(&r["from_event"]["davare"]), t["D07"]);
        same_bound("D19(MRT)", k, num(&r["from_event"]["duerr"]), t["D19(MRT)"]);
        // Dürr's reduced data age is freshness from the head's read.
        same_bound("D19(MRDA)", k, num(&f["duerr"]), t["D19(MRDA)"]);
        literature_bounds(k, r, f, t);
        // Kloda et al. 2018 (synchronous release): the known-offset bound.
        let known = num(&r["known_offsets"]["from_event"]["sound"]);
        same_bound("K18", k, known, t["K18"]);
        // Every rtpipe bound holds Günzel et al.'s exact schedule-based
        // figures (the schedule with every job at its WCET, which BCET =
        // WCET makes the only one).
        assert!(known >= t["G23(L-MRT)"] - ROUNDING_MS, "chain {k}");
        assert!(num(&r["from_event"]["sound"]) >= t["G23(L-MRT)"] - ROUNDING_MS);
    }
}

/// The figures `analyze` gives under the literature's names are the
/// literature's own: Dürr et al.'s maximum reaction time and maximum reduced
/// data age (their formulas), Davare's bound on both the reaction time and
/// the data age; and every sound one holds Günzel et al.'s exact figures.
fn literature_bounds(k: usize, r: &Value, f: &Value, t: &std::collections::HashMap<String, f64>) {
    let (lr, lf) = (&r["literature"], &f["literature"]);
    same_bound(
        "D19(MRT)",
        k,
        num(&lr["max_reaction_time"]["duerr"]),
        t["D19(MRT)"],
    );
    // Günzel et al.: the maximum data age is the maximum reaction time, so
    // Dürr's bound on the one bounds the other.
    same_bound(
        "D19(MRT) as MDA",
        k,
        num(&lr["max_data_age"]["duerr"]),
        t["D19(MRT)"],
    );
    same_bound(
        "D07 as MDA",
        k,
        num(&lr["max_data_age"]["davare"]),
        t["D07"],
    );
    same_bound(
        "D19(MRDA)",
        k,
        num(&lf["max_reduced_data_age"]["duerr"]),
        t["D19(MRDA)"],
    );
    let holds = |what: &str, ours: f64, theirs: f64| {
        assert!(
            ours >= theirs - ROUNDING_MS,
            "chain {k}, {what}: {ours} < {theirs}"
        );
    };
    holds(
        "MRT",
        num(&lr["max_reaction_time"]["sound"]),
        t["G23(L-MRT)"],
    );
    holds("MDA", num(&lr["max_data_age"]["sound"]), t["G23(L-MDA)"]);
    holds(
        "MRDA",
        num(&lf["max_reduced_data_age"]["sound"]),
        t["G23(L-MRDA)"],
    );
}

/// Günzel et al.'s schedule-based figures, measured on the simulated
/// schedule (every task released at 0 with its WCET: with BCET = WCET the
/// one schedule their analyses see): the maximum reaction time and the
/// maximum data age (equal, as they prove) from the event, the maximum
/// reduced data age as freshness from the read.
fn guenzel_figures(
    k: usize,
    reaction: &Value,
    freshness: &Value,
    t: &std::collections::HashMap<String, f64>,
) {
    let mrt = num(&reaction["observed_from_event"]["max"]);
    let mrda = num(&freshness["observed"]["max"]);
    for (what, theirs) in [
        ("G23(L-MRT)", t["G23(L-MRT)"]),
        ("G23(L-MDA)", t["G23(L-MDA)"]),
    ] {
        assert!(
            (mrt - theirs).abs() < ROUNDING_MS,
            "chain {k}, {what}: {mrt} against {theirs}"
        );
    }
    assert!(
        (mrda - t["G23(L-MRDA)"]).abs() < ROUNDING_MS,
        "chain {k}, G23(L-MRDA): {mrda}"
    );
    for c in [reaction, freshness] {
        assert_eq!(c["violations"]["sound"], 0, "chain {k}");
        assert_eq!(c["known_offsets"]["violations"], 0, "chain {k}");
    }
}

/// The simulator, releasing every task at 0 with its WCET, measures exactly
/// what Günzel et al.'s schedule-based analyses compute on the same
/// schedule: the maximum reaction time from the event (MRT) and the
/// maximum reduced data age, freshness from the head's read (MRDA).
#[test]
fn the_simulated_waters_schedule_gives_guenzel_s_exact_figures() {
    let (spec, _) = import_one("e2e-real-sim", "e2eeval-waters.yaml");
    // Ten hyperperiods (1 s): the longest chains (up to 4.6 s from the
    // event) complete several times.
    let s = rtpipe(&[
        "simulate",
        &spec.to_string_lossy(),
        "--duration",
        "10s",
        "--json",
    ]);
    assert_exit(&s, 0);
    let v = json_of(&s);
    let (reaction, freshness) = (chains(&v, "reaction"), chains(&v, "freshness"));
    for (k, t) in results("e2eeval-waters-results.csv").iter().enumerate() {
        guenzel_figures(k, reaction[k], freshness[k], t);
    }
}

/// Two more settings of E2EEvaluation's own WATERS generator (utilisation
/// 0.8 with 8 chains, 0.3 with 12; tests/data/README.md gives the
/// commands): every figure rtpipe reports under a literature name, from
/// `analyze` and from the simulated schedule, is the one E2EEvaluation's
/// own analyses computed.
#[test]
fn other_generator_settings_give_the_literature_s_figures_too() {
    for (tag, yaml, csv, size) in [
        (
            "e2e-util80",
            "e2eeval-util80.yaml",
            "e2eeval-util80-results.csv",
            "110 tasks on 1 ECU, 8 chains",
        ),
        (
            "e2e-util30",
            "e2eeval-util30.yaml",
            "e2eeval-util30-results.csv",
            "50 tasks on 1 ECU, 12 chains",
        ),
    ] {
        let (spec, table) = import_one(tag, yaml);
        assert!(table.contains(size), "{table}");
        let spec = spec.to_string_lossy();
        let a = rtpipe(&["analyze", &spec, "--json"]);
        assert_exit(&a, 0);
        let s = rtpipe(&["simulate", &spec, "--duration", "10s", "--json"]);
        assert_exit(&s, 0);
        let (a, s) = (json_of(&a), json_of(&s));
        let theirs = results(csv);
        let (reaction, freshness) = (chains(&a, "reaction"), chains(&a, "freshness"));
        let (sim_r, sim_f) = (chains(&s, "reaction"), chains(&s, "freshness"));
        assert_eq!(
            (reaction.len(), sim_r.len()),
            (theirs.len(), theirs.len()),
            "{yaml}"
        );
        for (k, t) in theirs.iter().enumerate() {
            let (r, f) = (reaction[k], freshness[k]);
            same_bound("D07", k, num(&r["from_event"]["davare"]), t["D07"]);
            same_bound(
                "K18",
                k,
                num(&r["known_offsets"]["from_event"]["sound"]),
                t["K18"],
            );
            literature_bounds(k, r, f, t);
            guenzel_figures(k, sim_r[k], sim_f[k], t);
        }
    }
}

/// Interconnected chains over three ECUs (three WATERS task sets, 20
/// chains): one spec, each ECU a CPU; Davare's and Dürr's inter-ECU bounds
/// as E2EEvaluation computes them.
#[test]
fn the_real_interconnected_export_gives_davare_and_duerr_across_ecus() {
    let (spec, table) = import_one("e2e-real-inter", "e2eeval-waters-inter.yaml");
    assert!(table.contains("182 tasks on 3 ECUs, 20 chains"), "{table}");
    let a = rtpipe(&["analyze", &spec.to_string_lossy(), "--json"]);
    assert_exit(&a, 0);
    let v = json_of(&a);
    let (reaction, freshness) = (chains(&v, "reaction"), chains(&v, "freshness"));
    let theirs = results("e2eeval-waters-inter-results.csv");
    assert_eq!(
        (reaction.len(), freshness.len(), theirs.len()),
        (20, 20, 20)
    );
    for (k, t) in theirs.iter().enumerate() {
        let (r, f) = (reaction[k], freshness[k]);
        same_bound("D07-I", k, num(&r["from_event"]["davare"]), t["D07-I"]);
        same_bound("D19(MRT)", k, num(&r["from_event"]["duerr"]), t["D19(MRT)"]);
        same_bound("D19(MRDA)", k, num(&f["duerr"]), t["D19(MRDA)"]);
        let sound = num(&r["from_event"]["sound"]);
        assert!(sound <= num(&r["from_event"]["davare"]), "chain {k}");
    }
}
