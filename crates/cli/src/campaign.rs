//! `rtpipe campaign CONFIG OUTDIR`: generate, analyse (and simulate) many
//! task sets on every core, into sharded Parquet (`rtpipe_campaign`).

use crate::command::{self, Answer};
use crate::report::record_table;
use rtpipe_campaign::{config, Part, Summary};
use rtpipe_model::Diagnostic;
use rtpipe_printer::{Cell, Column, Kind, Table};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// `rtpipe campaign`'s flags.
#[derive(clap::Args, Debug)]
pub struct CampaignArgs {
    /// The campaign (TOML), e.g. examples/campaigns/waters.toml.
    pub config: PathBuf,
    /// The directory of the shards (created; a run skips the shards it
    /// already holds, so an interrupted campaign resumes).
    #[arg(value_name = "OUTDIR")]
    pub out: PathBuf,
    /// Run only the shards k with k mod n = i, so that n machines (or
    /// processes) share a campaign; together they write exactly the files
    /// one run writes.
    #[arg(long, value_name = "i/n", value_parser = Part::parse)]
    pub shard: Option<Part>,
    /// Worker threads [default: every core].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub jobs: Option<u32>,
    #[command(flatten)]
    pub output: crate::command::FormatArgs,
    /// Only check the configuration and print the plan (systems, shards,
    /// which of them this part owns and which OUTDIR already holds): nothing
    /// is run or written.
    #[arg(long)]
    pub plan: bool,
}

pub fn run(a: &CampaignArgs) -> ExitCode {
    rtpipe_runtime::sys::catch_stop_signals();
    match execute(a, &rtpipe_runtime::sys::stop_requested) {
        Ok(answer) => answer.emit(),
        Err(b) => command::fail(b),
    }
}

/// The campaign `a` names, stopped after the shard in progress once `stop`
/// says so.
pub fn execute(a: &CampaignArgs, stop: &(dyn Fn() -> bool + Sync)) -> Result<Answer, Diagnostic> {
    let text = rtpipe_model::input::read_text(&a.config, &config::KIND).map_err(|e| e.located())?;
    let cfg = config::parse(&a.config.display().to_string(), &text).map_err(|e| e.located())?;
    let jobs = a.jobs.map_or_else(cores, |j| j as usize);
    let part = a.shard.unwrap_or(Part::ALL);
    let total = rtpipe_campaign::shard_count(&cfg);
    if a.plan {
        return plan(&cfg, a, part, total);
    }
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(cfg.systems.div_ceil(part.count)),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "campaign {msg} [{bar:30}] {pos}/{len} systems, {per_sec}, ETA {eta}",
    ) {
        pb.set_style(style);
    }
    pb.set_message(cfg.name.clone());
    let tick = || pb.inc(1);
    let s = rtpipe_campaign::run(&cfg, &text, &a.out, part, jobs, &tick, stop)
        .map_err(|e| Diagnostic::error(e.message, e.help))?;
    pb.finish_and_clear();
    let summary = CampaignSummary::of(&cfg, a, part, total, &s);
    let report = command::render(&summary, a.output.chosen())?;
    let notes = if s.stopped {
        vec![format!(
            "interrupted (Ctrl-C): {} shard(s) written; run the same command again to resume",
            s.written
        )]
    } else {
        Vec::new()
    };
    let status = if s.stopped {
        crate::interrupted_status()
    } else {
        0
    };
    Ok(Answer {
        report,
        notes,
        status,
    })
}

/// `--plan`: the shards, without running any: which the directory holds
/// whole (this campaign's, checked by their footers) and which it holds
/// unfinished or damaged (run again). A directory of another campaign is
/// refused, as a run refuses it.
fn plan(
    cfg: &config::Config,
    a: &CampaignArgs,
    part: Part,
    total: u64,
) -> Result<Answer, Diagnostic> {
    let found = rtpipe_campaign::survey(&a.out, cfg, part)
        .map_err(|e| Diagnostic::error(e.message, e.help))?;
    let plan = CampaignPlan {
        campaign: cfg.name.clone(),
        fingerprint: cfg.fingerprint(),
        out: a.out.display().to_string(),
        systems: cfg.systems,
        shard_size: cfg.shard_size,
        shards: total,
        part: format!("{}/{}", part.index, part.count),
        part_shards: part.shard_count(total),
        written: found.done.iter().copied().collect(),
        rerun: found.rerun.keys().copied().collect(),
    };
    let report = command::render(&plan, a.output.chosen())?;
    let notes = found
        .rerun
        .iter()
        .map(|(k, why)| {
            format!(
                "{} {why}: it will be run again",
                rtpipe_campaign::shard_path(&a.out, *k).display()
            )
        })
        .collect();
    Ok(Answer {
        report,
        notes,
        status: 0,
    })
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

/// `campaign --plan`'s report: the shards of the part, which the
/// directory holds whole and which it will run again.
#[derive(Serialize, schemars::JsonSchema)]
struct CampaignPlan {
    /// The campaign's name.
    campaign: String,
    /// The campaign's identity: a hash of every value that decides its
    /// rows, written in every shard's footer.
    fingerprint: String,
    /// The output directory.
    out: String,
    /// Systems in the whole campaign.
    systems: u64,
    /// Systems per shard.
    shard_size: u64,
    /// Shards in the whole campaign.
    shards: u64,
    /// The part planned, `i/n` (`0/1` for all).
    part: String,
    /// Shards in the part.
    part_shards: u64,
    /// The part's shards the directory holds whole.
    written: Vec<u64>,
    /// The part's shards there unfinished or damaged (run again).
    rerun: Vec<u64>,
}

impl rtpipe_printer::Report for CampaignPlan {
    fn text(&self) -> String {
        format!(
            "campaign {}: {} systems in {} shards of {}; part {} owns {} ({} already in {}, {} to run again)\n",
            self.campaign,
            self.systems,
            self.shards,
            self.shard_size,
            self.part,
            self.part_shards,
            self.written.len(),
            self.out,
            self.rerun.len()
        )
    }

    /// The plan (one row), then a row per shard of the part that the
    /// directory holds (`written`) or will run again (`rerun`).
    fn tables(&self) -> Vec<Table> {
        let plan = record_table(
            "plan",
            vec![
                ("campaign", Kind::Text, Cell::from(self.campaign.as_str())),
                (
                    "fingerprint",
                    Kind::Text,
                    Cell::from(self.fingerprint.as_str()),
                ),
                ("out", Kind::Text, Cell::from(self.out.as_str())),
                ("systems", Kind::UInt, Cell::UInt(self.systems)),
                ("shard_size", Kind::UInt, Cell::UInt(self.shard_size)),
                ("shards", Kind::UInt, Cell::UInt(self.shards)),
                ("part", Kind::Text, Cell::from(self.part.as_str())),
                ("part_shards", Kind::UInt, Cell::UInt(self.part_shards)),
            ],
        );
        let columns = vec![
            Column::new("shard", Kind::UInt),
            Column::new("state", Kind::Text),
        ];
        let Ok(mut shards) = Table::new("shards", columns) else {
            unreachable!("the shards table's columns are distinct names");
        };
        let states = [("written", &self.written), ("rerun", &self.rerun)];
        for (state, ks) in states {
            for k in ks {
                shards.push(vec![Cell::UInt(*k), Cell::from(state)]);
            }
        }
        vec![plan, shards]
    }
}

/// `rtpipe campaign`'s report: what a run of the part wrote, and how fast.
#[derive(Serialize, schemars::JsonSchema)]
pub struct CampaignSummary {
    /// The campaign's name.
    campaign: String,
    /// The output directory.
    out: String,
    /// Systems in the whole campaign.
    systems: u64,
    /// Systems per shard.
    shard_size: u64,
    /// Shards in the whole campaign.
    shards: u64,
    /// The part run, `i/n` (`0/1` for all).
    part: String,
    /// Shards in the part.
    part_shards: u64,
    /// Shards written by this run.
    written: u64,
    /// Damaged or unfinished shards written again.
    rewritten: u64,
    /// Shards the directory already held whole.
    skipped: u64,
    /// Systems this run analysed and simulated.
    systems_run: u64,
    /// Systems that got fewer chains than asked (the generator found too
    /// few).
    systems_short: u64,
    /// Systems generated without any chain.
    systems_without_chains: u64,
    /// Chains asked per system.
    chains_asked: u32,
    /// Rows written (one per chain and metric).
    rows: u64,
    /// Wall-clock seconds the run took.
    seconds: f64,
    /// Worker threads used.
    jobs: usize,
    /// Systems run per wall-clock second.
    systems_per_second: f64,
    /// systems_per_second / jobs.
    systems_per_second_per_job: f64,
    /// Whether Ctrl-C (or the stop flag) ended the run early.
    stopped: bool,
}

impl CampaignSummary {
    fn of(
        cfg: &config::Config,
        a: &CampaignArgs,
        part: Part,
        total: u64,
        s: &Summary,
    ) -> CampaignSummary {
        let rate = s.systems as f64 / s.seconds.max(1e-9);
        CampaignSummary {
            campaign: cfg.name.clone(),
            out: a.out.display().to_string(),
            systems: cfg.systems,
            shard_size: cfg.shard_size,
            shards: total,
            part: format!("{}/{}", part.index, part.count),
            part_shards: s.shards,
            written: s.written,
            rewritten: s.rewritten,
            skipped: s.skipped,
            systems_run: s.systems,
            systems_short: s.short,
            systems_without_chains: s.chainless,
            chains_asked: cfg.generate.chains,
            rows: s.rows,
            seconds: s.seconds,
            jobs: s.jobs,
            systems_per_second: rate,
            systems_per_second_per_job: rate / s.jobs as f64,
            stopped: s.stopped,
        }
    }
}

impl rtpipe_printer::Report for CampaignSummary {
    fn text(&self) -> String {
        let mut t = format!(
            "campaign {}: {} systems in {} shards of {}; part {} owns {}\n\
             wrote {} shard(s) to {} ({} already there{}): {} systems, {} rows in {:.2} s on {} thread(s)\n\
             throughput: {:.0} systems/s, {:.0} per thread\n",
            self.campaign,
            self.systems,
            self.shards,
            self.shard_size,
            self.part,
            self.part_shards,
            self.written,
            self.out,
            self.skipped,
            match self.rewritten {
                0 => String::new(),
                n => format!(", {n} unfinished or damaged and written again"),
            },
            self.systems_run,
            self.rows,
            self.seconds,
            self.jobs,
            self.systems_per_second,
            self.systems_per_second_per_job
        );
        if self.systems_short > 0 {
            t += &format!(
                "short: {} of {} systems have fewer than the {} chains asked ({} have none, so no rows): \
                 the generator found too few; their rows' `chains` column says how many they got\n",
                self.systems_short, self.systems_run, self.chains_asked, self.systems_without_chains
            );
        }
        t
    }

    /// The summary as one row, its columns the JSON's keys.
    fn tables(&self) -> Vec<Table> {
        let u = Cell::UInt;
        let f = Cell::Float;
        vec![record_table(
            "campaign",
            vec![
                ("campaign", Kind::Text, Cell::from(self.campaign.as_str())),
                ("out", Kind::Text, Cell::from(self.out.as_str())),
                ("systems", Kind::UInt, u(self.systems)),
                ("shard_size", Kind::UInt, u(self.shard_size)),
                ("shards", Kind::UInt, u(self.shards)),
                ("part", Kind::Text, Cell::from(self.part.as_str())),
                ("part_shards", Kind::UInt, u(self.part_shards)),
                ("written", Kind::UInt, u(self.written)),
                ("rewritten", Kind::UInt, u(self.rewritten)),
                ("skipped", Kind::UInt, u(self.skipped)),
                ("systems_run", Kind::UInt, u(self.systems_run)),
                ("systems_short", Kind::UInt, u(self.systems_short)),
                (
                    "systems_without_chains",
                    Kind::UInt,
                    u(self.systems_without_chains),
                ),
                ("chains_asked", Kind::UInt, u(u64::from(self.chains_asked))),
                ("rows", Kind::UInt, u(self.rows)),
                ("seconds", Kind::Float, f(self.seconds)),
                ("jobs", Kind::UInt, u(self.jobs as u64)),
                (
                    "systems_per_second",
                    Kind::Float,
                    f(self.systems_per_second),
                ),
                (
                    "systems_per_second_per_job",
                    Kind::Float,
                    f(self.systems_per_second_per_job),
                ),
                ("stopped", Kind::Bool, Cell::Bool(self.stopped)),
            ],
        )]
    }
}

impl command::Registered for CampaignArgs {
    fn run(&self) -> ExitCode {
        run(self)
    }

    fn call(&self, call: command::Call<'_>) -> Result<command::Done, Diagnostic> {
        execute(self, &call.stop_fn()).map(command::Done::from)
    }
}

/// The JSON Schema of `--json`'s report (its fields and their doc
/// comments: the source of the Python package's typed results).
pub fn json_schema() -> schemars::Schema {
    schemars::schema_for!(CampaignSummary)
}

/// The JSON Schema of `campaign --plan --json`'s report.
pub fn plan_json_schema() -> schemars::Schema {
    schemars::schema_for!(CampaignPlan)
}
