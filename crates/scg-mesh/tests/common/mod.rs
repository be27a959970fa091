//! Small mesh generators and independent mesh checks shared by the integration tests.
#![allow(dead_code)]

use std::collections::BTreeMap;

use glam::DVec3;
use scg_mesh::vtk::{assemble, cell_faces};
use scg_mesh::{CellField, Patch, PolyMesh};

/// A box of `n` cells from `lo` to `hi`, m: its points (x fastest) and, per hexahedron, its
/// 8 point indices in VTK order (bottom 0 1 2 3 counter-clockwise seen from +z, then top).
pub struct BoxGrid {
    pub points: Vec<DVec3>,
    pub hexes: Vec<[u32; 8]>,
    pub n: [usize; 3],
    pub lo: DVec3,
    pub hi: DVec3,
}

pub fn box_grid(n: [usize; 3], lo: DVec3, hi: DVec3) -> BoxGrid {
    let id = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
    let mut points = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let t = DVec3::new(
                    i as f64 / n[0] as f64,
                    j as f64 / n[1] as f64,
                    k as f64 / n[2] as f64,
                );
                points.push(lo + (hi - lo) * t);
            }
        }
    }
    let mut hexes = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                hexes.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
            }
        }
    }
    BoxGrid {
        points,
        hexes,
        n,
        lo,
        hi,
    }
}

impl BoxGrid {
    pub fn n_hex(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// Internal faces of the hexahedral grid: (nx−1)·ny·nz + nx·(ny−1)·nz + nx·ny·(nz−1).
    pub fn n_internal_quads(&self) -> usize {
        let [a, b, c] = self.n;
        (a - 1) * b * c + a * (b - 1) * c + a * b * (c - 1)
    }

    /// Boundary faces of the hexahedral grid: 2·(nx·ny + ny·nz + nx·nz).
    pub fn n_boundary_quads(&self) -> usize {
        let [a, b, c] = self.n;
        2 * (a * b + b * c + a * c)
    }

    /// Every hexahedron split into 6 tetrahedra around its diagonal 0–6 (Kuhn's
    /// decomposition: the same diagonal direction in every cell, so the triangles of
    /// neighbouring cells match).
    pub fn tets(&self) -> Vec<[u32; 4]> {
        // Hex corners by (x, y, z) bits → VTK hex index.
        let corner = |x: usize, y: usize, z: usize| [[[0, 4], [3, 7]], [[1, 5], [2, 6]]][x][y][z];
        let mut out = Vec::new();
        for h in &self.hexes {
            for perm in [
                [0, 1, 2],
                [0, 2, 1],
                [1, 0, 2],
                [1, 2, 0],
                [2, 0, 1],
                [2, 1, 0],
            ] {
                let mut b = [0usize; 3];
                let mut tet = [h[corner(0, 0, 0)]; 4];
                for (s, &axis) in perm.iter().enumerate() {
                    b[axis] = 1;
                    tet[s + 1] = h[corner(b[0], b[1], b[2])];
                }
                out.push(tet);
            }
        }
        out
    }

    /// Centre of hexahedron `c`, m (from the grid indices, not the points).
    pub fn hex_centre(&self, c: usize) -> DVec3 {
        let [a, b, _] = self.n;
        let (i, j, k) = (c % a, (c / a) % b, c / (a * b));
        let t = DVec3::new(
            (i as f64 + 0.5) / self.n[0] as f64,
            (j as f64 + 0.5) / self.n[1] as f64,
            (k as f64 + 0.5) / self.n[2] as f64,
        );
        self.lo + (self.hi - self.lo) * t
    }

    /// The hexahedral mesh, boundary split into patches by side: `walls` (type wall) on
    /// x and y sides, `bottom` (z = lo) and `top` (z = hi), type patch.
    pub fn hex_mesh(&self) -> PolyMesh {
        let cells = self
            .hexes
            .iter()
            .map(|h| cell_faces(12, h).unwrap())
            .collect();
        split_patches(
            assemble(self.points.clone(), cells).unwrap(),
            self.lo,
            self.hi,
        )
    }

    /// The tetrahedral mesh (6 tets per hexahedron), patches as [`BoxGrid::hex_mesh`].
    pub fn tet_mesh(&self) -> PolyMesh {
        let cells = self
            .tets()
            .iter()
            .map(|t| cell_faces(10, t).unwrap())
            .collect();
        split_patches(
            assemble(self.points.clone(), cells).unwrap(),
            self.lo,
            self.hi,
        )
    }
}

/// Regroup the single `boundary` patch of an assembled box mesh into `walls`, `bottom`, `top`.
fn split_patches(mut m: PolyMesh, lo: DVec3, hi: DVec3) -> PolyMesh {
    let ni = m.n_internal_faces();
    let mut groups: [Vec<usize>; 3] = Default::default();
    for f in ni..m.n_faces() {
        let c = m
            .face(f)
            .iter()
            .map(|&p| m.points[p as usize])
            .sum::<DVec3>()
            / m.face(f).len() as f64;
        let g = if (c.z - lo.z).abs() < 1e-12 {
            1
        } else if (c.z - hi.z).abs() < 1e-12 {
            2
        } else {
            0
        };
        groups[g].push(f);
    }
    let old = m.clone();
    m.face_offsets.truncate(ni + 1);
    m.face_points.truncate(old.face_offsets[ni] as usize);
    m.owner.truncate(ni);
    m.patches.clear();
    for (g, (name, kind)) in [("walls", "wall"), ("bottom", "patch"), ("top", "patch")]
        .into_iter()
        .enumerate()
    {
        m.patches.push(Patch {
            name: name.into(),
            kind: kind.into(),
            start: m.owner.len(),
            size: groups[g].len(),
        });
        for &f in &groups[g] {
            m.face_points.extend_from_slice(old.face(f));
            m.face_offsets.push(m.face_points.len() as u32);
            m.owner.push(old.owner[f]);
        }
    }
    m
}

/// An affine velocity, m/s: U = (1 + 2y, −3x + z, 0.5 + x − y) (x in m).
pub fn affine_u(x: DVec3) -> DVec3 {
    DVec3::new(1.0 + 2.0 * x.y, -3.0 * x.x + x.z, 0.5 + x.x - x.y)
}

/// Cell centres as the mean of each cell's distinct points, m.
pub fn point_mean_centres(m: &PolyMesh) -> Vec<DVec3> {
    let mut pts: Vec<Vec<u32>> = vec![Vec::new(); m.n_cells];
    for f in 0..m.n_faces() {
        pts[m.owner[f] as usize].extend_from_slice(m.face(f));
        if f < m.n_internal_faces() {
            pts[m.neighbour[f] as usize].extend_from_slice(m.face(f));
        }
    }
    pts.into_iter()
        .map(|mut p| {
            p.sort_unstable();
            p.dedup();
            p.iter().map(|&i| m.points[i as usize]).sum::<DVec3>() / p.len() as f64
        })
        .collect()
}

/// A field: the affine velocity at the point-mean cell centres, and at the face centres of
/// every patch but the last, which gets no value.
pub fn affine_field(m: &PolyMesh) -> CellField {
    let cells = point_mean_centres(m).into_iter().map(affine_u).collect();
    let mut patches: Vec<Option<Vec<DVec3>>> = m
        .patches
        .iter()
        .map(|p| {
            Some(
                (p.start..p.start + p.size)
                    .map(|f| {
                        let c = m
                            .face(f)
                            .iter()
                            .map(|&i| m.points[i as usize])
                            .sum::<DVec3>()
                            / m.face(f).len() as f64;
                        affine_u(c)
                    })
                    .collect(),
            )
        })
        .collect();
    if let Some(last) = patches.last_mut() {
        *last = None;
    }
    CellField { cells, patches }
}

/// Area vector (½ Σ (pᵢ − c) × (pᵢ₊₁ − c)) and point-mean centre of face `f`, computed here
/// independently of the crate.
pub fn face_geometry(m: &PolyMesh, f: usize) -> (DVec3, DVec3) {
    let pts: Vec<DVec3> = m.face(f).iter().map(|&i| m.points[i as usize]).collect();
    let c = pts.iter().sum::<DVec3>() / pts.len() as f64;
    let a = (0..pts.len())
        .map(|k| (pts[k] - c).cross(pts[(k + 1) % pts.len()] - c))
        .sum::<DVec3>()
        * 0.5;
    (a, c)
}

/// Check outward orientation: for every cell the outward area vectors sum to ~0 (closed
/// cell, relative to the cell's total face area, 1e-12) and each outward normal points away
/// from the cell's point-mean centre. Returns the largest relative closure error and the
/// smallest normalised dot product n̂ · (face centre − cell centre) / |face centre − cell centre|.
pub fn check_orientation(m: &PolyMesh) -> (f64, f64) {
    let centres = point_mean_centres(m);
    let mut sum = vec![DVec3::ZERO; m.n_cells];
    let mut total = vec![0.0; m.n_cells];
    let mut min_dot = f64::INFINITY;
    for f in 0..m.n_faces() {
        let (a, c) = face_geometry(m, f);
        let mut sides = vec![(m.owner[f] as usize, a)];
        if f < m.n_internal_faces() {
            sides.push((m.neighbour[f] as usize, -a));
        }
        for (cell, a) in sides {
            sum[cell] += a;
            total[cell] += a.length();
            let d = c - centres[cell];
            min_dot = min_dot.min(a.normalize().dot(d.normalize()));
        }
    }
    let closure = sum
        .iter()
        .zip(&total)
        .map(|(s, t)| s.length() / t)
        .fold(0.0, f64::max);
    (closure, min_dot)
}

/// The mesh as a set of faces independent of face and point numbering: for every face, its
/// points' coordinates (bit patterns, sorted) → (owner, neighbour or patch name), cells named
/// by their point-mean centres.
pub fn canonical(m: &PolyMesh) -> BTreeMap<Vec<[u64; 3]>, (String, String)> {
    let centres = point_mean_centres(m);
    let key = |p: DVec3| p.to_array().map(|x| x.to_bits());
    let name = |c: DVec3| format!("{:.9} {:.9} {:.9}", c.x, c.y, c.z);
    let mut out = BTreeMap::new();
    for f in 0..m.n_faces() {
        let mut k: Vec<[u64; 3]> = m
            .face(f)
            .iter()
            .map(|&i| key(m.points[i as usize]))
            .collect();
        k.sort_unstable();
        let owner = name(centres[m.owner[f] as usize]);
        let other = if f < m.n_internal_faces() {
            name(centres[m.neighbour[f] as usize])
        } else {
            m.patches[m.patch_of_face(f).unwrap()].name.clone()
        };
        out.insert(k, (owner, other));
    }
    out
}
