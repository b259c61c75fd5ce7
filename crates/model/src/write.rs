//! Spec → TOML, complete and exact: `Spec::parse(to_toml(s)) == s`.
//!
//! Times are written as strings with a unit suffix (`"1.15ms"`), which parse
//! exactly; numbers that are not times use Rust's shortest round-trip form.

use crate::{format_in, Chain, Channel, Nanos, PeriodSpec, Port, Spec, Task};
use std::fmt::Write;

fn time(spec: &Spec, ns: Nanos) -> String {
    format!("\"{}{}\"", format_in(ns, spec.time_unit), spec.time_unit)
}

fn quoted(s: &str) -> String {
    // TOML basic strings: escape backslash and quote; names are plain text.
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A bare key when possible, else a quoted one.
fn key(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        s.to_string()
    } else {
        quoted(s)
    }
}

fn num(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}

fn port(spec: &Spec, p: &Port) -> String {
    format!(
        "{{ channel = {}, size = {} }}",
        quoted(&spec.channels[p.channel].name),
        num(p.size)
    )
}

/// Writes a complete spec: every task field explicit, budgets included.
pub fn to_toml(spec: &Spec) -> String {
    let mut o = String::new();
    system(&mut o, spec);
    for c in &spec.channels {
        channel(&mut o, spec, c);
    }
    for th in &spec.threads {
        let _ = writeln!(o, "\n[threads.{}]", key(&th.name));
        let _ = writeln!(o, "priority = {}", th.priority);
        let _ = writeln!(o, "cpu = {}", th.cpu);
    }
    for t in &spec.tasks {
        task(&mut o, spec, t);
    }
    for c in &spec.chains {
        chain(&mut o, spec, c);
    }
    o
}

/// The `[system]` table. `resolution` and `harmonic` are written only when
/// they differ from their defaults, so a spec that never set them reads the
/// same after a round trip.
fn system(o: &mut String, spec: &Spec) {
    let _ = writeln!(o, "[system]");
    let _ = writeln!(o, "name = {}", quoted(&spec.name));
    let _ = writeln!(o, "time_unit = \"{}\"", spec.time_unit);
    let _ = writeln!(o, "scheduler = \"{}\"", spec.scheduler.name());
    let _ = writeln!(o, "schedulability = \"{}\"", spec.schedulability.name());
    if spec.resolution != spec.time_unit.nanos() {
        let _ = writeln!(o, "resolution = {}", time(spec, spec.resolution));
    }
    if spec.harmonic {
        let _ = writeln!(o, "harmonic = true");
    }
    if spec.priorities != crate::Priorities::RateMonotonic {
        let _ = writeln!(o, "priorities = \"{}\"", spec.priorities.name());
    }
    if spec.communication != crate::Communication::Implicit {
        let _ = writeln!(o, "communication = \"{}\"", spec.communication.name());
    }
    if spec.resource_protocol != crate::ResourceProtocol::Pcp {
        let _ = writeln!(
            o,
            "resource_protocol = \"{}\"",
            spec.resource_protocol.name()
        );
    }
    overheads(o, spec);
    for r in &spec.resources {
        let _ = writeln!(o, "\n[resources.{}]", key(&r.name));
    }
}

/// `overheads = { ..., cpu = { N = { ... } } }`, only the keys given.
fn overheads(o: &mut String, spec: &Spec) {
    let ov = &spec.overheads;
    if *ov == crate::Overheads::default() {
        return;
    }
    let s = ov.system;
    let mut keys = costs(
        spec,
        [Some(s.context_switch), Some(s.release), Some(s.replenish)],
    );
    if !ov.cpus.is_empty() {
        let cpus: Vec<String> = ov
            .cpus
            .iter()
            .map(|(n, c)| {
                let kv = costs(spec, [c.context_switch, c.release, c.replenish]);
                format!("{n} = {{ {} }}", kv.join(", "))
            })
            .collect();
        keys.push(format!("cpu = {{ {} }}", cpus.join(", ")));
    }
    let _ = writeln!(o, "overheads = {{ {} }}", keys.join(", "));
}

/// `key = "time"` for each cost given.
fn costs(spec: &Spec, v: [Option<Nanos>; 3]) -> Vec<String> {
    ["context_switch", "release", "replenish"]
        .iter()
        .zip(v)
        .filter_map(|(k, v)| Some(format!("{k} = {}", time(spec, v?))))
        .collect()
}

/// One `[channels.NAME]` table.
fn channel(o: &mut String, spec: &Spec, c: &Channel) {
    let _ = writeln!(o, "\n[channels.{}]", key(&c.name));
    let _ = writeln!(o, "bandwidth = {}", num(c.bandwidth));
    let _ = writeln!(o, "overhead = {}", time(spec, c.overhead));
}

/// One `[tasks.NAME]` table, its keys in the order a reader expects them:
/// the job's demand and data flow, then its timing, then its placement.
/// Optional keys are left out when they hold their default.
fn task(o: &mut String, spec: &Spec, t: &Task) {
    let _ = writeln!(o, "\n[tasks.{}]", key(&t.name));
    let _ = writeln!(o, "exec = {}", time(spec, t.exec));
    if t.exec_min != 0 {
        let _ = writeln!(o, "exec_min = {}", time(spec, t.exec_min));
    }
    if let Some(p) = &t.input {
        let _ = writeln!(o, "input = {}", port(spec, p));
    }
    if !t.reads.is_empty() {
        let _ = writeln!(o, "reads = [{}]", task_names(spec, &t.reads));
    }
    if let Some(p) = &t.output {
        let _ = writeln!(o, "output = {}", port(spec, p));
    }
    period(o, spec, &t.period);
    if let Some(b) = t.budget_given {
        let _ = writeln!(o, "budget = {}", time(spec, b));
    }
    if let Some(x) = t.offset {
        let _ = writeln!(o, "offset = {}", time(spec, x));
    }
    if let Some(d) = t.deadline_given {
        let _ = writeln!(o, "deadline = {}", time(spec, d));
    }
    if t.jitter != 0 {
        let _ = writeln!(o, "jitter = {}", time(spec, t.jitter));
    }
    if !t.sections.is_empty() {
        let cs: Vec<String> = t
            .sections
            .iter()
            .map(|s| {
                format!(
                    "{{ resource = {}, length = {} }}",
                    quoted(&spec.resources[s.resource].name),
                    time(spec, s.length)
                )
            })
            .collect();
        let _ = writeln!(o, "critical_sections = [{}]", cs.join(", "));
    }
    if let Some(m) = t.max_period {
        let _ = writeln!(o, "max_period = {}", time(spec, m));
    }
    if let (Some(p), None) = (t.priority, t.thread) {
        let _ = writeln!(o, "priority = {p}");
    }
    if let Some(th) = t.thread {
        let _ = writeln!(o, "thread = {}", quoted(&spec.threads[th].name));
    }
    let _ = writeln!(o, "server = \"{}\"", t.server.name());
    let _ = writeln!(o, "cpu = {}", t.cpu);
    if let Some(m) = t.serves {
        let _ = writeln!(o, "serves = {}", quoted(&spec.tasks[m].name));
    }
    if let Some(b) = &t.body {
        let _ = writeln!(o, "body = {}", quoted(b));
    }
}

/// A task's `period` key in whichever of its three forms the spec uses; a
/// free period (for `design` to choose) writes no key at all.
fn period(o: &mut String, spec: &Spec, period: &PeriodSpec) {
    match period {
        PeriodSpec::Fixed(p) => {
            let _ = writeln!(o, "period = {}", time(spec, *p));
        }
        PeriodSpec::Range { min, max } => {
            let mut parts = Vec::new();
            if let Some(m) = min {
                parts.push(format!("min = {}", time(spec, *m)));
            }
            if let Some(m) = max {
                parts.push(format!("max = {}", time(spec, *m)));
            }
            let _ = writeln!(o, "period = {{ {} }}", parts.join(", "));
        }
        PeriodSpec::Choices(c) => {
            let v: Vec<String> = c.iter().map(|&p| time(spec, p)).collect();
            let _ = writeln!(o, "period = {{ choices = [{}] }}", v.join(", "));
        }
        PeriodSpec::Free => {}
        PeriodSpec::Triggered { triggers, join } => {
            let _ = writeln!(o, "activation = \"data\"");
            let _ = writeln!(o, "triggers = [{}]", task_names(spec, triggers));
            if *join != crate::Join::Any {
                let _ = writeln!(o, "join = \"{}\"", join.name());
            }
        }
    }
}

/// One `[[chain]]` table.
fn chain(o: &mut String, spec: &Spec, c: &Chain) {
    let _ = writeln!(o, "\n[[chain]]");
    if let Some(n) = &c.name {
        let _ = writeln!(o, "name = {}", quoted(n));
    }
    let _ = writeln!(o, "path = [{}]", task_names(spec, &c.path));
    if let Some(l) = c.reaction {
        let _ = writeln!(o, "reaction = {}", time(spec, l));
    }
    if let Some(l) = c.freshness {
        let _ = writeln!(o, "freshness = {}", time(spec, l));
    }
    if let Some(l) = c.max_reaction_time {
        let _ = writeln!(o, "max_reaction_time = {}", time(spec, l));
    }
    if let Some(l) = c.freshness_from_event {
        let _ = writeln!(o, "freshness_from_event = {}", time(spec, l));
    }
    if let Some(m) = c.communication {
        let _ = writeln!(o, "communication = \"{}\"", m.name());
    }
}

/// Tasks named by index as the items of a TOML list (`"a", "b"`): tasks are
/// referred to by name in a spec, by index in memory.
fn task_names(spec: &Spec, tasks: &[usize]) -> String {
    let names: Vec<String> = tasks.iter().map(|&i| quoted(&spec.tasks[i].name)).collect();
    names.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gen::{random_system, GenConfig};

    fn roundtrip(s: &Spec) {
        let text = to_toml(s);
        match Spec::parse("w.toml", &text) {
            Ok(back) => assert_eq!(&back, s, "{text}"),
            Err(e) => panic!("{e}\n{text}"),
        }
    }

    #[test]
    fn examples_roundtrip() {
        for f in [
            "paper-table2.toml",
            "cleanflight.toml",
            "paper-table3.toml",
            "overheads.toml",
        ] {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../examples")
                .join(f);
            match Spec::load(&p) {
                Ok(s) => roundtrip(&s),
                Err(e) => panic!("{e}"),
            }
        }
    }

    #[test]
    fn random_systems_roundtrip() {
        for seed in 0..200 {
            let cfg = GenConfig {
                tasks: 12,
                cpus: 2,
                mixed_servers: true,
                feedback: 0.1,
                ..GenConfig::default()
            };
            roundtrip(&random_system(seed, &cfg));
        }
    }
}
