//! Which observations of a real run break a sound bound, and which of them
//! a cause in their own window excuses (`rtpipe_runtime::blame`): per chain
//! sample and quantity, per job whose response exceeds R(job), and every
//! job of a task the analysis bounds no response for (never excused: no
//! disturbance explains an overload the spec itself declares).

use rtpipe_analysis::disturbance::explains;
use rtpipe_analysis::{Anchor, Metric, Report};
use rtpipe_joblog::{sample_rows, SampleRow};
use rtpipe_model::{Nanos, Server, Spec};
use rtpipe_runtime::blame::{Blame, Cause};
use rtpipe_runtime::RunResult;
use serde::Serialize;

/// One observation above its sound bound.
#[derive(Debug, Clone, Serialize, schemars::JsonSchema)]
pub(super) struct Violation {
    /// The chain's label, or the task's name.
    pub(super) what: String,
    /// `reaction`/`freshness` from `read`/`event`, or `response`.
    pub(super) quantity: String,
    /// The sample id (chains) or the job index (tasks).
    pub(super) id: u64,
    /// The observed value and the bound, in the spec's unit (`None`: the
    /// analysis bounds no response of the task).
    pub(super) value: f64,
    pub(super) bound: Option<f64>,
    /// The window the causes were looked for in, in the spec's unit.
    pub(super) window: (f64, f64),
    /// The causes found there; excused when they can explain the excess.
    pub(super) causes: Vec<String>,
    pub(super) excused: bool,
}

/// Every observation above a sound bound.
#[derive(Debug, Default, Serialize, schemars::JsonSchema)]
pub(super) struct Verdict {
    pub(super) excused: usize,
    pub(super) unexcused: usize,
    /// Of the unexcused, the jobs of tasks with no bounded response.
    pub(super) unbounded: usize,
    pub(super) violations: Vec<Violation>,
}

/// The value of one row for one quantity and its window (anchor → the
/// output that ends it), when the run saw both.
fn measured(r: &SampleRow, metric: Metric, anchor: Anchor) -> Option<(Nanos, (Nanos, Nanos))> {
    let (from, to) = match (metric, anchor) {
        (Metric::Reaction, Anchor::Read) => (Some(r.read), r.first),
        (Metric::Freshness, Anchor::Read) => (Some(r.read), r.last),
        (Metric::Reaction, Anchor::Event) => (r.event, r.event_first),
        (Metric::Freshness, Anchor::Event) => (r.event, r.last),
    };
    let (from, to) = (from?, to?);
    Some((to - from, (from, to)))
}

/// Judges `res` against `report`'s sound bounds.
pub(super) fn judge(spec: &Spec, report: &Report, res: &RunResult) -> Verdict {
    let blame = Blame::new(spec, res);
    let mut v = Verdict::default();
    let rows = sample_rows(spec, &res.sim.jobs);
    for c in &report.chains {
        let path = &spec.chains[c.chain].path;
        for a in Anchor::ALL {
            let Some(bound) = c.bound.sound(a) else {
                continue;
            };
            for r in rows.get(c.chain).into_iter().flatten() {
                let Some((value, window)) = measured(r, c.metric, a) else {
                    continue;
                };
                if value > bound {
                    let quantity = format!("{} from {}", c.metric.name(), a.name());
                    let what = spec.chain_label(c.chain);
                    let window = blame.extend(window, path);
                    let obs = Obs {
                        what,
                        quantity,
                        id: r.sample,
                        value,
                        bound: Some(bound),
                        window,
                    };
                    v.push(spec, obs, blame.causes(window, path), path);
                }
            }
        }
    }
    judge_jobs(spec, report, res, &blame, &mut v);
    v
}

/// The schedule's responses (under LET the job log holds period ends):
/// each above its task's R(job), and each of a task with no bounded
/// response but a guarantee (a background task has none by design).
fn judge_jobs(spec: &Spec, report: &Report, res: &RunResult, blame: &Blame, v: &mut Verdict) {
    for j in res.scheduled() {
        let bound = report.timing.get(j.task).and_then(|t| t.bounded_response());
        let guaranteed = spec.tasks[j.task].server != Server::Background;
        let value = j.finish - j.release;
        if bound.map_or(guaranteed, |b| value > b) {
            let window = blame.extend((j.release, j.finish), &[j.task]);
            let what = spec.tasks[j.task].name.clone();
            let obs = Obs {
                what,
                quantity: "response".into(),
                id: j.index,
                value,
                bound,
                window,
            };
            v.push(spec, obs, blame.causes(window, &[j.task]), &[j.task]);
        }
    }
}

/// An observation above its bound, before its causes are judged.
struct Obs {
    what: String,
    quantity: String,
    id: u64,
    value: Nanos,
    /// `None`: no bounded response (an unschedulable task).
    bound: Option<Nanos>,
    window: (Nanos, Nanos),
}

impl Verdict {
    /// Records an observation with the causes found in its window: excused
    /// when their total, as a disturbance of the analysis, can lengthen the
    /// response of one of `tasks` by the excess (a chain's stages add their
    /// delays, each at most that task's inflation by its share; where the
    /// inflation is superadditive the largest single inflation by the total
    /// covers their sum; where its steps make it not, the allowance can
    /// fall short of that sum: a false alarm, never a false excuse). An
    /// observation with no bound is never excused.
    fn push(&mut self, spec: &Spec, o: Obs, causes: Vec<Cause>, tasks: &[usize]) {
        let b = Blame::total(&causes);
        let excused = o
            .bound
            .is_some_and(|bound| explains(spec, tasks, b, o.value - bound));
        if excused {
            self.excused += 1;
        } else {
            self.unexcused += 1;
            self.unbounded += usize::from(o.bound.is_none());
        }
        self.violations.push(Violation {
            what: o.what,
            quantity: o.quantity,
            id: o.id,
            value: spec.in_unit(o.value),
            bound: o.bound.map(|b| spec.in_unit(b)),
            window: (spec.in_unit(o.window.0), spec.in_unit(o.window.1)),
            causes: causes.iter().map(|c| c.describe(spec)).collect(),
            excused,
        });
    }

    /// ", N of them jobs of tasks with no bounded response" when there are.
    pub(super) fn unbounded_note(&self) -> String {
        if self.unbounded == 0 {
            return String::new();
        }
        format!(
            " ({} of them job(s) of tasks the analysis bounds no response for)",
            self.unbounded
        )
    }

    /// The text report's lines: the observations nothing excuses, each
    /// (at most `shown`), then the excused ones counted per task or chain
    /// and quantity, with the worst of each (a partitioned EDF run has
    /// hundreds, each explained by its own job's start latency: listing
    /// them hid the few that matter).
    pub(super) fn text(&self, spec: &Spec, shown: usize) -> String {
        if self.violations.is_empty() {
            return "no observation above a sound bound\n".into();
        }
        let mut out = format!(
            "{} observation(s) above a sound bound: {} excused by what broke the model in their window on their CPUs, {} not{}\n",
            self.violations.len(),
            self.excused,
            self.unexcused,
            self.unbounded_note()
        );
        let unit = spec.time_unit.to_string();
        for x in self.violations.iter().filter(|x| !x.excused).take(shown) {
            out.push_str(&format!(
                "  {}: VIOLATION ({})\n",
                x.line(&unit),
                x.because()
            ));
        }
        if self.unexcused > shown {
            out.push_str(&format!(
                "  ... {} more not excused in --json\n",
                self.unexcused - shown
            ));
        }
        for (n, worst) in self.excused_groups() {
            out.push_str(&format!(
                "  excused: {} {} above its bound {n} time(s), the worst {}: excused ({})\n",
                worst.what,
                worst.quantity,
                worst.line(&unit),
                worst.because()
            ));
        }
        out
    }

    /// The excused observations per (task or chain, quantity), in the order
    /// first seen: how many, and the one furthest above its bound.
    fn excused_groups(&self) -> Vec<(usize, &Violation)> {
        let mut groups: Vec<(usize, &Violation)> = Vec::new();
        for x in self.violations.iter().filter(|x| x.excused) {
            let same =
                |g: &&mut (usize, &Violation)| g.1.what == x.what && g.1.quantity == x.quantity;
            match groups.iter_mut().find(same) {
                Some(g) => {
                    g.0 += 1;
                    if x.excess() > g.1.excess() {
                        g.1 = x;
                    }
                }
                None => groups.push((1, x)),
            }
        }
        groups
    }
}

impl Violation {
    /// What was observed, its bound and its window.
    fn line(&self, unit: &str) -> String {
        let bound = match self.bound {
            Some(b) => format!("> {b} {unit}"),
            None => format!(
                "{unit}, with no bounded response (the analysis finds the task unschedulable)"
            ),
        };
        format!(
            "{} {} #{}: {} {bound} in [{}, {}] {unit}",
            self.what, self.quantity, self.id, self.value, self.window.0, self.window.1,
        )
    }

    /// How far above its bound (infinite without one).
    fn excess(&self) -> f64 {
        self.bound.map_or(f64::INFINITY, |b| self.value - b)
    }

    /// Its causes ([`abridged`]), or that none was found.
    fn because(&self) -> String {
        abridged(&self.causes)
    }
}

/// A violation's causes for the text: all of them up to [`CAUSES_SHOWN`];
/// beyond, the first few (job overruns, which a long busy period gathers
/// by the hundred) and the last ones (the foreign time and steal of each
/// CPU), the count of those left out between. `--json` has them all.
fn abridged(causes: &[String]) -> String {
    if causes.is_empty() {
        return "no cause found".to_string();
    }
    if causes.len() <= CAUSES_SHOWN {
        return causes.join("; ");
    }
    let (head, tail) = (3, CAUSES_SHOWN - 3);
    let left_out = causes.len() - head - tail;
    format!(
        "{}; ... {left_out} more in --json; {}",
        causes[..head].join("; "),
        causes[causes.len() - tail..].join("; ")
    )
}

/// The most causes the text lists for one violation.
const CAUSES_SHOWN: usize = 7;

#[cfg(test)]
mod tests {
    use super::*;

    fn violation(what: &str, id: u64, value: f64, excused: bool) -> Violation {
        Violation {
            what: what.into(),
            quantity: "response".into(),
            id,
            value,
            bound: Some(1.0),
            window: (0.0, value),
            causes: vec![format!("cause of #{id}")],
            excused,
        }
    }

    /// The unexcused are listed one by one; the excused are counted per
    /// task and quantity, the worst of each named.
    #[test]
    fn the_excused_are_counted_the_rest_listed() {
        let spec = rtpipe_testkit::example("paper-table3.toml");
        let violations = vec![
            violation("p2", 0, 1.1, true),
            violation("p2", 1, 1.3, true),
            violation("p2", 2, 1.2, true),
            violation("p3", 7, 2.0, false),
            violation("p1", 4, 1.05, true),
        ];
        let v = Verdict {
            excused: 4,
            unexcused: 1,
            unbounded: 0,
            violations,
        };
        let text = v.text(&spec, 10);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 4, "{text}");
        assert!(lines[1].starts_with("  p3 response #7: 2 > 1 ms"), "{text}");
        assert!(lines[1].ends_with("VIOLATION (cause of #7)"), "{text}");
        assert!(
            lines[2].starts_with("  excused: p2 response above its bound 3 time(s), the worst p2 response #1: 1.3 > 1 ms"),
            "{text}"
        );
        assert!(
            lines[3].contains("p1 response above its bound 1 time(s)"),
            "{text}"
        );
        // Past `shown`, the unexcused are counted.
        let text = v.text(&spec, 0);
        assert!(
            text.contains("  ... 1 more not excused in --json"),
            "{text}"
        );
    }

    #[test]
    fn a_long_list_of_causes_keeps_its_first_and_last_in_the_text() {
        let causes: Vec<String> = (0..100).map(|k| format!("c{k}")).collect();
        assert_eq!(
            abridged(&causes),
            "c0; c1; c2; ... 93 more in --json; c96; c97; c98; c99"
        );
        assert_eq!(abridged(&causes[..7]), "c0; c1; c2; c3; c4; c5; c6");
        assert_eq!(abridged(&[]), "no cause found");
    }
}
