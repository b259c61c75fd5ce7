//! Scratch directories that leave the machine as it was: a test's files go
//! with the test, unless it fails.
//!
//! [`Scratch::new`] makes a fresh, empty `rtpipe-TAG-PID` in the system's
//! temporary directory (`TMPDIR`, else `/tmp`). Dropping the guard removes
//! it, with everything in it — except when the drop happens while the
//! thread panics (a failing assertion unwinds through the test), so that a
//! failing test's files can still be inspected: the guard then keeps the
//! directory and says where it is on stderr, which the test harness shows
//! with the failure.

use std::ffi::OsStr;
use std::ops::Deref;
use std::path::{Path, PathBuf};

/// A fresh, empty directory, removed when the guard is dropped (kept, and
/// its path printed, when the test fails). Dereferences to its [`Path`].
#[derive(Debug)]
#[must_use = "the directory is removed when the guard is dropped"]
pub struct Scratch {
    /// The directory made, and removed by the drop.
    root: PathBuf,
    /// What the guard dereferences to: `root`, or a path inside it.
    path: PathBuf,
}

impl Scratch {
    /// Makes `rtpipe-TAG-PID` in the temporary directory, empty (a
    /// leftover of a killed run with the same pid is removed first). `tag`
    /// must be unique among the tests of one test binary, which run in one
    /// process in parallel.
    pub fn new(tag: &str) -> Self {
        let path = std::env::temp_dir().join(format!("rtpipe-{tag}-{}", std::process::id()));
        // A leftover is only possible after a run that was killed (or
        // failed) with this same pid: it is stale.
        let _ = std::fs::remove_dir_all(&path);
        if let Err(e) = std::fs::create_dir_all(&path) {
            panic!(
                "cannot create the scratch directory {}: {e}",
                path.display()
            );
        }
        Scratch {
            root: path.clone(),
            path,
        }
    }

    /// The same guard (it still removes the whole directory), dereferencing
    /// to `name` inside it: for a helper that returns the path of a file or
    /// directory it prepared (or that a command will write) together with
    /// what keeps it alive. Makes nothing.
    pub fn within(mut self, name: &str) -> Self {
        self.path = self.root.join(name);
        self
    }

    /// The path (the directory, or the one [`Scratch::within`] chose).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The path as UTF-8 text, for a command line (the test fails if the
    /// temporary directory's name is not UTF-8).
    pub fn text(&self) -> &str {
        match self.path.to_str() {
            Some(s) => s,
            None => panic!("the scratch path {} is not UTF-8", self.path.display()),
        }
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!(
                "kept the failing test's scratch directory {} (remove it when done)",
                self.root.display()
            );
            return;
        }
        // Nothing to do if the test removed it itself; any other failure
        // is worth a line, not a second panic during the drop.
        match std::fs::remove_dir_all(&self.root) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => eprintln!("cannot remove {}: {e}", self.root.display()),
        }
    }
}

impl Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<OsStr> for Scratch {
    fn as_ref(&self) -> &OsStr {
        self.path.as_os_str()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_passing_tests_directory_goes_with_its_guard() {
        let s = Scratch::new("testkit-scratch-pass");
        let kept = s.path().to_path_buf();
        std::fs::create_dir_all(s.join("a/b")).expect("a subdirectory");
        std::fs::write(s.join("a/b/f.txt"), "x").expect("a file");
        assert!(kept.is_dir());
        drop(s);
        assert!(!kept.exists(), "{} is left", kept.display());
    }

    #[test]
    fn a_failing_tests_directory_is_kept_for_inspection() {
        let path = std::env::temp_dir().join(format!(
            "rtpipe-testkit-scratch-fail-{}",
            std::process::id()
        ));
        let unwound = std::panic::catch_unwind(|| {
            let s = Scratch::new("testkit-scratch-fail");
            std::fs::write(s.join("evidence.txt"), "x").expect("a file");
            panic!("the test fails");
        });
        assert!(unwound.is_err());
        let kept = path.join("evidence.txt").is_file();
        let _ = std::fs::remove_dir_all(&path);
        assert!(kept, "{} was removed", path.display());
    }

    #[test]
    fn a_guard_within_removes_the_whole_directory() {
        let out = Scratch::new("testkit-scratch-within").within("out");
        let root = out.parent().map(Path::to_path_buf).expect("a parent");
        assert!(out.ends_with("out") && !out.exists());
        std::fs::create_dir_all(out.path()).expect("made");
        assert_eq!(out.text(), out.path().to_string_lossy());
        drop(out);
        assert!(!root.exists(), "{} is left", root.display());
    }

    #[test]
    fn a_directory_the_test_removed_itself_is_no_error() {
        let s = Scratch::new("testkit-scratch-gone");
        std::fs::remove_dir_all(s.path()).expect("removed");
    }

    #[test]
    fn a_stale_leftover_is_emptied() {
        let first = Scratch::new("testkit-scratch-stale");
        std::fs::write(first.join("old.txt"), "x").expect("a file");
        std::mem::forget(first); // as if the run had been killed
        let again = Scratch::new("testkit-scratch-stale");
        assert_eq!(
            std::fs::read_dir(again.path()).map(|d| d.count()).ok(),
            Some(0)
        );
    }
}
