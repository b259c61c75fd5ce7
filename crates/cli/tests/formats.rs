//! `--format text|json|csv`: one flag for every command's report, `--json`
//! its synonym, CSV from the report's tables (RFC 4180, headers as named).

mod common;
use common::*;

/// The CSV part headed `# NAME`, its lines.
fn csv_table<'a>(out: &'a str, name: &str) -> Vec<&'a str> {
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
         paper_from_event,sound_from_event,davare_from_event,duerr_from_event,paper_ok,ok"
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

/// `fly` and `campaign` render their own reports yet: no tables to print.
#[test]
fn commands_without_tables_refuse_csv_plainly() {
    let o = rtpipe(&["fly", &example("cleanflight.toml"), "--format", "csv"]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("`fly` has no CSV report yet"), "{err}");
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
