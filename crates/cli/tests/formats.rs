//! `--format text|json|csv`: one flag for every command's report, `--json`
//! its synonym, CSV from the report's tables (RFC 4180, headers as named).

mod common;
use common::*;

/// The CSV part headed `# NAME`, its lines (a report of one table prints
/// it without a heading: then that table).
fn csv_table<'a>(out: &'a str, name: &str) -> Vec<&'a str> {
    if !out.starts_with("# ") {
        return out.lines().collect();
    }
    let head = format!("# {name}");
    out.split("\n\n")
        .find(|part| part.starts_with(&head))
        .map(|part| part.lines().skip(1).collect())
        .unwrap_or_default()
}

#[test]
fn format_json_is_the_json_flag() {
    let spec = example("paper-table2.toml");
    let a = rtpipe(&["analyze", &spec, "--json"]);
    let b = rtpipe(&["analyze", &spec, "--format", "json"]);
    assert!(!a.stdout.is_empty());
    assert_eq!((a.stdout, a.status), (b.stdout, b.status));
    let t = rtpipe(&["analyze", &spec]);
    let text = rtpipe(&["analyze", &spec, "--format", "text"]);
    assert_eq!(t.stdout, text.stdout);
}

#[test]
fn format_and_json_together_are_refused() {
    let o = rtpipe(&[
        "analyze",
        &example("paper-table2.toml"),
        "--json",
        "--format",
        "csv",
    ]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--json") && err.contains("--format"), "{err}");
}

#[test]
fn analyze_prints_its_tasks_and_chains_as_csv() {
    let spec = example("paper-table2.toml");
    let o = rtpipe(&["analyze", &spec, "--format", "csv"]);
    // Table II fails some sound limits: exit 1, the report printed.
    assert_exit(&o, 1);
    let out = String::from_utf8_lossy(&o.stdout);
    let tasks = csv_table(&out, "tasks");
    assert!(tasks[0].starts_with("task,server,cpu,priority,"), "{out}");
    let json = json_of(&rtpipe(&["analyze", &spec, "--json"]));
    let n = json["tasks"].as_array().map_or(0, Vec::len);
    assert_eq!(tasks.len(), 1 + n, "{out}");
    let chains = csv_table(&out, "chains");
    assert_eq!(
        chains[0],
        "chain,metric,limit,event_limit,paper,sound,davare,duerr,\
         paper_from_event,sound_from_event,davare_from_event,duerr_from_event,paper_ok,ok,\
         literature,literature_from_event"
    );
    // The literature's names of each row's figures: reaction from the event
    // is the maximum reaction time and the maximum data age, freshness from
    // the read the maximum reduced data age.
    assert!(
        chains[1].ends_with(",,max_reaction_time;max_data_age"),
        "{}",
        chains[1]
    );
    assert!(
        chains[2].ends_with(",max_reduced_data_age,"),
        "{}",
        chains[2]
    );
    let m = json["chains"].as_array().map_or(0, Vec::len);
    assert_eq!(chains.len(), 1 + m, "{out}");
    // Every row has as many fields as the header (no field holds a comma
    // unquoted: the path labels are quoted when they hold one).
    let first = chains[1];
    let sound = json["chains"][0]["sound"].as_f64().map(|v| v.to_string());
    assert!(first.contains(&sound.unwrap_or_default()), "{first}");
}

#[test]
fn simulate_adds_what_it_observed_as_a_table() {
    let spec = example("paper-table3.toml");
    let o = rtpipe(&["simulate", &spec, "--outputs", "20", "--format", "csv"]);
    assert_exit(&o, 0);
    let out = String::from_utf8_lossy(&o.stdout);
    let observed = csv_table(&out, "observed");
    assert_eq!(
        observed.first().copied(),
        Some("chain,metric,from,count,min,mean,p99,max,paper,sound,over_paper,over_sound")
    );
    assert!(observed.len() > 1, "{out}");
    assert!(observed[1..]
        .iter()
        .all(|l| l.contains(",read,") || l.contains(",event,")));
}

#[test]
fn design_prints_the_designed_tasks_as_csv() {
    let o = rtpipe(&[
        "design",
        &example("table2-design.toml"),
        "--mode",
        "paper",
        "--format",
        "csv",
    ]);
    assert_exit(&o, 0);
    let out = String::from_utf8_lossy(&o.stdout);
    let tasks = csv_table(&out, "tasks");
    assert!(tasks.len() > 1, "{out}");
    assert!(!csv_table(&out, "chains").is_empty(), "{out}");
}

/// The CSV table `name` as (header, rows), each line split at commas
/// (the values these tests compare hold none).
fn csv_rows(out: &str, name: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let lines = csv_table(out, name);
    let split = |l: &str| l.split(',').map(String::from).collect::<Vec<_>>();
    let header = lines.first().map(|l| split(l)).unwrap_or_default();
    (header, lines.iter().skip(1).map(|l| split(l)).collect())
}

/// Row `row`'s field of column `column`.
fn field<'a>(t: &'a (Vec<String>, Vec<Vec<String>>), row: usize, column: &str) -> &'a str {
    let k = t.0.iter().position(|c| c == column);
    k.and_then(|k| t.1.get(row)?.get(k))
        .map_or("<none>", String::as_str)
}

#[test]
fn fly_prints_the_flight_and_its_steps_as_csv() {
    let spec = example("cleanflight.toml");
    let args = ["fly", &spec, "--duration", "4s", "--mission", "hover"];
    let o = rtpipe(&[&args[..], &["--format", "csv"]].concat());
    assert_exit(&o, 0);
    let out = String::from_utf8_lossy(&o.stdout);
    let v = json_of(&rtpipe(&[&args[..], &["--json"]].concat()));
    for name in ["tasks", "chains", "observed"] {
        assert!(csv_table(&out, name).len() > 1, "{name}: {out}");
    }
    let flight = csv_rows(&out, "flight");
    assert_eq!(flight.1.len(), 1, "{out}");
    assert_eq!(flight.0.first().map(String::as_str), Some("vehicle"));
    assert_eq!(field(&flight, 0, "mission"), "hover");
    assert_eq!(field(&flight, 0, "crashed"), "false");
    assert_eq!(field(&flight, 0, "criteria_met"), "true");
    // The same figures as the JSON, to the last digit.
    for (column, key) in [("drift_m", "drift_m"), ("airborne_s", "airborne_s")] {
        let json = v["flight"][key].as_f64().map(|x| x.to_string());
        assert_eq!(
            Some(field(&flight, 0, column).to_string()),
            json,
            "{column}"
        );
    }
    let rms = v["flight"]["attitude_error_deg"]["rms"].as_f64();
    let csv_rms = field(&flight, 0, "attitude_error_deg_rms")
        .parse::<f64>()
        .ok();
    assert_eq!(csv_rms, rms);
    // The hover flies no steps: the table has its header and no row.
    let steps = csv_table(&out, "steps");
    assert_eq!(
        steps.first().map(|h| h.starts_with("axis,at_s,")),
        Some(true)
    );
    assert_eq!(
        steps.len(),
        1 + v["flight"]["steps"].as_array().map_or(0, Vec::len)
    );
}

#[test]
fn fly_sweep_prints_its_points_and_limits_as_csv() {
    let spec = example("cleanflight.toml");
    let args = [
        "fly",
        &spec,
        "--sweep",
        "--scale",
        "1..2",
        "--per-octave",
        "1",
        "--resolution",
        "0",
        "--duration",
        "4s",
        "--mission",
        "hover",
    ];
    let o = rtpipe(&[&args[..], &["--format", "csv"]].concat());
    assert_exit(&o, 0);
    let out = String::from_utf8_lossy(&o.stdout);
    let v = json_of(&rtpipe(&[&args[..], &["--json"]].concat()));
    let points = csv_rows(&out, "points");
    let n = v["points"].as_array().map_or(0, Vec::len);
    assert!(n > 0, "{v}");
    assert_eq!(points.1.len(), n, "{out}");
    for (k, p) in v["points"].as_array().into_iter().flatten().enumerate() {
        assert_eq!(
            field(&points, k, "varied"),
            p["varied"].as_str().unwrap_or("?")
        );
        assert_eq!(field(&points, k, "flies"), p["flies"].to_string());
    }
    // Every point has a row per chain from the read and from the event.
    let chains = v["limits_ms"].as_array().map_or(0, Vec::len);
    assert_eq!(csv_rows(&out, "bounds").1.len(), n * chains * 2, "{out}");
    let limits = csv_rows(&out, "limits");
    assert_eq!(limits.1.len(), chains, "{out}");
    let first = v["limits_ms"][0]["reaction"]
        .as_f64()
        .map(|x| x.to_string());
    assert_eq!(Some(field(&limits, 0, "reaction_ms").to_string()), first);
    let setup = csv_rows(&out, "sweep");
    assert_eq!(field(&setup, 0, "system"), "cleanflight");
    assert!(csv_table(&out, "sweep")[1].ends_with(",1,1,1"), "{out}");
}

/// The bundled campaign, shrunk to a few short systems.
fn small_campaign(dir: &std::path::Path) -> String {
    let text = std::fs::read_to_string(example("campaigns/waters.toml")).unwrap_or_default();
    let text = text
        .replace("systems = 2000", "systems = 10")
        .replace("shard_size = 500", "shard_size = 5")
        .replace("duration = \"2s\"", "duration = \"100ms\"");
    let path = dir.join("c.toml");
    assert!(std::fs::write(&path, text).is_ok());
    path.display().to_string()
}

#[test]
fn campaign_prints_its_summary_and_plan_as_csv() {
    let dir = scratch("formats-campaign");
    let config = small_campaign(&dir);
    let out_dir = dir.join("out").display().to_string();
    let plan = rtpipe(&["campaign", &config, &out_dir, "--plan", "--format", "csv"]);
    assert_exit(&plan, 0);
    let plan = String::from_utf8_lossy(&plan.stdout);
    let p = csv_rows(&plan, "plan");
    assert_eq!(
        (field(&p, 0, "systems"), field(&p, 0, "shards")),
        ("10", "2")
    );
    // Nothing written yet: no shard to list.
    assert_eq!(csv_table(&plan, "shards"), ["shard,state"]);
    let o = rtpipe(&["campaign", &config, &out_dir, "--format", "csv"]);
    assert_exit(&o, 0);
    let out = String::from_utf8_lossy(&o.stdout);
    let c = csv_rows(&out, "campaign");
    assert_eq!(c.1.len(), 1, "{out}");
    assert_eq!(
        (field(&c, 0, "systems_run"), field(&c, 0, "written")),
        ("10", "2")
    );
    assert_eq!(field(&c, 0, "stopped"), "false");
    // Run again: the JSON and the CSV say the same of the same directory.
    let v = json_of(&rtpipe(&["campaign", &config, &out_dir, "--json"]));
    let again = rtpipe(&["campaign", &config, &out_dir, "--format", "csv"]);
    let again = csv_rows(&String::from_utf8_lossy(&again.stdout), "campaign");
    for key in ["written", "skipped", "rows", "part"] {
        let json = match &v[key] {
            serde_json::Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        assert_eq!(field(&again, 0, key), json, "{key}");
    }
    let plan = rtpipe(&["campaign", &config, &out_dir, "--plan", "--format", "csv"]);
    let plan = String::from_utf8_lossy(&plan.stdout);
    assert_eq!(
        csv_table(&plan, "shards"),
        ["shard,state", "0,written", "1,written"]
    );
}

#[test]
fn analyze_adds_the_margins_table_that_margins_csv_writes() {
    let dir = scratch("formats-margins");
    let file = dir.join("m.csv");
    let spec = example("paper-table3.toml");
    let file_arg = file.to_string_lossy();
    let o = rtpipe(&[
        "analyze",
        &spec,
        "--format",
        "csv",
        "--margins-csv",
        &file_arg,
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    let printed = csv_table(&out, "margins").join("\n") + "\n";
    let written = std::fs::read_to_string(&file).unwrap_or_default();
    assert!(written.starts_with("kind,subject,key,value,"), "{written}");
    assert_eq!(printed, written);
}
