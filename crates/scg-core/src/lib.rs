//! scg-core: particles, coarse-grain laws, fluid drag, contacts and integration as
//! bevy_ecs components and systems. No I/O lives here.
//!
//! * [`physics`] — pure laws and kernels (scaling, drag, flow, integration, contact laws,
//!   wall geometry, neighbour list), unit-tested without a World;
//! * [`stages`] — the systems that apply them, one module per effect, each adding its
//!   systems to the step only when the scene declares the effect;
//! * [`step`] — the whole step: the ordered system sets, the plan, the stage timers;
//! * [`exec`] — where the work runs (the thread team, parallel loops);
//! * [`components`], [`state`] (clock, health, tally), [`spawn`] (particles enter
//!   coarse-grained), [`stats`] (recorded scalar names), [`frame`] (what recorders get),
//!   [`region`] (random placement), [`diagnostics`];
//! * [`sim`] builds a runnable [`Simulation`].
//!
//! # Example
//!
//! A simulation built in code, without a scene file: one 10 µm particle released at rest
//! in a uniform air flow relaxes toward it exactly as Stokes drag says,
//! v(t) = U·(1 − e^(−t/τ)), τ = ρ·d²/(18·μ).
//!
//! ```
//! use glam::DVec3;
//! use scg_core::physics::{drag::DragLaw, flow::{FlowField, Fluid}, integrate::Integrator};
//! use scg_core::physics::scaling::CoarseGrainLaw;
//! use scg_core::{ParticleSpec, SimConfig, Simulation};
//!
//! let u = DVec3::new(2.0, 0.0, 0.0);
//! let mut sim = Simulation::new(SimConfig {
//!     dt: 1e-4,
//!     integrator: Integrator::Exponential,
//!     drag: Some(DragLaw::Stokes),
//!     fluid: Some(Fluid { density: 1.2, viscosity: 1.8e-5 }),
//!     flow: FlowField::Uniform(u),
//!     mesh_flow: None,
//!     gravity: None,
//!     buoyancy: false,
//!     scg_at_original: false,
//!     extra_forces: Default::default(),
//!     walls: None,
//!     contacts: None,
//!     record_every: None,
//!     groups: vec!["dust".into()],
//!     carrier: None,
//! });
//! sim.spawn(&ParticleSpec {
//!     group: 0,
//!     diameter: 10e-6,
//!     density: 1000.0,
//!     alpha: 1.0,
//!     law: CoarseGrainLaw::Scg,
//!     position: DVec3::ZERO,
//!     velocity: DVec3::ZERO,
//! });
//! sim.run(10, |_| true).unwrap();
//! let tau = 1000.0 * 10e-6 * 10e-6 / (18.0 * 1.8e-5);
//! let v = sim.particles()[0].velocity;
//! let exact = u * (1.0 - (-sim.time() / tau).exp());
//! assert!((v - exact).length() < 1e-12);
//! // `scg run --plan` prints the same schedule:
//! assert!(sim.plan().render().contains("integrate_stokes_exponential"));
//! ```
pub mod checkpoint;
pub mod components;
pub mod diagnostics;
pub mod exec;
pub mod frame;
pub mod physics;
pub mod region;
pub mod sim;
mod simd;
pub mod spawn;
pub mod stages;
pub mod state;
pub mod stats;
pub mod step;

pub use sim::{SimConfig, SimError, Simulation};
pub use spawn::ParticleSpec;
