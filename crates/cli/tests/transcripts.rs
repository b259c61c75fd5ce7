//! Every command transcript in README.md and docs/**/*.md is run and its
//! output held against the text (docs/reference/transcripts.md): a figure
//! that moves fails this test instead of going stale.
//!
//! `RTPIPE_BLESS=1 cargo test --release -p rtpipe --test transcripts`
//! rewrites the blocks to the current output, keeping their `...` and
//! `[..]` elisions where they still match; `RTPIPE_TRANSCRIPTS=WORD` runs
//! only the documents whose path contains WORD.

mod pages;
mod transcript;

use pages::{markdown_pages as documents, read_page, repository_root};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};
use transcript::{compare, parse, trim_trailing_blanks, Block};

/// A command that runs longer is stopped and fails its step (a transcript
/// that needs longer belongs in an ignore-reason block).
const STEP_TIME_LIMIT: Duration = Duration::from_secs(300);

/// What checking one document found.
#[derive(Default)]
struct Outcome {
    checked_blocks: usize,
    checked_steps: usize,
    ignored: Vec<String>,
    failures: Vec<String>,
    stale_blocks: usize,
    /// The document's text with its blocks blessed, when any changed.
    blessed: Option<String>,
}

/// A scratch folder to run a document's commands in, seen as the
/// repository root: `examples`, `crates` and `scripts` link to the real
/// ones (inputs), everything a command writes lands in the scratch folder.
fn workdir(root: &Path, document: &Path) -> PathBuf {
    let name = document
        .strip_prefix(root)
        .unwrap_or(document)
        .to_string_lossy()
        .replace(['/', '.'], "_");
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("transcripts")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("docs")).expect("create the scratch folder");
    for linked in ["examples", "crates", "scripts"] {
        std::os::unix::fs::symlink(root.join(linked), dir.join(linked))
            .expect("link an input folder into the scratch folder");
    }
    dir
}

/// Runs one command line with bash in `dir`, the built `rtpipe` first on
/// PATH; stdout and stderr merged as a terminal shows them.
fn run_step(dir: &Path, command: &str) -> Result<Vec<String>, String> {
    let bin = Path::new(env!("CARGO_BIN_EXE_rtpipe"));
    let bin_dir = bin.parent().expect("the binary has a folder");
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let output_file = dir.join(".transcript-output");
    let output = std::fs::File::create(&output_file).map_err(|e| e.to_string())?;
    let mut child = Command::new("bash")
        .arg("-c")
        .arg(format!("exec 2>&1\n{command}"))
        .current_dir(dir)
        .env("PATH", path)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(output)
        .spawn()
        .map_err(|e| format!("cannot run bash: {e}"))?;
    let started = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if started.elapsed() > STEP_TIME_LIMIT => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!("stopped after {} s", STEP_TIME_LIMIT.as_secs()));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(e.to_string()),
        }
    }
    let bytes = std::fs::read(&output_file).map_err(|e| e.to_string())?;
    let _ = std::fs::remove_file(&output_file);
    let mut lines: Vec<String> = String::from_utf8_lossy(&bytes)
        .lines()
        .map(|l| l.trim_end().to_string())
        .collect();
    trim_trailing_blanks(&mut lines);
    Ok(lines)
}

/// Runs a block's steps in order; the blessed text of the block, and
/// whether every step matched.
fn check_block(dir: &Path, block: &Block, label: &str, outcome: &mut Outcome) -> Vec<String> {
    let mut text = vec![block.fence.clone()];
    let mut stale = false;
    for step in &block.steps {
        text.push(format!("$ {}", step.command));
        outcome.checked_steps += 1;
        match run_step(dir, &step.command) {
            Ok(actual) => {
                let comparison = compare(&step.expected, &actual);
                if !comparison.matches {
                    stale = true;
                    outcome.failures.push(format!(
                        "{label}: `$ {}` printed something else:\n--- expected\n{}\n--- printed\n{}\n",
                        step.command,
                        step.expected.join("\n"),
                        actual.join("\n")
                    ));
                }
                text.extend(comparison.blessed);
            }
            Err(e) => {
                stale = true;
                outcome
                    .failures
                    .push(format!("{label}: `$ {}`: {e}", step.command));
                text.extend(step.expected.iter().cloned());
            }
        }
    }
    text.push("```".to_string());
    outcome.stale_blocks += usize::from(stale);
    text
}

fn check_document(root: &Path, document: &Path) -> Outcome {
    let (text, _, shown) = read_page(root, document);
    let mut outcome = Outcome::default();
    let parsed = parse(&text);
    for problem in &parsed.problems {
        outcome.failures.push(format!("{shown}:{problem}"));
    }
    if parsed.blocks.is_empty() {
        return outcome;
    }
    let dir = workdir(root, document);
    let lines: Vec<&str> = text.lines().collect();
    let mut out: Vec<String> = Vec::new();
    let mut copied = 0;
    for block in &parsed.blocks {
        let label = format!("{shown}:{}", block.open + 1);
        out.extend(lines[copied..block.open].iter().map(|l| l.to_string()));
        copied = block.close + 1;
        if let Some(reason) = &block.ignore {
            outcome.ignored.push(format!("{label}: {reason}"));
            out.extend(lines[block.open..copied].iter().map(|l| l.to_string()));
            continue;
        }
        outcome.checked_blocks += 1;
        out.extend(check_block(&dir, block, &label, &mut outcome));
    }
    out.extend(lines[copied..].iter().map(|l| l.to_string()));
    let mut blessed = out.join("\n");
    blessed.push('\n');
    if blessed != text {
        outcome.blessed = Some(blessed);
    }
    let _ = std::fs::remove_dir_all(&dir);
    outcome
}

/// Checks the documents on two threads (the machine's cores), each
/// document's blocks in order (a later block may read what an earlier one
/// wrote).
fn check_all(root: &Path, docs: &[PathBuf]) -> Vec<(PathBuf, Outcome)> {
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(doc) = docs.get(i) else { break };
                let outcome = check_document(root, doc);
                results
                    .lock()
                    .expect("a checker panicked")
                    .push((doc.clone(), outcome));
            });
        }
    });
    let mut results = results.into_inner().expect("a checker panicked");
    results.sort_by(|a, b| a.0.cmp(&b.0));
    results
}

#[test]
fn every_transcript_prints_what_the_docs_say() {
    let root = repository_root();
    let only = std::env::var("RTPIPE_TRANSCRIPTS").unwrap_or_default();
    let bless = std::env::var_os("RTPIPE_BLESS").is_some();
    let docs: Vec<PathBuf> = documents(&root)
        .into_iter()
        .filter(|d| d.to_string_lossy().contains(&only))
        .collect();
    let results = check_all(&root, &docs);
    let (mut blocks, mut steps, mut stale) = (0, 0, 0);
    let mut failures = Vec::new();
    let mut ignored = Vec::new();
    for (doc, outcome) in results {
        blocks += outcome.checked_blocks;
        steps += outcome.checked_steps;
        stale += outcome.stale_blocks;
        ignored.extend(outcome.ignored);
        if bless {
            if let Some(text) = &outcome.blessed {
                std::fs::write(&doc, text).expect("write the blessed document");
            }
        }
        failures.extend(outcome.failures);
    }
    println!(
        "transcripts: {blocks} blocks ({steps} commands) run, {stale} stale, {} not run:",
        ignored.len()
    );
    for line in &ignored {
        println!("  not run: {line}");
    }
    if bless {
        println!("blessed: the stale blocks were rewritten to the current output");
        return;
    }
    assert!(
        failures.is_empty(),
        "{} transcript problem(s) (rewrite with RTPIPE_BLESS=1 after checking the change is intended):\n\n{}",
        failures.len(),
        failures.join("\n")
    );
}

fn lines(text: &str) -> Vec<String> {
    text.lines().map(str::to_string).collect()
}

#[test]
fn elisions_match_what_they_stand_for() {
    assert!(transcript::line_matches("in [..] s (x)", "in 0.21 s (x)"));
    assert!(!transcript::line_matches("in [..] s (x)", "in 0.21 ms (y)"));
    let expected = lines("head\n...\ntail [..]");
    assert!(compare(&expected, &lines("head\na\nb\ntail 1")).matches);
    assert!(compare(&expected, &lines("head\ntail 2")).matches);
    assert!(!compare(&expected, &lines("head\na\nfoot")).matches);
}

#[test]
fn a_bless_keeps_the_elisions_that_still_match() {
    let expected = lines("a\n...\nrow  1  [..]  x\nz");
    let compared = compare(&expected, &lines("a\nb\nc\nrow  2  0.5  x\nz"));
    assert!(!compared.matches);
    assert_eq!(compared.blessed, lines("a\n...\nrow  2  [..]  x\nz"));
    // A long run of lines the page did not show stays unshown; a new
    // block shows everything.
    let shown = compare(&lines("a\nz"), &lines("a\n1\n2\n3\n4\nz"));
    assert_eq!(shown.blessed, lines("a\n...\nz"));
    let new = compare(&[], &lines("a\n1\n2\n3\n4\nz"));
    assert_eq!(new.blessed, lines("a\n1\n2\n3\n4\nz"));
}

#[test]
fn a_transcript_outside_a_console_block_is_a_problem() {
    let parsed = parse("```\n$ rtpipe analyze x.toml\nout\n```\n");
    assert_eq!(parsed.problems.len(), 1, "{:?}", parsed.problems);
    let parsed = parse("```console,ignore-reason=root\n$ rtpipe run x\n```\n");
    assert_eq!(parsed.blocks[0].ignore.as_deref(), Some("root"));
}
