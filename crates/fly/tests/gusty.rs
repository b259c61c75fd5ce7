//! The `gusty` mission on Table V's schedule (examples/cleanflight.toml):
//! hover attitude errors of the order real vehicles show, growing with the
//! turbulence.

use rtpipe_flight::preset::BUILTIN;
use rtpipe_flight::wind::Intensity;
use rtpipe_fly::{fly, setup, Request};
use rtpipe_model::Spec;
use rtpipe_sim::ExecModel;
use std::path::Path;

#[test]
fn table_v_hovers_in_gusts_with_real_world_attitude_errors() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cleanflight.toml");
    let spec = Spec::load(&path).unwrap_or_else(|e| panic!("{e}"));
    for vehicle in BUILTIN {
        let mut rms = Vec::new();
        for intensity in Intensity::ALL {
            let r = Request {
                spec_path: &path,
                vehicle,
                mission: "gusty",
                horizon: None,
                seed: 0,
            };
            let mut s = setup(&spec, &r).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.mission.world.turbulence, Intensity::Moderate);
            s.mission.world.turbulence = intensity;
            let f = fly(&spec, &s, ExecModel::Uniform).unwrap_or_else(|e| panic!("{e}"));
            let q = &f.quality;
            println!(
                "{vehicle} {:>8}: attitude RMS {:.3}°, altitude RMS {:.4} m, position RMS {:.3} m, failures {:?}",
                intensity.name(),
                q.attitude_error_deg.rms,
                q.altitude_error_m.rms,
                q.position_error_m.rms,
                q.failures(&s.criteria())
            );
            assert!(!q.crashed && q.landed_s.is_some(), "{vehicle}: {q:?}");
            // 20 s of hover judged (4 s to 24 s, one point every 2 ms).
            assert!(q.attitude_error_deg.count >= 9_900, "{vehicle}: {q:?}");
            rms.push(q.attitude_error_deg.rms);
        }
        // Moderate turbulence: between 0.2° and 5°, as real multirotors.
        assert!((0.2..5.0).contains(&rms[2]), "{vehicle}: {rms:?}");
        // More turbulence, more attitude error.
        assert!(rms[3] > rms[0], "{vehicle}: {rms:?}");
    }
}
