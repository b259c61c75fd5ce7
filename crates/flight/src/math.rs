//! Small 3-vector and quaternion maths (f64).
//!
//! [`Quat`] is a Hamilton quaternion (w, x, y, z) that rotates body-frame
//! vectors into the world frame: `v_world = q ⊗ v_body ⊗ q*`.

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// Standard gravity, m/s² (the value Betaflight's pid.h uses too).
pub const GRAVITY: f64 = 9.80665;

/// A 3-vector.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Vec3 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);

    /// A vector from components.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
    /// Dot product.
    pub fn dot(self, o: Vec3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product `self × o`.
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Euclidean norm.
    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }
    /// Unit vector, or zero if the norm is zero.
    pub fn normalized(self) -> Vec3 {
        let n = self.norm();
        if n > 0.0 {
            self / n
        } else {
            Vec3::ZERO
        }
    }
    /// Component-wise product.
    pub fn hadamard(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    /// Component `i` (0 = x, 1 = y, 2 = z).
    pub fn axis(self, i: usize) -> f64 {
        match i {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }
    /// From an array `[x, y, z]`.
    pub fn from_array(a: [f64; 3]) -> Self {
        Vec3::new(a[0], a[1], a[2])
    }
    /// As an array `[x, y, z]`.
    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<f64> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f64) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}
impl Div<f64> for Vec3 {
    type Output = Vec3;
    fn div(self, s: f64) -> Vec3 {
        Vec3::new(self.x / s, self.y / s, self.z / s)
    }
}
impl Neg for Vec3 {
    type Output = Vec3;
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}
impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Vec3) {
        *self = *self + o;
    }
}
impl SubAssign for Vec3 {
    fn sub_assign(&mut self, o: Vec3) {
        *self = *self - o;
    }
}

/// Roll, pitch, yaw in radians (ZYX convention, see the crate docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Euler {
    /// Rotation about body x; positive lowers the right side.
    pub roll: f64,
    /// Rotation about body y; positive lowers the nose.
    pub pitch: f64,
    /// Rotation about world z; positive turns left.
    pub yaw: f64,
}

/// A Hamilton quaternion; unit quaternions rotate body → world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quat {
    /// Scalar part.
    pub w: f64,
    /// i component.
    pub x: f64,
    /// j component.
    pub y: f64,
    /// k component.
    pub z: f64,
}

impl Default for Quat {
    fn default() -> Self {
        Quat::IDENTITY
    }
}

impl Quat {
    /// The identity rotation.
    pub const IDENTITY: Quat = Quat {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// A quaternion from components (not normalised).
    pub const fn new(w: f64, x: f64, y: f64, z: f64) -> Self {
        Self { w, x, y, z }
    }

    /// Rotation of `angle` radians about `axis` (need not be unit).
    pub fn from_axis_angle(axis: Vec3, angle: f64) -> Quat {
        let a = axis.normalized();
        let (s, c) = (0.5 * angle).sin_cos();
        Quat::new(c, a.x * s, a.y * s, a.z * s)
    }

    /// The rotation `exp(½·v)`: rotate by |v| radians about v (a rotation
    /// vector). Exact for any |v|; used to integrate a constant body rate.
    pub fn from_rotation_vector(v: Vec3) -> Quat {
        let angle = v.norm();
        if angle < 1e-12 {
            // Second-order series avoids 0/0; normalise keeps it unit.
            Quat::new(1.0, 0.5 * v.x, 0.5 * v.y, 0.5 * v.z).normalized()
        } else {
            Quat::from_axis_angle(v, angle)
        }
    }

    /// From ZYX Euler angles: q = Rz(yaw)·Ry(pitch)·Rx(roll).
    pub fn from_euler(e: Euler) -> Quat {
        let (sr, cr) = (0.5 * e.roll).sin_cos();
        let (sp, cp) = (0.5 * e.pitch).sin_cos();
        let (sy, cy) = (0.5 * e.yaw).sin_cos();
        Quat::new(
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        )
    }

    /// ZYX Euler angles; pitch is clamped to ±90° at the singularity.
    pub fn to_euler(self) -> Euler {
        let q = self;
        let roll = (2.0 * (q.w * q.x + q.y * q.z)).atan2(1.0 - 2.0 * (q.x * q.x + q.y * q.y));
        let sp = (2.0 * (q.w * q.y - q.z * q.x)).clamp(-1.0, 1.0);
        let yaw = (2.0 * (q.w * q.z + q.x * q.y)).atan2(1.0 - 2.0 * (q.y * q.y + q.z * q.z));
        Euler {
            roll,
            pitch: sp.asin(),
            yaw,
        }
    }

    /// Hamilton product `self ⊗ o` (also available as `self * o`).
    pub fn compose(self, o: Quat) -> Quat {
        Quat::new(
            self.w * o.w - self.x * o.x - self.y * o.y - self.z * o.z,
            self.w * o.x + self.x * o.w + self.y * o.z - self.z * o.y,
            self.w * o.y - self.x * o.z + self.y * o.w + self.z * o.x,
            self.w * o.z + self.x * o.y - self.y * o.x + self.z * o.w,
        )
    }

    /// Conjugate (the inverse of a unit quaternion).
    pub fn conj(self) -> Quat {
        Quat::new(self.w, -self.x, -self.y, -self.z)
    }

    /// Norm.
    pub fn norm(self) -> f64 {
        (self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z).sqrt()
    }

    /// Unit quaternion (identity if the norm is zero).
    pub fn normalized(self) -> Quat {
        let n = self.norm();
        if n > 0.0 {
            Quat::new(self.w / n, self.x / n, self.y / n, self.z / n)
        } else {
            Quat::IDENTITY
        }
    }

    /// Rotate a body vector into the world: `q ⊗ v ⊗ q*`.
    pub fn rotate(self, v: Vec3) -> Vec3 {
        // v + 2w(u×v) + 2u×(u×v), u the vector part: no full products needed.
        let u = Vec3::new(self.x, self.y, self.z);
        let t = u.cross(v) * 2.0;
        v + t * self.w + u.cross(t)
    }

    /// Rotate a world vector into the body: `q* ⊗ v ⊗ q`.
    pub fn rotate_inv(self, v: Vec3) -> Vec3 {
        self.conj().rotate(v)
    }

    /// Time derivative for body rate `w`: q̇ = ½ q ⊗ (0, w).
    pub fn derivative(self, w: Vec3) -> Quat {
        let d = self.compose(Quat::new(0.0, w.x, w.y, w.z));
        Quat::new(0.5 * d.w, 0.5 * d.x, 0.5 * d.y, 0.5 * d.z)
    }

    /// `self + o·s` component-wise (for integrators).
    pub fn add_scaled(self, o: Quat, s: f64) -> Quat {
        Quat::new(
            self.w + o.w * s,
            self.x + o.x * s,
            self.y + o.y * s,
            self.z + o.z * s,
        )
    }

    /// The body z axis in the world (the thrust direction).
    pub fn body_z_world(self) -> Vec3 {
        self.rotate(Vec3::new(0.0, 0.0, 1.0))
    }

    /// Tilt: angle between body z and world z, radians.
    pub fn tilt(self) -> f64 {
        self.body_z_world().z.clamp(-1.0, 1.0).acos()
    }

    /// Rotation angle (radians, in [0, π]) between two attitudes.
    pub fn angle_to(self, o: Quat) -> f64 {
        let d = self.conj().compose(o);
        2.0 * d.w.abs().clamp(0.0, 1.0).acos()
    }
}

impl Mul for Quat {
    type Output = Quat;
    fn mul(self, o: Quat) -> Quat {
        self.compose(o)
    }
}

/// Wrap an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a.rem_euclid(t);
    if r > std::f64::consts::PI {
        r - t
    } else {
        r
    }
}

/// The difference `a − b` of two angles in degrees, wrapped to
/// (−180°, 180°]: how far `a` is from `b` the short way round (the one
/// home of a heading or yaw difference in degrees; [`wrap_pi`] in radians).
pub fn angle_diff_deg(a: f64, b: f64) -> f64 {
    wrap_pi((a - b).to_radians()).to_degrees()
}

/// Degrees to radians.
pub fn deg(d: f64) -> f64 {
    d.to_radians()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f64) -> bool {
        (a - b).norm() < tol
    }

    #[test]
    fn rotate_matches_hand_computed_90_degree_turns() {
        // +90° yaw takes body x (forward) to world y (left).
        let q = Quat::from_axis_angle(Vec3::new(0.0, 0.0, 1.0), deg(90.0));
        assert!(close(
            q.rotate(Vec3::new(1.0, 0.0, 0.0)),
            Vec3::new(0.0, 1.0, 0.0),
            1e-12
        ));
        // +90° roll takes body y (left) to world z (up): the right side goes down.
        let q = Quat::from_euler(Euler {
            roll: deg(90.0),
            pitch: 0.0,
            yaw: 0.0,
        });
        assert!(close(
            q.rotate(Vec3::new(0.0, 1.0, 0.0)),
            Vec3::new(0.0, 0.0, 1.0),
            1e-12
        ));
        // +90° pitch takes body x (nose) to world −z: the nose goes down.
        let q = Quat::from_euler(Euler {
            roll: 0.0,
            pitch: deg(90.0),
            yaw: 0.0,
        });
        assert!(close(
            q.rotate(Vec3::new(1.0, 0.0, 0.0)),
            Vec3::new(0.0, 0.0, -1.0),
            1e-12
        ));
        assert!(close(
            q.rotate_inv(q.rotate(Vec3::new(0.3, -2.0, 1.0))),
            Vec3::new(0.3, -2.0, 1.0),
            1e-12
        ));
    }

    #[test]
    fn euler_round_trip() {
        let e = Euler {
            roll: 0.3,
            pitch: -0.7,
            yaw: 2.5,
        };
        let back = Quat::from_euler(e).to_euler();
        assert!((back.roll - e.roll).abs() < 1e-12);
        assert!((back.pitch - e.pitch).abs() < 1e-12);
        assert!((back.yaw - e.yaw).abs() < 1e-12);
    }

    #[test]
    fn rotation_vector_integrates_constant_rate_exactly() {
        // 1 rad/s about z for 0.5 s = a 0.5 rad yaw.
        let q = Quat::IDENTITY.compose(Quat::from_rotation_vector(Vec3::new(0.0, 0.0, 0.5)));
        assert!((q.to_euler().yaw - 0.5).abs() < 1e-12);
        assert!((wrap_pi(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_pi(-0.5) + 0.5).abs() < 1e-15);
        // Heading differences the short way round, in (−180°, 180°].
        for (a, b, d) in [
            (-179.0, 179.0, 2.0),
            (0.0, 180.0, 180.0),
            (180.0, 0.0, 180.0),
            (10.0, 370.0, 0.0),
        ] {
            assert!((angle_diff_deg(a, b) - d).abs() < 1e-9, "{a} − {b}");
        }
    }
}
