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
//! bad path is reported at once, not after a long solve.

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
        _ => Err(err(
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
        if same_file(&target, input) {
            match overwrite_input {
                Some((true, _)) => {}
                Some((false, allow)) => {
                    return Err(err(
                        format!(
                            "{flag} {} would overwrite the input spec (its comments and period ranges would be lost)",
                            path.display()
                        ),
                        format!("write to another file, or add {allow} to replace the spec"),
                    ))
                }
                None => {
                    return Err(err(
                        format!("{flag} {} would overwrite the input spec", path.display()),
                        "write to another file",
                    ))
                }
            }
        }
    }
    Ok(Output {
        flag,
        given: path.to_path_buf(),
        target,
    })
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

/// A fresh temporary path beside `target` (same directory, so a rename
/// puts it in place), told apart by `what` and this process. The
/// temporaries an rtpipe killed by SIGKILL left in that directory (it ran
/// no clean-up) go first ([`remove_stale_temps`]).
pub fn temp_beside(target: &Path, what: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = parent_dir(target);
    remove_stale_temps(dir);
    dir.join(format!(".{name}.{}.{what}.tmp", std::process::id()))
}

/// Removes from `dir` every temporary of [`temp_beside`]'s making
/// (`.NAME.PID.WHAT.tmp`) whose process is gone: a stop signal or an error
/// removes its own, a SIGKILL cannot. A process of another pid namespace
/// sharing the directory would look gone; rtpipe writes are not meant to
/// share one.
fn remove_stale_temps(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.filter_map(Result::ok) {
        let name = e.file_name();
        let Some(pid) = name.to_str().and_then(temp_owner) else {
            continue;
        };
        let regular = e.file_type().is_ok_and(|t| t.is_file());
        if regular && !Path::new("/proc").join(pid.to_string()).exists() {
            let _ = fs::remove_file(e.path());
        }
    }
}

/// The pid in a temporary's name (`.NAME.PID.WHAT.tmp`, WHAT a number,
/// `chainN` or `joined`); `None` for any other name.
fn temp_owner(name: &str) -> Option<u32> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (rest, what) = inner.rsplit_once('.')?;
    let (_, pid) = rest.rsplit_once('.')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let known = digits(what) || what == "joined" || what.strip_prefix("chain").is_some_and(digits);
    let pid: u32 = pid.parse().ok().filter(|_| digits(pid))?;
    (known && pid != std::process::id()).then_some(pid)
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
        let written = fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
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

/// Refuses a `--plot` directory that exists as something else (a file).
pub fn check_dir(dir: &Path) -> Result<(), Diagnostic> {
    match fs::metadata(dir) {
        Ok(m) if !m.is_dir() => Err(err(
            format!(
                "--plot {} exists and is not a directory: --plot names the directory the plots are written into",
                dir.display()
            ),
            "give a new or existing directory, e.g. --plot plots",
        )),
        _ => Ok(()),
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
    fn only_the_temporaries_of_its_own_making_are_stale_candidates() {
        assert_eq!(temp_owner(".s.csv.4242.chain0.tmp"), Some(4242));
        assert_eq!(temp_owner(".s.csv.4242.joined.tmp"), Some(4242));
        assert_eq!(temp_owner(".out.toml.17.0.tmp"), Some(17));
        assert_eq!(temp_owner(".s.csv.4242.mine.tmp"), None);
        assert_eq!(temp_owner("s.csv.4242.0.tmp"), None);
        assert_eq!(temp_owner(".s.csv.42x.0.tmp"), None);
        let own = format!(".s.csv.{}.0.tmp", std::process::id());
        assert_eq!(temp_owner(&own), None);
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
