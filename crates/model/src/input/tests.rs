use super::*;

/// `bytes` as `f.toml` in a scratch directory that goes with the guard.
fn scratch(tag: &str, bytes: &[u8]) -> rtpipe_testkit::Scratch {
    let p = rtpipe_testkit::Scratch::new(&format!("input-{tag}")).within("f.toml");
    let _ = std::fs::write(&p, bytes);
    p
}

#[test]
fn a_bom_is_dropped_and_bad_bytes_are_located() {
    let p = scratch("bom", b"\xEF\xBB\xBFname = \"x\"\n");
    assert_eq!(
        read_text(&p, &Kind::MISSION).ok().as_deref(),
        Some("name = \"x\"\n")
    );
    let p = scratch("utf8", b"a = 1\nb = \"\xFF\"\n");
    let e = read_text(&p, &Kind::MISSION)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains(":2:6: error: cannot read the mission: not UTF-8 text (byte 0xFF"),
        "{e}"
    );
}

#[test]
fn control_characters_are_refused_with_their_place() {
    let p = scratch("ctl", b"name = \"x\" # a \x07 bell\n");
    let e = read_text(&p, &Kind::PRESET)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("f.toml:1:16: error: the vehicle preset holds the control character U+0007"),
        "{e}"
    );
    assert!(e.contains("\\u{7}"), "the line is shown escaped: {e}");
}

#[test]
fn deep_nesting_is_refused_before_parsing_and_quickly() {
    let t0 = std::time::Instant::now();
    let deep = "[".repeat(100_000);
    assert_eq!(
        too_deep(&format!("a = {deep}"), Syntax::Toml),
        Some(4 + MAX_NESTING)
    );
    assert!(too_deep(&format!("- {deep}"), Syntax::Yaml).is_some());
    assert!(too_deep(&"- ".repeat(50_000), Syntax::Yaml).is_some());
    let nested: String = (0..200).map(|k| format!("{}a:\n", " ".repeat(k))).collect();
    assert!(too_deep(&nested, Syntax::Yaml).is_some());
    assert!(t0.elapsed().as_secs_f64() < 1.0);
    // Brackets in strings and comments do not count, nor apostrophes in words.
    let fine = format!("a = \"{deep}\" # {deep}\nb = '{deep}'\n");
    assert_eq!(too_deep(&fine, Syntax::Toml), None);
    let yaml = format!("d: it's [x]\ne: \"{deep}\"\n");
    assert_eq!(too_deep(&yaml, Syntax::Yaml), None);
    let ok = "Tasks:\n  - !Task {a: 1, b: [1, 2]}\nChains: [[1, 2], [3]]\n";
    assert_eq!(too_deep(ok, Syntax::Yaml), None);
}

#[test]
fn toml_errors_name_line_and_column() {
    #[derive(serde::Deserialize, Debug)]
    #[allow(dead_code)]
    struct T {
        a: i64,
    }
    let e = parse_toml::<T>("m.toml", "\na = \"x\"\n", &Kind::MISSION)
        .err()
        .map(|e| e.located().message)
        .unwrap_or_default();
    assert!(e.starts_with("m.toml:2:5: "), "{e}");
}

#[test]
fn names_that_print_as_something_else_are_refused() {
    assert_eq!(name_problem("gyro"), None);
    assert_eq!(name_problem("Kreisel ü"), None);
    assert!(name_problem(&"x".repeat(MAX_NAME_CHARS + 1)).is_some_and(|m| m.contains("257")));
    assert!(name_problem("a\u{202E}b").is_some_and(|m| m.contains("bidirectional")));
    assert!(name_problem("a\u{200B}b").is_some_and(|m| m.contains("invisible")));
    assert!(name_problem("a\u{1b}[31mb").is_some_and(|m| m.contains("control")));
    assert!(name_problem(" ").is_some());
}

#[test]
fn fields_are_located_in_the_usual_toml() {
    let text = "name = \"m\"\n[body]\nmass_kg = 1\n[[step]]\nat = 0\n[[step]]\nat = 2\nroll_deg = 90\n[criteria]\n";
    let at = |f: &str| locate(text, f).map(|r| crate::line_col(text, r.start));
    assert_eq!(at("name"), Some((1, 1)));
    assert_eq!(at("body.mass_kg"), Some((3, 1)));
    assert_eq!(at("step[1].roll_deg"), Some((8, 1)));
    assert_eq!(at("step[0].at"), Some((5, 1)));
    assert_eq!(at("criteria.overshoot"), Some((9, 1)));
    assert_eq!(at("world.speed_mps"), None);
}

#[test]
fn lines_are_read_one_at_a_time_by_the_same_rules() {
    let kind = Kind {
        name: "measurements file",
        max_bytes: u64::MAX,
        syntax: Syntax::Toml,
        help: "h",
    };
    let p = scratch("lines", b"\xEF\xBB\xBFa,b\r\nc\n\nd");
    let mut lines = Lines::open(&p, &kind).ok();
    let mut seen = Vec::new();
    while let Some(Ok(Some((n, l)))) = lines.as_mut().map(|l| l.next_line()) {
        seen.push((n, l.to_string()));
    }
    let want = [(1, "a,b"), (2, "c"), (3, ""), (4, "d")].map(|(n, l)| (n, l.to_string()));
    assert_eq!(seen, want);

    let error = |bytes: &[u8]| {
        let p = scratch("lines-bad", bytes);
        let mut lines = Lines::open(&p, &kind).map_err(|e| e.message)?;
        loop {
            match lines.next_line() {
                Ok(Some(_)) => {}
                Ok(None) => return Ok(()),
                Err(e) => return Err(e.message),
            }
        }
    };
    let e = error(b"ok\nab\xFFc\n").err().unwrap_or_default();
    assert!(
        e.ends_with("f.toml:2:3: cannot read the measurements file: not UTF-8 text (byte 0xFF)"),
        "{e}"
    );
    let e = error(b"ok\nok\n\xC3\xA9\x07\n").err().unwrap_or_default();
    assert!(e.ends_with("f.toml:3:2: the measurements file holds the control character U+0007; it holds printable text"), "{e}");
    let long = vec![b'x'; MAX_LINE_BYTES + 1];
    let e = error(&long).err().unwrap_or_default();
    assert!(e.contains(":1:1: the line is longer than 64 KiB"), "{e}");
    assert!(
        error(&long[1..]).is_ok(),
        "a line of the cap's length is read"
    );
    let file = scratch("lines-dir", b"");
    let e = error_at(&file.with_file_name(""), &kind);
    assert!(e.contains("it is a directory, not a regular file"), "{e}");
}

fn error_at(p: &std::path::Path, kind: &Kind) -> String {
    Lines::open(p, kind)
        .err()
        .map(|e| e.message)
        .unwrap_or_default()
}
