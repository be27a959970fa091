//! Wall geometry (pure): where a sphere touches a wall, and how to draw the wall.

use glam::DVec3;
use std::f64::consts::TAU;
use std::sync::Arc;

use super::trimesh::{MeshScratch, TriMesh};

/// A rigid wall.
#[derive(Clone, Debug, PartialEq)]
pub enum WallShape {
    /// An infinite plane; particles live on the side `normal` points to.
    Plane {
        /// A point on the plane, m.
        point: DVec3,
        /// Unit normal pointing into the domain.
        normal: DVec3,
    },
    /// The inside of a cylinder (a vessel); particles live inside it.
    CylinderInside {
        /// A point on the axis, m.
        center: DVec3,
        /// Unit axis vector.
        axis: DVec3,
        /// Radius, m.
        radius: f64,
        /// Axial extent (from, to) relative to `center` along `axis`, m; `None` = infinite.
        extent: Option<(f64, f64)>,
    },
    /// The outside of a cylinder (e.g. an outlet nozzle pipe); particles live outside it.
    CylinderOutside {
        /// A point on the axis, m.
        center: DVec3,
        /// Unit axis vector.
        axis: DVec3,
        /// Radius, m.
        radius: f64,
        /// Axial extent (from, to) relative to `center` along `axis`, m; `None` = infinite.
        extent: Option<(f64, f64)>,
    },
    /// A rigid triangle mesh (two-sided; see [`TriMesh::contacts`]). A sphere may touch
    /// it in several places at once: the wall stage asks the mesh for all its contacts;
    /// [`WallShape::touch`] gives only the deepest.
    Mesh(Arc<TriMesh>),
}

/// Where a sphere touches a wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallTouch {
    /// Overlap δ > 0, m.
    pub overlap: f64,
    /// Unit normal from the wall toward the sphere centre.
    pub normal: DVec3,
    /// The mesh triangle touched (its index in the mesh); 0 for an analytic shape.
    pub element: u32,
}

fn in_extent(extent: Option<(f64, f64)>, h: f64) -> bool {
    extent.is_none_or(|(a, b)| h >= a && h <= b)
}

/// The offset of `x` from a cylinder's axis, perpendicular to it; `None` outside the
/// axial extent.
#[inline]
fn radial_offset(
    center: DVec3,
    axis: DVec3,
    extent: Option<(f64, f64)>,
    x: DVec3,
) -> Option<DVec3> {
    let rel = x - center;
    let h = rel.dot(axis);
    in_extent(extent, h).then(|| rel - h * axis)
}

/// Distance of `x` from a cylinder's axis and the unit outward radial direction; `None`
/// outside the axial extent. On the axis any direction perpendicular to it will do.
fn radial(
    center: DVec3,
    axis: DVec3,
    extent: Option<(f64, f64)>,
    x: DVec3,
) -> Option<(f64, DVec3)> {
    let r = radial_offset(center, axis, extent, x)?;
    let rho = r.length();
    let outward = if rho > 0.0 {
        r / rho
    } else {
        axis.any_orthonormal_vector()
    };
    Some((rho, outward))
}

impl WallShape {
    /// Signed distance from the wall surface to `x`, positive on the domain side, m, with
    /// the unit normal pointing into the domain; `None` outside a finite cylinder's extent
    /// and for a mesh (two-sided: it has no inside).
    #[inline(always)]
    pub fn distance(&self, x: DVec3) -> Option<(f64, DVec3)> {
        match *self {
            WallShape::Mesh(_) => None,
            WallShape::Plane { point, normal } => Some(((x - point).dot(normal), normal)),
            WallShape::CylinderInside {
                center,
                axis,
                radius,
                extent,
            } => radial(center, axis, extent, x).map(|(rho, out)| (radius - rho, -out)),
            WallShape::CylinderOutside {
                center,
                axis,
                radius,
                extent,
            } => radial(center, axis, extent, x).map(|(rho, out)| (rho - radius, out)),
        }
    }

    /// True when a sphere of radius `radius` (m) centred at `x` is certainly clear of the
    /// wall: the cheap test of the particles away from every wall (no square root or
    /// division). Exactly `touch(..).is_none()` for a plane; for a cylinder it answers
    /// `false` (not sure) within a relative 1e-9 of the touching distance, where the caller
    /// falls back to [`WallShape::touch`]. For a mesh, the bin grid's test
    /// ([`TriMesh::surely_clear`]).
    #[inline]
    pub fn surely_clear(&self, x: DVec3, radius: f64) -> bool {
        const MARGIN: f64 = 1e-9;
        let radial2 = |center, axis, extent| {
            radial_offset(center, axis, extent, x).map(DVec3::length_squared)
        };
        match *self {
            WallShape::Mesh(ref m) => m.surely_clear(x, radius),
            WallShape::Plane { point, normal } => (x - point).dot(normal) >= radius,
            WallShape::CylinderInside {
                center,
                axis,
                radius: rc,
                extent,
            } => radial2(center, axis, extent).is_none_or(|rho2| {
                let lim = rc - radius;
                lim > 0.0 && rho2 < lim * lim * (1.0 - MARGIN)
            }),
            WallShape::CylinderOutside {
                center,
                axis,
                radius: rc,
                extent,
            } => radial2(center, axis, extent).is_none_or(|rho2| {
                let lim = rc + radius;
                rho2 > lim * lim * (1.0 + MARGIN)
            }),
        }
    }

    /// Contact of a sphere of radius `radius` (m) centred at `x`, if it overlaps the wall
    /// (for a mesh: its deepest contact).
    #[inline]
    pub fn touch(&self, x: DVec3, radius: f64) -> Option<WallTouch> {
        if let WallShape::Mesh(m) = self {
            let mut out = Vec::new();
            m.contacts(x, radius, &mut MeshScratch::default(), &mut out);
            return out
                .iter()
                .max_by(|a, b| a.overlap.total_cmp(&b.overlap))
                .map(|c| WallTouch {
                    overlap: c.overlap,
                    normal: c.normal,
                    element: c.triangle,
                });
        }
        let (dist, normal) = self.distance(x)?;
        let overlap = radius - dist;
        (overlap > 0.0).then_some(WallTouch {
            overlap,
            normal,
            element: 0,
        })
    }

    /// The centroid (m) and area (m²) of the face a touch's `element` names: a mesh's
    /// triangle; `None` for an analytic shape (one unbounded face).
    pub fn face(&self, element: u32) -> Option<(DVec3, f64)> {
        let WallShape::Mesh(m) = self else {
            return None;
        };
        let [a, b, c] = m.triangles()[element as usize].map(|i| m.vertices()[i as usize]);
        Some(((a + b + c) / 3.0, 0.5 * (b - a).cross(c - a).length()))
    }

    /// True when a sphere centre `x` is on the domain side (distance ≥ 0).
    pub fn contains(&self, x: DVec3) -> bool {
        self.distance(x).is_none_or(|(d, _)| d >= 0.0)
    }

    /// Line strips that draw the wall; `size` (m) sets the drawn size of infinite shapes.
    /// A mesh is drawn by its feature edges ([`TriMesh::outline`]).
    pub fn outline(&self, size: f64) -> Vec<Vec<[f64; 3]>> {
        let p = |v: DVec3| [v.x, v.y, v.z];
        match *self {
            WallShape::Mesh(ref m) => m.outline(),
            WallShape::Plane { point, normal } => {
                let (a, b) = normal.any_orthonormal_pair();
                let h = 0.5 * size;
                let c = [(-h, -h), (h, -h), (h, h), (-h, h), (-h, -h)];
                vec![c.iter().map(|(s, t)| p(point + a * *s + b * *t)).collect()]
            }
            WallShape::CylinderInside {
                center,
                axis,
                radius,
                extent,
            }
            | WallShape::CylinderOutside {
                center,
                axis,
                radius,
                extent,
            } => {
                let (a, b) = axis.any_orthonormal_pair();
                let (h0, h1) = extent.unwrap_or((-0.5 * size, 0.5 * size));
                let ring = |h: f64| -> Vec<[f64; 3]> {
                    (0..=48)
                        .map(|k| {
                            let phi = TAU * k as f64 / 48.0;
                            p(center + axis * h + radius * (a * phi.cos() + b * phi.sin()))
                        })
                        .collect()
                };
                let mut strips = vec![ring(h0), ring(h1)];
                for k in 0..4 {
                    let phi = TAU * k as f64 / 4.0;
                    let off = radius * (a * phi.cos() + b * phi.sin());
                    strips.push(vec![
                        p(center + axis * h0 + off),
                        p(center + axis * h1 + off),
                    ]);
                }
                strips
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylinder_inside_touch() {
        let w = WallShape::CylinderInside {
            center: DVec3::ZERO,
            axis: DVec3::Z,
            radius: 1.0,
            extent: None,
        };
        let t = w.touch(DVec3::new(0.95, 0.0, 3.0), 0.1).unwrap();
        assert!((t.overlap - 0.05).abs() < 1e-12);
        assert_eq!(t.normal, DVec3::new(-1.0, 0.0, 0.0));
        assert!(w.touch(DVec3::ZERO, 0.1).is_none());
        // On the axis the distance is well defined and finite.
        let (d, n) = w.distance(DVec3::ZERO).unwrap();
        assert_eq!(d, 1.0);
        assert!(n.is_finite());
    }

    #[test]
    fn plane_touch() {
        let w = WallShape::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Z,
        };
        assert!(w.touch(DVec3::new(0.0, 0.0, 0.2), 0.1).is_none());
        let t = w.touch(DVec3::new(5.0, 1.0, 0.05), 0.1).unwrap();
        assert!((t.overlap - 0.05).abs() < 1e-15);
        assert!(!w.contains(DVec3::new(0.0, 0.0, -1.0)));
    }

    #[test]
    fn outside_cylinder_with_extent() {
        let w = WallShape::CylinderOutside {
            center: DVec3::ZERO,
            axis: DVec3::Z,
            radius: 0.5,
            extent: Some((0.0, 1.0)),
        };
        assert!(w.touch(DVec3::new(0.55, 0.0, 0.5), 0.1).is_some());
        assert!(w.touch(DVec3::new(0.55, 0.0, 1.5), 0.1).is_none());
    }

    proptest::proptest! {
        /// The cheap clearance test never calls a touching sphere clear, and for a plane
        /// it is exactly the negation of `touch`; near the surface it may be unsure.
        #[test]
        fn surely_clear_never_misses_a_touch(
            x in -1.2..1.2_f64, y in -1.2..1.2_f64, z in -0.5..1.5_f64,
            r in 1e-4..0.3_f64, wall in 0..3_usize,
        ) {
            let p = DVec3::new(x, y, z);
            let axis = DVec3::new(0.3, -0.2, 1.0).normalize();
            let shape = match wall {
                0 => WallShape::Plane { point: DVec3::new(0.1, 0.0, 0.2), normal: axis },
                1 => WallShape::CylinderInside {
                    center: DVec3::ZERO, axis, radius: 1.0, extent: Some((0.0, 1.0)),
                },
                _ => WallShape::CylinderOutside {
                    center: DVec3::ZERO, axis, radius: 0.5, extent: None,
                },
            };
            if shape.surely_clear(p, r) {
                proptest::prop_assert!(shape.touch(p, r).is_none());
            }
            if wall == 0 {
                proptest::prop_assert_eq!(shape.surely_clear(p, r), shape.touch(p, r).is_none());
            } else if let Some((d, _)) = shape.distance(p) {
                // Unsure only within the margin of the touching distance.
                if !shape.surely_clear(p, r) && shape.touch(p, r).is_none() {
                    proptest::prop_assert!((d - r).abs() <= 1e-8 * (1.0 + d.abs()));
                }
            }
        }
    }
}
