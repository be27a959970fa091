//! Boundary faces whose surface moves while the mesh stays: the rotor walls of a
//! frozen-rotor (MRF) zone, turning at Ω about an axis. A particle rebounding off one
//! rebounds relative to the surface's velocity Ω×(x − origin) at the point it meets
//! ([`super::land`]); the geometry itself does not turn (the frozen rotor's assumption).

use glam::DVec3;

use super::MeshFlow;

/// A rigid rotation: the angular velocity (rad/s) and a point on its axis (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spin {
    /// Angular velocity vector, rad/s.
    pub omega: DVec3,
    /// A point on the axis, m.
    pub origin: DVec3,
}

impl Spin {
    /// The velocity of the turning surface at x, m/s.
    #[inline]
    pub fn velocity(&self, x: DVec3) -> DVec3 {
        self.omega.cross(x - self.origin)
    }
}

/// Which boundary faces move, and how.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MovingFaces {
    /// The first boundary face of the mesh (the number of internal faces).
    first: usize,
    /// Per boundary face, the index of its spin in `spins` (`u16::MAX`: at rest).
    of_face: Vec<u16>,
    spins: Vec<Spin>,
}

impl MovingFaces {
    /// The faces `faces[k] = (mesh face, spin index)` of a mesh whose boundary faces are
    /// `first..first + n_boundary`; an internal face or an index past `spins` is an error.
    pub fn new(
        first: usize,
        n_boundary: usize,
        spins: Vec<Spin>,
        faces: &[(u32, usize)],
    ) -> Result<Self, String> {
        if spins.len() >= u16::MAX as usize {
            return Err(format!("{} spins (at most {})", spins.len(), u16::MAX - 1));
        }
        let mut of_face = vec![u16::MAX; n_boundary];
        for &(f, s) in faces {
            let k = (f as usize)
                .checked_sub(first)
                .filter(|k| *k < n_boundary)
                .ok_or_else(|| format!("face {f} is not a boundary face"))?;
            if s >= spins.len() {
                return Err(format!("face {f}: spin {s} of {}", spins.len()));
            }
            of_face[k] = s as u16;
        }
        Ok(MovingFaces {
            first,
            of_face,
            spins,
        })
    }

    /// The spin of mesh face `f`, `None` when it is at rest (or not a boundary face).
    #[inline]
    pub fn spin(&self, f: u32) -> Option<&Spin> {
        let k = (f as usize).checked_sub(self.first)?;
        let s = *self.of_face.get(k)?;
        self.spins.get(s as usize)
    }

    /// How many faces move.
    pub fn count(&self) -> usize {
        self.of_face.iter().filter(|s| **s != u16::MAX).count()
    }
}

impl MeshFlow {
    /// Let the boundary faces of `moving` move (a frozen rotor's walls).
    pub fn set_moving_faces(&mut self, moving: MovingFaces) {
        self.moving = Some(moving);
    }

    /// The moving boundary faces, if any.
    pub fn moving_faces(&self) -> Option<&MovingFaces> {
        self.moving.as_ref()
    }

    /// The velocity of boundary face `f`'s surface at x when it moves, m/s (`None` at
    /// rest).
    #[inline]
    pub fn surface_velocity(&self, f: u32, x: DVec3) -> Option<DVec3> {
        Some(self.moving.as_ref()?.spin(f)?.velocity(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_map_to_their_spins() {
        let s = Spin {
            omega: DVec3::Z * 2.0,
            origin: DVec3::X,
        };
        let m = MovingFaces::new(10, 5, vec![s], &[(12, 0), (14, 0)]).unwrap();
        assert_eq!(m.count(), 2);
        assert_eq!(m.spin(12), Some(&s));
        assert_eq!(m.spin(13), None);
        assert_eq!(m.spin(9), None);
        assert_eq!(m.spin(15), None);
        assert_eq!(
            s.velocity(DVec3::new(2.0, 0.0, 0.0)),
            DVec3::new(0.0, 2.0, 0.0)
        );
        assert!(MovingFaces::new(10, 5, vec![s], &[(9, 0)]).is_err());
        assert!(MovingFaces::new(10, 5, vec![s], &[(11, 1)]).is_err());
    }
}
