//! Where a move ends on the mesh: [`land`] follows a particle from its last cell to its
//! new centre, crossing faces and applying every boundary patch's interaction on the way.

use glam::DVec3;
use scg_mesh::{Location, NO_TET, TableWalk};

use super::{MeshFlow, PatchInteraction, hint, rebound};
use crate::physics::carrier::Place;

/// Where a move from `x0` (in cell `h0`) to `x1` ends on the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing {
    /// Final centre, m.
    pub x: DVec3,
    /// Final velocity, m/s.
    pub v: DVec3,
    /// The fluid velocity at `x` when the landing found it on the table (m/s): what
    /// [`MeshFlow::velocity`] gives for `x` from the cell `hint`, bit for bit (the same
    /// records).
    pub u: Option<DVec3>,
    /// Next hint: the cell, or a departure marker ([`hint::escaped`], [`hint::stuck`],
    /// [`hint::LOST`]).
    pub hint: u32,
    /// The tetrahedron hint of the cell ([`NO_TET`] where the table did not find `x`).
    pub tet: u32,
    /// The step's first impact on a wall patch that rebounds or sticks (erosion logs it).
    pub impact: Option<WallImpact>,
}

/// A particle meeting a wall patch face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallImpact {
    /// The boundary face (the mesh's face index).
    pub face: u32,
    /// The face's unit normal, into the fluid.
    pub normal: DVec3,
    /// The particle's velocity as it met the face, m/s.
    pub velocity: DVec3,
}

/// Most wall reflections tried in one step before the particle is put back at its start.
pub const MAX_REFLECTIONS: usize = 8;

/// Settle the end of a move on the mesh: locate `x1` from `h_from` (a cell near the path);
/// crossing a patch applies that patch's interaction (`models`, one per patch; a patch
/// past the list escapes): a rebound changes the velocity and moves the rest of the step
/// after the impact on the new one ([`rebound`]), then locates again, at most [`MAX_REFLECTIONS`] times, after
/// which the particle goes back to `x0` (its start, in cell `h0`) with the rebound
/// velocity, so a wall is never passed; a stick or escape marks the particle
/// ([`hint::stuck`], [`hint::escaped`]). A boundary face the walk passes on its way to a
/// point inside the mesh (`Location::Crossed`: a concave boundary) counts as crossed. When
/// the wall patches are also a contact wall, this rebound is the last-resort guard (a
/// centre reaches a wall patch only through an overlap beyond the radius).
#[inline]
pub fn land(
    flow: &MeshFlow,
    x0: DVec3,
    h0: u32,
    h_from: Place,
    x1: DVec3,
    v1: DVec3,
    models: &[PatchInteraction],
) -> Landing {
    // The table first: x1 is in the tetrahedron of the mid-step point (most steps), its
    // cell, or a few cells on.
    let walked = flow.walk_from(h_from, x1);
    if let TableWalk::Inside { cell, tet, value } = walked {
        return Landing {
            x: x1,
            v: v1,
            u: Some(flow.near_wall(cell, x1, value)),
            hint: cell,
            tet,
            impact: None,
        };
    }
    land_boundary(flow, (x0, h0), h_from.cell, walked, x1, v1, models)
}

/// [`land`] when the table did not find x1 from `h_from` (`walked`): the boundary, the
/// locator. Out of line, so that the common case stays small where it is inlined.
#[inline(never)]
fn land_boundary(
    flow: &MeshFlow,
    (x0, h0): (DVec3, u32),
    h_from: u32,
    mut walked: TableWalk,
    mut x1: DVec3,
    mut v1: DVec3,
    models: &[PatchInteraction],
) -> Landing {
    let mut from = h_from;
    let mut impact = None;
    // the step's path length: what a rebound may give back along the wall
    let reach = (x1 - x0).length();
    for k in 0..MAX_REFLECTIONS {
        // The table's walk met a boundary face (a particle at a wall), or could not tell.
        // Whether the point beyond that face is inside the mesh elsewhere
        // (`Location::Crossed`) or not (`Left`) changes only the cell the next walk starts
        // from, so it is not asked.
        if k > 0 {
            walked = flow.walk_table(from, x1);
        }
        let (face, patch) = match walked {
            TableWalk::Inside { cell, tet, value } => {
                return Landing {
                    x: x1,
                    v: v1,
                    u: Some(flow.near_wall(cell, x1, value)),
                    hint: cell,
                    tet,
                    impact,
                };
            }
            TableWalk::Boundary { cell, face } => {
                from = cell;
                (face, flow.patch_of(face))
            }
            TableWalk::Unknown => match flow.track(from, x1) {
                Location::Inside(h) => {
                    return Landing {
                        x: x1,
                        v: v1,
                        u: None,
                        hint: h.cell,
                        tet: NO_TET,
                        impact,
                    };
                }
                Location::Crossed { face, patch, hit } => {
                    // The walk passed a boundary face (a concave boundary, a thin baffle)
                    // on its way to a point inside: the face's model decides, as when
                    // leaving.
                    from = hit.cell;
                    (face, patch)
                }
                Location::Left { face, patch } => (face, patch),
                Location::Outside => {
                    return Landing {
                        x: x1,
                        v: v1,
                        u: None,
                        hint: hint::LOST,
                        tet: NO_TET,
                        impact,
                    };
                }
            },
        };
        let model = models
            .get(patch as usize)
            .copied()
            .unwrap_or(PatchInteraction::Escape);
        let marker = match model {
            PatchInteraction::Rebound { e, mu, friction } => {
                let (n, p) = flow.face_plane(face);
                // a moving surface: the rebound relative to it
                let w = flow.surface_velocity(face, x1 - (x1 - p).dot(n) * n);
                impact = impact.or(Some(WallImpact {
                    face,
                    normal: -n,
                    velocity: w.map_or(v1, |w| v1 - w),
                }));
                (x1, v1) = match w {
                    None => rebound(x1, v1, p, n, e, mu, friction, reach),
                    Some(w) => {
                        let (x, v) = rebound(x1, v1 - w, p, n, e, mu, friction, reach);
                        (x, v + w)
                    }
                };
                continue;
            }
            PatchInteraction::Stick => {
                impact = impact.or(Some(WallImpact {
                    face,
                    normal: -flow.face_plane(face).0,
                    velocity: v1,
                }));
                hint::stuck(patch)
            }
            PatchInteraction::Escape => hint::escaped(patch),
        };
        return Landing {
            x: x1,
            v: v1,
            u: None,
            hint: marker,
            tet: NO_TET,
            impact,
        };
    }
    Landing {
        x: x0,
        v: v1,
        u: None,
        hint: h0,
        tet: NO_TET,
        impact,
    }
}
