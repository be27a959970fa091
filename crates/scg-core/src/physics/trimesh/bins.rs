//! The bin grid of a triangle mesh: which triangles may pass through each cell, how far
//! each cell is from the nearest triangle (coarse and fine clearance bounds), and the
//! compressed lists (CSR) the mesh's topology uses too.

use glam::DVec3;

use super::closest_point_on_triangle;

/// Compressed lists: the items of key `k` are `items[start[k]..start[k + 1]]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Csr {
    pub(super) start: Vec<u32>,
    pub(super) items: Vec<u32>,
}

impl Csr {
    /// Build from (key, item) pairs, keys in `0..keys`, items kept in pair order per key.
    pub(super) fn build(keys: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Csr {
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
    pub(super) fn get(&self, k: usize) -> &[u32] {
        &self.items[self.start[k] as usize..self.start[k + 1] as usize]
    }
}

/// A uniform grid over the mesh bounds; each cell lists the triangles that may pass
/// through it, and how far (in cells) it is from the nearest non-empty cell.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct BinGrid {
    /// Lower corner, m.
    pub(super) origin: DVec3,
    /// Cell edge, m, and its inverse, 1/m.
    pub(super) h: f64,
    pub(super) inv_h: f64,
    /// Cells per axis (also as floats).
    pub(super) dims: [usize; 3],
    pub(super) dims_f: DVec3,
    /// Triangles per cell.
    pub(super) cells: Csr,
    /// Chebyshev distance in cells to the nearest non-empty cell (0 = non-empty),
    /// saturated at `u16::MAX`.
    pub(super) reach: Vec<u16>,
    /// A lower bound of the distance from each cell's centre to the mesh, m (exact, then
    /// rounded down to f32, within [`NEAR`] cells of a triangle's box; `NEAR`·h beyond).
    pub(super) centre_clear: Vec<f32>,
    /// Coarse cells of `COARSE`³ cells (a few kilobytes, so that the clearance test of a
    /// particle far from the mesh touches little memory): cells per axis, and a lower
    /// bound of the distance from each coarse centre to the mesh, m.
    pub(super) coarse_dims: [usize; 3],
    pub(super) coarse_clear: Vec<f32>,
}

/// Cells per coarse cell and axis.
pub(super) const COARSE: usize = 4;

/// `d` rounded down to f32, less a relative 1e-9 for the rounding of distances.
pub(super) fn down(d: f64) -> f32 {
    let d = d * (1.0 - 1e-9);
    let f = d as f32;
    if f as f64 > d { f.next_down() } else { f }
}

/// Cells around each triangle's box where the centre distance is computed exactly.
pub(super) const NEAR: usize = 2;

/// Most cells a grid may have.
pub(super) const MAX_CELLS: usize = 1 << 22;

impl BinGrid {
    pub(super) fn build(vertices: &[DVec3], triangles: &[[u32; 3]]) -> BinGrid {
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
    pub(super) fn upper(&self) -> DVec3 {
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
    pub(super) fn range(&self, lo: DVec3, hi: DVec3) -> Option<([usize; 3], [usize; 3])> {
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
