//! Spawning: particles enter the world already coarse-grained, with every component the
//! scene's layout needs, in one bundle, so that all particles share one storage table
//! ([`crate::stages::table`]) and nothing moves them between tables later.

use bevy_ecs::prelude::*;
use glam::DVec3;

use crate::components::*;
use crate::physics::drag::{cunningham_davies, stokes_response_time};
use crate::physics::flow::Fluid;
use crate::physics::forces::ExtraForces;
use crate::physics::integrate::exponential_factors;
use crate::physics::scaling::{CoarseGrainLaw, coarse_grain};
use crate::state::{NextParticleId, SimClock};

/// An original particle to spawn; it enters coarse-grained by `law` with ratio `alpha`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParticleSpec {
    /// Group index.
    pub group: u32,
    /// Original diameter, m.
    pub diameter: f64,
    /// Original density, kg/m³.
    pub density: f64,
    /// Coarse-graining ratio α.
    pub alpha: f64,
    /// Coarse-graining law.
    pub law: CoarseGrainLaw,
    /// Initial centre, m.
    pub position: DVec3,
    /// Initial velocity, m/s.
    pub velocity: DVec3,
}

/// What every particle of a scene gets besides its own spec (resource).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct SpawnRules {
    /// Wall force/torque accumulators, angular velocity and wall history (walls present).
    pub forces: bool,
    /// Angular velocity (walls or particle contacts present).
    pub spin: bool,
    /// Gravity, m/s², when the scene declares it (then every particle has a
    /// [`BodyAcceleration`]).
    pub gravity: Option<DVec3>,
    /// Reduce gravity by the buoyancy of the fluid: a = g·(1 − ρ_f/ρ_p).
    pub buoyancy: bool,
    /// The fluid, if any (drag response time, buoyancy).
    pub fluid: Option<Fluid>,
    /// SCG particles' Reynolds-dependent drag correction and buoyancy as the original's
    /// (`SimConfig::scg_at_original`).
    pub scg_at_original: bool,
    /// Forces besides drag and gravity (the Cunningham slip enters τ here).
    pub extra_forces: crate::physics::forces::ExtraForces,
    /// A flow on a mesh: every particle has a [`CellHint`] (spawned unlocated).
    pub mesh: bool,
    /// A carrier modifier: every particle has a [`CarrierOffset`] (zero at spawn).
    pub carrier_offset: bool,
    /// Turbulent dispersion: every particle has an [`Eddy`] (age 0, no fluctuation, as
    /// OpenFOAM's parcels enter).
    pub dispersion: bool,
}

/// The simulated quantities of an original particle coarse-grained by `law` with ratio
/// `alpha`, for time step `dt`: diameter, density, mass, fluid coupling, Stokes factors.
/// With `as_original` (an SCG particle under `scg_at_original`: [`SpawnRules::as_original`])
/// the drag correction is taken at the original diameter's Reynolds number (the SCG
/// premise, equal acceleration, under any drag law). With a Cunningham mean free path
/// `forces` (Cunningham slip, added mass) τ grows by C_c and by the inertia factor k,
/// both at the diameter and density the correction is taken at.
pub fn coarse_grained(
    cg: &CoarseGrain,
    fluid: Option<&Fluid>,
    dt: f64,
    as_original: bool,
    forces: &ExtraForces,
) -> (Diameter, Density, Mass, FluidCoupling, StokesFactors) {
    let s = coarse_grain(cg.law, cg.alpha, cg.original_diameter, cg.original_density);
    let mass = s.mass();
    let reynolds_diameter = if as_original {
        cg.original_diameter
    } else {
        s.drag_diameter
    };
    let force_density = if reynolds_diameter == cg.original_diameter {
        cg.original_density
    } else {
        s.density
    };
    let tau = match fluid {
        Some(f) if f.viscosity > 0.0 => {
            let cc = forces
                .cunningham
                .map_or(1.0, |l| cunningham_davies(reynolds_diameter, l));
            stokes_response_time(mass, f.viscosity, s.drag_diameter, s.force_scale)
                * cc
                * forces.inertia(fluid, force_density)
        }
        _ => f64::INFINITY,
    };
    let (gain, relax) = exponential_factors(tau, dt);
    (
        Diameter(s.diameter),
        Density(s.density),
        Mass(mass),
        FluidCoupling {
            drag_diameter: s.drag_diameter,
            reynolds_diameter,
            force_density,
            force_scale: s.force_scale,
            tau,
        },
        StokesFactors { gain, relax },
    )
}

impl SpawnRules {
    /// Whether the particle `cg` takes its Reynolds-dependent drag correction and its
    /// buoyancy as its original's: an SCG particle under `scg_at_original`.
    pub fn as_original(&self, cg: &CoarseGrain) -> bool {
        self.scg_at_original && cg.law == CoarseGrainLaw::Scg
    }

    /// Body acceleration of a particle of simulated density `density` (kg/m³), m/s².
    pub fn body_acceleration(&self, density: f64) -> DVec3 {
        let reduce = match self.fluid {
            Some(f) if self.buoyancy => 1.0 - f.density / density,
            _ => 1.0,
        };
        self.gravity.unwrap_or(DVec3::ZERO) * reduce
    }
}

/// What a checkpoint does with a component of the particle layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The particle's identity and original (recorded: [`ParticleSpec`], id).
    Identity,
    /// State the next steps read: recorded per particle
    /// (`checkpoint::records::ParticleRecord`).
    Recorded,
    /// Derived again, exactly, by the spawn path from the identity and the scene.
    Derived,
    /// Rewritten before it is read in every step, or a cache whose "unknown" value is
    /// always valid: not recorded.
    Scratch,
}

/// Every per-particle component type, once: the particle layout. Spawning
/// ([`SpawnRules`] decides which of the optional ones a scene's particles carry), the
/// reordering of the particle table by mesh cell, the layout checks and the checkpoint
/// round-trip test all visit this list, so a new component is added here (with its
/// [`Role`]) and to the spawn groups below.
pub trait LayoutVisitor {
    /// Visit component type `T`, whose checkpoint role is `role`.
    fn visit<T: LayoutComponent>(&mut self, role: Role);
}

/// What every component of the particle layout is: a mutable component that can be
/// cloned (the cell sort), compared and printed (the checkpoint round-trip test).
pub trait LayoutComponent:
    Component<Mutability = bevy_ecs::component::Mutable> + Clone + PartialEq + std::fmt::Debug
{
}

impl<T> LayoutComponent for T where
    T: Component<Mutability = bevy_ecs::component::Mutable> + Clone + PartialEq + std::fmt::Debug
{
}

/// Visit every component of the particle layout, in a fixed order.
pub fn visit_layout(v: &mut impl LayoutVisitor) {
    use Role::*;
    v.visit::<ParticleId>(Identity);
    v.visit::<GroupId>(Identity);
    v.visit::<Position>(Recorded);
    v.visit::<Velocity>(Recorded);
    v.visit::<CoarseGrain>(Identity);
    v.visit::<Diameter>(Derived);
    v.visit::<Density>(Derived);
    v.visit::<Mass>(Derived);
    v.visit::<FluidCoupling>(Derived);
    v.visit::<StokesFactors>(Derived);
    v.visit::<Force>(Recorded);
    v.visit::<Torque>(Recorded);
    v.visit::<AngularVelocity>(Recorded);
    v.visit::<WallHistory>(Recorded);
    v.visit::<BodyAcceleration>(Derived);
    v.visit::<CellHint>(Recorded);
    // A cache: unknown after a restore, which gives the same bits (its docs).
    v.visit::<FlowAtCentre>(Scratch);
    // A hint that changes no result (its docs).
    v.visit::<TetHint>(Scratch);
    // The constant offset is rewritten before every integration, but turbulent
    // dispersion keeps its fluctuation from step to step: state.
    v.visit::<CarrierOffset>(Recorded);
    v.visit::<Eddy>(Recorded);
}

/// Spawn one particle with every component of the layout: the base bundle, then each
/// optional group the rules ask for, through a `World` or `Commands` (both have `spawn`
/// and `insert`). A particle's inserts follow its spawn directly, so it ends in the one
/// table of the layout, rows in spawn order.
macro_rules! spawn_bundle {
    ($spawner:expr, $rules:expr, $spec:expr, $id:expr, $dt:expr) => {
        spawn_bundle!(
            $spawner,
            $rules,
            $spec,
            $id,
            $dt,
            crate::physics::mesh_flow::hint::UNLOCATED
        )
    };
    ($spawner:expr, $rules:expr, $spec:expr, $id:expr, $dt:expr, $hint:expr) => {{
        let hint: u32 = $hint;
        let rules: &SpawnRules = $rules;
        let spec: &ParticleSpec = $spec;
        let cg = CoarseGrain {
            alpha: spec.alpha,
            law: spec.law,
            original_diameter: spec.diameter,
            original_density: spec.density,
        };
        let as_original = rules.as_original(&cg);
        let scaled = coarse_grained(
            &cg,
            rules.fluid.as_ref(),
            $dt,
            as_original,
            &rules.extra_forces,
        );
        // buoyancy of the original when its forces are (equal acceleration)
        let buoyant = if as_original {
            cg.original_density
        } else {
            scaled.1.0
        };
        // with added mass the inertia is m + C_A·m_f: every acceleration divides by k
        let k = rules
            .extra_forces
            .inertia(rules.fluid.as_ref(), scaled.3.force_density);
        let gravity = BodyAcceleration(rules.body_acceleration(buoyant) / k);
        let mut e = $spawner.spawn((
            ParticleId($id),
            GroupId(spec.group),
            Position(spec.position),
            Velocity(spec.velocity),
            cg,
            scaled,
        ));
        if rules.forces {
            e.insert((Force::default(), Torque::default(), WallHistory::default()));
        }
        if rules.forces || rules.spin {
            e.insert(AngularVelocity::default());
        }
        if rules.gravity.is_some() {
            e.insert(gravity);
        }
        if rules.mesh {
            e.insert((
                CellHint(hint),
                TetHint(scg_mesh::NO_TET),
                FlowAtCentre::UNKNOWN,
            ));
        }
        if rules.carrier_offset {
            e.insert(CarrierOffset::default());
        }
        if rules.dispersion {
            e.insert(Eddy::default());
        }
        e.id()
    }};
}

/// Spawn an original particle into `world` coarse-grained, with the next free id;
/// returns the id.
pub fn spawn_particle(world: &mut World, spec: &ParticleSpec) -> u32 {
    let rules = *world.resource::<SpawnRules>();
    let dt = world.resource::<SimClock>().dt;
    let id = world.resource_mut::<NextParticleId>().take();
    let _ = spawn_bundle!(world, &rules, spec, id, dt);
    id
}

/// Spawn a particle with a given id (restoring a checkpoint); returns its entity. The
/// next free id is not changed.
pub fn spawn_particle_with_id(world: &mut World, spec: &ParticleSpec, id: u32) -> Entity {
    let rules = *world.resource::<SpawnRules>();
    let dt = world.resource::<SimClock>().dt;
    spawn_bundle!(world, &rules, spec, id, dt)
}

/// Same as [`spawn_particle`] through `Commands` (for systems such as feeders), with the
/// id `id` and time step `dt` (s).
pub fn spawn_particle_deferred(
    commands: &mut Commands,
    rules: &SpawnRules,
    spec: &ParticleSpec,
    id: u32,
    dt: f64,
) -> Entity {
    spawn_bundle!(commands, rules, spec, id, dt)
}

/// [`spawn_particle_deferred`] with the mesh cell hint `hint` (a cell holding the centre,
/// or [`crate::physics::mesh_flow::hint::UNLOCATED`]); ignored without a mesh flow.
pub fn spawn_particle_deferred_in(
    commands: &mut Commands,
    rules: &SpawnRules,
    spec: &ParticleSpec,
    id: u32,
    dt: f64,
    hint: u32,
) -> Entity {
    spawn_bundle!(commands, rules, spec, id, dt, hint)
}
