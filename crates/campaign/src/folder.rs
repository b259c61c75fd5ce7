//! A campaign's directory: whose it is (the fingerprint of its
//! `_campaign.parquet` and of its shards' footers) and which shards of a
//! part it already holds whole. Only a complete shard of this campaign
//! counts as done; another campaign's file is never trusted, replaced or
//! counted.

use crate::parquet_out::{read_footer, read_kept, ShardMeta};
use crate::{config, shard_count, shard_systems, Config, Error, Part};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The file that keeps a directory's configuration: Parquet with the
/// shards' columns and no rows, the configuration in its footer. pyarrow
/// and pandas skip `_` and `.` names; polars reads every file of a folder
/// and refuses one that mixes file types, so the folder holds Parquet
/// only and this file adds no row.
pub const KEPT: &str = "_campaign.parquet";

/// Where directories written before `_campaign.parquet` kept their
/// configuration, as TOML. Still read; a run of the same campaign
/// replaces it by [`KEPT`] (the text kept as it was).
pub const LEGACY_KEPT: &str = "_campaign.toml";

/// What a directory holds of a campaign, for the shards of one part.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Survey {
    /// `_campaign.parquet` is there, and it is this campaign's (else a
    /// run writes it).
    pub kept: bool,
    /// An older run's `_campaign.toml` is there, and it is this
    /// campaign's: a run replaces it by `_campaign.parquet`.
    pub legacy: bool,
    /// The part's shards the directory holds whole: the files to skip.
    pub done: BTreeSet<u64>,
    /// The part's shards whose file is there but is not a complete shard
    /// of this campaign (truncated, not Parquet, no campaign metadata,
    /// another shard's systems), with why: a run writes them again.
    pub rerun: BTreeMap<u64, String>,
}

/// Reads `dir` (which need not exist) for `cfg`'s shards of `part`.
/// Refuses a directory that belongs to another campaign (its
/// `_campaign.parquet` or `_campaign.toml`, or a shard's footer, names
/// another fingerprint) and a shard name that is not a regular file (a
/// directory, a link, a pipe): rtpipe neither trusts nor replaces what it
/// did not write.
pub fn survey(dir: &Path, cfg: &Config, part: Part) -> Result<Survey, Error> {
    let mut s = Survey::default();
    match std::fs::metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(s),
        Err(e) => return Err(Error::io("read", dir, &e)),
        Ok(m) if !m.is_dir() => {
            return Err(Error {
                message: format!("{} is not a directory", dir.display()),
                help: "name a new or existing directory for the shards".into(),
            })
        }
        Ok(_) => {}
    }
    let fingerprint = cfg.fingerprint();
    s.kept = kept_is_this(dir, KEPT, &fingerprint)?;
    s.legacy = kept_is_this(dir, LEGACY_KEPT, &fingerprint)?;
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io("read", dir, &e))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io("read", dir, &e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(k) = shard_index(&name) else {
            continue;
        };
        let path = entry.path();
        let mine = k.is_some_and(|k| k < shard_count(cfg) && k % part.count == part.index);
        match shard_state(&path, cfg, &fingerprint, k)? {
            Ok(()) if mine => {
                s.done.insert(k.unwrap_or_default());
            }
            Err(why) if mine => {
                s.rerun.insert(k.unwrap_or_default(), why);
            }
            // Another part's shard, or a stray name no run writes.
            _ => {}
        }
    }
    Ok(s)
}

/// `Some(index)` of a name `shard-*.parquet` (`Some(None)` when the middle
/// is not a number), `None` for every other name.
fn shard_index(name: &str) -> Option<Option<u64>> {
    let middle = name.strip_prefix("shard-")?.strip_suffix(".parquet")?;
    Some(middle.parse().ok())
}

/// Whether the directory's `name` ([`KEPT`] or [`LEGACY_KEPT`]) is there
/// and this campaign's; an error when it is another campaign's, or not a
/// campaign configuration at all.
fn kept_is_this(dir: &Path, name: &str, fingerprint: &str) -> Result<bool, Error> {
    let kept = dir.join(name);
    match std::fs::symlink_metadata(&kept) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => return Err(Error::io("read", &kept, &e)),
        Ok(m) if !m.is_file() => return Err(not_a_file(&kept, &m)),
        Ok(_) => {}
    }
    let not_a_configuration = |why: String| Error {
        message: format!(
            "{} holds {name}, which is not a campaign configuration: {why}",
            dir.display()
        ),
        help: "write to another OUTDIR; rtpipe does not replace a file it did not write".into(),
    };
    let text = if name == KEPT {
        read_kept(&kept).map_err(not_a_configuration)?
    } else {
        rtpipe_model::input::read_text(&kept, &config::KIND)
            .map_err(|e| not_a_configuration(e.to_string()))?
    };
    let theirs = config::parse(&kept.display().to_string(), &text)
        .map_err(|e| not_a_configuration(e.to_string()))?;
    if theirs.fingerprint() != fingerprint {
        return Err(Error {
            message: format!(
                "{} holds the shards of another campaign configuration (`{}`, fingerprint {}; this one is {fingerprint})",
                dir.display(),
                theirs.name,
                theirs.fingerprint()
            ),
            help: "write to another OUTDIR, or remove that one to start again".into(),
        });
    }
    Ok(true)
}

/// A shard name's file: `Ok(Ok(()))` a complete shard `k` of this
/// campaign, `Ok(Err(why))` a file to write again, `Err` one never to
/// touch (not a regular file, or another campaign's shard).
fn shard_state(
    path: &Path,
    cfg: &Config,
    fingerprint: &str,
    k: Option<u64>,
) -> Result<Result<(), String>, Error> {
    let m = std::fs::symlink_metadata(path).map_err(|e| Error::io("read", path, &e))?;
    if !m.is_file() {
        return Err(not_a_file(path, &m));
    }
    let (meta, rows) = match read_footer(path) {
        Ok(found) => found,
        Err(why) => return Ok(Err(why)),
    };
    if meta.campaign != fingerprint {
        return Err(Error {
            message: format!(
                "{} is a shard of another campaign (fingerprint {}; this one is {fingerprint})",
                path.display(),
                meta.campaign
            ),
            help: "write to another OUTDIR, or move the other campaign's shards away".into(),
        });
    }
    Ok(complete(&meta, rows, cfg, k))
}

/// Whether a footer of this campaign is shard `k`'s, with at most the rows
/// its systems can have (two metrics per chain).
fn complete(meta: &ShardMeta, rows: u64, cfg: &Config, k: Option<u64>) -> Result<(), String> {
    let Some(k) = k else {
        return Err("is not named by a shard number".into());
    };
    let systems = shard_systems(cfg, k);
    if meta.shard != k || meta.systems != systems {
        return Err(format!(
            "holds shard {} (systems {:?}), not shard {k} (systems {systems:?})",
            meta.shard, meta.systems
        ));
    }
    let most = (systems.end - systems.start) * 2 * u64::from(cfg.generate.chains);
    if rows > most {
        return Err(format!(
            "has {rows} rows, more than its systems can have ({most})"
        ));
    }
    Ok(())
}

fn not_a_file(path: &Path, m: &std::fs::Metadata) -> Error {
    let kind = if m.is_dir() {
        "a directory"
    } else if m.file_type().is_symlink() {
        "a symbolic link"
    } else {
        "not a regular file (a pipe, socket or device)"
    };
    Error {
        message: format!(
            "{} is {kind}: a campaign only reads and replaces the regular files it writes",
            path.display()
        ),
        help: "remove or move it, or write to another OUTDIR".into(),
    }
}
