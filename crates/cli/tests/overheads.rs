//! `[system] overheads` through the binary: a bad value is exit 2 with its
//! place, and `run --measure-overheads --write-spec` measures this machine
//! (best effort here, so no privilege is needed) and writes a validated
//! copy of the spec, never the input.

mod common;

use common::{assert_exit, example, rtpipe, scratch};
use rtpipe_model::Spec;

#[test]
fn a_bad_overhead_is_exit_2_with_its_place() {
    let dir = scratch("ovh-bad");
    let p = dir.join("bad.toml");
    let text = "[system]\nname = \"b\"\noverheads = { release = \"-1us\" }\n[tasks.a]\nexec = 1\nperiod = 4\n";
    std::fs::write(&p, text).unwrap_or_else(|e| panic!("{e}"));
    let o = rtpipe(&["analyze", &p.to_string_lossy()]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml:3:25: error: release must not be negative"),
        "{err}"
    );
}

/// `design`'s box search charges overheads (the example's periods are
/// fixed and verify); the MILP has no term for them and says so at the
/// table that gives them.
#[test]
fn design_charges_overheads_and_the_milp_refuses_them() {
    let o = rtpipe(&["design", &example("overheads.toml")]);
    assert_exit(&o, 0);
    let o = rtpipe(&["design", &example("overheads.toml"), "--method", "milp"]);
    assert_exit(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("overheads.toml:30:1: error: [system] overheads (scheduling overheads): the MILP (--method milp) has no blocking, overhead or jitter term"),
        "{err}"
    );
}

#[test]
fn measured_overheads_go_into_a_copy_of_the_spec() {
    let spec = example("overheads.toml");
    let dir = scratch("ovh-measure");
    let out = dir.join("measured.toml");
    let out_s = out.to_string_lossy().into_owned();
    // --write-spec needs --measure-overheads; the input is never replaced.
    assert_exit(&rtpipe(&["run", &spec, "--write-spec", &out_s]), 2);
    let o = rtpipe(&["run", &spec, "--measure-overheads", "--write-spec", &spec]);
    assert_exit(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("would overwrite the input spec"));
    let args = [
        "run",
        &spec,
        "--measure-overheads",
        "--policy",
        "other",
        "--best-effort",
    ];
    let o = rtpipe(&[&args[..], &["--write-spec", &out_s]].concat());
    assert_exit(&o, 0);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("context_switch    20000"), "{text}");
    assert!(text.contains("release            2000"), "{text}");
    let written = Spec::load(&out).unwrap_or_else(|e| panic!("{e}"));
    let given = Spec::load(std::path::Path::new(&spec)).unwrap_or_else(|e| panic!("{e}"));
    for cpu in [0, 1] {
        let (w, g) = (written.overheads.on(cpu), given.overheads.on(cpu));
        assert!(w.context_switch > 0 && w.release > 0, "{w:?}");
        assert_eq!(w.replenish, g.replenish, "replenish is not measured");
    }
    // Everything but the overheads is the input's.
    let mut back = written.clone();
    back.overheads = given.overheads.clone();
    assert_eq!(back, given);
}

/// A copy that does not validate is refused before anything is said to
/// be written: no "written as" line, no file, exit 2.
#[test]
fn a_copy_that_does_not_validate_is_never_said_written() {
    let dir = scratch("ovh-refused");
    // Utilisation bounds refuse overheads (they do not cover release
    // handlers): the measured copy of this spec cannot validate.
    let text = std::fs::read_to_string(example("paper-table3.toml"))
        .unwrap_or_default()
        .replace(
            "schedulability = \"rta\"",
            "schedulability = \"liu-layland\"",
        );
    let spec = dir.join("ll.toml");
    if let Err(e) = std::fs::write(&spec, text) {
        panic!("cannot write {}: {e}", spec.display());
    }
    let out = dir.join("measured.toml");
    let o = rtpipe(&[
        "run",
        &spec.to_string_lossy(),
        "--measure-overheads",
        "--policy",
        "other",
        "--best-effort",
        "--write-spec",
        &out.to_string_lossy(),
    ]);
    assert_exit(&o, 2);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(!said.contains("written as"), "{said}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("does not validate"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
