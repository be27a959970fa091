//! The near-wall velocity a particle sees in a wall-adjacent cell of a RANS flow computed
//! with wall functions: the log law of the wall, as the CFD's wall function assumed it.
//!
//! A RANS case with wall functions (OpenFOAM's `nutkWallFunction`, y⁺ ≫ 1 in the first
//! cell) carries in the wall-adjacent cell the velocity at its centre, at y_c from the
//! wall; between that centre and the wall the flow follows the log law, which the solver
//! used to set the wall shear stress. Interpolating linearly from the centre to the
//! no-slip wall's zero instead puts a slow layer a cell thick next to every wall (at
//! y⁺ ≈ 450 in the coarse cyclone, ≈ 0.5 m/s at 1 mm where the log law gives ≈ 6 m/s),
//! in which particles pile up.
//!
//! [`LogLaw`]: u⁺ = y⁺ below y⁺_lam, (1/κ)·ln(E·y⁺) above, with OpenFOAM's constants
//! (κ = 0.41, E = 9.8, C_μ = 0.09; y⁺_lam = 11.53 where the two meet). The friction
//! velocity is u_τ = C_μ^¼·√k of the wall cell (`nutkWallFunction`'s) when the cell's k
//! is known, else the one the log law gives for the cell's own tangential speed at y_c
//! ([`LogLaw::friction_velocity`]).
//!
//! [`WallCells`] holds, for every cell with a face on a wall patch, each wall face's plane,
//! the centre's distance y_c and u_τ. For a point x at distance y < y_c from the nearest
//! of its cell's wall planes, [`WallCells::apply`] keeps the normal component of the
//! interpolated velocity at x and takes the cell's own tangential velocity scaled by
//! u⁺(y⁺)/u⁺(y⁺_c): the log law from the cell centre to the wall, as the CFD's wall
//! function relates each wall face to its owner cell's velocity (zero at the wall; at
//! y = y_c it meets the interpolation up to the interpolation's own deviation from the
//! cell value there, a few per cent). The wall
//! patches' face values are the slip values (the owner's velocity less its normal
//! component; [`slip_wall_values`]), so that the interpolation itself does not ramp to
//! zero. Lengths in m, velocities in m/s, ν in m²/s.

use glam::DVec3;
use scg_mesh::{CellField, MeshGeometry, PolyMesh};

/// The log law of the wall (OpenFOAM's wall-function constants by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLaw {
    /// von Kármán constant κ.
    pub kappa: f64,
    /// Roughness parameter E (9.8 for a smooth wall).
    pub e: f64,
    /// C_μ of the k–ε family (u_τ = C_μ^¼·√k).
    pub c_mu: f64,
}

impl Default for LogLaw {
    fn default() -> Self {
        LogLaw {
            kappa: 0.41,
            e: 9.8,
            c_mu: 0.09,
        }
    }
}

impl LogLaw {
    /// y⁺ where the viscous sublayer u⁺ = y⁺ meets the log law (OpenFOAM's `yPlusLam`:
    /// eleven fixed-point iterations of y = ln(E·y)/κ from 11), 11.53 for the defaults.
    pub fn y_plus_lam(&self) -> f64 {
        let mut y = 11.0;
        for _ in 0..10 {
            y = (self.e * y).max(1.0).ln() / self.kappa;
        }
        y
    }

    /// u⁺(y⁺): y⁺ in the viscous sublayer (below [`LogLaw::y_plus_lam`]), (1/κ)·ln(E·y⁺)
    /// above; 0 for y⁺ ≤ 0.
    pub fn u_plus(&self, y_plus: f64, y_plus_lam: f64) -> f64 {
        if y_plus <= 0.0 {
            0.0
        } else if y_plus < y_plus_lam {
            y_plus
        } else {
            (self.e * y_plus).ln() / self.kappa
        }
    }

    /// u_τ = C_μ^¼·√k (m/s), the friction velocity of `nutkWallFunction`.
    pub fn friction_velocity_from_k(&self, k: f64) -> f64 {
        self.c_mu.powf(0.25) * k.max(0.0).sqrt()
    }

    /// The u_τ (m/s) for which the law gives tangential speed `u` at distance `y` from the
    /// wall, viscosity `nu`: u = u_τ·u⁺(y·u_τ/ν), solved by bisection on u_τ (the
    /// right-hand side increases with u_τ). 0 for u ≤ 0.
    pub fn friction_velocity(&self, u: f64, y: f64, nu: f64) -> f64 {
        if !(u > 0.0 && y > 0.0 && nu > 0.0) {
            return 0.0;
        }
        let lam = self.y_plus_lam();
        let speed = |ut: f64| ut * self.u_plus(y * ut / nu, lam);
        // bracket: u_τ = u gives u⁺ ≥ 1 at y⁺ ≥ 1 or is small enough to scale up
        let (mut lo, mut hi) = (0.0, u.max(nu / y));
        while speed(hi) < u {
            hi *= 2.0;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if speed(mid) < u {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-15 * hi {
                break;
            }
        }
        0.5 * (lo + hi)
    }
}

/// One wall face of a wall-adjacent cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallPlane {
    /// A point of the face (its centre), m.
    pub point: DVec3,
    /// Unit normal out of the fluid.
    pub normal: DVec3,
    /// Distance of the cell centre from the face's plane, m (> 0).
    pub y_c: f64,
    /// Friction velocity, m/s.
    pub u_tau: f64,
    /// u⁺ at the cell centre.
    pub u_plus_c: f64,
    /// The cell's velocity less its normal component, m/s.
    pub u_t: DVec3,
}

/// The wall faces of every wall-adjacent cell (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct WallCells {
    law: LogLaw,
    y_plus_lam: f64,
    nu: f64,
    /// Offsets into `planes`, one per cell plus one.
    offsets: Vec<u32>,
    planes: Vec<WallPlane>,
}

/// Where u_τ comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum FrictionVelocity {
    /// u_τ = C_μ^¼·√k with k per cell (m²/s²).
    FromK(Vec<f64>),
    /// The log law solved for the cell's tangential speed at its centre.
    FromVelocity,
}

impl WallCells {
    /// The wall faces of `mesh` (geometry `geom`) on the patches where `wall[p]` holds,
    /// with u_τ from `friction` and the cell values of `field`; `nu` the kinematic
    /// viscosity (m²/s). A face whose owner's centre is not inside its plane (a degenerate
    /// face) is skipped.
    pub fn new(
        mesh: &PolyMesh,
        geom: &MeshGeometry,
        field: &CellField,
        wall: &[bool],
        law: LogLaw,
        nu: f64,
        friction: &FrictionVelocity,
    ) -> Self {
        let lam = law.y_plus_lam();
        let mut by_cell: Vec<(u32, WallPlane)> = Vec::new();
        for (p, patch) in mesh.patches.iter().enumerate() {
            if !wall.get(p).copied().unwrap_or(false) {
                continue;
            }
            for f in patch.start..patch.start + patch.size {
                let c = mesh.owner[f];
                let normal = geom.face_areas[f].normalize_or_zero();
                let point = geom.face_centres[f];
                let cc = geom.cell_centres[c as usize];
                let y_c = (point - cc).dot(normal);
                if !(y_c > 0.0 && normal != DVec3::ZERO) {
                    continue;
                }
                let uc = field.cells[c as usize];
                let ut = uc - uc.dot(normal) * normal;
                let u_tau = match friction {
                    FrictionVelocity::FromK(k) => {
                        law.friction_velocity_from_k(k.get(c as usize).copied().unwrap_or(0.0))
                    }
                    FrictionVelocity::FromVelocity => law.friction_velocity(ut.length(), y_c, nu),
                };
                let u_plus_c = law.u_plus(y_c * u_tau / nu, lam);
                by_cell.push((
                    c,
                    WallPlane {
                        point,
                        normal,
                        y_c,
                        u_tau,
                        u_plus_c,
                        u_t: ut,
                    },
                ));
            }
        }
        by_cell.sort_by_key(|(c, _)| *c);
        let mut offsets = vec![0u32; mesh.n_cells + 1];
        for (c, _) in &by_cell {
            offsets[*c as usize + 1] += 1;
        }
        for i in 0..mesh.n_cells {
            offsets[i + 1] += offsets[i];
        }
        WallCells {
            law,
            y_plus_lam: lam,
            nu,
            offsets,
            planes: by_cell.into_iter().map(|(_, w)| w).collect(),
        }
    }

    /// The law.
    pub fn law(&self) -> LogLaw {
        self.law
    }

    /// Wall-adjacent cells, and wall faces.
    pub fn counts(&self) -> (usize, usize) {
        let cells = self.offsets.windows(2).filter(|w| w[1] > w[0]).count();
        (cells, self.planes.len())
    }

    /// The wall faces of cell `c` (empty for a cell off the walls or out of range).
    #[inline]
    pub fn planes(&self, c: u32) -> &[WallPlane] {
        let c = c as usize;
        match (self.offsets.get(c), self.offsets.get(c + 1)) {
            (Some(&a), Some(&b)) => &self.planes[a as usize..b as usize],
            _ => &[],
        }
    }

    /// y⁺ of the cell centres: (smallest, median, largest) over the wall faces.
    pub fn y_plus_range(&self) -> Option<(f64, f64, f64)> {
        let mut y: Vec<f64> = self
            .planes
            .iter()
            .map(|w| w.y_c * w.u_tau / self.nu)
            .collect();
        if y.is_empty() {
            return None;
        }
        y.sort_by(f64::total_cmp);
        Some((y[0], y[y.len() / 2], y[y.len() - 1]))
    }

    /// The nearest wall plane of cell `c` to x when x is closer to it than the cell
    /// centre, with the distance y (m; < y_c, clamped at 0).
    #[inline]
    pub fn nearest(&self, c: u32, x: DVec3) -> Option<(WallPlane, f64)> {
        let mut best: Option<(WallPlane, f64)> = None;
        for w in self.planes(c) {
            let y = (w.point - x).dot(w.normal);
            if y < w.y_c && best.is_none_or(|(_, b)| y < b) {
                best = Some((*w, y.max(0.0)));
            }
        }
        best
    }

    /// The velocity at x (m/s), in cell `c`, from the interpolated velocity `u` at x:
    /// unchanged off the walls and beyond the cell centre's distance; nearer the wall,
    /// `u`'s normal component and the log law's share u⁺(y⁺)/u⁺(y⁺_c) of the cell's own
    /// tangential velocity (see the module documentation).
    #[inline]
    pub fn apply(&self, c: u32, x: DVec3, u: DVec3) -> DVec3 {
        match self.nearest(c, x) {
            None => u,
            Some((w, y)) => self.log_profile(&w, y, u),
        }
    }

    #[inline(never)]
    fn log_profile(&self, w: &WallPlane, y: f64, u: DVec3) -> DVec3 {
        let n = w.normal;
        let share = if w.u_plus_c > 0.0 {
            self.law.u_plus(y * w.u_tau / self.nu, self.y_plus_lam) / w.u_plus_c
        } else {
            0.0
        };
        u.dot(n) * n + share * w.u_t
    }
}

/// `field` with the slip value on every face of the patches where `wall[p]` holds: the
/// owner cell's velocity less its component along the face normal (what a wall function
/// leaves of the no-slip condition for the interpolation to see).
pub fn slip_wall_values(
    mesh: &PolyMesh,
    geom: &MeshGeometry,
    field: &CellField,
    wall: &[bool],
) -> CellField {
    let mut out = field.clone();
    if out.patches.len() != mesh.patches.len() {
        out.patches = vec![None; mesh.patches.len()];
    }
    for (p, patch) in mesh.patches.iter().enumerate() {
        if !wall.get(p).copied().unwrap_or(false) {
            continue;
        }
        let vals = (patch.start..patch.start + patch.size)
            .map(|f| {
                let n = geom.face_areas[f].normalize_or_zero();
                let u = field.cells[mesh.owner[f] as usize];
                u - u.dot(n) * n
            })
            .collect();
        out.patches[p] = Some(vals);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_law_constants_and_inverse() {
        let law = LogLaw::default();
        let lam = law.y_plus_lam();
        assert!((lam - 11.53).abs() < 0.01, "{lam}");
        // continuous where the sublayer meets the log law
        let below = law.u_plus(lam * (1.0 - 1e-12), lam);
        let above = law.u_plus(lam, lam);
        assert!((below - above).abs() < 1e-6, "{below} {above}");
        assert_eq!(law.u_plus(5.0, lam), 5.0);
        assert!((law.u_plus(100.0, lam) - (980.0f64).ln() / 0.41).abs() < 1e-12);
        // the inverse recovers u_τ in the log region and in the sublayer
        let nu = 1.5e-5;
        for (ut, y) in [(0.5, 0.015), (0.5, 1e-4), (2.0, 0.03), (0.01, 1e-3)] {
            let lam = law.y_plus_lam();
            let u = ut * law.u_plus(y * ut / nu, lam);
            let got = law.friction_velocity(u, y, nu);
            assert!((got - ut).abs() < 1e-9 * ut, "{ut} {y}: {got}");
        }
        assert_eq!(law.friction_velocity(0.0, 0.01, nu), 0.0);
        assert!((law.friction_velocity_from_k(1.0) - 0.09f64.sqrt().sqrt()).abs() < 1e-15);
    }
}
