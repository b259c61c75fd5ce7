//! Behaviour pinned byte for byte: every bundled example and a fixed set of
//! generated systems through analyze, simulate, design, fly, generate and
//! import, text and JSON, with the files they write (specs, SVG plots,
//! traces). A refactoring must leave every byte as it is; wall-clock
//! figures (search and simulation times, events per second) are masked.
//!
//! Regenerate after an intended change with `RTPIPE_BLESS=1 cargo test
//! --release -p rtpipe --test golden`, and read the diff before committing.

mod common;

use common::{example, rtpipe_in, scratch};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One pinned invocation: a name (its golden file) and its arguments.
/// `@NAME` is a bundled example, `%NAME` a file in the scratch directory,
/// `^NAME` an output file (or directory) in the scratch directory whose
/// contents join the golden text.
struct Case {
    name: String,
    args: Vec<String>,
}

type Fixed = (&'static str, &'static [&'static str]);

const fn case(name: &'static str, args: &'static [&'static str]) -> Fixed {
    (name, args)
}

/// The bundled examples.
const EXAMPLES: [&str; 22] = [
    "cleanflight-derived-design",
    "cleanflight-derived",
    "cleanflight-design",
    "cleanflight-event-limits",
    "cleanflight",
    "e2e-golden",
    "edf-srp",
    "paper-table2-edf",
    "jitter-deadlines",
    "let",
    "let-mixed",
    "overheads",
    "paper-table2",
    "paper-table3-loaded",
    "paper-table3",
    "published-audsley1993",
    "published-let-rosace",
    "resources",
    "resources-design",
    "table2-design-rta",
    "table2-design",
    "timing-design",
];

/// Generated systems (run first: later cases read them).
const GENERATED: &[Fixed] = &[
    case(
        "gen-waters-runnables",
        &["generate", "waters", "^w0.toml", "--seed", "7"],
    ),
    case(
        "gen-waters-tasks",
        &[
            "generate", "waters", "^w1.toml", "--tasks", "24", "--cpus", "2", "--seed", "3",
            "--chains", "6",
        ],
    ),
    case(
        "gen-waters-dense",
        &[
            "generate",
            "waters",
            "^w2.toml",
            "--tasks",
            "40",
            "--utilization",
            "0.8",
            "--seed",
            "11",
        ],
    ),
];

/// Everything else, in order.
const CASES: &[Fixed] = &[
    case("analyze-w0", &["analyze", "%w0.toml"]),
    case("analyze-w1-json", &["analyze", "%w1.toml", "--json"]),
    case(
        "analyze-w2-paper",
        &["analyze", "%w2.toml", "--mode", "paper"],
    ),
    case(
        "analyze-w2-all-paths-json",
        &["analyze", "%w2.toml", "--all-paths", "--json"],
    ),
    case(
        "simulate-w1",
        &[
            "simulate",
            "%w1.toml",
            "--outputs",
            "50",
            "--phasing",
            "random",
            "--seed",
            "5",
        ],
    ),
    case(
        "simulate-w2-json",
        &[
            "simulate",
            "%w2.toml",
            "--outputs",
            "50",
            "--exec",
            "uniform",
            "--json",
        ],
    ),
    case(
        "analyze-table2-all-paths",
        &["analyze", "@paper-table2", "--all-paths"],
    ),
    case(
        "analyze-let-mixed-all-paths",
        &["analyze", "@let-mixed", "--all-paths"],
    ),
    case(
        "analyze-cleanflight-all-paths-json",
        &["analyze", "@cleanflight", "--all-paths", "--json"],
    ),
    case(
        "analyze-table2-paper",
        &["analyze", "@paper-table2", "--mode", "paper"],
    ),
    case(
        "analyze-jitter-deadlines-margins",
        &["analyze", "@jitter-deadlines", "--margins"],
    ),
    case(
        "analyze-cleanflight-margins-paper-json",
        &[
            "analyze",
            "@cleanflight",
            "--margins",
            "--mode",
            "paper",
            "--json",
        ],
    ),
    case("analyze-w1-margins", &["analyze", "%w1.toml", "--margins"]),
    case(
        "simulate-table3-files",
        &[
            "simulate",
            "@paper-table3",
            "--outputs",
            "100",
            "--plot",
            "^fig9.svg",
            "--gantt",
            "^gantt.svg",
            "--trace",
            "^trace.json",
        ],
    ),
    case(
        "simulate-table2-samples",
        &[
            "simulate",
            "@paper-table2",
            "--outputs",
            "50",
            "--exec",
            "uniform",
            "--phasing",
            "random",
            "--samples",
            "^samples.csv",
        ],
    ),
    case(
        "simulate-table3-search",
        &[
            "simulate",
            "@paper-table3",
            "--outputs",
            "100",
            "--phasing",
            "search",
            "--search-steps",
            "6",
            "--json",
        ],
    ),
    case(
        "simulate-table2-extremes",
        &[
            "simulate",
            "@paper-table2",
            "--outputs",
            "300",
            "--exec",
            "extremes",
            "--phasing",
            "random",
            "--seed",
            "9",
        ],
    ),
    case(
        "simulate-cleanflight-json",
        &[
            "simulate",
            "@cleanflight",
            "--outputs",
            "300",
            "--exec",
            "uniform",
            "--json",
        ],
    ),
    case(
        "simulate-golden-search",
        &[
            "simulate",
            "@e2e-golden",
            "--outputs",
            "100",
            "--phasing",
            "search",
            "--search-steps",
            "4",
        ],
    ),
    case(
        "design-table2-paper",
        &["design", "@table2-design", "--mode", "paper"],
    ),
    case(
        "design-table2-sound-json",
        &["design", "@table2-design", "--json"],
    ),
    case(
        "design-table2-rta-sound",
        &["design", "@table2-design-rta", "--write", "^t2rta.toml"],
    ),
    case(
        "design-table2-rta-milp",
        &[
            "design",
            "@table2-design-rta",
            "--method",
            "milp",
            "--mode",
            "paper",
        ],
    ),
    case(
        "design-cleanflight-sound",
        &["design", "@cleanflight-design"],
    ),
    case(
        "design-cleanflight-paper-json",
        &["design", "@cleanflight-design", "--mode", "paper", "--json"],
    ),
    case(
        "design-cleanflight-derived",
        &["design", "@cleanflight-derived-design"],
    ),
    case("design-resources", &["design", "@resources-design"]),
    case(
        "design-resources-milp",
        &["design", "@resources-design", "--method", "milp"],
    ),
    case(
        "design-cleanflight-event-limits",
        &["design", "@cleanflight-event-limits"],
    ),
    case("design-timing", &["design", "@timing-design"]),
    case(
        "design-timing-milp",
        &["design", "@timing-design", "--method", "milp"],
    ),
    case("fly-cleanflight", &["fly", "@cleanflight"]),
    case(
        "fly-cleanflight-json",
        &[
            "fly",
            "@cleanflight",
            "--json",
            "--vehicle",
            "aero1kg",
            "--mission",
            "hover",
            "--duration",
            "4s",
            "--seed",
            "2",
        ],
    ),
    case(
        "fly-cleanflight-plots",
        &[
            "fly",
            "@cleanflight",
            "--duration",
            "3s",
            "--plot",
            "^flyplots",
        ],
    ),
    case("fly-gusty", &["fly", "@cleanflight", "--mission", "gusty"]),
    case(
        "fly-gusty-json",
        &[
            "fly",
            "@cleanflight",
            "--mission",
            "gusty",
            "--vehicle",
            "aero1kg",
            "--turbulence",
            "light",
            "--json",
        ],
    ),
    case(
        "design-derived-write",
        &[
            "design",
            "@cleanflight-derived-design",
            "--write",
            "^cfd.toml",
        ],
    ),
    case(
        "fly-designed-paper",
        &["fly", "%cfd.toml", "--mission", "paper", "--exec", "worst"],
    ),
    case(
        "fly-sweep",
        &[
            "fly",
            "@cleanflight",
            "--sweep",
            "--mission",
            "hover",
            "--duration",
            "2s",
            "--scale",
            "0.5..2",
            "--json",
        ],
    ),
    case(
        "import-golden",
        &["import", "e2eeval", "#e2eeval-golden.yaml", "^imported"],
    ),
    case(
        "import-inter",
        &[
            "import",
            "e2eeval",
            "#e2eeval-inter.yaml",
            "^imported-inter",
        ],
    ),
];

/// Replaces wall-clock figures (which differ run to run) by `*`.
fn mask(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        out.push_str(&mask_line(line));
    }
    out
}

/// The wall-clock figures of one line: design's "in 0.59 s", the
/// simulator's "in 0.001 s (9.66M events/s)", JSON's "seconds" and
/// "events_per_second".
fn mask_line(line: &str) -> String {
    for key in [
        "\"seconds\":",
        "\"first_design_seconds\":",
        "\"events_per_second\":",
        "\"wall_seconds\":",
        "\"elapsed_s\":",
    ] {
        if let Some(i) = line.find(key) {
            let tail = &line[i + key.len()..];
            let end = tail.find([',', '\n', '}']).unwrap_or(tail.len());
            return format!("{}{} *{}", &line[..i], key, &tail[end..]);
        }
    }
    let mut s = line.to_string();
    for (pre, post) in [
        (" in ", " s"),
        ("(", " events/s)"),
        ("(", "M events/s)"),
        ("(", "k events/s)"),
        ("(", "× real time)"),
    ] {
        s = mask_between(&s, pre, post);
    }
    // The rate's unit prefix varies with the rate.
    s.replace("*M events/s", "* events/s")
        .replace("*k events/s", "* events/s")
}

/// Masks every number that sits between `pre` and `post`.
fn mask_between(line: &str, pre: &str, post: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    while let Some(i) = rest.find(pre) {
        let after = &rest[i + pre.len()..];
        let n = after
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(after.len());
        if n > 0 && after[n..].starts_with(post) {
            out.push_str(&rest[..i + pre.len()]);
            out.push('*');
            rest = &after[n..];
        } else {
            out.push_str(&rest[..i + pre.len()]);
            rest = after;
        }
    }
    out.push_str(rest);
    out
}

/// Resolves one argument; records output paths in `outputs`.
fn resolve(arg: &str, dir: &Path, outputs: &mut Vec<PathBuf>) -> String {
    let at = |p: PathBuf| p.to_string_lossy().into_owned();
    if let Some(n) = arg.strip_prefix('@') {
        example(&format!("{n}.toml"))
    } else if let Some(n) = arg.strip_prefix('%') {
        n.to_string()
    } else if let Some(n) = arg.strip_prefix('#') {
        at(Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data")
            .join(n))
    } else if let Some(n) = arg.strip_prefix('^') {
        let p = dir.join(n);
        let _ = std::fs::remove_dir_all(&p);
        let _ = std::fs::remove_file(&p);
        outputs.push(p);
        n.to_string()
    } else {
        arg.to_string()
    }
}

/// The contents of an output file, or of every file of an output directory.
fn append_output(text: &mut String, path: &Path, dir: &Path) {
    let mut files = Vec::new();
    if path.is_dir() {
        if let Ok(rd) = std::fs::read_dir(path) {
            files.extend(rd.flatten().map(|e| e.path()));
        }
        files.sort();
    } else {
        files.push(path.to_path_buf());
    }
    for f in files {
        let name = f.strip_prefix(dir).unwrap_or(&f).display().to_string();
        let body = std::fs::read(&f)
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .unwrap_or_else(|e| format!("(not written: {e})\n"));
        let _ = write!(text, "--- file {name}\n{}\n", mask(&body));
    }
}

/// Runs one case and returns its golden text.
fn run(case: &Case, dir: &Path) -> String {
    let mut outputs = Vec::new();
    let args: Vec<String> = case
        .args
        .iter()
        .map(|a| resolve(a, dir, &mut outputs))
        .collect();
    let argv: Vec<&str> = args.iter().map(String::as_str).collect();
    // Run in the scratch directory with relative paths, so that no output
    // (a table's column widths included) depends on where it is.
    let o = rtpipe_in(dir, &argv, &[], std::time::Duration::from_secs(600));
    let mut text = format!(
        "$ rtpipe {}\nexit {:?}\n--- stdout\n{}--- stderr\n{}",
        case.args.join(" "),
        o.status.code(),
        mask(&places(&String::from_utf8_lossy(&o.stdout), dir)),
        mask(&places(&String::from_utf8_lossy(&o.stderr), dir))
    );
    for p in &outputs {
        append_output(&mut text, p, dir);
    }
    text
}

/// Machine-independent paths in messages.
fn places(text: &str, dir: &Path) -> String {
    let examples = example("x.toml");
    let examples = examples.trim_end_matches("x.toml");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/");
    text.replace(examples, "$EXAMPLES/")
        .replace(&data.display().to_string(), "$DATA/")
        .replace(&dir.display().to_string(), "$DIR")
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// Every case in order: generated systems first (later cases read them),
/// then every example through analyze (text, JSON) and simulate, then the rest.
fn cases() -> Vec<Case> {
    let fixed = |&(n, a): &Fixed| Case {
        name: n.to_string(),
        args: a.iter().map(|s| s.to_string()).collect(),
    };
    let mut v: Vec<Case> = GENERATED.iter().map(fixed).collect();
    for e in EXAMPLES {
        let at = format!("@{e}");
        for (name, extra) in [("analyze", &[][..]), ("analyze-json", &["--json"][..])] {
            let mut args = vec!["analyze".to_string(), at.clone()];
            args.extend(extra.iter().map(|s| s.to_string()));
            v.push(Case {
                name: format!("{name}-{e}"),
                args,
            });
        }
        v.push(Case {
            name: format!("simulate-{e}"),
            args: vec!["simulate".into(), at, "--outputs".into(), "200".into()],
        });
    }
    v.extend(CASES.iter().map(fixed));
    v
}

#[test]
fn outputs_are_unchanged() {
    let dir = scratch("golden");
    let bless = std::env::var_os("RTPIPE_BLESS").is_some();
    let mut changed = Vec::new();
    for c in cases() {
        let got = run(&c, &dir);
        let path = golden_dir().join(format!("{}.txt", c.name));
        if bless {
            if let Err(e) =
                std::fs::create_dir_all(golden_dir()).and_then(|_| std::fs::write(&path, &got))
            {
                panic!("cannot write {}: {e}", path.display());
            }
            continue;
        }
        let want = std::fs::read_to_string(&path).unwrap_or_default();
        if want != got {
            let _ = std::fs::write(dir.join(format!("{}.got.txt", c.name)), &got);
            changed.push(c.name);
        }
    }
    assert!(
        changed.is_empty(),
        "outputs changed (new outputs in {}): {changed:?}",
        dir.display()
    );
}
