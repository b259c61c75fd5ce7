//! Motor output protocols: analog PWM, Oneshot125, DShot600.
//!
//! Pulse widths follow the conventions of Betaflight's
//! src/main/drivers/pwm_output.c (PWM 1000–2000 µs, Oneshot125 = PWM / 8);
//! DShot framing follows drivers/dshot.c (`prepareDshotPacket`): an 11-bit
//! value, one telemetry-request bit, and a 4-bit checksum, the XOR of the
//! three nibbles of (value << 1 | telemetry).

/// PWM pulse for zero throttle / disarmed, µs.
pub const PWM_MIN_US: f64 = 1000.0;
/// PWM pulse for full throttle, µs.
pub const PWM_MAX_US: f64 = 2000.0;
/// Oneshot125 pulse for zero throttle, µs.
pub const ONESHOT125_MIN_US: f64 = 125.0;
/// Oneshot125 pulse for full throttle, µs.
pub const ONESHOT125_MAX_US: f64 = 250.0;

/// DShot value meaning "motor stop" (disarmed).
pub const DSHOT_DISARMED: u16 = 0;
/// Smallest DShot throttle value (1–47 are commands).
pub const DSHOT_MIN_THROTTLE: u16 = 48;
/// Largest DShot throttle value (11 bits).
pub const DSHOT_MAX_THROTTLE: u16 = 2047;

/// DShot600 bit rate, bit/s.
pub const DSHOT600_BITRATE: f64 = 600_000.0;
/// DShot600 bit period, ns (1/600 kHz ≈ 1.67 µs).
pub const DSHOT600_BIT_NS: f64 = 1e9 / DSHOT600_BITRATE;
/// DShot600 high time of a 1 bit, ns (75 % of the bit: 1.25 µs).
pub const DSHOT600_T1H_NS: f64 = 0.75 * DSHOT600_BIT_NS;
/// DShot600 high time of a 0 bit, ns (37.5 % of the bit: 0.625 µs).
pub const DSHOT600_T0H_NS: f64 = 0.375 * DSHOT600_BIT_NS;
/// Duration of one 16-bit DShot600 frame, ns (≈ 26.7 µs).
pub const DSHOT600_FRAME_NS: f64 = 16.0 * DSHOT600_BIT_NS;

/// PWM pulse width for a command in [0, 1]; `PWM_MIN_US` when disarmed.
pub fn pwm_us(cmd: f64, armed: bool) -> f64 {
    if !armed {
        return PWM_MIN_US;
    }
    PWM_MIN_US + cmd.clamp(0.0, 1.0) * (PWM_MAX_US - PWM_MIN_US)
}

/// Oneshot125 pulse width for a command in [0, 1] (PWM scaled by 1/8).
pub fn oneshot125_us(cmd: f64, armed: bool) -> f64 {
    pwm_us(cmd, armed) / 8.0
}

/// Command in [0, 1] from a PWM pulse width (the ESC's view).
pub fn cmd_from_pwm_us(us: f64) -> f64 {
    ((us - PWM_MIN_US) / (PWM_MAX_US - PWM_MIN_US)).clamp(0.0, 1.0)
}

/// DShot throttle value for a command in [0, 1]: 48–2047 when armed, 0 when not.
pub fn dshot_value(cmd: f64, armed: bool) -> u16 {
    if !armed {
        return DSHOT_DISARMED;
    }
    let span = f64::from(DSHOT_MAX_THROTTLE - DSHOT_MIN_THROTTLE);
    DSHOT_MIN_THROTTLE + (cmd.clamp(0.0, 1.0) * span).round() as u16
}

/// Command in [0, 1] from a DShot value (the ESC's view); `None` for
/// disarmed (0) and special commands (1–47).
pub fn cmd_from_dshot(value: u16) -> Option<f64> {
    if value < DSHOT_MIN_THROTTLE {
        return None;
    }
    let span = f64::from(DSHOT_MAX_THROTTLE - DSHOT_MIN_THROTTLE);
    Some(f64::from(value.min(DSHOT_MAX_THROTTLE) - DSHOT_MIN_THROTTLE) / span)
}

/// What the ESCs make of four motor commands sent as DShot600 frames: each
/// command quantised to the protocol's 11 bits (0 when disarmed).
pub fn through_dshot(motors: [f64; 4], armed: bool) -> [f64; 4] {
    motors.map(|m| {
        let frame = dshot_frame(dshot_value(m, armed), false);
        dshot_decode(frame)
            .and_then(|(v, _)| cmd_from_dshot(v))
            .unwrap_or(0.0)
    })
}

/// The 16-bit DShot frame: (value << 1 | telemetry) << 4 | crc, where crc is
/// the XOR of the three nibbles of (value << 1 | telemetry). `value` is
/// masked to 11 bits.
pub fn dshot_frame(value: u16, telemetry: bool) -> u16 {
    let packet = ((value & 0x07FF) << 1) | u16::from(telemetry);
    let crc = (packet ^ (packet >> 4) ^ (packet >> 8)) & 0x0F;
    (packet << 4) | crc
}

/// Split a frame into (value, telemetry) if its checksum is right.
pub fn dshot_decode(frame: u16) -> Option<(u16, bool)> {
    let packet = frame >> 4;
    let value = packet >> 1;
    let telem = packet & 1 == 1;
    (dshot_frame(value, telem) == frame).then_some((value, telem))
}

/// High time of bit `i` (0 = most significant, sent first) of a frame, ns.
pub fn dshot600_high_ns(frame: u16, i: u32) -> f64 {
    if (frame >> (15 - i.min(15))) & 1 == 1 {
        DSHOT600_T1H_NS
    } else {
        DSHOT600_T0H_NS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dshot_frames_match_hand_computed_values() {
        // 1046 << 1 = 0x82C; crc = 8 ^ 2 ^ C = 6.
        assert_eq!(dshot_frame(1046, false), 0x82C6);
        // With telemetry: 0x82D; crc = 8 ^ 2 ^ D = 7.
        assert_eq!(dshot_frame(1046, true), 0x82D7);
        // Disarmed: all zero.
        assert_eq!(dshot_frame(0, false), 0x0000);
        // Minimum throttle 48: packet 0x060, crc = 0 ^ 6 ^ 0 = 6.
        assert_eq!(dshot_frame(48, false), 0x0606);
        assert_eq!(dshot_decode(0x82C6), Some((1046, false)));
        assert_eq!(dshot_decode(0x82C7), None);
    }

    #[test]
    fn dshot_values_and_timing() {
        assert_eq!(dshot_value(0.0, true), 48);
        assert_eq!(dshot_value(1.0, true), 2047);
        assert_eq!(dshot_value(0.7, false), 0);
        assert_eq!(cmd_from_dshot(2047), Some(1.0));
        assert_eq!(cmd_from_dshot(0), None);
        assert!((DSHOT600_BIT_NS - 1666.667).abs() < 1e-3);
        assert!((DSHOT600_T1H_NS - 1250.0).abs() < 1e-9);
        assert!((DSHOT600_T0H_NS - 625.0).abs() < 1e-9);
        assert_eq!(dshot600_high_ns(0x8000, 0), DSHOT600_T1H_NS);
        assert_eq!(dshot600_high_ns(0x8000, 1), DSHOT600_T0H_NS);
    }

    #[test]
    fn pwm_and_oneshot_widths() {
        assert_eq!(pwm_us(0.0, true), 1000.0);
        assert_eq!(pwm_us(0.5, true), 1500.0);
        assert_eq!(pwm_us(1.0, true), 2000.0);
        assert_eq!(pwm_us(0.8, false), 1000.0);
        assert_eq!(oneshot125_us(0.0, true), 125.0);
        assert_eq!(oneshot125_us(0.5, true), 187.5);
        assert_eq!(oneshot125_us(1.0, true), 250.0);
        assert_eq!(cmd_from_pwm_us(1250.0), 0.25);
    }
}
