//! The workspace's shape, held by a test (docs/architecture.md states it):
//! no non-test source file over 1,000 lines, no function over 70 lines, and
//! no module import cycle inside any crate.
//!
//! A module `a` imports `b` when its non-test code names `crate::b` (or
//! `b` inside a `crate::{..}` group) outside comments; the crate root, which declares and
//! re-exports modules, is left out. Cycles are strongly connected
//! components of that graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 1000;
const MAX_FN_LINES: usize = 70;

fn crates_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Each crate's `src` directory.
fn crate_sources() -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(crates_dir())
        .into_iter()
        .flatten()
        .flatten()
    {
        let src = e.path().join("src");
        if src.is_dir() {
            out.push((e.file_name().to_string_lossy().into_owned(), src));
        }
    }
    out.sort();
    out
}

/// A file holds only tests (`tests.rs`, `tests_*.rs`, `*/tests/*`).
fn test_only(p: &Path) -> bool {
    let name = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    name == "tests" || name.starts_with("tests_")
}

/// The text before the file's `#[cfg(test)] mod tests`.
fn non_test(text: &str) -> &str {
    text.find("#[cfg(test)]\nmod tests")
        .map_or(text, |i| &text[..i])
}

/// The top-level module a file belongs to (`""` for the crate root).
fn module_of(src: &Path, p: &Path) -> String {
    let rel = p.strip_prefix(src).unwrap_or(p);
    let first = rel
        .components()
        .next()
        .map(|c| c.as_os_str().to_string_lossy().into_owned());
    match first.as_deref() {
        Some("lib.rs") | Some("main.rs") | None => String::new(),
        Some(f) => f.trim_end_matches(".rs").to_string(),
    }
}

/// Identifiers that follow `crate::` in `text`, single or in a `{..}` group.
fn crate_refs(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let body = &group[..group.find('}').unwrap_or(group.len())];
            for part in body.split(',') {
                out.insert(ident(part.trim()));
            }
        } else {
            out.insert(ident(rest));
        }
    }
    out
}

/// The module graph of one crate, root left out.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let files = rust_files(src);
    let modules: BTreeSet<String> = files.iter().map(|p| module_of(src, p)).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for p in &files {
        let a = module_of(src, p);
        if a.is_empty() || test_only(p) {
            continue;
        }
        let text = std::fs::read_to_string(p).unwrap_or_default();
        // Comments (doc links included) import nothing.
        let code: String = non_test(&text)
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .map(|l| format!("{l}\n"))
            .collect();
        let refs = crate_refs(&code);
        let entry = graph.entry(a.clone()).or_default();
        entry.extend(
            refs.into_iter()
                .filter(|b| *b != a && modules.contains(b) && !b.starts_with("tests")),
        );
    }
    graph
}

/// The strongly connected components of more than one module (Tarjan).
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'g> {
        graph: &'g BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        found: Vec<Vec<String>>,
    }
    fn visit<'g>(s: &mut State<'g>, v: &'g str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        for w in s.graph.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low[v].min(lw);
                s.low.insert(v, lv);
            } else if s.stack.contains(&w) {
                let lv = s.low[v].min(s.index[w]);
                s.low.insert(v, lv);
            }
        }
        if s.low[v] == s.index[v] {
            let at = s.stack.iter().rposition(|x| *x == v).unwrap_or(0);
            let comp: Vec<String> = s.stack.drain(at..).map(String::from).collect();
            if comp.len() > 1 {
                s.found.push(comp);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.found
}

#[test]
fn no_module_import_cycle_in_any_crate() {
    let mut found = Vec::new();
    for (name, src) in crate_sources() {
        for c in cycles(&module_graph(&src)) {
            found.push(format!("{name}: {}", c.join(" <-> ")));
        }
    }
    assert!(
        found.is_empty(),
        "module import cycles:\n{}",
        found.join("\n")
    );
}

#[test]
fn no_source_file_over_a_thousand_lines() {
    let mut long = Vec::new();
    for (_, src) in crate_sources() {
        for p in rust_files(&src) {
            let text = std::fs::read_to_string(&p).unwrap_or_default();
            let n = non_test(&text).lines().count();
            if !test_only(&p) && n > MAX_FILE_LINES {
                long.push(format!("{} ({n} lines)", p.display()));
            }
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_FILE_LINES} lines:\n{}",
        long.join("\n")
    );
}

/// The length of every `fn` in `text` that starts a line (after
/// indentation), to its closing brace at the same indentation.
fn long_functions(text: &str) -> Vec<(usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let indent = l.len() - t.len();
        let is_fn = [
            "fn ",
            "pub fn ",
            "pub(crate) fn ",
            "const fn ",
            "pub const fn ",
            "async fn ",
        ]
        .iter()
        .any(|p| t.starts_with(p));
        if !is_fn || t.ends_with(';') {
            continue;
        }
        let close = format!("{}}}", " ".repeat(indent));
        if let Some(end) = lines[i..].iter().position(|x| *x == close) {
            out.push((i + 1, end + 1));
        }
    }
    out.retain(|&(_, n)| n > MAX_FN_LINES);
    out
}

#[test]
fn no_function_over_seventy_lines() {
    let mut long = Vec::new();
    for (_, src) in crate_sources() {
        for p in rust_files(&src) {
            if test_only(&p) {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap_or_default();
            for (line, n) in long_functions(non_test(&text)) {
                long.push(format!("{}:{line} ({n} lines)", p.display()));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines:\n{}",
        long.join("\n")
    );
}

#[test]
fn the_checks_see_what_they_look_for() {
    // A cycle a <-> b and a chain c -> a are told apart.
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("a".into());
    g.entry("c".into()).or_default().insert("a".into());
    let mut c = cycles(&g);
    c.iter_mut().for_each(|x| x.sort());
    assert_eq!(c, vec![vec!["a".to_string(), "b".to_string()]]);
    let refs = crate_refs("use crate::x::Y;\nuse crate::{a::B, c};\n");
    assert_eq!(refs.into_iter().collect::<Vec<_>>(), ["a", "c", "x"]);
    let body: String = (0..80).map(|_| "    x();\n").collect();
    let f = format!("fn long() {{\n{body}}}\nfn short() {{\n}}\n");
    assert_eq!(long_functions(&f), vec![(1, 82)]);
}
