//! The reader against facts pyulog (commit 3cf1779) prints for the
//! fixtures, and fuzzed: truncated and flipped bytes give `Err` or `Ok`,
//! never a panic.

use super::*;

fn fixture(name: &str) -> Vec<u8> {
    let path = format!("{}/tests/data/px4/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(path).expect("fixture")
}

fn count(log: &Ulog, topic: &str, multi: u8) -> usize {
    log.topic(topic, multi).map_or(0, Subscription::len)
}

#[test]
fn the_cube_orange_log_reads_as_pyulog_reads_it() {
    let log = Ulog::parse(fixture("sample_log_small.ulg")).unwrap();
    let with_data = log.subscriptions.iter().filter(|s| !s.is_empty()).count();
    assert_eq!(with_data, 70);
    assert_eq!(count(&log, "vehicle_angular_velocity", 0), 1812);
    assert_eq!(count(&log, "actuator_controls_0", 0), 1812);
    assert_eq!(count(&log, "sensor_combined", 0), 1298);
    assert_eq!(count(&log, "sensor_gyro", 2), 6);
    assert_eq!(
        log.info_text("ver_hw").as_deref(),
        Some("CUBEPILOT_CUBEORANGE")
    );
    assert_eq!(
        log.info_text("ver_sw_branch").as_deref(),
        Some("v1.11.2_w_rc_sysid")
    );
    assert_eq!(log.parameters["IMU_GYRO_RATEMAX"].number(), 400.0);
    assert!((log.parameters["MC_ROLLRATE_P"].number() - 0.15).abs() < 1e-6);
    assert_eq!(log.dropouts, 1);
    assert_eq!(log.info_multiple["perf_top_preflight"][0].len(), 31);
    assert_eq!(log.info_multiple["perf_counter_preflight"][0].len(), 89);
    let v = log.topic("vehicle_angular_velocity", 0).unwrap();
    let t = log.u64_values(v, "timestamp").unwrap();
    let s = log.u64_values(v, "timestamp_sample").unwrap();
    let ages: Vec<u64> = t.iter().zip(&s).map(|(t, s)| t - s).collect();
    assert_eq!(
        (ages.iter().min(), ages.iter().max()),
        (Some(&395), Some(&445))
    );
}

#[test]
fn appended_data_is_read_past_each_offset() {
    let log = Ulog::parse(fixture("sample_appended_multiple.ulg")).unwrap();
    assert_eq!(
        log.subscriptions.iter().filter(|s| !s.is_empty()).count(),
        20
    );
    assert_eq!(count(&log, "actuator_controls_0", 0), 95);
    assert_eq!(count(&log, "sensor_combined", 0), 2373);
    assert_eq!(count(&log, "vehicle_attitude", 0), 306);
    assert_eq!(log.info_text("ver_hw").as_deref(), Some("PX4FMU_V4PRO"));
}

#[test]
fn bad_files_are_refused_with_their_place() {
    let e = Ulog::parse(b"not a log at all".to_vec()).unwrap_err();
    assert_eq!((e.offset, e.message_type), (0, None));
    let mut cut = fixture("sample_log_small.ulg");
    cut.truncate(500_000);
    let e = Ulog::parse(cut).unwrap_err();
    assert!(e.problem.contains("cut log"), "{e}");
    assert!(e.offset > 400_000 && e.offset < 500_000, "{e}");
    // A data message whose id was never subscribed.
    let mut b = fixture("sample_log_small.ulg")[..16].to_vec();
    b.extend_from_slice(&[4, 0, b'D', 0x34, 0x12, 0, 0]);
    let e = Ulog::parse(b).unwrap_err();
    assert_eq!((e.offset, e.message_type), (16, Some(b'D')));
    assert!(e.to_string().contains("byte 16, message 'D'"), "{e}");
}

#[test]
fn a_format_that_contains_itself_is_refused() {
    let mut b = fixture("sample_log_small.ulg")[..16].to_vec();
    for (kind, payload) in [(b'F', &b"loop:loop x;"[..]), (b'A', &b"\0\x01\0loop"[..])] {
        b.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        b.push(kind);
        b.extend_from_slice(payload);
    }
    let e = Ulog::parse(b).unwrap_err();
    assert!(e.problem.contains("nests deeper"), "{e}");
}

#[test]
fn truncated_and_flipped_logs_never_panic() {
    let base = fixture("sample_appended_multiple.ulg");
    // Seeded draws, so a failure reproduces.
    let mut rng = crate::gen::Rng::new(1);
    let (mut ok, mut err) = (0, 0);
    for case in 0..3000 {
        let mut b = base.clone();
        if case % 3 == 0 {
            b.truncate((rng.next_u64() % b.len() as u64) as usize);
        }
        // Most flips in the definitions, where the formats are.
        let span = if case % 2 == 0 { 8000 } else { b.len() };
        for _ in 0..1 + rng.next_u64() % 4 {
            if span.min(b.len()) > 0 {
                let at = (rng.next_u64() % span.min(b.len()) as u64) as usize;
                b[at] ^= 1 << (rng.next_u64() % 8);
            }
        }
        match Ulog::parse(b) {
            Ok(_) => ok += 1,
            Err(_) => err += 1,
        }
    }
    assert_eq!(ok + err, 3000);
    assert!(err > 0, "some mutation must be refused");
}

#[test]
fn mutated_cube_orange_logs_import_or_fail_cleanly() {
    let base = fixture("sample_log_small.ulg");
    let mut rng = crate::gen::Rng::new(2);
    let mut imported = 0;
    for case in 0..600 {
        let mut b = base.clone();
        // The definitions and info messages hold what the spec is built from.
        let span = if case % 2 == 0 { 200_000 } else { b.len() };
        for _ in 0..1 + rng.next_u64() % 3 {
            let at = (rng.next_u64() % span as u64) as usize;
            b[at] ^= 1 << (rng.next_u64() % 8);
        }
        if let Ok(log) = Ulog::parse(b) {
            let from = if case % 2 == 0 {
                ExecFrom::Max
            } else {
                ExecFrom::Mean
            };
            imported += usize::from(import(&log, "fuzz", &stat(from)).is_ok());
        }
    }
    assert!(imported > 0, "most single flips leave an importable log");
}

#[test]
fn the_cube_orange_spec_holds_its_threads_modules_and_chains() {
    let log = Ulog::parse(fixture("sample_log_small.ulg")).unwrap();
    let i = import(&log, "cube", &stat(ExecFrom::Max)).unwrap();
    let spec = crate::Spec::parse("spec.toml", &i.spec).unwrap_or_else(|e| panic!("{e}"));
    let thread = |n: &str| {
        spec.threads
            .iter()
            .find(|t| t.name == n)
            .map(|t| t.priority)
    };
    // NuttX 255, 253, 250, 246, 245, 242, 241, 240 ranked 1.. (px4io, 237, is a task).
    assert_eq!(thread("rate_ctrl"), Some(1));
    assert_eq!(thread("SPI1"), Some(2));
    assert_eq!(thread("attitude_ctrl"), Some(6));
    assert_eq!(thread("hp_default"), Some(8));
    let task = |n: &str| spec.tasks.iter().find(|t| t.name == n).expect(n);
    assert_eq!(task("mc_rate_control").exec, 257_000);
    // io update's max (18353 µs) times waits for the IO coprocessor: px4io
    // is charged its CPU time from top, 426 ms of 21.326 s per 2500 µs.
    assert_eq!(task("px4io").exec, 50_000);
    let index = |n: &str| spec.tasks.iter().position(|t| t.name == n).expect(n);
    let triggers = task("mc_rate_control").triggers().map(|(t, _)| t.to_vec());
    assert_eq!(triggers, Some(vec![index("vehicle_angular_velocity")]));
    let spi1 = spec.threads.iter().position(|t| t.name == "SPI1");
    assert_eq!(task("gyro").thread, spi1);
    let names: Vec<&str> = spec
        .chains
        .iter()
        .filter_map(|c| c.name.as_deref())
        .collect();
    assert_eq!(
        names,
        [
            "gyro to vehicle_angular_velocity",
            "gyro to actuator_controls_0",
            "gyro to outputs"
        ]
    );
    let ages: Vec<(&str, usize, u64, u64)> = i
        .ages
        .iter()
        .map(|a| (a.topic.as_str(), a.count, a.min_ns, a.max_ns))
        .collect();
    assert_eq!(
        ages,
        [
            ("vehicle_angular_velocity", 1812, 395_000, 445_000),
            ("actuator_controls_0", 1812, 414_000, 465_000)
        ]
    );
    assert_eq!(i.observed.lines().count(), 1 + 2 * 1812);
    let mean = import(&log, "cube", &stat(ExecFrom::Mean)).unwrap();
    let spec = crate::Spec::parse("spec.toml", &mean.spec).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        spec.tasks
            .iter()
            .find(|t| t.name == "mc_rate_control")
            .map(|t| t.exec),
        Some(8_000)
    );
}

fn stat(stat: ExecFrom) -> Options<'static> {
    Options {
        stat,
        ..Options::default()
    }
}

/// The v1.6.0 log (ekf2) with the Cube Orange's counters.
fn before_work_queues(
    log: &Ulog,
    version: Option<(u32, u32)>,
) -> Result<Import, crate::Diagnostic> {
    let cube = Ulog::parse(fixture("sample_log_small.ulg")).unwrap();
    let opts = Options {
        stat: ExecFrom::Max,
        exec_log: Some((&cube, "cube.ulg")),
        exec_us: &[],
        px4_version: version,
    };
    import(log, "v16", &opts)
}

#[test]
fn a_log_before_work_queues_imports_as_tasks_polling_the_topic_before() {
    let log = Ulog::parse(fixture("sample_appended_multiple.ulg")).unwrap();
    let e = import(&log, "x", &stat(ExecFrom::Max)).unwrap_err();
    assert!(e.message.contains("lacks perf_counter_*"), "{}", e.message);
    let got = before_work_queues(&log, None).unwrap();
    let spec = crate::Spec::parse("v16.toml", &got.spec).unwrap();
    let names: Vec<&str> = spec.tasks.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["gyro", "sensors", "ekf2", "mc_att_control"]);
    // The timer callout first, then data-flow order; no threads.
    let prios: Vec<Option<u32>> = spec.tasks.iter().map(|t| t.priority).collect();
    assert_eq!(prios, [Some(1), Some(2), Some(3), Some(4)]);
    assert!(spec.threads.is_empty());
    assert_eq!(spec.tasks[0].period, crate::PeriodSpec::Fixed(4_000_000));
    assert_eq!(spec.triggered_by(), [vec![1], vec![2], vec![3], vec![]]);
    assert_eq!(got.ages.len(), 1);
    assert_eq!(
        (got.ages[0].count, got.ages[0].min_ns, got.ages[0].max_ns),
        (95, 3_520_000, 4_660_000)
    );
    assert_eq!(spec.chains.len(), 1);
    // The log's version disagrees with a given one; a version no table
    // covers is refused by name.
    let e = before_work_queues(&log, Some((1, 11))).unwrap_err();
    assert!(e.message.contains("v1.6.0"), "{}", e.message);
    let mut v18 = log.clone();
    v18.info.remove("ver_sw_release");
    let e = before_work_queues(&v18, Some((1, 8))).unwrap_err();
    assert!(
        e.message.contains("v1.8") && e.message.contains("v1.5–v1.6"),
        "{}",
        e.message
    );
    // Without the version and without the topics that show it.
    v18.subscriptions.retain(|s| s.name != "control_state");
    let e = before_work_queues(&v18, None).unwrap_err();
    assert!(e.message.contains("ver_sw_release"), "{}", e.message);
    assert!(e.help.unwrap_or_default().contains("--px4-version"));
}

#[test]
fn a_log_without_perf_counters_is_refused_naming_the_flags() {
    let mut log = Ulog::parse(fixture("sample_px4_events.ulg")).unwrap();
    log.info_multiple
        .retain(|k, _| !k.starts_with("perf_counter_"));
    let e = import(&log, "x", &stat(ExecFrom::Max)).unwrap_err();
    assert!(e.message.contains("lacks perf_counter_*"), "{}", e.message);
    let help = e.help.unwrap_or_default();
    assert!(
        help.contains("--exec-from") && help.contains("--exec-us"),
        "{help}"
    );
}

/// The SITL logs with the Cube Orange's counters, `--exec mean`.
fn sitl(name: &str, given: &[(String, u64)]) -> Result<Import, crate::Diagnostic> {
    let log = Ulog::parse(fixture(name)).unwrap();
    let cube = Ulog::parse(fixture("sample_log_small.ulg")).unwrap();
    let opts = Options {
        stat: ExecFrom::Mean,
        exec_log: Some((&cube, "cube.ulg")),
        exec_us: given,
        px4_version: None,
    };
    import(&log, "sitl", &opts)
}

#[test]
fn sitl_logs_import_with_another_logs_counters_and_lockstep_ages() {
    for (name, version, topics) in [
        (
            "sample_logging_tagged_and_default_params.ulg",
            "PX4 v1.13.0",
            &["vehicle_angular_velocity", "actuator_controls_0"][..],
        ),
        (
            "sample_px4_events.ulg",
            "PX4 v1.15.0",
            &[
                "vehicle_angular_velocity",
                "vehicle_torque_setpoint",
                "actuator_motors",
            ][..],
        ),
    ] {
        let i = sitl(name, &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            i.lockstep && i.board == format!("PX4_SITL ({version})"),
            "{}",
            i.board
        );
        let measured: Vec<&str> = i.ages.iter().map(|a| a.topic.as_str()).collect();
        assert_eq!(measured, topics, "{name}");
        assert!(i.ages.iter().all(|a| a.max_ns == 0), "lockstep ages are 0");
        assert!(i.assumptions.iter().any(|a| a.contains("lockstep ages")));
        assert!(i.assumptions.iter().any(|a| a.contains("no perf_top_*")));
        let spec = crate::Spec::parse("spec.toml", &i.spec).unwrap_or_else(|e| panic!("{e}"));
        let prio = |n: &str| {
            spec.threads
                .iter()
                .find(|t| t.name == n)
                .map(|t| t.priority)
        };
        // The simulator (SCHED_PRIORITY_MAX, as rate_ctrl) ranked just above it.
        assert_eq!((prio("simulator"), prio("rate_ctrl")), (Some(1), Some(2)));
        let task = |n: &str| spec.tasks.iter().find(|t| t.name == n).expect(n);
        // The Cube's `mc_rate_control: cycle` average, 7.43 µs, rounded up;
        // SITL's gyro step, 4 ms, measured from timestamp_sample.
        assert_eq!(task("mc_rate_control").exec, 8_000);
        assert!(i.spec.contains("period = \"4000us\""), "{}", i.spec);
        assert!(i.spec.contains("from top of --exec-from cube.ulg"));
    }
}

#[test]
fn given_times_override_and_unknown_modules_are_refused() {
    let given = [("control_allocator".to_string(), 20)];
    let i = sitl("sample_px4_events.ulg", &given).unwrap();
    let spec = crate::Spec::parse("spec.toml", &i.spec).unwrap_or_else(|e| panic!("{e}"));
    let ca = spec.tasks.iter().find(|t| t.name == "control_allocator");
    assert_eq!(ca.map(|t| t.exec), Some(20_000));
    let typo = [("control_alocator".to_string(), 20)];
    let e = sitl("sample_px4_events.ulg", &typo).unwrap_err();
    assert!(
        e.message.contains("no module `control_alocator`"),
        "{}",
        e.message
    );
}

#[test]
fn a_sitl_log_alone_is_refused_for_its_zero_times() {
    let log = Ulog::parse(fixture("sample_px4_events.ulg")).unwrap();
    let e = import(&log, "x", &stat(ExecFrom::Max)).unwrap_err();
    assert!(
        e.message.contains("0 µs") && e.message.contains("lockstep"),
        "{}",
        e.message
    );
    assert!(e.help.unwrap_or_default().contains("--exec-from"));
}

#[test]
fn an_empty_array_value_is_no_number_and_no_panic() {
    let mut b = fixture("sample_log_small.ulg")[..16].to_vec();
    let key = b"uint32_t[0] ver_sw_release";
    b.extend_from_slice(&(1 + key.len() as u16).to_le_bytes());
    b.push(b'I');
    b.push(key.len() as u8);
    b.extend_from_slice(key);
    let log = Ulog::parse(b).unwrap();
    assert!(log.info["ver_sw_release"].number().is_nan());
    let e = import(&log, "x", &stat(ExecFrom::Max)).unwrap_err();
    assert!(e.message.contains("ver_sw_release"), "{}", e.message);
}
