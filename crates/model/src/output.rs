//! The one way rtpipe writes a file (`design --write`, `simulate
//! --trace/--plot/--gantt`, `generate`, `import`, a campaign's shards and
//! its `_campaign.toml`):
//!
//! - the content goes to a fresh temporary file beside the real target,
//!   created exclusively ([`write_temp`]: `O_CREAT | O_EXCL`, so a file or
//!   a symlink someone planted at a temporary's name is never opened,
//!   followed or truncated; the next name is tried instead), synced, and
//!   renamed over the target, so the target holds either its old content
//!   or the complete new one; on any error the temporaries this call
//!   created are removed, and nothing else;
//! - the rename replaces the target's directory entry: a symlink at the
//!   target itself is replaced, not followed, unless the command resolved
//!   it first ([`prepare`] does, below).
//!
//! A command's output paths (named by flags) are checked by [`prepare`]
//! before the command does its work, so a bad path is reported at once,
//! not after a long solve (its directory exists, is a directory and takes
//! a new file: [`check_writable`]; a write that fails after the work still
//! prints the work's report, the cli's `Answer::after_write`):
//!
//! - a symlink is followed and its target written (the link stays a link);
//! - an existing path must be a regular file: directories, devices, pipes
//!   and sockets are refused with an error naming the flag and the path
//!   (rtpipe never replaces them, and never writes into them);
//! - the input spec is never overwritten unless the command allows it
//!   (`design --overwrite-spec`), and no other file the command reads
//!   (`--mission`, `--vehicle`, `--criterion`, the file `import` reads:
//!   [`register_input`]) ever is, whatever path names it (symlinks and
//!   hard links are the same file).

use crate::Diagnostic;
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
    /// The flag (or argument) that named the output.
    pub flag: &'static str,
    /// The path as the user gave it (for messages).
    pub given: PathBuf,
    /// The file really written.
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
        "--margins-csv" => "margins.csv",
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

/// A temporary path beside `target` (same directory, so a rename puts it
/// in place), told apart by `what` and this process. The name is
/// predictable: open it only exclusively ([`write_temp`] does).
///
/// The target's name is cut so that the temporary's stays within
/// [`NAME_MAX`] bytes whatever the target's length (a 250-byte output name
/// is valid).
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

/// The longest file name (bytes) Linux file systems take.
const NAME_MAX: usize = 255;

/// How many names [`write_temp`] tries before it gives up: a name taken
/// (by a file of a crashed run, or a link planted there) costs one try.
pub const TEMP_TRIES: u32 = 16;

/// The names [`write_temp`] may use for `target` and `what`, in order.
pub fn temp_names<'a>(target: &'a Path, what: &'a str) -> impl Iterator<Item = PathBuf> + 'a {
    (0..TEMP_TRIES).map(move |k| match k {
        0 => temp_beside(target, what),
        _ => temp_beside(target, &format!("{what}-{k}")),
    })
}

/// Creates a fresh temporary beside `target` exclusively (`O_CREAT |
/// O_EXCL`: never an existing file, never through a symlink), with the
/// permissions of the file it will replace. The temporaries a killed
/// rtpipe left in that directory go first ([`remove_stale_temps`]).
pub fn create_temp(target: &Path, what: &str) -> std::io::Result<(PathBuf, fs::File)> {
    remove_stale_temps(parent_dir(target));
    for tmp in temp_names(target, what) {
        match fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => {
                // Keep the permissions of a file being replaced.
                if let Ok(m) = fs::metadata(target) {
                    if let Err(e) = f.set_permissions(m.permissions()) {
                        let _ = fs::remove_file(&tmp);
                        return Err(e);
                    }
                }
                return Ok((tmp, f));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::AlreadyExists,
        format!(
            "every temporary name beside it is taken (files named {}*)",
            temp_beside(target, what).display()
        ),
    ))
}

/// Removes from `dir` every temporary of this writer's making
/// (`.NAME.PID.WHAT.tmp`, [`temp_owner`]) whose process is gone: a stop
/// signal or an error removes its own, a SIGKILL cannot. A process of
/// another pid namespace sharing the directory would look gone; rtpipe
/// writes are not meant to share one.
///
/// Each directory is swept once per process: what it clears was left by
/// runs before this one, and a campaign writing thousands of shards into
/// one folder would otherwise read the whole folder at every shard.
fn remove_stale_temps(dir: &Path) {
    static SWEPT: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    {
        let mut swept = SWEPT.lock().unwrap_or_else(|e| e.into_inner());
        if swept.iter().any(|d| d == dir) {
            return;
        }
        swept.push(dir.to_path_buf());
    }
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

/// The pid in a temporary's name (`.NAME.PID.WHAT.tmp`, WHAT one of the
/// writers' tags — a number, `chainN`, `joined`, `shard`, `config`, `probe` —
/// possibly with [`temp_names`]' `-K`); `None` for any other name and for
/// this process' own.
fn temp_owner(name: &str) -> Option<u32> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (rest, what) = inner.rsplit_once('.')?;
    let (_, pid) = rest.rsplit_once('.')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let tag = match what.rsplit_once('-') {
        Some((tag, try_k)) if digits(try_k) => tag,
        _ => what,
    };
    let known = digits(tag)
        || ["joined", "shard", "config", "probe"].contains(&tag)
        || tag.strip_prefix("chain").is_some_and(digits);
    let pid: u32 = pid.parse().ok().filter(|_| digits(pid))?;
    (known && pid != std::process::id()).then_some(pid)
}

/// Writes a fresh temporary beside `target` (see [`create_temp`]): `fill`
/// writes the content, then it is synced. Returns the temporary's path and
/// what `fill` returned; on any error the temporary is removed.
pub fn write_temp<T>(
    target: &Path,
    what: &str,
    fill: impl FnOnce(&mut fs::File) -> std::io::Result<T>,
) -> std::io::Result<(PathBuf, T)> {
    let (tmp, mut file) = create_temp(target, what)?;
    match fill(&mut file).and_then(|v| file.sync_all().map(|()| v)) {
        Ok(v) => Ok((tmp, v)),
        Err(e) => {
            // Only the temporary this call created is removed.
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Writes `target` whole or not at all: `fill` writes the content into a
/// fresh temporary ([`write_temp`]), which is then renamed over `target`.
/// On any error `target` is unchanged and the temporary removed.
pub fn write_atomically<T>(
    target: &Path,
    what: &str,
    fill: impl FnOnce(&mut fs::File) -> std::io::Result<T>,
) -> std::io::Result<T> {
    let (tmp, value) = write_temp(target, what, fill)?;
    if let Err(e) = fs::rename(&tmp, target) {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    Ok(value)
}

/// Writes every file to a fresh temporary beside its real target
/// ([`write_temp`]), then renames them all over their targets. A failed
/// write removes every temporary and changes no target; a failed rename
/// (rare: same directory) keeps the targets renamed before it and removes
/// the other temporaries.
pub fn write_all(files: &[(&Output, &str)]) -> Result<(), Diagnostic> {
    let mut temps: Vec<PathBuf> = Vec::new();
    let cleanup = |temps: &[PathBuf]| {
        for t in temps {
            let _ = fs::remove_file(t);
        }
    };
    for (k, (out, text)) in files.iter().enumerate() {
        let written = injected_failure().and_then(|()| {
            write_temp(&out.target, &k.to_string(), |f| {
                f.write_all(text.as_bytes())
            })
        });
        match written {
            Ok((tmp, ())) => temps.push(tmp),
            Err(e) => {
                cleanup(&temps);
                return Err(err(
                    format!("{} {}: cannot write: {e}", out.flag, out.given.display()),
                    "check that the directory is writable and the disk not full",
                ));
            }
        }
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

/// A CSV field (RFC 4180): quoted when it holds a comma, quote or newline.
/// A field a spreadsheet would run as a formula (it begins with `=`, `+`,
/// `-`, `@`, tab or carriage return) gets a leading `'` and quotes, as
/// OWASP's CSV-injection guidance says: names come from the spec, which
/// may not be the reader's own.
pub fn csv_field(s: &str) -> String {
    let formula = s.starts_with(['=', '+', '-', '@', '\t', '\r']);
    if formula {
        format!("\"'{}\"", s.replace('"', "\"\""))
    } else if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> rtpipe_testkit::Scratch {
        rtpipe_testkit::Scratch::new(&format!("model-output-{tag}"))
    }

    #[test]
    fn only_the_temporaries_of_its_own_making_are_stale_candidates() {
        assert_eq!(temp_owner(".s.csv.4242.chain0.tmp"), Some(4242));
        assert_eq!(temp_owner(".s.csv.4242.joined.tmp"), Some(4242));
        assert_eq!(temp_owner(".out.toml.17.0.tmp"), Some(17));
        assert_eq!(temp_owner(".shard-3.parquet.17.shard-2.tmp"), Some(17));
        assert_eq!(temp_owner(".s.csv.4242.mine.tmp"), None);
        assert_eq!(temp_owner("s.csv.4242.0.tmp"), None);
        assert_eq!(temp_owner(".s.csv.42x.0.tmp"), None);
        let own = format!(".s.csv.{}.0.tmp", std::process::id());
        assert_eq!(temp_owner(&own), None);
    }

    /// A temporary of a process that is gone (a SIGKILLed run) is removed
    /// by the next write into its directory; a live process' is kept.
    #[test]
    fn a_dead_process_temporaries_go_at_the_next_write() {
        let d = scratch("stale");
        // pid_max is at most 2^22: this pid cannot be running.
        let dead = d.join(".out.csv.4194399.chain0.tmp");
        let live = d.join(format!(".out.csv.{}.chain0.tmp", std::process::id()));
        let init = d.join(".out.csv.1.chain0.tmp");
        for f in [&dead, &live, &init] {
            let _ = fs::write(f, "partial");
        }
        if let Err(e) = write_atomically(&d.join("other.toml"), "config", |f| {
            std::io::Write::write_all(f, b"x")
        }) {
            panic!("{e}");
        }
        assert!(!dead.exists(), "a dead process' temporary stayed");
        assert!(
            live.exists() && init.exists(),
            "a live process' temporary went"
        );
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

    /// A link planted at every name the writer might use is never
    /// followed: its target keeps its content, and the write fails with a
    /// message; a link at the first name only costs one try.
    #[cfg(unix)]
    #[test]
    fn planted_links_at_temporary_names_are_never_followed() {
        let d = scratch("planted");
        let victim = d.join("victim");
        let _ = fs::write(&victim, "precious");
        let target = d.join("out.parquet");
        let names: Vec<PathBuf> = temp_names(&target, "shard").collect();
        assert_eq!(names.len() as u32, TEMP_TRIES);
        for n in &names {
            let _ = std::os::unix::fs::symlink(&victim, n);
        }
        let r = write_atomically(&target, "shard", |f| f.write_all(b"new"));
        assert!(r.is_err_and(|e| e.to_string().contains("temporary name")));
        assert_eq!(
            fs::read_to_string(&victim).ok().as_deref(),
            Some("precious")
        );
        assert!(!target.exists());
        let _ = fs::remove_file(&names[1]);
        let r = write_atomically(&target, "shard", |f| f.write_all(b"new"));
        assert!(r.is_ok());
        assert_eq!(fs::read_to_string(&target).ok().as_deref(), Some("new"));
        assert_eq!(
            fs::read_to_string(&victim).ok().as_deref(),
            Some("precious")
        );
        // write_all's names too.
        let o = Output {
            flag: "--write",
            given: d.join("x.toml"),
            target: d.join("x.toml"),
        };
        for n in temp_names(&o.target, "0") {
            let _ = std::os::unix::fs::symlink(&victim, n);
        }
        assert!(write_all(&[(&o, "new")]).is_err());
        assert_eq!(
            fs::read_to_string(&victim).ok().as_deref(),
            Some("precious")
        );
        let _ = fs::remove_dir_all(&d);
    }

    /// A failed fill leaves neither the target changed nor a temporary.
    #[test]
    fn a_failed_write_leaves_nothing() {
        let d = scratch("failed");
        let target = d.join("t.txt");
        let _ = fs::write(&target, "old");
        let r = write_atomically(&target, "x", |f| {
            f.write_all(b"half")?;
            Err::<(), _>(std::io::Error::other("disk full"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read_to_string(&target).ok().as_deref(), Some("old"));
        assert_eq!(fs::read_dir(&d).map(|r| r.count()).unwrap_or(0), 1);
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
