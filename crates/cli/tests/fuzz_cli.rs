//! The whole binary on mutated specs (from examples/) and random flag
//! combinations: no panic, no hang (killed after 30 s), an exit status in
//! the documented set {0, 1, 2, 3}, and nothing written but the named
//! outputs (each run has its own directory, whose listing is compared).
//!
//! `RTPIPE_CLI_FUZZ_CASES` sets the number of runs (default 200, about
//! 10 s), `RTPIPE_CLI_FUZZ_SEED` the first seed. A failing case is left in
//! its directory with the command line, to replay.

mod common;

use common::{example, listing, rtpipe_in};
use std::collections::BTreeSet;
use std::path::Path;
use std::time::Duration;

const EXAMPLES: [&str; 7] = [
    "paper-table2.toml",
    "paper-table3.toml",
    "paper-table3-loaded.toml",
    "cleanflight.toml",
    "table2-design.toml",
    "table2-design-rta.toml",
    "cleanflight-design.toml",
];

/// The draws of a seed: the workspace's SplitMix64 stream
/// (`rtpipe_model::gen::Rng`) with the picks this test makes.
struct Rng(rtpipe_model::gen::Rng);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
}

const NUMBERS: [&str; 16] = [
    "0",
    "-1",
    "1e-12",
    "nan",
    "inf",
    "-inf",
    "1e30",
    "99999999999999999999",
    "0.5",
    "\"1e3us\"",
    "\"1e30ms\"",
    "\"2.5ms\"",
    "\"-3ms\"",
    "{ max = \"50s\" }",
    "{ choices = [] }",
    "{ min = 5, max = 1 }",
];

const STRINGS: [&str; 8] = [
    "\"\"",
    "\"a>b\"",
    "\"\\u001b[31mred\"",
    "\"t1\"",
    "\"zz\"",
    "\"edf\"",
    "\"io\"",
    "\"µs\"",
];

/// One random edit of a spec's text.
fn mutate(text: &str, r: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return text.to_string();
    }
    let edits = 1 + r.below(2);
    for _ in 0..edits {
        let i = r.below(lines.len());
        match r.below(9) {
            0 => {
                lines.remove(i);
                if lines.is_empty() {
                    lines.push(String::new());
                }
            }
            1 => {
                let l = lines[i].clone();
                lines.insert(i, l);
            }
            2 | 3 => {
                // A value replaced by a number or a table.
                if let Some((k, _)) = lines[i].split_once('=') {
                    lines[i] = format!("{k}= {}", r.pick(&NUMBERS));
                }
            }
            4 => {
                if let Some((k, _)) = lines[i].split_once('=') {
                    lines[i] = format!("{k}= {}", r.pick(&STRINGS));
                }
            }
            5 => {
                let j = r.below(lines.len());
                lines.swap(i, j);
            }
            6 => {
                // A task or channel renamed.
                if let Some(rest) = lines[i].strip_prefix("[tasks.") {
                    let _ = rest;
                    lines[i] = format!("[tasks.{}]", r.pick(&STRINGS));
                }
            }
            7 => {
                let cut = r.below(lines[i].len() + 1);
                let mut l = lines[i].clone();
                while !l.is_char_boundary(cut.min(l.len())) {
                    l.pop();
                }
                l.truncate(cut.min(l.len()));
                lines[i] = l;
            }
            _ => {
                // Junk: a long line, a stray key, a harmonic system.
                let junk = [
                    format!("name = \"{}\"", "x".repeat(5000)),
                    "harmonic = true".to_string(),
                    "resolution = \"1ns\"".to_string(),
                    "bogus = 1".to_string(),
                    "[[chain]]\npath = [\"t1\", \"t2\"]".to_string(),
                ];
                lines.insert(i, junk[r.below(junk.len())].clone());
            }
        }
    }
    lines.join("\n") + "\n"
}

/// A random command line; the outputs it names (file names in the run's
/// directory).
fn command(r: &mut Rng) -> (Vec<String>, Vec<String>) {
    let mut args: Vec<String> = Vec::new();
    let mut outs = Vec::new();
    let s = |x: &str| x.to_string();
    // An output name: usually fresh, sometimes the input spec.
    let mut out = |r: &mut Rng, name: &str| {
        let n = if r.chance(15) {
            s("spec.toml")
        } else {
            s(name)
        };
        outs.push(n.clone());
        n
    };
    match r.below(3) {
        0 => {
            args.extend([s("analyze"), s("spec.toml")]);
            if r.chance(50) {
                args.push(s("--json"));
            }
            if r.chance(30) {
                args.push(s("--all-paths"));
            }
            if r.chance(30) {
                args.extend([s("--mode"), s("paper")]);
            }
        }
        1 => {
            args.extend([s("simulate"), s("spec.toml")]);
            if r.chance(85) {
                args.extend([s("--outputs"), (1 + r.below(30)).to_string()]);
            } else {
                args.extend([
                    s("--duration"),
                    s(r.pick(&["50ms", "0", "-1", "1e3us", "x"])),
                ]);
            }
            if r.chance(40) {
                args.push(s("--json"));
            }
            if r.chance(40) {
                args.extend([s("--phasing"), s(r.pick(&["sync", "random", "search"]))]);
            }
            if r.chance(30) {
                args.extend([
                    s("--exec"),
                    s(r.pick(&["worst", "uniform", "best", "extremes"])),
                ]);
            }
            if r.chance(30) {
                args.extend([s("--seed"), r.below(1000).to_string()]);
            }
            if r.chance(25) {
                args.extend([s("--search-steps"), (1 + r.below(3)).to_string()]);
            }
            if r.chance(25) {
                let o = out(r, "trace.json");
                args.extend([s("--trace"), o]);
            }
            if r.chance(25) {
                let o = out(r, "plot.svg");
                args.extend([s("--plot"), o]);
            }
            if r.chance(25) {
                let o = out(r, "gantt.svg");
                args.extend([s("--gantt"), o]);
            }
            if r.chance(15) {
                args.extend([s("--window"), s(r.pick(&["0,10", "5,1", "0,1e9", "x"]))]);
            }
        }
        _ => {
            args.extend([s("design"), s("spec.toml")]);
            args.extend([
                s("--time-limit"),
                s(r.pick(&["0.3", "0.5", "1", "0", "1e20"])),
            ]);
            if r.chance(50) {
                args.extend([s("--mode"), s(r.pick(&["paper", "sound"]))]);
            }
            if r.chance(40) {
                args.push(s("--json"));
            }
            if r.chance(40) {
                let o = out(r, "designed.toml");
                args.extend([s("--write"), o]);
                if r.chance(30) {
                    args.push(s("--overwrite-spec"));
                }
            }
        }
    }
    (args, outs)
}

fn run_case(seed: u64, root: &Path, texts: &[String]) -> Result<i32, String> {
    let mut r = Rng(rtpipe_model::gen::Rng::new(seed));
    let base = &texts[r.below(texts.len())];
    let spec = if r.chance(60) {
        mutate(base, &mut r)
    } else {
        base.clone()
    };
    let (args, outs) = command(&mut r);
    let dir = root.join(format!("case-{seed}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    std::fs::write(dir.join("spec.toml"), &spec).map_err(|e| e.to_string())?;
    let argv: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = rtpipe_in(&dir, &argv, &[], Duration::from_secs(30));
    let code = o.status.code();
    let err = String::from_utf8_lossy(&o.stderr);
    let mut problems = Vec::new();
    if !matches!(code, Some(0..=3)) {
        problems.push(format!("exit status {code:?} not in {{0, 1, 2, 3}}"));
    }
    if err.contains("panicked at") {
        problems.push("panicked".to_string());
    }
    let allowed: BTreeSet<String> = outs
        .iter()
        .cloned()
        .chain([String::from("spec.toml")])
        .collect();
    let extra: Vec<String> = listing(&dir)
        .into_iter()
        .filter(|n| !allowed.contains(n))
        .collect();
    if !extra.is_empty() {
        problems.push(format!("wrote files it did not name: {extra:?}"));
    }
    let overwrite = args.iter().any(|a| a == "--overwrite-spec");
    let now = std::fs::read_to_string(dir.join("spec.toml")).unwrap_or_default();
    if now != spec && !overwrite {
        problems.push("the input spec changed".to_string());
    }
    if problems.is_empty() {
        let _ = std::fs::remove_dir_all(&dir);
        Ok(code.unwrap_or(-1))
    } else {
        let replay = format!("cd {} && rtpipe {}", dir.display(), args.join(" "));
        let _ = std::fs::write(dir.join("REPLAY"), &replay);
        Err(format!(
            "seed {seed}: {}\n  {replay}\n  stderr: {}",
            problems.join("; "),
            err.chars().take(2000).collect::<String>()
        ))
    }
}

#[test]
fn the_binary_survives_mutated_specs_and_random_flags() {
    let cases: u64 = std::env::var("RTPIPE_CLI_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let first: u64 = std::env::var("RTPIPE_CLI_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let texts: Vec<String> = EXAMPLES
        .iter()
        .map(|n| match std::fs::read_to_string(example(n)) {
            Ok(t) => t,
            Err(e) => panic!("{n}: {e}"),
        })
        .collect();
    // Kept for inspection when a case fails (the guard's rule), removed
    // otherwise.
    let root = rtpipe_testkit::Scratch::new("cli-fuzz");
    let mut failures = Vec::new();
    let mut codes = std::collections::BTreeMap::new();
    for seed in first..first + cases {
        match run_case(seed, &root, &texts) {
            Ok(c) => *codes.entry(c).or_insert(0) += 1,
            Err(e) => failures.push(e),
        }
    }
    eprintln!("exit statuses (status: runs): {codes:?}");
    assert!(
        failures.is_empty(),
        "{} of {cases} runs failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
