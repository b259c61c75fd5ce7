//! The files rtpipe writes (`design --write`, `simulate --trace/--plot/--gantt`),
//! written one way:
//!
//! - a symlink is followed and its target written (the link stays a link);
//! - an existing path must be a regular file: directories, devices, pipes
//!   and sockets are refused with an error naming the flag and the path
//!   (rtpipe never replaces them, and never writes into them);
//! - the input spec is never overwritten unless the command allows it
//!   (`design --overwrite-spec`), and no other file the command reads
//!   (`--mission`, `--vehicle`, `--criterion`, the file `import` reads:
//!   [`register_input`]) ever is, whatever path names it (symlinks and
//!   hard links are the same file);
//! - the text goes to a fresh temporary file beside the real target, which
//!   is then renamed over it, so the target holds either its old content or
//!   the complete new one; on any error the temporaries are removed.
//!
//! Paths are checked by [`prepare`] before the command does its work, so a
//! bad path is reported at once, not after a long solve: its directory
//! exists, is a directory and takes a new file ([`check_writable`]). A write
//! that fails after the work still prints the work's report
//! (`Answer::after_write`).

use rtpipe_model::Diagnostic;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The files this process reads besides its spec, with the flag that named
/// each: no output replaces them.
static INPUTS: Mutex<Vec<(&'static str, PathBuf)>> = Mutex::new(Vec::new());

/// Registers a file the command reads (named by `flag`): [`prepare`]
/// refuses every output that would replace it.
pub fn register_input(flag: &'static str, path: &Path) {
    if let Ok(mut v) = INPUTS.lock() {
        v.push((flag, path.to_path_buf()));
    }
}

/// An error when `target` (the output `flag` names as `path`) is a
/// registered input.
fn refuse_inputs(flag: &str, path: &Path, target: &Path) -> Result<(), Diagnostic> {
    let Ok(inputs) = INPUTS.lock() else {
        return Ok(());
    };
    match inputs.iter().find(|(_, p)| same_file(target, p)) {
        None => Ok(()),
        Some((by, read)) => Err(err(
            format!(
                "{flag} {} would overwrite {by} {}, a file this command reads",
                path.display(),
                read.display()
            ),
            format!("write to another file, e.g. {flag} {}", example_name(flag)),
        )),
    }
}

/// An output path that cannot be written, or a failed write: the flag and
/// path, and how to fix it.
fn err(msg: String, help: impl Into<String>) -> Diagnostic {
    Diagnostic::error(msg, help)
}

/// A checked output: the flag that named it, the path as given and the real
/// file it writes (symlinks followed, directory canonicalised).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Output {
    pub flag: &'static str,
    pub given: PathBuf,
    pub target: PathBuf,
}

/// The directory of a path ("." for a bare file name).
pub fn parent_dir(p: &Path) -> &Path {
    match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Follows symlinks (at most 40) to the path that will really be written;
/// its directory is canonicalised. The file itself need not exist.
fn resolve(flag: &str, p: &Path) -> Result<PathBuf, Diagnostic> {
    let mut cur = p.to_path_buf();
    let mut hops = 0;
    while let Ok(m) = fs::symlink_metadata(&cur) {
        if !m.file_type().is_symlink() {
            break;
        }
        hops += 1;
        if hops > 40 {
            return Err(err(
                format!("{flag} {}: too many levels of symbolic links", p.display()),
                "point the link at a file",
            ));
        }
        let t = fs::read_link(&cur).map_err(|e| {
            err(
                format!("{flag} {}: cannot read the link: {e}", p.display()),
                "",
            )
        })?;
        cur = if t.is_absolute() {
            t
        } else {
            parent_dir(&cur).join(t)
        };
    }
    let Some(name) = cur.file_name().map(|n| n.to_os_string()) else {
        return Err(err(
            format!("{flag} needs a file name, found `{}`", p.display()),
            format!("write e.g. {flag} out/{}", example_name(flag)),
        ));
    };
    let dir = parent_dir(&cur);
    match fs::canonicalize(dir) {
        Ok(d) if d.is_dir() => Ok(d.join(name)),
        Ok(_) => Err(err(
            format!(
                "{flag} {}: {} is a file, not a directory",
                p.display(),
                dir.display()
            ),
            format!("write into a directory, e.g. {flag} {}", example_name(flag)),
        )),
        Err(_) => Err(err(
            format!(
                "{flag} {}: directory {} does not exist",
                p.display(),
                dir.display()
            ),
            "create the directory first, or write somewhere else",
        )),
    }
}

fn example_name(flag: &str) -> &'static str {
    match flag {
        "--trace" => "trace.json",
        "--plot" => "fig9.svg",
        "--write" => "designed.toml",
        "--log" => "flight.csv",
        "--write-limits" => "limits.toml",
        "--gantt" => "gantt.svg",
        "--export-rt-app" => "rt-app.json",
        "--samples" => "samples.csv",
        "--write-spec" => "measured.toml",
        "OUTFILE" => "spec.toml",
        _ => "out.txt",
    }
}

/// Whether two existing paths are the same file (hard links included).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (fs::metadata(a), fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Checks that `path` (named by `flag`) can be written: see the module
/// documentation. `input` is the spec the command reads; writing over it
/// needs `overwrite_input` (the name of the flag that allows it, if any).
pub fn prepare(
    flag: &'static str,
    path: &Path,
    input: &Path,
    overwrite_input: Option<(bool, &str)>,
) -> Result<Output, Diagnostic> {
    if path.as_os_str().is_empty() {
        return Err(err(
            format!("{flag} needs a file name, found `{}`", path.display()),
            format!("write e.g. {flag} out/{}", example_name(flag)),
        ));
    }
    let target = resolve(flag, path)?;
    if let Ok(m) = fs::metadata(&target) {
        if m.is_dir() {
            return Err(err(
                format!("{flag} {} is a directory", path.display()),
                format!(
                    "give a file name, e.g. {flag} {}",
                    path.join(example_name(flag)).display()
                ),
            ));
        }
        if !m.is_file() {
            return Err(err(
                format!(
                    "{flag} {} is not a regular file (a device, pipe or socket); rtpipe only replaces regular files",
                    path.display()
                ),
                format!(
                    "write to a file and copy it from there, e.g. {flag} {}",
                    example_name(flag)
                ),
            ));
        }
        refuse_inputs(flag, path, &target)?;
        refuse_input_spec(flag, path, &target, input, overwrite_input)?;
    }
    check_writable(flag, path, &target)?;
    Ok(Output {
        flag,
        given: path.to_path_buf(),
        target,
    })
}

/// An error when `target` is the input spec and the command may not
/// replace it (see [`prepare`]).
fn refuse_input_spec(
    flag: &'static str,
    path: &Path,
    target: &Path,
    input: &Path,
    overwrite_input: Option<(bool, &str)>,
) -> Result<(), Diagnostic> {
    if !same_file(target, input) {
        return Ok(());
    }
    match overwrite_input {
        Some((true, _)) => Ok(()),
        Some((false, allow)) => Err(err(
            format!(
                "{flag} {} would overwrite the input spec (its comments and period ranges would be lost)",
                path.display()
            ),
            format!("write to another file, or add {allow} to replace the spec"),
        )),
        None => Err(err(
            format!("{flag} {} would overwrite the input spec", path.display()),
            "write to another file",
        )),
    }
}

/// Checks, before the work, that the directory of `target` (the output
/// `flag` names as `path`) takes a new file: a probe file is created beside
/// it and removed. Asking the file system itself answers for permissions,
/// ACLs and read-only mounts alike, which the mode bits alone do not.
pub fn check_writable(flag: &str, path: &Path, target: &Path) -> Result<(), Diagnostic> {
    let probe = temp_beside(target, "probe");
    match fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = fs::remove_file(&probe);
            Ok(())
        }
        // A stale probe of a crashed run with this process id: the
        // directory took it, so it takes the output.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(err(
            format!(
                "{flag} {}: cannot write in {}: {e}",
                path.display(),
                parent_dir(target).display()
            ),
            "write into a directory you can write, or fix its permissions",
        )),
    }
}

/// Refuses two outputs that write the same file.
pub fn distinct(outs: &[Output]) -> Result<(), Diagnostic> {
    for (k, o) in outs.iter().enumerate() {
        if let Some(other) = outs[..k].iter().find(|q| q.target == o.target) {
            return Err(err(
                format!(
                    "{} and {} both write {}",
                    other.flag,
                    o.flag,
                    o.target.display()
                ),
                "give each output its own file",
            ));
        }
    }
    Ok(())
}

/// The longest file name (bytes) Linux file systems take.
const NAME_MAX: usize = 255;

/// A fresh temporary path beside `target` (same directory, so a rename
/// puts it in place), told apart by `what` and this process. The target's
/// name is cut so that the temporary's stays within [`NAME_MAX`] bytes
/// whatever the target's length (a 250-byte output name is valid).
pub fn temp_beside(target: &Path, what: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = format!(".{}.{what}.tmp", std::process::id());
    let room = NAME_MAX.saturating_sub(suffix.len() + 1);
    let mut cut = name.len().min(room);
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    parent_dir(target).join(format!(".{}{suffix}", &name[..cut]))
}

/// Writes every file to a fresh temporary file beside its real target, then
/// renames them all over their targets. A failed write removes every
/// temporary and changes no target; a failed rename (rare: same directory)
/// keeps the targets renamed before it and removes the other temporaries.
pub fn write_all(files: &[(&Output, &str)]) -> Result<(), Diagnostic> {
    let mut temps: Vec<PathBuf> = Vec::new();
    let cleanup = |temps: &[PathBuf]| {
        for t in temps {
            let _ = fs::remove_file(t);
        }
    };
    for (k, (out, text)) in files.iter().enumerate() {
        let tmp = temp_beside(&out.target, &k.to_string());
        let written = injected_failure()
            .and_then(|()| {
                fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(&tmp)
            })
            .and_then(|mut f| {
                // Keep the permissions of a file being replaced.
                if let Ok(m) = fs::metadata(&out.target) {
                    f.set_permissions(m.permissions())?;
                }
                f.write_all(text.as_bytes())?;
                f.sync_all()
            });
        if let Err(e) = written {
            // Only a temporary this call created is removed.
            if e.kind() != std::io::ErrorKind::AlreadyExists {
                let _ = fs::remove_file(&tmp);
            }
            cleanup(&temps);
            return Err(err(
                format!("{} {}: cannot write: {e}", out.flag, out.given.display()),
                "check that the directory is writable and the disk not full",
            ));
        }
        temps.push(tmp);
    }
    for (k, ((out, _), tmp)) in files.iter().zip(&temps).enumerate() {
        if let Err(e) = fs::rename(tmp, &out.target) {
            cleanup(&temps[k..]);
            return Err(err(
                format!("{} {}: cannot write: {e}", out.flag, out.given.display()),
                "check that the directory is writable",
            ));
        }
    }
    Ok(())
}

/// A write error the tests inject (`RTPIPE_TEST_WRITE_FAILS` set): a write
/// that fails after the work cannot be provoked from outside on cue, and
/// that the work's result is still printed then must be tested.
fn injected_failure() -> std::io::Result<()> {
    match std::env::var_os("RTPIPE_TEST_WRITE_FAILS") {
        Some(_) => Err(std::io::Error::other("RTPIPE_TEST_WRITE_FAILS is set")),
        None => Ok(()),
    }
}

/// Checks the output paths again (they may have changed during the run) and
/// writes them all or none (see [`write_all`]).
pub fn write_files(
    spec: &Path,
    files: &[(&'static str, PathBuf, String)],
) -> Result<(), Diagnostic> {
    let mut outs = Vec::new();
    for (flag, path, _) in files {
        outs.push(prepare(flag, path, spec, None)?);
    }
    let pairs: Vec<(&Output, &str)> = outs
        .iter()
        .zip(files)
        .map(|(o, (_, _, text))| (o, text.as_str()))
        .collect();
    write_all(&pairs)
}

/// Checks a `--plot` directory before the work: it is a directory that
/// takes new files, or it is missing and its nearest existing ancestor is
/// one (where [`ensure_dir`] will create it).
pub fn check_dir(dir: &Path) -> Result<(), Diagnostic> {
    if let Ok(m) = fs::metadata(dir) {
        if !m.is_dir() {
            return Err(err(
                format!(
                    "--plot {} exists and is not a directory: --plot names the directory the plots are written into",
                    dir.display()
                ),
                "give a new or existing directory, e.g. --plot plots",
            ));
        }
        return check_writable("--plot", dir, &dir.join("plot"));
    }
    let ancestor = dir
        .ancestors()
        .skip(1)
        .map(|a| {
            if a.as_os_str().is_empty() {
                Path::new(".")
            } else {
                a
            }
        })
        .find(|a| fs::metadata(a).is_ok());
    match ancestor {
        Some(a) if !a.is_dir() => Err(err(
            format!(
                "--plot {}: {} is a file, not a directory",
                dir.display(),
                a.display()
            ),
            "give a new or existing directory, e.g. --plot plots",
        )),
        Some(a) => check_writable("--plot", dir, &a.join("plot")),
        // Nothing of the path exists (not even `/`): creating it fails and
        // says why.
        None => Ok(()),
    }
}

/// Creates the `--plot` directory when it is missing.
pub fn ensure_dir(dir: &Path) -> Result<(), Diagnostic> {
    if dir.is_dir() {
        return Ok(());
    }
    check_dir(dir)?;
    std::fs::create_dir_all(dir).map_err(|e| {
        Diagnostic::error(
            format!("--plot {}: cannot create the directory: {e}", dir.display()),
            "name a directory you can write",
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rtpipe-output-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        let _ = fs::create_dir_all(&d);
        d
    }

    #[test]
    fn writes_through_a_symlink_and_keeps_it() {
        let d = scratch("link");
        let real = d.join("real.svg");
        let link = d.join("link.svg");
        let _ = fs::write(&real, "old");
        #[cfg(unix)]
        {
            let _ = std::os::unix::fs::symlink("real.svg", &link);
            let input = d.join("spec.toml");
            let o = match prepare("--plot", &link, &input, None) {
                Ok(o) => o,
                Err(e) => panic!("{e}"),
            };
            assert!(write_all(&[(&o, "new")]).is_ok());
            assert!(fs::symlink_metadata(&link).is_ok_and(|m| m.file_type().is_symlink()));
            assert_eq!(fs::read_to_string(&real).ok().as_deref(), Some("new"));
            // Nothing else is left in the directory.
            assert_eq!(fs::read_dir(&d).map(|r| r.count()).unwrap_or(0), 2);
        }
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn refuses_non_regular_files_and_the_input() {
        let d = scratch("refuse");
        let input = d.join("spec.toml");
        let _ = fs::write(&input, "x");
        let e = prepare("--write", &d, &input, Some((false, "--overwrite-spec")));
        assert!(e.is_err_and(|e| e.message.contains("is a directory")));
        #[cfg(unix)]
        {
            let e = prepare("--write", Path::new("/dev/null"), &input, None);
            assert!(e.is_err_and(|e| e.message.contains("not a regular file")));
        }
        let e = prepare("--write", &input, &input, Some((false, "--overwrite-spec")));
        assert!(e.is_err_and(|e| e.help.is_some_and(|h| h.contains("--overwrite-spec"))));
        assert!(prepare("--write", &input, &input, Some((true, "--overwrite-spec"))).is_ok());
        let e = prepare("--write", &d.join("no/such/dir/x.toml"), &input, None);
        assert!(e.is_err_and(|e| e.message.contains("does not exist")));
        let _ = fs::remove_dir_all(&d);
    }
}
