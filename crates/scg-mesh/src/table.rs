//! [`CellTable`]: what locating a point in a given cell and interpolating there reads,
//! stored per cell in a few contiguous records, for the hot path of particle tracking.
//!
//! [`crate::Locator::probe`] and [`crate::Interpolator::at`] read a cell's centre, its face
//! list, every face's centre and area vector, the face's point list and points, the cell
//! value and three node values: about 20 cache lines scattered over a dozen arrays. A
//! particle moving a fraction of a cell per step stays in its cell most steps, and then
//! this table answers with three records:
//!
//! * the cell (one 64-byte line): its centre `cc` and value `u_c`;
//! * its faces (32 bytes each, contiguous): `q_f = A_f / ((x_f − cc)·A_f)`, so that
//!   `q_f·(x − cc)` is the ratio [`crate::Locator::probe`] maximises to pick the face the
//!   ray from the centre toward x leaves through;
//! * the tetrahedra of that face (144 bytes each: one for a triangle, one per edge for a
//!   polygon's face-centre fan): the rows of the inverse of the matrix (T − cc), so that the
//!   barycentric coordinates of x are `w = M·(x − cc)`, and the node values minus the cell
//!   value, so that the interpolated value is `u_c + Σ w_i Δu_i`.
//!
//! The same tetrahedra, the same tolerance and the same face choice as the locator; the
//! coordinates and the value are computed from precomputed inverses instead of from the
//! points, so they may differ from [`crate::Interpolator::at`]'s in the last bits. When the
//! point is not found in the cell (it left it, or the chosen face's triangles do not take
//! the ray), [`CellTable::velocity_in`] answers `None`. [`CellTable::walk`] then goes on
//! as the locator's walk does, across the face the ray leaves through into the cell beyond
//! (each record knows the cell across each face), for a few cells; it gives up, and the
//! caller walks with the locator, at a boundary face or where the records cannot name the
//! exit. On a mesh finer than a particle's step this keeps most face crossings on the
//! table's few lines. Cells whose tetrahedra are degenerate have no records and always
//! answer `None`.
//!
//! A convex cell of triangular faces (every tetrahedral cell) is split into one tetrahedron
//! per face, and its value is linear in each: such a *simple* cell keeps, per face, `q_f`
//! and the rows of the value's gradient together (96 bytes), so that a query reads the cell
//! line and one contiguous run of face records, and nothing else.
//!
//! With [`crate::Interpolation::Conservative`] every cell takes the general records, and a
//! query answers its tetrahedron's constant velocity instead of the linear value, read
//! from the interpolator's velocities (shared, not copied: each cell record knows where
//! its cell's start).
//!
//! Memory: 64 bytes per cell; a simple cell 96 per face (a tetrahedron: 0.45 kB); any other
//! 32 per cell face and 144 per tetrahedron of the decomposition (a hexahedron's 24:
//! 3.7 kB). [`CellTable::new`] declines (returns `None`) above [`CellTable::MAX_BYTES`].

use glam::DVec3;

use crate::interp::Interpolator;

/// Relative tolerance of the inside test (the locator's).
const TOL: f64 = 1e-9;

#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct CellRec {
    cc: DVec3,
    uc: DVec3,
    /// First face record.
    face: u32,
    /// Face records (0: no records, ask the locator).
    n_faces: u32,
    /// A convex cell of triangular faces: one tetrahedron per face, whose record holds
    /// the rows of the value's gradient G (u = u_c + G·(x − cc)) instead of M and Δu.
    simple: u32,
    /// The conservative scheme: the index of the cell's first tetrahedron in
    /// [`CellTable::tet_values`].
    tet_base: u32,
}

// the cell record is one cache line (the conservative scheme's `tet_base` uses its spare
// four bytes)
const _: () = assert!(size_of::<CellRec>() == 64);

#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct FaceRec {
    q: DVec3,
    /// First tetrahedron record.
    tet: u32,
    n_tets: u32,
}

#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(16))]
struct TetRec {
    /// Rows of the inverse of (v1 v2 v3), v_i = node_i − cc.
    m: [DVec3; 3],
    /// Node values minus the cell value.
    du: [DVec3; 3],
}

/// A face of a convex cell of triangular faces (a `simple` cell): the exit ratio's `q` and
/// the rows of the value's gradient in the face's tetrahedron, together, so that such a
/// cell is answered from its cell record and one contiguous run of face records.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct SimpleFace {
    q: DVec3,
    /// Rows of G: u = u_c + G·(x − cc) in this face's tetrahedron.
    g: [DVec3; 3],
}

/// Per-cell records for locating a point in a known cell and interpolating there (see the
/// module documentation).
#[derive(Clone, Debug, Default)]
pub struct CellTable {
    cells: Vec<CellRec>,
    faces: Vec<FaceRec>,
    tets: Vec<TetRec>,
    /// Face records of the simple cells (their cell record's `face` indexes here).
    simple: Vec<SimpleFace>,
    /// What is across each of `simple`'s faces (see [`BOUNDARY`]).
    simple_next: Vec<u32>,
    /// What is across each of `faces`' faces (see [`BOUNDARY`]; [`NO_CELL`] for padding).
    faces_next: Vec<u32>,
    /// The conservative scheme's tetrahedron velocities, the interpolator's (`None` for the
    /// other schemes; with them no cell is simple, and a query answers its tetrahedron's
    /// value).
    tet_values: Option<std::sync::Arc<[DVec3]>>,
}

/// Nothing across (padding records).
const NO_CELL: u32 = u32::MAX;

/// Across a face: the neighbour cell, or for a boundary face `BOUNDARY | face` (the mesh's
/// face index; meshes have fewer than 2^31 faces).
const BOUNDARY: u32 = 1 << 31;

/// Where [`CellTable::walk`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableWalk {
    /// x is in `cell`; the interpolated value there.
    Inside {
        /// The cell holding x.
        cell: u32,
        /// The interpolated value at x.
        value: DVec3,
    },
    /// The ray toward x leaves `cell` through boundary face `face` (the mesh's index).
    Boundary {
        /// The last cell before the boundary.
        cell: u32,
        /// The boundary face.
        face: u32,
    },
    /// The table cannot tell (ask the locator).
    Unknown,
}

/// What [`CellTable::query`] learns of x from cell `c`'s records.
enum Query {
    /// x is in the cell; the interpolated value.
    Inside(DVec3),
    /// x is beyond the face the ray from the centre leaves through: what is across it
    /// (see [`BOUNDARY`]).
    Beyond(u32),
    /// The records cannot tell (no records, out of range, a ray the exit face's
    /// tetrahedra do not take).
    Unknown,
}

impl CellTable {
    /// Largest table [`CellTable::new`] builds, bytes (4 GiB).
    pub const MAX_BYTES: usize = 4 << 30;

    /// The records of `it`'s mesh and field (any scheme: for `CellValue` the node
    /// differences are zero and the value is the cell's). `None` when the table would
    /// exceed [`CellTable::MAX_BYTES`].
    pub fn new(it: &Interpolator<'_>) -> Option<Self> {
        let loc = it.locator();
        let mesh = loc.mesh();
        let geom = loc.geometry();
        let nc = mesh.n_cells;
        let n_faces = geom.cell_faces.len();
        let n_tets: usize = geom
            .cell_faces
            .iter()
            .map(|&f| {
                let k = mesh.face(f as usize).len();
                if k == 3 { 1 } else { k }
            })
            .sum();
        let bytes = nc * size_of::<CellRec>()
            + n_faces * (size_of::<FaceRec>() + size_of::<u32>())
            + n_tets * size_of::<TetRec>();
        if bytes > Self::MAX_BYTES || n_tets > u32::MAX as usize {
            return None;
        }
        let cellv = it.cell_values();
        let nodev = it.node_values();
        let np = mesh.points.len() as u32;
        let mut t = CellTable {
            cells: Vec::with_capacity(nc),
            faces: Vec::with_capacity(n_faces),
            tets: Vec::with_capacity(n_tets),
            simple: Vec::new(),
            simple_next: Vec::new(),
            faces_next: Vec::with_capacity(n_faces),
            tet_values: None,
        };
        let shared = it.tet_velocities();
        t.tet_values = shared.map(|(v, _)| std::sync::Arc::clone(v));
        let conservative = shared.is_some();
        // room for the cells that may be simple (all faces triangles), each on a line
        let tri_faced: usize = (0..nc)
            .map(|c| geom.faces_of(c))
            .filter(|fs| fs.iter().all(|&f| mesh.face(f as usize).len() == 3))
            .map(|fs| fs.len() + 1)
            .sum();
        t.simple.reserve_exact(tri_faced);
        t.simple_next.reserve_exact(tri_faced);
        huge_pages(&t.cells);
        huge_pages(&t.faces);
        huge_pages(&t.tets);
        huge_pages(&t.simple);
        for (c, (&cc, &uc)) in geom.cell_centres.iter().zip(cellv).enumerate() {
            if t.faces.len() % 2 == 1 {
                // start every cell's face records on a 64-byte line (a tetrahedral cell's
                // four: two lines)
                t.faces.push(FaceRec::default());
                t.faces_next.push(NO_CELL);
            }
            let (f0, t0) = (t.faces.len(), t.tets.len());
            let mut ok = true;
            for &f in geom.faces_of(c) {
                let fi = f as usize;
                let a = geom.face_areas[fi];
                let den = (geom.face_centres[fi] - cc).dot(a);
                let q = a / den;
                let tet = t.tets.len() as u32;
                let pts = mesh.face(fi);
                let flip = mesh.owner[fi] as usize != c;
                let mut push = |nodes: [u32; 3]| {
                    let v = nodes.map(|n| loc.node(n) - cc);
                    let n23 = v[1].cross(v[2]);
                    let det = v[0].dot(n23);
                    if det.is_nan() || det <= 0.0 {
                        return false;
                    }
                    let inv = 1.0 / det;
                    let m = [n23 * inv, v[2].cross(v[0]) * inv, v[0].cross(v[1]) * inv];
                    let du = nodes.map(|n| nodev.get(n as usize).map_or(DVec3::ZERO, |&u| u - uc));
                    t.tets.push(TetRec { m, du });
                    true
                };
                if pts.len() == 3 {
                    let (a, b) = if flip {
                        (pts[2], pts[1])
                    } else {
                        (pts[1], pts[2])
                    };
                    ok &= push([pts[0], a, b]);
                } else {
                    let n = pts.len();
                    for i in 0..n {
                        let (pa, pb) = (pts[i], pts[(i + 1) % n]);
                        let (a, b) = if flip { (pb, pa) } else { (pa, pb) };
                        ok &= push([np + f, a, b]);
                    }
                }
                ok &= q.is_finite();
                t.faces.push(FaceRec {
                    q,
                    tet,
                    n_tets: t.tets.len() as u32 - tet,
                });
                let across = if mesh.owner[fi] as usize == c {
                    mesh.neighbour.get(fi).copied()
                } else {
                    Some(mesh.owner[fi])
                };
                t.faces_next.push(across.unwrap_or(BOUNDARY | f));
            }
            if !ok {
                t.faces.truncate(f0);
                t.faces_next.truncate(f0);
                t.tets.truncate(t0);
            }
            // convex with triangular faces: every point of the cell on the inner side of
            // every face plane, one tetrahedron per face
            let faces = &t.faces[f0..];
            let simple = ok
                && !conservative
                && faces.iter().all(|f| f.n_tets == 1)
                && geom.faces_of(c).iter().all(|&f| {
                    mesh.face(f as usize).len() == 3
                        && geom.faces_of(c).iter().all(|&g| {
                            mesh.face(g as usize).iter().all(|&p| {
                                faces
                                    .iter()
                                    .all(|fr| fr.q.dot(mesh.points[p as usize] - cc) <= 1.0 + 1e-9)
                            })
                        })
                });
            let (face, n_faces) = if simple {
                // the gradient of each face's tetrahedron beside the face's q, and no
                // general records
                if t.simple.len() % 2 == 1 {
                    // start on a 64-byte line (a tetrahedral cell's four: six lines)
                    t.simple.push(SimpleFace::default());
                    t.simple_next.push(NO_CELL);
                }
                let s0 = t.simple.len();
                t.simple_next.extend_from_slice(&t.faces_next[f0..]);
                for fr in &t.faces[f0..] {
                    let tr = &t.tets[fr.tet as usize];
                    let g = [0, 1, 2].map(|j| {
                        tr.m[0] * tr.du[0][j] + tr.m[1] * tr.du[1][j] + tr.m[2] * tr.du[2][j]
                    });
                    t.simple.push(SimpleFace { q: fr.q, g });
                }
                t.faces.truncate(f0);
                t.faces_next.truncate(f0);
                t.tets.truncate(t0);
                (s0, t.simple.len() - s0)
            } else {
                (f0, t.faces.len() - f0)
            };
            t.cells.push(CellRec {
                cc,
                uc,
                face: face as u32,
                n_faces: n_faces as u32,
                simple: u32::from(simple),
                tet_base: shared.map_or(0, |(_, offsets)| {
                    offsets[geom.cell_face_offsets[c] as usize]
                }),
            });
        }
        // the general records were sized for every cell: give back what the simple cells
        // did not use
        t.faces.shrink_to_fit();
        t.faces_next.shrink_to_fit();
        t.tets.shrink_to_fit();
        Some(t)
    }

    /// Cells on the short path (convex, triangular faces), and cells without records.
    pub fn counts(&self) -> (usize, usize) {
        (
            self.cells.iter().filter(|c| c.simple != 0).count(),
            self.cells.iter().filter(|c| c.n_faces == 0).count(),
        )
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.cells.len() * size_of::<CellRec>()
            + self.faces.len() * (size_of::<FaceRec>() + size_of::<u32>())
            + self.tets.len() * size_of::<TetRec>()
            + self.simple.len() * (size_of::<SimpleFace>() + size_of::<u32>())
    }

    /// The interpolated value at x when x is in cell `c` (in one of its tetrahedra, up to
    /// the locator's tolerance); `None` when it is not, when the table cannot tell, or when
    /// `c` is out of range.
    #[inline]
    pub fn velocity_in(&self, c: u32, x: DVec3) -> Option<DVec3> {
        match self.query(c, x) {
            Query::Inside(u) => Some(u),
            Query::Beyond(_) | Query::Unknown => None,
        }
    }

    /// Where x is, found from cell `c` by walking across at most `hops` interior faces,
    /// each the face the ray from the cell's centre toward x leaves through (the locator's
    /// walk, on the table's records): the cell holding x and the value there, or the
    /// boundary face the walk meets; [`TableWalk::Unknown`] when the table cannot tell
    /// within that (a warped or non-convex cell whose exit the records cannot name, too
    /// far): ask the locator.
    #[inline]
    pub fn walk(&self, mut c: u32, x: DVec3, hops: usize) -> TableWalk {
        for _ in 0..=hops {
            match self.query(c, x) {
                Query::Inside(value) => return TableWalk::Inside { cell: c, value },
                Query::Beyond(NO_CELL) | Query::Unknown => return TableWalk::Unknown,
                Query::Beyond(next) if next & BOUNDARY != 0 => {
                    return TableWalk::Boundary {
                        cell: c,
                        face: next & !BOUNDARY,
                    };
                }
                Query::Beyond(next) => c = next,
            }
        }
        TableWalk::Unknown
    }

    /// What cell `c`'s records tell of x (see [`Query`]).
    #[inline(never)]
    fn query(&self, c: u32, x: DVec3) -> Query {
        let Some(rec) = self.cells.get(c as usize) else {
            return Query::Unknown;
        };
        let d = x - rec.cc;
        if rec.simple != 0 {
            self.query_simple(rec, d)
        } else {
            self.query_general(rec, d)
        }
    }

    /// [`CellTable::query`] for a simple cell (convex, planar faces): inside when the
    /// exit ratio is ≤ 1, and then in the tetrahedron of the exit face.
    #[inline(always)]
    fn query_simple(&self, rec: &CellRec, d: DVec3) -> Query {
        let r = rec.face as usize..(rec.face + rec.n_faces) as usize;
        let (Some(faces), Some(next)) = (self.simple.get(r.clone()), self.simple_next.get(r))
        else {
            return Query::Unknown;
        };
        let Some((best, best_ratio)) = exit_face(faces, |f| f.q, d) else {
            return Query::Unknown;
        };
        if best_ratio > 1.0 + TOL {
            return Query::Beyond(next[best]);
        }
        let g = &faces[best].g;
        Query::Inside(rec.uc + DVec3::new(g[0].dot(d), g[1].dot(d), g[2].dot(d)))
    }

    /// [`CellTable::query`] for any other cell: the exit face's tetrahedra, then (a warped
    /// face, a non-convex cell) all the cell's. Kept out of line so that the simple path
    /// stays small where it is inlined.
    #[inline(never)]
    fn query_general(&self, rec: &CellRec, d: DVec3) -> Query {
        let r = rec.face as usize..(rec.face + rec.n_faces) as usize;
        let (Some(faces), Some(next)) = (self.faces.get(r.clone()), self.faces_next.get(r)) else {
            return Query::Unknown;
        };
        let Some((best, _)) = exit_face(faces, |f| f.q, d) else {
            return Query::Unknown;
        };
        let bf = &faces[best];
        let Some(tets) = self
            .tets
            .get(bf.tet as usize..(bf.tet + bf.n_tets) as usize)
        else {
            return Query::Unknown;
        };
        // the index of `tets`' first in the shared velocities (conservative scheme)
        let first = rec.tet_base as usize + (bf.tet - faces[0].tet) as usize;
        match self.in_tets(first, tets, rec.uc, d) {
            Some(Some(u)) => return Query::Inside(u),
            // the ray leaves through the outer triangle of one of this face's tetrahedra:
            // the locator crosses this face too
            Some(None) => return Query::Beyond(next[best]),
            None => {}
        }
        // the ray leaves through another face (a warped face, a non-convex cell): all the
        // cell's tetrahedra, as the locator scans all faces
        let (a, b) = (faces[0].tet, faces[faces.len() - 1]);
        let Some(all) = self.tets.get(a as usize..(b.tet + b.n_tets) as usize) else {
            return Query::Unknown;
        };
        match self.in_tets(rec.tet_base as usize, all, rec.uc, d) {
            Some(Some(u)) => Query::Inside(u),
            _ => Query::Unknown,
        }
    }

    /// The tetrahedron of `tets` the ray from the centre along d crosses: `Some(Some(u))`
    /// when d is inside it, `Some(None)` when beyond its outer triangle, `None` when no
    /// tetrahedron takes the ray. With the conservative scheme's velocities the value is
    /// that of the tetrahedron's, `first` being the index of `tets[0]` among them.
    #[inline(always)]
    fn in_tets(&self, first: usize, tets: &[TetRec], uc: DVec3, d: DVec3) -> Option<Option<DVec3>> {
        for (i, t) in tets.iter().enumerate() {
            // the two coordinates of the face's edge nodes first: they place the ray in a
            // face-centre fan, and most tetrahedra fail one of them
            let b = t.m[1].dot(d);
            if b < -TOL {
                continue;
            }
            let c = t.m[2].dot(d);
            if c < -TOL {
                continue;
            }
            let a = t.m[0].dot(d);
            if a < -TOL {
                continue;
            }
            let w = DVec3::new(a, b, c);
            if w.element_sum() > 1.0 + TOL {
                return Some(None);
            }
            if let Some(v) = &self.tet_values {
                return v.get(first + i).map(|&u| Some(u));
            }
            return Some(Some(uc + w.x * t.du[0] + w.y * t.du[1] + w.z * t.du[2]));
        }
        None
    }

    /// Ask the processor to load cell `c`'s record; when `deep`, also its face records
    /// (addressed by the cell record, which should be in cache by then). No effect on
    /// results.
    #[inline]
    pub fn prefetch(&self, c: u32, deep: bool) {
        let Some(rec) = self.cells.get(c as usize) else {
            return;
        };
        if !deep {
            crate::prefetch::lines(rec, 1);
            return;
        }
        if rec.simple != 0 {
            if let Some(f) = self.simple.get(rec.face as usize) {
                crate::prefetch::lines(
                    f,
                    (rec.n_faces as usize * size_of::<SimpleFace>()).div_ceil(64),
                );
            }
            return;
        }
        if let Some(f) = self.faces.get(rec.face as usize) {
            crate::prefetch::lines(
                f,
                (rec.n_faces as usize * size_of::<FaceRec>()).div_ceil(64),
            );
        }
    }

    /// Ask the processor to load the tetrahedron records [`CellTable::velocity_in`] reads
    /// for x in cell `c` (the cell and face records should be in cache). No effect on
    /// results.
    #[inline(always)]
    pub fn prefetch_at(&self, c: u32, x: DVec3) {
        let Some(rec) = self.cells.get(c as usize) else {
            return;
        };
        if rec.simple != 0 {
            // all a simple cell's records are its face records
            return;
        }
        let Some(faces) = self
            .faces
            .get(rec.face as usize..(rec.face + rec.n_faces) as usize)
        else {
            return;
        };
        if let Some((best, _)) = exit_face(faces, |f| f.q, x - rec.cc)
            && let Some(t) = self.tets.get(faces[best].tet as usize)
        {
            // every tetrahedron of the exit face's fan: the scan may end in any of them
            let bytes = faces[best].n_tets as usize * size_of::<TetRec>();
            crate::prefetch::lines(t, bytes.div_ceil(64));
        }
    }
}

/// The face record the ray from the centre along `d` leaves through: the largest ratio
/// `q·d` (the first of equals), and that ratio; `None` without faces.
#[inline(always)]
fn exit_face<F>(faces: &[F], q: impl Fn(&F) -> DVec3, d: DVec3) -> Option<(usize, f64)> {
    let (mut best, mut best_ratio) = (0, q(faces.first()?).dot(d));
    for (k, f) in faces.iter().enumerate().skip(1) {
        let r = q(f).dot(d);
        if r > best_ratio {
            best_ratio = r;
            best = k;
        }
    }
    Some((best, best_ratio))
}

/// Ask Linux to back the (still untouched) capacity of `v` with transparent huge pages
/// where it spans whole 2 MiB pages: particles visit the cells of a large mesh at random,
/// and with 4 KiB pages nearly every record read would also miss the TLB. A hint: no
/// effect on results, ignored where unsupported.
fn huge_pages<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = v.as_ptr() as usize;
        let end = start + v.capacity() * size_of::<T>();
        let (a, b) = (start.next_multiple_of(HUGE), end / HUGE * HUGE);
        if b > a {
            // SAFETY: madvise only advises on pages of this live allocation; it does not
            // change their contents or validity.
            unsafe {
                libc::madvise(a as *mut libc::c_void, b - a, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

#[cfg(test)]
mod tests;
