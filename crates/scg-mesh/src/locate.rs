//! Point location on a [`PolyMesh`]: first location through a uniform grid of bins, then
//! tracking by walking across faces, as OpenFOAM's face-crossing tracking does.
//!
//! # The tetrahedral decomposition
//!
//! Every cell is split into tetrahedra (cell centre, and a triangle of one of its faces):
//! a triangular face is its own triangle; a face of more points is a fan of triangles
//! (face centre, two consecutive points), like OpenFOAM's face-centre tet decomposition.
//! Neighbouring cells share the triangles of their common face, so the tetrahedra of all
//! cells tile the domain without gaps or overlaps even when faces are not planar: a point
//! is **in a cell** when it is in one of the cell's tetrahedra (up to a relative tolerance
//! of 1e-9). Cells must be star-shaped about their centre (every tetrahedron positive),
//! which all usable CFD meshes are.
//!
//! # Probing a cell
//!
//! For a cell c with centre `cc` and a target x, the ray from `cc` toward x leaves c
//! through exactly one face triangle T: the one for which x − cc has non-negative
//! coordinates in the basis (T − cc). The same coordinates are the barycentric
//! coordinates of x in the tetrahedron (cc, T); their sum ≤ 1 means x is inside c (and
//! they are the interpolation weights), otherwise the walk steps across the face holding
//! T into the neighbour and probes again from the neighbour's centre.
//!
//! # Boundaries
//!
//! When the walk reaches a boundary face, x is looked up in the bin grid: if it is outside
//! the mesh the result is [`Location::Left`] with that face and its patch; if it is inside
//! (the straight walk left through a concave boundary, or across a thin wall) the result is
//! [`Location::Crossed`] with the face, its patch and the cell holding x. The caller decides
//! what a wall crossing means; in a convex domain with planar boundary faces a walk never
//! reaches the boundary while x is inside, so `Crossed` does not occur there.
//!
//! The walk is capped ([`Locator::max_steps`]); past the cap, when it steps back into the
//! cell it came from (a two-cell cycle), or when no face triangle takes the ray (a
//! degenerate cell), the grid decides.

use std::sync::Arc;

use glam::DVec3;

use crate::geometry::MeshGeometry;
use crate::shared::Shared;
use crate::{MeshError, PolyMesh};

/// Relative tolerance of the inside tests (barycentric coordinates may be this negative).
const TOL: f64 = 1e-9;

/// Where a point is: its cell, the tetrahedron of the cell's decomposition holding it, and
/// its barycentric coordinates there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The cell.
    pub cell: u32,
    /// The face whose triangle, with the cell centre, forms the tetrahedron.
    pub face: u32,
    /// The triangle's corners as node numbers: `< n_points` a mesh point, otherwise the
    /// centre of face `node − n_points`.
    pub nodes: [u32; 3],
    /// Barycentric coordinates of the point: on the cell centre, then on `nodes`.
    pub weights: [f64; 4],
}

/// The result of [`Locator::track`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Location {
    /// The point is inside the mesh, found without crossing the boundary.
    Inside(Hit),
    /// The point is outside the mesh; the walk left it through boundary face `face` of
    /// patch `patch`.
    Left {
        /// The boundary face.
        face: u32,
        /// Its patch (index into [`PolyMesh::patches`]).
        patch: u32,
    },
    /// The point is inside the mesh, but the walk toward it crossed boundary face `face` of
    /// patch `patch` (a concave boundary, or a thin wall).
    Crossed {
        /// The boundary face.
        face: u32,
        /// Its patch.
        patch: u32,
        /// Where the point is.
        hit: Hit,
    },
    /// The walk failed and the grid finds the point in no cell.
    Outside,
}

/// How a walk of [`Locator::track_walk`] went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Walk {
    /// Cells probed.
    pub cells: u32,
    /// Whether the grid had to decide (bad hint, step cap, cycle, degenerate cell).
    pub grid: bool,
}

/// What one probe of a cell finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Probe {
    /// The point is in the cell.
    Inside(Hit),
    /// The ray from the cell centre toward the point leaves the cell through `face`, before
    /// reaching the point; `hit` holds the tetrahedron it crosses and the point's
    /// barycentric coordinates there (the cell-centre one negative).
    Exit {
        /// The face.
        face: u32,
        /// The tetrahedron, with extrapolating coordinates.
        hit: Hit,
    },
    /// No face triangle takes the ray (a degenerate or non-star-shaped cell).
    Fail,
}

/// A uniform grid of bins over the mesh, each listing the cells whose bounding box
/// overlaps it.
#[derive(Clone, Debug)]
struct BinGrid {
    lo: DVec3,
    inv: DVec3,
    n: [u32; 3],
    offsets: Vec<u32>,
    cells: Vec<u32>,
}

impl BinGrid {
    fn new(geom: &MeshGeometry) -> Self {
        let nc = geom.cell_bounds.len().max(1);
        let [lo, hi] = geom.bounds();
        let ext = (hi - lo).max(DVec3::splat(1e-300));
        let (lo, ext) = if lo.is_finite() && hi.is_finite() {
            (lo - 1e-9 * ext, ext * (1.0 + 2e-9))
        } else {
            (DVec3::ZERO, DVec3::ONE)
        };
        // about one bin per cell
        let s = (ext.x * ext.y * ext.z / nc as f64).cbrt();
        let n = [0, 1, 2].map(|a| ((ext[a] / s).ceil() as u64).clamp(1, 1 << 20) as u32);
        let n = if n.iter().map(|&k| k as u64).product::<u64>() > 8 * nc as u64 {
            [1, 1, 1]
        } else {
            n
        };
        let inv = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64) / ext;
        let nb = (n[0] * n[1] * n[2]) as usize;
        let mut grid = BinGrid {
            lo,
            inv,
            n,
            offsets: vec![0; nb + 1],
            cells: Vec::new(),
        };
        for pass in 0..2 {
            let mut fill = grid.offsets.clone();
            for (c, b) in geom.cell_bounds.iter().enumerate() {
                let (a, z) = (grid.bin(b[0]), grid.bin(b[1]));
                for k in a[2]..=z[2] {
                    for j in a[1]..=z[1] {
                        for i in a[0]..=z[0] {
                            let idx = grid.index([i, j, k]);
                            if pass == 0 {
                                grid.offsets[idx + 1] += 1;
                            } else {
                                grid.cells[fill[idx] as usize] = c as u32;
                                fill[idx] += 1;
                            }
                        }
                    }
                }
            }
            if pass == 0 {
                for i in 0..nb {
                    grid.offsets[i + 1] += grid.offsets[i];
                }
                grid.cells = vec![0; grid.offsets[nb] as usize];
            }
        }
        grid
    }

    /// Bin coordinates of x, clamped to the grid.
    fn bin(&self, x: DVec3) -> [u32; 3] {
        let r = (x - self.lo) * self.inv;
        [0, 1, 2].map(|a| {
            let v = r[a];
            if v.is_nan() || v < 0.0 {
                0
            } else {
                (v as u64).min(self.n[a] as u64 - 1) as u32
            }
        })
    }

    fn index(&self, b: [u32; 3]) -> usize {
        (b[0] + self.n[0] * (b[1] + self.n[1] * b[2])) as usize
    }

    /// Cells that may hold x (none when x is off the grid).
    fn candidates(&self, x: DVec3) -> &[u32] {
        let r = (x - self.lo) * self.inv;
        let n = DVec3::new(self.n[0] as f64, self.n[1] as f64, self.n[2] as f64);
        if !(r.cmpge(DVec3::ZERO).all() && r.cmplt(n).all()) {
            return &[];
        }
        let i = self.index(self.bin(x));
        &self.cells[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// Point location on a mesh: [`Locator::find_cell`] and [`Locator::track`].
///
/// It borrows its mesh and geometry ([`Locator::new`]) or shares their ownership
/// ([`Locator::owned`], a `Locator<'static>` that frees them with its last `Arc`).
#[derive(Clone, Debug)]
pub struct Locator<'a> {
    mesh: Shared<'a, PolyMesh>,
    geom: Shared<'a, MeshGeometry>,
    grid: BinGrid,
    n_points: u32,
    /// Patch of every boundary face (index `f − n_internal_faces`).
    face_patch: Vec<u32>,
    /// Most cells a walk visits before the grid takes over.
    pub max_steps: u32,
}

impl<'a> Locator<'a> {
    /// A locator over `mesh` and its geometry (an error if `geom` is not `mesh`'s).
    pub fn new(mesh: &'a PolyMesh, geom: &'a MeshGeometry) -> Result<Self, MeshError> {
        Self::from_shared(Shared::Borrowed(mesh), Shared::Borrowed(geom))
    }

    fn from_shared(
        mesh: Shared<'a, PolyMesh>,
        geom: Shared<'a, MeshGeometry>,
    ) -> Result<Self, MeshError> {
        if geom.cell_centres.len() != mesh.n_cells
            || geom.face_centres.len() != mesh.n_faces()
            || geom.point_cell_offsets.len() != mesh.points.len() + 1
            || mesh.face_offsets.len() != mesh.n_faces() + 1
        {
            return Err(MeshError::invalid(
                "<mesh>",
                "geometry",
                "the geometry was derived from another mesh",
            ));
        }
        let ni = mesh.n_internal_faces();
        let mut face_patch = vec![u32::MAX; mesh.n_faces() - ni];
        for (i, p) in mesh.patches.iter().enumerate() {
            for f in p.start..(p.start + p.size).min(mesh.n_faces()) {
                if f >= ni {
                    face_patch[f - ni] = i as u32;
                }
            }
        }
        Ok(Locator {
            grid: BinGrid::new(&geom),
            n_points: mesh.points.len() as u32,
            mesh,
            geom,
            face_patch,
            max_steps: 256,
        })
    }

    /// The mesh.
    #[inline]
    pub fn mesh(&self) -> &PolyMesh {
        &self.mesh
    }

    /// The geometry.
    #[inline]
    pub fn geometry(&self) -> &MeshGeometry {
        &self.geom
    }

    /// The mesh's `Arc` when the locator owns it ([`Locator::owned`]).
    pub fn mesh_arc(&self) -> Option<&Arc<PolyMesh>> {
        self.mesh.arc()
    }

    /// The geometry's `Arc` when the locator owns it ([`Locator::owned`]).
    pub fn geometry_arc(&self) -> Option<&Arc<MeshGeometry>> {
        self.geom.arc()
    }

    /// Position of node `n` (a point, or a face centre past the points), m; NaN when out
    /// of range.
    #[inline]
    pub fn node(&self, n: u32) -> DVec3 {
        let p = if n < self.n_points {
            self.mesh.points.get(n as usize)
        } else {
            self.geom.face_centres.get((n - self.n_points) as usize)
        };
        p.copied().unwrap_or(DVec3::NAN)
    }

    /// Number of nodes (points, then face centres).
    pub fn n_nodes(&self) -> usize {
        self.mesh.points.len() + self.mesh.n_faces()
    }

    /// Patch of boundary face `f` (`u32::MAX` for an internal face).
    #[inline]
    pub fn patch_of(&self, f: u32) -> u32 {
        let ni = self.mesh.n_internal_faces() as u32;
        if f < ni {
            u32::MAX
        } else {
            self.face_patch[(f - ni) as usize]
        }
    }

    /// Probe cell `c` for x (see the module documentation).
    ///
    /// The face whose plane the ray from the centre meets first (largest
    /// `d·A_f / ((x_f − cc)·A_f)`, exact for convex cells with planar faces) is tried
    /// first; only if none of its triangles takes the ray are all faces scanned.
    pub fn probe(&self, c: u32, x: DVec3) -> Probe {
        let ci = c as usize;
        let Some(&cc) = self.geom.cell_centres.get(ci) else {
            return Probe::Fail;
        };
        let d = x - cc;
        let faces = self.geom.faces_of(ci);
        let (mut best, mut best_ratio) = (u32::MAX, f64::NEG_INFINITY);
        for &f in faces {
            let a = self.geom.face_areas[f as usize];
            let den = (self.geom.face_centres[f as usize] - cc).dot(a);
            // den ≠ 0 and of either sign: the ratio does not depend on the orientation
            let ratio = d.dot(a) / den;
            if ratio > best_ratio {
                best_ratio = ratio;
                best = f;
            }
        }
        if best != u32::MAX
            && let Some(p) = self.probe_face(c, cc, d, best)
        {
            return p;
        }
        for &f in faces {
            if f != best
                && let Some(p) = self.probe_face(c, cc, d, f)
            {
                return p;
            }
        }
        Probe::Fail
    }

    /// The triangles of face `f` of cell `c`: `Some` when one takes the ray from `cc`
    /// along `d`.
    #[inline]
    fn probe_face(&self, c: u32, cc: DVec3, d: DVec3, f: u32) -> Option<Probe> {
        let mesh: &PolyMesh = &self.mesh;
        let fi = f as usize;
        let pts = mesh.face(fi);
        let flip = mesh.owner[fi] != c;
        if pts.len() == 3 {
            let (a, b) = if flip {
                (pts[2], pts[1])
            } else {
                (pts[1], pts[2])
            };
            return self.tet(c, cc, d, f, [pts[0], a, b]);
        }
        let fc = self.geom.face_centres[fi];
        let v1 = fc - cc;
        let n = pts.len();
        let d2 = d.length_squared();
        let sign = if flip { -1.0 } else { 1.0 };
        // t_i = ±d · (v1 × (p_i − cc)): the side of the plane (cc, fc, p_i) x is on,
        // signed so that the ray crosses triangle (fc, p_i, p_i+1) out of c when
        // t_i ≥ 0 ≥ t_i+1 (up to the tolerance, without a square root)
        let side = |i: usize| {
            let p = mesh.points[pts[i] as usize] - cc;
            let cr = v1.cross(p);
            let t = sign * d.dot(cr);
            let slack = TOL * TOL * cr.length_squared() * d2;
            (t >= 0.0 || t * t <= slack, t <= 0.0 || t * t <= slack)
        };
        let first = side(0);
        let mut prev = first;
        for i in 0..n {
            let next = if i + 1 == n { first } else { side(i + 1) };
            if prev.0 && next.1 {
                let (pa, pb) = (pts[i], pts[(i + 1) % n]);
                let (a, b) = if flip { (pb, pa) } else { (pa, pb) };
                if let Some(p) = self.tet(c, cc, d, f, [self.n_points + f, a, b]) {
                    return Some(p);
                }
            }
            prev = next;
        }
        None
    }

    /// Coordinates of `d = x − cc` in the tetrahedron (cc, nodes); `Some` when the ray
    /// from cc crosses its outer triangle.
    #[inline]
    fn tet(&self, c: u32, cc: DVec3, d: DVec3, f: u32, nodes: [u32; 3]) -> Option<Probe> {
        let v1 = self.node(nodes[0]) - cc;
        let v2 = self.node(nodes[1]) - cc;
        let v3 = self.node(nodes[2]) - cc;
        let n23 = v2.cross(v3);
        let det = v1.dot(n23);
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let a = d.dot(n23) * inv;
        let b = d.dot(v3.cross(v1)) * inv;
        let g = d.dot(v1.cross(v2)) * inv;
        if a < -TOL || b < -TOL || g < -TOL {
            return None;
        }
        let s = a + b + g;
        let hit = Hit {
            cell: c,
            face: f,
            nodes,
            weights: [1.0 - s, a, b, g],
        };
        if s <= 1.0 + TOL {
            Some(Probe::Inside(hit))
        } else {
            Some(Probe::Exit { face: f, hit })
        }
    }

    /// The cell holding x, by the bin grid and the exact inside test; `None` outside the
    /// mesh.
    pub fn find(&self, x: DVec3) -> Option<Hit> {
        for &c in self.grid.candidates(x) {
            let [lo, hi] = self.geom.cell_bounds[c as usize];
            let pad = TOL * (hi - lo).max_element();
            if x.cmplt(lo - pad).any() || x.cmpgt(hi + pad).any() {
                continue;
            }
            if let Probe::Inside(h) = self.probe(c, x) {
                return Some(h);
            }
        }
        None
    }

    /// The cell holding x (see [`Locator::find`]).
    pub fn find_cell(&self, x: DVec3) -> Option<u32> {
        self.find(x).map(|h| h.cell)
    }

    /// Walk from cell `hint` (the particle's last cell) to x.
    pub fn track(&self, hint: u32, x: DVec3) -> Location {
        self.track_walk(hint, x).0
    }

    /// [`Locator::track`], also telling how the walk went.
    pub fn track_walk(&self, hint: u32, x: DVec3) -> (Location, Walk) {
        let mut walk = Walk {
            cells: 0,
            grid: true,
        };
        let grid = |walk: Walk| match self.find(x) {
            Some(h) => (Location::Inside(h), walk),
            None => (Location::Outside, walk),
        };
        if hint as usize >= self.mesh.n_cells || !x.is_finite() {
            return grid(walk);
        }
        let ni = self.mesh.n_internal_faces() as u32;
        let mut c = hint;
        let mut from = u32::MAX;
        for _ in 0..self.max_steps {
            walk.cells += 1;
            match self.probe(c, x) {
                Probe::Inside(h) => {
                    walk.grid = false;
                    return (Location::Inside(h), walk);
                }
                Probe::Exit { face, .. } => {
                    if face < ni {
                        let (o, n) = (
                            self.mesh.owner[face as usize],
                            self.mesh.neighbour[face as usize],
                        );
                        let next = if o == c { n } else { o };
                        if next == from {
                            // back where it came from: a two-cell cycle
                            break;
                        }
                        from = c;
                        c = next;
                    } else {
                        let patch = self.patch_of(face);
                        walk.grid = false;
                        return match self.find(x) {
                            None => (Location::Left { face, patch }, walk),
                            Some(hit) => (Location::Crossed { face, patch, hit }, walk),
                        };
                    }
                }
                Probe::Fail => break,
            }
        }
        grid(walk)
    }

    /// Ask the processor to start loading what [`Locator::track_from`] reads first for
    /// `hit` (its cell centre and the positions of its nodes). Calling it a few particles
    /// ahead hides memory latency when particles are sparse in a large mesh. No effect on
    /// results; a no-op off x86-64.
    #[inline]
    pub fn prefetch(&self, hit: &Hit) {
        crate::prefetch::element(&self.geom.cell_centres, hit.cell as usize);
        for &n in &hit.nodes {
            if n < self.n_points {
                crate::prefetch::element(&self.mesh.points, n as usize);
            } else {
                crate::prefetch::element(&self.geom.face_centres, (n - self.n_points) as usize);
            }
        }
    }

    /// Like [`Locator::track`] from a previous [`Hit`], trying its tetrahedron first (a
    /// particle moving a fraction of a cell per step usually stays in it).
    #[inline]
    pub fn track_from(&self, prev: &Hit, x: DVec3) -> Location {
        if let Some(c) = self.geom.cell_centres.get(prev.cell as usize) {
            let cc = *c;
            let d = x - cc;
            if let Some(Probe::Inside(h)) = self.tet(prev.cell, cc, d, prev.face, prev.nodes) {
                return Location::Inside(h);
            }
        }
        self.track(prev.cell, x)
    }
}

impl Locator<'static> {
    /// A locator sharing the ownership of `mesh` and `geom` (an error if `geom` is not
    /// `mesh`'s): nothing is borrowed, and both are freed with their last `Arc`.
    pub fn owned(mesh: Arc<PolyMesh>, geom: Arc<MeshGeometry>) -> Result<Self, MeshError> {
        Self::from_shared(Shared::Owned(mesh), Shared::Owned(geom))
    }
}

#[cfg(test)]
mod tests;
