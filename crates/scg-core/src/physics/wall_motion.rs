//! A wall's prescribed rigid motion (pure): where the wall is at time t and how fast its
//! surface moves at a point. Contacts are found in the wall's rest frame (the frame its
//! geometry and bin grid were built in), so a moving wall needs no rebuilt geometry; the
//! surface velocity at the contact point enters the contact model
//! ([`crate::physics::contact::model::wall_geometry`]).

use glam::{DMat3, DVec3};

/// Rigid motion at constant rates: translation at `velocity` and rotation at
/// `angular_velocity` about the point `centre` (where it is at t = 0), both from t = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallMotion {
    /// Velocity of `centre`, m/s.
    pub velocity: DVec3,
    /// Angular velocity (axis times rate, right-handed), rad/s.
    pub angular_velocity: DVec3,
    /// The rotation centre at t = 0, m.
    pub centre: DVec3,
}

impl Default for WallMotion {
    fn default() -> Self {
        Self::FIXED
    }
}

impl WallMotion {
    /// A wall at rest.
    pub const FIXED: WallMotion = WallMotion {
        velocity: DVec3::ZERO,
        angular_velocity: DVec3::ZERO,
        centre: DVec3::ZERO,
    };

    /// True for a wall at rest (its contacts take the rest-frame path, bit for bit as a
    /// wall without motion).
    pub fn is_fixed(&self) -> bool {
        self.velocity == DVec3::ZERO && self.angular_velocity == DVec3::ZERO
    }

    /// The wall's pose at time `t` (s).
    pub fn pose(&self, t: f64) -> Pose {
        let angle = self.angular_velocity * t;
        Pose {
            rotation: DMat3::from_axis_angle(
                angle.try_normalize().unwrap_or(DVec3::Z),
                angle.length(),
            ),
            centre: self.centre + self.velocity * t,
            rest_centre: self.centre,
            velocity: self.velocity,
            angular_velocity: self.angular_velocity,
        }
    }
}

/// Where a moving wall is at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation from the rest frame to the world.
    pub rotation: DMat3,
    /// The rotation centre now, m.
    pub centre: DVec3,
    /// The rotation centre at rest, m.
    pub rest_centre: DVec3,
    /// Velocity of the centre, m/s.
    pub velocity: DVec3,
    /// Angular velocity, rad/s.
    pub angular_velocity: DVec3,
}

impl Pose {
    /// The world point `x` (m) in the wall's rest frame.
    #[inline]
    pub fn to_rest(&self, x: DVec3) -> DVec3 {
        self.rotation.transpose() * (x - self.centre) + self.rest_centre
    }

    /// A rest-frame point in the world: R·(x − c₀) + c(t).
    #[inline]
    pub fn to_world(&self, x: DVec3) -> DVec3 {
        self.rotation * (x - self.rest_centre) + self.centre
    }

    /// The translation of the rest frame → world map x ↦ R·x + (c(t) − R·c₀), m (what a
    /// viewer's transform takes with the rotation R).
    #[inline]
    pub fn translation(&self) -> DVec3 {
        self.centre - self.rotation * self.rest_centre
    }

    /// A rest-frame direction in the world.
    #[inline]
    pub fn to_world_direction(&self, n: DVec3) -> DVec3 {
        self.rotation * n
    }

    /// Velocity of the wall's surface at the world point `x` (m), m/s: v + ω × (x − c).
    #[inline]
    pub fn velocity_at(&self, x: DVec3) -> DVec3 {
        self.velocity + self.angular_velocity.cross(x - self.centre)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point fixed on a wall rotating about z at ω through c + v·t: after t its world
    /// position is the rotated one, and the surface velocity there is v + ω × r.
    #[test]
    fn a_rotating_translating_wall() {
        let m = WallMotion {
            velocity: DVec3::new(0.5, 0.0, 0.0),
            angular_velocity: DVec3::new(0.0, 0.0, 2.0),
            centre: DVec3::new(1.0, 1.0, 0.0),
        };
        let t = 0.3;
        let p = m.pose(t);
        let on_wall = DVec3::new(2.0, 1.0, 0.5); // at rest: 1 m from the centre along x
        let (s, c) = (0.6_f64.sin(), 0.6_f64.cos());
        let world = m.centre + m.velocity * t + DVec3::new(c, s, 0.5);
        assert!((p.to_rest(world) - on_wall).length() < 1e-14);
        assert!((p.to_world(on_wall) - world).length() < 1e-14);
        assert!((p.rotation * on_wall + p.translation() - world).length() < 1e-14);
        let v = p.velocity_at(world);
        assert!((v - (m.velocity + 2.0 * DVec3::new(-s, c, 0.0))).length() < 1e-14);
        assert!((p.to_world_direction(DVec3::X) - DVec3::new(c, s, 0.0)).length() < 1e-15);
        assert!(WallMotion::FIXED.is_fixed() && !m.is_fixed());
    }
}
