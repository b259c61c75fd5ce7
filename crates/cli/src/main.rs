//! `rtpipe`: analyse pipe systems (Cheng, West, Einstein, EMSOFT 2018).

use clap::{CommandFactory, FromArgMatches, Parser};
use rtpipe::registry::Commands;
use rtpipe::{output, EXIT_BAD_INPUT, EXIT_BROKEN_PIPE, EXIT_INTERNAL};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "rtpipe",
    version,
    about = "End-to-end timing analysis of pipelines of periodic tasks (the pipe model of Cheng, West, Einstein, EMSOFT 2018)"
)]
struct Cli {
    #[command(subcommand)]
    command: Commands,
}

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

fn main() -> ExitCode {
    exit_on_panic();
    let cli = match Cli::from_arg_matches(&Cli::command().get_matches()) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    let command = cli.command.registered();
    // No output flag may replace a file the command reads.
    for (flag, path) in command.inputs() {
        output::register_input(flag, path);
    }
    command.run()
}
