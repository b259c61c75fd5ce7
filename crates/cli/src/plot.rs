//! SVG figures, one module per chart: observed vs predicted end-to-end
//! times (the paper's Fig. 9), the schedule (Gantt), a flight over time,
//! the timing sweep. `canvas` holds what they share.

mod canvas;
mod fig9;
mod flight;
mod gantt;
mod sweep;

pub use fig9::fig9;
pub use flight::{flight_altitude, flight_attitude, flight_motors};
pub use gantt::gantt;
pub use sweep::{sweep_chart, DotOutcome, SweepDot, SweepMeasure};
