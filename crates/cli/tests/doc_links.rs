//! Every relative link in README.md and docs/**/*.md (the book's pages,
//! its SUMMARY.md among them) names a file that exists: mdBook builds a
//! page with a dead link without a word, so this test is the book's link
//! check.

mod pages;

use pages::{markdown_pages as markdown_files, read_page, repository_root};
use std::path::Path;

/// The targets of the inline links `[text](target)` of a line, code spans
/// and fenced code aside by the caller.
fn link_targets(line: &str) -> Vec<&str> {
    let mut targets = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        let Some(end) = after.find(')') else { break };
        targets.push(&after[..end]);
        rest = &after[end..];
    }
    targets
}

/// `Some(path)` for a link to a file of the repository (not a web address
/// nor an anchor in the same page), its `#fragment` dropped.
fn local_path(target: &str) -> Option<&str> {
    let target = target.split_whitespace().next()?;
    if target.contains("://") || target.starts_with('#') || target.starts_with("mailto:") {
        return None;
    }
    Some(target.split('#').next().unwrap_or(target))
}

/// The dead links of one file, each as `file:line: target`.
fn dead_links(root: &Path, file: &Path) -> Vec<String> {
    let (text, folder, shown) = read_page(root, file);
    let mut dead = Vec::new();
    let mut in_fence = false;
    for (number, line) in text.lines().enumerate() {
        if line.starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        for target in link_targets(line).into_iter().filter_map(local_path) {
            if !folder.join(target).exists() {
                dead.push(format!("{shown}:{}: {target}", number + 1));
            }
        }
    }
    dead
}

#[test]
fn every_relative_link_in_the_docs_names_a_file() {
    let root = repository_root();
    let files = markdown_files(&root);
    assert!(
        files.iter().any(|f| f.ends_with("docs/SUMMARY.md")),
        "the book's docs/SUMMARY.md is missing"
    );
    let dead: Vec<String> = files.iter().flat_map(|f| dead_links(&root, f)).collect();
    assert!(
        dead.is_empty(),
        "{} dead link(s):\n{}",
        dead.len(),
        dead.join("\n")
    );
}

/// The broken `{{#include FILE:ANCHOR}}` directives of one file (mdBook
/// includes nothing for an anchor it cannot find, silently).
fn broken_includes(root: &Path, file: &Path) -> Vec<String> {
    let (text, folder, shown) = read_page(root, file);
    let mut broken = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let Some(directive) = line
            .trim()
            .strip_prefix("{{#include ")
            .and_then(|d| d.strip_suffix("}}"))
        else {
            continue;
        };
        let (path, anchor) = directive.split_once(':').unwrap_or((directive, ""));
        let place = format!("{shown}:{}: {directive}", number + 1);
        let Ok(included) = std::fs::read_to_string(folder.join(path)) else {
            broken.push(format!("{place}: no such file"));
            continue;
        };
        let has = |mark: &str| included.lines().any(|l| l.contains(mark));
        let anchored = has(&format!("ANCHOR: {anchor} ")) && has(&format!("ANCHOR_END: {anchor} "));
        if !anchor.is_empty() && !anchored {
            broken.push(format!("{place}: no ANCHOR/ANCHOR_END pair `{anchor}`"));
        }
    }
    broken
}

#[test]
fn every_include_of_the_book_finds_its_file_and_anchor() {
    let root = repository_root();
    let broken: Vec<String> = markdown_files(&root)
        .iter()
        .flat_map(|f| broken_includes(&root, f))
        .collect();
    assert!(
        broken.is_empty(),
        "broken include(s):\n{}",
        broken.join("\n")
    );
}

#[test]
fn the_link_finder_finds_links_and_skips_web_addresses() {
    let line = "see [a](guide/a.md#x), [b](https://x.y) and [c](#here)";
    let targets: Vec<&str> = link_targets(line)
        .into_iter()
        .filter_map(local_path)
        .collect();
    assert_eq!(targets, ["guide/a.md"]);
}
