//! LET communication in the simulator (`[system] communication = "let"`,
//! Kirsch and Sokolova 2012): a job reads its inputs at its release and
//! its output becomes visible at the end of its period, release + T,
//! whenever the schedule ran it. The schedule still decides when jobs run
//! (and whether one misses its deadline, which the task's statistics
//! count); the sample provenance, the job log and the bodies' hooks
//! (`bodies.rs`: a LET task's body runs on what it read at its release,
//! and its output reaches the registers and the world at its period's
//! end) see only the LET instants, so the measured reaction and freshness
//! are LET's, and so is a flight's data flow (`rtpipe fly`).
//!
//! Per chain (`Spec::communications`) only the LET tasks communicate here;
//! the others read at their start and publish at their completion, which
//! at one instant come first (the engine completes jobs before it
//! releases), so every publish of an instant precedes every read.
//!
//! At one instant every period that ends publishes before any release
//! reads: a job released when its producer's period ends reads the value
//! published then (the LET convention, and the analysis' in
//! `rtpipe_analysis::let_bound`). The model refuses jitter under LET, so a
//! task's period ends exactly at its next release.

use crate::engine::{Hooks, LetJob, Sim};
use rtpipe_joblog::JobRecord;

impl<H: Hooks> Sim<H> {
    /// The jobs just released, in release order: at each instant, first
    /// every earlier job of their tasks publishes (its period ends), then
    /// they read.
    pub(crate) fn let_boundary(&mut self, mut released: Vec<LetJob>) {
        released.sort_by_key(|j| j.release);
        let mut at = 0;
        while at < released.len() {
            let r = released[at].release;
            let end = released[at..]
                .iter()
                .position(|j| j.release != r)
                .map_or(released.len(), |k| at + k);
            for j in &released[at..end] {
                if let Some(prev) = self.let_open[j.task].take() {
                    self.let_publish(prev);
                }
            }
            for j in &released[at..end] {
                self.prov.read(j.task, j.release);
                self.let_open[j.task] = Some(*j);
                self.hooks.read(&rtpipe_body::Job {
                    task: j.task,
                    index: j.index,
                    release: j.release,
                    read: j.release,
                });
            }
            at = end;
        }
    }

    /// `job`'s period ends: its output becomes visible (a tail's output).
    fn let_publish(&mut self, job: LetJob) {
        let t = job.release + job.period;
        self.prov.publish(job.task, t);
        self.hooks.publish(job.task, t);
        if let Some(log) = &mut self.log {
            // The log holds the communication instants, which the replay
            // (`chains_from_jobs`) and the traces' data flows read.
            log.push(JobRecord {
                task: job.task,
                index: job.index,
                release: job.release,
                demand: job.demand,
                read: job.release,
                finish: t,
                carried: self.prov.record(job.task),
                trigger: None,
            });
        }
        self.publish_triggers(job.task, job.index, t);
    }
}
