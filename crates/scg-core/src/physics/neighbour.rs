//! Verlet neighbour list built by sorted-cell binning (pure).
//!
//! Two particles i, j are neighbours when their centre distance (minimum image in a
//! periodic box) is below r_i + r_j + skin. Particles are binned in cubic cells of edge
//! ≥ d_max + skin (d_max the largest diameter), so every neighbour of a particle lies in its
//! own cell or one of the 26 around it, whatever the size ratio. The particles are sorted by
//! cell once per build and a hash map gives each occupied cell's range, so memory and work
//! stay linear in N however far apart the particles are (no all-pairs fallback). Where the
//! particles fill their bounding box well enough, a dense grid replaces the hash map
//! ([`GridKind`]). The pair list is canonical: (i, j) with i < j, sorted, whichever grid
//! found it.
//!
//! The list is rebuilt only when some particle moved more than half the skin since the
//! last build (then no pair can have come into contact unseen).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;

use super::periodic::{PeriodicBox, separation};

/// A tiny deterministic hasher for integer cell keys (FxHash style).
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
    fn write_usize(&mut self, x: usize) {
        // Array length prefixes: one round, not one per byte.
        self.write_u64(x as u64);
    }
}

type CellMap = HashMap<[i64; 3], (u32, u32), BuildHasherDefault<CellHasher>>;

/// The cells a build binned the particles in (diagnostics; the pairs are the same).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GridKind {
    /// No build yet, or fewer than two particles.
    #[default]
    None,
    /// A dense grid over the bounding box, cells of edge ≥ the cut-off and at most about
    /// 4 per particle.
    Dense,
    /// A dense grid of cells much wider than the cut-off, about 4 per particle: a cloud
    /// spread evenly through a box much larger than the particles need (few particles in
    /// each cell, so few candidates each).
    Coarse,
    /// Cells of the cut-off's edge in a hash map, for particles too far apart or too
    /// clustered for a dense grid.
    Hashed,
}

/// The most a coarse grid may crowd its particles: Σ (particles per cell)² ≤ this × N,
/// i.e. a particle shares its cell with about this many others on average (an even cloud
/// on about 4 cells per particle: ≈ 1.25). More clustered clouds are hashed.
const COARSE_CROWDING: usize = 4;

/// The Verlet neighbour list.
#[derive(Clone, Debug, Default)]
pub struct NeighbourList {
    /// Skin distance, m.
    pub skin: f64,
    /// Periodic box, if any.
    pub periodic: Option<PeriodicBox>,
    /// Candidate pairs (i, j), i < j, sorted.
    pub pairs: Vec<[u32; 2]>,
    /// Positions at the last build.
    reference: Vec<DVec3>,
    /// Builds so far.
    pub builds: u64,
    /// Wall time spent in builds (diagnostics).
    pub build_time: std::time::Duration,
    /// Exact displacement checks so far (diagnostics).
    pub checks: u64,
    /// The cells the last build used (diagnostics).
    pub grid: GridKind,
    /// Upper bound on any particle's displacement since the last build, m.
    drift_bound: f64,
    // Scratch buffers kept between builds.
    order: Vec<([i64; 3], u32)>,
    cells: CellMap,
}

impl NeighbourList {
    /// An empty list with skin `skin` (m) and an optional periodic box.
    pub fn new(skin: f64, periodic: Option<PeriodicBox>) -> Self {
        NeighbourList {
            skin,
            periodic,
            ..Default::default()
        }
    }

    /// Positions at the last build (m) and the displacement bound since (m), for
    /// checkpoints.
    pub fn carried(&self) -> (&[DVec3], f64) {
        (&self.reference, self.drift_bound)
    }

    /// Restore a list saved by a checkpoint: its pairs, reference positions, counters and
    /// displacement bound.
    pub fn restore(
        &mut self,
        pairs: Vec<[u32; 2]>,
        reference: Vec<DVec3>,
        builds: u64,
        checks: u64,
        drift_bound: f64,
    ) {
        self.pairs = pairs;
        self.reference = reference;
        self.builds = builds;
        self.checks = checks;
        self.drift_bound = drift_bound;
    }

    /// True when the particle count changed or some particle moved more than skin/2
    /// since the last build.
    ///
    /// `drift` is an upper bound on how far any particle moved since the previous call
    /// (m), when the caller knows one (e.g. the integrator's largest step displacement);
    /// `None` means unknown. The exact check, a pass over every particle, runs only when
    /// the accumulated bound exceeds skin/2; it then replaces the bound with the exact
    /// largest displacement.
    pub fn needs_rebuild(&mut self, pos: &[DVec3], drift: Option<f64>) -> bool {
        self.needs_rebuild_of(pos, pos.len(), drift)
    }

    /// [`NeighbourList::needs_rebuild`] for a list over `rows` particles of which `pos`
    /// are the first: the others' displacement is someone else's to check (the ghost rows
    /// of a decomposed run, checked by the processes that own them).
    pub fn needs_rebuild_of(&mut self, pos: &[DVec3], rows: usize, drift: Option<f64>) -> bool {
        if rows != self.reference.len() || pos.len() > rows || self.builds == 0 {
            return true;
        }
        self.drift_bound += drift.unwrap_or(f64::INFINITY);
        let half = 0.5 * self.skin;
        if self.drift_bound <= half {
            return false;
        }
        self.checks += 1;
        let d2 = crate::exec::par::par_max_zip(pos, &self.reference[..pos.len()], |x, r| {
            (*x - *r).length_squared()
        });
        // A NaN displacement (non-finite state) also rebuilds.
        if d2.is_nan() || d2 > half * half {
            return true;
        }
        self.drift_bound = d2.sqrt();
        false
    }

    /// Rebuild if needed (see [`NeighbourList::needs_rebuild`]); returns true when it
    /// rebuilt.
    pub fn update(&mut self, pos: &[DVec3], radius: &[f64], drift: Option<f64>) -> bool {
        if self.needs_rebuild(pos, drift) {
            self.build(pos, radius);
            true
        } else {
            false
        }
    }

    /// Rebuild the list now from positions and radii (m).
    pub fn build(&mut self, pos: &[DVec3], radius: &[f64]) {
        let t0 = std::time::Instant::now();
        self.build_pairs(pos, radius);
        self.build_time += t0.elapsed();
    }

    fn build_pairs(&mut self, pos: &[DVec3], radius: &[f64]) {
        assert_eq!(pos.len(), radius.len());
        self.builds += 1;
        self.drift_bound = 0.0;
        self.reference.clear();
        self.reference.extend_from_slice(pos);
        self.pairs.clear();
        self.grid = GridKind::None;
        let n = pos.len();
        if n < 2 {
            return;
        }
        let rmax = radius.iter().copied().fold(0.0_f64, f64::max);
        let min_cell = (2.0 * rmax + self.skin).max(f64::MIN_POSITIVE);
        if let Some((pairs, kind)) = self.dense_grid_pairs(pos, radius, min_cell) {
            self.pairs = pairs;
            self.grid = kind;
            return;
        }
        self.grid = GridKind::Hashed;
        // Cells: edge per axis, count per axis (periodic only).
        let (edge, dims) = match self.periodic {
            Some(b) => {
                let dims = (b.lengths / min_cell).floor().max(DVec3::ONE);
                (
                    b.lengths / dims,
                    Some([dims.x as i64, dims.y as i64, dims.z as i64]),
                )
            }
            None => (DVec3::splat(min_cell), None),
        };
        let cell_of = |x: DVec3| -> [i64; 3] {
            let x = match self.periodic {
                Some(b) => b.wrap(x),
                None => x,
            };
            let c = (x / edge).floor();
            let mut k = [c.x as i64, c.y as i64, c.z as i64];
            if let Some(d) = dims {
                for a in 0..3 {
                    k[a] = k[a].clamp(0, d[a] - 1);
                }
            }
            k
        };
        self.order.clear();
        self.order
            .extend(pos.iter().enumerate().map(|(i, x)| (cell_of(*x), i as u32)));
        self.order.sort_unstable();
        self.cells.clear();
        let mut start = 0;
        for k in 1..=n {
            if k == n || self.order[k].0 != self.order[start].0 {
                self.cells
                    .insert(self.order[start].0, (start as u32, k as u32));
                start = k;
            }
        }
        let periodic = self.periodic;
        // With fewer than three cells along an axis the 27 neighbours repeat: dedup then.
        let repeats = dims.is_some_and(|d| d.iter().any(|&k| k < 3));
        let (cells, order, skin) = (&self.cells, &self.order, self.skin);
        // Centres, radii and indices in cell order, so that a cell's particles are read
        // together.
        let body: Vec<(DVec3, f64, u32)> = order
            .iter()
            .map(|&(_, j)| (pos[j as usize], radius[j as usize], j))
            .collect();
        // The pairs of the particles in slots [lo, hi) of the cell order, listed particle by
        // particle (each one's j ascending); the 27 look-ups are made once per cell.
        let pairs_of = |lo: usize, hi: usize| -> Vec<[u32; 2]> {
            let mut out = Vec::new();
            let mut neighbour_cells: Vec<[i64; 3]> = Vec::with_capacity(27);
            let mut ranges: Vec<(u32, u32)> = Vec::with_capacity(27);
            let mut current: Option<[i64; 3]> = None;
            let mut cand: Vec<u32> = Vec::new();
            for s in lo..hi {
                let c = order[s].0;
                if current != Some(c) {
                    current = Some(c);
                    neighbour_cells.clear();
                    for dx in -1..=1 {
                        for dy in -1..=1 {
                            for dz in -1..=1 {
                                let mut k = [c[0] + dx, c[1] + dy, c[2] + dz];
                                if let Some(d) = dims {
                                    for a in 0..3 {
                                        k[a] = k[a].rem_euclid(d[a]);
                                    }
                                }
                                neighbour_cells.push(k);
                            }
                        }
                    }
                    if repeats {
                        neighbour_cells.sort_unstable();
                        neighbour_cells.dedup();
                    }
                    ranges.clear();
                    ranges.extend(neighbour_cells.iter().filter_map(|k| cells.get(k).copied()));
                }
                let (xi, ri, i) = body[s];
                cand.clear();
                for &(a, b) in &ranges {
                    for &(xj, rj, j) in &body[a as usize..b as usize] {
                        if j <= i {
                            continue;
                        }
                        let d = separation(xi, xj, periodic.as_ref());
                        let cut = ri + rj + skin;
                        if d.length_squared() < cut * cut {
                            cand.push(j);
                        }
                    }
                }
                cand.sort_unstable();
                out.extend(cand.iter().map(|&j| [i, j]));
            }
            out
        };
        self.pairs = by_first(&in_blocks(n, pairs_of), n);
    }

    /// The pairs found through a dense grid of cells over the particles' bounding box
    /// (or the periodic box), or `None` when such a grid would be too large, or too coarse
    /// for how the particles cluster: then the hashed cells are used.
    ///
    /// Cells have an edge of `min_cell` (the largest cut-off), or larger in a dilute cloud
    /// so that there are at most about 4 cells per particle. Particles are counting-sorted by cell
    /// (stable, so each cell lists its particles in index order), and, taken in that order,
    /// every particle scans the cells around its own by direct indexing. Cells wider than 4 cut-offs are kept
    /// only when they crowd the particles no more than [`COARSE_CROWDING`] allows: an even
    /// cloud in a large box, not far-apart clusters. (Hashed, such a cloud cost 27 hash
    /// look-ups per particle, mostly of empty cells: 7 s a build for 2·10^6 particles of
    /// 100 µm in a cubic metre, 0.5 s on the coarse grid.)
    fn dense_grid_pairs(
        &self,
        pos: &[DVec3],
        radius: &[f64],
        min_cell: f64,
    ) -> Option<(Vec<[u32; 2]>, GridKind)> {
        let n = pos.len();
        // A hair wider than the cut-off, so rounding in the cell coordinates can never put
        // two particles closer than the cut-off two cells apart.
        let min_cell = min_cell * (1.0 + 1e-9);
        let (lo, extent) = match self.periodic {
            Some(b) => (DVec3::ZERO, b.lengths),
            None => {
                let (mut lo, mut hi) = (pos[0], pos[0]);
                for x in pos {
                    lo = lo.min(*x);
                    hi = hi.max(*x);
                }
                (lo, hi - lo)
            }
        };
        if !extent.is_finite() {
            return None;
        }
        // Cells as small as the cut-off allows (few candidates per particle even where the
        // particles crowd, e.g. against a wall), but at most about 4 per particle so a
        // dilute cloud does not get a huge grid: edge ≥ (volume / 4·N)^(1/3), the volume
        // the particles occupy (in a periodic box, whose grid tiles the whole box, the
        // slices of it they occupy: a rank of a decomposed run holds one region of it,
        // and cells sized by the whole box would hold twice the candidates on 2 ranks).
        let volume = match self.periodic {
            Some(b) => occupied_volume(pos, &b).max(min_cell.powi(3)),
            None => extent.x.max(min_cell) * extent.y.max(min_cell) * extent.z.max(min_cell),
        };
        let edge_target = min_cell.max((volume / (4.0 * n as f64)).cbrt());
        // Much wider than the cut-off: an even cloud in a large box, or far-apart clusters
        // (told apart below, by how many particles share a cell).
        let coarse = edge_target > 4.0 * min_cell;
        let (edge, dims) = match self.periodic {
            Some(_) => {
                let d = (extent / edge_target).floor().max(DVec3::ONE);
                (extent / d, d)
            }
            None => (
                DVec3::splat(edge_target),
                (extent / edge_target).floor() + DVec3::ONE,
            ),
        };
        let cells = dims.x * dims.y * dims.z;
        if cells > (64 * n + 4096) as f64 {
            return None;
        }
        let dims = [dims.x as i64, dims.y as i64, dims.z as i64];
        let periodic = self.periodic;
        let inv_edge = edge.recip();
        let coord = |x: DVec3| -> [i64; 3] {
            let x = match periodic {
                Some(b) => b.wrap(x),
                None => x - lo,
            };
            let c = (x * inv_edge).floor();
            [
                (c.x as i64).clamp(0, dims[0] - 1),
                (c.y as i64).clamp(0, dims[1] - 1),
                (c.z as i64).clamp(0, dims[2] - 1),
            ]
        };
        let linear = |c: [i64; 3]| ((c[2] * dims[1] + c[1]) * dims[0] + c[0]) as usize;
        // Counting sort by cell: start[c]..start[c + 1] are the slots of cell c in `sorted`.
        let cell: Vec<u32> = pos.iter().map(|x| linear(coord(*x)) as u32).collect();
        let mut start = vec![0u32; cells as usize + 1];
        for &c in &cell {
            start[c as usize + 1] += 1;
        }
        if coarse {
            let crowding = start
                .iter()
                .map(|&k| k as usize * k as usize)
                .sum::<usize>();
            if crowding > COARSE_CROWDING * n {
                return None;
            }
        }
        for k in 1..start.len() {
            start[k] += start[k - 1];
        }
        let mut fill = start.clone();
        let mut sorted = vec![0u32; n];
        for (i, &c) in cell.iter().enumerate() {
            sorted[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        drop(fill);
        // Centres, radii and indices in cell order: a cell's particles are contiguous, and
        // so are the cells of a row, so the scan below reads memory mostly in sequence.
        let body: Vec<(DVec3, f64, u32)> = sorted
            .iter()
            .map(|&j| (pos[j as usize], radius[j as usize], j))
            .collect();
        let skin = self.skin;
        // Neighbour coordinates along one axis: i−1, i, i+1, wrapped (periodic) or cut at
        // the grid's faces, without repeats when the axis has fewer than three cells.
        let around = |i: i64, d: i64, out: &mut [i64; 3]| -> usize {
            let mut m = 0;
            for k in [i - 1, i, i + 1] {
                // i is in [0, d): one wrap at most (no integer division).
                let k = if periodic.is_some() {
                    if k < 0 {
                        k + d
                    } else if k >= d {
                        k - d
                    } else {
                        k
                    }
                } else if k < 0 || k >= d {
                    continue;
                } else {
                    k
                };
                if !out[..m].contains(&k) {
                    out[m] = k;
                    m += 1;
                }
            }
            m
        };
        let pairs_of = |lo_i: usize, hi_i: usize| -> Vec<[u32; 2]> {
            let mut out = Vec::new();
            let mut cand: Vec<u32> = Vec::new();
            let (mut xs, mut ys, mut zs) = ([0i64; 3], [0i64; 3], [0i64; 3]);
            for s in lo_i..hi_i {
                // In cell order: the cells around consecutive particles are the same or
                // next in memory (in index order, particles placed at random or fed over
                // time missed the cache on every row of cells around them).
                let (xi, ri, i) = body[s];
                let (i, c) = (i as usize, coord(xi));
                let nx = around(c[0], dims[0], &mut xs);
                let ny = around(c[1], dims[1], &mut ys);
                let nz = around(c[2], dims[2], &mut zs);
                cand.clear();
                for &z in &zs[..nz] {
                    for &y in &ys[..ny] {
                        for &x in &xs[..nx] {
                            let k = linear([x, y, z]);
                            let (a, b) = (start[k] as usize, start[k + 1] as usize);
                            for &(xj, rj, j) in &body[a..b] {
                                if (j as usize) <= i {
                                    continue;
                                }
                                let d = separation(xi, xj, periodic.as_ref());
                                let cut = ri + rj + skin;
                                if d.length_squared() < cut * cut {
                                    cand.push(j);
                                }
                            }
                        }
                    }
                }
                cand.sort_unstable();
                out.extend(cand.iter().map(|&j| [i as u32, j]));
            }
            out
        };
        let kind = if coarse {
            GridKind::Coarse
        } else {
            GridKind::Dense
        };
        Some((by_first(&in_blocks(n, pairs_of), n), kind))
    }
}

/// Slices a periodic box's grid is not wasted on: per axis the share of 64 slices that
/// hold a particle (wrapped), the box's volume times the three shares, m³.
fn occupied_volume(pos: &[DVec3], b: &PeriodicBox) -> f64 {
    const SLICES: usize = 64;
    let mut hit = [[false; SLICES]; 3];
    let scale = DVec3::splat(SLICES as f64) / b.lengths;
    for x in pos {
        let k = (b.wrap(*x) * scale).floor();
        for a in 0..3 {
            if k[a].is_finite() {
                hit[a][(k[a] as usize).min(SLICES - 1)] = true;
            }
        }
    }
    (0..3)
        .map(|a| {
            let occupied = hit[a].iter().filter(|&&h| h).count().max(1);
            b.lengths[a] * occupied as f64 / SLICES as f64
        })
        .product()
}

/// Pairs listed particle by particle (each particle's pairs together, its j ascending), in
/// the canonical order: by i, then j (a stable counting sort by i).
fn by_first(pairs: &[[u32; 2]], n: usize) -> Vec<[u32; 2]> {
    let mut at = vec![0u32; n + 1];
    for p in pairs {
        at[p[0] as usize + 1] += 1;
    }
    for k in 1..at.len() {
        at[k] += at[k - 1];
    }
    let mut out = vec![[0u32; 2]; pairs.len()];
    for p in pairs {
        let k = &mut at[p[0] as usize];
        out[*k as usize] = *p;
        *k += 1;
    }
    out
}

/// `pairs_of(lo, hi)` over blocks of the `n` particles (slots of the cell order), in
/// parallel, concatenated in block order: the list is the same whatever the thread count.
fn in_blocks(n: usize, pairs_of: impl Fn(usize, usize) -> Vec<[u32; 2]> + Sync) -> Vec<[u32; 2]> {
    const BLOCK: usize = 1024;
    if n <= 2 * BLOCK {
        return pairs_of(0, n);
    }
    let mut blocks: Vec<Vec<[u32; 2]>> = vec![Vec::new(); n.div_ceil(BLOCK)];
    crate::exec::team::for_each_item(&mut blocks, |k, out| {
        *out = pairs_of(k * BLOCK, ((k + 1) * BLOCK).min(n));
    });
    let mut out = Vec::with_capacity(blocks.iter().map(Vec::len).sum());
    for b in blocks {
        out.extend_from_slice(&b);
    }
    out
}

/// All pairs (i < j, sorted) with centre distance below r_i + r_j + skin, by the O(N²)
/// search (reference for tests).
pub fn brute_force_pairs(
    pos: &[DVec3],
    radius: &[f64],
    skin: f64,
    periodic: Option<&PeriodicBox>,
) -> Vec<[u32; 2]> {
    let mut out = Vec::new();
    for i in 0..pos.len() {
        for j in i + 1..pos.len() {
            let d = separation(pos[i], pos[j], periodic);
            let cut = radius[i] + radius[j] + skin;
            if d.length_squared() < cut * cut {
                out.push([i as u32, j as u32]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
