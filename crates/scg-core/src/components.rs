//! Per-particle components. SI units throughout; each doc says the unit. Every particle
//! has the same set (the scene's layout, [`crate::spawn::SpawnRules`]), so all live in one
//! storage table ([`crate::stages::table`]).

use bevy_ecs::prelude::Component;
use bytemuck::TransparentWrapper;
use glam::DVec3;

use crate::physics::scaling::CoarseGrainLaw;

/// Centre position, m.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct Position(pub DVec3);

/// Translational velocity, m/s.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct Velocity(pub DVec3);

/// Angular velocity, rad/s.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct AngularVelocity(pub DVec3);

/// Diameter as simulated (after coarse graining), m.
#[derive(Component, Clone, Copy, Debug, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct Diameter(pub f64);

/// Density as simulated (after coarse graining), kg/m³.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Density(pub f64);

/// Mass, kg (= ρ·π·d³/6, kept so the hot loops need not recompute it).
#[derive(Component, Clone, Copy, Debug, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct Mass(pub f64);

/// Wall force of this step, N (set by the wall stage every step).
/// Present only in scenes with walls (particle contacts kick the velocity directly).
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct Force(pub DVec3);

/// Wall torque of this step, N·m (set by the wall stage every step). Present only
/// in scenes with walls.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct Torque(pub DVec3);

/// Stable particle id, unique over a run and never reused.
#[derive(
    Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, TransparentWrapper,
)]
#[repr(transparent)]
pub struct ParticleId(pub u32);

/// Index of the scene group (size class) the particle belongs to.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct GroupId(pub u32);

/// How the particle was coarse grained (set at spawn).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct CoarseGrain {
    /// Coarse-graining ratio α = d_CG / d_original (1 = original particle).
    pub alpha: f64,
    /// The scaling law applied.
    pub law: CoarseGrainLaw,
    /// Original diameter, m.
    pub original_diameter: f64,
    /// Original density, kg/m³.
    pub original_density: f64,
}

/// How the fluid sees the particle (set at spawn).
///
/// The fluid force is computed for a sphere of diameter `drag_diameter` and multiplied by
/// `force_scale`: (d, 1) for every law but `parcel`, (d/α, α³) for `parcel`.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct FluidCoupling {
    /// Diameter the drag law is evaluated for, m.
    pub drag_diameter: f64,
    /// Diameter the particle Reynolds number of the drag law's correction is taken at, m:
    /// `drag_diameter`, or the original's for an SCG particle whose forces are evaluated
    /// as the original's (`SimConfig::scg_at_original`).
    pub reynolds_diameter: f64,
    /// Density of the sphere of `reynolds_diameter` (kg/m³): the original's where that
    /// diameter is the original's, else the simulated one. The opt-in forces
    /// ([`crate::physics::forces`]) give the acceleration of this sphere.
    pub force_density: f64,
    /// Factor applied to the fluid force, dimensionless.
    pub force_scale: f64,
    /// Stokes momentum response time τ = m / (3π·μ·d_drag·force_scale), s (∞ without drag).
    pub tau: f64,
}

/// Stokes-drag factors precomputed once per particle for a fixed dt (exponential scheme),
/// with τ from [`FluidCoupling::tau`]. Kept to the two numbers the drag-only kernel reads.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct StokesFactors {
    /// 1 − e^(−dt/τ), dimensionless.
    pub gain: f64,
    /// τ·(1 − e^(−dt/τ)), s.
    pub relax: f64,
}

/// Tangential history of a particle's wall contacts: (history key, history displacement, m);
/// the key is the wall index, or for a mesh wall its flat region's key
/// (`stages::walls::history_keys`).
/// Present with walls; empty while the particle touches no wall.
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct WallHistory(pub Vec<(u32, DVec3)>);

/// Constant body acceleration of a particle (gravity, reduced by buoyancy), m/s².
/// Present only when the scene declares gravity.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct BodyAcceleration(pub DVec3);

/// The mesh cell holding the particle's centre at the end of the last step (mesh flows
/// only; see [`crate::physics::mesh_flow::hint`] for the markers a value may also be).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, TransparentWrapper)]
#[repr(transparent)]
pub struct CellHint(pub u32);

/// The record of the mesh cell's tetrahedron that held the particle at the last query
/// (mesh flows only; `scg_mesh::NO_TET` when unknown): a hint that lets the next query read
/// that tetrahedron alone ([`scg_mesh::CellTable::walk`]). It changes what is read, never
/// a result, so it is scratch: unknown after a restore or a migration.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq, TransparentWrapper)]
#[repr(transparent)]
pub struct TetHint(pub u32);

/// The fluid velocity at the particle's centre as the last step's landing on the mesh
/// found it (mesh flows only): `u` (m/s) at the centre `at` (m). A step starting from
/// `at` takes `u` instead of locating the centre again, which gives the same value bit
/// for bit (the same cell records); `at` is NaN when unknown (a new, restored or migrated
/// particle, a landing off the table), and then the step locates it. Kept only where the
/// step reads it (the explicit scheme, Reynolds-dependent drag) or the dispersion does
/// (`stochastic_ras`'s slip); unknown otherwise.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct FlowAtCentre {
    /// The centre the value was found at, m (NaN: unknown).
    pub at: DVec3,
    /// The fluid velocity there, m/s (of an unsteady series: its earlier snapshot's).
    pub u: DVec3,
    /// An unsteady series: the later snapshot's velocity there, m/s (NaN otherwise), so
    /// that the step blends the two at its own weight.
    pub later: DVec3,
}

impl FlowAtCentre {
    /// Nothing known.
    pub const UNKNOWN: FlowAtCentre = FlowAtCentre {
        at: DVec3::NAN,
        u: DVec3::NAN,
        later: DVec3::NAN,
    };

    /// The value at `x` when it is known there (`x` bit for bit the centre it was found
    /// at).
    #[inline]
    pub fn at(&self, x: DVec3) -> Option<DVec3> {
        let same =
            |a: DVec3, b: DVec3| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits);
        same(self.at, x).then_some(self.u)
    }

    /// The values of both snapshots of a series at `x` when they are known there.
    #[inline]
    pub fn pair_at(&self, x: DVec3) -> Option<(DVec3, DVec3)> {
        self.at(x).map(|u| (u, self.later))
    }
}

/// Velocity added to the carrier velocity this particle sees, m/s: the slot of the
/// carrier modifiers ([`crate::physics::carrier`]; turbulent dispersion writes its
/// fluctuation here). Present only when the scene declares a carrier modifier; every
/// integration scheme adds it to each fluid-velocity evaluation of the particle's step.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, TransparentWrapper)]
#[repr(transparent)]
pub struct CarrierOffset(pub DVec3);

/// A particle's turbulent-dispersion state besides its fluctuation (which is its
/// [`CarrierOffset`]): see [`crate::physics::dispersion::State`]. Present only when the
/// scene declares `[dispersion]`.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq)]
pub struct Eddy {
    /// `stochastic_ras`: age of the current eddy, s (OpenFOAM's `tTurb`; 0 at entry).
    pub age: f64,
    /// `langevin`: the rms velocity σ the fluctuation was set with, m/s (0: none yet).
    pub sigma: f64,
}
