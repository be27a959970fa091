//! Inlets on CFD meshes: positions sampled uniformly by area on a boundary patch, and the
//! flow through it. Pure functions of the mesh, a random stream and a flow; the feeder
//! system that uses them is [`crate::stages::feeder`].
//!
//! A patch's faces are split into triangles once ([`PatchSampler::new`]): a triangle face
//! is kept, a polygon is fanned about its point average (the triangles OpenFOAM's face
//! area is the sum of). A cumulative-area table over the triangles makes one uniform draw
//! pick a triangle with probability proportional to its area, and two more draws pick a
//! point uniformly in it (the unit square folded onto the triangle). The particle's centre
//! is then moved inward along the face's unit inward normal by its simulated radius, so it
//! starts inside the mesh without touching the patch plane.
//!
//! Lengths in m, areas in m², velocities in m/s, flow rates in m³/s.

use glam::DVec3;
use rand::Rng;
use scg_mesh::{Location, MeshGeometry, PolyMesh};

use super::mesh_flow::{MeshFlow, hint};

/// One triangle of a patch face: corner `a` and edges `e1 = b − a`, `e2 = c − a`, m.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Triangle {
    a: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Index into [`PatchSampler::faces`].
    face: u32,
}

/// A boundary face of the patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InletFace {
    /// Global face index in the mesh.
    pub face: u32,
    /// Its owner cell (the cell inside the mesh).
    pub owner: u32,
    /// Unit normal pointing into the mesh.
    pub inward: DVec3,
    /// Face centre, m.
    pub centre: DVec3,
    /// Face area, m² (sum of its triangles).
    pub area: f64,
}

/// Uniform-by-area sampling of one boundary patch (built once per scene).
#[derive(Clone, Debug, PartialEq)]
pub struct PatchSampler {
    /// Patch index in the mesh.
    pub patch: usize,
    /// Patch name.
    pub name: String,
    faces: Vec<InletFace>,
    tris: Vec<Triangle>,
    /// Cumulative triangle areas, m² (the last is the patch area).
    cum: Vec<f64>,
}

/// Where a fed particle starts on a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InletPoint {
    /// The sampled point on the patch, m.
    pub on_patch: DVec3,
    /// The particle's centre: `on_patch` moved inward by the radius, m.
    pub centre: DVec3,
    /// Index of the face (into [`PatchSampler::faces`]).
    pub face: usize,
}

/// The flow through a patch, from the interpolated field at its face centres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchFlux {
    /// Patch area, m².
    pub area: f64,
    /// Volume flow rate into the mesh, Q = Σ u(x_f)·n_in,f A_f ≈ ∫ u·n_in dA, m³/s
    /// (positive inflow, negative outflow).
    pub inflow: f64,
    /// Area-weighted mean velocity over the patch, Σ u(x_f) A_f / A, m/s.
    pub mean_velocity: DVec3,
}

impl PatchSampler {
    /// The sampler of patch `patch` of `mesh` (with its `geom`). Errors (as text) for an
    /// unknown patch, a patch without faces or with zero area.
    pub fn new(mesh: &PolyMesh, geom: &MeshGeometry, patch: usize) -> Result<Self, String> {
        let p = mesh
            .patches
            .get(patch)
            .ok_or_else(|| format!("no patch {patch}"))?;
        let mut faces = Vec::with_capacity(p.size);
        let mut tris = Vec::new();
        let mut cum = Vec::new();
        let mut total = 0.0;
        for f in p.start..p.start + p.size {
            let (Some(&owner), Some(&a_vec), Some(&centre)) = (
                mesh.owner.get(f),
                geom.face_areas.get(f),
                geom.face_centres.get(f),
            ) else {
                return Err(format!("patch `{}`: face {f} is not in the mesh", p.name));
            };
            let inward = -a_vec.normalize_or_zero();
            if inward == DVec3::ZERO {
                continue; // a degenerate face: never sampled
            }
            let local = faces.len() as u32;
            let mut area = 0.0;
            let mut push = |a: DVec3, b: DVec3, c: DVec3| {
                let (e1, e2) = (b - a, c - a);
                let s = 0.5 * e1.cross(e2).length();
                if s > 0.0 {
                    area += s;
                    total += s;
                    tris.push(Triangle {
                        a,
                        e1,
                        e2,
                        face: local,
                    });
                    cum.push(total);
                }
            };
            let pts: Vec<DVec3> = mesh
                .face(f)
                .iter()
                .map(|&i| mesh.points[i as usize])
                .collect();
            if pts.len() == 3 {
                push(pts[0], pts[1], pts[2]);
            } else if !pts.is_empty() {
                let avg = pts.iter().sum::<DVec3>() / pts.len() as f64;
                for i in 0..pts.len() {
                    push(pts[i], pts[(i + 1) % pts.len()], avg);
                }
            }
            faces.push(InletFace {
                face: f as u32,
                owner,
                inward,
                centre,
                area,
            });
        }
        if !(total > 0.0 && total.is_finite()) {
            return Err(format!(
                "patch `{}` has no area to feed from ({} faces, area {total:e} m²)",
                p.name, p.size
            ));
        }
        Ok(PatchSampler {
            patch,
            name: p.name.clone(),
            faces,
            tris,
            cum,
        })
    }

    /// Patch area, m².
    pub fn area(&self) -> f64 {
        self.cum.last().copied().unwrap_or(0.0)
    }

    /// The patch's faces (degenerate ones left out).
    pub fn faces(&self) -> &[InletFace] {
        &self.faces
    }

    /// Number of triangles sampled from.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// A point uniformly distributed by area on the patch, with the centre of a particle
    /// of radius `radius` (m) placed there: three draws from `rng` (the triangle, then
    /// the point in it).
    pub fn sample(&self, rng: &mut impl Rng, radius: f64) -> InletPoint {
        let total = self.area();
        let u = rng.random::<f64>() * total;
        let k = self
            .cum
            .partition_point(|&c| c <= u)
            .min(self.tris.len().saturating_sub(1));
        let (mut r1, mut r2): (f64, f64) = (rng.random(), rng.random());
        if r1 + r2 > 1.0 {
            (r1, r2) = (1.0 - r1, 1.0 - r2);
        }
        let t = &self.tris[k];
        let on_patch = t.a + r1 * t.e1 + r2 * t.e2;
        let face = t.face as usize;
        InletPoint {
            on_patch,
            centre: on_patch + radius * self.faces[face].inward,
            face,
        }
    }

    /// The flow through the patch in `flow` (velocity interpolated at each face centre
    /// from its owner cell).
    pub fn flux(&self, flow: &MeshFlow) -> PatchFlux {
        let mut inflow = 0.0;
        let mut sum = DVec3::ZERO;
        for f in &self.faces {
            let (u, _) = flow.velocity(f.owner, f.centre);
            inflow += u.dot(f.inward) * f.area;
            sum += u * f.area;
        }
        let area = self.area();
        PatchFlux {
            area,
            inflow,
            mean_velocity: sum / area,
        }
    }
}

/// The cell hint and the interpolated fluid velocity (m/s) of a particle starting at `x`
/// next to a face owned by cell `owner`: the cell the locator walks to from the owner (the
/// owner itself when it holds x); when the walk does not end inside the mesh, the bin
/// grid's cell, or [`hint::UNLOCATED`] (then the particle is lost at its first step) with
/// the velocity extrapolated from the owner.
pub fn settle(flow: &MeshFlow, owner: u32, x: DVec3) -> (u32, DVec3) {
    match flow.track(owner, x) {
        Location::Inside(h) => (h.cell, flow.near_wall(h.cell, x, flow.at(&h))),
        _ => match flow.find_cell(x) {
            Some(c) => {
                let (u, _) = flow.velocity(c, x);
                (c, u)
            }
            None => (hint::UNLOCATED, flow.velocity(owner, x).0),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};

    /// A 1 × 1 × 1 box of 1 × 2 × 1 hexahedra whose middle y layer is moved to y = 0.3, so
    /// the x-min patch has two quads of areas 0.3 and 0.7 m².
    fn two_face_box() -> PolyMesh {
        let mut m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [1, 2, 1])
            .shape(CellShape::Hex)
            .naming(PatchNaming::Sides)
            .build()
            .unwrap();
        for p in &mut m.points {
            if (p.y - 0.5).abs() < 1e-12 {
                p.y = 0.3;
            }
        }
        m
    }

    #[test]
    fn quads_are_split_by_area_and_points_lie_on_the_patch() {
        let m = two_face_box();
        let g = MeshGeometry::new(&m).unwrap();
        let xmin = m.patches.iter().position(|p| p.name == "xmin").unwrap();
        let s = PatchSampler::new(&m, &g, xmin).unwrap();
        assert_eq!(s.faces().len(), 2);
        assert_eq!(s.triangle_count(), 8);
        assert!((s.area() - 1.0).abs() < 1e-15);
        let mut areas: Vec<f64> = s.faces().iter().map(|f| f.area).collect();
        areas.sort_by(f64::total_cmp);
        assert!((areas[0] - 0.3).abs() < 1e-15 && (areas[1] - 0.7).abs() < 1e-15);
        for f in s.faces() {
            assert_eq!(f.inward, DVec3::X);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 100_000;
        let mut low = 0usize;
        let mut quad = [0usize; 4]; // quarters of the patch in (y, z)
        let r = 0.01;
        for _ in 0..n {
            let p = s.sample(&mut rng, r);
            assert_eq!(p.on_patch.x, 0.0);
            assert_eq!(p.centre.x, r);
            assert!(p.on_patch.y >= 0.0 && p.on_patch.y <= 1.0);
            assert!(p.on_patch.z >= 0.0 && p.on_patch.z <= 1.0);
            // the face it was drawn from holds it
            let lower = s.faces()[p.face].centre.y < 0.3;
            assert_eq!(lower, p.on_patch.y <= 0.3, "{p:?}");
            low += usize::from(lower);
            quad[usize::from(p.on_patch.y > 0.5) + 2 * usize::from(p.on_patch.z > 0.5)] += 1;
        }
        // binomial: share on the 0.3 m² face within 4σ
        let sigma = (n as f64 * 0.3 * 0.7).sqrt();
        assert!((low as f64 - 0.3 * n as f64).abs() < 4.0 * sigma, "{low}");
        // each quarter (cutting across the fan triangles) holds 1/4 within 4σ
        let sigma = (n as f64 * 0.25 * 0.75).sqrt();
        for q in quad {
            assert!((q as f64 - 0.25 * n as f64).abs() < 4.0 * sigma, "{quad:?}");
        }
    }

    #[test]
    fn same_stream_same_points_and_three_draws_each() {
        let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [2, 2, 2])
            .shape(CellShape::Tet)
            .naming(PatchNaming::InletOutletWalls { axis: 2 })
            .build()
            .unwrap();
        let g = MeshGeometry::new(&m).unwrap();
        let s = PatchSampler::new(&m, &g, 0).unwrap();
        assert_eq!(s.name, "inlet");
        assert_eq!(s.triangle_count(), s.faces().len()); // triangles kept whole
        let mut a = ChaCha8Rng::seed_from_u64(3);
        let mut b = ChaCha8Rng::seed_from_u64(3);
        let pa = s.sample(&mut a, 0.1);
        let pb = s.sample(&mut b, 0.1);
        assert_eq!(pa, pb);
        // three f64 draws: two words each
        assert_eq!(a.get_word_pos(), 6);
        assert!((pa.centre - pa.on_patch - 0.1 * DVec3::Z).length() < 1e-16);
    }

    #[test]
    fn empty_or_unknown_patches_are_errors() {
        let mut m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [1, 1, 1])
            .naming(PatchNaming::Sides)
            .build()
            .unwrap();
        let end = m.n_faces();
        m.patches.push(scg_mesh::Patch {
            name: "empty".into(),
            kind: "patch".into(),
            start: end,
            size: 0,
        });
        let g = MeshGeometry::new(&m).unwrap();
        let e = PatchSampler::new(&m, &g, m.patches.len() - 1).unwrap_err();
        assert!(e.contains("empty") && e.contains("no area"), "{e}");
        assert!(PatchSampler::new(&m, &g, 99).is_err());
    }

    #[test]
    fn settle_and_flux_on_an_affine_field() {
        use scg_mesh::{CellField, Interpolation};
        let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [3, 3, 3])
            .shape(CellShape::Tet)
            .naming(PatchNaming::InletOutletWalls { axis: 0 })
            .perturbed(0.2, 4)
            .build()
            .unwrap();
        // The walls carry the affine field too (they move), so they are type `patch`: at a
        // no-slip `wall` meeting the inlet cell-point bounds the point values (interp.rs).
        let mut m = m;
        for p in &mut m.patches {
            p.kind = "patch".into();
        }
        let g = MeshGeometry::new(&m).unwrap();
        let u = |x: DVec3| DVec3::new(2.0 + x.y, 0.5 * x.z, -0.25);
        // patch values at the face centres: linear-exact point values on the boundary too
        let field = CellField {
            cells: g.cell_centres.iter().map(|&c| u(c)).collect(),
            patches: m
                .patches
                .iter()
                .map(|p| {
                    Some(
                        (p.start..p.start + p.size)
                            .map(|f| u(g.face_centres[f]))
                            .collect(),
                    )
                })
                .collect(),
        };
        let s = PatchSampler::new(&m, &g, 0).unwrap();
        let roles = vec![super::super::mesh_flow::PatchRole::Inlet; m.patches.len()];
        let flow = MeshFlow::new(m, &field, Interpolation::CellPointLinearExact, roles).unwrap();
        // Q = ∫ (2 + y) dy dz over the unit square = 2.5 m³/s; mean u = (2.5, 0.25, −0.25)
        let q = s.flux(&flow);
        assert!((q.area - 1.0).abs() < 1e-14);
        // exact but for the patch's edges and corners, where the point values are convex
        // combinations (no overshoot) rather than the affine fit: within 2 %
        assert!((q.inflow - 2.5).abs() < 2e-2 * 2.5, "{q:?}");
        assert!((q.mean_velocity - DVec3::new(2.5, 0.25, -0.25)).length() < 2e-2 * 2.5);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200 {
            let p = s.sample(&mut rng, 0.02);
            let owner = s.faces()[p.face].owner;
            let (cell, v) = settle(&flow, owner, p.centre);
            assert!((cell as usize) < flow.mesh().n_cells);
            // the interpolated field: exact but in cells at the box's edges and corners, where
            // point values are convex combinations; on this 3 × 3 × 3 box that is every cell
            let (w, _) = flow.velocity(cell, p.centre);
            assert!((v - w).length() < 1e-12, "{v} {w}");
            assert!(
                (v - u(p.centre)).length() < 0.1 * u(p.centre).length(),
                "{v} {}",
                u(p.centre)
            );
            assert!(matches!(flow.track(cell, p.centre), Location::Inside(h) if h.cell == cell));
        }
    }
}
