//! Evaluation campaigns: many generated task sets, each analysed (and
//! simulated, when asked), written as sharded Parquet.
//!
//! - **Deterministic per seed.** System `i` is generated from
//!   [`system_seed`]`(seed, i)` alone, so its rows are the same whichever
//!   machine, thread count or shard runs it.
//! - **Sharded.** Shard `k` holds systems `k·shard_size ..` and is one
//!   Parquet file, `shard-KKKKKK.parquet`; `--shard i/n` runs the shards
//!   `k ≡ i (mod n)`, so `n` machines together write exactly the files one
//!   machine writes.
//! - **Resumable.** A shard's file appears whole (written beside, then
//!   renamed: `rtpipe_model::output`) or not at all; a run skips the shards
//!   already written, and only those: a shard counts when its footer names
//!   this campaign's [`Config::fingerprint`], its index and its systems
//!   ([`survey`]). The directory keeps the configuration
//!   (`_campaign.parquet`: no rows, the text in its footer, so the folder
//!   is Parquet only and every reader takes it as it is) and refuses
//!   another campaign's.
//! - **Bounded.** Shards are planned by index, never listed, and written a
//!   row group at a time ([`ROW_GROUP_ROWS`]), so memory does not grow with
//!   the campaign or the shard; the stop flag is asked inside each
//!   system's simulation too.

pub mod columns;
pub mod config;
mod folder;
mod parquet_out;
mod system;

pub use config::Config;
pub use folder::{survey, Survey, KEPT, LEGACY_KEPT};
pub use parquet_out::ROW_GROUP_ROWS;
pub use system::{run_system, run_system_until, system_seed, Row};

use parquet_out::{ShardMeta, ShardWriter};
use rayon::prelude::*;
use rtpipe_model::output;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Which shards a run takes: `index` of `count` (`--shard index/count`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Part {
    pub index: u64,
    pub count: u64,
}

impl Part {
    /// Every shard.
    pub const ALL: Part = Part { index: 0, count: 1 };

    /// `i/n` with `i < n`.
    pub fn parse(s: &str) -> Result<Part, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}` is not i/n, e.g. 0/4"))?;
        let (i, n): (u64, u64) = match (i.trim().parse(), n.trim().parse()) {
            (Ok(i), Ok(n)) => (i, n),
            _ => return Err(format!("`{s}` is not two whole numbers i/n, e.g. 0/4")),
        };
        if n == 0 || i >= n {
            return Err(format!(
                "`{s}`: i must be below n (0/4 to 3/4 split four ways)"
            ));
        }
        Ok(Part { index: i, count: n })
    }

    /// How many of `total` shards this part owns.
    pub fn shard_count(self, total: u64) -> u64 {
        if self.index >= total {
            0
        } else {
            (total - 1 - self.index) / self.count + 1
        }
    }

    /// The shards of `total` this part owns, in order, one at a time
    /// (a campaign of 10⁹ shards is never listed).
    pub fn shards(self, total: u64) -> impl Iterator<Item = u64> {
        (0..self.shard_count(total)).map(move |j| self.index + j * self.count)
    }
}

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Shards this part owns.
    pub shards: u64,
    /// Of them, written by this run.
    pub written: u64,
    /// Of those written, found unfinished or damaged and written again.
    pub rewritten: u64,
    /// Of them, found already written and skipped.
    pub skipped: u64,
    /// Systems generated and analysed by this run.
    pub systems: u64,
    /// Of them, with fewer chains than asked (the generator found too few).
    pub short: u64,
    /// Of those, with no chain at all: no rows.
    pub chainless: u64,
    /// Rows written by this run.
    pub rows: u64,
    /// Wall-clock seconds of this run.
    pub seconds: f64,
    /// Worker threads.
    pub jobs: usize,
    /// Stopped by the stop flag before the last shard.
    pub stopped: bool,
}

/// Why a run could not go on.
#[derive(Debug)]
pub struct Error {
    pub message: String,
    pub help: String,
}

impl Error {
    fn io(what: &str, path: &Path, e: &dyn std::fmt::Display) -> Error {
        Error {
            message: format!("cannot {what} {}: {e}", path.display()),
            help: "check that the directory is writable and the disk not full".into(),
        }
    }
}

/// The number of shards of `cfg`.
pub fn shard_count(cfg: &Config) -> u64 {
    cfg.systems.div_ceil(cfg.shard_size)
}

/// The systems of shard `k`.
pub fn shard_systems(cfg: &Config, k: u64) -> Range<u64> {
    let first = k.saturating_mul(cfg.shard_size).min(cfg.systems);
    first..first.saturating_add(cfg.shard_size).min(cfg.systems)
}

/// The file of shard `k`.
pub fn shard_path(dir: &Path, k: u64) -> PathBuf {
    dir.join(format!("shard-{k:06}.parquet"))
}

/// What a run shares with its shards.
struct Work<'a> {
    cfg: &'a Config,
    fingerprint: String,
    dir: &'a Path,
    pool: rayon::ThreadPool,
    jobs: usize,
    on_system: &'a (dyn Fn() + Sync),
    stop: &'a (dyn Fn() -> bool + Sync),
}

/// Runs the shards of `part` not yet in `dir` on `jobs` threads;
/// `on_system` is called once per system done; `stop` (asked from every
/// worker, and inside each simulation) ends the run: the shard in progress
/// is dropped (nothing half-written stays). A directory of another
/// campaign is refused before anything is written ([`survey`]).
pub fn run(
    cfg: &Config,
    config_text: &str,
    dir: &Path,
    part: Part,
    jobs: usize,
    on_system: &(dyn Fn() + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Summary, Error> {
    assert!(part.index < part.count && jobs >= 1);
    let found = prepare_dir(dir, cfg, config_text, part)?;
    let started = Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::io("start threads for", dir, &e))?;
    let work = Work {
        cfg,
        fingerprint: cfg.fingerprint(),
        dir,
        pool,
        jobs,
        on_system,
        stop,
    };
    let total = shard_count(cfg);
    let mut s = Summary {
        shards: part.shard_count(total),
        written: 0,
        rewritten: 0,
        skipped: 0,
        systems: 0,
        short: 0,
        chainless: 0,
        rows: 0,
        seconds: 0.0,
        jobs,
        stopped: false,
    };
    for k in part.shards(total) {
        if found.done.contains(&k) {
            s.skipped += 1;
            continue;
        }
        if stop() {
            s.stopped = true;
            break;
        }
        let Some(t) = run_shard(&work, k)? else {
            s.stopped = true;
            break;
        };
        s.written += 1;
        s.rewritten += u64::from(found.rerun.contains_key(&k));
        s.systems += t.systems;
        s.short += t.short;
        s.chainless += t.chainless;
        s.rows += t.rows;
    }
    s.seconds = started.elapsed().as_secs_f64();
    Ok(s)
}

/// What a shard's systems came to.
#[derive(Debug, Default, Clone, Copy)]
struct Tally {
    systems: u64,
    short: u64,
    chainless: u64,
    rows: u64,
}

impl Tally {
    fn add(&mut self, cfg: &Config, rows: &[Row]) {
        let got = rows.first().map_or(0, |r| r.chains);
        self.systems += 1;
        // An event-triggered system draws its chains: none is short.
        self.short += u64::from(cfg.generate.exact_chains() && got < cfg.generate.chains);
        self.chainless += u64::from(got == 0 && cfg.generate.chains > 0);
        self.rows += rows.len() as u64;
    }
}

/// Shard `k`: its systems in parallel, a batch at a time, their rows in
/// index order into row groups of [`ROW_GROUP_ROWS`] (the same groups
/// whatever the threads), into a temporary renamed into place at the end.
/// `None` when stopped (nothing written).
fn run_shard(w: &Work, k: u64) -> Result<Option<Tally>, Error> {
    let path = shard_path(w.dir, k);
    let systems = shard_systems(w.cfg, k);
    let meta = ShardMeta {
        campaign: w.fingerprint.clone(),
        shard: k,
        systems: systems.clone(),
    };
    let written = output::write_atomically(&path, "shard", |file| {
        let mut out = ShardWriter::new(file, &meta.key_values())?;
        let mut pending: Vec<Row> = Vec::new();
        let mut tally = Tally::default();
        let batch = 4 * w.jobs as u64;
        for first in systems.clone().step_by(batch as usize) {
            let last = (first + batch).min(systems.end);
            for rows in run_batch(w, first..last) {
                let rows = rows.ok_or_else(stopped)?;
                tally.add(w.cfg, &rows);
                pending.extend(rows);
                if pending.len() >= ROW_GROUP_ROWS {
                    out.row_group(&pending)?;
                    pending.clear();
                }
            }
        }
        out.row_group(&pending)?;
        out.finish()?;
        Ok(tally)
    });
    match written {
        Ok(t) => Ok(Some(t)),
        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => Ok(None),
        Err(e) => Err(Error::io("write", &path, &e)),
    }
}

/// The rows of `systems`, in order, computed in parallel; `None` for a
/// system the stop flag ended or skipped.
fn run_batch(w: &Work, systems: Range<u64>) -> Vec<Option<Vec<Row>>> {
    w.pool.install(|| {
        systems
            .into_par_iter()
            .map(|i| {
                if (w.stop)() {
                    return None;
                }
                let rows = run_system_until(w.cfg, i, w.stop)?;
                (w.on_system)();
                Some(rows)
            })
            .collect()
    })
}

/// The text of `dir`'s `_campaign.toml` (checked as this campaign's by
/// [`survey`]), `None` when another part run at the same time has
/// replaced it since.
fn legacy_text(dir: &Path) -> Result<Option<String>, Error> {
    let legacy = dir.join(LEGACY_KEPT);
    match std::fs::read_to_string(&legacy) {
        Ok(text) => Ok(Some(text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(Error::io("read", &legacy, &e)),
    }
}

/// The error that ends a shard's write when the stop flag is set: the
/// temporary is removed and nothing is renamed.
fn stopped() -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::Interrupted, "stopped")
}

/// Checks `dir` ([`survey`]: another campaign's directory is refused),
/// creates it and writes its `_campaign.parquet` when it has none; an
/// older run's `_campaign.toml` of this campaign goes once the Parquet
/// file holds its text (a folder of Parquet only, for every reader).
fn prepare_dir(dir: &Path, cfg: &Config, config_text: &str, part: Part) -> Result<Survey, Error> {
    let found = survey(dir, cfg, part)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io("create", dir, &e))?;
    let kept = dir.join(KEPT);
    if !found.kept {
        let text = if found.legacy {
            legacy_text(dir)?.unwrap_or_else(|| config_text.to_string())
        } else {
            config_text.to_string()
        };
        output::write_atomically(&kept, "config", |f| {
            parquet_out::write_kept(f, &cfg.fingerprint(), &text)
        })
        .map_err(|e| Error::io("write", &kept, &e))?;
    }
    if found.legacy {
        // Gone already is fine: another part of the same campaign, run at
        // the same time, replaced it first.
        let legacy = dir.join(LEGACY_KEPT);
        match std::fs::remove_file(&legacy) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(Error::io("remove", &legacy, &e));
            }
            _ => {}
        }
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two parts of one campaign started together on an older folder both
    /// replace its `_campaign.toml`: the one that comes second finds it
    /// gone, which is no error.
    #[test]
    fn a_legacy_file_gone_since_the_survey_is_no_error() {
        let dir = std::env::temp_dir().join(format!("rtpipe-legacy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a folder");
        assert_eq!(legacy_text(&dir).ok(), Some(None));
        std::fs::write(dir.join(LEGACY_KEPT), "# kept\n").expect("write");
        assert_eq!(legacy_text(&dir).ok(), Some(Some("# kept\n".to_string())));
        let _ = std::fs::remove_dir_all(dir);
    }
}
