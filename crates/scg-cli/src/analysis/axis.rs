//! The flow axis: where radial distances are measured from.

use glam::DVec3;

use scg_core::physics::flow::FlowField;

/// The axis of a flow: the vortex axis of a vortex or classifier flow, else the z axis
/// through the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlowAxis {
    /// A point on the axis, m.
    pub center: DVec3,
    /// Unit direction.
    pub axis: DVec3,
}

impl FlowAxis {
    /// The axis of `flow`.
    pub fn of(flow: &FlowField) -> Self {
        let (center, axis) = flow
            .vortex()
            .map_or((DVec3::ZERO, DVec3::Z), |v| (v.center, v.axis));
        FlowAxis { center, axis }
    }

    /// The part of `p − center` normal to the axis (what the vortex itself calls radial).
    pub fn radial(&self, p: [f64; 3]) -> DVec3 {
        let rel = DVec3::from_array(p) - self.center;
        rel - rel.dot(self.axis) * self.axis
    }

    /// Distance of `p` from the axis, m.
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.radial(p).length()
    }

    /// Two unit vectors spanning the plane normal to the axis (top-view coordinates).
    pub fn basis(&self) -> (DVec3, DVec3) {
        self.axis.any_orthonormal_pair()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_axis_is_z_through_the_origin() {
        let a = FlowAxis::of(&FlowField::Still);
        assert_eq!(a.distance([3.0, 4.0, 12.0]), 5.0);
        assert_eq!(a.radial([3.0, -4.0, 1.5]), DVec3::new(3.0, -4.0, 0.0));
    }
}
