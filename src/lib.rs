//! scg: a DEM simulator for dilute particle-laden flows, built around the simpler
//! coarse-grain (SCG) model of Kushimoto et al. (Processes 2021, 9, 1098).
//!
//! This facade re-exports the workspace crates: [`core`] (physics and ECS systems),
//! [`scene`] (scene files), [`record`] (recordings) and [`cli`].
pub use scg_cli as cli;
pub use scg_core as core;
pub use scg_record as record;
pub use scg_scene as scene;
