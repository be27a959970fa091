//! scg-core: particles, coarse-grain laws, fluid drag, contacts and integration as
//! bevy_ecs components and systems. No I/O lives here.
//!
//! Pure physics lives in [`scaling`], [`drag`], [`flow`], [`integrate`], [`contact`] and
//! [`walls`]; the systems that apply it live in [`effects`]; [`step`] shows the whole step
//! and [`sim`] builds a runnable [`sim::Simulation`].
pub mod components;
pub mod contact;
pub mod drag;
pub mod effects;
pub mod flow;
pub mod frame;
pub mod integrate;
pub mod neighbour;
pub mod par;
pub mod region;
pub mod scaling;
pub mod sim;
pub mod step;
pub mod team;
pub mod walls;

pub use sim::{ParticleSpec, SimConfig, SimError, Simulation};
