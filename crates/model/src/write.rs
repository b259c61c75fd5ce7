//! Spec → TOML, complete and exact: `Spec::parse(to_toml(s)) == s`.
//!
//! Times are written as strings with a unit suffix (`"1.15ms"`), which parse
//! exactly; numbers that are not times use Rust's shortest round-trip form.

use crate::{format_in, Nanos, PeriodSpec, Port, Spec};
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
    for c in &spec.channels {
        let _ = writeln!(o, "\n[channels.{}]", key(&c.name));
        let _ = writeln!(o, "bandwidth = {}", num(c.bandwidth));
        let _ = writeln!(o, "overhead = {}", time(spec, c.overhead));
    }
    for t in &spec.tasks {
        let _ = writeln!(o, "\n[tasks.{}]", key(&t.name));
        let _ = writeln!(o, "exec = {}", time(spec, t.exec));
        if t.exec_min != 0 {
            let _ = writeln!(o, "exec_min = {}", time(spec, t.exec_min));
        }
        if let Some(p) = &t.input {
            let _ = writeln!(o, "input = {}", port(spec, p));
        }
        if !t.reads.is_empty() {
            let names: Vec<String> = t
                .reads
                .iter()
                .map(|&i| quoted(&spec.tasks[i].name))
                .collect();
            let _ = writeln!(o, "reads = [{}]", names.join(", "));
        }
        if let Some(p) = &t.output {
            let _ = writeln!(o, "output = {}", port(spec, p));
        }
        match &t.period {
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
        }
        if let Some(b) = t.budget_given {
            let _ = writeln!(o, "budget = {}", time(spec, b));
        }
        if let Some(x) = t.offset {
            let _ = writeln!(o, "offset = {}", time(spec, x));
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
    for c in &spec.chains {
        let _ = writeln!(o, "\n[[chain]]");
        if let Some(n) = &c.name {
            let _ = writeln!(o, "name = {}", quoted(n));
        }
        let names: Vec<String> = c
            .path
            .iter()
            .map(|&i| quoted(&spec.tasks[i].name))
            .collect();
        let _ = writeln!(o, "path = [{}]", names.join(", "));
        if let Some(l) = c.reaction {
            let _ = writeln!(o, "reaction = {}", time(spec, l));
        }
        if let Some(l) = c.freshness {
            let _ = writeln!(o, "freshness = {}", time(spec, l));
        }
    }
    o
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
        for f in ["paper-table2.toml", "cleanflight.toml", "paper-table3.toml"] {
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
