//! `rtpipe` as a library: every command of the `rtpipe` binary (parse,
//! call, render), and [`api`], the entry points the Python package calls.
//! The binary (`main.rs`) is only the command line in front of them.

pub mod analyze;
pub mod api;
pub mod campaign;
pub mod command;
pub mod design;
pub mod fly;
pub mod generate;
pub mod import;
pub mod output;
pub mod plot;
pub mod registry;
pub mod report;
pub mod run;
pub mod schema;
pub mod simulate;
pub mod table;

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

/// Exit status of a command a stop signal ended early: 128 + the signal,
/// as a shell reports a process that signal ended (130 for Ctrl-C, 143
/// for SIGTERM, 129 for SIGHUP; `rtpipe_runtime::sys::STOP_SIGNALS`).
pub fn interrupted_status() -> u8 {
    rtpipe_runtime::sys::stop_signal()
        .and_then(|s| u8::try_from(128 + s).ok())
        .unwrap_or(EXIT_INTERRUPTED)
}

/// Exit status when the reader of stdout went away (128 + SIGPIPE, what a
/// shell reports for a process a broken pipe ends).
pub const EXIT_BROKEN_PIPE: u8 = 141;
