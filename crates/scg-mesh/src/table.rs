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
//! from the interpolator's velocities (shared, not copied: each tetrahedron record knows
//! its index there).
//!
//! # Tetrahedron hints
//!
//! A particle moving a fraction of a tetrahedron per step is found, most steps, in the
//! tetrahedron of its last query. [`CellTable::walk`] takes that record as a hint (each
//! particle carries it): the query reads the cell record and that one tetrahedron record
//! (4 cache lines instead of the ~13 of a hexahedron's exit face and fan), and on a miss
//! hops to the sibling across the side of the most negative coordinate (each record links
//! its three siblings and the tetrahedron across its outer triangle, the next cell's hint).
//! A hint changes what is read, never the answer: a tetrahedron is taken only where the
//! point lies deeper inside it than its margin, which is where the search (exit face, fan,
//! all tetrahedra) provably ends in the same tetrahedron with the same arithmetic
//! (`build::tet_margins`); anything else is searched as without a hint. So results do not
//! depend on hints (tested bit for bit at points within 10^-12–10^-6 of every side, and on
//! whole runs), and a hint is scratch state: unknown after a restart or a migration.
//!
//! Memory: 64 bytes per cell; a simple cell 96 per face (a tetrahedron: 0.45 kB); any other
//! 36 per cell face and 176 per tetrahedron of the decomposition (a hexahedron's 24:
//! 4.5 kB). [`CellTable::new`] declines (returns `None`) above [`CellTable::MAX_BYTES`] or
//! when the memory cannot be had.

use std::sync::Arc;

use glam::DVec3;

use values::{Own, Values};

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
}

// the cell record is one cache line
const _: () = assert!(size_of::<CellRec>() == 64);
// a tetrahedron record under three
const _: () = assert!(size_of::<TetRec>() == 176);

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
    /// The hinted query's margin (`build::tet_margins`): a point whose three coordinates exceed
    /// it is in this tetrahedron and within the tolerance of no other of its cell's.
    margin: f64,
    /// The cell it belongs to.
    cell: u32,
    /// The conservative scheme: its index in [`CellTable::tet_values`].
    value: u32,
    /// The record of the cell's tetrahedron across the side opposite corner j (the side
    /// where coordinate j is 0), [`NO_TET`] if none.
    links: [u32; 3],
    /// The record of the tetrahedron across the outer triangle, in the next cell
    /// ([`NO_TET`] at the boundary or where that cell has no tetrahedron records).
    across: u32,
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
///
/// A table of another field on the same mesh ([`CellTable::for_field`], the later
/// snapshots of an unsteady series) shares this one's records and keeps only its own
/// values ([`values`]): the cell values, the differences at the nodes of each cell's
/// tetrahedra and the gradients of the simple cells' faces (0.36 kB of a hexahedron's
/// 4.5 kB of records).
#[derive(Clone, Debug, Default)]
pub struct CellTable {
    r: Arc<Records>,
    /// The conservative scheme's tetrahedron velocities, the interpolator's (`None` for the
    /// other schemes; with them no cell is simple, and a query answers its tetrahedron's
    /// value).
    tet_values: Option<Arc<[DVec3]>>,
    /// Another field's values on `r` (`None`: the values in `r` are this table's).
    values: Option<Arc<values::FieldValues>>,
}

/// The records of a table: the mesh's geometry as the queries read it, with the values of
/// the field they were built for.
#[derive(Debug, Default)]
struct Records {
    cells: Vec<CellRec>,
    faces: Vec<FaceRec>,
    tets: Vec<TetRec>,
    /// Face records of the simple cells (their cell record's `face` indexes here).
    simple: Vec<SimpleFace>,
    /// What is across each of `simple`'s faces (see [`BOUNDARY`]).
    simple_next: Vec<u32>,
    /// What is across each of `faces`' faces (see [`BOUNDARY`]; [`NO_CELL`] for padding).
    faces_next: Vec<u32>,
    /// The nodes of the tetrahedra, for the tables of other fields on these records
    /// ([`CellTable::for_field`]), built by the first of them.
    node_map: std::sync::OnceLock<Arc<values::NodeMap>>,
}

/// Most sibling tetrahedra a hinted query tries before it searches the cell.
const HINT_HOPS: usize = 3;

/// Nothing across (padding records).
const NO_CELL: u32 = u32::MAX;

/// Across a face: the neighbour cell, or for a boundary face `BOUNDARY | face` (the mesh's
/// face index; meshes have fewer than 2^31 faces).
const BOUNDARY: u32 = 1 << 31;

/// No tetrahedron hint (a new particle, or one found on a simple cell's records).
pub const NO_TET: u32 = u32::MAX;

/// Where [`CellTable::walk`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TableWalk {
    /// x is in `cell`; the interpolated value there.
    Inside {
        /// The cell holding x.
        cell: u32,
        /// The tetrahedron record holding x, the hint of the next query from this cell
        /// ([`NO_TET`] for a simple cell, whose query reads no tetrahedron record).
        tet: u32,
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
    /// x is in the cell; the interpolated value and the tetrahedron record holding x
    /// ([`NO_TET`] on a simple cell).
    Inside(DVec3, u32),
    /// x is beyond the face the ray from the centre leaves through: what is across it
    /// (see [`BOUNDARY`]), and the tetrahedron record across the triangle the ray leaves
    /// through (the next query's hint, [`NO_TET`] if none).
    Beyond(u32, u32),
    /// The records cannot tell (no records, out of range, a ray the exit face's
    /// tetrahedra do not take).
    Unknown,
}

impl CellTable {
    /// Largest table [`CellTable::new`] builds, bytes (16 GiB: a 3.5·10^6-cell hexahedral
    /// mesh). A fixed bound, not the machine's memory, so that whether a mesh gets a table
    /// (which changes the interpolated values in their last bits) does not depend on where
    /// it runs; an allocation the machine refuses declines the table as well.
    pub const MAX_BYTES: usize = 16 << 30;

    /// Cells on the short path (convex, triangular faces), and cells without records.
    pub fn counts(&self) -> (usize, usize) {
        (
            self.r.cells.iter().filter(|c| c.simple != 0).count(),
            self.r.cells.iter().filter(|c| c.n_faces == 0).count(),
        )
    }

    /// Bytes held (a table of another field on shared records: its values alone).
    pub fn bytes(&self) -> usize {
        if let Some(v) = &self.values {
            return v.bytes();
        }
        self.r.cells.len() * size_of::<CellRec>()
            + self.r.faces.len() * (size_of::<FaceRec>() + size_of::<u32>())
            + self.r.tets.len() * size_of::<TetRec>()
            + self.r.simple.len() * (size_of::<SimpleFace>() + size_of::<u32>())
    }

    /// The interpolated value at x when x is in cell `c` (in one of its tetrahedra, up to
    /// the locator's tolerance); `None` when it is not, when the table cannot tell, or when
    /// `c` is out of range.
    #[inline]
    pub fn velocity_in(&self, c: u32, x: DVec3) -> Option<DVec3> {
        let q = match &self.values {
            None => self.view(Own).query(c, NO_TET, x),
            Some(v) => self.view(&**v).query(c, NO_TET, x),
        };
        match q {
            Query::Inside(u, _) => Some(u),
            Query::Beyond(..) | Query::Unknown => None,
        }
    }

    /// Where x is, found from cell `c` by walking across at most `hops` interior faces,
    /// each the face the ray from the cell's centre toward x leaves through (the locator's
    /// walk, on the table's records): the cell holding x and the value there, or the
    /// boundary face the walk meets; [`TableWalk::Unknown`] when the table cannot tell
    /// within that (a warped or non-convex cell whose exit the records cannot name, too
    /// far): ask the locator.
    ///
    /// `tet` is a hint: the tetrahedron record where the last query from `c` found its
    /// point ([`TableWalk::Inside`]'s `tet`), or [`NO_TET`]. It changes how much is read,
    /// never the answer: the hinted tetrahedron alone is taken only where the point lies
    /// deeper inside it than its margin, where the search finds that tetrahedron too
    /// (tested bit for bit with and without hints).
    #[inline]
    pub fn walk(&self, c: u32, tet: u32, x: DVec3, hops: usize) -> TableWalk {
        match &self.values {
            None => self.view(Own).walk(c, tet, x, hops),
            Some(v) => self.view(&**v).walk(c, tet, x, hops),
        }
    }

    /// The queries' view of this table with the values `v`.
    #[inline(always)]
    fn view<V: Values>(&self, v: V) -> View<'_, V> {
        View {
            r: &self.r,
            tet_values: self.tet_values.as_deref(),
            v,
        }
    }

    /// Ask the processor to load cell `c`'s record; when `deep`, also its face records
    /// (addressed by the cell record, which should be in cache by then). No effect on
    /// results.
    #[inline]
    pub fn prefetch(&self, c: u32, deep: bool) {
        if let Some(v) = &self.values {
            Self::prefetch_values(v, Some(c), None);
        }
        let Some(rec) = self.r.cells.get(c as usize) else {
            return;
        };
        if !deep {
            crate::prefetch::lines(rec, 1);
            return;
        }
        if rec.simple != 0 {
            if let Some(f) = self.r.simple.get(rec.face as usize) {
                crate::prefetch::lines(
                    f,
                    (rec.n_faces as usize * size_of::<SimpleFace>()).div_ceil(64),
                );
            }
            return;
        }
        if let Some(f) = self.r.faces.get(rec.face as usize) {
            crate::prefetch::lines(
                f,
                (rec.n_faces as usize * size_of::<FaceRec>()).div_ceil(64),
            );
        }
    }

    /// Ask the processor to load tetrahedron record `tet` (a hint of [`CellTable::walk`]);
    /// false when there is no such record. No effect on results.
    #[inline(always)]
    pub fn prefetch_tet(&self, tet: u32) -> bool {
        if let Some(v) = &self.values {
            Self::prefetch_values(v, None, Some(tet));
        }
        match self.r.tets.get(tet as usize) {
            Some(t) => {
                crate::prefetch::lines(t, size_of::<TetRec>().div_ceil(64) + 1);
                true
            }
            None => false,
        }
    }

    /// Ask the processor to load the tetrahedron records [`CellTable::velocity_in`] reads
    /// for x in cell `c` (the cell and face records should be in cache). No effect on
    /// results.
    #[inline(always)]
    pub fn prefetch_at(&self, c: u32, x: DVec3) {
        let Some(rec) = self.r.cells.get(c as usize) else {
            return;
        };
        if rec.simple != 0 {
            // all a simple cell's records are its face records
            return;
        }
        let Some(faces) = self
            .r
            .faces
            .get(rec.face as usize..(rec.face + rec.n_faces) as usize)
        else {
            return;
        };
        if let Some((best, _)) = exit_face(faces, |f| f.q, x - rec.cc)
            && let Some(t) = self.r.tets.get(faces[best].tet as usize)
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

mod build;
mod query;
pub mod values;

use query::View;

#[cfg(test)]
mod tests;
