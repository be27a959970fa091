//! Another field's values on a table's records: [`CellTable::for_field`].
//!
//! The records of a [`CellTable`] are the mesh's geometry as the queries read it (centres,
//! exit ratios, the tetrahedra's inverse matrices, margins and links) with the values of
//! one field beside it (the cell value, the tetrahedra's node differences, the simple
//! cells' gradients). The snapshots of an unsteady series are fields on one mesh: each
//! keeps its own values ([`FieldValues`]: per cell its value and the differences at the
//! nodes of its tetrahedra, 0.36 kB of a hexahedron's 4.5; per simple face its gradient)
//! and shares the first snapshot's records, with a map from each tetrahedron to its
//! three nodes built once for them all (`NodeMap`, 0.35 kB per hexahedron).
//! A query reads the same records either way; only where the values come from differs
//! (`Values`), and they are computed with the same operations as the records' own, so a
//! table for a field answers bit for bit as a table built from scratch for it.

use std::sync::Arc;

use glam::DVec3;

use super::build::{
    face_tets, gradient_rows, huge_room, inverse_rows, node_difference, node_differences,
};
use super::{CellRec, CellTable, Records, SimpleFace, TetRec};
use crate::interp::Interpolator;

/// Where a query takes its values from: the records themselves ([`Own`]) or another
/// field's [`FieldValues`].
pub(super) trait Values: Copy {
    /// The value at cell `c`'s centre (`rec` its record).
    fn uc(self, c: u32, rec: &CellRec) -> DVec3;
    /// The node differences of tetrahedron record `k` (`t` the record).
    fn du(self, k: u32, t: &TetRec) -> [DVec3; 3];
    /// The gradient rows of simple face record `s` (`f` the record).
    fn g(self, s: usize, f: &SimpleFace) -> [DVec3; 3];
}

/// The values in the records (a table built for its own field).
#[derive(Clone, Copy)]
pub(super) struct Own;

impl Values for Own {
    #[inline(always)]
    fn uc(self, _: u32, rec: &CellRec) -> DVec3 {
        rec.uc
    }
    #[inline(always)]
    fn du(self, _: u32, t: &TetRec) -> [DVec3; 3] {
        t.du
    }
    #[inline(always)]
    fn g(self, _: usize, f: &SimpleFace) -> [DVec3; 3] {
        f.g
    }
}

/// The nodes of the general cells' tetrahedra, as [`FieldValues`] index them: the same
/// for every field on the records, so built once ([`Records::node_map`]).
#[derive(Debug, Default)]
pub(super) struct NodeMap {
    /// Per tetrahedron record: its three entries (of `node_ids`, and of every field's
    /// `node_du`).
    tet_nodes: Vec<[u32; 3]>,
    /// Per entry: the interpolator's node number.
    node_ids: Vec<u32>,
    /// Per cell: its first entry (and one past the last cell's).
    cell_first: Vec<u32>,
}

impl NodeMap {
    /// The map of the records `r` on `loc`'s mesh (the traversal of the records' build:
    /// each face's tetrahedra in order, a cell's nodes numbered as first met).
    fn new(r: &Records, loc: &crate::Locator<'_>) -> Option<NodeMap> {
        let (mesh, geom) = (loc.mesh(), loc.geometry());
        let np = mesh.points.len() as u32;
        // read at random by every step: on huge pages, as the records are
        let mut m = NodeMap {
            tet_nodes: huge_room(r.tets.len())?,
            node_ids: Vec::new(),
            cell_first: Vec::with_capacity(r.cells.len() + 1),
        };
        m.tet_nodes.resize(r.tets.len(), [u32::MAX; 3]);
        for (c, rec) in r.cells.iter().enumerate() {
            let first = m.node_ids.len();
            m.cell_first.push(first as u32);
            if rec.n_faces == 0 || rec.simple != 0 {
                continue;
            }
            for (k, &f) in geom.faces_of(c).iter().enumerate() {
                let fi = f as usize;
                let flip = mesh.owner[fi] as usize != c;
                let t0 = r.faces.get(rec.face as usize + k)?.tet as usize;
                for (i, nodes) in face_tets(mesh.face(fi), flip, np + f).enumerate() {
                    let entry = nodes.map(|n| {
                        let j = m.node_ids[first..]
                            .iter()
                            .position(|&q| q == n)
                            .unwrap_or_else(|| {
                                m.node_ids.push(n);
                                m.node_ids.len() - 1 - first
                            });
                        (first + j) as u32
                    });
                    *m.tet_nodes.get_mut(t0 + i)? = entry;
                }
            }
        }
        m.cell_first.push(m.node_ids.len() as u32);
        u32::try_from(m.node_ids.len()).ok()?;
        Some(m)
    }

    /// Bytes held.
    fn bytes(&self) -> usize {
        self.tet_nodes.len() * size_of::<[u32; 3]>()
            + (self.node_ids.len() + self.cell_first.len()) * size_of::<u32>()
    }
}

/// One field's values on another table's records, indexed as those records are.
#[derive(Debug, Default)]
pub struct FieldValues {
    /// Per cell record: the value at the centre.
    uc: Vec<DVec3>,
    /// Per entry of the records' [`NodeMap`]: the node's value minus its cell's (empty
    /// with the conservative scheme, whose tetrahedra answer their constant).
    node_du: Vec<DVec3>,
    /// The records' node map (shared by every field on them).
    map: Arc<NodeMap>,
    /// Per simple face record: the rows of the value's gradient.
    g: Vec<[DVec3; 3]>,
}

impl FieldValues {
    /// Bytes held (the node map, shared by every field on the records, not counted).
    pub fn bytes(&self) -> usize {
        (self.uc.len() + self.node_du.len()) * size_of::<DVec3>()
            + self.g.len() * size_of::<[DVec3; 3]>()
    }

    /// Bytes of the node map shared by every field on the records.
    pub fn shared_bytes(&self) -> usize {
        self.map.bytes()
    }
}

impl Values for &FieldValues {
    #[inline(always)]
    fn uc(self, c: u32, _: &CellRec) -> DVec3 {
        self.uc.get(c as usize).copied().unwrap_or(DVec3::NAN)
    }
    #[inline(always)]
    fn du(self, k: u32, _: &TetRec) -> [DVec3; 3] {
        let at = |i: u32| self.node_du.get(i as usize).copied().unwrap_or(DVec3::NAN);
        match self.map.tet_nodes.get(k as usize) {
            Some(&[a, b, c]) => [at(a), at(b), at(c)],
            None => [DVec3::NAN; 3],
        }
    }
    #[inline(always)]
    fn g(self, s: usize, _: &SimpleFace) -> [DVec3; 3] {
        self.g.get(s).copied().unwrap_or([DVec3::NAN; 3])
    }
}

impl CellTable {
    /// The table of `it`'s field on this table's records: `it` interpolates on the same
    /// mesh (the same locator's, or one equal to it) with the same scheme. It keeps only
    /// its values and answers every query bit for bit as [`CellTable::new`]`(it)` would.
    /// `None` when `it`'s mesh does not match the records (its cell count, or a
    /// conservative scheme on one side only).
    pub fn for_field(&self, it: &Interpolator<'_>) -> Option<CellTable> {
        let loc = it.locator();
        let (mesh, geom) = (loc.mesh(), loc.geometry());
        let r = &self.r;
        let tet_values = it.tet_velocities().map(|(v, _)| Arc::clone(v));
        if mesh.n_cells != r.cells.len() || tet_values.is_some() != self.tet_values.is_some() {
            return None;
        }
        // the node map serves the node differences, which the conservative scheme has not
        let map = match (r.node_map.get(), &tet_values) {
            (_, Some(_)) => Arc::new(NodeMap::default()),
            (Some(m), None) => Arc::clone(m),
            (None, None) => {
                let m = Arc::new(NodeMap::new(r, loc)?);
                Arc::clone(r.node_map.get_or_init(|| m))
            }
        };
        let (cellv, nodev) = (it.cell_values(), it.node_values());
        let np = mesh.points.len() as u32;
        // (empty with the conservative scheme's empty map)
        let mut node_du = huge_room(map.node_ids.len())?;
        for (c, w) in map.cell_first.windows(2).enumerate() {
            let uc = cellv[c];
            node_du.extend(
                map.node_ids[w[0] as usize..w[1] as usize]
                    .iter()
                    .map(|&n| node_difference(nodev, n, uc)),
            );
        }
        let mut g = vec![[DVec3::ZERO; 3]; r.simple.len()];
        for (c, rec) in r.cells.iter().enumerate() {
            if rec.n_faces == 0 || rec.simple == 0 {
                continue;
            }
            // one tetrahedron per face: its gradient, as the records were built
            let (cc, uc) = (geom.cell_centres[c], cellv[c]);
            for (k, &f) in geom.faces_of(c).iter().enumerate() {
                let fi = f as usize;
                let flip = mesh.owner[fi] as usize != c;
                let nodes = face_tets(mesh.face(fi), flip, np + f).next()?;
                let m = inverse_rows(nodes.map(|n| loc.node(n) - cc))?;
                let du = node_differences(nodev, nodes, uc);
                *g.get_mut(rec.face as usize + k)? = gradient_rows(&m, &du);
            }
        }
        let mut uc = huge_room(cellv.len())?;
        uc.extend_from_slice(cellv);
        let v = FieldValues {
            uc,
            node_du,
            map,
            g,
        };
        Some(CellTable {
            r: Arc::clone(&self.r),
            tet_values,
            values: Some(Arc::new(v)),
        })
    }

    /// Ask the processor to load this field's values of cell `c` (`tet`: also those of
    /// that tetrahedron record); no effect on results.
    #[inline(always)]
    pub(super) fn prefetch_values(v: &FieldValues, c: Option<u32>, tet: Option<u32>) {
        if let Some(u) = c.and_then(|c| v.uc.get(c as usize)) {
            crate::prefetch::lines(u, 1);
        }
        if let Some(n) = tet.and_then(|t| v.map.tet_nodes.get(t as usize)) {
            crate::prefetch::lines(n, 1);
        }
    }

    /// Ask the processor to load the node differences of tetrahedron record `tet` of this
    /// table's own values (a table of another field, [`CellTable::for_field`]; nothing for
    /// a table built for its field, whose records hold them). Reads the tetrahedron's
    /// entry of the values: call it after [`CellTable::prefetch_tet`] had time to load it.
    /// No effect on results.
    #[inline(always)]
    pub fn prefetch_tet_values(&self, tet: u32) {
        let Some(v) = &self.values else {
            return;
        };
        if let Some(&[a, b, c]) = v.map.tet_nodes.get(tet as usize) {
            for i in [a, b, c] {
                if let Some(d) = v.node_du.get(i as usize) {
                    crate::prefetch::lines(d, 1);
                }
            }
        }
    }

    /// A table of another field on shared records: the bytes it shares with every other
    /// such table (the tetrahedron-to-node map), not in [`CellTable::bytes`]; 0 otherwise.
    pub fn shared_bytes(&self) -> usize {
        self.values.as_ref().map_or(0, |v| v.shared_bytes())
    }

    /// True when this table and `other` read the same records (one built for the other's
    /// mesh with [`CellTable::for_field`], or both from one table).
    pub fn shares_records(&self, other: &CellTable) -> bool {
        Arc::ptr_eq(&self.r, &other.r)
    }
}
