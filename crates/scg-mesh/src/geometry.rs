//! Geometry derived once from a [`PolyMesh`]: face centres and area vectors, cell centres
//! and volumes (OpenFOAM's `primitiveMesh` formulas), cell bounding boxes, and the
//! connectivity the locator and the interpolation need (faces of each cell, cells of each
//! point), stored compressed with `u32` indices.

use glam::DVec3;

use crate::{MeshError, PolyMesh};

/// Face centre and area vector of a polygon by OpenFOAM's method
/// (`primitiveMeshFaceCentresAndAreas`): a fan of triangles about the point average; the
/// centre is the area-weighted mean of the triangle centroids, the area vector half the sum
/// of the triangle normals (m, m²). A degenerate face gets its point average and a zero
/// area.
pub fn face_centre_and_area(points: &[DVec3], face: &[u32]) -> (DVec3, DVec3) {
    let n = face.len();
    if n == 3 {
        let [a, b, c] = [0, 1, 2].map(|i| points[face[i] as usize]);
        return ((a + b + c) / 3.0, 0.5 * (b - a).cross(c - a));
    }
    let avg = face.iter().map(|&p| points[p as usize]).sum::<DVec3>() / n as f64;
    let (mut sum_n, mut sum_a, mut sum_ac) = (DVec3::ZERO, 0.0, DVec3::ZERO);
    for i in 0..n {
        let p = points[face[i] as usize];
        let q = points[face[(i + 1) % n] as usize];
        let nrm = (q - p).cross(avg - p);
        let a = nrm.length();
        sum_n += nrm;
        sum_a += a;
        sum_ac += a * (p + q + avg);
    }
    if sum_a < 1e-300 {
        (avg, DVec3::ZERO)
    } else {
        (sum_ac / (3.0 * sum_a), 0.5 * sum_n)
    }
}

/// Weights of the face's points and of its point average in its centre, as
/// [`face_centre_and_area`] computes it: `centre = Σ w_i p_i + w_avg · avg`. Returned as
/// per-point weights with the average folded in (they sum to 1), so that a quantity known
/// at the points is carried to the face centre exactly when it is affine in space.
pub fn face_centre_weights(points: &[DVec3], face: &[u32], out: &mut Vec<f64>) {
    let n = face.len();
    out.clear();
    out.resize(n, 1.0 / n as f64);
    if n == 3 {
        return;
    }
    let avg = face.iter().map(|&p| points[p as usize]).sum::<DVec3>() / n as f64;
    let mut sum_a = 0.0;
    let mut w = vec![0.0; n];
    let mut w_avg = 0.0;
    for i in 0..n {
        let j = (i + 1) % n;
        let p = points[face[i] as usize];
        let q = points[face[j] as usize];
        let a = (q - p).cross(avg - p).length();
        sum_a += a;
        w[i] += a;
        w[j] += a;
        w_avg += a;
    }
    if sum_a < 1e-300 {
        return;
    }
    for i in 0..n {
        out[i] = (w[i] + w_avg / n as f64) / (3.0 * sum_a);
    }
}

/// Everything the locator and the interpolation derive from the mesh, computed once.
#[derive(Clone, Debug, Default)]
pub struct MeshGeometry {
    /// Face centres, m.
    pub face_centres: Vec<DVec3>,
    /// Face area vectors (out of the owner), m².
    pub face_areas: Vec<DVec3>,
    /// Cell centres (centroids), m.
    pub cell_centres: Vec<DVec3>,
    /// Cell volumes, m³.
    pub cell_volumes: Vec<f64>,
    /// Cell bounding boxes (low, high corner), m.
    pub cell_bounds: Vec<[DVec3; 2]>,
    /// Offsets into `cell_faces`, one per cell plus one.
    pub cell_face_offsets: Vec<u32>,
    /// Faces of every cell, concatenated (in increasing face order).
    pub cell_faces: Vec<u32>,
    /// Offsets into `point_cells`, one per point plus one.
    pub point_cell_offsets: Vec<u32>,
    /// Cells using every point, concatenated.
    pub point_cells: Vec<u32>,
}

impl MeshGeometry {
    /// Derive the geometry of `mesh`; an error if it fails [`PolyMesh::check`].
    pub fn new(mesh: &PolyMesh) -> Result<Self, MeshError> {
        mesh.check(std::path::Path::new("<mesh>"))?;
        let nf = mesh.n_faces();
        let nc = mesh.n_cells;
        let mut face_centres = Vec::with_capacity(nf);
        let mut face_areas = Vec::with_capacity(nf);
        for f in 0..nf {
            let (c, a) = face_centre_and_area(&mesh.points, mesh.face(f));
            face_centres.push(c);
            face_areas.push(a);
        }
        // faces of each cell (CSR)
        let mut cell_face_offsets = vec![0u32; nc + 1];
        for &c in mesh.owner.iter().chain(&mesh.neighbour) {
            cell_face_offsets[c as usize + 1] += 1;
        }
        for c in 0..nc {
            cell_face_offsets[c + 1] += cell_face_offsets[c];
        }
        let mut fill = cell_face_offsets.clone();
        let mut cell_faces = vec![0u32; cell_face_offsets[nc] as usize];
        for f in 0..nf {
            let o = mesh.owner[f] as usize;
            cell_faces[fill[o] as usize] = f as u32;
            fill[o] += 1;
            if let Some(&n) = mesh.neighbour.get(f) {
                cell_faces[fill[n as usize] as usize] = f as u32;
                fill[n as usize] += 1;
            }
        }
        // centres and volumes: pyramids on the faces about the face-centre average
        let mut cell_centres = Vec::with_capacity(nc);
        let mut cell_volumes = Vec::with_capacity(nc);
        for c in 0..nc {
            let faces =
                &cell_faces[cell_face_offsets[c] as usize..cell_face_offsets[c + 1] as usize];
            let est = faces
                .iter()
                .map(|&f| face_centres[f as usize])
                .sum::<DVec3>()
                / faces.len().max(1) as f64;
            let (mut vol3, mut ctr) = (0.0, DVec3::ZERO);
            for &f in faces {
                let f = f as usize;
                let sign = if mesh.owner[f] as usize == c {
                    1.0
                } else {
                    -1.0
                };
                let pyr3 = sign * face_areas[f].dot(face_centres[f] - est);
                vol3 += pyr3;
                ctr += pyr3 * (0.75 * face_centres[f] + 0.25 * est);
            }
            if vol3.abs() > 1e-300 {
                cell_centres.push(ctr / vol3);
            } else {
                cell_centres.push(est);
            }
            cell_volumes.push(vol3 / 3.0);
        }
        // cells of each point (CSR), bounding boxes
        let np = mesh.points.len();
        let mut mark = vec![u32::MAX; np];
        let mut point_cell_offsets = vec![0u32; np + 1];
        let mut cell_bounds = Vec::with_capacity(nc);
        let for_points = |c: usize, mark: &mut [u32], g: &mut dyn FnMut(usize)| {
            for &f in &cell_faces[cell_face_offsets[c] as usize..cell_face_offsets[c + 1] as usize]
            {
                for &p in mesh.face(f as usize) {
                    if mark[p as usize] != c as u32 {
                        mark[p as usize] = c as u32;
                        g(p as usize);
                    }
                }
            }
        };
        for c in 0..nc {
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for_points(c, &mut mark, &mut |p| {
                point_cell_offsets[p + 1] += 1;
                lo = lo.min(mesh.points[p]);
                hi = hi.max(mesh.points[p]);
            });
            cell_bounds.push([lo, hi]);
        }
        for p in 0..np {
            point_cell_offsets[p + 1] += point_cell_offsets[p];
        }
        mark.fill(u32::MAX);
        let mut fill = point_cell_offsets.clone();
        let mut point_cells = vec![0u32; point_cell_offsets[np] as usize];
        for c in 0..nc {
            for_points(c, &mut mark, &mut |p| {
                point_cells[fill[p] as usize] = c as u32;
                fill[p] += 1;
            });
        }
        Ok(MeshGeometry {
            face_centres,
            face_areas,
            cell_centres,
            cell_volumes,
            cell_bounds,
            cell_face_offsets,
            cell_faces,
            point_cell_offsets,
            point_cells,
        })
    }

    /// Faces of cell `c`.
    #[inline]
    pub fn faces_of(&self, c: usize) -> &[u32] {
        &self.cell_faces[self.cell_face_offsets[c] as usize..self.cell_face_offsets[c + 1] as usize]
    }

    /// Cells using point `p`.
    #[inline]
    pub fn cells_of_point(&self, p: usize) -> &[u32] {
        &self.point_cells
            [self.point_cell_offsets[p] as usize..self.point_cell_offsets[p + 1] as usize]
    }

    /// Bounding box of the whole mesh (from the cells'), m.
    pub fn bounds(&self) -> [DVec3; 2] {
        self.cell_bounds.iter().fold(
            [DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)],
            |[lo, hi], [a, b]| [lo.min(*a), hi.max(*b)],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::{BoxMesh, CellShape};

    #[test]
    fn planar_quad_and_triangle() {
        let pts = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let (c, a) = face_centre_and_area(&pts, &[0, 1, 2, 3]);
        assert!((c - DVec3::new(1.0, 0.5, 0.0)).length() < 1e-15);
        assert!((a - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-15);
        // a trapezoid: the centroid is not the point average
        let pts = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
        ];
        let (c, a) = face_centre_and_area(&pts, &[0, 1, 2, 3]);
        // centroid of a trapezoid with parallel sides 3 (y=0) and 1 (y=1): y = (3+2·1)/(3(3+1))
        assert!(
            (c - DVec3::new(1.5, 5.0 / 12.0, 0.0)).length() < 1e-14,
            "{c}"
        );
        assert!((a.z - 2.0).abs() < 1e-14);
        let mut w = Vec::new();
        face_centre_weights(&pts, &[0, 1, 2, 3], &mut w);
        let cw: DVec3 = w.iter().zip(&pts).map(|(w, p)| *w * *p).sum();
        assert!((cw - c).length() < 1e-14);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn hex_box_volumes_and_centres() {
        let m = BoxMesh::new(DVec3::ZERO, DVec3::new(3.0, 2.0, 1.0), [3, 2, 2])
            .build()
            .unwrap();
        let g = MeshGeometry::new(&m).unwrap();
        for c in 0..m.n_cells {
            assert!((g.cell_volumes[c] - 0.5).abs() < 1e-14);
            let [lo, hi] = g.cell_bounds[c];
            assert!((g.cell_centres[c] - 0.5 * (lo + hi)).length() < 1e-14);
            assert!((hi - lo - DVec3::new(1.0, 1.0, 0.5)).length() < 1e-14);
        }
        // a corner point is in one cell, an interior point in 8
        let counts: Vec<usize> = (0..m.points.len())
            .map(|p| g.cells_of_point(p).len())
            .collect();
        assert_eq!(counts.iter().filter(|&&n| n == 1).count(), 8);
        assert_eq!(counts.iter().filter(|&&n| n == 8).count(), 2);
    }

    /// Perturbed hex, tet and polyhedral boxes: volumes add up to the box, every cell is
    /// closed (its outward area vectors sum to zero), and volumes are positive.
    #[test]
    fn perturbed_meshes_are_closed_and_fill_the_box() {
        for shape in [
            CellShape::Hex,
            CellShape::Tet,
            CellShape::Poly { refine: 0.3 },
        ] {
            let m = BoxMesh::new(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), [4, 5, 6])
                .shape(shape)
                .perturbed(0.25, 11)
                .build()
                .unwrap();
            let g = MeshGeometry::new(&m).unwrap();
            let total: f64 = g.cell_volumes.iter().sum();
            assert!((total - 6.0).abs() < 1e-12, "{shape:?}: {total}");
            assert!(g.cell_volumes.iter().all(|&v| v > 0.0));
            let mut closure = vec![DVec3::ZERO; m.n_cells];
            for f in 0..m.n_faces() {
                closure[m.owner[f] as usize] += g.face_areas[f];
                if let Some(&n) = m.neighbour.get(f) {
                    closure[n as usize] -= g.face_areas[f];
                }
            }
            let worst = closure.iter().map(|c| c.length()).fold(0.0, f64::max);
            assert!(worst < 1e-14, "{shape:?}: {worst}");
        }
    }
}
