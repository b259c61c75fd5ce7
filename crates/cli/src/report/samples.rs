//! One row per sample (`--samples FILE.csv` of `simulate`, `fly` and
//! `run`): every chain's head samples with the instants that end their
//! latencies, for pandas, polars or a spreadsheet.

use crate::output::{self, Output};
use rtpipe_joblog::{samples, RowSink};
// The rows' CSV is the job log's (built optimised: it runs per sample).
pub use rtpipe_joblog::samples::{samples_csv, HEADER};
use rtpipe_model::{Diagnostic, Spec};
use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// `--samples` written as the run makes the rows: each chain's rows go to
/// a temporary file beside the target as they complete, and
/// [`finish`](SamplesFile::finish) joins them (header, then chain by
/// chain, as [`samples_csv`]) into one more temporary that
/// [`commit`](SamplesFile::commit) renames over the target. Memory holds
/// only the rows in flight, whatever the run's length.
pub struct SamplesFile {
    out: Output,
    parts: Arc<Mutex<Parts>>,
}

struct Parts {
    labels: Vec<String>,
    files: Vec<(PathBuf, BufWriter<File>)>,
    rows: u64,
    error: Option<std::io::Error>,
}

impl SamplesFile {
    /// `--samples PATH` (checked as every output flag is) opened for a run
    /// of `spec`, read from `spec_path`; `None` without the flag. `hooks`
    /// with a stop flag means the caller owns Ctrl-C (the Python package):
    /// then a stop unwinds the run and dropping the file removes its
    /// temporaries; else Ctrl-C, SIGTERM and SIGHUP are caught here.
    pub fn open(
        path: Option<&PathBuf>,
        spec_path: &std::path::Path,
        spec: &Spec,
        hooks: &crate::command::Hooks,
    ) -> Result<Option<SamplesFile>, Diagnostic> {
        let Some(path) = path else { return Ok(None) };
        let out = output::prepare("--samples", path, spec_path, None)?;
        if hooks.stop.is_none() {
            rtpipe_runtime::sys::catch_stop_signals();
        }
        SamplesFile::create(out, spec).map(Some)
    }

    /// One temporary per chain beside `out`'s target. A stop signal, when it is
    /// caught ([`SamplesFile::open`]), lets [`stop_if_interrupted`] take
    /// them away; they also go when the file is dropped unfinished.
    pub fn create(out: Output, spec: &Spec) -> Result<SamplesFile, Diagnostic> {
        let mut files = Vec::with_capacity(spec.chains.len());
        for c in 0..spec.chains.len() {
            // Exclusively created: never through a link planted at the name.
            match output::create_temp(&out.target, &format!("chain{c}")) {
                Ok((path, f)) => {
                    register(&path);
                    files.push((path, BufWriter::new(f)));
                }
                Err(e) => {
                    files
                        .iter()
                        .for_each(|(p, _)| drop(std::fs::remove_file(p)));
                    return Err(cannot(&out, &e));
                }
            }
        }
        let labels = (0..spec.chains.len())
            .map(|c| spec.chain_label(c))
            .collect();
        let parts = Parts {
            labels,
            files,
            rows: 0,
            error: None,
        };
        Ok(SamplesFile {
            out,
            parts: Arc::new(Mutex::new(parts)),
        })
    }

    /// Where the run hands its rows.
    pub fn sink(&self) -> RowSink {
        let parts = self.parts.clone();
        Box::new(move |c, r| {
            let Ok(mut p) = parts.lock() else { return };
            let p = &mut *p;
            p.rows += 1;
            if let Err(e) = samples::write_row(&mut p.files[c].1, &p.labels[c], r) {
                p.error.get_or_insert(e);
            }
        })
    }

    /// Joins the parts into one temporary beside the target: the rows
    /// written, and that temporary (not yet in place).
    fn finish(self) -> Result<Prepared, Diagnostic> {
        let parts = Arc::try_unwrap(self.parts)
            .ok()
            .and_then(|m| m.into_inner().ok());
        let Some(mut p) = parts else {
            return Err(Diagnostic::error(
                "internal: the run still holds the --samples rows",
                "",
            ));
        };
        let (joined, file) =
            output::create_temp(&self.out.target, "joined").map_err(|e| cannot(&self.out, &e))?;
        register(&joined);
        // Made now, so that it goes whatever happens next.
        let prepared = Prepared {
            out: self.out,
            temp: Some(joined),
            rows: p.rows,
        };
        join(&mut p, file).map_err(|e| cannot(&prepared.out, &e))?;
        Ok(prepared)
    }
}

impl Drop for Parts {
    /// The per-chain temporaries never outlive the run.
    fn drop(&mut self) {
        for (path, _) in &self.files {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// The header and every chain's part, in chain order, into `joined`.
fn join(p: &mut Parts, joined: File) -> std::io::Result<()> {
    if let Some(e) = p.error.take() {
        return Err(e);
    }
    let mut w = BufWriter::new(joined);
    w.write_all(HEADER.as_bytes())?;
    w.write_all(b"\n")?;
    for (path, part) in &mut p.files {
        part.flush()?;
        std::io::copy(&mut File::open(&*path)?, &mut w)?;
    }
    w.flush()?;
    w.get_ref().sync_all()
}

/// Writes a command's `files` all or none ([`output::write_files`]), then
/// puts its `--samples` (written as the run went) in place: the rows
/// written, if any. When a write fails no `--samples` file stays behind.
pub fn write_with(
    spec_path: &std::path::Path,
    files: &[(&'static str, PathBuf, String)],
    samples: Option<SamplesFile>,
) -> Result<Option<u64>, Diagnostic> {
    let prepared = samples.map(SamplesFile::finish).transpose()?;
    // A failed write drops `prepared`, which removes its temporary.
    output::write_files(spec_path, files)?;
    prepared
        .map(|p| {
            let rows = p.rows;
            p.commit().map(|()| rows)
        })
        .transpose()
}

/// A `--samples` file written beside its target, to be renamed into place
/// (removed if it never is).
struct Prepared {
    out: Output,
    temp: Option<PathBuf>,
    /// Rows written.
    rows: u64,
}

impl Prepared {
    /// Renames the file into place (after the command's other outputs).
    fn commit(mut self) -> Result<(), Diagnostic> {
        let Some(temp) = self.temp.take() else {
            return Ok(());
        };
        std::fs::rename(&temp, &self.out.target).map_err(|e| {
            let _ = std::fs::remove_file(&temp);
            cannot(&self.out, &e)
        })
    }
}

impl Drop for Prepared {
    fn drop(&mut self) {
        if let Some(temp) = &self.temp {
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// The temporaries of a `--samples` being written, for Ctrl-C.
static TEMPS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn register(path: &std::path::Path) {
    if let Ok(mut t) = TEMPS.lock() {
        t.push(path.to_path_buf());
    }
}

/// Called as a run that streams `--samples` goes: after Ctrl-C (caught
/// since [`SamplesFile::open`]) it runs `before` (clear a progress bar),
/// removes the temporaries and ends the command with 130, like every other
/// one stopped by Ctrl-C. Without a `--samples` file it does nothing.
pub fn stop_if_interrupted(before: impl FnOnce()) {
    if rtpipe_runtime::sys::stop_requested() {
        before();
        exit_interrupted();
    }
}

fn exit_interrupted() -> ! {
    if let Ok(t) = TEMPS.lock() {
        for p in t.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
    eprintln!(
        "interrupted ({}): nothing written",
        rtpipe_runtime::sys::stop_name()
    );
    std::process::exit(crate::interrupted_status().into())
}

fn cannot(out: &Output, e: &std::io::Error) -> Diagnostic {
    Diagnostic::error(
        format!("{} {}: cannot write: {e}", out.flag, out.given.display()),
        "check that the directory is writable and the disk not full",
    )
}

#[cfg(test)]
mod tests {
    use rtpipe_model::output::csv_field as quoted;

    #[test]
    fn fields_with_commas_or_quotes_are_quoted() {
        assert_eq!(quoted("gyro→pwm"), "gyro→pwm");
        assert_eq!(quoted("a,b"), "\"a,b\"");
        assert_eq!(quoted("say \"hi\""), "\"say \"\"hi\"\"\"");
    }

    #[test]
    fn fields_a_spreadsheet_would_run_are_neutralised() {
        assert_eq!(quoted("=1+2"), "\"'=1+2\"");
        assert_eq!(quoted("+cmd"), "\"'+cmd\"");
        assert_eq!(quoted("-2+3"), "\"'-2+3\"");
        assert_eq!(quoted("@SUM(A1)"), "\"'@SUM(A1)\"");
        assert_eq!(quoted("\tx"), "\"'\tx\"");
        assert_eq!(quoted("\rx"), "\"'\rx\"");
        assert_eq!(quoted("=HYPERLINK(\"x\")"), "\"'=HYPERLINK(\"\"x\"\")\"");
        // Inside a name they are harmless.
        assert_eq!(quoted("a=b"), "a=b");
    }
}
