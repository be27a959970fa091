//! Building a [`CellTable`] from an interpolator: the records, the tetrahedron margins and
//! links of the hinted query, and the huge-page advice.

use glam::DVec3;

use std::sync::Arc;

use super::{
    BOUNDARY, CellRec, CellTable, FaceRec, NO_CELL, NO_TET, Records, SimpleFace, TOL, TetRec,
};
use crate::interp::Interpolator;

impl CellTable {
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
        let shared = it.tet_velocities();
        let tet_values = shared.map(|(v, _)| Arc::clone(v));
        let conservative = shared.is_some();
        // room for the cells that may be simple (all faces triangles), each on a line
        let tri_faced: usize = (0..nc)
            .map(|c| geom.faces_of(c))
            .filter(|fs| fs.iter().all(|&f| mesh.face(f as usize).len() == 3))
            .map(|fs| fs.len() + 1)
            .sum();
        // the records read at random on huge pages (an allocation the machine refuses
        // declines the table)
        let mut t = Records {
            cells: huge_room(nc)?,
            faces: huge_room(n_faces)?,
            tets: huge_room(n_tets)?,
            simple: huge_room(tri_faced)?,
            simple_next: room(tri_faced)?,
            faces_next: room(n_faces)?,
            node_map: Default::default(),
        };
        // the corners v_i − cc of the cell's tetrahedra (for their margins) and their node
        // numbers (for their links)
        let mut corners: Vec<[DVec3; 3]> = Vec::new();
        let mut ids: Vec<[u32; 3]> = Vec::new();
        // each face's first tetrahedron record on its owner's and its neighbour's side
        let mut side_first = vec![[NO_TET; 2]; mesh.n_faces()];
        for (c, (&cc, &uc)) in geom.cell_centres.iter().zip(cellv).enumerate() {
            if t.faces.len() % 2 == 1 {
                // start every cell's face records on a 64-byte line (a tetrahedral cell's
                // four: two lines)
                t.faces.push(FaceRec::default());
                t.faces_next.push(NO_CELL);
            }
            let (f0, t0) = (t.faces.len(), t.tets.len());
            let mut ok = true;
            corners.clear();
            ids.clear();
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
                    let Some(m) = inverse_rows(v) else {
                        return false;
                    };
                    let du = node_differences(nodev, nodes, uc);
                    corners.push(v);
                    ids.push(nodes);
                    t.tets.push(TetRec {
                        m,
                        du,
                        margin: f64::INFINITY,
                        cell: c as u32,
                        value: 0,
                        links: [NO_TET; 3],
                        across: NO_TET,
                    });
                    true
                };
                for nodes in face_tets(pts, flip, np + f) {
                    ok &= push(nodes);
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
            if ok && !simple {
                // only general cells keep tetrahedron records: their margins, links and
                // conservative-velocity indices
                let tet_base = shared.map_or(0, |(_, offsets)| {
                    offsets[geom.cell_face_offsets[c] as usize]
                });
                tet_margins(&mut t.tets[t0..], &corners);
                tet_links(&mut t.tets[t0..], t0 as u32, &ids);
                for (k, r) in t.tets[t0..].iter_mut().enumerate() {
                    r.value = tet_base + k as u32;
                }
                for (k, &f) in geom.faces_of(c).iter().enumerate() {
                    let side = usize::from(mesh.owner[f as usize] as usize != c);
                    side_first[f as usize][side] = t.faces[f0 + k].tet;
                }
            }
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
                    let g = gradient_rows(&tr.m, &tr.du);
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
            });
        }
        // across each face's triangles: the same fan position on the other side
        for (f, &[own, nb]) in side_first.iter().enumerate() {
            if own == NO_TET || nb == NO_TET {
                continue;
            }
            let n = match mesh.face(f).len() {
                3 => 1,
                k => k as u32,
            };
            for i in 0..n {
                t.tets[(own + i) as usize].across = nb + i;
                t.tets[(nb + i) as usize].across = own + i;
            }
        }
        // the general records were sized for every cell: give back what the simple cells
        // did not use
        t.faces.shrink_to_fit();
        t.faces_next.shrink_to_fit();
        t.tets.shrink_to_fit();
        Some(CellTable {
            r: Arc::new(t),
            tet_values,
            values: None,
        })
    }
}

/// An empty vector with room for `n` elements, `None` when the allocation fails.
fn room<T>(n: usize) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok()?;
    Some(v)
}

/// [`room`] backed by transparent huge pages where it spans them ([`huge_pages`]): for
/// what the step reads at random.
pub(super) fn huge_room<T>(n: usize) -> Option<Vec<T>> {
    let v = room(n)?;
    huge_pages(&v);
    Some(v)
}

/// The corner nodes of the tetrahedra of a cell's face of points `pts` (`flip`: the cell
/// is the face's neighbour; `centre`: the node number of the face's centre), in record
/// order: one for a triangle, else one per edge, each with the face centre.
pub(super) fn face_tets(pts: &[u32], flip: bool, centre: u32) -> impl Iterator<Item = [u32; 3]> {
    let n = pts.len();
    let tri = n == 3;
    (0..if tri { 1 } else { n }).map(move |i| {
        if tri {
            let (a, b) = if flip {
                (pts[2], pts[1])
            } else {
                (pts[1], pts[2])
            };
            [pts[0], a, b]
        } else {
            let (pa, pb) = (pts[i], pts[(i + 1) % n]);
            let (a, b) = if flip { (pb, pa) } else { (pa, pb) };
            [centre, a, b]
        }
    })
}

/// The rows of the inverse of the matrix of columns v (a tetrahedron's corners minus the
/// cell centre), `None` unless its determinant is positive.
#[inline]
pub(super) fn inverse_rows(v: [DVec3; 3]) -> Option<[DVec3; 3]> {
    let n23 = v[1].cross(v[2]);
    let det = v[0].dot(n23);
    if det.is_nan() || det <= 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    Some([n23 * inv, v[2].cross(v[0]) * inv, v[0].cross(v[1]) * inv])
}

/// The node values minus the cell value `uc` (zero for a node without a value).
#[inline]
pub(super) fn node_differences(nodev: &[DVec3], nodes: [u32; 3], uc: DVec3) -> [DVec3; 3] {
    nodes.map(|n| node_difference(nodev, n, uc))
}

/// Node `n`'s value minus the cell value `uc` (zero for a node without a value).
#[inline]
pub(super) fn node_difference(nodev: &[DVec3], n: u32, uc: DVec3) -> DVec3 {
    nodev.get(n as usize).map_or(DVec3::ZERO, |&u| u - uc)
}

/// The rows of the value's gradient in a tetrahedron of inverse rows `m` and node
/// differences `du`.
#[inline]
pub(super) fn gradient_rows(m: &[DVec3; 3], du: &[DVec3; 3]) -> [DVec3; 3] {
    [0, 1, 2].map(|j| m[0] * du[0][j] + m[1] * du[1][j] + m[2] * du[2][j])
}

/// The margins of one cell's tetrahedra (`corners`: each one's v_i = node_i − cc, the
/// columns of the inverse of its rows m), so that a point whose three coordinates in
/// tetrahedron t exceed t's margin is found in t by [`CellTable::query`]'s search as well.
///
/// The search takes the first tetrahedron t′ (exit face first, then all) whose three
/// coordinates w′_j = m′_j·d are ≥ −TOL, i.e. whose cone from the centre x lies within
/// δ′_j ≥ −TOL·H′_j of each side plane (H′_j = 1/|m′_j| the height of corner j above the
/// plane opposite it, δ′ the signed distance). A point meeting those is within
/// ‖N′⁻¹‖·√3·TOL·max_j H′_j of the cone (N′ the unit side normals m′_j/|m′_j| as rows:
/// x′ = N′⁻¹·max(N′d, 0) is in the cone, and ‖N′⁻¹‖_F² = Σ_j |v′_j|²·|m′_j|² since
/// N′⁻¹ = V′·diag|m′_j|): K(t′) = √3·‖N′⁻¹‖_F·max_j H′_j·TOL. The cones of a star-shaped
/// cell do not overlap, so a point inside t's cone at distance ρ = min_j w_j·H_j from its
/// sides is at least ρ from every other cone, and no other meets the search's test when
/// ρ > K = max_t′ K(t′): when every w_j > 4·K·max_j |m_j| (a factor 4 over the bound for
/// the rounding of both sides). Such a point's ray also leaves through t's face, so the
/// search, exit face first or all, ends in t with the same arithmetic.
fn tet_margins(tets: &mut [TetRec], corners: &[[DVec3; 3]]) {
    let k = tets
        .iter()
        .zip(corners)
        .map(|(t, v)| {
            let norms = t.m.map(|m| m.length());
            let frob: f64 = (0..3)
                .map(|j| v[j].length_squared() * norms[j] * norms[j])
                .sum();
            let h_max = norms.iter().fold(0.0_f64, |h, &n| h.max(1.0 / n));
            3.0_f64.sqrt() * frob.sqrt() * h_max * TOL
        })
        .fold(0.0_f64, f64::max);
    for t in tets.iter_mut() {
        let m_max = t.m.iter().fold(0.0_f64, |a, m| a.max(m.length()));
        let margin = 4.0 * k * m_max;
        // a cell whose bound is not finite takes no hint
        t.margin = if margin.is_finite() {
            margin
        } else {
            f64::INFINITY
        };
    }
}

/// The links of one cell's tetrahedra (records from `first`, corner node numbers `ids`):
/// across the side opposite corner j, the other tetrahedron holding the other two corners.
fn tet_links(tets: &mut [TetRec], first: u32, ids: &[[u32; 3]]) {
    // (edge, tetrahedron, corner opposite), sorted by edge: the two holders side by side
    let mut sides: Vec<([u32; 2], u32, usize)> = Vec::with_capacity(3 * ids.len());
    for (k, n) in ids.iter().enumerate() {
        for j in 0..3 {
            let (p, q) = (n[(j + 1) % 3], n[(j + 2) % 3]);
            sides.push(([p.min(q), p.max(q)], k as u32, j));
        }
    }
    sides.sort_unstable();
    for pair in sides.windows(2) {
        let ((e0, k0, j0), (e1, k1, j1)) = (pair[0], pair[1]);
        if e0 == e1 && k0 != k1 {
            tets[k0 as usize].links[j0] = first + k1;
            tets[k1 as usize].links[j1] = first + k0;
        }
    }
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
