//! Missions, vehicle presets and criteria from files: random
//! bytes and mutated valid files are read without a panic, and every
//! refusal names the file (and its line and column when it has a place)
//! and says what is wrong.

use proptest::prelude::*;
use rtpipe_flight::preset::{Preset, AERO1KG_TOML, RACER5_TOML};
use rtpipe_flight::quality::Criteria;
use rtpipe_flight::radio::{Mission, BREEZE_TOML, GUSTY_TOML, HOVER_TOML, PAPER_TOML, STEPS_TOML};
use rtpipe_model::SpecError;
use rtpipe_testkit::Scratch;
use std::path::Path;

const CRITERION: &str = "attitude_rms_deg = 2.0\naltitude_rms_m = 0.1\novershoot = 0.2\nsettling_s = 0.5\nposition_rms_m = 0.3\n";

/// `TAG.toml` (not yet written) in a scratch directory that goes with
/// the guard.
fn file(tag: &str) -> Scratch {
    Scratch::new(&format!("flight-fuzz-{tag}")).within(&format!("{tag}.toml"))
}

/// Reads `bytes` as each kind of file: a refusal names the file and holds a
/// message; an accepted mission or preset has a printable name.
fn read_all(bytes: &[u8]) -> Result<(), TestCaseError> {
    let p = file(&format!("{:?}", std::thread::current().id()).replace(['(', ')'], ""));
    std::fs::write(&p, bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let shown = p.display().to_string();
    let refused = |e: SpecError| -> Result<(), TestCaseError> {
        let d = e.located();
        prop_assert!(d.message.starts_with(&shown), "{}", d.message);
        prop_assert!(d.message.len() > shown.len() + 3, "empty: {}", d.message);
        prop_assert!(
            !d.message.chars().any(|c| c.is_control()),
            "{:?}",
            d.message
        );
        Ok(())
    };
    match Mission::from_file(&p) {
        Ok(m) => prop_assert!(rtpipe_model::input::name_problem(&m.name).is_none()),
        Err(e) => refused(e)?,
    }
    match Preset::from_file(&p) {
        Ok(v) => prop_assert!(rtpipe_model::input::name_problem(&v.name).is_none()),
        Err(e) => refused(e)?,
    }
    if let Err(e) = Criteria::from_file(&p) {
        refused(e)?;
    }
    Ok(())
}

fn mutated(texts: &'static [&'static str]) -> impl Strategy<Value = Vec<u8>> {
    (
        0..texts.len(),
        prop::collection::vec((any::<prop::sample::Index>(), 0u8..4, any::<u8>()), 1..6),
    )
        .prop_map(move |(k, edits)| {
            let mut b = texts[k].as_bytes().to_vec();
            for (at, op, byte) in edits {
                if b.is_empty() {
                    b.push(byte);
                    continue;
                }
                let i = at.index(b.len());
                match op {
                    0 => b[i] = byte,
                    1 => b.insert(i, byte),
                    2 => {
                        b.remove(i);
                    }
                    _ => b.truncate(i),
                }
            }
            b
        })
}

const VALID: [&str; 8] = [
    HOVER_TOML,
    BREEZE_TOML,
    STEPS_TOML,
    PAPER_TOML,
    GUSTY_TOML,
    RACER5_TOML,
    AERO1KG_TOML,
    CRITERION,
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_are_refused_with_a_message(b in prop::collection::vec(any::<u8>(), 0..400)) {
        read_all(&b)?;
    }

    #[test]
    fn mutated_files_are_read_or_refused_with_a_message(b in mutated(&VALID)) {
        read_all(&b)?;
    }
}

#[test]
fn the_valid_files_read() {
    let p = file("valid");
    for (text, kind) in [(HOVER_TOML, 0), (RACER5_TOML, 1), (CRITERION, 2)] {
        let _ = std::fs::write(&p, text);
        let ok = match kind {
            0 => Mission::from_file(Path::new(&p)).is_ok(),
            1 => Preset::from_file(Path::new(&p)).is_ok(),
            _ => Criteria::from_file(Path::new(&p)).is_ok(),
        };
        assert!(ok, "{text}");
    }
}
