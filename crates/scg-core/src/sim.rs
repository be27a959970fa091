//! A simulation: a bevy World with the scene's resources, and the step schedule built
//! from the scene's effects.

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use glam::DVec3;

use crate::components::*;
use crate::drag::DragLaw;
use crate::effects::contacts::ContactConfig;
use crate::effects::feeder::FeederSpec;
use crate::effects::guard::{Health, NonFinite};
use crate::effects::motion::{BodyAcceleration, Motion, SimClock};
use crate::effects::outlet::OutletSpec;
use crate::effects::recording::{RecordingParams, Tally};
use crate::effects::walls::{WallSet, WallTangential};
use crate::effects::{contacts, feeder, guard, motion, outlet, recording, scaling, walls};
use crate::flow::{FlowField, Fluid};
use crate::frame::{FrameSink, Recorders};
use crate::integrate::Integrator;
use crate::scaling::CoarseGrainLaw;
use crate::step::{Plan, StageTimers, StepBuilder};

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
    /// Gravity, m/s²; `None` = no gravity effect.
    pub gravity: Option<DVec3>,
    /// Reduce gravity by the buoyancy of the fluid (ρ_f/ρ_p).
    pub buoyancy: bool,
    /// Walls, if any.
    pub walls: Option<WallSet>,
    /// Particle–particle contacts, if declared.
    pub contacts: Option<ContactConfig>,
    /// Steps between recorded frames; `None` = no recording stage.
    pub record_every: Option<u64>,
    /// Group names, indexed by [`GroupId`].
    pub groups: Vec<String>,
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
}

/// An original particle to spawn; the scaling stage coarse-grains it.
#[derive(Clone, Copy, Debug, PartialEq)]
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

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The state turned non-finite.
    #[error("{0}")]
    NonFinite(NonFinite),
    /// A recorder failed.
    #[error("recorder failed: {0}")]
    Recorder(String),
}

/// Which optional per-particle components the scene's effects need.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct ParticleLayout {
    /// Wall force/torque accumulators and wall history (walls present).
    pub forces: bool,
    /// Angular velocity (walls or particle contacts present).
    pub spin: bool,
    /// Body acceleration (gravity present).
    pub gravity: bool,
}

/// Spawn one particle with every component its layout needs in a single bundle (no
/// archetype moves), through a `World` or `Commands` (both have `spawn`).
macro_rules! spawn_with_layout {
    ($spawner:expr, $layout:expr, $spec:expr, $id:expr) => {{
        let base = base_bundle($spec, $id);
        let walls = (
            Force::default(),
            Torque::default(),
            AngularVelocity::default(),
            WallHistory::default(),
        );
        let spin = AngularVelocity::default();
        let gravity = BodyAcceleration(DVec3::ZERO);
        match ($layout.forces, $layout.spin, $layout.gravity) {
            (true, _, false) => $spawner.spawn((base, walls)).id(),
            (true, _, true) => $spawner.spawn((base, walls, gravity)).id(),
            (false, true, false) => $spawner.spawn((base, spin)).id(),
            (false, true, true) => $spawner.spawn((base, spin, gravity)).id(),
            (false, false, false) => $spawner.spawn(base).id(),
            (false, false, true) => $spawner.spawn((base, gravity)).id(),
        }
    }};
}

/// Insert an original particle into `world` with the id `id`; the scaling stage fills in
/// the simulated quantities on the next step.
pub fn spawn_particle(world: &mut World, spec: &ParticleSpec, id: u32) -> Entity {
    let layout = *world.resource::<ParticleLayout>();
    spawn_with_layout!(world, layout, spec, id)
}

/// Same as [`spawn_particle`], through `Commands` (for systems such as feeders).
pub fn spawn_particle_deferred(
    commands: &mut Commands,
    layout: ParticleLayout,
    spec: &ParticleSpec,
    id: u32,
) -> Entity {
    spawn_with_layout!(commands, layout, spec, id)
}

fn base_bundle(spec: &ParticleSpec, id: u32) -> impl Bundle {
    (
        ParticleId(id),
        GroupId(spec.group),
        Unscaled,
        Position(spec.position),
        Velocity(spec.velocity),
        CoarseGrain {
            alpha: spec.alpha,
            law: spec.law,
            original_diameter: spec.diameter,
            original_density: spec.density,
        },
        // Placeholders; the scaling stage overwrites them before anything reads them.
        (
            Diameter(spec.diameter),
            Density(spec.density),
            Mass(0.0),
            FluidCoupling {
                drag_diameter: spec.diameter,
                force_scale: 1.0,
                tau: f64::INFINITY,
            },
            StokesFactors {
                gain: 0.0,
                relax: 0.0,
            },
        ),
    )
}

/// Next free particle id (resource).
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct NextParticleId(pub u32);

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

/// Start the compute thread pool with `threads` threads (0 = all cores). Only the first
/// call in a process has an effect; results do not depend on the thread count.
pub fn init_threads(threads: usize) {
    let n = if threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        threads
    };
    bevy_tasks::ComputeTaskPool::get_or_init(|| {
        bevy_tasks::TaskPoolBuilder::new().num_threads(n).build()
    });
}

impl Simulation {
    /// Build the world and the step schedule from `cfg`, adding only the effects it declares.
    pub fn new(cfg: SimConfig) -> Self {
        Self::with_inlet_outlet(cfg, InletOutlet::default())
    }

    /// Same as [`Simulation::new`], with feeders and an outlet.
    pub fn with_inlet_outlet(cfg: SimConfig, io: InletOutlet) -> Self {
        init_threads(
            std::env::var("SCG_THREADS")
                .ok()
                .and_then(|s| s.parse().ok())
                .unwrap_or(0),
        );
        let mut world = World::new();
        let motion_res = Motion {
            dt: cfg.dt,
            integrator: cfg.integrator,
            drag: cfg.drag,
            gravity: cfg.gravity.unwrap_or(DVec3::ZERO),
            buoyancy: cfg.buoyancy,
        };
        world.insert_resource(SimClock {
            step: 0,
            dt: cfg.dt,
            particle_steps: 0,
        });
        world.insert_resource(motion_res);
        world.insert_resource(cfg.flow);
        if let Some(f) = cfg.fluid {
            world.insert_resource(f);
        }
        world.insert_resource(Health::default());
        world.insert_resource(StageTimers::default());
        world.insert_resource(NextParticleId::default());
        world.insert_resource(Recorders::default());
        let ng = cfg.groups.len();
        world.insert_resource(Tally {
            drained: vec![0; ng],
            fed: vec![0; ng],
            collisions: vec![0; ng],
        });
        world.insert_resource(RecordingParams {
            every: cfg.record_every.unwrap_or(u64::MAX).max(1),
            groups: cfg.groups.clone(),
        });
        // Walls accumulate into Force/Torque; particle contacts kick velocities directly.
        let has_forces = cfg.walls.is_some();
        world.insert_resource(ParticleLayout {
            forces: has_forces,
            spin: has_forces || cfg.contacts.is_some(),
            gravity: cfg.gravity.is_some(),
        });

        let mut b = StepBuilder::new();
        scaling::plugin(&mut b);
        let mut rotation = false;
        if let Some(c) = &cfg.contacts {
            // Contacts kick the angular velocity themselves; integrate_rotation is for
            // the wall torques.
            contacts::plugin(&mut world, &mut b, c);
        }
        if let Some(w) = cfg.walls {
            // Wall contacts use the wall material's friction, and the rolling friction and
            // stiffness rule of the particle contacts when declared.
            let law = match &cfg.contacts {
                Some(c) => crate::contact::TangentialLaw {
                    friction: w.material.friction,
                    ..c.tangential()
                },
                None => crate::contact::TangentialLaw::new(w.law, w.material.friction, 0.0),
            };
            let t = WallTangential {
                law: crate::contact::TangentialLaw {
                    damping: crate::contact::tangential::damping_factor(w.law),
                    ..law
                },
                // A wall of the same material: G* = G/(2(2 − ν)).
                g_eff: w.material.effective_shear_modulus(),
            };
            rotation |= t.law.active();
            world.insert_resource(w);
            walls::plugin(&mut world, &mut b, Some(t));
        }
        motion::plugin(&mut b, &motion_res, rotation);
        if let Some(o) = io.outlet {
            outlet::plugin(&mut world, &mut b, o, ng);
        }
        feeder::plugin(&mut world, &mut b, &io.feeders, io.seed);
        guard::plugin(&mut b);
        if cfg.record_every.is_some() {
            recording::plugin(&mut b);
        }
        let (schedule, plan) = b.build();
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

    /// Spawn an original particle (coarse-grained on the next step); returns its id.
    pub fn spawn(&mut self, spec: &ParticleSpec) -> u32 {
        let id = {
            let mut next = self.world.resource_mut::<NextParticleId>();
            let id = next.0;
            next.0 += 1;
            id
        };
        spawn_particle(&mut self.world, spec, id);
        id
    }

    /// Apply the scaling stage now (normally the first thing a step does), so the
    /// simulated quantities can be inspected before the first step.
    pub fn scale_new_particles(&mut self) {
        let _ = self
            .world
            .run_system_once(scaling::coarse_grain_new_particles);
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
        if self.plan.contains("record_frame") {
            self.scale_new_particles();
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

    /// Flush and close every recorder.
    pub fn finish_recorders(&mut self) -> Result<(), SimError> {
        let mut rec = self.world.resource_mut::<Recorders>();
        let mut first = None;
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
