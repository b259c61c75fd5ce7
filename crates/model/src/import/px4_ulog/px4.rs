//! What PX4's source says and a log does not: which work queue each module
//! runs on, what releases it, and which `perf` counter times it.
//!
//! The table covers PX4 v1.11 and v1.12 (the log's `ver_sw_release`:
//! `major << 24 | minor << 16 | patch << 8 | type`), when the rate loop was
//! gyro driver → `sensors`' `VehicleAngularVelocity` → `mc_rate_control`
//! (→ `vtol_att_control` on a VTOL) → `actuator_controls_0` → the output
//! driver, all data-triggered through uORB callbacks. It follows those
//! versions' `ScheduledWorkItem(MODULE_NAME, px4::wq_configurations::…)`
//! and `WorkItem(…)` constructors (`src/modules/*`, `src/drivers/*`;
//! checked against the source: `vtol_att_control` and its counter on
//! `rate_ctrl`, `fw_att_control` on `attitude_ctrl`, px4io's `io update`
//! and `io control latency` counters; the other entries have not been
//! checked one by one, and a log whose `top` or `perf` disagrees is the
//! cue to fix them); the
//! queues' priorities are not taken from `WorkQueueManager.hpp` but from
//! the log's own `top` (`perf_top_*`), which shows what the board ran.
//! From v1.13 the allocator (`control_allocator`, `actuator_motors`)
//! replaces the mixers: another table, not written yet.

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
    /// Its `perf` elapsed-time counter, when it has one.
    pub(super) counter: Option<&'static str>,
    pub(super) queue: Queue,
    pub(super) release: Release,
    /// The uORB topic it publishes, when the rate loop's observed data end there.
    pub(super) publishes: Option<&'static str>,
    /// Only in the spec when its counter counted events (`vtol_att_control`
    /// runs on VTOLs only).
    pub(super) optional: bool,
}

const fn m(
    name: &'static str,
    counter: Option<&'static str>,
    queue: Queue,
    release: Release,
) -> Module {
    Module {
        name,
        counter,
        queue,
        release,
        publishes: None,
        optional: false,
    }
}

/// The rate loop of v1.11–v1.12, in data-flow order, then the modules that
/// compete with it on its threads or on threads above the output driver.
pub(super) const V1_11: &[Module] = &[
    m("gyro", None, Queue::GyroBus, Release::Gyro),
    Module {
        publishes: Some("vehicle_angular_velocity"),
        ..m(
            "vehicle_angular_velocity",
            None,
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    Module {
        publishes: Some("actuator_controls_0"),
        ..m(
            "mc_rate_control",
            Some("mc_rate_control: cycle"),
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    Module {
        publishes: Some("actuator_controls_0"),
        optional: true,
        ..m(
            "vtol_att_control",
            Some("vtol_att_control: cycle"),
            Queue::Wq("wq:rate_ctrl"),
            Release::Loop,
        )
    },
    m(
        "px4io",
        Some("io update"),
        Queue::Own("px4io"),
        Release::Loop,
    ),
    m(
        "mc_att_control",
        Some("mc_att_control: cycle"),
        Queue::Wq("wq:attitude_ctrl"),
        Release::Periodic,
    ),
    m(
        "fw_att_control",
        Some("fw_att_control: cycle"),
        Queue::Wq("wq:attitude_ctrl"),
        Release::Periodic,
    ),
    m(
        "ekf2",
        Some("ekf2: update"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "sensors",
        Some("sensors"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "vehicle_air_data",
        Some("vehicle_air_data: cycle"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "land_detector",
        Some("land_detector: cycle"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "mc_pos_control",
        Some("mc_pos_control: cycle time"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "fw_pos_control_l1",
        Some("fw_pos_control_l1: cycle"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "airspeed_selector",
        Some("airspeed_selector: elapsed"),
        Queue::Wq("wq:nav_and_controllers"),
        Release::Periodic,
    ),
    m(
        "pwm_out",
        Some("pwm_out: cycle"),
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
    m(
        "rc_update",
        Some("rc_update"),
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
    m(
        "battery_status",
        Some("battery_status"),
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
    m(
        "adc",
        Some("adc: sample"),
        Queue::Wq("wq:hp_default"),
        Release::Periodic,
    ),
];

/// The table for the log's `ver_sw_release`, or the versions covered.
pub(super) fn table(release: u32) -> Result<&'static [Module], String> {
    let (major, minor) = (release >> 24, (release >> 16) & 0xff);
    match (major, minor) {
        (1, 11) | (1, 12) => Ok(V1_11),
        _ => Err(format!(
            "PX4 v{major}.{minor}.{}: rtpipe's module → work-queue table covers v1.11 and v1.12",
            (release >> 8) & 0xff
        )),
    }
}

/// The work queue of an SPI device: PX4's device id packs bus type (3
/// bits, 2 = SPI), bus (5 bits), address and device type.
pub(super) fn spi_queue(device_id: u32) -> Option<String> {
    let (bus_type, bus) = (device_id & 0x7, (device_id >> 3) & 0x1f);
    (bus_type == 2).then(|| format!("wq:SPI{bus}"))
}
