//! `[[walls]]`: analytic shapes and STL meshes, with their prescribed motion.

use scg_core::physics::flow::rpm_to_rad_per_s;
use scg_core::physics::trimesh::{TriMesh, weld};
use scg_core::physics::wall_shape::WallShape;
use scg_core::stages::walls::Wall;

use super::Ctx;
use crate::error::SceneError;
use crate::raw::{RawWall, RawWallKind};

/// `walls[i]`.
pub(super) fn wall(w: &RawWall, i: usize, cx: &Ctx) -> Result<Wall, SceneError> {
    let k = |s: &str| format!("walls[{i}].{s}");
    let extent = match w.extent {
        None => None,
        Some([a, b]) => {
            let (a, b) = (cx.finite(&k("extent"), a)?, cx.finite(&k("extent"), b)?);
            if a >= b {
                return Err(cx.err(&k("extent"), "must be [from, to] with from < to"));
            }
            Some((a, b))
        }
    };
    let shape = match w.kind {
        RawWallKind::Mesh => WallShape::Mesh(std::sync::Arc::new(mesh(w, i, cx)?)),
        RawWallKind::Plane => WallShape::Plane {
            point: cx.vec3(&k("point"), cx.need(&k("point"), &w.point)?)?,
            normal: cx.unit(&k("normal"), cx.need(&k("normal"), &w.normal)?)?,
        },
        RawWallKind::CylinderInside | RawWallKind::CylinderOutside => {
            let center = cx.vec3(&k("center"), w.center.unwrap_or([0.0; 3]))?;
            let axis = cx.unit(&k("axis"), w.axis.unwrap_or([0.0, 0.0, 1.0]))?;
            let radius = cx.positive(&k("radius"), cx.need(&k("radius"), &w.radius)?)?;
            if w.kind == RawWallKind::CylinderInside {
                WallShape::CylinderInside {
                    center,
                    axis,
                    radius,
                    extent,
                }
            } else {
                WallShape::CylinderOutside {
                    center,
                    axis,
                    radius,
                    extent,
                }
            }
        }
    };
    Ok(Wall {
        name: w.name.clone().unwrap_or_else(|| format!("wall{i}")),
        shape,
        motion: wall_motion(w.motion.as_ref(), i, cx)?,
    })
}

/// `walls[i].motion`: velocity and angular velocity (from `rpm` about a unit `axis`, or
/// `angular_velocity` itself) about `center`; a motion that moves nothing is refused.
fn wall_motion(
    m: Option<&crate::raw::RawWallMotion>,
    i: usize,
    cx: &Ctx,
) -> Result<scg_core::physics::wall_motion::WallMotion, SceneError> {
    use scg_core::physics::wall_motion::WallMotion;
    let Some(m) = m else {
        return Ok(WallMotion::FIXED);
    };
    let k = |s: &str| format!("walls[{i}].motion.{s}");
    let velocity = cx.vec3(&k("velocity"), m.velocity.unwrap_or([0.0; 3]))?;
    let angular_velocity = match (m.rpm, m.axis, m.angular_velocity) {
        (Some(_), _, Some(_)) | (None, Some(_), Some(_)) => {
            return Err(cx.err(
                &k("angular_velocity"),
                "give either `rpm` with `axis` or `angular_velocity`, not both",
            ));
        }
        (Some(rpm), axis, None) => {
            let axis = cx.unit(&k("axis"), cx.need(&k("axis"), &axis)?)?;
            axis * rpm_to_rad_per_s(cx.finite(&k("rpm"), rpm)?)
        }
        (None, Some(_), None) => return Err(cx.err(&k("axis"), "needs `rpm`")),
        (None, None, Some(w)) => cx.vec3(&k("angular_velocity"), w)?,
        (None, None, None) => glam::DVec3::ZERO,
    };
    let centre = cx.vec3(&k("center"), m.center.unwrap_or([0.0; 3]))?;
    let motion = WallMotion {
        velocity,
        angular_velocity,
        centre,
    };
    if motion.is_fixed() {
        return Err(cx.err(
            &format!("walls[{i}].motion"),
            "moves nothing: give `velocity`, `rpm` with `axis`, or `angular_velocity`",
        ));
    }
    Ok(motion)
}

/// `walls[i]` of kind `mesh`: the STL file (relative to the scene file's folder), scaled,
/// rotated and translated: x' = translate + R·(scale·x), R = R_z(rz)·R_y(ry)·R_x(rx) for
/// `rotate = [rx, ry, rz]` in degrees (about the fixed axes, x first), m.
fn mesh(w: &RawWall, i: usize, cx: &Ctx) -> Result<TriMesh, SceneError> {
    let k = |s: &str| format!("walls[{i}].{s}");
    let file = cx.need(&k("file"), &w.file)?;
    let scale = cx.positive(&k("scale"), w.scale.unwrap_or(1.0))?;
    let translate = cx.vec3(&k("translate"), w.translate.unwrap_or([0.0; 3]))?;
    let rot = cx.vec3(&k("rotate"), w.rotate.unwrap_or([0.0; 3]))?;
    let path = cx.base.join(&file);
    let shown = path.display();
    let soup = crate::stl::read(&path).map_err(|e| cx.err(&k("file"), format!("{shown}: {e}")))?;
    let (vertices, triangles) = weld(&soup);
    let vertices = crate::stl::place(vertices, scale, rot, translate);
    TriMesh::new(vertices, triangles).map_err(|e| cx.err(&k("file"), format!("{shown}: {e}")))
}
