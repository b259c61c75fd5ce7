//! The repository's Markdown pages, one place for the tests that read
//! them all (the transcripts and the book's links).

use std::path::{Path, PathBuf};

/// The repository's root, seen from the cli crate's tests.
pub fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// README.md and every Markdown file under docs/ (the book's pages,
/// SUMMARY.md among them), sorted.
pub fn markdown_pages(root: &Path) -> Vec<PathBuf> {
    let mut found = vec![root.join("README.md")];
    let mut folders = vec![root.join("docs")];
    while let Some(folder) = folders.pop() {
        let entries =
            std::fs::read_dir(&folder).unwrap_or_else(|e| panic!("read {}: {e}", folder.display()));
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// A page's text, its folder (what its relative links start from) and its
/// path from the root (what a failure names).
pub fn read_page(root: &Path, file: &Path) -> (String, PathBuf, String) {
    let text =
        std::fs::read_to_string(file).unwrap_or_else(|e| panic!("read {}: {e}", file.display()));
    let folder = file.parent().expect("a file has a folder").to_path_buf();
    let shown = file
        .strip_prefix(root)
        .unwrap_or(file)
        .display()
        .to_string();
    (text, folder, shown)
}
