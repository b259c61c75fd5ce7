//! Validation of shared resources: `[resources.NAME]`, `[system]
//! resource_protocol` and each task's `critical_sections = [{ resource =
//! "bus", length = "200us" }, ...]`.
//!
//! Refused, each with its place and a fix:
//! - a section on a resource that is not declared, of zero length, longer
//!   than the task's `exec`, or sections that together exceed it;
//! - more than [`MAX_SECTIONS`] sections in one task;
//! - a section in a task with a budget server (`main`, `io`) or in a
//!   background task: a server out of budget would hold the resource while
//!   it waits, which no protocol here bounds (`server = "none"` runs it);
//! - one resource used on two CPUs (that needs a multiprocessor protocol,
//!   MPCP or MSRP);
//! - a protocol the policy does not implement
//!   ([`crate::SchedPolicy::resource_protocols`]: under EDF only the stack
//!   resource policy, `"srp"`, which a spec must name there).

use super::{span, Builder};
use crate::raw::{RawResource, RawSection, RawSystem, RawTask, S};
use crate::*;
use std::collections::HashMap;

/// The most critical sections one task may have.
pub const MAX_SECTIONS: usize = 16;

impl Builder {
    /// `[resources]`, `resource_protocol` and every task's sections (set on
    /// `tasks`).
    pub(super) fn resources(
        &mut self,
        sys: &RawSystem,
        raw: &[(S<String>, S<RawResource>)],
        raw_tasks: &[(S<String>, S<RawTask>)],
        tasks: &mut [Task],
        scheduler: Option<Scheduler>,
    ) -> (ResourceProtocol, Vec<Resource>) {
        let protocol = match &sys.resource_protocol {
            Some(p) => {
                let options = ResourceProtocol::ALL.map(|p| (p.name(), p));
                self.choice(p, "resource protocol", &options)
                    .unwrap_or_default()
            }
            None => ResourceProtocol::Pcp,
        };
        let mut resources = Vec::new();
        let mut index = HashMap::new();
        for (k, _) in raw {
            if self.check_name("resource", k, "[resources.bus]") {
                index.insert(k.get_ref().clone(), resources.len());
                resources.push(Resource {
                    name: k.get_ref().clone(),
                });
            }
        }
        if let (Some(s), Some((k, _))) = (scheduler, raw.first()) {
            let at = sys.resource_protocol.as_ref().map_or_else(|| span(k), span);
            if !s.policy().resource_protocols.contains(&protocol) {
                let msg = match &sys.resource_protocol {
                    Some(_) => format!(
                        "resource protocol \"{}\" does not apply to scheduler \"{}\"",
                        protocol.name(),
                        s.name()
                    ),
                    None => format!(
                        "shared resources under scheduler \"{}\" with the default resource protocol \"{}\"",
                        s.name(),
                        protocol.name()
                    ),
                };
                self.err(msg, at, s.policy().resources_help);
            }
        }
        let mut cpu_of: Vec<Option<u32>> = vec![None; resources.len()];
        for ((k, v), t) in raw_tasks.iter().zip(tasks.iter_mut()) {
            if let Some(cs) = &v.get_ref().critical_sections {
                t.sections = self.sections(k, cs, t, &index, &resources, &mut cpu_of);
            }
        }
        (protocol, resources)
    }

    /// One task's `critical_sections`.
    fn sections(
        &mut self,
        k: &S<String>,
        cs: &S<Vec<S<RawSection>>>,
        t: &Task,
        index: &HashMap<String, usize>,
        resources: &[Resource],
        cpu_of: &mut [Option<u32>],
    ) -> Vec<CriticalSection> {
        let name = k.get_ref();
        self.section_server(cs, t);
        if cs.get_ref().len() > MAX_SECTIONS {
            self.err(
                format!(
                    "task `{name}` has {} critical sections, more than {MAX_SECTIONS}",
                    cs.get_ref().len()
                ),
                span(cs),
                "merge sections on the same resource: the analysis uses the longest one per resource",
            );
        }
        let u = self.unit();
        let mut out = Vec::new();
        for s in cs.get_ref() {
            let s = s.get_ref();
            let Some(length) = self.positive_time(&s.length, "critical section length") else {
                continue;
            };
            if length > t.exec {
                self.err(
                    format!(
                        "critical section of `{name}` on `{}` ({}{u}) is longer than its exec ({}{u})",
                        s.resource.get_ref(),
                        format_in(length, u),
                        format_in(t.exec, u)
                    ),
                    span(&s.length),
                    "a section is part of the job's processing: make it at most exec, or raise exec",
                );
            }
            let Some(r) = self.section_resource(&s.resource, t, resources, index, cpu_of) else {
                continue;
            };
            out.push(CriticalSection {
                resource: r,
                length,
            });
        }
        let total = out.iter().fold(0, |a: Nanos, s| a.saturating_add(s.length));
        if total > t.exec && out.iter().all(|s| s.length <= t.exec) {
            self.err(
                format!(
                    "the critical sections of `{name}` take {}{u} together, more than its exec ({}{u})",
                    format_in(total, u),
                    format_in(t.exec, u)
                ),
                span(cs),
                "sections run one after the other within the job's processing: shorten them, or raise exec",
            );
        }
        out
    }

    /// Sections only in a task no budget suspends.
    fn section_server(&mut self, cs: &S<Vec<S<RawSection>>>, t: &Task) {
        if !matches!(t.server, Server::None) {
            self.err(
                format!(
                    "task `{}` has critical sections but server \"{}\"",
                    t.name,
                    t.server.name()
                ),
                span(cs),
                "a budget server that runs out inside a section would hold the resource while it waits (and a background task has no guarantee): give the task server = \"none\", or move the shared work to such a task",
            );
        }
    }

    /// The resource a section names: declared, and on one CPU only.
    fn section_resource(
        &mut self,
        r: &S<String>,
        t: &Task,
        resources: &[Resource],
        index: &HashMap<String, usize>,
        cpu_of: &mut [Option<u32>],
    ) -> Option<usize> {
        let Some(&i) = index.get(r.get_ref()) else {
            let help = match suggest(r.get_ref(), resources.iter().map(|x| x.name.as_str())) {
                Some(n) => format!(
                    "did you mean \"{n}\"? Or declare it: [resources.{}]",
                    r.get_ref()
                ),
                None => format!("declare it: [resources.{}]", r.get_ref()),
            };
            self.err(
                format!("unknown resource \"{}\"", r.get_ref()),
                span(r),
                help,
            );
            return None;
        };
        match cpu_of[i] {
            Some(c) if c != t.cpu => {
                self.err(
                    format!(
                        "resource `{}` is used on cpu {c} and on cpu {} (by `{}`)",
                        r.get_ref(),
                        t.cpu,
                        t.name
                    ),
                    span(r),
                    "a resource shared across CPUs needs a multiprocessor protocol (MPCP, MSRP), which rtpipe does not implement: put the tasks that use it on one cpu, or give each CPU its own resource",
                );
                None
            }
            _ => {
                cpu_of[i] = Some(t.cpu);
                Some(i)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::*;

    const BASE: &str = r#"[system]
name = "r"
time_unit = "ms"

[resources.bus]

[tasks.a]
exec = 1
period = 5
server = "none"
critical_sections = [{ resource = "bus", length = 0.5 }]

[tasks.b]
exec = 2
period = 10
server = "none"
"#;

    /// The spec with task b's extra lines; its first diagnostic as
    /// (file:line:column, message, help).
    fn first_error(system: &str, b: &str) -> (String, String, String) {
        let src = BASE.replace(
            "time_unit = \"ms\"\n",
            &format!("time_unit = \"ms\"\n{system}"),
        ) + b;
        match Spec::parse("r.toml", &src) {
            Ok(_) => panic!("expected an error:\n{src}"),
            Err(e) => {
                let d = &e.diagnostics[0];
                let help = d.help.clone().unwrap_or_default();
                (e.locations()[0].clone(), d.message.clone(), help)
            }
        }
    }

    #[test]
    fn sections_parse_and_round_trip() {
        let src =
            BASE.to_string() + "critical_sections = [{ resource = \"bus\", length = \"300us\" }]\n";
        let s = Spec::parse("r.toml", &src).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.resources.len(), 1);
        assert_eq!(s.resource_protocol, ResourceProtocol::Pcp);
        assert_eq!(
            s.tasks[1].sections,
            vec![CriticalSection {
                resource: 0,
                length: 300_000
            }]
        );
        let back = Spec::parse("w.toml", &to_toml(&s)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back, s);
        let pip = src.replace(
            "time_unit = \"ms\"\n",
            "time_unit = \"ms\"\nresource_protocol = \"pip\"\n",
        );
        let s = Spec::parse("r.toml", &pip).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(Spec::parse("w.toml", &to_toml(&s)).ok(), Some(s));
    }

    #[test]
    fn bad_combinations_are_located_with_a_fix() {
        let cases: [(&str, &str, &str, &str); 7] = [
            ("", "critical_sections = [{ resource = \"bus\", length = 3 }]\n", "r.toml:17:51", "longer than its exec"),
            ("", "critical_sections = [{ resource = \"bsu\", length = 1 }]\n", "r.toml:17:35", "unknown resource"),
            ("", "critical_sections = [{ resource = \"bus\", length = 0 }]\n", "r.toml:17:51", "must be positive"),
            (
                "",
                "critical_sections = [{ resource = \"bus\", length = 1.5 }, { resource = \"bus\", length = 1 }]\n",
                "r.toml:17:21",
                "together, more than its exec",
            ),
            ("", "cpu = 1\ncritical_sections = [{ resource = \"bus\", length = 1 }]\n", "r.toml:18:35", "on cpu 0 and on cpu 1"),
            ("scheduler = \"edf\"\n", "", "r.toml:6:12", "under scheduler \"edf\""),
            ("resource_protocol = \"pi\"\n", "", "r.toml:4:21", "unknown resource protocol"),
        ];
        for (system, b, at, what) in cases {
            let (loc, msg, help) = first_error(system, b);
            assert_eq!(loc, at, "{msg}");
            assert!(msg.contains(what), "{msg}");
            assert!(!help.is_empty(), "{msg}: no fix");
        }
        let main = BASE.replace("server = \"none\"\ncritical", "server = \"main\"\ncritical");
        let e = Spec::parse("r.toml", &main)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("r.toml:11:21: error: task `a` has critical sections but server \"main\""),
            "{e}"
        );
        assert!(e.contains("server = \"none\""), "{e}");
    }
}
