//! A simulation: a bevy World with the scene's resources, and the step schedule built
//! from the scene's effects.

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use glam::DVec3;

use crate::components::*;
use crate::frame::{FrameSink, Recorders};
use crate::physics::drag::DragLaw;
use crate::physics::flow::{FlowField, Fluid};
use crate::physics::forces::ExtraForces;
use crate::physics::integrate::Integrator;
use crate::spawn::{ParticleSpec, SpawnRules, spawn_particle};
use crate::stages::carrier::CarrierModifier;
use crate::stages::contacts::ContactConfig;
use crate::stages::feeder::FeederSpec;
use crate::stages::mesh_flow::MeshFlowSpec;
use crate::stages::motion::Motion;
use crate::stages::outlet::OutletSpec;
use crate::stages::recording::RecordingParams;
use crate::stages::walls::{WallSet, WallTangential};
use crate::stages::{
    carrier, contacts, feeder, guard, mesh_flow, motion, outlet, recording, walls,
};
use crate::state::{
    ContactCount, ContactResolution, Health, NextParticleId, NonFinite, SimClock, Tally,
};
use crate::step::{Plan, StageTimers, StepBuilder, StepSet, StepSystem};

/// Everything the core needs to build a simulation (the scene crate produces it).
#[derive(Clone, Debug)]
pub struct SimConfig {
    /// Time step, s.
    pub dt: f64,
    /// Integrator.
    pub integrator: Integrator,
    /// Drag law; `None` = no fluid drag.
    pub drag: Option<DragLaw>,
    /// Fluid properties (needed for drag and buoyancy).
    pub fluid: Option<Fluid>,
    /// Flow field.
    pub flow: FlowField,
    /// A flow on a CFD mesh; when set it replaces `flow` for the drag (which should then
    /// be [`FlowField::Still`]).
    pub mesh_flow: Option<MeshFlowSpec>,
    /// Gravity, m/s²; `None` = no gravity effect.
    pub gravity: Option<DVec3>,
    /// Reduce gravity by the buoyancy of the fluid (ρ_f/ρ_p).
    pub buoyancy: bool,
    /// Evaluate an SCG particle's Reynolds-dependent drag correction and its buoyancy as
    /// the original particle's (`[coarse_grain] forces_at = "original"`): its acceleration
    /// is then the original's under any drag law, not only Stokes'. `false`: as the
    /// simulated sphere's.
    pub scg_at_original: bool,
    /// Forces besides drag and gravity the scene declares (Cunningham slip), each for
    /// the original particle.
    pub extra_forces: crate::physics::forces::ExtraForces,
    /// Walls, if any.
    pub walls: Option<WallSet>,
    /// Particle–particle contacts, if declared.
    pub contacts: Option<ContactConfig>,
    /// Steps between recorded frames; `None` = no recording stage.
    pub record_every: Option<u64>,
    /// Group names, indexed by [`GroupId`].
    pub groups: Vec<String>,
    /// A carrier modifier (added to the fluid velocity every particle sees), if any.
    pub carrier: Option<CarrierModifier>,
}

/// Feeders and outlet of a scene (the inlet/outlet stage).
#[derive(Clone, Debug, Default)]
pub struct InletOutlet {
    /// Feeders, in scene order.
    pub feeders: Vec<FeederSpec>,
    /// The outlet, if any.
    pub outlet: Option<OutletSpec>,
    /// Scene seed (feeders' random streams derive from it).
    pub seed: u64,
    /// Walls that rebound, stick or escape as impulses (no contact law).
    pub impulse_walls: Vec<crate::stages::impulse_walls::ImpulseWall>,
    /// Collecting zones and the steps a particle's centre must stay in each before it is
    /// removed as collected (0: on entry).
    pub collect_zones: Vec<(crate::region::Region, u64)>,
    /// `[erosion]`: what is logged (mesh patches, impulse walls).
    pub erosion: Option<crate::stages::erosion::ErosionSpec>,
}

/// Why a run stopped early.
/// The contacts of a run so far, measured at their real approach speeds: particle–wall
/// and particle–particle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Resolved {
    /// Time step, s.
    pub dt: f64,
    /// Particle–wall contacts.
    pub wall: ContactCount,
    /// Particle–particle contacts.
    pub pair: ContactCount,
}

impl Resolved {
    /// Share of under-resolved contacts above which a run warns.
    pub const TOLERATED_SHARE: f64 = 0.01;

    /// One line per contact kind met: how many, the shortest in steps, the share
    /// under-resolved.
    pub fn summary(&self) -> Vec<String> {
        self.kinds()
            .filter_map(|(kind, c)| {
                let t = c.shortest?;
                Some(format!(
                    "{kind} contacts: {} started, shortest {t:.3e} s = {:.1} steps, {:.2} % under {} steps (measured at their approach speeds)",
                    c.contacts,
                    t / self.dt,
                    100.0 * c.under_resolved as f64 / c.contacts.max(1) as f64,
                    ContactResolution::MIN_STEPS
                ))
            })
            .collect()
    }

    /// Warnings for the contact kinds of which more than [`Resolved::TOLERATED_SHARE`] of
    /// the contacts lasted fewer than [`ContactResolution::MIN_STEPS`] steps.
    pub fn warnings(&self) -> Vec<String> {
        self.kinds()
            .filter(|(_, c)| {
                c.under_resolved as f64 > Self::TOLERATED_SHARE * c.contacts as f64
            })
            .map(|(kind, c)| {
                format!(
                    "{} of {} {kind} contacts ({:.1} %) lasted fewer than {} steps at their measured approach speed (shortest {:.1} steps): lower dt, or soften the material if the overlaps stay small",
                    c.under_resolved,
                    c.contacts,
                    100.0 * c.under_resolved as f64 / c.contacts.max(1) as f64,
                    ContactResolution::MIN_STEPS,
                    c.shortest.unwrap_or(f64::INFINITY) / self.dt
                )
            })
            .collect()
    }

    fn kinds(&self) -> impl Iterator<Item = (&'static str, ContactCount)> {
        [
            ("particle–wall", self.wall),
            ("particle–particle", self.pair),
        ]
        .into_iter()
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The state turned non-finite.
    #[error("{0}")]
    NonFinite(NonFinite),
    /// A recorder failed.
    #[error("recorder failed: {0}")]
    Recorder(String),
    /// A snapshot of an unsteady flow could not be read.
    #[error("unsteady flow: {0}")]
    Flow(String),
}

/// A ready-to-run simulation.
pub struct Simulation {
    /// The ECS world (particles and resources).
    pub world: World,
    schedule: Schedule,
    plan: Plan,
}

/// A particle's state, for tests and analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleState {
    /// Id.
    pub id: u32,
    /// Group.
    pub group: u32,
    /// Position, m.
    pub position: DVec3,
    /// Velocity, m/s.
    pub velocity: DVec3,
    /// Diameter, m.
    pub diameter: f64,
    /// Density, kg/m³.
    pub density: f64,
}

impl Simulation {
    /// Build the world and the step schedule from `cfg`, adding only the effects it declares.
    pub fn new(cfg: SimConfig) -> Self {
        Self::with_inlet_outlet(cfg, InletOutlet::default())
    }

    /// Same as [`Simulation::new`], with feeders and an outlet.
    pub fn with_inlet_outlet(cfg: SimConfig, io: InletOutlet) -> Self {
        let mut world = World::new();
        let motion_res = Motion {
            integrator: cfg.integrator,
            drag: cfg.drag,
            forces: match (cfg.drag, cfg.fluid) {
                (Some(_), Some(f)) => cfg.extra_forces.step(f),
                _ => None,
            },
        };
        let motion_forces = motion_res.forces.is_some();
        world.insert_resource(SimClock::new(cfg.dt));
        world.insert_resource(motion_res);
        world.insert_resource(cfg.flow);
        if let Some(f) = cfg.fluid {
            world.insert_resource(f);
        }
        world.insert_resource(Health::default());
        world.insert_resource(crate::checkpoint::records::Persistence::default());
        world.insert_resource(StageTimers::default());
        world.insert_resource(NextParticleId::default());
        world.insert_resource(Recorders::default());
        let ng = cfg.groups.len();
        world.insert_resource(Tally::new(ng));
        world.insert_resource(ContactResolution::new(cfg.dt));
        world.insert_resource(RecordingParams {
            every: cfg.record_every.unwrap_or(u64::MAX).max(1),
            groups: cfg.groups.clone(),
        });
        // Walls accumulate into Force/Torque; particle contacts kick velocities directly.
        let has_forces = cfg.walls.is_some();
        world.insert_resource(SpawnRules {
            forces: has_forces,
            spin: has_forces || cfg.contacts.is_some() || cfg.extra_forces.rubinow_keller,
            gravity: cfg.gravity,
            buoyancy: cfg.buoyancy,
            fluid: cfg.fluid,
            scg_at_original: cfg.scg_at_original,
            extra_forces: cfg.extra_forces,
            mesh: cfg.mesh_flow.is_some(),
            carrier_offset: cfg.carrier.is_some(),
            dispersion: cfg
                .carrier
                .as_ref()
                .is_some_and(|c| c.dispersion().is_some()),
        });

        let mut b = StepBuilder::new();
        let mut rotation = false;
        if let Some(c) = &cfg.contacts {
            // Contacts kick the angular velocity themselves; integrate_rotation is for
            // the wall torques.
            contacts::plugin(&mut world, &mut b, c);
        }
        if let Some(w) = cfg.walls {
            let t = WallTangential::new(&w, cfg.contacts.as_ref().map(|c| c.tangential()));
            rotation |= t.law.active();
            world.insert_resource(w);
            walls::plugin(&mut world, &mut b, Some(t));
        }
        let lift = cfg.extra_forces.rubinow_keller && cfg.drag.is_some() && cfg.fluid.is_some();
        if let Some(m) = cfg.carrier {
            // the rotational lift reads the offsets before the move: then its own pass
            let fuse = cfg.mesh_flow.is_some() && !lift;
            carrier::plugin(&mut world, &mut b, m, fuse);
        }
        if lift {
            let ca = cfg.extra_forces.added_mass.unwrap_or(0.0);
            crate::stages::rotational_lift::plugin(&mut world, &mut b, ca);
        }
        motion::plugin(&mut b, &motion_res, rotation, cfg.mesh_flow.is_some());
        if let Some(e) = io.erosion {
            crate::stages::erosion::plugin(&mut world, crate::stages::erosion::ErosionLog::new(e));
        }
        if let Some(m) = cfg.mesh_flow.clone() {
            mesh_flow::plugin(&mut world, &mut b, m, ng);
        }
        if !io.impulse_walls.is_empty() {
            crate::stages::impulse_walls::plugin(&mut world, &mut b, io.impulse_walls, ng);
        }
        if let Some(o) = io.outlet {
            outlet::plugin(&mut world, &mut b, o, ng);
        }
        if !io.collect_zones.is_empty() {
            crate::stages::collect::plugin(&mut world, &mut b, io.collect_zones, ng);
        }
        feeder::plugin(&mut world, &mut b, &io.feeders, io.seed);
        if cfg.mesh_flow.as_ref().is_some_and(|m| m.sort_every > 0) && cfg.contacts.is_none() {
            mesh_flow::add_sort(&mut b);
        }
        guard::plugin(&mut b);
        if cfg.record_every.is_some() {
            recording::plugin(&mut b);
        }
        let (schedule, mut plan) = b.build();
        plan.notes = force_notes(&cfg.extra_forces, motion_forces);
        world.insert_resource(plan.clone());
        Simulation {
            world,
            schedule,
            plan,
        }
    }

    /// The systems this simulation runs, in order.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Spawn an original particle (it enters coarse-grained); returns its id.
    pub fn spawn(&mut self, spec: &ParticleSpec) -> u32 {
        spawn_particle(&mut self.world, spec)
    }

    /// Add a recorder.
    pub fn add_recorder(&mut self, sink: Box<dyn FrameSink>) {
        self.world.resource_mut::<Recorders>().sinks.push(sink);
    }

    /// Steps completed.
    pub fn step_count(&self) -> u64 {
        self.world.resource::<SimClock>().step
    }

    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.world.resource::<SimClock>().time()
    }

    /// Particle-steps done so far.
    pub fn particle_steps(&self) -> u64 {
        self.world.resource::<SimClock>().particle_steps
    }

    /// Time step, s.
    pub fn dt(&self) -> f64 {
        self.world.resource::<SimClock>().dt
    }

    /// Record the current state now (used for the initial frame).
    pub fn record_now(&mut self) -> Result<(), SimError> {
        if self.plan.contains(StepSystem::RecordFrame) {
            let _ = self.world.run_system_once(recording::record_frame);
        }
        self.check()
    }

    fn check(&mut self) -> Result<(), SimError> {
        if let Some(f) = &self.world.resource::<Health>().failure {
            return Err(SimError::NonFinite(f.clone()));
        }
        if let Some(e) = &self.world.resource::<Recorders>().error {
            return Err(SimError::Recorder(e.clone()));
        }
        if let Some(e) = self
            .world
            .get_resource::<crate::stages::flow_series::FlowSeries>()
            .and_then(|s| s.failure.as_ref())
        {
            return Err(SimError::Flow(e.clone()));
        }
        Ok(())
    }

    /// Advance one step.
    pub fn step(&mut self) -> Result<(), SimError> {
        self.schedule.run(&mut self.world);
        self.check()
    }

    /// Advance `steps` steps, calling `each` after every step (progress, interrupts: return
    /// `false` to stop early).
    pub fn run(&mut self, steps: u64, mut each: impl FnMut(u64) -> bool) -> Result<u64, SimError> {
        for i in 0..steps {
            self.step()?;
            if !each(i + 1) {
                return Ok(i + 1);
            }
        }
        Ok(steps)
    }

    /// Flush and close every recorder, handing each the wear of the walls first when the
    /// run logs erosion ([`FrameSink::write_wear`]).
    pub fn finish_recorders(&mut self) -> Result<(), SimError> {
        let wear = crate::stages::erosion::wear_map(&self.world, self.step_count(), self.time());
        let mut rec = self.world.resource_mut::<Recorders>();
        let mut first = None;
        if let Some(w) = &wear {
            for s in rec.sinks.iter_mut() {
                if let Err(e) = s.write_wear(w)
                    && first.is_none()
                {
                    first = Some(e);
                }
            }
        }
        for s in rec.sinks.iter_mut() {
            if let Err(e) = s.finish()
                && first.is_none()
            {
                first = Some(e);
            }
        }
        rec.sinks.clear();
        first.map_or(Ok(()), |e| Err(SimError::Recorder(e)))
    }

    /// The shortest contacts met so far, measured at their real approach speeds.
    pub fn contact_resolution(&self) -> Resolved {
        let r = self.world.resource::<ContactResolution>();
        Resolved {
            dt: self.dt(),
            wall: r.wall(),
            pair: r.pair(),
        }
    }

    /// Wall time per step stage.
    pub fn timers(&self) -> &StageTimers {
        self.world.resource::<StageTimers>()
    }

    /// All particles, sorted by id.
    pub fn particles(&mut self) -> Vec<ParticleState> {
        let mut q = self.world.query::<(
            &ParticleId,
            &GroupId,
            &Position,
            &Velocity,
            &Diameter,
            &Density,
        )>();
        let mut v: Vec<_> = q
            .iter(&self.world)
            .map(|(id, g, x, v, d, r)| ParticleState {
                id: id.0,
                group: g.0,
                position: x.0,
                velocity: v.0,
                diameter: d.0,
                density: r.0,
            })
            .collect();
        v.sort_by_key(|p| p.id);
        v
    }
}

/// What `scg run --plan` lists of the opt-in forces: under scaling what is set once per particle at
/// spawn, under forces what the integration's step evaluates (`stepped`: the scene
/// has the drag these act through).
fn force_notes(f: &ExtraForces, stepped: bool) -> Vec<(StepSet, String)> {
    let mut v = Vec::new();
    if let Some(l) = f.cunningham {
        v.push((
            StepSet::Scaling,
            format!(
                "at spawn: cunningham_davies slip, τ·C_c(d), mean free path {l:e} m, at \
                 the original d"
            ),
        ));
    }
    if let Some(c) = f.added_mass {
        v.push((
            StepSet::Scaling,
            format!(
                "at spawn: added_mass inertia m + {c}·m_f (τ and body acceleration / \
                 (1 + {c}·ρ_f/ρ_p))"
            ),
        ));
    }
    if let Some(fr) = &f.frame {
        v.push((
            StepSet::Integration,
            format!(
                "[frame] rotating at {:.6} rpm about {:?} through {:?}: centrifugal and \
                 Coriolis accelerations at mid-step (positions and velocities relative to it)",
                crate::physics::flow::rad_per_s_to_rpm(fr.omega.length()),
                fr.omega.normalize_or_zero().to_array(),
                fr.centre.to_array()
            ),
        ));
    }
    if f.rubinow_keller {
        v.push((
            StepSet::Integration,
            "[forces:rubinow_keller] spin relaxed toward ω/2 (τ_r = ρd²/60μ) and the lift \
             as a kick before the move, for the original"
                .to_string(),
        ));
    }
    let names = f.step_names();
    if stepped && !names.is_empty() {
        v.push((
            StepSet::Forces,
            format!(
                "[forces:{}] in the integration's step, at mid-step, for the original",
                names.join("+")
            ),
        ));
    }
    v
}
