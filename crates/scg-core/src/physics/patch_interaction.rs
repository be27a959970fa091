//! What a particle whose centre reaches a boundary patch of a mesh flow does: the patch
//! interaction models (OpenFOAM's `localInteraction`: rebound, stick, escape), the impulse
//! rebound with restitution and Coulomb friction, and the cell-hint markers a departure
//! leaves for the boundary stage. Pure functions; [`super::mesh_flow::land`] applies them.

use glam::DVec3;
use serde::Deserialize;

/// What a particle whose centre reaches a boundary patch does: the patch interaction
/// models of OpenFOAM's `localInteraction` (rebound, stick, escape), one per patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PatchInteraction {
    /// Rebounds as an impulse ([`rebound_velocity`]): normal restitution `e` and friction
    /// `mu` under the rule `friction`; the centre is mirrored back inside, never crossing
    /// the wall.
    Rebound {
        /// Normal restitution, v_n' = −e·v_n, in [0, 1].
        e: f64,
        /// Friction coefficient, ≥ 0 (its meaning is `friction`'s).
        mu: f64,
        /// What `mu` does to the tangential velocity.
        friction: WallFriction,
    },
    /// Sticks (deposits): removed from the flow and counted as stuck on the patch.
    Stick,
    /// Escapes: removed and counted as escaped through the patch (an outlet drains).
    Escape,
}

impl PatchInteraction {
    /// A rebound without friction, restitution `e` (the contact law's guard, the mirror of
    /// a constraint patch).
    pub const fn frictionless(e: f64) -> Self {
        PatchInteraction::Rebound {
            e,
            mu: 0.0,
            friction: WallFriction::Coulomb,
        }
    }

    /// Name used in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            PatchInteraction::Rebound { .. } => "rebound",
            PatchInteraction::Stick => "stick",
            PatchInteraction::Escape => "escape",
        }
    }
}

/// The tangential rule of a rebound: what its friction coefficient μ means (scene files
/// name it: `friction_model = "coulomb" | "openfoam_fraction"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallFriction {
    /// The rigid-sphere impact with Coulomb friction μ ([`coulomb_rebound`]): sliding
    /// loses μ(1 + e)·v_n, a sphere that stops slipping leaves rolling at 5/7·v_t.
    #[default]
    Coulomb,
    /// OpenFOAM's `rebound` (`localInteraction`, `standardWallInteraction`): the fraction
    /// μ of the tangential velocity removed at every impact, whatever its angle
    /// ([`openfoam_fraction_rebound`]).
    OpenfoamFraction,
}

impl WallFriction {
    /// Name used in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            WallFriction::Coulomb => "coulomb",
            WallFriction::OpenfoamFraction => "openfoam_fraction",
        }
    }
}

/// The velocity after an impulsive impact on a wall of unit outward normal `n` (at rest),
/// restitution `e`, friction `mu` under the rule `friction`.
#[inline]
pub fn rebound_velocity(v: DVec3, n: DVec3, e: f64, mu: f64, friction: WallFriction) -> DVec3 {
    match friction {
        WallFriction::Coulomb => coulomb_rebound(v, n, e, mu),
        WallFriction::OpenfoamFraction => openfoam_fraction_rebound(v, n, e, mu),
    }
}

/// OpenFOAM's rebound (v1912's `LocalInteraction::correct` and
/// `StandardWallInteraction::correct`, `itRebound`), on a wall of unit outward normal `n`
/// at rest: with v_n = v·n and v_t = v − v_n·n taken before the impact,
/// v' = v − (1 + e)·v_n·n (only when v_n > 0), then v' −= μ·v_t. The tangential loss is a
/// fraction of v_t at every angle of incidence, unlike [`coulomb_rebound`]'s impulse;
/// the two agree at μ = 0.
#[inline]
pub fn openfoam_fraction_rebound(v: DVec3, n: DVec3, e: f64, mu: f64) -> DVec3 {
    let vn = v.dot(n);
    let vt = v - vn * n;
    let mut u = v;
    if vn > 0.0 {
        u -= (1.0 + e) * vn * n;
    }
    u - mu * vt
}

/// The velocity after an impulsive impact on a wall of unit outward normal `n` (the wall
/// at rest), with normal restitution `e` and Coulomb friction `mu`, for a sphere without
/// spin before the impact (the rigid-sphere impact of Crowe, Sommerfeld & Tsuji, *Multiphase
/// Flows with Droplets and Particles*, ch. 5):
/// * normal: v_n' = −e·v_n (only when moving into the wall, v_n = v·n > 0; otherwise the
///   velocity is returned unchanged);
/// * tangential, sliding through the impact when |v_t| > (7/2)·μ·(1 + e)·v_n: the friction
///   impulse μ·(1 + e)·m·v_n against the slip, Δv_t = −μ(1 + e)·v_n·t̂;
/// * otherwise the contact point stops slipping during the impact and the sphere leaves
///   rolling: v_t' = (5/7)·v_t (the rolling limit of a solid sphere, I = (2/5)·m·r²).
#[inline]
pub fn coulomb_rebound(v: DVec3, n: DVec3, e: f64, mu: f64) -> DVec3 {
    let vn = v.dot(n);
    if vn <= 0.0 {
        return v;
    }
    if mu == 0.0 {
        // frictionless: the tangential velocity is kept (the specular rebound)
        return v - (1.0 + e) * vn * n;
    }
    let vt = v - vn * n;
    let slip = vt.length();
    let jt = mu * (1.0 + e) * vn;
    let vt1 = if slip > 3.5 * jt {
        vt - (jt / slip) * vt
    } else {
        (5.0 / 7.0) * vt
    };
    vt1 - e * vn * n
}

/// A particle's cell hint (the component stores the `u32`): a cell index, or one of
/// these markers (all ≥ any cell count a `u32` mesh can hold in practice).
pub mod hint {
    /// Not located yet (spawned this step): the locator's grid finds it.
    pub const UNLOCATED: u32 = u32::MAX - 2;
    /// Left the mesh other than through a patch (or was never in it): the boundary stage
    /// removes it as lost.
    pub const LOST: u32 = u32::MAX - 1;
    /// The first marker of a departure through a patch: [`escaped`] and [`stuck`] code the
    /// patch in the markers `DEPARTED..UNLOCATED`.
    pub const DEPARTED: u32 = 0xC000_0000;

    /// Patches the markers can name (patch indices below this).
    pub const MAX_PATCHES: u32 = (UNLOCATED - DEPARTED) / 2;

    /// Escaped through patch `p` this step (`p` < [`MAX_PATCHES`]).
    #[inline]
    pub const fn escaped(p: u32) -> u32 {
        DEPARTED + 2 * p
    }

    /// Stuck on patch `p` this step.
    #[inline]
    pub const fn stuck(p: u32) -> u32 {
        DEPARTED + 2 * p + 1
    }

    /// What a hint says of a particle that left this step.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Departure {
        /// Escaped through the patch.
        Escaped(u32),
        /// Stuck on the patch.
        Stuck(u32),
        /// Lost (outside the mesh).
        Lost,
    }

    /// The departure `h` marks, `None` for a cell or [`UNLOCATED`].
    #[inline]
    pub const fn departure(h: u32) -> Option<Departure> {
        if h == LOST {
            Some(Departure::Lost)
        } else if h >= DEPARTED && h < UNLOCATED {
            let k = h - DEPARTED;
            Some(if k.is_multiple_of(2) {
                Departure::Escaped(k / 2)
            } else {
                Departure::Stuck(k / 2)
            })
        } else {
            None
        }
    }
}

/// The rebound of a particle that crossed the wall plane through `p` with unit outward
/// normal `n` during a step, ending at `x` with velocity `v`: the velocity is changed by
/// [`rebound_velocity`] (restitution `e`, friction `mu` under `friction`), and the part of
/// the step after the impact is moved again on the new velocity, as a tracker that stops
/// at the face does (OpenFOAM's): the centre went `d = (x − p)·n` beyond the plane in the
/// time τ = d / v_n since it met it (v_n = v·n > 0), so it ends at x + (v' − v)·τ — `e·d`
/// inside the plane, mirrored in full only at e = 1, and its slide along the wall after
/// the impact shortened by the friction. The tangential shift is at most `reach` (m, the
/// length of the step's move: a grazing impact's τ is long, and the move has no more
/// path than that to give back). At e = 0 the centre would end on the plane itself; it
/// is kept 10^-6·d inside it, so that it is located inside the cell. A centre beyond the
/// plane whose velocity already points inward (a curved path) is mirrored back, its
/// velocity unchanged. Returns (x', v').
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn rebound(
    x: DVec3,
    v: DVec3,
    p: DVec3,
    n: DVec3,
    e: f64,
    mu: f64,
    friction: WallFriction,
    reach: f64,
) -> (DVec3, DVec3) {
    let d = (x - p).dot(n);
    let v1 = rebound_velocity(v, n, e, mu, friction);
    if d <= 0.0 {
        return (x, v1);
    }
    let vn = v.dot(n);
    if vn <= 0.0 {
        return (x - 2.0 * d * n, v1);
    }
    let tau = d / vn;
    let dv = v1 - v;
    let dvn = dv.dot(n);
    let mut shift = (dv - dvn * n) * tau;
    let len = shift.length();
    if len > reach {
        shift *= reach / len;
    }
    // normal: (v1 − v)·n·τ = −(1 + e)·d for the restitution rules here; at least
    // 10^-6·d back inside the plane
    let back = (dvn * tau).min(-(1.0 + 1e-6) * d);
    (x + back * n + shift, v1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rest of the step after the impact goes on the new velocity: e = 1 mirrors the
    /// penetration, e = 0.5 puts the centre half of it inside, e = 0 just inside the
    /// plane; friction shortens the slide after the impact, at most by the step's length.
    #[test]
    fn rebound_moves_the_rest_of_the_step_on_the_new_velocity() {
        let at = |e: f64, mu: f64, friction, reach| {
            rebound(
                DVec3::new(1.1, 0.5, 0.5),
                DVec3::new(2.0, 1.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::X,
                e,
                mu,
                friction,
                reach,
            )
        };
        // τ = 0.1 / 2 = 0.05 s since the impact
        let (x, v) = at(1.0, 0.0, WallFriction::Coulomb, 1.0);
        assert!((x - DVec3::new(0.9, 0.5, 0.5)).length() < 1e-15, "{x}");
        assert_eq!(v, DVec3::new(-2.0, 1.0, 0.0));
        let (x, v) = at(0.5, 0.0, WallFriction::Coulomb, 1.0);
        assert!((x - DVec3::new(0.95, 0.5, 0.5)).length() < 1e-15, "{x}");
        assert_eq!(v, DVec3::new(-1.0, 1.0, 0.0));
        let (x, _) = at(0.0, 0.0, WallFriction::Coulomb, 1.0);
        assert!(x.x < 1.0 && x.x > 1.0 - 1e-6, "{x}");
        // OpenFOAM's friction: v_t loses 0.3·1 m/s, so the slide after the impact is
        // 0.3·0.05 = 0.015 m shorter; capped by a reach of 0.01 m
        let (x, v) = at(0.5, 0.3, WallFriction::OpenfoamFraction, 1.0);
        assert!((x - DVec3::new(0.95, 0.485, 0.5)).length() < 1e-15, "{x}");
        assert!((v - DVec3::new(-1.0, 0.7, 0.0)).length() < 1e-15);
        let (x, _) = at(0.5, 0.3, WallFriction::OpenfoamFraction, 0.01);
        assert!((x - DVec3::new(0.95, 0.49, 0.5)).length() < 1e-15, "{x}");
        // beyond the plane but moving inward already: mirrored, velocity kept
        let (x, v) = rebound(
            DVec3::new(1.1, 0.0, 0.0),
            -DVec3::X,
            DVec3::X,
            DVec3::X,
            0.5,
            0.3,
            WallFriction::Coulomb,
            1.0,
        );
        assert!((x - DVec3::new(0.9, 0.0, 0.0)).length() < 1e-15);
        assert_eq!(v, -DVec3::X);
        // inside the plane: the centre stays, the velocity rebounds
        let (x, v) = rebound(
            DVec3::new(0.9, 0.0, 0.0),
            DVec3::X,
            DVec3::X,
            DVec3::X,
            0.5,
            0.0,
            WallFriction::Coulomb,
            1.0,
        );
        assert_eq!(x, DVec3::new(0.9, 0.0, 0.0));
        assert_eq!(v, -0.5 * DVec3::X);
    }

    /// The impulse rebound against its closed forms: normal, oblique sliding (the friction
    /// impulse μ(1+e)v_n against the slip) and oblique sticking (5/7 of the tangential
    /// velocity), on a tilted wall, to 1e-12.
    #[test]
    fn coulomb_rebound_matches_the_closed_forms() {
        let n = DVec3::new(1.0, 2.0, -0.5).normalize();
        let t = n.any_orthonormal_vector();
        let (e, mu) = (0.7, 0.3);
        let close = |a: DVec3, b: DVec3| (a - b).length() <= 1e-12 * b.length().max(1.0);
        // normal
        let v = coulomb_rebound(4.0 * n, n, e, mu);
        assert!(close(v, -e * 4.0 * n), "{v}");
        // oblique, sliding: |v_t| = 10 > 3.5·μ(1+e)·v_n = 3.5·0.3·1.7·2 = 3.57
        let v = coulomb_rebound(2.0 * n + 10.0 * t, n, e, mu);
        let want = -e * 2.0 * n + (10.0 - mu * (1.0 + e) * 2.0) * t;
        assert!(close(v, want), "{v} vs {want}");
        // oblique, sticking: |v_t| = 3 < 3.57: leaves rolling at 5/7
        let v = coulomb_rebound(2.0 * n + 3.0 * t, n, e, mu);
        let want = -e * 2.0 * n + (5.0 / 7.0) * 3.0 * t;
        assert!(close(v, want), "{v} vs {want}");
        // the sliding result meets the rolling one at the limit (continuous)
        let lim = 3.5 * mu * (1.0 + e) * 2.0;
        let a = coulomb_rebound(2.0 * n + (lim * (1.0 + 1e-12)) * t, n, e, mu);
        let b = coulomb_rebound(2.0 * n + (lim * (1.0 - 1e-12)) * t, n, e, mu);
        assert!((a - b).length() < 1e-9, "{a} {b}");
        // frictionless: the tangential velocity is kept
        let v = coulomb_rebound(2.0 * n + 3.0 * t, n, e, 0.0);
        assert!(close(v, -e * 2.0 * n + 3.0 * t));
    }

    /// OpenFOAM's rule against its closed form, and against the Coulomb impact: the same
    /// at μ = 0, and at μ = 0.3, e = 0.5 a grazing impact (v_t = 10·v_n) keeps 0.7·v_t
    /// where the Coulomb impact keeps v_t − 0.45·v_n (0.955·v_t): 6.7 times less
    /// tangential loss under the other reading of the same μ.
    #[test]
    fn openfoam_fraction_is_openfoams_rebound() {
        let n = DVec3::new(0.3, -1.0, 0.2).normalize();
        let t = n.any_orthonormal_vector();
        let close = |a: DVec3, b: DVec3| (a - b).length() <= 1e-12 * b.length().max(1.0);
        let (e, mu) = (0.5, 0.3);
        let v = 1.0 * n + 10.0 * t;
        let of = rebound_velocity(v, n, e, mu, WallFriction::OpenfoamFraction);
        assert!(close(of, -e * n + 0.7 * 10.0 * t), "{of}");
        let co = rebound_velocity(v, n, e, mu, WallFriction::Coulomb);
        assert!(close(co, -e * n + (10.0 - mu * (1.0 + e)) * t), "{co}");
        let loss = |w: DVec3| 10.0 - w.dot(t);
        assert!((loss(of) / loss(co) - 3.0 / 0.45).abs() < 1e-9);
        // μ = 0: both the specular rebound with restitution
        for f in [WallFriction::Coulomb, WallFriction::OpenfoamFraction] {
            assert!(close(rebound_velocity(v, n, e, 0.0, f), -e * n + 10.0 * t));
        }
        // moving away from the wall: OpenFOAM still takes μ·v_t off (its rule has no test)
        let away = rebound_velocity(-n + 2.0 * t, n, e, mu, WallFriction::OpenfoamFraction);
        assert!(close(away, -n + 1.4 * t), "{away}");
        assert_eq!(WallFriction::OpenfoamFraction.name(), "openfoam_fraction");
    }

    /// Departure markers decode back to their patch and fate, and are never a cell.
    #[test]
    fn markers_decode_back() {
        // markers are never cells, and decode back
        for p in [0, 1, 7, hint::MAX_PATCHES - 1] {
            assert_eq!(
                hint::departure(hint::escaped(p)),
                Some(hint::Departure::Escaped(p))
            );
            assert_eq!(
                hint::departure(hint::stuck(p)),
                Some(hint::Departure::Stuck(p))
            );
        }
        assert_eq!(hint::departure(hint::UNLOCATED), None);
        assert_eq!(hint::departure(12), None);
    }
}
