//! The one registration of every command: its name and help (the doc
//! comment, which `rtpipe --help` and docs/reference/cli.md show), its
//! flags (the clap struct, which implements [`Registered`] in the
//! command's own file) and how Python reaches it. The binary (`main.rs`)
//! parses and runs a [`Commands`]; the Python package's entry points
//! (`api.rs`) parse the same enum from its keywords and call it. Adding a
//! command is its file and one line here.

use crate::command::{Reach, Registered};
use crate::{analyze, campaign, design, fly, generate, import, run, simulate};

/// Declares [`Commands`] (the clap subcommands, one variant per command)
/// and, beside each, how Python reaches it, from one list.
macro_rules! commands {
    ($($(#[$help:meta])* $variant:ident($args:ty) => [$(($path:literal, $reach:expr)),+ $(,)?],)+) => {
        /// Every command of the binary.
        #[derive(clap::Subcommand)]
        pub enum Commands {
            $($(#[$help])* $variant($args),)+
        }

        impl Commands {
            /// The command's flags, as the command they are.
            pub fn registered(&self) -> &dyn Registered {
                match self {
                    $(Commands::$variant(a) => a,)+
                }
            }
        }

        /// How Python reaches each command: its path (`import e2eeval`
        /// for a command with subcommands), and the function or method
        /// that calls it, or why none does.
        pub const REACH: &[(&str, Reach)] = &[$($(($path, $reach),)+)+];
    };
}

commands! {
    /// Schedulability and worst-case reaction/freshness bounds of every chain.
    ///
    /// Exit status: 0 when every limit and the schedulability test hold (under
    /// the analysis --mode names, sound by default), 1 when one fails, 2 on bad
    /// input, 3 on an internal error (a bug).
    Analyze(analyze::AnalyzeArgs) => [("analyze", Reach::Python("System.analyze"))],
    /// Simulate the system and hold observed reaction and freshness times
    /// against the analysis' bounds.
    ///
    /// Exit status: 0 when no sample exceeds a sound bound, 1 when one does
    /// (a bug in the analysis), 2 on bad input (flags, spec, output paths), 3
    /// on an internal error (a bug).
    Simulate(simulate::SimulateArgs) => [("simulate", Reach::Python("System.simulate"))],
    /// Fly a simulated quadrotor with the spec's task code on the simulated
    /// schedule (software in the loop) and report the flight's quality and
    /// each chain's observed latencies against the bounds.
    ///
    /// Exit status: 0 when the flight meets its criteria and no sample
    /// exceeds a sound bound, 1 otherwise, 2 on bad input, 3 on an internal
    /// error.
    Fly(fly::FlyArgs) => [("fly", Reach::Python("System.fly"))],
    /// Run the spec for real: one thread per task under SCHED_FIFO (rm) or
    /// SCHED_DEADLINE (edf), synthetic bodies burning each task's demand,
    /// four-slot registers between tasks; observed reaction and freshness
    /// against the bounds, response times, overruns, missed periods.
    ///
    /// Exit status: 0 when the run completed and no observation exceeds a
    /// sound bound or the excess is explained by the measurement (overruns,
    /// missed periods, steal time, best effort), 1 otherwise, 2 on bad input
    /// or when the kernel refuses the scheduling class, 3 on an internal
    /// error.
    Run(run::RunArgs) => [("run", Reach::Python("System.run"))],
    /// Choose the free periods so that every limit holds at least utilisation
    /// (Section IV), and re-check the answer with the analysis.
    ///
    /// Exit status: 0 with a verified design, 1 when none exists (or none was
    /// found in time), 2 on bad input (flags, spec, output path), 3 when the
    /// solver fails or on an internal error (a bug), 130 when Ctrl-C stopped
    /// the search (the best verified design so far is printed, and written
    /// with --write).
    Design(design::DesignArgs) => [("design", Reach::Python("System.design"))],
    /// Turn the task sets of other tools into rtpipe specs: `import e2eeval
    /// FILE.yaml OUTDIR` reads TU Dortmund's E2EEvaluation framework,
    /// `import px4-ulog LOG.ulg OUTDIR` a PX4 flight log.
    ///
    /// Exit status: 0 when every spec was written, 2 on bad input (nothing is
    /// written then), 3 on an internal error.
    Import(import::ImportArgs) => [
        ("import e2eeval", Reach::Python("rtpipe.import_e2eeval")),
        ("import px4-ulog", Reach::Python("rtpipe.import_px4_ulog")),
    ],
    /// Generate random systems: `generate waters` writes an automotive task
    /// set with cause-effect chains (WATERS 2015, as E2EEvaluation does).
    ///
    /// Exit status: 0 when the spec was written, 2 on bad input, 3 on an
    /// internal error.
    Generate(generate::GenerateArgs) => [("generate waters", Reach::Python("rtpipe.waters"))],
    /// Generate, analyse (and simulate) many task sets on every core, into
    /// sharded Parquet: deterministic per seed, resumable, `--shard i/n` to
    /// fan out over machines.
    ///
    /// Exit status: 0 when every shard of the part is written, 2 on bad
    /// input (config, flags, output directory), 3 on an internal error, 130
    /// when Ctrl-C stopped it (the shards written stay; run again to resume).
    Campaign(campaign::CampaignArgs) => [("campaign", Reach::Python("rtpipe.campaign"))],
}

/// How Python reaches the command at `path` (`analyze`, `import
/// e2eeval`), if it is registered.
pub fn reach(path: &str) -> Option<Reach> {
    REACH.iter().find(|(p, _)| *p == path).map(|(_, r)| *r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Subcommand;

    /// The binary's command paths, down to the commands that run.
    fn leaves(cmd: &clap::Command, prefix: &str, out: &mut Vec<String>) {
        for sub in cmd.get_subcommands() {
            let path = format!("{prefix}{}", sub.get_name());
            if sub.has_subcommands() {
                leaves(sub, &format!("{path} "), out);
            } else {
                out.push(path);
            }
        }
    }

    #[test]
    fn every_command_of_the_binary_says_how_python_reaches_it() {
        let cmd = Commands::augment_subcommands(clap::Command::new("rtpipe"));
        let mut paths = Vec::new();
        leaves(&cmd, "", &mut paths);
        let listed: Vec<String> = REACH.iter().map(|(p, _)| p.to_string()).collect();
        assert_eq!(
            paths, listed,
            "REACH lists every command of the binary, in order"
        );
        for (path, r) in REACH {
            match r {
                Reach::Python(name) => assert!(
                    name.starts_with("rtpipe.") || name.starts_with("System."),
                    "{path}: {name}"
                ),
                Reach::Not(why) => assert!(!why.is_empty(), "{path}: say why not"),
            }
        }
    }
}
