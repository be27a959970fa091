//! Boundary patches as triangle surfaces: the faces of one or more patches split into
//! triangles that share the mesh's points (so neighbouring faces share their edges), for
//! contact walls and for drawing. Lengths in metres.

use glam::DVec3;

use crate::PolyMesh;
use crate::geometry::face_centre_and_area;

/// How a face of more than three points is split into triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fan {
    /// One triangle per edge, to the face centre (OpenFOAM's face centre, as
    /// [`face_centre_and_area`] and the locator's tetrahedra use it): n triangles and one
    /// added vertex per face of n points. The surface is exactly the boundary the
    /// locator tracks against, also for warped and non-convex (star-shaped) faces.
    Centre,
    /// A fan from the face's first point: n − 2 triangles, no added vertex (compact;
    /// exact for planar convex faces). For drawing.
    FirstPoint,
}

/// Triangles of boundary patches.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surface {
    /// Vertices, m: the mesh points the faces use (in first-use order), then, with
    /// [`Fan::Centre`], the face centres.
    pub vertices: Vec<DVec3>,
    /// Triangles as indices into `vertices`, oriented as their faces (right-hand normal
    /// out of the mesh).
    pub triangles: Vec<[u32; 3]>,
    /// Triangles per requested patch (same order as the request).
    pub per_patch: Vec<usize>,
}

/// True when the triangle `(a, b, c)` is too thin to have a normal (zero area or a
/// normal that is rounding noise): the test `scg-core`'s triangle meshes apply.
pub fn degenerate(a: DVec3, b: DVec3, c: DVec3) -> bool {
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    (b - a).cross(c - a).length() <= 1e-12 * longest
}

/// The faces of `patches` (indices into `mesh.patches`; unknown ones give no triangle)
/// as triangles split by `fan`. Triangles that are degenerate ([`degenerate`]: repeated
/// or collinear points) are left out: they have no area to touch or draw.
pub fn patch_surface(mesh: &PolyMesh, patches: &[usize], fan: Fan) -> Surface {
    let mut index = vec![u32::MAX; mesh.points.len()];
    let mut out = Surface::default();
    let mut centres: Vec<DVec3> = Vec::new();
    let mut centre_tris: Vec<[u32; 3]> = Vec::new();
    let mut vertex = |p: u32, out: &mut Surface| -> u32 {
        let slot = &mut index[p as usize];
        if *slot == u32::MAX {
            *slot = out.vertices.len() as u32;
            out.vertices.push(mesh.points[p as usize]);
        }
        *slot
    };
    for &pi in patches {
        let before = out.triangles.len() + centre_tris.len();
        if let Some(patch) = mesh.patches.get(pi) {
            let faces = patch.start..(patch.start + patch.size).min(mesh.n_faces());
            for f in faces {
                let face = mesh.face(f);
                if face.iter().any(|&p| p as usize >= mesh.points.len()) {
                    continue;
                }
                let at = |k: usize| mesh.points[face[k] as usize];
                let n = face.len();
                if n == 3 || fan == Fan::FirstPoint {
                    for k in 1..n.saturating_sub(1) {
                        if !degenerate(at(0), at(k), at(k + 1)) {
                            let t = [face[0], face[k], face[k + 1]].map(|p| vertex(p, &mut out));
                            out.triangles.push(t);
                        }
                    }
                } else {
                    let (c, _) = face_centre_and_area(&mesh.points, face);
                    let mut ci = None;
                    for k in 0..n {
                        let (a, b) = (at(k), at((k + 1) % n));
                        if degenerate(c, a, b) {
                            continue;
                        }
                        let centre = *ci.get_or_insert_with(|| {
                            centres.push(c);
                            centres.len() as u32 - 1
                        });
                        let [va, vb] = [face[k], face[(k + 1) % n]].map(|p| vertex(p, &mut out));
                        centre_tris.push([centre, va, vb]);
                    }
                }
            }
        }
        out.per_patch
            .push(out.triangles.len() + centre_tris.len() - before);
    }
    if !centre_tris.is_empty() {
        // The centres are numbered after the points; centre-fan triangles follow the
        // plain ones.
        let base = out.vertices.len() as u32;
        out.vertices.extend(centres);
        out.triangles
            .extend(centre_tris.into_iter().map(|[c, a, b]| [base + c, a, b]));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::{BoxMesh, CellShape, PatchNaming};

    fn area(s: &Surface) -> f64 {
        s.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| s.vertices[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[test]
    fn box_sides_are_covered_once() {
        for shape in [
            CellShape::Hex,
            CellShape::Tet,
            CellShape::Poly { refine: 0.5 },
        ] {
            let m = BoxMesh::new(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), [3, 4, 5])
                .shape(shape)
                .naming(PatchNaming::Sides)
                .build()
                .unwrap();
            let all: Vec<usize> = (0..m.patches.len()).collect();
            for fan in [Fan::Centre, Fan::FirstPoint] {
                let s = patch_surface(&m, &all, fan);
                assert_eq!(s.per_patch.len(), 6);
                assert_eq!(s.per_patch.iter().sum::<usize>(), s.triangles.len());
                // The whole surface of the box: 2·(1·2 + 2·3 + 1·3) = 22 m².
                assert!((area(&s) - 22.0).abs() < 1e-12, "{shape:?} {fan:?}");
                // Every triangle's normal points out of the box.
                let mid = DVec3::new(0.5, 1.0, 1.5);
                for t in &s.triangles {
                    let [a, b, c] = t.map(|i| s.vertices[i as usize]);
                    assert!((b - a).cross(c - a).dot(a - mid) > 0.0);
                }
                // Points are shared: a closed surface, each edge in two triangles (a
                // first-point fan may bridge a hanging node: then not along that edge).
                if fan == Fan::FirstPoint && shape != CellShape::Hex {
                    continue;
                }
                let mut edges = std::collections::HashMap::new();
                for t in &s.triangles {
                    for k in 0..3 {
                        let (p, q) = (t[k], t[(k + 1) % 3]);
                        *edges.entry((p.min(q), p.max(q))).or_insert(0) += 1;
                    }
                }
                assert!(edges.values().all(|&n| n == 2), "{shape:?} {fan:?}");
            }
            if shape == CellShape::Hex {
                let s = patch_surface(&m, &[0], Fan::Centre);
                // xmin: 4 × 5 quads, 4 triangles each, 30 points + 20 centres.
                assert_eq!(s.triangles.len(), 80);
                assert_eq!(s.vertices.len(), 50);
                let s = patch_surface(&m, &[0], Fan::FirstPoint);
                assert_eq!((s.triangles.len(), s.vertices.len()), (40, 30));
            }
        }
        let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [1, 1, 1])
            .build()
            .unwrap();
        let s = patch_surface(&m, &[99], Fan::Centre);
        assert_eq!(s.per_patch, vec![0]);
        assert!(s.triangles.is_empty());
    }
}
