//! Ideal timing: the flight tasks of [`crate::tasks`] flying the
//! co-simulated world ([`Cosim`]) with every task released exactly
//! periodically at Cleanflight's Table V rates (gyro and accel 1 ms, AHRS
//! 5 ms, PID 2 ms, motor output 5 ms, radio 10 ms) and every output visible
//! to its consumers, and to the world, a fixed transport delay after the
//! release (latest-value registers). It shows the controller flies at the
//! paper's rates with no scheduling effects at all; `rtpipe fly` runs the
//! same bodies and the same world on the simulated schedule, so the two
//! differ only in timing.
//!
//! The executor here is the whole of what this module adds: it decides when
//! each body runs and when its output is published, nothing else.

use crate::error::ConfigError;
use crate::preset::Preset;
use crate::radio::Mission;
use crate::tasks::{body, BodyKind, Cosim, CosimConfig, Value};
use crate::trace::TracePoint;
use rtpipe_body::{Body, Environment, Job, Nanos, Stamp, Stamped};
use std::collections::VecDeque;

const MS: u64 = 1_000_000;

/// True if `t` is a release instant of a task with period `p` (p > 0).
// The workspace's rust-version (1.80) predates u64::is_multiple_of (1.87).
#[allow(clippy::manual_is_multiple_of)]
fn due(t: u64, p: u64) -> bool {
    t % p == 0
}

/// Task periods and the transport delay, ns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Gyro sampling period.
    pub gyro: u64,
    /// Accelerometer sampling period.
    pub accel: u64,
    /// AHRS period.
    pub ahrs: u64,
    /// PID (+ mixer) period.
    pub pid: u64,
    /// Motor output period.
    pub pwm: u64,
    /// Radio (+ autopilot) period.
    pub radio: u64,
    /// Delay from a release to its output being visible.
    pub delay: u64,
    /// Simulation tick; every period and the delay must be multiples.
    pub tick: u64,
}

impl Timing {
    /// Cleanflight's Table V rates with a `delay_ms` transport delay.
    pub fn table_v(delay_ms: u64) -> Self {
        Self {
            gyro: MS,
            accel: MS,
            ahrs: 5 * MS,
            pid: 2 * MS,
            pwm: 5 * MS,
            radio: 10 * MS,
            delay: delay_ms * MS,
            tick: MS,
        }
    }

    /// The period of the task of `role` (0 for a role the loop lacks).
    fn period(&self, role: BodyKind) -> u64 {
        match role {
            BodyKind::Gyro => self.gyro,
            BodyKind::Accel => self.accel,
            BodyKind::Ahrs => self.ahrs,
            BodyKind::Pid => self.pid,
            BodyKind::Pwm => self.pwm,
            BodyKind::Radio => self.radio,
            _ => 0,
        }
    }

    /// Every period positive and, with the delay, a multiple of a positive
    /// tick: releases and publishes then fall on ticks.
    fn check(&self) -> Result<(), ConfigError> {
        for (role, _) in TASKS {
            let p = self.period(role);
            if self.tick == 0 || p == 0 || !due(p, self.tick) || !due(self.delay, self.tick) {
                return Err(ConfigError::new(
                    format!("timing.{}", role.name()),
                    "periods and the delay must be multiples of a positive tick",
                ));
            }
        }
        Ok(())
    }
}

/// Scenario options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopConfig {
    /// Task timing.
    pub timing: Timing,
    /// Simulated duration, ns.
    pub duration_ns: u64,
    /// The world: IMU noise and its seed, disturbances, radio loss, how
    /// often to record.
    pub world: CosimConfig,
}

impl LoopConfig {
    /// Table V timing with a 2 ms delay, noise on, `secs` long.
    pub fn new(secs: f64, seed: u64) -> Self {
        Self {
            timing: Timing::table_v(2),
            duration_ns: (secs * 1e9) as u64,
            world: CosimConfig::new(seed),
        }
    }
}

/// The loop's tasks in their release order within an instant (the pilot's
/// frame first, the motor output last), each with the tasks it reads, by
/// index into this list: Fig. 11's critical path.
const TASKS: [(BodyKind, &[usize]); 6] = [
    (BodyKind::Radio, &[]),
    (BodyKind::Gyro, &[]),
    (BodyKind::Accel, &[]),
    (BodyKind::Ahrs, &[1, 2]),
    (BodyKind::Pid, &[3, 0]),
    (BodyKind::Pwm, &[4]),
];

/// The ideal-timing executor: bodies, their registers and the outputs in
/// flight to them.
struct Executor {
    timing: Timing,
    bodies: Vec<Box<dyn Body<Value>>>,
    /// The latest published output of each task.
    latest: Vec<Option<Stamped<Value>>>,
    /// Outputs not yet visible, in publish order (one delay for all, so
    /// release order is publish order).
    pending: VecDeque<Stamped<Value>>,
    /// Jobs released so far, per task.
    jobs: Vec<u64>,
}

fn nanos(t: u64) -> Nanos {
    Nanos::try_from(t).unwrap_or(Nanos::MAX)
}

impl Executor {
    /// Makes every output due by `t` visible, and hands it to the world.
    fn publish(&mut self, t: u64, world: &mut Cosim) {
        while let Some(s) = self.pending.front().copied() {
            if s.stamp.publish > nanos(t) {
                break;
            }
            self.pending.pop_front();
            self.latest[s.stamp.task] = Some(s);
            world.actuate(s.stamp.task, s.stamp.publish, &s.value);
        }
    }

    /// Releases every task due at `t`, in [`TASKS`] order: each reads and
    /// runs at its release; with no delay, later tasks see its output.
    fn release(&mut self, t: u64, world: &mut Cosim) {
        let mut inputs: [Option<Stamped<Value>>; 2] = [None; 2];
        for (i, (role, reads)) in TASKS.iter().enumerate() {
            if !due(t, self.timing.period(*role)) {
                continue;
            }
            for (slot, &r) in inputs.iter_mut().zip(reads.iter()) {
                *slot = self.latest[r];
            }
            let job = Job {
                task: i,
                index: self.jobs[i],
                release: nanos(t),
                read: nanos(t),
            };
            self.jobs[i] += 1;
            let device = world.sense(i, job.read);
            let value = self.bodies[i].run(&job, &inputs[..reads.len()], device);
            let stamp = Stamp {
                task: i,
                job: job.index,
                read: job.read,
                publish: nanos(t + self.timing.delay),
            };
            self.pending.push_back(Stamped { value, stamp });
            self.publish(t, world);
        }
    }
}

/// Flies `mission` with `preset` under ideal timing; returns the trace (a
/// point every `cfg.world.trace_every_ns` up to the duration).
pub fn fly(
    preset: &Preset,
    mission: Mission,
    cfg: LoopConfig,
) -> Result<Vec<TracePoint>, ConfigError> {
    let tm = cfg.timing;
    tm.check()?;
    let mut bodies = Vec::with_capacity(TASKS.len());
    for (role, _) in TASKS {
        bodies.push(body(role, nanos(tm.period(role)), preset)?);
    }
    let kinds = TASKS.iter().map(|&(r, _)| Some(r)).collect();
    let mut world = Cosim::new(preset, mission, kinds, cfg.world)?;
    world.reserve(cfg.duration_ns);
    let mut exec = Executor {
        timing: tm,
        bodies,
        latest: vec![None; TASKS.len()],
        pending: VecDeque::new(),
        jobs: vec![0; TASKS.len()],
    };
    let mut t = 0;
    while t < cfg.duration_ns {
        exec.publish(t, &mut world);
        exec.release(t, &mut world);
        t += tm.tick;
    }
    world.advance(cfg.duration_ns);
    Ok(std::mem::take(&mut world.trace))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timing_off_the_tick_is_refused() {
        assert!(Timing::table_v(2).check().is_ok());
        let mut t = Timing::table_v(2);
        t.delay = 1_500_000;
        assert!(t.check().is_err());
        let mut t = Timing::table_v(0);
        t.tick = 0;
        assert!(t.check().is_err());
        let mut t = Timing::table_v(2);
        t.pid = 0;
        let e = t.check().err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("timing.pid"), "{e}");
    }

    /// The motors first spin a transport delay after the motor task's
    /// first armed release, never between releases.
    #[test]
    fn outputs_reach_the_world_a_delay_after_a_release() -> Result<(), ConfigError> {
        let preset = Preset::builtin("racer5")?;
        for delay_ms in [0, 3] {
            let mut cfg = LoopConfig::new(1.0, 1);
            cfg.timing = Timing::table_v(delay_ms);
            cfg.world.trace_every_ns = MS;
            let tr = fly(&preset, Mission::builtin("hover")?, cfg)?;
            let armed = tr.iter().find(|p| p.armed).map_or(0, |p| p.t_ns);
            // The trace records the world before what is published at the
            // same instant, so the first armed point is one tick later.
            let published = armed - MS;
            assert!(armed > 0, "never armed");
            assert_eq!(
                published
                    .checked_sub(delay_ms * MS)
                    .map(|r| r % cfg.timing.pwm),
                Some(0),
                "delay {delay_ms} ms: motors armed at {armed} ns"
            );
        }
        Ok(())
    }
}
