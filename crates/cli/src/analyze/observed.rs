//! `analyze --observed FILE.csv`: measured chain latencies held against the
//! report's bounds. The file is read and judged by
//! `rtpipe_sim::observe::file` (per-row work, built optimised); the report's
//! JSON view and text are here.

mod render;

pub use render::{text, view, ObservedView};
pub use rtpipe_sim::observe::file::{read, Entry, Observed, OPEN_SAMPLES};
