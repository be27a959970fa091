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

mod bins;

use bins::{BinGrid, COARSE, Csr};

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
