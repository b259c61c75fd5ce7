//! One task's keys: ports, execution times, reads, placement and the
//! period (fixed, or a domain for `design`), each parsed on its own;
//! [`Builder::task`] puts them together.

use super::{span, Builder, Known};
use crate::raw::{RawPort, RawTask, S};
use crate::*;
use std::collections::HashMap;

impl Builder {
    pub(super) fn port(
        &mut self,
        p: &S<RawPort>,
        ch_index: &HashMap<String, usize>,
        channels: &[Channel],
    ) -> Option<Port> {
        let rp = p.get_ref();
        let ch = match ch_index.get(rp.channel.get_ref()) {
            Some(&c) => Some(c),
            None => {
                let help = match suggest(
                    rp.channel.get_ref(),
                    channels.iter().map(|c| c.name.as_str()),
                ) {
                    Some(s) => format!("did you mean \"{s}\"?"),
                    None => format!(
                        "declare it: [channels.{}] with bandwidth and overhead",
                        rp.channel.get_ref()
                    ),
                };
                self.err(
                    format!("unknown channel \"{}\"", rp.channel.get_ref()),
                    span(&rp.channel),
                    help,
                );
                None
            }
        };
        let size = self.number(&rp.size, "size", false);
        Some(Port {
            channel: ch?,
            size: size?,
        })
    }

    pub(super) fn task(&mut self, k: &S<String>, v: &S<RawTask>, known: &Known) -> Option<Task> {
        let (ch_index, channels) = (known.ch_index, known.channels);
        let (task_index, names) = (known.task_index, known.names);
        let t = v.get_ref();
        let (exec, exec_min) = self.exec_times(t);
        let input = match &t.input {
            Some(p) => self.port(p, ch_index, channels).map(Some),
            None => Some(None),
        };
        let output = match &t.output {
            Some(p) => self.port(p, ch_index, channels).map(Some),
            None => Some(None),
        };
        let reads = self.reads(t, task_index, names);
        let triggered = self.activation(t, reads.as_deref(), task_index, names);
        let period = match (triggered, &t.period) {
            (None, _) => None,
            (Some(Some(triggered)), _) => Some(triggered),
            (Some(None), Some(p)) => self.period(p),
            (Some(None), None) => Some(PeriodSpec::Free),
        };
        let thread = self.task_thread(t, known.thread_index);
        let budget = match &t.budget {
            Some(b) => self.positive_time(b, "budget").map(Some),
            None => Some(None),
        };
        let (server, cpu) = self.placement(t);
        let offset = match &t.offset {
            Some(o) => self.nonneg_time(o, "offset").map(Some),
            None => Some(None),
        };
        let (priority, deadline, jitter) = self.timing_keys(t);
        let max_period = match &t.max_period {
            Some(m) => self.positive_time(m, "max_period").map(Some),
            None => Some(None),
        };
        let body = self.body(k.get_ref(), t.body.as_ref());
        Some(Task {
            name: k.get_ref().clone(),
            exec: exec?,
            exec_min: exec_min?,
            input: input?,
            output: output?,
            reads: reads?,
            period: period?,
            budget_given: budget?,
            server: server?,
            cpu: cpu?,
            serves: None,
            body: body?,
            offset: offset?,
            priority: priority?,
            deadline_given: deadline?,
            jitter: jitter?,
            max_period: max_period?,
            sections: Vec::new(),
            thread: thread?,
            delta_in: 0,
            delta_out: 0,
        })
    }

    /// `exec` and `exec_min` (at most `exec`).
    pub(super) fn exec_times(&mut self, t: &RawTask) -> (Option<Nanos>, Option<Nanos>) {
        let exec = self.positive_time(&t.exec, "exec");
        let exec_min = match &t.exec_min {
            Some(e) => self.nonneg_time(e, "exec_min"),
            None => Some(0),
        };
        if let (Some(a), Some(b), Some(es)) = (exec_min, exec, &t.exec_min) {
            if a > b {
                self.err(
                    format!(
                        "exec_min {} is larger than exec {}",
                        format_in(a, self.unit()),
                        format_in(b, self.unit())
                    ),
                    span(es),
                    "exec_min is the best-case processing time: make it at most exec",
                );
            }
        }
        (exec, exec_min)
    }

    /// `reads`: known producers, each once.
    pub(super) fn reads(
        &mut self,
        t: &RawTask,
        task_index: &HashMap<String, usize>,
        names: &[String],
    ) -> Option<Vec<usize>> {
        let mut reads = Vec::new();
        let mut reads_ok = true;
        for r in &t.reads {
            match task_index.get(r.get_ref()) {
                Some(&i) => {
                    if reads.contains(&i) {
                        self.err(
                            format!("`{}` appears twice in reads", r.get_ref()),
                            span(r),
                            "list each producer once",
                        );
                        reads_ok = false;
                    }
                    reads.push(i)
                }
                None => {
                    self.unknown_task(r, names);
                    reads_ok = false;
                }
            }
        }
        reads_ok.then_some(reads)
    }

    /// `server` and `cpu`.
    pub(super) fn placement(&mut self, t: &RawTask) -> (Option<Server>, Option<u32>) {
        let server = match &t.server {
            Some(s) => self.choice(
                s,
                "server",
                &[
                    ("main", Server::Main),
                    ("io", Server::Io),
                    ("none", Server::None),
                    ("background", Server::Background),
                ],
            ),
            None => Some(Self::default_server(t)),
        };
        let cpu = match &t.cpu {
            Some(c) => self.cpu_index(c),
            None => Some(0),
        };
        (server, cpu)
    }

    /// A `cpu` key: a core index from 0 to 1023.
    pub(super) fn cpu_index(&mut self, c: &S<toml::Value>) -> Option<u32> {
        match c.get_ref() {
            toml::Value::Integer(i) if (0..=1023).contains(i) => Some(*i as u32),
            _ => {
                self.err(
                    "cpu must be an integer from 0 to 1023",
                    span(c),
                    "write the core index, e.g. cpu = 0",
                );
                None
            }
        }
    }

    /// `period`: a fixed time, or a domain for `design` to choose from.
    pub(super) fn period(&mut self, p: &S<toml::Value>) -> Option<PeriodSpec> {
        match p.get_ref() {
            toml::Value::Table(t) => self.period_domain(p, t),
            _ => self.positive_time(p, "period").map(PeriodSpec::Fixed),
        }
    }

    /// `period = { min = .., max = .. }` (either end may be left out) or
    /// `period = { choices = [..] }`, never both. The first bad key ends the
    /// check: the rest of a table that is wrong anyway would only add noise.
    pub(super) fn period_domain(
        &mut self,
        p: &S<toml::Value>,
        t: &toml::Table,
    ) -> Option<PeriodSpec> {
        let mut min = None;
        let mut max = None;
        let mut choices = None;
        for (key, val) in t {
            // Inner values have no spans of their own; point at the table.
            let sv = S::new(p.span(), val.clone());
            match key.as_str() {
                "min" => min = Some(self.positive_time(&sv, "period min")?),
                "max" => max = Some(self.positive_time(&sv, "period max")?),
                "choices" => choices = Some(self.period_choices(p, val)?),
                other => {
                    self.err(
                        format!("unknown key `{other}` in period"),
                        Some(p.span()),
                        "a period is a time, { min = .., max = .. } or { choices = [..] }",
                    );
                    return None;
                }
            }
        }
        if let Some(c) = choices {
            if min.is_some() || max.is_some() {
                self.err(
                    "period has both choices and min/max",
                    Some(p.span()),
                    "use either choices or a min/max range",
                );
                return None;
            }
            return Some(PeriodSpec::Choices(c));
        }
        if let (Some(a), Some(b)) = (min, max) {
            if a > b {
                self.err(
                    "period min is larger than max",
                    Some(p.span()),
                    "swap min and max",
                );
                return None;
            }
        }
        Some(PeriodSpec::Range { min, max })
    }

    /// `choices = [..]` of `period` (the table `p`): a non-empty list of
    /// positive times, returned sorted and without repeats: the domain is a
    /// set, whatever order the spec lists it in.
    pub(super) fn period_choices(
        &mut self,
        p: &S<toml::Value>,
        val: &toml::Value,
    ) -> Option<Vec<Nanos>> {
        let arr = match val {
            toml::Value::Array(a) if !a.is_empty() => a,
            _ => {
                self.err(
                    "period choices must be a non-empty list of times",
                    Some(p.span()),
                    "write e.g. period = { choices = [\"1ms\", \"2ms\"] }",
                );
                return None;
            }
        };
        let mut out = Vec::new();
        for x in arr {
            out.push(self.positive_time(&S::new(p.span(), x.clone()), "period choice")?);
        }
        out.sort_unstable();
        out.dedup();
        Some(out)
    }
}
