//! The `foxglove.SceneUpdate` messages of an MCAP recording: a mesh flow's boundary
//! patches ([`TOPIC_PATCHES`](crate::layout::TOPIC_PATCHES), once) and the moving walls ([`TOPIC_WALLS`](crate::layout::TOPIC_WALLS), per frame), so
//! Foxglove's 3D panel draws the geometry beside the particles.

use foxglove::messages::{
    Color, KeyValuePair, LinePrimitive, Point3, Pose, Quaternion, SceneEntity, SceneUpdate,
    Timestamp, TriangleListPrimitive, Vector3,
};
use scg_core::frame::{Outline, RunMeta};

use crate::layout::{FRAME_ID, patch_color};

/// The identity pose.
pub(crate) fn identity() -> Pose {
    Pose {
        position: Some(Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        }),
        orientation: Some(Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }),
    }
}

/// The [`TOPIC_PATCHES`](crate::layout::TOPIC_PATCHES) message: one entity per boundary patch (id = its name, metadata
/// `role`), one indexed triangle list each, coloured by role, in frame `world`, forever.
pub(crate) fn patches_update(meta: &RunMeta) -> SceneUpdate {
    let entities = meta
        .patches
        .iter()
        .map(|p| {
            let [r, g, b, a] = patch_color(&p.role).map(|c| f64::from(c) / 255.0);
            SceneEntity {
                timestamp: Some(Timestamp::new(0, 0)),
                frame_id: FRAME_ID.to_owned(),
                id: p.name.clone(),
                lifetime: None,
                frame_locked: false,
                metadata: vec![KeyValuePair {
                    key: "role".to_owned(),
                    value: p.role.clone(),
                }],
                triangles: vec![TriangleListPrimitive {
                    pose: Some(identity()),
                    points: points(&p.vertices),
                    color: Some(Color { r, g, b, a }),
                    colors: Vec::new(),
                    indices: p.triangles.iter().flatten().copied().collect(),
                }],
                ..Default::default()
            }
        })
        .collect();
    SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}

/// Points in m as foxglove's.
fn points(v: &[[f64; 3]]) -> Vec<Point3> {
    v.iter()
        .map(|v| Point3 {
            x: v[0],
            y: v[1],
            z: v[2],
        })
        .collect()
}

/// The [`TOPIC_WALLS`](crate::layout::TOPIC_WALLS) message of a frame at time `t` (s,
/// stamped `timestamp`): every moving wall's strips at rest with the pose that moves them
/// where the wall is then.
pub(crate) fn walls_update(moving: &[Outline], t: f64, timestamp: Timestamp) -> SceneUpdate {
    let entities = moving
        .iter()
        .map(|o| {
            let p = o.motion.pose(t);
            let d = p.translation();
            let q = glam::DQuat::from_mat3(&p.rotation);
            let pose = Pose {
                position: Some(Vector3 {
                    x: d.x,
                    y: d.y,
                    z: d.z,
                }),
                orientation: Some(Quaternion {
                    x: q.x,
                    y: q.y,
                    z: q.z,
                    w: q.w,
                }),
            };
            SceneEntity {
                timestamp: Some(timestamp),
                frame_id: FRAME_ID.to_owned(),
                id: o.name.clone(),
                lines: o
                    .strips
                    .iter()
                    .map(|strip| LinePrimitive {
                        r#type: 0, // LINE_STRIP
                        pose: Some(pose),
                        thickness: 2.0,
                        scale_invariant: true,
                        points: points(strip),
                        color: Some(Color {
                            r: 0.63,
                            g: 0.63,
                            b: 0.63,
                            a: 1.0,
                        }),
                        ..Default::default()
                    })
                    .collect(),
                ..Default::default()
            }
        })
        .collect();
    SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}
