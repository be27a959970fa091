//! The queries of a [`CellTable`](super::CellTable) (its [`View`]): locate a point from a cell's records and
//! interpolate there, with the values of the table's own field or of another's.

use glam::DVec3;

use super::values::Values;
use super::{
    BOUNDARY, CellRec, HINT_HOPS, NO_CELL, NO_TET, Query, Records, TOL, TableWalk, TetRec,
    exit_face,
};

/// The queries' view of a table: its records and where the values come from.
#[derive(Clone, Copy)]
pub(super) struct View<'a, V> {
    pub(super) r: &'a Records,
    pub(super) tet_values: Option<&'a [DVec3]>,
    pub(super) v: V,
}

impl<V: Values> View<'_, V> {
    /// [`CellTable::walk`].
    #[inline(always)]
    pub(super) fn walk(self, mut c: u32, mut tet: u32, x: DVec3, hops: usize) -> TableWalk {
        for _ in 0..=hops {
            match self.query(c, tet, x) {
                Query::Inside(value, tet) => {
                    return TableWalk::Inside {
                        cell: c,
                        tet,
                        value,
                    };
                }
                Query::Beyond(NO_CELL, _) | Query::Unknown => return TableWalk::Unknown,
                Query::Beyond(next, _) if next & BOUNDARY != 0 => {
                    return TableWalk::Boundary {
                        cell: c,
                        face: next & !BOUNDARY,
                    };
                }
                Query::Beyond(next, across) => {
                    c = next;
                    tet = across;
                }
            }
        }
        TableWalk::Unknown
    }

    /// What cell `c`'s records tell of x (see [`Query`]), the tetrahedron record `hint`
    /// tried first ([`CellTable::walk`]).
    #[inline(never)]
    pub(super) fn query(self, c: u32, hint: u32, x: DVec3) -> Query {
        let Some(rec) = self.r.cells.get(c as usize) else {
            return Query::Unknown;
        };
        let d = x - rec.cc;
        if let Some(q) = self.hinted(c, rec, hint, d) {
            return q;
        }
        if rec.simple != 0 {
            self.query_simple(c, rec, d)
        } else {
            self.query_general(c, rec, d)
        }
    }

    /// [`CellTable::query`] for a simple cell (convex, planar faces): inside when the
    /// exit ratio is ≤ 1, and then in the tetrahedron of the exit face.
    #[inline(always)]
    pub(super) fn query_simple(self, c: u32, rec: &CellRec, d: DVec3) -> Query {
        let Some((faces, next)) = cell_faces(rec, &self.r.simple, &self.r.simple_next) else {
            return Query::Unknown;
        };
        let Some((best, best_ratio)) = exit_face(faces, |f| f.q, d) else {
            return Query::Unknown;
        };
        if best_ratio > 1.0 + TOL {
            return Query::Beyond(next[best], NO_TET);
        }
        let g = self.v.g(rec.face as usize + best, &faces[best]);
        Query::Inside(
            self.v.uc(c, rec) + DVec3::new(g[0].dot(d), g[1].dot(d), g[2].dot(d)),
            NO_TET,
        )
    }

    /// What the search would answer for d in cell `c`, found from tetrahedron record
    /// `k` (the hint) and at most [`HINT_HOPS`] of its siblings across the side of the
    /// most negative coordinate: x inside one deeper than its margin (where the search
    /// finds that tetrahedron as well, `build::tet_margins`; the value with
    /// [`View::in_tets`]'s operations, so the same bits), or beyond its outer
    /// triangle when that is on the face the search's ray leaves through; `None` where the
    /// hints cannot tell (then search).
    #[inline(always)]
    pub(super) fn hinted(self, c: u32, rec: &CellRec, mut k: u32, d: DVec3) -> Option<Query> {
        for _ in 0..=HINT_HOPS {
            let t = self.r.tets.get(k as usize)?;
            if t.cell != c {
                return None;
            }
            let (b, cw, a) = (t.m[1].dot(d), t.m[2].dot(d), t.m[0].dot(d));
            let w = DVec3::new(a, b, cw);
            if a > t.margin && b > t.margin && cw > t.margin {
                if w.element_sum() <= 1.0 + TOL {
                    return Some(Query::Inside(self.tet_value(k, t, self.v.uc(c, rec), w), k));
                }
                return self.beyond(rec, k, t.across, d);
            }
            let j = if a <= b && a <= cw {
                0
            } else if b <= cw {
                1
            } else {
                2
            };
            k = t.links[j];
        }
        None
    }

    /// [`Query::Beyond`] for d deeper than its margin in the cone of tetrahedron record
    /// `k` and beyond its outer triangle, when the search's exit face (the largest ratio)
    /// is `k`'s face: the search then takes `k` first in that face's fan and answers so.
    #[inline(always)]
    pub(super) fn beyond(self, rec: &CellRec, k: u32, across: u32, d: DVec3) -> Option<Query> {
        let (faces, next) = cell_faces(rec, &self.r.faces, &self.r.faces_next)?;
        let (best, _) = exit_face(faces, |f| f.q, d)?;
        let f = &faces[best];
        (f.tet..f.tet + f.n_tets)
            .contains(&k)
            .then(|| Query::Beyond(next[best], across))
    }

    /// The value in tetrahedron `t` (record `k`) at coordinates `w`: the conservative
    /// scheme's constant, else linear from the node differences.
    #[inline(always)]
    pub(super) fn tet_value(self, k: u32, t: &TetRec, uc: DVec3, w: DVec3) -> DVec3 {
        match &self.tet_values {
            Some(tv) => tv.get(t.value as usize).copied().unwrap_or(DVec3::NAN),
            None => {
                let du = self.v.du(k, t);
                uc + w.x * du[0] + w.y * du[1] + w.z * du[2]
            }
        }
    }

    /// [`CellTable::query`] for any other cell: the exit face's tetrahedra, then (a warped
    /// face, a non-convex cell) all the cell's. Kept out of line so that the simple path
    /// stays small where it is inlined.
    #[inline(never)]
    pub(super) fn query_general(self, c: u32, rec: &CellRec, d: DVec3) -> Query {
        let Some((faces, next)) = cell_faces(rec, &self.r.faces, &self.r.faces_next) else {
            return Query::Unknown;
        };
        let Some((best, _)) = exit_face(faces, |f| f.q, d) else {
            return Query::Unknown;
        };
        let bf = &faces[best];
        let Some(tets) = self
            .r
            .tets
            .get(bf.tet as usize..(bf.tet + bf.n_tets) as usize)
        else {
            return Query::Unknown;
        };
        let uc = self.v.uc(c, rec);
        match self.in_tets(bf.tet, tets, uc, d) {
            Some((Some(u), t)) => return Query::Inside(u, t),
            // the ray leaves through the outer triangle of one of this face's tetrahedra:
            // the locator crosses this face too
            Some((None, t)) => {
                let across = self.r.tets.get(t as usize).map_or(NO_TET, |r| r.across);
                return Query::Beyond(next[best], across);
            }
            None => {}
        }
        // the ray leaves through another face (a warped face, a non-convex cell): all the
        // cell's tetrahedra, as the locator scans all faces
        let (a, b) = (faces[0].tet, faces[faces.len() - 1]);
        let Some(all) = self.r.tets.get(a as usize..(b.tet + b.n_tets) as usize) else {
            return Query::Unknown;
        };
        match self.in_tets(a, all, uc, d) {
            Some((Some(u), t)) => Query::Inside(u, t),
            _ => Query::Unknown,
        }
    }

    /// The tetrahedron of `tets` the ray from the centre along d crosses, and its record's
    /// index (`first` being that of `tets[0]`): with `Some(u)` the value when d is inside
    /// it, `None` when d is beyond its outer triangle; `None` when no tetrahedron takes
    /// the ray. With the conservative scheme's velocities the value is the tetrahedron's.
    #[inline(always)]
    pub(super) fn in_tets(
        self,
        first: u32,
        tets: &[TetRec],
        uc: DVec3,
        d: DVec3,
    ) -> Option<(Option<DVec3>, u32)> {
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
            let k = first + i as u32;
            if w.element_sum() > 1.0 + TOL {
                return Some((None, k));
            }
            return Some((Some(self.tet_value(k, t, uc, w)), k));
        }
        None
    }
}

/// Cell record `rec`'s run of face records in `faces` and what is across each in `next`
/// (`None` out of range).
#[inline(always)]
fn cell_faces<'a, F>(
    rec: &CellRec,
    faces: &'a [F],
    next: &'a [u32],
) -> Option<(&'a [F], &'a [u32])> {
    let r = rec.face as usize..(rec.face + rec.n_faces) as usize;
    Some((faces.get(r.clone())?, next.get(r)?))
}
