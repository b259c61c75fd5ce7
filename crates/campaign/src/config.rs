//! A campaign's configuration (TOML): how many systems, how each is
//! generated, and what is done to it. Read by `model::input`'s rules; every
//! wrong value is a diagnostic at its key with a fix.

use rtpipe_model::input::{self, Kind, Syntax};
use rtpipe_model::{parse_time_str, Diagnostic, Nanos, SpecError};
use serde::Deserialize;
use std::path::Path;

/// The file kind: a campaign is small.
pub const KIND: Kind = Kind {
    name: "campaign",
    max_bytes: 1 << 20,
    syntax: Syntax::Toml,
    help: "see examples/campaigns/waters.toml for the format",
};

/// The most systems one campaign generates.
pub const MAX_SYSTEMS: u64 = 1_000_000_000;
/// The most systems in one shard (one Parquet file).
pub const MAX_SHARD: u64 = 1_000_000;
/// The longest simulation of one system.
pub const MAX_SIM: Nanos = 3_600_000_000_000;

/// A validated campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    pub name: String,
    /// Systems 0..systems are generated.
    pub systems: u64,
    /// System `i` is generated from `system_seed(seed, i)`.
    pub seed: u64,
    /// Systems per shard: shard `k` holds systems `k·shard_size ..`.
    pub shard_size: u64,
    pub generate: Generate,
    pub simulate: Option<Simulate>,
}

impl Config {
    /// The campaign's identity: a hash (FNV-1a, 64 bits, hex) of every
    /// value that decides its rows (the name included) and of the columns.
    /// Written in every shard's footer and compared with the directory's
    /// `_campaign.toml`, so a directory holds one campaign's shards only.
    /// Comments and layout of the file do not change it.
    pub fn fingerprint(&self) -> String {
        let g = &self.generate;
        let sim = self.simulate.as_ref().map_or("none".to_string(), |s| {
            format!("{} {} {}", s.horizon, s.random_phasing, s.uniform_exec)
        });
        let canonical = format!(
            "rtpipe campaign\ncolumns {}\nname {:?}\nsystems {}\nseed {}\nshard_size {}\n\
             tasks {:?}\nutilization {:?}\nchains {}\ncpus {}\nsynchronous {}\nsimulate {sim}\n",
            crate::columns::names().join(","),
            self.name,
            self.systems,
            self.seed,
            self.shard_size,
            g.tasks,
            g.utilization,
            g.chains,
            g.cpus,
            g.synchronous,
        );
        // Appended for the newer generator only, so that a WATERS
        // campaign keeps the fingerprint its folders were written with.
        let canonical = match &g.events {
            None => canonical,
            Some(e) => format!(
                "{canonical}kind event-triggered\nthreads {}\nlinks {:?}\ndata_fraction {:?}\n",
                e.threads, e.links, e.data_fraction
            ),
        };
        let hash = canonical.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
        format!("{hash:016x}")
    }
}

/// How each system is generated: WATERS 2015 task sets, as E2EEvaluation
/// generates them (`kind = "waters"`), or event-triggered systems (`kind =
/// "event-triggered"`: work-queue threads and data-triggered tasks,
/// `rtpipe_model::gen::event_triggered_system`); a range is drawn
/// uniformly per system.
#[derive(Debug, Clone, PartialEq)]
pub struct Generate {
    /// Tasks per system (UUniFast); `None`: the paper's runnables (WATERS
    /// only: an event-triggered system's tasks follow from its chains).
    pub tasks: Option<(u32, u32)>,
    /// Utilisation per CPU.
    pub utilization: (f64, f64),
    /// Chains per system: exactly (WATERS), at most (event-triggered,
    /// drawn from 1).
    pub chains: u32,
    /// CPUs per system: exactly (WATERS), at most (event-triggered).
    pub cpus: u32,
    /// Every task released at 0 (known-offset bounds are added).
    pub synchronous: bool,
    /// The event-triggered generator's own keys; `None` for WATERS.
    pub events: Option<EventKeys>,
}

/// `kind = "event-triggered"`'s keys.
#[derive(Debug, Clone, PartialEq)]
pub struct EventKeys {
    /// Threads per system, at most (drawn from 1).
    pub threads: u32,
    /// Tasks per chain, drawn in this range (at least 2).
    pub links: (u32, u32),
    /// The probability that a link after a chain's head is data-triggered.
    pub data_fraction: f64,
}

impl Generate {
    /// Does every system get exactly `chains` chains (so fewer is short)?
    pub fn exact_chains(&self) -> bool {
        self.events.is_none()
    }
}

/// One simulation per system, held against its bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulate {
    pub horizon: Nanos,
    /// Random release offsets (else all at 0).
    pub random_phasing: bool,
    /// Uniform demands in [exec_min, exec] (else the worst case).
    pub uniform_exec: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    campaign: RawCampaign,
    generate: RawGenerate,
    simulate: Option<RawSimulate>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCampaign {
    name: String,
    systems: u64,
    #[serde(default)]
    seed: u64,
    shard_size: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGenerate {
    kind: String,
    tasks: Option<Span<u32>>,
    utilization: Span<f64>,
    #[serde(default = "five")]
    chains: u32,
    #[serde(default = "one")]
    cpus: u32,
    #[serde(default = "arbitrary")]
    release: String,
    threads: Option<u32>,
    links: Option<Span<u32>>,
    data_fraction: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSimulate {
    duration: String,
    #[serde(default = "random")]
    phasing: String,
    #[serde(default = "uniform")]
    exec: String,
}

/// A number, or `[lo, hi]` drawn uniformly per system.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
enum Span<T> {
    One(T),
    Range([T; 2]),
}

impl<T: Copy> Span<T> {
    fn bounds(self) -> (T, T) {
        match self {
            Span::One(x) => (x, x),
            Span::Range([a, b]) => (a, b),
        }
    }
}

fn five() -> u32 {
    5
}
fn one() -> u32 {
    1
}
fn arbitrary() -> String {
    "arbitrary".into()
}
fn random() -> String {
    "random".into()
}
fn uniform() -> String {
    "uniform".into()
}

/// Reads and checks a campaign file.
pub fn load(path: &Path) -> Result<Config, SpecError> {
    let text = input::read_text(path, &KIND)?;
    parse(&path.display().to_string(), &text)
}

/// Parses and checks campaign text; `file` names it in messages.
pub fn parse(file: &str, text: &str) -> Result<Config, SpecError> {
    let raw: Raw = input::parse_toml(file, text, &KIND)?;
    let at = |field: &str, message: String, help: &str| SpecError {
        file: file.to_string(),
        source: text.to_string(),
        diagnostics: vec![Diagnostic::new(message, input::locate(text, field)).help(help)],
    };
    validate(raw).map_err(|(field, message, help)| at(field, message, help))
}

/// A wrong value: its field, what is wrong, the fix.
type Problem = (&'static str, String, &'static str);

fn validate(raw: Raw) -> Result<Config, Problem> {
    let c = &raw.campaign;
    if c.name.trim().is_empty() || c.name.chars().any(char::is_control) {
        return Err((
            "campaign.name",
            "the name is empty or holds control characters".into(),
            "give a short printable name",
        ));
    }
    if !(1..=MAX_SYSTEMS).contains(&c.systems) {
        return Err((
            "campaign.systems",
            format!("{} systems is outside 1..={MAX_SYSTEMS}", c.systems),
            "give a whole number of systems, e.g. systems = 100000",
        ));
    }
    let shard_size = c.shard_size.unwrap_or(c.systems.clamp(1, 10_000));
    if !(1..=MAX_SHARD).contains(&shard_size) {
        return Err((
            "campaign.shard_size",
            format!("{shard_size} is outside 1..={MAX_SHARD}"),
            "give the systems per Parquet file, e.g. shard_size = 10000",
        ));
    }
    Ok(Config {
        name: c.name.clone(),
        systems: c.systems,
        seed: c.seed,
        shard_size,
        generate: generate(&raw.generate)?,
        simulate: raw.simulate.as_ref().map(simulate).transpose()?,
    })
}

fn generate(g: &RawGenerate) -> Result<Generate, Problem> {
    let events = match g.kind.as_str() {
        "waters" => {
            waters_has_no_event_keys(g)?;
            None
        }
        "event-triggered" => Some(event_keys(g)?),
        other => {
            return Err((
                "generate.kind",
                format!("no generator `{other}`"),
                "use kind = \"waters\" (WATERS 2015, as E2EEvaluation) or \"event-triggered\" (threads and data-triggered tasks)",
            ))
        }
    };
    let tasks = g.tasks.map(Span::bounds);
    if let Some((lo, hi)) = tasks {
        if lo < 1 || lo > hi || hi > 100_000 {
            return Err((
                "generate.tasks",
                format!("tasks [{lo}, {hi}] is not a range within 1..=100000"),
                "give a number or [lo, hi] with lo <= hi",
            ));
        }
    }
    let (ulo, uhi) = g.utilization.bounds();
    if !(0.001..=1.0).contains(&ulo) || !(ulo..=1.0).contains(&uhi) {
        return Err((
            "generate.utilization",
            format!("utilization [{ulo}, {uhi}] is not a range within [0.001, 1]"),
            "give a number or [lo, hi] per CPU, e.g. utilization = [0.5, 0.9]",
        ));
    }
    if !(1..=1024).contains(&g.cpus) || g.chains > 10_000 {
        let field = if g.chains > 10_000 {
            "generate.chains"
        } else {
            "generate.cpus"
        };
        return Err((
            field,
            format!("{} CPUs, {} chains", g.cpus, g.chains),
            "give 1..=1024 CPUs and 0..=10000 chains",
        ));
    }
    let synchronous = match g.release.as_str() {
        "synchronous" => true,
        "arbitrary" => false,
        other => {
            return Err((
                "generate.release",
                format!("no release `{other}`"),
                "use \"synchronous\" or \"arbitrary\"",
            ))
        }
    };
    Ok(Generate {
        tasks,
        utilization: (ulo, uhi),
        chains: g.chains,
        cpus: g.cpus,
        synchronous,
        events,
    })
}

/// The event-triggered generator's keys belong to it alone.
fn waters_has_no_event_keys(g: &RawGenerate) -> Result<(), Problem> {
    let given = [
        ("generate.threads", g.threads.is_some()),
        ("generate.links", g.links.is_some()),
        ("generate.data_fraction", g.data_fraction.is_some()),
    ];
    match given.iter().find(|(_, set)| *set) {
        Some((field, _)) => Err((
            field,
            format!("`{}` is a key of kind = \"event-triggered\"", &field[9..]),
            "remove it, or use kind = \"event-triggered\"",
        )),
        None => Ok(()),
    }
}

/// `threads`, `links` and `data_fraction` of an event-triggered campaign;
/// `tasks` and a synchronous release are WATERS' alone.
fn event_keys(g: &RawGenerate) -> Result<EventKeys, Problem> {
    if g.tasks.is_some() {
        return Err((
            "generate.tasks",
            "an event-triggered system's tasks follow from its chains".into(),
            "remove `tasks`; give `chains` (at most per system) and `links` (tasks per chain)",
        ));
    }
    if g.release != "arbitrary" {
        return Err((
            "generate.release",
            format!("release `{}` with kind = \"event-triggered\"", g.release),
            "remove `release`: data-triggered tasks are released by their triggers, periodic ones at unknown offsets",
        ));
    }
    let threads = g.threads.unwrap_or(6);
    let sizes = [
        ("generate.threads", threads, 64),
        ("generate.cpus", g.cpus, 4),
        ("generate.chains", g.chains, 16),
    ];
    if let Some(&(field, _, _)) = sizes.iter().find(|(_, n, most)| !(1..=*most).contains(n)) {
        return Err((
            field,
            format!("{threads} threads, {} CPUs, {} chains", g.cpus, g.chains),
            "give 1..=64 threads, 1..=4 CPUs and 1..=16 chains per system (each at most; drawn from 1)",
        ));
    }
    let (lo, hi) = g.links.map_or((2, 8), Span::bounds);
    if lo < 2 || lo > hi || hi > 32 {
        return Err((
            "generate.links",
            format!("links [{lo}, {hi}] is not a range within 2..=32"),
            "give the tasks per chain as a number or [lo, hi], e.g. links = [2, 8]",
        ));
    }
    let data_fraction = g.data_fraction.unwrap_or(0.6);
    if !(0.0..=1.0).contains(&data_fraction) {
        return Err((
            "generate.data_fraction",
            format!("data_fraction {data_fraction} is not a probability"),
            "give a number in [0, 1], e.g. data_fraction = 0.6",
        ));
    }
    Ok(EventKeys {
        threads,
        links: (lo, hi),
        data_fraction,
    })
}

fn simulate(s: &RawSimulate) -> Result<Simulate, Problem> {
    let horizon = parse_time_str(&s.duration).map_err(|e| {
        (
            "simulate.duration",
            format!("duration `{}`: {e}", s.duration),
            "write a time with a unit, e.g. \"1s\" or \"500ms\"",
        )
    })?;
    if !(1..=MAX_SIM).contains(&horizon) {
        return Err((
            "simulate.duration",
            format!("duration `{}` is outside (0, 3600 s]", s.duration),
            "give a positive time up to \"3600s\"",
        ));
    }
    let random_phasing = match s.phasing.as_str() {
        "random" => true,
        "sync" => false,
        other => {
            return Err((
                "simulate.phasing",
                format!("no phasing `{other}`"),
                "use \"random\" or \"sync\"",
            ))
        }
    };
    let uniform_exec = match s.exec.as_str() {
        "uniform" => true,
        "worst" => false,
        other => {
            return Err((
                "simulate.exec",
                format!("no exec `{other}`"),
                "use \"uniform\" or \"worst\"",
            ))
        }
    };
    Ok(Simulate {
        horizon,
        random_phasing,
        uniform_exec,
    })
}
