//! Every file a user hands rtpipe (spec,
//! mission, vehicle preset, criterion, YAML import) is read by the same
//! rules, no output replaces it, no input makes reading slow, and names
//! print as themselves.

mod common;

use common::{assert_exit, example, rtpipe_in, scratch};
use std::path::Path;
use std::time::{Duration, Instant};

const LIMIT: Duration = Duration::from_secs(60);

fn write(p: &Path, bytes: &[u8]) {
    if let Err(e) = std::fs::write(p, bytes) {
        panic!("cannot write {}: {e}", p.display());
    }
}

fn read(p: &Path) -> Vec<u8> {
    match std::fs::read(p) {
        Ok(s) => s,
        Err(e) => panic!("cannot read {}: {e}", p.display()),
    }
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs rtpipe in `dir`; exit 2 with every `needles` in stderr.
fn refused(dir: &Path, args: &[&str], needles: &[&str]) -> Duration {
    let t0 = Instant::now();
    let o = rtpipe_in(dir, args, &[], LIMIT);
    let took = t0.elapsed();
    assert_exit(&o, 2);
    let err = stderr(&o);
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} not in:\n{err}");
    }
    took
}

const MISSION: &str = "name = \"m\"\n[[step]]\nat = 0.1\narm = true\n";

#[test]
fn endless_and_huge_inputs_are_refused_after_the_cap() {
    let d = scratch("inputs-cap");
    let spec = example("cleanflight.toml");
    let cap = "larger than 16 MiB, the most rtpipe reads";
    let sparse = d.join("sparse.toml");
    match std::fs::File::create(&sparse).and_then(|f| f.set_len(2 << 30)) {
        Ok(()) => {}
        Err(e) => panic!("cannot make a sparse file: {e}"),
    }
    let sparse = sparse.to_string_lossy().into_owned();
    let device = "it is a device, not a regular file";
    for (file, why) in [("/dev/zero", device), (sparse.as_str(), cap)] {
        for args in [
            vec!["fly", &spec, "--mission", file],
            vec!["fly", &spec, "--vehicle", file],
            vec!["fly", &spec, "--sweep", "--criterion", file],
            vec!["run", &spec, "--mission", file],
            vec!["analyze", file],
        ] {
            let took = refused(&d, &args, &[why, file]);
            assert!(took < Duration::from_secs(20), "{args:?} took {took:?}");
        }
    }
    let t0 = Instant::now();
    let o = rtpipe_in(&d, &["import", "e2eeval", &sparse, "out"], &[], LIMIT);
    assert_exit(&o, 2);
    assert!(stderr(&o).contains("larger than 64 MiB"), "{}", stderr(&o));
    assert!(t0.elapsed() < Duration::from_secs(5));
    // A flight log may be larger (512 MiB), not the 2 GiB sparse file.
    let t0 = Instant::now();
    let o = rtpipe_in(&d, &["import", "px4-ulog", &sparse, "out"], &[], LIMIT);
    assert_exit(&o, 2);
    assert!(stderr(&o).contains("larger than 512 MiB"), "{}", stderr(&o));
    assert!(t0.elapsed() < Duration::from_secs(5));
    assert!(!d.join("out").exists());
}

#[test]
fn text_rules_are_the_same_for_every_file_kind() {
    let d = scratch("inputs-text");
    let spec = example("cleanflight.toml");
    // A byte-order mark is dropped: the spec, mission and preset read.
    let mut bom = b"\xEF\xBB\xBF".to_vec();
    bom.extend_from_slice(MISSION.as_bytes());
    write(&d.join("bom.toml"), &bom);
    let o = rtpipe_in(
        &d,
        &["fly", &spec, "--mission", "bom.toml", "--duration", "0.3s"],
        &[],
        LIMIT,
    );
    assert_ne!(o.status.code(), Some(2), "{}", stderr(&o));
    let mut spec_bom = b"\xEF\xBB\xBF".to_vec();
    spec_bom.extend(read(Path::new(&example("paper-table2.toml"))));
    write(&d.join("s.toml"), &spec_bom);
    let o = rtpipe_in(&d, &["analyze", "s.toml"], &[], LIMIT);
    let plain = rtpipe_in(&d, &["analyze", &example("paper-table2.toml")], &[], LIMIT);
    assert_ne!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(o.stdout, plain.stdout);
    // A control character in a comment: refused with its place.
    write(
        &d.join("c.toml"),
        b"name = \"m\"\n# a \x1b[31m red comment\n",
    );
    for flag in ["--mission", "--vehicle"] {
        refused(
            &d,
            &["fly", &spec, flag, "c.toml"],
            &[&format!("{flag} c.toml:2:5: "), "control character U+001B"],
        );
    }
    write(&d.join("crit.toml"), b"overshoot = 0.3\n\x07\n");
    refused(
        &d,
        &["fly", &spec, "--sweep", "--criterion", "crit.toml"],
        &["--criterion crit.toml:2:1: ", "U+0007"],
    );
    // Not UTF-8: the place of the byte; a syntax error: line and column.
    write(
        &d.join("u.toml"),
        b"name = \"m\"\n[[step]]\nat = \"\xFF\"\n",
    );
    refused(
        &d,
        &["fly", &spec, "--mission", "u.toml"],
        &["u.toml:3:7: ", "not UTF-8"],
    );
    write(&d.join("t.toml"), b"name = \"m\"\n[[step]]\nat = = 1\n");
    refused(
        &d,
        &["fly", &spec, "--mission", "t.toml"],
        &["--mission t.toml:3:6: "],
    );
    // A value out of range: the line and column of its key.
    write(
        &d.join("r.toml"),
        b"name = \"m\"\n[[step]]\nat = 1\n[[step]]\nat = 2\nroll_deg = 90\n",
    );
    refused(
        &d,
        &["fly", &spec, "--mission", "r.toml"],
        &["--mission r.toml:6:1: invalid `step[1].roll_deg`: must be in [-60, 60]"],
    );
    write(&d.join("k.toml"), b"\novershot = 0.3\n");
    refused(
        &d,
        &["fly", &spec, "--sweep", "--criterion", "k.toml"],
        &["--criterion k.toml:2:1: ", "overshot"],
    );
}

#[test]
fn deep_nesting_and_many_steps_are_refused_quickly() {
    let d = scratch("inputs-deep");
    let spec = example("cleanflight.toml");
    for (name, text) in [
        ("flow.yaml", "[".repeat(50_000)),
        ("block.yaml", "- ".repeat(50_000) + "x\n"),
    ] {
        write(&d.join(name), text.as_bytes());
        let took = refused(
            &d,
            &["import", "e2eeval", name, "out"],
            &["nests deeper than 64"],
        );
        assert!(took < Duration::from_secs(5), "{name} took {took:?}");
    }
    let deep = format!("name = \"m\"\nx = {}\n", "[".repeat(100_000));
    write(&d.join("deep.toml"), deep.as_bytes());
    refused(
        &d,
        &["fly", &spec, "--mission", "deep.toml"],
        &["deep.toml:2:69: ", "nests deeper"],
    );
    let steps = |n: usize| {
        let mut m = String::from("name = \"many\"\n");
        for k in 0..n {
            m.push_str(&format!("[[step]]\nat = {}\narm = true\n", k as f64 * 2e-5));
        }
        m
    };
    write(&d.join("many.toml"), steps(100_000).as_bytes());
    let took = refused(
        &d,
        &["fly", &spec, "--mission", "many.toml", "--duration", "2s"],
        &["100000 steps, more than the 10000"],
    );
    assert!(took < Duration::from_secs(10), "took {took:?}");
    // The most steps allowed fly in about the time of one step.
    write(&d.join("most.toml"), steps(10_000).as_bytes());
    let t0 = Instant::now();
    let o = rtpipe_in(
        &d,
        &["fly", &spec, "--mission", "most.toml", "--duration", "2s"],
        &[],
        LIMIT,
    );
    assert_ne!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        t0.elapsed() < Duration::from_secs(20),
        "took {:?}",
        t0.elapsed()
    );
}

#[test]
fn no_output_flag_replaces_an_input() {
    let d = scratch("inputs-overwrite");
    let spec = example("cleanflight.toml");
    write(&d.join("m.toml"), MISSION.as_bytes());
    let preset = read(Path::new(&format!(
        "{}/../flight/presets/racer5.toml",
        env!("CARGO_MANIFEST_DIR")
    )));
    write(&d.join("v.toml"), &preset);
    write(&d.join("c.toml"), b"overshoot = 0.3\n");
    #[cfg(unix)]
    {
        let _ = std::os::unix::fs::symlink("m.toml", d.join("link.toml"));
        let _ = std::fs::hard_link(d.join("v.toml"), d.join("hard.toml"));
    }
    let before: Vec<Vec<u8>> = ["m.toml", "v.toml", "c.toml"]
        .map(|f| read(&d.join(f)))
        .into();
    for (args, needle) in [
        (
            vec!["fly", &spec, "--mission", "m.toml", "--log", "m.toml"],
            "--log m.toml would overwrite --mission m.toml",
        ),
        (
            vec!["fly", &spec, "--vehicle", "v.toml", "--log", "v.toml"],
            "--log v.toml would overwrite --vehicle v.toml",
        ),
        (
            vec![
                "fly",
                &spec,
                "--mission",
                "m.toml",
                "--samples",
                "link.toml",
            ],
            "--samples link.toml would overwrite --mission m.toml",
        ),
        (
            vec!["fly", &spec, "--vehicle", "v.toml", "--log", "hard.toml"],
            "would overwrite --vehicle v.toml",
        ),
        (
            vec![
                "fly",
                &spec,
                "--sweep",
                "--criterion",
                "c.toml",
                "--write-limits",
                "c.toml",
            ],
            "--write-limits c.toml would overwrite --criterion c.toml",
        ),
        (
            vec!["run", &spec, "--mission", "m.toml", "--trace", "m.toml"],
            "--trace m.toml would overwrite --mission m.toml",
        ),
        (
            vec!["run", &spec, "--vehicle", "v.toml", "--plot", "v.toml"],
            "--plot v.toml would overwrite --vehicle v.toml",
        ),
    ] {
        let args: Vec<&str> = args.iter().copied().chain(["--duration", "0.2s"]).collect();
        refused(&d, &args, &[needle, "write to another file"]);
    }
    let after: Vec<Vec<u8>> = ["m.toml", "v.toml", "c.toml"]
        .map(|f| read(&d.join(f)))
        .into();
    assert!(before == after, "an input changed");
    // `fly --plot` names a directory: a file there is refused by name.
    refused(
        &d,
        &["fly", &spec, "--plot", "m.toml", "--duration", "0.2s"],
        &["--plot m.toml exists and is not a directory"],
    );
}

#[test]
fn names_print_as_themselves() {
    let d = scratch("inputs-names");
    let spec = example("cleanflight.toml");
    write(&d.join("esc.toml"), b"name = \"x\\u001b[2J\"\n");
    refused(
        &d,
        &["fly", &spec, "--mission", "esc.toml"],
        &["invalid `name`", "U+001B"],
    );
    let long = format!("name = \"{}\"\n", "x".repeat(100_000));
    write(&d.join("long.toml"), long.as_bytes());
    let took = refused(
        &d,
        &["fly", &spec, "--mission", "long.toml"],
        &["100000 characters, more than the 256"],
    );
    assert!(took < Duration::from_secs(5));
    let preset = String::from_utf8_lossy(&read(Path::new(&format!(
        "{}/../flight/presets/racer5.toml",
        env!("CARGO_MANIFEST_DIR")
    ))))
    .replacen("name = \"", "name = \"\u{202E}", 1);
    write(&d.join("v.toml"), preset.as_bytes());
    refused(
        &d,
        &["fly", &spec, "--vehicle", "v.toml"],
        &["bidirectional control U+202E"],
    );
    let task =
        |name: &str| format!("[system]\nname = \"s\"\n[tasks.\"{name}\"]\nperiod = 10\nexec = 1\n");
    write(&d.join("t.toml"), task(&"t".repeat(100_000)).as_bytes());
    refused(
        &d,
        &["analyze", "t.toml"],
        &["t.toml:3:8: error: task name", "more than the 256"],
    );
    write(&d.join("z.toml"), task("a\u{200B}b").as_bytes());
    refused(&d, &["analyze", "z.toml"], &["invisible character U+200B"]);
    write(&d.join("at.toml"), b"name = \"m\"\n[[step]]\nat = 1e30\n");
    refused(
        &d,
        &["fly", &spec, "--mission", "at.toml"],
        &["from 0 to 9007199 s", "got 1e30"],
    );
}

/// The binary on mutated missions, presets and criteria: exit 0, 1 or 2,
/// never a panic, and a refusal is one located message.
#[test]
fn mutated_missions_presets_and_criteria_are_refused_plainly() {
    let d = scratch("inputs-fuzz");
    let spec = example("cleanflight.toml");
    let dir = env!("CARGO_MANIFEST_DIR");
    let valid: Vec<(&str, Vec<u8>)> = [
        ("--mission", "missions/steps.toml"),
        ("--mission", "missions/gusty.toml"),
        ("--vehicle", "presets/racer5.toml"),
        ("--criterion", ""),
    ]
    .map(|(flag, f)| {
        let text = if f.is_empty() {
            b"overshoot = 0.3\nsettling_s = 0.5\n".to_vec()
        } else {
            read(Path::new(&format!("{dir}/../flight/{f}")))
        };
        (flag, text)
    })
    .into();
    let mut seed: u64 = 0x2400;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 33) as usize
    };
    for case in 0..60 {
        let (flag, text) = &valid[case % valid.len()];
        let mut b = text.clone();
        for _ in 0..1 + next() % 4 {
            let i = next() % b.len().max(1);
            let byte = (next() % 256) as u8;
            match next() % 3 {
                0 if i < b.len() => b[i] = byte,
                1 => b.insert(i.min(b.len()), byte),
                _ => b.truncate(i),
            }
        }
        write(&d.join("f.toml"), &b);
        let mut args = vec!["fly", spec.as_str(), flag, "f.toml", "--duration", "0.2s"];
        if *flag == "--criterion" {
            args.insert(2, "--sweep");
        }
        let o = rtpipe_in(&d, &args, &[], LIMIT);
        let err = stderr(&o);
        match o.status.code() {
            Some(0 | 1) => {}
            Some(2) => {
                assert!(
                    err.starts_with(&format!("error: {flag} f.toml")),
                    "case {case}: {err}"
                );
                assert!(!err.contains("panicked"), "{err}");
            }
            other => panic!("case {case}: exit {other:?}: {err}"),
        }
    }
}

/// A refused value names the limit it broke; examples in
/// errors fit their flag; no "-0.0000".
#[test]
fn messages_name_the_limit_and_fitting_examples() {
    let d = scratch("inputs-messages");
    let spec = example("cleanflight.toml");
    let table2 =
        String::from_utf8_lossy(&read(Path::new(&example("paper-table2.toml")))).into_owned();
    let bw = table2.replacen("bandwidth = ", "bandwidth = 1e15 #", 1);
    assert_ne!(bw, table2);
    write(&d.join("bw.toml"), bw.as_bytes());
    write(&d.join("t2.toml"), table2.as_bytes());
    refused(
        &d,
        &["analyze", "bw.toml"],
        &["must be > 0 and below 1e15, found 1e15"],
    );
    refused(
        &d,
        &["fly", &spec, "--duration", "1e9s"],
        &["--duration: time is too large", "up to 9007199 s"],
    );
    refused(
        &d,
        &["simulate", "t2.toml", "--outputs", "1000000000"],
        &["the longest the model allows, 9007199 s (about 104 days)"],
    );
    std::fs::create_dir_all(d.join("dir")).ok();
    refused(
        &d,
        &["run", &spec, "--export-rt-app", "dir"],
        &["--export-rt-app dir is a directory", "dir/rt-app.json"],
    );
    // A CPU with background tasks only: U = 0, not -0.
    let bg = "[system]\nname = \"bg\"\n[tasks.a]\nperiod = 10\nexec = 1\n[tasks.b]\nperiod = 10\nexec = 1\ncpu = 1\nserver = \"background\"\n";
    write(&d.join("bg.toml"), bg.as_bytes());
    let o = rtpipe_in(&d, &["analyze", "bg.toml"], &[], LIMIT);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("U = 0.0000") && !out.contains("-0.0"), "{out}");
}
