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
//!   renamed) or not at all; a run skips the shards already written. The
//!   directory keeps the configuration (`_campaign.toml`) and refuses a
//!   different one.

pub mod config;
mod parquet_out;
mod system;

pub use config::Config;
pub use parquet_out::COLUMNS;
pub use system::{run_system, system_seed, Row};

use rayon::prelude::*;
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
}

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Shards this part owns.
    pub shards: u64,
    /// Of them, written by this run.
    pub written: u64,
    /// Of them, found already written and skipped.
    pub skipped: u64,
    /// Systems generated and analysed by this run.
    pub systems: u64,
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

/// The file of shard `k`.
pub fn shard_path(dir: &Path, k: u64) -> PathBuf {
    dir.join(format!("shard-{k:06}.parquet"))
}

/// Runs the shards of `part` not yet in `dir` on `jobs` threads;
/// `on_system` is called once per system done; `stop` (asked from every
/// worker) ends the run after
/// the shard in progress (nothing half-written stays).
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
    prepare_dir(dir, config_text)?;
    let started = Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::io("start threads for", dir, &e))?;
    let mine: Vec<u64> = (0..shard_count(cfg))
        .filter(|k| k % part.count == part.index)
        .collect();
    let mut s = Summary {
        shards: mine.len() as u64,
        written: 0,
        skipped: 0,
        systems: 0,
        rows: 0,
        seconds: 0.0,
        jobs,
        stopped: false,
    };
    for &k in &mine {
        if shard_path(dir, k).exists() {
            s.skipped += 1;
            continue;
        }
        if stop() {
            s.stopped = true;
            break;
        }
        let (systems, rows) = pool.install(|| run_shard(cfg, dir, k, on_system, stop))?;
        if systems.is_none() {
            s.stopped = true;
            break;
        }
        (s.written, s.systems, s.rows) = (
            s.written + 1,
            s.systems + systems.unwrap_or(0),
            s.rows + rows,
        );
    }
    s.seconds = started.elapsed().as_secs_f64();
    Ok(s)
}

/// Shard `k`: its systems in parallel (in order), then its file. `None`
/// systems when stopped (nothing written).
fn run_shard(
    cfg: &Config,
    dir: &Path,
    k: u64,
    on_system: &(dyn Fn() + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(Option<u64>, u64), Error> {
    let first = k * cfg.shard_size;
    let last = (first + cfg.shard_size).min(cfg.systems);
    let per_system: Vec<Option<Vec<Row>>> = (first..last)
        .into_par_iter()
        .map(|i| {
            if stop() {
                return None;
            }
            let rows = run_system(cfg, i);
            on_system();
            Some(rows)
        })
        .collect();
    if per_system.iter().any(Option::is_none) {
        return Ok((None, 0));
    }
    let rows: Vec<Row> = per_system.into_iter().flatten().flatten().collect();
    parquet_out::write_atomically(&shard_path(dir, k), &rows)?;
    Ok((Some(last - first), rows.len() as u64))
}

/// Creates `dir` with the configuration, or checks that the one it holds
/// is this one (a resumed campaign must be the same campaign).
fn prepare_dir(dir: &Path, config_text: &str) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io("create", dir, &e))?;
    // `_` and `.` files are not data to Parquet readers (pyarrow, polars, Spark).
    let kept = dir.join("_campaign.toml");
    match std::fs::read_to_string(&kept) {
        Ok(old) if old == config_text => Ok(()),
        Ok(_) => Err(Error {
            message: format!(
                "{} holds the shards of another campaign configuration",
                dir.display()
            ),
            help: "write to another --out directory, or remove that one to start again".into(),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            parquet_out::write_bytes_atomically(&kept, config_text.as_bytes())
        }
        Err(e) => Err(Error::io("read", &kept, &e)),
    }
}
