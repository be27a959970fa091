//! Triangle-mesh walls (pure geometry): closest points on triangles, the mesh's topology
//! (shared edges and vertices, coplanar regions, feature edges), a triangle bin grid, and
//! the contacts of a sphere with the mesh, one per touched surface feature.
//!
//! * Closest point on a triangle and the feature it lies on: Ericson, *Real-Time Collision
//!   Detection* (2005), §5.1.5, with Ericson's region tests.
//! * One contact per touched feature, in the spirit of LIGGGHTS `fix mesh/surface`: a
//!   sphere touching a shared edge or vertex of several triangles feels one contact, not
//!   one per triangle (see [`TriMesh::contacts`]).
//!
//! All lengths in metres. The mesh is two-sided: the contact normal points from the
//! closest point on the surface toward the sphere centre, whichever side the centre is on.

use std::collections::HashMap;

use glam::DVec3;

/// Where on a triangle a closest point lies. Local indices: vertex `k` is the triangle's
/// `k`-th corner, edge `k` joins corners `k` and `(k + 1) % 3`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// The open face.
    Face,
    /// An edge (local index 0..3).
    Edge(u8),
    /// A corner (local index 0..3).
    Vertex(u8),
}

/// Closest point to `p` on the triangle `(a, b, c)` and the feature it lies on (Ericson
/// 2005, §5.1.5 `ClosestPtPointTriangle`). Points on the boundary between two regions are
/// given to the lower-dimensional feature (edge before face, vertex before edge).
#[inline]
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, Feature) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, Feature::Edge(0));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, Feature::Face)
}

/// Why a set of triangles is not a usable mesh.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{message}", triangle.map(|t| format!("triangle {t}: ")).unwrap_or_default())]
pub struct TriMeshError {
    /// The offending triangle (0-based, in file order), when one is to blame.
    pub triangle: Option<usize>,
    /// What is wrong.
    pub message: String,
}

/// Two unit normals belong to one flat region when their cosine is at least this
/// (an angle below ≈ 1.4·10⁻⁵ rad).
const COPLANAR_COS: f64 = 1.0 - 1e-10;

/// Merge coincident corners of a triangle soup: corners with bit-identical coordinates
/// (after −0 → +0) become one vertex, which recovers the shared-edge topology that STL
/// files (one facet at a time) do not store. Returns the vertices (first-seen order) and
/// the triangles as vertex indices.
pub fn weld(soup: &[[DVec3; 3]]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(soup.len());
    let mut vertices = Vec::new();
    let triangles = soup
        .iter()
        .map(|tri| {
            tri.map(|v| {
                // +0.0 turns −0 into +0 so that the two weld.
                let key = [
                    (v.x + 0.0).to_bits(),
                    (v.y + 0.0).to_bits(),
                    (v.z + 0.0).to_bits(),
                ];
                *index.entry(key).or_insert_with(|| {
                    vertices.push(v);
                    (vertices.len() - 1) as u32
                })
            })
        })
        .collect();
    (vertices, triangles)
}

/// Compressed lists: the items of key `k` are `items[start[k]..start[k + 1]]`.
#[derive(Clone, Debug, Default, PartialEq)]
struct Csr {
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Csr {
    /// Build from (key, item) pairs, keys in `0..keys`, items kept in pair order per key.
    fn build(keys: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Csr {
        let mut start = vec![0u32; keys + 1];
        for (k, _) in pairs.clone() {
            start[k as usize + 1] += 1;
        }
        for k in 0..keys {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[keys] as usize];
        for (k, it) in pairs {
            items[fill[k as usize] as usize] = it;
            fill[k as usize] += 1;
        }
        Csr { start, items }
    }

    #[inline]
    fn get(&self, k: usize) -> &[u32] {
        &self.items[self.start[k] as usize..self.start[k + 1] as usize]
    }
}

/// A uniform grid over the mesh bounds; each cell lists the triangles that may pass
/// through it, and how far (in cells) it is from the nearest non-empty cell.
#[derive(Clone, Debug, PartialEq)]
struct BinGrid {
    /// Lower corner, m.
    origin: DVec3,
    /// Cell edge, m, and its inverse, 1/m.
    h: f64,
    inv_h: f64,
    /// Cells per axis (also as floats).
    dims: [usize; 3],
    dims_f: DVec3,
    /// Triangles per cell.
    cells: Csr,
    /// Chebyshev distance in cells to the nearest non-empty cell (0 = non-empty),
    /// saturated at `u16::MAX`.
    reach: Vec<u16>,
    /// A lower bound of the distance from each cell's centre to the mesh, m (exact, then
    /// rounded down to f32, within [`NEAR`] cells of a triangle's box; `NEAR`·h beyond).
    centre_clear: Vec<f32>,
    /// Coarse cells of `COARSE`³ cells (a few kilobytes, so that the clearance test of a
    /// particle far from the mesh touches little memory): cells per axis, and a lower
    /// bound of the distance from each coarse centre to the mesh, m.
    coarse_dims: [usize; 3],
    coarse_clear: Vec<f32>,
}

/// Cells per coarse cell and axis.
const COARSE: usize = 4;

/// `d` rounded down to f32, less a relative 1e-9 for the rounding of distances.
fn down(d: f64) -> f32 {
    let d = d * (1.0 - 1e-9);
    let f = d as f32;
    if f as f64 > d { f.next_down() } else { f }
}

/// Cells around each triangle's box where the centre distance is computed exactly.
const NEAR: usize = 2;

/// Most cells a grid may have.
const MAX_CELLS: usize = 1 << 22;

impl BinGrid {
    fn build(vertices: &[DVec3], triangles: &[[u32; 3]]) -> BinGrid {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for v in vertices {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        let ext = hi - lo;
        let emax = ext.max_element().max(f64::MIN_POSITIVE);
        // Cells about half the median edge length, between 1/512 and 1/8 of the largest
        // extent, and never more than MAX_CELLS.
        let mut lengths: Vec<f64> = triangles
            .iter()
            .flat_map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                [(b - a).length(), (c - b).length(), (a - c).length()]
            })
            .collect();
        let mid = lengths.len() / 2;
        let median_edge = *lengths.select_nth_unstable_by(mid, f64::total_cmp).1;
        let mut h = (0.5 * median_edge).clamp(emax / 512.0, emax / 8.0);
        // Pad by a cell's hundredth so that points on the bounds fall inside.
        let (origin, dims) = loop {
            let pad = DVec3::splat(0.01 * h);
            let origin = lo - pad;
            let span = ext + 2.0 * pad;
            let dims = [0, 1, 2].map(|k| ((span[k] / h).ceil() as usize).max(1));
            let cells = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
            if cells.is_some_and(|c| c <= MAX_CELLS) || !h.is_finite() {
                break (origin, dims);
            }
            h *= 1.25;
        };
        let ncell = dims[0] * dims[1] * dims[2];
        let index = |i: usize, j: usize, k: usize| (k * dims[1] + j) * dims[0] + i;
        let cell_of = |x: f64, k: usize| -> usize {
            (((x - origin[k]) / h).floor().max(0.0) as usize).min(dims[k] - 1)
        };
        // A triangle goes into every cell of its box whose centre lies within half a cell
        // diagonal of it (so every cell the triangle passes through, and few others).
        let half_diag = 0.5 * 3f64.sqrt() * h * (1.0 + 1e-9);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            let (tlo, thi) = (a.min(b).min(c), a.max(b).max(c));
            let l = [0, 1, 2].map(|k| cell_of(tlo[k], k));
            let u = [0, 1, 2].map(|k| cell_of(thi[k], k));
            for k in l[2]..=u[2] {
                for j in l[1]..=u[1] {
                    for i in l[0]..=u[0] {
                        let centre =
                            origin + h * DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                        let (q, _) = closest_point_on_triangle(centre, a, b, c);
                        if (q - centre).length() <= half_diag {
                            pairs.push((index(i, j, k) as u32, t as u32));
                        }
                    }
                }
            }
        }
        let cells = Csr::build(ncell, pairs.iter().copied());
        // Multi-source breadth-first search over the 26 neighbours: Chebyshev distance.
        let mut reach = vec![u16::MAX; ncell];
        let mut front: Vec<usize> = (0..ncell).filter(|&c| !cells.get(c).is_empty()).collect();
        for &c in &front {
            reach[c] = 0;
        }
        let mut level = 0u16;
        while !front.is_empty() && level < u16::MAX - 1 {
            level += 1;
            let mut next = Vec::new();
            for &c in &front {
                let (i, j, k) = (
                    c % dims[0],
                    (c / dims[0]) % dims[1],
                    c / (dims[0] * dims[1]),
                );
                for dk in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let (ni, nj, nk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                            if ni < 0
                                || nj < 0
                                || nk < 0
                                || ni >= dims[0] as i64
                                || nj >= dims[1] as i64
                                || nk >= dims[2] as i64
                            {
                                continue;
                            }
                            let n = index(ni as usize, nj as usize, nk as usize);
                            if reach[n] == u16::MAX {
                                reach[n] = level;
                                next.push(n);
                            }
                        }
                    }
                }
            }
            front = next;
        }
        // Centre distances near the triangles: each triangle updates the cells of its box
        // widened by NEAR cells. A cell no triangle's widened box reaches is at least
        // NEAR·h from every triangle, as is its centre.
        let near = NEAR as f64 * h;
        let mut centre = vec![near; ncell];
        for tri in triangles {
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            let (tlo, thi) = (a.min(b).min(c), a.max(b).max(c));
            let l = [0, 1, 2].map(|k| cell_of(tlo[k], k).saturating_sub(NEAR));
            let u = [0, 1, 2].map(|k| (cell_of(thi[k], k) + NEAR).min(dims[k] - 1));
            for k in l[2]..=u[2] {
                for j in l[1]..=u[1] {
                    for i in l[0]..=u[0] {
                        let ctr =
                            origin + h * DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                        let d = (closest_point_on_triangle(ctr, a, b, c).0 - ctr).length();
                        let slot = &mut centre[index(i, j, k)];
                        *slot = slot.min(d);
                    }
                }
            }
        }
        // Each fine centre's bound also holds from the reach: every point of the cell is at
        // least (reach − 1)·h from the mesh.
        for (c, d) in centre.iter_mut().enumerate() {
            *d = d.max((f64::from(reach[c]) - 1.0) * h);
        }
        // A coarse centre C: d(C) ≥ d(c) − |C − c| for the fine centres c around it
        // (the distance to the mesh is 1-Lipschitz).
        let coarse_dims = dims.map(|d| d.div_ceil(COARSE));
        let hc = COARSE as f64 * h;
        let mut coarse_clear = Vec::with_capacity(coarse_dims.iter().product());
        for k in 0..coarse_dims[2] {
            for j in 0..coarse_dims[1] {
                for i in 0..coarse_dims[0] {
                    let cc =
                        origin + hc * DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                    let around = |m: usize, n: usize| {
                        let f = (cc[n] - origin[n]) / h - 0.5;
                        let a = (f.floor().max(0.0) as usize).min(dims[n] - 1);
                        let _ = m;
                        a..=(a + 1).min(dims[n] - 1)
                    };
                    let mut best = 0.0_f64;
                    for fk in around(k, 2) {
                        for fj in around(j, 1) {
                            for fi in around(i, 0) {
                                let fc = origin
                                    + h * DVec3::new(
                                        fi as f64 + 0.5,
                                        fj as f64 + 0.5,
                                        fk as f64 + 0.5,
                                    );
                                best = best.max(centre[index(fi, fj, fk)] - (cc - fc).length());
                            }
                        }
                    }
                    coarse_clear.push(down(best));
                }
            }
        }
        let centre_clear = centre.into_iter().map(down).collect();
        BinGrid {
            inv_h: 1.0 / h,
            dims_f: DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64),
            coarse_dims,
            coarse_clear,
            origin,
            h,
            dims,
            cells,
            reach,
            centre_clear,
        }
    }

    /// The grid's upper corner, m.
    fn upper(&self) -> DVec3 {
        self.origin
            + self.h
                * DVec3::new(
                    self.dims[0] as f64,
                    self.dims[1] as f64,
                    self.dims[2] as f64,
                )
    }

    /// Cell index range (inclusive) covering `[lo, hi]`, clamped; `None` when the box
    /// misses the grid.
    #[inline]
    fn range(&self, lo: DVec3, hi: DVec3) -> Option<([usize; 3], [usize; 3])> {
        let up = self.upper();
        if lo.cmpgt(up).any() || hi.cmplt(self.origin).any() {
            return None;
        }
        let c = |x: f64, k: usize| -> usize {
            // `as usize` truncates toward zero and saturates negatives (and NaN) to 0: the
            // floor for the non-negative values that matter, without a libm call.
            (((x - self.origin[k]) / self.h) as usize).min(self.dims[k] - 1)
        };
        Some((
            [c(lo.x, 0), c(lo.y, 1), c(lo.z, 2)],
            [c(hi.x, 0), c(hi.y, 1), c(hi.z, 2)],
        ))
    }
}

/// A rigid triangle mesh ready for contact queries.
#[derive(Clone, Debug, PartialEq)]
pub struct TriMesh {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Unit normals (right-hand rule over the corners' order).
    normals: Vec<DVec3>,
    /// Edge ids of each triangle's local edges 0, 1, 2.
    tri_edges: Vec<[u32; 3]>,
    /// Edges as (lower, higher) vertex index.
    edges: Vec<[u32; 2]>,
    /// Triangles of each edge.
    edge_tris: Csr,
    /// Triangles of each vertex.
    vertex_tris: Csr,
    /// Flat region of each triangle.
    region: Vec<u32>,
    regions: u32,
    closed: bool,
    grid: BinGrid,
}

/// A sphere's contact with a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshContact {
    /// Overlap δ = r − distance > 0, m.
    pub overlap: f64,
    /// Unit normal from the closest point toward the sphere centre.
    pub normal: DVec3,
    /// Closest point on the mesh, m.
    pub point: DVec3,
    /// Flat region (connected coplanar triangles) of the triangle giving the contact.
    pub region: u32,
    /// Triangle giving the contact.
    pub triangle: u32,
    /// Feature of that triangle the closest point lies on.
    pub feature: Feature,
}

/// Reusable buffers of [`TriMesh::contacts`] (one per thread).
#[derive(Clone, Debug, Default)]
pub struct MeshScratch {
    tris: Vec<u32>,
    hits: Vec<Hit>,
}

#[derive(Clone, Copy, Debug)]
struct Hit {
    tri: u32,
    point: DVec3,
    feature: Feature,
    dist2: f64,
}

impl TriMesh {
    /// A mesh from vertices (m) and triangles (vertex indices). Rejects an empty mesh,
    /// non-finite coordinates, indices out of range and degenerate (zero-area) triangles,
    /// naming the triangle. Computes the topology, the flat regions and the bin grid.
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<TriMesh, TriMeshError> {
        let err = |t: Option<usize>, m: String| TriMeshError {
            triangle: t,
            message: m,
        };
        if triangles.is_empty() {
            return Err(err(None, "the mesh has no triangles".into()));
        }
        let mut normals = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            if tri.iter().any(|&i| i as usize >= vertices.len()) {
                return Err(err(Some(t), "vertex index out of range".into()));
            }
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                return Err(err(
                    Some(t),
                    format!("non-finite corner {:?}", [a, b, c].map(|v| v.to_array())),
                ));
            }
            let cross = (b - a).cross(c - a);
            let longest = (b - a)
                .length_squared()
                .max((c - b).length_squared())
                .max((a - c).length_squared());
            // Zero area, or so thin that its normal is rounding noise.
            if tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[2] == tri[0]
                || cross.length() <= 1e-12 * longest
            {
                return Err(err(Some(t), "degenerate triangle (zero area)".into()));
            }
            normals.push(cross.normalize());
        }
        // Edges: (lower, higher) vertex pair → id.
        let mut edge_id: HashMap<[u32; 2], u32> = HashMap::with_capacity(3 * triangles.len() / 2);
        let mut edges = Vec::new();
        let tri_edges: Vec<[u32; 3]> = triangles
            .iter()
            .map(|tri| {
                [0, 1, 2].map(|k| {
                    let (p, q) = (tri[k], tri[(k + 1) % 3]);
                    let key = [p.min(q), p.max(q)];
                    *edge_id.entry(key).or_insert_with(|| {
                        edges.push(key);
                        (edges.len() - 1) as u32
                    })
                })
            })
            .collect();
        let edge_tris = Csr::build(
            edges.len(),
            tri_edges
                .iter()
                .enumerate()
                .flat_map(|(t, es)| es.iter().map(move |&e| (e, t as u32))),
        );
        let vertex_tris = Csr::build(
            vertices.len(),
            triangles
                .iter()
                .enumerate()
                .flat_map(|(t, vs)| vs.iter().map(move |&v| (v, t as u32))),
        );
        let closed = (0..edges.len()).all(|e| edge_tris.get(e).len() == 2);
        let mut mesh = TriMesh {
            grid: BinGrid::build(&vertices, &triangles),
            vertices,
            triangles,
            normals,
            tri_edges,
            edges,
            edge_tris,
            vertex_tris,
            region: Vec::new(),
            regions: 0,
            closed,
        };
        mesh.find_regions();
        Ok(mesh)
    }

    /// True when triangles `s` and `t`, which share edge `e`, continue one flat surface:
    /// parallel normals (up to orientation) and on opposite sides of the edge.
    fn flat_across(&self, e: usize, s: usize, t: usize) -> bool {
        let (ns, nt) = (self.normals[s], self.normals[t]);
        if ns.dot(nt).abs() < COPLANAR_COS {
            return false;
        }
        let [p, q] = self.edges[e].map(|i| self.vertices[i as usize]);
        let opposite = |tri: usize| {
            let v = self.triangles[tri]
                .into_iter()
                .find(|&v| !self.edges[e].contains(&v))
                .expect("a triangle has a corner off each of its edges");
            self.vertices[v as usize]
        };
        let dir = q - p;
        let side = |x: DVec3| (x - p).cross(dir).dot(ns);
        side(opposite(s)) * side(opposite(t)) < 0.0
    }

    /// Label connected flat regions (union–find over edges shared by exactly two
    /// triangles that continue one flat surface).
    fn find_regions(&mut self) {
        let n = self.triangles.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(p: &mut [u32], mut i: u32) -> u32 {
            while p[i as usize] != i {
                p[i as usize] = p[p[i as usize] as usize];
                i = p[i as usize];
            }
            i
        }
        for e in 0..self.edges.len() {
            if let &[s, t] = self.edge_tris.get(e)
                && self.flat_across(e, s as usize, t as usize)
            {
                let (a, b) = (root(&mut parent, s), root(&mut parent, t));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let mut label = vec![u32::MAX; n];
        let mut region = Vec::with_capacity(n);
        let mut next = 0;
        for t in 0..n as u32 {
            let r = root(&mut parent, t) as usize;
            if label[r] == u32::MAX {
                label[r] = next;
                next += 1;
            }
            region.push(label[r]);
        }
        self.region = region;
        self.regions = next;
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
    /// Number of (merged) vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }
    /// Number of distinct edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }
    /// Number of flat regions (connected sets of coplanar triangles).
    pub fn region_count(&self) -> u32 {
        self.regions
    }
    /// Flat region of each triangle.
    pub fn regions(&self) -> &[u32] {
        &self.region
    }
    /// True when every edge is shared by exactly two triangles (a closed surface).
    pub fn is_closed(&self) -> bool {
        self.closed
    }
    /// The vertices, m.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }
    /// The triangles (vertex indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// Axis-aligned bounds (lower, upper corner), m.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        )
    }
    /// Bin-grid cell edge, m, and cells per axis.
    pub fn grid_shape(&self) -> (f64, [usize; 3]) {
        (self.grid.h, self.grid.dims)
    }

    /// Feature edges as vertex pairs: boundary edges (one triangle), non-manifold edges
    /// (more than two) and edges between triangles that do not continue one flat surface.
    pub fn feature_edges(&self) -> Vec<[u32; 2]> {
        (0..self.edges.len())
            .filter(|&e| match *self.edge_tris.get(e) {
                [s, t] => !self.flat_across(e, s as usize, t as usize),
                _ => true,
            })
            .map(|e| self.edges[e])
            .collect()
    }

    /// True when a sphere of radius `radius` (m) centred at `x` is certainly clear of the
    /// mesh: `x` is at least `radius` from the grid's box, or its cell is at least
    /// `radius` from every cell holding a triangle, or (the distance being 1-Lipschitz)
    /// |x − c| ≤ d_c − radius with d_c the stored lower bound of the distance from its
    /// cell's centre c to the mesh. No square root.
    #[inline]
    pub fn surely_clear(&self, x: DVec3, radius: f64) -> bool {
        let g = &self.grid;
        let rel = (x - g.origin) * g.inv_h;
        if rel.cmplt(DVec3::ZERO).any() || rel.cmpge(g.dims_f).any() {
            let below = (g.origin - x).max(DVec3::ZERO);
            let above = (x - g.upper()).max(DVec3::ZERO);
            return (below + above).length_squared() >= radius * radius;
        }
        // Inside the box: rel ≥ 0, so `as usize` (truncation, no libm call) is the floor.
        let cc = [0, 1, 2]
            .map(|k| ((rel[k] * (1.0 / COARSE as f64)) as usize).min(g.coarse_dims[k] - 1));
        let ci = (cc[2] * g.coarse_dims[1] + cc[1]) * g.coarse_dims[0] + cc[0];
        let room = f64::from(g.coarse_clear[ci]) - radius;
        if room > 0.0 {
            // Offset from the coarse centre, in cells.
            let off =
                rel - (DVec3::new(cc[0] as f64, cc[1] as f64, cc[2] as f64) + 0.5) * COARSE as f64;
            if off.length_squared() * (g.h * g.h) <= room * room {
                return true;
            }
        }
        let c = [0, 1, 2].map(|k| (rel[k] as usize).min(g.dims[k] - 1));
        let cell = (c[2] * g.dims[1] + c[1]) * g.dims[0] + c[0];
        // Any point of a cell `reach` cells from the nearest non-empty one is at least
        // (reach − 1) cells from every triangle.
        if (f64::from(g.reach[cell]) - 1.0) * g.h >= radius {
            return true;
        }
        let room = f64::from(g.centre_clear[cell]) - radius;
        let off = rel - (DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) + 0.5);
        room > 0.0 && off.length_squared() * (g.h * g.h) <= room * room
    }

    /// Closest point to `x` on triangle `t`, m.
    #[inline]
    fn closest(&self, x: DVec3, t: u32) -> DVec3 {
        let [a, b, c] = self.triangles[t as usize].map(|i| self.vertices[i as usize]);
        closest_point_on_triangle(x, a, b, c).0
    }

    /// The contacts of a sphere (centre `x`, radius `radius`, m) with the mesh, written to
    /// `out` (cleared first), one per touched surface feature:
    ///
    /// 1. every triangle of the bin cells the sphere's box covers whose closest point is
    ///    nearer than `radius` is a candidate (closest point, feature);
    /// 2. a face candidate is kept; an edge or vertex candidate is kept only when every
    ///    triangle sharing that edge or vertex has its closest point there too (within
    ///    10⁻⁹·radius): a neighbour whose closest point is elsewhere is nearer (closest
    ///    points are unique), so the sphere's true contact is on that neighbour (it is a
    ///    candidate too), as when a sphere over one triangle of a flat region also reaches
    ///    the next triangle's edge, or over two triangles folded very slightly (a quad
    ///    whose corners were rounded to f32);
    /// 3. a candidate whose closest point equals (within 10⁻⁹·radius) that of a candidate
    ///    already kept is dropped: the triangles around a touched edge or vertex give it
    ///    once. Face candidates are taken first, then the others, each in triangle order.
    ///
    /// So a sphere on a flat region of many triangles gets exactly one contact whose
    /// overlap and normal are the plane's, and a sphere in a concave corner one contact
    /// per face. A face contact's distance is measured along the face normal (the plane
    /// distance, to rounding); the others' as |x − q|. Normal = (x − q)/|x − q|.
    pub fn contacts(&self, x: DVec3, radius: f64, s: &mut MeshScratch, out: &mut Vec<MeshContact>) {
        out.clear();
        let g = &self.grid;
        let Some((l, u)) = g.range(x - DVec3::splat(radius), x + DVec3::splat(radius)) else {
            return;
        };
        s.tris.clear();
        for k in l[2]..=u[2] {
            for j in l[1]..=u[1] {
                for i in l[0]..=u[0] {
                    s.tris
                        .extend_from_slice(g.cells.get((k * g.dims[1] + j) * g.dims[0] + i));
                }
            }
        }
        if l != u {
            s.tris.sort_unstable();
            s.tris.dedup();
        }
        let r2 = radius * radius;
        s.hits.clear();
        for &t in &s.tris {
            let [a, b, c] = self.triangles[t as usize].map(|i| self.vertices[i as usize]);
            // The triangle's plane is no farther than the triangle: a cheap rejection.
            if (x - a).dot(self.normals[t as usize]).abs() >= radius {
                continue;
            }
            let (q, feature) = closest_point_on_triangle(x, a, b, c);
            let dist2 = (q - x).length_squared();
            if dist2 < r2 {
                s.hits.push(Hit {
                    tri: t,
                    point: q,
                    feature,
                    dist2,
                });
            }
        }
        if s.hits.is_empty() {
            return;
        }
        // Faces first (stable: each kind stays in triangle order).
        s.hits.sort_by_key(|h| h.feature != Feature::Face);
        let tol = 1e-9 * radius;
        let tol2 = tol * tol;
        for h in &s.hits {
            let d = h.dist2.sqrt();
            // Another triangle at this edge or vertex whose closest point is elsewhere is
            // nearer than this point (closest points are unique): not a contact here.
            let elsewhere =
                |n: &u32| *n != h.tri && (self.closest(x, *n) - h.point).length_squared() > tol2;
            let dominated = match h.feature {
                Feature::Face => false,
                Feature::Edge(k) => {
                    let e = self.tri_edges[h.tri as usize][k as usize] as usize;
                    self.edge_tris.get(e).iter().any(elsewhere)
                }
                Feature::Vertex(k) => {
                    let v = self.triangles[h.tri as usize][k as usize] as usize;
                    self.vertex_tris.get(v).iter().any(elsewhere)
                }
            };
            if dominated
                || out
                    .iter()
                    .any(|c| (c.point - h.point).length_squared() <= tol2)
            {
                continue;
            }
            let n_face = self.normals[h.tri as usize];
            let (dist, normal) = if h.feature == Feature::Face {
                let a = self.vertices[self.triangles[h.tri as usize][0] as usize];
                let sd = (x - a).dot(n_face);
                if sd >= 0.0 {
                    (sd, n_face)
                } else {
                    (-sd, -n_face)
                }
            } else if d > 0.0 {
                (d, (x - h.point) / d)
            } else {
                (0.0, n_face)
            };
            out.push(MeshContact {
                overlap: radius - dist,
                normal,
                point: h.point,
                region: self.region[h.tri as usize],
                triangle: h.tri,
                feature: h.feature,
            });
        }
    }

    /// Line strips drawing the mesh: its feature edges, chained into polylines (each
    /// feature edge drawn once).
    pub fn outline(&self) -> Vec<Vec<[f64; 3]>> {
        let edges = self.feature_edges();
        let at = Csr::build(
            self.vertices.len(),
            edges
                .iter()
                .enumerate()
                .flat_map(|(e, &[p, q])| [(p, e as u32), (q, e as u32)]),
        );
        let mut used = vec![false; edges.len()];
        let mut strips = Vec::new();
        for start in 0..edges.len() {
            if used[start] {
                continue;
            }
            used[start] = true;
            let [p, mut v] = edges[start];
            let mut strip = vec![p, v];
            // Walk on while an unused feature edge leaves the last vertex.
            while let Some(&e) = at.get(v as usize).iter().find(|&&e| !used[e as usize]) {
                used[e as usize] = true;
                let [a, b] = edges[e as usize];
                v = if a == v { b } else { a };
                strip.push(v);
            }
            strips.push(
                strip
                    .into_iter()
                    .map(|i| self.vertices[i as usize].to_array())
                    .collect(),
            );
        }
        strips
    }
}

#[cfg(test)]
mod tests;
