//! `rtpipe`: analyse pipe systems (Cheng, West, Einstein, EMSOFT 2018).

mod analyze;
mod command;
mod design;
mod fly;
mod generate;
mod import;
mod output;
mod plot;
mod report;
mod run;
mod simulate;
mod table;

use clap::builder::TypedValueParser;
use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use rtpipe_analysis::Mode;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "rtpipe",
    version,
    about = "End-to-end timing analysis of pipelines of periodic tasks (the pipe model of Cheng, West, Einstein, EMSOFT 2018)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Schedulability and worst-case reaction/freshness bounds of every chain.
    ///
    /// Exit status: 0 when every limit and the schedulability test hold (under
    /// the analysis --mode names, sound by default), 1 when one fails, 2 on bad
    /// input, 3 on an internal error (a bug).
    Analyze {
        /// The system spec (TOML), e.g. examples/paper-table2.toml.
        spec: PathBuf,
        /// Print one JSON object instead of tables.
        #[arg(long)]
        json: bool,
        /// Also list the worst path between every source and sink.
        #[arg(long)]
        all_paths: bool,
        /// The analysis the verdict and the exit status follow (both are
        /// always shown).
        #[arg(long, value_parser = mode_parser(), default_value = "sound")]
        mode: Mode,
    },
    /// Simulate the system and hold observed reaction and freshness times
    /// against the analysis' bounds.
    ///
    /// Exit status: 0 when no sample exceeds a sound bound, 1 when one does
    /// (a bug in the analysis), 2 on bad input (flags, spec, output paths), 3
    /// on an internal error (a bug).
    Simulate(simulate::SimulateArgs),
    /// Fly a simulated quadrotor with the spec's task code on the simulated
    /// schedule (software in the loop) and report the flight's quality and
    /// each chain's observed latencies against the bounds.
    ///
    /// Exit status: 0 when the flight meets its criteria and no sample
    /// exceeds a sound bound, 1 otherwise, 2 on bad input, 3 on an internal
    /// error.
    Fly(fly::FlyArgs),
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
    Run(run::RunArgs),
    /// Choose the free periods so that every limit holds at least utilisation
    /// (Section IV), and re-check the answer with the analysis.
    ///
    /// Exit status: 0 with a verified design, 1 when none exists (or none was
    /// found in time), 2 on bad input (flags, spec, output path), 3 when the
    /// solver fails or on an internal error (a bug), 130 when Ctrl-C stopped
    /// the search (the best verified design so far is printed, and written
    /// with --write).
    Design {
        /// The system spec (TOML); tasks without a fixed period are designed.
        spec: PathBuf,
        /// The analysis the chain limits are judged by.
        #[arg(long, value_parser = mode_parser(), default_value = "sound")]
        mode: Mode,
        /// Print one JSON object: the analysis of the design plus "design".
        #[arg(long)]
        json: bool,
        /// Write the complete designed spec here (accepted by `analyze`).
        /// Symlinks are followed; only regular files are replaced, atomically;
        /// never the input spec unless --overwrite-spec is given.
        #[arg(long, value_name = "OUT.toml")]
        write: Option<PathBuf>,
        /// Allow --write to replace the input spec (its comments and period
        /// ranges are lost).
        #[arg(long, requires = "write")]
        overwrite_spec: bool,
        /// The exact search: `boxes` (branch and bound over period boxes,
        /// pruned by the sound analysis; sound mode without harmonic
        /// periods), `milp` (the mixed-integer model; every case), or `auto`
        /// (boxes where they apply, else milp).
        #[arg(long, value_enum, default_value = "auto")]
        method: design::MethodArg,
        /// MILP backend [default: highs when built with `--features highs`,
        /// else microlp].
        #[arg(long, value_enum)]
        solver: Option<design::SolverArg>,
        /// Stop after this many seconds (at most 1000000) and report the best
        /// verified design and its gap. Without it the search is bounded by
        /// work, not time, so the answer is the same on every machine.
        #[arg(long, value_name = "S", value_parser = design::parse_time_limit, allow_hyphen_values = true)]
        time_limit: Option<f64>,
        /// Fly every design the search would return on this mission (built-in
        /// steps, hover, paper, gusty, or a mission file; repeat or separate
        /// with commas for several): one that misses the mission's criteria is
        /// cut, with every design no faster than 95 % of it, and the search
        /// goes on. The answer is the least-utilisation design that both
        /// verifies and flies. Box search only (sound mode, no harmonic periods).
        #[arg(long = "fly", value_name = "MISSION", value_delimiter = ',')]
        missions: Vec<String>,
        /// With --fly: the vehicles (built-in racer5, aero1kg, or preset files;
        /// repeat or separate with commas) [default: racer5].
        #[arg(long = "vehicle", value_name = "PRESET|FILE", value_delimiter = ',')]
        vehicles: Vec<String>,
        /// With --fly: the seeds of the sensor noise and execution times
        /// (repeat or separate with commas) [default: 0].
        #[arg(long = "seed", value_name = "S", value_delimiter = ',')]
        seeds: Vec<u64>,
    },
    /// Turn the task sets of other tools into rtpipe specs: `import e2eeval
    /// FILE.yaml OUTDIR` reads TU Dortmund's E2EEvaluation framework.
    ///
    /// Exit status: 0 when every spec was written, 2 on bad input (nothing is
    /// written then), 3 on an internal error.
    Import {
        #[command(subcommand)]
        format: import::ImportCommand,
    },
    /// Generate random systems: `generate waters` writes an automotive task
    /// set with cause-effect chains (WATERS 2015, as E2EEvaluation does).
    ///
    /// Exit status: 0 when the spec was written, 2 on bad input, 3 on an
    /// internal error.
    Generate {
        #[command(subcommand)]
        kind: generate::GenerateCommand,
    },
}

/// `--mode`: the one [`Mode`] of the analysis crate, its names listed in
/// the help and in errors.
fn mode_parser() -> impl clap::builder::TypedValueParser<Value = Mode> {
    clap::builder::PossibleValuesParser::new(Mode::ALL.map(Mode::name))
        .try_map(|s| s.parse::<Mode>())
}

/// A spinner with a message and the elapsed time on stderr (hidden when
/// stderr is not a terminal).
pub fn spinner(msg: String) -> indicatif::ProgressBar {
    let pb =
        indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{spinner} {msg} [{elapsed_precise}]")
    {
        pb.set_style(style);
    }
    pb.set_message(msg);
    pb.enable_steady_tick(std::time::Duration::from_millis(100));
    pb
}

/// Exit status for bad input (clap uses 2 for bad flags too).
pub const EXIT_BAD_INPUT: u8 = 2;

/// Exit status for an internal error: a panic (a bug) or a solver failure.
pub const EXIT_INTERNAL: u8 = 3;

/// Exit status when Ctrl-C stopped `design` (128 + SIGINT, as a shell
/// reports a process that SIGINT ended), whether or not a design was found
/// and printed: the answer is not the one the complete search gives.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Exit status when the reader of stdout went away (128 + SIGPIPE, what a
/// shell reports for a process a broken pipe ends).
pub const EXIT_BROKEN_PIPE: u8 = 141;

/// A panic anywhere (any thread) prints its message and ends the process
/// with [`EXIT_INTERNAL`]: it never leaves a waiting thread behind. A
/// failed write to stdout or stderr (`print!` panics on one) is not a bug:
/// a closed pipe ends the process quietly, any other failure (a full disk)
/// with a plain error and [`EXIT_BAD_INPUT`], as an output file that cannot
/// be written does.
fn exit_on_panic() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(why) = payload.strip_prefix("failed printing to std") {
            if why.contains("Broken pipe") {
                std::process::exit(i32::from(EXIT_BROKEN_PIPE));
            }
            if why.starts_with("err") {
                // Nowhere left to say it (printing would panic again).
                std::process::exit(i32::from(EXIT_BAD_INPUT));
            }
            let why = why.trim_start_matches("out: ").trim_start_matches("err: ");
            eprintln!("error: cannot write the output: {why}");
            std::process::exit(i32::from(EXIT_BAD_INPUT));
        }
        default(info);
        eprintln!(
            "error: internal error (a bug in rtpipe); please report it with the spec and the command line"
        );
        std::process::exit(i32::from(EXIT_INTERNAL));
    }));
}

/// Every file the command reads besides its spec, so that no output flag
/// replaces one ([`output::register_input`]); built-in vehicles and
/// missions are names, not files.
fn register_inputs(command: &Command) {
    let world = |vehicle: &str, mission: &str| {
        if !rtpipe_flight::preset::BUILTIN.contains(&vehicle) {
            output::register_input("--vehicle", std::path::Path::new(vehicle));
        }
        if !rtpipe_flight::radio::BUILTIN_MISSIONS.contains(&mission) {
            output::register_input("--mission", std::path::Path::new(mission));
        }
    };
    match command {
        Command::Fly(a) => {
            world(&a.vehicle, &a.mission);
            if let Some(c) = &a.criterion {
                output::register_input("--criterion", c);
            }
        }
        Command::Run(a) => world(&a.vehicle, &a.mission),
        Command::Design {
            missions, vehicles, ..
        } => {
            vehicles.iter().for_each(|v| world(v, "steps"));
            missions.iter().for_each(|m| world("racer5", m));
        }
        Command::Import { format } => import::register_inputs(format),
        _ => {}
    }
}

fn main() -> ExitCode {
    exit_on_panic();
    let matches = Cli::command().get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    let given = |name: &str| {
        matches.subcommand().is_some_and(|(_, m)| {
            m.try_get_raw(name).is_ok_and(|v| v.is_some())
                && m.value_source(name) == Some(ValueSource::CommandLine)
        })
    };
    let (seed_given, steps_given) = (given("seed"), given("search_steps"));
    register_inputs(&cli.command);
    match cli.command {
        Command::Analyze {
            spec,
            json,
            all_paths,
            mode,
        } => analyze::run(&spec, json, all_paths, mode),
        Command::Simulate(mut args) => {
            args.seed_given = seed_given;
            args.search_steps_given = steps_given;
            simulate::run(&args)
        }
        Command::Fly(args) => fly::run(&args),
        Command::Run(mut args) => {
            args.world_given = given("vehicle") || given("mission");
            run::run(&args)
        }
        Command::Design {
            spec,
            mode,
            json,
            write,
            overwrite_spec,
            method,
            solver,
            time_limit,
            missions,
            vehicles,
            seeds,
        } => design::run(design::Args {
            spec: &spec,
            mode,
            json,
            write: write.as_deref(),
            overwrite_spec,
            method,
            solver,
            time_limit,
            missions,
            vehicles,
            seeds,
        }),
        Command::Import { format } => import::run(&format),
        Command::Generate { kind } => generate::run(&kind),
    }
}
