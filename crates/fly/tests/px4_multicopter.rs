//! PX4's multicopter rate loop from the Cube Orange log
//! (examples/px4-multicopter.toml): the gyro driver every 2.5 ms, the rate
//! controller and the output driver released by each sample, the attitude
//! controller at the log's interval. Both bundled vehicles fly the `steps`
//! and `gusty` missions within their criteria, and every observed latency,
//! from the read and from the event, stays within its sound bound.

use rtpipe_analysis::{analyze, Anchor, Metric, Mode};
use rtpipe_flight::preset::BUILTIN;
use rtpipe_fly::{fly, setup, Request};
use rtpipe_joblog::ChainStats;
use rtpipe_model::Spec;
use rtpipe_sim::ExecModel;
use std::path::Path;

#[test]
fn px4_multicopter_flies_steps_and_gusty_on_both_vehicles() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/px4-multicopter.toml");
    let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let report = analyze(&spec);
    assert!(
        report.ok_in(Mode::Sound),
        "px4-multicopter.toml is not sound"
    );
    let rate_pid = spec
        .tasks
        .iter()
        .position(|t| t.name == "mc_rate_control")
        .unwrap_or_else(|| panic!("no mc_rate_control task"));
    for vehicle in BUILTIN {
        for mission in ["steps", "gusty"] {
            let r = Request {
                spec_path: &path,
                vehicle,
                mission,
                horizon: None,
                seed: 0,
            };
            let s = setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
            // The sensor delivers a sample for every read of the driver.
            assert_eq!(s.world.imu.gyro_odr_hz, 400);
            let f = fly(&spec, &s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"));
            let failures = f.quality.failures(&s.criteria());
            assert!(failures.is_empty(), "{vehicle} {mission}: {failures:?}");
            // One rate-controller job per gyro sample: 400 Hz over the flight.
            let seconds = f.sim.horizon as f64 * 1e-9;
            let jobs = f.sim.tasks[rate_pid].completed as f64;
            assert!(
                (jobs - 400.0 * seconds).abs() <= 2.0,
                "{vehicle} {mission}: {jobs} rate-loop jobs in {seconds} s"
            );
            within_sound_bounds(&report, &f.sim.chains, &format!("{vehicle} {mission}"));
        }
    }
}

/// Every chain's largest observed reaction and freshness, from the head's
/// read and from the event, is measured and at most its sound bound.
fn within_sound_bounds(report: &rtpipe_analysis::Report, chains: &[ChainStats], what: &str) {
    for c in &report.chains {
        let o = &chains[c.chain];
        let (read, event) = match c.metric {
            Metric::Reaction => (o.reaction.max, o.event_reaction.max),
            Metric::Freshness => (o.freshness.max, o.event_freshness.max),
        };
        for (anchor, max) in [(Anchor::Read, read), (Anchor::Event, event)] {
            let bound = c.bound.sound(anchor);
            assert!(
                max.is_some() && bound.is_some() && max <= bound,
                "{what}, chain {} {:?} from {anchor:?}: observed {max:?} > sound {bound:?}",
                c.chain,
                c.metric
            );
        }
    }
}
