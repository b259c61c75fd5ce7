//! What PX4's source says and a log does not: which work queue each module
//! runs on, what releases it, which `perf` counter times it, and (for a log
//! without `top`) each work queue's priority.
//!
//! The tables, by the log's `ver_sw_release` (`major << 24 | minor << 16 |
//! patch << 8 | type`):
//!
//! - [`V1_11`] (v1.11, v1.12): gyro driver → `sensors`'
//!   `VehicleAngularVelocity` → `mc_rate_control` (→ `vtol_att_control` on a
//!   VTOL) → `actuator_controls_0` → the output driver, all data-triggered
//!   through uORB callbacks. Checked against the source: `vtol_att_control`
//!   and its counter on `rate_ctrl`, `fw_att_control` on `attitude_ctrl`,
//!   px4io's `io update` and `io control latency` counters; the other
//!   entries have not been checked one by one (a log whose `top` or `perf`
//!   disagrees is the cue to fix them).
//! - [`V1_13`] (v1.13 to v1.15): the same loop, and `control_allocator`
//!   (`rate_ctrl`) after `mc_rate_control` when the log ran it (its counter
//!   counted runs): it takes `vehicle_torque_setpoint` and publishes
//!   `actuator_motors`. Each entry says in a comment whether its
//!   `ScheduledWorkItem`/`WorkItem` line was read in PX4-Autopilot's source
//!   (docs/px4.md's table gives the line and the stored version read, which
//!   is not the release tag: the tags themselves could not be read here).
//!
//! - [`V1_6_Q`] / [`V1_6_EKF2`] (v1.5–v1.6, before work queues): each
//!   module a task of its own polling the topic before it, at the
//!   `px4_task_spawn_cmd` priorities of [`task_priority`].
//!
//! The queues' priorities come from the log's own `top` (`perf_top_*`) when
//! it has one (what the board ran); without it from [`wq_priority`],
//! PX4's `WorkQueueManager.hpp` (each queue's priority relative to
//! `SCHED_PRIORITY_MAX`).

/// Where a module runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Queue {
    /// A work-queue thread, by its name in `top`.
    Wq(&'static str),
    /// The SPI bus work queue of the selected gyro (its device id says the bus).
    GyroBus,
    /// A thread of its own, by its name in `top`.
    Own(&'static str),
}

/// What releases a module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Release {
    /// The sensor's data-ready rate (the gyro driver).
    Gyro,
    /// A publication of the module before it on the rate loop.
    Loop,
    /// Its own rate, observed as `perf` events over the uptime.
    Periodic,
}

/// One module of the table.
#[derive(Debug, Clone, Copy)]
pub(super) struct Module {
    /// Its task name in the spec (PX4's module name).
    pub(super) name: &'static str,
    /// Its `perf` elapsed-time counter's names across the versions the
    /// table covers (the first the log has is taken); none when it has none.
    pub(super) counter: &'static [&'static str],
    pub(super) queue: Queue,
    pub(super) release: Release,
    /// The uORB topics it publishes where the rate loop's observed data may
    /// end (a chain is written for each the log has with `timestamp_sample`).
    pub(super) publishes: &'static [&'static str],
    /// Only in the spec when its counter counted events (`vtol_att_control`
    /// runs on VTOLs only).
    pub(super) optional: bool,
}

const fn m(
    name: &'static str,
    counter: &'static [&'static str],
    queue: Queue,
    release: Release,
) -> Module {
    Module {
        name,
        counter,
        queue,
        release,
        publishes: &[],
        optional: false,
    }
}

/// The gyro driver, on the SPI (or I2C) work queue of its bus.
const GYRO: Module = m("gyro", &[], Queue::GyroBus, Release::Gyro);
/// `sensors`' `vehicle_angular_velocity` on `wq:rate_ctrl`, released by
/// each gyro sample (v1.11–v1.15 alike). Its `gyro filter` counter (v1.13+)
/// times the filters only, not the run, so it has none here.
const ANGULAR_VELOCITY: Module = Module {
    publishes: &["vehicle_angular_velocity"],
    ..m(
        "vehicle_angular_velocity",
        &[],
        Queue::Wq("wq:rate_ctrl"),
        Release::Loop,
    )
};
/// `sensors` on `wq:nav_and_controllers` (v1.11–v1.15 alike).
const SENSORS: Module = m(
    "sensors",
    &["sensors"],
    Queue::Wq("wq:nav_and_controllers"),
    Release::Periodic,
);
/// `vehicle_air_data` on `wq:nav_and_controllers` (v1.11–v1.15 alike).
const VEHICLE_AIR_DATA: Module = m(
    "vehicle_air_data",
    &["vehicle_air_data: cycle"],
    Queue::Wq("wq:nav_and_controllers"),
    Release::Periodic,
);
/// `land_detector` on `wq:nav_and_controllers` (v1.11–v1.15 alike).
const LAND_DETECTOR: Module = m(
    "land_detector",
    &["land_detector: cycle"],
    Queue::Wq("wq:nav_and_controllers"),
    Release::Periodic,
);
/// `mc_pos_control` on `wq:nav_and_controllers` (v1.11–v1.15 alike).
const MC_POS_CONTROL: Module = m(
    "mc_pos_control",
    &["mc_pos_control: cycle time"],
    Queue::Wq("wq:nav_and_controllers"),
    Release::Periodic,
);

/// The rate loop of v1.11–v1.12, in data-flow order, then the modules that
/// compete with it on its threads or on threads above the output driver.
pub(super) const V1_11: &[Module] = &[
    GYRO,
    ANGULAR_VELOCITY,
    Module {
        publishes: &["actuator_controls_0"],
        ..m(
            "mc_rate_control",
            &["mc_rate_control: cycle"],
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    Module {
        publishes: &["actuator_controls_0"],
        optional: true,
        ..m(
            "vtol_att_control",
            &["vtol_att_control: cycle"],
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    m("px4io", &["io update"], Queue::Own("px4io"), Release::Loop),
    m(
        "mc_att_control",
        &["mc_att_control: cycle"],
        Queue::Wq("wq:attitude_ctrl"),
        Release::Periodic,
    ),
    m(
        "fw_att_control",
        &["fw_att_control: cycle"],
        Queue::Wq("wq:attitude_ctrl"),
        Release::Periodic,
    ),
    m(
        "ekf2",
        &["ekf2: update"],
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    SENSORS,
    VEHICLE_AIR_DATA,
    LAND_DETECTOR,
    MC_POS_CONTROL,
    m(
        "fw_pos_control_l1",
        &["fw_pos_control_l1: cycle"],
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "airspeed_selector",
        &["airspeed_selector: elapsed"],
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "pwm_out",
        &["pwm_out: cycle"],
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
    m(
        "rc_update",
        &["rc_update"],
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
    m(
        "battery_status",
        &["battery_status"],
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
    m(
        "adc",
        &["adc: sample"],
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
];

/// The rate loop of v1.13–v1.15, then the modules that compete with it.
/// Source lines (docs/px4.md, "The module table"): `VehicleAngularVelocity`
/// `ScheduledWorkItem(MODULE_NAME, px4::wq_configurations::rate_ctrl)`,
/// `MulticopterRateControl` `WorkItem(MODULE_NAME,
/// px4::wq_configurations::rate_ctrl)`, `ControlAllocator`
/// `ScheduledWorkItem(MODULE_NAME, px4::wq_configurations::rate_ctrl)`:
/// read (verified); the periodic modules' queues are carried over from
/// v1.11 (`attitude_ctrl` no longer exists: `mc_att_control` is on
/// `nav_and_controllers`) and not verified.
pub(super) const V1_13: &[Module] = &[
    GYRO,
    ANGULAR_VELOCITY,
    Module {
        publishes: &["actuator_controls_0", "vehicle_torque_setpoint"],
        ..m(
            "mc_rate_control",
            &["mc_rate_control: cycle"],
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    Module {
        publishes: &["actuator_motors"],
        optional: true,
        ..m(
            "control_allocator",
            &["control_allocator: cycle"],
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    m(
        "mc_att_control",
        &["mc_att_control: cycle"],
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    SENSORS,
    VEHICLE_AIR_DATA,
    LAND_DETECTOR,
    MC_POS_CONTROL,
];

/// The thread-less task the gyro driver runs in before work queues: a
/// high-resolution-timer callout, i.e. interrupt context, above every task.
pub(super) const HRT: &str = "hrt";

/// The rate loop of v1.5–v1.6, before work queues: each module its own
/// task (`px4_task_spawn_cmd`) blocking in `px4_poll()` on the topic before
/// it. The IMU driver's timer callout publishes the gyro; `sensors` polls
/// it and publishes `sensor_combined`; the estimator (`ESTIMATOR`) polls
/// that and publishes `control_state`; `mc_att_control` (attitude and rate
/// control in one task) polls `control_state` and publishes
/// `actuator_controls_0`, stamping it with `control_state`'s timestamp.
/// Which estimator ran is the log's `SYS_MC_EST_GROUP` (1: `attitude_estimator_q`,
/// 2: `ekf2`). Source lines: docs/px4.md, "Before work queues".
const fn pre_wq(estimator: &'static str, counter: &'static [&'static str]) -> [Module; 4] {
    [
        m("gyro", &[], Queue::Own(HRT), Release::Gyro),
        m(
            "sensors",
            &["sensors"],
            Queue::Own("sensors"),
            Release::Loop,
        ),
        m(estimator, counter, Queue::Own(estimator), Release::Loop),
        Module {
            publishes: &["actuator_controls_0"],
            ..m(
                "mc_att_control",
                &["mc_att_control: cycle", "mc_att_control"],
                Queue::Own("mc_att_control"),
                Release::Loop,
            )
        },
    ]
}

/// v1.5–v1.6 with `attitude_estimator_q` (`SYS_MC_EST_GROUP` 1).
pub(super) const V1_6_Q: &[Module] = &pre_wq("attitude_estimator_q", &[]);
/// v1.5–v1.6 with `ekf2` (`SYS_MC_EST_GROUP` 2).
pub(super) const V1_6_EKF2: &[Module] = &pre_wq("ekf2", &["ekf2: update"]);

/// A task's priority relative to `SCHED_PRIORITY_MAX` before work queues
/// (`px4_task_spawn_cmd(name, SCHED_DEFAULT, SCHED_PRIORITY_MAX - 5, …)` in
/// `sensors.cpp`, `ekf2_main.cpp`, `attitude_estimator_q_main.cpp`,
/// `mc_att_control_main.cpp`), and the timer callout's (above every task).
pub(super) fn task_priority(name: &str) -> Option<i16> {
    match name {
        HRT => Some(1),
        "sensors" | "ekf2" | "attitude_estimator_q" | "mc_att_control" => Some(-5),
        _ => None,
    }
}

/// The table for PX4 `vMAJOR.MINOR`; `est_group` is the log's
/// `SYS_MC_EST_GROUP` (which estimator ran before work queues).
pub(super) fn table(
    major: u32,
    minor: u32,
    est_group: Option<f64>,
) -> Result<&'static [Module], String> {
    match (major, minor) {
        (1, 11) | (1, 12) => Ok(V1_11),
        (1, 13..=15) => Ok(V1_13),
        (1, 5 | 6) => match est_group {
            Some(1.0) => Ok(V1_6_Q),
            Some(2.0) => Ok(V1_6_EKF2),
            _ => Err(format!("PX4 v{major}.{minor}: the parameter SYS_MC_EST_GROUP (which estimator fed mc_att_control) is {}, not 1 (attitude_estimator_q) or 2 (ekf2)", est_group.map_or("missing".to_string(), |g| g.to_string()))),
        },
        (1, 7..=10) => Err(format!(
            "PX4 v{major}.{minor}: rtpipe's module tables cover v1.5–v1.6 (tasks polling control_state) and v1.11–v1.15 (work queues); from v1.7 mc_att_control polled the gyro itself, and v1.10 began moving modules onto work queues: no table describes v1.7 to v1.10"
        )),
        _ => Err(format!(
            "PX4 v{major}.{minor}: rtpipe's module tables cover v1.5–v1.6 and v1.11 to v1.15"
        )),
    }
}

/// The thread the simulator publishes the gyro on in SITL (PX4's device
/// id's bus type 4, SIMULATION). Its task is spawned at
/// `SCHED_PRIORITY_MAX` (not verified against the source).
pub(super) const SIMULATOR: &str = "simulator";

/// A work queue's priority relative to `SCHED_PRIORITY_MAX`, from PX4's
/// `platforms/common/include/px4_platform_common/px4_work_queue/WorkQueueManager.hpp`
/// (`wq_config_t{name, stacksize, relative_priority}`; read at a stored
/// version with the `INS0`..`INS3` queues, v1.13 and later), and the
/// simulator's task.
pub(super) fn wq_priority(name: &str) -> Option<i16> {
    let bus = |prefix: &str, first: i16, count: i16| -> Option<i16> {
        let n: i16 = name.strip_prefix(prefix)?.parse().ok()?;
        (0..count).contains(&n).then_some(first - n)
    };
    match name {
        "wq:rate_ctrl" | SIMULATOR => Some(0),
        "wq:nav_and_controllers" => Some(-13),
        "wq:hp_default" => Some(-18),
        "wq:uavcan" => Some(-19),
        "wq:lp_default" => Some(-50),
        _ => bus("wq:SPI", -1, 7)
            .or_else(|| bus("wq:I2C", -8, 5))
            .or_else(|| bus("wq:INS", -14, 4)),
    }
}

/// The thread of the gyro with this device id: PX4's device id packs bus
/// type (3 bits: 2 = SPI, 4 = SIMULATION), bus (5 bits), address and
/// device type; an SPI gyro's driver runs on its bus' work queue.
pub(super) fn gyro_queue(device_id: u32) -> Option<String> {
    let (bus_type, bus) = (device_id & 0x7, (device_id >> 3) & 0x1f);
    match bus_type {
        2 => Some(format!("wq:SPI{bus}")),
        4 => Some(SIMULATOR.to_string()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queues_and_priorities_follow_the_work_queue_manager() {
        assert_eq!(wq_priority("wq:rate_ctrl"), Some(0));
        assert_eq!(wq_priority("wq:SPI1"), Some(-2));
        assert_eq!(wq_priority("wq:SPI6"), Some(-7));
        assert_eq!(wq_priority("wq:SPI7"), None);
        assert_eq!(wq_priority("wq:I2C4"), Some(-12));
        assert_eq!(wq_priority("wq:INS0"), Some(-14));
        assert_eq!(wq_priority("wq:nav_and_controllers"), Some(-13));
        assert_eq!(wq_priority("wq:attitude_ctrl"), None);
        // The Cube Orange's gyro (SPI bus 1) and SITL's simulated one.
        assert_eq!(gyro_queue(2_490_378).as_deref(), Some("wq:SPI1"));
        assert_eq!(gyro_queue(1_310_988).as_deref(), Some(SIMULATOR));
        assert_eq!(gyro_queue(1), None);
        assert!(table(1, 13, None).is_ok() && table(1, 15, None).is_ok());
        assert_eq!(table(1, 6, Some(2.0)).unwrap()[2].name, "ekf2");
        assert_eq!(
            table(1, 5, Some(1.0)).unwrap()[2].name,
            "attitude_estimator_q"
        );
        let est = table(1, 6, None).unwrap_err();
        assert!(est.contains("SYS_MC_EST_GROUP"), "{est}");
        let wq = table(1, 8, Some(2.0)).unwrap_err();
        assert!(wq.contains("v1.8") && wq.contains("v1.5–v1.6"), "{wq}");
        assert_eq!(task_priority("ekf2"), Some(-5));
        assert_eq!(task_priority(HRT), Some(1));
    }
}
