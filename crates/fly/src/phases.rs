//! The phases of a flight: where each periodic task's first release falls
//! within its period, and where the mission's stick steps fall within the
//! motor-output period. Neither is the controller's design, yet either can
//! decide whether a flight meets its criteria (a step that lands just after
//! an output job waits a whole output period for its first effect), so a
//! limit or a design judged by flights is flown over several of them.
//!
//! Draw 0 is the nominal phase (every task at 0, steps where the mission
//! puts them); draw k ≥ 1 places each periodic task's first release
//! uniformly in [0, T) and shifts every step after the start uniformly in
//! [0, T_out), from its own random stream (SplitMix64, `rtpipe_sim::Rng`)
//! — independent of the seed of the noise and execution times, so seeds and
//! phases vary separately. A task with a known offset in the spec keeps it;
//! a data-triggered task has none.

use crate::Setup;
use rtpipe_flight::tasks::BodyKind;
use rtpipe_model::{Nanos, Spec};
use rtpipe_sim::Rng;

/// Mixed into the draw's index so that phase streams differ from the
/// simulator's seeded streams of the same number.
const PHASE_STREAM: u64 = 0x5048_4153_4553_0001;

/// `s` at phase draw `draw` (0: `s` itself). The flight is lengthened by
/// the steps' shift, so that it still ends as long after the last step.
pub fn phased(spec: &Spec, s: &Setup, draw: u64) -> Setup {
    if draw == 0 {
        return s.clone();
    }
    let mut rng = Rng::new(draw ^ PHASE_STREAM);
    let offsets = spec
        .tasks
        .iter()
        .map(|t| match (t.is_triggered(), t.offset, t.fixed_period()) {
            (true, _, _) => 0,
            (false, Some(known), _) => known,
            (false, None, Some(p)) if p > 0 => rng.range(0, p as u64 - 1) as Nanos,
            (false, None, _) => 0,
        })
        .collect();
    let shift = output_period(spec, s).map_or(0, |p| rng.range(0, p as u64 - 1));
    let mut out = s.clone();
    out.offsets = Some(offsets);
    out.mission = s.mission.shifted(shift);
    out.horizon = s.horizon + shift as Nanos;
    out
}

/// The motor-output task's period (the first one's, when several).
fn output_period(spec: &Spec, s: &Setup) -> Option<Nanos> {
    let i = s.kinds.iter().position(|k| *k == Some(BodyKind::Pwm))?;
    spec.activation_period(i).filter(|&p| p > 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cleanflight() -> (Spec, Setup) {
        crate::sweep::tests::cleanflight("racer5")
    }

    #[test]
    fn draws_place_every_task_within_its_period_and_shift_the_steps() {
        let (spec, s) = cleanflight();
        assert!(phased(&spec, &s, 0).offsets.is_none(), "draw 0 is nominal");
        let pwm = output_period(&spec, &s).unwrap_or(0);
        assert!(pwm > 0);
        let mut shifts = Vec::new();
        for draw in 1..=20 {
            let p = phased(&spec, &s, draw);
            let Some(offsets) = &p.offsets else {
                panic!("draw {draw} has no offsets");
            };
            for (t, &o) in spec.tasks.iter().zip(offsets) {
                let period = t.fixed_period().unwrap_or(1);
                assert!((0..period).contains(&o), "{} at {o}", t.name);
            }
            let shift = p.horizon - s.horizon;
            assert!((0..pwm).contains(&shift));
            for (a, b) in s.mission.steps.iter().zip(&p.mission.steps) {
                let by = if a.t_ns == 0 { 0 } else { shift as u64 };
                assert_eq!(b.t_ns, a.t_ns + by);
            }
            shifts.push(shift);
            assert_eq!(phased(&spec, &s, draw).offsets, p.offsets, "deterministic");
        }
        shifts.sort_unstable();
        shifts.dedup();
        assert!(shifts.len() > 15, "the shifts vary: {shifts:?}");
    }
}
