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
